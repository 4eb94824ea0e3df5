//! The angle chart changed during a dynamic run (`docs/decisions.md`, D32).
//!
//! A forward case is solved in the chart `Q = Q_E(α) B` of R1 (`docs/rotation.md`, D21), whose
//! singular set is `d3 = ±n`, `n = Bᵀ e2` (`det A = −cos β`, eqs. 27–28). A rod that tumbles
//! (the three-dimensional flying spaghetti) brings some director `d3` near `±n` whatever `B`
//! is. At the start of a time step, when the smallest `|cos β|` over the nodes is below
//! [`CHANGE_BELOW`], the run takes a new base `B'` whose axis is the R4 axis of the current
//! nodal directors (`frame_axis` on the polyline whose chords are the `d3_i`) and re-expresses
//! the state of the Appendix A scheme (eqs. 68–69) in it:
//!
//! ```text
//!   x̃' = C x̃,   ẋ̃' = C ẋ̃,               C = B' Bᵀ
//!   Q_E(α') = Q_E(α) B B'ᵀ                   (angles unwrapped node to node, R6)
//!   α̇' = A(α')⁻¹ A(α) α̇                     (the local angular velocity ωˡ = A α̇ of eq. 27 is
//!                                             chart independent: Q̇ Qᵀ = Q̇_E Q_Eᵀ, R2)
//!   P_{n−1} = P(u'_{n−1}, u̇'_{n−1}),   F_{n−1} = F(u'_{n−1}, t_{n−1})   in the new chart
//! ```
//! Nodal positions, velocities, frames and angular velocities are the same in space; the
//! momenta and the loads of the previous step are recomputed in the new chart (global loads
//! rotated by `B'`, follower loads unchanged, D21).
//!
//! **What is exact and what is not.** Only a new base that differs from the old by a rotation
//! about the axis (`B' = Ry(θ) B`) or by its flip (`B' = Rz(π) B`) is an affine relabelling of the
//! angles (R5): then the P1 interpolation of α, the midpoint `(u_n + u_{n−1})/2` and the
//! trapezoidal rate (69) commute with it, and the step after the change is the same discrete step
//! in other coordinates (to round-off). A general change is a change of discretisation: the
//! interpolation of the frame between nodes and along a time step follows other curves in
//! SO(3), so the run afterwards differs from the unchanged one by the discretisation error,
//! O(h²) + O(Δt²) (measured in `tests/chart_change.rs`).
use nalgebra::{DVector, Vector3};

use super::Problem;
use crate::model::chart::{axis_margin, frame_axis, Chart};
use crate::model::ends::Ends;
use crate::model::geometry::{min_abs_cos_beta, RestShape, Rod};
use crate::model::mesh::{DofMap, Field};
use crate::model::rotation::a_matrix;

/// A dynamic run changes its chart at the start of a step when the smallest `|cos β|` over
/// the nodes is below this: the margin ½ of R4 (`|d3·n| > √3/2`), the level at which D21
/// stops keeping the paper's chart for a reference. A step that starts above it turns no
/// director by more than the 30° left to the singular set at the step sizes of the cases
/// (the three-dimensional flying spaghetti turns its tip frame by at most 0.081 rad in a step of
/// 0.025 s); the new axis gives a margin of at least ½ except for a rod whose directors come
/// near every direction (the R4 fallback then maximises it).
pub const CHANGE_BELOW: f64 = 0.5;

/// When a dynamic run changes its chart (D32).
#[derive(Clone, Debug, PartialEq)]
pub enum ChartRule {
    /// never: the case's chart throughout
    Never,
    /// at the start of a step whose smallest `|cos β|` is below the threshold, to the axis
    /// of the current directors ([`director_axis`]) if that axis has a larger margin
    Below(f64),
    /// at the start of the given steps, to the given charts (tests of the re-expression)
    At(Vec<(usize, Chart)>),
}

impl Default for ChartRule {
    fn default() -> Self {
        ChartRule::Below(CHANGE_BELOW)
    }
}

impl ChartRule {
    /// The chart the run changes to at the start of step `n` from the state `u` in `current`,
    /// if it changes.
    pub fn decide(&self, problem: &Problem, n: usize, u: &DVector<f64>, current: &Chart) -> Option<Chart> {
        match self {
            ChartRule::Never => None,
            ChartRule::At(list) => list.iter().find(|(k, _)| *k == n).map(|(_, c)| *c),
            ChartRule::Below(threshold) => {
                let margin = min_abs_cos_beta(&problem.mesh, u);
                if margin >= *threshold {
                    return None;
                }
                let d3 = directors(&problem.dofs(), u, current);
                let axis = director_axis(&d3, &current.axis());
                (axis_margin(&polyline(&d3), &axis) > margin).then(|| Chart::with_axis(&axis))
            }
        }
    }
}

/// The nodal directors `d3_i` of the state `u` in `chart`, in space coordinates.
pub fn directors(dofs: &DofMap, u: &DVector<f64>, chart: &Chart) -> Vec<Vector3<f64>> {
    dofs.field(u, Field::Alpha).iter().map(|a| chart.rotation(a).row(2).transpose()).collect()
}

/// The polyline whose chords are the given unit vectors (the input of the R4 rules, which
/// measure chords).
fn polyline(d3: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    let mut x = vec![Vector3::zeros()];
    for d in d3 {
        x.push(x[x.len() - 1] + d);
    }
    x
}

/// The R4 axis of the nodal directors (`chart::frame_axis` on them: the direction that
/// minimises `Σ (d3_i·n)²`, or the largest margin when that leaves less than ½), its sign
/// nearest `prev`. The margin of a chart is `min_i |cos β_i| = min_i √(1 − (d3_i·n)²)`: the
/// directors, not the chords, are what β measures (they differ by the shear).
pub fn director_axis(d3: &[Vector3<f64>], prev: &Vector3<f64>) -> Vector3<f64> {
    frame_axis(&polyline(d3), Some(prev))
}

/// The rod of `problem` (its reference and ends) posed in `chart` (the paper's straight
/// clamped–free rod when the problem has none).
pub fn rod_in_chart(problem: &Problem, chart: Chart) -> Rod {
    match problem.rod {
        Some(r) => Rod { rest: r.rest.in_chart(&problem.mesh, chart), ends: r.ends.clone() },
        None => Rod { rest: RestShape::straight(&problem.mesh, chart), ends: Ends::CLAMPED_FREE },
    }
}

/// The state `u` and its rates `v` (chart `from`) re-expressed in the chart `to` (module doc):
/// positions and velocities by `C = B' Bᵀ`, angles by R6 (unwrapped node to node), angle rates
/// so that `A(α) α̇` is kept. `None` where some node is on the new chart's singular set.
pub fn reexpress_state(
    dofs: &DofMap,
    from: &Chart,
    to: &Chart,
    u: &DVector<f64>,
    v: &DVector<f64>,
) -> Option<(DVector<f64>, DVector<f64>)> {
    let c = to.base * from.base.transpose();
    let alpha = dofs.field(u, Field::Alpha);
    let new_alpha = to.reexpress(from, &alpha, None);
    let (mut u2, mut v2) = (u.clone(), v.clone());
    for (i, (a, a2)) in alpha.iter().zip(&new_alpha).enumerate() {
        let omega = a_matrix(a) * dofs.get(v, i, Field::Alpha);
        let rate = a_matrix(a2).lu().solve(&omega)?;
        dofs.set(&mut u2, i, Field::X, &(c * dofs.get(u, i, Field::X)));
        dofs.set(&mut v2, i, Field::X, &(c * dofs.get(v, i, Field::X)));
        dofs.set(&mut u2, i, Field::Alpha, a2);
        dofs.set(&mut v2, i, Field::Alpha, &rate);
    }
    Some((u2, v2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::mesh::Mesh;
    use crate::model::rotation::rotation;

    fn chart(v: [f64; 3]) -> Chart {
        Chart { base: nalgebra::Rotation3::new(Vector3::from(v)).into_inner() }
    }

    /// The angle rates of a frame path `Q(t) = Q_E(α(t)) B` re-expressed in another chart are
    /// the derivative of its angles there (central differences): `A α̇` is chart independent.
    #[test]
    fn rates_are_the_derivative_of_the_reexpressed_angles() {
        let mesh = Mesh::new(1.0, 3);
        let dofs = mesh.dofs();
        let (from, to) = (chart([0.3, -0.2, 0.5]), chart([-1.1, 0.4, 0.9]));
        let path = |t: f64| -> DVector<f64> {
            let mut u = dofs.zeros();
            for i in 0..mesh.nodes() {
                let k = i as f64;
                dofs.set(&mut u, i, Field::X, &Vector3::new(t * k, 0.1 * k, 1.0 - t));
                let a = Vector3::new(0.2 * k + 0.7 * t, 0.3 - 0.5 * t * t + 0.1 * k, -0.4 + 1.3 * t);
                dofs.set(&mut u, i, Field::Alpha, &a);
            }
            u
        };
        let (t, h) = (0.4, 1e-6);
        let rate = (path(t + h) - path(t - h)) / (2.0 * h);
        let (u2, v2) = reexpress_state(&dofs, &from, &to, &path(t), &rate).expect("regular");
        let (up, _) = reexpress_state(&dofs, &from, &to, &path(t + h), &rate).unwrap();
        let (um, _) = reexpress_state(&dofs, &from, &to, &path(t - h), &rate).unwrap();
        let fd = (up - um) / (2.0 * h);
        assert!((&fd - &v2).amax() < 1e-8, "{}", (fd - &v2).amax());
        for i in 0..mesh.nodes() {
            let (a, a2) = (dofs.get(&path(t), i, Field::Alpha), dofs.get(&u2, i, Field::Alpha));
            assert!((from.rotation(&a) - to.rotation(&a2)).amax() < 1e-13, "the same frame in space");
            let x = from.to_space(&dofs.get(&path(t), i, Field::X));
            assert!((x - to.to_space(&dofs.get(&u2, i, Field::X))).amax() < 1e-14, "the same position");
        }
    }

    /// A base turned about its own axis by θ only shifts γ by −θ (R5: `Q_E(α) Ry(θ)ᵀ`): the
    /// rates are unchanged.
    #[test]
    fn a_turn_about_the_axis_keeps_the_rates() {
        let mesh = Mesh::new(1.0, 2);
        let dofs = mesh.dofs();
        let from = chart([0.2, 0.1, -0.3]);
        let ry = nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), 0.8).into_inner();
        let to = Chart { base: ry * from.base };
        let mut u = dofs.zeros();
        let mut v = dofs.zeros();
        for i in 0..mesh.nodes() {
            dofs.set(&mut u, i, Field::Alpha, &Vector3::new(0.1 * i as f64, 0.2, 0.3));
            dofs.set(&mut v, i, Field::Alpha, &Vector3::new(0.5, -0.7, 1.1));
        }
        let (u2, v2) = reexpress_state(&dofs, &from, &to, &u, &v).unwrap();
        for i in 0..mesh.nodes() {
            let (a, a2) = (dofs.get(&u, i, Field::Alpha), dofs.get(&u2, i, Field::Alpha));
            assert!((a2 - a + Vector3::new(0.0, 0.0, 0.8)).amax() < 1e-13, "{a} → {a2}");
            assert!((dofs.get(&v2, i, Field::Alpha) - dofs.get(&v, i, Field::Alpha)).amax() < 1e-13);
        }
        assert!(
            (rotation(&dofs.get(&u2, 0, Field::Alpha)) * to.base - from.rotation(&Vector3::new(0.0, 0.2, 0.3))).amax()
                < 1e-13
        );
    }

    /// Directors along e2 (on the paper's chart's singular set) get an axis away from them.
    #[test]
    fn the_axis_of_directors_leaves_a_margin() {
        let d3: Vec<Vector3<f64>> = (0..11)
            .map(|i| {
                let t = 0.15 * i as f64;
                Vector3::new(t.sin() * 0.3, t.cos(), t.sin() * 0.9).normalize()
            })
            .collect();
        let n = director_axis(&d3, &Vector3::y());
        let margin = axis_margin(&polyline(&d3), &n);
        assert!(margin > 0.9, "margin {margin}, axis {n}");
        assert!(axis_margin(&polyline(&d3), &Vector3::y()) < 0.01, "e2 is singular for them");
    }
}
