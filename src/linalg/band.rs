//! Banded LU with partial pivoting (Gaussian elimination with row interchanges, the algorithm
//! of LAPACK `dgbtf2`/`dgbtrs`) for the block-tridiagonal systems of the solvers.
//!
//! Every system matrix of the crate couples a node only with its neighbours: with `b`
//! unknowns per node it is block tridiagonal with `b × b` blocks, i.e. banded with
//! `kl = ku = 2b − 1`. Partial pivoting on the band is exactly Gaussian elimination with
//! partial pivoting on the full matrix (the pivot search runs over the whole sub-column, which
//! lies inside the band); row interchanges widen the upper band to `kl + ku`. Cost per
//! factorisation `O(n kl (kl + ku))`, no symbolic step, no allocation after construction.
//!
//! Storage (column-major, as LAPACK's `AB`): entry `(i, j)` lives at
//! `ab[j ld + kl + ku + i − j]`, `ld = 2 kl + ku + 1`; the first `kl` rows of each column
//! hold the fill of the interchanges.
use super::cpu::Avx2;
use super::LinearError;

/// A square band matrix and, after [`BandLu::factor`], its LU factors with the pivots.
#[derive(Clone, Debug)]
pub struct BandLu {
    n: usize,
    kl: usize,
    ku: usize,
    /// unknowns per node of a block-tridiagonal matrix (0: a general band): row `i` then has
    /// no entries beyond column `(i / block + 2) block − 1`, nor column `j` below that row,
    /// so elimination skips the band's structural zeros
    block: usize,
    ld: usize,
    ab: Vec<f64>,
    piv: Vec<usize>,
    /// [`BandLu::reach`] of every row, computed once (an integer division per call otherwise)
    reach: Vec<usize>,
}

impl BandLu {
    /// A zero `n × n` matrix with `kl` sub- and `ku` super-diagonals.
    pub fn new(n: usize, kl: usize, ku: usize) -> Self {
        let ld = 2 * kl + ku + 1;
        let reach = (0..n).map(|i| (i + kl).min(n.saturating_sub(1))).collect();
        BandLu { n, kl, ku, block: 0, ld, ab: vec![0.0; ld * n], piv: vec![0; n], reach }
    }

    /// A zero block-tridiagonal matrix of `nodes` × `nodes` blocks of size `block`
    /// (`kl = ku = 2 block − 1`). Its factorisation skips the structural zeros of the band:
    /// the same operations on the non-zeros, hence the same numbers as a general band.
    pub fn block_tridiagonal(nodes: usize, block: usize) -> Self {
        assert!(block > 0, "block size must be positive");
        let band = 2 * block - 1;
        let n = nodes * block;
        let reach = (0..n).map(|i| ((i / block + 2) * block - 1).min(n.saturating_sub(1))).collect();
        BandLu { block, reach, ..Self::new(n, band, band) }
    }

    /// Last row (or column) that row (or column) `i` can reach: `i + kl` for a general band,
    /// the end of the next node's block for a block-tridiagonal matrix.
    #[inline]
    fn reach(&self, i: usize) -> usize {
        self.reach[i]
    }

    pub fn n(&self) -> usize {
        self.n
    }

    /// Sub-diagonals `kl` (the first `kl` stored rows of every column are the fill of the
    /// interchanges).
    pub fn kl(&self) -> usize {
        self.kl
    }

    /// Stored length of a column, `2 kl + ku + 1`.
    pub fn ld(&self) -> usize {
        self.ld
    }

    /// Set every entry (and the fill area) to zero.
    pub fn clear(&mut self) {
        self.ab.iter_mut().for_each(|v| *v = 0.0);
    }

    /// Whether `(i, j)` lies inside the band.
    pub fn in_band(&self, i: usize, j: usize) -> bool {
        i < self.n && j < self.n && i <= j + self.kl && j <= i + self.ku
    }

    /// Storage index of the in-band entry `(i, j)`.
    #[inline]
    pub fn index(&self, i: usize, j: usize) -> usize {
        debug_assert!(self.in_band(i, j), "({i}, {j}) outside the band");
        j * self.ld + self.kl + self.ku + i - j
    }

    /// The band storage (LAPACK layout, see the module docs), e.g. to copy whole columns in.
    pub fn band_mut(&mut self) -> &mut [f64] {
        &mut self.ab
    }

    /// Set the in-band entry `(i, j)` (before [`BandLu::factor`]).
    #[inline]
    pub fn set(&mut self, i: usize, j: usize, v: f64) {
        let k = self.index(i, j);
        self.ab[k] = v;
    }

    /// Entry `(i, j)` of the stored matrix (0 outside the band).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        if self.in_band(i, j) {
            self.ab[self.index(i, j)]
        } else {
            0.0
        }
    }

    /// Factor in place, `P A = L U`, with partial pivoting (largest magnitude in the column).
    /// On x86-64 CPUs with AVX2 the rank-1 updates run four rows per instruction (eight with
    /// AVX-512, [`simd::update`]): the same multiplications and subtractions, so the same factors
    /// bit for bit.
    pub fn factor(&mut self) -> Result<(), LinearError> {
        // The fill rows (above the stored upper band) start at zero.
        let (kl, ld) = (self.kl, self.ld);
        for column in self.ab.chunks_exact_mut(ld) {
            column[..kl].fill(0.0);
        }
        self.factor_cleared()
    }

    /// [`BandLu::factor`] of a band whose fill rows (the first `kl` stored rows of every
    /// column) are zero already, e.g. written whole by the caller column by column.
    pub fn factor_cleared(&mut self) -> Result<(), LinearError> {
        #[cfg(target_arch = "x86_64")]
        if let Some(cpu) = Avx2::detect() {
            // SAFETY: the token `cpu` exists, so the CPU has AVX2.
            return unsafe { self.factor_avx2(cpu) };
        }
        self.factor_with(None)
    }

    /// [`BandLu::factor_cleared`] compiled for AVX2 (the divisions and interchanges too).
    ///
    /// # Safety
    /// The CPU must have AVX2 (`cpu` proves it: a token is only made after the check).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn factor_avx2(&mut self, cpu: Avx2) -> Result<(), LinearError> {
        self.factor_with(Some(cpu))
    }

    /// The body of [`BandLu::factor_cleared`]; `wide`: the AVX2 token where the CPU has AVX2.
    #[inline(always)]
    fn factor_with(&mut self, wide: Option<Avx2>) -> Result<(), LinearError> {
        let (n, ld) = (self.n, self.ld);
        let kv = self.kl + self.ku;
        // last column touched by an interchange so far (U's extent)
        let mut ju = 0usize;
        for j in 0..n {
            // rows below j with (structurally) non-zero entries in column j: j + 1..=j + km
            let km = self.reach(j) - j;
            let col = j * ld + kv;
            let (p, best) = pivot(&self.ab[col..=col + km]);
            self.piv[j] = j + p;
            if best == 0.0 || !best.is_finite() {
                return Err(LinearError::ZeroPivot { column: j, pivot: best });
            }
            // the pivot row reaches column j + p + ku (general band) or the end of the node
            // after its own (block tridiagonal)
            ju = ju.max(if self.block > 0 { self.reach(j + p) } else { (j + p + self.ku).min(n - 1) });
            if p != 0 {
                // interchange rows j and j + p in columns j..=ju: (j, c) and (j + p, c) sit at
                // c ld + kv + j − c and p further down the same column
                for c in j..=ju {
                    let k = c * ld + kv + j - c;
                    self.ab.swap(k, k + p);
                }
            }
            if km == 0 {
                continue;
            }
            let pivot = self.ab[col];
            let (head, tail) = self.ab.split_at_mut((j + 1) * ld);
            for v in &mut head[col + 1..col + 1 + km] {
                *v /= pivot;
            }
            // rank-1 update of the columns j + 1..=ju, rows j + 1..=j + km; for the usual
            // block sizes (6 and 12 unknowns per node: km from 6 to 11 and from 12 to 23) with
            // a fixed, unrolled length
            let at = Sweep { col, kv, ld, span: ju - j };
            macro_rules! fixed {
                ($($k:literal)*) => {
                    match (km, wide) {
                        $(($k, Some(cpu)) => simd::update::<$k>(cpu, head, tail, at),)*
                        $(($k, None) => update::<$k>(head, tail, at),)*
                        _ => update_any(head, tail, at, km),
                    }
                };
            }
            fixed!(6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23);
        }
        Ok(())
    }

    /// The sign of the determinant of the factored matrix (`P A = L U`: the signs of U's
    /// diagonal and of the permutation), +1 or −1.
    pub fn determinant_sign(&self) -> i8 {
        let kv = self.kl + self.ku;
        let mut negative = false;
        for j in 0..self.n {
            negative ^= self.ab[j * self.ld + kv] < 0.0;
            negative ^= self.piv[j] != j;
        }
        if negative {
            -1
        } else {
            1
        }
    }

    /// Solve `A x = b` in place with the factors of [`BandLu::factor`] (compiled for AVX2 too,
    /// chosen at run time; the same numbers).
    pub fn solve_in_place(&self, b: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        if Avx2::detect().is_some() {
            // SAFETY: an `Avx2` token was just made, so the CPU has AVX2.
            return unsafe { self.solve_avx2(b) };
        }
        self.solve_portable(b)
    }

    /// [`BandLu::solve_portable`] compiled for AVX2.
    ///
    /// # Safety
    /// The CPU must have AVX2 (an [`Avx2`] token was made).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn solve_avx2(&self, b: &mut [f64]) {
        self.solve_portable(b)
    }

    #[inline(always)]
    fn solve_portable(&self, b: &mut [f64]) {
        let (n, ld) = (self.n, self.ld);
        let kv = self.kl + self.ku;
        assert_eq!(b.len(), n, "right-hand side length");
        // L y = P b
        for j in 0..n {
            let p = self.piv[j];
            if p != j {
                b.swap(j, p);
            }
            let km = self.reach(j) - j;
            let bj = b[j];
            if bj != 0.0 {
                let l = &self.ab[j * ld + kv + 1..j * ld + kv + 1 + km];
                for (bi, li) in b[j + 1..j + 1 + km].iter_mut().zip(l) {
                    *bi -= li * bj;
                }
            }
        }
        // U x = y (U has kv super-diagonals)
        for j in (0..n).rev() {
            let col = j * ld + kv;
            b[j] /= self.ab[col];
            let bj = b[j];
            if bj != 0.0 {
                let lo = j.saturating_sub(kv);
                let u = &self.ab[col - (j - lo)..col];
                for (bi, ui) in b[lo..j].iter_mut().zip(u) {
                    *bi -= ui * bj;
                }
            }
        }
    }
}

/// Column length up to which [`pivot`] scans sequentially.
const SHORT_COLUMN: usize = 12;

/// The pivot of a column `v` (the diagonal entry first, then the rows below it): the first
/// entry of largest magnitude, and that magnitude; NaN entries are passed over, and a NaN on
/// the diagonal is kept (the caller reports it). As the sequential scan
/// `if |v_t| > best { best = |v_t|; p = t }` from `best = |v_0|`, in two passes: the maximum
/// in four independent lanes (the same value: `max` is exact and, over non-NaN values,
/// independent of order), then the first entry equal to it.
/// Up to [`SHORT_COLUMN`] entries (block size 6: at most 12 rows) the sequential scan itself is
/// faster.
#[inline]
fn pivot(v: &[f64]) -> (usize, f64) {
    let first = v[0].abs();
    if v.len() <= SHORT_COLUMN {
        let (mut p, mut best) = (0, first);
        for (t, x) in v.iter().enumerate().skip(1) {
            if x.abs() > best {
                best = x.abs();
                p = t;
            }
        }
        return (p, best);
    }
    let mut acc = [first; 4];
    let mut chunks = v[1..].chunks_exact(4);
    for c in &mut chunks {
        for l in 0..4 {
            let a = c[l].abs();
            acc[l] = if a > acc[l] { a } else { acc[l] };
        }
    }
    for x in chunks.remainder() {
        let a = x.abs();
        acc[0] = if a > acc[0] { a } else { acc[0] };
    }
    let mut best = acc[0];
    for a in &acc[1..] {
        best = if *a > best { *a } else { best };
    }
    if best.is_nan() || best == first {
        return (0, best);
    }
    let p = v.iter().position(|x| x.abs() == best).unwrap_or(0);
    (p, best)
}

/// Where a rank-1 update of [`BandLu::factor`] works in the band storage (`ld` values per
/// column, the diagonal at offset `kv`): the pivot column's diagonal at `col` of the `head`
/// slice, and the `span` columns after it at the start of the `tail` slice. Small and `Copy`, so
/// that the kernels take it in registers as they took its four numbers.
#[derive(Clone, Copy, Debug)]
struct Sweep {
    col: usize,
    kv: usize,
    ld: usize,
    span: usize,
}

/// [`update`] for any number `km` of rows below the pivot.
fn update_any(head: &[f64], tail: &mut [f64], at: Sweep, km: usize) {
    let Sweep { col, kv, ld, span } = at;
    let l = &head[col + 1..col + 1 + km];
    for (t, column) in tail.chunks_exact_mut(ld).take(span).enumerate() {
        let base = kv - 1 - t;
        let ujc = column[base];
        if ujc != 0.0 {
            for (d, li) in column[base + 1..base + 1 + km].iter_mut().zip(l) {
                *d -= li * ujc;
            }
        }
    }
}

/// The rank-1 update of [`BandLu::factor`] over the `span` columns after the pivot column
/// (`head` ends with it, its multipliers at `col + 1..`; `tail` holds the next columns), the `KL`
/// rows below the pivot row that can hold non-zeros.
#[inline]
fn update<const KL: usize>(head: &[f64], tail: &mut [f64], at: Sweep) {
    let Sweep { col, kv, ld, span } = at;
    let l: &[f64; KL] = head[col + 1..col + 1 + KL].try_into().expect("KL multipliers");
    for (t, column) in tail.chunks_exact_mut(ld).take(span).enumerate() {
        // column c = j + 1 + t: row j at kv + j − c
        let base = kv - 1 - t;
        let ujc = column[base];
        if ujc != 0.0 {
            let dst: &mut [f64; KL] = (&mut column[base + 1..base + 1 + KL]).try_into().expect("KL rows");
            for r in 0..KL {
                dst[r] -= l[r] * ujc;
            }
        }
    }
}

/// The rank-1 update of [`BandLu::factor`] with AVX2 (or AVX-512) vectors where the CPU has them.
mod simd;

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    /// Deterministic pseudo-random numbers in [−1, 1).
    fn rng(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        move || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        }
    }

    fn band_from_dense(a: &DMatrix<f64>, kl: usize, ku: usize) -> BandLu {
        let mut m = BandLu::new(a.nrows(), kl, ku);
        for j in 0..a.ncols() {
            for i in 0..a.nrows() {
                if m.in_band(i, j) {
                    m.set(i, j, a[(i, j)]);
                } else {
                    assert_eq!(a[(i, j)], 0.0);
                }
            }
        }
        m
    }

    /// The diagonal of a random test matrix: as random as the rest, or made dominant.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    enum Diagonal {
        Random,
        Dominant,
    }

    /// Random block-tridiagonal matrix (blocks `b`, `nb` blocks), its diagonal as `diagonal` says.
    fn block_tridiagonal(nb: usize, b: usize, seed: u64, diagonal: Diagonal) -> DMatrix<f64> {
        let mut r = rng(seed);
        let n = nb * b;
        DMatrix::from_fn(n, n, |i, j| {
            if (i / b).abs_diff(j / b) <= 1 {
                r() + if diagonal == Diagonal::Dominant && i == j { 4.0 * b as f64 } else { 0.0 }
            } else {
                0.0
            }
        })
    }

    #[test]
    fn determinant_sign_is_the_dense_determinant_s() {
        for seed in 0..20 {
            let a = block_tridiagonal(5, 3, 100 + seed, Diagonal::Random);
            let mut lu = band_from_dense(&a, 5, 5);
            lu.factor().expect("factor");
            let det = a.clone().determinant();
            assert!(det.abs() > 1e-12);
            assert_eq!(lu.determinant_sign(), if det < 0.0 { -1 } else { 1 }, "seed {seed}: det {det:e}");
        }
    }

    fn check(a: &DMatrix<f64>, kl: usize, ku: usize, seed: u64) -> DVector<f64> {
        let mut lu = band_from_dense(a, kl, ku);
        solve_and_check(a, &mut lu, seed)
    }

    fn solve_and_check(a: &DMatrix<f64>, lu: &mut BandLu, seed: u64) -> DVector<f64> {
        let n = a.nrows();
        let mut r = rng(seed);
        let b = DVector::from_fn(n, |_, _| r());
        lu.factor().expect("factor");
        let mut x = b.clone();
        lu.solve_in_place(x.as_mut_slice());
        let res = (a * &x - &b).norm() / (a.norm() * x.norm() + b.norm());
        assert!(res <= 1e-15, "relative residual {res:e}");
        let dense = a.clone().lu().solve(&b).expect("dense LU");
        let diff = (&x - &dense).norm() / dense.norm();
        assert!(diff <= 1e-12, "banded vs dense LU {diff:e}");
        x
    }

    /// The block-tridiagonal layout (structural zeros skipped) gives bit for bit the solution
    /// of the general band.
    fn check_blocks(a: &DMatrix<f64>, b: usize, seed: u64) {
        let general = check(a, 2 * b - 1, 2 * b - 1, seed);
        let mut lu = BandLu::block_tridiagonal(a.nrows() / b, b);
        for j in 0..a.ncols() {
            for i in 0..a.nrows() {
                if lu.in_band(i, j) {
                    lu.set(i, j, a[(i, j)]);
                }
            }
        }
        let blocks = solve_and_check(a, &mut lu, seed);
        assert_eq!(general, blocks);
    }

    #[test]
    fn random_block_tridiagonal_systems_match_dense_lu() {
        for (nb, b, seed) in [(1, 6, 1), (2, 6, 2), (17, 6, 3), (9, 12, 4), (40, 12, 5), (3, 1, 6), (50, 2, 7)] {
            check_blocks(&block_tridiagonal(nb, b, seed, Diagonal::Dominant), b, seed + 100);
            // Not diagonally dominant: pivoting is exercised.
            check_blocks(&block_tridiagonal(nb, b, seed + 50, Diagonal::Random), b, seed + 200);
        }
    }

    /// The AVX2 and AVX-512 variants (where this CPU has them) give the portable code's factors, pivots and
    /// solutions bit for bit, with and without interchanges, for every row count of the unrolled
    /// updates (block sizes 6 and 12: 6..=23 rows below a pivot) and a general band.
    #[test]
    fn wide_and_portable_factors_agree_bit_for_bit() {
        for (nb, b, seed) in [(17, 6, 31), (40, 12, 32), (9, 12, 33), (50, 2, 34)] {
            for diagonal in [Diagonal::Dominant, Diagonal::Random] {
                let a = block_tridiagonal(nb, b, seed, diagonal);
                let mut wide = BandLu::block_tridiagonal(nb, b);
                for j in 0..a.ncols() {
                    for i in 0..a.nrows() {
                        if wide.in_band(i, j) {
                            wide.set(i, j, a[(i, j)]);
                        }
                    }
                }
                let mut portable = wide.clone();
                let mut general = band_from_dense(&a, 2 * b - 1, 2 * b - 1);
                let mut general_portable = general.clone();
                wide.factor().expect("factor");
                portable.factor_with(None).expect("portable factor");
                general.factor().expect("factor");
                general_portable.factor_with(None).expect("portable factor");
                assert_eq!((&wide.ab, &wide.piv), (&portable.ab, &portable.piv), "{nb}×{b}, {diagonal:?}");
                assert_eq!((&general.ab, &general.piv), (&general_portable.ab, &general_portable.piv));
                let mut r = rng(seed + 7);
                let rhs: Vec<f64> = (0..a.nrows()).map(|_| r()).collect();
                let (mut x, mut y) = (rhs.clone(), rhs);
                wide.solve_in_place(&mut x);
                portable.solve_portable(&mut y);
                assert_eq!(x, y);
            }
        }
    }

    /// The two-pass pivot search against the sequential scan it replaced, on columns with
    /// ties, zeros of both signs, infinities and NaNs anywhere.
    #[test]
    fn pivot_search_matches_the_sequential_scan() {
        let scan = |v: &[f64]| {
            let (mut p, mut best) = (0, v[0].abs());
            for (t, x) in v.iter().enumerate().skip(1) {
                if x.abs() > best {
                    best = x.abs();
                    p = t;
                }
            }
            (p, best)
        };
        let specials = [0.0, -0.0, 1.0, -1.0, 0.5, f64::INFINITY, f64::NEG_INFINITY, f64::NAN, 1e-300];
        let mut r = rng(41);
        for len in 1..=24 {
            for _ in 0..400 {
                let v: Vec<f64> = (0..len)
                    .map(|_| {
                        let u = r();
                        if u > 0.5 {
                            specials[((u * 1e6) as usize) % specials.len()]
                        } else {
                            (u * 8.0).round() / 4.0
                        }
                    })
                    .collect();
                let (a, b) = (pivot(&v), scan(&v));
                assert!(a.0 == b.0 && a.1.to_bits() == b.1.to_bits(), "{v:?}: {a:?} vs {b:?}");
            }
        }
    }

    #[test]
    fn zero_leading_diagonal_needs_pivoting() {
        // [[0, 1], [1, 0]] ⊕ ...: elimination without interchanges fails at the first pivot.
        let mut a = block_tridiagonal(8, 3, 9, Diagonal::Random);
        a[(0, 0)] = 0.0;
        a[(4, 4)] = 0.0;
        check_blocks(&a, 3, 11);
        let p = DMatrix::from_row_slice(3, 3, &[0.0, 1.0, 0.0, 1.0, 0.0, 2.0, 0.0, 3.0, 1.0]);
        check(&p, 2, 2, 12);
        let mut lu = band_from_dense(&p, 2, 2);
        lu.factor().expect("factor");
        assert_eq!(lu.piv[0], 1, "the first pivot must come from row 1");
    }

    #[test]
    fn singular_matrix_is_an_error() {
        let a = DMatrix::from_row_slice(3, 3, &[1.0, 2.0, 0.0, 2.0, 4.0, 0.0, 0.0, 0.0, 1.0]);
        let mut lu = band_from_dense(&a, 2, 2);
        assert!(matches!(lu.factor(), Err(LinearError::ZeroPivot { column: 1, .. })), "{:?}", lu.factor());
    }
}
