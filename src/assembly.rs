//! Gather → kernel → scatter, written once and used by every solver (static, dynamic, modes).
//!
//! Element `e` owns the contiguous global unknowns `[6e, 6e + 12)`, so gathering is a slice
//! copy. The sparsity pattern (block tridiagonal, 6 × 6 blocks) and the symbolic LU are built
//! once per mesh; every iterate only refills the values and refactors numerically.
use faer::linalg::solvers::SolveCore;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut};
use nalgebra::DVector;

use crate::element::{LocalMat, LocalVec};
use crate::mesh::{Mesh, DOFS_PER_ELEMENT};

/// Errors of the linear algebra layer.
#[derive(Debug, thiserror::Error)]
pub enum LinearError {
    #[error("sparse LU factorisation failed: {0}")]
    Factorisation(String),
    #[error("linear solve produced a non-finite value at unknown {index}")]
    NonFinite { index: usize },
}

/// Local unknowns of element `e`.
pub fn gather(u: &DVector<f64>, e: usize) -> LocalVec {
    LocalVec::from_column_slice(&u.as_slice()[6 * e..6 * e + DOFS_PER_ELEMENT])
}

/// Add a local vector into the global one.
pub fn scatter_vec(r: &mut DVector<f64>, e: usize, local: &LocalVec) {
    for i in 0..DOFS_PER_ELEMENT {
        r[6 * e + i] += local[i];
    }
}

/// Assemble `Σ_e kernel(e, s0_e, u_e)` into a global vector.
pub fn assemble_vector(mesh: &Mesh, mut kernel: impl FnMut(usize, f64) -> LocalVec) -> DVector<f64> {
    let mut r = DVector::zeros(mesh.ndofs());
    for e in 0..mesh.elements {
        let local = kernel(e, mesh.node_s(e));
        scatter_vec(&mut r, e, &local);
    }
    r
}

/// CSC sparsity pattern of the block-tridiagonal system matrix with, per element, the
/// position of each of its 144 local entries in the value array.
pub struct Pattern {
    ndofs: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// value index of local entry (i, j) of element e: `slots[e][12 i + j]`
    slots: Vec<[usize; DOFS_PER_ELEMENT * DOFS_PER_ELEMENT]>,
    diag: Vec<usize>,
}

impl Pattern {
    pub fn new(mesh: &Mesh) -> Self {
        let n = mesh.ndofs();
        // Column j couples with rows of the nodes of every element containing node(j).
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for j in 0..n {
            let node = j / 6;
            let lo = node.saturating_sub(1) * 6;
            let hi = ((node + 2).min(mesh.nodes())) * 6;
            row_idx.extend(lo..hi);
            col_ptr.push(row_idx.len());
        }
        let find = |i: usize, j: usize| -> usize {
            let range = col_ptr[j]..col_ptr[j + 1];
            let first = row_idx[range.start];
            range.start + (i - first)
        };
        let mut slots = Vec::with_capacity(mesh.elements);
        for e in 0..mesh.elements {
            let mut s = [0usize; DOFS_PER_ELEMENT * DOFS_PER_ELEMENT];
            for i in 0..DOFS_PER_ELEMENT {
                for j in 0..DOFS_PER_ELEMENT {
                    s[DOFS_PER_ELEMENT * i + j] = find(6 * e + i, 6 * e + j);
                }
            }
            slots.push(s);
        }
        let diag = (0..n).map(|j| find(j, j)).collect();
        Pattern { ndofs: n, col_ptr, row_idx, slots, diag }
    }

    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Add a local matrix of element `e` into the values.
    pub fn scatter_mat(&self, values: &mut [f64], e: usize, local: &LocalMat) {
        let s = &self.slots[e];
        for i in 0..DOFS_PER_ELEMENT {
            for j in 0..DOFS_PER_ELEMENT {
                values[s[DOFS_PER_ELEMENT * i + j]] += local[(i, j)];
            }
        }
    }

    /// Replace the rows of the given unknowns by identity rows (exact Dirichlet conditions).
    pub fn set_identity_rows(&self, values: &mut [f64], rows: &[usize]) {
        for j in 0..self.ndofs {
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                if rows.contains(&self.row_idx[k]) {
                    values[k] = 0.0;
                }
            }
        }
        for &r in rows {
            values[self.diag[r]] = 1.0;
        }
    }

    /// Dense copy (for eigenvalue problems of modest size).
    pub fn to_dense(&self, values: &[f64]) -> nalgebra::DMatrix<f64> {
        let mut m = nalgebra::DMatrix::zeros(self.ndofs, self.ndofs);
        for j in 0..self.ndofs {
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                m[(self.row_idx[k], j)] += values[k];
            }
        }
        m
    }

    fn symbolic(&self) -> SymbolicSparseColMat<usize> {
        SymbolicSparseColMat::new_checked(self.ndofs, self.ndofs, self.col_ptr.clone(), None, self.row_idx.clone())
    }
}

/// Sparse LU with the symbolic analysis done once per pattern.
pub struct LinearSolver {
    symbolic_matrix: SymbolicSparseColMat<usize>,
    symbolic_lu: SymbolicLu<usize>,
}

impl LinearSolver {
    pub fn new(pattern: &Pattern) -> Result<Self, LinearError> {
        let symbolic_matrix = pattern.symbolic();
        let symbolic_lu = SymbolicLu::try_new(symbolic_matrix.as_ref()).map_err(|e| LinearError::Factorisation(format!("{e:?}")))?;
        Ok(LinearSolver { symbolic_matrix, symbolic_lu })
    }

    /// Solve `M x = b` for the matrix with the pattern's structure and the given values.
    pub fn solve(&self, values: &[f64], b: &DVector<f64>) -> Result<DVector<f64>, LinearError> {
        let mat = SparseColMatRef::new(self.symbolic_matrix.as_ref(), values);
        let lu = Lu::try_new_with_symbolic(self.symbolic_lu.clone(), mat).map_err(|e| LinearError::Factorisation(format!("{e:?}")))?;
        let mut x = b.clone();
        let n = x.len();
        let view = MatMut::from_column_major_slice_mut(x.as_mut_slice(), n, 1);
        lu.solve_in_place_with_conj(Conj::No, view);
        if let Some(index) = x.iter().position(|v| !v.is_finite()) {
            return Err(LinearError::NonFinite { index });
        }
        Ok(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pattern_scatter_and_solve() {
        let mesh = Mesh::new(1.0, 3);
        let p = Pattern::new(&mesh);
        let mut vals = vec![0.0; p.nnz()];
        // A diagonally dominant element matrix.
        let local = LocalMat::from_fn(|i, j| if i == j { 10.0 } else { 1.0 / (1.0 + i as f64 + 2.0 * j as f64) });
        for e in 0..mesh.elements {
            p.scatter_mat(&mut vals, e, &local);
        }
        let dense = p.to_dense(&vals);
        let b = DVector::from_fn(mesh.ndofs(), |i, _| (i as f64).cos());
        let solver = LinearSolver::new(&p).unwrap();
        let x = solver.solve(&vals, &b).unwrap();
        assert!((&dense * &x - &b).amax() < 1e-12);
        // Identity rows.
        p.set_identity_rows(&mut vals, &[0, 5]);
        let x = solver.solve(&vals, &b).unwrap();
        assert!((x[0] - b[0]).abs() < 1e-14 && (x[5] - b[5]).abs() < 1e-14);
    }
}
