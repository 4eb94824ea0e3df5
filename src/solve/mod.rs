//! Solvers, one file per stage: [`statics`] (the paper's relaxed fixed point of §4 and
//! Newton), [`dynamics`] (Appendix A time stepping, D6), [`modes`] (linearised natural
//! frequencies), [`inverse`] (one frame of Problem 2, eq. 61: fixed point and Newton) and
//! [`sequence`] (a clip of frames). Each solver has a params struct, returns a solution with
//! its info (iterations, history, [`Stop`]) and fails with a [`SolveError`] that carries the
//! numbers. All of them assemble through the one element loop of [`crate::assemble`].
pub mod dynamics;
pub mod inverse;
pub mod modes;
pub mod problem;
pub mod sequence;
pub mod statics;

pub use problem::Problem;

use crate::linalg::LinearError;

/// Why an iteration stopped with a usable iterate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// the stopping rule was met
    Converged,
    /// the iteration limit was reached first; the solution holds the last iterate
    MaxIterations,
}

/// Errors of the solvers; each variant carries the numbers needed to act on it.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    #[error(
        "fixed point did not converge after {iterations} iterations in continuation step {step} (last relative change {rel_change:e})"
    )]
    FixedPointNotConverged { step: usize, iterations: usize, rel_change: f64 },
    #[error("Newton did not converge after {iterations} iterations (last increment {increment:e}){}", step_text(*.step))]
    /// `step`: time step (dynamic) or continuation step (static)
    NewtonNotConverged { step: Option<usize>, iterations: usize, increment: f64 },
    #[error("non-finite value in iteration {iteration}{}", step_text(*.step))]
    NonFinite { step: Option<usize>, iteration: usize },
    #[error(
        "inverse fixed point of frame {frame} did not converge after {iterations} iterations (last relative change of (x, α) {rel_change:e})"
    )]
    InverseNotConverged { frame: usize, iterations: usize, rel_change: f64 },
    #[error(
        "inverse Newton of frame {frame} did not converge after {iterations} iterations (last residual ‖R‖/‖R₀‖ {residual:e})"
    )]
    InverseNewtonNotConverged { frame: usize, iterations: usize, residual: f64 },
    #[error("non-finite value in iteration {iteration} of inverse frame {frame}")]
    InverseNonFinite { frame: usize, iteration: usize },
    #[error("{what}: {nodes} nodes, but the mesh has {expected}")]
    NodeCount { what: &'static str, nodes: usize, expected: usize },
    #[error(transparent)]
    Linear(#[from] LinearError),
}

fn step_text(step: Option<usize>) -> String {
    step.map(|s| format!(" at time step {s}")).unwrap_or_default()
}
