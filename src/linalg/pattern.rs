//! The sparsity pattern of every system matrix of the crate: block tridiagonal, one block per
//! mesh node. Built once per mesh; iterates only refill its value array.
use nalgebra::SMatrix;

/// CSC sparsity pattern of a block-tridiagonal matrix of `nodes × nodes` blocks of size
/// `block`, assembled from overlapping `2 block × 2 block` submatrices ("elements": element `e`
/// covers the blocks of nodes `e` and `e + 1`, rows and columns `[block e, block (e + 2))`),
/// with the position of each entry of each element's submatrix in the value array.
#[derive(Clone, Debug)]
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
    /// Pattern of `nodes` blocks of `block` unknowns each (`nodes ≥ 2`).
    pub fn block_tridiagonal(nodes: usize, block: usize) -> Self {
        assert!(nodes >= 2 && block > 0, "a block-tridiagonal pattern needs at least 2 nodes and a block");
        let elements = nodes - 1;
        let n = nodes * block;
        // Column j couples with rows of the nodes of every element containing node(j).
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for j in 0..n {
            let node = j / block;
            let lo = node.saturating_sub(1) * block;
            let hi = ((node + 2).min(nodes)) * block;
            row_idx.extend(lo..hi);
            col_ptr.push(row_idx.len());
        }
        let find = |i: usize, j: usize| -> usize {
            let range = col_ptr[j]..col_ptr[j + 1];
            let first = row_idx[range.start];
            range.start + (i - first)
        };
        let ne = 2 * block;
        let mut slots = Vec::with_capacity(elements * ne * ne);
        for e in 0..elements {
            for i in 0..ne {
                for j in 0..ne {
                    slots.push(find(block * e + i, block * e + j));
                }
            }
        }
        let diag = (0..n).map(|j| find(j, j)).collect();
        Pattern { ndofs: n, block, col_ptr, row_idx, slots, diag }
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Order of the matrix.
    pub fn ndofs(&self) -> usize {
        self.ndofs
    }

    /// Unknowns per block.
    pub fn block(&self) -> usize {
        self.block
    }

    /// Column pointers (CSC).
    pub fn col_ptr(&self) -> &[usize] {
        &self.col_ptr
    }

    /// Row indices (CSC); the rows of a column are contiguous and ascending.
    pub fn row_idx(&self) -> &[usize] {
        &self.row_idx
    }

    /// Add a local `(2 block)²` matrix of element `e` into the values.
    pub fn scatter<const N: usize>(&self, values: &mut [f64], e: usize, local: &SMatrix<f64, N, N>) {
        assert_eq!(N, 2 * self.block, "local matrix size must be twice the block size");
        // Column j of the element holds rows block·e .. block·e + N of a pattern column, whose
        // rows are contiguous and ascending: one run of N values per column.
        let s = &self.slots[e * N * N..(e + 1) * N * N];
        for j in 0..N {
            let start = s[j];
            debug_assert!((0..N).all(|i| s[N * i + j] == start + i), "element rows must be contiguous in a column");
            let dst: &mut [f64; N] = (&mut values[start..start + N]).try_into().expect("N rows");
            // column-major storage: column j is the j-th run of N values
            let src: &[f64; N] = local.as_slice()[j * N..(j + 1) * N].try_into().expect("N rows");
            for i in 0..N {
                dst[i] += src[i];
            }
        }
    }

    /// Replace the rows of the given unknowns by identity rows (exact Dirichlet conditions).
    /// Touches only the entries of those rows (the columns of the neighbouring nodes).
    pub fn set_identity_rows(&self, values: &mut [f64], rows: &[usize]) {
        let nodes = self.ndofs / self.block;
        for &r in rows {
            let node = r / self.block;
            let lo = node.saturating_sub(1) * self.block;
            let hi = (node + 2).min(nodes) * self.block;
            for j in lo..hi {
                // column j holds the rows of the nodes around node(j), contiguously
                let first = self.row_idx[self.col_ptr[j]];
                values[self.col_ptr[j] + r - first] = 0.0;
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
}
