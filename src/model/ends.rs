//! The ends of the rod (`docs/decisions.md`, D22): clamped, pinned or free, each possibly moving,
//! and the rigid-body motions that a set of ends leaves free.
//!
//! A held unknown is a Dirichlet row of every solver (an exact row replacement). Its value is
//! the reference's, or, for a moving end, the prescribed position `B (x0 + u)` and the angles of
//! `Q0 R(θ)ᵀ Bᵀ` (`d_i = R(θ) d_i⁰`) in the case's chart `B` (D21), unwrapped along the path of
//! the motion.
use nalgebra::{DMatrix, Matrix3, Vector3};
use std::f64::consts::PI;

use super::chart::Chart;
use super::loads::VectorExpr;
use super::rotation::{a_matrix, skew, Angles};

/// How an end is held.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EndKind {
    /// position and the three angles held
    Clamped,
    /// position held; the angles free (zero end moment), except α — the roll of the section
    /// about its own d3 (the left factor `Rz(α)` of eq. 1) — when `twist_held`
    Pinned { twist_held: bool },
    /// nothing held
    Free,
}

impl EndKind {
    /// The held components of the end node: `x1, x2, x3, α, β, γ`.
    pub fn held(&self) -> [bool; 6] {
        match self {
            EndKind::Clamped => [true; 6],
            EndKind::Pinned { twist_held } => [true, true, true, *twist_held, false, false],
            EndKind::Free => [false; 6],
        }
    }

    /// The word of the case file.
    pub fn name(&self) -> &'static str {
        match self {
            EndKind::Clamped => "clamped",
            EndKind::Pinned { .. } => "pinned",
            EndKind::Free => "free",
        }
    }
}

/// A prescribed motion of a held end: displacement `u` [m] and rotation vector `θ` [rad], both
/// in space components, expressions of `t` (dynamic) or constants (static: scaled by the load
/// factor).
#[derive(Clone, Debug)]
pub struct Motion {
    pub displacement: VectorExpr,
    pub rotation: VectorExpr,
}

/// One end: how it is held, and its motion if it moves.
#[derive(Clone, Debug)]
pub struct End {
    pub kind: EndKind,
    pub motion: Option<Motion>,
}

/// Both ends: `start` at s = 0, `end` at s = L.
#[derive(Clone, Debug)]
pub struct Ends {
    pub start: End,
    pub end: End,
}

impl Ends {
    /// The paper's rod: clamped at s = 0 and free at s = L (D3).
    pub const CLAMPED_FREE: Ends =
        Ends { start: End { kind: EndKind::Clamped, motion: None }, end: End { kind: EndKind::Free, motion: None } };

    /// Does either end move?
    pub fn moving(&self) -> bool {
        self.start.motion.is_some() || self.end.motion.is_some()
    }

    /// The two ends with their node index on a mesh of `nodes` nodes.
    pub fn with_nodes(&self, nodes: usize) -> [(&End, usize); 2] {
        [(&self.start, 0), (&self.end, nodes - 1)]
    }
}

/// Where a motion is evaluated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MotionAt {
    /// a static solve at load factor λ: `λ u(0)`, `λ θ(0)`; the angles unwrapped along λ from
    /// the reference in `max(1, ⌈λ|θ| / (π/4)⌉)` equal steps
    Static { load_factor: f64 },
    /// a time step from `t_prev` to `t`: the angles unwrapped against the previous step's
    /// (`prev`) through [`DYNAMIC_SUBSTEPS`] equal sub-steps of t
    Dynamic { t_prev: f64, t: f64 },
}

/// Sub-steps of t between two time steps along which a prescribed rotation is unwrapped.
pub const DYNAMIC_SUBSTEPS: usize = 4;
/// Largest rotation between two samples of a static rotation's path [rad].
pub const STATIC_ROTATION_STEP_RAD: f64 = PI / 4.0;

/// The reference of one end: its position and frame in space, and its angles in the chart.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EndReference {
    /// position `x0` [m], space coordinates
    pub position: Vector3<f64>,
    /// frame `Q0` (rows d1, d2, d3), space coordinates
    pub frame: Matrix3<f64>,
    /// angles of `Q0 Bᵀ` in the chart [rad]
    pub angles: Angles,
}

/// `R(θ) = exp([θ]×)`, the rotation by the rotation vector `θ` [rad] (Rodrigues).
pub fn rotation_vector(theta: &Vector3<f64>) -> Matrix3<f64> {
    nalgebra::Rotation3::new(*theta).into_inner()
}

impl Motion {
    /// The end's prescribed position (chart coordinates) and angles (chart) at `at`, given the
    /// end's reference and, for a time step, the previous step's angles `prev`.
    pub fn target(
        &self,
        reference: &EndReference,
        chart: &Chart,
        at: MotionAt,
        prev: &Angles,
    ) -> (Vector3<f64>, Angles) {
        let frame_at = |theta: &Vector3<f64>| reference.frame * rotation_vector(theta).transpose();
        match at {
            MotionAt::Static { load_factor } => {
                let (u, theta) = (self.displacement.at(0.0, 0.0), self.rotation.at(0.0, 0.0));
                let samples = ((load_factor.abs() * theta.norm()) / STATIC_ROTATION_STEP_RAD).ceil().max(1.0) as usize;
                let mut angles = reference.angles;
                for k in 1..=samples {
                    let f = load_factor * k as f64 / samples as f64;
                    angles = chart.angles_of(&frame_at(&(theta * f)), &angles);
                }
                (chart.to_chart(&(reference.position + u * load_factor)), angles)
            }
            MotionAt::Dynamic { t_prev, t } => {
                let mut angles = *prev;
                for k in 1..=DYNAMIC_SUBSTEPS {
                    let tk = t_prev + (t - t_prev) * k as f64 / DYNAMIC_SUBSTEPS as f64;
                    angles = chart.angles_of(&frame_at(&self.rotation.at(0.0, tk)), &angles);
                }
                (chart.to_chart(&(reference.position + self.displacement.at(0.0, t))), angles)
            }
        }
    }
}

/// An infinitesimal rigid motion in space: `δx = translation + rotation × x`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidMotion {
    pub translation: Vector3<f64>,
    pub rotation: Vector3<f64>,
}

impl std::fmt::Display for RigidMotion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // three decimals, no negative zero
        let c = |x: f64| (x * 1e3).round() / 1e3 + 0.0;
        let v = |v: &Vector3<f64>| format!("({:.3}, {:.3}, {:.3})", c(v[0]), c(v[1]), c(v[2]));
        // a direction with its largest component positive
        let dir = |d: Vector3<f64>| if d[d.iamax()] < 0.0 { -d } else { d };
        let w = self.rotation.norm();
        if w < 1e-9 * self.translation.norm().max(1.0) {
            write!(f, "a translation along {}", v(&dir(self.translation.normalize())))
        } else {
            // the axis: points p with δx(p) ∥ ω, p = ω × t / |ω|²
            let point = self.rotation.cross(&self.translation) / (w * w);
            write!(f, "a rotation about the axis through {} m along {}", v(&point), v(&dir(self.rotation / w)))
        }
    }
}

/// The rigid-body motions of the rod that the held unknowns leave free (D22), in space
/// coordinates: a basis of the null space of the held rows applied to the six motions
/// `δx = t + ω × x0`, `δα = A(α0)⁻¹ Q0 ω` (`δθ = Qᵀ A δα`, eqs. 27, 30) at the two ends.
/// `length_m` scales rotations against translations. Empty when every motion is held.
pub fn free_rigid_motions(
    ends: &Ends,
    start: &EndReference,
    end: &EndReference,
    chart: &Chart,
    length_m: f64,
) -> Vec<RigidMotion> {
    let mut rows: Vec<[f64; 6]> = Vec::new();
    for (e, r) in [(&ends.start, start), (&ends.end, end)] {
        let held = e.kind.held();
        // in chart coordinates: x̃ = B x, ω̃ = B ω, Q̃ = Q Bᵀ
        let x = chart.to_chart(&r.position);
        let q = r.frame * chart.base.transpose();
        let minus_x = -skew(&x) * length_m; // ω × x = −[x]× ω, with ω scaled by 1/L
        let angle_rows = a_matrix(&r.angles).try_inverse().map(|ai| ai * q * length_m);
        for k in 0..3 {
            if held[k] {
                let mut row = [0.0; 6];
                row[k] = 1.0;
                for j in 0..3 {
                    row[3 + j] = minus_x[(k, j)];
                }
                rows.push(row);
            }
            if held[3 + k] {
                if let Some(m) = &angle_rows {
                    let mut row = [0.0; 6];
                    for j in 0..3 {
                        row[3 + j] = m[(k, j)];
                    }
                    rows.push(row);
                }
            }
        }
    }
    if rows.is_empty() {
        return (0..6).map(|k| basis_motion(k, chart, length_m)).collect();
    }
    let c = DMatrix::from_fn(rows.len(), 6, |i, j| rows[i][j]);
    // null vectors of C: eigenvalues of CᵀC at round-off (≈ ε |C|², measured 1e-17) against
    // the held ones (≥ 1e-2 |C|² for any end that holds a motion at all)
    let eig = (c.transpose() * &c).symmetric_eigen();
    let top = eig.eigenvalues.amax();
    (0..6)
        .filter(|&k| eig.eigenvalues[k] <= 1e-10 * top)
        .map(|k| {
            let v = eig.eigenvectors.column(k);
            let t = Vector3::new(v[0], v[1], v[2]);
            let w = Vector3::new(v[3], v[4], v[5]) / length_m;
            RigidMotion { translation: chart.to_space(&t), rotation: chart.to_space(&w) }
        })
        .collect()
}

fn basis_motion(k: usize, chart: &Chart, length_m: f64) -> RigidMotion {
    let mut v = [0.0; 6];
    v[k] = 1.0;
    let t = Vector3::new(v[0], v[1], v[2]);
    let w = Vector3::new(v[3], v[4], v[5]) / length_m;
    RigidMotion { translation: chart.to_space(&t), rotation: chart.to_space(&w) }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn straight_end(z: f64) -> EndReference {
        EndReference { position: Vector3::new(0.0, 0.0, z), frame: Matrix3::identity(), angles: Vector3::zeros() }
    }

    fn ends(start: EndKind, end: EndKind) -> Ends {
        Ends { start: End { kind: start, motion: None }, end: End { kind: end, motion: None } }
    }

    #[test]
    fn clamped_ends_hold_every_rigid_motion() {
        let (a, b) = (straight_end(0.0), straight_end(2.0));
        let c = Chart::identity();
        assert!(free_rigid_motions(&Ends::CLAMPED_FREE, &a, &b, &c, 2.0).is_empty());
        let pp = ends(EndKind::Pinned { twist_held: true }, EndKind::Pinned { twist_held: false });
        assert!(free_rigid_motions(&pp, &a, &b, &c, 2.0).is_empty());
        assert_eq!(free_rigid_motions(&ends(EndKind::Free, EndKind::Free), &a, &b, &c, 2.0).len(), 6);
    }

    #[test]
    fn pinned_pinned_leaves_the_spin_about_the_chord_free() {
        // a straight rod from (0, 0, 0) to (0, 0, 2), pinned at both ends: the spin about e3
        let (a, b) = (straight_end(0.0), straight_end(2.0));
        let pp = ends(EndKind::Pinned { twist_held: false }, EndKind::Pinned { twist_held: false });
        let free = free_rigid_motions(&pp, &a, &b, &Chart::identity(), 2.0);
        assert_eq!(free.len(), 1);
        let m = free[0];
        assert!(m.translation.norm() < 1e-12 && m.rotation.cross(&Vector3::z()).norm() < 1e-12, "{m:?}");
        assert!(m.to_string().contains("along (0.000, 0.000, "), "{m}");
        // pinned–free: rotations about every axis through the pin
        let pf = ends(EndKind::Pinned { twist_held: false }, EndKind::Free);
        let free = free_rigid_motions(&pf, &a, &b, &Chart::identity(), 2.0);
        assert_eq!(free.len(), 3);
        for m in free {
            assert!(m.translation.norm() < 1e-12, "about the pin at the origin: {m:?}");
        }
    }

    #[test]
    fn the_free_rotation_of_an_offset_pin_is_named_by_its_axis() {
        // pinned at (1, 2, 0) with the twist held and free at the other end: two rotations about
        // axes through the pin; in the paper's chart (β = 0) they are those perpendicular to d3
        let a = EndReference { position: Vector3::new(1.0, 2.0, 0.0), ..straight_end(0.0) };
        let b = EndReference { position: Vector3::new(1.0, 2.0, 1.0), ..straight_end(0.0) };
        let e = ends(EndKind::Pinned { twist_held: true }, EndKind::Free);
        let check = |chart: &Chart, perpendicular: bool| {
            let q: Matrix3<f64> = chart.base.transpose();
            let a = EndReference { angles: crate::model::rotation::angles_from_rotation(&q), ..a };
            let b = EndReference { angles: a.angles, ..b };
            let free = free_rigid_motions(&e, &a, &b, chart, 1.0);
            assert_eq!(free.len(), 2);
            for m in free {
                // the held angle α does not move: (A⁻¹ Q ω)_1 = 0 in chart coordinates
                let w = chart.to_chart(&m.rotation);
                let da = a_matrix(&a.angles).try_inverse().unwrap() * q * w;
                assert!(da[0].abs() < 1e-10 * w.norm(), "{m:?}");
                if perpendicular {
                    assert!(m.rotation[2].abs() < 1e-10 * w.norm(), "perpendicular to d3: {m:?}");
                }
                // the pin does not move: δx(pin) = t + ω × pin = 0
                let pin = Vector3::new(1.0, 2.0, 0.0);
                assert!((m.translation + m.rotation.cross(&pin)).norm() < 1e-10 * w.norm(), "{m}");
            }
        };
        check(&Chart::identity(), true);
        check(&Chart::with_axis(&Vector3::new(0.3, 0.9, 0.2)), false);
    }

    #[test]
    fn a_static_rotation_is_unwrapped_along_its_path() {
        // 27 turns about e3 of a clamped end of the straight rod: α = −27·2π (varying α rotates
        // d1, d2 about d3 by −α)
        let r = straight_end(1.0);
        let z = || crate::expr::Expr::parse("0").unwrap();
        let turns = crate::expr::Expr::parse("54*pi").unwrap();
        let constants = std::collections::BTreeMap::new();
        let m = Motion {
            displacement: VectorExpr::new([z(), z(), crate::expr::Expr::parse("-0.1").unwrap()], &constants).unwrap(),
            rotation: VectorExpr::new([z(), z(), turns], &constants).unwrap(),
        };
        let (x, a) = m.target(&r, &Chart::identity(), MotionAt::Static { load_factor: 1.0 }, &r.angles);
        assert!((x - Vector3::new(0.0, 0.0, 0.9)).norm() < 1e-15);
        assert!((a - Vector3::new(-54.0 * PI, 0.0, 0.0)).amax() < 1e-9, "{a}");
        let (_, half) = m.target(&r, &Chart::identity(), MotionAt::Static { load_factor: 0.5 }, &r.angles);
        assert!((half[0] + 27.0 * PI).abs() < 1e-9, "{half}");
    }
}
