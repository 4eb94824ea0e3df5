//! Pure P1 element kernels (no global state): residuals and tangents of one two-node element.
//!
//! Local unknowns are ordered `[x_a, α_a, x_b, α_b]` (12 values). Shape functions on the
//! element `[s0, s0 + h]`: `N = (1 − ξ, ξ)`, `∂s N = (−1/h, 1/h)`.
//!
//! Integrands (see `docs/decisions.md`, D3–D6, D20):
//!
//! ```text
//!   stretch–shear:  ∂sδx · n − δα · (∂s x × n),   n = Qᵀ K (Q ∂s x − e3 − ε̄)    eqs. (13), (40)
//!   bending:        ∂sδα · m,                      m = Qᵀ J (A ∂s α − κ̄)         eqs. (15), (28), (40)
//!   momentum:       δx · ρA ẋ + δα · Qᵀ I A α̇                                  eqs. (7), (27), (40)
//!   loads:          δx · f + δα · l                                             eq. (40)
//! ```
//!
//! `ε̄`, `κ̄` are the strains of the discrete reference configuration at the quadrature point
//! ([`ElementRest`], D20): zero for the paper's straight rod.
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use super::material::RodProperties;
use super::mesh::{DofMap, Field, QuadratureScheme, Rule};
use super::rotation::{curvature, rotation, rotation_derivatives, skew, Derivatives, PointFrame};

/// Local element vector (12 entries).
pub type LocalVec = SVector<f64, 12>;
/// Local element matrix (12 × 12).
pub type LocalMat = SMatrix<f64, 12, 12>;

/// The strains of the discrete reference configuration of one element at the three quadrature
/// points of any rule (slots of `mesh::POINT_SLOTS`), D20: `ε̄ = Q(α0_h) ∂s x0_h − e3` and
/// `κ̄ = A(α0_h) ∂s α0_h`. The constitutive laws measure strains from them, so the reference is
/// stress free. Zero for the straight rod along e3 ([`ElementRest::ZERO`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ElementRest {
    /// `ε̄` at each slot [-]
    pub stretch_shear: [Vector3<f64>; 3],
    /// `κ̄` at each slot [1/m]
    pub curvature: [Vector3<f64>; 3],
}

impl ElementRest {
    /// The straight reference along e3: no reference strain.
    pub const ZERO: ElementRest =
        ElementRest { stretch_shear: [Vector3::new(0.0, 0.0, 0.0); 3], curvature: [Vector3::new(0.0, 0.0, 0.0); 3] };

    /// The reference strains of the element whose reference nodal values are `u0` (forward
    /// element layout, chart coordinates) and size `h` [m]: the same interpolation as the
    /// kernels', so that `u0` is exactly stress free.
    pub fn of(u0: &LocalVec, h: f64) -> Self {
        let mut rest = ElementRest::ZERO;
        for (k, xi) in super::mesh::POINT_SLOTS.iter().enumerate() {
            let p = interpolate(u0, h, *xi);
            let f = PointFrame::new(&p.alpha, Derivatives::Without);
            rest.stretch_shear[k] = f.q * p.dx - Vector3::z();
            rest.curvature[k] = f.a * p.dalpha;
        }
        rest
    }
}

/// Layout of an element vector (two nodes of the forward layout).
const LOCAL: DofMap = DofMap::forward(2);
pub(crate) const X: [usize; 2] = [LOCAL.local(0, Field::X, 0), LOCAL.local(1, Field::X, 0)];
pub(crate) const ALPHA: [usize; 2] = [LOCAL.local(0, Field::Alpha, 0), LOCAL.local(1, Field::Alpha, 0)];

/// Fields interpolated at one point of an element.
#[derive(Clone, Copy, Debug)]
pub struct PointState {
    /// shape function values `N_a` at the point
    pub n: [f64; 2],
    /// shape function derivatives `∂s N_a` [1/m]
    pub dn: [f64; 2],
    pub x: Vector3<f64>,
    pub dx: Vector3<f64>,
    pub alpha: Vector3<f64>,
    pub dalpha: Vector3<f64>,
}

/// Interpolate the local unknowns `u` at `ξ ∈ [0, 1]` of an element of size `h` [m].
pub fn interpolate(u: &LocalVec, h: f64, xi: f64) -> PointState {
    let n = [1.0 - xi, xi];
    let dn = [-1.0 / h, 1.0 / h];
    let node = |a: usize, field: Field| {
        let i = LOCAL.local(a, field, 0);
        Vector3::new(u[i], u[i + 1], u[i + 2])
    };
    let (xa, xb, aa, ab) = (node(0, Field::X), node(1, Field::X), node(0, Field::Alpha), node(1, Field::Alpha));
    PointState {
        n,
        dn,
        x: xa * n[0] + xb * n[1],
        dx: xa * dn[0] + xb * dn[1],
        alpha: aa * n[0] + ab * n[1],
        dalpha: aa * dn[0] + ab * dn[1],
    }
}

#[inline]
fn add_vec(r: &mut LocalVec, off: usize, v: &Vector3<f64>) {
    let mut rows = r.fixed_rows_mut::<3>(off);
    rows += v;
}
#[inline]
fn add_mat(t: &mut LocalMat, ro: usize, co: usize, m: &Matrix3<f64>) {
    let mut block = t.fixed_view_mut::<3, 3>(ro, co);
    block += m;
}
fn columns(c: [Vector3<f64>; 3]) -> Matrix3<f64> {
    Matrix3::from_columns(&c)
}

/// Internal force `G(u)` of one element (D3, with the quadrature split of D4) and, if asked,
/// its exact tangent `∂G/∂u`.
#[allow(non_snake_case)] // paper symbols K, J, Q, A, S, C, Bk, H, I
pub fn internal_force(
    props: &RodProperties,
    scheme: QuadratureScheme,
    h: f64,
    u: &LocalVec,
    rest: &ElementRest,
    mut tangent: Option<&mut LocalMat>,
) -> LocalVec {
    let K = Matrix3::from_diagonal(&props.shear_stretch_n);
    let J = Matrix3::from_diagonal(&props.bend_twist_nm2);
    let mut r = LocalVec::zeros();
    let derivatives = Derivatives::for_tangent(&tangent);
    for_each_point(&scheme.stretch_shear(), h, u, |p, wh, slot| {
        let f = PointFrame::new(&p.alpha, derivatives);
        let Q = f.q;
        let e = Q * p.dx - Vector3::z() - rest.stretch_shear[slot];
        let n = Q.transpose() * (K * e);
        let c = p.dx.cross(&n);
        for a in 0..2 {
            add_vec(&mut r, X[a], &(n * (wh * p.dn[a])));
            add_vec(&mut r, ALPHA[a], &(c * (-wh * p.n[a])));
        }
        if let Some(t) = tangent.as_deref_mut() {
            let dQ = f.dq;
            let dn_dx = Q.transpose() * K * Q;
            let ke = K * e;
            let dn_da = columns([0, 1, 2].map(|j| dQ[j].transpose() * ke + Q.transpose() * (K * (dQ[j] * p.dx))));
            let dc_dx = -skew(&n) + skew(&p.dx) * dn_dx;
            let dc_da = skew(&p.dx) * dn_da;
            for a in 0..2 {
                for b in 0..2 {
                    add_mat(t, X[a], X[b], &(dn_dx * (wh * p.dn[a] * p.dn[b])));
                    add_mat(t, X[a], ALPHA[b], &(dn_da * (wh * p.dn[a] * p.n[b])));
                    add_mat(t, ALPHA[a], X[b], &(dc_dx * (-wh * p.n[a] * p.dn[b])));
                    add_mat(t, ALPHA[a], ALPHA[b], &(dc_da * (-wh * p.n[a] * p.n[b])));
                }
            }
        }
    });
    for_each_point(&scheme.bending(), h, u, |p, wh, slot| {
        let f = PointFrame::new(&p.alpha, derivatives);
        let (Q, A) = (f.q, f.a);
        let kappa = A * p.dalpha - rest.curvature[slot];
        let m = Q.transpose() * (J * kappa);
        for a in 0..2 {
            add_vec(&mut r, ALPHA[a], &(m * (wh * p.dn[a])));
        }
        if let Some(t) = tangent.as_deref_mut() {
            let (dQ, dA) = (f.dq, f.da);
            let dm_dda = Q.transpose() * J * A;
            let ja = J * kappa;
            let dm_da = columns([0, 1, 2].map(|j| dQ[j].transpose() * ja + Q.transpose() * (J * (dA[j] * p.dalpha))));
            for a in 0..2 {
                for b in 0..2 {
                    let blk = dm_dda * (wh * p.dn[a] * p.dn[b]) + dm_da * (wh * p.dn[a] * p.n[b]);
                    add_mat(t, ALPHA[a], ALPHA[b], &blk);
                }
            }
        }
    });
    r
}

/// The frozen-coefficient linear operator of the paper's fixed point (§4, D5) on one element:
/// returns `(L, b)` with `L(u_k) û = b(u_k)` (loads excluded from `b`), where `Q_k, A_k, B_k,
/// q3_k` come from the iterate `u_k`. At a fixed point `L u − b = G(u)`.
#[allow(non_snake_case)] // paper symbols K, J, Q, A, S, C, Bk, H, I
pub fn frozen_operator(
    props: &RodProperties,
    scheme: QuadratureScheme,
    h: f64,
    uk: &LocalVec,
    rest: &ElementRest,
) -> (LocalMat, LocalVec) {
    let K = Matrix3::from_diagonal(&props.shear_stretch_n);
    let J = Matrix3::from_diagonal(&props.bend_twist_nm2);
    let k33 = props.shear_stretch_n[2];
    let mut l = LocalMat::zeros();
    let mut b = LocalVec::zeros();
    for_each_point(&scheme.stretch_shear(), h, uk, |p, wh, slot| {
        let Q = rotation(&p.alpha);
        let S = Q.transpose() * K * Q;
        let q3: Vector3<f64> = Q.row(2).transpose();
        let Bk = skew(&p.dx);
        // Qᵀ K (e3 + ε̄) = K33 q3 + Qᵀ K ε̄ (D5, D20): the second term only where ε̄ ≠ 0
        let eps_bar = rest.stretch_shear[slot];
        if eps_bar != Vector3::zeros() {
            let qke = Q.transpose() * (K * eps_bar);
            for a in 0..2 {
                add_vec(&mut b, X[a], &(qke * (wh * p.dn[a])));
                add_vec(&mut b, ALPHA[a], &(Bk * qke * (-wh * p.n[a])));
            }
        }
        for a in 0..2 {
            add_vec(&mut b, X[a], &(q3 * (wh * p.dn[a] * k33)));
            add_vec(&mut b, ALPHA[a], &(Bk * q3 * (-wh * p.n[a] * k33)));
            for c in 0..2 {
                add_mat(&mut l, X[a], X[c], &(S * (wh * p.dn[a] * p.dn[c])));
                add_mat(&mut l, ALPHA[a], X[c], &(Bk * S * (-wh * p.n[a] * p.dn[c])));
            }
        }
    });
    for_each_point(&scheme.bending(), h, uk, |p, wh, slot| {
        let f = PointFrame::new(&p.alpha, Derivatives::Without);
        let (Q, A) = (f.q, f.a);
        let C = Q.transpose() * J * A;
        // the reference curvature on the right-hand side: ∂sδα · Qᵀ J κ̄ (D20)
        let kappa_bar = rest.curvature[slot];
        if kappa_bar != Vector3::zeros() {
            let mk = Q.transpose() * (J * kappa_bar);
            for a in 0..2 {
                add_vec(&mut b, ALPHA[a], &(mk * (wh * p.dn[a])));
            }
        }
        for a in 0..2 {
            for c in 0..2 {
                add_mat(&mut l, ALPHA[a], ALPHA[c], &(C * (wh * p.dn[a] * p.dn[c])));
            }
        }
    });
    (l, b)
}

/// The derivatives of an element's momentum functional `P(u, u̇)` ([`momentum`]) a caller asks
/// for: `∂P/∂u` into `d_u` and `∂P/∂u̇` into `d_udot`, each where a matrix is given (added into
/// it). `Default`: neither.
#[derive(Debug, Default)]
pub struct MomentumDerivatives<'a> {
    pub d_u: Option<&'a mut LocalMat>,
    pub d_udot: Option<&'a mut LocalMat>,
}

/// Momentum functional `P(u, u̇)` of one element (D6, 2-point Gauss; eqs. (7), (27), (40)) and
/// the derivatives `derivatives` asks for.
#[allow(non_snake_case)] // paper symbols K, J, Q, A, S, C, Bk, H, I
pub fn momentum(
    props: &RodProperties,
    scheme: QuadratureScheme,
    h: f64,
    u: &LocalVec,
    udot: &LocalVec,
    derivatives: MomentumDerivatives<'_>,
) -> LocalVec {
    let MomentumDerivatives { mut d_u, mut d_udot } = derivatives;
    let I = Matrix3::from_diagonal(&props.rotary_inertia_kg_m);
    let rho_a = props.mass_per_length_kg_m;
    let mut r = LocalVec::zeros();
    let rule = scheme.loads();
    for (xi, w) in rule.points.iter().zip(rule.weights) {
        let p = interpolate(u, h, *xi);
        let v = interpolate(udot, h, *xi);
        let wh = w * h;
        let f = PointFrame::new(&p.alpha, Derivatives::for_tangent(&d_u));
        let (Q, A) = (f.q, f.a);
        let H = Q.transpose() * I * A;
        let px = v.x * rho_a;
        let pa = H * v.alpha;
        for a in 0..2 {
            add_vec(&mut r, X[a], &(px * (wh * p.n[a])));
            add_vec(&mut r, ALPHA[a], &(pa * (wh * p.n[a])));
        }
        if let Some(t) = d_udot.as_deref_mut() {
            for a in 0..2 {
                for b in 0..2 {
                    let nn = wh * p.n[a] * p.n[b];
                    add_mat(t, X[a], X[b], &(Matrix3::identity() * (rho_a * nn)));
                    add_mat(t, ALPHA[a], ALPHA[b], &(H * nn));
                }
            }
        }
        if let Some(t) = d_u.as_deref_mut() {
            let (dQ, dA) = (f.dq, f.da);
            let ia = I * (A * v.alpha);
            let dp_da = columns([0, 1, 2].map(|j| dQ[j].transpose() * ia + Q.transpose() * (I * (dA[j] * v.alpha))));
            for a in 0..2 {
                for b in 0..2 {
                    add_mat(t, ALPHA[a], ALPHA[b], &(dp_da * (wh * p.n[a] * p.n[b])));
                }
            }
        }
    }
    r
}

/// Distributed loads of one element starting at `s0` [m]: `∫ N_a f`, `∫ N_a l` with the load
/// rule of D4; `field(s, out_f, out_l)` fills the global force [N/m] and torque [N m/m] at `s`.
pub fn distributed_load(
    scheme: QuadratureScheme,
    h: f64,
    s0: f64,
    field: &mut dyn FnMut(f64) -> (Vector3<f64>, Vector3<f64>),
) -> LocalVec {
    let mut r = LocalVec::zeros();
    let rule = scheme.loads();
    for (xi, w) in rule.points.iter().zip(rule.weights) {
        let (f, l) = field(s0 + xi * h);
        let n = [1.0 - xi, *xi];
        for a in 0..2 {
            add_vec(&mut r, X[a], &(f * (w * h * n[a])));
            add_vec(&mut r, ALPHA[a], &(l * (w * h * n[a])));
        }
    }
    r
}

/// Follower (local-frame) distributed loads of one element: `∫ N_a Qᵀ(α) fˡ`, `∫ N_a Qᵀ(α) lˡ`
/// (eq. 4: `vᵍ = Qᵀ vˡ`), load rule of D4, and optionally their derivative with respect to the
/// local unknowns `∂/∂u` added into `tangent`.
#[allow(non_snake_case)] // paper symbols K, J, Q, A, S, C, Bk, H, I
pub fn follower_load(
    scheme: QuadratureScheme,
    h: f64,
    s0: f64,
    u: &LocalVec,
    field: &mut dyn FnMut(f64) -> (Vector3<f64>, Vector3<f64>),
    mut tangent: Option<&mut LocalMat>,
) -> LocalVec {
    let mut r = LocalVec::zeros();
    for_each_point(&scheme.loads(), h, u, |p, wh, _| {
        let xi = p.n[1];
        let (fl, ll) = field(s0 + xi * h);
        let Qt = rotation(&p.alpha).transpose();
        for a in 0..2 {
            add_vec(&mut r, X[a], &(Qt * fl * (wh * p.n[a])));
            add_vec(&mut r, ALPHA[a], &(Qt * ll * (wh * p.n[a])));
        }
        if let Some(t) = tangent.as_deref_mut() {
            let dQ = rotation_derivatives(&p.alpha);
            let df = columns([0, 1, 2].map(|j| dQ[j].transpose() * fl));
            let dl = columns([0, 1, 2].map(|j| dQ[j].transpose() * ll));
            for a in 0..2 {
                for b in 0..2 {
                    add_mat(t, X[a], ALPHA[b], &(df * (wh * p.n[a] * p.n[b])));
                    add_mat(t, ALPHA[a], ALPHA[b], &(dl * (wh * p.n[a] * p.n[b])));
                }
            }
        }
    });
    r
}

/// A dead point load at `ξ` of an element (D23): `N_a(ξ) F` on the positions and `N_a(ξ) M` on
/// the angles of node a (a node with `N_a = 0` gets nothing: a load at a node stays there).
pub fn point_shape(xi: f64, force: &Vector3<f64>, torque: &Vector3<f64>) -> LocalVec {
    let mut r = LocalVec::zeros();
    for (a, n) in [1.0 - xi, xi].into_iter().enumerate() {
        if n != 0.0 {
            add_vec(&mut r, X[a], &(force * n));
            add_vec(&mut r, ALPHA[a], &(torque * n));
        }
    }
    r
}

/// A follower point load at `ξ` of an element (D23, eq. 4): components along d1, d2, d3, so
/// `N_a Qᵀ(α_h(ξ)) F`, `N_a Qᵀ(α_h(ξ)) M`; its derivative with respect to the element's
/// unknowns, `N_a N_b ∂Qᵀ/∂α_k F`, added into `tangent` if given.
#[allow(non_snake_case)] // paper symbol Q
pub fn follower_point_load(
    xi: f64,
    u: &LocalVec,
    force: &Vector3<f64>,
    torque: &Vector3<f64>,
    tangent: Option<&mut LocalMat>,
) -> LocalVec {
    let p = interpolate(u, 1.0, xi);
    let Qt = rotation(&p.alpha).transpose();
    let r = point_shape(xi, &(Qt * force), &(Qt * torque));
    if let Some(t) = tangent {
        let dQ = rotation_derivatives(&p.alpha);
        let df = columns([0, 1, 2].map(|j| dQ[j].transpose() * force));
        let dl = columns([0, 1, 2].map(|j| dQ[j].transpose() * torque));
        for a in 0..2 {
            for b in 0..2 {
                let nn = p.n[a] * p.n[b];
                if nn != 0.0 {
                    add_mat(t, X[a], ALPHA[b], &(df * nn));
                    add_mat(t, ALPHA[a], ALPHA[b], &(dl * nn));
                }
            }
        }
    }
    r
}

/// Curvature `κˡ = A(α_m) ∂sα` [1/m] (eq. 28) at the midpoint of every element of a nodal
/// field of angles `alpha` at the arc lengths `s` [m], with the midpoint arc length [m]:
/// `α_m = (α_e + α_{e+1})/2`, `∂sα = (α_{e+1} − α_e)/(s_{e+1} − s_e)`. The one curvature of
/// every output and error measure of the crate.
pub fn midpoint_curvatures(s: &[f64], alpha: &[Vector3<f64>]) -> Vec<(f64, Vector3<f64>)> {
    (0..s.len().saturating_sub(1))
        .map(|e| {
            let h = s[e + 1] - s[e];
            let mid = (alpha[e] + alpha[e + 1]) * 0.5;
            ((s[e] + s[e + 1]) * 0.5, curvature(&mid, &((alpha[e + 1] - alpha[e]) / h)))
        })
        .collect()
}

/// `f(point, w h, slot)` at every point of `rule` (slot: `mesh::POINT_SLOTS`).
pub(crate) fn for_each_point(rule: &Rule, h: f64, u: &LocalVec, mut f: impl FnMut(&PointState, f64, usize)) {
    for ((xi, w), slot) in rule.points.iter().zip(rule.weights).zip(rule.slots) {
        let p = interpolate(u, h, *xi);
        f(&p, w * h, *slot);
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::model::material::{CrossSection, Material, RodProperties};

    pub(crate) fn props() -> RodProperties {
        let mat = Material {
            young_modulus_pa: 7.1e10,
            shear_modulus_pa: 2.69e10,
            density_kg_m3: 2.73e3,
            shear_correction: 0.833,
        };
        RodProperties::new(&mat, &CrossSection::Rectangle { width_m: 0.06, height_m: 0.04 })
    }

    pub(crate) fn state() -> LocalVec {
        let h = 0.1;
        LocalVec::from_column_slice(&[0.01, -0.02, 0.0, 0.3, -0.5, 0.2, 0.03, 0.01, h * 1.01, 0.45, -0.35, 0.4])
    }

    fn fd_check(f: &dyn Fn(&LocalVec) -> LocalVec, t: &LocalMat, u: &LocalVec) {
        let eps = 1e-7;
        let scale = t.amax();
        for j in 0..12 {
            let mut up = *u;
            up[j] += eps;
            let mut um = *u;
            um[j] -= eps;
            let col = (f(&up) - f(&um)) / (2.0 * eps);
            let err = (col - t.column(j)).amax();
            assert!(err < 1e-6 * scale, "column {j}: fd error {err:e}, scale {scale:e}");
        }
    }

    #[test]
    fn internal_force_tangent_matches_fd() {
        let p = props();
        for scheme in [QuadratureScheme::Selective, QuadratureScheme::Full, QuadratureScheme::Reduced] {
            let u = state();
            let mut t = LocalMat::zeros();
            internal_force(&p, scheme, 0.1, &u, &ElementRest::ZERO, Some(&mut t));
            fd_check(&|v| internal_force(&p, scheme, 0.1, v, &ElementRest::ZERO, None), &t, &u);
        }
    }

    #[test]
    fn momentum_derivatives_match_fd() {
        let p = props();
        let u = state();
        let udot = LocalVec::from_fn(|i, _| 0.1 * (i as f64 + 1.0).sin());
        let mut du = LocalMat::zeros();
        let mut dv = LocalMat::zeros();
        let both = MomentumDerivatives { d_u: Some(&mut du), d_udot: Some(&mut dv) };
        momentum(&p, QuadratureScheme::Selective, 0.1, &u, &udot, both);
        let none = MomentumDerivatives::default;
        fd_check(&|v| momentum(&p, QuadratureScheme::Selective, 0.1, v, &udot, none()), &du, &u);
        fd_check(&|w| momentum(&p, QuadratureScheme::Selective, 0.1, &u, w, none()), &dv, &udot);
    }

    #[test]
    fn follower_load_tangent_matches_fd() {
        let u = state();
        let field = |s: f64| (Vector3::new(0.3 * s, -1.0 - s, 0.2), Vector3::new(0.01, 0.02 * s, -0.03));
        let mut t = LocalMat::zeros();
        follower_load(QuadratureScheme::Selective, 0.1, 0.2, &u, &mut field.clone(), Some(&mut t));
        fd_check(&|v| follower_load(QuadratureScheme::Selective, 0.1, 0.2, v, &mut field.clone(), None), &t, &u);
        // At α = 0 a follower load is the global load.
        let mut z = u;
        for k in [3, 4, 5, 9, 10, 11] {
            z[k] = 0.0;
        }
        let a = follower_load(QuadratureScheme::Selective, 0.1, 0.2, &z, &mut field.clone(), None);
        let b = distributed_load(QuadratureScheme::Selective, 0.1, 0.2, &mut field.clone());
        assert!((a - b).amax() < 1e-15);
    }

    #[test]
    fn follower_point_load_tangent_matches_fd_and_a_node_keeps_its_load() {
        let u = state();
        let (f, m) = (Vector3::new(0.3, -1.0, 0.2), Vector3::new(0.01, 0.02, -0.03));
        for xi in [0.0, 0.37, 1.0] {
            let mut t = LocalMat::zeros();
            follower_point_load(xi, &u, &f, &m, Some(&mut t));
            fd_check(&|v| follower_point_load(xi, v, &f, &m, None), &t, &u);
        }
        // at ξ = 1 everything is on node b, bit for bit the end load of the paper's D3
        let r = point_shape(1.0, &f, &m);
        assert_eq!(r.rows(0, 6).amax(), 0.0);
        assert_eq!(r.fixed_rows::<3>(6).into_owned(), f);
        // the virtual work of a point load is δx(ξ)·F: linear in ξ between the nodes
        let r = point_shape(0.25, &f, &m);
        assert!((r.fixed_rows::<3>(0) - f * 0.75).amax() < 1e-16 && (r.fixed_rows::<3>(9) - m * 0.25).amax() < 1e-16);
    }

    #[test]
    fn frozen_operator_is_consistent_with_the_residual() {
        // L(u) u − b(u) = G(u): the fixed point of §4 solves the discrete equations of D3.
        let p = props();
        for scheme in [QuadratureScheme::Selective, QuadratureScheme::Full] {
            let u = state();
            let (l, b) = frozen_operator(&p, scheme, 0.1, &u, &ElementRest::ZERO);
            let g = internal_force(&p, scheme, 0.1, &u, &ElementRest::ZERO, None);
            assert!((l * u - b - g).amax() < 1e-9 * g.amax());
        }
    }

    /// A reference element of any shape (D20): a curved, twisted, sheared pair of nodes.
    fn rest_element() -> (LocalVec, ElementRest) {
        let h = 0.1;
        let u0 = LocalVec::from_column_slice(&[0.2, -0.1, 0.3, 0.3, -0.4, 0.5, 0.21, -0.07, 0.39, 0.36, -0.45, 0.62]);
        (u0, ElementRest::of(&u0, h))
    }

    #[test]
    fn the_reference_is_stress_free_and_the_kernels_stay_consistent() {
        let p = props();
        let (u0, rest) = rest_element();
        assert!(rest.curvature[0].amax() > 0.1 && rest.stretch_shear[1].amax() > 0.1, "a curved, sheared reference");
        for scheme in [QuadratureScheme::Selective, QuadratureScheme::Full, QuadratureScheme::Reduced] {
            // G(u0) = 0 against the size of one strain's force, K ε̄ / h ~ 1e9
            let g = internal_force(&p, scheme, 0.1, &u0, &rest, None);
            assert!(g.amax() < 1e-15 * p.shear_stretch_n.amax(), "{scheme:?}: {g}");
            // the tangent at another state, and the frozen operator's identity L u − b = G
            let u = state();
            let mut t = LocalMat::zeros();
            internal_force(&p, scheme, 0.1, &u, &rest, Some(&mut t));
            fd_check(&|v| internal_force(&p, scheme, 0.1, v, &rest, None), &t, &u);
            let (l, b) = frozen_operator(&p, scheme, 0.1, &u, &rest);
            let g = internal_force(&p, scheme, 0.1, &u, &rest, None);
            assert!((l * u - b - g).amax() < 1e-9 * g.amax());
        }
    }

    #[test]
    fn rigid_motions_cost_nothing() {
        // Stress-free state: straight along e3 with α = 0, translated → zero internal force.
        let p = props();
        let h = 0.1;
        let u = LocalVec::from_column_slice(&[1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 1.0, 2.0, 3.0 + h, 0.0, 0.0, 0.0]);
        let g = internal_force(&p, QuadratureScheme::Selective, h, &u, &ElementRest::ZERO, None);
        assert!(g.amax() < 1e-6, "{g}");
        // Rigid rotation: x' = d3(α) with constant α → also stress free.
        let a = Vector3::new(0.3, 0.4, -0.2);
        let d3 = crate::model::rotation::d3(&a);
        let mut u = LocalVec::zeros();
        for k in 0..3 {
            u[6 + k] = h * d3[k];
            u[3 + k] = a[k];
            u[9 + k] = a[k];
        }
        let g = internal_force(&p, QuadratureScheme::Full, h, &u, &ElementRest::ZERO, None);
        assert!(g.amax() < 1e-6, "{g}");
    }
}
