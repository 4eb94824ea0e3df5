//! Newton mode of the inverse problem of one frame (`docs/inverse.md`, I8): Newton on the
//! discrete equations whose fixed point [`super::fixed_point`] seeks, eq. (61) with the
//! readings I3–I5.
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
//! `relative_change(x, α) ≤ tol` (D5) and the residual certificate of the new iterate
//! (`kkt::certificate`, `docs/certificate.md`) is within its tolerance; that step is taken
//! without line search. A step within the tolerance whose iterate is not certified does not
//! stop the iteration. Newton has stalled when the merit has fallen by less than
//! [`STALL_DECREASE`] over [`STALL_WINDOW`] iterations: the result is then converged if its
//! certificate is within the tolerance (the relative change is at its round-off floor) and
//! stalled otherwise.
//!
//! ## References
//! 1. Wang et al., Comput. Mech. 71 (2023), §3–4, eqs. (52)–(61), Remark 8, Remark 10.
use nalgebra::{DVector, Matrix3, Vector3};

use super::kkt::{add3, add_operator_blocks, element_part, element_system, KktMat, KktVec, PointRule, AL, X};
use super::measures::{position_error, record};
use super::{early_divergence, Frame, FrameSolver, InverseParams, InverseRecord, InverseSolution, Records};
use crate::assemble::{assemble, Tangent};
use crate::linalg::Pattern;
use crate::model::element::{internal_force, interpolate, LocalMat};
use crate::model::rotation::{
    a_matrix, a_matrix_derivatives, d3, d3_second_derivatives, rotation, rotation_derivatives, skew, PointFrame,
};
use crate::solve::statics::relative_change;
use crate::solve::{Problem, SolveError, Stop, CHORD_CONTRACTION};

/// Smallest step fraction of the backtracking line search (2⁻¹⁰).
const MIN_STEP: f64 = 1.0 / 1024.0;
/// Armijo constant of the line search: accept `t` if `φ(U + t δ) ≤ (1 − c t) φ(U)`.
const ARMIJO: f64 = 1e-4;
/// Chord steps are taken where they converge nearly as fast as Newton's: while their
/// contraction (the ratio of successive relative changes of `(x, α)`, D5) is at most this. A
/// chord step from a Jacobian factorised one step ago contracts by about the square of that
/// Newton step's contraction (the step's distance times Newton's constant `c_k / c_{k−1}²`).
/// At 3e-3 a chord step gains 2.5 decades for about a third of a Newton step's cost (no
/// factorisation, no Jacobian; `docs/inverse.md`, I8), so from the changes where it fires
/// (≤ 1e-4) it reaches the 1e-9 tolerances in at most one step more.
const CHORD_RATE: f64 = 3e-3;
/// Newton has stalled when the merit `φ` has fallen by less than this fraction over
/// [`STALL_WINDOW`] iterations.
pub const STALL_DECREASE: f64 = 0.1;
/// Iterations over which [`STALL_DECREASE`] is measured.
pub const STALL_WINDOW: usize = 20;

/// `∂/∂u [K_e(u) V − r_e(u)]` at `V = U_e` for one element (24 × 24, KKT numbering; only the
/// state columns are non-zero), added into `e`: the derivative of the frozen coefficients of I4;
/// `l`: the element's frozen operator `L(u)` (`element::frozen_operator`, as `element_system`
/// returns it).
///
/// ```text
///   primal rows:   ∂G/∂u − L(u)                                   (G(u) = L(u) u − b(u), D5)
///   adjoint rows:  ∂/∂u [L(u)ᵀ û]:  ∫ ∂sδx · S(α) (∂s x̂ + ∂s x × α̂),  S = QᵀKQ   (stretch–shear rule)
///                                   ∫ ∂sδα · (QᵀJA)ᵀ ∂s α̂                    (bending rule)
///                  λd:  −λd ∫ δα · [v·∂²d3/∂α_i∂α_j] δα,  v = ∂s x − d3            (stretch–shear rule)
///                  Λκ:  ∫ ∂sδα · ∂_α(AᵀΛκA) ∂sα                                    (Λκ rule, I12)
///                  Λω:  ∫ δα · ∂_α(AᵀΛωA) (α − α_{n−1}) / Δt²                      (objective rule)
/// ```
#[allow(non_snake_case)] // paper symbols K, J, Q, A, S, H2, Lk, Lw
fn coefficient_derivative(
    problem: &Problem,
    p: &InverseParams,
    first_frame: bool,
    ue: &KktVec,
    l: &LocalMat,
    alpha_prev: [Vector3<f64>; 2],
    e: &mut KktMat,
) {
    let h = problem.mesh.h();
    let props = &problem.props;
    let w8 = &p.weights;
    let (state, adj) = (element_part(ue, false), element_part(ue, true));
    // Primal rows: ∂G/∂u − L(u).
    let mut t = LocalMat::zeros();
    internal_force(props, problem.scheme, h, &state, Some(&mut t));
    add_operator_blocks(e, &(t - l), false);
    let columns = |c: [Vector3<f64>; 3]| Matrix3::from_columns(&c);
    let K = Matrix3::from_diagonal(&props.shear_stretch_n);
    let Jm = Matrix3::from_diagonal(&props.bend_twist_nm2);
    // Stretch–shear rule: L(u)ᵀ û on the x rows, and the λd term.
    for (xi, w) in problem.scheme.stretch_shear().iter() {
        let (q, qa) = (interpolate(&state, h, xi), interpolate(&adj, h, xi));
        let wh = w * h;
        let Q = rotation(&q.alpha);
        let dQ = rotation_derivatives(&q.alpha);
        let S = Q.transpose() * K * Q;
        let v = qa.dx + q.dx.cross(&qa.alpha);
        // ∂S/∂α_j v = dQ_jᵀ K (Q v) + Qᵀ K (dQ_j v), as matrix–vector products
        let kqv = K * (Q * v);
        let dS_v = columns([0, 1, 2].map(|j| dQ[j].transpose() * kqv + Q.transpose() * (K * (dQ[j] * v))));
        let dS_dx = -S * skew(&qa.alpha);
        for c in 0..2 {
            for b in 0..2 {
                add3(e, X[c], AL[b], &(dS_v * (wh * q.dn[c] * q.n[b])));
                add3(e, X[c], X[b], &(dS_dx * (wh * q.dn[c] * q.dn[b])));
            }
        }
    }
    // The λd term's rule (I11): the second derivative of d3 in −λd ∫ δα·D(α)ᵀ(∂s x − d3).
    for (xi, w) in PointRule::tangent(problem, p.stabilisation).iter() {
        let q = interpolate(&state, h, xi);
        let wh = w * h;
        let dd = d3_second_derivatives(&q.alpha);
        let mis = q.dx - d3(&q.alpha);
        let H2 = Matrix3::from_fn(|i, j| mis.dot(&dd[i][j])) * (-w8.lambda_d);
        for c in 0..2 {
            for b in 0..2 {
                add3(e, AL[c], AL[b], &(H2 * (wh * q.n[c] * q.n[b])));
            }
        }
    }
    // Bending rule: L(u)ᵀ û on the α rows.
    for (xi, w) in problem.scheme.bending().iter() {
        let (q, qa) = (interpolate(&state, h, xi), interpolate(&adj, h, xi));
        let wh = w * h;
        let f = PointFrame::new(&q.alpha, true);
        let (Q, A, dQ, dA) = (f.q, f.a, f.dq, f.da);
        // (dQ_jᵀ J A + Qᵀ J dA_j)ᵀ w = Aᵀ J (dQ_j w) + dA_jᵀ J (Q w), w = ∂s α̂
        let jqw = Jm * (Q * qa.dalpha);
        let blk = columns([0, 1, 2].map(|j| A.transpose() * (Jm * (dQ[j] * qa.dalpha)) + dA[j].transpose() * jqw));
        for c in 0..2 {
            for b in 0..2 {
                add3(e, AL[c], AL[b], &(blk * (wh * q.dn[c] * q.n[b])));
            }
        }
    }
    // The Λκ term's rule (I12).
    if w8.lambda_kappa.amax() > 0.0 {
        let Lk = Matrix3::from_diagonal(&w8.lambda_kappa);
        for (xi, w) in problem.scheme.kappa().iter() {
            let q = interpolate(&state, h, xi);
            let (A, dA) = (a_matrix(&q.alpha), a_matrix_derivatives(&q.alpha));
            let lka = Lk * (A * q.dalpha);
            let blk = columns([0, 1, 2].map(|j| dA[j].transpose() * lka + A.transpose() * (Lk * (dA[j] * q.dalpha))));
            for c in 0..2 {
                for b in 0..2 {
                    add3(e, AL[c], AL[b], &(blk * (w * h * q.dn[c] * q.n[b])));
                }
            }
        }
    }
    // Load rule: the Λω term (as in `element_system`).
    if !first_frame && w8.lambda_omega.amax() > 0.0 {
        let dt = p.frame_interval_s;
        let Lw = Matrix3::from_diagonal(&w8.lambda_omega) / (dt * dt);
        for (xi, w) in problem.scheme.objective().iter() {
            let q = interpolate(&state, h, xi);
            let wh = w * h;
            let A = a_matrix(&q.alpha);
            let dA = a_matrix_derivatives(&q.alpha);
            let da = q.alpha - (alpha_prev[0] * q.n[0] + alpha_prev[1] * q.n[1]);
            let lwa = Lw * (A * da);
            let blk = columns([0, 1, 2].map(|j| dA[j].transpose() * lwa + A.transpose() * (Lw * (dA[j] * da))));
            for c in 0..2 {
                for b in 0..2 {
                    add3(e, AL[c], AL[b], &(blk * (wh * q.n[c] * q.n[b])));
                }
            }
        }
    }
}

/// Newton residual `R(U) = K(u) U − r(u)` of I8 (KKT layout, Dirichlet rows `U_d − v_d` of
/// `fixed`, I5) and, when `jacobian = Some((pattern, values, rows))`, its exact Jacobian `J(U)`
/// into `values` (the Dirichlet `rows` identity). One pass of the element loop; without the
/// Jacobian the same element sums in the same order, so the same residual.
#[allow(clippy::too_many_arguments)]
pub fn assemble_residual(
    problem: &Problem,
    p: &InverseParams,
    frame: &Frame,
    alpha_prev: &[Vector3<f64>],
    big: &DVector<f64>,
    fixed: &[(usize, f64)],
    jacobian: Option<(&Pattern, &mut [f64], &[usize])>,
) -> DVector<f64> {
    let dofs = problem.mesh.kkt_dofs();
    let first = frame.is_first();
    let data = frame.tracking();
    let mut scratch = KktMat::zeros();
    let kernel = |e: usize, t: Option<&mut KktMat>| {
        let ue: KktVec = dofs.gather(big, e);
        let uk = element_part(&ue, false);
        let ap = [alpha_prev[e], alpha_prev[e + 1]];
        let jacobian = t.is_some();
        let m = t.unwrap_or_else(|| {
            scratch.as_mut_slice().fill(0.0);
            &mut scratch
        });
        let (rhs, l) = element_system(problem, p, first, &uk, data.element(e), ap, m);
        // by reference: `*m * ue` would copy the 24 × 24 matrix first
        #[allow(clippy::op_ref)]
        let r = &*m * ue - rhs;
        if jacobian {
            coefficient_derivative(problem, p, first, &ue, &l, ap, m);
        }
        r
    };
    let mut r = dofs.zeros();
    match jacobian {
        Some((pattern, values, rows)) => {
            assemble(&dofs, &mut r, Some(Tangent::overwriting(pattern, &mut *values, 1.0)), kernel);
            pattern.set_identity_rows(values, rows);
        }
        None => assemble(&dofs, &mut r, None, kernel),
    }
    for &(d, v) in fixed {
        r[d] = big[d] - v;
    }
    r
}

/// Newton of one frame (I8) from the state `u0` (forward layout) with `params`; the solver's
/// Dirichlet rows must be those of the frame. The adjoint is started consistently by one
/// linear solve of the fixed point, `K(u0) U = r(u0)` (I4), whose Ruiz factors (I6) scale
/// every Jacobian of the frame and weigh its merit. When the predicted contraction of a chord
/// step (the last factorised Jacobian reused) is within [`CHORD_RATE`], the next iteration is
/// one; a chord step that contracts by more than [`CHORD_CONTRACTION`], or fails the line
/// search's first test, is discarded and the iteration is Newton's.
/// `params.relaxation` is not used; `params.tolerance` bounds the relative change of `(x, α)`
/// of a full step (D5), and each record carries the equilibrated residual relative to its
/// start value. With [`Records::Last`] only the last iteration is recorded (and observed), and
/// the step that meets the tolerance is taken without assembling its residual: the same
/// iterates and the same last record, without that residual.
pub(crate) fn solve(
    s: &mut FrameSolver,
    params: &InverseParams,
    frame: &Frame,
    u0: &DVector<f64>,
    observer: &mut impl FnMut(&InverseRecord, &DVector<f64>, &DVector<f64>),
) -> Result<InverseSolution, SolveError> {
    solve_from(s, params, frame, u0, false, observer)
}

/// [`solve`]; `rescale`: the frame's Ruiz factors exist already (the warm start's fixed point
/// computed them), so the consistent start is scaled by them instead of equilibrating again.
fn solve_from(
    s: &mut FrameSolver,
    params: &InverseParams,
    frame: &Frame,
    u0: &DVector<f64>,
    rescale: bool,
    observer: &mut impl FnMut(&InverseRecord, &DVector<f64>, &DVector<f64>),
) -> Result<InverseSolution, SolveError> {
    // Consistent start: one linear solve of the fixed point at u0.
    let mut big = s.solve_linearised(params, frame, u0, rescale)?;
    let problem = s.problem;
    let fwd = problem.dofs();
    let FrameSolver {
        dofs,
        pattern,
        solver,
        fixed,
        rows,
        values,
        merit_weights,
        no_previous,
        records,
        cert_values,
        ..
    } = s;
    cert_values.resize(pattern.nnz(), 0.0);
    let lean = *records == Records::Last;
    let previous_angles = frame.previous.unwrap_or(no_previous.as_slice());
    // the Ruiz row factors of the start's matrix weigh the merit of the whole frame (I6)
    merit_weights.clear();
    merit_weights.extend_from_slice(solver.row_factors());
    let merit = |r: &DVector<f64>| r.iter().zip(merit_weights.iter()).map(|(a, b)| (a * b).powi(2)).sum::<f64>().sqrt();
    let mut history = Vec::new();
    let mut phi0 = f64::NAN;
    // the merit at the start of each iteration (stall detection)
    let mut phis: Vec<f64> = Vec::new();
    let mut certify = |big: &DVector<f64>| {
        super::kkt::certificate(problem, params, frame, previous_angles, big, pattern, cert_values)
    };
    let done = |u, adjoint, history, stop, certificate| InverseSolution {
        u,
        adjoint,
        history,
        stop,
        certificate,
        certificate_tolerance: params.certificate_tolerance,
    };
    let mut adjoint = fwd.zeros();
    let mut u = dofs.kkt_state(&big);
    // the residual at `big` when the line search already assembled it (with the Jacobian,
    // unless the next iteration is a chord step)
    let mut next: Option<DVector<f64>> = None;
    // this iteration solves with the last factorisation (a chord step)
    let mut chord = false;
    // the last step was damped by the line search: the next full step is then tried with its
    // residual alone (its Jacobian is wasted if the merit rejects it, as after a damped step it
    // often does)
    let mut damped = false;
    // relative change of the last step
    let mut previous = f64::INFINITY;
    let mut k = 0;
    while k < params.max_iterations {
        k += 1;
        let r = match next.take() {
            Some(r) => r,
            None => {
                let jacobian = (!chord).then_some((&*pattern, values.as_mut_slice(), rows.as_slice()));
                assemble_residual(problem, params, frame, previous_angles, &big, fixed, jacobian)
            }
        };
        let delta = if chord { solver.solve_factored(&(-&r))? } else { solver.solve_rescaled(values, &(-&r))? };
        let phi = merit(&r);
        if k == 1 {
            phi0 = phi;
        }
        if !chord {
            phis.push(phi);
        }
        // stalled: the merit fell by less than STALL_DECREASE over STALL_WINDOW iterations
        let n = phis.len();
        if !chord && n > STALL_WINDOW && phi > (1.0 - STALL_DECREASE) * phis[n - 1 - STALL_WINDOW] {
            let c = certify(&big);
            let stop = if c.within(params.certificate_tolerance) { Stop::Converged } else { Stop::Stalled };
            if lean {
                // a lean solve kept no record of the iterate it returns: its report is this one
                let rec = InverseRecord {
                    certificate: Some(c.value),
                    ..record(problem, params, frame, previous_angles, k - 1, previous, &u, &adjoint, Some(phi / phi0))
                };
                observer(&rec, &u, &adjoint);
                history.push(rec);
            }
            return Ok(done(u, adjoint, history, stop, c));
        }
        let change = relative_change(&fwd, &dofs.kkt_state(&(&big + &delta)), &dofs.kkt_state(&big));
        // A full step whose relative change is within the tolerance is taken without the
        // line search: the merit is then at its round-off floor and cannot decrease reliably.
        let full = change <= params.tolerance;
        let skip_residual = full && lean;
        if chord && !full && change > CHORD_CONTRACTION * previous {
            // too weak a contraction for the frozen Jacobian: this iteration is Newton's
            (chord, k) = (false, k - 1);
            continue;
        }
        // the next iteration reuses this factorisation if a chord step is predicted to
        // contract by CHORD_RATE: the square of this Newton step's contraction, or a chord
        // step's own
        let rate = match (chord, k) {
            (_, 1) => f64::INFINITY,
            (true, _) => change / previous,
            (false, _) => (change / previous).powi(2),
        };
        let chord_next = !full && rate <= CHORD_RATE;
        let mut t = 1.0;
        let (mut trial, mut phi_t);
        let accepted = loop {
            trial = &big + &delta * t;
            // The full step of an iteration that is not the last is usually accepted: its
            // residual comes with the Jacobian (unless a chord step follows), which the next
            // iteration then uses (the same element sums, so the same residual as assembling
            // it there).
            let with_jacobian = t == 1.0 && !full && !chord_next && !damped;
            let jacobian = with_jacobian.then_some((&*pattern, values.as_mut_slice(), rows.as_slice()));
            // the last step is taken without its residual where no record needs it
            if skip_residual {
                phi_t = f64::NAN;
                break true;
            }
            let r_t = assemble_residual(problem, params, frame, previous_angles, &trial, fixed, jacobian);
            phi_t = merit(&r_t);
            if full || phi_t <= (1.0 - ARMIJO * t) * phi || t <= MIN_STEP {
                if t == 1.0 && !full && (with_jacobian || chord_next) {
                    next = Some(r_t);
                }
                break true;
            }
            if chord {
                break false;
            }
            t *= 0.5;
        };
        if !accepted {
            // a chord step the merit rejects: this iteration is Newton's
            (chord, k) = (false, k - 1);
            continue;
        }
        chord = chord_next && t == 1.0;
        damped = t < 1.0;
        let u_old = dofs.kkt_state(&big);
        u = dofs.kkt_state(&trial);
        let rel_change = relative_change(&fwd, &u, &u_old);
        previous = rel_change;
        big = trial;
        adjoint = dofs.kkt_adjoint(&big);
        let last = k == params.max_iterations;
        let cert = (!lean || full || last).then(|| certify(&big));
        if lean && !full && !last {
            let x_err = position_error(problem, &u, frame.tracking());
            early_divergence(frame.index, k, rel_change, x_err, &u, &adjoint)?;
        } else {
            let residual = (!skip_residual).then_some(phi_t / phi0);
            let rec = InverseRecord {
                certificate: cert.map(|c| c.value),
                ..record(problem, params, frame, previous_angles, k, rel_change, &u, &adjoint, residual)
            };
            rec.divergence(frame.index, &u, &adjoint)?;
            observer(&rec, &u, &adjoint);
            history.push(rec);
        }
        match cert {
            Some(c) if full && c.within(params.certificate_tolerance) => {
                return Ok(done(u, adjoint, history, Stop::Converged, c));
            }
            Some(c) if last => return Ok(done(u, adjoint, history, Stop::MaxIterations, c)),
            // a step within the tolerance whose iterate is not certified: go on with Newton
            _ if full => (next, chord) = (None, false),
            _ => {}
        }
    }
    let c = certify(&big);
    Ok(done(u, adjoint, history, Stop::MaxIterations, c))
}

/// Newton started from the paper's fixed point (I8): the fixed point (relaxation
/// `relaxation` of the solver's params) runs from `u0` until its relative change is
/// ≤ `warm_start_tolerance`, then [`solve`] continues from its state until the tolerance. One
/// history (the Newton records continue the iteration count and carry `residual`);
/// `max_iterations` bounds the two phases together. From the straight reference state Newton
/// alone can reach a spurious root (I8), hence the warm start.
pub(crate) fn solve_warm(
    s: &mut FrameSolver,
    warm_start_tolerance: f64,
    frame: &Frame,
    u0: &DVector<f64>,
    observer: &mut impl FnMut(&InverseRecord, &DVector<f64>, &DVector<f64>),
) -> Result<InverseSolution, SolveError> {
    let p = s.params;
    let warm = InverseParams { tolerance: warm_start_tolerance.max(p.tolerance), ..p };
    let start = super::fixed_point::run(s, &warm, frame, u0, super::fixed_point::StopRule::FirstDip, observer)?;
    if start.stop != Stop::Converged {
        return Ok(start);
    }
    let done = start.history.len();
    let rest = InverseParams { max_iterations: p.max_iterations.saturating_sub(done).max(1), ..p };
    let newton = solve_from(s, &rest, frame, &start.u, true, &mut |r, u, a| {
        observer(&InverseRecord { iteration: r.iteration + done, ..*r }, u, a);
    })?;
    let mut history = start.history;
    history.extend(newton.history.into_iter().map(|r| InverseRecord { iteration: r.iteration + done, ..r }));
    Ok(InverseSolution { history, ..newton })
}
