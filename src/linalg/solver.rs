//! Direct solver of the block-tridiagonal systems ([`Pattern`]): Ruiz equilibration
//! (`docs/inverse.md`, I6) and a banded LU with partial pivoting ([`BandLu`]).
//!
//! The values are copied once into the band (one pass per column: the pattern's rows, zeros
//! around them), equilibrated there and factored in place: no intermediate copy, no pass that
//! zeroes the whole band.
use nalgebra::DVector;

#[cfg(target_arch = "x86_64")]
use super::cpu::Avx2;
use super::{BandLu, LinearError, Pattern};

/// Passes of Ruiz equilibration.
const RUIZ_PASSES: usize = 5;

/// How the values are copied into the band ([`LinearSolver::load`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Load {
    /// as given
    Plain,
    /// times `dr_i dc_j`, the factors of the last equilibration
    Scaled,
    /// as given, with Ruiz's first row and column maxima taken from each column just copied
    WithMaxima,
}

/// Whether a column of a Ruiz pass also takes the maxima of the scaled values (every pass but
/// the last, whose maxima no pass needs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Maxima {
    Take,
    Skip,
}

/// The accumulated row and column factors `D_r`, `D_c` of a Ruiz equilibration.
struct Factors<'a> {
    rows: &'a mut [f64],
    columns: &'a mut [f64],
}

/// Where column `j` of the pattern lives: its first row, its length and where its first entry
/// sits in the CSC value array and in the band storage.
#[derive(Clone, Debug)]
struct Columns {
    first: Vec<usize>,
    len: Vec<usize>,
    csc: Vec<usize>,
    band: Vec<usize>,
}

/// Direct solver of the pattern's block-tridiagonal systems: a banded LU with partial
/// pivoting ([`BandLu`], `kl = ku = 2 block − 1`) whose storage and scratch are allocated once
/// per pattern; each solve copies the values into the band, factors and solves, without
/// allocating (apart from the returned vector).
pub struct LinearSolver {
    cols: Columns,
    lu: BandLu,
    /// row/column factors of the last equilibration, and scratch of [`ruiz`]
    dr: Vec<f64>,
    dc: Vec<f64>,
    rmax: Vec<f64>,
    cmax: Vec<f64>,
    rnext: Vec<f64>,
    /// the factors in `lu` are those of the scaled matrix `D_r M D_c` (an equilibrated or
    /// rescaled solve), so [`LinearSolver::solve_factored`] scales too
    scaled: bool,
}

impl LinearSolver {
    pub fn new(pattern: &Pattern) -> Self {
        let n = pattern.ndofs();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let lu = BandLu::block_tridiagonal(n / pattern.block(), pattern.block());
        let first: Vec<usize> =
            (0..n).map(|j| if col_ptr[j] < col_ptr[j + 1] { row_idx[col_ptr[j]] } else { j }).collect();
        debug_assert!(
            (0..n).all(|j| (col_ptr[j]..col_ptr[j + 1]).all(|k| row_idx[k] == first[j] + k - col_ptr[j])),
            "rows of a column must be contiguous"
        );
        let cols = Columns {
            len: (0..n).map(|j| col_ptr[j + 1] - col_ptr[j]).collect(),
            csc: col_ptr[..n].to_vec(),
            band: (0..n).map(|j| lu.index(first[j], j)).collect(),
            first,
        };
        LinearSolver {
            cols,
            lu,
            dr: vec![1.0; n],
            dc: vec![1.0; n],
            rmax: vec![0.0; n],
            cmax: vec![0.0; n],
            rnext: vec![0.0; n],
            scaled: false,
        }
    }

    /// Solve `M x = b` after Ruiz equilibration (`docs/inverse.md`, I6): five passes of
    /// row/column max-norm scaling `A ← diag(1/√r) A diag(1/√c)`, then `x = D_c y`. The factors
    /// are kept for [`LinearSolver::solve_rescaled`].
    pub fn solve_equilibrated(&mut self, values: &[f64], b: &DVector<f64>) -> Result<DVector<f64>, LinearError> {
        // the copy into the band also takes Ruiz's first row and column maxima (each column
        // while it is in cache), so `ruiz` starts with its first scaling
        self.load_with_maxima(values);
        let factors = Factors { rows: &mut self.dr, columns: &mut self.dc };
        ruiz(&self.cols, self.lu.band_mut(), factors, &mut self.rmax, &mut self.cmax, &mut self.rnext);
        let solved = self.factor_and_solve_scaled(b);
        self.unscaled_if_zero_pivot(solved, values, b)
    }

    /// A scaled factorisation that met an exactly zero pivot is tried once more on the matrix
    /// as given. Scaling rows and columns by powers that differ by 1e13 can turn the small
    /// remainder of an elimination into an exact zero that the unscaled elimination keeps
    /// (`docs/inverse.md`, I13: eq. (64) with Λκ3 = 1, which FreeFEM's UMFPACK solves too). A
    /// factorisation that succeeds is never redone, so results elsewhere are unchanged.
    fn unscaled_if_zero_pivot(
        &mut self,
        solved: Result<DVector<f64>, LinearError>,
        values: &[f64],
        b: &DVector<f64>,
    ) -> Result<DVector<f64>, LinearError> {
        match solved {
            Err(LinearError::ZeroPivot { .. }) => self.solve(values, b),
            other => other,
        }
    }

    /// Solve `M x = b` scaled by the row and column factors of the last
    /// [`LinearSolver::solve_equilibrated`] (`D_r M D_c y = D_r b`, `x = D_c y`): one pass
    /// instead of Ruiz's five, for a matrix close to the one they were computed for (the
    /// Jacobians of one Newton solve). Any positive diagonal scaling leaves the solution
    /// unchanged up to round-off; these keep the pivots as well-scaled as the equilibrated ones.
    pub fn solve_rescaled(&mut self, values: &[f64], b: &DVector<f64>) -> Result<DVector<f64>, LinearError> {
        self.load(values, Load::Scaled);
        let solved = self.factor_and_solve_scaled(b);
        self.unscaled_if_zero_pivot(solved, values, b)
    }

    /// Row factors `D_r` of the last [`LinearSolver::solve_equilibrated`].
    pub fn row_factors(&self) -> &[f64] {
        &self.dr
    }

    /// Ruiz equilibration of I6: returns `(D_r A D_c, D_r, D_c)` (values, row and column
    /// factors) after five passes of row/column max-norm scaling.
    pub fn equilibrate(&self, values: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let n = self.cols.len.len();
        let mut a = values.to_vec();
        let (mut dr, mut dc) = (vec![1.0; n], vec![1.0; n]);
        let (mut r, mut c, mut r_next) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let csc = Columns { band: self.cols.csc.clone(), ..self.cols.clone() };
        column_maxima(&csc, &a, &mut r, &mut c);
        ruiz(&csc, &mut a, Factors { rows: &mut dr, columns: &mut dc }, &mut r, &mut c, &mut r_next);
        (a, dr, dc)
    }

    /// Solve `M x = b` for the matrix with the pattern's structure and the given values.
    pub fn solve(&mut self, values: &[f64], b: &DVector<f64>) -> Result<DVector<f64>, LinearError> {
        self.load(values, Load::Plain);
        self.scaled = false;
        self.lu.factor_cleared()?;
        self.solve_factored(b)
    }

    /// The sign of the determinant of the matrix of the last solve (its scalings, when
    /// equilibrated, are positive).
    pub fn determinant_sign(&self) -> i8 {
        self.lu.determinant_sign()
    }

    /// Solve `M x = b` with the factors of the last solve (no copy, no factorisation: the
    /// matrix of that solve, e.g. a chord step's frozen Jacobian), scaled as that solve was
    /// (`x = D_c (D_r M D_c)⁻¹ D_r b` after an equilibrated or rescaled solve).
    pub fn solve_factored(&self, b: &DVector<f64>) -> Result<DVector<f64>, LinearError> {
        let mut x = if self.scaled { DVector::from_fn(b.len(), |i, _| b[i] * self.dr[i]) } else { b.clone() };
        self.lu.solve_in_place(x.as_mut_slice());
        if self.scaled {
            for (xi, d) in x.iter_mut().zip(&self.dc) {
                *xi *= d;
            }
        }
        if let Some(index) = x.iter().position(|v| !v.is_finite()) {
            return Err(LinearError::NonFinite { index });
        }
        Ok(x)
    }

    /// [`LinearSolver::load`] with the row maxima `|a_ij|` into `rmax` and the column maxima into
    /// `cmax` taken from each column just copied (the first sweep of [`ruiz`]: the same numbers
    /// in the same order, without a second pass over the band).
    fn load_with_maxima(&mut self, values: &[f64]) {
        self.rmax.iter_mut().for_each(|v| *v = 0.0);
        self.load(values, Load::WithMaxima);
    }

    /// Copy `values` (CSC, the pattern's order) into the band, column by column: the pattern's
    /// rows (times `dr_i dc_j` if [`Load::Scaled`]) and zeros in the rest of the column, the
    /// fill rows of the interchanges included (ready for [`BandLu::factor_cleared`]).
    fn load(&mut self, values: &[f64], how: Load) {
        let c = &self.cols;
        let ld = self.lu.ld();
        for (j, col) in self.lu.band_mut().chunks_exact_mut(ld).enumerate() {
            let (s, len, k0) = (c.band[j] - j * ld, c.len[j], c.csc[j]);
            col[..s].fill(0.0);
            let dst = &mut col[s..s + len];
            let src = &values[k0..k0 + len];
            if how == Load::Scaled {
                let (dr, dcj) = (&self.dr[c.first[j]..c.first[j] + len], self.dc[j]);
                for ((d, v), r) in dst.iter_mut().zip(src).zip(dr) {
                    *d = v * (r * dcj);
                }
            } else {
                dst.copy_from_slice(src);
            }
            if how == Load::WithMaxima {
                self.cmax[j] = row_col_max(&mut self.rmax[c.first[j]..c.first[j] + len], dst);
            }
            col[s + len..].fill(0.0);
        }
    }

    /// Factor the loaded (scaled) band and solve with `D_r b`, returning `D_c y`.
    fn factor_and_solve_scaled(&mut self, b: &DVector<f64>) -> Result<DVector<f64>, LinearError> {
        self.scaled = true;
        self.lu.factor_cleared()?;
        self.solve_factored(b)
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

/// `v ← 1/√v` for `v > 0`, else 1 (a row or column of zeros keeps its scale), element-wise:
/// Ruiz's factors of a pass. Compiled for AVX2 too (chosen at run time): square roots and
/// divisions are correctly rounded in every instruction set, so the same bits, four at a time.
fn inv_sqrt_all(v: &mut [f64]) {
    #[inline(always)]
    fn body(v: &mut [f64]) {
        for x in v.iter_mut() {
            *x = if *x > 0.0 { 1.0 / x.sqrt() } else { 1.0 };
        }
    }
    /// `body` compiled for AVX2.
    ///
    /// # Safety
    /// The CPU must have AVX2 (an [`Avx2`] token was made).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn wide(v: &mut [f64]) {
        body(v)
    }
    #[cfg(target_arch = "x86_64")]
    if Avx2::detect().is_some() {
        // SAFETY: an `Avx2` token was just made, so the CPU has AVX2.
        return unsafe { wide(v) };
    }
    body(v)
}

/// One column of a Ruiz pass with `L` rows: `a_i ← a_i (r_i c)`, then (with [`Maxima::Take`])
/// the maxima of the scaled column into `next` (row-wise) and the returned column maximum, as
/// [`row_col_max`] takes them.
#[inline(always)]
fn scale_column<const L: usize>(a: &mut [f64], r: &[f64], c: f64, next: &mut [f64], maxima: Maxima) -> f64 {
    let a: &mut [f64; L] = a.try_into().expect("L rows");
    let r: &[f64; L] = r.try_into().expect("L rows");
    for i in 0..L {
        a[i] *= r[i] * c;
    }
    match maxima {
        Maxima::Take => row_col_max(next, a),
        Maxima::Skip => 0.0,
    }
}

/// A column of a Ruiz pass that is not the last, four rows per instruction: `a_i ← a_i (r_i c)`,
/// `next_i ← max(next_i, |a_i|)`, and the column's maximum `|a_i|` returned, in one sweep (the
/// scaled values are not read back). The same products, each rounded once, and the same maxima
/// (`_mm256_max_pd(m, x)` keeps `x` where `m` is NaN, as `if m > x { m } else { x }` does).
///
/// # Safety
/// The CPU must have AVX2 (an [`Avx2`] token was made). The slice lengths are checked.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn scale_and_measure_avx2(a: &mut [f64], r: &[f64], c: f64, next: &mut [f64]) -> f64 {
    use std::arch::x86_64::{
        _mm256_andnot_pd, _mm256_loadu_pd, _mm256_max_pd, _mm256_mul_pd, _mm256_set1_pd, _mm256_setzero_pd,
        _mm256_storeu_pd,
    };
    let n = a.len();
    assert!(r.len() == n && next.len() == n, "one row factor and one maximum per entry");
    let (cv, sign) = (_mm256_set1_pd(c), _mm256_set1_pd(-0.0));
    let mut acc = _mm256_setzero_pd();
    let full = n / 4 * 4;
    // SAFETY (loads and stores): lanes i..i + 4 ≤ n of the three slices of length n.
    for i in (0..full).step_by(4) {
        let v =
            _mm256_mul_pd(_mm256_loadu_pd(a.as_ptr().add(i)), _mm256_mul_pd(_mm256_loadu_pd(r.as_ptr().add(i)), cv));
        _mm256_storeu_pd(a.as_mut_ptr().add(i), v);
        let m = _mm256_andnot_pd(sign, v);
        let x = next.as_mut_ptr().add(i);
        _mm256_storeu_pd(x, _mm256_max_pd(m, _mm256_loadu_pd(x)));
        acc = _mm256_max_pd(m, acc);
    }
    let mut lanes = [0.0_f64; 4];
    _mm256_storeu_pd(lanes.as_mut_ptr(), acc);
    let mut best = lanes.iter().fold(0.0_f64, |b, &m| if m > b { m } else { b });
    for i in full..n {
        let v = a[i] * (r[i] * c);
        a[i] = v;
        let m = v.abs();
        next[i] = if m > next[i] { m } else { next[i] };
        best = if m > best { m } else { best };
    }
    best
}

/// The row and column maxima of the unscaled values `a` (laid out as [`ruiz`] says) into `r`
/// and `c`: what [`ruiz`] starts from.
fn column_maxima(cols: &Columns, a: &[f64], r: &mut [f64], c: &mut [f64]) {
    r.iter_mut().for_each(|v| *v = 0.0);
    for j in 0..cols.len.len() {
        let (k0, k1, first) = (cols.band[j], cols.band[j] + cols.len[j], cols.first[j]);
        c[j] = row_col_max(&mut r[first..first + (k1 - k0)], &a[k0..k1]);
    }
}

/// Five passes of Ruiz row/column max-norm scaling of the values in `a` (column `j` of the
/// pattern at `a[cols.band[j]..][..cols.len[j]]`, rows from `cols.first[j]`), in place, with the
/// accumulated row and column factors in `factors`, from the row and column maxima of `a` in
/// `r`, `c` ([`column_maxima`], or taken while the values were copied into the band; `r_next`:
/// scratch). Each pass scales `a_ij ← a_ij (1/√r_i)(1/√c_j)` ([`ruiz_pass`]) and takes the
/// maxima of the next in the same sweep over the values.
fn ruiz(cols: &Columns, a: &mut [f64], factors: Factors<'_>, r: &mut [f64], c: &mut [f64], r_next: &mut [f64]) {
    let Factors { rows: dr, columns: dc } = factors;
    dr.iter_mut().for_each(|v| *v = 1.0);
    dc.iter_mut().for_each(|v| *v = 1.0);
    for pass in 0..RUIZ_PASSES {
        // the factors of this pass, 1/√r and 1/√c, once per row and column
        inv_sqrt_all(r);
        inv_sqrt_all(c);
        for (d, cj) in dc.iter_mut().zip(c.iter()) {
            *d *= cj;
        }
        let maxima = if pass + 1 == RUIZ_PASSES { Maxima::Skip } else { Maxima::Take };
        r_next.iter_mut().for_each(|v| *v = 0.0);
        ruiz_pass(cols, a, r, c, r_next, maxima);
        for (d, ri) in dr.iter_mut().zip(r.iter()) {
            *d *= ri;
        }
        r.copy_from_slice(r_next);
    }
}

/// One pass of [`ruiz`] over the columns: `a_ij ← a_ij r_i c_j` with this pass's factors `r`,
/// `c`, and (with [`Maxima::Take`]) the maxima of the scaled values into `r_next` (row-wise)
/// and `c` (column-wise) for the next pass. (The slices are arguments of their own: gathered in
/// a struct they lose the compiler's no-alias knowledge, 9.5 % more instructions here.)
fn ruiz_pass(cols: &Columns, a: &mut [f64], r: &[f64], c: &mut [f64], r_next: &mut [f64], maxima: Maxima) {
    #[cfg(target_arch = "x86_64")]
    let wide = Avx2::detect();
    for j in 0..cols.len.len() {
        // the rows of a column are contiguous (block-tridiagonal pattern): slices, no gathers
        let (k0, k1, first) = (cols.band[j], cols.band[j] + cols.len[j], cols.first[j]);
        let cj = c[j];
        let (a, rows, next) = (&mut a[k0..k1], &r[first..first + (k1 - k0)], &mut r_next[first..first + (k1 - k0)]);
        // the maxima of the next pass come from the freshly scaled column; the columns of
        // a block-tridiagonal pattern hold 2 or 3 blocks of rows (block 6 or 12): those
        // lengths have loops of fixed length
        #[cfg(target_arch = "x86_64")]
        if let (Maxima::Take, Some(_cpu)) = (maxima, wide) {
            // SAFETY: the `Avx2` token `_cpu` exists, so the CPU has AVX2.
            c[j] = unsafe { scale_and_measure_avx2(a, rows, cj, next) };
            continue;
        }
        let m = match a.len() {
            36 => scale_column::<36>(a, rows, cj, next, maxima),
            24 => scale_column::<24>(a, rows, cj, next, maxima),
            18 => scale_column::<18>(a, rows, cj, next, maxima),
            12 => scale_column::<12>(a, rows, cj, next, maxima),
            _ => {
                for (av, rv) in a.iter_mut().zip(rows) {
                    *av *= rv * cj;
                }
                match maxima {
                    Maxima::Take => row_col_max(next, a),
                    Maxima::Skip => 0.0,
                }
            }
        };
        if maxima == Maxima::Take {
            c[j] = m;
        }
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
                let mut solver = LinearSolver::new(&p);
                let reference = ruiz_reference(&p, &v);
                assert_eq!(solver.equilibrate(&v), reference);
                // the solver's own path (first maxima taken while loading the band) as well;
                // the factorisation itself may fail on these values, the factors exist before
                let _ = solver.solve_equilibrated(&v, &DVector::from_element(p.ndofs(), 1.0));
                assert_eq!((solver.row_factors(), &solver.dc[..]), (&reference.1[..], &reference.2[..]));
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
        assert_eq!(solver.solve_factored(&b).unwrap(), x);
        // Equilibration does not change the solution of a well-conditioned system.
        let xe = solver.solve_equilibrated(&vals, &b).unwrap();
        assert!((&xe - &x).amax() < 1e-12);
        // Nor does the last equilibration's scaling reused for a nearby matrix.
        let near: Vec<f64> = vals.iter().enumerate().map(|(k, v)| v * (1.0 + 1e-3 * (k as f64).sin())).collect();
        let xn = solver.solve(&near, &b).unwrap();
        let xr = solver.solve_rescaled(&near, &b).unwrap();
        assert!((&xr - &xn).amax() < 1e-12);
        // Identity rows.
        p.set_identity_rows(&mut vals, &[0, 5]);
        let x = solver.solve(&vals, &b).unwrap();
        assert!((x[0] - b[0]).abs() < 1e-14 && (x[5] - b[5]).abs() < 1e-14);
    }
}
