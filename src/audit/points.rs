//! The points of a check's runs and how the report names them: the selection of a run's
//! points, their labels, why a point did not converge, and the outcome of a check over them
//! (shared by the checks of `check` and the convergence claims of `convergence`).
use super::numbers::{round_numbers, sig2};
use super::spec::Selector;
use super::{PointResult, RunResults};
use crate::engine::metrics::Metric;
use crate::solve;

/// How far a check holds (not an outcome of a run: that is `solve::Outcome`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Holding {
    Holds,
    /// holds on some points of the grid only
    Partly,
    Fails,
}

/// A point's label for the report: `λd = 1e-2` style from its grid values (`key=value`).
pub fn point_label(p: &PointResult) -> String {
    if p.point.is_empty() {
        return "the run".into();
    }
    p.point.iter().map(|(k, v)| format!("{k} = {v}")).collect::<Vec<_>>().join(", ")
}

/// Values of the points, `1e-20, 1e-10, 1` (single grid key) or full labels.
pub fn values(points: &[&PointResult]) -> String {
    let single = points.iter().all(|p| p.point.len() == 1);
    points.iter().map(|p| if single { p.point[0].1.to_string() } else { point_label(p) }).collect::<Vec<_>>().join(", ")
}

/// The grid key of a run with one key (for "λd = …" phrasing).
pub fn key_of(points: &[&PointResult]) -> String {
    points.first().and_then(|p| (p.point.len() == 1).then(|| p.point[0].0.clone())).unwrap_or_default()
}

/// Why a point did not converge, shortly: `not converged after N iterations` or the error.
pub fn failure(p: &PointResult) -> String {
    let e = p.outcome.error.as_deref().unwrap_or("no result");
    match p.outcome.status {
        solve::Outcome::IterationLimit | solve::Outcome::Stalled => {
            let its = p.value(Metric::Iterations).map(|i| format!(" after {i}")).unwrap_or_default();
            let x = p.value(Metric::XErrRel).map(|x| format!(", x error {}", sig2(x))).unwrap_or_default();
            let c = p.value(Metric::Certificate).map(|c| format!(", certificate {}", sig2(c))).unwrap_or_default();
            let word = if p.outcome.status == solve::Outcome::Stalled { "stalled" } else { "not converged" };
            format!("{word}{its} iterations{x}{c}")
        }
        _ => {
            // the innermost cause: after the last ": " of the error chain
            let short = e.rsplit(": ").take(2).collect::<Vec<_>>().into_iter().rev().collect::<Vec<_>>().join(": ");
            // whole: the report wraps it, and a cut message hides its end
            format!("failed: {}", round_numbers(&short.replace('\n', " ")))
        }
    }
}

/// Why a check could not be evaluated on the runs' points (a spec that names a run, point,
/// metric or history the runs do not have); the report says "not evaluated: …".
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CheckError {
    #[error("no run `{run}`")]
    NoRun { run: String },
    #[error("run `{run}` has no point {at:?}")]
    NoPoint { run: String, at: Selector },
    #[error("run `{run}` at {at:?} selects {count} points, not one")]
    NotOnePoint { run: String, at: Selector, count: usize },
    /// `point`: the point's label (`lambda_d = 1e-2`, `the run`)
    #[error("`{metric}` missing at {point}")]
    MissingMetric { metric: String, point: String },
    #[error("`within_factor` needs two points or more (run `{run}` and `with`)")]
    TooFewPoints { run: String },
    #[error("`{metric}` missing at some points of `{run}`")]
    MissingAtSomePoints { metric: String, run: String },
    #[error("no `{history}` history at the reference point")]
    NoHistory { history: String },
}

/// The points of `run` selected by `at`.
pub fn select<'a>(runs: &'a [RunResults], run: &str, at: &Selector) -> Result<Vec<&'a PointResult>, CheckError> {
    let r = runs.iter().find(|r| r.name == run).ok_or_else(|| CheckError::NoRun { run: run.to_string() })?;
    let pts: Vec<&PointResult> = r.select(at).collect();
    if pts.is_empty() {
        return Err(CheckError::NoPoint { run: run.to_string(), at: at.clone() });
    }
    Ok(pts)
}

/// The outcome of a check that holds at `good` of `total` points.
pub fn outcome(good: usize, total: usize) -> Holding {
    if good == total {
        Holding::Holds
    } else if good > 0 {
        Holding::Partly
    } else {
        Holding::Fails
    }
}
