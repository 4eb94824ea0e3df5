//! Time stepping of eq. (40) with inertia: Appendix A, eqs. (66)–(69), in momentum form (D6).
//!
//! ```text
//!   u̇_n = (2/Δt)(u_n − u_{n−1}) − u̇_{n−1}                                   (69)
//!   R_n(u_n) = [P(u_n, u̇_n) − P(u_{n−1}, u̇_{n−1})]/Δt
//!              + G((u_n + u_{n−1})/2) − ½ [F(t_n) + F(t_{n−1})] = 0           (68)
//!   ∂R_n/∂u_n = (1/Δt) ∂P/∂u + (2/Δt²) ∂P/∂u̇ + ½ ∂G/∂u
//! ```
//! solved by Newton from the predictor `u_{n−1} + Δt u̇_{n−1}`, with chord steps (the last
//! factorised Jacobian reused while the increments contract by [`CHORD_CONTRACTION`]). The printed (71)/(72) are not
//! used (errata: (Δt²/2) F_n and M_{n−2}; see PAPER-NOTES and `docs/decisions.md`).
use nalgebra::{DVector, Vector3};

use super::certificate::{system_terms, Certificate, System};
use super::chart_change::{self, ChartRule};
use super::problem::{FrameAt, Held, HeldRows};
use super::statics::frozen_system;
use super::{divergence, Problem, SolveError, Step, CHORD_CONTRACTION};
use crate::assemble::Tangent;
use crate::linalg::{LinearSolver, Pattern};
use crate::model::balance::Balance;
use crate::model::chart::Chart;
use crate::model::ends::MotionAt;
use crate::model::loads::LoadFrame;
use crate::model::mesh::Field;

/// Time-stepping parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DynamicParams {
    pub end_time_s: f64,
    pub steps: usize,
    pub newton_tolerance: f64,
    pub newton_max_iterations: usize,
    /// every step's residual certificate ([`step_certificate`]) must be at most this
    pub certificate_tolerance: f64,
}

/// Tip state at one time level.
#[derive(Clone, Copy, Debug)]
pub struct TipRecord {
    pub time_s: f64,
    pub position_m: Vector3<f64>,
    pub angles_rad: Vector3<f64>,
    pub newton_iterations: usize,
    /// the residual certificate of the step's equations (68) at the state ([`step_certificate`];
    /// 0 at t = 0, the initial state is given)
    pub certificate: f64,
    /// the rod's energy and momenta at the state `(u_n, u̇_n)` (momenta in space coordinates)
    pub balance: Balance,
    /// loads act in the step (its `F(t_n)` or `F(t_{n−1})` is not zero) or an end moves: the
    /// step may change the energy (and, with a held end, the momenta); false at t = 0 when
    /// `F(0)` is zero
    pub loaded: bool,
    /// the chart the state is in (D21, D32): the tip's angles are its angles, and the position
    /// is in its coordinates until the engine rotates it to space
    pub chart: Chart,
}

/// Result of a time integration.
#[derive(Clone, Debug)]
pub struct DynamicSolution {
    /// final state, in the chart [`DynamicSolution::chart`]
    pub u: DVector<f64>,
    /// the chart of the final state: the case's, or the last one the run changed to (D32)
    pub chart: Chart,
    pub tip: Vec<TipRecord>,
    pub total_newton_iterations: usize,
    pub max_newton_iterations: usize,
    /// the largest step certificate
    pub max_certificate: f64,
}

/// Integrate from the reference configuration at rest, changing the chart by the default
/// rule of D32 ([`ChartRule::default`]).
pub fn solve(
    problem: &Problem,
    params: &DynamicParams,
    progress: impl FnMut(usize, usize),
) -> Result<DynamicSolution, SolveError> {
    solve_charted(problem, params, &ChartRule::default(), progress)
}

/// Integrate from the reference configuration at rest, changing the chart when `rule` says so
/// (D32, [`super::chart_change`]): the run is a sequence of segments, each in one chart, the
/// state re-expressed between them.
pub fn solve_charted(
    problem: &Problem,
    params: &DynamicParams,
    rule: &ChartRule,
    mut progress: impl FnMut(usize, usize),
) -> Result<DynamicSolution, SolveError> {
    let mut run = Run::start(problem);
    let mut rod = None;
    let mut n = 1;
    loop {
        let current = match &rod {
            Some(r) => problem.on_rod(Some(r)),
            None => *problem,
        };
        let Some((at, chart)) = run.segment(&current, params, (n, rule), &mut progress)? else { break };
        let new_rod = chart_change::rod_in_chart(&current, chart);
        let next = current.on_rod(Some(&new_rod));
        let changed = run.rechart(&current, &next, (at - 1) as f64 * params.end_time_s / params.steps as f64);
        n = at;
        if changed {
            rod = Some(new_rod);
        }
    }
    Ok(DynamicSolution {
        u: run.prev.u,
        chart: run.tip.last().map(|t| t.chart).unwrap_or_default(),
        tip: run.tip,
        total_newton_iterations: run.total,
        max_newton_iterations: run.max_it,
        max_certificate: run.max_certificate,
    })
}

/// The time stepping's state across its segments: the last step's state, the tip records
/// and the counts.
struct Run {
    prev: StepState,
    tip: Vec<TipRecord>,
    total: usize,
    max_it: usize,
    max_certificate: f64,
    /// the step at which the last segment started in a new chart (a rule that names a step
    /// changes once there)
    changed_at: usize,
}

/// The tip record of the state `s` at `t` [s] in `problem`'s chart.
fn record(problem: &Problem, t: f64, s: &StepState, (it, certificate): (usize, f64), loaded: bool) -> TipRecord {
    let (dofs, last) = (problem.dofs(), problem.mesh.nodes() - 1);
    let (x, a) = (dofs.get(&s.u, last, Field::X), dofs.get(&s.u, last, Field::Alpha));
    let balance = problem.balance(&s.u, &s.v);
    let chart = problem.chart();
    TipRecord { time_s: t, position_m: x, angles_rad: a, newton_iterations: it, certificate, balance, loaded, chart }
}

impl Run {
    /// The reference configuration at rest, recorded at t = 0.
    fn start(problem: &Problem) -> Self {
        let dofs = problem.dofs();
        let (u0, v0) = (problem.reference_state(), DVector::zeros(dofs.len()));
        let prev = StepState { p: problem.momentum(&u0, &v0, None), f: problem.loads_at(&u0, 0.0, None), u: u0, v: v0 };
        let tip = vec![record(problem, 0.0, &prev, (0, 0.0), problem.ends().moving() || loaded(&prev.f))];
        Run { prev, tip, total: 0, max_it: 0, max_certificate: 0.0, changed_at: 0 }
    }

    /// Re-express the last step's state from `from`'s chart in `to`'s (`t_prev` [s]: its time):
    /// false (nothing changed) where some node is on the new chart's singular set.
    fn rechart(&mut self, from: &Problem, to: &Problem, t_prev: f64) -> bool {
        let Some((u, v)) =
            chart_change::reexpress_state(&from.dofs(), &from.chart(), &to.chart(), &self.prev.u, &self.prev.v)
        else {
            return false;
        };
        self.prev = StepState { p: to.momentum(&u, &v, None), f: to.loads_at(&u, t_prev, None), u, v };
        true
    }

    /// Steps `n..` in `problem`'s chart until the last one, or until `rule` changes the chart at
    /// the start of a step: that step and the new chart.
    fn segment(
        &mut self,
        problem: &Problem,
        params: &DynamicParams,
        (first, rule): (usize, &ChartRule),
        progress: &mut impl FnMut(usize, usize),
    ) -> Result<Option<(usize, Chart)>, SolveError> {
        let pattern = problem.dofs().pattern();
        let dt = params.end_time_s / params.steps as f64;
        let moving = problem.ends().moving();
        let mut cert_values = vec![0.0; pattern.nnz()];
        // Global-frame (or no distributed) loads do not depend on the state: F(t_n) once per step
        // instead of once per Newton iteration and again after it (the same numbers).
        let state_free_loads = !(problem.loads.has_distributed() && matches!(problem.loads.frame, LoadFrame::Local));
        let mut stepper = Stepper {
            problem,
            params,
            solver: LinearSolver::new(&pattern),
            values: vec![0.0; pattern.nnz()],
            pattern,
            dt,
            factored: false,
            refactor: true,
        };
        for n in first..=params.steps {
            if n != self.changed_at {
                if let Some(chart) = rule.decide(problem, n, &self.prev.u, &problem.chart()) {
                    self.changed_at = n;
                    return Ok(Some((n, chart)));
                }
            }
            if crate::interrupt::requested() {
                return Err(SolveError::Interrupted { what: "time steps", done: n - 1, total: params.steps });
            }
            let t = n as f64 * dt;
            let held = problem.held(MotionAt::Dynamic { t_prev: t - dt, t }, Some(&self.prev.u));
            let mut u = &self.prev.u + &self.prev.v * dt;
            if moving {
                // a moving end's held unknowns start at their targets; fixed ones keep the
                // predictor's (their Newton rows are identities with zero residual)
                held.impose(&mut u);
            }
            let f_step = if state_free_loads { Some(problem.loads_at(&u, t, None)) } else { None };
            let at = StepAt { n, t, held: &held, f_step: f_step.as_ref() };
            let (u, it, increment) = stepper.newton(at, u, &self.prev)?;
            let v = (&u - &self.prev.u) * (2.0 / dt) - &self.prev.v;
            let p_n = problem.momentum(&u, &v, None);
            let f_n = f_step.unwrap_or_else(|| problem.loads_at(&u, t, None));
            let prev = &self.prev;
            let terms = StepTerms {
                u: &u,
                u_prev: &prev.u,
                p: &p_n,
                p_prev: &prev.p,
                f: &f_n,
                f_prev: &prev.f,
                dt,
                held: &held,
            };
            let certificate = step_certificate(problem, terms, &stepper.pattern, &mut cert_values);
            if !certificate.within(params.certificate_tolerance) {
                return Err(SolveError::StepNotCertified {
                    step: n,
                    iterations: it,
                    increment,
                    certificate: certificate.value,
                    tolerance: params.certificate_tolerance,
                    block: certificate.worst_block(System::Forward),
                });
            }
            (self.total, self.max_it) = (self.total + it, self.max_it.max(it));
            self.max_certificate = self.max_certificate.max(certificate.value);
            let step_loaded = moving || loaded(&f_n) || loaded(&self.prev.f);
            self.prev = StepState { u, v, p: p_n, f: f_n };
            self.tip.push(record(problem, t, &self.prev, (it, certificate.value), step_loaded));
            progress(n, params.steps);
        }
        Ok(None)
    }
}

/// Does the load vector `F` hold a load (an entry that is not zero)?
fn loaded(f: &DVector<f64>) -> bool {
    f.iter().any(|v| *v != 0.0)
}

/// The state of a time step: `u_n`, `u̇_n`, the momentum `P(u_n, u̇_n)` and the loads `F(t_n)`.
struct StepState {
    u: DVector<f64>,
    v: DVector<f64>,
    p: DVector<f64>,
    f: DVector<f64>,
}

/// The Newton iteration of the time steps, with what it keeps across them: the pattern, the
/// Jacobian's values and its LU.
///
/// Chord steps (simplified Newton): the factorisation of the last Jacobian is reused across
/// iterations and time steps while the increments contract; an increment larger than
/// CHORD_CONTRACTION times the previous one of the step has the next iteration assemble and
/// factor the Jacobian at its iterate (a Newton step). The stopping rule is unchanged.
struct Stepper<'a, 'p> {
    problem: &'a Problem<'p>,
    params: &'a DynamicParams,
    pattern: Pattern,
    solver: LinearSolver,
    values: Vec<f64>,
    /// time step Δt [s]
    dt: f64,
    /// a factorisation exists, and the next iteration should make a new one
    factored: bool,
    refactor: bool,
}

impl Stepper<'_, '_> {
    /// Time step `n` (at `t`) from the predictor `u` after the step `prev` (`f_step`: the loads
    /// `F(t_n)` if they do not depend on the state): the state, the iterations and the last
    /// increment.
    fn newton(
        &mut self,
        at: StepAt,
        mut u: DVector<f64>,
        prev: &StepState,
    ) -> Result<(DVector<f64>, usize, f64), SolveError> {
        let (problem, dt) = (self.problem, self.dt);
        let StepAt { n, t, held, f_step } = at;
        let mut increment = f64::NAN;
        let mut previous = f64::INFINITY;
        for it in 1..=self.params.newton_max_iterations {
            let v = (&u - &prev.u) * (2.0 / dt) - &prev.v;
            let u_mid = (&u + &prev.u) * 0.5;
            let newton = self.refactor || !self.factored;
            let jacobian = if newton { Jacobian::Assembled } else { Jacobian::Frozen };
            if newton {
                self.values.iter_mut().for_each(|x| *x = 0.0);
            }
            let p = problem.momentum(
                &u,
                &v,
                tangent(jacobian, &self.pattern, &mut self.values, 1.0 / dt).map(|t| (t, 2.0 / (dt * dt))),
            );
            let g = problem.internal_force(&u_mid, tangent(jacobian, &self.pattern, &mut self.values, 0.5));
            // ½[F(t_n, u_n) + F(t_{n−1}, u_{n−1})]: only the first half depends on u_n.
            let f_state;
            let f_n = match f_step {
                Some(f) => f,
                None => {
                    f_state = problem.loads_at(&u, t, tangent(jacobian, &self.pattern, &mut self.values, -0.5));
                    &f_state
                }
            };
            let mut r = (p - &prev.p) / dt + g - (f_n + &prev.f) * 0.5;
            let values = if newton { Some(&mut self.values[..]) } else { None };
            problem.apply_held(
                &self.pattern,
                values,
                &mut r,
                held,
                HeldRows::Zero,
                FrameAt { state: &u_mid, rate: 0.5 },
            );
            let du = if newton {
                let du = self.solver.solve(&self.values, &(-r))?;
                (self.factored, self.refactor) = (true, false);
                du
            } else {
                self.solver.solve_factored(&(-r))?
            };
            u += &du;
            increment = problem.increment_measure(&du);
            if let Some((quantity, value)) = divergence(problem, &u, increment) {
                return Err(SolveError::Diverged { step: Some(Step::Time(n)), iteration: it, quantity, value });
            }
            if increment <= self.params.newton_tolerance {
                return Ok((u, it, increment));
            }
            if !newton && increment > CHORD_CONTRACTION * previous {
                self.refactor = true;
            }
            previous = increment;
        }
        Err(SolveError::NewtonNotConverged {
            step: Some(Step::Time(n)),
            iterations: self.params.newton_max_iterations,
            increment,
        })
    }
}

/// Where a time step's Newton starts from: step `n` at `t` [s], its held unknowns and, if they do
/// not depend on the state, its loads `F(t_n)`.
struct StepAt<'a> {
    n: usize,
    t: f64,
    held: &'a Held,
    f_step: Option<&'a DVector<f64>>,
}

/// What an iteration of a step's Newton does with the Jacobian: assembles it (a Newton step)
/// or keeps the last factorisation (a chord step).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Jacobian {
    Assembled,
    Frozen,
}

/// The assembly target of one term of the Jacobian, if one is assembled.
fn tangent<'a>(jacobian: Jacobian, pattern: &'a Pattern, values: &'a mut [f64], scale: f64) -> Option<Tangent<'a>> {
    (jacobian == Jacobian::Assembled).then(|| Tangent::new(pattern, values, scale))
}

/// What the certificate of a time step is made of: the step's state and the previous one, their
/// momenta `P(u_n, u̇_n)`, `P(u_{n−1}, u̇_{n−1})` and loads `F(t_n)`, `F(t_{n−1})`, and Δt [s].
pub struct StepTerms<'a> {
    pub u: &'a DVector<f64>,
    pub u_prev: &'a DVector<f64>,
    pub p: &'a DVector<f64>,
    pub p_prev: &'a DVector<f64>,
    pub f: &'a DVector<f64>,
    pub f_prev: &'a DVector<f64>,
    pub dt: f64,
    /// the held unknowns of the step and their values (D22)
    pub held: &'a Held,
}

/// The residual certificate of a time step (`docs/certificate.md`): the block backward error of
/// the step's equations (68) at its state, with the internal force in the fixed point's frozen
/// form at the midpoint state `m = (u_n + u_{n−1})/2`,
///
/// ```text
///   R = (P_n − P_{n−1})/Δt + L(m) m − b(m) − ½(F_n + F_{n−1})
///   S = (|P_n| + |P_{n−1}|)/Δt + |L(m)| |m| + |b(m)| + ½(|F_n| + |F_{n−1}|)
/// ```
/// the clamp's rows as `u_d − u_ref,d` against `|u_d| + |u_ref,d|`. `values`: scratch of
/// `pattern`'s size.
pub fn step_certificate(problem: &Problem, s: StepTerms, pattern: &Pattern, values: &mut [f64]) -> Certificate {
    let dofs = problem.dofs();
    let mid = (s.u + s.u_prev) * 0.5;
    // the frozen system at m without loads: b(m) (Dirichlet rows: the clamp's values)
    let unloaded = Problem { load_factor: 0.0, ..*problem };
    let b = frozen_system(&unloaded, &mid, pattern, values, s.held);
    let (mut res, mut scale) = system_terms(pattern, values, &mid, &b);
    let fixed = &s.held.dofs;
    for i in 0..res.len() {
        if fixed.binary_search(&i).is_ok() {
            continue;
        }
        res[i] += (s.p[i] - s.p_prev[i]) / s.dt - 0.5 * (s.f[i] + s.f_prev[i]);
        scale[i] += (s.p[i].abs() + s.p_prev[i].abs()) / s.dt + 0.5 * (s.f[i].abs() + s.f_prev[i].abs());
    }
    // a twist-held node's moment rows as the solver combines them (D22): the residual with the
    // frame at the midpoint, the term sizes with its magnitudes
    for &node in &s.held.twist_nodes {
        let i0 = dofs.index(node, crate::model::mesh::Field::Alpha, 0);
        let t = super::problem::twist_rows(&dofs.get(&mid, node, crate::model::mesh::Field::Alpha)).t;
        let (r, sc) = (res.fixed_rows::<3>(i0).into_owned(), scale.fixed_rows::<3>(i0).into_owned());
        let perm = nalgebra::Matrix3::from_fn(|i, j| t[i][j]);
        res.fixed_rows_mut::<3>(i0).copy_from(&(perm * r));
        scale.fixed_rows_mut::<3>(i0).copy_from(&(perm.abs() * sc));
    }
    for (&d, &v) in s.held.dofs.iter().zip(&s.held.values) {
        res[d] = s.u[d] - v;
        scale[d] = s.u[d].abs() + v.abs();
    }
    Certificate::from_residual(&dofs, &res, &scale)
}
