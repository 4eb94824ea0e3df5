//! Static forward solve of the primal equation (52) with `j = 1` and no inertia (D5).
//!
//! * `FixedPoint` — the paper's scheme (§4, Remark 10): freeze `Q_k, A_k, B_k, q3_k` at the
//!   iterate, solve the linear problem for `û`, relax `u_{k+1} = w û + (1 − w) u_k`, stop when
//!   `max(‖Δx‖₂/‖x‖₂, ‖Δα‖₂/‖α‖₂) ≤ tol`. FreeFEM runs exactly this iteration.
//! * `Newton` — exact Jacobian of the residual of D3, stop when `max(‖δx‖∞/L, ‖δα‖∞) ≤ tol`.
//!
//! A fixed point of the first is a zero of the residual the second drives to zero, so both
//! converge to the same discrete solution (checked in `tests/forward.rs`).
//!
//! ## References
//! 1. Wang et al., Comput. Mech. 71 (2023), §4, eqs. (52), (61), Remark 10.
use nalgebra::DVector;

use super::{divergence, Problem, SolveError, Step, Stop};
use crate::assemble::{assemble, Tangent};
use crate::linalg::{LinearSolver, Pattern};
use crate::model::element::frozen_operator;
use crate::model::mesh::DofMap;

/// Static solver parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StaticParams {
    pub method: Method,
    pub tolerance: f64,
    pub max_iterations: usize,
    /// loads ramped by k/steps, k = 1..=steps, each step started from the previous solution
    pub continuation_steps: usize,
}

/// Nonlinear solver of a static problem (D5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// The paper's relaxed fixed point (§4, Remark 10) with relaxation w ∈ (0, 1].
    FixedPoint { relaxation: f64 },
    /// Newton with the exact Jacobian.
    Newton,
}

/// One row of the iteration history.
#[derive(Clone, Copy, Debug)]
pub struct IterationRecord {
    /// continuation step (1-based)
    pub step: usize,
    /// iteration within the step (1-based)
    pub iteration: usize,
    /// fixed point: relative change; Newton: increment measure
    pub change: f64,
}

/// Result of a static solve: the last iterate and its info.
#[derive(Clone, Debug)]
pub struct StaticSolution {
    pub u: DVector<f64>,
    /// total iterations over all continuation steps
    pub iterations: usize,
    pub last_change: f64,
    /// `‖R(u)‖∞ / ‖F‖∞` over the free unknowns (D5)
    pub residual: f64,
    pub history: Vec<IterationRecord>,
    /// [`Stop::MaxIterations`]: a continuation step reached `max_iterations` (the last record
    /// names it); `u` is its last iterate and the later steps did not run
    pub stop: Stop,
    pub method: Method,
}

impl StaticSolution {
    /// The solution if it met the stopping rule, else the error naming step and change.
    pub fn converged(self) -> Result<Self, SolveError> {
        if self.stop == Stop::Converged {
            return Ok(self);
        }
        let last = self.history.last().copied();
        let (step, iterations, change) =
            last.map(|r| (r.step, r.iteration, r.change)).unwrap_or((1, self.iterations, f64::NAN));
        Err(match self.method {
            Method::FixedPoint { .. } => SolveError::FixedPointNotConverged { step, iterations, rel_change: change },
            Method::Newton => {
                SolveError::NewtonNotConverged { step: Some(Step::Continuation(step)), iterations, increment: change }
            }
        })
    }
}

/// Solve the static problem from the reference configuration, with load continuation. A step
/// that reaches `max_iterations` ends the solve with [`Stop::MaxIterations`] (see
/// [`StaticSolution::converged`]).
pub fn solve(
    problem: &Problem,
    params: &StaticParams,
    mut progress: impl FnMut(&IterationRecord),
) -> Result<StaticSolution, SolveError> {
    let pattern = problem.dofs().pattern();
    let mut solver = LinearSolver::new(&pattern);
    let steps = params.continuation_steps.max(1);
    let mut u = problem.reference_state();
    let mut history = Vec::new();
    let mut last_change = f64::NAN;
    let mut stop = Stop::Converged;
    for step in 1..=steps {
        let p = Problem { load_factor: problem.load_factor * step as f64 / steps as f64, ..*problem };
        let (u_new, change, step_stop) =
            solve_step(&p, params, &pattern, &mut solver, u, step, &mut history, &mut progress)?;
        u = u_new;
        last_change = change;
        if step_stop != Stop::Converged {
            stop = step_stop;
            break;
        }
    }
    let residual = relative_residual(problem, &u);
    Ok(StaticSolution { iterations: history.len(), u, last_change, residual, history, stop, method: params.method })
}

/// One continuation step: iterate from `u` to the stopping rule of D5 (or the iteration
/// limit): the last iterate, its change and why it stopped.
#[allow(clippy::too_many_arguments)]
fn solve_step(
    problem: &Problem,
    params: &StaticParams,
    pattern: &Pattern,
    solver: &mut LinearSolver,
    mut u: DVector<f64>,
    step: usize,
    history: &mut Vec<IterationRecord>,
    progress: &mut impl FnMut(&IterationRecord),
) -> Result<(DVector<f64>, f64, Stop), SolveError> {
    let dofs = problem.dofs();
    let fixed = problem.clamped_dofs();
    let reference = problem.reference_state();
    let mut values = vec![0.0; pattern.nnz()];
    let h = problem.mesh.h();
    let mut last = f64::NAN;
    for k in 1..=params.max_iterations {
        if crate::interrupt::requested() {
            return Err(SolveError::Interrupted {
                what: "iterations",
                done: history.len(),
                total: params.max_iterations,
            });
        }
        values.iter_mut().for_each(|v| *v = 0.0);
        let change = match params.method {
            Method::FixedPoint { relaxation } => {
                let mut b = problem.loads_at(&u, 0.0, None);
                assemble(&dofs, &mut b, Some(Tangent::new(pattern, &mut values, 1.0)), |e, t| {
                    let (l, bl) = frozen_operator(&problem.props, problem.scheme, h, &dofs.gather(&u, e));
                    if let Some(t) = t {
                        *t = l;
                    }
                    bl
                });
                for &d in &fixed {
                    b[d] = reference[d];
                }
                pattern.set_identity_rows(&mut values, &fixed);
                let u_hat = solver.solve(&values, &b)?;
                let u_new = &u_hat * relaxation + &u * (1.0 - relaxation);
                let change = relative_change(&dofs, &u_new, &u);
                u = u_new;
                change
            }
            Method::Newton => {
                let g = problem.internal_force(&u, Some(Tangent::new(pattern, &mut values, 1.0)));
                let mut r = g - problem.loads_at(&u, 0.0, Some(Tangent::new(pattern, &mut values, -1.0)));
                for &d in &fixed {
                    r[d] = u[d] - reference[d];
                }
                pattern.set_identity_rows(&mut values, &fixed);
                let du = solver.solve(&values, &(-r))?;
                u += &du;
                problem.increment_measure(&du)
            }
        };
        if let Some((quantity, value)) = divergence(problem, &u, change) {
            return Err(SolveError::Diverged { step: Some(Step::Continuation(step)), iteration: k, quantity, value });
        }
        let rec = IterationRecord { step, iteration: k, change };
        progress(&rec);
        history.push(rec);
        last = change;
        if change <= params.tolerance {
            return Ok((u, change, Stop::Converged));
        }
    }
    Ok((u, last, Stop::MaxIterations))
}

/// `max(‖Δx‖₂/‖x‖₂, ‖Δα‖₂/‖α‖₂)` with 0/0 = 0 (D5), of two forward nodal vectors.
pub fn relative_change(dofs: &DofMap, new: &DVector<f64>, old: &DVector<f64>) -> f64 {
    let (dx, da) = dofs.split_norms_2(&(new - old));
    let (nx, na) = dofs.split_norms_2(new);
    let ratio = |d: f64, n: f64| if d == 0.0 { 0.0 } else { d / n };
    ratio(dx, nx).max(ratio(da, na))
}

/// `‖G(u) − F(u)‖∞ / ‖F(u)‖∞` over free unknowns.
pub fn relative_residual(problem: &Problem, u: &DVector<f64>) -> f64 {
    let f_ext = problem.loads_at(u, 0.0, None);
    let r = problem.internal_force(u, None) - &f_ext;
    let scale = problem.free_norm_inf(&f_ext);
    let rn = problem.free_norm_inf(&r);
    if scale > 0.0 {
        rn / scale
    } else {
        rn
    }
}
