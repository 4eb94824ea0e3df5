//! Rotation kinematics of the paper's Euler-type angle chart, §2.1 and §2.3.
//!
//! The frame is parametrised by `α = (α, β, γ)` [rad] through
//!
//! ```text
//!   Q = Rz(α) Rx(β) Ry(γ)                                   eq. (1)
//!   [d1, d2, d3] = [e1, e2, e3] Qᵀ   (d_i = rows of Q)      eq. (2), Remark 3
//!   κˡ = A(α) ∂s α,   ωˡ = A(α) ∂t α                         eqs. (27), (28)
//!
//!         ⎡ 0  −cos α   sin α cos β ⎤
//!   A  =  ⎢ 0  −sin α  −cos α cos β ⎥        det A = −cos β
//!         ⎣−1    0       −sin β     ⎦
//! ```
//!
//! Every derivative used by the Newton Jacobians is here and is finite-difference checked in
//! the tests below (see also `docs/decisions.md`, D1).
use std::cell::Cell;

use nalgebra::{Matrix3, Vector3};

/// Angles `(α, β, γ)` of eq. (1) [rad].
pub type Angles = Vector3<f64>;

/// Sines and cosines of the three angles, computed once per quadrature point.
#[derive(Clone, Copy, Debug)]
struct Trig {
    ca: f64,
    sa: f64,
    cb: f64,
    sb: f64,
    cg: f64,
    sg: f64,
}

impl Trig {
    /// The sines and cosines of `a`, from [`TRIG_CACHE`] if they were computed lately. Inlined
    /// into every kernel (the lookup is a few comparisons; a call costs as much).
    #[inline(always)]
    fn new(a: &Angles) -> Self {
        let key = [a[0].to_bits(), a[1].to_bits(), a[2].to_bits()];
        TRIG_CACHE.with(|c| {
            if let Some(k) = c.keys.iter().position(|k| k.get() == key) {
                return c.values[k].get();
            }
            let t = Self::compute(a);
            let k = c.next.get();
            c.keys[k].set(key);
            c.values[k].set(t);
            c.next.set((k + 1) % TRIG_SLOTS);
            t
        })
    }

    #[inline(never)]
    fn compute(a: &Angles) -> Self {
        let (sa, ca) = a[0].sin_cos();
        let (sb, cb) = a[1].sin_cos();
        let (sg, cg) = a[2].sin_cos();
        Trig { ca, sa, cb, sb, cg, sg }
    }
}

/// Entries of [`TRIG_CACHE`]: the distinct quadrature points of one element (midpoint and the
/// two Gauss points) and one more.
const TRIG_SLOTS: usize = 4;

/// The last few angle triples (by their bits) and their sines and cosines, per thread. The
/// kernels of one element evaluate `Q`, `A`, `d3` and their derivatives at the same few points
/// many times (the element system, the coefficient derivative, the measures): the same
/// numbers, computed once.
struct TrigCache {
    keys: [Cell<[u64; 3]>; TRIG_SLOTS],
    values: [Cell<Trig>; TRIG_SLOTS],
    next: Cell<usize>,
}

const NO_TRIG: Trig = Trig { ca: 1.0, sa: 0.0, cb: 1.0, sb: 0.0, cg: 1.0, sg: 0.0 };

thread_local! {
    // keys start as the bits of (0, 0, 0) with the values of (0, 0, 0)
    static TRIG_CACHE: TrigCache = const {
        TrigCache {
            keys: [const { Cell::new([0; 3]) }; TRIG_SLOTS],
            values: [const { Cell::new(NO_TRIG) }; TRIG_SLOTS],
            next: Cell::new(0),
        }
    };
}

fn rz(c: f64, s: f64) -> Matrix3<f64> {
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}
fn rx(c: f64, s: f64) -> Matrix3<f64> {
    Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
}
fn ry(c: f64, s: f64) -> Matrix3<f64> {
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}
/// Derivatives of the elementary rotations with respect to their angle.
fn drz(c: f64, s: f64) -> Matrix3<f64> {
    Matrix3::new(-s, -c, 0.0, c, -s, 0.0, 0.0, 0.0, 0.0)
}
fn drx(c: f64, s: f64) -> Matrix3<f64> {
    Matrix3::new(0.0, 0.0, 0.0, 0.0, -s, -c, 0.0, c, -s)
}
fn dry(c: f64, s: f64) -> Matrix3<f64> {
    Matrix3::new(-s, 0.0, c, 0.0, 0.0, 0.0, -c, 0.0, -s)
}

/// The rotation matrix `Q(α)` of eq. (1).
pub fn rotation(a: &Angles) -> Matrix3<f64> {
    rotation_t(&Trig::new(a))
}

fn rotation_t(t: &Trig) -> Matrix3<f64> {
    rz(t.ca, t.sa) * rx(t.cb, t.sb) * ry(t.cg, t.sg)
}

/// `∂Q/∂α_j` for j = 0, 1, 2 (derivative of eq. (1) with respect to α, β, γ).
pub fn rotation_derivatives(a: &Angles) -> [Matrix3<f64>; 3] {
    rotation_derivatives_t(&Trig::new(a))
}

fn rotation_derivatives_t(t: &Trig) -> [Matrix3<f64>; 3] {
    let (z, x, y) = (rz(t.ca, t.sa), rx(t.cb, t.sb), ry(t.cg, t.sg));
    [drz(t.ca, t.sa) * x * y, z * drx(t.cb, t.sb) * y, z * x * dry(t.cg, t.sg)]
}

/// The matrix `A(α)` of eqs. (27)/(28), mapping angle rates to local angular velocity/curvature.
pub fn a_matrix(a: &Angles) -> Matrix3<f64> {
    a_matrix_t(&Trig::new(a))
}

fn a_matrix_t(t: &Trig) -> Matrix3<f64> {
    Matrix3::new(0.0, -t.ca, t.sa * t.cb, 0.0, -t.sa, -t.ca * t.cb, -1.0, 0.0, -t.sb)
}

/// `∂A/∂α_j` for j = 0, 1, 2.
pub fn a_matrix_derivatives(a: &Angles) -> [Matrix3<f64>; 3] {
    a_matrix_derivatives_t(&Trig::new(a))
}

fn a_matrix_derivatives_t(t: &Trig) -> [Matrix3<f64>; 3] {
    [
        Matrix3::new(0.0, t.sa, t.ca * t.cb, 0.0, -t.ca, t.sa * t.cb, 0.0, 0.0, 0.0),
        Matrix3::new(0.0, 0.0, -t.sa * t.sb, 0.0, 0.0, t.ca * t.sb, 0.0, 0.0, -t.cb),
        Matrix3::zeros(),
    ]
}

/// `Q`, `A` and, if asked, `∂Q/∂α_j`, `∂A/∂α_j` at one point from one evaluation of the sines
/// and cosines: the same numbers as [`rotation`], [`a_matrix`], [`rotation_derivatives`] and
/// [`a_matrix_derivatives`], for kernels that need several of them at the same angles.
#[derive(Clone, Copy, Debug)]
pub struct PointFrame {
    pub q: Matrix3<f64>,
    pub a: Matrix3<f64>,
    /// `∂Q/∂α_j` (zeros unless made with derivatives)
    pub dq: [Matrix3<f64>; 3],
    /// `∂A/∂α_j` (zeros unless made with derivatives)
    pub da: [Matrix3<f64>; 3],
}

/// Whether a [`PointFrame`] also holds the derivatives `∂Q/∂α_j`, `∂A/∂α_j` (a kernel that
/// assembles a tangent needs them, a residual alone does not).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Derivatives {
    Without,
    With,
}

impl Derivatives {
    /// [`Derivatives::With`] where a tangent is assembled (`tangent` is `Some`).
    pub fn for_tangent<T>(tangent: &Option<T>) -> Self {
        match tangent {
            Some(_) => Derivatives::With,
            None => Derivatives::Without,
        }
    }
}

impl PointFrame {
    pub fn new(a: &Angles, derivatives: Derivatives) -> Self {
        let t = Trig::new(a);
        let (dq, da) = match derivatives {
            Derivatives::With => (rotation_derivatives_t(&t), a_matrix_derivatives_t(&t)),
            Derivatives::Without => ([Matrix3::zeros(); 3], [Matrix3::zeros(); 3]),
        };
        PointFrame { q: rotation_t(&t), a: a_matrix_t(&t), dq, da }
    }
}

/// Director `d3 = q3 = (−cos β sin γ, sin β, cos β cos γ)`, third row of Q (eq. (2), §4).
pub fn d3(a: &Angles) -> Vector3<f64> {
    let t = Trig::new(a);
    Vector3::new(-t.cb * t.sg, t.sb, t.cb * t.cg)
}

/// Second derivatives `∂²d3/∂α_i∂α_j` (symmetric in i, j; d3 does not depend on α), used by
/// the Newton Jacobian of the λd term of the inverse problem (eqs. 56–58 differentiated once more).
pub fn d3_second_derivatives(a: &Angles) -> [[Vector3<f64>; 3]; 3] {
    let t = Trig::new(a);
    let z = Vector3::zeros();
    let bb = Vector3::new(t.cb * t.sg, -t.sb, -t.cb * t.cg);
    let bg = Vector3::new(t.sb * t.cg, 0.0, t.sb * t.sg);
    let gg = Vector3::new(t.cb * t.sg, 0.0, -t.cb * t.cg);
    [[z, z, z], [z, bb, bg], [z, bg, gg]]
}

/// Local curvature `κˡ = A(α) ∂s α` [1/m], eq. (28).
pub fn curvature(a: &Angles, da_ds: &Vector3<f64>) -> Vector3<f64> {
    a_matrix(a) * da_ds
}

/// Cross-product matrix `[v]×` so that `[v]× w = v × w`; this is `B(x)` of eq. (35) for `v = ∂s x`.
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0)
}

/// Recover angles from a rotation matrix in the chart of eq. (1) (inverse of [`rotation`]).
/// Valid away from the singular set cos β = 0; returns β in [−π/2, π/2].
pub fn angles_from_rotation(q: &Matrix3<f64>) -> Angles {
    // Row 3 of Q: (−cβ sγ, sβ, cβ cγ); column 2: (−sα cβ, cα cβ, sβ).
    let beta = q[(2, 1)].clamp(-1.0, 1.0).asin();
    let gamma = (-q[(2, 0)]).atan2(q[(2, 2)]);
    let alpha = (-q[(0, 1)]).atan2(q[(1, 1)]);
    Vector3::new(alpha, beta, gamma)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Smooth angle field used by the finite-difference checks.
    fn field(s: f64) -> Angles {
        Vector3::new(0.7 * (1.3 * s).sin() + 0.2, -0.4 * (0.9 * s).cos() + 0.1, 0.5 * s * s - 0.3)
    }
    fn dfield(s: f64) -> Vector3<f64> {
        Vector3::new(0.7 * 1.3 * (1.3 * s).cos(), 0.4 * 0.9 * (0.9 * s).sin(), s)
    }

    #[test]
    fn q_is_orthonormal_and_proper() {
        for k in 0..50 {
            let a = field(0.37 * k as f64 - 3.0) * 3.0;
            let q = rotation(&a);
            assert!((q * q.transpose() - Matrix3::identity()).amax() < 1e-14);
            assert!((q.determinant() - 1.0).abs() < 1e-14);
        }
    }

    #[test]
    fn q_matches_printed_matrix_of_eq_1() {
        let a: Vector3<f64> = Vector3::new(0.3, -0.8, 1.1);
        let (ca, sa, cb, sb, cg, sg) = (a[0].cos(), a[0].sin(), a[1].cos(), a[1].sin(), a[2].cos(), a[2].sin());
        let printed = Matrix3::new(
            ca * cg - sa * sb * sg,
            -sa * cb,
            ca * sg + sa * sb * cg,
            sa * cg + ca * sb * sg,
            ca * cb,
            sa * sg - ca * sb * cg,
            -cb * sg,
            sb,
            cb * cg,
        );
        assert!((rotation(&a) - printed).amax() < 1e-15);
        assert!((d3(&a) - rotation(&a).row(2).transpose()).amax() < 1e-15);
    }

    /// κ from eq. (19), κ = ½ Σ d_i × ∂s d_i, expressed in the local frame (κˡ = Q κᵍ, eq. 4),
    /// must equal A ∂s α of eq. (28).
    #[test]
    fn curvature_matches_eq_19_by_finite_differences() {
        let h = 1e-6;
        for k in 0..20 {
            let s = -2.0 + 0.21 * k as f64;
            let q = rotation(&field(s));
            let dq = (rotation(&field(s + h)) - rotation(&field(s - h))) / (2.0 * h);
            let mut kappa_g = Vector3::zeros();
            for i in 0..3 {
                let d: Vector3<f64> = q.row(i).transpose();
                let dd: Vector3<f64> = dq.row(i).transpose();
                kappa_g += 0.5 * d.cross(&dd);
            }
            let kappa_l = q * kappa_g;
            let from_a = curvature(&field(s), &dfield(s));
            assert!((kappa_l - from_a).amax() < 1e-8, "s={s}: {kappa_l} vs {from_a}");
        }
    }

    #[test]
    fn small_angle_limit() {
        // About Q = I: κˡ ≈ −(β', γ', α') (PAPER-NOTES).
        let eps = 1e-7;
        let da = Vector3::new(0.3, -0.2, 0.5);
        let k = curvature(&(da * eps), &da);
        assert!((k - Vector3::new(-da[1], -da[2], -da[0])).amax() < 1e-6);
        let q = rotation(&(da * eps));
        let skew_part = (q - q.transpose()) / (2.0 * eps);
        // Q ≈ I + ε [θ]× with θ = (β, γ, α): β about e1, γ about e2, α about e3.
        assert!((skew_part - skew(&Vector3::new(da[1], da[2], da[0]))).amax() < 1e-6);
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let a = Vector3::new(0.4, -0.7, 1.2);
        let h = 1e-6;
        let dq = rotation_derivatives(&a);
        let da = a_matrix_derivatives(&a);
        for j in 0..3 {
            let mut ap = a;
            ap[j] += h;
            let mut am = a;
            am[j] -= h;
            let fq = (rotation(&ap) - rotation(&am)) / (2.0 * h);
            let fa = (a_matrix(&ap) - a_matrix(&am)) / (2.0 * h);
            assert!((fq - dq[j]).amax() < 1e-9, "dQ/da_{j}");
            assert!((fa - da[j]).amax() < 1e-9, "dA/da_{j}");
        }
    }

    #[test]
    fn d3_second_derivatives_match_finite_differences() {
        let h = 1e-6;
        for a in [Vector3::new(0.4, -0.7, 1.2), Vector3::new(-1.1, 2.8, -0.3), Vector3::zeros()] {
            let dd = d3_second_derivatives(&a);
            for j in 0..3 {
                let mut ap = a;
                ap[j] += h;
                let mut am = a;
                am[j] -= h;
                let (dp, dm) = (rotation_derivatives(&ap), rotation_derivatives(&am));
                for i in 0..3 {
                    let fd: Vector3<f64> = (dp[i].row(2) - dm[i].row(2)).transpose() / (2.0 * h);
                    assert!((fd - dd[i][j]).amax() < 1e-9, "d2 d3 / da_{i} da_{j} at {a}");
                }
            }
        }
    }

    #[test]
    fn point_frame_is_the_separate_functions() {
        for k in 0..10 {
            let a = field(0.7 * k as f64) * 2.0;
            let f = PointFrame::new(&a, Derivatives::With);
            assert_eq!(f.q, rotation(&a));
            assert_eq!(f.a, a_matrix(&a));
            assert_eq!(f.dq, rotation_derivatives(&a));
            assert_eq!(f.da, a_matrix_derivatives(&a));
        }
    }

    #[test]
    fn determinant_of_a_is_minus_cos_beta() {
        for k in 0..10 {
            let a = field(k as f64);
            assert!((a_matrix(&a).determinant() + a[1].cos()).abs() < 1e-14);
        }
    }

    #[test]
    fn angles_round_trip() {
        for k in 0..30 {
            let a = Vector3::new(-2.5 + 0.17 * k as f64, -1.2 + 0.08 * k as f64, 2.9 - 0.19 * k as f64);
            let b = angles_from_rotation(&rotation(&a));
            assert!((rotation(&b) - rotation(&a)).amax() < 1e-13);
            assert!((b - a).amax() < 1e-12);
        }
    }
}
