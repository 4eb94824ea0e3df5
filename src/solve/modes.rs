//! Natural frequencies of the rod linearised about its rest state (clamped at s = 0).
//!
//! `K = ∂G/∂u` and `M = ∂P/∂u̇` at the reference configuration (D3, D6). The paper's weak form
//! tests the moment balance with `δα` rather than with the virtual rotation `δθ = Qᵀ A δα`
//! (eqs. 27, 30), so the α rows are not symmetric. Left-multiplying them by `A(0)ᵀ` (the
//! virtual-work form at rest) gives symmetric `K_s`, `M_s` with `M_s` positive definite; we
//! solve `K_s φ = ω² M_s φ` by Cholesky reduction. The symmetry is checked, not assumed.
use nalgebra::{DMatrix, DVector, SymmetricEigen};

use super::{Problem, SolveError};
use crate::assemble::Tangent;
use crate::model::mesh::{DofMap, Field};
use crate::model::rotation::a_matrix;

/// Linearised modal model on the free unknowns (node 0 removed).
pub struct ModalModel {
    /// circular frequencies ω_i [rad/s], ascending
    pub omegas: Vec<f64>,
    /// mass-normalised mode shapes on the free unknowns (columns), `Φᵀ M_s Φ = I`
    pub shapes: DMatrix<f64>,
    /// symmetrising left factor applied to rows (free unknowns), to project loads: `g = Φᵀ T F`
    pub row_transform: DMatrix<f64>,
    /// largest relative asymmetry found in `K_s` and `M_s`
    pub asymmetry: f64,
    /// full index of the first free unknown
    first_free: usize,
}

/// Errors of the eigen-analysis.
#[derive(Debug, thiserror::Error)]
pub enum ModesError {
    #[error("mass matrix is not positive definite after symmetrisation")]
    MassNotDefinite,
    #[error("linearised operators are not symmetric after the A(0)ᵀ transform (relative asymmetry {0:e})")]
    NotSymmetric(f64),
    #[error(transparent)]
    Solve(#[from] SolveError),
}

/// The free unknowns: all but the clamped node 0. They keep the forward layout, one node less.
fn free_dofs(problem: &Problem) -> (std::ops::Range<usize>, DofMap) {
    let dofs = problem.dofs();
    (dofs.block()..dofs.len(), DofMap::forward(dofs.nodes() - 1))
}

/// Build the modal model (dense; intended for a few hundred unknowns).
pub fn modal_model(problem: &Problem) -> Result<ModalModel, ModesError> {
    let pattern = problem.dofs().pattern();
    let u0 = problem.reference_state();
    let zero = DVector::zeros(u0.len());
    let mut kv = vec![0.0; pattern.nnz()];
    problem.internal_force(&u0, Some(Tangent::new(&pattern, &mut kv, 1.0)));
    let mut mv = vec![0.0; pattern.nnz()];
    problem.momentum(&u0, &zero, Some((Tangent::new(&pattern, &mut mv, 0.0), 1.0)));
    let (free, free_dofs) = free_dofs(problem);
    let n = free.len();
    let kd = pattern.to_dense(&kv).view((free.start, free.start), (n, n)).into_owned();
    let md = pattern.to_dense(&mv).view((free.start, free.start), (n, n)).into_owned();
    let a0t = a_matrix(&nalgebra::Vector3::zeros()).transpose();
    let mut t = DMatrix::identity(n, n);
    for node in 0..free_dofs.nodes() {
        let o = free_dofs.index(node, Field::Alpha, 0);
        t.view_mut((o, o), (3, 3)).copy_from(&a0t);
    }
    let ks = &t * kd;
    let ms = &t * md;
    let asym = |m: &DMatrix<f64>| (m - m.transpose()).amax() / m.amax();
    let asymmetry = asym(&ks).max(asym(&ms));
    if asymmetry > 1e-10 {
        return Err(ModesError::NotSymmetric(asymmetry));
    }
    let ks = (&ks + ks.transpose()) * 0.5;
    let ms = (&ms + ms.transpose()) * 0.5;
    let chol = ms.cholesky().ok_or(ModesError::MassNotDefinite)?;
    let l = chol.l();
    // C = L⁻¹ K L⁻ᵀ
    let linv_k = l.solve_lower_triangular(&ks).ok_or(ModesError::MassNotDefinite)?;
    let c = l.solve_lower_triangular(&linv_k.transpose()).ok_or(ModesError::MassNotDefinite)?;
    let c = (&c + c.transpose()) * 0.5;
    let eig = SymmetricEigen::new(c);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
    let omegas = order.iter().map(|&i| eig.eigenvalues[i].max(0.0).sqrt()).collect();
    let y = DMatrix::from_fn(n, n, |r, c| eig.eigenvectors[(r, order[c])]);
    let shapes = l.transpose().solve_upper_triangular(&y).ok_or(ModesError::MassNotDefinite)?;
    Ok(ModalModel { omegas, shapes, row_transform: t, asymmetry, first_free: free.start })
}

impl ModalModel {
    /// Modal load amplitudes `g = Φᵀ T F` for a full-length load vector `F` (node 0 dropped).
    pub fn project(&self, f_full: &DVector<f64>) -> DVector<f64> {
        let n = self.shapes.nrows();
        let f = f_full.rows(self.first_free, n).into_owned();
        self.shapes.transpose() * (&self.row_transform * f)
    }

    /// Displacement of free unknown `index` (full numbering) for modal coordinates `q`.
    pub fn displacement(&self, index: usize, q: &DVector<f64>) -> f64 {
        (self.shapes.row(index - self.first_free) * q)[(0, 0)]
    }
}
