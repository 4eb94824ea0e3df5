//! Stability of a static state and linearised buckling (`docs/decisions.md`, D27).
//!
//! Both work on Newton's matrix of the static equations `R(u, λ) = G(u) − λ F₁(u) = 0` (D3,
//! with the held rows of D22), `K(u, λ) = ∂R/∂u`:
//!
//! ```text
//!   stability of (u, λ):   M(u) φ̈ + K(u, λ) φ = 0 on the unknowns not held,  ω² = eig(M⁻¹K),
//!                          ω²_min = min Re ω² [1/s²]
//!   linearised buckling:   (K₀ + λ K_σ) φ = 0,  K₀ = K(u_ref, 0),  K_σ = d/dε K(u_ref + ε u₁, ε)|₀,  K₀ u₁ = ∂F/∂λ
//! ```
//! `M = ∂P/∂u̇` (D6). The paper's weak form tests the moment balance with δα (D9), in `K` and in
//! `M` alike, so `M⁻¹K` is similar to the virtual-work form's `M_s⁻¹ K_s` and its eigenvalues
//! do not depend on the angle chart: for dead loads `K_s` is the energy's Hessian, the `ω²` are
//! real, and `ω²_min ≤ 0` exactly when the second variation has a non-positive direction (an
//! unstable state). A measure against `K₀` alone (`K φ = μ K₀ φ`) is not chart-free: it is
//! negative on stable cantilevers bent by a dead load (measured on Bisshopp–Drucker, −0.93).
//! **Which loads.** In the angle chart the first-order change of `K` along `u₁` holds, besides
//! the stresses' geometric stiffness, the turning of the stiff axial and shear directions with the
//! sections (terms of order EA·α₁), which only the second order balances: for a transverse tip
//! load the linear eigenproblem gave a critical factor 0.30 where the rod stays stable to 1 and
//! beyond (`timoshenko_5pct`). So buckling is computed only where `u₁` turns no section
//! (`|α₁| ≤ 10⁻⁸ |x₁|/L`: columns under end forces or end shortening) and refused otherwise; a
//! path by arc length finds the critical points of any load (D25).
//! Follower loads, and moments (a dead moment of fixed axis is not conservative in 3D: Ziegler),
//! make `K_s` non-symmetric and can lose stability by flutter (complex `ω²`): `ω²_min` is then
//! reported without a verdict. `K_σ` is taken by central differences (ε such
//! that `‖ε u₁‖_w = 10⁻⁵`); the critical load factors are the reciprocals of the positive real
//! eigenvalues of `−K₀⁻¹ K_σ` and each mode is the null vector of `K₀ + λ_cr K_σ` (its smallest
//! singular vector). Held unknowns have identity rows in `K₀` and `K_σ = 0` there: no critical
//! load.
//!
//! Dense: up to [`DENSE_LIMIT`] unknowns (300 elements); above it the stability is not computed
//! (`None`) and buckling takes the banded matrices, `K₀` factored once and the lowest factors
//! by shift-invert block Arnoldi ([`buckling_sparse`], D28; the same factors to 1e-9, tests/buckling.rs).
use nalgebra::{DMatrix, DVector};

use super::arclength::{load_rate, newton_system, wnorm2};
use super::problem::{FrameAt, HeldRows};
use super::{Problem, SolveError};
use crate::assemble::Tangent;
use crate::linalg::{largest_real_positive, Krylov, LinearSolver};
use crate::model::mesh::Field;

/// The largest rotation of the sections in the linear pre-buckling response, relative to its
/// largest displacement over the rod length, for which the linearised buckling is computed.
pub const PREBUCKLING_TURN: f64 = 1e-8;

/// Most unknowns of the dense eigen-analyses (6 per node: 300 elements).
pub const DENSE_LIMIT: usize = 1806;

/// The stability of a static state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stability {
    /// `min Re ω²` of the rod linearised about the state [1/s²] (with unit inertias where the
    /// case has none: then only its sign is physical): ≤ 0 unstable
    pub smallest_eigenvalue_per_s2: f64,
    /// how many `μ` have a negative real part
    pub negative: usize,
    /// every load is dead (global frame, [`crate::model::loads::Loads::conservative`]): the
    /// sign of `μ_min` is a verdict; follower loads can lose stability by flutter, which no
    /// static eigenvalue sees
    pub conservative: bool,
}

impl Stability {
    /// Stable: the loads are conservative and every `ω²` is positive; `None` for
    /// non-conservative loads (follower loads and moments: a flutter has no static sign).
    pub fn stable(&self) -> Option<bool> {
        self.conservative.then_some(self.smallest_eigenvalue_per_s2 > 0.0)
    }
}

/// One buckling mode of the linearised problem.
#[derive(Clone, Debug)]
pub struct BucklingMode {
    /// the critical load factor `λ_cr` [-] (the case's loads times it buckle the rod)
    pub load_factor: f64,
    /// the mode: increments of the unknowns `(x, α)` in the problem's layout, scaled so that
    /// `‖φ‖_w = 1` (positions relative to the rod length) with its largest entry positive
    pub shape: DVector<f64>,
}

/// Errors of the eigen-analyses.
#[derive(Debug, thiserror::Error)]
pub enum StabilityError {
    #[error("{unknowns} unknowns: the dense eigen-analysis takes at most {limit} (300 elements)")]
    TooLarge { unknowns: usize, limit: usize },
    #[error("the linear response to the loads turns the sections (by {turn_rad:.3e} rad per unit load factor, against a displacement of {shift:.3e} rod lengths): linearised buckling about the reference is computed only for loads that compress or stretch the rod without turning it (a column, D27); follow the path with solver.continuation = \"arc_length\", whose critical_points.csv holds its limit and bifurcation points")]
    TurningPrebuckling { turn_rad: f64, shift: f64 },
    #[error("the unloaded rod's Newton matrix K0 is singular (a rigid-body motion is left free)")]
    SingularReference,
    #[error("the mass matrix is singular (the chart's singular set, cos β = 0, at a node?)")]
    SingularMass,
    #[error("the eigenvalues did not converge (QR iteration on {0} x {0})")]
    NoEigenvalues(usize),
    #[error(transparent)]
    Solve(#[from] SolveError),
}

/// `K(u, λ)` as a dense matrix.
fn dense_tangent(problem: &Problem, u: &DVector<f64>, lambda: f64) -> DMatrix<f64> {
    let pattern = problem.dofs().pattern();
    let mut values = vec![0.0; pattern.nnz()];
    newton_system(problem, u, lambda, &pattern, &mut values);
    pattern.to_dense(&values)
}

fn check_size(problem: &Problem) -> Result<usize, StabilityError> {
    let n = problem.dofs().len();
    if n > DENSE_LIMIT {
        return Err(StabilityError::TooLarge { unknowns: n, limit: DENSE_LIMIT });
    }
    Ok(n)
}

/// The eigenvalues (re, im) of a square matrix (faer's Hessenberg–Schur QR).
fn eigenvalues(m: DMatrix<f64>) -> Result<Vec<(f64, f64)>, StabilityError> {
    let n = m.nrows();
    let f = faer::Mat::<f64>::from_fn(n, n, |i, j| m[(i, j)]);
    let values = f.eigenvalues().map_err(|_| StabilityError::NoEigenvalues(n))?;
    Ok(values.iter().map(|z| (z.re, z.im)).collect())
}

/// The stability of the static state `u` at the problem's load factor (D27).
pub fn stability(problem: &Problem, u: &DVector<f64>) -> Result<Stability, StabilityError> {
    check_size(problem)?;
    let (w, negative) = lowest_frequency_squared(problem, u, problem.load_factor)?;
    Ok(Stability { smallest_eigenvalue_per_s2: w, negative, conservative: problem.loads.conservative() })
}

/// `min Re ω²` of the rod linearised about `(u, λ)`, `M(u) φ̈ + K(u, λ) φ = 0` on the unknowns
/// that are not held, and how many `ω²` have a negative real part.
fn lowest_frequency_squared(problem: &Problem, u: &DVector<f64>, lambda: f64) -> Result<(f64, usize), StabilityError> {
    let held = problem.clamped_dofs();
    let free: Vec<usize> = (0..problem.dofs().len()).filter(|i| !held.contains(i)).collect();
    let pick = |m: &DMatrix<f64>| DMatrix::from_fn(free.len(), free.len(), |i, j| m[(free[i], free[j])]);
    let k = pick(&dense_tangent(problem, u, lambda));
    let m = pick(&dense_mass(problem, u));
    let w2 = eigenvalues(m.lu().solve(&k).ok_or(StabilityError::SingularMass)?)?;
    let smallest = w2.iter().map(|z| z.0).fold(f64::INFINITY, f64::min);
    Ok((smallest, w2.iter().filter(|z| z.0 < 0.0).count()))
}

/// `∂P/∂u̇` at `u` (u̇ = 0, D6) with a twist-held pin's rows combined as the tangent's (D22). A
/// static case without inertias gets unit ones: ρA = 1 kg/m and ρI = (EI1, EI2, EI1 + EI2)/EA
/// (kg m; the radii of gyration of a homogeneous section), which move the `ω²` but not their
/// signs, and not the ratio `μ_min` along a straight path.
fn dense_mass(problem: &Problem, u: &DVector<f64>) -> DMatrix<f64> {
    let mut props = problem.props;
    if props.mass_per_length_kg_m <= 0.0 {
        let (j, ea) = (props.bend_twist_nm2, props.shear_stretch_n[2]);
        props.mass_per_length_kg_m = 1.0;
        props.rotary_inertia_kg_m = nalgebra::Vector3::new(j[0], j[1], j[0] + j[1]) / ea;
    }
    let p = Problem { props, ..*problem };
    let pattern = p.dofs().pattern();
    let mut values = vec![0.0; pattern.nnz()];
    let zero = p.dofs().zeros();
    p.momentum(u, &zero, Some((Tangent::new(&pattern, &mut values, 0.0), 1.0)));
    let mut r = p.dofs().zeros();
    p.apply_held(&pattern, Some(&mut values), &mut r, &p.held_static(), HeldRows::Values, FrameAt::of(u));
    pattern.to_dense(&values)
}

/// The lowest `count` positive critical load factors of the case's loads about the reference,
/// with their modes (D27), ascending: dense up to [`DENSE_LIMIT`] unknowns, above it by
/// shift-invert Arnoldi on the banded matrices ([`buckling_sparse`], D28).
pub fn buckling(problem: &Problem, count: usize) -> Result<Vec<BucklingMode>, StabilityError> {
    if problem.dofs().len() > DENSE_LIMIT {
        return buckling_sparse(problem, count);
    }
    let pattern = problem.dofs().pattern();
    let u0 = problem.reference_state();
    let k0 = dense_tangent(problem, &u0, 0.0);
    let q = load_rate(problem, &u0, 0.0, &pattern);
    let lu = k0.clone().lu();
    let u1 = lu.solve(&q).ok_or(StabilityError::SingularReference)?;
    let Some(eps) = prebuckling_step(problem, &u1)? else {
        return Ok(Vec::new()); // no load: nothing buckles
    };
    let kp = dense_tangent(problem, &(&u0 + &u1 * eps), eps);
    let km = dense_tangent(problem, &(&u0 - &u1 * eps), -eps);
    let k_sigma = (kp - km) / (2.0 * eps);
    let b = -lu.solve(&k_sigma).ok_or(StabilityError::SingularReference)?;
    let nu = eigenvalues(b)?;
    let mut factors: Vec<f64> = nu
        .iter()
        .filter(|z| {
            z.0 > 0.0 && z.1.abs() <= 1e-8 * z.0 && z.0 > 1e-12 * nu.iter().map(|z| z.0.abs()).fold(0.0, f64::max)
        })
        .map(|z| 1.0 / z.0)
        .collect();
    factors.sort_by(f64::total_cmp);
    factors.truncate(count);
    Ok(factors
        .into_iter()
        .map(|lambda| BucklingMode { load_factor: lambda, shape: mode_shape(problem, &k0, &k_sigma, lambda) })
        .collect())
}

/// The step `ε` (`‖ε u₁‖_w = 10⁻⁵`) of the central difference of `K_σ` along the linear
/// pre-buckling response `u₁` (`None`: no load), after checking that `u₁` turns no section
/// (module doc).
fn prebuckling_step(problem: &Problem, u1: &DVector<f64>) -> Result<Option<f64>, StabilityError> {
    let size = wnorm2(problem, u1, u1).sqrt();
    if size == 0.0 || !size.is_finite() {
        return Ok(None);
    }
    let dofs = problem.dofs();
    let (mut turn, mut shift) = (0.0_f64, 0.0_f64);
    for (i, v) in u1.iter().enumerate() {
        if dofs.field_of(i) == Field::X {
            shift = shift.max(v.abs() / problem.mesh.length_m);
        } else {
            turn = turn.max(v.abs());
        }
    }
    if turn > PREBUCKLING_TURN * shift {
        return Err(StabilityError::TurningPrebuckling { turn_rad: turn, shift });
    }
    Ok(Some(1e-5 / size))
}

/// Block size of the Arnoldi method of [`buckling_sparse`]: at least the multiplicity of the
/// wanted factors (a round column buckles alike in two planes).
pub const ARNOLDI_BLOCK: usize = 3;

/// A Ritz pair of [`buckling_sparse`] is converged when its residual is at most this times the
/// largest `|ν|`.
pub const ARNOLDI_TOLERANCE: f64 = 1e-10;

/// [`buckling`] on the banded matrices (D28): `K₀` factored once (the crate's banded LU with
/// Ruiz equilibration), `K_σ` by the same central difference, and the largest positive real
/// eigenvalues `ν` of `−K₀⁻¹ K_σ` by block Arnoldi with full reorthogonalisation
/// ([`crate::linalg::largest_real_positive`]); `λ_cr = 1/ν`, each mode the Ritz vector scaled
/// as [`mode_shape`] scales the dense null vector.
pub fn buckling_sparse(problem: &Problem, count: usize) -> Result<Vec<BucklingMode>, StabilityError> {
    let pattern = problem.dofs().pattern();
    let u0 = problem.reference_state();
    let mut k0 = vec![0.0; pattern.nnz()];
    newton_system(problem, &u0, 0.0, &pattern, &mut k0);
    let q = load_rate(problem, &u0, 0.0, &pattern);
    let mut solver = LinearSolver::new(&pattern);
    let u1 = solver.solve_equilibrated(&k0, &q).map_err(|_| StabilityError::SingularReference)?;
    let Some(eps) = prebuckling_step(problem, &u1)? else {
        return Ok(Vec::new());
    };
    let (mut kp, mut km) = (vec![0.0; pattern.nnz()], vec![0.0; pattern.nnz()]);
    newton_system(problem, &(&u0 + &u1 * eps), eps, &pattern, &mut kp);
    newton_system(problem, &(&u0 - &u1 * eps), -eps, &pattern, &mut km);
    let k_sigma: Vec<f64> = kp.iter().zip(&km).map(|(p, m)| (p - m) / (2.0 * eps)).collect();
    let op = |v: &DVector<f64>| solver.solve_factored(&-pattern.multiply(&k_sigma, v));
    let n = u0.len();
    let mut krylov = Krylov::new(n, ARNOLDI_BLOCK, op, |v: &DVector<f64>| v.clone()).map_err(SolveError::from)?;
    let pairs = largest_real_positive(&mut krylov, count, ARNOLDI_TOLERANCE).map_err(SolveError::from)?;
    Ok(pairs
        .into_iter()
        .map(|(nu, phi)| BucklingMode { load_factor: 1.0 / nu, shape: normalised(problem, phi) })
        .collect())
}

/// The null vector of `K₀ + λ K_σ`, scaled to `‖φ‖_w = 1` with its largest entry positive.
fn mode_shape(problem: &Problem, k0: &DMatrix<f64>, k_sigma: &DMatrix<f64>, lambda: f64) -> DVector<f64> {
    let svd = (k0 + k_sigma * lambda).svd(false, true);
    let vt = svd.v_t.expect("requested");
    let (k, _) = svd.singular_values.argmin();
    normalised(problem, vt.row(k).transpose())
}

/// A mode scaled to `‖φ‖_w = 1` with its largest entry (positions over L) positive, zero on
/// the held unknowns.
fn normalised(problem: &Problem, mut phi: DVector<f64>) -> DVector<f64> {
    // a held unknown does not move (its row of K₀ + λ K_σ is the identity's); the SVD leaves ~1e-8
    for d in problem.clamped_dofs() {
        phi[d] = 0.0;
    }
    let norm = wnorm2(problem, &phi, &phi).sqrt();
    phi /= norm;
    let dofs = problem.dofs();
    let scaled = |i: usize| if dofs.field_of(i) == Field::X { phi[i] / problem.mesh.length_m } else { phi[i] };
    let big = (0..phi.len()).max_by(|&i, &j| scaled(i).abs().total_cmp(&scaled(j).abs())).unwrap_or(0);
    if phi[big] < 0.0 {
        phi = -phi;
    }
    phi
}
