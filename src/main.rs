//! `cosserat` command-line interface (thin: parsing, progress and printing only).
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

use cosserat::case::Case;
use cosserat::io::compact::OutputFormat;
use cosserat::io::job::{case_label, run_into, run_manifest};
use cosserat::io::run_folder::{input_file, Manifest, Mode, RunFolder, Status};
use cosserat::io::sweep::RunStatus;
use cosserat::run::budget::{self, default_limit_bytes, Footprint, GIB};
use cosserat::run::Engine;
use cosserat::solve::modes::modal_model;

mod cli;

use cli::progress::{FreefemProgress, Progress};

/// Forward Cosserat rods after Wang et al. (Comput. Mech. 71, 2023), in Rust and FreeFEM.
#[derive(Parser, Debug)]
#[command(name = "cosserat", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a case and write fields (CSV), metrics.json and plot.svg.
    Run {
        /// Case file (TOML), e.g. cases/timoshenko_10pct.toml
        case: PathBuf,
        /// Which engine to run
        #[arg(long, value_enum, default_value_t = Engine::Rust)]
        engine: Engine,
        /// Output directory [default: out/<case name>/<engine>]. The run writes into a staging
        /// folder beside it that replaces it whole at the end; run.json says what it holds
        #[arg(long)]
        out: Option<PathBuf>,
        /// Replace the output directory even if it holds files but no run.json
        #[arg(long)]
        force: bool,
        /// Continue the interrupted, failed or killed clip of the output directory from its
        /// last converged frame (same case file and clip file), in a staging folder of its own;
        /// the CSVs are then byte for byte those of an uninterrupted run
        #[arg(long, conflicts_with = "force")]
        resume: bool,
        /// Clips: per-node fields as CSV + ParaView VTK, or all in one fields.npz (docs/output.md)
        #[arg(long, value_enum, default_value_t = OutputFormat::Csv)]
        output_format: OutputFormat,
        #[command(flatten)]
        limits: Limits,
        /// Do not show progress (a bar on a terminal, else a line every 10 s)
        #[arg(long)]
        quiet: bool,
        /// Clips: exit with status 1 when frames are over the fit-quality gate (run.json then
        /// says complete_with_warnings either way)
        #[arg(long)]
        strict: bool,
    },
    /// Run both engines and compare them; exit status 1 if any row fails.
    ///
    /// Newton runs are compared at their roots, an inverse fixed point at the same iteration
    /// (FreeFEM runs exactly the iterations Rust needed), a clip frame by frame over its first
    /// frames. Each tolerance is derived from the case's conditioning: the Rust engine runs the
    /// case again with its input perturbed by 1e-13 (relative), and a row passes when the
    /// engines differ by less than 10 x (that change + the solver tolerance) + 1e-12. Values in
    /// the case's [compare] table override them (with a `reason`). Writes compare.csv, the
    /// engines' outputs (single runs) and FreeFEM's work folder to --out.
    Compare {
        /// Case file (TOML)
        case: PathBuf,
        /// Directory for both engines' outputs [default: out/<case name>]
        #[arg(long)]
        out: Option<PathBuf>,
        /// Short horizon: 200 time steps, 40 fixed-point iterations, 3 clip frames
        #[arg(long)]
        short: bool,
        /// Clip cases: frames to compare, a number or `all` [default: the case's
        /// `[compare] frames`, 10]
        #[arg(long, value_parser = cli::parse_frames)]
        frames: Option<usize>,
        /// Replace the output directory even if it holds files but no run.json
        #[arg(long)]
        force: bool,
        #[command(flatten)]
        limits: Limits,
    },
    /// Run a case for every point of a parameter grid (in parallel) and summarise.
    ///
    /// Writes one folder per run (the files of `run`), `summary.csv` (one row per run: the swept
    /// values, status, iterations, recovery errors, objective, wall time, error message) and
    /// `convergence.svg` (log-log histories, one curve per run; Figs. 9-11 of the paper). A run
    /// that reaches its iteration limit is `not_converged`: its folder holds the last iterate
    /// with a run.json saying failed, and its curve is plotted. A clip case solves its whole clip for every
    /// point (the folder holds the files of `run` on the clip; the summary has one row per
    /// point: frames, iterations, worst fit, tangent misfit, |j - 1|, objective). Exit status 1
    /// if any run failed or did not converge (after writing everything).
    Sweep {
        /// Case file (TOML)
        case: PathBuf,
        /// Parameter and values, e.g. `--set lambda_d=1e-6,1e-4`; repeat for a cartesian
        /// product. Each value is set in the case file's table and the case validated again.
        /// Inverse cases: lambda_g, lambda_f, lambda_l, lambda_d, lambda_kappa1..3,
        /// lambda_omega1..3, relaxation, warm_start_tolerance, tolerance, max_iterations,
        /// elements, stabilisation. Static: relaxation, tolerance, max_iterations,
        /// continuation_steps, elements. Dynamic: tolerance, max_iterations, steps, elements
        #[arg(long = "set", value_name = "KEY=V1,V2,...", required = true)]
        set: Vec<String>,
        /// Output directory [default: out/<case name>/sweep]
        #[arg(long)]
        out: Option<PathBuf>,
        /// Replace the output directory even if it holds files but no run.json
        #[arg(long)]
        force: bool,
        #[command(flatten)]
        limits: Limits,
        /// Parallel runs [default: number of cores]
        #[arg(long)]
        jobs: Option<usize>,
        /// Do not show progress (a bar on a terminal, else a line every 10 s)
        #[arg(long)]
        quiet: bool,
    },
    /// Audit the paper: regenerate its figures and judge its claims (§5-6).
    ///
    /// Reads the audit specs (default: every *.toml of cases/paper/), runs every point of every
    /// run in parallel (one folder per point, the files of `run`/`sweep`), draws the paper's
    /// figures and writes REPORT.md (one row per claim: the paper's words and number, ours, the
    /// verdict - reproduced, differs, refuted, not computable here - and its cause) and
    /// report.csv. `--quick` runs the specs' short grids and clip excerpts (the subset asserted by
    /// `cargo test`). Exit status 1 if a claim's verdict is not the one its spec expects (the
    /// report is written first).
    Audit {
        /// Audit specs (TOML) or folders of them [default: cases/paper]
        specs: Vec<PathBuf>,
        /// Short grids and clip excerpts (`quick_grid`, `quick_set` of the specs)
        #[arg(long)]
        quick: bool,
        /// Output directory [default: out/audit, out/audit-quick with --quick]; replaced whole
        #[arg(long)]
        out: Option<PathBuf>,
        /// Replace the output directory even if it holds files but no run.json
        #[arg(long)]
        force: bool,
        /// Parallel runs [default: number of cores]
        #[arg(long)]
        jobs: Option<usize>,
        /// Do not show progress (a bar on a terminal, else a line every 10 s)
        #[arg(long)]
        quiet: bool,
        /// Clip points keep compact fields.npz and figures [default: tables only, ≤ 200 MB]
        #[arg(long, conflicts_with = "vtk")]
        fields: bool,
        /// Clip points keep fields.csv, curvature.csv, VTK and figures (GBs for the full audit)
        #[arg(long)]
        vtk: bool,
        /// Continue the unfinished audit of --out: keep the specs it judged whole, rerun the rest
        #[arg(long, conflicts_with = "force")]
        resume: bool,
    },
    /// Run a clip case over many recordings (here, or as a Slurm job array with --slurm).
    Batch(cli::BatchArgs),
    /// Run one task of a batch's Slurm job array (called by the job script).
    #[command(hide = true)]
    BatchTask(cli::TaskArgs),
    /// Write OUT/summary.csv from the recordings' folders of a batch (after a Slurm job array).
    Gather {
        /// Output folder of the batch (`--out` of `cosserat batch`: holds batch.json and one
        /// folder per recording); summary.csv is written there
        out: PathBuf,
    },
    /// Write a corpus of synthetic 3D recordings with their ground truth.
    Synth(cli::synth::SynthArgs),
    /// Reconstruct synthetic recordings at several noise levels beside a smoothing spline.
    NoiseStudy(cli::noise_study::NoiseStudyArgs),
    /// List the cases of a directory with their descriptions.
    List {
        /// Directory holding *.toml case files
        #[arg(default_value = "cases")]
        dir: PathBuf,
    },
    /// Natural frequencies of the rod linearised about its rest state (clamped at s = 0).
    Modes {
        /// Case file (TOML); loads and time settings are ignored
        case: PathBuf,
        /// How many modes to print (at least 1)
        #[arg(long, default_value_t = 10, allow_hyphen_values = true, value_parser = cli::parse_count)]
        count: usize,
        #[command(flatten)]
        limits: Limits,
    },
}

/// Resource limits of a run.
#[derive(clap::Args, Debug, Clone, Copy)]
struct Limits {
    /// Refuse a run whose estimated memory exceeds this [GiB] [default: half the machine's
    /// memory]
    #[arg(long, value_name = "GIB")]
    max_memory_gib: Option<f64>,
}

/// Exit status of a run stopped by SIGINT/SIGTERM (128 + SIGINT, the shell's convention).
const EXIT_INTERRUPTED: u8 = 130;

/// SIGINT/SIGTERM/SIGHUP: the first asks the running loops to stop after the current frame
/// (time step, iteration) so that the files stay consistent; a second one exits at once.
fn install_signal_handler() {
    let result = ctrlc::set_handler(|| {
        if cosserat::interrupt::requested() {
            eprintln!("\nsecond signal: exiting at once (the output folder keeps its previous state)");
            std::process::exit(i32::from(EXIT_INTERRUPTED));
        }
        cosserat::interrupt::request();
        eprintln!("\nsignal received: stopping after the current frame / step (again to exit at once)");
    });
    if let Err(e) = result {
        eprintln!("warning: cannot handle SIGINT/SIGTERM ({e}); an interrupted run will not be marked");
    }
}

/// A failed allocation ends the process with a message and status 1, not an abort.
#[global_allocator]
static ALLOCATOR: cli::alloc::Guarded = cli::alloc::Guarded;

fn main() -> ExitCode {
    cli::alloc::at_start();
    cli::keep_freed_memory();
    let cli = Cli::parse();
    install_signal_handler();
    match dispatch(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(1)
        }
    }
}

fn dispatch(cli: Cli) -> Result<ExitCode> {
    match cli.command {
        Command::Run { case, engine, out, force, resume, output_format, limits, quiet, strict } => {
            let mode = if resume { Mode::Resume } else { Mode::Fresh { force } };
            cmd_run(&case, engine, out, (mode, output_format), limits, (quiet, strict))
        }
        Command::Compare { case, out, short, frames, force, limits } => {
            cmd_compare(&case, out, short, frames, force, limits)
        }
        Command::Sweep { case, set, out, force, limits, jobs, quiet } => {
            cmd_sweep(&case, &set, out, force, limits, jobs, quiet)
        }
        Command::Audit { specs, quick, out, force, jobs, quiet, fields, vtk, resume } => {
            let fields = cosserat::audit::PointFields::from_flags(fields, vtk);
            cmd_audit(&specs, quick, out, (!resume).then_some(force), jobs, quiet, fields)
        }
        Command::Batch(a) => cli::cmd_batch(a),
        Command::BatchTask(a) => cli::cmd_batch_task(a),
        Command::Gather { out } => cli::cmd_gather(&out),
        Command::Synth(a) => cli::synth::cmd_synth(a),
        Command::NoiseStudy(a) => cli::noise_study::cmd_noise_study(a),
        Command::List { dir } => cli::list::cmd_list(&dir),
        Command::Modes { case, count, limits } => cmd_modes(&case, count, limits),
    }
}

/// The case of `path`, its `rod.length_m = "from_data"` resolved from its recording.
fn load(path: &Path) -> Result<Case> {
    Ok(cosserat::io::clip_files::resolve_length(&Case::from_file(path)?)?)
}

/// Refuse a run whose estimated memory exceeds the limit (`--max-memory-gib`).
fn check_memory(case: &Case, what: Footprint, limits: Limits) -> Result<()> {
    let limit = limits.max_memory_gib.map(|g| g * GIB).unwrap_or_else(default_limit_bytes);
    Ok(budget::check(case, what, limit)?)
}

fn cmd_run(
    path: &Path,
    engine: Engine,
    out: Option<PathBuf>,
    mode: (Mode, OutputFormat),
    limits: Limits,
    (quiet, strict): (bool, bool),
) -> Result<ExitCode> {
    let case = load(path)?;
    check_memory(&case, Footprint::Run, limits)?;
    let dir = out.unwrap_or_else(|| PathBuf::from("out").join(&case.name).join(engine.to_string()));
    let pb = Progress::new(&format!("{} [{engine}]", case.name), cli::outcome::progress_unit(&case, engine), 0, quiet);
    if engine == Engine::Freefem && !quiet {
        eprintln!("{} [freefem]: running FreeFEM in a staging folder beside {}", case.name, dir.display());
    }
    let end = run_into(&case, engine, &dir, mode, |done, total| pb.set(done, total))
        .with_context(|| format!("{}: output folder {}", case_label(&case), dir.display()))?;
    pb.finish();
    for n in &end.notes {
        eprintln!("note: {n}");
    }
    cli::outcome::run_end(end, (&case, engine), path, &dir, strict)
}

fn cmd_compare(
    path: &Path,
    out: Option<PathBuf>,
    short: bool,
    frames: Option<usize>,
    force: bool,
    limits: Limits,
) -> Result<ExitCode> {
    use cosserat::io::compare::default_dir;
    let case = load(path)?;
    check_memory(&case, Footprint::Run, limits)?;
    let target = out.unwrap_or_else(|| default_dir(&case));
    let mut manifest = run_manifest(&case, Engine::Rust)?;
    manifest.writer.command = "compare".into();
    manifest.input.engine = Some("rust and freefem".into());
    let folder = RunFolder::begin(&target, manifest, Mode::Fresh { force })
        .with_context(|| format!("{}: output folder {}", case_label(&case), target.display()))?;
    for n in &folder.notes {
        eprintln!("note: {n}");
    }
    // FreeFEM's frames (a clip) or time steps (a dynamic case) as it runs: a bar on a terminal,
    // elsewhere a line every 10 s and a final line. Other cases: without a terminal, a line
    // every 10 s says the comparison is still running.
    let counted = case.clip().is_some() || matches!(case.analysis, cosserat::case::Analysis::Dynamic(_));
    let on_terminal = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let pb = Progress::new(&format!("{} compare", case.name), "", 0, on_terminal || counted);
    let freefem = FreefemProgress::start(&format!("{} FreeFEM", case.name));
    let result = compare_into(&case, folder.dir(), &target, short, frames);
    freefem.finish();
    pb.finish();
    let (status, message) = match &result {
        Ok(_) => (Status::Complete, None),
        Err(_) if cosserat::interrupt::requested() => (Status::Interrupted, Some("interrupted by a signal".into())),
        Err(e) => (Status::Failed, Some(format!("{e:#}"))),
    };
    folder.finish(status, message)?;
    match (status, result) {
        (Status::Interrupted, _) => {
            eprintln!("{}: interrupted; {} holds run.json saying interrupted", case.name, target.display());
            Ok(ExitCode::from(EXIT_INTERRUPTED))
        }
        (_, Err(e)) => Err(e.context(format!("{} holds run.json saying failed", target.display()))),
        (_, Ok(code)) => Ok(code),
    }
}

/// Both engines on `case` and their comparison, written into `dir` (the staging folder).
fn compare_into(case: &Case, dir: &Path, target: &Path, short: bool, frames: Option<usize>) -> Result<ExitCode> {
    use cosserat::io::compare::{compare_case, report_table, write_compare, CompareOptions, Horizon};
    let opts = CompareOptions { horizon: if short { Horizon::Short } else { Horizon::Full }, frames };
    eprintln!(
        "{}: rust engine (twice: as given and with its input perturbed by 1e-13), then FreeFEM in {}",
        case.name,
        target.join("freefem_work").display()
    );
    let report = compare_case(case, dir, &opts).with_context(|| case_label(case))?;
    write_compare(case, &report, dir)?;
    print!("{}", report_table(case, &report));
    println!("wrote {}", target.join("compare.csv").display());
    let failed = report.failed();
    if failed > 0 {
        eprintln!("{}: {failed} of {} rows FAILED", case.name, report.rows.len());
    }
    Ok(if failed == 0 { ExitCode::SUCCESS } else { ExitCode::from(1) })
}

#[allow(clippy::too_many_arguments)]
fn cmd_sweep(
    path: &Path,
    set: &[String],
    out: Option<PathBuf>,
    force: bool,
    limits: Limits,
    jobs: Option<usize>,
    quiet: bool,
) -> Result<ExitCode> {
    use cosserat::case::sweep::{parse_set, product};
    use cosserat::io::sweep::sweep_into;
    let case = load(path)?;
    let params = set.iter().map(|s| parse_set(s)).collect::<Result<Vec<_>, _>>()?;
    let points = product(&case, &params)?;
    for (_, c) in &points {
        check_memory(c, Footprint::Run, limits).with_context(|| format!("sweep point {}", c.name))?;
    }
    let target = out.unwrap_or_else(|| PathBuf::from("out").join(&case.name).join("sweep"));
    let mut manifest = run_manifest(&case, Engine::Rust)?;
    manifest.writer.command = "sweep".into();
    let folder = RunFolder::begin(&target, manifest, Mode::Fresh { force })
        .with_context(|| format!("{}: output folder {}", case_label(&case), target.display()))?;
    for n in &folder.notes {
        eprintln!("note: {n}");
    }
    let pb = Progress::new(&format!("{} sweep", case.name), "points", points.len(), quiet);
    let keys: Vec<String> = params.iter().map(|p| p.key.clone()).collect();
    let result = sweep_into(&case, &keys, &points, folder.dir(), jobs.unwrap_or(0), || pb.inc());
    pb.finish();
    let rows = match result {
        Ok(rows) => rows,
        Err(e) if cosserat::io::disk::is_full(&e) => {
            folder.abandon();
            anyhow::bail!("{}: sweep: {}", case_label(&case), cli::outcome::disk_full_text(&e, &target, "sweep"));
        }
        Err(e) => {
            let message = cosserat::io::sweep::chain(&e);
            folder.finish(Status::Failed, Some(message.clone()))?;
            anyhow::bail!("{}: sweep: {message}; {} holds run.json saying failed", case_label(&case), target.display());
        }
    };
    let count = |s: RunStatus| rows.iter().filter(|r| r.status == s).count();
    let complete = rows.iter().filter(|r| r.status.is_complete()).count();
    let (interrupted, failed) = (count(RunStatus::Interrupted), rows.len() - complete);
    let status = if interrupted > 0 {
        Status::Interrupted
    } else if failed > 0 {
        Status::Failed
    } else {
        Status::Complete
    };
    let message = (failed > 0).then(|| {
        format!("{failed} of {} points failed, did not converge or were interrupted (summary.csv)", rows.len())
    });
    folder.finish(status, message)?;
    println!(
        "{}: {} runs, {} failed or not converged, {interrupted} interrupted; wrote {} and one folder per run to {}",
        case.name,
        rows.len(),
        failed - interrupted,
        target.join("summary.csv").display(),
        target.display()
    );
    for r in rows.iter().filter(|r| r.error.as_deref() != Some(cosserat::io::sweep::NOT_STARTED)) {
        if let Some(e) = &r.error {
            eprintln!("  {}: {}: {e}", r.name, r.status.as_str());
        }
    }
    if interrupted > 0 {
        eprintln!("{}", cli::outcome::sweep_interrupted_summary(&rows, &target));
    }
    Ok(if interrupted > 0 {
        ExitCode::from(EXIT_INTERRUPTED)
    } else if failed == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

fn cmd_audit(
    paths: &[PathBuf],
    quick: bool,
    out: Option<PathBuf>,
    force: Option<bool>,
    jobs: Option<usize>,
    quiet: bool,
    fields: cosserat::audit::PointFields,
) -> Result<ExitCode> {
    use cosserat::audit::{run_audit, spec::read_spec, spec_files, AuditOptions, AuditStatus, Verdict};
    let default = [PathBuf::from("cases/paper")];
    let mut files = Vec::new();
    for p in if paths.is_empty() { &default[..] } else { paths } {
        if p.is_dir() {
            files.extend(spec_files(p)?);
        } else {
            files.push(p.clone());
        }
    }
    if files.is_empty() {
        let given: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
        anyhow::bail!(
            "no audit specs (*.toml) in {}",
            if given.is_empty() { "cases/paper".to_string() } else { given.join(", ") }
        );
    }
    let specs = files.iter().map(|f| read_spec(f, quick)).collect::<Result<Vec<_>, _>>()?;
    let out = out.unwrap_or_else(|| PathBuf::from(if quick { "out/audit-quick" } else { "out/audit" }));
    // an audit folder of an older version carries the audit's marker instead of run.json
    let marker = out.join(cosserat::audit::MARKER).is_file();
    let mode = force.map_or(Mode::Resume, |f| Mode::Fresh { force: f || marker });
    let mut manifest = Manifest::new("audit");
    manifest.input.inputs = files.iter().map(|f| input_file(f)).collect::<Result<_, _>>()?;
    manifest.input.settings.insert("quick".into(), f64::from(u8::from(quick)).into());
    let resume = force.is_none();
    let folder =
        RunFolder::begin(&out, manifest, mode).with_context(|| format!("audit: output folder {}", out.display()))?;
    let pb = Progress::new(if quick { "audit (quick)" } else { "audit" }, "points", 0, quiet);
    let opts = AuditOptions { out: folder.dir().to_path_buf(), jobs: jobs.unwrap_or(0), fields, resume };
    let points = std::sync::atomic::AtomicUsize::new(0);
    let report = run_audit(&specs, quick, &opts, |done, total| {
        points.store(total, std::sync::atomic::Ordering::SeqCst);
        pb.set(done, total);
    });
    pb.finish();
    let report = match report {
        Ok(r) => r,
        Err(e) => {
            let message = format!("{:#}", anyhow::Error::from(e));
            folder.finish(Status::Failed, Some(message.clone()))?;
            anyhow::bail!("audit: {message}; {} holds run.json saying failed", out.display());
        }
    };
    let judged = format!("{} of {} claims judged", report.claims.len() - report.unjudged(), report.claims.len());
    match &report.status {
        AuditStatus::Complete => {
            folder.finish(Status::Complete, None)?;
        }
        AuditStatus::Interrupted => {
            let kept = cli::outcome::audit_points_kept(folder.dir(), points.load(std::sync::atomic::Ordering::SeqCst));
            folder.finish(Status::Interrupted, Some(format!("interrupted by a signal: {kept}; {judged}")))?;
            eprintln!(
                "audit interrupted: {kept}; {judged}; REPORT.md is headed interrupted and marks the others not judged; {} holds run.json saying interrupted",
                out.display()
            );
            return Ok(ExitCode::from(EXIT_INTERRUPTED));
        }
        AuditStatus::Failed(errors) => {
            let message = format!("{judged}: {}", errors.join("; "));
            folder.finish(Status::Failed, Some(message.clone()))?;
            anyhow::bail!(
                "audit failed: {message}; REPORT.md is headed failed; {} holds run.json saying failed",
                out.display()
            );
        }
    }
    let counts = report.counts();
    let summary: Vec<String> = Verdict::ALL.iter().zip(counts).map(|(v, n)| format!("{n} {}", v.as_str())).collect();
    let ours = report.claims.iter().filter(|c| c.claim.ours).count();
    println!(
        "{} claims of the paper and {ours} checks of ours in {} specs: {}; {} figures; {:.0} s; {:.1} MB; wrote {}",
        report.claims.len() - ours,
        specs.len(),
        summary.join(", "),
        report.figures.len(),
        report.wall_time_s,
        report.bytes as f64 / 1e6,
        out.join("REPORT.md").display()
    );
    let unexpected: Vec<_> = report.claims.iter().filter(|c| c.verdict != Some(c.claim.expect)).collect();
    for c in &unexpected {
        eprintln!(
            "  {} ({}): {} where the spec expects {}; ours: {}",
            c.claim.id,
            c.spec,
            c.verdict.map_or("not judged", |v| v.as_str()),
            c.claim.expect.as_str(),
            c.ours
        );
    }
    Ok(if unexpected.is_empty() { ExitCode::SUCCESS } else { ExitCode::from(1) })
}

fn cmd_modes(path: &Path, count: usize, limits: Limits) -> Result<ExitCode> {
    let case = load(path)?;
    if !case.density_given() {
        anyhow::bail!(
            "{}: material.density_kg_m3 [kg/m^3] is required by `modes` (the natural frequencies scale as 1/sqrt(density)) and is missing from this case",
            path.display()
        );
    }
    check_memory(&case, Footprint::Modes, limits)?;
    let model = modal_model(&case.problem())?;
    println!(
        "{}: natural frequencies of the linearised rod (clamped at s = 0, {} elements)",
        case.name, case.mesh.elements
    );
    println!("{:>4} {:>16} {:>14}", "mode", "omega_rad_per_s", "f_hz");
    for (i, w) in model.omegas.iter().take(count).enumerate() {
        println!("{:>4} {:>16.6} {:>14.6}", i + 1, w, w / (2.0 * std::f64::consts::PI));
    }
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn cli_is_consistent() {
        Cli::command().debug_assert();
    }
}
