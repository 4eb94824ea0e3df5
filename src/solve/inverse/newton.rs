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
use std::ops::ControlFlow;

use nalgebra::{DVector, Matrix3, Vector3};

use super::kkt::{
    add_node_pairs, add_operator_blocks, element_part, element_system, Blocks, KktMat, KktVec, Part, PointRule, AL, X,
};
use super::measures::{position_error, record};
use super::{
    early_divergence, Frame, FrameProblem, FrameSolver, InverseParams, InverseRecord, InverseSolution, Records, Scaling,
};
use crate::assemble::{assemble, Tangent};
use crate::linalg::Pattern;
use crate::model::element::{internal_force, interpolate, ElementRest, LocalMat};
use crate::model::mesh::DofMap;
use crate::model::rotation::{
    a_matrix, a_matrix_derivatives, d3, d3_second_derivatives, rotation, rotation_derivatives, skew, Derivatives,
    PointFrame,
};
use crate::solve::certificate::Certificate;
use crate::solve::statics::relative_change;
use crate::solve::{SolveError, Stop, CHORD_CONTRACTION};

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

/// `∂/∂u [K_e(u) V − r_e(u)]` at `V = U_e` for element `element` of the frame's problem `fp`
/// (24 × 24, KKT numbering; only the state columns are non-zero), added into `e`: the
/// derivative of the frozen coefficients of I4;
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
fn coefficient_derivative(fp: &FrameProblem<'_>, element: usize, ue: &KktVec, l: &LocalMat, e: &mut KktMat) {
    let FrameProblem { problem, params: p, frame, alpha_prev } = *fp;
    let alpha_prev = [alpha_prev[element], alpha_prev[element + 1]];
    let h = problem.mesh.h();
    let props = &problem.props;
    let w8 = &p.weights;
    let (state, adj) = (element_part(ue, Part::State), element_part(ue, Part::Adjoint));
    // Primal rows: ∂G/∂u − L(u).
    let mut t = LocalMat::zeros();
    internal_force(props, problem.scheme, h, &state, &ElementRest::ZERO, Some(&mut t));
    add_operator_blocks(e, &(t - l), Blocks::AdjointRows);
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
        // ∂S/∂α_j v = dQ_jᵀ K (Q v) + Qᵀ K (dQ_j v)
        let dS_v = product_rule((&Q, &dQ), &K, (&Q, &dQ), &v);
        let dS_dx = -S * skew(&qa.alpha);
        add_node_pairs(e, (X, AL), &dS_v, wh, (&q.dn, &q.n));
        add_node_pairs(e, (X, X), &dS_dx, wh, (&q.dn, &q.dn));
    }
    // The λd term's rule (I11): the second derivative of d3 in −λd ∫ δα·D(α)ᵀ(∂s x − d3).
    for (xi, w) in PointRule::tangent(problem, p.stabilisation).iter() {
        let q = interpolate(&state, h, xi);
        let dd = d3_second_derivatives(&q.alpha);
        let mis = q.dx - d3(&q.alpha);
        let H2 = Matrix3::from_fn(|i, j| mis.dot(&dd[i][j])) * (-w8.lambda_d);
        add_node_pairs(e, (AL, AL), &H2, w * h, (&q.n, &q.n));
    }
    // Bending rule: L(u)ᵀ û on the α rows.
    for (xi, w) in problem.scheme.bending().iter() {
        let (q, qa) = (interpolate(&state, h, xi), interpolate(&adj, h, xi));
        let f = PointFrame::new(&q.alpha, Derivatives::With);
        // (dQ_jᵀ J A + Qᵀ J dA_j)ᵀ w = dA_jᵀ J (Q w) + Aᵀ J (dQ_j w), w = ∂s α̂
        let blk = product_rule((&f.a, &f.da), &Jm, (&f.q, &f.dq), &qa.dalpha);
        add_node_pairs(e, (AL, AL), &blk, w * h, (&q.dn, &q.n));
    }
    // The Λκ term's rule (I12).
    if w8.lambda_kappa.amax() > 0.0 {
        let Lk = Matrix3::from_diagonal(&w8.lambda_kappa);
        for (xi, w) in problem.scheme.kappa().iter() {
            let q = interpolate(&state, h, xi);
            let (A, dA) = (a_matrix(&q.alpha), a_matrix_derivatives(&q.alpha));
            let blk = product_rule((&A, &dA), &Lk, (&A, &dA), &q.dalpha);
            add_node_pairs(e, (AL, AL), &blk, w * h, (&q.dn, &q.n));
        }
    }
    // Load rule: the Λω term (as in `element_system`).
    if !frame.is_first() && w8.lambda_omega.amax() > 0.0 {
        let dt = p.frame_interval_s;
        let Lw = Matrix3::from_diagonal(&w8.lambda_omega) / (dt * dt);
        for (xi, w) in problem.scheme.objective().iter() {
            let q = interpolate(&state, h, xi);
            let (A, dA) = (a_matrix(&q.alpha), a_matrix_derivatives(&q.alpha));
            let da = q.alpha - (alpha_prev[0] * q.n[0] + alpha_prev[1] * q.n[1]);
            let blk = product_rule((&A, &dA), &Lw, (&A, &dA), &da);
            add_node_pairs(e, (AL, AL), &blk, w * h, (&q.n, &q.n));
        }
    }
}

/// The product rule of every coefficient derivative above: the 3 × 3 block whose column j is
/// `∂/∂α_j [Pᵀ M R] v = dP_jᵀ (M R v) + Pᵀ M (dR_j v)` (`(P, dP)`, `(R, dR)`: a matrix of the
/// angles and its derivatives in α_1, α_2, α_3; `M R v` formed once).
fn product_rule(
    (p, dp): (&Matrix3<f64>, &[Matrix3<f64>; 3]),
    m: &Matrix3<f64>,
    (r, dr): (&Matrix3<f64>, &[Matrix3<f64>; 3]),
    v: &Vector3<f64>,
) -> Matrix3<f64> {
    let mrv = m * (r * v);
    Matrix3::from_columns(&[0, 1, 2].map(|j| dp[j].transpose() * mrv + p.transpose() * (m * (dr[j] * v))))
}

/// Newton residual `R(U) = K(u) U − r(u)` of I8 (KKT layout, Dirichlet rows `U_d − v_d` of
/// `fixed`, I5) and, when `jacobian = Some((pattern, values, rows))`, its exact Jacobian `J(U)`
/// into `values` (the Dirichlet `rows` identity). One pass of the element loop; without the
/// Jacobian the same element sums in the same order, so the same residual.
pub fn assemble_residual(
    fp: FrameProblem<'_>,
    big: &DVector<f64>,
    fixed: &[(usize, f64)],
    jacobian: Option<(&Pattern, &mut [f64], &[usize])>,
) -> DVector<f64> {
    let dofs = fp.problem.mesh.kkt_dofs();
    let mut scratch = KktMat::zeros();
    let kernel = |e: usize, t: Option<&mut KktMat>| {
        let ue: KktVec = dofs.gather(big, e);
        let uk = element_part(&ue, Part::State);
        let jacobian = t.is_some();
        let m = t.unwrap_or_else(|| {
            scratch.as_mut_slice().fill(0.0);
            &mut scratch
        });
        let (rhs, l) = element_system(&fp, e, &uk, m);
        // by reference: `*m * ue` would copy the 24 × 24 matrix first
        #[allow(clippy::op_ref)]
        let r = &*m * ue - rhs;
        if jacobian {
            coefficient_derivative(&fp, e, &ue, &l, m);
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
    observer: &mut impl FnMut(&InverseRecord, &DVector<f64>, &DVector<f64>) -> ControlFlow<()>,
) -> Result<InverseSolution, SolveError> {
    solve_from(s, params, frame, u0, Scaling::Equilibrated, observer)
}

/// [`solve`], the consistent start scaled as `scaling` says: [`Scaling::Rescaled`] where the
/// frame's Ruiz factors exist already (the warm start's fixed point computed them).
/// Each iteration is one [`Newton::attempt`], or two when a chord step is rejected and the
/// iteration is redone as Newton's ([`Mode`]).
fn solve_from(
    s: &mut FrameSolver,
    params: &InverseParams,
    frame: &Frame,
    u0: &DVector<f64>,
    scaling: Scaling,
    observer: &mut impl FnMut(&InverseRecord, &DVector<f64>, &DVector<f64>) -> ControlFlow<()>,
) -> Result<InverseSolution, SolveError> {
    // Consistent start: one linear solve of the fixed point at u0.
    let big = s.solve_linearised(params, frame, u0, scaling)?;
    let fwd = s.problem.dofs();
    s.work.cert_values.resize(s.pattern.nnz(), 0.0);
    let lean = s.records == Records::Last;
    // the Ruiz row factors of the start's matrix weigh the merit of the whole frame (I6)
    s.work.merit_weights.clear();
    s.work.merit_weights.extend_from_slice(s.solver.row_factors());
    let mut it = Iterate {
        u: s.dofs.kkt_state(&big),
        big,
        adjoint: fwd.zeros(),
        next: None,
        mode: Mode::Newton,
        damped: false,
        previous: f64::INFINITY,
        phi0: f64::NAN,
        phis: Vec::new(),
        history: Vec::new(),
    };
    let mut newton = Newton { s, params, frame, fwd, lean };
    for k in 1..=params.max_iterations {
        loop {
            match newton.attempt(&mut it, k, observer)? {
                // too weak a contraction for the frozen Jacobian, or a step the merit rejects:
                // the iteration is Newton's
                Attempt::ChordRejected => it.mode = Mode::Newton,
                Attempt::Taken => break,
                Attempt::Done(stop, c) => return Ok(newton.done(it, stop, c)),
            }
        }
    }
    let c = newton.certify(&it.big);
    Ok(newton.done(it, Stop::MaxIterations, c))
}

/// How an iteration of [`solve_from`] solves for its step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    /// with the Jacobian at the iterate (assembled here, or by the last line search)
    Newton,
    /// with the last factorisation (a chord step)
    Chord,
}

/// What an assembly of [`Newton::residual`] gives: the residual alone, or with the Jacobian.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Eval {
    Residual,
    WithJacobian,
}

/// An iteration's step as [`Newton::attempt`] judges it before the line search.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum StepKind {
    /// its relative change is within the tolerance: taken whole, without the line search
    WithinTolerance,
    /// searched; the next iteration is predicted to be a chord step ([`CHORD_RATE`])
    ChordNext,
    /// searched; the next iteration is Newton's
    NewtonNext,
}

/// What became of an attempt at an iteration.
enum Attempt {
    /// a chord step rejected: the iteration is attempted again as Newton's
    ChordRejected,
    /// the step was taken; the next iteration follows
    Taken,
    /// the solve ends with this stop and the certificate of its iterate
    Done(Stop, Certificate),
}

/// The iterate of [`solve_from`] and what one iteration hands to the next.
struct Iterate {
    /// the KKT vector `(x, α, x̂, α̂)` and its state and adjoint parts (forward layout)
    big: DVector<f64>,
    u: DVector<f64>,
    adjoint: DVector<f64>,
    /// the residual at `big` when the line search already assembled it (with the Jacobian,
    /// unless the next iteration is a chord step)
    next: Option<DVector<f64>>,
    mode: Mode,
    /// the last step was damped by the line search: the next full step is then tried with its
    /// residual alone (its Jacobian is wasted if the merit rejects it, as after a damped step it
    /// often does)
    damped: bool,
    /// relative change of the last step
    previous: f64,
    /// the merit at the start, and at the start of each Newton iteration (stall detection)
    phi0: f64,
    phis: Vec<f64>,
    history: Vec<InverseRecord>,
}

/// What stays fixed over a frame's Newton iteration: the solver (pattern, LU, Dirichlet rows,
/// merit weights) and the frame.
struct Newton<'a, 'p, 'f> {
    s: &'a mut FrameSolver<'p>,
    params: &'a InverseParams,
    frame: &'a Frame<'f>,
    fwd: DofMap,
    /// only the last record is kept ([`Records::Last`])
    lean: bool,
}

impl Newton<'_, '_, '_> {
    /// The merit: the residual's norm weighted by the start's Ruiz row factors (I6).
    fn merit(&self, r: &DVector<f64>) -> f64 {
        r.iter().zip(self.s.work.merit_weights.iter()).map(|(a, b)| (a * b).powi(2)).sum::<f64>().sqrt()
    }

    /// The residual at `big` ([`assemble_residual`]), with the Jacobian into the solver's
    /// values for [`Eval::WithJacobian`].
    fn residual(&mut self, big: &DVector<f64>, eval: Eval) -> DVector<f64> {
        let s = &mut *self.s;
        let fp = FrameProblem::of(s.problem, self.params, self.frame, &s.no_previous);
        let jacobian = (eval == Eval::WithJacobian).then_some((
            &s.pattern,
            s.work.values.as_mut_slice(),
            s.dirichlet.rows.as_slice(),
        ));
        assemble_residual(fp, big, &s.dirichlet.fixed, jacobian)
    }

    /// The residual certificate of `big` (`kkt::certificate`).
    fn certify(&mut self, big: &DVector<f64>) -> Certificate {
        let s = &mut *self.s;
        let fp = FrameProblem::of(s.problem, self.params, self.frame, &s.no_previous);
        super::kkt::certificate(fp, big, &s.pattern, &mut s.work.cert_values)
    }

    /// The record of iteration `k` (`measures::record`).
    fn record(
        &self,
        k: usize,
        change: f64,
        u: &DVector<f64>,
        adjoint: &DVector<f64>,
        residual: Option<f64>,
    ) -> InverseRecord {
        let fp = FrameProblem::of(self.s.problem, self.params, self.frame, &self.s.no_previous);
        record(fp, (k, change), u, adjoint, residual)
    }

    fn done(&self, it: Iterate, stop: Stop, certificate: Certificate) -> InverseSolution {
        InverseSolution {
            u: it.u,
            adjoint: it.adjoint,
            history: it.history,
            stop,
            certificate,
            certificate_tolerance: self.params.certificate_tolerance,
        }
    }

    /// Iteration `k` in the iterate's mode: the step, the stall test, the chord step's
    /// contraction test, the line search and the step taken.
    fn attempt(
        &mut self,
        it: &mut Iterate,
        k: usize,
        observer: &mut impl FnMut(&InverseRecord, &DVector<f64>, &DVector<f64>) -> ControlFlow<()>,
    ) -> Result<Attempt, SolveError> {
        let chord = it.mode == Mode::Chord;
        let r = match it.next.take() {
            Some(r) => r,
            None => self.residual(&it.big, if chord { Eval::Residual } else { Eval::WithJacobian }),
        };
        let delta = if chord {
            self.s.solver.solve_factored(&(-&r))?
        } else {
            self.s.solver.solve_rescaled(&self.s.work.values, &(-&r))?
        };
        let phi = self.merit(&r);
        if k == 1 {
            it.phi0 = phi;
        }
        if !chord {
            it.phis.push(phi);
        }
        // stalled: the merit fell by less than STALL_DECREASE over STALL_WINDOW iterations
        let n = it.phis.len();
        if !chord && n > STALL_WINDOW && phi > (1.0 - STALL_DECREASE) * it.phis[n - 1 - STALL_WINDOW] {
            let (stop, c) = self.stall(it, k, phi, observer);
            return Ok(Attempt::Done(stop, c));
        }
        let dofs = self.s.dofs;
        let change = relative_change(&self.fwd, &dofs.kkt_state(&(&it.big + &delta)), &dofs.kkt_state(&it.big));
        // A full step whose relative change is within the tolerance is taken without the
        // line search: the merit is then at its round-off floor and cannot decrease reliably.
        let full = change <= self.params.tolerance;
        if chord && !full && change > CHORD_CONTRACTION * it.previous {
            return Ok(Attempt::ChordRejected);
        }
        // the next iteration reuses this factorisation if a chord step is predicted to
        // contract by CHORD_RATE: the square of this Newton step's contraction, or a chord
        // step's own
        let rate = match (chord, k) {
            (_, 1) => f64::INFINITY,
            (true, _) => change / it.previous,
            (false, _) => (change / it.previous).powi(2),
        };
        let kind = match (full, rate <= CHORD_RATE) {
            (true, _) => StepKind::WithinTolerance,
            (false, true) => StepKind::ChordNext,
            (false, false) => StepKind::NewtonNext,
        };
        let Some((t, trial, phi_t)) = self.line_search(it, &delta, phi, kind) else {
            return Ok(Attempt::ChordRejected);
        };
        it.mode = if kind == StepKind::ChordNext && t == 1.0 { Mode::Chord } else { Mode::Newton };
        it.damped = t < 1.0;
        self.take_step(it, k, trial, kind, phi_t, observer)
    }

    /// A stalled iteration `k` (merit `phi`): converged if its iterate is certified; a lean
    /// solve records the iterate it returns (it kept no record of it).
    fn stall(
        &mut self,
        it: &mut Iterate,
        k: usize,
        phi: f64,
        observer: &mut impl FnMut(&InverseRecord, &DVector<f64>, &DVector<f64>) -> ControlFlow<()>,
    ) -> (Stop, Certificate) {
        let c = self.certify(&it.big);
        let stop = if c.within(self.params.certificate_tolerance) { Stop::Converged } else { Stop::Stalled };
        if self.lean {
            let rec = InverseRecord {
                certificate: Some(c.value),
                ..self.record(k - 1, it.previous, &it.u, &it.adjoint, Some(phi / it.phi0))
            };
            // the solve ends here whatever the observer asks
            let _ = observer(&rec, &it.u, &it.adjoint);
            it.history.push(rec);
        }
        (stop, c)
    }

    /// The backtracking line search along `delta` from the iterate (merit `phi`): the step
    /// length, the trial iterate and its merit (NaN where its residual was not assembled);
    /// `None`: a chord step the merit rejects.
    fn line_search(
        &mut self,
        it: &mut Iterate,
        delta: &DVector<f64>,
        phi: f64,
        kind: StepKind,
    ) -> Option<(f64, DVector<f64>, f64)> {
        let chord = it.mode == Mode::Chord;
        let (full, chord_next) = (kind == StepKind::WithinTolerance, kind == StepKind::ChordNext);
        let mut t = 1.0;
        loop {
            let trial = &it.big + delta * t;
            // The full step of an iteration that is not the last is usually accepted: its
            // residual comes with the Jacobian (unless a chord step follows), which the next
            // iteration then uses (the same element sums, so the same residual as assembling
            // it there).
            let with_jacobian = t == 1.0 && !full && !chord_next && !it.damped;
            let eval = if with_jacobian { Eval::WithJacobian } else { Eval::Residual };
            // the last step is taken without its residual where no record needs it
            if full && self.lean {
                return Some((t, trial, f64::NAN));
            }
            let r_t = self.residual(&trial, eval);
            let phi_t = self.merit(&r_t);
            if full || phi_t <= (1.0 - ARMIJO * t) * phi || t <= MIN_STEP {
                if t == 1.0 && !full && (with_jacobian || chord_next) {
                    it.next = Some(r_t);
                }
                return Some((t, trial, phi_t));
            }
            if chord {
                return None;
            }
            t *= 0.5;
        }
    }

    /// Take the step to `trial` (merit `phi_t`) as iteration `k`: record it (a lean solve only
    /// checks for divergence until the last iteration) and stop if it is certified within the
    /// tolerance, or the last.
    fn take_step(
        &mut self,
        it: &mut Iterate,
        k: usize,
        trial: DVector<f64>,
        kind: StepKind,
        phi_t: f64,
        observer: &mut impl FnMut(&InverseRecord, &DVector<f64>, &DVector<f64>) -> ControlFlow<()>,
    ) -> Result<Attempt, SolveError> {
        let full = kind == StepKind::WithinTolerance;
        let dofs = self.s.dofs;
        let u_old = dofs.kkt_state(&it.big);
        it.u = dofs.kkt_state(&trial);
        let rel_change = relative_change(&self.fwd, &it.u, &u_old);
        it.previous = rel_change;
        it.big = trial;
        it.adjoint = dofs.kkt_adjoint(&it.big);
        let last = k == self.params.max_iterations;
        let cert = (!self.lean || full || last).then(|| self.certify(&it.big));
        if self.lean && !full && !last {
            let x_err = position_error(self.s.problem, &it.u, self.frame.tracking());
            early_divergence(self.frame.index, k, rel_change, x_err, &it.u, &it.adjoint)?;
        } else {
            let residual = (!(full && self.lean)).then_some(phi_t / it.phi0);
            let rec = InverseRecord {
                certificate: cert.map(|c| c.value),
                ..self.record(k, rel_change, &it.u, &it.adjoint, residual)
            };
            rec.divergence(self.frame.index, &it.u, &it.adjoint)?;
            let stop_requested = observer(&rec, &it.u, &it.adjoint).is_break();
            it.history.push(rec);
            if stop_requested {
                return Err(SolveError::Interrupted { what: "iterations", done: 0, total: 0 });
            }
        }
        match cert {
            Some(c) if full && c.within(self.params.certificate_tolerance) => {
                return Ok(Attempt::Done(Stop::Converged, c));
            }
            Some(c) if last => return Ok(Attempt::Done(Stop::MaxIterations, c)),
            // a step within the tolerance whose iterate is not certified: go on with Newton
            _ if full => (it.next, it.mode) = (None, Mode::Newton),
            _ => {}
        }
        Ok(Attempt::Taken)
    }
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
    observer: &mut impl FnMut(&InverseRecord, &DVector<f64>, &DVector<f64>) -> ControlFlow<()>,
) -> Result<InverseSolution, SolveError> {
    let p = s.params;
    let warm = InverseParams { tolerance: warm_start_tolerance.max(p.tolerance), ..p };
    let start = super::fixed_point::run(s, &warm, frame, u0, super::fixed_point::StopRule::FirstDip, observer)?;
    if start.stop != Stop::Converged {
        return Ok(start);
    }
    let done = start.history.len();
    let rest = InverseParams { max_iterations: p.max_iterations.saturating_sub(done).max(1), ..p };
    let newton = solve_from(s, &rest, frame, &start.u, Scaling::Rescaled, &mut |r, u, a| {
        observer(&InverseRecord { iteration: r.iteration + done, ..*r }, u, a)
    })?;
    let mut history = start.history;
    history.extend(newton.history.into_iter().map(|r| InverseRecord { iteration: r.iteration + done, ..r }));
    Ok(InverseSolution { history, ..newton })
}
