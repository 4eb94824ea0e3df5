//! One clip case over many recordings (`cosserat batch`): the recording replaces the case's
//! `clip.file`, each recording runs into its own folder `OUT/NAME` under the output-folder
//! contract ([`crate::output::run_folder`], `run.json` with command `batch`), and `OUT/summary.csv` has
//! one row per recording ([`SUMMARY_COLUMNS`]).
//!
//! The batch is described once by its plan, `OUT/batch.json` ([`Plan`]: the case file and every
//! recording with its folder, absolute paths). Every way of running it reads the plan and runs
//! its recordings with [`run_recording`]: all of them on a thread pool ([`run_batch`]), or a
//! chunk of them per Slurm array task ([`run_task`], `super::slurm`). Each recording leaves its
//! summary row in its folder (`batch_row.json`), so that [`gather`] builds the same summary
//! from the folders, whoever ran them. A recording whose folder's `run.json` says complete for
//! the same case file and recording (SHA-256 of both, and of the truth sidecar) is not run
//! again: its row is read back.
use std::path::{Path, PathBuf};
use std::time::Instant;

use super::solved::{chain, solve_into};
use crate::case::{Analysis, Case, CaseError, DataSource};
use crate::engine::clip_metrics::clip_metrics;
use crate::engine::input::truth_file::{is_truth_sidecar, truth_sidecar};
use crate::engine::metrics::Metric;
use crate::engine::Engine;
use crate::io::compact::OutputFormat;
use crate::io::files::{write_atomic, OutputError};
use crate::jobs::clip_run::ClipOptions;
use crate::output::run_folder::{
    input_file_as, resumable_beside, sha256_file, FolderError, InputFile, Manifest, Mode, Placed, RunFolder, Status,
};
use crate::solve::Outcome;

pub use super::batch_summary::{summary_csv, BatchRow, SummaryColumn, MISSING, SUMMARY, SUMMARY_COLUMNS};

/// The plan of a batch in its output folder.
pub const PLAN: &str = "batch.json";
/// The summary row of a recording in its folder.
pub const ROW: &str = "batch_row.json";

/// Errors of a batch as a whole (a recording's own failure is its row's, not one of these).
#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    #[error("{path}: no recordings (*.csv or *.npy files, truth sidecars *.truth.npy excepted)")]
    NoRecordings { path: PathBuf },
    #[error("cannot read the recordings {path}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(transparent)]
    Case(#[from] CaseError),
    #[error("case `{0}` has no [clip]: a batch runs a clip case over recordings")]
    NotAClip(String),
    #[error(transparent)]
    Folder(#[from] FolderError),
    #[error(transparent)]
    Input(#[from] crate::io::files::InputError),
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error("{path}: {reason}")]
    Plan { path: PathBuf, reason: String },
    #[error(
        "{path} holds files ({examples}) but no {PLAN}: it is not the output folder of a batch; choose another --out"
    )]
    Foreign { path: PathBuf, examples: String },
    #[error("task {index} does not exist: the batch has {tasks} tasks (0 to {})", tasks.saturating_sub(1))]
    Task { index: usize, tasks: usize },
    #[error("cannot start the thread pool: {0}")]
    Pool(String),
}

/// One recording of a plan.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlanEntry {
    /// the recording (absolute)
    pub path: PathBuf,
    /// its folder under the output folder
    pub folder: String,
}

/// `OUT/batch.json`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Plan {
    /// the case file (absolute)
    pub case: PathBuf,
    pub recordings: Vec<PlanEntry>,
    /// recordings per Slurm array task (1 for a local batch)
    pub per_task: usize,
    /// how each recording's per-node fields are written (`csv` if absent)
    #[serde(default)]
    pub format: OutputFormat,
}

impl BatchRow {
    fn without_result(entry: &PlanEntry, status: Option<Outcome>, reason: String) -> Self {
        BatchRow {
            recording: entry.path.display().to_string(),
            folder: entry.folder.clone(),
            status,
            reason: Some(reason),
            ..BatchRow::default()
        }
    }
}

fn read_err(path: &Path) -> impl Fn(std::io::Error) -> BatchError + '_ {
    move |source| BatchError::Read { path: path.to_path_buf(), source }
}

/// Is `path` a recording by its name (`.csv` or `.npy`, not a truth sidecar, not a folder)?
/// A pipe or device of that name is one: its row fails, saying what it is.
fn is_recording(path: &Path) -> bool {
    let ext = path.extension().and_then(|e| e.to_str());
    matches!(ext, Some("csv") | Some("npy")) && !is_truth_sidecar(path) && !path.is_dir()
}

/// Largest list of recordings read [bytes]: 16 MiB, some 100 000 paths.
const LIST_FILE_CAP_BYTES: u64 = 16 << 20;

/// The recordings of `input`: the `.csv` and `.npy` files of a folder (sorted by name; truth
/// sidecars excepted), or the lines of a list file (paths relative to the list's folder;
/// blank lines and lines starting with `#` skipped). Paths are made absolute.
pub fn list_recordings(input: &Path) -> Result<Vec<PathBuf>, BatchError> {
    let mut out = Vec::new();
    if input.is_dir() {
        for entry in std::fs::read_dir(input).map_err(read_err(input))? {
            let p = entry.map_err(read_err(input))?.path();
            if is_recording(&p) {
                out.push(p);
            }
        }
        out.sort();
    } else {
        let text = crate::io::files::read_capped_text(input, LIST_FILE_CAP_BYTES, "list of recordings")?;
        let base = input.parent().unwrap_or(Path::new(""));
        out = text
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && !l.starts_with('#'))
            .map(|l| base.join(l))
            .collect();
    }
    if out.is_empty() {
        return Err(BatchError::NoRecordings { path: input.to_path_buf() });
    }
    Ok(out.iter().map(|p| absolute(p)).collect())
}

/// `path` made absolute (canonical where it exists: a missing recording fails alone, later).
fn absolute(path: &Path) -> PathBuf {
    std::fs::canonicalize(path)
        .unwrap_or_else(|_| std::env::current_dir().map(|d| d.join(path)).unwrap_or_else(|_| path.to_path_buf()))
}

/// One folder name per recording: its file name without extension (characters other than
/// letters, digits, `-`, `_` and `.` replaced by `_`); a name taken by an earlier recording
/// gets `-2`, `-3`, … (so `a.csv` and `a.npy` run into `a` and `a-2`).
pub fn folder_names(paths: &[PathBuf]) -> Vec<String> {
    let mut taken = std::collections::BTreeSet::new();
    paths
        .iter()
        .map(|p| {
            let stem = p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            let clean: String =
                stem.chars().map(|c| if c.is_ascii_alphanumeric() || "-_.".contains(c) { c } else { '_' }).collect();
            let base = if clean.is_empty() || clean.starts_with('.') { format!("rec{clean}") } else { clean };
            let mut name = base.clone();
            let mut k = 2;
            while !taken.insert(name.to_lowercase()) {
                name = format!("{base}-{k}");
                k += 1;
            }
            name
        })
        .collect()
}

impl Plan {
    /// The plan of `case_file` over `recordings`, `per_task` recordings per Slurm task.
    pub fn new(case_file: &Path, recordings: &[PathBuf], per_task: usize) -> Plan {
        let names = folder_names(recordings);
        Plan {
            case: absolute(case_file),
            recordings: recordings
                .iter()
                .zip(names)
                .map(|(p, folder)| PlanEntry { path: absolute(p), folder })
                .collect(),
            per_task: per_task.max(1),
            format: OutputFormat::Csv,
        }
    }

    /// Slurm array tasks of the plan.
    pub fn tasks(&self) -> usize {
        self.recordings.len().div_ceil(self.per_task)
    }

    /// The recordings of task `index`.
    pub fn task(&self, index: usize) -> Result<&[PlanEntry], BatchError> {
        if index >= self.tasks() {
            return Err(BatchError::Task { index, tasks: self.tasks() });
        }
        let a = index * self.per_task;
        Ok(&self.recordings[a..(a + self.per_task).min(self.recordings.len())])
    }

    /// Read `out/batch.json`.
    pub fn read(out: &Path) -> Result<Plan, BatchError> {
        let path = out.join(PLAN);
        let bytes = std::fs::read(&path).map_err(read_err(&path))?;
        serde_json::from_slice(&bytes).map_err(|e| BatchError::Plan { path, reason: format!("not a batch plan: {e}") })
    }

    /// Claim `out` for this plan: a new or empty folder, or the folder of a batch (its plan is
    /// replaced and its `summary.csv` removed; its recordings' folders stay, for the skip of
    /// complete ones).
    pub fn begin(&self, out: &Path) -> Result<(), BatchError> {
        if out.exists() && !out.join(PLAN).is_file() {
            let mut names: Vec<String> = std::fs::read_dir(out)
                .map_err(read_err(out))?
                .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
                .collect();
            if !names.is_empty() {
                names.sort();
                let examples = names.into_iter().take(3).collect::<Vec<_>>().join(", ");
                return Err(BatchError::Foreign { path: out.to_path_buf(), examples });
            }
        }
        std::fs::create_dir_all(out).map_err(|source| OutputError::Io { path: out.to_path_buf(), source })?;
        // the summary of an earlier batch goes before this one's plan is written: it would
        // describe folders this batch may replace (it is written again, last, from the rows)
        let summary = out.join(SUMMARY);
        match std::fs::remove_file(&summary) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(OutputError::Io { path: summary, source: e }.into());
            }
            _ => {}
        }
        let path = out.join(PLAN);
        let text = serde_json::to_string_pretty(self)
            .map_err(|e| BatchError::Plan { path: path.clone(), reason: e.to_string() })?;
        Ok(write_atomic(&path, format!("{text}\n").as_bytes())?)
    }
}

/// `case` with its clip file replaced by `recording`.
pub fn with_recording(case: &Case, recording: &Path) -> Result<Case, BatchError> {
    let mut c = case.clone();
    match &mut c.analysis {
        Analysis::Inverse(s) => match &mut s.data {
            DataSource::Clip(clip) => clip.file = recording.to_path_buf(),
            DataSource::Forward(_) => return Err(BatchError::NotAClip(case.name.clone())),
        },
        _ => return Err(BatchError::NotAClip(case.name.clone())),
    }
    Ok(c)
}

/// The `run.json` of a recording's folder: the case file and its hash, the recording and its
/// truth sidecar with theirs.
fn recording_manifest(
    case: &Case,
    case_file: &InputFile,
    recording: &Path,
    format: OutputFormat,
) -> Result<Manifest, FolderError> {
    // the format is part of the command, so that a complete run in the other format is not
    // taken for this one's
    let mut m = Manifest::new(match format {
        OutputFormat::Csv => "batch",
        OutputFormat::Compact => "batch --output-format compact",
    });
    m.input.case_name = Some(case.name.clone());
    m.input.case = Some(case_file.clone());
    m.input.inputs.push(input_file_as(recording, "recording")?);
    let sidecar = truth_sidecar(recording);
    if sidecar.is_file() {
        m.input.inputs.push(input_file_as(&sidecar, "ground-truth sidecar")?);
    }
    m.input.engine = Some(Engine::Rust.to_string());
    m.frames.frames_done = Some(0);
    Ok(m)
}

/// The row of a complete run of the same case and inputs in `dir`, if there is one.
fn complete_row(dir: &Path, wanted: &Manifest) -> Option<BatchRow> {
    let m = Manifest::read(dir).ok()??;
    let hashes = |m: &Manifest| m.input.inputs.iter().map(|f| f.sha256.clone()).collect::<Vec<_>>();
    let same = m.status.is_complete()
        && m.writer.command == wanted.writer.command
        && m.writer.version == wanted.writer.version
        && m.input.case.as_ref().map(|c| &c.sha256) == wanted.input.case.as_ref().map(|c| &c.sha256)
        && hashes(&m) == hashes(wanted);
    if !same {
        return None;
    }
    serde_json::from_slice(&std::fs::read(dir.join(ROW)).ok()?).ok()
}

/// The reason of a recording not started because a stop was requested.
pub const NOT_STARTED: &str = "not started: a stop was requested before its turn";

/// How [`run_recording`] ended.
pub struct Ran {
    pub row: BatchRow,
    /// a complete run was found and not run again
    pub skipped: bool,
}

/// Run `case` (its file hashed in `case_file`) on the recording of `entry` into
/// `out/entry.folder`, or read its row back when that folder holds a complete run of the same
/// case and recording. Never fails as a whole: a failure is the row's.
pub fn run_recording(case: &Case, case_file: &InputFile, entry: &PlanEntry, out: &Path, opts: RecordingOptions) -> Ran {
    let start = Instant::now();
    let dir = out.join(&entry.folder);
    let failed = |reason: String| Ran {
        row: BatchRow {
            wall_time_s: start.elapsed().as_secs_f64(),
            ..BatchRow::without_result(entry, Some(Outcome::Failed), reason)
        },
        skipped: false,
    };
    let manifest = match recording_manifest(case, case_file, &entry.path, opts.format) {
        Ok(m) => m,
        Err(e) => return failed(chain(&e)),
    };
    if let Some(row) = complete_row(&dir, &manifest) {
        return Ran { row, skipped: true };
    }
    if crate::interrupt::requested() {
        let row = BatchRow::without_result(entry, Some(Outcome::Interrupted), NOT_STARTED.into());
        return Ran { row, skipped: false };
    }
    let case = match with_recording(case, &entry.path) {
        Ok(c) => c,
        Err(e) => return failed(chain(&e)),
    };
    // rod.length_m = "from_data": this recording's body length
    let case = match crate::engine::input::resolve::resolve_recording(&case) {
        Ok(c) => c,
        Err(e) => return failed(chain(&e)),
    };
    let (mut folder, resume) = match begin_recording(&dir, manifest, opts) {
        Ok(f) => f,
        Err(e) => return failed(chain(&e)),
    };
    let clip = ClipOptions { journal: true, resume, format: opts.format };
    let solved = solve_into(&case, Engine::Rust, folder.dir(), clip, |_| {}, |_, _| {});
    folder.manifest.frames.frames_done = solved.frames.map(|f| f.0);
    folder.manifest.frames.frames_total = solved.frames.map(|f| f.1);
    if solved.disk_full {
        return failed(stopped_by_full_disk(folder, &dir, solved.frames, solved.error));
    }
    let mut row = result_row(&case, entry, &solved, start);
    folder.manifest.weights = solved.clip.as_ref().and_then(|c| c.weights);
    folder.manifest.certificate = solved.certificate(&case);
    folder.manifest.recording = solved.recording_notes(&case);
    let written = serde_json::to_vec_pretty(&row)
        .map_err(|e| OutputError::Invalid { path: folder.dir().join(ROW), reason: e.to_string() })
        .and_then(|bytes| write_atomic(&folder.dir().join(ROW), &bytes));
    let (status, message) = match written {
        Ok(()) => (solved.status.into(), solved.error),
        Err(e) => (Status::Failed, Some(chain(&e))),
    };
    match folder.finish(status, message.clone()) {
        Err(e) => return failed(chain(&e)),
        Ok(placed @ Placed::Beside { .. }) => {
            row.reason = Some(format!("{}{}", row.reason.unwrap_or_default(), placed.kept_text(NEXT_BATCH)));
        }
        Ok(Placed::InPlace(_)) if status == Status::Failed && row.frames.is_some_and(|n| n > 0) => {
            let n = row.frames.unwrap_or(0);
            let kept = format!("; the {n} converged frames before it are in {}", dir.display());
            row.reason = Some(format!("{}{kept}", row.reason.unwrap_or_default()));
        }
        Ok(Placed::InPlace(_)) => {}
    }
    match status {
        Status::Failed if row.is_ok() => failed(message.unwrap_or_default()),
        _ => Ran { row, skipped: false },
    }
}

/// What continues a recording's run kept beside its folder.
const NEXT_BATCH: &str = "(the next batch of this case continues it; `--force` lets a batch replace a complete run)";

/// How [`run_batch`] runs a plan: on `jobs` threads (`--jobs`; 0: one per core; at most the
/// recordings and [`super::MAX_JOBS`]), each recording with `force` ([`RecordingOptions`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct BatchOptions {
    pub jobs: usize,
    pub force: bool,
}

/// How [`run_recording`] runs a recording.
#[derive(Clone, Copy, Debug, Default)]
pub struct RecordingOptions {
    /// how its per-node fields are written
    pub format: OutputFormat,
    /// `--force`: its run replaces a complete run of its folder even if it fails or is
    /// interrupted (`RunFolder::finish`)
    pub force: bool,
}

/// Claim the folder `dir` of a recording: continuing the run of the same case and recording
/// kept beside it (killed, stopped by a full disk, or stopped beside a complete run), if there
/// is one (`true`), else fresh; `opts.force` (`--force`): always fresh.
fn begin_recording(dir: &Path, manifest: Manifest, opts: RecordingOptions) -> Result<(RunFolder, bool), FolderError> {
    if !opts.force && resumable_beside(dir, &manifest) {
        match RunFolder::begin(dir, manifest.clone(), Mode::Resume) {
            Ok(f) => return Ok((f, true)),
            Err(FolderError::CannotResume { .. }) => {}
            Err(e) => return Err(e),
        }
    }
    Ok((RunFolder::begin(dir, manifest, Mode::Fresh { force: opts.force })?, false))
}

/// A recording's run stopped by a full disk: its folder `dir` is left as it was; its converged
/// frames (`frames`) stay in its staging folder, which the next batch continues, or, without
/// any, that folder goes (freeing its space). The reason of its row.
fn stopped_by_full_disk(
    folder: RunFolder,
    dir: &Path,
    frames: Option<(usize, usize)>,
    error: Option<String>,
) -> String {
    let full = format!("{}: {}", crate::io::disk::full_text(dir), error.unwrap_or_default());
    let kept = match frames {
        Some((n, _)) if n > 0 => {
            let staging = folder.keep_staging(Status::Failed, Some(full.clone()));
            format!(
                "the {n} converged frames are kept in {}: the next batch continues from them once there is space (or remove that folder to free its space)",
                staging.display()
            )
        }
        _ => {
            folder.abandon();
            "nothing of this run was kept (its staging folder is removed)".into()
        }
    };
    format!("{full}; {} is left as it was; {kept}", dir.display())
}

/// The summary row of a recording's run (`solved`), begun at `start`.
fn result_row(case: &Case, entry: &PlanEntry, solved: &super::solved::Solved, start: Instant) -> BatchRow {
    let metrics = solved.clip.as_ref().filter(|c| !c.reports.is_empty()).map(|c| clip_metrics(case, c));
    let get = |k: Metric| metrics.as_ref().and_then(|m| m.get(k));
    let weights = solved.clip.as_ref().and_then(|c| c.weights);
    BatchRow {
        recording: entry.path.display().to_string(),
        folder: entry.folder.clone(),
        status: Some(solved.status),
        frames: solved.frames.map(|f| f.0),
        newton_iterations_per_frame: get(Metric::IterationsMean),
        certificate_max: get(Metric::Certificate),
        fit_position_rel_length_max: get(Metric::FitPositionRelLengthMax),
        curvature_err_rel_max: get(Metric::TruthBendingErrRelMax),
        noise_m: weights.map(|w| w.noise_m),
        lambda_g: weights.map(|w| w.lambda_g),
        length_m: Some(case.mesh.length_m),
        length_spread_rel: case.body_length().map(|b| b.spread_rel),
        reason: solved.error.clone(),
        wall_time_s: start.elapsed().as_secs_f64(),
    }
}

/// The case of a plan, and its file with its hash.
pub fn plan_case(plan: &Plan) -> Result<(Case, InputFile), BatchError> {
    let case = Case::from_file(&plan.case)?;
    if case.clip().is_none() {
        return Err(BatchError::NotAClip(case.name.clone()));
    }
    let sha256 = sha256_file(&plan.case).map_err(read_err(&plan.case))?;
    Ok((case, InputFile { path: plan.case.display().to_string(), sha256 }))
}

/// Which recordings of the plan in `out` hold a complete run of the same case and recording
/// (and are skipped when run again), in the plan's order.
pub fn complete_recordings(plan: &Plan, out: &Path) -> Result<Vec<bool>, BatchError> {
    let (case, case_file) = plan_case(plan)?;
    Ok(plan
        .recordings
        .iter()
        .map(|e| {
            recording_manifest(&case, &case_file, &e.path, plan.format)
                .is_ok_and(|m| complete_row(&out.join(&e.folder), &m).is_some())
        })
        .collect())
}

/// The Slurm array tasks of the plan that have a recording to run (`complete`: as
/// [`complete_recordings`] says).
pub fn unfinished_tasks(plan: &Plan, complete: &[bool]) -> Vec<usize> {
    (0..plan.tasks()).filter(|&t| complete.chunks(plan.per_task).nth(t).is_some_and(|c| c.iter().any(|d| !d))).collect()
}

/// Run every recording of the plan in `out` as `opts` says ([`BatchOptions`]), then write
/// `summary.csv`; `tick` after each recording that ran to its end (not after one a stop request
/// stopped or kept from starting). Rows in the plan's order.
pub fn run_batch(plan: &Plan, out: &Path, opts: BatchOptions, tick: impl Fn() + Sync) -> Result<Vec<Ran>, BatchError> {
    use rayon::prelude::*;
    let (case, case_file) = plan_case(plan)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(super::threads_for(opts.jobs, plan.recordings.len()))
        .build()
        .map_err(|e| BatchError::Pool(e.to_string()))?;
    let ran: Vec<Ran> = pool.install(|| {
        plan.recordings
            .par_iter()
            .map(|entry| {
                let r = run_recording(
                    &case,
                    &case_file,
                    entry,
                    out,
                    RecordingOptions { format: plan.format, force: opts.force },
                );
                // a recording stopped (or never started) by a stop request is not done
                if r.row.status != Some(crate::solve::Outcome::Interrupted) {
                    tick();
                }
                r
            })
            .collect()
    });
    let rows: Vec<BatchRow> = ran.iter().map(|r| r.row.clone()).collect();
    // what killed runs left (their locks, staging folders, temporary files); the work of a
    // recording not complete stays for the next batch to continue
    let unfinished = |name: &str| rows.iter().any(|r| r.folder == name && !r.is_ok());
    crate::output::tidy::clear_ended(out, unfinished)?;
    write_summary(out, &rows)?;
    Ok(ran)
}

/// The rows of the plan in `out` from its recordings' folders (`missing` where a folder holds
/// no row), and `summary.csv` written from them, after clearing what ended runs left
/// (`output::tidy`; a live task's files stay).
pub fn gather(out: &Path) -> Result<Vec<BatchRow>, BatchError> {
    let plan = Plan::read(out)?;
    let rows: Vec<BatchRow> = plan
        .recordings
        .iter()
        .map(|e| {
            let path = out.join(&e.folder).join(ROW);
            match std::fs::read(&path).ok().and_then(|b| serde_json::from_slice::<BatchRow>(&b).ok()) {
                Some(row) => row,
                None => BatchRow::without_result(
                    e,
                    None,
                    format!("{} holds no result: its task has not run, or stopped (see slurm/)", path.display()),
                ),
            }
        })
        .collect();
    // as at a batch's end: what ended runs left (a Slurm batch's tasks, a killed batch), the
    // work of a recording not complete kept for the next batch
    let unfinished = |name: &str| rows.iter().any(|r| r.folder == name && !r.is_ok());
    crate::output::tidy::clear_ended(out, unfinished)?;
    write_summary(out, &rows)?;
    Ok(rows)
}

/// Write `out/summary.csv` (atomically).
pub fn write_summary(out: &Path, rows: &[BatchRow]) -> Result<(), BatchError> {
    let path = out.join(SUMMARY);
    let text = summary_csv(rows).map_err(|e| OutputError::Invalid { path: path.clone(), reason: e.to_string() })?;
    Ok(write_atomic(&path, text.as_bytes())?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folder_names_are_distinct() {
        let p = |s: &str| PathBuf::from(s);
        let names = folder_names(&[p("/a/w 1.csv"), p("/b/w 1.npy"), p("/a/x.npy"), p("/c/W 1.npy"), p("/d/.npy")]);
        assert_eq!(names, ["w_1", "w_1-2", "x", "W_1-3", "rec.npy"]);
    }

    #[test]
    fn summary_columns_and_a_missing_row() {
        let entry = PlanEntry { path: PathBuf::from("/r/a.npy"), folder: "a".into() };
        let row = BatchRow::without_result(&entry, None, "no\nresult".into());
        let text = summary_csv(&[row]).unwrap();
        assert_eq!(
            text,
            "recording,folder,status,frames,newton_iterations_per_frame,certificate_max,fit_position_rel_length_max,curvature_err_rel_max,length_m,length_spread_rel,noise_m,lambda_g,reason,wall_time_s\n/r/a.npy,a,missing,,,,,,,,,,no result,0.000\n"
        );
    }

    #[test]
    fn plan_tasks_are_chunks() {
        let recs: Vec<PathBuf> = (0..5).map(|k| PathBuf::from(format!("/r/{k}.npy"))).collect();
        let plan = Plan::new(Path::new("/c.toml"), &recs, 2);
        assert_eq!(plan.tasks(), 3);
        assert_eq!(plan.task(2).unwrap().len(), 1);
        assert!(plan.task(3).unwrap_err().to_string().contains("0 to 2"));
    }
}
