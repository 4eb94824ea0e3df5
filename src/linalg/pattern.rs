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

/// How an element's matrix goes into the values: added to what they hold
/// ([`Pattern::scatter`]), or in a pass over every element in order that writes the entries no
/// earlier element touched ([`Pattern::scatter_first`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Pass {
    Adding,
    First,
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
        self.scatter_with(values, e, local, Pass::Adding);
    }

    /// [`Pattern::scatter`] of an assembly pass that starts from whatever `values` holds, with
    /// the elements in order `0, 1, …`: the entries no earlier element touched are written
    /// (`0 + a`, bit for bit what adding into zeroed values gives), the others added. Element
    /// `e` shares only the block of node `e` (rows and columns `< block`) with element `e − 1`;
    /// every entry of the pattern belongs to some element, so the pass leaves no old value and
    /// the values need no zeroing before it.
    pub fn scatter_first<const N: usize>(&self, values: &mut [f64], e: usize, local: &SMatrix<f64, N, N>) {
        self.scatter_with(values, e, local, Pass::First);
    }

    #[inline]
    fn scatter_with<const N: usize>(&self, values: &mut [f64], e: usize, local: &SMatrix<f64, N, N>, pass: Pass) {
        let first = pass == Pass::First;
        assert_eq!(N, 2 * self.block, "local matrix size must be twice the block size");
        // rows [0, shared) of the columns [0, block) were touched by element e − 1 (first pass)
        let shared = match (first, e) {
            (false, _) => N,
            (true, 0) => 0,
            (true, _) => self.block,
        };
        // Column j of the element holds rows block·e .. block·e + N of a pattern column, whose
        // rows are contiguous and ascending: one run of N values per column.
        let s = &self.slots[e * N * N..(e + 1) * N * N];
        for j in 0..N {
            let start = s[j];
            debug_assert!((0..N).all(|i| s[N * i + j] == start + i), "element rows must be contiguous in a column");
            let dst: &mut [f64; N] = (&mut values[start..start + N]).try_into().expect("N rows");
            // column-major storage: column j is the j-th run of N values
            let src: &[f64; N] = local.as_slice()[j * N..(j + 1) * N].try_into().expect("N rows");
            // rows [0, added) are added into, the others written
            let added = if j < self.block || !first { shared } else { 0 };
            for i in 0..added {
                dst[i] += src[i];
            }
            for i in added..N {
                // 0 + a: a, with −0 turned into +0 as the addition does
                dst[i] = 0.0 + src[i];
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

    /// The position in `values` of the entry `(row, col)`, if the pattern holds it.
    pub fn position(&self, row: usize, col: usize) -> Option<usize> {
        let (lo, hi) = (self.col_ptr[col], self.col_ptr[col + 1]);
        let first = self.row_idx[lo];
        (row >= first && row - first < hi - lo).then(|| lo + row - first)
    }

    /// Replace the three rows `rows` of one node by their combinations
    /// `row'_k = Σ_j t[k][j] row_j`, over every column of the node's band.
    pub fn combine_rows(&self, values: &mut [f64], rows: [usize; 3], t: &[[f64; 3]; 3]) {
        let nodes = self.ndofs / self.block;
        let node = rows[0] / self.block;
        let lo = node.saturating_sub(1) * self.block;
        let hi = (node + 2).min(nodes) * self.block;
        for j in lo..hi {
            let first = self.row_idx[self.col_ptr[j]];
            let at = rows.map(|r| self.col_ptr[j] + r - first);
            let old = at.map(|k| values[k]);
            for (k, pos) in at.iter().enumerate() {
                values[*pos] = t[k][0] * old[0] + t[k][1] * old[1] + t[k][2] * old[2];
            }
        }
    }

    /// The product `A x` of the matrix with these values and a vector.
    pub fn multiply(&self, values: &[f64], x: &nalgebra::DVector<f64>) -> nalgebra::DVector<f64> {
        let mut y = nalgebra::DVector::zeros(self.ndofs);
        for j in 0..self.ndofs {
            let xj = x[j];
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                y[self.row_idx[k]] += values[k] * xj;
            }
        }
        y
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

#[cfg(test)]
mod tests {
    use super::*;

    /// `multiply` is the dense product of `to_dense` (integer-valued entries: exact).
    #[test]
    fn multiply_is_the_dense_product() {
        let p = Pattern::block_tridiagonal(5, 3);
        let values: Vec<f64> = (0..p.nnz()).map(|k| ((7 * k) % 11) as f64 - 5.0).collect();
        let x = nalgebra::DVector::from_fn(p.ndofs(), |i, _| (i % 4) as f64 - 1.5);
        assert_eq!(p.multiply(&values, &x), p.to_dense(&values) * &x);
    }

    /// A pass of `scatter_first` over every element, in order, on values holding garbage gives
    /// bit for bit what zeroing them and adding with `scatter` gives (signed zeros included).
    #[test]
    fn scatter_first_replaces_zeroing_bit_for_bit() {
        for (nodes, block) in [(2, 3), (5, 6), (9, 12)] {
            let p = Pattern::block_tridiagonal(nodes, block);
            let mut seed = 0x2545_F491_4F6C_DD1Du64 ^ (nodes * block) as u64;
            let mut next = || {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                seed
            };
            let locals: Vec<SMatrix<f64, 24, 24>> = (0..nodes - 1)
                .map(|_| {
                    SMatrix::from_fn(|_, _| match next() % 5 {
                        0 => -0.0,
                        1 => 0.0,
                        _ => (next() >> 11) as f64 / (1u64 << 53) as f64 - 0.5,
                    })
                })
                .collect();
            let run =
                |pass: Pass| {
                    let mut values: Vec<f64> = if pass == Pass::First {
                        (0..p.nnz()).map(|k| 1e300 * (k as f64 + 1.0)).collect()
                    } else {
                        vec![0.0; p.nnz()]
                    };
                    for (e, l) in locals.iter().enumerate() {
                        // the top-left (2 block)² corner of the 24 × 24 sample
                        let local = SMatrix::<f64, 24, 24>::from_fn(|i, j| {
                            if i < 2 * block && j < 2 * block {
                                l[(i, j)]
                            } else {
                                0.0
                            }
                        });
                        match block {
                            12 if pass == Pass::First => p.scatter_first(&mut values, e, &local),
                            12 => p.scatter(&mut values, e, &local),
                            6 => scatter_n::<12>(&p, &mut values, e, &local, pass),
                            _ => scatter_n::<6>(&p, &mut values, e, &local, pass),
                        }
                    }
                    values.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
                };
            assert_eq!(run(Pass::First), run(Pass::Adding), "{nodes} nodes, block {block}");
        }
    }

    /// The `N × N` corner of `local`, scattered by `scatter_first` or `scatter`.
    fn scatter_n<const N: usize>(p: &Pattern, values: &mut [f64], e: usize, local: &SMatrix<f64, 24, 24>, pass: Pass) {
        let m = SMatrix::<f64, N, N>::from_fn(|i, j| local[(i, j)]);
        if pass == Pass::First {
            p.scatter_first(values, e, &m)
        } else {
            p.scatter(values, e, &m)
        }
    }
}
