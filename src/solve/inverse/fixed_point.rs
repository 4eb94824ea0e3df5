//! The paper's monolithic fixed point of one frame (eq. 61, Remark 10; `docs/inverse.md` I4):
//!
//! ```text
//!   U_{k+1} = K(u_k)⁻¹ r(u_k),   u_{k+1} = w u(U_{k+1}) + (1 − w) u_k
//! ```
//! with the boundary conditions of I5 and Ruiz equilibration (I6). As a solve it stops when the
//! relative change of (x, α) (D5) has been ≤ the tolerance in
//! [`PLATEAU_ITERATIONS`] consecutive iterations, and the residual certificate of the iterate
//! (`kkt::certificate`, `docs/certificate.md`) decides between converged and stalled. As
//! Newton's warm start it stops at the first change within its tolerance.
//!
//! ## References
//! 1. Wang et al., Comput. Mech. 71 (2023), eq. (61), Remark 10.
use std::ops::ControlFlow;

use nalgebra::DVector;

use super::measures::record;
use super::{Frame, FrameProblem, FrameSolver, InverseParams, InverseRecord, InverseSolution, Records, Scaling};
use crate::solve::certificate::Certificate;
use crate::solve::statics::relative_change;
use crate::solve::{SolveError, Stop, PLATEAU_ITERATIONS};

/// How a fixed-point run stops on its relative change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum StopRule {
    /// a solve: [`PLATEAU_ITERATIONS`] consecutive changes within the tolerance, then the
    /// certificate decides between converged and stalled
    Plateau,
    /// Newton's warm start: the first change within the tolerance (the iterate is only a start;
    /// no certificate)
    FirstDip,
}

/// Run the fixed point of `frame` from `u0` with `params` (relaxation, tolerance, iteration
/// limit) as a solve ([`StopRule::Plateau`]); the solver's Dirichlet rows must be those of the
/// frame. Every record carries its certificate when the solver keeps every record.
pub(crate) fn solve(
    s: &mut FrameSolver,
    params: &InverseParams,
    frame: &Frame,
    u0: &DVector<f64>,
    observer: &mut impl FnMut(&InverseRecord, &DVector<f64>, &DVector<f64>) -> ControlFlow<()>,
) -> Result<InverseSolution, SolveError> {
    run(s, params, frame, u0, StopRule::Plateau, observer)
}

/// The fixed point with the stop rule `rule`.
pub(crate) fn run(
    s: &mut FrameSolver,
    params: &InverseParams,
    frame: &Frame,
    u0: &DVector<f64>,
    rule: StopRule,
    observer: &mut impl FnMut(&InverseRecord, &DVector<f64>, &DVector<f64>) -> ControlFlow<()>,
) -> Result<InverseSolution, SolveError> {
    let fwd = s.problem.dofs();
    let mut u = u0.clone();
    let mut adjoint = fwd.zeros();
    let mut history = Vec::new();
    let every = s.records == Records::Every && rule == StopRule::Plateau;
    let needed = match rule {
        StopRule::Plateau => PLATEAU_ITERATIONS,
        StopRule::FirstDip => 1,
    };
    let mut within = 0;
    let mut certificate = Certificate::default();
    for k in 1..=params.max_iterations {
        // Ruiz (I6) on the first iteration's matrix; its factors scale the later ones
        let scaling = if k == 1 { Scaling::Equilibrated } else { Scaling::Rescaled };
        let big = s.solve_linearised(params, frame, &u, scaling)?;
        let u_new = s.dofs.kkt_state(&big);
        adjoint = s.dofs.kkt_adjoint(&big);
        let u_next = &u_new * params.relaxation + &u * (1.0 - params.relaxation);
        let rel_change = relative_change(&fwd, &u_next, &u);
        u = u_next;
        within = if rel_change <= params.tolerance { within + 1 } else { 0 };
        let stop = within >= needed;
        let certify = every || (rule == StopRule::Plateau && stop) || k == params.max_iterations;
        let cert = certify.then(|| s.certify(frame, &u, &adjoint));
        if let Some(c) = cert {
            certificate = c;
        }
        let rec = InverseRecord {
            certificate: cert.map(|c| c.value),
            ..record(FrameProblem::of(s.problem, params, frame, &s.no_previous), (k, rel_change), &u, &adjoint, None)
        };
        rec.divergence(frame.index, &u, &adjoint)?;
        let stop_requested = observer(&rec, &u, &adjoint).is_break();
        history.push(rec);
        if stop_requested {
            return Err(SolveError::Interrupted { what: "iterations", done: 0, total: 0 });
        }
        if stop {
            let stop = match rule {
                StopRule::FirstDip => Stop::Converged,
                StopRule::Plateau if certificate.within(params.certificate_tolerance) => Stop::Converged,
                StopRule::Plateau => Stop::Stalled,
            };
            let certificate_tolerance = params.certificate_tolerance;
            return Ok(InverseSolution { u, adjoint, history, stop, certificate, certificate_tolerance });
        }
    }
    let certificate_tolerance = params.certificate_tolerance;
    Ok(InverseSolution { u, adjoint, history, stop: Stop::MaxIterations, certificate, certificate_tolerance })
}
