//! The paper's monolithic fixed point of one frame (eq. 61, Remark 10; `docs/inverse.md` I4):
//!
//! ```text
//!   U_{k+1} = K(u_k)⁻¹ r(u_k),   u_{k+1} = w u(U_{k+1}) + (1 − w) u_k
//! ```
//! with the boundary conditions of I5 and Ruiz equilibration (I6); stop when the relative
//! change of (x, α) (D5) is ≤ the tolerance.
//!
//! ## References
//! 1. Wang et al., Comput. Mech. 71 (2023), eq. (61), Remark 10.
use nalgebra::DVector;

use super::measures::record;
use super::{Frame, FrameSolver, InverseParams, InverseRecord, InverseSolution};
use crate::solve::statics::relative_change;
use crate::solve::{SolveError, Stop};

/// Run the fixed point of `frame` from `u0` with `params` (relaxation, tolerance, iteration
/// limit); the solver's Dirichlet rows must be those of the frame.
pub(crate) fn solve(
    s: &mut FrameSolver,
    params: &InverseParams,
    frame: &Frame,
    u0: &DVector<f64>,
    observer: &mut impl FnMut(&InverseRecord, &DVector<f64>, &DVector<f64>),
) -> Result<InverseSolution, SolveError> {
    let fwd = s.problem.dofs();
    let mut u = u0.clone();
    let mut adjoint = fwd.zeros();
    let mut history = Vec::new();
    for k in 1..=params.max_iterations {
        // Ruiz (I6) on the first iteration's matrix; its factors scale the later ones
        let big = s.solve_linearised(params, frame, &u, k > 1)?;
        let u_new = s.dofs.kkt_state(&big);
        adjoint = s.dofs.kkt_adjoint(&big);
        let u_next = &u_new * params.relaxation + &u * (1.0 - params.relaxation);
        let rel_change = relative_change(&fwd, &u_next, &u);
        u = u_next;
        let previous = frame.previous.unwrap_or(&s.no_previous);
        let rec = record(s.problem, params, frame, previous, k, rel_change, &u, &adjoint, None);
        rec.divergence(frame.index, &u, &adjoint)?;
        observer(&rec, &u, &adjoint);
        history.push(rec);
        if rel_change <= params.tolerance {
            return Ok(InverseSolution { u, adjoint, history, stop: Stop::Converged });
        }
    }
    Ok(InverseSolution { u, adjoint, history, stop: Stop::MaxIterations })
}
