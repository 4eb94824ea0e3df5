//! The inverse problem over a clip of frames (paper §3.4, §6): one monolithic solve per frame
//! (Problem 2, eq. 61), the first frame with α(a) = α0 and Λω = 0 (Remark 6), every later frame
//! with Λω, the previous frame's angles as α_{n−1} and its state as the initial iterate.
//!
//! The angle chart of eq. (1) is singular where cos β = 0 (det A = −cos β). With
//! [`RotationTreatment::Rebased`] (the default) each frame is solved in its own chart
//! `Q = Q_E(α) B` whose singular axis is chosen away from the frame's tangents
//! (`crate::model::chart`, `docs/rotation.md`); with [`RotationTreatment::GlobalEuler`] every frame uses
//! the paper's chart. Either way every frame is guarded: a frame whose recovered β comes within
//! `min_cos_beta` of ±π/2 at any node stops the clip with an error naming frame and node (the
//! failure is otherwise silent: the fit stays good while α and κ3 explode, PAPER-NOTES).
pub use crate::recorded::smoothing::{frame_geometry, NOISY_GEOMETRY};
use std::f64::consts::PI;

use nalgebra::{DVector, Matrix3, Vector3};

mod accept;
mod carry;
mod report;
use accept::{accepted, frame_fit, StartedFrom};
pub use carry::vector_to_space;
use carry::{carry_converted, carry_state, to_space};
pub use report::{DataMisfit, FrameConditioning, FrameConvergence, FrameReport};

use crate::model::chart::{frame_axis, Chart};
use crate::model::mesh::{DofMap, Field};
use crate::model::rotation::{angles_from_rotation, skew, Angles};

use super::inverse::tracking::tracking_weights;
use super::inverse::{Frame, FrameSolver, InverseParams, InverseRecord, InverseSolution, Records, Start};
use super::{Problem, SolveError};
use crate::recorded::fit::FitGate;

/// Settings of a clip solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SequenceParams {
    /// weights, Δt, method, relaxation, tolerance and per-frame iteration budget
    pub inverse: InverseParams,
    /// guard of the angle chart: stop when |cos β| < this at any node
    pub min_cos_beta: f64,
    /// number of the first frame in reports and errors (the clip's frame range may not start at 0)
    pub frame_offset: usize,
    /// initial iterate of every frame after the first
    pub start: FrameStart,
    /// angle chart of each frame
    pub rotation: RotationTreatment,
    /// first frame's roll gauge (Remark 6 read in space, R7): the chart's singular axis of the
    /// first frame, so that `α(0) = α0` means `d1(0) ⟂ gauge` (for α0 = 0); e2 is the paper's
    pub gauge: Vector3<f64>,
    /// which Newton iterations of a frame keep a record: [`Records::Last`] where only the frame
    /// reports are kept (the iterates, and so the frames, are the same either way)
    pub records: Records,
    /// the fit-quality gate that flags frames (`solve::fit`)
    pub gate: FitGate,
    /// the unit normal of the plane a planar recording lies in (`clip::recording`), in space
    /// coordinates; `None`: 3D data. Planar data do not hold the roll of the frame about the
    /// centreline, so every frame, not only the first, has the gauge `α(0) = α0` (R7), and the
    /// noise is estimated in the plane ([`crate::recorded::fit::noise_level_in`])
    pub plane: Option<Vector3<f64>>,
}

/// The frames of a clip as the solve takes them: positions per node (untracked ones filled,
/// `clip::missing`) and which nodes were tracked (`None`: all of them).
#[derive(Clone, Copy, Debug)]
pub struct ClipData<'a> {
    pub positions: &'a [Vec<Vector3<f64>>],
    pub tracked: Option<&'a [Vec<bool>]>,
}

impl ClipData<'_> {
    /// The tracking weights of frame `i` ([`tracking_weights`]); `None`: w ≡ 1.
    pub fn weights(&self, i: usize) -> Option<Vec<f64>> {
        self.tracked.map(|t| tracking_weights(&t[i]))
    }

    /// The tracked nodes of frame `i`.
    pub fn tracked(&self, i: usize) -> Option<&[bool]> {
        self.tracked.map(|t| &t[i][..])
    }
}

impl<'a> From<&'a [Vec<Vector3<f64>>]> for ClipData<'a> {
    fn from(positions: &'a [Vec<Vector3<f64>>]) -> Self {
        ClipData { positions, tracked: None }
    }
}

impl<'a> From<&'a Vec<Vec<Vector3<f64>>>> for ClipData<'a> {
    fn from(positions: &'a Vec<Vec<Vector3<f64>>>) -> Self {
        ClipData { positions, tracked: None }
    }
}

/// Angle chart of each frame (`docs/rotation.md`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RotationTreatment {
    /// the paper's chart of eq. (1) for every frame
    GlobalEuler,
    /// per frame the chart `Q = Q_E(α) B` whose singular axis is [`frame_axis`] of the frame's
    /// data (the gauge on the first frame), R1–R7
    #[default]
    Rebased,
}

/// Initial iterate of the frames after the first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameStart {
    /// the previous frame's solution (restart from the data guess if that fails)
    PreviousFrame,
    /// [`data_frame_guess`] of the frame itself (D13)
    DataGuess,
}

/// Errors of a clip solve: the frame's own error, or the chart guard.
#[derive(Debug, thiserror::Error)]
pub enum SequenceError {
    #[error("frame {frame}: |cos β| = {cos_beta:.3e} at node {node} (below the guard {guard:e}): the frame's tangent there is along the angle chart's singular axis ({:.3}, {:.3}, {:.3}) (eq. 1, det A = −cos β). {}", axis[0], axis[1], axis[2], chart_hint(*.frame, .degraded))]
    SingularChart {
        frame: usize,
        node: usize,
        cos_beta: f64,
        guard: f64,
        axis: [f64; 3],
        /// frames over the fit-quality gate among those this solve ran before it:
        /// `(count, first flagged, first frame of the solve)`
        degraded: Option<(usize, usize, usize)>,
    },
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// The frame's callback stopped the clip (`stop` says why).
    #[error("frame {frame}: {stop}")]
    Callback { frame: usize, stop: FrameStop },
    /// The frame's solve returned without an iteration record.
    #[error("frame {frame}: no iteration ran")]
    NoIteration { frame: usize },
}

/// Why the callback of a clip solve stopped the clip: the caller's own error type.
pub type FrameStop = Box<dyn std::error::Error + Send + Sync>;

/// The chart of a clip's first frame: the paper's global chart, or the rebased chart whose
/// singular axis is the gauge (R7).
pub fn first_chart(sp: &SequenceParams) -> Chart {
    match sp.rotation {
        RotationTreatment::GlobalEuler => Chart::identity(),
        RotationTreatment::Rebased => Chart::with_axis(&sp.gauge),
    }
}

/// The chart of a frame with data `x_space` (space coordinates) after a frame in chart `prev`
/// (`None`: the clip's first frame): [`first_chart`] for the first frame and for the global
/// chart, else the chart whose axis is [`frame_axis`] of the data, signed against `prev`'s
/// (R4). It depends on the data only, so [`clip_charts`] gives every frame's chart up front.
pub fn frame_chart(sp: &SequenceParams, prev: Option<&Chart>, x_space: &[Vector3<f64>], length_m: f64) -> Chart {
    match (sp.rotation, prev) {
        (RotationTreatment::GlobalEuler, _) | (_, None) => first_chart(sp),
        (RotationTreatment::Rebased, Some(c)) => {
            Chart::with_axis(&frame_axis(&frame_geometry(x_space, length_m), Some(&c.axis())))
        }
    }
}

/// The chart of every frame of a clip, in order ([`frame_chart`]): what [`solve_sequence`]
/// uses, for an engine that is handed the charts (the FreeFEM clip driver).
pub fn clip_charts(sp: &SequenceParams, frames: &[Vec<Vector3<f64>>], length_m: f64) -> Vec<Chart> {
    let mut charts: Vec<Chart> = Vec::with_capacity(frames.len());
    for x in frames {
        let c = frame_chart(sp, charts.last(), x, length_m);
        charts.push(c);
    }
    charts
}

/// Smallest |cos β| over the nodes of a state (forward layout `dofs`) and its node.
pub fn min_cos_beta(dofs: &DofMap, u: &DVector<f64>) -> (f64, usize) {
    (0..dofs.nodes()).map(|i| (dofs.get(u, i, Field::Alpha)[1].cos().abs(), i)).fold((f64::INFINITY, 0), |a, b| {
        if b.0 < a.0 {
            b
        } else {
            a
        }
    })
}

/// max_e |j_e − 1|, j_e = |x_{e+1} − x_e| / h (Remark 9), over the elements whose two nodes
/// were tracked (`tracked`; `None`: all).
pub fn max_stretch_deviation(x_g: &[Vector3<f64>], h: f64, tracked: Option<&[bool]>) -> f64 {
    let both = |e: usize| tracked.is_none_or(|t| t[e] && t[e + 1]);
    (0..x_g.len().saturating_sub(1))
        .filter(|&e| both(e))
        .map(|e| ((x_g[e + 1] - x_g[e]).norm() / h - 1.0).abs())
        .fold(0.0, f64::max)
}

/// The advice of a chart-guard stop: where the fit had degraded before it, the degradation;
/// otherwise the gauge.
fn chart_hint(frame: usize, degraded: &Option<(usize, usize, usize)>) -> String {
    match degraded {
        Some((count, first, from)) => format!(
            "The fit had degraded before this frame: {count} of the frames {from}–{} are over the fit-quality gate (the first is frame {first}; `flagged` in frames.csv): the reconstruction had left its data, so the chart is not the cause. A large Λω makes the frames lag behind the data and d3 leave the tangent; lower inverse.lambda_omega (or raise inverse.lambda_d) rather than changing clip.gauge",
            frame - 1
        ),
        None => "With clip.rotation = \"rebased\" only the first frame's axis is fixed, by clip.gauge: choose a gauge vector away from the first frame's tangents (e.g. the normal of its plane)".to_string(),
    }
}

/// An initial iterate read off the data (D13): x = x_g, and at each node the frame whose d3
/// is the data tangent (central differences), carried along the rod by parallel transport
/// (the minimal rotation between neighbouring tangents) from the frame at s = 0 with
/// `d3 = t_0`, `d1 ∥ e2 × t_0`, `d2·e2 > 0` — the gauge α(0) = 0 of Remark 6 (R7); the
/// construction commutes with rotations about e2, so it rotates with the data in a rebased
/// chart (R5). Angles from [`angles_from_rotation`], each unwrapped against the previous node
/// (no 2π jumps). For a planar clip in the x–z plane this is α = β = 0, γ = −θ (θ the tangent
/// angle from e3 towards e1).
pub fn data_frame_guess(x_g: &[Vector3<f64>]) -> DVector<f64> {
    let n = x_g.len();
    let tangent = |i: usize| {
        let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
        (x_g[b] - x_g[a]).normalize()
    };
    // Rotation taking unit a to unit b minimally (Rodrigues); rows of Q are the directors, so
    // the director frame transforms as Q → Q Rᵀ.
    let minimal = |a: &Vector3<f64>, b: &Vector3<f64>| -> Matrix3<f64> {
        let v = a.cross(b);
        let c = a.dot(b);
        if (1.0 + c).abs() < 1e-12 {
            // opposite: half turn about any axis normal to a
            let axis = if a.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
            let k = a.cross(&axis).normalize();
            return Matrix3::identity() * -1.0 + k * k.transpose() * 2.0;
        }
        let vx = skew(&v);
        Matrix3::identity() + vx + vx * vx / (1.0 + c)
    };
    let dofs = DofMap::forward(n);
    let mut u = dofs.zeros();
    // rows d1, d2, d3 at s = 0 (the gauge frame; e3's minimal turn if t_0 = ±e2)
    let t0 = tangent(0);
    let mut q = match Vector3::y().cross(&t0).try_normalize(1e-9) {
        Some(d1) => Matrix3::from_rows(&[d1.transpose(), t0.cross(&d1).transpose(), t0.transpose()]),
        None => minimal(&Vector3::z(), &t0).transpose(),
    };
    let mut prev_t = t0;
    let mut prev_a: Option<Vector3<f64>> = None;
    for i in 0..n {
        let t = tangent(i);
        q *= minimal(&prev_t, &t).transpose();
        prev_t = t;
        let mut a = angles_from_rotation(&q);
        if let Some(p) = prev_a {
            for k in 0..3 {
                a[k] += (2.0 * PI) * ((p[k] - a[k]) / (2.0 * PI)).round();
            }
        }
        prev_a = Some(a);
        dofs.set(&mut u, i, Field::X, &x_g[i]);
        dofs.set(&mut u, i, Field::Alpha, &a);
    }
    u
}

/// A converged frame in space coordinates: positions, the force adjoint x̂ and the moment
/// adjoint α̂ rotated back from the chart (R3); the angles stay the chart's, with `chart`.
pub struct FrameSolution<'a> {
    pub solution: &'a InverseSolution,
    pub chart: Chart,
    /// the previous frame's angles α_{n−1} [rad] per node in this frame's chart, exactly as the
    /// Λω term of (41) used them (re-expressed and unwrapped, R6); `None` on the first frame
    /// (Remark 6). With the solution's angles they give the frame's angular velocity
    /// (`inverse::measures::angular_velocity`, eq. 27).
    pub previous: Option<&'a [Angles]>,
    /// the state `(x, α)` in the frame's chart: what the next frames start from
    /// ([`ResumeFrom`])
    pub state: &'a DVector<f64>,
}

/// Decades of λg below the case's at which [`continued`] starts.
pub const CONTINUATION_DECADES: i32 = 3;

/// Errors of a frame's solve that another start may avoid.
fn recoverable(e: &SolveError) -> bool {
    matches!(
        e,
        SolveError::InverseNotConverged { .. }
            | SolveError::InverseNewtonNotConverged { .. }
            | SolveError::Stalled(_)
            | SolveError::InverseDiverged { .. }
    )
}

/// The data guess ([`data_frame_guess`]) of the frame's data smoothed by a GCV smoothing spline
/// (`solve::smoothing`, nodes equally spaced over `length_m`): on noisy data the plain guess's
/// tangents carry the noise. `None` where no spline can be fitted.
pub fn smoothed_guess(x_g: &[Vector3<f64>], length_m: f64) -> Option<DVector<f64>> {
    let s = crate::recorded::smoothing::SmoothingSpline::fit_uniform(x_g, length_m)?;
    Some(data_frame_guess(s.knot_values()))
}

/// Continuation in λg of a frame that failed from its starts (`docs/noise.md`, N7): solved from
/// `guess` at `λg·10^−CONTINUATION_DECADES`, where the tracking term is weak and the frame is
/// smooth, then at ten times that from the last solution, up to `lambda_g`.
fn continued(
    solve: &mut impl FnMut(&DVector<f64>, Start, f64) -> Result<InverseSolution, SolveError>,
    guess: &DVector<f64>,
    lambda_g: f64,
) -> Result<InverseSolution, SolveError> {
    let mut sol = solve(guess, Start::Guess, lambda_g * 10f64.powi(-CONTINUATION_DECADES))?;
    for d in (0..CONTINUATION_DECADES).rev() {
        sol = solve(&sol.u, Start::Near, lambda_g * 10f64.powi(-d))?;
    }
    Ok(sol)
}

/// Decades of λg above the case's at which [`continued_down`] starts.
pub const DOWN_DECADES: i32 = 2;

/// Continuation in λg from above of a frame that [`continued`] could not bring to `lambda_g`
/// either (`docs/noise.md`, N7): solved from `guess` at `λg·10^DOWN_DECADES`, where the frame
/// follows its data closely, then down by half a decade at a time to `lambda_g`. A frame
/// whose data a rod cannot follow exactly (smooth changes of shape that stretch the body by a
/// few per cent) has its twist held by the weak load terms only; in a band of λg the twist
/// changes branch there, the moment rows of Newton's matrix are near singular and Newton
/// stalls when it comes from below. From above it lands on the branch of the closely
/// followed data.
fn continued_down(
    solve: &mut impl FnMut(&DVector<f64>, Start, f64) -> Result<InverseSolution, SolveError>,
    guess: &DVector<f64>,
    lambda_g: f64,
) -> Result<InverseSolution, SolveError> {
    let mut sol = solve(guess, Start::Guess, lambda_g * 10f64.powi(DOWN_DECADES))?;
    for half in (0..2 * DOWN_DECADES).rev() {
        sol = solve(&sol.u, Start::Near, lambda_g * 10f64.powf(0.5 * half as f64))?;
    }
    Ok(sol)
}

/// The initial iterate of a clip's first frame, in the chart of that frame.
#[derive(Clone, Copy, Debug)]
pub enum FirstStart<'a> {
    /// [`data_frame_guess`] of the frame's data (from the fixed point's warm start, I8)
    DataGuess,
    /// a guess: the fixed point's warm start runs first (I8)
    Guess(&'a DVector<f64>),
    /// a state near the frame's solution (its solution at a nearby λg, `engine::weights`): Newton
    /// directly, as from a previous frame, and the data guess if that fails
    Near(&'a DVector<f64>),
}

/// Solve every frame of `frames` (positions per node, the mesh's nodes) in order, the first
/// from `first` ([`FirstStart`]). Later frames start from the previous frame's
/// solution re-expressed in their chart (and, if that fails, once more from the data guess) or
/// from the data guess, as `sp.start` says. `on_frame` receives each converged frame (e.g. to
/// stream it to disk) and may stop the clip by returning an error ([`FrameStop`]); `on_iteration` sees
/// every iteration's record.
pub fn solve_sequence<'a>(
    problem: &Problem,
    sp: &SequenceParams,
    frames: impl Into<ClipData<'a>>,
    first: FirstStart<'_>,
    on_iteration: impl FnMut(usize, &InverseRecord),
    on_frame: impl FnMut(&FrameReport, &FrameSolution) -> Result<(), FrameStop>,
) -> Result<Vec<FrameReport>, SequenceError> {
    solve_sequence_from(problem, sp, frames, SequenceStart { first, resume: None }, on_iteration, on_frame)
}

/// Where a clip's solve starts: the initial iterate of its first frame and, when it resumes,
/// the frames already solved ([`ResumeFrom`]).
#[derive(Clone, Debug)]
pub struct SequenceStart<'a> {
    pub first: FirstStart<'a>,
    pub resume: Option<ResumeFrom>,
}

/// Where a clip solve resumes: the number of frames already solved (≥ 1) and the states of
/// the last two of them in their charts, exactly as [`FrameSolution::state`] gave them. A clip
/// resumed from the states of its frames `next − 2` and `next − 1` continues bit for bit as the
/// uninterrupted solve would (every frame's solve depends on those two states, its data and
/// its chart only).
#[derive(Clone, Debug)]
pub struct ResumeFrom {
    pub next: usize,
    pub prev: (Chart, DVector<f64>),
    pub prev2: Option<(Chart, DVector<f64>)>,
}

/// [`solve_sequence`] from `start` (the first frame from `start.first`), optionally resumed
/// after the frames of `start.resume`; the reports returned
/// are those of the frames solved here. Before each frame it checks for a requested stop
/// (`crate::interrupt`): the clip then ends with [`SolveError::Interrupted`], every frame before
/// it handed to `on_frame`.
pub fn solve_sequence_from<'a>(
    problem: &Problem,
    sp: &SequenceParams,
    data: impl Into<ClipData<'a>>,
    start: SequenceStart<'_>,
    mut on_iteration: impl FnMut(usize, &InverseRecord),
    mut on_frame: impl FnMut(&FrameReport, &FrameSolution) -> Result<(), FrameStop>,
) -> Result<Vec<FrameReport>, SequenceError> {
    let (data, SequenceStart { first: start0, resume }) = (data.into(), start);
    let frames = data.positions;
    let dofs = problem.dofs();
    let h = problem.mesh.h();
    let mut reports: Vec<FrameReport> = Vec::with_capacity(frames.len());
    // the previous frame: its chart and its state in that chart; the frame before that, for
    // the linear predictor of a warm start
    let (first, mut prev, mut prev2) = resume.map_or((0, None, None), |r| (r.next, Some(r.prev), r.prev2));
    // pattern, LU storage and scratch once per clip, reused by every frame
    let mut solver = FrameSolver::new(problem, sp.inverse).with_records(sp.records);
    for (i, x_space) in frames.iter().enumerate().skip(first) {
        if crate::interrupt::requested() {
            return Err(SolveError::Interrupted { what: "frames", done: i, total: frames.len() }.into());
        }
        let k = i + sp.frame_offset;
        let start = std::time::Instant::now();
        let FramePrep { chart, x_g, first_start, alpha_prev, carried } =
            prepare(sp, problem, x_space, prev.as_ref(), prev2.as_ref(), start0);
        let guess = || data_frame_guess(&frame_geometry(&x_g, problem.mesh.length_m));
        let (weight, tracked) = (data.weights(i), data.tracked(i));
        let (previous, fix_roll) = (alpha_prev.as_deref(), sp.plane.is_some());
        let frame = Frame { index: k, x_g: &x_g, previous, weight: weight.as_deref(), fix_roll };
        // From the previous frame's solution (already close) Newton runs directly; from a guess
        // it needs the fixed point's warm start (I8).
        let lambda_g = sp.inverse.weights.lambda_g;
        let mut solve = |u0: &DVector<f64>, start: Start, lambda: f64| -> Result<InverseSolution, SolveError> {
            solver.params.weights.lambda_g = lambda;
            solver.solve(&frame, u0, start, |r, _, _| on_iteration(k, r))?.converged(k)
        };
        // restarts from the data guess (D13) and continuation in λg: [`with_restarts`]
        let from = StartedFrom::frame(i, sp.start);
        let near = from == StartedFrom::PreviousFrame || (carried.is_none() && matches!(start0, FirstStart::Near(_)));
        let smooth = || smoothed_guess(&x_g, problem.mesh.length_m);
        let kind = if near { Start::Near } else { Start::Guess };
        let first = with_restarts(&mut solve, &first_start, kind, &guess, &smooth, lambda_g)?;
        let check = |sol: &InverseSolution| frame_fit(sp, problem, sol, (&x_g[..], tracked), &chart);
        let (sol, restarted, fit) = accepted(first, from, &check, || solve(&guess(), Start::Guess, lambda_g).ok());
        let (cos_beta, node) = min_cos_beta(&dofs, &sol.u);
        chart_guard(sp, &reports, k, &chart, (cos_beta, node))?;
        let last = sol.history.last().copied().ok_or(SequenceError::NoIteration { frame: k })?;
        let rep = FrameReport {
            frame: k,
            convergence: FrameConvergence::at(&last),
            misfit: DataMisfit::at(&last),
            conditioning: FrameConditioning {
                min_cos_beta: cos_beta,
                min_cos_beta_node: node,
                max_stretch_deviation: max_stretch_deviation(x_space, h, tracked),
            },
            restarted,
            chart_axis: chart.axis(),
            wall_time_s: start.elapsed().as_secs_f64(),
            certificate: sol.certificate.value,
            fit,
            nodes_tracked: tracked.map_or(x_g.len(), |t| t.iter().filter(|t| **t).count()),
        };
        let in_space = if chart.is_identity() { None } else { Some(to_space(&dofs, &chart, &sol)) };
        let solution = FrameSolution {
            solution: in_space.as_ref().unwrap_or(&sol),
            chart,
            previous: frame.previous,
            state: &sol.u,
        };
        on_frame(&rep, &solution).map_err(|stop| SequenceError::Callback { frame: k, stop })?;
        prev2 = prev.take();
        prev = Some((chart, sol.u));
        reports.push(rep);
    }
    Ok(reports)
}

/// What a frame's solve starts from: its chart, its data in that chart, the initial iterate,
/// the previous frame's angles in this chart (the Λω term) and the carried previous state.
struct FramePrep {
    chart: Chart,
    x_g: Vec<Vector3<f64>>,
    first_start: DVector<f64>,
    alpha_prev: Option<Vec<Angles>>,
    carried: Option<DVector<f64>>,
}

/// The start of a frame with data `x_space` after the frames with states `prev` and `prev2`
/// (each in its chart): the chart follows the data ([`frame_chart`]); the previous frame's state
/// is carried to this chart (R6) and, with two previous frames, extrapolated by the linear
/// predictor 2 u_{n−1} − u_{n−2} (the clip is sampled smoothly in time). (Carrying the adjoint
/// as well, instead of Newton's consistent-start solve, sent frame 659 of worm_roll_3d to a
/// wrong root: not done.) The previous frame's angles are converted to this chart once,
/// unwrapped twice (along the rod for the carried state, against the start for the Λω term).
fn prepare(
    sp: &SequenceParams,
    problem: &Problem,
    x_space: &[Vector3<f64>],
    prev: Option<&(Chart, DVector<f64>)>,
    prev2: Option<&(Chart, DVector<f64>)>,
    start0: FirstStart<'_>,
) -> FramePrep {
    let dofs = problem.dofs();
    let chart = frame_chart(sp, prev.map(|(c, _)| c), x_space, problem.mesh.length_m);
    let x_g: Vec<Vector3<f64>> =
        if chart.is_identity() { x_space.to_vec() } else { x_space.iter().map(|x| chart.to_chart(x)).collect() };
    let prev_angles = prev.map(|(c, u)| chart.converted(c, &dofs.field(u, Field::Alpha)));
    let carried = prev.map(|(c, u)| {
        let u1 = carry_converted(&dofs, &chart, c, u, prev_angles.as_ref(), None);
        match prev2 {
            Some((c2, u2)) => &u1 * 2.0 - carry_state(&dofs, &chart, c2, u2, Some(&u1)),
            None => u1,
        }
    });
    let first_start = match (&carried, sp.start, start0) {
        (None, _, FirstStart::Guess(u0) | FirstStart::Near(u0)) => u0.clone(),
        (Some(u), FrameStart::PreviousFrame, _) => u.clone(),
        _ => data_frame_guess(&frame_geometry(&x_g, problem.mesh.length_m)),
    };
    let alpha_prev: Option<Vec<Angles>> = prev_angles.as_ref().map(|converted| {
        let near = dofs.field(&first_start, Field::Alpha);
        converted.unwrapped(Some(&near))
    });
    FramePrep { chart, x_g, first_start, alpha_prev, carried }
}

/// A frame solved from `first_start` as `first_kind` says ([`Start::Near`]: a start near its
/// solution, [`Start::Guess`]: a guess, from which the restart below is not tried); one that does not
/// converge from there is solved again from the data `guess` (D13), and one that does not
/// converge from there either is continued in λg from the `smooth`ed data ([`continued`]).
/// Whether it was restarted.
fn with_restarts(
    solve: &mut impl FnMut(&DVector<f64>, Start, f64) -> Result<InverseSolution, SolveError>,
    first_start: &DVector<f64>,
    first_kind: Start,
    guess: &dyn Fn() -> DVector<f64>,
    smooth: &dyn Fn() -> Option<DVector<f64>>,
    lambda_g: f64,
) -> Result<(InverseSolution, bool), SolveError> {
    match solve(first_start, first_kind, lambda_g) {
        Ok(sol) => Ok((sol, false)),
        Err(e) if recoverable(&e) => {
            let again = if first_kind == Start::Near { solve(&guess(), Start::Guess, lambda_g) } else { Err(e) };
            match again {
                Ok(sol) => Ok((sol, true)),
                Err(e) if recoverable(&e) => {
                    let smooth = smooth().unwrap_or_else(guess);
                    match continued(solve, &smooth, lambda_g) {
                        Ok(sol) => Ok((sol, true)),
                        Err(_) => Ok((continued_down(solve, &smooth, lambda_g).map_err(|_| e)?, true)),
                    }
                }
                Err(e) => Err(e),
            }
        }
        Err(e) => Err(e),
    }
}

/// The chart guard: an error if the frame's smallest |cos β| (at `node`) is below
/// `sp.min_cos_beta`, naming the frames among `reports` that were over the fit-quality gate.
fn chart_guard(
    sp: &SequenceParams,
    reports: &[FrameReport],
    k: usize,
    chart: &Chart,
    (cos_beta, node): (f64, usize),
) -> Result<(), SequenceError> {
    if cos_beta < sp.min_cos_beta {
        let flagged: Vec<usize> = reports.iter().filter(|r| r.fit.flagged).map(|r| r.frame).collect();
        return Err(SequenceError::SingularChart {
            frame: k,
            node,
            cos_beta,
            guard: sp.min_cos_beta,
            axis: chart.axis().into(),
            degraded: flagged.first().map(|&first| (flagged.len(), first, reports[0].frame)),
        });
    }
    Ok(())
}
