//! Static forward solve of the primal equation (52) with `j = 1` and no inertia (D5).
//!
//! * `FixedPoint` — the paper's scheme (§4, Remark 10): freeze `Q_k, A_k, B_k, q3_k` at the
//!   iterate, solve the linear problem for `û`, relax `u_{k+1} = w û + (1 − w) u_k`, stop when
//!   `max(‖Δx‖₂/‖x‖₂, ‖Δα‖₂/‖α‖₂) ≤ tol` in [`PLATEAU_ITERATIONS`] consecutive iterations.
//!   FreeFEM runs exactly this iteration.
//! * `Newton` — exact Jacobian of the residual of D3, stop when `max(‖δx‖∞/L, ‖δα‖∞) ≤ tol`.
//!
//! Either way the result is `converged` only if its residual certificate (the block backward
//! error of D3's equations at the returned state, [`certificate`], `docs/certificate.md`) is
//! within `certificate_tolerance`; otherwise it is `stalled`.
//!
//! A fixed point of the first is a zero of the residual the second drives to zero, so both
//! converge to the same discrete solution (checked in `tests/forward.rs`).
//!
//! ## References
//! 1. Wang et al., Comput. Mech. 71 (2023), §4, eqs. (52), (61), Remark 10.
use nalgebra::DVector;

use super::certificate::{of_system, Certificate, System, DEFAULT_CERTIFICATE_TOLERANCE};
use super::problem::{FrameAt, Held, HeldRows};
use super::{divergence, Problem, SolveError, Stall, Step, Stop, PLATEAU_ITERATIONS};
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
    /// the result is converged only with its certificate ([`certificate`]) at most this
    pub certificate_tolerance: f64,
    /// path following through limit points instead of load steps (`solver.continuation =
    /// "arc_length"`, D25)
    pub path: Option<super::continuation::ArcLengthParams>,
    /// the lowest critical load factors of the case's loads about the reference to compute with
    /// their modes (`solver.buckling_modes`, D27); 0: none
    pub buckling_modes: usize,
    /// the lowest natural frequencies of the rod about its rest state to compute
    /// (`solver.vibration_modes`, D28, `solve::modes::lowest_modes`); 0: none
    pub vibration_modes: usize,
}

impl StaticParams {
    /// Parameters with the default certificate tolerance.
    pub fn new(method: Method, tolerance: f64, max_iterations: usize, continuation_steps: usize) -> Self {
        StaticParams {
            method,
            tolerance,
            max_iterations,
            continuation_steps,
            certificate_tolerance: DEFAULT_CERTIFICATE_TOLERANCE,
            path: None,
            buckling_modes: 0,
            vibration_modes: 0,
        }
    }
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
    /// the residual certificate of the iterate for this step's loads ([`certificate`])
    pub certificate: f64,
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
    /// the residual certificate at `u` ([`certificate`])
    pub certificate: Certificate,
    pub history: Vec<IterationRecord>,
    /// the tolerance the certificate was held to
    pub certificate_tolerance: f64,
    /// [`Stop::MaxIterations`]: a continuation step reached `max_iterations` (the last record
    /// names it); `u` is its last iterate and the later steps did not run. [`Stop::Stalled`]:
    /// every step met its stopping rule but the certificate is above its tolerance
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
        let solver = match self.method {
            Method::FixedPoint { .. } => "static fixed point",
            Method::Newton => "static Newton",
        };
        Err(match (self.stop, self.method) {
            (Stop::Stalled, _) => SolveError::Stalled(Box::new(Stall {
                solver: solver.to_string(),
                iterations: self.iterations,
                rel_change: change,
                certificate: self.certificate.value,
                tolerance: self.certificate_tolerance,
                block: self.certificate.worst_block(System::Forward),
            })),
            (_, Method::FixedPoint { .. }) => {
                SolveError::FixedPointNotConverged { step, iterations, rel_change: change }
            }
            (_, Method::Newton) => {
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
    let solver = LinearSolver::new(&pattern);
    let mut shared = Steps { params, pattern, solver, history: Vec::new(), progress: &mut progress };
    let steps = params.continuation_steps.max(1);
    let mut u = problem.reference_state();
    let mut last_change = f64::NAN;
    let mut stop = Stop::Converged;
    for step in 1..=steps {
        let p = Problem { load_factor: problem.load_factor * step as f64 / steps as f64, ..*problem };
        let (u_new, change, step_stop) = solve_step(&p, &mut shared, u, step)?;
        u = u_new;
        last_change = change;
        if step_stop != Stop::Converged {
            stop = step_stop;
            break;
        }
    }
    let history = shared.history;
    let residual = relative_residual(problem, &u);
    let certificate = certificate(problem, &u);
    if stop == Stop::Converged && !certificate.within(params.certificate_tolerance) {
        stop = Stop::Stalled;
    }
    Ok(StaticSolution {
        iterations: history.len(),
        u,
        last_change,
        residual,
        certificate,
        certificate_tolerance: params.certificate_tolerance,
        history,
        stop,
        method: params.method,
    })
}

/// What the continuation steps of one static solve share: its parameters, the pattern of the
/// tangent and its solver, the iteration history and the progress callback.
struct Steps<'a, F> {
    params: &'a StaticParams,
    pattern: Pattern,
    solver: LinearSolver,
    history: Vec<IterationRecord>,
    progress: F,
}

/// One continuation step (number `step`): iterate from `u` to the stopping rule of D5 (or the
/// iteration limit): the last iterate, its change and why it stopped.
fn solve_step(
    problem: &Problem,
    shared: &mut Steps<'_, impl FnMut(&IterationRecord)>,
    mut u: DVector<f64>,
    step: usize,
) -> Result<(DVector<f64>, f64, Stop), SolveError> {
    let Steps { params, pattern, solver, history, progress } = shared;
    let (params, pattern) = (*params, &*pattern);
    let dofs = problem.dofs();
    let held = problem.held_static();
    let mut values = vec![0.0; pattern.nnz()];
    let mut cert_values = vec![0.0; pattern.nnz()];
    let mut last = f64::NAN;
    // consecutive fixed-point changes within the tolerance (Newton stops on the first)
    let mut within = 0;
    let needed = match params.method {
        Method::FixedPoint { .. } => PLATEAU_ITERATIONS,
        Method::Newton => 1,
    };
    for k in 1..=params.max_iterations {
        if crate::interrupt::requested() {
            return Err(SolveError::Interrupted {
                what: "iterations",
                done: history.len(),
                total: params.max_iterations,
            });
        }
        let change = match params.method {
            Method::FixedPoint { relaxation } => {
                let b = frozen_system(problem, &u, pattern, &mut values, &held);
                let u_hat = solver.solve(&values, &b)?;
                let u_new = &u_hat * relaxation + &u * (1.0 - relaxation);
                let change = relative_change(&dofs, &u_new, &u);
                u = u_new;
                change
            }
            Method::Newton => {
                values.iter_mut().for_each(|v| *v = 0.0);
                let g = problem.internal_force(&u, Some(Tangent::new(pattern, &mut values, 1.0)));
                let mut r = g - problem.loads_at(&u, 0.0, Some(Tangent::new(pattern, &mut values, -1.0)));
                problem.apply_held(pattern, Some(&mut values), &mut r, &held, HeldRows::Residual(&u), FrameAt::of(&u));
                let du = solver.solve(&values, &(-r))?;
                u += &du;
                problem.increment_measure(&du)
            }
        };
        if let Some((quantity, value)) = divergence(problem, &u, change) {
            return Err(SolveError::Diverged { step: Some(Step::Continuation(step)), iteration: k, quantity, value });
        }
        let b = frozen_system(problem, &u, pattern, &mut cert_values, &held);
        let certificate = of_system(&dofs, pattern, &cert_values, &u, &b).value;
        let rec = IterationRecord { step, iteration: k, change, certificate };
        progress(&rec);
        history.push(rec);
        last = change;
        within = if change <= params.tolerance { within + 1 } else { 0 };
        if within >= needed {
            return Ok((u, change, Stop::Converged));
        }
    }
    Ok((u, last, Stop::MaxIterations))
}

/// The frozen-coefficient system of the fixed point (D5) at `u` into `values` (replaced), with
/// the identity rows of the `held` unknowns (D22): returns its right-hand side `b(u) + F(u)`
/// (the held values in the held rows). `L(u) u − b(u) − F(u)` is D3's residual `G(u) − F(u)`.
pub fn frozen_system(
    problem: &Problem,
    u: &DVector<f64>,
    pattern: &Pattern,
    values: &mut [f64],
    held: &Held,
) -> DVector<f64> {
    let dofs = problem.dofs();
    let h = problem.mesh.h();
    // (a problem without loads, the dynamic step's certificate: no pass over the loads)
    let mut b = if problem.load_factor == 0.0 { dofs.zeros() } else { problem.loads_at(u, 0.0, None) };
    assemble(&dofs, &mut b, Some(Tangent::overwriting(pattern, values, 1.0)), |e, t| {
        let (l, bl) = frozen_operator(&problem.props, problem.scheme, h, &dofs.gather(u, e), problem.rest(e));
        if let Some(t) = t {
            *t = l;
        }
        bl
    });
    problem.apply_held(pattern, Some(values), &mut b, held, HeldRows::Values, FrameAt::of(u));
    b
}

/// The residual certificate of a static state `u` (`docs/certificate.md`): the block backward
/// error of D3's equations written as the fixed point's frozen system, `L(u) u − b(u) − F(u)`,
/// against `|L(u)| |u| + |b(u) + F(u)|` (the clamp at the origin, so positions are measured
/// from it), force and moment rows apart.
pub fn certificate(problem: &Problem, u: &DVector<f64>) -> Certificate {
    let dofs = problem.dofs();
    let pattern = dofs.pattern();
    let mut values = vec![0.0; pattern.nnz()];
    let b = frozen_system(problem, u, &pattern, &mut values, &problem.held_static());
    of_system(&dofs, &pattern, &values, u, &b)
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
