//! Gather → kernel → scatter, written once and used by every solver: the static fixed point and
//! Newton, the time stepping, the modal analysis, the inverse KKT system and its Newton
//! residual and Jacobian (the last two with 12 unknowns per node). Scalar functionals of a
//! state (the objective (41), fit measures) go through [`integrate`].
//!
//! The element vectors and matrices come from kernels (`model::element`,
//! `solve::inverse::kkt`); the layout of the unknowns from [`DofMap`]; the matrix structure,
//! built once per mesh, from [`Pattern`]. Every iterate only refills the values.
use nalgebra::{DVector, SMatrix, SVector};

use crate::linalg::Pattern;
use crate::model::mesh::{DofMap, Mesh};

/// The system matrix an assembly pass adds into: `values` in the structure of `pattern`, each
/// element matrix multiplied by `scale` first.
pub struct Tangent<'a> {
    pub pattern: &'a Pattern,
    pub values: &'a mut [f64],
    pub scale: f64,
    /// the pass writes every entry's first contribution instead of adding it
    /// ([`Pattern::scatter_first`]): `values` needs no zeroing before it
    pub overwrite: bool,
}

impl<'a> Tangent<'a> {
    pub fn new(pattern: &'a Pattern, values: &'a mut [f64], scale: f64) -> Self {
        Tangent { pattern, values, scale, overwrite: false }
    }

    /// The same target for another pass (which adds into the values the first pass left).
    pub fn reborrow(&mut self) -> Tangent<'_> {
        Tangent { pattern: self.pattern, values: &mut *self.values, scale: self.scale, overwrite: self.overwrite }
    }

    /// A pass that replaces the values (the same numbers as zeroing them and adding,
    /// [`Pattern::scatter_first`]), without a sweep that zeroes them first.
    pub fn overwriting(pattern: &'a Pattern, values: &'a mut [f64], scale: f64) -> Self {
        Tangent { pattern, values, scale, overwrite: true }
    }
}

/// The one element loop. For every element `e`, in order, `kernel(e, t)` returns the element
/// vector, which is added into `rhs`; when a `tangent` is given, the kernel also fills the
/// element matrix `t` (zeroed before the call), which is added as `scale · t` into the
/// tangent's values. `N` is twice the block size of `dofs` (12 forward, 24 inverse).
pub fn assemble<const N: usize>(
    dofs: &DofMap,
    rhs: &mut DVector<f64>,
    mut tangent: Option<Tangent<'_>>,
    mut kernel: impl FnMut(usize, Option<&mut SMatrix<f64, N, N>>) -> SVector<f64, N>,
) {
    let mut local = SMatrix::<f64, N, N>::zeros();
    for e in 0..dofs.nodes().saturating_sub(1) {
        let r = match tangent.as_mut() {
            Some(t) => {
                local.as_mut_slice().fill(0.0);
                let r = kernel(e, Some(&mut local));
                if t.scale != 1.0 {
                    local *= t.scale;
                }
                if t.overwrite {
                    t.pattern.scatter_first(t.values, e, &local);
                } else {
                    t.pattern.scatter(t.values, e, &local);
                }
                r
            }
            None => kernel(e, None),
        };
        dofs.add_element(rhs, e, &r);
    }
}

/// [`assemble`] into a new zero vector of the layout.
pub fn assemble_new<const N: usize>(
    dofs: &DofMap,
    tangent: Option<Tangent<'_>>,
    kernel: impl FnMut(usize, Option<&mut SMatrix<f64, N, N>>) -> SVector<f64, N>,
) -> DVector<f64> {
    let mut r = dofs.zeros();
    assemble(dofs, &mut r, tangent, kernel);
    r
}

/// One pass of a scalar functional over the mesh: `f(e, ξ, w)` at every point `(ξ, w)` of
/// `rule` (on the unit interval) of every element, element by element. Callers accumulate
/// their sums in this order.
pub fn integrate<R>(mesh: &Mesh, rule: R, mut f: impl FnMut(usize, f64, f64))
where
    R: IntoIterator<Item = (f64, f64)> + Clone,
{
    for e in 0..mesh.elements {
        for (xi, w) in rule.clone() {
            f(e, xi, w);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::LinearSolver;
    use crate::model::mesh::GAUSS2;

    /// The loop adds each element's vector and scaled matrix once, at the element's unknowns:
    /// the P1 stiffness of `−u'' = 1` assembled by it is the textbook tridiagonal matrix.
    #[test]
    fn assembles_element_blocks_at_their_nodes() {
        let mesh = Mesh::new(1.0, 4);
        let dofs = mesh.dofs();
        let pattern = dofs.pattern();
        let mut values = vec![0.0; pattern.nnz()];
        let h = mesh.h();
        let rhs = assemble_new::<12>(&dofs, Some(Tangent::new(&pattern, &mut values, 2.0)), |_, t| {
            let t = t.expect("tangent requested");
            for c in 0..6 {
                t[(c, c)] = 1.0 / h;
                t[(c + 6, c + 6)] = 1.0 / h;
                t[(c, c + 6)] = -1.0 / h;
                t[(c + 6, c)] = -1.0 / h;
            }
            SVector::<f64, 12>::from_element(h / 2.0)
        });
        let k = pattern.to_dense(&values);
        for node in 0..5 {
            let i = dofs.index(node, crate::model::mesh::Field::Alpha, 1);
            let interior = node > 0 && node < 4;
            assert_eq!(k[(i, i)], if interior { 4.0 / h } else { 2.0 / h });
            assert_eq!(rhs[i], if interior { h } else { h / 2.0 });
        }
        // Clamped at node 0 and 4: the discrete solution of −u'' = 1 is exact at the nodes.
        let rows: Vec<usize> = (0..6).chain(24..30).collect();
        pattern.set_identity_rows(&mut values, &rows);
        let mut b = rhs * 2.0;
        rows.iter().for_each(|&r| b[r] = 0.0);
        let u = LinearSolver::new(&pattern).solve(&values, &b).expect("solve");
        let s = mesh.node_s(2);
        assert!((u[12] - s * (1.0 - s) / 2.0).abs() < 1e-15, "{}", u[12]);
    }

    #[test]
    fn integrate_visits_every_point_of_every_element() {
        let mesh = Mesh::new(2.0, 5);
        let h = mesh.h();
        let mut integral = 0.0;
        integrate(&mesh, GAUSS2.iter(), |e, xi, w| {
            let s = mesh.node_s(e) + xi * h;
            integral += w * h * s * s * s;
        });
        assert!((integral - 4.0).abs() < 1e-14, "{integral}");
    }
}
