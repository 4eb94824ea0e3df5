//! The files of a parameter sweep: one folder per grid point (the files of `run`, or of the
//! last iterate when the point did not converge, and the point's `run.json` saying which) and
//! `summary.csv`. The
//! grid itself is `case::sweep`'s. A point of a clip case solves the whole clip (the frames
//! of `run` on a clip, its row the metrics of `engine::clip_metrics`).
use std::path::Path;

pub use super::solved::{case_label, chain, Solved as SweepOutcome};
use super::solved::{solve_into, Solved};
use crate::case::sweep::Point;
use crate::case::Case;
use crate::engine::clip::ClipFrame;
use crate::engine::metrics::{Metric, Metrics};
use crate::engine::{Engine, RunResult};
use crate::io::files::OutputError;
use crate::jobs::clip_run::ClipOptions;
use crate::output::run_folder::Manifest;
use crate::solve::Outcome;

/// Columns of the summary table after the swept keys.
pub const SUMMARY_METRICS: [Metric; 12] = [
    Metric::Iterations,
    Metric::Certificate,
    Metric::XErrRel,
    Metric::KappaErrRel,
    Metric::KappaErrRelInner,
    Metric::TangentMisfit,
    Metric::JTracking,
    Metric::JTotal,
    Metric::ForceL2,
    Metric::TorqueL2,
    Metric::TipY,
    Metric::WallTime,
];

/// One row of the summary: the point, its status, its metrics (also those of the last iterate
/// of a run that did not converge) and its error message.
#[derive(Clone, Debug)]
pub struct SummaryRow {
    /// the point's folder name
    pub name: String,
    pub point: Point,
    pub status: Outcome,
    pub metrics: Option<Metrics>,
    pub error: Option<String>,
}

/// Columns of the summary table of a clip case after the swept keys (`engine::clip_metrics`).
pub const CLIP_SUMMARY_METRICS: [Metric; 12] = [
    Metric::Frames,
    Metric::Certificate,
    Metric::IterationsMean,
    Metric::IterationsMax,
    Metric::XErrRelMax,
    Metric::TangentMisfitRelMax,
    Metric::MaxAbsJMinus1,
    Metric::ShearShareMedian,
    Metric::JTotalMedian,
    Metric::MinAbsCosBeta,
    Metric::TruthXErrRelMax,
    Metric::WallTime,
];

/// CSV text of the summary (header: swept keys, `status` (`ok`, `not_converged`, `failed`),
/// `columns` ([`SUMMARY_METRICS`], or [`CLIP_SUMMARY_METRICS`] for a clip case), `error`).
pub fn summary_csv(keys: &[String], columns: &[Metric], rows: &[SummaryRow]) -> Result<String, csv::Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header: Vec<String> = keys.to_vec();
    header.push("status".into());
    header.extend(columns.iter().map(|s| s.as_str().to_string()));
    header.push("error".into());
    w.write_record(&header)?;
    for r in rows {
        let mut rec: Vec<String> = r.point.iter().map(|(_, v)| v.to_string()).collect();
        rec.push(r.status.as_str().into());
        rec.extend(
            columns
                .iter()
                .map(|k| r.metrics.as_ref().and_then(|m| m.get(*k)).map(|v| summary_number(*k, v)).unwrap_or_default()),
        );
        rec.push(r.error.as_deref().unwrap_or("").replace('\n', " "));
        w.write_record(&rec)?;
    }
    let bytes = w.into_inner().map_err(|e| csv::Error::from(e.into_error()))?;
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

/// The columns of the summary that count (iterations, frames): written as integers.
pub const SUMMARY_INTEGER_METRICS: [Metric; 3] = [Metric::Iterations, Metric::Frames, Metric::IterationsMax];

/// A value of the summary: a count of [`SUMMARY_INTEGER_METRICS`] as an integer, any other
/// number with 10 significant digits.
fn summary_number(column: Metric, v: f64) -> String {
    let mut s = String::new();
    if SUMMARY_INTEGER_METRICS.contains(&column) {
        crate::io::number::push_integer(&mut s, v, 10);
    } else {
        crate::io::number::push_exp(&mut s, v, 10);
    }
    s
}

/// One point of a sweep in the Rust engine, writing its folder `dir` and its `run.json`
/// (`template` with the point's status and message). A run that stops at its iteration limit
/// still writes the files of its last iterate (its `run.json` says failed). A clip case solves
/// its whole clip ([`run_clip_point`]). A point reached after a stop was requested
/// (`crate::interrupt`) is not started and writes nothing.
pub fn run_point(case: &Case, dir: &Path, template: &Manifest) -> SweepOutcome {
    run_point_in(case, Engine::Rust, dir, template)
}

/// [`run_point`] in `engine` (the audit's reruns in FreeFEM, `audit::engines`).
pub fn run_point_in(case: &Case, engine: Engine, dir: &Path, template: &Manifest) -> SweepOutcome {
    let mut m = template.clone();
    m.input.engine = Some(engine.to_string());
    finish_point(dir, &m, case, solve_into(case, engine, dir, ClipOptions::default(), |_| {}, |_, _| {}))
}

/// The whole clip of a clip case in the Rust engine as a point of a sweep or audit, frames
/// streamed to `dir` and shown to `observer`, then the clip's figures (over the frames solved,
/// also when it stopped early) and its `run.json`. A clip that stops at a frame keeps the
/// converged frames; its status is `failed` (or `interrupted`).
pub fn run_clip_point(
    case: &Case,
    dir: &Path,
    template: &Manifest,
    format: crate::io::compact::OutputFormat,
    observer: impl FnMut(&ClipFrame) + Send,
) -> SweepOutcome {
    let opts = ClipOptions { format, ..ClipOptions::default() };
    finish_point(dir, template, case, solve_into(case, Engine::Rust, dir, opts, observer, |_, _| {}))
}

/// The `run.json` of a point of `command` (a sweep, an audit): the case and its file's hash,
/// the point's settings, the Rust engine.
pub fn point_manifest(command: &str, case: &Case, point: &Point) -> Manifest {
    let mut m = Manifest::new(command);
    m.input.case_name = Some(case.name.clone());
    m.input.case = super::job::case_file(case).ok().flatten();
    m.input.inputs = super::job::case_inputs(case).unwrap_or_default();
    m.input.settings = point.iter().cloned().collect();
    m.input.engine = Some("rust".into());
    m.recording.body_length = case.body_length();
    m
}

/// The point's `run.json`: `template` with the case's name, the point's status and message.
fn finish_point(dir: &Path, template: &Manifest, case: &Case, outcome: Solved) -> Solved {
    if !dir.is_dir() {
        return not_started(outcome);
    }
    let mut m = template.clone();
    m.certificate = outcome.certificate(case);
    if let Some(c) = &outcome.clip {
        m.frames.frames_done = Some(c.reports.len());
    }
    match m.finish(dir, outcome.status.into(), outcome.error.clone()) {
        Ok(()) => outcome,
        Err(e) => Solved::failed(chain(&e)),
    }
}

/// Run every point of a sweep of `case` (`points`: the grid of `case::sweep::product`, swept
/// `keys`) in parallel on `jobs` threads (0: one per core; at most one per point and
/// [`super::MAX_JOBS`]), each into its folder under `dir`
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
    let threads = super::threads_for(jobs, points.len());
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().map_err(|e| OutputError::Invalid {
        path: dir.to_path_buf(),
        reason: format!("cannot start the thread pool: {e}"),
    })?;
    let results: Vec<(String, Point, SweepOutcome)> = pool.install(|| {
        points
            .par_iter()
            .map(|(point, c)| {
                let template = point_manifest("sweep point", c, point);
                let r = with_kept_frames(c, run_point(c, &dir.join(&c.name), &template));
                tick();
                (c.name.clone(), point.clone(), r)
            })
            .collect()
    });
    stop_if_disk_full(dir, &results)?;
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
    let columns: &[Metric] = if case.clip().is_some() { &CLIP_SUMMARY_METRICS } else { &SUMMARY_METRICS };
    let text = summary_csv(keys, columns, &rows)
        .map_err(|e| OutputError::Invalid { path: dir.join("summary.csv"), reason: e.to_string() })?;
    crate::io::files::write_atomic(&dir.join("summary.csv"), text.as_bytes())?;
    let curves: Vec<(&String, &RunResult)> =
        results.iter().filter_map(|(name, _, o)| o.single.as_ref().map(|run| (name, run))).collect();
    if !curves.is_empty() {
        crate::output::run_files::write_convergence_plot(&curves, &dir.join("convergence.svg"))?;
    }
    Ok(rows)
}

/// A point that a stop request kept from starting says so (its row, no folder).
fn not_started(outcome: Solved) -> Solved {
    match outcome.status {
        Outcome::Interrupted => Solved { error: Some(NOT_STARTED.into()), ..outcome },
        _ => outcome,
    }
}

/// The message of a point not started because a stop was requested.
pub const NOT_STARTED: &str = "not started: a stop was requested before its turn";

/// A clip point of a sweep that stopped early (interrupted, failed) reports the metrics of the
/// frames it kept, so that its row says how many (`frames`) and how they went.
fn with_kept_frames(case: &Case, outcome: Solved) -> Solved {
    match (&outcome.metrics, &outcome.clip) {
        (None, Some(c)) if !c.reports.is_empty() => {
            Solved { metrics: Some(crate::engine::clip_metrics::clip_metrics(case, c)), ..outcome }
        }
        _ => outcome,
    }
}

/// A point stopped by a full disk stops the sweep: its folder is not a result to put in place.
fn stop_if_disk_full(dir: &Path, results: &[(String, Point, SweepOutcome)]) -> Result<(), OutputError> {
    match results.iter().find(|(_, _, o)| o.disk_full) {
        Some((name, _, o)) => Err(OutputError::DiskFull {
            path: dir.join(name),
            message: o.error.clone().unwrap_or_else(|| "no space left on device".into()),
        }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_has_header_and_failures() {
        let mut m = Metrics::new();
        m.insert(Metric::Iterations, 12.0);
        let rows = vec![
            SummaryRow {
                name: String::new(),
                point: vec![("lambda_l".into(), 1e-20.into())],
                status: Outcome::Converged,
                metrics: Some(m.clone()),
                error: None,
            },
            SummaryRow {
                name: String::new(),
                point: vec![("lambda_l".into(), 1e3.into())],
                status: Outcome::IterationLimit,
                metrics: Some(m),
                error: Some("did not converge,\nat all".into()),
            },
            SummaryRow {
                name: String::new(),
                point: vec![("lambda_l".into(), 1.0.into())],
                status: Outcome::Failed,
                metrics: None,
                error: Some("bad".into()),
            },
        ];
        let text = summary_csv(&["lambda_l".into()], &SUMMARY_METRICS, &rows).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert!(lines[0].starts_with("lambda_l,status,iterations,certificate,x_err_rel"), "{}", lines[0]);
        assert!(lines[1].starts_with("1e-20,ok,12,"), "{}", lines[1]);
        assert!(
            lines[2].starts_with("1e3,not_converged,12,") && lines[2].ends_with("\"did not converge, at all\""),
            "{}",
            lines[2]
        );
        assert!(lines[3].starts_with("1,failed,,") && lines[3].ends_with(",bad"), "{}", lines[3]);
    }
}
