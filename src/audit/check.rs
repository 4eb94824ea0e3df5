//! Judging a claim: the check of its spec on the runs' points gives a [`Holding`] (holds,
//! holds in part, fails) and our numbers as text; the verdict follows from the outcome and the
//! claim's declared fallbacks. Numbers are written as `numbers` says: two significant digits,
//! counts exactly, a value beside its reference with the digits that show their difference.
use super::cause::{fill, PointState};
use super::convergence::{converges, met_rule, Claimed};
use super::numbers::{against, input, sig2};
use super::points::{key_of, outcome, point_label, select, values};
pub use super::points::{CheckError, Holding};
use super::spec::{Check, Claim, Ref, Selector, Spec};
use super::{ClaimResult, PointResult, RunResults, Verdict};
use crate::jobs::sweep::NOT_STARTED;
use crate::solve;

mod compound;
mod truth_rows;

/// `metric` at each point, `label: value` joined by commas (no label for a single point),
/// each value with the digits that show its difference from `reference`.
fn metric_list(pts: &[&PointResult], metric: &str, reference: f64) -> String {
    pts.iter()
        .map(|p| {
            let label = if pts.len() == 1 { String::new() } else { format!("{}: ", point_label(p)) };
            format!("{label}{}", p.metric(metric).map_or_else(|| "–".into(), |v| against(v, reference)))
        })
        .collect::<Vec<_>>()
        .join(", ")
}

fn metric_text(p: &PointResult, metric: &str) -> String {
    p.metric(metric).map(sig2).unwrap_or_else(|| "–".into())
}

fn one<'a>(runs: &'a [RunResults], r: &Ref) -> Result<&'a PointResult, CheckError> {
    let pts = select(runs, &r.run, &r.at)?;
    match pts.as_slice() {
        [p] => Ok(p),
        _ => Err(CheckError::NotOnePoint { run: r.run.clone(), at: r.at.clone(), count: pts.len() }),
    }
}

/// Evaluate a check: its outcome and our numbers.
pub fn evaluate(check: &Check, runs: &[RunResults]) -> (Holding, String) {
    match evaluate_inner(check, runs) {
        Ok(r) => r,
        Err(e) => (Holding::Fails, format!("not evaluated: {e}")),
    }
}

fn split_by<'a>(
    pts: &[&'a PointResult],
    ok: impl Fn(&PointResult) -> bool,
) -> (Vec<&'a PointResult>, Vec<&'a PointResult>) {
    pts.iter().partition(|p| ok(p))
}

/// The outcome and text of `check`, one stage per kind of check.
fn evaluate_inner(check: &Check, runs: &[RunResults]) -> Result<(Holding, String), CheckError> {
    match check {
        Check::Converges { run } => converges(runs, run, Claimed::Converges),
        Check::DoesNotConverge { run, with } => {
            let mut all = converges(runs, run, Claimed::DoesNotConverge)?;
            for w in with {
                let (o, text) = converges(runs, w, Claimed::DoesNotConverge)?;
                all.1.push_str(&format!("; {w}: {text}"));
                all.0 = match (all.0, o) {
                    (Holding::Holds, Holding::Holds) => Holding::Holds,
                    (Holding::Fails, Holding::Fails) => Holding::Fails,
                    _ => Holding::Partly,
                };
            }
            Ok(all)
        }
        Check::Below { run, metric, limit, at, with } => threshold(runs, (run, with), metric, *limit, at, Side::AtMost),
        Check::Above { run, metric, limit, at, with } => {
            threshold(runs, (run, with), metric, *limit, at, Side::AtLeast)
        }
        Check::Increasing { run, metric } => increasing(runs, run, metric),
        Check::RatioAbove { metric, numerator, denominator, limit } => {
            ratio(runs, metric, numerator, denominator, *limit, Side::AtLeast)
        }
        Check::RatioBelow { metric, numerator, denominator, limit } => {
            ratio(runs, metric, numerator, denominator, *limit, Side::AtMost)
        }
        Check::WithinFactor { run, metric, factor, with, also } => {
            let mut worst = within_factor(runs, run, metric, *factor, with)?;
            for m in also {
                let (o, text) = within_factor(runs, run, m, *factor, with)?;
                worst.1.push_str(&format!("; {text}"));
                worst.0 = match (worst.0, o) {
                    (Holding::Fails, _) | (_, Holding::Fails) => Holding::Fails,
                    (Holding::Partly, _) | (_, Holding::Partly) => Holding::Partly,
                    _ => Holding::Holds,
                };
            }
            Ok(worst)
        }
        Check::Magnitude { run, metric, value, orders, at } => magnitude(runs, run, metric, *value, *orders, at),
        Check::SameHistories { run, history, reference, limit } => {
            same_histories(runs, run, history, reference, *limit)
        }
        Check::All { checks } => Ok(compound::all(checks, runs)),
        Check::Varies { run, with, metrics, factor } => compound::varies(runs, run, with, metrics, *factor),
        Check::WithTruth { check, runs: names, bending_below, twist_below } => {
            truth_rows::with_truth(check, runs, names, (*bending_below, *twist_below))
        }
    }
}

/// Which side of its limit a value must lie on: `≤` (`below`, `ratio_below`) or `≥` (`above`,
/// `ratio_above`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Side {
    AtMost,
    AtLeast,
}

impl Side {
    /// Does `v` lie on this side of `limit` (the limit included)?
    fn holds(self, v: f64, limit: f64) -> bool {
        match self {
            Side::AtMost => v <= limit,
            Side::AtLeast => v >= limit,
        }
    }

    /// `≤` or `≥`, as the claim's text writes it.
    fn symbol(self) -> &'static str {
        match self {
            Side::AtMost => "≤",
            Side::AtLeast => "≥",
        }
    }
}

/// `below` (or `above`, as `side` says): `metric ≤ limit` (`≥`) at every selected point of
/// `run` and every point of the runs `with`.
fn threshold(
    runs: &[RunResults],
    (run, with): (&str, &[String]),
    metric: &str,
    limit: f64,
    at: &Selector,
    side: Side,
) -> Result<(Holding, String), CheckError> {
    let mut pts = select(runs, run, at)?;
    let mut list = metric_list(&pts, metric, limit);
    for w in with {
        let more = select(runs, w, &Selector::new())?;
        list.push_str(&format!("; {w}: {}", metric_list(&more, metric, limit)));
        pts.extend(more);
    }
    let pass = |p: &PointResult| p.metric(metric).is_some_and(|v| side.holds(v, limit));
    let (ok, _) = split_by(&pts, pass);
    let rel = side.symbol();
    Ok((outcome(ok.len(), pts.len()), format!("{metric} {list} (claim: {rel} {})", input(limit))))
}

/// `increasing`: `metric` rises along the run's single grid key.
fn increasing(runs: &[RunResults], run: &str, metric: &str) -> Result<(Holding, String), CheckError> {
    let pts = select(runs, run, &Selector::new())?;
    let mut sorted = pts.clone();
    sorted.sort_by(|a, b| {
        let v = |p: &PointResult| p.point.first().and_then(|x| x.1.number()).unwrap_or(0.0);
        v(a).total_cmp(&v(b))
    });
    let vals: Vec<Option<f64>> = sorted.iter().map(|p| p.metric(metric)).collect();
    let rising = vals.windows(2).filter(|w| matches!((w[0], w[1]), (Some(a), Some(b)) if b > a)).count();
    let text = format!(
        "{metric} at {} = {}: {}",
        key_of(&sorted),
        values(&sorted),
        sorted.iter().map(|p| metric_text(p, metric)).collect::<Vec<_>>().join(", ")
    );
    Ok((outcome(rising, vals.len().saturating_sub(1)), text))
}

/// `ratio_above` (or `ratio_below`, as `side` says): `metric(numerator) / metric(denominator) ≥
/// limit` (`≤`).
fn ratio(
    runs: &[RunResults],
    metric: &str,
    numerator: &Ref,
    denominator: &Ref,
    limit: f64,
    side: Side,
) -> Result<(Holding, String), CheckError> {
    let (a, b) = (one(runs, numerator)?, one(runs, denominator)?);
    let missing = |p: &PointResult| CheckError::MissingMetric { metric: metric.to_string(), point: point_label(p) };
    let (va, vb) = (a.metric(metric).ok_or_else(|| missing(a))?, b.metric(metric).ok_or_else(|| missing(b))?);
    let ratio = va / vb;
    let pass = side.holds(ratio, limit);
    let text = format!(
        "{metric}: {} ({}, {}) / {} ({}, {}) = {} (claim: {} {})",
        sig2(va),
        numerator.run,
        point_label(a),
        sig2(vb),
        denominator.run,
        point_label(b),
        against(ratio, limit),
        side.symbol(),
        input(limit)
    );
    Ok((if pass { Holding::Holds } else { Holding::Fails }, text))
}

/// `within_factor`: `max / min` of the magnitudes of `metric` over the points of `run` and of
/// the runs `with` at most `factor`; partly when a group of two or more points is.
fn within_factor(
    runs: &[RunResults],
    run: &str,
    metric: &str,
    factor: f64,
    with: &[String],
) -> Result<(Holding, String), CheckError> {
    let empty = Selector::new();
    let mut pts = select(runs, run, &empty)?;
    // (run, point) names for a check across runs
    let mut names: Vec<String> = pts.iter().map(|p| format!("{run} {}", p.label)).collect();
    for w in with {
        let more = select(runs, w, &empty)?;
        names.extend(more.iter().map(|p| format!("{w} {}", p.label)));
        pts.extend(more);
    }
    if pts.len() < 2 {
        return Err(CheckError::TooFewPoints { run: run.to_string() });
    }
    // magnitudes: a deflection is negative
    let v: Vec<f64> = pts.iter().filter_map(|p| p.metric(metric)).map(f64::abs).collect();
    if v.len() != pts.len() {
        return Err(CheckError::MissingAtSomePoints { metric: metric.to_string(), run: run.to_string() });
    }
    let (lo, hi) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
    // The largest group of points within the factor of each other, for a partial answer.
    let within = |x: f64| v.iter().filter(|y| **y >= x && **y <= x * factor).count();
    let best = v.iter().map(|x| within(*x)).max().unwrap_or(0);
    let at = if with.is_empty() { format!("{} = {}", key_of(&pts), values(&pts)) } else { names.join(", ") };
    let text = format!(
        "{metric} at {at}: {} (max/min of the magnitudes 1 + {}; claim: ≤ 1 + {})",
        pts.iter().map(|p| metric_text(p, metric)).collect::<Vec<_>>().join(", "),
        if hi == 0.0 { "0".to_string() } else { against(hi / lo - 1.0, factor - 1.0) },
        input(factor - 1.0)
    );
    // every value 0 (a term whose weight is 0): the same everywhere
    let o = if hi <= lo * factor || hi == 0.0 {
        Holding::Holds
    } else if best > 1 {
        Holding::Partly
    } else {
        Holding::Fails
    };
    Ok((o, text))
}

/// `magnitude`: `metric` within `orders` orders of magnitude of `value` at every selected point.
fn magnitude(
    runs: &[RunResults],
    run: &str,
    metric: &str,
    value: f64,
    orders: f64,
    at: &Selector,
) -> Result<(Holding, String), CheckError> {
    let pts = select(runs, run, at)?;
    let apart = |p: &PointResult| p.metric(metric).map(|v| (v.abs() / value).log10().abs());
    let (ok, _) = split_by(&pts, |p| apart(p).is_some_and(|o| o <= orders));
    let list = metric_list(&pts, metric, value);
    let text = format!("{metric} {list} (claim: within {} orders of magnitude of {})", input(orders), input(value));
    Ok((outcome(ok.len(), pts.len()), text))
}

/// Spread and length of each point's history
type Spreads<'a> = Vec<(&'a PointResult, Option<(f64, usize)>)>;

/// The reference point of `same_histories`, its history, and for each other point of `run`
/// the largest relative spread of its history from the reference's over their common
/// iterations, with its length.
fn history_spreads<'a>(
    runs: &'a [RunResults],
    run: &str,
    history: &str,
    reference: &Selector,
) -> Result<(&'a PointResult, Vec<f64>, Spreads<'a>), CheckError> {
    let pts = select(runs, run, &Selector::new())?;
    let base = one(runs, &Ref { run: run.to_string(), at: reference.clone() })?;
    let hb = history_of(base, history).ok_or_else(|| CheckError::NoHistory { history: history.to_string() })?;
    let spreads = pts
        .into_iter()
        .filter(|p| !std::ptr::eq(*p, base))
        .map(|p| {
            let s = history_of(p, history).map(|hp| {
                let n = hp.len().min(hb.len());
                ((0..n).map(|i| (hp[i] - hb[i]).abs() / hb[i].abs()).fold(0.0, f64::max), hp.len())
            });
            (p, s)
        })
        .collect();
    Ok((base, hb, spreads))
}

/// The same curve also stops at the same iteration (±1 %, at least one).
fn same_length(n: usize, reference: usize) -> bool {
    n.abs_diff(reference) as f64 <= (0.01 * reference as f64).max(1.0)
}

/// `same_histories`: the `history` of every point of `run` against the `reference` point's,
/// relative spread ≤ `limit` over their common iterations and the same length ±1 %.
fn same_histories(
    runs: &[RunResults],
    run: &str,
    history: &str,
    reference: &Selector,
    limit: f64,
) -> Result<(Holding, String), CheckError> {
    let (base, hb, spreads) = history_spreads(runs, run, history, reference)?;
    let same_length = |n: usize| same_length(n, hb.len());
    let good = spreads.iter().filter(|(_, s)| s.is_some_and(|(s, n)| s <= limit && same_length(n))).count();
    let text = format!(
        "max relative spread of the {history} history against {} ({} iterations): {} (claim: ≤ {} and the \
         same number of iterations ±1 %)",
        point_label(base),
        hb.len(),
        spreads
            .iter()
            .map(|(p, s)| format!(
                "{}: {}",
                p.point.first().map(|x| x.1.to_string()).unwrap_or_default(),
                s.map(|(s, n)| format!("{} ({n} its)", against(s, limit))).unwrap_or_else(|| "–".into())
            ))
            .collect::<Vec<_>>()
            .join(", "),
        input(limit)
    );
    Ok((outcome(good, spreads.len()), text))
}

/// A per-iteration history of an inverse point: `x_err_rel`, `rel_change`, `tangent_misfit`,
/// `j_total`, `kappa_err_rel`, `kappa_err_rel_inner`.
pub fn history_of(p: &PointResult, name: &str) -> Option<Vec<f64>> {
    let inv = p.outcome.single.as_ref()?.inverse.as_ref()?;
    let h = &inv.history;
    Some(match name {
        "x_err_rel" => h.iter().map(|r| r.x_err_rel).collect(),
        "rel_change" => h.iter().map(|r| r.rel_change).collect(),
        "tangent_misfit" => h.iter().map(|r| r.tangent_misfit).collect(),
        "j_total" => h.iter().map(|r| r.objective.total()).collect(),
        "kappa_err_rel" => inv.kappa_err.iter().map(|k| k[0]).collect(),
        "kappa_err_rel_inner" => inv.kappa_err.iter().map(|k| k[1]).collect(),
        _ => return None,
    })
}

/// Where the runs of `check` solve otherwise than the paper's scheme (the relaxed fixed point
/// of eq. (61) with w = 0.5, Remark 10, on the chart of eq. (1)): Newton (I8), the rebased
/// chart (docs/rotation.md), the λd blend ε (I11), our quadrature mix (D4). Empty: the
/// paper's scheme as printed, in one of its one-rule readings.
pub fn scheme_deviations(spec: &Spec, check: &Check) -> Vec<String> {
    use crate::model::mesh::QuadratureScheme;
    use crate::solve::inverse::InverseMethod;
    let mut out: Vec<String> = Vec::new();
    let mut add = |s: String| {
        if !out.contains(&s) {
            out.push(s);
        }
    };
    for run in check.runs().iter().filter_map(|r| spec.run(r)) {
        let Some(inv) = run.case.inverse() else { continue };
        let p = &inv.params;
        if matches!(p.method, InverseMethod::Newton { .. }) {
            add("Newton (docs/inverse.md I8), not the fixed point".into());
        }
        if run.case.clip().is_some_and(|c| c.rotation == crate::solve::sequence::RotationTreatment::Rebased) {
            add("rebased chart per frame (docs/rotation.md)".into());
        }
        if p.stabilisation > 0.0 {
            add(format!("λd blend ε = {} (I11)", sig2(p.stabilisation)));
        }
        if run.case.quadrature == QuadratureScheme::Selective {
            add("selective quadrature (D4)".into());
        }
    }
    out
}

/// A point that a signal stopped, or kept from starting: its outcome says nothing about the
/// scheme (its "failed" is not a failure to converge).
pub fn stopped(p: &PointResult) -> bool {
    p.outcome.status == solve::Outcome::Interrupted
        || p.outcome.error.as_deref().is_some_and(|e| e.contains("interrupted by a signal") || e.contains(NOT_STARTED))
}

/// Why `check` cannot be judged on `runs`: the points of its runs that a signal stopped.
fn unjudgeable(check: &Check, runs: &[RunResults]) -> Option<String> {
    let why: Vec<String> = check
        .runs()
        .iter()
        .filter_map(|name| {
            let r = runs.iter().find(|r| r.name == *name)?;
            let n = r.points.iter().filter(|p| stopped(p)).count();
            (n > 0).then(|| format!("{n} of {} points of run `{name}` stopped or never started", r.points.len()))
        })
        .collect();
    (!why.is_empty()).then(|| format!("not judged: {}", why.join(", ")))
}

/// Judge `claim` of `spec` on its runs; not judged (verdict `None`) when a point it reads was
/// stopped by a signal.
pub fn judge(spec: &Spec, claim: &Claim, runs: &[RunResults]) -> ClaimResult {
    let result = |verdict, ours, cause| ClaimResult {
        spec: spec.name.clone(),
        claim: claim.clone(),
        verdict,
        ours,
        standard: super::convergence::standard(&claim.check, runs),
        cause,
        figure: claim.figure.clone(),
        engines: None,
    };
    if let Some(why) = unjudgeable(&claim.check, runs) {
        return result(None, why, None);
    }
    let (o, mut ours) = evaluate(&claim.check, runs);
    // the cause explains a failure: none for a check that holds
    let cause = match (o, &claim.caveats.cause) {
        (Holding::Holds, _) | (_, None) => None,
        (_, Some(text)) => Some(fill(text, &point_states(&claim.check, runs))),
    };
    if let Some(s) = &claim.caveats.substitute {
        ours = format!("{ours} [on {s}]");
    }
    let deviations = scheme_deviations(spec, &claim.check);
    if !deviations.is_empty() {
        ours = format!("{ours} [scheme not the paper's: {}]", deviations.join(", "));
    }
    if let Some(p) = &claim.caveats.partial {
        ours = format!("{ours} [partial check: {p}]");
    }
    // A claim on data we do not have is "not computable here" when its check holds on the
    // substitute; when it does not hold there either, the substitute's outcome decides.
    let verdict = match (o, claim.caveats.not_computable.is_some()) {
        (Holding::Holds, true) => Verdict::NotComputable,
        (Holding::Holds, false) => Verdict::Reproduced,
        (Holding::Partly, _) => claim.fallback.if_partly,
        (Holding::Fails, _) => claim.fallback.if_fails,
    };
    // a check weaker than the paper's words cannot reproduce it
    let verdict = match (verdict, &claim.caveats.partial) {
        (Verdict::Reproduced | Verdict::NotComputable, Some(_)) => Verdict::Differs,
        (v, _) => v,
    };
    result(Some(verdict), ours, cause)
}

/// The points of a `converges` or `same_histories` check in the order of the grid, each
/// holding or not, for the placeholders of its cause (`super::cause`); none for other checks.
fn point_states(check: &Check, runs: &[RunResults]) -> Vec<PointState> {
    let state = |p: &PointResult, holds: bool| PointState {
        value: p.point.first().map_or_else(|| point_label(p), |x| x.1.to_string()),
        holds,
        stalled: p.outcome.status == solve::Outcome::Stalled,
    };
    match check {
        Check::Converges { run } => select(runs, run, &Selector::new())
            .map(|pts| pts.iter().map(|p| state(p, met_rule(p))).collect())
            .unwrap_or_default(),
        Check::SameHistories { run, history, reference, limit } => {
            let Ok((base, hb, spreads)) = history_spreads(runs, run, history, reference) else { return Vec::new() };
            let holds = |p: &PointResult| {
                std::ptr::eq(p, base)
                    || spreads.iter().any(|(q, s)| {
                        std::ptr::eq(*q, p) && s.is_some_and(|(s, n)| s <= *limit && same_length(n, hb.len()))
                    })
            };
            select(runs, run, &Selector::new())
                .map(|pts| pts.iter().map(|p| state(p, holds(p))).collect())
                .unwrap_or_default()
        }
        Check::WithTruth { check, .. } => point_states(check, runs),
        _ => Vec::new(),
    }
}
