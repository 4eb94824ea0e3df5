//! Natural frequencies of the rod linearised about its rest state (clamped at s = 0).
//!
//! `K = ∂G/∂u` and `M = ∂P/∂u̇` at the reference configuration (D3, D6). The paper's weak form
//! tests the moment balance with `δα` rather than with the virtual rotation `δθ = Qᵀ A δα`
//! (eqs. 27, 30), so the α rows are not symmetric. Left-multiplying them by `A(0)ᵀ` (the
//! virtual-work form at rest) gives symmetric `K_s`, `M_s` with `M_s` positive definite; we
//! solve `K_s φ = ω² M_s φ`. The symmetry is checked, not assumed.
//!
//! Two solvers of the same pencil:
//! - [`modal_model`]: every mode, dense (Cholesky reduction `L⁻¹ K_s L⁻ᵀ`, `M_s = L Lᵀ`, and
//!   the symmetric QR iteration): for the modal superposition of a whole response, a few
//!   hundred elements at most (O(n²) memory, O(n³) time);
//! - [`lowest_modes`]: the lowest `k` modes by shift-invert block Lanczos (D28): the operator
//!   `(K − σM)⁻¹M = (K_s − σM_s)⁻¹M_s` (the same for the paper's rows and the symmetrised ones,
//!   `T = blockdiag(I, A(0)ᵀ)` being invertible), one banded LU of `K` (σ = 0: the clamped rod
//!   has no rigid motion) and one solve per Lanczos vector, the vectors `M_s`-orthonormal, so
//!   that `V_mᵀ M_s (K_s − σM_s)⁻¹ M_s V_m` is symmetric and its largest eigenvalues
//!   `θ = 1/(ω² − σ)` give the lowest `ω²`: O(n k) memory, O(n (k + bandwidth²)) time.
use nalgebra::{DMatrix, DVector, Matrix3, SymmetricEigen};

use super::{Problem, SolveError};
use crate::assemble::Tangent;
use crate::linalg::{largest_symmetric, Krylov, LinearSolver, Pattern};
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

/// `K = ∂G/∂u` and `M = ∂P/∂u̇` at the reference configuration (D3, D6), on the full
/// pattern: its values `(pattern, K, M)`.
fn rest_operators(problem: &Problem) -> (Pattern, Vec<f64>, Vec<f64>) {
    let pattern = problem.dofs().pattern();
    let u0 = problem.reference_state();
    let zero = DVector::zeros(u0.len());
    let mut kv = vec![0.0; pattern.nnz()];
    problem.internal_force(&u0, Some(Tangent::new(&pattern, &mut kv, 1.0)));
    let mut mv = vec![0.0; pattern.nnz()];
    problem.momentum(&u0, &zero, Some((Tangent::new(&pattern, &mut mv, 0.0), 1.0)));
    (pattern, kv, mv)
}

/// Build the modal model (dense; intended for a few hundred unknowns).
pub fn modal_model(problem: &Problem) -> Result<ModalModel, ModesError> {
    let (pattern, kv, mv) = rest_operators(problem);
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

/// The lowest modes of the rod linearised about its rest state ([`lowest_modes`]).
#[derive(Clone, Debug)]
pub struct LowestModes {
    /// circular frequencies ω_i [rad/s], ascending
    pub omegas: Vec<f64>,
    /// the modes in the problem's layout (zero on the clamped node 0), `φᵀ M_s φ = 1`
    pub shapes: Vec<DVector<f64>>,
    /// largest relative asymmetry found in `K_s` and `M_s`
    pub asymmetry: f64,
}

/// Block size of the Lanczos method: at least the multiplicity of the wanted frequencies (a
/// section with EI1 = EI2 bends alike in two planes: every bending frequency is double).
pub const LANCZOS_BLOCK: usize = 3;

/// A Ritz pair is converged when its residual is at most this times the largest `θ`
/// (`‖(K_s − σM_s)⁻¹M_s x − θ x‖_{M_s}`; the error of `θ` is of the order of its square over
/// the gap to the next one, Saad 2011, Th. 4.8 of [`crate::linalg::Krylov`]'s references).
pub const RITZ_TOLERANCE: f64 = 1e-10;

/// The lowest `count` modes of the rod clamped at s = 0, linearised about its rest state
/// (module doc): the same pencil as [`modal_model`], by shift-invert block Lanczos (D28).
/// `count` is capped at half the free unknowns.
pub fn lowest_modes(problem: &Problem, count: usize) -> Result<LowestModes, ModesError> {
    let (pattern, mut kv, mut mv) = rest_operators(problem);
    let (free, free_dofs) = free_dofs(problem);
    let a0t = a_matrix(&nalgebra::Vector3::zeros()).transpose();
    let alpha = problem.dofs().index(0, Field::Alpha, 0);
    let asymmetry = symmetrised_asymmetry(&pattern, &kv, &a0t, alpha, free.start)
        .max(symmetrised_asymmetry(&pattern, &mv, &a0t, alpha, free.start));
    if asymmetry > 1e-10 {
        return Err(ModesError::NotSymmetric(asymmetry));
    }
    // node 0 clamped: identity rows in K, zero rows in M (the vectors vanish there)
    let clamped: Vec<usize> = (0..free.start).collect();
    pattern.set_identity_rows(&mut kv, &clamped);
    pattern.set_identity_rows(&mut mv, &clamped);
    for &d in &clamped {
        mv[pattern.position(d, d).expect("diagonal")] = 0.0;
    }
    let mut solver = LinearSolver::new(&pattern);
    let mut factored = false;
    let op = |v: &DVector<f64>| {
        let b = pattern.multiply(&mv, v);
        if factored {
            solver.solve_factored(&b)
        } else {
            factored = true;
            solver.solve_equilibrated(&kv, &b)
        }
    };
    let block = pattern.block();
    let inner = |v: &DVector<f64>| transform_rows(pattern.multiply(&mv, v), &a0t, block, alpha);
    let count = count.min(free_dofs.len() / 2);
    let mut krylov = Krylov::new(problem.dofs().len(), LANCZOS_BLOCK, op, inner).map_err(SolveError::from)?;
    let pairs = largest_symmetric(&mut krylov, count, RITZ_TOLERANCE).map_err(SolveError::from)?;
    let (omegas, shapes) = pairs.into_iter().map(|(theta, x)| ((1.0 / theta).max(0.0).sqrt(), x)).unzip();
    Ok(LowestModes { omegas, shapes, asymmetry })
}

/// `T v`: `A(0)ᵀ` applied to every node's angle triple (at `alpha` within its block).
fn transform_rows(mut v: DVector<f64>, a0t: &Matrix3<f64>, block: usize, alpha: usize) -> DVector<f64> {
    for node in 0..v.len() / block {
        let o = node * block + alpha;
        let t = a0t * v.fixed_rows::<3>(o);
        v.fixed_rows_mut::<3>(o).copy_from(&t);
    }
    v
}

/// The largest `|(T A)_ij − (T A)_ji|` over the unknowns from `first` on, relative to the
/// largest `|(T A)_ij|` there (`T` as in [`transform_rows`]; a column's rows are whole blocks).
fn symmetrised_asymmetry(pattern: &Pattern, values: &[f64], a0t: &Matrix3<f64>, alpha: usize, first: usize) -> f64 {
    let (n, block) = (pattern.ndofs(), pattern.block());
    let mut ta = values.to_vec();
    let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
    for j in 0..n {
        for k in (col_ptr[j]..col_ptr[j + 1]).step_by(block) {
            let o = k + alpha - (row_idx[k] % block);
            let t = a0t * nalgebra::Vector3::new(values[o], values[o + 1], values[o + 2]);
            ta[o..o + 3].copy_from_slice(t.as_slice());
        }
    }
    let (mut diff, mut big) = (0.0_f64, 0.0_f64);
    for j in first..n {
        for k in col_ptr[j]..col_ptr[j + 1] {
            let i = row_idx[k];
            if i >= first {
                let back = pattern.position(j, i).map_or(0.0, |p| ta[p]);
                diff = diff.max((ta[k] - back).abs());
                big = big.max(ta[k].abs());
            }
        }
    }
    diff / big
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
