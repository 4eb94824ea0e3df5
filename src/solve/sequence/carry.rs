//! A state or solution of one chart in another (R6) or in space coordinates (R3).
use nalgebra::DVector;

use crate::model::chart::{Chart, Converted};
use crate::model::mesh::{DofMap, Field};
use crate::model::rotation::Angles;

use crate::solve::inverse::kkt::Part;
use crate::solve::inverse::InverseSolution;

/// A state `(x, α)` of chart `from` in chart `to` (R6): positions rotated by `B_to B_fromᵀ`,
/// angles re-expressed node by node without 2π jumps along the rod (or against `near`).
/// `near`: a state in chart `to` whose angles the result's are unwrapped against (R6).
pub(super) fn carry_state(
    dofs: &DofMap,
    to: &Chart,
    from: &Chart,
    u: &DVector<f64>,
    near: Option<&DVector<f64>>,
) -> DVector<f64> {
    carry_converted(dofs, to, from, u, None, near)
}

/// [`carry_state`] with `u`'s angles already converted to `to` (`Chart::converted`), if given.
pub(super) fn carry_converted(
    dofs: &DofMap,
    to: &Chart,
    from: &Chart,
    u: &DVector<f64>,
    converted: Option<&Converted>,
    near: Option<&DVector<f64>>,
) -> DVector<f64> {
    if to.base == from.base {
        return u.clone();
    }
    let near: Option<Vec<Angles>> = near.map(|v| dofs.field(v, Field::Alpha));
    let alpha = match converted {
        Some(c) => c.unwrapped(near.as_deref()),
        None => to.converted(from, &dofs.field(u, Field::Alpha)).unwrapped(near.as_deref()),
    };
    let mut out = dofs.zeros();
    for j in 0..dofs.nodes() {
        dofs.set(&mut out, j, Field::X, &to.to_chart(&from.to_space(&dofs.get(u, j, Field::X))));
        dofs.set(&mut out, j, Field::Alpha, &alpha[j]);
    }
    out
}

/// The solution with positions and adjoints in space coordinates (R3); angles unchanged.
pub(super) fn to_space(dofs: &DofMap, chart: &Chart, sol: &InverseSolution) -> InverseSolution {
    InverseSolution {
        u: vector_to_space(dofs, chart, &sol.u, Part::State),
        adjoint: vector_to_space(dofs, chart, &sol.adjoint, Part::Adjoint),
        history: sol.history.clone(),
        stop: sol.stop,
        certificate: sol.certificate,
        certificate_tolerance: sol.certificate_tolerance,
    }
}

/// A forward-layout vector of chart `chart` in space coordinates (R3): the position block
/// rotated, the angle block rotated too for an adjoint (`part`: [`Part::Adjoint`], whose α̂ is
/// a vector of space), unchanged for a state (angles stay the chart's). What
/// [`super::FrameSolution::solution`] holds, from the chart's state and adjoint.
pub fn vector_to_space(dofs: &DofMap, chart: &Chart, v: &DVector<f64>, part: Part) -> DVector<f64> {
    if chart.is_identity() {
        return v.clone();
    }
    let mut out = v.clone();
    for j in 0..dofs.nodes() {
        let (a, b) = (dofs.get(v, j, Field::X), dofs.get(v, j, Field::Alpha));
        let (a, b) = (chart.to_space(&a), if part == Part::Adjoint { chart.to_space(&b) } else { b });
        dofs.set(&mut out, j, Field::X, &a);
        dofs.set(&mut out, j, Field::Alpha, &b);
    }
    out
}
