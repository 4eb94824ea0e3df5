//! Commands beyond a single case: `list` ([`list`]), and those of many recordings: `batch`
//! (locally or as a Slurm job array), the hidden
//! `batch-task` of an array task, `gather` and `synth`.
pub mod alloc;
pub mod args;
pub mod commands;
pub mod list;
pub mod noise_study;
pub mod outcome;
pub mod progress;
pub mod synth;

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use anyhow::{Context, Result};

use args::OutputFormatArg;
use cosserat::jobs::batch::{self, gather, list_recordings, run_batch, BatchRow, Plan, SUMMARY};
use cosserat::jobs::batch_task::run_task;
use cosserat::jobs::slurm;
use cosserat::jobs::MAX_JOBS;
use cosserat::solve::Outcome;

use progress::{Progress, Visibility};

/// `cosserat batch`.
#[derive(clap::Args, Debug)]
pub struct BatchArgs {
    /// Clip case file (TOML); each recording replaces its `clip.file`
    case: PathBuf,
    /// A folder of recordings (*.csv, *.npy; truth sidecars *.truth.npy are read with their
    /// recording) or a file listing one recording per line (relative to the list's folder)
    #[arg(long)]
    recordings: PathBuf,
    /// Output folder: one folder per recording, summary.csv, batch.json (the plan)
    #[arg(long)]
    out: PathBuf,
    /// Recordings run at once, 1 to 256 [default: number of cores; never more than the recordings]
    #[arg(long, value_parser = parse_jobs)]
    jobs: Option<usize>,
    /// `--slurm` and the options of the Slurm job array
    #[command(flatten)]
    slurm: SlurmArgs,
    /// How each recording's per-node fields are written (as `cosserat run --output-format`).
    /// A batch writes the compact format unless told otherwise: about 31 KB per frame of 128
    /// nodes against about 130 KB as CSV and VTK (docs/results.md, "Memory and output of long
    /// recordings")
    #[arg(long, value_enum, default_value_t = OutputFormatArg::Compact)]
    output_format: OutputFormatArg,
    /// Do not show progress (a bar on a terminal, else a line every 10 s)
    #[arg(long)]
    quiet: bool,
    /// A recording's run replaces its folder even when it fails or is interrupted and the
    /// folder holds a complete run (without it, that run stays and this one is kept beside it)
    #[arg(long)]
    force: bool,
}

/// `cosserat batch --slurm`: whether to submit a job array, and its options (each but `--slurm`
/// requires `--slurm`).
#[derive(clap::Args, Debug)]
pub struct SlurmArgs {
    /// Submit a Slurm job array (sbatch) instead of running here; `cosserat gather OUT` then
    /// writes summary.csv. OUT must be on a filesystem that every node sees
    #[arg(id = "slurm", long = "slurm")]
    submit: bool,
    /// Recordings per Slurm array task
    #[arg(long, default_value_t = 1, requires = "slurm", value_parser = clap::value_parser!(u64).range(1..))]
    per_task: u64,
    /// Slurm partition [default: the cluster's default]
    #[arg(long, requires = "slurm")]
    partition: Option<String>,
    /// Block until the job array has finished, then gather
    #[arg(long, requires = "slurm")]
    wait: bool,
    /// Time limit of each array task (sbatch --time: `MM`, `HH:MM:SS`, `D-HH:MM`) [default:
    /// the partition's]
    #[arg(long, value_name = "TIME", requires = "slurm")]
    time: Option<String>,
    /// Memory of each array task (sbatch --mem: `500M`, `2G`) [default: the partition's]
    #[arg(long, value_name = "MEM", requires = "slurm")]
    mem: Option<String>,
    /// Account charged for the array (sbatch --account)
    #[arg(long, value_name = "ACCOUNT", requires = "slurm")]
    account: Option<String>,
    /// Any other sbatch option, written as an `#SBATCH` line of the job script; repeat for
    /// more, e.g. `--sbatch-arg=--qos=long --sbatch-arg=--constraint=avx2`
    #[arg(long = "sbatch-arg", value_name = "ARG", allow_hyphen_values = true, requires = "slurm")]
    sbatch_arg: Vec<String>,
    /// A file of shell lines that each array task runs before cosserat (`module load …`,
    /// `export …`), copied into the job script
    #[arg(long, value_name = "FILE", requires = "slurm")]
    setup: Option<PathBuf>,
    /// Write the plan (batch.json) and the job script (batch.sbatch) into OUT without
    /// submitting it; `sbatch OUT/batch.sbatch` submits it
    #[arg(long, requires = "slurm", conflicts_with = "wait")]
    dry_run: bool,
}

/// `cosserat batch-task` (run by a Slurm array task).
#[derive(clap::Args, Debug)]
pub struct TaskArgs {
    /// Output folder of the batch (holds batch.json)
    out: PathBuf,
    /// Array task index ($SLURM_ARRAY_TASK_ID)
    #[arg(long)]
    index: usize,
}

/// Print the outcome of `rows` (written to `out/summary.csv`): one line on stdout, one line per
/// failure and a one-line summary on stderr; exit status 1 if any recording did not succeed.
fn report(out: &Path, rows: &[BatchRow], skipped: usize) -> ExitCode {
    let failed: Vec<&BatchRow> = rows.iter().filter(|r| !r.is_ok()).collect();
    let frames: usize = rows.iter().filter_map(|r| r.frames).sum();
    println!(
        "{} recordings: {} ok ({skipped} already complete, skipped), {} not; {frames} frames; wrote {}",
        rows.len(),
        rows.len() - failed.len(),
        failed.len(),
        out.join(SUMMARY).display()
    );
    for r in &failed {
        eprintln!("  {} ({}): {}", r.folder, r.status_word(), r.reason.as_deref().unwrap_or(""));
    }
    if failed.is_empty() {
        return ExitCode::SUCCESS;
    }
    if rows.iter().any(|r| r.status == Some(Outcome::Interrupted)) {
        eprintln!("{}", interrupted_summary(out, rows));
        return ExitCode::from(crate::EXIT_INTERRUPTED);
    }
    let names: Vec<&str> = failed.iter().map(|r| r.folder.as_str()).collect();
    eprintln!("error: {} of {} recordings failed: {} (see {})", failed.len(), rows.len(), names.join(", "), SUMMARY);
    ExitCode::from(1)
}

/// What an interrupted batch kept: recordings complete, stopped at their next frame (with the
/// frames their folders keep), not started, failed.
fn interrupted_summary(out: &Path, rows: &[BatchRow]) -> String {
    let not_started = rows.iter().filter(|r| r.reason.as_deref() == Some(batch::NOT_STARTED)).count();
    let stopped: Vec<String> = rows
        .iter()
        .filter(|r| r.status == Some(Outcome::Interrupted) && r.reason.as_deref() != Some(batch::NOT_STARTED))
        .map(|r| format!("{} ({} frames)", r.folder, r.frames.unwrap_or(0)))
        .collect();
    let ok = rows.iter().filter(|r| r.is_ok()).count();
    let failed = rows.iter().filter(|r| !r.is_ok() && r.status != Some(Outcome::Interrupted)).count();
    format!(
        "interrupted: {ok} of {} recordings complete, {} stopped at their next frame{}, {not_started} not started, {failed} failed; {} marks each. Run the same command again to run the others (complete recordings are skipped)",
        rows.len(),
        stopped.len(),
        if stopped.is_empty() { String::new() } else { format!(": {}", stopped.join(", ")) },
        out.join(SUMMARY).display()
    )
}

pub fn cmd_batch(a: BatchArgs) -> Result<ExitCode> {
    let recordings = list_recordings(&a.recordings)?;
    let per_task = if a.slurm.submit { a.slurm.per_task as usize } else { 1 };
    let mut plan = Plan::new(&a.case, &recordings, per_task);
    plan.format = a.output_format.into();
    // the case is read (and refused if it is not a clip case) before anything is written
    let (case, _) = batch::plan_case(&plan).with_context(|| format!("batch of {}", a.case.display()))?;
    let (_lock, real) = lock_batch(&a.out, "batch")?;
    plan.begin(&real)?;
    let out = std::fs::canonicalize(&real).with_context(|| format!("output folder {}", a.out.display()))?;
    if a.slurm.submit {
        return submit_batch(&a.slurm, Visibility::unless(a.quiet), &plan, &out, &case.name);
    }
    let pb = Progress::new(
        &format!("{} batch", case.name),
        "recordings",
        plan.recordings.len(),
        Visibility::unless(a.quiet),
    );
    let ran = run_batch(&plan, &out, batch::BatchOptions { jobs: a.jobs.unwrap_or(0), force: a.force }, || pb.inc())?;
    pb.finish();
    let skipped = ran.iter().filter(|r| r.skipped).count();
    let rows: Vec<BatchRow> = ran.into_iter().map(|r| r.row).collect();
    Ok(report(&out, &rows, skipped))
}

/// The lock of a batch's output folder while this process writes its plan and runs or submits
/// it (`doing`: "batch"), or gathers its rows ("gather"): a second `cosserat batch` or a
/// `gather` into the same folder is refused at once, by any of its names (a symbolic link is
/// resolved: the folder it names is locked and written through it). The lock and the folder.
fn lock_batch(out: &Path, doing: &str) -> Result<(cosserat::output::folder_lock::FolderLock, PathBuf)> {
    use cosserat::output::folder_lock::{real_folder, FolderLock, LockError};
    let io = |path: PathBuf, source| anyhow::Error::new(source).context(format!("cannot lock {}", path.display()));
    let real = real_folder(out).map_err(|e| match e {
        LockError::Io { path, source } => io(path, source),
        LockError::Held { .. } => anyhow::anyhow!("cannot lock {}", out.display()),
    })?;
    let name = real.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "batch".into());
    let parent = real.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    std::fs::create_dir_all(parent).with_context(|| format!("cannot create {}", parent.display()))?;
    let lock = FolderLock::acquire(parent, &name).map_err(|e| match e {
        LockError::Held { pid } => anyhow::anyhow!(
            "{} is being written by another cosserat process ({}): wait for it to end before this {doing}, or choose \
             another folder",
            out.display(),
            pid.map_or("its pid not yet known".to_string(), |p| format!("pid {p}"))
        ),
        LockError::Io { path, source } => io(path, source),
    })?;
    Ok((lock, real))
}

/// `batch --slurm`: the job script of the array tasks that have a recording to run (a
/// resubmission runs only the unfinished recordings), submitted unless `--dry-run`; with
/// `--wait`, waited for (progress as `visibility` says) and gathered.
fn submit_batch(a: &SlurmArgs, visibility: Visibility, plan: &Plan, out: &Path, name: &str) -> Result<ExitCode> {
    let exe = std::env::current_exe().context("cannot find the cosserat executable for the job script")?;
    let complete = batch::complete_recordings(plan, out)?;
    let skipped = complete.iter().filter(|c| **c).count();
    let tasks = batch::unfinished_tasks(plan, &complete);
    let total = plan.recordings.len();
    if tasks.is_empty() {
        eprintln!("{name}: all {total} recordings hold a complete run: nothing to submit");
        let rows = gather(out)?;
        return Ok(report(out, &rows, skipped));
    }
    let setup = match &a.setup {
        Some(p) => Some(cosserat::io::files::read_capped_text(p, SETUP_FILE_CAP_BYTES, "set-up file")?),
        None => None,
    };
    let opts = slurm::JobOptions {
        partition: a.partition.clone(),
        time: a.time.clone(),
        mem: a.mem.clone(),
        account: a.account.clone(),
        sbatch_args: a.sbatch_arg.clone(),
        setup,
    };
    let script = slurm::write_script(plan, &tasks, out, &exe, &opts)?;
    let counts = format!(
        "{} of {total} recordings to run ({skipped} already complete, skipped) in {} of {} array tasks",
        total - skipped,
        tasks.len(),
        plan.tasks()
    );
    if a.dry_run {
        eprintln!(
            "{name}: wrote {} ({counts}); not submitted: `sbatch {}` submits it",
            script.display(),
            script.display()
        );
        println!("{}", script.display());
        return Ok(ExitCode::SUCCESS);
    }
    let id = slurm::submit(&script)?;
    eprintln!("{name}: submitted Slurm job {id}: {counts}; job script {}", script.display());
    if !a.wait {
        println!("{id}");
        eprintln!("when it has finished: cosserat gather {}", out.display());
        return Ok(ExitCode::SUCCESS);
    }
    let pb = Progress::new(&format!("{name} job {id}"), "array tasks", tasks.len(), visibility);
    slurm::wait(&id, Duration::from_millis(500), |queued| pb.set(tasks.len() - queued.min(tasks.len()), 0))?;
    pb.finish();
    let rows = gather(out)?;
    Ok(report(out, &rows, skipped))
}

/// Largest `--setup` file read [bytes]: 64 KiB of shell lines.
const SETUP_FILE_CAP_BYTES: u64 = 64 << 10;

pub fn cmd_batch_task(a: TaskArgs) -> Result<ExitCode> {
    let pb = Progress::new(&format!("batch task {}", a.index), "recordings", 0, Visibility::Shown);
    let ran = run_task(&a.out, a.index, |done, total| pb.set(done, total))?;
    pb.finish();
    for r in &ran {
        let what = if r.skipped { "already complete" } else { r.row.status_word() };
        eprintln!("{}: {what}{}", r.row.folder, r.row.reason.as_deref().map(|m| format!(": {m}")).unwrap_or_default());
    }
    Ok(if ran.iter().all(|r| r.row.is_ok()) { ExitCode::SUCCESS } else { ExitCode::from(1) })
}

pub fn cmd_gather(out: &Path) -> Result<ExitCode> {
    // not while a batch runs into it (its rows are being written)
    let (_lock, real) = lock_batch(out, "gather")?;
    let rows = gather(&real).with_context(|| format!("gather {}", out.display()))?;
    Ok(report(out, &rows, 0))
}

/// glibc's malloc hands the top of its heap back to the system whenever more than 128 KB of
/// it is free, and takes it back at the next allocation (a `brk` call, then page faults that
/// zero the pages again). A clip frees and allocates its per-frame vectors some 500 times per
/// thousand frames that way; keeping up to 64 MiB of freed memory (and serving blocks up to
/// 32 MiB from the heap, not from fresh mappings) removes those system calls. Only the
/// process's memory reuse changes, not its results.
pub fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        extern "C" {
            fn mallopt(param: std::ffi::c_int, value: std::ffi::c_int) -> std::ffi::c_int;
        }
        const M_TRIM_THRESHOLD: std::ffi::c_int = -1;
        const M_MMAP_THRESHOLD: std::ffi::c_int = -3;
        // SAFETY: mallopt only sets allocator parameters; called before any thread starts.
        unsafe {
            mallopt(M_TRIM_THRESHOLD, 64 << 20);
            mallopt(M_MMAP_THRESHOLD, 32 << 20);
        }
    }
}

/// A count option that is not a positive number; clap prints it after the option's name.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CountError {
    /// `--count` of `cosserat modes`
    #[error("expected a number of modes >= 1, got `{given}`")]
    Modes { given: String },
    /// `--frames` of `cosserat compare`
    #[error("expected a number of frames >= 1 or `all`, got `{given}`")]
    Frames { given: String },
    /// `--jobs` of `batch`, `sweep` and `audit`
    #[error("expected a number of parallel runs from 1 to {MAX_JOBS}, got `{given}`")]
    Jobs { given: String },
}

/// `--jobs`: 1 to [`MAX_JOBS`] (the threads are also never more than the work's items).
pub fn parse_jobs(s: &str) -> Result<usize, CountError> {
    match s.parse::<usize>() {
        Ok(n) if (1..=MAX_JOBS).contains(&n) => Ok(n),
        _ => Err(CountError::Jobs { given: s.to_string() }),
    }
}

/// `--count`: a positive number.
pub fn parse_count(s: &str) -> Result<usize, CountError> {
    match s.parse::<usize>() {
        Ok(n) if n > 0 => Ok(n),
        _ => Err(CountError::Modes { given: s.to_string() }),
    }
}

/// `--frames`: a positive count or `all`.
pub fn parse_frames(s: &str) -> Result<usize, CountError> {
    if s == "all" {
        return Ok(usize::MAX);
    }
    match s.parse::<usize>() {
        Ok(n) if n > 0 => Ok(n),
        _ => Err(CountError::Frames { given: s.to_string() }),
    }
}
