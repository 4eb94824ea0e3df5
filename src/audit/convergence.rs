//! Convergence claims (`converges`, `does_not_converge`), judged by two facts per point:
//! - **the paper's words**: did the point stop by the paper's rule, its relative change of
//!   (x, α) below the threshold within the iteration cap (§5.2; D5)? Outcome `ok` or
//!   `stalled` (`solve::Outcome`: the rule met, the certificate above ours), with its
//!   iterations. The verdict follows this fact.
//! - **our standard**, a column beside the verdict: how far the returned iterate is from a
//!   solution of the same discrete equations, its residual certificate against
//!   [`OUR_TOLERANCE`] with the margin (`docs/certificate.md`), and for a single frame the
//!   distance in x and κ to the certified Newton solution from the same data
//!   ([`super::newton_distance`]) set against the discretisation error the point reports
//!   (`x_err_rel`, `kappa_err_rel` against the exact data). A clip says it per frame.
use super::numbers::{input, sig2};
use super::points::{failure, key_of, outcome, point_label, select, values, CheckError, Holding};
use super::spec::{Check, Selector};
use super::{PointResult, RunResults};
use crate::engine::metrics::Metric;
use crate::solve;

/// Our standard of a solution: the residual certificate at most this (`docs/certificate.md`;
/// the default `solver.certificate_tolerance`).
pub const OUR_TOLERANCE: f64 = 1e-10;

/// The point stopped by the paper's rule: its relative change settled within the iteration
/// cap, certified or not (`ok`, `complete_with_warnings`, `stalled`).
pub fn met_rule(p: &PointResult) -> bool {
    p.converged() || p.outcome.status == solve::Outcome::Stalled
}

/// The frames' reports of a clip point (empty for a single frame).
fn frames(p: &PointResult) -> &[crate::solve::sequence::FrameReport] {
    p.outcome.clip.as_ref().map_or(&[], |c| c.reports.as_slice())
}

/// `(min, max)` of the values, `None` for none.
fn range(v: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    v.fold(None, |acc, x| Some(acc.map_or((x, x), |(a, b): (f64, f64)| (a.min(x), b.max(x)))))
}

/// `lo–hi` (or `lo` when equal), counts written exactly.
fn span((lo, hi): (f64, f64)) -> String {
    if lo == hi {
        format!("{lo}")
    } else {
        format!("{lo}–{hi}")
    }
}

/// The iterations of the points that met the rule: per point for a single frame, per frame
/// for a clip (`(60 frames, 21–130 iterations per frame)`).
fn iterations(pts: &[&PointResult]) -> String {
    let clip = pts.iter().any(|p| p.outcome.clip.is_some());
    if clip {
        let n = range(pts.iter().map(|p| frames(p).len() as f64));
        let its = range(pts.iter().flat_map(|p| frames(p).iter().map(|r| r.convergence.iterations as f64)));
        match (n, its) {
            (Some(n), Some(i)) => format!(" ({} frames, {} iterations per frame)", span(n), span(i)),
            _ => String::new(),
        }
    } else {
        range(pts.iter().filter_map(|p| p.value(Metric::Iterations)))
            .map_or(String::new(), |r| format!(" ({} iterations)", span(r)))
    }
}

/// What a convergence check claims of its points: that they stop by the paper's rule
/// (`converges`) or that they do not (`does_not_converge`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Claimed {
    Converges,
    DoesNotConverge,
}

/// `converges` (or `does_not_converge`, as `claimed`): the points that stop by the paper's
/// rule, with their iterations, and why each other did not; the outcome counts the former
/// (the latter).
pub fn converges(runs: &[RunResults], run: &str, claimed: Claimed) -> Result<(Holding, String), CheckError> {
    let pts = select(runs, run, &Selector::new())?;
    let (ok, bad): (Vec<&PointResult>, Vec<&PointResult>) = pts.iter().partition(|p| met_rule(p));
    let key = key_of(&pts);
    let named = |v: &[&PointResult]| if key.is_empty() { values(v) } else { format!("{key} = {}", values(v)) };
    let mut parts = Vec::new();
    if !ok.is_empty() {
        parts.push(format!("stops by the paper's rule for {}{}", named(&ok), iterations(&ok)));
    }
    parts.extend(bad.iter().map(|p| format!("{}: {}", named(&[p]), failure(p))));
    let good = match claimed {
        Claimed::Converges => ok.len(),
        Claimed::DoesNotConverge => bad.len(),
    };
    Ok((outcome(good, pts.len()), parts.join("; ")))
}

/// The column "our standard" of a convergence claim: per point of its runs the certificate
/// against [`OUR_TOLERANCE`] with its margin (a clip: per frame), and the distance to the
/// Newton solution beside the discretisation error; `None` for other checks.
pub fn standard(check: &Check, runs: &[RunResults]) -> Option<String> {
    let names: Vec<&str> = match check {
        Check::Converges { .. } | Check::DoesNotConverge { .. } => check.runs(),
        // a convergence check shown with the errors against the substitute's truth
        Check::WithTruth { check, .. } => return standard(check, runs),
        _ => return None,
    };
    let many = names.len() > 1;
    let mut parts = Vec::new();
    for name in names {
        let pts = select(runs, name, &Selector::new()).ok()?;
        let prefix = if many { format!("{name}: ") } else { String::new() };
        // each point named by its grid values where the run has more than one
        let label = |p: &PointResult| if pts.len() > 1 { format!("{}: ", point_label(p)) } else { String::new() };
        let each: Vec<String> = pts.iter().map(|p| format!("{}{}", label(p), point_standard(p))).collect();
        parts.push(format!("{prefix}{}", each.join("; ")));
    }
    Some(format!("certificate ≤ {}: {}", input(OUR_TOLERANCE), parts.join("; ")))
}

/// A point's part of [`standard`]: `λd = 1e-6: 4.2e-7 (4200×); Newton from it x 1e-6, κ 1e-3
/// (discretisation x 2e-4, κ 0.11)`.
fn point_standard(p: &PointResult) -> String {
    if !frames(p).is_empty() {
        return clip_standard(frames(p));
    }
    let Some(c) = p.value(Metric::Certificate) else { return "no certificate".to_string() };
    let mut text = format!("{} ({}× ours)", sig2(c), sig2(c / OUR_TOLERANCE));
    if let (Some(x), Some(k)) = (p.metric("newton_x_dist_rel"), p.metric("newton_kappa_dist_rel")) {
        let root = if p.metric("newton_certified") == Some(1.0) {
            "the Newton solution".to_string()
        } else {
            format!(
                "Newton's last iterate (not certified, {})",
                sig2(p.metric("newton_certificate").unwrap_or(f64::NAN))
            )
        };
        let disc = match (p.value(Metric::XErrRel), p.value(Metric::KappaErrRel)) {
            (Some(dx), Some(dk)) => format!(" against the discretisation error x {}, κ {}", sig2(dx), sig2(dk)),
            _ => String::new(),
        };
        text.push_str(&format!(", from {root} x {}, κ {}{disc}", sig2(x), sig2(k)));
    }
    text
}

/// A clip's part of [`standard`]: the frames certified, the largest certificate with its
/// margin and frame, and the first frame above.
fn clip_standard(reports: &[crate::solve::sequence::FrameReport]) -> String {
    let good = reports.iter().filter(|r| r.certificate <= OUR_TOLERANCE).count();
    let worst = reports.iter().max_by(|a, b| a.certificate.total_cmp(&b.certificate));
    let first = reports.iter().find(|r| r.certificate > OUR_TOLERANCE);
    let mut text = format!("{good} of {} frames", reports.len());
    if let Some(w) = worst {
        text.push_str(&format!(
            ", largest {} ({}× ours) at frame {}",
            sig2(w.certificate),
            sig2(w.certificate / OUR_TOLERANCE),
            w.frame
        ));
    }
    if let Some(f) = first {
        text.push_str(&format!(", first above at frame {} ({})", f.frame, sig2(f.certificate)));
    }
    text
}
