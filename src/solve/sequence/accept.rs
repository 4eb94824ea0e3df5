//! Whether a frame's solution is kept: its fit against the data and the gate (`solve::fit`),
//! and the re-solve from the frame's own data of a solution carried from the previous frame
//! that is over the gate (docs/decisions.md D26).
use nalgebra::Vector3;

use super::{FrameStart, SequenceParams};
use crate::model::chart::Chart;
use crate::model::element::midpoint_curvatures;
use crate::model::mesh::Field;
use crate::recorded::fit::{noise_level_in, position_misfit, FrameFit};
use crate::solve::inverse::tracking::MIN_TRACKED;
use crate::solve::inverse::InverseSolution;
use crate::solve::Problem;

/// The fit measures of a frame's solution `sol` on its data `x_g` (chart coordinates both) over
/// its `tracked` nodes (`None`: all), its largest curvature, and the gate's verdict
/// (`solve::fit`). The noise level is the case's (`clip.noise_m`) or the frame's own estimate,
/// in the recording's plane for planar data (`sp.plane`, here in the frame's `chart`).
pub(super) fn frame_fit(
    sp: &SequenceParams,
    problem: &Problem,
    sol: &InverseSolution,
    (x_g, tracked): (&[Vector3<f64>], Option<&[bool]>),
    chart: &Chart,
) -> FrameFit {
    let (dofs, length) = (problem.dofs(), problem.mesh.length_m);
    // the noise of the tracked positions only (the filled ones are smooth by construction)
    let recorded: Vec<Vector3<f64>> = match tracked {
        Some(t) => x_g.iter().zip(t).map(|(x, &t)| if t { *x } else { Vector3::repeat(f64::NAN) }).collect(),
        None => Vec::new(),
    };
    let plane = sp.plane.map(|n| chart.to_chart(&n));
    let estimated = noise_level_in(if tracked.is_some() { &recorded } else { x_g }, plane.as_ref());
    let s: Vec<f64> = (0..dofs.nodes()).map(|i| problem.mesh.node_s(i)).collect();
    let kappa = midpoint_curvatures(&s, &dofs.field(&sol.u, Field::Alpha));
    let tangent_misfit = sol.history.last().map_or(f64::NAN, |r| r.tangent_misfit);
    let mut fit = FrameFit {
        noise_m: sp.gate.noise(estimated),
        position: position_misfit(&dofs.field(&sol.u, Field::X), x_g, tracked, length),
        tangent: tangent_misfit / length.sqrt(),
        curvature_max_per_m: kappa.iter().map(|(_, k)| k.norm()).fold(0.0, f64::max),
        flagged: false,
        resolved: false,
    };
    // a bridged frame (too few tracked nodes, `clip::missing`) has no data to fall short of,
    // but its curvature is still bounded
    let bridged = tracked.is_some_and(|t| t.iter().filter(|t| **t).count() < MIN_TRACKED);
    fit.flagged = if bridged {
        fit.curvature_max_per_m.is_nan() || fit.curvature_max_per_m > sp.gate.max_curvature_per_m
    } else {
        sp.gate.check(&fit, length, problem.mesh.h())
    };
    fit
}

/// Where the first solve of a frame started from: the previous frame's solution (carried into
/// this frame's chart) or anything else (a guess, a nearby solution of the first frame).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum StartedFrom {
    PreviousFrame,
    Other,
}

impl StartedFrom {
    /// Where frame `i` of a clip (counted from 0) that starts its frames as `start` says starts
    /// from: the previous frame's solution on every frame after the first with
    /// [`FrameStart::PreviousFrame`].
    pub(super) fn frame(i: usize, start: FrameStart) -> Self {
        if i > 0 && start == FrameStart::PreviousFrame {
            StartedFrom::PreviousFrame
        } else {
            StartedFrom::Other
        }
    }
}

/// The solution a frame keeps (`first`: the solve and whether it restarted) with its fit
/// (`check`): a solution from the previous frame's ([`StartedFrom::PreviousFrame`]) that is over the gate —
/// the previous frame's branch, carried — is solved again from the frame's own data guess
/// (`again`) and that kept (`resolved`, flagged if it is over the gate too); a failure of that
/// solve keeps the first, flagged.
pub(super) fn accepted(
    (sol, restarted): (InverseSolution, bool),
    from: StartedFrom,
    check: &dyn Fn(&InverseSolution) -> FrameFit,
    again: impl FnOnce() -> Option<InverseSolution>,
) -> (InverseSolution, bool, FrameFit) {
    let fit = check(&sol);
    if !(from == StartedFrom::PreviousFrame && !restarted && fit.flagged) {
        return (sol, restarted, fit);
    }
    match again() {
        Some(s) => {
            let fit = FrameFit { resolved: true, ..check(&s) };
            (s, true, fit)
        }
        None => (sol, restarted, fit),
    }
}
