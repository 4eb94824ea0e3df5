//! Checks made of other checks or of a spread, for sentences of the paper that say several
//! things at once or that a quantity changes:
//! - `all`: every check of a list holds (a sentence with several parts, each its own check);
//! - `varies`: some metric of a list changes by more than a factor over the points of a run
//!   and of the runs `with` (§6, Remark 13: "we again can observe a variation of other
//!   objective terms"), the converse of `within_factor`.
use super::super::numbers::{input, sig2};
use super::super::spec::{Check, Selector};
use super::super::{PointResult, RunResults};
use super::{evaluate, CheckError, Holding};

/// Two outcomes of one sentence together: holds when both hold, fails when both fail,
/// partly otherwise.
pub fn both(a: Holding, b: Holding) -> Holding {
    match (a, b) {
        (Holding::Holds, Holding::Holds) => Holding::Holds,
        (Holding::Fails, Holding::Fails) => Holding::Fails,
        _ => Holding::Partly,
    }
}

/// `all`: each check's outcome and text, numbered; holds when every check holds, fails when
/// every check fails, partly otherwise.
pub fn all(checks: &[Check], runs: &[RunResults]) -> (Holding, String) {
    let results: Vec<(Holding, String)> = checks.iter().map(|c| evaluate(c, runs)).collect();
    let outcome = if results.iter().all(|r| r.0 == Holding::Holds) {
        Holding::Holds
    } else if results.iter().all(|r| r.0 == Holding::Fails) {
        Holding::Fails
    } else {
        Holding::Partly
    };
    let word = |o: Holding| match o {
        Holding::Holds => "holds",
        Holding::Partly => "holds in part",
        Holding::Fails => "fails",
    };
    let text: Vec<String> =
        results.iter().enumerate().map(|(i, (o, t))| format!("({}) {t} [{}]", i + 1, word(*o))).collect();
    (outcome, text.join("; "))
}

/// `varies`: `max / min` of the magnitude of each metric of `metrics` over the points of `run`
/// and of the runs `with`; holds when some metric's exceeds `factor`.
pub fn varies(
    runs: &[RunResults],
    run: &str,
    with: &[String],
    metrics: &[String],
    factor: f64,
) -> Result<(Holding, String), CheckError> {
    let mut pts: Vec<&PointResult> = Vec::new();
    for name in std::iter::once(run).chain(with.iter().map(String::as_str)) {
        let r = runs.iter().find(|r| r.name == name).ok_or_else(|| CheckError::NoRun { run: name.to_string() })?;
        pts.extend(r.select(&Selector::new()));
    }
    if pts.len() < 2 {
        return Err(CheckError::TooFewPoints { run: run.to_string() });
    }
    let mut parts = Vec::new();
    let mut varied = false;
    for metric in metrics {
        let v: Vec<f64> = pts.iter().filter_map(|p| p.metric(metric)).map(f64::abs).collect();
        if v.len() != pts.len() {
            return Err(CheckError::MissingAtSomePoints { metric: metric.clone(), run: run.to_string() });
        }
        let (lo, hi) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
        let spread = if lo > 0.0 {
            hi / lo
        } else if hi > 0.0 {
            f64::INFINITY
        } else {
            1.0
        };
        varied |= spread > factor;
        parts.push(format!("{metric} {}", if spread.is_finite() { sig2(spread) } else { "∞".into() }));
    }
    let text = format!("max/min over {} points: {} (claim: some > {})", pts.len(), parts.join(", "), input(factor));
    Ok((if varied { Holding::Holds } else { Holding::Fails }, text))
}
