//! Judging a claim: the check of its spec on the runs' points gives an [`Outcome`] (holds,
//! holds in part, fails) and our numbers as text; the verdict follows from the outcome and the
//! claim's declared fallbacks. Numbers are printed with two significant digits, so that the
//! report's text changes only when a result does.
use super::spec::{Check, Claim, Ref, Selector, Spec};
use super::{ClaimResult, PointResult, RunResults, Verdict};
use crate::io::sweep::{RunStatus, NOT_STARTED};

/// How far a check holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    Holds,
    /// holds on some points of the grid only
    Partly,
    Fails,
}

/// `x` with two significant digits: plain for 0.01 ≤ |x| < 1e4, else scientific (`8.2e-5`).
pub fn sig2(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    if x == 0.0 {
        return "0".into();
    }
    let a = x.abs();
    if (0.01..1e4).contains(&a) {
        let digits = (1 - a.log10().floor() as i32).max(0) as usize;
        let r = format!("{x:.digits$}");
        // 2 significant digits of an integer ≥ 100: round the rest away (361 → 360)
        if a >= 100.0 {
            let p = 10f64.powi(a.log10().floor() as i32 - 1);
            return format!("{}", (x / p).round() * p);
        }
        r
    } else {
        let s = format!("{x:.1e}");
        s.replace("e-0", "e-")
    }
}

/// `metric` at each point, `label: value` joined by commas (no label for a single point).
fn metric_list(pts: &[&PointResult], metric: &str) -> String {
    pts.iter()
        .map(|p| {
            let label = if pts.len() == 1 { String::new() } else { format!("{}: ", point_label(p)) };
            format!("{label}{}", metric_text(p, metric))
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// A point's label for the report: `λd = 1e-2` style from its grid values (`key=value`).
fn point_label(p: &PointResult) -> String {
    if p.point.is_empty() {
        return "the run".into();
    }
    p.point.iter().map(|(k, v)| format!("{k} = {v}")).collect::<Vec<_>>().join(", ")
}

/// Values of the points, `1e-20, 1e-10, 1` (single grid key) or full labels.
fn values(points: &[&PointResult]) -> String {
    let single = points.iter().all(|p| p.point.len() == 1);
    points.iter().map(|p| if single { p.point[0].1.to_string() } else { point_label(p) }).collect::<Vec<_>>().join(", ")
}

/// The grid key of a run with one key (for "λd = …" phrasing).
fn key_of(points: &[&PointResult]) -> String {
    points.first().and_then(|p| (p.point.len() == 1).then(|| p.point[0].0.clone())).unwrap_or_default()
}

/// Why a point did not converge, shortly: `not converged after N iterations` or the error.
fn failure(p: &PointResult) -> String {
    let e = p.outcome.error.as_deref().unwrap_or("no result");
    match p.outcome.status {
        RunStatus::NotConverged | RunStatus::Stalled => {
            let its = p.metric("iterations").map(|i| format!(" after {}", sig2(i))).unwrap_or_default();
            let x = p.metric("x_err_rel").map(|x| format!(", x error {}", sig2(x))).unwrap_or_default();
            let c = p.metric("certificate").map(|c| format!(", certificate {}", sig2(c))).unwrap_or_default();
            let word = if p.outcome.status == RunStatus::Stalled { "stalled" } else { "not converged" };
            format!("{word}{its} iterations{x}{c}")
        }
        _ => {
            // the innermost cause: after the last ": " of the error chain
            let short = e.rsplit(": ").take(2).collect::<Vec<_>>().into_iter().rev().collect::<Vec<_>>().join(": ");
            let mut short = short.replace('\n', " ");
            if short.len() > 140 {
                let cut = (0..=140).rev().find(|&i| short.is_char_boundary(i)).unwrap_or(0);
                short.truncate(cut);
                short.push('…');
            }
            format!("failed: {short}")
        }
    }
}

fn metric_text(p: &PointResult, metric: &str) -> String {
    p.metric(metric).map(sig2).unwrap_or_else(|| "–".into())
}

/// The points of `run` selected by `at`, or an error text.
fn select<'a>(runs: &'a [RunResults], run: &str, at: &Selector) -> Result<Vec<&'a PointResult>, String> {
    let r = runs.iter().find(|r| r.name == run).ok_or_else(|| format!("no run `{run}`"))?;
    let pts: Vec<&PointResult> = r.select(at).collect();
    if pts.is_empty() {
        return Err(format!("run `{run}` has no point {at:?}"));
    }
    Ok(pts)
}

fn one<'a>(runs: &'a [RunResults], r: &Ref) -> Result<&'a PointResult, String> {
    let pts = select(runs, &r.run, &r.at)?;
    match pts.as_slice() {
        [p] => Ok(p),
        _ => Err(format!("run `{}` at {:?} selects {} points, not one", r.run, r.at, pts.len())),
    }
}

/// Evaluate a check: its outcome and our numbers.
pub fn evaluate(check: &Check, runs: &[RunResults]) -> (Outcome, String) {
    match evaluate_inner(check, runs) {
        Ok(r) => r,
        Err(e) => (Outcome::Fails, format!("not evaluated: {e}")),
    }
}

fn split_by<'a>(
    pts: &[&'a PointResult],
    ok: impl Fn(&PointResult) -> bool,
) -> (Vec<&'a PointResult>, Vec<&'a PointResult>) {
    pts.iter().partition(|p| ok(p))
}

fn outcome(good: usize, total: usize) -> Outcome {
    if good == total {
        Outcome::Holds
    } else if good > 0 {
        Outcome::Partly
    } else {
        Outcome::Fails
    }
}

fn iterations_range(pts: &[&PointResult], metric: &str) -> String {
    let v: Vec<f64> = pts.iter().filter_map(|p| p.metric(metric)).collect();
    if v.is_empty() {
        return String::new();
    }
    let (lo, hi) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
    // frames are counted exactly; iterations to two digits (they may move by one between
    // machines)
    let f = |x: f64| if metric == "frames" { format!("{x}") } else { sig2(x) };
    if lo == hi {
        format!(" ({} {metric})", f(lo))
    } else {
        format!(" ({}–{} {metric})", f(lo), f(hi))
    }
}

fn evaluate_inner(check: &Check, runs: &[RunResults]) -> Result<(Outcome, String), String> {
    let empty = Selector::new();
    Ok(match check {
        Check::Converges { run } | Check::DoesNotConverge { run } => {
            let pts = select(runs, run, &empty)?;
            let (ok, bad) = split_by(&pts, |p| p.converged());
            let count = if pts.iter().any(|p| p.outcome.clip.is_some()) { "frames" } else { "iterations" };
            let mut text = String::new();
            let key = key_of(&pts);
            let named = |v: &[&PointResult]| {
                if key.is_empty() {
                    values(v)
                } else {
                    format!("{key} = {}", values(v))
                }
            };
            if !ok.is_empty() {
                text.push_str(&format!("converges for {}{}", named(&ok), iterations_range(&ok, count)));
            }
            for p in &bad {
                if !text.is_empty() {
                    text.push_str("; ");
                }
                text.push_str(&format!("{}: {}", named(&[p]), failure(p)));
            }
            let o = outcome(ok.len(), pts.len());
            match check {
                Check::DoesNotConverge { .. } => (outcome(bad.len(), pts.len()), text),
                _ => (o, text),
            }
        }
        Check::Below { run, metric, limit, at } | Check::Above { run, metric, limit, at } => {
            let below = matches!(check, Check::Below { .. });
            let pts = select(runs, run, at)?;
            let pass =
                |p: &PointResult| p.metric(metric).is_some_and(|v| if below { v <= *limit } else { v >= *limit });
            let (ok, _) = split_by(&pts, pass);
            let rel = if below { "≤" } else { "≥" };
            let list = metric_list(&pts, metric);
            (outcome(ok.len(), pts.len()), format!("{metric} {list} (claim: {rel} {})", sig2(*limit)))
        }
        Check::Increasing { run, metric } => {
            let pts = select(runs, run, &empty)?;
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
            (outcome(rising, vals.len().saturating_sub(1)), text)
        }
        Check::RatioAbove { metric, numerator, denominator, limit }
        | Check::RatioBelow { metric, numerator, denominator, limit } => {
            let above = matches!(check, Check::RatioAbove { .. });
            let (a, b) = (one(runs, numerator)?, one(runs, denominator)?);
            let (va, vb) = (
                a.metric(metric).ok_or_else(|| format!("`{metric}` missing at {}", point_label(a)))?,
                b.metric(metric).ok_or_else(|| format!("`{metric}` missing at {}", point_label(b)))?,
            );
            let ratio = va / vb;
            let pass = if above { ratio >= *limit } else { ratio <= *limit };
            let text = format!(
                "{metric}: {} ({}, {}) / {} ({}, {}) = {} (claim: {} {})",
                sig2(va),
                numerator.run,
                point_label(a),
                sig2(vb),
                denominator.run,
                point_label(b),
                sig2(ratio),
                if above { "≥" } else { "≤" },
                sig2(*limit)
            );
            (if pass { Outcome::Holds } else { Outcome::Fails }, text)
        }
        Check::WithinFactor { run, metric, factor, with } => {
            let mut pts = select(runs, run, &empty)?;
            // (run, point) names for a check across runs
            let mut names: Vec<String> = pts.iter().map(|p| format!("{run} {}", p.label)).collect();
            for w in with {
                let more = select(runs, w, &empty)?;
                names.extend(more.iter().map(|p| format!("{w} {}", p.label)));
                pts.extend(more);
            }
            if pts.len() < 2 {
                return Err(format!("`within_factor` needs two points or more (run `{run}` and `with`)"));
            }
            // magnitudes: a deflection is negative
            let v: Vec<f64> = pts.iter().filter_map(|p| p.metric(metric)).map(f64::abs).collect();
            if v.len() != pts.len() {
                return Err(format!("`{metric}` missing at some points of `{run}`"));
            }
            let (lo, hi) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
            // The largest group of points within the factor of each other, for a partial answer.
            let within = |x: f64| v.iter().filter(|y| **y >= x && **y <= x * factor).count();
            let best = v.iter().map(|x| within(*x)).max().unwrap_or(0);
            let at = if with.is_empty() { format!("{} = {}", key_of(&pts), values(&pts)) } else { names.join(", ") };
            let text = format!(
                "{metric} at {at}: {} (max/min of the magnitudes 1 + {}; claim: ≤ 1 + {})",
                pts.iter().map(|p| metric_text(p, metric)).collect::<Vec<_>>().join(", "),
                sig2(hi / lo - 1.0),
                sig2(*factor - 1.0)
            );
            let o = if hi <= lo * factor {
                Outcome::Holds
            } else if best > 1 {
                Outcome::Partly
            } else {
                Outcome::Fails
            };
            (o, text)
        }
        Check::Magnitude { run, metric, value, orders, at } => {
            let pts = select(runs, run, at)?;
            let apart = |p: &PointResult| p.metric(metric).map(|v| (v.abs() / value).log10().abs());
            let (ok, _) = split_by(&pts, |p| apart(p).is_some_and(|o| o <= *orders));
            let list = metric_list(&pts, metric);
            let text =
                format!("{metric} {list} (claim: within {} orders of magnitude of {})", sig2(*orders), sig2(*value));
            (outcome(ok.len(), pts.len()), text)
        }
        Check::SameHistories { run, history, reference, limit } => {
            let pts = select(runs, run, &empty)?;
            let base = one(runs, &Ref { run: run.clone(), at: reference.clone() })?;
            let h = |p: &PointResult| -> Option<Vec<f64>> { history_of(p, history) };
            let hb = h(base).ok_or_else(|| format!("no `{history}` history at the reference point"))?;
            // (spread over the common iterations, iterations) per point; the same curve also
            // stops at the same iteration (±1 %)
            let mut spreads = Vec::new();
            for p in pts.iter().filter(|p| !std::ptr::eq(**p, base)) {
                let s = h(p).map(|hp| {
                    let n = hp.len().min(hb.len());
                    ((0..n).map(|i| (hp[i] - hb[i]).abs() / hb[i].abs()).fold(0.0, f64::max), hp.len())
                });
                spreads.push((p, s));
            }
            let same_length = |n: usize| n.abs_diff(hb.len()) as f64 <= (0.01 * hb.len() as f64).max(1.0);
            let good = spreads.iter().filter(|(_, s)| s.is_some_and(|(s, n)| s <= *limit && same_length(n))).count();
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
                        s.map(|(s, n)| format!("{} ({n} its)", sig2(s))).unwrap_or_else(|| "–".into())
                    ))
                    .collect::<Vec<_>>()
                    .join(", "),
                sig2(*limit)
            );
            (outcome(good, spreads.len()), text)
        }
    })
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
    p.outcome.status == RunStatus::Interrupted
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
    let result = |verdict, ours| ClaimResult {
        spec: spec.name.clone(),
        claim: claim.clone(),
        verdict,
        ours,
        figure: claim.figure.clone(),
    };
    if let Some(why) = unjudgeable(&claim.check, runs) {
        return result(None, why);
    }
    let (o, mut ours) = evaluate(&claim.check, runs);
    if let Some(s) = &claim.substitute {
        ours = format!("{ours} [on {s}]");
    }
    let deviations = scheme_deviations(spec, &claim.check);
    if !deviations.is_empty() {
        ours = format!("{ours} [scheme not the paper's: {}]", deviations.join(", "));
    }
    if let Some(p) = &claim.partial {
        ours = format!("{ours} [partial check: {p}]");
    }
    // A claim on data we do not have is "not computable here" when its check holds on the
    // substitute; when it does not hold there either, the substitute's outcome decides.
    let verdict = match (o, claim.not_computable.is_some()) {
        (Outcome::Holds, true) => Verdict::NotComputable,
        (Outcome::Holds, false) => Verdict::Reproduced,
        (Outcome::Partly, _) => claim.if_partly,
        (Outcome::Fails, _) => claim.if_fails,
    };
    // a check weaker than the paper's words cannot reproduce it
    let verdict = match (verdict, &claim.partial) {
        (Verdict::Reproduced | Verdict::NotComputable, Some(_)) => Verdict::Differs,
        (v, _) => v,
    };
    result(Some(verdict), ours)
}

#[cfg(test)]
mod tests {
    use super::sig2;

    #[test]
    fn two_significant_digits() {
        assert_eq!(sig2(8.19499e-5), "8.2e-5");
        assert_eq!(sig2(0.0860337), "0.086");
        assert_eq!(sig2(361.0), "360");
        assert_eq!(sig2(1.0), "1.0");
        assert_eq!(sig2(12.4), "12");
        assert_eq!(sig2(2.5e6), "2.5e6");
        assert_eq!(sig2(-0.0025), "-2.5e-3");
    }
}
