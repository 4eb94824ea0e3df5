//! How far the returned iterate of the paper's fixed point lies from a solution of the same
//! discrete equations: Newton (`docs/inverse.md`, I8) on the equations of Problem 2, eq. (61),
//! with the run's own data, weights and quadrature, started from the iterate itself
//! ([`Start::Near`]), to a certified root (`docs/certificate.md`). The distance is measured in
//! the norms of the run's own errors: `‖x − x_N‖/‖x_N‖` in the L² norm of `x_err_rel` (the
//! objective's rule, I2) and `‖κ − κ_N‖/‖κ_N‖` over the element midpoints as `kappa_err_rel`
//! (eq. 28). Beside the discretisation error the row also reports (`x_err_rel`,
//! `kappa_err_rel`: against the exact data), it says whether the stall of the fixed point
//! (`stalled`: the paper's rule met, the certificate above ours) changes the quantities the
//! paper reports.
//!
//! Metrics added to a single-frame inverse point run by the fixed point:
//! - `newton_x_dist_rel`, `newton_kappa_dist_rel`: the two distances;
//! - `newton_certificate`: the certificate of Newton's root;
//! - `newton_certified`: 1 when that root is certified (≤ the case's tolerance), else 0 (then
//!   the distances are to Newton's last iterate, not to a solution).
use nalgebra::Vector3;

use crate::case::Case;
use crate::engine::metrics::{relative_error, Metrics};
use crate::engine::{NodalState, RunResult};
use crate::solve::inverse::{measures::position_error, Frame, FrameSolver, InverseMethod, Start};

/// Newton's stopping rule from the iterate: a full step changing (x, α) by at most this
/// (relative), as `cases/inverse_bend_twist_newton.toml`.
pub const NEWTON_TOLERANCE: f64 = 1e-10;

/// Newton's iterations from the iterate at most (the committed Newton case allows 200).
pub const NEWTON_MAX_ITERATIONS: usize = 200;

/// The distance of a fixed-point iterate to the Newton solution of the same equations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonDistance {
    /// `‖x − x_N‖/‖x_N‖`, L² with the objective's rule (the norm of `x_err_rel`)
    pub x_rel: f64,
    /// `‖κ − κ_N‖/‖κ_N‖` over the element midpoints (the norm of `kappa_err_rel`)
    pub kappa_rel: f64,
    /// the residual certificate of Newton's last iterate
    pub certificate: f64,
    /// that certificate is within the case's tolerance
    pub certified: bool,
}

/// The distance of the result `run` of the single-frame inverse case `case` to the Newton
/// solution from it; `None` for other runs, for Newton runs (their result is Newton's), and
/// when Newton fails outright (a singular matrix, a divergence).
pub fn newton_distance(case: &Case, run: &RunResult) -> Option<NewtonDistance> {
    let settings = case.inverse()?;
    let inv = run.inverse.as_ref()?;
    if case.clip().is_some() || settings.params.method != InverseMethod::FixedPoint {
        return None;
    }
    let mut params = settings.params;
    params.method = InverseMethod::Newton { warm_start_tolerance: params.tolerance };
    params.tolerance = NEWTON_TOLERANCE;
    params.max_iterations = NEWTON_MAX_ITERATIONS;
    let problem = case.problem();
    let dofs = problem.dofs();
    let mut u0 = problem.reference_state();
    for (i, (x, a)) in run.nodes.x.iter().zip(&run.nodes.alpha).enumerate() {
        dofs.set(&mut u0, i, crate::model::mesh::Field::X, x);
        dofs.set(&mut u0, i, crate::model::mesh::Field::Alpha, a);
    }
    let frame = Frame { index: 0, x_g: &inv.data.x, previous: None, weight: None, fix_roll: false };
    let sol = FrameSolver::new(&problem, params).solve(&frame, &u0, Start::Near, |_, _, _| {}).ok()?;
    let newton = NodalState::from_vector(&case.mesh, &sol.u);
    let kappa = |n: &NodalState| -> Vec<Vector3<f64>> { n.element_curvature().into_iter().map(|(_, k)| k).collect() };
    Some(NewtonDistance {
        x_rel: position_error(&problem, &u0, &newton.x[..]),
        kappa_rel: relative_error(&kappa(&run.nodes), &kappa(&newton), 0),
        certificate: sol.certificate.value,
        certified: sol.certificate.value <= params.certificate_tolerance,
    })
}

/// The metrics of [`newton_distance`] (module documentation); none where it is `None`.
pub fn newton_metrics(case: &Case, run: Option<&RunResult>) -> Metrics {
    let mut m = Metrics::new();
    if let Some(d) = run.and_then(|r| newton_distance(case, r)) {
        m.insert_named("newton_x_dist_rel", d.x_rel);
        m.insert_named("newton_kappa_dist_rel", d.kappa_rel);
        m.insert_named("newton_certificate", d.certificate);
        m.insert_named("newton_certified", if d.certified { 1.0 } else { 0.0 });
    }
    m
}
