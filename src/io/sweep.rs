//! The files of a parameter sweep: one folder per grid point (the files of `run`, or of the
//! last iterate when the point did not converge, and the point's `run.json` saying which) and
//! `summary.csv`. The
//! grid itself is `case::sweep`'s. A point of a clip case solves the whole clip (the frames
//! of `run` on a clip, its row the metrics of `run::clip_metrics`).
use std::path::Path;

use super::data::write_data;
use super::engine::{load_data, run_clip_to, run_inverse_on, write_clip_figures, ClipOptions, EngineError};
use super::files::OutputError;
use super::run_files::write_run;
use super::run_folder::{input_file, Manifest, Status};
use crate::case::sweep::{fmt_value, Point};
use crate::case::Case;
use crate::run::clip::{ClipFrame, ClipRun};
use crate::run::clip_metrics::clip_metrics;
use crate::run::metrics::{all_metrics, Metrics};
use crate::run::{run_forward, RunError, RunResult};

/// Columns of the summary table after the swept keys.
pub const SUMMARY_METRICS: [&str; 11] = [
    "iterations",
    "x_err_rel",
    "kappa_err_rel",
    "kappa_err_rel_inner",
    "tangent_misfit_m05",
    "j_tracking",
    "j_total",
    "force_l2_n_per_m05",
    "torque_l2_n_m05",
    "tip_y_m",
    "wall_time_s",
];

/// One row of the summary: the point, its status, its metrics (also those of the last iterate
/// of a run that did not converge) and its error message.
#[derive(Clone, Debug)]
pub struct SummaryRow {
    /// the point's folder name
    pub name: String,
    pub point: Point,
    pub status: RunStatus,
    pub metrics: Option<Metrics>,
    pub error: Option<String>,
}

impl SweepOutcome {
    /// A point that produced no result, with its error.
    fn failed(error: String) -> Self {
        SweepOutcome { status: RunStatus::Failed, metrics: None, run: None, clip: None, error: Some(error) }
    }

    /// A point stopped (or not started) by a signal.
    fn interrupted() -> Self {
        SweepOutcome {
            status: RunStatus::Interrupted,
            metrics: None,
            run: None,
            clip: None,
            error: Some("interrupted by a signal".into()),
        }
    }
}

/// Outcome of one run of a sweep.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunStatus {
    Ok,
    /// iteration limit reached; the metrics are those of the last iterate
    NotConverged,
    Failed,
    /// stopped by a signal (or not started because of one)
    Interrupted,
}

impl RunStatus {
    pub fn as_str(&self) -> &'static str {
        match self {
            RunStatus::Ok => "ok",
            RunStatus::NotConverged => "not_converged",
            RunStatus::Failed => "failed",
            RunStatus::Interrupted => "interrupted",
        }
    }

    /// The status of the point's folder (`run.json`).
    pub fn folder_status(&self) -> Status {
        match self {
            RunStatus::Ok => Status::Complete,
            RunStatus::NotConverged | RunStatus::Failed => Status::Failed,
            RunStatus::Interrupted => Status::Interrupted,
        }
    }
}

/// Columns of the summary table of a clip case after the swept keys (`run::clip_metrics`).
pub const CLIP_SUMMARY_METRICS: [&str; 11] = [
    "frames",
    "iterations_mean",
    "iterations_max",
    "x_err_rel_max",
    "tangent_misfit_rel_max",
    "max_abs_j_minus_1",
    "shear_share_median",
    "j_total_median",
    "min_abs_cos_beta",
    "truth_x_err_rel_max",
    "wall_time_s",
];

/// CSV text of the summary (header: swept keys, `status` (`ok`, `not_converged`, `failed`),
/// `columns` ([`SUMMARY_METRICS`], or [`CLIP_SUMMARY_METRICS`] for a clip case), `error`).
pub fn summary_csv(keys: &[String], columns: &[&str], rows: &[SummaryRow]) -> Result<String, csv::Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header: Vec<String> = keys.to_vec();
    header.push("status".into());
    header.extend(columns.iter().map(|s| s.to_string()));
    header.push("error".into());
    w.write_record(&header)?;
    for r in rows {
        let mut rec: Vec<String> = r.point.iter().map(|(_, v)| fmt_value(*v)).collect();
        rec.push(r.status.as_str().into());
        rec.extend(
            columns
                .iter()
                .map(|k| r.metrics.as_ref().and_then(|m| m.get(*k)).map(|v| format!("{v:.10e}")).unwrap_or_default()),
        );
        rec.push(r.error.as_deref().unwrap_or("").replace('\n', " "));
        w.write_record(&rec)?;
    }
    let bytes = w.into_inner().map_err(|e| csv::Error::from(e.into_error()))?;
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

/// What one run of a sweep produced: a single-frame or forward run (`run`) or a clip (`clip`).
pub struct SweepOutcome {
    pub status: RunStatus,
    pub metrics: Option<Metrics>,
    pub run: Option<RunResult>,
    pub clip: Option<ClipRun>,
    pub error: Option<String>,
}

/// One point of a sweep in the Rust engine, writing its folder `dir` and its `run.json`
/// (`template` with the point's status and message). A run that stops at its iteration limit
/// still writes the files of its last iterate (its `run.json` says failed). A clip case solves
/// its whole clip ([`run_clip_point`]). A point reached after a stop was requested
/// (`crate::interrupt`) is not started and writes nothing.
pub fn run_point(case: &Case, dir: &Path, template: &Manifest) -> SweepOutcome {
    if crate::interrupt::requested() {
        return SweepOutcome::interrupted();
    }
    let outcome = if case.clip().is_some() { clip_point(case, dir, |_| {}) } else { single_point(case, dir) };
    finish_point(dir, template, outcome)
}

/// The whole clip of a clip case in the Rust engine as a point of a sweep or audit, frames
/// streamed to `dir` and shown to `observer`, then the clip's figures (over the frames solved,
/// also when it stopped early) and its `run.json`. A clip that stops at a frame keeps the
/// converged frames; its status is `failed` (or `interrupted`).
pub fn run_clip_point(
    case: &Case,
    dir: &Path,
    template: &Manifest,
    observer: impl FnMut(&ClipFrame) + Send,
) -> SweepOutcome {
    if crate::interrupt::requested() {
        return SweepOutcome::interrupted();
    }
    finish_point(dir, template, clip_point(case, dir, observer))
}

/// The `run.json` of a point of `command` (a sweep, an audit): the case and its file's hash,
/// the point's settings, the Rust engine.
pub fn point_manifest(command: &str, case: &Case, point: &Point) -> Manifest {
    let mut m = Manifest::new(command);
    m.case_name = Some(case.name.clone());
    m.case = case.source.as_deref().and_then(|p| input_file(p).ok());
    m.inputs = case.clip().and_then(|c| input_file(&c.file).ok()).into_iter().collect();
    m.settings = point.iter().cloned().collect();
    m.engine = Some("rust".into());
    m
}

/// The point's `run.json`: `template` with the case's name, the point's status and message.
fn finish_point(dir: &Path, template: &Manifest, outcome: SweepOutcome) -> SweepOutcome {
    if !dir.is_dir() {
        return outcome;
    }
    let mut m = template.clone();
    if let Some(c) = &outcome.clip {
        m.frames_done = Some(c.reports.len());
    }
    match m.finish(dir, outcome.status.folder_status(), outcome.error.clone()) {
        Ok(()) => outcome,
        Err(e) => SweepOutcome::failed(chain(&e)),
    }
}

fn single_point(case: &Case, dir: &Path) -> SweepOutcome {
    let failed = |e: &dyn std::fmt::Display| SweepOutcome::failed(e.to_string());
    let outcome: Result<RunResult, EngineError> = if case.inverse().is_some() {
        let path = dir.join("data.csv");
        match load_data(case).and_then(|d| Ok(write_data(&path, &d)?)) {
            Ok(()) => run_inverse_on(case, crate::run::Engine::Rust, &path, &dir.join("freefem_work"), |_, _| {}),
            Err(e) => return failed(&format_args!("{}: generating the forward data: {}", case_label(case), chain(&e))),
        }
    } else {
        run_forward(case, |_, _| {}).map_err(EngineError::from)
    };
    let (status, r, error) = match outcome {
        Ok(r) => (RunStatus::Ok, r, None),
        Err(EngineError::Run(e)) if e.is_interrupted() => return SweepOutcome::interrupted(),
        Err(EngineError::Run(RunError::Incomplete { source, partial })) => {
            (RunStatus::NotConverged, *partial, Some(format!("{source}; the files here hold the last iterate")))
        }
        Err(e) => return failed(&format_args!("{}: {}", case_label(case), chain(&e))),
    };
    let write = || -> Result<Metrics, String> {
        let m = all_metrics(case, &r).map_err(|e| chain(&e))?;
        write_run(case, &r, &m, dir).map_err(|e| chain(&e))?;
        Ok(m)
    };
    match write() {
        Ok(m) => SweepOutcome { status, metrics: Some(m), run: Some(r), clip: None, error },
        Err(e) => failed(&e),
    }
}

fn clip_point(case: &Case, dir: &Path, observer: impl FnMut(&ClipFrame) + Send) -> SweepOutcome {
    let out = match run_clip_to(case, dir, ClipOptions::default(), observer, |_, _| {}) {
        Ok(out) => out,
        Err(e) => return SweepOutcome::failed(format!("{}: {}", case_label(case), chain(&e))),
    };
    let (status, error) = match &out.stopped {
        None => (RunStatus::Ok, None),
        Some(e) if e.is_interrupted() => (RunStatus::Interrupted, Some(chain(e))),
        Some(e) => (
            RunStatus::Failed,
            Some(format!("{}: {}; the converged frames before it are in this folder", case_label(case), chain(e))),
        ),
    };
    if !out.run.reports.is_empty() {
        if let Err(e) = write_clip_figures(case, &out.run, dir) {
            return SweepOutcome::failed(format!("{}: {}", case_label(case), chain(&e)));
        }
    }
    let m = (status == RunStatus::Ok).then(|| clip_metrics(case, &out.run));
    SweepOutcome { status, metrics: m, run: None, clip: Some(out.run), error }
}

/// Run every point of a sweep of `case` (`points`: the grid of `case::sweep::product`, swept
/// `keys`) in parallel on `jobs` threads (0: one per core), each into its folder under `dir`
/// ([`run_point`]), then write `summary.csv` and `convergence.svg`; `tick` after each point.
/// Two points with the same folder name are refused (they would write into one folder).
pub fn sweep_into(
    case: &Case,
    keys: &[String],
    points: &[(Point, Case)],
    dir: &Path,
    jobs: usize,
    tick: impl Fn() + Sync,
) -> Result<Vec<SummaryRow>, OutputError> {
    use rayon::prelude::*;
    let mut names = std::collections::BTreeSet::new();
    for (_, c) in points {
        if !names.insert(c.name.as_str()) {
            return Err(OutputError::Invalid {
                path: dir.join(&c.name),
                reason: "two points of the sweep have this folder (a value given twice?)".into(),
            });
        }
    }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(jobs).build().map_err(|e| OutputError::Invalid {
        path: dir.to_path_buf(),
        reason: format!("cannot start the thread pool: {e}"),
    })?;
    let results: Vec<(String, Point, SweepOutcome)> = pool.install(|| {
        points
            .par_iter()
            .map(|(point, c)| {
                let template = point_manifest("sweep point", c, point);
                let r = run_point(c, &dir.join(&c.name), &template);
                tick();
                (c.name.clone(), point.clone(), r)
            })
            .collect()
    });
    let rows: Vec<SummaryRow> = results
        .iter()
        .map(|(name, point, o)| SummaryRow {
            name: name.clone(),
            point: point.clone(),
            status: o.status,
            metrics: o.metrics.clone(),
            error: o.error.clone(),
        })
        .collect();
    let columns: &[&str] = if case.clip().is_some() { &CLIP_SUMMARY_METRICS } else { &SUMMARY_METRICS };
    let text = summary_csv(keys, columns, &rows)
        .map_err(|e| OutputError::Invalid { path: dir.join("summary.csv"), reason: e.to_string() })?;
    super::files::write_atomic(&dir.join("summary.csv"), text.as_bytes())?;
    let curves: Vec<(&String, &RunResult)> =
        results.iter().filter_map(|(name, _, o)| o.run.as_ref().map(|run| (name, run))).collect();
    if !curves.is_empty() {
        super::run_files::write_convergence_plot(&curves, &dir.join("convergence.svg"))?;
    }
    Ok(rows)
}

/// How messages name a case: `case NAME (FILE)`, or `case NAME` for a case not read from a file.
pub fn case_label(case: &Case) -> String {
    match &case.source {
        Some(p) => format!("case {} ({})", case.name, p.display()),
        None => format!("case {}", case.name),
    }
}

/// An error and its sources, `a: b: c` (as `anyhow`'s `{:#}`).
pub fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut source = e.source();
    while let Some(cause) = source {
        s.push_str(": ");
        s.push_str(&cause.to_string());
        source = cause.source();
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_has_header_and_failures() {
        let mut m = Metrics::new();
        m.insert("iterations".into(), 12.0);
        let rows = vec![
            SummaryRow {
                name: String::new(),
                point: vec![("lambda_l".into(), 1e-20)],
                status: RunStatus::Ok,
                metrics: Some(m.clone()),
                error: None,
            },
            SummaryRow {
                name: String::new(),
                point: vec![("lambda_l".into(), 1e3)],
                status: RunStatus::NotConverged,
                metrics: Some(m),
                error: Some("did not converge,\nat all".into()),
            },
            SummaryRow {
                name: String::new(),
                point: vec![("lambda_l".into(), 1.0)],
                status: RunStatus::Failed,
                metrics: None,
                error: Some("bad".into()),
            },
        ];
        let text = summary_csv(&["lambda_l".into()], &SUMMARY_METRICS, &rows).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert!(lines[0].starts_with("lambda_l,status,iterations,x_err_rel"));
        assert!(lines[1].starts_with("1e-20,ok,1.2000000000e1"));
        assert!(
            lines[2].starts_with("1e3,not_converged,1.2000000000e1")
                && lines[2].ends_with("\"did not converge, at all\""),
            "{}",
            lines[2]
        );
        assert!(lines[3].starts_with("1,failed,,") && lines[3].ends_with(",bad"), "{}", lines[3]);
    }
}
