//! Solvers, one file per stage: [`statics`] (the paper's relaxed fixed point of §4 and
//! Newton), [`dynamics`] (Appendix A time stepping, D6), [`modes`] (linearised natural
//! frequencies), [`inverse`] (one frame of Problem 2, eq. 61: fixed point and Newton) and
//! [`sequence`] (a clip of frames). Each solver has a params struct, returns a solution with
//! its info (iterations, history, [`Stop`]) and fails with a [`SolveError`] that carries the
//! numbers. All of them assemble through the one element loop of [`crate::assemble`].
pub mod arclength;
pub mod certificate;
pub mod chart_change;
pub mod continuation;
pub mod dynamics;
pub mod inverse;
pub mod modes;
pub mod outcome;
pub mod problem;
pub mod sequence;
pub mod stability;
pub mod statics;

pub use outcome::Outcome;
pub use problem::Problem;

use crate::linalg::LinearError;
use crate::model;

/// Why an iteration stopped with a usable iterate: the part of a run's [`Outcome`] its
/// solver decides (`Outcome::from`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// the stopping rule was met and the residual certificate is within its tolerance
    /// (`certificate`, `docs/certificate.md`)
    Converged,
    /// the iteration stopped moving (a fixed point whose relative change stayed within the
    /// tolerance for [`PLATEAU_ITERATIONS`] iterations, a Newton whose line search no longer
    /// reduces the residual) but the certificate is above its tolerance: not a solution
    Stalled,
    /// the iteration limit was reached first; the solution holds the last iterate
    MaxIterations,
}

/// A fixed point stops on its relative change only when the change has stayed within the
/// tolerance for this many consecutive iterations (one dip of a stalled iteration is not a
/// stop); the certificate then decides between converged and stalled.
pub const PLATEAU_ITERATIONS: usize = 5;

/// Errors of the solvers; each variant carries the numbers needed to act on it.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    #[error(
        "fixed point did not converge after {iterations} iterations in continuation step {step} (last relative change {rel_change:e})"
    )]
    FixedPointNotConverged { step: usize, iterations: usize, rel_change: f64 },
    #[error("Newton did not converge after {iterations} iterations (last increment {increment:e}){}", step_text(*.step))]
    /// `step`: time step (dynamic) or continuation step (static)
    NewtonNotConverged { step: Option<Step>, iterations: usize, increment: f64 },
    /// A time step met Newton's increment rule but its certificate is above the tolerance.
    #[error(
        "time step {step}: Newton's increment {increment:e} after {iterations} iterations is within its tolerance, but the residual certificate {certificate:e} is above its tolerance {tolerance:e} (worst block: {block}; docs/certificate.md)"
    )]
    StepNotCertified {
        step: usize,
        iterations: usize,
        increment: f64,
        certificate: f64,
        tolerance: f64,
        block: &'static str,
    },
    #[error("diverged in iteration {iteration}{}: {quantity} = {value:e}", step_text(*.step))]
    /// `quantity` named with its limit (a non-finite value or one beyond [`DIVERGED_LENGTHS`],
    /// [`DIVERGED_ANGLE_RAD`]); the iterate is not returned.
    Diverged { step: Option<Step>, iteration: usize, quantity: &'static str, value: f64 },
    /// A stop was requested (`crate::interrupt`, SIGINT/SIGTERM) before `done + 1` of `total`.
    #[error("interrupted by a signal after {done} of {total} {what}")]
    Interrupted { what: &'static str, done: usize, total: usize },
    #[error(
        "inverse fixed point of frame {frame} did not converge after {iterations} iterations (last relative change of (x, α) {rel_change:e})"
    )]
    InverseNotConverged { frame: usize, iterations: usize, rel_change: f64 },
    #[error(
        "inverse Newton of frame {frame} did not converge after {iterations} iterations (last residual ‖R‖/‖R₀‖ {residual:e}, certificate {certificate:e})"
    )]
    InverseNewtonNotConverged { frame: usize, iterations: usize, residual: f64, certificate: f64 },
    /// The iteration stopped moving but its certificate is above the tolerance (`Stop::Stalled`).
    #[error(transparent)]
    Stalled(Box<Stall>),
    /// The KKT matrix of a frame is singular to working precision (a zero pivot of the band LU).
    #[error(
        "inverse frame {frame}: the KKT matrix is singular to working precision at the unknown {unknown}: {cause}"
    )]
    InverseSingular { frame: usize, unknown: String, cause: String },
    #[error("inverse frame {frame} diverged in iteration {iteration}: {quantity} = {value:e}")]
    /// `quantity` named with its limit (a non-finite value, or the misfit beyond
    /// [`inverse::DIVERGED_X_ERR`]); the iterate is not returned.
    InverseDiverged { frame: usize, iteration: usize, quantity: &'static str, value: f64 },
    #[error("{what}: {nodes} nodes, but the mesh has {expected}")]
    NodeCount { what: &'static str, nodes: usize, expected: usize },
    #[error(transparent)]
    Linear(#[from] LinearError),
}

/// A forward iterate whose centreline lies farther than this many rod lengths from the
/// reference configuration has diverged (a converging static or dynamic solve of a rod of
/// length L stays within L of its clamp).
pub const DIVERGED_LENGTHS: f64 = 1e3;
/// A forward iterate with an angle beyond this [rad] (≈ 160 turns) has diverged.
pub const DIVERGED_ANGLE_RAD: f64 = 1e3;

/// Chord steps (a factorised Jacobian reused for later iterations: the time stepping and the
/// inverse Newton) are kept while each increment is at most this fraction of the one before;
/// a weaker contraction has the iteration assemble and factor the Jacobian at its iterate.
pub(crate) const CHORD_CONTRACTION: f64 = 0.01;

/// The first sign of divergence of a forward iterate `u` after a step measured by `change`:
/// `(quantity with its limit, value)`, or `None` when every unknown is finite and within
/// [`DIVERGED_LENGTHS`] and [`DIVERGED_ANGLE_RAD`].
pub(crate) fn divergence(problem: &Problem, u: &nalgebra::DVector<f64>, change: f64) -> Option<(&'static str, f64)> {
    if !change.is_finite() {
        return Some(("the relative change (non-finite)", change));
    }
    if let Some(v) = u.iter().find(|v| !v.is_finite()) {
        return Some(("an unknown of the iterate (non-finite)", *v));
    }
    let dofs = problem.dofs();
    let reference = problem.reference_state();
    let length = problem.mesh.length_m;
    let far = dofs
        .field(u, model::mesh::Field::X)
        .iter()
        .zip(dofs.field(&reference, model::mesh::Field::X))
        .map(|(x, x0)| (x - x0).amax() / length)
        .fold(0.0, f64::max);
    if far > DIVERGED_LENGTHS {
        return Some(("max |x − x_ref| / L (limit 1e3)", far));
    }
    let angle = dofs.field(u, model::mesh::Field::Alpha).iter().map(|a| a.amax()).fold(0.0, f64::max);
    if angle > DIVERGED_ANGLE_RAD {
        return Some(("max |α| [rad] (limit 1e3)", angle));
    }
    None
}

/// A solve that stopped moving with its certificate above the tolerance (`Stop::Stalled`,
/// `docs/certificate.md`): which solver, after how many iterations, and the numbers.
#[derive(Debug, thiserror::Error)]
#[error(
    "{solver} stalled after {iterations} iterations: the relative change of (x, α) is {rel_change:e}, but the residual certificate is {certificate:e} > its tolerance {tolerance:e} (worst block: {block}); the iterate does not solve the discrete equations (docs/certificate.md)"
)]
pub struct Stall {
    /// the solver and, for an inverse frame, its frame
    pub solver: String,
    pub iterations: usize,
    /// the last relative change of (x, α) (D5)
    pub rel_change: f64,
    pub certificate: f64,
    pub tolerance: f64,
    /// the block of equations with the largest backward error
    pub block: &'static str,
}

/// Where a forward solve was when it stopped: a time step (dynamic) or a load-continuation
/// step (static).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    Time(usize),
    Continuation(usize),
}

fn step_text(step: Option<Step>) -> String {
    match step {
        Some(Step::Time(n)) => format!(" at time step {n}"),
        Some(Step::Continuation(n)) => format!(" of load-continuation step {n}"),
        None => String::new(),
    }
}
