//! The rebased angle chart (issue 5; derivation in `docs/rotation.md`, R1–R7).
//!
//! The paper's frame `Q = Q_E(α) = Rz(α) Rx(β) Ry(γ)` (eq. 1) is singular where `d3 = ±e2`
//! (`det A = −cos β`, eqs. 27–28). A [`Chart`] composes it with a constant rotation `B` (the
//! *base*), chosen per frame from the data:
//!
//! ```text
//!   Q = Q_E(α) B,     d_i = Bᵀ d̃_i(α),     singular set: d3 = ±n,  n = Bᵀ e2        (R1)
//! ```
//!
//! Because `B` is constant along the rod, `∂s Q Qᵀ = ∂s Q_E Q_Eᵀ`: the local curvature
//! `κˡ = A(α) ∂s α` (eq. 28), the angular velocity `ωˡ = A(α) ∂t α` (eq. 27), `A`, `∂d3/∂α`
//! and every linearisation of the solvers keep their form (R2). Solving the frame in the chart
//! with base `B` is solving the paper's problem for the data rotated by `B` (`x̃_g = B x_g`) and
//! rotating the answer back (R3): the element code is unchanged. The base is chosen so that
//! the chart's singular axis `n` is as far as possible from every tangent of the frame (R4).
use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use std::f64::consts::PI;

use super::rotation::{angles_from_rotation, rotation, Angles};

/// A chart `Q = Q_E(α) B` of eq. (1) composed with a constant base rotation `B` (R1).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Chart {
    /// `B`: maps space coordinates to chart coordinates (`x̃ = B x`)
    pub base: Matrix3<f64>,
}

impl Default for Chart {
    fn default() -> Self {
        Chart::identity()
    }
}

impl Chart {
    /// The paper's global chart, `B = I`.
    pub fn identity() -> Self {
        Chart { base: Matrix3::identity() }
    }

    /// The chart whose singular axis is `±n` (R4): `B` is the minimal rotation taking the unit
    /// vector `n` to `e2` (the identity for `n = e2`). Any other `B'` with `B' n = e2` differs
    /// by a rotation about e2, which only shifts γ (R5), so the solution does not depend on
    /// this choice.
    pub fn with_axis(n: &Vector3<f64>) -> Self {
        let n = n.normalize();
        let e2 = Vector3::y();
        let c = n.dot(&e2);
        let base = if (c - 1.0).abs() < 1e-15 {
            Matrix3::identity()
        } else if (c + 1.0).abs() < 1e-15 {
            // half turn about e3 (n = −e2)
            Matrix3::from_diagonal(&Vector3::new(-1.0, -1.0, 1.0))
        } else {
            let vx = super::rotation::skew(&n.cross(&e2));
            Matrix3::identity() + vx + vx * vx / (1.0 + c)
        };
        Chart { base }
    }

    /// The singular axis `n = Bᵀ e2` of the chart.
    pub fn axis(&self) -> Vector3<f64> {
        self.base.transpose() * Vector3::y()
    }

    pub fn is_identity(&self) -> bool {
        self.base == Matrix3::identity()
    }

    /// `Q = Q_E(α) B` (R1): rows are the directors in space coordinates.
    pub fn rotation(&self, a: &Angles) -> Matrix3<f64> {
        rotation(a) * self.base
    }

    /// Space → chart coordinates of a vector (`B v`).
    pub fn to_chart(&self, v: &Vector3<f64>) -> Vector3<f64> {
        self.base * v
    }

    /// Chart → space coordinates of a vector (`Bᵀ v`).
    pub fn to_space(&self, v: &Vector3<f64>) -> Vector3<f64> {
        self.base.transpose() * v
    }

    /// Angles of the frame `q` (rows = directors, space coordinates) in this chart, each
    /// angle shifted by a multiple of 2π to lie nearest `near` (R6).
    pub fn angles_of(&self, q: &Matrix3<f64>, near: &Angles) -> Angles {
        unwrap_near(angles_from_rotation(&(q * self.base.transpose())), near)
    }

    /// Re-express nodal angles of `from` in this chart (R6): each node's frame
    /// `Q_E(α_i) B_from` is converted, and unwrapped against `near_i` (if given) or else
    /// against the previous node. Returns the input unchanged when the bases are equal.
    pub fn reexpress(&self, from: &Chart, alpha: &[Angles], near: Option<&[Angles]>) -> Vec<Angles> {
        self.converted(from, alpha).unwrapped(near)
    }

    /// The conversion step of [`Chart::reexpress`], before unwrapping: for angles that are
    /// re-expressed against more than one guide, the (costly) conversion once.
    pub fn converted(&self, from: &Chart, alpha: &[Angles]) -> Converted {
        if from.base == self.base {
            return Converted::Same(alpha.to_vec());
        }
        Converted::Raw(
            alpha.iter().map(|a| angles_from_rotation(&(from.rotation(a) * self.base.transpose()))).collect(),
        )
    }
}

/// Nodal angles converted to a chart by [`Chart::converted`], to be unwrapped.
#[derive(Clone, Debug)]
pub enum Converted {
    /// the charts are the same: the angles as they were (not unwrapped)
    Same(Vec<Angles>),
    /// the angles of `angles_from_rotation` in the new chart
    Raw(Vec<Angles>),
}

impl Converted {
    /// The angles unwrapped as [`Chart::reexpress`] does: against `near_i` (if given) or else
    /// against the previous node (the first node against itself).
    pub fn unwrapped(&self, near: Option<&[Angles]>) -> Vec<Angles> {
        let raw = match self {
            Converted::Same(a) => return a.clone(),
            Converted::Raw(raw) => raw,
        };
        let mut out: Vec<Angles> = Vec::with_capacity(raw.len());
        for (i, a) in raw.iter().enumerate() {
            let guide = match (near, out.last()) {
                (Some(nr), _) => nr[i],
                (None, Some(p)) => *p,
                (None, None) => *a,
            };
            out.push(unwrap_near(*a, &guide));
        }
        out
    }
}

/// `a` with each angle shifted by a multiple of 2π to lie nearest `near` (R6).
fn unwrap_near(mut a: Angles, near: &Angles) -> Angles {
    for k in 0..3 {
        a[k] += 2.0 * PI * ((near[k] - a[k]) / (2.0 * PI)).round();
    }
    a
}

/// Unit tangents of the elements of a polyline (chords).
fn element_tangents(x: &[Vector3<f64>]) -> impl Iterator<Item = Vector3<f64>> + '_ {
    x.windows(2).filter_map(|w| (w[1] - w[0]).try_normalize(0.0))
}

/// Margin of a candidate singular axis `n` for a frame (R4): `min_e √(1 − (t_e·n)²)` over the
/// element tangents `t_e`, i.e. the smallest |cos β| the data's own frame would have.
pub fn axis_margin(x: &[Vector3<f64>], n: &Vector3<f64>) -> f64 {
    element_tangents(x).map(|t| (1.0 - t.dot(n).powi(2)).max(0.0).sqrt()).fold(1.0, f64::min)
}

/// The singular axis of a frame (R4): the eigenvector of the smallest eigenvalue of the
/// tangent scatter `T = Σ_e t_e t_eᵀ` (it minimises `Σ (t_e·n)²`; for a planar frame it is the
/// plane's normal, where every node has β = 0). The sign is chosen with `n·prev ≥ 0` (`prev`:
/// the previous frame's axis), or `n·e2 ≥ 0` without one. If that axis leaves a margin below
/// ½ (a strongly non-planar frame), the axis of largest margin among 2 × 4000 quasi-uniform
/// directions is used instead. Both choices rotate with the data (equivariance, R5) except in
/// that fallback and when two eigenvalues coincide (a straight frame).
pub fn frame_axis(x: &[Vector3<f64>], prev: Option<&Vector3<f64>>) -> Vector3<f64> {
    let mut t = Matrix3::zeros();
    for e in element_tangents(x) {
        t += e * e.transpose();
    }
    let eig = SymmetricEigen::new(t);
    let k = eig.eigenvalues.imin();
    let mut n: Vector3<f64> = eig.eigenvectors.column(k).into_owned();
    // Exact zeros stay exact (a planar x–z frame gives exactly ±e2).
    n.iter_mut().for_each(|v| {
        if v.abs() < 1e-15 {
            *v = 0.0
        }
    });
    n = n.normalize();
    if axis_margin(x, &n) < 0.5 {
        n = best_margin_axis(x);
    }
    let reference = prev.copied().unwrap_or_else(Vector3::y);
    if n.dot(&reference) < 0.0 {
        n = -n;
    }
    n
}

/// The direction of largest [`axis_margin`] among a Fibonacci lattice on the upper half sphere.
fn best_margin_axis(x: &[Vector3<f64>]) -> Vector3<f64> {
    const N: usize = 4000;
    let golden = PI * (3.0 - 5f64.sqrt());
    (0..N)
        .map(|i| {
            let z = (i as f64 + 0.5) / N as f64; // upper half sphere: ±n are the same axis
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            Vector3::new(r * phi.cos(), z, r * phi.sin())
        })
        .map(|n| (axis_margin(x, &n), n))
        .fold((-1.0, Vector3::y()), |a, b| if b.0 > a.0 { b } else { a })
        .1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::rotation::{a_matrix, curvature, d3, rotation_derivatives};

    fn random_rotation(seed: u64) -> Matrix3<f64> {
        let mut s = seed;
        let mut next = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let v = Vector3::new(next(), next(), next()) * 2.5;
        nalgebra::Rotation3::new(v).into_inner()
    }

    #[test]
    fn with_axis_maps_the_axis_to_e2() {
        for k in 0..20 {
            let n = random_rotation(k) * Vector3::new(0.3, -0.5, 0.8).normalize();
            let c = Chart::with_axis(&n);
            assert!((c.base * n - Vector3::y()).amax() < 1e-14);
            assert!((c.base * c.base.transpose() - Matrix3::identity()).amax() < 1e-14);
            assert!((c.base.determinant() - 1.0).abs() < 1e-14);
            assert!((c.axis() - n).amax() < 1e-14);
        }
        assert!(Chart::with_axis(&Vector3::y()).is_identity());
        assert!((Chart::with_axis(&-Vector3::y()).axis() + Vector3::y()).amax() < 1e-15);
    }

    /// R2: with a constant base, the curvature of `Q_E(α(s)) B` from eq. (19) is `A(α) ∂s α`,
    /// and `d3 = Bᵀ d̃3` with `∂d3/∂α = Bᵀ ∂d̃3/∂α` (finite differences).
    #[test]
    fn curvature_and_d3_variation_are_base_independent() {
        let field = |s: f64| Vector3::new(0.7 * (1.3 * s).sin() + 0.2, -0.4 * (0.9 * s).cos() + 0.1, 0.5 * s * s - 0.3);
        let dfield = |s: f64| Vector3::new(0.7 * 1.3 * (1.3 * s).cos(), 0.4 * 0.9 * (0.9 * s).sin(), s);
        let chart = Chart { base: random_rotation(7) };
        let h = 1e-6;
        for k in 0..15 {
            let s = -1.5 + 0.2 * k as f64;
            let q = chart.rotation(&field(s));
            let dq = (chart.rotation(&field(s + h)) - chart.rotation(&field(s - h))) / (2.0 * h);
            let mut kappa_g = Vector3::zeros();
            for i in 0..3 {
                let (d, dd): (Vector3<f64>, Vector3<f64>) = (q.row(i).transpose(), dq.row(i).transpose());
                kappa_g += 0.5 * d.cross(&dd);
            }
            assert!((q * kappa_g - curvature(&field(s), &dfield(s))).amax() < 1e-8);
            // d3 in space coordinates and its angle derivatives.
            let a = field(s);
            assert!((q.row(2).transpose() - chart.to_space(&d3(&a))).amax() < 1e-15);
            let dqe = rotation_derivatives(&a);
            for j in 0..3 {
                let (mut ap, mut am) = (a, a);
                ap[j] += h;
                am[j] -= h;
                let fd = (chart.rotation(&ap).row(2) - chart.rotation(&am).row(2)).transpose() / (2.0 * h);
                assert!((fd - chart.to_space(&dqe[j].row(2).transpose())).amax() < 1e-9);
            }
            // det A = −cos β in any chart: the chart's β is what the guard watches.
            assert!((a_matrix(&a).determinant() + a[1].cos()).abs() < 1e-14);
        }
    }

    /// R5: a base rotated about e2 by θ only shifts γ by θ; the axis −n shifts α by π and
    /// negates β, γ. Both maps are affine in the angles, so linear interpolation commutes with them.
    #[test]
    fn equivalent_bases_are_affine_relabellings() {
        let a = Vector3::new(0.4, -0.3, 1.1);
        let b = random_rotation(3);
        for theta in [0.3, -2.0, 3.1] {
            let ry = nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), theta).into_inner();
            let lhs = rotation(&a) * ry * b;
            let rhs = rotation(&Vector3::new(a[0], a[1], a[2] + theta)) * b;
            assert!((lhs - rhs).amax() < 1e-14);
        }
        let flip = Matrix3::from_diagonal(&Vector3::new(-1.0, -1.0, 1.0));
        let lhs = rotation(&a) * flip;
        let rhs = rotation(&Vector3::new(a[0] + PI, -a[1], -a[2]));
        assert!((lhs - rhs).amax() < 1e-14);
    }

    #[test]
    fn reexpress_round_trips_and_unwraps() {
        let from = Chart { base: random_rotation(11) };
        let to = Chart { base: random_rotation(12) };
        // A smooth frame field regular in both charts.
        let alpha: Vec<Angles> =
            (0..40).map(|i| Vector3::new(0.1 * i as f64, 0.2 * (0.1 * i as f64).sin(), 0.15 * i as f64)).collect();
        let mid = to.reexpress(&from, &alpha, None);
        for (a, m) in alpha.iter().zip(&mid) {
            assert!((from.rotation(a) - to.rotation(m)).amax() < 1e-13);
        }
        for w in mid.windows(2) {
            assert!((w[1] - w[0]).amax() < 1.0, "no 2π jumps: {} → {}", w[0], w[1]);
        }
        let back = from.reexpress(&to, &mid, Some(&alpha));
        for (a, b) in alpha.iter().zip(&back) {
            assert!((a - b).amax() < 1e-12);
        }
        assert_eq!(from.reexpress(&from, &alpha, None), alpha);
    }

    fn planar_frame(rot: &Matrix3<f64>) -> Vec<Vector3<f64>> {
        (0..60)
            .map(|i| {
                let s = i as f64 / 59.0;
                rot * Vector3::new(0.2 * (4.0 * s).sin(), 0.0, s + 0.1 * (3.0 * s).cos())
            })
            .collect()
    }

    #[test]
    fn frame_axis_is_the_plane_normal_and_rotates_with_the_data() {
        let xz = planar_frame(&Matrix3::identity());
        let n = frame_axis(&xz, None);
        assert_eq!(n, Vector3::y(), "an x–z frame gives exactly e2 (the global chart)");
        assert_eq!(axis_margin(&xz, &n), 1.0);
        for k in 0..10 {
            let r = random_rotation(100 + k);
            let nr = frame_axis(&planar_frame(&r), Some(&(r * Vector3::y())));
            assert!((nr - r * Vector3::y()).amax() < 1e-12, "{nr} vs {}", r * Vector3::y());
        }
    }

    #[test]
    fn axis_of_a_helix_keeps_its_margin() {
        // Two whole turns of a helix: its tangents sweep a cone of half-angle 60° about e3; the
        // axis is e3 and the margin sin 60°.
        let x: Vec<Vector3<f64>> = (0..200)
            .map(|i| {
                let t = i as f64 * 4.0 * PI / 199.0;
                Vector3::new(t.cos(), t.sin(), 0.577 * t)
            })
            .collect();
        let n = frame_axis(&x, None);
        assert!((n - Vector3::z()).amax() < 1e-2 || (n + Vector3::z()).amax() < 1e-2, "{n}");
        assert!(axis_margin(&x, &n) > 0.85, "margin {}", axis_margin(&x, &n));
    }
}
