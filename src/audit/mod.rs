//! The audit of the paper (`cosserat audit`): every figure, table and claim of §5–6 that can
//! be computed here, regenerated from the specs of `cases/paper/` ([`spec`]) and judged with
//! numbers ([`check`]): *reproduced*, *differs*, *refuted* or *not computable here*. Runs go
//! through the same path as `cosserat sweep` (`jobs::sweep::run_point`), one folder per point;
//! [`measures`] adds the numbers a claim needs beyond a run's metrics, [`figures`] draws the
//! paper's panels and [`report`] writes `REPORT.md` and `report.csv`.
pub mod cause;
pub mod check;
pub mod convergence;
pub mod engines;
pub mod figures;
pub mod inventory;
pub mod measures;
pub mod newton_distance;
pub mod numbers;
pub mod points;
pub mod report;
pub mod resume;
pub mod spec;
pub mod truth;
pub mod wave;

pub use crate::jobs::depth::Depth;
use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::Deserialize;

use crate::case::sweep::{product, Point, SweepError};
use crate::io::compact::OutputFormat;
use crate::jobs::sweep::{point_manifest, run_clip_point, run_point, SweepOutcome};
use crate::output::manifest::Status;
use measures::{derived_metrics, ClipRecorder, ClipSeries};
use spec::{Claim, RunSpec, Spec};

/// The judgement of one claim.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// our numbers satisfy the paper's statement
    Reproduced,
    /// our numbers satisfy it in part, or with different numbers (the cause is given)
    Differs,
    /// our numbers contradict it, for a cause shown in `docs/audit.md`
    Refuted,
    /// the paper's data or setting is not available; the check ran on a substitute
    NotComputable,
}

impl Verdict {
    pub fn as_str(&self) -> &'static str {
        match self {
            Verdict::Reproduced => "reproduced",
            Verdict::Differs => "differs",
            Verdict::Refuted => "refuted",
            Verdict::NotComputable => "not computable here",
        }
    }
    pub const ALL: [Verdict; 4] = [Verdict::Reproduced, Verdict::Differs, Verdict::Refuted, Verdict::NotComputable];
}

/// Errors of an audit (before any run: the runs' own failures are results).
#[derive(Debug, thiserror::Error)]
pub enum AuditError {
    #[error(transparent)]
    Spec(#[from] spec::SpecError),
    #[error("spec {spec}: run `{run}`")]
    Grid {
        spec: String,
        run: String,
        #[source]
        source: SweepError,
    },
    #[error(
        "{path}: claim `{claim}`: unknown metric `{metric}`: no point of run `{run}` reports it (its points report: {known})"
    )]
    UnknownMetric { path: PathBuf, claim: String, metric: String, run: String, known: String },
    #[error("writing the report")]
    Output(#[from] crate::io::OutputError),
    #[error("writing the report")]
    Csv(#[from] csv::Error),
    #[error("{path} exists and is not an audit folder (no {MARKER}); choose another --out")]
    Foreign { path: PathBuf },
    #[error("cannot prepare the audit folder {path}")]
    Folder {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot list audit specs in {path}")]
    List {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// One point of a run with what it produced.
pub struct PointResult {
    /// grid values (empty for a run without a grid)
    pub point: Point,
    /// folder name of the point
    pub label: String,
    pub outcome: SweepOutcome,
    /// clip runs: per-frame series the figures and measures need beyond `frames.csv`
    pub series: Option<ClipSeries>,
}

impl PointResult {
    pub fn converged(&self) -> bool {
        self.outcome.status.is_complete()
    }
    /// A metric of the point by the name a spec gives (its run's metrics with
    /// [`measures::derived_metrics`]).
    pub fn metric(&self, name: &str) -> Option<f64> {
        self.outcome.metrics.as_ref().and_then(|m| m.named(name))
    }
    /// A metric of the point's run.
    pub fn value(&self, key: crate::engine::metrics::Metric) -> Option<f64> {
        self.outcome.metrics.as_ref().and_then(|m| m.get(key))
    }
    /// Does the point have these grid values?
    pub fn matches(&self, at: &spec::Selector) -> bool {
        at.iter().all(|(k, v)| {
            self.point.iter().any(|(pk, pv)| pk == k && pv.number().is_some_and(|pv| (pv - v).abs() <= 1e-12 * v.abs()))
        })
    }
}

/// The points of one run of a spec.
pub struct RunResults {
    pub name: String,
    pub points: Vec<PointResult>,
    /// the case's description (for the report)
    pub case_name: String,
}

impl RunResults {
    /// The selected points (`at` empty: all).
    pub fn select(&self, at: &spec::Selector) -> impl Iterator<Item = &PointResult> + '_ {
        let at = at.clone();
        self.points.iter().filter(move |p| p.matches(&at))
    }
}

/// A claim of the report: judged, or not (its points were stopped or never ran).
#[derive(Clone, Debug)]
pub struct ClaimResult {
    pub spec: String,
    pub claim: Claim,
    /// the verdict; `None`: not judged (an interrupted or failed audit), `ours` says why
    pub verdict: Option<Verdict>,
    /// our numbers, two significant digits or those a verdict needs (not judged: why)
    pub ours: String,
    /// a convergence claim: our standard of a solution, the certificate against 1e-10 with
    /// its margin and the distance to Newton's solution (`convergence::standard`)
    pub standard: Option<String>,
    /// why the check did not hold: the spec's cause with its points filled in from the
    /// runs (`cause`); `None` when it held, was not judged or the spec gives no cause
    pub cause: Option<String>,
    /// the figure illustrating the claim, relative to the audit folder
    pub figure: Option<String>,
    /// the check in the other engine and one-rule readings (`engines`), where it was rerun
    pub engines: Option<String>,
}

/// How far an audit got (the audit as a whole; each of its points ends with an
/// [`crate::solve::Outcome`], and a claim is judged with a [`Verdict`], neither an outcome of
/// this kind). Only a complete audit's verdicts are the audit's; an unfinished one
/// judges the claims whose points all finished and marks the others *not judged*.
#[derive(Clone, Debug, PartialEq)]
pub enum AuditStatus {
    Complete,
    /// stopped by a signal (SIGINT, SIGTERM): points stopped or never started
    Interrupted,
    /// the runs finished but something could not be judged or drawn (the errors)
    Failed(Vec<String>),
}

impl AuditStatus {
    /// The state of the audit's folder (`run.json`): complete, interrupted or failed.
    pub fn folder_status(&self) -> Status {
        match self {
            AuditStatus::Complete => Status::Complete,
            AuditStatus::Interrupted => Status::Interrupted,
            AuditStatus::Failed(_) => Status::Failed,
        }
    }

    /// The word of the folder's state.
    pub fn as_str(&self) -> &'static str {
        self.folder_status().as_str()
    }
}

/// Everything an audit produced.
pub struct AuditReport {
    pub claims: Vec<ClaimResult>,
    /// figures written, relative to the audit folder
    pub figures: Vec<String>,
    /// the grids run (`--quick` or full)
    pub depth: Depth,
    pub wall_time_s: f64,
    /// CPU time of the audit's process (user + system) [s], `None` where /proc is not there
    pub cpu_time_s: Option<f64>,
    pub status: AuditStatus,
    /// size of the audit folder when the report was written [bytes]
    pub bytes: u64,
    /// what the clip points kept
    pub fields: PointFields,
    /// the claims inventory beside the specs (`inventory.csv`) against the rows, if there is
    /// one; `Err`: it could not be read (the report says so)
    pub coverage: Option<Result<inventory::Coverage, inventory::InventoryError>>,
}

impl AuditReport {
    /// Judged claims of the paper per verdict, in the order of [`Verdict::ALL`] (our own
    /// checks, `ours = true`, are counted apart: [`AuditReport::our_counts`]).
    pub fn counts(&self) -> [usize; 4] {
        Verdict::ALL.map(|v| self.claims.iter().filter(|c| !c.claim.ours && c.verdict == Some(v)).count())
    }
    /// Judged checks of ours per verdict.
    pub fn our_counts(&self) -> [usize; 4] {
        Verdict::ALL.map(|v| self.claims.iter().filter(|c| c.claim.ours && c.verdict == Some(v)).count())
    }
    /// Claims not judged (their points were stopped, never ran, or the audit failed on them).
    pub fn unjudged(&self) -> usize {
        self.claims.iter().filter(|c| c.verdict.is_none()).count()
    }
}

/// Settings of an audit.
#[derive(Clone, Debug)]
pub struct AuditOptions {
    /// output folder (one subfolder per spec, `REPORT.md`, `report.csv`)
    pub out: PathBuf,
    /// parallel runs (0: one per core)
    pub jobs: usize,
    /// what a clip point keeps beside its tables ([`PointFields`])
    pub fields: PointFields,
    /// continue the audit of `out`: specs it judged whole ([`resume::JUDGED`]) are taken
    /// from it, the others run again
    pub resume: bool,
    /// rerun the failing rows of the printed scheme in the other engine and reading
    /// ([`engines`]), so that a row can be refuted
    pub engines: bool,
}

impl AuditOptions {
    /// An audit into `out`: one run per core, the default point fields, not resumed, the
    /// Rust engine only.
    pub fn new(out: PathBuf) -> Self {
        AuditOptions { out, jobs: 0, fields: PointFields::default(), resume: false, engines: false }
    }
}

/// What a clip point of the audit keeps in its folder. Its claims and the audit's figures
/// read the series the audit records in memory ([`measures::ClipSeries`]), not these files.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PointFields {
    /// `frames.csv`, `truth.csv`, `run.json` only (the default, so that the full audit stays
    /// within [`FULL_AUDIT_BUDGET_BYTES`]: 19 clip points of 1160 frames)
    #[default]
    Tables,
    /// also the per-node fields as one compact `fields.npz` and the run's own figures
    Compact,
    /// also `fields.csv`, `curvature.csv`, ParaView VTK files and the run's own figures
    Vtk,
}

impl PointFields {
    pub fn as_str(&self) -> &'static str {
        match self {
            PointFields::Tables => {
                "clip points keep their tables only; `--fields` for compact fields, `--vtk` for CSV and VTK"
            }
            PointFields::Compact => "`--fields`: compact fields.npz and figures per clip point",
            PointFields::Vtk => "`--vtk`: fields.csv, curvature.csv, VTK and figures per clip point",
        }
    }
}

/// The files a clip point of [`PointFields::Tables`] removes after its run: the per-node
/// fields and the run's own figures (the audit draws its own).
const BULKY: [&str; 5] = ["fields.npz", "kymograph.svg", "omega.svg", "truth.svg", "truth_errors.svg"];

/// What the full audit may write by default [bytes]: 200 MB (issue 30; it wrote 2.9 GB with
/// `fields.csv` and VTK for every frame of every clip point).
pub const FULL_AUDIT_BUDGET_BYTES: u64 = 200_000_000;

/// Bytes of the files under `dir` (the audit folder's size, printed in REPORT.md).
pub use crate::io::files::folder_bytes;

/// The spec files of a folder (`*.toml`, sorted).
pub fn spec_files(dir: &Path) -> Result<Vec<PathBuf>, AuditError> {
    let list = |source| AuditError::List { path: dir.to_path_buf(), source };
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(list)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    Ok(files)
}

/// The file that marks a folder as an audit's output (so that a new audit may replace it).
pub const MARKER: &str = ".cosserat-audit";

/// Empty `out` for a new audit: a previous audit's folder (it holds [`MARKER`]) is removed
/// whole, so that no point of an older audit survives next to the new ones; any other
/// non-empty folder is refused.
fn prepare_folder(out: &Path) -> Result<(), AuditError> {
    let io = |source| AuditError::Folder { path: out.to_path_buf(), source };
    if out.exists() {
        // empty, or a staging folder of the output-folder contract (`output::run_folder`) holding
        // only its run.json
        let empty = std::fs::read_dir(out)
            .map_err(io)?
            .filter_map(Result::ok)
            .all(|e| e.file_name() == crate::output::run_folder::MANIFEST);
        if empty {
            return std::fs::write(out.join(MARKER), "written by `cosserat audit`\n").map_err(io);
        }
        if !empty && !out.join(MARKER).exists() {
            return Err(AuditError::Foreign { path: out.to_path_buf() });
        }
        std::fs::remove_dir_all(out).map_err(io)?;
    }
    std::fs::create_dir_all(out).map_err(io)?;
    std::fs::write(out.join(MARKER), "written by `cosserat audit`; replaced whole by the next audit\n").map_err(io)
}

/// One job of the audit: a point of a run of a spec.
struct Job<'a> {
    spec: usize,
    run: &'a RunSpec,
    point: Point,
    case: crate::case::Case,
    dir: PathBuf,
    fields: PointFields,
}

/// User + system CPU time of this process so far [s], from `/proc/self/stat` (fields 14 and 15,
/// in clock ticks of 1/100 s, Linux's USER_HZ); `None` elsewhere. The audit's points run in
/// this process's threads, so this is the audit's CPU time.
fn process_cpu_time_s() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // the command name (field 2) is in parentheses and may hold spaces
    let rest = stat.rsplit_once(')')?.1;
    let fields: Vec<&str> = rest.split_whitespace().collect();
    // `rest` starts at field 3
    let ticks = |n: usize| fields.get(n - 3)?.parse::<f64>().ok();
    Some((ticks(14)? + ticks(15)?) / 100.0)
}

/// Run every point of every run of `specs` in parallel (clip runs first: they are the longest),
/// judge every claim, draw every figure and write `REPORT.md` and `report.csv` into
/// `opts.out`. `progress(done, total)` after each point.
pub fn run_audit(
    specs: &[Spec],
    depth: Depth,
    opts: &AuditOptions,
    progress: impl Fn(usize, usize) + Sync,
) -> Result<AuditReport, AuditError> {
    let start = std::time::Instant::now();
    let cpu_start = process_cpu_time_s();
    let reused: Vec<Option<(Vec<ClaimResult>, Vec<String>)>> =
        specs.iter().map(|s| if opts.resume { resume::load(s, depth, &opts.out) } else { None }).collect();
    let mut jobs = plan_jobs(specs, &reused, opts)?;
    if opts.resume {
        resume_folder(&opts.out, specs, &reused)?;
    } else {
        prepare_folder(&opts.out)?;
    }
    jobs.sort_by_key(|j| j.case.clip().is_none());
    let total = jobs.len();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(crate::jobs::threads_for(opts.jobs, total)).build().ok();
    let work = || -> Vec<(usize, String, PointResult)> {
        jobs.par_iter()
            .map(|j| {
                let r = run_job(j);
                // a point stopped by a stop request is not done
                if r.outcome.status != crate::solve::Outcome::Interrupted {
                    progress(done.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1, total);
                }
                (j.spec, j.run.name.clone(), r)
            })
            .collect()
    };
    let finished = match &pool {
        Some(p) => p.install(work),
        None => work(),
    };
    let results = regroup(specs, finished);
    // the failing rows of the printed scheme in the other engine and reading (`engines`)
    let reruns = if opts.engines { engines::plan(specs, &results, &opts.out) } else { Vec::new() };
    let reruns = if crate::interrupt::requested() {
        specs.iter().map(|_| Vec::new()).collect()
    } else {
        match &pool {
            Some(p) => p.install(|| engines::run(specs, &reruns)),
            None => engines::run(specs, &reruns),
        }
    };
    let interrupted = crate::interrupt::requested();
    let (claims, figures, failures) = judge_all(specs, (&results, &reruns), &opts.out, reused, depth);
    let status = if interrupted {
        AuditStatus::Interrupted
    } else if failures.is_empty() {
        AuditStatus::Complete
    } else {
        AuditStatus::Failed(failures)
    };
    let report = AuditReport {
        claims,
        figures,
        depth,
        wall_time_s: start.elapsed().as_secs_f64(),
        cpu_time_s: process_cpu_time_s().zip(cpu_start).map(|(end, start)| end - start),
        status,
        bytes: folder_bytes(&opts.out),
        fields: opts.fields,
        coverage: None,
    };
    let report = AuditReport { coverage: coverage(specs, &report.claims), ..report };
    report::write_report(&report, &opts.out)?;
    Ok(report)
}

/// One job per point of every run of the specs not taken from the audit being resumed, each
/// with its folder `out/<spec>/<run>/<point>` (`run` for a run without a grid).
fn plan_jobs<'a>(
    specs: &'a [Spec],
    reused: &[Option<(Vec<ClaimResult>, Vec<String>)>],
    opts: &AuditOptions,
) -> Result<Vec<Job<'a>>, AuditError> {
    let mut jobs: Vec<Job> = Vec::new();
    for (i, spec) in specs.iter().enumerate().filter(|(i, _)| reused[*i].is_none()) {
        for run in &spec.runs {
            let grid_err = |source| AuditError::Grid { spec: spec.name.clone(), run: run.name.clone(), source };
            let points = product(&run.case, &run.grid).map_err(grid_err)?;
            for (point, case) in points {
                let label = if point.is_empty() { "run".to_string() } else { case.name.clone() };
                let dir = opts.out.join(&spec.name).join(&run.name).join(&label);
                jobs.push(Job { spec: i, run, point, case, dir, fields: opts.fields });
            }
        }
    }
    Ok(jobs)
}

/// The finished points `(spec, run, result)` regrouped by spec and run, in the specs' order.
fn regroup(specs: &[Spec], finished: Vec<(usize, String, PointResult)>) -> Vec<Vec<RunResults>> {
    let mut results: Vec<Vec<RunResults>> = specs
        .iter()
        .map(|s| {
            s.runs
                .iter()
                .map(|r| RunResults { name: r.name.clone(), points: Vec::new(), case_name: r.case.name.clone() })
                .collect()
        })
        .collect();
    for (spec, run, r) in finished {
        if let Some(rr) = results[spec].iter_mut().find(|x| x.name == run) {
            rr.points.push(r);
        }
    }
    results
}

/// The claims inventory beside the first spec, against the claims judged.
fn coverage(specs: &[Spec], claims: &[ClaimResult]) -> Option<Result<inventory::Coverage, inventory::InventoryError>> {
    let path = specs.first()?.path.parent()?.join(inventory::INVENTORY);
    path.is_file().then(|| inventory::read_inventory(&path).map(|e| inventory::Coverage::new(e, claims)))
}

/// Judge every claim of `specs` on `results` and draw every figure of the specs whose points
/// all finished (none stopped by a signal); a spec taken from the audit being resumed
/// (`reused`) keeps its claims and figures. A claim whose metric no point reports, or that
/// reads a point a signal stopped, is not judged; the failures (metric typos, figures not
/// written) are returned as text. A spec judged whole is recorded for `--resume`. A claim
/// rerun in the other engine and reading (`reruns`, [`engines`]) shows it, and may be refuted.
fn judge_all(
    specs: &[Spec],
    (results, reruns): (&[Vec<RunResults>], &engines::Reruns),
    out: &Path,
    reused: Vec<Option<(Vec<ClaimResult>, Vec<String>)>>,
    depth: Depth,
) -> (Vec<ClaimResult>, Vec<String>, Vec<String>) {
    let (mut claims, mut figures, mut failures) = (Vec::new(), Vec::new(), Vec::new());
    for (((spec, runs), old), reruns) in specs.iter().zip(results).zip(reused).zip(reruns) {
        if let Some((c, f)) = old {
            claims.extend(c);
            figures.extend(f);
            continue;
        }
        let whole = runs.iter().all(|r| r.points.iter().all(|p| !check::stopped(p)));
        if whole {
            match figures::write_figures(spec, runs, &out.join(&spec.name)) {
                Ok(written) => figures.extend(written.iter().map(|f| format!("{}/{f}", spec.name))),
                Err((file, e)) => failures.push(format!("spec {}: figure {file}: {e}", spec.name)),
            }
        }
        let first = claims.len();
        for claim in &spec.claims {
            let mut c = check::judge(spec, claim, runs);
            engines::apply(spec, claim, &mut c, reruns);
            if let Err(e) = check_metric_name(spec, claim, runs) {
                c.ours = format!("not judged: {e}");
                c.verdict = None;
                failures.push(e.to_string());
            }
            claims.push(c);
        }
        if whole && failures.is_empty() {
            if let Err(e) = resume::store(spec, &claims[first..], &figures, depth, out) {
                failures.push(format!("spec {}: {e}", spec.name));
            }
        }
    }
    (claims, figures, failures)
}

/// The folder of an audit being resumed: the folders of the specs that run again are emptied
/// (no point of the interrupted audit is mixed with new ones).
fn resume_folder(
    out: &Path,
    specs: &[Spec],
    reused: &[Option<(Vec<ClaimResult>, Vec<String>)>],
) -> Result<(), AuditError> {
    let io = |source| AuditError::Folder { path: out.to_path_buf(), source };
    std::fs::create_dir_all(out).map_err(io)?;
    std::fs::write(out.join(MARKER), "written by `cosserat audit`; replaced whole by the next audit\n").map_err(io)?;
    for (spec, old) in specs.iter().zip(reused) {
        let dir = out.join(&spec.name);
        if old.is_none() && dir.exists() {
            std::fs::remove_dir_all(&dir).map_err(io)?;
        }
    }
    Ok(())
}

/// The metric a claim reads is reported by some point of its runs that has metrics (a typo
/// in a spec is an error naming it, not a claim judged on a missing number).
fn check_metric_name(spec: &Spec, claim: &Claim, runs: &[RunResults]) -> Result<(), AuditError> {
    let Some(metric) = claim.check.metric() else { return Ok(()) };
    for run in claim.check.runs() {
        let Some(rr) = runs.iter().find(|r| r.name == run) else { continue };
        let reported: Vec<&crate::engine::metrics::Metrics> =
            rr.points.iter().filter_map(|p| p.outcome.metrics.as_ref()).collect();
        if reported.is_empty() || reported.iter().any(|m| m.named(metric).is_some()) {
            continue;
        }
        let known: std::collections::BTreeSet<&str> = reported.iter().flat_map(|m| m.names()).collect();
        return Err(AuditError::UnknownMetric {
            path: spec.path.clone(),
            claim: claim.id.clone(),
            metric: metric.to_string(),
            run: run.to_string(),
            known: known.into_iter().collect::<Vec<_>>().join(", "),
        });
    }
    Ok(())
}

/// Run one point: a clip case solves its clip (recording the series the figures need), any
/// other case runs as in `cosserat sweep`; then the derived metrics of [`measures`].
fn run_job(j: &Job) -> PointResult {
    let label = j.dir.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default();
    let template = point_manifest("audit point", &j.case, &j.point);
    let (mut outcome, series) = if j.case.clip().is_some() {
        let mut recorder = ClipRecorder::new(&j.run.keep_frames);
        let format = if j.fields == PointFields::Vtk { OutputFormat::Csv } else { OutputFormat::Compact };
        let outcome = run_clip_point(&j.case, &j.dir, &template, format, |frame| recorder.record(frame));
        if j.fields == PointFields::Tables {
            for f in BULKY {
                let _ = std::fs::remove_file(j.dir.join(f));
            }
        }
        (outcome, Some(recorder.finish()))
    } else {
        (run_point(&j.case, &j.dir, &template), None)
    };
    if let Some(m) = outcome.metrics.as_mut() {
        m.extend(derived_metrics(&j.case, outcome.single.as_ref(), series.as_ref()));
        m.extend(newton_distance::newton_metrics(&j.case, outcome.single.as_ref()));
    }
    PointResult { point: j.point.clone(), label, outcome, series }
}
