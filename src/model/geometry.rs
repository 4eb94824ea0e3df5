//! The reference (stress-free) configuration of a rod other than straight (`docs/decisions.md`,
//! D20) in the chart of its case (D21), and the rod a forward problem is posed on: reference and
//! ends ([`Rod`]).
//!
//! ```text
//!   Q0' = −[κ̄(s)]× Q0,   x0' = Q0ᵀ e3          (d_i' = κ × d_i, κ = Q0ᵀ κ̄; unit stretch, no shear)
//!   per substep Δ:  Q_{k+1} = E(κ̄_m Δ) Q_k,   x_{k+1} = x_k + Q_kᵀ W(κ̄_m, Δ)ᵀ e3,   κ̄_m = κ̄(s_k + Δ/2)
//!   E(v) = exp(−[v]×) = I − a [v]× + b [v]×²,   W = ∫_0^Δ exp(−[κ̄]× σ) dσ = Δ (I − b [v]× + c [v]×²)
//!   a = sin θ/θ,  b = (1 − cos θ)/θ²,  c = (θ − sin θ)/θ³,  θ = |v|,  v = κ̄_m Δ
//! ```
//! exact for a constant κ̄ (arcs, helices), second order otherwise. The discrete reference is the
//! P1 interpolant of the nodal values, and the element's reference strains are measured from it
//! ([`ElementRest`]), so it is exactly stress free.
use nalgebra::{DVector, Matrix3, Vector3};

use super::chart::{frame_axis, Chart};
use super::element::{ElementRest, LocalVec};
use super::ends::{EndReference, Ends};
use super::loads::VectorExpr;
use super::mesh::{Field, Mesh};
use super::rotation::skew;

/// Substeps per element of the integration of the reference frame (D20).
pub const REST_SUBSTEPS: usize = 16;
/// Below this rotation per substep [rad] the coefficients `a, b, c` use their series.
const SERIES_BELOW_RAD: f64 = 1e-4;
/// The paper's chart is kept for a reference whose tangents all keep `|d3·e2|` at most this
/// (a margin of ½, R4 of `docs/rotation.md`).
pub const KEEP_GLOBAL_CHART_BELOW: f64 = 0.866_025_403_784_438_6; // √3/2

/// What a case gives of its reference configuration (D20).
#[derive(Clone, Debug)]
pub struct RestSpec {
    /// position of s = 0 [m], space coordinates
    pub start_position_m: Vector3<f64>,
    /// frame at s = 0: rows d1, d2, d3 in space coordinates (orthonormal, proper)
    pub start_frame: Matrix3<f64>,
    /// intrinsic curvature and twist κ̄(s) [1/m], body-frame components, expressions of `s`
    pub curvature: VectorExpr,
}

/// `(a, b, c)` of the module doc at θ [rad].
fn coefficients(theta: f64) -> (f64, f64, f64) {
    if theta < SERIES_BELOW_RAD {
        let t2 = theta * theta;
        (1.0 - t2 / 6.0, 0.5 - t2 / 24.0, 1.0 / 6.0 - t2 / 120.0)
    } else {
        let (s, c) = theta.sin_cos();
        (s / theta, (1.0 - c) / (theta * theta), (theta - s) / (theta * theta * theta))
    }
}

/// The reference centreline [m] and frames (rows d_i) at the nodes of `mesh`, in space
/// coordinates, by the substep rule of the module doc.
pub fn integrate(mesh: &Mesh, spec: &RestSpec) -> (Vec<Vector3<f64>>, Vec<Matrix3<f64>>) {
    let (h, n) = (mesh.h(), REST_SUBSTEPS);
    let delta = h / n as f64;
    let mut q = spec.start_frame;
    let mut x = spec.start_position_m;
    if spec.curvature.is_zero() {
        // straight: x0 = x(0) + s d3 exactly
        let d3 = q.row(2).transpose();
        return ((0..mesh.nodes()).map(|i| x + d3 * mesh.node_s(i)).collect(), vec![q; mesh.nodes()]);
    }
    let (mut xs, mut qs) = (vec![x], vec![q]);
    for e in 0..mesh.elements {
        for k in 0..n {
            let s_mid = mesh.node_s(e) + (k as f64 + 0.5) * delta;
            let v = spec.curvature.at(s_mid, 0.0) * delta;
            let (a, b, c) = coefficients(v.norm());
            let (vx, vx2) = (skew(&v), skew(&v) * skew(&v));
            let w = (Matrix3::identity() - vx * b + vx2 * c) * delta;
            x += q.transpose() * (w.transpose() * Vector3::z());
            q = (Matrix3::identity() - vx * a + vx2 * b) * q;
        }
        // re-orthonormalise once per element (the substeps keep Q orthogonal to round-off)
        q = nalgebra::Rotation3::from_matrix(&q).into_inner();
        xs.push(x);
        qs.push(q);
    }
    (xs, qs)
}

/// The chart of a forward case without `rod.chart_axis` (D21): the paper's when every
/// reference tangent keeps `|d3·e2| ≤ √3/2`, else the axis of R4 over the reference centreline
/// (the plane's normal for a planar one).
pub fn default_chart(positions: &[Vector3<f64>], frames: &[Matrix3<f64>]) -> Chart {
    let keeps = frames.iter().all(|q| q[(2, 1)].abs() <= KEEP_GLOBAL_CHART_BELOW);
    if keeps {
        Chart::identity()
    } else {
        Chart::with_axis(&frame_axis(positions, None))
    }
}

/// The discrete reference configuration of a rod on a mesh, in a chart (D20, D21).
#[derive(Clone, Debug)]
pub struct RestShape {
    pub chart: Chart,
    /// nodal `(x̃0, α0)` in chart coordinates, forward layout: the initial iterate and the
    /// values of held unknowns
    pub state: DVector<f64>,
    /// per element, the reference strains at the quadrature points
    pub strains: Vec<ElementRest>,
    /// reference positions `x0(s_i)` [m], space coordinates
    pub positions: Vec<Vector3<f64>>,
    /// reference frames `Q0(s_i)` (rows d_i), space coordinates
    pub frames: Vec<Matrix3<f64>>,
    /// the intrinsic curvature κ̄(s) it was integrated from (for the FreeFEM engine, which
    /// integrates it again)
    pub curvature: VectorExpr,
}

impl RestShape {
    /// The discrete reference of `spec` on `mesh` in `chart` (the nodal angles those of
    /// `Q0 Bᵀ`, each unwrapped against the previous node's).
    pub fn new(mesh: &Mesh, spec: &RestSpec, chart: Option<Chart>) -> Self {
        let (positions, frames) = integrate(mesh, spec);
        let chart = chart.unwrap_or_else(|| default_chart(&positions, &frames));
        Self::from_frames(mesh, positions, frames, chart, spec.curvature.clone())
    }

    /// The same reference posed in another chart (D32: a dynamic run that changes its chart):
    /// the nodal state and the reference strains recomputed from the space positions and frames,
    /// so that the reference is exactly stress free in the new chart's interpolation too.
    pub fn in_chart(&self, mesh: &Mesh, chart: Chart) -> Self {
        Self::from_frames(mesh, self.positions.clone(), self.frames.clone(), chart, self.curvature.clone())
    }

    /// The paper's straight rod along e3 from the origin (`x0 = (0, 0, s)`, `Q0 = I`, D1) posed in
    /// `chart`.
    pub fn straight(mesh: &Mesh, chart: Chart) -> Self {
        let positions = (0..mesh.nodes()).map(|i| Vector3::new(0.0, 0.0, mesh.node_s(i))).collect();
        let frames = vec![Matrix3::identity(); mesh.nodes()];
        Self::from_frames(mesh, positions, frames, chart, VectorExpr::zero())
    }

    /// The discrete reference of nodal positions and frames (space coordinates) in `chart`.
    fn from_frames(
        mesh: &Mesh,
        positions: Vec<Vector3<f64>>,
        frames: Vec<Matrix3<f64>>,
        chart: Chart,
        curvature: VectorExpr,
    ) -> Self {
        let dofs = mesh.dofs();
        let mut state = dofs.zeros();
        let mut prev: Option<Vector3<f64>> = None;
        for (i, (x, q)) in positions.iter().zip(&frames).enumerate() {
            let raw = super::rotation::angles_from_rotation(&(q * chart.base.transpose()));
            let a = prev.map(|p| chart.angles_of(q, &p)).unwrap_or(raw);
            // (+ 0.0: no negative zeros in the reference)
            dofs.set(&mut state, i, Field::X, &(chart.to_chart(x).map(|v| v + 0.0)));
            dofs.set(&mut state, i, Field::Alpha, &a.map(|v| v + 0.0));
            prev = Some(a);
        }
        let h = mesh.h();
        let strains = (0..mesh.elements).map(|e| ElementRest::of(&dofs.gather::<12>(&state, e), h)).collect();
        RestShape { chart, state, strains, positions, frames, curvature }
    }

    /// The reference of the node `i` (an end).
    pub fn end_reference(&self, mesh: &Mesh, i: usize) -> EndReference {
        EndReference {
            position: self.positions[i],
            frame: self.frames[i],
            angles: mesh.dofs().get(&self.state, i, Field::Alpha),
        }
    }

    /// The smallest `|cos β|` of the reference's nodes in its chart (1 far from the singular set).
    pub fn min_abs_cos_beta(&self, mesh: &Mesh) -> f64 {
        min_abs_cos_beta(mesh, &self.state)
    }
}

/// The smallest `|cos β|` over the nodes of a forward state `u` (D21: the chart's distance from
/// its singular set, `det A = −cos β`).
pub fn min_abs_cos_beta(mesh: &Mesh, u: &DVector<f64>) -> f64 {
    mesh.dofs().field(u, Field::Alpha).iter().map(|a| a[1].cos().abs()).fold(1.0, f64::min)
}

/// The rod of a forward problem beyond the paper's: its reference configuration in its chart and
/// its ends (D20–D22).
#[derive(Clone, Debug)]
pub struct Rod {
    pub rest: RestShape,
    pub ends: Ends,
}

/// The element vector of the straight reference along e3 (used by tests of other modules).
pub fn straight_element(h: f64) -> LocalVec {
    let mut u = LocalVec::zeros();
    u[8] = h;
    u
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::Expr;
    use std::collections::BTreeMap;
    use std::f64::consts::PI;

    fn spec(k: [&str; 3], frame: Matrix3<f64>) -> RestSpec {
        let e = |t: &str| Expr::parse(t).unwrap();
        RestSpec {
            start_position_m: Vector3::new(1.0, -2.0, 0.5),
            start_frame: frame,
            curvature: VectorExpr::new([e(k[0]), e(k[1]), e(k[2])], &BTreeMap::new()).unwrap(),
        }
    }

    #[test]
    fn a_constant_curvature_makes_an_exact_arc() {
        // κ̄2 = 1/R on a straight start along e3 bends d3 towards d1 = e1: a circle in the x–z
        // plane through the start, centre at start + R e1
        let r = 0.7;
        let mesh = Mesh::new(PI * r, 9);
        let (x, q) = integrate(&mesh, &spec(["0", "1/0.7", "0"], Matrix3::identity()));
        let centre = Vector3::new(1.0, -2.0, 0.5) + Vector3::new(r, 0.0, 0.0);
        for (xi, qi) in x.iter().zip(&q) {
            assert!(((xi - centre).norm() - r).abs() < 1e-14, "on the circle: {}", (xi - centre).norm() - r);
            let d3 = qi.row(2).transpose();
            assert!(d3.dot(&(xi - centre)).abs() < 1e-14, "tangent");
            assert!((qi * qi.transpose() - Matrix3::identity()).amax() < 1e-15);
        }
        // half a turn: the end is at start + 2R e1 with d3 = −e3
        assert!((x[9] - (Vector3::new(1.0, -2.0, 0.5) + Vector3::new(2.0 * r, 0.0, 0.0))).norm() < 1e-14);
    }

    #[test]
    fn a_constant_curvature_and_twist_make_an_exact_helix() {
        // κ̄ = (0, κ, τ): a helix of radius κ/(κ² + τ²), pitch 2π τ/(κ² + τ²) along the axis
        // direction ω = κ d2 + τ d3 (fixed in space); every point at the same distance from it
        let (k, t) = (2.0, 1.5);
        let mesh = Mesh::new(6.0, 40);
        let (x, q) = integrate(&mesh, &spec(["0", "2", "1.5"], Matrix3::identity()));
        let w = (q[0].transpose() * Vector3::new(0.0, k, t)).normalize();
        let radius = k / (k * k + t * t);
        // the axis passes through start + radius · (the normal towards the centre, d1 here)
        let centre0 = x[0] + q[0].row(0).transpose() * radius;
        for (xi, qi) in x.iter().zip(&q) {
            let rel = xi - centre0;
            let dist = (rel - w * rel.dot(&w)).norm();
            assert!((dist - radius).abs() < 1e-13, "radius {dist} vs {radius}");
            let omega = qi.transpose() * Vector3::new(0.0, k, t);
            assert!((omega.normalize() - w).norm() < 1e-13, "the Darboux vector is fixed");
        }
        let s = mesh.length_m;
        let rise = (x[40] - x[0]).dot(&w);
        assert!((rise - s * t / (k * k + t * t).sqrt()).abs() < 1e-12, "{rise}");
    }

    #[test]
    fn a_varying_curvature_converges_at_second_order() {
        // κ̄ = (0, 3s, ½): the axis of the curvature turns along the rod, so substeps do not
        // commute; compare meshes against a much finer one (the substeps shrink with h)
        let sp = spec(["0", "3*s", "0.5"], Matrix3::identity());
        let end = |n: usize| {
            let (x, _) = integrate(&Mesh::new(2.0, n), &sp);
            x[n]
        };
        let fine = end(4096);
        let (e1, e2) = ((end(4) - fine).norm(), (end(8) - fine).norm());
        let order = (e1 / e2).log2();
        assert!(order > 1.9 && order < 2.2, "order {order} ({e1:e}, {e2:e})");
    }

    #[test]
    fn the_discrete_reference_is_stress_free_in_any_chart() {
        let frame = nalgebra::Rotation3::new(Vector3::new(0.4, -0.2, 0.9)).into_inner();
        let sp = spec(["0.3", "0.5", "0.2*s"], frame);
        // the default chart, and another one away from the singular set (a chart near it, with
        // |cos β| = 0.14, is pre-asymptotic: order 1.3, then 1.6)
        let other = [Vector3::new(0.2, 0.3, 0.9), Vector3::new(-0.6, 0.3, 0.7), Vector3::new(0.9, 0.4, -0.2)]
            .into_iter()
            .map(|n| Chart::with_axis(&n))
            .find(|c| RestShape::new(&Mesh::new(3.0, 48), &sp, Some(*c)).min_abs_cos_beta(&Mesh::new(3.0, 48)) > 0.4)
            .expect("an axis with a margin");
        for chart in [None, Some(other)] {
            let mesh = Mesh::new(3.0, 12);
            let rest = RestShape::new(&mesh, &sp, chart);
            // the nodal frames of the chart angles are the integrated frames
            for i in 0..mesh.nodes() {
                let a = mesh.dofs().get(&rest.state, i, Field::Alpha);
                assert!((rest.chart.rotation(&a) - rest.frames[i]).amax() < 1e-14);
                let x = mesh.dofs().get(&rest.state, i, Field::X);
                assert!((rest.chart.to_space(&x) - rest.positions[i]).amax() < 1e-14);
            }
            // the discrete strains converge to the continuum's (κ̄, 0) at second order
            let worst = |n: usize| {
                let mesh = Mesh::new(3.0, n);
                let rest = RestShape::new(&mesh, &sp, chart);
                rest.strains.iter().enumerate().fold((0.0_f64, 0.0_f64), |(k, e), (i, r)| {
                    let s = mesh.node_s(i) + mesh.h() / 2.0;
                    let exact = Vector3::new(0.3, 0.5, 0.2 * s);
                    (k.max((r.curvature[1] - exact).amax()), e.max(r.stretch_shear[1].amax()))
                })
            };
            let (coarse, fine) = (worst(24), worst(48));
            for (c, f) in [(coarse.0, fine.0), (coarse.1, fine.1)] {
                let order = (c / f).log2();
                assert!(order > 1.8 && f < 1e-2, "order {order}: {c:e} → {f:e}");
            }
        }
    }

    #[test]
    fn the_straight_reference_keeps_the_global_chart() {
        let mesh = Mesh::new(1.0, 4);
        let rest = RestShape::new(&mesh, &spec(["0", "0", "0"], Matrix3::identity()), None);
        assert!(rest.chart.is_identity());
        // a planar arc in the x–y plane starting along e2 (singular in the paper's chart) gets
        // the plane's normal as its axis
        let mesh = Mesh::new(1.0, 8);
        let frame = Matrix3::new(1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -1.0, 0.0); // d1 = e1, d2 = e3, d3 = −e2
        let rest = RestShape::new(&mesh, &spec(["0", "1", "0"], frame), None);
        assert!((rest.chart.axis().cross(&Vector3::z())).norm() < 1e-12, "{}", rest.chart.axis());
        assert!(rest.min_abs_cos_beta(&mesh) > 1.0 - 1e-12);
        let _ = straight_element(0.1);
    }
}
