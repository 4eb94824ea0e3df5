//! The fixed point of the inverse problem on the eq. (64) data, one iteration at a time with the
//! state after each: what `tests/inverse_claims.rs` (rigid motions) and
//! `examples/eq64_findings.rs` (the regularisation sweeps of §5.2) measure.
use cosserat::case::Case;
use cosserat::engine::metrics::curvature_error;
use cosserat::solve::inverse::{InverseParams, InverseRecord, Start};
use cosserat::solve::Problem;
use nalgebra::{DVector, Vector3};

use super::{case_from, case_text, edit};

/// Iteration cap of the sweeps: the base run stops after 361 iterations.
pub const CAP: usize = 600;

/// Forward data of eq. (64): the Newton solution (truth) and its nodal positions x_g.
pub struct Data {
    pub case: Case,
    pub truth: DVector<f64>,
    pub xg: Vec<Vector3<f64>>,
}

impl Data {
    pub fn new(elements: usize) -> Self {
        let text = case_text("follower_bend_64");
        let text =
            if elements == 100 { text } else { edit(&text, "elements = 100", &format!("elements = {elements}")) };
        let case = case_from(&text, "f64");
        let (truth, xg) = super::forward_data(&case, 5);
        Data { case, truth, xg }
    }
    pub fn problem(&self) -> Problem<'_> {
        self.case.problem()
    }
}

/// The paper's first setting with the iteration cap [`CAP`].
pub fn paper() -> InverseParams {
    InverseParams { max_iterations: CAP, ..super::paper_params_64() }
}

/// One run of the fixed point with the state after every iteration.
pub struct Run {
    pub history: Vec<InverseRecord>,
    /// `(‖κ − κ_f‖/‖κ_f‖` all elements, without 5 end elements) per iteration (if tracked)
    pub kappa: Vec<(f64, f64)>,
    pub converged: bool,
    pub u: DVector<f64>,
}

impl Run {
    pub fn last(&self) -> &InverseRecord {
        self.history.last().expect("at least one iteration")
    }
    pub fn iterations(&self) -> usize {
        self.history.len()
    }
    /// ‖l‖ [L² norm] from λl/2 ∫|l|² (l = α̂/λl of the last solve).
    pub fn torque_norm(&self, lambda_l: f64) -> f64 {
        (2.0 * self.last().objective.torque / lambda_l).sqrt()
    }
}

/// The fixed point one iteration per `solve_frame` call (max_iterations 1, tolerance ∞). An
/// iteration depends on the state `(x, α)` only (the adjoint is solved afresh), so this is the
/// same sequence as one call, with the state available after every iteration. Stops at
/// `params.tolerance`, after `params.max_iterations` or at the first solver error.
pub fn run(d: &Data, params: &InverseParams, xg: &[Vector3<f64>], u0: &DVector<f64>, track_kappa: bool) -> Run {
    let p = d.problem();
    let one = InverseParams { max_iterations: 1, tolerance: f64::INFINITY, ..*params };
    let mut u = u0.clone();
    let (mut history, mut kappa, mut converged) = (Vec::new(), Vec::new(), false);
    for k in 1..=params.max_iterations {
        let Ok(sol) = super::solve_frame_any(&p, &one, xg, None, &u, Start::Guess, |_| {}) else { break };
        u = sol.u;
        let rec = InverseRecord { iteration: k, ..sol.history[0] };
        history.push(rec);
        if track_kappa {
            kappa.push((curvature_error(&p.mesh, &u, &d.truth, 0), curvature_error(&p.mesh, &u, &d.truth, 5)));
        }
        if rec.rel_change <= params.tolerance {
            converged = true;
            break;
        }
    }
    Run { history, kappa, converged, u }
}
