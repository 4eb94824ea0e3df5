//! Path following through limit points (`docs/decisions.md`, D25): Crisfield's cylindrical
//! arc-length method on the static equations of D3 with the load factor λ as an unknown.
//!
//! ```text
//!   R(u, λ) = G(u) − F(u; λ) = 0,   F(u; λ) = λ F₁(u)            (loads, D3/D23; held values at λ, D22)
//!   ‖Δu‖_w² = Δl²,   ‖v‖_w² = (1/N) Σ_i (|v_x,i|² / L² + |v_α,i|²)   (cylindrical: no λ term)
//!   predictor:  K q_t = ∂F/∂λ,  Δλ = ± Δl / ‖q_t‖_w  (the sign keeps ⟨q_t, Δu_prev⟩_w > 0)
//!   corrector:  K δu_R = −R,  K δu_T = ∂F/∂λ,  δu = δu_R + δλ δu_T,  ‖Δu + δu‖_w = Δl
//!               (the root δλ whose step stays closest to the previous direction)
//! ```
//! A step converges when Newton's increment measure (D5) is within the tolerance and the
//! residual certificate of the state at its λ within its tolerance; a step that fails is
//! repeated with half the arc length. Δl follows the iterations:
//! `Δl ← Δl √(target / iterations)` within the case's bounds. A **limit point** is where λ
//! turns (Δλ changes sign; λ estimated by the parabola through the three points around it), a
//! **bifurcation point** where the tangent's determinant changes sign while λ keeps its
//! direction.
//!
//! ## References
//! 1. M. A. Crisfield, *A fast incremental/iterative solution procedure that handles
//!    "snap-through"*, Computers & Structures 13 (1981) 55–62.
//! 2. E. Riks, *An incremental approach to the solution of snapping and buckling problems*,
//!    Int. J. Solids Struct. 15 (1979) 529–551.
use nalgebra::{DVector, Vector3};

use super::certificate::DEFAULT_CERTIFICATE_TOLERANCE;
use super::problem::{FrameAt, Held, HeldRows};
use super::statics::{certificate, IterationRecord};
use super::{divergence, Problem, SolveError, Step};
use crate::assemble::Tangent;
use crate::linalg::{LinearSolver, Pattern};
use crate::model::mesh::Field;

pub use super::continuation::ArcLengthParams;

/// One converged point of the path.
#[derive(Clone, Debug)]
pub struct PathPoint {
    /// path step (0: the reference, λ = 0)
    pub step: usize,
    /// the load factor λ [-]
    pub load_factor: f64,
    /// arc length travelled, `Σ Δl` [-]
    pub arc_length: f64,
    /// the sign of the tangent's determinant relative to the reference's (+1, −1)
    pub determinant_sign: i8,
    /// Newton iterations of the step
    pub iterations: usize,
    /// the residual certificate of the state at its λ
    pub certificate: f64,
    /// the state (chart coordinates)
    pub u: DVector<f64>,
}

/// A critical point found along the path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Critical {
    /// λ turns back (a snap-through load): the estimated load factor at the turn, between
    /// path steps `after` and `after + 1`
    Limit { load_factor: f64, after: usize },
    /// the tangent's determinant changes sign while λ keeps its direction: the load factors of
    /// the two path points around it
    Bifurcation { between: (f64, f64), after: usize },
}

impl Critical {
    /// The load factor of the point (a bifurcation's midpoint).
    pub fn load_factor(&self) -> f64 {
        match self {
            Critical::Limit { load_factor, .. } => *load_factor,
            Critical::Bifurcation { between, .. } => 0.5 * (between.0 + between.1),
        }
    }
}

/// Why the path ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathEnd {
    /// λ reached `max_load_factor` (the last point is solved at exactly that λ)
    ReachedLoad,
    /// `steps` path steps were taken first
    Steps,
}

/// The path: its points (the reference first), the critical points and why it ended.
#[derive(Clone, Debug)]
pub struct PathSolution {
    pub points: Vec<PathPoint>,
    pub critical: Vec<Critical>,
    pub end: PathEnd,
    /// every Newton iteration, numbered per path step (its `step`)
    pub history: Vec<IterationRecord>,
}

/// Most halvings of the arc length within one step before the path gives up.
const MAX_CUTS: usize = 12;

/// `‖v‖_w²` of the module doc: positions scaled by the rod length, RMS over nodes.
pub(crate) fn wnorm2(problem: &Problem, a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    let dofs = problem.dofs();
    let l2 = problem.mesh.length_m * problem.mesh.length_m;
    let mut s = 0.0;
    for (i, (x, y)) in a.iter().zip(b.iter()).enumerate() {
        s += if dofs.field_of(i) == Field::X { x * y / l2 } else { x * y };
    }
    s / dofs.nodes() as f64
}

/// The certificate a converged step's state must meet with Newton's tolerance `tolerance`.
pub fn step_certificate_bound(tolerance: f64) -> f64 {
    DEFAULT_CERTIFICATE_TOLERANCE.max(1e3 * tolerance)
}

/// The node whose displacement a path records for the arc length `s_m` [m]: the nearest.
pub fn record_node(mesh: &crate::model::mesh::Mesh, s_m: f64) -> usize {
    let (e, xi) = mesh.locate(s_m);
    if xi < 0.5 {
        e
    } else {
        e + 1
    }
}

/// Newton's matrix of `R(·, λ)` at `u` with its held rows, and the residual.
struct System {
    pattern: Pattern,
    values: Vec<f64>,
    solver: LinearSolver,
}

impl System {
    fn new(problem: &Problem) -> Self {
        let pattern = problem.dofs().pattern();
        let values = vec![0.0; pattern.nnz()];
        let solver = LinearSolver::new(&pattern);
        System { pattern, values, solver }
    }

    /// Assemble at `(u, λ)`: returns `R(u, λ)` (held rows `u − value`) and factors `K`.
    fn residual(&mut self, problem: &Problem, u: &DVector<f64>, lambda: f64) -> Result<DVector<f64>, SolveError> {
        let r = newton_system(problem, u, lambda, &self.pattern, &mut self.values);
        // factor once: the predictor and corrector solves reuse it
        self.solver.solve(&self.values, &problem.dofs().zeros())?;
        Ok(r)
    }

    fn solve(&self, b: &DVector<f64>) -> Result<DVector<f64>, SolveError> {
        Ok(self.solver.solve_factored(b)?)
    }
}

/// Newton's matrix of `R(·, λ)` at `u` into `values` (in `pattern`, overwritten) with its held
/// rows (D22), and the residual `R(u, λ)` (held rows `u − value`).
pub(crate) fn newton_system(
    problem: &Problem,
    u: &DVector<f64>,
    lambda: f64,
    pattern: &Pattern,
    values: &mut [f64],
) -> DVector<f64> {
    let p = Problem { load_factor: lambda, ..*problem };
    let held = p.held_static();
    values.iter_mut().for_each(|v| *v = 0.0);
    let g = p.internal_force(u, Some(Tangent::new(pattern, values, 1.0)));
    let mut r = g - p.loads_at(u, 0.0, Some(Tangent::new(pattern, values, -1.0)));
    p.apply_held(pattern, Some(values), &mut r, &held, HeldRows::Residual(u), FrameAt::of(u));
    r
}

/// `∂F/∂λ` at `(u, λ)` with the held rows' `d value / dλ` (fourth-order central differences of
/// the targets, D22), rows combined as the matrix's are.
pub(crate) fn load_rate(problem: &Problem, u: &DVector<f64>, lambda: f64, pattern: &Pattern) -> DVector<f64> {
    let unit = Problem { load_factor: 1.0, ..*problem };
    let mut q = unit.loads_at(u, 0.0, None);
    // the targets' rates by the fourth-order central stencil with h = 1e-3 max(|λ|, 1): a
    // prescribed displacement of microns on positions of metres loses 1e-16/(h d) to
    // cancellation, 2e-5 with h = 1e-6 and d = 5e-6 (D27)
    let h = 1e-3 * lambda.abs().max(1.0);
    let at = |l: f64| Problem { load_factor: l, ..*problem }.held_static();
    let (p1, m1, p2, m2) = (at(lambda + h), at(lambda - h), at(lambda + 2.0 * h), at(lambda - 2.0 * h));
    let values = (0..p1.values.len())
        .map(|k| (8.0 * (p1.values[k] - m1.values[k]) - (p2.values[k] - m2.values[k])) / (12.0 * h))
        .collect();
    let rate = Held { values, ..p1 };
    problem.apply_held(pattern, None, &mut q, &rate, HeldRows::Values, FrameAt::of(u));
    q
}

/// Follow the path of the static problem from its reference (λ = 0) with Newton's tolerance
/// `tolerance` (D5), at most `max_iterations` per step; `progress(step, steps)` per step.
pub fn follow(
    problem: &Problem,
    params: &ArcLengthParams,
    tolerance: f64,
    max_iterations: usize,
    mut progress: impl FnMut(usize, usize),
) -> Result<PathSolution, SolveError> {
    let mut sys = System::new(problem);
    let u0 = problem.reference_state();
    sys.residual(problem, &u0, 0.0)?;
    let sign0 = sys.solver.determinant_sign();
    let point0 = PathPoint {
        step: 0,
        load_factor: 0.0,
        arc_length: 0.0,
        determinant_sign: 1,
        iterations: 0,
        certificate: certificate(&Problem { load_factor: 0.0, ..*problem }, &u0).value,
        u: u0,
    };
    let mut path =
        PathSolution { points: vec![point0], critical: Vec::new(), end: PathEnd::Steps, history: Vec::new() };
    let mut dl = params.initial_increment;
    let mut direction: Option<DVector<f64>> = None;
    for step in 1..=params.steps {
        if crate::interrupt::requested() {
            return Err(SolveError::Interrupted { what: "path steps", done: step - 1, total: params.steps });
        }
        let last = path.points.last().expect("the reference").clone();
        let mut cuts = 0;
        let Corrected { u, lambda, iterations, records } = loop {
            let from = StepFrom { step, last: &last, direction: direction.as_ref(), dl };
            match corrected_step(problem, &mut sys, from, Stopping { tolerance, max_iterations }) {
                Ok(c) => break c,
                Err(e) if cuts < MAX_CUTS && !matches!(e, SolveError::Interrupted { .. }) => {
                    cuts += 1;
                    dl *= 0.5;
                    if dl < params.min_increment {
                        return Err(e);
                    }
                }
                Err(e) => return Err(e),
            }
        };
        path.history.extend(records);
        // crossing the end load: solve at exactly λ = max by load control from the last point
        let (u, lambda, end) = if lambda >= params.max_load_factor && last.load_factor < params.max_load_factor {
            let f = (params.max_load_factor - last.load_factor) / (lambda - last.load_factor);
            let start = &last.u + (&u - &last.u) * f;
            let (u, _) = load_controlled(problem, &mut sys, start, params.max_load_factor, tolerance, max_iterations)?;
            (u, params.max_load_factor, true)
        } else {
            (u, lambda, false)
        };
        sys.residual(problem, &u, lambda)?;
        let sign = sys.solver.determinant_sign() * sign0;
        let du = &u - &last.u;
        let point = PathPoint {
            step,
            load_factor: lambda,
            arc_length: last.arc_length + wnorm2(problem, &du, &du).sqrt(),
            determinant_sign: sign,
            iterations,
            certificate: certificate(&Problem { load_factor: lambda, ..*problem }, &u).value,
            u,
        };
        direction = Some(du);
        detect(&mut path, &point);
        path.points.push(point);
        progress(step, params.steps);
        if end {
            path.end = PathEnd::ReachedLoad;
            break;
        }
        let factor = (params.target_iterations as f64 / iterations.max(1) as f64).sqrt();
        dl = (dl * factor).clamp(params.min_increment, params.max_increment);
    }
    Ok(path)
}

/// An arc-length step to take: path step `step` from the point `last` with arc length `dl`,
/// oriented by the direction of the step before (`None` at the first step).
#[derive(Clone, Copy)]
struct StepFrom<'a> {
    step: usize,
    last: &'a PathPoint,
    direction: Option<&'a DVector<f64>>,
    dl: f64,
}

/// Newton's stopping rule in a step: the tolerance of the increment (D5) and the iteration limit.
#[derive(Clone, Copy)]
struct Stopping {
    tolerance: f64,
    max_iterations: usize,
}

/// A converged arc-length step: the state `u`, its load factor λ, the iterations and their records.
struct Corrected {
    u: DVector<f64>,
    lambda: f64,
    iterations: usize,
    records: Vec<IterationRecord>,
}

/// One arc-length step (`from`): the converged `(u, λ)`, its iterations and their records.
fn corrected_step(
    problem: &Problem,
    sys: &mut System,
    from: StepFrom<'_>,
    stopping: Stopping,
) -> Result<Corrected, SolveError> {
    let (StepFrom { step, last, direction, dl }, Stopping { tolerance, max_iterations }) = (from, stopping);
    // predictor along the tangent
    sys.residual(problem, &last.u, last.load_factor)?;
    let q = load_rate(problem, &last.u, last.load_factor, &sys.pattern);
    let qt = sys.solve(&q)?;
    let norm = wnorm2(problem, &qt, &qt).sqrt();
    let sign = match direction {
        Some(d) if wnorm2(problem, &qt, d) < 0.0 => -1.0,
        _ => 1.0,
    };
    let mut dlambda = sign * dl / norm;
    let mut du = &qt * dlambda;
    let mut records = Vec::new();
    for it in 1..=max_iterations {
        let (u, lambda) = (&last.u + &du, last.load_factor + dlambda);
        let r = sys.residual(problem, &u, lambda)?;
        let q = load_rate(problem, &u, lambda, &sys.pattern);
        let (ur, ut) = (sys.solve(&(-&r))?, sys.solve(&q)?);
        // ‖du + ur + δλ ut‖² = dl²
        let base = &du + &ur;
        let a = wnorm2(problem, &ut, &ut);
        let b = 2.0 * wnorm2(problem, &base, &ut);
        let c = wnorm2(problem, &base, &base) - dl * dl;
        let disc = b * b - 4.0 * a * c;
        if disc.is_nan() || disc < 0.0 {
            return Err(SolveError::NewtonNotConverged {
                step: Some(Step::Continuation(step)),
                iterations: it,
                increment: f64::NAN,
            });
        }
        let roots = [(-b + disc.sqrt()) / (2.0 * a), (-b - disc.sqrt()) / (2.0 * a)];
        let score = |d: f64| wnorm2(problem, &(&base + &ut * d), &du);
        let dl_new = if score(roots[0]) >= score(roots[1]) { roots[0] } else { roots[1] };
        let delta = &ur + &ut * dl_new;
        du += &delta;
        dlambda += dl_new;
        let increment = problem.increment_measure(&delta);
        let u = &last.u + &du;
        if let Some((quantity, value)) = divergence(problem, &u, increment) {
            return Err(SolveError::Diverged { step: Some(Step::Continuation(step)), iteration: it, quantity, value });
        }
        let lambda = last.load_factor + dlambda;
        let cert = certificate(&Problem { load_factor: lambda, ..*problem }, &u).value;
        records.push(IterationRecord { step, iteration: it, change: increment, certificate: cert });
        if increment <= tolerance && cert <= step_certificate_bound(tolerance) {
            return Ok(Corrected { u, lambda, iterations: it, records });
        }
    }
    Err(SolveError::NewtonNotConverged {
        step: Some(Step::Continuation(step)),
        iterations: max_iterations,
        increment: f64::NAN,
    })
}

/// Newton at a fixed λ from `u` (the path's last point at exactly `max_load_factor`).
fn load_controlled(
    problem: &Problem,
    sys: &mut System,
    mut u: DVector<f64>,
    lambda: f64,
    tolerance: f64,
    max_iterations: usize,
) -> Result<(DVector<f64>, usize), SolveError> {
    for it in 1..=max_iterations {
        let r = sys.residual(problem, &u, lambda)?;
        let du = sys.solve(&(-r))?;
        u += &du;
        if problem.increment_measure(&du) <= tolerance {
            return Ok((u, it));
        }
    }
    Err(SolveError::NewtonNotConverged { step: None, iterations: max_iterations, increment: f64::NAN })
}

/// Record the critical point between the last point of `path` and `next`, if any.
fn detect(path: &mut PathSolution, next: &PathPoint) {
    let n = path.points.len();
    let last = &path.points[n - 1];
    let d_next = next.load_factor - last.load_factor;
    let d_last = if n >= 2 { last.load_factor - path.points[n - 2].load_factor } else { d_next };
    if d_last > 0.0 && d_next < 0.0 || d_last < 0.0 && d_next > 0.0 {
        // parabola λ(a) through the three points: its vertex
        let p0 = &path.points[n - 2];
        let (a0, a1, a2) = (p0.arc_length, last.arc_length, next.arc_length);
        let (l0, l1, l2) = (p0.load_factor, last.load_factor, next.load_factor);
        let denom = (a0 - a1) * (a0 - a2) * (a1 - a2);
        let ca = (a2 * (l1 - l0) + a1 * (l0 - l2) + a0 * (l2 - l1)) / denom;
        let cb = (a2 * a2 * (l0 - l1) + a1 * a1 * (l2 - l0) + a0 * a0 * (l1 - l2)) / denom;
        let cc = (a1 * a2 * (a1 - a2) * l0 + a2 * a0 * (a2 - a0) * l1 + a0 * a1 * (a0 - a1) * l2) / denom;
        let vertex = -cb / (2.0 * ca);
        let load_factor =
            if ca != 0.0 && (a0..=a2).contains(&vertex) { cc - cb * cb / (4.0 * ca) } else { last.load_factor };
        // the tangent is singular at a limit point: a sign change one step before it is the
        // limit's own, not a bifurcation
        if matches!(path.critical.last(), Some(Critical::Bifurcation { after, .. }) if *after + 1 == last.step) {
            path.critical.pop();
        }
        path.critical.push(Critical::Limit { load_factor, after: last.step });
    } else if next.determinant_sign != last.determinant_sign {
        path.critical.push(Critical::Bifurcation { between: (last.load_factor, next.load_factor), after: last.step });
    }
}

/// The displacement [m] (space coordinates) of the node nearest `s_m` in a path point.
pub fn displacement_at(problem: &Problem, u: &DVector<f64>, s_m: f64) -> Vector3<f64> {
    let node = record_node(&problem.mesh, s_m);
    let dofs = problem.dofs();
    let chart = problem.chart();
    let d = dofs.get(u, node, Field::X) - dofs.get(&problem.reference_state(), node, Field::X);
    chart.to_space(&d)
}
