//! The stress resultants of an element, the internal force `n` [N] and moment `m` [N m] as the
//! discrete equations of `model::element` balance them (eqs. 13, 15, 28).
use nalgebra::{Matrix3, Vector3};

use super::element::{for_each_point, ElementRest, LocalVec, ALPHA, X};
use super::material::RodProperties;
use super::mesh::QuadratureScheme;
use super::rotation::{rotation, Derivatives, PointFrame};

/// The stress resultants of one element: the internal force `n` [N] and moment `m` [N m], as
/// the element's discrete equations see them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Resultants {
    /// internal force `n = Qᵀ K (Q ∂s x − e3)` [N], global components (eq. 13)
    pub n: Vector3<f64>,
    /// internal moment `m = Qᵀ J A ∂s α` [N m], global components (eqs. 15, 28)
    pub m: Vector3<f64>,
    /// `nˡ = Q n = K (Q ∂s x − e3)` [N]: shear forces on d1, d2 and the tension along d3
    pub n_local: Vector3<f64>,
    /// `mˡ = Q m = J A ∂s α = J κ` [N m]: bending moments about d1, d2 and the twisting moment
    pub m_local: Vector3<f64>,
}

/// The stress resultants of one element (local unknowns `u`, size `h` [m]), each the mean over
/// the element of its integrand's rule (D4): `n̄ = Σ_q w_q n(ξ_q)` with the stretch–shear rule,
/// `m̄ = Σ_q w_q m(ξ_q)` with the bending rule (weights summing to 1). These are the values the
/// discrete equations balance: with P1 test functions, `∫ ∂sδx · n = ±n̄` on each element, so
/// the force rows of D3 read `n̄_e − n̄_{e−1} + ∫ N_a f = 0` (∂s n + f = 0) and the moment rows
/// `m̄_e − m̄_{e−1} + ∫ N_a (∂s x × n) + ∫ N_a l = 0` (∂s m + ∂s x × n + l = 0), exactly.
#[allow(non_snake_case)] // paper symbols K, J, Q, A
pub fn resultants(
    props: &RodProperties,
    scheme: QuadratureScheme,
    h: f64,
    u: &LocalVec,
    rest: &ElementRest,
) -> Resultants {
    let K = Matrix3::from_diagonal(&props.shear_stretch_n);
    let J = Matrix3::from_diagonal(&props.bend_twist_nm2);
    let mut r = Resultants::default();
    for_each_point(&scheme.stretch_shear(), h, u, |p, wh, slot| {
        let Q = rotation(&p.alpha);
        // strains from the reference (D20): n = Qᵀ K (Q ∂s x − e3 − ε̄)
        let nl = K * (Q * p.dx - Vector3::z() - rest.stretch_shear[slot]);
        r.n_local += nl * (wh / h);
        r.n += Q.transpose() * nl * (wh / h);
    });
    for_each_point(&scheme.bending(), h, u, |p, wh, slot| {
        let f = PointFrame::new(&p.alpha, Derivatives::Without);
        let ml = J * (f.a * p.dalpha - rest.curvature[slot]);
        r.m_local += ml * (wh / h);
        r.m += f.q.transpose() * ml * (wh / h);
    });
    r
}

/// [`resultants`] of every element of a nodal state: positions `x` [m] and angles `alpha`
/// [rad] in the state's chart at the arc lengths `s` [m], with the reference strains of a rod
/// that has a reference of its own (D20; `None`: the paper's straight rod).
pub fn element_resultants(
    props: &RodProperties,
    scheme: QuadratureScheme,
    (s, x, alpha): (&[f64], &[Vector3<f64>], &[Vector3<f64>]),
    rest: Option<&[ElementRest]>,
) -> Vec<Resultants> {
    (0..s.len().saturating_sub(1))
        .map(|e| {
            let mut u = LocalVec::zeros();
            for a in 0..2 {
                u.fixed_rows_mut::<3>(X[a]).copy_from(&x[e + a]);
                u.fixed_rows_mut::<3>(ALPHA[a]).copy_from(&alpha[e + a]);
            }
            resultants(props, scheme, s[e + 1] - s[e], &u, rest.map_or(&ElementRest::ZERO, |r| &r[e]))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::element::internal_force;
    use crate::model::element::tests::{props, state};

    /// The resultants are what the residual balances (D3): on one element the force rows are
    /// `∓n̄` and, with a one-point stretch–shear rule (∂s x and n constant on the element), the
    /// moment rows `∓m̄ − (h/2) ∂s x × n̄`. Two kernels written apart, checked on a bent, twisted,
    /// stretched state.
    #[test]
    fn resultants_are_what_the_residual_balances() {
        let p = props();
        let (h, u) = (0.1, state());
        for scheme in [QuadratureScheme::Selective, QuadratureScheme::Full, QuadratureScheme::Reduced] {
            let g = internal_force(&p, scheme, h, &u, &ElementRest::ZERO, None);
            let r = resultants(&p, scheme, h, &u, &ElementRest::ZERO);
            let v = |i: usize| Vector3::new(g[i], g[i + 1], g[i + 2]);
            let scale = r.n.amax();
            assert!((v(X[1]) - r.n).amax() < 1e-12 * scale && (v(X[0]) + r.n).amax() < 1e-12 * scale, "{scheme:?}");
            // local components are the global ones seen from the frame at the same points
            assert!((r.n_local.norm() - r.n.norm()).abs() < 1e-12 * scale || scheme == QuadratureScheme::Full);
            if scheme != QuadratureScheme::Full {
                let dx = Vector3::new(u[6] - u[0], u[7] - u[1], u[8] - u[2]) / h;
                let b = dx.cross(&r.n) * (h / 2.0);
                let ms = r.m.amax();
                assert!((v(ALPHA[1]) + b - r.m).amax() < 1e-12 * ms.max(b.amax()), "{scheme:?}");
                assert!((v(ALPHA[0]) + b + r.m).amax() < 1e-12 * ms.max(b.amax()), "{scheme:?}");
            }
        }
    }
}
