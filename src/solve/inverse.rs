//! Inverse problem of one frame: Problem 1 (41)–(43) solved by the monolithic fixed point of
//! Problem 2, eq. (61), with the corrections and readings of `docs/inverse.md` (I1–I6).
//!
//! ```text
//!   ⎡ H_k   L_kᵀ ⎤ ⎡u⎤   ⎡h_k⎤     u = (x, α) state, û = (x̂, α̂) adjoint,
//!   ⎣ L_k   −C   ⎦ ⎣û⎦ = ⎣b_k⎦     f = x̂/λf, l = α̂/λl (eq. 54)
//! ```
//! `L_k`, `b_k`: the frozen operator of the forward fixed point (D5). `H_k`: the objective's
//! second-order terms with `d3` linearised as in (60) and the corrected sign of the λd term.
//! `C`: control mass matrices `(1/λf) M`, `(1/λl) M`. State relaxed with w (Remark 10).
//!
//! ## References
//! 1. Wang et al., Comput. Mech. 71 (2023), §3–4, eqs. (41), (52)–(61), Remark 6, Remark 10.
#![allow(non_snake_case)]
use nalgebra::{DVector, Matrix3, SMatrix, SVector, Vector3};

use super::statics::relative_change;
use super::{Problem, SolveError};
use crate::assembly::{LinearSolver, Pattern};
use crate::element::{frozen_operator, interpolate, LocalVec};
use crate::mesh::GAUSS2;
use crate::rotation::{a_matrix, d3, rotation_derivatives};

/// Unknowns per node of the KKT system: `[x, α, x̂, α̂]`.
pub const BLOCK: usize = 12;
pub(crate) type KktMat = SMatrix<f64, 24, 24>;
pub(crate) type KktVec = SVector<f64, 24>;

/// Regularisation weights of eq. (41) and the iteration settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InverseParams {
    /// λg [1/m³·…]: weight of the tracking term
    pub lambda_g: f64,
    pub lambda_f: f64,
    pub lambda_l: f64,
    pub lambda_d: f64,
    /// Λκ diagonal
    pub lambda_kappa: Vector3<f64>,
    /// Λω diagonal (applied from the second frame on)
    pub lambda_omega: Vector3<f64>,
    /// frame interval Δt [s]
    pub dt: f64,
    /// first frame: α(0) = `alpha0` on the first angle and no Λω term (Remark 6)
    pub first_frame: bool,
    /// Dirichlet value of the first angle α at s = 0 on the first frame [rad]; 0 in Remark 6,
    /// the rotation angle about e3 when the data are rotated rigidly about e3 (invariance).
    pub alpha0: f64,
    /// frame index, used in error messages only
    pub frame: usize,
    /// weight ε ∈ [0, 1] of the two-point rule in the λd term (I11): the term is integrated
    /// with (1 − ε)·(the stretch–shear rule, D4) + ε·(2-point Gauss). 0 is the paper's element;
    /// ε > 0 penalises the nodal zig-zag of the angles that the one-point rule cannot see.
    pub stabilisation: f64,
    pub relaxation: f64,
    pub tolerance: f64,
    pub max_iterations: usize,
}

/// Per-iteration record (`docs/inverse.md`): relative change of (x, α) (D5),
/// ‖x − x_g‖/‖x_g‖ and ‖∂s x − d3‖ [L² norm, m^½] at the relaxed iterate, and the terms of
/// the objective (41) at that iterate with the controls of the last solve.
#[derive(Clone, Copy, Debug)]
pub struct InverseRecord {
    pub iteration: usize,
    pub rel_change: f64,
    pub x_err_rel: f64,
    pub tangent_misfit: f64,
    pub objective: ObjectiveTerms,
    /// Newton only (`docs/inverse.md`, I8): equilibrated KKT residual `‖D_r R(U)‖₂` after the
    /// step, relative to its value at the start of Newton; `None` for the fixed point
    pub residual: Option<f64>,
}

/// The six terms of the objective (41), each with its weight and the ½, with the
/// integration rules of I2.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ObjectiveTerms {
    /// λg/2 ∫|x − x_g|²
    pub tracking: f64,
    /// λf/2 ∫|f|², f = x̂/λf (eq. 54)
    pub force: f64,
    /// λl/2 ∫|l|², l = α̂/λl (eq. 54)
    pub torque: f64,
    /// λd/2 ∫|∂s x − d3|²
    pub shear: f64,
    /// ½ ∫ κᵀ Λκ κ, κ = A ∂sα (eq. 28)
    pub bending: f64,
    /// ½ ∫ ωᵀ Λω ω, ω = A (α − α_{n−1})/Δt (eq. 27, backward difference; 0 on the first frame)
    pub angular: f64,
}

impl ObjectiveTerms {
    pub fn total(&self) -> f64 {
        self.tracking + self.force + self.torque + self.shear + self.bending + self.angular
    }
    /// Names in CSV order, with units (J = the objective's unit).
    pub const NAMES: [&'static str; 7] =
        ["j_tracking", "j_force", "j_torque", "j_shear", "j_bending", "j_angular", "j_total"];
    pub fn values(&self) -> [f64; 7] {
        [self.tracking, self.force, self.torque, self.shear, self.bending, self.angular, self.total()]
    }
}

/// Converged frame.
#[derive(Clone, Debug)]
pub struct InverseSolution {
    /// state `(x, α)`, 6 per node
    pub u: DVector<f64>,
    /// adjoint `(x̂, α̂)`, 6 per node (last solve)
    pub adjoint: DVector<f64>,
    pub history: Vec<InverseRecord>,
}

/// Points and weights of the λd term's rule (I11): `(1 − ε)` times the stretch–shear rule of
/// the scheme plus `ε` times 2-point Gauss (the same rule when the scheme is already full).
pub fn tangent_rule(problem: &Problem, p: &InverseParams) -> Vec<(f64, f64)> {
    tangent_points(problem, p).iter().collect()
}

/// [`tangent_rule`] without allocation (at most 2 + 2 points), for the element loops.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PointRule {
    points: [(f64, f64); 4],
    len: usize,
}

impl PointRule {
    pub(crate) fn iter(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.points[..self.len].iter().copied()
    }
}

pub(crate) fn tangent_points(problem: &Problem, p: &InverseParams) -> PointRule {
    let base = problem.scheme.stretch_shear();
    let eps = p.stabilisation;
    let mut rule = PointRule { points: [(0.0, 0.0); 4], len: 0 };
    let mut push = |x: f64, w: f64| {
        if w != 0.0 {
            rule.points[rule.len] = (x, w);
            rule.len += 1;
        }
    };
    for (x, w) in base.points.iter().zip(base.weights) {
        push(*x, w * (1.0 - eps));
    }
    if eps > 0.0 {
        for (x, w) in GAUSS2.points.iter().zip(GAUSS2.weights) {
            push(*x, w * eps);
        }
    }
    rule
}

/// Map a forward local index (`[x_a, α_a, x_b, α_b]`) to the KKT local index; `hat` selects
/// the adjoint copy.
pub(crate) fn kkt(i: usize, hat: bool) -> usize {
    BLOCK * (i / 6) + i % 6 + if hat { 6 } else { 0 }
}

/// `∂d3/∂α = [0 | d_β | d_γ]` (eqs. 56–58).
pub(crate) fn d3_jacobian(alpha: &Vector3<f64>) -> Matrix3<f64> {
    let dq = rotation_derivatives(alpha);
    Matrix3::from_columns(&[dq[0].row(2).transpose(), dq[1].row(2).transpose(), dq[2].row(2).transpose()])
}

/// Local KKT matrix and right-hand side of one element (I4).
pub(crate) fn element_system(
    problem: &Problem,
    p: &InverseParams,
    uk: &LocalVec,
    xg: [Vector3<f64>; 2],
    alpha_prev: [Vector3<f64>; 2],
) -> (KktMat, KktVec) {
    let h = problem.mesh.h();
    let mut m = KktMat::zeros();
    let mut r = KktVec::zeros();
    // Frozen operator: primal rows (hat test) × state columns, and its transpose.
    let (l, b) = frozen_operator(&problem.props, problem.scheme, h, uk);
    for i in 0..12 {
        r[kkt(i, true)] += b[i];
        for j in 0..12 {
            m[(kkt(i, true), kkt(j, false))] += l[(i, j)];
            m[(kkt(j, false), kkt(i, true))] += l[(i, j)];
        }
    }
    let add3 = |m: &mut KktMat, ro: usize, co: usize, blk: &Matrix3<f64>| {
        for i in 0..3 {
            for j in 0..3 {
                m[(ro + i, co + j)] += blk[(i, j)];
            }
        }
    };
    let (X, AL, XH, ALH) = ([0, 12], [3, 15], [6, 18], [9, 21]);
    let omega_on = !p.first_frame && p.lambda_omega.amax() > 0.0;
    // Mass-type terms (load rule): tracking, control costs, Λω.
    for (xi, w) in GAUSS2.points.iter().zip(GAUSS2.weights) {
        let q = interpolate(uk, h, *xi);
        let n = q.n;
        let wh = w * h;
        let xg_q = xg[0] * n[0] + xg[1] * n[1];
        let ap_q = alpha_prev[0] * n[0] + alpha_prev[1] * n[1];
        let W = if omega_on {
            let A = a_matrix(&q.alpha);
            A.transpose() * Matrix3::from_diagonal(&p.lambda_omega) * A / (p.dt * p.dt)
        } else {
            Matrix3::zeros()
        };
        for a in 0..2 {
            for i in 0..3 {
                r[X[a] + i] += wh * n[a] * p.lambda_g * xg_q[i];
            }
            let wa = W * ap_q * (wh * n[a]);
            for i in 0..3 {
                r[AL[a] + i] += wa[i];
            }
            for c in 0..2 {
                let nn = wh * n[a] * n[c];
                add3(&mut m, X[a], X[c], &(Matrix3::identity() * (p.lambda_g * nn)));
                add3(&mut m, XH[a], XH[c], &(Matrix3::identity() * (-nn / p.lambda_f)));
                add3(&mut m, ALH[a], ALH[c], &(Matrix3::identity() * (-nn / p.lambda_l)));
                add3(&mut m, AL[a], AL[c], &(W * nn));
            }
        }
    }
    // λd term (its rule, I11): λd ∫ (∂sδx − D δα)·(∂s x − D α − d3^k + D α_k).
    for (xi, w) in tangent_points(problem, p).iter() {
        let q = interpolate(uk, h, xi);
        let wh = w * h * p.lambda_d;
        let D = d3_jacobian(&q.alpha);
        let c = d3(&q.alpha) - D * q.alpha;
        for a in 0..2 {
            let ta = [Matrix3::identity() * q.dn[a], -D * q.n[a]]; // test operator blocks (x, α)
            for i in 0..3 {
                r[X[a] + i] += wh * (ta[0].transpose() * c)[i];
                r[AL[a] + i] += wh * (ta[1].transpose() * c)[i];
            }
            for cc in 0..2 {
                let tc = [Matrix3::identity() * q.dn[cc], -D * q.n[cc]];
                for (ra, ro) in [(0, X[a]), (1, AL[a])] {
                    for (ca, co) in [(0, X[cc]), (1, AL[cc])] {
                        add3(&mut m, ro, co, &(ta[ra].transpose() * tc[ca] * wh));
                    }
                }
            }
        }
    }
    // Λκ term (bending rule): ∫ ∂sδα · Aᵀ Λκ A ∂sα.
    if p.lambda_kappa.amax() > 0.0 {
        let rule = problem.scheme.bending();
        for (xi, w) in rule.points.iter().zip(rule.weights) {
            let q = interpolate(uk, h, *xi);
            let A = a_matrix(&q.alpha);
            let Kk = A.transpose() * Matrix3::from_diagonal(&p.lambda_kappa) * A * (w * h);
            for a in 0..2 {
                for c in 0..2 {
                    add3(&mut m, AL[a], AL[c], &(Kk * (q.dn[a] * q.dn[c])));
                }
            }
        }
    }
    (m, r)
}

/// Solve one frame from the initial state `u0` (6 per node). `x_g`: data positions per node;
/// `alpha_prev`: previous frame's angles per node (unused at the first frame).
pub fn solve_frame(
    problem: &Problem,
    p: &InverseParams,
    x_g: &[Vector3<f64>],
    alpha_prev: &[Vector3<f64>],
    u0: &DVector<f64>,
    mut progress: impl FnMut(&InverseRecord),
) -> Result<InverseSolution, SolveError> {
    solve_frame_observed(problem, p, x_g, alpha_prev, u0, |r, _, _| progress(r))
}

/// [`solve_frame`] whose callback also sees the relaxed state `(x, α)` and the adjoint
/// `(x̂, α̂)` (6 per node each) of each iteration, e.g. to follow the curvature error against
/// known data or to keep the last iterate of a run that fails.
pub fn solve_frame_observed(
    problem: &Problem,
    p: &InverseParams,
    x_g: &[Vector3<f64>],
    alpha_prev: &[Vector3<f64>],
    u0: &DVector<f64>,
    progress: impl FnMut(&InverseRecord, &DVector<f64>, &DVector<f64>),
) -> Result<InverseSolution, SolveError> {
    solve_frame_observed_in(&mut InverseWorkspace::new(problem)?, problem, p, x_g, alpha_prev, u0, progress)
}

/// [`solve_frame_observed`] in a workspace made once per mesh (e.g. once per clip) and reused
/// for every frame: no symbolic set-up and no allocation of the system per frame.
#[allow(clippy::too_many_arguments)]
pub fn solve_frame_observed_in(
    ws: &mut InverseWorkspace,
    problem: &Problem,
    p: &InverseParams,
    x_g: &[Vector3<f64>],
    alpha_prev: &[Vector3<f64>],
    u0: &DVector<f64>,
    mut progress: impl FnMut(&InverseRecord, &DVector<f64>, &DVector<f64>),
) -> Result<InverseSolution, SolveError> {
    ws.check(problem)?;
    ws.set_dirichlet(p, x_g);
    let mut u = u0.clone();
    let mut history = Vec::new();
    for k in 1..=p.max_iterations {
        let sol = ws.solve_at(problem, p, &u, x_g, alpha_prev)?;
        let (u_new, adjoint) = (part(&sol, false), part(&sol, true));
        let u_next = &u_new * p.relaxation + &u * (1.0 - p.relaxation);
        let rel_change = relative_change(&u_next, &u);
        u = u_next;
        if !rel_change.is_finite() || u.iter().chain(adjoint.iter()).any(|v| !v.is_finite()) {
            return Err(SolveError::InverseNonFinite { frame: p.frame, iteration: k });
        }
        let rec = record(problem, p, k, rel_change, &u, &adjoint, x_g, alpha_prev, None);
        progress(&rec, &u, &adjoint);
        history.push(rec);
        if rel_change <= p.tolerance {
            return Ok(InverseSolution { u, adjoint, history });
        }
    }
    Err(SolveError::InverseNotConverged {
        frame: p.frame,
        iterations: p.max_iterations,
        rel_change: history.last().map(|h| h.rel_change).unwrap_or(f64::NAN),
    })
}

/// Everything the inverse solvers of one frame (fixed point, Newton, warm start) need besides
/// the data, built once per mesh and reused for every frame of a clip: the KKT sparsity
/// pattern ([`BLOCK`] unknowns per node, block tridiagonal), the banded LU's storage and
/// scratch ([`LinearSolver`]), the value arrays of the Jacobian and of the line search, and
/// the Dirichlet rows of I5 (refilled per frame by [`InverseWorkspace::set_dirichlet`]: the
/// positions depend only on `first_frame`, the values on the frame's data).
///
/// ```ignore
/// let mut ws = InverseWorkspace::new(&problem)?;        // once per clip
/// for frame in frames {
///     solve_frame_warm_in(&mut ws, &problem, &p, tol, x_g, &prev, &u0, |_, _, _| {})?;
/// }
/// ```
pub struct InverseWorkspace {
    pub(crate) nodes: usize,
    pub(crate) pattern: Pattern,
    pub(crate) solver: LinearSolver,
    /// Dirichlet unknowns of I5 and their values (KKT numbering)
    pub(crate) fixed: Vec<(usize, f64)>,
    pub(crate) rows: Vec<usize>,
    /// system values (pattern order)
    pub(crate) values: Vec<f64>,
    /// Newton: the residual merit's row weights (Ruiz row factors of the first Jacobian)
    pub(crate) weights: Vec<f64>,
}

impl InverseWorkspace {
    /// Workspace for the mesh of `problem`.
    pub fn new(problem: &Problem) -> Result<Self, SolveError> {
        let pattern = Pattern::with_block(&problem.mesh, BLOCK);
        let solver = LinearSolver::new(&pattern)?;
        let values = vec![0.0; pattern.nnz()];
        Ok(InverseWorkspace {
            nodes: problem.mesh.nodes(),
            pattern,
            solver,
            fixed: Vec::new(),
            rows: Vec::new(),
            values,
            weights: Vec::new(),
        })
    }

    /// The workspace must have been made for this mesh.
    pub(crate) fn check(&self, problem: &Problem) -> Result<(), SolveError> {
        if problem.mesh.nodes() != self.nodes {
            return Err(SolveError::Unsupported("inverse workspace made for another mesh"));
        }
        Ok(())
    }

    /// Dirichlet rows and values of I5 for the frame (`p.first_frame`, data `x_g`).
    pub fn set_dirichlet(&mut self, p: &InverseParams, x_g: &[Vector3<f64>]) {
        dirichlet_into(p, x_g, &mut self.fixed);
        self.rows.clear();
        self.rows.extend(self.fixed.iter().map(|f| f.0));
    }

    /// Solve `K(u) U = r(u)` with the boundary conditions of I5 (equilibrated, I6); `U` has
    /// [`BLOCK`] unknowns per node. [`InverseWorkspace::set_dirichlet`] must have run for the frame.
    pub(crate) fn solve_at(
        &mut self,
        problem: &Problem,
        p: &InverseParams,
        u: &DVector<f64>,
        x_g: &[Vector3<f64>],
        alpha_prev: &[Vector3<f64>],
    ) -> Result<DVector<f64>, SolveError> {
        let mut rhs = assemble_kkt(problem, p, &self.pattern, &mut self.values, u, x_g, alpha_prev);
        for &(d, v) in &self.fixed {
            rhs[d] = v;
        }
        self.pattern.set_identity_rows(&mut self.values, &self.rows);
        Ok(self.solver.solve_equilibrated(&self.values, &rhs)?)
    }
}

/// The state (`hat = false`) or adjoint part, 6 per node, of a KKT vector ([`BLOCK`] per node).
pub(crate) fn part(big: &DVector<f64>, hat: bool) -> DVector<f64> {
    let off = if hat { 6 } else { 0 };
    DVector::from_fn(big.len() / 2, |i, _| big[BLOCK * (i / 6) + off + i % 6])
}

/// The per-iteration record at the state `u` with the adjoint `adjoint` (fit measures and the
/// objective terms of (41)).
#[allow(clippy::too_many_arguments)]
pub(crate) fn record(
    problem: &Problem,
    p: &InverseParams,
    iteration: usize,
    rel_change: f64,
    u: &DVector<f64>,
    adjoint: &DVector<f64>,
    x_g: &[Vector3<f64>],
    alpha_prev: &[Vector3<f64>],
    residual: Option<f64>,
) -> InverseRecord {
    let (x_err_rel, tangent_misfit) = fit_measures(problem, p, u, x_g);
    let objective = objective_terms(problem, p, u, adjoint, x_g, alpha_prev);
    InverseRecord { iteration, rel_change, x_err_rel, tangent_misfit, objective, residual }
}

/// Dirichlet unknowns of I5 in KKT numbering with their values: `x = x_g` and `x̂ = α̂ = 0`
/// at both ends, and at the first frame `α(0) = 0` (first angle only).
pub fn dirichlet(p: &InverseParams, x_g: &[Vector3<f64>]) -> Vec<(usize, f64)> {
    let mut fixed = Vec::new();
    dirichlet_into(p, x_g, &mut fixed);
    fixed
}

/// [`dirichlet`] into a reused vector (cleared first).
pub(crate) fn dirichlet_into(p: &InverseParams, x_g: &[Vector3<f64>], fixed: &mut Vec<(usize, f64)>) {
    fixed.clear();
    let last = x_g.len() - 1;
    for node in [0, last] {
        for k in 0..3 {
            fixed.push((BLOCK * node + k, x_g[node][k]));
        }
        for k in 6..12 {
            fixed.push((BLOCK * node + k, 0.0));
        }
    }
    if p.first_frame {
        fixed.push((3, p.alpha0));
    }
}

/// Assemble the KKT matrix (into `values`, zeroed first) and right-hand side of I4 with the
/// coefficients frozen at the state `u` (6 per node); boundary conditions not applied.
pub fn assemble_kkt(
    problem: &Problem,
    p: &InverseParams,
    pattern: &Pattern,
    values: &mut [f64],
    u: &DVector<f64>,
    x_g: &[Vector3<f64>],
    alpha_prev: &[Vector3<f64>],
) -> DVector<f64> {
    assemble_blocks(problem, pattern, values, |e| {
        let uk = LocalVec::from_column_slice(&u.as_slice()[6 * e..6 * e + 12]);
        element_system(problem, p, &uk, [x_g[e], x_g[e + 1]], [alpha_prev[e], alpha_prev[e + 1]])
    })
}

/// The one element loop of the inverse problem (fixed point and Newton): zero `values`, add
/// each element's local KKT matrix `kernel(e).0` into them, and return the sum of the local
/// vectors `kernel(e).1` (12 unknowns per node).
pub(crate) fn assemble_blocks(
    problem: &Problem,
    pattern: &Pattern,
    values: &mut [f64],
    mut kernel: impl FnMut(usize) -> (KktMat, KktVec),
) -> DVector<f64> {
    values.iter_mut().for_each(|v| *v = 0.0);
    let mut rhs = DVector::zeros(BLOCK * problem.mesh.nodes());
    for e in 0..problem.mesh.elements {
        let (m, r) = kernel(e);
        pattern.scatter_local(values, e, &m);
        for i in 0..24 {
            rhs[BLOCK * e + i] += r[i];
        }
    }
    rhs
}

/// `(‖x − x_g‖/‖x_g‖, ‖∂s x − d3‖)` with the integration rules of I2 (the misfit with the λd
/// term's rule, I11).
pub fn fit_measures(problem: &Problem, p: &InverseParams, u: &DVector<f64>, x_g: &[Vector3<f64>]) -> (f64, f64) {
    let h = problem.mesh.h();
    let (mut e2, mut g2, mut t2) = (0.0, 0.0, 0.0);
    let rule = tangent_points(problem, p);
    for e in 0..problem.mesh.elements {
        let ue = LocalVec::from_column_slice(&u.as_slice()[6 * e..6 * e + 12]);
        for (xi, w) in GAUSS2.points.iter().zip(GAUSS2.weights) {
            let q = interpolate(&ue, h, *xi);
            let xg = x_g[e] * q.n[0] + x_g[e + 1] * q.n[1];
            e2 += w * h * (q.x - xg).norm_squared();
            g2 += w * h * xg.norm_squared();
        }
        for (xi, w) in rule.iter() {
            let q = interpolate(&ue, h, xi);
            t2 += w * h * (q.dx - d3(&q.alpha)).norm_squared();
        }
    }
    ((e2 / g2).sqrt(), t2.sqrt())
}

/// The terms of the objective (41) at the state `u` with the adjoint `adjoint` (6 per node
/// each), integrated with the rules of I2.
pub fn objective_terms(
    problem: &Problem,
    p: &InverseParams,
    u: &DVector<f64>,
    adjoint: &DVector<f64>,
    x_g: &[Vector3<f64>],
    alpha_prev: &[Vector3<f64>],
) -> ObjectiveTerms {
    let h = problem.mesh.h();
    let mut t = ObjectiveTerms::default();
    let omega_on = !p.first_frame;
    for e in 0..problem.mesh.elements {
        let ue = LocalVec::from_column_slice(&u.as_slice()[6 * e..6 * e + 12]);
        let ae = LocalVec::from_column_slice(&adjoint.as_slice()[6 * e..6 * e + 12]);
        for (xi, w) in GAUSS2.points.iter().zip(GAUSS2.weights) {
            let q = interpolate(&ue, h, *xi);
            let qa = interpolate(&ae, h, *xi);
            let wh = 0.5 * w * h;
            let xg = x_g[e] * q.n[0] + x_g[e + 1] * q.n[1];
            t.tracking += wh * p.lambda_g * (q.x - xg).norm_squared();
            t.force += wh * qa.x.norm_squared() / p.lambda_f;
            t.torque += wh * qa.alpha.norm_squared() / p.lambda_l;
            if omega_on {
                let ap = alpha_prev[e] * q.n[0] + alpha_prev[e + 1] * q.n[1];
                let om = a_matrix(&q.alpha) * (q.alpha - ap) / p.dt;
                t.angular += wh * om.component_mul(&om).dot(&p.lambda_omega);
            }
        }
        for (xi, w) in tangent_points(problem, p).iter() {
            let q = interpolate(&ue, h, xi);
            t.shear += 0.5 * w * h * p.lambda_d * (q.dx - d3(&q.alpha)).norm_squared();
        }
        for (xi, w) in problem.scheme.bending().points.iter().zip(problem.scheme.bending().weights) {
            let q = interpolate(&ue, h, *xi);
            let k = crate::rotation::curvature(&q.alpha, &q.dalpha);
            t.bending += 0.5 * w * h * k.component_mul(&k).dot(&p.lambda_kappa);
        }
    }
    t
}

/// Element-midpoint curvature `κˡ = A(α_mid) ∂sα` [1/m] of a nodal state (eq. 28).
pub fn element_curvatures(problem: &Problem, u: &DVector<f64>) -> Vec<Vector3<f64>> {
    let h = problem.mesh.h();
    (0..problem.mesh.elements)
        .map(|e| {
            let q = interpolate(&LocalVec::from_column_slice(&u.as_slice()[6 * e..6 * e + 12]), h, 0.5);
            crate::rotation::curvature(&q.alpha, &q.dalpha)
        })
        .collect()
}

/// `‖κ − κ_f‖/‖κ_f‖` over element midpoints, skipping `skip` elements at each end.
pub fn curvature_error(problem: &Problem, u: &DVector<f64>, truth: &DVector<f64>, skip: usize) -> f64 {
    relative_error(&element_curvatures(problem, u), &element_curvatures(problem, truth), skip)
}

/// Discrete relative ℓ² error `‖a − b‖/‖b‖` of two equally long lists of 3-vectors, skipping
/// `skip` entries at each end (at most half of them).
pub fn relative_error(a: &[Vector3<f64>], b: &[Vector3<f64>], skip: usize) -> f64 {
    let n = a.len().min(b.len());
    let range = skip.min(n / 2)..n - skip.min(n / 2);
    let num: f64 = range.clone().map(|e| (a[e] - b[e]).norm_squared()).sum();
    let den: f64 = range.map(|e| b[e].norm_squared()).sum();
    (num / den).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case::Case;

    /// With the corrected sign of the λd term (I3) the element KKT matrix is symmetric; the
    /// printed sign would make the α–α block λd DᵀD negative and break the symmetry.
    #[test]
    fn element_kkt_matrix_is_symmetric() {
        let text =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/cases/follower_bend_64.toml")).expect("case");
        let case = Case::from_toml(&text, "c", std::path::Path::new("c")).expect("case");
        let problem = Problem::from_case(&case);
        let h = case.mesh.h();
        let uk = LocalVec::from_column_slice(&[0.0, 1e-6, 0.0, 0.1, -0.4, 0.2, 2e-7, 3e-6, h, 0.15, -0.5, 0.25]);
        let p = InverseParams {
            lambda_g: 1e9,
            lambda_f: 1.0,
            lambda_l: 1e-10,
            lambda_d: 1e-6,
            lambda_kappa: Vector3::new(0.0, 1e-12, 1e-10),
            lambda_omega: Vector3::new(1e-3, 0.0, 1e-2),
            dt: 0.04,
            first_frame: false,
            alpha0: 0.0,
            frame: 0,
            stabilisation: 0.0,
            relaxation: 0.5,
            tolerance: 1e-6,
            max_iterations: 1,
        };
        let (m, _) =
            element_system(&problem, &p, &uk, [Vector3::zeros(), Vector3::new(0.0, 0.0, h)], [Vector3::zeros(); 2]);
        let asym = (m - m.transpose()).amax() / m.amax();
        assert!(asym < 1e-14, "asymmetry {asym:e}");
        // The λd block alone is positive semi-definite.
        let p_d = InverseParams { lambda_g: 0.0, lambda_kappa: Vector3::zeros(), lambda_omega: Vector3::zeros(), ..p };
        let (m_d, _) = element_system(&problem, &p_d, &uk, [Vector3::zeros(); 2], [Vector3::zeros(); 2]);
        let mut state = nalgebra::DMatrix::zeros(12, 12);
        for i in 0..12 {
            for j in 0..12 {
                state[(i, j)] = m_d[(kkt(i, false), kkt(j, false))];
            }
        }
        let eig = nalgebra::SymmetricEigen::new(state.clone());
        assert!(eig.eigenvalues.min() > -1e-12 * state.amax(), "{}", eig.eigenvalues.min());
    }
}
