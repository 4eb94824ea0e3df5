//! What a frame's iterate is measured by (`docs/inverse.md`, I2): the fit to the data and the
//! terms of the objective (41), in one pass of [`integrate`] over the mesh per rule.
use nalgebra::{DVector, Vector3};

use super::kkt::PointRule;
use super::tracking::weight_at;
use super::{FrameProblem, InverseRecord, ObjectiveTerms, Tracking};
use crate::assemble::integrate;
use crate::model::element::{interpolate, LocalVec, PointState};
use crate::model::rotation::{a_matrix, curvature, d3, Angles};
use crate::solve::Problem;

/// The angular velocity that the Λω term of (41) penalises: eq. (27), `ωˡ = A(α) ∂t α`, with
/// the backward difference `∂t α ≈ (α − α_{n−1})/Δt` [rad/s], components in the local frame
/// (d1, d2, d3) as κˡ (eq. 28). `alpha_prev` must be in the chart of `alpha` (on a rebased
/// clip, the previous frame's angles re-expressed in this frame's chart, as
/// `solve::sequence` hands them to the solver); `dt_s`: the frame interval Δt [s].
pub fn angular_velocity(alpha: &Angles, alpha_prev: &Angles, dt_s: f64) -> Vector3<f64> {
    a_matrix(alpha) * (alpha - alpha_prev) / dt_s
}

/// The fit to the data and the objective (41) at one iterate, with the rules of I2. The fit
/// and the tracking term are weighted by the tracking weight `w` (I14): over the tracked nodes.
#[derive(Clone, Copy, Debug)]
pub struct Measures {
    /// ‖x − x_g‖/‖x_g‖ (2-point Gauss), both norms weighted by `w` (I14)
    pub x_err_rel: f64,
    /// ‖∂s x − d3‖ [m^½] (the λd term's rule, I11)
    pub tangent_misfit: f64,
    pub objective: ObjectiveTerms,
}

/// [`Measures`] of the frame's problem `fp` (its data, tracking weights and previous frame's
/// angles; the Λω term is off on a first frame) at the state `u` with the adjoint `adjoint`
/// (forward layout each). Three
/// passes of [`integrate`], one per rule: the 2-point Gauss rule (fit, tracking, controls, Λω),
/// the λd term's rule (misfit and shear term from the same `|∂s x − d3|²`) and the Λκ rule.
pub fn measures(fp: &FrameProblem<'_>, u: &DVector<f64>, adjoint: &DVector<f64>) -> Measures {
    let FrameProblem { problem, params: p, frame, alpha_prev } = *fp;
    let (first_frame, data) = (frame.is_first(), frame.tracking());
    let (mesh, dofs) = (&problem.mesh, problem.dofs());
    let h = mesh.h();
    let w8 = &p.weights;
    let mut t = ObjectiveTerms::default();
    let (mut e2, mut g2, mut t2) = (0.0, 0.0, 0.0);
    let state = |e: usize, xi: f64| interpolate(&dofs.gather::<12>(u, e), h, xi);
    integrate(mesh, problem.scheme.objective().iter(), |e, xi, w| {
        let q = state(e, xi);
        let ae: LocalVec = dofs.gather(adjoint, e);
        let qa = interpolate(&ae, h, xi);
        let (d2, xg2, wq) = data_misfit(&data, e, &q);
        e2 += w * h * wq * d2;
        g2 += w * h * wq * xg2;
        let wh = 0.5 * w * h;
        t.tracking += wh * w8.lambda_g * wq * d2;
        t.force += wh * qa.x.norm_squared() / w8.lambda_f;
        t.torque += wh * qa.alpha.norm_squared() / w8.lambda_l;
        if !first_frame {
            let ap = alpha_prev[e] * q.n[0] + alpha_prev[e + 1] * q.n[1];
            let om = angular_velocity(&q.alpha, &ap, p.frame_interval_s);
            t.angular += wh * om.component_mul(&om).dot(&w8.lambda_omega);
        }
    });
    integrate(mesh, PointRule::tangent(problem, p.stabilisation).iter(), |e, xi, w| {
        let q = state(e, xi);
        let m2 = (q.dx - d3(&q.alpha)).norm_squared();
        t2 += w * h * m2;
        t.shear += 0.5 * w * h * w8.lambda_d * m2;
    });
    integrate(mesh, problem.scheme.kappa().iter(), |e, xi, w| {
        let q = state(e, xi);
        let k = curvature(&q.alpha, &q.dalpha);
        t.bending += 0.5 * w * h * k.component_mul(&k).dot(&w8.lambda_kappa);
    });
    Measures { x_err_rel: (e2 / g2).sqrt(), tangent_misfit: t2.sqrt(), objective: t }
}

/// `‖x − x_g‖/‖x_g‖` of [`measures`] alone (the same sums): no angles, no trigonometry.
pub fn position_error<'a>(problem: &Problem, u: &DVector<f64>, data: impl Into<Tracking<'a>>) -> f64 {
    let data = data.into();
    let (mesh, dofs) = (&problem.mesh, problem.dofs());
    let h = mesh.h();
    let (mut e2, mut g2) = (0.0, 0.0);
    integrate(mesh, problem.scheme.objective().iter(), |e, xi, w| {
        let (d2, xg2, wq) = data_misfit(&data, e, &interpolate(&dofs.gather(u, e), h, xi));
        e2 += w * h * wq * d2;
        g2 += w * h * wq * xg2;
    });
    (e2 / g2).sqrt()
}

/// `(|x − x_g|², |x_g|², w)` at a point `q` of element `e`, `x_g` and the tracking weight `w`
/// interpolated from the nodes: the summands of `‖x − x_g‖/‖x_g‖` ([`measures`],
/// [`position_error`]) and their weight.
fn data_misfit(data: &Tracking, e: usize, q: &PointState) -> (f64, f64, f64) {
    let ([a, b], [wa, wb]) = data.element(e);
    let xg = a * q.n[0] + b * q.n[1];
    ((q.x - xg).norm_squared(), xg.norm_squared(), weight_at([wa, wb], q.n))
}

/// The per-iteration record of `frame` at the state `u` with the adjoint `adjoint` (fit
/// measures and the objective terms of (41)).
/// `(iteration, rel_change)`: the iteration's number and relative change.
pub(crate) fn record(
    fp: FrameProblem<'_>,
    (iteration, rel_change): (usize, f64),
    u: &DVector<f64>,
    adjoint: &DVector<f64>,
    residual: Option<f64>,
) -> InverseRecord {
    let m = measures(&fp, u, adjoint);
    let (x_err_rel, tangent_misfit, objective) = (m.x_err_rel, m.tangent_misfit, m.objective);
    InverseRecord { iteration, rel_change, x_err_rel, tangent_misfit, objective, residual, certificate: None }
}
