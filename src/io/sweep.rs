//! The files of a parameter sweep: one folder per grid point (the files of `run`, or of the
//! last iterate with `FAILED.txt` when the point did not converge) and `summary.csv`. The
//! grid itself is `case::sweep`'s. A point of a clip case solves the whole clip (the frames
//! of `run` on a clip, its row the metrics of `run::clip_metrics`).
use std::path::Path;

use super::data::write_data;
use super::engine::{load_data, run_clip_case_observed, run_inverse_on, write_clip_figures, EngineError};
use super::files::write_atomic;
use super::run_files::write_run;
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
}

/// Outcome of one run of a sweep.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunStatus {
    Ok,
    /// iteration limit reached; the metrics are those of the last iterate
    NotConverged,
    Failed,
}

impl RunStatus {
    pub fn as_str(&self) -> &'static str {
        match self {
            RunStatus::Ok => "ok",
            RunStatus::NotConverged => "not_converged",
            RunStatus::Failed => "failed",
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

/// One point of a sweep in the Rust engine, writing its folder `dir`. A run that stops at its
/// iteration limit still writes the files of its last iterate, plus `FAILED.txt` with the error.
/// A clip case solves its whole clip ([`run_clip_point`]).
pub fn run_point(case: &Case, dir: &Path) -> SweepOutcome {
    if case.clip().is_some() {
        return run_clip_point(case, dir, |_| {});
    }
    let failed = |e: &dyn std::fmt::Display| SweepOutcome::failed(e.to_string());
    let outcome: Result<RunResult, EngineError> = if case.inverse().is_some() {
        let path = dir.join("data.csv");
        match load_data(case).and_then(|d| Ok(write_data(&path, &d)?)) {
            Ok(()) => run_inverse_on(case, crate::run::Engine::Rust, &path, &dir.join("freefem_work"), |_, _| {}),
            Err(e) => return failed(&format_args!("case {}: generating the forward data: {}", case.name, chain(&e))),
        }
    } else {
        run_forward(case, |_, _| {}).map_err(EngineError::from)
    };
    let (status, r, error) = match outcome {
        Ok(r) => (RunStatus::Ok, r, None),
        Err(EngineError::Run(RunError::Incomplete { source, partial })) => {
            (RunStatus::NotConverged, *partial, Some(source.to_string()))
        }
        Err(e) => return failed(&format_args!("case {}: {}", case.name, chain(&e))),
    };
    let write = || -> Result<Metrics, String> {
        let m = all_metrics(case, &r).map_err(|e| chain(&e))?;
        write_run(case, &r, &m, dir).map_err(|e| chain(&e))?;
        if let Some(e) = &error {
            write_atomic(&dir.join("FAILED.txt"), format!("{e}\nThe files here hold the last iterate.\n").as_bytes())
                .map_err(|e| chain(&e))?;
        }
        Ok(m)
    };
    match write() {
        Ok(m) => SweepOutcome { status, metrics: Some(m), run: Some(r), clip: None, error },
        Err(e) => failed(&e),
    }
}

/// The whole clip of a clip case in the Rust engine, frames streamed to `dir` and shown to
/// `observer`, then the clip's figures. A clip that stops at a frame keeps the converged frames
/// and writes `FAILED.txt` naming the frame; its status is `failed`.
pub fn run_clip_point(case: &Case, dir: &Path, observer: impl FnMut(&ClipFrame) + Send) -> SweepOutcome {
    let failed = |e: String| {
        let _ = write_atomic(
            &dir.join("FAILED.txt"),
            format!("{e}\nThe converged frames before it are in this folder.\n").as_bytes(),
        );
        SweepOutcome::failed(e)
    };
    let run = match run_clip_case_observed(case, dir, observer, |_, _| {}) {
        Ok(r) => r,
        Err(e) => return failed(format!("case {}: {}", case.name, chain(&e))),
    };
    if let Err(e) = write_clip_figures(case, &run, dir) {
        return failed(format!("case {}: {}", case.name, chain(&e)));
    }
    let m = clip_metrics(case, &run);
    SweepOutcome { status: RunStatus::Ok, metrics: Some(m), run: None, clip: Some(run), error: None }
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
                point: vec![("lambda_l".into(), 1e-20)],
                status: RunStatus::Ok,
                metrics: Some(m.clone()),
                error: None,
            },
            SummaryRow {
                point: vec![("lambda_l".into(), 1e3)],
                status: RunStatus::NotConverged,
                metrics: Some(m),
                error: Some("did not converge,\nat all".into()),
            },
            SummaryRow {
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
