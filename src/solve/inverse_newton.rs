//! Newton mode of the inverse problem of one frame (`docs/inverse.md`, I8): Newton on the
//! discrete equations whose fixed point [`inverse::solve_frame`](super::inverse::solve_frame)
//! seeks, eq. (61) with the readings I3–I5.
//!
//! ```text
//!   R(U) = K(u) U − r(u),     U = (u, û),  u = (x, α) the state part of U
//!   J(U) = K(u) + ∂/∂u [K(u) V − r(u)]|_{V = U}
//! ```
//! `K`, `r` are the fixed point's KKT matrix and right-hand side (I4) with every coefficient
//! (Q, A, B, q3, d3, D = [0 | d_β | d_γ]) at the current state; the Dirichlet rows of I5 are
//! `U_d − v_d`. The coefficient derivative is exact: on the primal rows it is `∂G/∂u − L(u)`
//! (the forward tangent of `element::internal_force` minus the frozen operator, since
//! `L(u) u − b(u) = G(u)`), on the adjoint rows it is the derivative of `L(u)ᵀ û` and of the
//! λd, Λκ and Λω terms (`coefficient_derivative`). A zero of `R` is a fixed point of the
//! paper's scheme, so both modes converge to the same discrete solution. Remark 8's variant
//! (an adjoint that also varies Q, A, B) is a different problem and is not used.
//!
//! Steps are damped by backtracking on the equilibrated residual norm `‖D_r R‖₂` (D_r: Ruiz
//! row factors of the first Jacobian, I6). Stop when the full Newton step has
//! `relative_change(x, α) ≤ tol` (D5); that step is taken without line search.
//!
//! ## References
//! 1. Wang et al., Comput. Mech. 71 (2023), §3–4, eqs. (52)–(61), Remark 8, Remark 10.
#![allow(non_snake_case)]
use nalgebra::{DVector, Matrix3, Vector3};

use super::inverse::{
    assemble_blocks, dirichlet, element_system, kkt, part, record, tangent_points, InverseParams, InverseRecord,
    InverseSolution, InverseWorkspace, KktMat, KktVec, BLOCK,
};
use super::statics::relative_change;
use super::{Problem, SolveError};
use crate::assembly::Pattern;
use crate::element::{frozen_operator, internal_force, interpolate, LocalMat, LocalVec};
use crate::mesh::GAUSS2;
use crate::rotation::{
    a_matrix, a_matrix_derivatives, d3, d3_second_derivatives, rotation, rotation_derivatives, skew, PointFrame,
};

/// Smallest step fraction of the backtracking line search (2⁻¹⁰).
const MIN_STEP: f64 = 1.0 / 1024.0;
/// Armijo constant of the line search: accept `t` if `φ(U + t δ) ≤ (1 − c t) φ(U)`.
const ARMIJO: f64 = 1e-4;

/// `∂/∂u [K_e(u) V − r_e(u)]` at `V = U_e` for one element (24 × 24, KKT numbering; only the
/// state columns are non-zero): the derivative of the frozen coefficients of I4.
///
/// ```text
///   primal rows:   ∂G/∂u − L(u)                                   (G(u) = L(u) u − b(u), D5)
///   adjoint rows:  ∂/∂u [L(u)ᵀ û]:  ∫ ∂sδx · S(α) (∂s x̂ + ∂s x × α̂),  S = QᵀKQ   (stretch–shear rule)
///                                   ∫ ∂sδα · (QᵀJA)ᵀ ∂s α̂                    (bending rule)
///                  λd:  −λd ∫ δα · [v·∂²d3/∂α_i∂α_j] δα,  v = ∂s x − d3            (stretch–shear rule)
///                  Λκ:  ∫ ∂sδα · ∂_α(AᵀΛκA) ∂sα                                    (bending rule)
///                  Λω:  ∫ δα · ∂_α(AᵀΛωA) (α − α_{n−1}) / Δt²                      (load rule)
/// ```
fn coefficient_derivative(problem: &Problem, p: &InverseParams, ue: &KktVec, alpha_prev: [Vector3<f64>; 2]) -> KktMat {
    let h = problem.mesh.h();
    let props = &problem.props;
    let state = LocalVec::from_fn(|i, _| ue[kkt(i, false)]);
    let adj = LocalVec::from_fn(|i, _| ue[kkt(i, true)]);
    let mut e = KktMat::zeros();
    // Primal rows: ∂G/∂u − L(u).
    let mut t = LocalMat::zeros();
    internal_force(props, problem.scheme, h, &state, Some(&mut t));
    let (l, _) = frozen_operator(props, problem.scheme, h, &state);
    for i in 0..12 {
        for j in 0..12 {
            e[(kkt(i, true), kkt(j, false))] = t[(i, j)] - l[(i, j)];
        }
    }
    let add3 = |e: &mut KktMat, ro: usize, co: usize, blk: &Matrix3<f64>| {
        for i in 0..3 {
            for j in 0..3 {
                e[(ro + i, co + j)] += blk[(i, j)];
            }
        }
    };
    let columns = |c: [Vector3<f64>; 3]| Matrix3::from_columns(&c);
    let (X, AL) = ([0, 12], [3, 15]);
    let K = Matrix3::from_diagonal(&props.shear_stretch_n);
    let Jm = Matrix3::from_diagonal(&props.bend_twist_nm2);
    // Stretch–shear rule: L(u)ᵀ û on the x rows, and the λd term.
    let rule = problem.scheme.stretch_shear();
    for (xi, w) in rule.points.iter().zip(rule.weights) {
        let (q, qa) = (interpolate(&state, h, *xi), interpolate(&adj, h, *xi));
        let wh = w * h;
        let Q = rotation(&q.alpha);
        let dQ = rotation_derivatives(&q.alpha);
        let S = Q.transpose() * K * Q;
        let v = qa.dx + q.dx.cross(&qa.alpha);
        let dS_v = columns([0, 1, 2].map(|j| (dQ[j].transpose() * K * Q + Q.transpose() * K * dQ[j]) * v));
        let dS_dx = -S * skew(&qa.alpha);
        for c in 0..2 {
            for b in 0..2 {
                add3(&mut e, X[c], AL[b], &(dS_v * (wh * q.dn[c] * q.n[b])));
                add3(&mut e, X[c], X[b], &(dS_dx * (wh * q.dn[c] * q.dn[b])));
            }
        }
    }
    // The λd term's rule (I11): the second derivative of d3 in −λd ∫ δα·D(α)ᵀ(∂s x − d3).
    for (xi, w) in tangent_points(problem, p).iter() {
        let q = interpolate(&state, h, xi);
        let wh = w * h;
        let dd = d3_second_derivatives(&q.alpha);
        let mis = q.dx - d3(&q.alpha);
        let H2 = Matrix3::from_fn(|i, j| mis.dot(&dd[i][j])) * (-p.lambda_d);
        for c in 0..2 {
            for b in 0..2 {
                add3(&mut e, AL[c], AL[b], &(H2 * (wh * q.n[c] * q.n[b])));
            }
        }
    }
    // Bending rule: L(u)ᵀ û on the α rows, and the Λκ term.
    let kappa_on = p.lambda_kappa.amax() > 0.0;
    let Lk = Matrix3::from_diagonal(&p.lambda_kappa);
    let rule = problem.scheme.bending();
    for (xi, w) in rule.points.iter().zip(rule.weights) {
        let (q, qa) = (interpolate(&state, h, *xi), interpolate(&adj, h, *xi));
        let wh = w * h;
        let f = PointFrame::new(&q.alpha, true);
        let (Q, A, dQ, dA) = (f.q, f.a, f.dq, f.da);
        let mut blk = columns(
            [0, 1, 2].map(|j| (dQ[j].transpose() * Jm * A + Q.transpose() * Jm * dA[j]).transpose() * qa.dalpha),
        );
        if kappa_on {
            blk += columns([0, 1, 2].map(|j| (dA[j].transpose() * Lk * A + A.transpose() * Lk * dA[j]) * q.dalpha));
        }
        for c in 0..2 {
            for b in 0..2 {
                add3(&mut e, AL[c], AL[b], &(blk * (wh * q.dn[c] * q.n[b])));
            }
        }
    }
    // Load rule: the Λω term (as in `element_system`).
    if !p.first_frame && p.lambda_omega.amax() > 0.0 {
        let Lw = Matrix3::from_diagonal(&p.lambda_omega) / (p.dt * p.dt);
        for (xi, w) in GAUSS2.points.iter().zip(GAUSS2.weights) {
            let q = interpolate(&state, h, *xi);
            let wh = w * h;
            let A = a_matrix(&q.alpha);
            let dA = a_matrix_derivatives(&q.alpha);
            let da = q.alpha - (alpha_prev[0] * q.n[0] + alpha_prev[1] * q.n[1]);
            let blk = columns([0, 1, 2].map(|j| (dA[j].transpose() * Lw * A + A.transpose() * Lw * dA[j]) * da));
            for c in 0..2 {
                for b in 0..2 {
                    add3(&mut e, AL[c], AL[b], &(blk * (wh * q.n[c] * q.n[b])));
                }
            }
        }
    }
    e
}

/// Newton residual `R(U) = K(u) U − r(u)` of I8 (12 unknowns per node, Dirichlet rows
/// `U_d − v_d` of I5) and its exact Jacobian `J(U)` (into `values`, Dirichlet rows identity).
pub fn assemble_newton(
    problem: &Problem,
    p: &InverseParams,
    pattern: &Pattern,
    values: &mut [f64],
    big: &DVector<f64>,
    x_g: &[Vector3<f64>],
    alpha_prev: &[Vector3<f64>],
) -> DVector<f64> {
    let fixed = dirichlet(p, x_g);
    let rows: Vec<usize> = fixed.iter().map(|f| f.0).collect();
    assemble_newton_with(problem, p, pattern, values, big, x_g, alpha_prev, &fixed, &rows)
}

/// [`assemble_newton`] with the Dirichlet unknowns given (`fixed`, and their indices `rows`).
#[allow(clippy::too_many_arguments)]
fn assemble_newton_with(
    problem: &Problem,
    p: &InverseParams,
    pattern: &Pattern,
    values: &mut [f64],
    big: &DVector<f64>,
    x_g: &[Vector3<f64>],
    alpha_prev: &[Vector3<f64>],
    fixed: &[(usize, f64)],
    rows: &[usize],
) -> DVector<f64> {
    let mut r = assemble_blocks(problem, pattern, values, |e| {
        let ue = KktVec::from_column_slice(&big.as_slice()[BLOCK * e..BLOCK * (e + 2)]);
        let uk = LocalVec::from_fn(|i, _| ue[kkt(i, false)]);
        let ap = [alpha_prev[e], alpha_prev[e + 1]];
        let (m, rhs) = element_system(problem, p, &uk, [x_g[e], x_g[e + 1]], ap);
        (m + coefficient_derivative(problem, p, &ue, ap), m * ue - rhs)
    });
    for &(d, v) in fixed {
        r[d] = big[d] - v;
    }
    pattern.set_identity_rows(values, rows);
    r
}

/// The residual of [`assemble_newton`] alone (the line search's merit needs no Jacobian):
/// the same element sums in the same order, so the same numbers.
fn newton_residual(
    problem: &Problem,
    p: &InverseParams,
    big: &DVector<f64>,
    x_g: &[Vector3<f64>],
    alpha_prev: &[Vector3<f64>],
    fixed: &[(usize, f64)],
) -> DVector<f64> {
    let mut r = DVector::zeros(BLOCK * problem.mesh.nodes());
    for e in 0..problem.mesh.elements {
        let ue = KktVec::from_column_slice(&big.as_slice()[BLOCK * e..BLOCK * (e + 2)]);
        let uk = LocalVec::from_fn(|i, _| ue[kkt(i, false)]);
        let (m, rhs) = element_system(problem, p, &uk, [x_g[e], x_g[e + 1]], [alpha_prev[e], alpha_prev[e + 1]]);
        let re = m * ue - rhs;
        for i in 0..24 {
            r[BLOCK * e + i] += re[i];
        }
    }
    for &(d, v) in fixed {
        r[d] = big[d] - v;
    }
    r
}

/// Solve one frame by Newton (I8) from the state `u0` (6 per node). The adjoint is started
/// consistently by one linear solve of the fixed point, `K(u0) U = r(u0)` (I4). Arguments and
/// records as [`solve_frame`](super::inverse::solve_frame); `p.relaxation` is not used,
/// `p.tolerance` bounds the relative change of `(x, α)` of a full Newton step (D5), and each
/// record carries the equilibrated residual relative to its start value.
pub fn solve_frame_newton(
    problem: &Problem,
    p: &InverseParams,
    x_g: &[Vector3<f64>],
    alpha_prev: &[Vector3<f64>],
    u0: &DVector<f64>,
    mut progress: impl FnMut(&InverseRecord),
) -> Result<InverseSolution, SolveError> {
    solve_frame_newton_observed(problem, p, x_g, alpha_prev, u0, |r, _, _| progress(r))
}

/// [`solve_frame_newton`] whose callback also sees the state `(x, α)` and adjoint after each step.
pub fn solve_frame_newton_observed(
    problem: &Problem,
    p: &InverseParams,
    x_g: &[Vector3<f64>],
    alpha_prev: &[Vector3<f64>],
    u0: &DVector<f64>,
    progress: impl FnMut(&InverseRecord, &DVector<f64>, &DVector<f64>),
) -> Result<InverseSolution, SolveError> {
    solve_frame_newton_observed_in(&mut InverseWorkspace::new(problem)?, problem, p, x_g, alpha_prev, u0, progress)
}

/// [`solve_frame_newton_observed`] in a workspace reused across frames (see [`InverseWorkspace`]).
#[allow(clippy::too_many_arguments)]
pub fn solve_frame_newton_observed_in(
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
    // Consistent start: one linear solve of the fixed point at u0.
    let mut big = ws.solve_at(problem, p, u0, x_g, alpha_prev)?;
    let InverseWorkspace { pattern, solver, fixed, rows, values, weights, .. } = ws;
    let mut history = Vec::new();
    let mut phi0 = f64::NAN;
    let mut last = f64::NAN;
    for k in 1..=p.max_iterations {
        let r = assemble_newton_with(problem, p, pattern, values, &big, x_g, alpha_prev, fixed, rows);
        let delta = solver.solve_equilibrated(values, &(-&r))?;
        if k == 1 {
            // the Ruiz row factors of the first Jacobian weigh the merit of the whole frame
            weights.clear();
            weights.extend_from_slice(solver.row_factors());
        }
        let merit = |r: &DVector<f64>| r.iter().zip(weights.iter()).map(|(a, b)| (a * b).powi(2)).sum::<f64>().sqrt();
        let phi = merit(&r);
        if k == 1 {
            phi0 = phi;
        }
        // A full step whose relative change is within the tolerance is taken without the
        // line search: the merit is then at its round-off floor and cannot decrease reliably.
        let full = relative_change(&part(&(&big + &delta), false), &part(&big, false)) <= p.tolerance;
        let mut t = 1.0;
        let (mut trial, mut phi_t);
        loop {
            trial = &big + &delta * t;
            phi_t = merit(&newton_residual(problem, p, &trial, x_g, alpha_prev, fixed));
            if full || phi_t <= (1.0 - ARMIJO * t) * phi || t <= MIN_STEP {
                break;
            }
            t *= 0.5;
        }
        let (u_old, u) = (part(&big, false), part(&trial, false));
        let rel_change = relative_change(&u, &u_old);
        big = trial;
        if !rel_change.is_finite() || !phi_t.is_finite() || big.iter().any(|v| !v.is_finite()) {
            return Err(SolveError::InverseNonFinite { frame: p.frame, iteration: k });
        }
        let adjoint = part(&big, true);
        last = phi_t / phi0;
        let rec = record(problem, p, k, rel_change, &u, &adjoint, x_g, alpha_prev, Some(last));
        progress(&rec, &u, &adjoint);
        history.push(rec);
        if full {
            return Ok(InverseSolution { u, adjoint, history });
        }
    }
    Err(SolveError::InverseNewtonNotConverged { frame: p.frame, iterations: p.max_iterations, residual: last })
}

/// Newton started from the paper's fixed point (I8): the fixed point (relaxation
/// `p.relaxation`) runs from `u0` until its relative change is ≤ `warm_start_tolerance`, then
/// [`solve_frame_newton`] continues from its state until `p.tolerance`. One history (the Newton
/// records continue the iteration count and carry `residual`); `p.max_iterations` bounds the
/// two phases together. From the straight reference state Newton alone can reach a spurious
/// root (I8), hence the warm start. The callback sees each record and state.
pub fn solve_frame_warm(
    problem: &Problem,
    p: &InverseParams,
    warm_start_tolerance: f64,
    x_g: &[Vector3<f64>],
    alpha_prev: &[Vector3<f64>],
    u0: &DVector<f64>,
    progress: impl FnMut(&InverseRecord, &DVector<f64>, &DVector<f64>),
) -> Result<InverseSolution, SolveError> {
    solve_frame_warm_in(
        &mut InverseWorkspace::new(problem)?,
        problem,
        p,
        warm_start_tolerance,
        x_g,
        alpha_prev,
        u0,
        progress,
    )
}

/// [`solve_frame_warm`] in a workspace reused across frames (see [`InverseWorkspace`]).
#[allow(clippy::too_many_arguments)]
pub fn solve_frame_warm_in(
    ws: &mut InverseWorkspace,
    problem: &Problem,
    p: &InverseParams,
    warm_start_tolerance: f64,
    x_g: &[Vector3<f64>],
    alpha_prev: &[Vector3<f64>],
    u0: &DVector<f64>,
    mut progress: impl FnMut(&InverseRecord, &DVector<f64>, &DVector<f64>),
) -> Result<InverseSolution, SolveError> {
    let warm = InverseParams { tolerance: warm_start_tolerance.max(p.tolerance), ..*p };
    let start = super::inverse::solve_frame_observed_in(ws, problem, &warm, x_g, alpha_prev, u0, &mut progress)?;
    let done = start.history.len();
    let rest = InverseParams { max_iterations: p.max_iterations.saturating_sub(done).max(1), ..*p };
    let newton = solve_frame_newton_observed_in(ws, problem, &rest, x_g, alpha_prev, &start.u, |r, u, a| {
        progress(&InverseRecord { iteration: r.iteration + done, ..*r }, u, a);
    })
    .map_err(|e| match e {
        SolveError::InverseNewtonNotConverged { frame, iterations, residual } => {
            SolveError::InverseNewtonNotConverged { frame, iterations: iterations + done, residual }
        }
        other => other,
    })?;
    let mut history = start.history;
    history.extend(newton.history.into_iter().map(|r| InverseRecord { iteration: r.iteration + done, ..r }));
    Ok(InverseSolution { history, ..newton })
}
