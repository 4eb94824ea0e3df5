//! Inverse problem of one frame: Problem 1 (41)–(43) solved by the monolithic scheme of
//! Problem 2, eq. (61), with the corrections and readings of `docs/inverse.md` (I1–I11).
//!
//! ```text
//!   ⎡ H_k   L_kᵀ ⎤ ⎡u⎤   ⎡h_k⎤     u = (x, α) state, û = (x̂, α̂) adjoint,
//!   ⎣ L_k   −C   ⎦ ⎣û⎦ = ⎣b_k⎦     f = x̂/λf, l = α̂/λl (eq. 54)
//! ```
//! `L_k`, `b_k`: the frozen operator of the forward fixed point (D5). `H_k`: the objective's
//! second-order terms with `d3` linearised as in (60) and the corrected sign of the λd term.
//! `C`: control mass matrices `(1/λf) M`, `(1/λl) M`.
//!
//! One entry point, [`FrameSolver`]: made once per mesh (it owns the KKT pattern, the LU
//! storage and the scratch, reused for every frame of a clip), it solves a [`Frame`] with the
//! method of its [`InverseParams`]:
//! - [`InverseMethod::FixedPoint`]: the paper's scheme, the state relaxed with w (Remark 10),
//!   [`fixed_point`];
//! - [`InverseMethod::Newton`]: Newton on the same discrete equations with the exact Jacobian
//!   (I8), [`newton`], started by the fixed point from a guess or directly from a start close
//!   to the solution ([`Start`]).
//!
//! Files: [`kkt`] (the element system of I4 and the boundary conditions of I5), [`measures`]
//! (fit and objective (41), I2), [`tracking`] (the data and nodal weights of the tracking term,
//! I14), [`fixed_point`], [`newton`].
//!
//! ## References
//! 1. Wang et al., Comput. Mech. 71 (2023), §3–4, eqs. (41), (52)–(61), Remark 6, Remark 10.
pub mod fixed_point;
pub mod kkt;
pub mod measures;
pub mod newton;
pub mod tracking;

pub use tracking::Tracking;

use std::ops::ControlFlow;

use nalgebra::{DVector, Vector3};

use super::certificate::{Certificate, System};
use super::{Problem, SolveError, Stall, Stop};
use crate::linalg::{LinearError, LinearSolver, Pattern};
use crate::model::mesh::DofMap;
use crate::model::rotation::Angles;

/// Regularisation weights of eq. (41).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weights {
    /// λg: weight of the tracking term ½λg ∫|x − x_g|²
    pub lambda_g: f64,
    /// λf: weight of the force control ½λf ∫|f|²
    pub lambda_f: f64,
    /// λl: weight of the torque control ½λl ∫|l|²
    pub lambda_l: f64,
    /// λd: weight of the shear–stretch penalty ½λd ∫|∂s x − d3|²
    pub lambda_d: f64,
    /// Λκ diagonal (bending and twist)
    pub lambda_kappa: Vector3<f64>,
    /// Λω diagonal (angular velocity; frames after the first only, Remark 6)
    pub lambda_omega: Vector3<f64>,
}

/// Nonlinear solver of one frame (`docs/inverse.md`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InverseMethod {
    /// The paper's relaxed fixed point (eq. 61, Remark 10).
    FixedPoint,
    /// Newton on the same discrete equations (I8). From a guess it starts at the fixed point's
    /// iterate whose relative change is ≤ `warm_start_tolerance`.
    Newton { warm_start_tolerance: f64 },
}

/// Default weight ε of the two-point rule in the λd term (I11): the smallest blend that makes the
/// (64) data converge for λd from 1e-10 to 10 (361–375 iterations at 1e-2…10; ε = 0, the
/// one-point rule, needs 2827 at 1e-2 and does not converge at 1 or 10). Where λd is small
/// against the bending stiffness or the Λκ term, [`default_stabilisation`] raises it.
pub const DEFAULT_STABILISATION: f64 = 1e-3;

/// The default ε of the λd term's blend (I11, I13) for the weights `w` on a rod of length
/// `length_m` [m] with bending and twist stiffnesses `bend_twist_nm2` [N m²]:
/// [`DEFAULT_STABILISATION`], raised to `max(J, Λκ) / (λd L²)` (at most 1). The penalty
/// `ε λd` on the within-element variation of `∂s x − d3` is then never weaker than the bending
/// stiffness or the curvature weight on the rod's length scale. Weaker, the nodal zig-zag of
/// the angles that the one-point rules cannot see is held by too little: Newton's Jacobian gets
/// a cluster of near-zero singular values and Newton stalls (`docs/inverse.md`, I13: eq. (64)
/// and (65) data with λd = 1e-6, where ε = 1e-3 stalls and ε ≥ 0.034 converges).
pub fn default_stabilisation(w: &Weights, bend_twist_nm2: &Vector3<f64>, length_m: f64) -> f64 {
    let held = bend_twist_nm2.amax().max(w.lambda_kappa.amax()) / (w.lambda_d * length_m * length_m);
    if held.is_nan() {
        DEFAULT_STABILISATION
    } else {
        held.clamp(DEFAULT_STABILISATION, 1.0)
    }
}

/// Settings of the inverse solver, the same for every frame of a clip.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InverseParams {
    pub weights: Weights,
    /// Δt between frames [s] (the Λω term)
    pub frame_interval_s: f64,
    /// Dirichlet value of the first angle α at s = 0 on the first frame [rad]; 0 in Remark 6,
    /// the rotation angle about e3 when the data are rotated rigidly about e3 (invariance)
    pub alpha0_rad: f64,
    /// weight ε ∈ [0, 1] of the two-point rule in the λd term (I11): the term is integrated
    /// with (1 − ε)·(the stretch–shear rule, D4) + ε·(2-point Gauss). 0 is the one-point rule;
    /// ε > 0 penalises the nodal zig-zag of the angles that the one-point rule cannot see
    /// (default [`DEFAULT_STABILISATION`]).
    pub stabilisation: f64,
    /// relaxation w ∈ (0, 1] of the fixed point (Remark 10); Newton's warm start uses it too
    pub relaxation: f64,
    pub method: InverseMethod,
    /// stopping rule: relative change of (x, α) (D5) ≤ tolerance (the fixed point: in
    /// [`crate::solve::PLATEAU_ITERATIONS`] consecutive iterations)
    pub tolerance: f64,
    /// iterations per frame (fixed point and Newton together)
    pub max_iterations: usize,
    /// a frame is converged only with its residual certificate (`kkt::certificate`,
    /// `docs/certificate.md`) at most this
    pub certificate_tolerance: f64,
}

/// Which iterations of a Newton solve keep a record (fit measures and objective terms, each a
/// few passes over the mesh; `docs/inverse.md`, I8).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Records {
    /// every iteration, each with its residual: the history a single frame's run writes
    #[default]
    Every,
    /// the last iteration only (its `iteration` is the count); the other iterations check
    /// their iterate and misfit for divergence ([`early_divergence`]), and a step that stops
    /// the solve (within the tolerance) is taken without assembling its residual, so that
    /// record has none. What a clip keeps of a frame: its report.
    Last,
}

/// The data of one frame.
#[derive(Clone, Copy, Debug)]
pub struct Frame<'a> {
    /// frame number, in records and errors
    pub index: usize,
    /// data positions x_g per node [m]
    pub x_g: &'a [Vector3<f64>],
    /// the previous frame's angles per node (the Λω term), or `None` on the first frame, which
    /// has α(0) = α0 instead and no Λω term (Remark 6)
    pub previous: Option<&'a [Angles]>,
    /// the nodal weight `w_i` of the tracking term (`clip::missing`, I14); `None`: w ≡ 1
    pub weight: Option<&'a [f64]>,
    /// `α(0) = α0` on this frame too although it is not the first (a planar recording, whose
    /// data do not hold the roll about the centreline: `solve::sequence::SequenceParams::plane`)
    pub fix_roll: bool,
}

impl<'a> Frame<'a> {
    pub fn is_first(&self) -> bool {
        self.previous.is_none()
    }

    /// Does the frame have the Dirichlet value `α(0) = α0` (the first frame, Remark 6, and every
    /// frame with [`Frame::fix_roll`])?
    pub fn fixes_alpha0(&self) -> bool {
        self.is_first() || self.fix_roll
    }

    /// The data of the tracking term: positions and weights.
    pub fn tracking(&self) -> Tracking<'a> {
        Tracking { x_g: self.x_g, weight: self.weight }
    }
}

/// One frame's problem as the inverse kernels take it: the rod, the inverse parameters, the
/// frame, and the previous frame's angles `α_{n−1}` per node in the frame's chart (zeros on a
/// first frame, whose Λω term is off).
#[derive(Clone, Copy)]
pub struct FrameProblem<'a> {
    pub problem: &'a Problem<'a>,
    pub params: &'a InverseParams,
    pub frame: &'a Frame<'a>,
    pub alpha_prev: &'a [Vector3<f64>],
}

impl<'a> FrameProblem<'a> {
    /// The problem of `frame`: its previous angles, or `no_previous` (zeros, one per node) on a
    /// first frame. Every kernel's caller builds it here.
    pub fn of(
        problem: &'a Problem<'a>,
        params: &'a InverseParams,
        frame: &'a Frame<'a>,
        no_previous: &'a [Vector3<f64>],
    ) -> Self {
        FrameProblem { problem, params, frame, alpha_prev: frame.previous.unwrap_or(no_previous) }
    }
}

/// Where a frame's solve starts from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Start {
    /// a guess (the reference state, the data guess): Newton is warm-started by the fixed point
    Guess,
    /// an iterate close to the solution (the previous frame's): Newton runs directly
    Near,
}

/// Per-iteration record (`docs/inverse.md`): relative change of (x, α) (D5),
/// ‖x − x_g‖/‖x_g‖ and ‖∂s x − d3‖ [L² norm, m^½] at the relaxed iterate, and the terms of
/// the objective (41) at that iterate with the controls of the last solve.
#[derive(Clone, Copy, Debug)]
pub struct InverseRecord {
    pub iteration: usize,
    pub rel_change: f64,
    pub x_err_rel: f64,
    pub tangent_misfit: f64,
    pub objective: ObjectiveTerms,
    /// Newton only (`docs/inverse.md`, I8): equilibrated KKT residual `‖D_r R(U)‖₂` after the
    /// step, relative to its value at the start of Newton; `None` for the fixed point
    pub residual: Option<f64>,
    /// the residual certificate of the iterate (`kkt::certificate`); `None` where it was not
    /// computed (a clip's Newton iterations before the last, [`Records::Last`])
    pub certificate: Option<f64>,
}

/// A frame's iterate whose centreline lies farther from the data than this multiple of the
/// data's own size (`‖x − x_g‖/‖x_g‖`, I2) has diverged: the straight start of a frame is
/// within 1 of any centreline of the same length.
pub const DIVERGED_X_ERR: f64 = 10.0;

impl InverseRecord {
    /// The first sign of divergence in this record and its iterate, as the error that stops
    /// the frame: a non-finite unknown or measure, or the misfit beyond [`DIVERGED_X_ERR`].
    pub(crate) fn divergence(&self, frame: usize, u: &DVector<f64>, adjoint: &DVector<f64>) -> Result<(), SolveError> {
        let o = &self.objective;
        let measures = [
            ("the relative change of (x, α)", self.rel_change),
            ("‖x − x_g‖/‖x_g‖", self.x_err_rel),
            ("‖∂s x − d3‖", self.tangent_misfit),
            ("the objective term λg/2 ∫|x − x_g|²", o.tracking),
            ("the objective term λf/2 ∫|f|²", o.force),
            ("the objective term λl/2 ∫|l|²", o.torque),
            ("the objective term λd/2 ∫|∂s x − d3|²", o.shear),
            ("the objective term ½∫κᵀΛκκ", o.bending),
            ("the objective term ½∫ωᵀΛωω", o.angular),
            ("the Newton residual ‖R‖/‖R₀‖", self.residual.unwrap_or(0.0)),
            ("the residual certificate", self.certificate.unwrap_or(0.0)),
        ];
        divergence(frame, self.iteration, &measures, self.x_err_rel, u, adjoint)
    }
}

/// [`InverseRecord::divergence`] of an iteration that keeps no record ([`Records::Last`]):
/// the same checks on what such an iteration has, its iterate, relative change and misfit
/// (the other measures are finite wherever the iterate is, short of overflow).
pub(crate) fn early_divergence(
    frame: usize,
    iteration: usize,
    rel_change: f64,
    x_err_rel: f64,
    u: &DVector<f64>,
    adjoint: &DVector<f64>,
) -> Result<(), SolveError> {
    let measures = [("the relative change of (x, α)", rel_change), ("‖x − x_g‖/‖x_g‖", x_err_rel)];
    divergence(frame, iteration, &measures, x_err_rel, u, adjoint)
}

/// The first non-finite unknown of `u`, `adjoint`, then the first non-finite measure, then
/// the misfit beyond [`DIVERGED_X_ERR`], as the error of iteration `iteration`.
fn divergence(
    frame: usize,
    iteration: usize,
    measures: &[(&'static str, f64)],
    x_err_rel: f64,
    u: &DVector<f64>,
    adjoint: &DVector<f64>,
) -> Result<(), SolveError> {
    let state = [("a state unknown (x, α)", u), ("an adjoint unknown (x̂, α̂)", adjoint)];
    let bad = state
        .iter()
        .find_map(|(q, v)| v.iter().find(|v| !v.is_finite()).map(|v| (*q, *v)))
        .or_else(|| measures.iter().find(|(_, v)| !v.is_finite()).copied())
        .or_else(|| (x_err_rel > DIVERGED_X_ERR).then_some(("‖x − x_g‖/‖x_g‖ (limit 10)", x_err_rel)));
    match bad {
        Some((quantity, value)) => Err(SolveError::InverseDiverged { frame, iteration, quantity, value }),
        None => Ok(()),
    }
}

/// The six terms of the objective (41), each with its weight and the ½, with the
/// integration rules of I2.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ObjectiveTerms {
    /// λg/2 ∫|x − x_g|²
    pub tracking: f64,
    /// λf/2 ∫|f|², f = x̂/λf (eq. 54)
    pub force: f64,
    /// λl/2 ∫|l|², l = α̂/λl (eq. 54)
    pub torque: f64,
    /// λd/2 ∫|∂s x − d3|²
    pub shear: f64,
    /// ½ ∫ κᵀ Λκ κ, κ = A ∂sα (eq. 28)
    pub bending: f64,
    /// ½ ∫ ωᵀ Λω ω, ω = A (α − α_{n−1})/Δt (eq. 27, backward difference; 0 on the first frame)
    pub angular: f64,
}

impl ObjectiveTerms {
    pub fn total(&self) -> f64 {
        self.tracking + self.force + self.torque + self.shear + self.bending + self.angular
    }
    /// Names in CSV order, with units (J = the objective's unit).
    pub const NAMES: [&'static str; 7] =
        ["j_tracking", "j_force", "j_torque", "j_shear", "j_bending", "j_angular", "j_total"];
    pub fn values(&self) -> [f64; 7] {
        [self.tracking, self.force, self.torque, self.shear, self.bending, self.angular, self.total()]
    }
}

/// The result of one frame: the last iterate, its history and why it stopped.
#[derive(Clone, Debug)]
pub struct InverseSolution {
    /// state `(x, α)` (forward layout)
    pub u: DVector<f64>,
    /// adjoint `(x̂, α̂)` (forward layout) of the last solve
    pub adjoint: DVector<f64>,
    pub history: Vec<InverseRecord>,
    /// [`Stop::MaxIterations`] or [`Stop::Stalled`]: `u` is the last iterate (see
    /// [`InverseSolution::converged`])
    pub stop: Stop,
    /// the residual certificate at `(u, adjoint)` (`kkt::certificate`)
    pub certificate: Certificate,
    /// the tolerance it was held to
    pub certificate_tolerance: f64,
}

impl InverseSolution {
    /// The solution if it met the stopping rule, else the error of frame `frame` with the
    /// iterations and the last relative change (fixed point) or Newton residual.
    pub fn converged(self, frame: usize) -> Result<Self, SolveError> {
        if self.stop == Stop::Converged {
            return Ok(self);
        }
        let last = self.history.last();
        let iterations = last.map_or(0, |r| r.iteration);
        let rel_change = last.map(|r| r.rel_change).unwrap_or(f64::NAN);
        let newton = self.history.iter().any(|r| r.residual.is_some());
        Err(match (self.stop, last.and_then(|r| r.residual)) {
            (Stop::Stalled, _) => SolveError::Stalled(Box::new(Stall {
                solver: format!("inverse {} of frame {frame}", if newton { "Newton" } else { "fixed point" }),
                iterations,
                rel_change,
                certificate: self.certificate.value,
                tolerance: self.certificate_tolerance,
                block: self.certificate.worst_block(System::Kkt),
            })),
            (_, Some(residual)) => SolveError::InverseNewtonNotConverged {
                frame,
                iterations,
                residual,
                certificate: self.certificate.value,
            },
            (_, None) if newton => SolveError::InverseNewtonNotConverged {
                frame,
                iterations,
                residual: f64::NAN,
                certificate: self.certificate.value,
            },
            (_, None) => SolveError::InverseNotConverged { frame, iterations, rel_change },
        })
    }
}

/// The one entry point of the inverse problem of a frame: the method of its params, and what
/// every frame of a clip reuses (built once per mesh): the KKT sparsity pattern
/// ([`DofMap::kkt`] layout, block tridiagonal), the banded LU's storage and scratch
/// ([`LinearSolver`]), the value arrays of the Jacobian and the line search, and the Dirichlet
/// rows of I5 (refilled per frame: the positions depend only on whether the frame is the
/// first, the values on its data).
///
/// ```ignore
/// let mut solver = FrameSolver::new(&problem, params);   // once per clip
/// for frame in frames {
///     let sol = solver.solve(&frame, &u0, Start::Near, |_, _, _| {})?.converged(frame.index)?;
/// }
/// ```
pub struct FrameSolver<'p> {
    pub(crate) problem: &'p Problem<'p>,
    pub(crate) params: InverseParams,
    pub(crate) dofs: DofMap,
    pub(crate) pattern: Pattern,
    pub(crate) solver: LinearSolver,
    /// the Dirichlet conditions of I5 of the frame being solved
    pub(crate) dirichlet: Dirichlet,
    /// the value arrays refilled per frame
    pub(crate) work: Workspace,
    /// zero angles: the `α_{n−1}` of a first frame (its Λω term is off)
    pub(crate) no_previous: Vec<Angles>,
    /// which Newton iterations keep a record
    pub(crate) records: Records,
    /// polled after every recorded iteration: `true` stops the solve there with
    /// [`SolveError::Interrupted`] ([`FrameSolver::stopped_by`])
    pub(crate) stop: Option<fn() -> bool>,
}

/// How a frame's linear solve scales its matrix (I6).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Scaling {
    /// by a Ruiz equilibration of this matrix ([`LinearSolver::solve_equilibrated`])
    Equilibrated,
    /// by the factors of the frame's last equilibration, for a matrix of the same frame
    /// ([`LinearSolver::solve_rescaled`])
    Rescaled,
}

/// The Dirichlet conditions of I5 of a frame, refilled per frame: the positions depend only
/// on whether the frame is the first, the values on its data.
#[derive(Default)]
pub(crate) struct Dirichlet {
    /// the fixed unknowns (KKT numbering) and their values: `x = x_g` [m] and `x̂ = α̂ = 0` at
    /// both ends, and on the first frame `α(0) = α0` [rad] ([`kkt::dirichlet_into`])
    pub(crate) fixed: Vec<(usize, f64)>,
    /// the fixed unknowns alone: the rows of the system set to identity rows
    pub(crate) rows: Vec<usize>,
}

/// The value arrays of a [`FrameSolver`], kept between frames so that no frame allocates them.
pub(crate) struct Workspace {
    /// system (Jacobian) values, in the pattern's order
    pub(crate) values: Vec<f64>,
    /// Newton: the residual merit's row weights (Ruiz row factors of the first Jacobian)
    pub(crate) merit_weights: Vec<f64>,
    /// scratch matrix values of the certificate's system (`kkt::certificate`)
    pub(crate) cert_values: Vec<f64>,
}

impl<'p> FrameSolver<'p> {
    /// A solver for the mesh of `problem`.
    pub fn new(problem: &'p Problem<'p>, params: InverseParams) -> Self {
        let dofs = problem.mesh.kkt_dofs();
        let pattern = dofs.pattern();
        let solver = LinearSolver::new(&pattern);
        let values = vec![0.0; pattern.nnz()];
        FrameSolver {
            problem,
            params,
            dofs,
            pattern,
            solver,
            dirichlet: Dirichlet::default(),
            work: Workspace { values, merit_weights: Vec::new(), cert_values: Vec::new() },
            no_previous: vec![Vector3::zeros(); problem.mesh.nodes()],
            records: Records::Every,
            stop: None,
        }
    }

    /// The solver keeping the records `records` of its Newton iterations (the fixed point
    /// keeps every record).
    pub fn with_records(self, records: Records) -> Self {
        FrameSolver { records, ..self }
    }

    /// Stop a solve at its next recorded iteration once `requested()` says so (e.g.
    /// `crate::interrupt::requested`): the solve returns [`SolveError::Interrupted`] with that
    /// iteration. Without it a solve runs to its end (a clip stops between frames instead).
    pub fn stopped_by(self, requested: fn() -> bool) -> Self {
        FrameSolver { stop: Some(requested), ..self }
    }

    pub fn params(&self) -> &InverseParams {
        &self.params
    }

    /// Solve one frame from the state `u0` (forward layout) by the method of the params (see
    /// [`Start`]). `observer` sees every iteration's record, state and adjoint. Hitting the
    /// iteration limit is not an error here: the solution says [`Stop::MaxIterations`].
    pub fn solve(
        &mut self,
        frame: &Frame,
        u0: &DVector<f64>,
        start: Start,
        mut observer: impl FnMut(&InverseRecord, &DVector<f64>, &DVector<f64>),
    ) -> Result<InverseSolution, SolveError> {
        let expected = self.problem.mesh.nodes();
        let fwd = self.problem.dofs();
        for (what, nodes) in [
            ("data x_g", frame.x_g.len()),
            ("tracking weights", frame.weight.map_or(expected, <[f64]>::len)),
            ("previous frame's angles", frame.previous.map_or(expected, <[Angles]>::len)),
            ("initial state", if u0.len() == fwd.len() { expected } else { u0.len() / fwd.block() }),
        ] {
            if nodes != expected {
                return Err(SolveError::NodeCount { what, nodes, expected });
            }
        }
        self.set_dirichlet(frame);
        let params = self.params;
        // the observer, then the stop token: the iteration a stop was requested after
        let (stop, mut stopped_at) = (self.stop, 0);
        let mut watch = |r: &InverseRecord, u: &DVector<f64>, a: &DVector<f64>| {
            observer(r, u, a);
            stopped_at = r.iteration;
            if stop.is_some_and(|requested| requested()) {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        };
        let solved = match (params.method, start) {
            (InverseMethod::FixedPoint, _) => fixed_point::solve(self, &params, frame, u0, &mut watch),
            (InverseMethod::Newton { .. }, Start::Near) => newton::solve(self, &params, frame, u0, &mut watch),
            (InverseMethod::Newton { warm_start_tolerance }, Start::Guess) => {
                newton::solve_warm(self, warm_start_tolerance, frame, u0, &mut watch)
            }
        };
        solved.map_err(|e| match e {
            SolveError::Linear(LinearError::ZeroPivot { column, .. }) => self.singular(frame.index, column),
            SolveError::Interrupted { what, .. } => {
                SolveError::Interrupted { what, done: stopped_at, total: params.max_iterations }
            }
            e => e,
        })
    }

    /// The error of a KKT matrix singular to working precision at unknown `column` (KKT
    /// numbering), with the likely cause: a Λκ term that outweighs the bending stiffness by
    /// more than the precision can hold, integrated by a one-point rule (`docs/inverse.md`, I13).
    fn singular(&self, frame: usize, column: usize) -> SolveError {
        const NAMES: [&str; 12] = ["x", "y", "z", "α", "β", "γ", "x̂1", "x̂2", "x̂3", "α̂1", "α̂2", "α̂3"];
        let block = self.dofs.block();
        let unknown = format!("{} of node {}", NAMES[column % block], column / block);
        let stiffness = self.problem.props.bend_twist_nm2.amin();
        let ratio = self.params.weights.lambda_kappa.amax() / stiffness;
        let one_point = self.problem.scheme.kappa().points.len() == 1;
        let cause = if ratio > 1e10 && one_point {
            format!(
                "the curvature weight max Λκ = {:e} outweighs the bending stiffness {stiffness:e} N m² by {ratio:.1e}; integrated at one point per element (solver.quadrature = \"{}\"), the Λκ term constrains one combination of the angle rates per element and leaves the other to the bending stiffness alone, and both the equilibrated and the plain band LU lose it (docs/inverse.md, I13): use solver.quadrature = \"gauss2\" or a smaller Λκ",
                self.params.weights.lambda_kappa.amax(),
                self.problem.scheme.name()
            )
        } else {
            "the equilibrated KKT matrix has no usable pivot there (docs/inverse.md, I6)".to_string()
        };
        SolveError::InverseSingular { frame, unknown, cause }
    }

    /// The residual certificate of the state `u` with the adjoint `adjoint` (forward layout
    /// each) for `frame` (`kkt::certificate`).
    pub(crate) fn certify(&mut self, frame: &Frame, u: &DVector<f64>, adjoint: &DVector<f64>) -> Certificate {
        let big = self.dofs.kkt_join(u, adjoint);
        self.certify_kkt(frame, &big)
    }

    /// [`FrameSolver::certify`] of a KKT vector.
    pub(crate) fn certify_kkt(&mut self, frame: &Frame, big: &DVector<f64>) -> Certificate {
        self.work.cert_values.resize(self.pattern.nnz(), 0.0);
        let fp = FrameProblem::of(self.problem, &self.params, frame, &self.no_previous);
        kkt::certificate(fp, big, &self.pattern, &mut self.work.cert_values)
    }

    /// Dirichlet rows and values of I5 for the frame.
    fn set_dirichlet(&mut self, frame: &Frame) {
        kkt::dirichlet_into(&self.dofs, self.params.alpha0_rad, frame, &mut self.dirichlet.fixed);
        self.dirichlet.rows.clear();
        self.dirichlet.rows.extend(self.dirichlet.fixed.iter().map(|f| f.0));
    }

    /// Solve `K(u) U = r(u)` of I4 with the boundary conditions of I5 (equilibrated, I6); `U`
    /// has the KKT layout, the matrix scaled as `scaling` says.
    pub(crate) fn solve_linearised(
        &mut self,
        params: &InverseParams,
        frame: &Frame,
        u: &DVector<f64>,
        scaling: Scaling,
    ) -> Result<DVector<f64>, SolveError> {
        let fp = FrameProblem::of(self.problem, params, frame, &self.no_previous);
        let mut rhs = kkt::assemble_system(fp, &self.pattern, &mut self.work.values, u);
        for &(d, v) in &self.dirichlet.fixed {
            rhs[d] = v;
        }
        self.pattern.set_identity_rows(&mut self.work.values, &self.dirichlet.rows);
        Ok(match scaling {
            Scaling::Rescaled => self.solver.solve_rescaled(&self.work.values, &rhs)?,
            Scaling::Equilibrated => self.solver.solve_equilibrated(&self.work.values, &rhs)?,
        })
    }
}
