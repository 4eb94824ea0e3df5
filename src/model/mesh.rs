//! Uniform P1 mesh of the reference arc length `s ∈ [0, L]`, the layout of the unknowns
//! ([`DofMap`], the only place that knows it) and the quadrature rules of `docs/decisions.md`
//! (D4).
use nalgebra::{DVector, SVector, Vector3};

use crate::linalg::Pattern;

/// A point within this fraction of an element from a node is at the node (`Mesh::locate`).
pub const NODE_SNAP: f64 = 1e-12;

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
    /// The element holding the arc length `s` [m] and the point's coordinate `ξ ∈ [0, 1]` in it,
    /// snapped to a node within 1e-12 (D23); `s` is clamped to `[0, L]`.
    pub fn locate(&self, s: f64) -> (usize, f64) {
        let at = (s / self.h()).clamp(0.0, self.elements as f64);
        let e = (at.floor() as usize).min(self.elements - 1);
        let xi = at - e as f64;
        let xi = if xi.abs() < NODE_SNAP {
            0.0
        } else if (xi - 1.0).abs() < NODE_SNAP {
            1.0
        } else {
            xi
        };
        (e, xi)
    }
    /// Layout of the forward unknowns `(x, α)` on this mesh.
    pub fn dofs(&self) -> DofMap {
        DofMap::forward(self.nodes())
    }
    /// Layout of the unknowns `(x, α, x̂, α̂)` of the inverse problem's KKT system on this mesh.
    pub fn kkt_dofs(&self) -> DofMap {
        DofMap::kkt(self.nodes())
    }
}

/// The 3-vector fields held at a node: position `x` [m], angles `α = (α, β, γ)` [rad] and, in
/// the inverse problem, their adjoints `x̂`, `α̂` (`docs/inverse.md`, I1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Field {
    X = 0,
    Alpha = 1,
    XHat = 2,
    AlphaHat = 3,
}

/// Layout of a nodal vector: node-major, `fields` 3-vectors per node (`[x, α]` for the forward
/// problem, `[x, α, x̂, α̂]` for the KKT system of the inverse problem). Element `e` owns the
/// contiguous unknowns of its nodes `e`, `e + 1`, so gathering is a slice copy and an element
/// vector is `[node e fields…, node e + 1 fields…]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DofMap {
    nodes: usize,
    fields: usize,
}

impl DofMap {
    /// `[x, α]` per node.
    pub const fn forward(nodes: usize) -> Self {
        DofMap { nodes, fields: 2 }
    }
    /// `[x, α, x̂, α̂]` per node.
    pub const fn kkt(nodes: usize) -> Self {
        DofMap { nodes, fields: 4 }
    }
    /// Unknowns per node.
    pub const fn block(&self) -> usize {
        3 * self.fields
    }
    pub const fn nodes(&self) -> usize {
        self.nodes
    }
    /// Total number of unknowns.
    pub const fn len(&self) -> usize {
        self.block() * self.nodes
    }
    pub const fn is_empty(&self) -> bool {
        self.nodes == 0
    }
    /// Global index of component `k` of `field` at `node`.
    pub const fn index(&self, node: usize, field: Field, k: usize) -> usize {
        self.block() * node + 3 * field as usize + k
    }
    /// Index of component `k` of `field` of the element's node `a` (0 or 1) in an element vector.
    pub const fn local(&self, a: usize, field: Field, k: usize) -> usize {
        self.block() * a + 3 * field as usize + k
    }
    /// The field of global (or element-local) index `i`.
    pub fn field_of(&self, i: usize) -> Field {
        match (i % self.block()) / 3 {
            0 => Field::X,
            1 => Field::Alpha,
            2 => Field::XHat,
            _ => Field::AlphaHat,
        }
    }
    /// A zero vector of this layout.
    pub fn zeros(&self) -> DVector<f64> {
        DVector::zeros(self.len())
    }
    /// The sparsity pattern of a system matrix on this layout.
    pub fn pattern(&self) -> Pattern {
        Pattern::block_tridiagonal(self.nodes, self.block())
    }
    /// `field` at `node` of a nodal vector.
    pub fn get(&self, u: &DVector<f64>, node: usize, field: Field) -> Vector3<f64> {
        let i = self.index(node, field, 0);
        Vector3::new(u[i], u[i + 1], u[i + 2])
    }
    /// Set `field` at `node`.
    pub fn set(&self, u: &mut DVector<f64>, node: usize, field: Field, v: &Vector3<f64>) {
        let i = self.index(node, field, 0);
        for k in 0..3 {
            u[i + k] = v[k];
        }
    }
    /// `field` at every node.
    pub fn field(&self, u: &DVector<f64>, field: Field) -> Vec<Vector3<f64>> {
        (0..self.nodes).map(|i| self.get(u, i, field)).collect()
    }
    /// The element vector of element `e` (`N` = two blocks).
    #[inline]
    pub fn gather<const N: usize>(&self, u: &DVector<f64>, e: usize) -> SVector<f64, N> {
        debug_assert_eq!(N, 2 * self.block(), "element vector size");
        let start = self.block() * e;
        SVector::<f64, N>::from_column_slice(&u.as_slice()[start..start + N])
    }
    /// Add an element vector of element `e` into a global vector.
    #[inline]
    pub fn add_element<const N: usize>(&self, r: &mut DVector<f64>, e: usize, local: &SVector<f64, N>) {
        debug_assert_eq!(N, 2 * self.block(), "element vector size");
        let start = self.block() * e;
        for i in 0..N {
            r[start + i] += local[i];
        }
    }
    /// `(‖x‖₂, ‖α‖₂)` of a forward nodal vector: the position and the angle components.
    pub fn split_norms_2(&self, u: &DVector<f64>) -> (f64, f64) {
        let mut nx = 0.0;
        let mut na = 0.0;
        for (i, v) in u.iter().enumerate() {
            if self.field_of(i) == Field::X {
                nx += v * v;
            } else {
                na += v * v;
            }
        }
        (f64::sqrt(nx), f64::sqrt(na))
    }
    /// `(‖x‖∞, ‖α‖∞)` of a forward nodal vector.
    pub fn split_norms_inf(&self, u: &DVector<f64>) -> (f64, f64) {
        let mut nx: f64 = 0.0;
        let mut na: f64 = 0.0;
        for (i, v) in u.iter().enumerate() {
            if self.field_of(i) == Field::X {
                nx = nx.max(v.abs());
            } else {
                na = na.max(v.abs());
            }
        }
        (nx, na)
    }
    /// The KKT vector of a state `u` and an adjoint `adjoint` (forward layout each).
    pub fn kkt_join(&self, u: &DVector<f64>, adjoint: &DVector<f64>) -> DVector<f64> {
        debug_assert_eq!(self.fields, 4, "a KKT layout");
        let fwd = DofMap::forward(self.nodes);
        let half = 3 * Field::XHat as usize;
        DVector::from_fn(self.len(), |i, _| {
            let (node, c) = (i / self.block(), i % self.block());
            if c < half {
                u[fwd.block() * node + c]
            } else {
                adjoint[fwd.block() * node + c - half]
            }
        })
    }
    /// The state `(x, α)` of a KKT vector, in the forward layout.
    pub fn kkt_state(&self, big: &DVector<f64>) -> DVector<f64> {
        self.kkt_part(big, 0)
    }
    /// The adjoint `(x̂, α̂)` of a KKT vector, in the forward layout.
    pub fn kkt_adjoint(&self, big: &DVector<f64>) -> DVector<f64> {
        self.kkt_part(big, 3 * Field::XHat as usize)
    }
    fn kkt_part(&self, big: &DVector<f64>, offset: usize) -> DVector<f64> {
        debug_assert_eq!(self.fields, 4, "a KKT layout");
        let fwd = DofMap::forward(self.nodes);
        DVector::from_fn(fwd.len(), |i, _| big[self.block() * (i / fwd.block()) + offset + i % fwd.block()])
    }
}

/// Which element integrals are under-integrated (D4), and the rules of the inverse problem's
/// terms (`docs/inverse.md`, I2, I11, I12).
///
/// The first three are ours: they choose a rule per integrand. The last two are the paper's
/// scheme as printed read with ONE rule for every integral of (52) and (61), the λd and Λκ terms,
/// the control costs, the tracking term and the loads included (`docs/decisions.md`, D4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QuadratureScheme {
    /// Stretch–shear 1-point, bending 2-point (default, locking-free and full rank in α).
    Selective,
    /// Everything 2-point Gauss (shear-locks).
    Full,
    /// Stretch–shear and bending 1-point (locking-free; zero-energy α zig-zag in the inverse).
    Reduced,
    /// The midpoint rule for every integral (static and inverse problems only: the P1 mass
    /// matrix of the midpoint rule is singular).
    Midpoint,
    /// 2-point Gauss for every integral.
    Gauss2,
}

impl QuadratureScheme {
    /// One rule for every integral (the λd blend of I11 does not apply)?
    pub fn is_one_rule(&self) -> bool {
        matches!(self, QuadratureScheme::Midpoint | QuadratureScheme::Gauss2)
    }
    /// The name in case files (`solver.quadrature`).
    pub fn name(&self) -> &'static str {
        match self {
            QuadratureScheme::Selective => "selective",
            QuadratureScheme::Full => "full",
            QuadratureScheme::Reduced => "reduced",
            QuadratureScheme::Midpoint => "midpoint",
            QuadratureScheme::Gauss2 => "gauss2",
        }
    }
}

/// A Gauss rule on the unit interval: points ξ ∈ (0,1) and weights summing to 1, and the slot of
/// each point among the three points any rule uses (`ξ = G2A, ½, G2B` → slots 0, 1, 2), where
/// per-point data of an element (the reference strains of D20, `element::ElementRest`) is kept.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rule {
    pub points: &'static [f64],
    pub weights: &'static [f64],
    pub slots: &'static [usize],
}

/// The points of every rule on the unit interval, by slot (FreeFEM's `coefficients.idp` keeps its
/// fields at the same three points).
pub const POINT_SLOTS: [f64; 3] = [G2A, 0.5, G2B];

impl Rule {
    /// `(ξ, w)` of every point.
    pub fn iter(&self) -> impl Iterator<Item = (f64, f64)> + Clone + '_ {
        self.points.iter().copied().zip(self.weights.iter().copied())
    }
}

const G2A: f64 = 0.211_324_865_405_187_1; // (1 − 1/√3)/2
const G2B: f64 = 0.788_675_134_594_812_9; // (1 + 1/√3)/2

/// 1-point Gauss (midpoint), FreeFEM `qf1pE`.
pub const GAUSS1: Rule = Rule { points: &[0.5], weights: &[1.0], slots: &[1] };
/// 2-point Gauss, FreeFEM `qf2pE`.
pub const GAUSS2: Rule = Rule { points: &[G2A, G2B], weights: &[0.5, 0.5], slots: &[0, 2] };

impl QuadratureScheme {
    /// Rule for the stretch–shear integrand `∂sδx·n − δα·(∂s x × n)`.
    pub fn stretch_shear(&self) -> Rule {
        match self {
            QuadratureScheme::Full | QuadratureScheme::Gauss2 => GAUSS2,
            QuadratureScheme::Selective | QuadratureScheme::Reduced | QuadratureScheme::Midpoint => GAUSS1,
        }
    }
    /// Rule for the bending integrand `∂sδα·m`.
    pub fn bending(&self) -> Rule {
        match self {
            QuadratureScheme::Reduced | QuadratureScheme::Midpoint => GAUSS1,
            QuadratureScheme::Selective | QuadratureScheme::Full | QuadratureScheme::Gauss2 => GAUSS2,
        }
    }
    /// Rule for loads and inertia: 2-point (a midpoint mass matrix is singular for P1), except
    /// in the one-rule midpoint scheme (which refuses dynamic cases).
    pub fn loads(&self) -> Rule {
        match self {
            QuadratureScheme::Midpoint => GAUSS1,
            _ => GAUSS2,
        }
    }
    /// Rule of the inverse problem's mass-type terms (I2): the tracking term λg, the control costs
    /// λf, λl and the Λω term; the loads' rule.
    pub fn objective(&self) -> Rule {
        self.loads()
    }
    /// Rule of the Λκ term `½ ∫ κᵀ Λκ κ` (I12): the midpoint in our schemes, the one rule in the
    /// one-rule schemes.
    pub fn kappa(&self) -> Rule {
        match self {
            QuadratureScheme::Gauss2 => GAUSS2,
            _ => GAUSS1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_rules_integrate_polynomials() {
        // 1-point exact for degree 1, 2-point for degree 3 on (0,1).
        let integ = |r: &Rule, f: &dyn Fn(f64) -> f64| r.iter().map(|(p, w)| w * f(p)).sum::<f64>();
        assert!((integ(&GAUSS1, &|x| 3.0 * x + 1.0) - 2.5).abs() < 1e-15);
        assert!((integ(&GAUSS2, &|x| x * x * x) - 0.25).abs() < 1e-15);
        assert!((integ(&GAUSS2, &|x| x * x) - 1.0 / 3.0).abs() < 1e-15);
        assert!((G2A - (1.0 - 1.0 / 3f64.sqrt()) / 2.0).abs() < 1e-16);
    }

    #[test]
    fn dof_layout() {
        let m = Mesh::new(2.0, 4);
        assert_eq!(m.nodes(), 5);
        let d = m.dofs();
        assert_eq!(d.len(), 30);
        assert_eq!(d.index(2, Field::Alpha, 1), 16);
        assert_eq!(d.local(1, Field::X, 2), 8);
        assert_eq!(m.node_s(4), 2.0);
        let k = m.kkt_dofs();
        assert_eq!((k.len(), k.index(1, Field::AlphaHat, 0), k.local(1, Field::XHat, 0)), (60, 21, 18));
        assert_eq!(k.field_of(21), Field::AlphaHat);
        // a KKT vector splits into the forward layout of its state and its adjoint
        let big = DVector::from_fn(k.len(), |i, _| i as f64);
        let (u, a) = (k.kkt_state(&big), k.kkt_adjoint(&big));
        assert_eq!(
            (d.get(&u, 1, Field::Alpha), d.get(&a, 1, Field::X)),
            (k.get(&big, 1, Field::Alpha), k.get(&big, 1, Field::XHat))
        );
    }
}
