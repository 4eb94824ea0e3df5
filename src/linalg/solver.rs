//! Direct solver of the block-tridiagonal systems ([`Pattern`]): Ruiz equilibration
//! (`docs/inverse.md`, I6) and a banded LU with partial pivoting ([`BandLu`]).
use nalgebra::DVector;

use super::{BandLu, LinearError, Pattern};

/// Passes of Ruiz equilibration.
const RUIZ_PASSES: usize = 5;

/// Direct solver of the pattern's block-tridiagonal systems: a banded LU with partial
/// pivoting ([`BandLu`], `kl = ku = 2 block − 1`) whose storage and scratch are allocated once
/// per pattern; each solve copies the values into the band, factors and solves, without
/// allocating (apart from the returned vector).
pub struct LinearSolver {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    lu: BandLu,
    /// equilibrated values and the row/column factors (scratch of [`LinearSolver::solve_equilibrated`])
    scaled: Vec<f64>,
    dr: Vec<f64>,
    dc: Vec<f64>,
    rmax: Vec<f64>,
    cmax: Vec<f64>,
    rnext: Vec<f64>,
}

impl LinearSolver {
    pub fn new(pattern: &Pattern) -> Self {
        let n = pattern.ndofs();
        LinearSolver {
            col_ptr: pattern.col_ptr().to_vec(),
            row_idx: pattern.row_idx().to_vec(),
            lu: BandLu::block_tridiagonal(n / pattern.block(), pattern.block()),
            scaled: vec![0.0; pattern.nnz()],
            dr: vec![1.0; n],
            dc: vec![1.0; n],
            rmax: vec![0.0; n],
            cmax: vec![0.0; n],
            rnext: vec![0.0; n],
        }
    }

    /// Solve `M x = b` after Ruiz equilibration (`docs/inverse.md`, I6): five passes of
    /// row/column max-norm scaling `A ← diag(1/√r) A diag(1/√c)`, then `x = D_c y`.
    pub fn solve_equilibrated(&mut self, values: &[f64], b: &DVector<f64>) -> Result<DVector<f64>, LinearError> {
        let mut scaled = std::mem::take(&mut self.scaled);
        self.equilibrate_into(values, &mut scaled);
        let mut x = DVector::from_fn(b.len(), |i, _| b[i] * self.dr[i]);
        let res = self.factor_and_solve(&scaled, &mut x);
        self.scaled = scaled;
        res?;
        for (xi, d) in x.iter_mut().zip(&self.dc) {
            *xi *= d;
        }
        Ok(x)
    }

    /// Row factors `D_r` of the last [`LinearSolver::solve_equilibrated`].
    pub fn row_factors(&self) -> &[f64] {
        &self.dr
    }

    /// Ruiz equilibration of I6: returns `(D_r A D_c, D_r, D_c)` (values, row and column
    /// factors) after five passes of row/column max-norm scaling.
    pub fn equilibrate(&self, values: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let n = self.col_ptr.len() - 1;
        let mut a = vec![0.0; values.len()];
        let (mut dr, mut dc) = (vec![1.0; n], vec![1.0; n]);
        let (mut r, mut c, mut r_next) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        ruiz(&self.col_ptr, &self.row_idx, values, &mut a, &mut dr, &mut dc, &mut r, &mut c, &mut r_next);
        (a, dr, dc)
    }

    /// [`LinearSolver::equilibrate`] into `scaled` and the solver's own factors `self.dr`, `self.dc`.
    fn equilibrate_into(&mut self, values: &[f64], scaled: &mut [f64]) {
        ruiz(
            &self.col_ptr,
            &self.row_idx,
            values,
            scaled,
            &mut self.dr,
            &mut self.dc,
            &mut self.rmax,
            &mut self.cmax,
            &mut self.rnext,
        );
    }

    /// Solve `M x = b` for the matrix with the pattern's structure and the given values.
    pub fn solve(&mut self, values: &[f64], b: &DVector<f64>) -> Result<DVector<f64>, LinearError> {
        let mut x = b.clone();
        self.factor_and_solve(values, &mut x)?;
        Ok(x)
    }

    /// Copy `values` into the band, factor, and overwrite `x` (the right-hand side) by the solution.
    fn factor_and_solve(&mut self, values: &[f64], x: &mut DVector<f64>) -> Result<(), LinearError> {
        self.lu.clear();
        for j in 0..self.col_ptr.len() - 1 {
            let (k0, k1) = (self.col_ptr[j], self.col_ptr[j + 1]);
            if k0 == k1 {
                continue;
            }
            // rows of a column are contiguous in the pattern and in the band
            let start = self.lu.index(self.row_idx[k0], j);
            self.lu.band_mut()[start..start + (k1 - k0)].copy_from_slice(&values[k0..k1]);
        }
        self.lu.factor()?;
        self.lu.solve_in_place(x.as_mut_slice());
        if let Some(index) = x.iter().position(|v| !v.is_finite()) {
            return Err(LinearError::NonFinite { index });
        }
        Ok(())
    }
}

/// `r_i ← max(r_i, |a_i|)` and return `max_i |a_i|` (0 for an empty slice; NaN ignored, as
/// `f64::max` with a non-NaN first argument does). Branch-free selects in four independent
/// lanes, so that the loop vectorises and is not one chain of dependent `max` operations.
#[inline]
fn row_col_max(r: &mut [f64], a: &[f64]) -> f64 {
    let mut acc = [0.0_f64; 4];
    let mut rc = r.chunks_exact_mut(4);
    let mut ac = a.chunks_exact(4);
    for (rs, as_) in (&mut rc).zip(&mut ac) {
        for l in 0..4 {
            let v = as_[l].abs();
            rs[l] = if v > rs[l] { v } else { rs[l] };
            acc[l] = if v > acc[l] { v } else { acc[l] };
        }
    }
    for (rv, av) in rc.into_remainder().iter_mut().zip(ac.remainder()) {
        let v = av.abs();
        *rv = if v > *rv { v } else { *rv };
        acc[0] = if v > acc[0] { v } else { acc[0] };
    }
    acc[0].max(acc[1]).max(acc[2].max(acc[3]))
}

/// Five passes of Ruiz row/column max-norm scaling of the CSC values `values` into `a`, with
/// the accumulated row and column factors in `dr`, `dc` (`r`, `c`, `r_next`: scratch). Each pass takes
/// the row and column maxima of `a`, then scales `a_ij ← a_ij (1/√r_i)(1/√c_j)`; the scaling
/// of one pass and the maxima of the next share one sweep over the values.
#[allow(clippy::too_many_arguments)] // the CSC arrays, the values and the scratch of one solver
fn ruiz(
    col_ptr: &[usize],
    row_idx: &[usize],
    values: &[f64],
    a: &mut [f64],
    dr: &mut [f64],
    dc: &mut [f64],
    r: &mut [f64],
    c: &mut [f64],
    r_next: &mut [f64],
) {
    let n = col_ptr.len() - 1;
    a.copy_from_slice(values);
    dr.iter_mut().for_each(|v| *v = 1.0);
    dc.iter_mut().for_each(|v| *v = 1.0);
    debug_assert!(
        (0..n).all(|j| (col_ptr[j]..col_ptr[j + 1]).all(|k| row_idx[k] == row_idx[col_ptr[j]] + k - col_ptr[j])),
        "rows of a column must be contiguous"
    );
    let inv_sqrt = |v: f64| if v > 0.0 { 1.0 / v.sqrt() } else { 1.0 };
    // the rows of a column are contiguous (block-tridiagonal pattern): slices, no gathers
    let column =
        |j: usize| (col_ptr[j], col_ptr[j + 1], if col_ptr[j] < col_ptr[j + 1] { row_idx[col_ptr[j]] } else { 0 });
    // maxima of the unscaled values
    r.iter_mut().for_each(|v| *v = 0.0);
    for j in 0..n {
        let (k0, k1, first) = column(j);
        c[j] = row_col_max(&mut r[first..first + (k1 - k0)], &a[k0..k1]);
    }
    for pass in 0..RUIZ_PASSES {
        // the factors of this pass, 1/√r and 1/√c, once per row and column
        r.iter_mut().for_each(|v| *v = inv_sqrt(*v));
        c.iter_mut().for_each(|v| *v = inv_sqrt(*v));
        let last = pass + 1 == RUIZ_PASSES;
        r_next.iter_mut().for_each(|v| *v = 0.0);
        for j in 0..n {
            let (k0, k1, first) = column(j);
            let cj = c[j];
            dc[j] *= cj;
            for (av, rv) in a[k0..k1].iter_mut().zip(&r[first..first + (k1 - k0)]) {
                *av *= rv * cj;
            }
            if !last {
                // the maxima of the next pass, from the freshly scaled column
                c[j] = row_col_max(&mut r_next[first..first + (k1 - k0)], &a[k0..k1]);
            }
        }
        for i in 0..n {
            dr[i] *= r[i];
        }
        r.copy_from_slice(r_next);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Ruiz scaling as first written (two sweeps per pass, `f64::max`, factors per entry):
    /// the reference for the fused, branch-free version.
    fn ruiz_reference(p: &Pattern, values: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let n = p.ndofs();
        let mut a = values.to_vec();
        let (mut dr, mut dc) = (vec![1.0; n], vec![1.0; n]);
        for _ in 0..RUIZ_PASSES {
            let (mut r, mut c) = (vec![0.0_f64; n], vec![0.0_f64; n]);
            for j in 0..n {
                for k in p.col_ptr()[j]..p.col_ptr()[j + 1] {
                    let v = a[k].abs();
                    r[p.row_idx()[k]] = r[p.row_idx()[k]].max(v);
                    c[j] = c[j].max(v);
                }
            }
            let inv_sqrt = |v: f64| if v > 0.0 { 1.0 / v.sqrt() } else { 1.0 };
            for j in 0..n {
                for k in p.col_ptr()[j]..p.col_ptr()[j + 1] {
                    a[k] *= inv_sqrt(r[p.row_idx()[k]]) * inv_sqrt(c[j]);
                }
            }
            for i in 0..n {
                dr[i] *= inv_sqrt(r[i]);
                dc[i] *= inv_sqrt(c[i]);
            }
        }
        (a, dr, dc)
    }

    #[test]
    fn ruiz_matches_the_reference_bit_for_bit() {
        for (elements, block) in [(3, 6), (7, 12), (1, 12)] {
            let p = Pattern::block_tridiagonal(elements + 1, block);
            // entries over many decades, some zero rows (identity rows after Dirichlet)
            let vals: Vec<f64> =
                (0..p.nnz()).map(|k| (k as f64 * 0.37).sin() * 10f64.powi((k % 13) as i32 - 6)).collect();
            let mut vals2 = vals.clone();
            p.set_identity_rows(&mut vals2, &[0, 2, block + 1]);
            for v in [vals, vals2] {
                let solver = LinearSolver::new(&p);
                assert_eq!(solver.equilibrate(&v), ruiz_reference(&p, &v));
            }
        }
    }

    #[test]
    fn set_identity_rows_matches_a_dense_rewrite() {
        let p = Pattern::block_tridiagonal(5, 12);
        let vals: Vec<f64> = (0..p.nnz()).map(|k| 1.0 + k as f64).collect();
        let rows = [0, 3, 11, 12, 30, 59];
        let mut v = vals.clone();
        p.set_identity_rows(&mut v, &rows);
        let mut expected = p.to_dense(&vals);
        for &r in &rows {
            expected.row_mut(r).fill(0.0);
            expected[(r, r)] = 1.0;
        }
        assert_eq!(p.to_dense(&v), expected);
    }

    /// The banded solver against faer's sparse LU (the solver it replaced) on a real KKT
    /// matrix of the inverse problem is in `tests/inverse_newton.rs`; here a random
    /// block-tridiagonal matrix with pivoting forced by zero diagonal blocks.
    #[test]
    fn banded_solver_matches_faer_sparse_lu() {
        use faer::linalg::solvers::SolveCore;
        use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
        use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
        let p = Pattern::block_tridiagonal(10, 12);
        // diagonally heavy, but the first diagonal entry of every node block is zero: the
        // elimination must pivot there
        let vals: Vec<f64> = (0..p.ndofs())
            .flat_map(|j| (p.col_ptr()[j]..p.col_ptr()[j + 1]).map(move |k| (j, k)))
            .map(|(j, k)| {
                let i = p.row_idx()[k];
                if i == j && i.is_multiple_of(12) {
                    0.0
                } else {
                    (0.7 * k as f64).sin() + if i == j { 12.0 } else { 0.0 }
                }
            })
            .collect();
        assert_eq!(vals.len(), p.nnz());
        let b = DVector::from_fn(p.ndofs(), |i, _| (0.3 * i as f64).cos());
        let x = LinearSolver::new(&p).solve(&vals, &b).unwrap();
        let sym =
            SymbolicSparseColMat::new_checked(p.ndofs(), p.ndofs(), p.col_ptr().to_vec(), None, p.row_idx().to_vec());
        let lu = Lu::try_new_with_symbolic(
            SymbolicLu::try_new(sym.as_ref()).unwrap(),
            SparseColMatRef::new(sym.as_ref(), &vals),
        )
        .unwrap();
        let mut y = b.clone();
        let n = y.len();
        lu.solve_in_place_with_conj(faer::Conj::No, faer::MatMut::from_column_major_slice_mut(y.as_mut_slice(), n, 1));
        let dense = p.to_dense(&vals);
        let scale = dense.norm() * x.norm();
        assert!((&dense * &x - &b).norm() <= 1e-14 * scale, "banded residual {:e}", (&dense * &x - &b).norm() / scale);
        let cond =
            dense.clone().svd(false, false).singular_values.max() / dense.svd(false, false).singular_values.min();
        assert!(
            (&x - &y).norm() <= 1e-12 * y.norm(),
            "banded vs faer {:e} (condition {cond:e})",
            (&x - &y).norm() / y.norm()
        );
    }

    #[test]
    fn pattern_scatter_and_solve() {
        let p = Pattern::block_tridiagonal(4, 6);
        let mut vals = vec![0.0; p.nnz()];
        // A diagonally dominant element matrix.
        let local = nalgebra::SMatrix::<f64, 12, 12>::from_fn(|i, j| {
            if i == j {
                10.0
            } else {
                1.0 / (1.0 + i as f64 + 2.0 * j as f64)
            }
        });
        for e in 0..3 {
            p.scatter(&mut vals, e, &local);
        }
        let dense = p.to_dense(&vals);
        let b = DVector::from_fn(p.ndofs(), |i, _| (i as f64).cos());
        let mut solver = LinearSolver::new(&p);
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
