//! `with_truth`: a check with the errors of its runs' points against the substitute's ground
//! truth (`crate::audit::truth`) in its numbers, and in its outcome where the paper's sentence
//! is about recovering the worm's state.
use super::super::numbers::{input, sig2};
use super::super::spec::{Check, Selector};
use super::super::RunResults;
use super::compound::both;
use super::{evaluate, CheckError, Holding};

/// `with_truth`: the outcome and text of `check`, with the errors against the truth of every
/// point of the runs `runs` (`truth_bending_err_rel_mean`, `truth_twist_err_rel`); with
/// `bending_below` or `twist_below` the check holds only where the errors are within them
/// (the outcomes combine as `all`: holds when both hold, fails when both fail).
pub fn with_truth(
    check: &Check,
    runs: &[RunResults],
    names: &[String],
    (bending_below, twist_below): (Option<f64>, Option<f64>),
) -> Result<(Holding, String), CheckError> {
    let (inner, mut text) = evaluate(check, runs);
    let (mut good, mut total) = (0usize, 0usize);
    let mut parts = Vec::new();
    for name in names {
        let r = runs.iter().find(|r| r.name == *name).ok_or_else(|| CheckError::NoRun { run: name.clone() })?;
        for p in r.select(&Selector::new()) {
            let (b, w) = (p.metric("truth_bending_err_rel_mean"), p.metric("truth_twist_err_rel"));
            let label = if p.point.is_empty() { name.clone() } else { format!("{name} {}", p.label) };
            let show = |v: Option<f64>| v.map_or_else(|| "–".to_string(), |v| format!("{} %", sig2(100.0 * v)));
            parts.push(format!("{label}: bending error {}, twist error {} of the true twist", show(b), show(w)));
            let within = |v: Option<f64>, lim: Option<f64>| lim.is_none_or(|l| v.is_some_and(|v| v <= l));
            total += 1;
            if within(b, bending_below) && within(w, twist_below) {
                good += 1;
            }
        }
    }
    text.push_str(&format!("; against the truth: {}", parts.join("; ")));
    if bending_below.is_none() && twist_below.is_none() {
        return Ok((inner, text));
    }
    let limits: Vec<String> = [("bending", bending_below), ("twist", twist_below)]
        .iter()
        .filter_map(|(w, l)| l.map(|l| format!("{w} error ≤ {} %", input(100.0 * l))))
        .collect();
    text.push_str(&format!(" (claim: {})", limits.join(", ")));
    let truth = match good {
        g if g == total => Holding::Holds,
        0 => Holding::Fails,
        _ => Holding::Partly,
    };
    Ok((both(inner, truth), text))
}
