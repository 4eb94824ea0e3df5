//! The energy and the momenta of a rod state `(u, u̇)`: what a free flight conserves.
//!
//! ```text
//!   kinetic energy    T = ½ ∫ (ρA |ẋ|² + ωᵀ I ω) ds,          ω = A(α) α̇          eqs. (7), (8), (27)
//!   elastic energy    V = ½ ∫ (εᵀ K ε + κᵀ J κ) ds,           ε = Q ∂s x − e3 − ε̄, κ = A ∂s α − κ̄
//!                                                                                    eqs. (12), (16), (28), D20
//!   linear momentum   p = ∫ ρA ẋ ds
//!   angular momentum  h = ∫ (x × ρA ẋ + Qᵀ I ω) ds             (about the origin)
//! ```
//!
//! Each integral with the rule of the term it is the energy or the momentum of (D4): the kinetic
//! terms and the momenta with the inertia rule of the momentum functional `P` (so that
//! `p = Σ_i P_x,i`, the sum of its position rows), the strain energies with the stretch–shear and
//! the bending rules of `G`. A state and its rate in the same chart: the vectors come out in that
//! chart's coordinates.
use nalgebra::{Matrix3, Vector3};

use super::element::{for_each_point, interpolate, ElementRest, LocalVec};
use super::material::RodProperties;
use super::mesh::QuadratureScheme;
use super::rotation::{Derivatives, PointFrame};

/// Energy [J] and momenta of a rod, or of one of its elements.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Balance {
    /// `T` [J]
    pub kinetic_j: f64,
    /// `V` [J]
    pub elastic_j: f64,
    /// `p` [N s]
    pub momentum_n_s: Vector3<f64>,
    /// `h` about the origin [N m s]
    pub angular_momentum_n_m_s: Vector3<f64>,
}

impl Balance {
    /// `T + V` [J]
    pub fn energy_j(&self) -> f64 {
        self.kinetic_j + self.elastic_j
    }

    /// The momenta in the coordinates `R v` (a rotation `R`: the chart's base back to space);
    /// the energies are invariant.
    pub fn rotated(&self, r: &Matrix3<f64>) -> Balance {
        Balance {
            momentum_n_s: r * self.momentum_n_s,
            angular_momentum_n_m_s: r * self.angular_momentum_n_m_s,
            ..*self
        }
    }
}

impl std::ops::AddAssign for Balance {
    fn add_assign(&mut self, b: Balance) {
        self.kinetic_j += b.kinetic_j;
        self.elastic_j += b.elastic_j;
        self.momentum_n_s += b.momentum_n_s;
        self.angular_momentum_n_m_s += b.angular_momentum_n_m_s;
    }
}

/// The balance of one element of size `h` [m] with local unknowns `u`, rates `udot` and
/// reference strains `rest`.
#[allow(non_snake_case)] // paper symbols K, J, I, Q, A
pub fn element_balance(
    props: &RodProperties,
    scheme: QuadratureScheme,
    h: f64,
    (u, udot): (&LocalVec, &LocalVec),
    rest: &ElementRest,
) -> Balance {
    let K = Matrix3::from_diagonal(&props.shear_stretch_n);
    let J = Matrix3::from_diagonal(&props.bend_twist_nm2);
    let I = Matrix3::from_diagonal(&props.rotary_inertia_kg_m);
    let rho_a = props.mass_per_length_kg_m;
    let mut b = Balance::default();
    let rule = scheme.loads();
    for (xi, w) in rule.points.iter().zip(rule.weights) {
        let (p, v) = (interpolate(u, h, *xi), interpolate(udot, h, *xi));
        let f = PointFrame::new(&p.alpha, Derivatives::Without);
        let omega = f.a * v.alpha;
        let spin = I * omega;
        let wh = w * h;
        b.kinetic_j += 0.5 * wh * (rho_a * v.x.norm_squared() + omega.dot(&spin));
        b.momentum_n_s += v.x * (rho_a * wh);
        b.angular_momentum_n_m_s += (p.x.cross(&v.x) * rho_a + f.q.transpose() * spin) * wh;
    }
    for_each_point(&scheme.stretch_shear(), h, u, |p, wh, slot| {
        let f = PointFrame::new(&p.alpha, Derivatives::Without);
        let e = f.q * p.dx - Vector3::z() - rest.stretch_shear[slot];
        b.elastic_j += 0.5 * wh * e.dot(&(K * e));
    });
    for_each_point(&scheme.bending(), h, u, |p, wh, slot| {
        let f = PointFrame::new(&p.alpha, Derivatives::Without);
        let kappa = f.a * p.dalpha - rest.curvature[slot];
        b.elastic_j += 0.5 * wh * kappa.dot(&(J * kappa));
    });
    b
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::element::tests::{props, state};
    use crate::model::element::{momentum, MomentumDerivatives, X};

    /// The linear momentum is the sum of the momentum functional's position rows (the same
    /// rule): `P` is `δx · ρA ẋ + δα · Qᵀ I A α̇` and `Σ_a N_a = 1`.
    #[test]
    fn linear_momentum_is_the_row_sum_of_the_momentum_functional() {
        let (p, h) = (props(), 0.1);
        let u = state();
        let udot = LocalVec::from_fn(|i, _| 0.3 * (i as f64 + 1.0).sin());
        let pv = momentum(&p, QuadratureScheme::Selective, h, &u, &udot, MomentumDerivatives::default());
        let b = element_balance(&p, QuadratureScheme::Selective, h, (&u, &udot), &ElementRest::ZERO);
        let rows = |off: usize| Vector3::new(pv[off], pv[off + 1], pv[off + 2]);
        let sum_x = rows(X[0]) + rows(X[1]);
        assert!((b.momentum_n_s - sum_x).norm() <= 1e-14 * sum_x.norm());
    }

    /// A rigid motion has no strain energy; a rigid translation with velocity `c` carries
    /// `p = m c`, `T = ½ m |c|²` and `h = ∫ x ds × ρA c`.
    #[test]
    fn rigid_translation_is_exact() {
        let (p, h) = (props(), 0.1);
        let mut u = LocalVec::zeros();
        u[8] = h; // node b at (0, 0, h): straight along e3, unstrained
        let c = Vector3::new(0.2, -0.1, 0.05);
        let mut udot = LocalVec::zeros();
        for a in X {
            udot.fixed_rows_mut::<3>(a).copy_from(&c);
        }
        let b = element_balance(&p, QuadratureScheme::Selective, h, (&u, &udot), &ElementRest::ZERO);
        let m = p.mass_per_length_kg_m * h;
        assert_eq!(b.elastic_j, 0.0);
        assert!((b.kinetic_j - 0.5 * m * c.norm_squared()).abs() <= 1e-14 * b.kinetic_j);
        assert!((b.momentum_n_s - c * m).norm() <= 1e-14 * m * c.norm());
        let centre = Vector3::new(0.0, 0.0, h / 2.0);
        assert!((b.angular_momentum_n_m_s - centre.cross(&c) * m).norm() <= 1e-14 * m * c.norm() * h);
    }

    /// A spin about the straight rod's axis at rate `w` carries `T = ½ I3 w² h` and
    /// `h = I3 w h e3`: at α = 0, `A = [[0, −1, 0], [0, 0, −1], [−1, 0, 0]]` (eq. 27), so the
    /// rates are `α̇ = −w`, `β̇ = γ̇ = 0`.
    #[test]
    fn spin_about_the_axis_is_exact() {
        let (p, h) = (props(), 0.1);
        let mut u = LocalVec::zeros();
        u[8] = h;
        let w = 3.0;
        let mut udot = LocalVec::zeros();
        udot[3] = -w;
        udot[9] = -w;
        let b = element_balance(&p, QuadratureScheme::Full, h, (&u, &udot), &ElementRest::ZERO);
        let i3 = p.rotary_inertia_kg_m[2];
        assert!((b.kinetic_j - 0.5 * i3 * w * w * h).abs() <= 1e-14 * b.kinetic_j);
        assert!((b.angular_momentum_n_m_s - Vector3::z() * (i3 * w * h)).norm() <= 1e-14 * i3 * w * h);
    }
}
