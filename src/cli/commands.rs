//! The commands on one case or one set of specs: `run`, `compare`, `sweep`, `audit` and
//! `modes` (the commands of many recordings are in [`super`]).
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context, Result};

use super::args::{AuditArgs, CompareArgs, Limits, RunArgs, SweepArgs};
use super::progress::{FreefemProgress, Progress, Visibility};
use cosserat::case::Case;
use cosserat::engine::budget::{self, default_limit_bytes, Footprint, GIB};
use cosserat::engine::Engine;
use cosserat::io::compact::OutputFormat;
use cosserat::jobs::job::{case_label, run_into, run_manifest};
use cosserat::output::run_folder::{input_file, Manifest, Mode, Placed, RunFolder, Status};
use cosserat::solve::modes::lowest_modes;
use cosserat::solve::Outcome;

/// The case of `path`, its `rod.length_m = "from_data"` resolved from its recording.
fn load(path: &Path) -> Result<Case> {
    Ok(cosserat::engine::input::resolve::resolve_recording(&Case::from_file(path)?)?)
}

/// Refuse a run whose estimated memory exceeds the limit (`--max-memory-gib`).
fn check_memory(case: &Case, what: Footprint, limits: Limits) -> Result<()> {
    let limit = limits.max_memory_gib.map(|g| g * GIB).unwrap_or_else(default_limit_bytes);
    Ok(budget::check(case, what, limit)?)
}

pub fn cmd_run(args: RunArgs) -> Result<ExitCode> {
    let strictness = args.strictness();
    let RunArgs { case: path, engine, out, force, resume, output_format, limits, quiet, .. } = args;
    let (path, engine) = (path.as_path(), Engine::from(engine));
    let mode = (if resume { Mode::Resume } else { Mode::Fresh { force } }, OutputFormat::from(output_format));
    let case = load(path)?;
    if let Some(why) = cosserat::jobs::solved::unsupported(&case, engine) {
        bail!(why);
    }
    check_memory(&case, Footprint::Run, limits)?;
    let dir = out.unwrap_or_else(|| PathBuf::from("out").join(&case.name).join(engine.to_string()));
    // FreeFEM's frames (a clip) or time steps (a dynamic case) as the script writes them; its other
    // runs show the time elapsed
    let counted = engine == Engine::Freefem
        && (case.clip().is_some() || matches!(case.analysis, cosserat::case::Analysis::Dynamic(_)));
    let label = format!("{} [{engine}]", case.name);
    let shown = Visibility::unless(quiet || counted);
    let pb = Progress::new(&label, super::outcome::progress_unit(&case, engine), 0, shown);
    let freefem = (counted && !quiet).then(|| FreefemProgress::start(&label));
    if engine == Engine::Freefem && !quiet {
        eprintln!("{} [freefem]: running FreeFEM in a staging folder beside {}", case.name, dir.display());
    }
    let end = run_into(&case, engine, &dir, mode, |done, total| pb.set(done, total));
    drop(freefem);
    let end = end.with_context(|| format!("{}: output folder {}", case_label(&case), dir.display()))?;
    pb.finish();
    for n in &end.notes {
        eprintln!("note: {n}");
    }
    super::outcome::run_end(end, (&case, engine), path, &dir, strictness)
}

pub fn cmd_compare(args: CompareArgs) -> Result<ExitCode> {
    use cosserat::jobs::compare::{default_dir, CompareOptions, Horizon};
    let CompareArgs { case: path, out, short, frames, force, limits } = args;
    let opts = CompareOptions { horizon: if short { Horizon::Short } else { Horizon::Full }, frames };
    let case = load(&path)?;
    if let Some(why) = cosserat::engine::published::unavailable(&case) {
        bail!(why);
    }
    check_memory(&case, Footprint::Run, limits)?;
    let target = out.unwrap_or_else(|| default_dir(&case));
    let mut manifest = run_manifest(&case, Engine::Rust)?;
    manifest.writer.command = "compare".into();
    manifest.input.engine = Some("rust and freefem".into());
    let folder = CommandFolder::begin(&target, manifest, Mode::Fresh { force }, &case_label(&case), COMPARE_THEN)?;
    // FreeFEM's frames (a clip) or time steps (a dynamic case) as it runs: a bar on a terminal,
    // elsewhere a line every 10 s and a final line. Other cases: without a terminal, a line
    // every 10 s says the comparison is still running.
    let counted = case.clip().is_some() || matches!(case.analysis, cosserat::case::Analysis::Dynamic(_));
    let on_terminal = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let pb = Progress::new(&format!("{} compare", case.name), "", 0, Visibility::unless(on_terminal || counted));
    let freefem = FreefemProgress::start(&format!("{} FreeFEM", case.name));
    let result = compare_into(&case, folder.dir(), &target, &opts);
    freefem.finish();
    pb.finish();
    let (status, message) = match &result {
        Ok(_) => (Status::Complete, None),
        Err(_) if cosserat::interrupt::requested() => (Status::Interrupted, Some("interrupted by a signal".into())),
        Err(e) => (Status::Failed, Some(format!("{e:#}"))),
    };
    let placed = folder.finish(status, message)?;
    match (status, result) {
        (Status::Interrupted, _) => {
            eprintln!("{}: interrupted; {}", case.name, held(&placed, "interrupted", COMPARE_THEN));
            Ok(ExitCode::from(crate::EXIT_INTERRUPTED))
        }
        (_, Err(e)) => Err(e.context(held(&placed, "failed", COMPARE_THEN))),
        (_, Ok(code)) => Ok(code),
    }
}

/// Both engines on `case` at `opts` and their comparison, written into `dir` (the staging folder).
fn compare_into(
    case: &Case,
    dir: &Path,
    target: &Path,
    opts: &cosserat::jobs::compare::CompareOptions,
) -> Result<ExitCode> {
    use cosserat::jobs::compare::{compare_case, report_table, write_compare};
    eprintln!(
        "{}: rust engine (twice: as given and with its input perturbed by 1e-13), then FreeFEM in {}",
        case.name,
        target.join("freefem_work").display()
    );
    let report = compare_case(case, dir, opts).with_context(|| case_label(case))?;
    write_compare(case, &report, dir)?;
    print!("{}", report_table(case, &report));
    println!("wrote {}", target.join("compare.csv").display());
    let failed = report.failed();
    if failed > 0 {
        eprintln!("{}: {failed} of {} rows FAILED", case.name, report.rows.len());
    }
    let missed = compare_published(case, &report, opts.horizon, dir, target)?;
    Ok(if failed == 0 && missed == 0 { ExitCode::SUCCESS } else { ExitCode::from(1) })
}

/// The published values of `case` in both engines of `report`: their table, `reference.csv`
/// in `dir`; returns how many missed in either engine.
fn compare_published(
    case: &Case,
    report: &cosserat::jobs::compare::CompareReport,
    horizon: cosserat::jobs::compare::Horizon,
    dir: &Path,
    target: &Path,
) -> Result<usize> {
    use cosserat::jobs::compare_published::PublishedComparison;
    let Some(p) = PublishedComparison::of(case, report, horizon).with_context(|| case_label(case))? else {
        return Ok(0);
    };
    cosserat::io::files::write_atomic(&dir.join("reference.csv"), p.csv().as_bytes())?;
    print!("{}", p.table());
    println!("wrote {}", target.join("reference.csv").display());
    let missed = p.missed();
    if missed > 0 {
        eprintln!("{}: {missed} of {} published values MISSED in rust or freefem", case.name, p.rust.len());
    }
    Ok(missed)
}

pub fn cmd_sweep(args: SweepArgs) -> Result<ExitCode> {
    let SweepArgs { case: path, set, out, force, limits, jobs, quiet } = args;
    let path = path.as_path();
    use cosserat::case::sweep::{parse_set, product};
    use cosserat::jobs::sweep::sweep_into;
    let case = load(path)?;
    let params = set.iter().map(|s| parse_set(s)).collect::<Result<Vec<_>, _>>()?;
    let points = product(&case, &params)?;
    for (_, c) in &points {
        check_memory(c, Footprint::Run, limits).with_context(|| format!("sweep point {}", c.name))?;
    }
    let target = out.unwrap_or_else(|| PathBuf::from("out").join(&case.name).join("sweep"));
    let mut manifest = run_manifest(&case, Engine::Rust)?;
    manifest.writer.command = "sweep".into();
    let folder = CommandFolder::begin(&target, manifest, Mode::Fresh { force }, &case_label(&case), SWEEP_THEN)?;
    let pb = Progress::new(&format!("{} sweep", case.name), "points", points.len(), Visibility::unless(quiet));
    let keys: Vec<String> = params.iter().map(|p| p.key.clone()).collect();
    let result = sweep_into(&case, &keys, &points, folder.dir(), jobs.unwrap_or(0), || pb.inc());
    pb.finish();
    let rows = match result {
        Ok(rows) => rows,
        Err(e) if cosserat::io::disk::is_full(&e) => {
            folder.folder.abandon();
            anyhow::bail!("{}: sweep: {}", case_label(&case), super::outcome::disk_full_text(&e, &target, "sweep"));
        }
        Err(e) => return Err(folder.failed(&format!("{}: sweep", case_label(&case)), cosserat::jobs::sweep::chain(&e))),
    };
    let count = |s: Outcome| rows.iter().filter(|r| r.status == s).count();
    let complete = rows.iter().filter(|r| r.status.is_complete()).count();
    let (interrupted, failed) = (count(Outcome::Interrupted), rows.len() - complete);
    let status = ended(interrupted, failed);
    let message = (failed > 0).then(|| {
        format!("{failed} of {} points failed, did not converge or were interrupted (summary.csv)", rows.len())
    });
    let placed = folder.finish(status, message)?;
    // where the summary and the points' folders are: the output folder, or beside it
    let written = if let Placed::Beside { kept: Some(k), .. } = &placed { k.clone() } else { target.clone() };
    println!(
        "{}: {} runs, {} failed or not converged, {interrupted} interrupted; wrote {} and one folder per run to {}",
        case.name,
        rows.len(),
        failed - interrupted,
        written.join("summary.csv").display(),
        written.display()
    );
    if let Placed::Beside { .. } = placed {
        eprintln!("{}: sweep {}", case.name, held(&placed, "", SWEEP_THEN));
    }
    for r in rows.iter().filter(|r| r.error.as_deref() != Some(cosserat::jobs::sweep::NOT_STARTED)) {
        if let Some(e) = &r.error {
            eprintln!("  {}: {}: {e}", r.name, r.status.as_str());
        }
    }
    if interrupted > 0 {
        eprintln!("{}", super::outcome::sweep_interrupted_summary(&rows, &written));
    }
    Ok(exit_code(status))
}

/// What continues a compare's, a sweep's or an audit's run kept beside a complete one ([`held`]).
const COMPARE_THEN: &str = "until the next compare into it";
const SWEEP_THEN: &str = "until the next sweep into it";
const AUDIT_THEN: &str = "(`cosserat audit --resume` with the same specs continues it)";

/// The output folder of a command that writes one (`compare`, `sweep`, `audit`; `run`'s is
/// `jobs::job::run_into`'s): begun with its notes shown, then finished with the status its
/// work ended in ([`ended`], [`exit_code`]); `then` says what continues a run kept beside a
/// complete one.
struct CommandFolder {
    folder: RunFolder,
    then: &'static str,
}

impl CommandFolder {
    /// Begin `target` for `manifest` in `mode`; `what` names the run in an error.
    fn begin(target: &Path, manifest: Manifest, mode: Mode, what: &str, then: &'static str) -> Result<Self> {
        let folder = RunFolder::begin(target, manifest, mode)
            .with_context(|| format!("{what}: output folder {}", target.display()))?;
        for n in &folder.notes {
            eprintln!("note: {n}");
        }
        Ok(CommandFolder { folder, then })
    }

    /// Where the work writes (the staging folder).
    fn dir(&self) -> &Path {
        self.folder.dir()
    }

    /// Finish the folder with `status` and `message`: where the run is now.
    fn finish(self, status: Status, message: Option<String>) -> Result<Placed> {
        Ok(self.folder.finish(status, message)?)
    }

    /// The work failed with `message`: the folder finished failed, and the error `what: message;`
    /// followed by where the run is.
    fn failed(self, what: &str, message: String) -> anyhow::Error {
        let then = self.then;
        match self.finish(Status::Failed, Some(message.clone())) {
            Ok(placed) => anyhow::anyhow!("{what}: {message}; {}", held(&placed, "failed", then)),
            Err(e) => e.context(format!("{what}: {message}")),
        }
    }
}

/// The status of work of which `interrupted` parts were stopped by a signal and `failed`
/// parts (those stopped among them) did not complete: interrupted, failed, else complete.
fn ended(interrupted: usize, failed: usize) -> Status {
    match (interrupted, failed) {
        (1.., _) => Status::Interrupted,
        (0, 1..) => Status::Failed,
        (0, 0) => Status::Complete,
    }
}

/// The exit code of a command whose work ended `status`: 0 complete, 1 failed, 130 interrupted.
fn exit_code(status: Status) -> ExitCode {
    match status {
        Status::Interrupted => ExitCode::from(crate::EXIT_INTERRUPTED),
        Status::Failed | Status::Stalled => ExitCode::from(1),
        Status::Complete | Status::CompleteWithWarnings | Status::Running => ExitCode::SUCCESS,
    }
}

/// Where a run that ended `word` ("failed", "interrupted") is, for a message: its output folder
/// holding `run.json` saying so, or (a complete run was there) beside it, `then` saying what
/// continues it.
fn held(placed: &Placed, word: &str, then: &str) -> String {
    match placed {
        Placed::InPlace(t) => format!("{} holds run.json saying {word}", t.display()),
        beside => beside.kept_text(then).trim_start_matches("; ").to_string(),
    }
}

pub fn cmd_audit(args: AuditArgs) -> Result<ExitCode> {
    use cosserat::audit::{run_audit, spec::read_spec, AuditOptions, AuditStatus, Depth};
    let (fields, depth) = (args.point_fields(), args.depth());
    let AuditArgs { specs: paths, out, force, jobs, quiet, resume, engines, .. } = args;
    let quick = depth == Depth::Quick;
    let paths = paths.as_slice();
    // --resume keeps what the folder holds: no replacing it (`None`)
    let force = (!resume).then_some(force);
    let files = audit_spec_files(paths)?;
    let specs = files.iter().map(|f| read_spec(f, depth)).collect::<Result<Vec<_>, _>>()?;
    let out = out.unwrap_or_else(|| PathBuf::from(if quick { "out/audit-quick" } else { "out/audit" }));
    // an audit folder of an older version carries the audit's marker instead of run.json
    let marker = out.join(cosserat::audit::MARKER).is_file();
    let mode = force.map_or(Mode::Resume, |f| Mode::Fresh { force: f || marker });
    let mut manifest = Manifest::new("audit");
    manifest.input.inputs = files.iter().map(|f| input_file(f)).collect::<Result<_, _>>()?;
    manifest.input.settings.insert("quick".into(), f64::from(u8::from(quick)).into());
    let resume = force.is_none();
    let folder = CommandFolder::begin(&out, manifest, mode, "audit", AUDIT_THEN)?;
    let pb = Progress::new(if quick { "audit (quick)" } else { "audit" }, "points", 0, Visibility::unless(quiet));
    let opts = AuditOptions { out: folder.dir().to_path_buf(), jobs: jobs.unwrap_or(0), fields, resume, engines };
    let points = std::sync::atomic::AtomicUsize::new(0);
    let report = run_audit(&specs, depth, &opts, |done, total| {
        points.store(total, std::sync::atomic::Ordering::SeqCst);
        pb.set(done, total);
    });
    pb.finish();
    let report = match report {
        Ok(r) => r,
        Err(e) => return Err(folder.failed("audit", format!("{:#}", anyhow::Error::from(e)))),
    };
    let judged = format!("{} of {} claims judged", report.claims.len() - report.unjudged(), report.claims.len());
    match &report.status {
        AuditStatus::Complete => {
            folder.finish(Status::Complete, None)?;
        }
        AuditStatus::Interrupted => {
            let kept =
                super::outcome::audit_points_kept(folder.dir(), points.load(std::sync::atomic::Ordering::SeqCst));
            let placed =
                folder.finish(Status::Interrupted, Some(format!("interrupted by a signal: {kept}; {judged}")))?;
            eprintln!(
                "audit interrupted: {kept}; {judged}; REPORT.md is headed interrupted and marks the others not judged; {}",
                held(&placed, "interrupted", AUDIT_THEN)
            );
            return Ok(ExitCode::from(crate::EXIT_INTERRUPTED));
        }
        AuditStatus::Failed(errors) => {
            let message = format!("{judged}: {}", errors.join("; "));
            let placed = folder.finish(Status::Failed, Some(message.clone()))?;
            anyhow::bail!(
                "audit failed: {message}; REPORT.md is headed failed; {}",
                held(&placed, "failed", AUDIT_THEN)
            );
        }
    }
    Ok(audit_summary(&report, specs.len(), &out))
}

/// The spec files of `paths` (a folder: its `*.toml`; none given: `cases/paper`).
fn audit_spec_files(paths: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let default = [PathBuf::from("cases/paper")];
    let mut files = Vec::new();
    for p in if paths.is_empty() { &default[..] } else { paths } {
        if p.is_dir() {
            files.extend(cosserat::audit::spec_files(p)?);
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
    Ok(files)
}

/// The one-line summary of a finished audit on stdout and each claim whose verdict is not the
/// one its spec expects on stderr; status 1 if there is one.
fn audit_summary(report: &cosserat::audit::AuditReport, specs: usize, out: &Path) -> ExitCode {
    use cosserat::audit::Verdict;
    let counts = report.counts();
    let summary: Vec<String> = Verdict::ALL.iter().zip(counts).map(|(v, n)| format!("{n} {}", v.as_str())).collect();
    let ours = report.claims.iter().filter(|c| c.claim.ours).count();
    println!(
        "{} claims of the paper and {ours} checks of ours in {} specs: {}; {} figures; {:.0} s; {:.1} MB; wrote {}",
        report.claims.len() - ours,
        specs,
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
    if unexpected.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}

/// `cosserat buckling`: the lowest `count` critical load factors of a static case (D27).
pub fn cmd_buckling(path: &Path, count: usize) -> Result<ExitCode> {
    let case = load(path)?;
    if !matches!(case.analysis, cosserat::case::Analysis::Static(_)) {
        anyhow::bail!(
            "{}: `buckling` takes a static case (solver.analysis = \"static\"): its loads are what buckles the rod",
            path.display()
        );
    }
    let problem = case.problem();
    let modes = cosserat::solve::stability::buckling(&problem, count)?;
    println!(
        "{}: critical load factors of the case's loads about the reference ({} elements, D27)",
        case.name, case.mesh.elements
    );
    if modes.is_empty() {
        println!("none: the loads do not buckle the rod (no positive critical load factor)");
        return Ok(ExitCode::SUCCESS);
    }
    println!("{:>4} {:>16} {:>24}", "mode", "load_factor", "largest_displacement_at_s_m");
    let dofs = problem.dofs();
    for (i, m) in modes.iter().enumerate() {
        let node = (0..dofs.nodes())
            .max_by(|&a, &b| {
                let d = |n| dofs.get(&m.shape, n, cosserat::model::mesh::Field::X).norm();
                d(a).total_cmp(&d(b))
            })
            .unwrap_or(0);
        println!("{:>4} {:>16.9} {:>24.6}", i + 1, m.load_factor, case.mesh.node_s(node));
    }
    Ok(ExitCode::SUCCESS)
}

/// `cosserat modes`: the lowest `count` natural frequencies of the rod clamped at s = 0,
/// linearised about its rest state (shift-invert block Lanczos, D28).
pub fn cmd_modes(path: &Path, count: usize, limits: Limits) -> Result<ExitCode> {
    let case = load(path)?;
    if !case.density_given() {
        anyhow::bail!(
            "{}: material.density_kg_m3 [kg/m^3] is required by `modes` (the natural frequencies scale as 1/sqrt(density)) and is missing from this case",
            path.display()
        );
    }
    check_memory(&case, Footprint::Modes { count }, limits)?;
    let model = lowest_modes(&case.problem(), count)?;
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
