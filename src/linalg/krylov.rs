//! Block Krylov subspaces with full reorthogonalisation, for the few extreme eigenpairs of an
//! operator given only by its action: the shift-invert operators of the modal and buckling
//! analyses (`docs/decisions.md`, D27, D28), each application one solve with a banded LU
//! factored once.
//!
//! ```text
//!   V = [v_1 … v_m]   B-orthonormal (Vᵀ B V = I),  v_{j+p} ∝ (I − V Vᵀ B) Op v_j   (block size p)
//!   Op V_m = V_{m+p} H̃,   H_m = H̃[0..m, 0..m] = V_mᵀ B Op V_m  (the Rayleigh–Ritz matrix)
//!   Ritz pair (θ, V_m y):  H_m y = θ y,  residual ‖Op V_m y − θ V_m y‖_B = ‖H̃[m..m+p, 0..m] y‖
//! ```
//! With `B` such that `Op` is `B`-self-adjoint (the mass matrix for `(K − σM)⁻¹M`), `H_m` is
//! symmetric: the Lanczos method, kept as a full Gram–Schmidt against every vector (twice,
//! "twice is enough": Kahan, Parlett, The Symmetric Eigenvalue Problem, 1980, §6.9), so that no
//! ghost copies appear. With `B = I` it is Arnoldi's method for any operator. The block size
//! `p` ≥ the multiplicity of the wanted eigenvalues: a single start vector sees one vector of
//! each eigenspace only (a round rod's bending frequencies are double).
//!
//! # References
//! 1. Y. Saad, *Numerical Methods for Large Eigenvalue Problems*, 2nd ed., SIAM (2011), §6.2
//!    (Arnoldi), §6.6 (Lanczos), §6.7 (block methods), §4.1 (shift-and-invert).
//! 2. R. G. Grimes, J. G. Lewis, H. D. Simon, *A shifted block Lanczos algorithm for solving
//!    sparse symmetric generalized eigenproblems*, SIAM J. Matrix Anal. Appl. 15 (1994) 228–272.
use nalgebra::{DMatrix, DVector};

use super::LinearError;

/// The operator `Op` of a [`Krylov`] basis: one application (a solve with factors).
type Operator<'a> = Box<dyn FnMut(&DVector<f64>) -> Result<DVector<f64>, LinearError> + 'a>;
/// The matrix `B` of a [`Krylov`] basis's inner product `uᵀ B v`, applied to a vector.
type InnerProduct<'a> = Box<dyn Fn(&DVector<f64>) -> DVector<f64> + 'a>;

/// A block Krylov basis being built: the vectors, their `B`-images and the coefficients `H̃`.
pub struct Krylov<'a> {
    op: Operator<'a>,
    inner: InnerProduct<'a>,
    /// `v_1 … v_{m+p}` (`B`-orthonormal)
    vectors: Vec<DVector<f64>>,
    /// `B v_i`
    images: Vec<DVector<f64>>,
    /// `H̃` by columns: column `j` holds the coefficients of `Op v_j` on `v_1 … v_{j+p}`
    columns: Vec<Vec<f64>>,
    block: usize,
    seed: u64,
    /// no direction is left outside the basis (the operator's range is spanned)
    exhausted: bool,
}

impl<'a> Krylov<'a> {
    /// Start a basis of block size `block` for `op` with the inner product `⟨u, v⟩ = uᵀ B v`
    /// (`inner` applies `B`) from pseudo-random vectors of length `n` mapped once through `op`
    /// (so that they lie in its range: zero on the unknowns a singular `B` leaves out).
    pub fn new(
        n: usize,
        block: usize,
        mut op: impl FnMut(&DVector<f64>) -> Result<DVector<f64>, LinearError> + 'a,
        inner: impl Fn(&DVector<f64>) -> DVector<f64> + 'a,
    ) -> Result<Self, LinearError> {
        let mut seed = 0x9E37_79B9_7F4A_7C15_u64;
        let mut starts = Vec::with_capacity(block);
        for _ in 0..block {
            let r = DVector::from_fn(n, |_, _| next_uniform(&mut seed));
            starts.push(op(&r)?);
        }
        let mut k = Krylov {
            op: Box::new(op),
            inner: Box::new(inner),
            vectors: Vec::new(),
            images: Vec::new(),
            columns: Vec::new(),
            block,
            seed,
            exhausted: false,
        };
        for s in starts {
            k.append(s, None);
        }
        Ok(k)
    }

    /// Vectors whose images have been taken (`m`; the basis holds `m + p`).
    pub fn dimension(&self) -> usize {
        self.columns.len()
    }

    /// The most `m` the operator's space allows (reached once its range is spanned).
    pub fn limit(&self) -> usize {
        if self.exhausted {
            return self.columns.len();
        }
        self.vectors.first().map_or(0, |v| v.len()).saturating_sub(self.block)
    }

    /// Take the images of the basis vectors until `m = to` (at most [`Krylov::limit`]).
    pub fn extend(&mut self, to: usize) -> Result<(), LinearError> {
        while !self.exhausted && self.columns.len() < to.min(self.limit()) {
            let j = self.columns.len();
            let w = (self.op)(&self.vectors[j])?;
            let mut coefficients = Vec::with_capacity(j + self.block + 1);
            self.append(w, Some(&mut coefficients));
            self.columns.push(coefficients);
        }
        Ok(())
    }

    /// Orthogonalise `w` against the basis (two passes of classical Gram–Schmidt in `B`),
    /// normalise it and append it; the coefficients (and the norm) go to `coefficients`. A `w`
    /// in the span (norm below 1e-10 of its start) is replaced by a fresh random direction,
    /// with a zero coefficient: the Krylov space is invariant and any new direction continues it.
    /// When no direction is left (the random one is in the span too), nothing is appended.
    fn append(&mut self, mut w: DVector<f64>, coefficients: Option<&mut Vec<f64>>) {
        let n = w.len();
        let start = (self.inner)(&w).dot(&w).max(0.0).sqrt();
        let mut h = vec![0.0; self.vectors.len()];
        for _ in 0..2 {
            for (i, (v, bv)) in self.vectors.iter().zip(&self.images).enumerate() {
                let c = bv.dot(&w);
                w.axpy(-c, v, 1.0);
                h[i] += c;
            }
        }
        let mut bw = (self.inner)(&w);
        let mut norm = bw.dot(&w).max(0.0).sqrt();
        let mut fresh = false;
        // (a NaN norm counts as none: the fresh direction replaces it)
        if norm.is_nan() || norm <= 1e-10 * start {
            let r = DVector::from_fn(n, |_, _| next_uniform(&mut self.seed));
            let r = (self.op)(&r).unwrap_or(r);
            let before = (self.inner)(&r).dot(&r).max(0.0).sqrt();
            self.append_direction(r, &mut bw, &mut norm, &mut w);
            fresh = true;
            if norm.is_nan() || norm <= 1e-10 * before {
                self.exhausted = true;
            }
        }
        if let Some(c) = coefficients {
            c.extend_from_slice(&h);
            c.push(if fresh { 0.0 } else { norm });
        }
        if self.exhausted {
            return;
        }
        self.vectors.push(w / norm);
        self.images.push(bw / norm);
    }

    /// A random direction orthogonalised against the basis, for [`Krylov::append`].
    fn append_direction(&self, mut r: DVector<f64>, bw: &mut DVector<f64>, norm: &mut f64, w: &mut DVector<f64>) {
        for _ in 0..2 {
            for (v, bv) in self.vectors.iter().zip(&self.images) {
                let c = bv.dot(&r);
                r.axpy(-c, v, 1.0);
            }
        }
        *bw = (self.inner)(&r);
        *norm = bw.dot(&r).max(f64::MIN_POSITIVE).sqrt();
        *w = r;
    }

    /// `H_m` (m × m), the Rayleigh–Ritz matrix `V_mᵀ B Op V_m`.
    pub fn rayleigh_ritz(&self) -> DMatrix<f64> {
        let m = self.columns.len();
        DMatrix::from_fn(m, m, |i, j| self.columns[j].get(i).copied().unwrap_or(0.0))
    }

    /// The residual `‖H̃[m..m+p, 0..m] y‖` of the Ritz vector `V_m y` (`‖y‖ = 1`).
    pub fn residual(&self, y: &DVector<f64>) -> f64 {
        let m = self.columns.len();
        let mut sq = 0.0;
        for i in m..m + self.block {
            let r: f64 = (0..m).map(|j| self.columns[j].get(i).copied().unwrap_or(0.0) * y[j]).sum();
            sq += r * r;
        }
        sq.sqrt()
    }

    /// The Ritz vector `V_m y` in the operator's space.
    pub fn ritz_vector(&self, y: &DVector<f64>) -> DVector<f64> {
        let mut x = DVector::zeros(self.vectors[0].len());
        for (v, c) in self.vectors.iter().zip(y.iter()) {
            x.axpy(*c, v, 1.0);
        }
        x
    }
}

/// A pseudo-random number in [−1, 1) (xorshift64*; deterministic, so runs repeat bit for bit).
fn next_uniform(state: &mut u64) -> f64 {
    *state ^= *state >> 12;
    *state ^= *state << 25;
    *state ^= *state >> 27;
    let bits = state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11;
    bits as f64 / (1u64 << 52) as f64 - 1.0
}

/// The `count` largest eigenvalues `θ` of a `B`-self-adjoint operator with their Ritz vectors
/// (`B`-orthonormal), descending, by block Lanczos: the basis grows by `4 (count + p)`
/// vectors at a time until every wanted pair's residual is at most `tolerance · θ_1`.
pub fn largest_symmetric(
    krylov: &mut Krylov,
    count: usize,
    tolerance: f64,
) -> Result<Vec<(f64, DVector<f64>)>, LinearError> {
    let step = 4 * (count + krylov.block);
    let mut m = step;
    loop {
        krylov.extend(m)?;
        let h = krylov.rayleigh_ritz();
        let h = (&h + h.transpose()) * 0.5;
        let eig = nalgebra::SymmetricEigen::new(h);
        let mut order: Vec<usize> = (0..eig.eigenvalues.len()).collect();
        order.sort_by(|&i, &j| eig.eigenvalues[j].total_cmp(&eig.eigenvalues[i]));
        order.truncate(count);
        let scale = order.first().map_or(0.0, |&i| eig.eigenvalues[i].abs());
        let done =
            order.iter().all(|&i| krylov.residual(&eig.eigenvectors.column(i).into_owned()) <= tolerance * scale);
        if done || krylov.dimension() >= krylov.limit() {
            return Ok(order
                .into_iter()
                .map(|i| (eig.eigenvalues[i], krylov.ritz_vector(&eig.eigenvectors.column(i).into_owned())))
                .collect());
        }
        m += step;
    }
}

/// The `count` largest positive real eigenvalues `ν` of any operator (`B = I`: Arnoldi) with
/// their Ritz vectors (unit norm), descending: the basis grows by `4 (count + p)` vectors at a
/// time until every wanted pair's residual is at most `tolerance · max |ν|`. A Ritz value is
/// real when `|Im ν| ≤ 1e-8 Re ν`, and counts only above `1e-12 max |ν|` (as the dense
/// analysis of `solve::stability` counts them).
pub fn largest_real_positive(
    krylov: &mut Krylov,
    count: usize,
    tolerance: f64,
) -> Result<Vec<(f64, DVector<f64>)>, LinearError> {
    let step = 4 * (count + krylov.block);
    let mut m = step;
    loop {
        krylov.extend(m)?;
        let h = krylov.rayleigh_ritz();
        let n = h.nrows();
        let f = faer::Mat::<f64>::from_fn(n, n, |i, j| h[(i, j)]);
        let values: Vec<(f64, f64)> = f.eigenvalues().map_or(Vec::new(), |v| v.iter().map(|z| (z.re, z.im)).collect());
        let scale = values.iter().map(|z| z.0.hypot(z.1)).fold(0.0, f64::max);
        let mut wanted: Vec<f64> =
            values.iter().filter(|z| z.0 > 1e-12 * scale && z.1.abs() <= 1e-8 * z.0).map(|z| z.0).collect();
        wanted.sort_by(|a, b| b.total_cmp(a));
        wanted.truncate(count);
        let pairs: Vec<(f64, DVector<f64>)> = wanted.iter().map(|&nu| (nu, null_vector(&h, nu))).collect();
        let done = pairs.len() == count && pairs.iter().all(|(_, y)| krylov.residual(y) <= tolerance * scale);
        if done || krylov.dimension() >= krylov.limit() {
            return Ok(pairs.into_iter().map(|(nu, y)| (nu, krylov.ritz_vector(&y))).collect());
        }
        m += step;
    }
}

/// The unit right singular vector of `H − ν I` of the smallest singular value.
fn null_vector(h: &DMatrix<f64>, nu: f64) -> DVector<f64> {
    let shifted = h - DMatrix::identity(h.nrows(), h.ncols()) * nu;
    let svd = shifted.svd(false, true);
    let (k, _) = svd.singular_values.argmin();
    svd.v_t.map_or_else(|| DVector::zeros(h.ncols()), |vt| vt.row(k).transpose())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pencil `K φ = λ M φ` of a 1D Laplacian `K = tridiag(−1, 2, −1)` and a lumped mass
    /// `M = m I`, twice (two uncoupled copies: every eigenvalue double). `Op = K⁻¹ M` is
    /// `M`-self-adjoint; its largest θ are the reciprocals of the smallest
    /// `λ_k = 4 sin²(kπ/(2(n+1)))/m`, each found twice by a block of two.
    #[test]
    fn lanczos_finds_double_eigenvalues_of_a_pencil() {
        let n = 200;
        let mass = 2.0;
        // two uncoupled copies of the Laplacian: each eigenvalue double
        let solve = |b: &DVector<f64>| -> DVector<f64> {
            // K⁻¹ (M b) for K = tridiag(−1, 2, −1) in each half (Thomas algorithm)
            let mut x = DVector::zeros(2 * n);
            for half in 0..2 {
                let rhs: Vec<f64> = (0..n).map(|i| mass * b[half * n + i]).collect();
                let (mut c, mut d) = (vec![0.0; n], vec![0.0; n]);
                for i in 0..n {
                    let den = 2.0 + if i > 0 { c[i - 1] } else { 0.0 };
                    c[i] = -1.0 / den;
                    d[i] = (rhs[i] + if i > 0 { d[i - 1] } else { 0.0 }) / den;
                }
                for i in (0..n).rev() {
                    x[half * n + i] = d[i] - c[i] * if i + 1 < n { x[half * n + i + 1] } else { 0.0 };
                }
            }
            x
        };
        let mut k = Krylov::new(2 * n, 2, |b| Ok(solve(b)), |v| v * mass).expect("start");
        let pairs = largest_symmetric(&mut k, 6, 1e-12).expect("lanczos");
        for (i, (theta, x)) in pairs.iter().enumerate() {
            let kk = (i / 2 + 1) as f64;
            let lambda = 4.0 * (kk * std::f64::consts::PI / (2.0 * (n as f64 + 1.0))).sin().powi(2) / mass;
            assert!((1.0 / theta / lambda - 1.0).abs() < 1e-10, "pair {i}: {} vs {lambda}", 1.0 / theta);
            assert!((x.dot(x) * mass - 1.0).abs() < 1e-10, "M-norm of the Ritz vector");
        }
    }
}
