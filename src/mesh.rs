//! Uniform P1 mesh of the reference arc length `s ∈ [0, L]`, degree-of-freedom numbering and
//! the quadrature rules of `docs/decisions.md` (D4).

/// The six unknowns at a node: position `x = (x, y, z)` [m] and angles `α = (α, β, γ)` [rad].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dof {
    X = 0,
    Y = 1,
    Z = 2,
    Alpha = 3,
    Beta = 4,
    Gamma = 5,
}

/// Unknowns per node.
pub const DOFS_PER_NODE: usize = 6;
/// Unknowns per two-node element.
pub const DOFS_PER_ELEMENT: usize = 2 * DOFS_PER_NODE;

/// A uniform mesh of `elements` segments on `[0, length_m]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mesh {
    /// Reference length L [m]
    pub length_m: f64,
    /// Number of elements
    pub elements: usize,
}

impl Mesh {
    pub fn new(length_m: f64, elements: usize) -> Self {
        Mesh { length_m, elements }
    }
    pub fn nodes(&self) -> usize {
        self.elements + 1
    }
    /// Element size h [m].
    pub fn h(&self) -> f64 {
        self.length_m / self.elements as f64
    }
    /// Reference arc length of node `i` [m].
    pub fn node_s(&self, i: usize) -> f64 {
        self.length_m * i as f64 / self.elements as f64
    }
    /// Global index of unknown `c` at node `i`. The only place that knows the layout.
    pub fn dof(&self, node: usize, c: Dof) -> usize {
        DOFS_PER_NODE * node + c as usize
    }
    /// Total number of unknowns.
    pub fn ndofs(&self) -> usize {
        DOFS_PER_NODE * self.nodes()
    }
}

/// Which element integrals are under-integrated (D4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QuadratureScheme {
    /// Stretch–shear 1-point, bending 2-point (default, locking-free and full rank in α).
    Selective,
    /// Everything 2-point Gauss (shear-locks).
    Full,
    /// Stretch–shear and bending 1-point (locking-free; zero-energy α zig-zag in the inverse).
    Reduced,
}

/// A Gauss rule on the unit interval: points ξ ∈ (0,1) and weights summing to 1.
#[derive(Clone, Copy, Debug)]
pub struct Rule {
    pub points: &'static [f64],
    pub weights: &'static [f64],
}

const G2A: f64 = 0.211_324_865_405_187_1; // (1 − 1/√3)/2
const G2B: f64 = 0.788_675_134_594_812_9; // (1 + 1/√3)/2

/// 1-point Gauss (midpoint), FreeFEM `qf1pE`.
pub const GAUSS1: Rule = Rule { points: &[0.5], weights: &[1.0] };
/// 2-point Gauss, FreeFEM `qf2pE`.
pub const GAUSS2: Rule = Rule { points: &[G2A, G2B], weights: &[0.5, 0.5] };

impl QuadratureScheme {
    /// Rule for the stretch–shear integrand `∂sδx·n − δα·(∂s x × n)`.
    pub fn stretch_shear(&self) -> Rule {
        match self {
            QuadratureScheme::Full => GAUSS2,
            QuadratureScheme::Selective | QuadratureScheme::Reduced => GAUSS1,
        }
    }
    /// Rule for the bending integrand `∂sδα·m`.
    pub fn bending(&self) -> Rule {
        match self {
            QuadratureScheme::Reduced => GAUSS1,
            QuadratureScheme::Selective | QuadratureScheme::Full => GAUSS2,
        }
    }
    /// Rule for loads and inertia (always 2-point: a midpoint mass matrix is singular for P1).
    pub fn loads(&self) -> Rule {
        GAUSS2
    }
    /// FreeFEM name of a rule.
    pub fn freefem_name(rule: &Rule) -> &'static str {
        if rule.points.len() == 1 {
            "qf1pE"
        } else {
            "qf2pE"
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_rules_integrate_polynomials() {
        // 1-point exact for degree 1, 2-point for degree 3 on (0,1).
        let integ =
            |r: &Rule, f: &dyn Fn(f64) -> f64| r.points.iter().zip(r.weights).map(|(p, w)| w * f(*p)).sum::<f64>();
        assert!((integ(&GAUSS1, &|x| 3.0 * x + 1.0) - 2.5).abs() < 1e-15);
        assert!((integ(&GAUSS2, &|x| x * x * x) - 0.25).abs() < 1e-15);
        assert!((integ(&GAUSS2, &|x| x * x) - 1.0 / 3.0).abs() < 1e-15);
        assert!((G2A - (1.0 - 1.0 / 3f64.sqrt()) / 2.0).abs() < 1e-16);
    }

    #[test]
    fn dof_layout() {
        let m = Mesh::new(2.0, 4);
        assert_eq!(m.nodes(), 5);
        assert_eq!(m.ndofs(), 30);
        assert_eq!(m.dof(2, Dof::Beta), 16);
        assert_eq!(m.node_s(4), 2.0);
    }
}
