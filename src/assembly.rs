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

/// CSC sparsity pattern of the block-tridiagonal system matrix (`block` unknowns per node,
/// 6 for the forward problem, 12 for the inverse) with, per element, the position of each of
/// its `(2 block)²` local entries in the value array.
pub struct Pattern {
    ndofs: usize,
    block: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// value index of local entry (i, j) of element e: `slots[e * n² + n i + j]`, n = 2 block
    slots: Vec<usize>,
    diag: Vec<usize>,
}

impl Pattern {
    /// Pattern of the forward problem (6 unknowns per node).
    pub fn new(mesh: &Mesh) -> Self {
        Self::with_block(mesh, 6)
    }

    /// Pattern for `block` unknowns per node, element `e` owning `[block e, block (e + 2))`.
    pub fn with_block(mesh: &Mesh, block: usize) -> Self {
        let n = mesh.nodes() * block;
        // Column j couples with rows of the nodes of every element containing node(j).
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for j in 0..n {
            let node = j / block;
            let lo = node.saturating_sub(1) * block;
            let hi = ((node + 2).min(mesh.nodes())) * block;
            row_idx.extend(lo..hi);
            col_ptr.push(row_idx.len());
        }
        let find = |i: usize, j: usize| -> usize {
            let range = col_ptr[j]..col_ptr[j + 1];
            let first = row_idx[range.start];
            range.start + (i - first)
        };
        let ne = 2 * block;
        let mut slots = Vec::with_capacity(mesh.elements * ne * ne);
        for e in 0..mesh.elements {
            for i in 0..ne {
                for j in 0..ne {
                    slots.push(find(block * e + i, block * e + j));
                }
            }
        }
        let diag = (0..n).map(|j| find(j, j)).collect();
        Pattern { ndofs: n, block, col_ptr, row_idx, slots, diag }
    }

    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Add a local matrix of element `e` into the values.
    pub fn scatter_mat(&self, values: &mut [f64], e: usize, local: &LocalMat) {
        self.scatter_local(values, e, local);
    }

    /// Add a local `(2 block)²` matrix of element `e` into the values.
    pub fn scatter_local<const N: usize>(&self, values: &mut [f64], e: usize, local: &nalgebra::SMatrix<f64, N, N>) {
        assert_eq!(N, 2 * self.block, "local matrix size must be twice the block size");
        let s = &self.slots[e * N * N..(e + 1) * N * N];
        for i in 0..N {
            for j in 0..N {
                values[s[N * i + j]] += local[(i, j)];
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

/// Passes of Ruiz equilibration.
const RUIZ_PASSES: usize = 5;

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

    /// Solve `M x = b` after Ruiz equilibration (`docs/inverse.md`, I6): five passes of
    /// row/column max-norm scaling `A ← diag(1/√r) A diag(1/√c)`, then `x = D_c y`.
    pub fn solve_equilibrated(&self, values: &[f64], b: &DVector<f64>) -> Result<DVector<f64>, LinearError> {
        let (a, dr, dc) = self.equilibrate(values);
        let rhs = DVector::from_fn(b.len(), |i, _| b[i] * dr[i]);
        let y = self.solve(&a, &rhs)?;
        Ok(DVector::from_fn(b.len(), |i, _| y[i] * dc[i]))
    }

    /// Ruiz equilibration of I6: returns `(D_r A D_c, D_r, D_c)` (values, row and column
    /// factors) after five passes of row/column max-norm scaling.
    pub fn equilibrate(&self, values: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let n = self.symbolic_matrix.ncols();
        let col_ptr = self.symbolic_matrix.col_ptr();
        let row_idx = self.symbolic_matrix.row_idx();
        let mut a = values.to_vec();
        let (mut dr, mut dc) = (vec![1.0; n], vec![1.0; n]);
        for _ in 0..RUIZ_PASSES {
            let (mut r, mut c) = (vec![0.0_f64; n], vec![0.0_f64; n]);
            for j in 0..n {
                for k in col_ptr[j]..col_ptr[j + 1] {
                    let v = a[k].abs();
                    r[row_idx[k]] = r[row_idx[k]].max(v);
                    c[j] = c[j].max(v);
                }
            }
            let inv_sqrt = |v: f64| if v > 0.0 { 1.0 / v.sqrt() } else { 1.0 };
            for j in 0..n {
                for k in col_ptr[j]..col_ptr[j + 1] {
                    a[k] *= inv_sqrt(r[row_idx[k]]) * inv_sqrt(c[j]);
                }
            }
            for i in 0..n {
                dr[i] *= inv_sqrt(r[i]);
                dc[i] *= inv_sqrt(c[i]);
            }
        }
        (a, dr, dc)
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
        // Equilibration does not change the solution of a well-conditioned system.
        let xe = solver.solve_equilibrated(&vals, &b).unwrap();
        assert!((&xe - &x).amax() < 1e-12);
        // Identity rows.
        p.set_identity_rows(&mut vals, &[0, 5]);
        let x = solver.solve(&vals, &b).unwrap();
        assert!((x[0] - b[0]).abs() < 1e-14 && (x[5] - b[5]).abs() < 1e-14);
    }
}
