//! Running a case in either engine, producing one engine-agnostic [`RunResult`].
use std::path::Path;
use std::time::Instant;

use nalgebra::{DVector, Vector3};

use crate::case::{Analysis, Case, ClipKind, DataSource, InverseMethod, InverseSettings, StaticMethod};
use crate::clip::synthetic::{compare_frame, roll_clip, FrameComparison, GroundTruth, RecoveredFrame};
use crate::clip::{read_kymogram, read_recording, Clip, ClipError, KymogramParams};
use crate::data::{read_data, write_data, DataError};
use crate::freefem::{self, FreeFemError};
use crate::metrics::INNER_SKIP_ELEMENTS;
use crate::output::{planar_xz_curvature, sign_alternation, ClipWriter, OutputError};
use crate::solve::dynamics::{self, DynamicParams, TipRecord};
use crate::solve::inverse::{self, InverseParams, InverseRecord};
use crate::solve::inverse_newton;
pub use crate::solve::sequence::FrameStart;
use crate::solve::sequence::{solve_sequence, FrameMethod, FrameReport, SequenceError, SequenceParams};
use crate::solve::statics::{self, IterationRecord, Method, StaticParams};
use crate::solve::{node_values, Problem, SolveError};

/// Which implementation produced a result.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Engine {
    Rust,
    Freefem,
}

impl std::fmt::Display for Engine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Engine::Rust => "rust",
            Engine::Freefem => "freefem",
        })
    }
}

/// Nodal fields of the final state.
#[derive(Clone, Debug, PartialEq)]
pub struct NodalState {
    /// reference arc length [m]
    pub s: Vec<f64>,
    /// position [m]
    pub x: Vec<Vector3<f64>>,
    /// angles (α, β, γ) [rad] in `chart`
    pub alpha: Vec<Vector3<f64>>,
    /// the angles' chart (`crate::chart`; the paper's global chart unless a clip was rebased)
    pub chart: crate::chart::Chart,
}

impl NodalState {
    pub fn from_vector(case: &Case, u: &DVector<f64>) -> Self {
        let n = case.mesh.nodes();
        let (x, alpha) = (0..n).map(|i| node_values(u, i)).unzip();
        NodalState { s: (0..n).map(|i| case.mesh.node_s(i)).collect(), x, alpha, chart: Default::default() }
    }
    /// Element-midpoint curvature `κˡ = A(α) ∂s α` [1/m] with the midpoint arc length [m] (eq. 28).
    pub fn element_curvature(&self) -> Vec<(f64, Vector3<f64>)> {
        (0..self.s.len().saturating_sub(1))
            .map(|e| {
                let h = self.s[e + 1] - self.s[e];
                let mid = (self.alpha[e] + self.alpha[e + 1]) * 0.5;
                (
                    (self.s[e] + self.s[e + 1]) * 0.5,
                    crate::rotation::curvature(&mid, &((self.alpha[e + 1] - self.alpha[e]) / h)),
                )
            })
            .collect()
    }
    /// Directors `d1, d2, d3` per node (rows of Q, eq. 2).
    pub fn directors(&self) -> Vec<[Vector3<f64>; 3]> {
        self.alpha
            .iter()
            .map(|a| {
                let q = self.chart.rotation(a);
                [q.row(0).transpose(), q.row(1).transpose(), q.row(2).transpose()]
            })
            .collect()
    }
    /// Displacement from the reference configuration `(0, 0, s)` [m].
    pub fn displacement(&self) -> Vec<Vector3<f64>> {
        self.x.iter().zip(&self.s).map(|(x, s)| x - Vector3::new(0.0, 0.0, *s)).collect()
    }
}

/// Solver statistics.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SolverStats {
    /// static: iterations of the nonlinear solver; dynamic: total Newton iterations
    pub iterations: usize,
    /// static: last relative change (fixed point) or increment (Newton)
    pub last_change: Option<f64>,
    /// static: ‖R‖∞/‖F‖∞ at the solution
    pub residual: Option<f64>,
    /// dynamic: largest Newton iteration count of a step
    pub max_newton_iterations: Option<usize>,
    /// wall-clock time of the solve (engine-internal) [s]
    pub wall_time_s: f64,
}

/// Result of running a case in one engine.
#[derive(Clone, Debug)]
pub struct RunResult {
    pub engine: Engine,
    /// final state; for an inverse case the recovered `(x, α)`
    pub nodes: NodalState,
    /// static iteration history
    pub history: Vec<IterationRecord>,
    /// dynamic tip history (including t = 0)
    pub tip: Vec<TipRecord>,
    pub stats: SolverStats,
    /// inverse cases: data, adjoint (controls) and per-iteration history
    pub inverse: Option<InverseOutput>,
}

/// What an inverse run adds to its [`RunResult`].
#[derive(Clone, Debug)]
pub struct InverseOutput {
    /// the data read from `data.csv` (x_g and the forward angles α_f, I7)
    pub data: NodalState,
    /// whether `data.alpha` holds true angles (synthetic data) or zeros (a recorded clip,
    /// whose frame is unknown): curvature errors are only reported in the first case
    pub angles_known: bool,
    /// adjoint x̂ per node; the force control is f = x̂/λf [N/m] (eq. 54)
    pub xhat: Vec<Vector3<f64>>,
    /// adjoint α̂ per node; the torque control is l = α̂/λl [N] (eq. 54)
    pub ahat: Vec<Vector3<f64>>,
    /// one record per iteration (relative change, fit measures, objective terms of (41))
    pub history: Vec<InverseRecord>,
    /// per iteration: curvature error against the data's `[all elements, inner]`
    /// (`metrics::inverse_metrics`); empty when the engine does not report it (FreeFEM)
    pub kappa_err: Vec<[f64; 2]>,
    pub lambda_f: f64,
    pub lambda_l: f64,
}

impl InverseOutput {
    /// Force control f = x̂/λf per node [N/m].
    pub fn force(&self) -> Vec<Vector3<f64>> {
        self.xhat.iter().map(|v| v / self.lambda_f).collect()
    }
    /// Torque control l = α̂/λl per node [N·m/m].
    pub fn torque(&self) -> Vec<Vector3<f64>> {
        self.ahat.iter().map(|v| v / self.lambda_l).collect()
    }
}

/// Errors of running a case.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error("rust engine")]
    Solve(#[from] SolveError),
    #[error("freefem engine")]
    FreeFem(#[from] FreeFemError),
    #[error("inverse data")]
    Data(#[from] DataError),
    #[error("clip")]
    Clip(#[from] ClipError),
    #[error("clip: {0}")]
    ClipShape(String),
    #[error("clip")]
    Sequence(#[from] SequenceError),
    #[error("writing the clip")]
    Output(#[from] OutputError),
    /// The solver stopped without meeting its rule; `partial` holds the last iterate and the
    /// history up to there (sweeps keep it so that non-converging values still show).
    #[error("rust engine stopped after {} iterations without meeting its stopping rule", .partial.stats.iterations)]
    Incomplete { source: SolveError, partial: Box<RunResult> },
}

/// The solver parameters of the first (only) frame of an inverse case.
pub fn inverse_params(settings: &InverseSettings) -> InverseParams {
    let w = &settings.weights;
    InverseParams {
        lambda_g: w.lambda_g,
        lambda_f: w.lambda_f,
        lambda_l: w.lambda_l,
        lambda_d: w.lambda_d,
        lambda_kappa: Vector3::from(w.lambda_kappa),
        lambda_omega: Vector3::from(w.lambda_omega),
        dt: settings.frame_interval_s,
        first_frame: true,
        alpha0: settings.alpha0_rad,
        frame: 0,
        stabilisation: settings.stabilisation,
        relaxation: match settings.method {
            InverseMethod::FixedPoint { relaxation } | InverseMethod::Newton { relaxation, .. } => relaxation,
        },
        tolerance: settings.tolerance,
        max_iterations: settings.max_iterations,
    }
}

/// Generate the data of an inverse case: the Rust forward engine on [`Case::data_case`].
///
/// A clip case's single-frame data are the first frame of its range, with zero angles (the
/// recording has no frame): `run`/`compare` then treat that frame alone, as the first frame of
/// the clip is treated (Remark 6); `run_clip` solves the whole clip.
pub fn generate_data(case: &Case) -> Result<NodalState, RunError> {
    if matches!(case.inverse().map(|i| &i.data), Some(DataSource::Clip(_))) {
        let clip = load_clip(case)?;
        let x = clip
            .frames
            .into_iter()
            .next()
            .ok_or_else(|| RunError::ClipShape(format!("case {}: the clip has no frames", case.name)))?;
        let n = x.len();
        return Ok(NodalState {
            s: (0..n).map(|i| case.mesh.node_s(i)).collect(),
            x,
            alpha: vec![Vector3::zeros(); n],
            chart: Default::default(),
        });
    }
    let data_case = case.data_case().ok_or_else(|| SolveError::NotInverse(case.name.clone()))?;
    Ok(run_rust(&data_case, |_, _| {})?.nodes)
}

/// Does the data source of an inverse case carry the true angles (synthetic forward data)?
pub fn angles_known(case: &Case) -> bool {
    matches!(case.inverse().map(|i| &i.data), Some(DataSource::Forward(_)))
}

/// Solve the inverse case `case` in the Rust engine on the given data.
pub fn run_rust_inverse(
    case: &Case,
    data: &NodalState,
    mut progress: impl FnMut(usize, usize),
) -> Result<RunResult, RunError> {
    let settings = case.inverse().ok_or_else(|| SolveError::NotInverse(case.name.clone()))?;
    let problem = Problem::from_case(case);
    let params = inverse_params(settings);
    let n = case.mesh.nodes();
    let prev = vec![Vector3::zeros(); n];
    let start = Instant::now();
    let known = angles_known(case);
    let truth: Vec<Vector3<f64>> = data.element_curvature().into_iter().map(|(_, k)| k).collect();
    let mut kappa_err = Vec::new();
    let mut records = Vec::new();
    let mut last: Option<(DVector<f64>, DVector<f64>)> = None;
    let report = |r: &InverseRecord, u: &DVector<f64>, adjoint: &DVector<f64>| {
        if known {
            let k = inverse::element_curvatures(&problem, u);
            kappa_err.push([
                inverse::relative_error(&k, &truth, 0),
                inverse::relative_error(&k, &truth, INNER_SKIP_ELEMENTS),
            ]);
        }
        records.push(*r);
        last = Some((u.clone(), adjoint.clone()));
        progress(r.iteration, params.max_iterations)
    };
    let outcome = match settings.method {
        InverseMethod::FixedPoint { .. } => {
            inverse::solve_frame_observed(&problem, &params, &data.x, &prev, &problem.reference_state(), report)
        }
        InverseMethod::Newton { warm_start_tolerance, .. } => inverse_newton::solve_frame_warm(
            &problem,
            &params,
            warm_start_tolerance,
            &data.x,
            &prev,
            &problem.reference_state(),
            report,
        ),
    };
    let wall_time_s = start.elapsed().as_secs_f64();
    let result = |u: &DVector<f64>, adjoint: &DVector<f64>, history: Vec<InverseRecord>, kappa_err: Vec<[f64; 2]>| {
        let (xhat, ahat) = (0..n).map(|i| node_values(adjoint, i)).unzip();
        RunResult {
            engine: Engine::Rust,
            nodes: NodalState::from_vector(case, u),
            history: Vec::new(),
            tip: Vec::new(),
            stats: SolverStats {
                iterations: history.len(),
                last_change: history.last().map(|h| h.rel_change),
                residual: None,
                max_newton_iterations: None,
                wall_time_s,
            },
            inverse: Some(InverseOutput {
                data: data.clone(),
                angles_known: known,
                xhat,
                ahat,
                history,
                kappa_err,
                lambda_f: params.lambda_f,
                lambda_l: params.lambda_l,
            }),
        }
    };
    match outcome {
        Ok(sol) => Ok(result(&sol.u, &sol.adjoint, sol.history, kappa_err)),
        Err(source @ (SolveError::InverseNotConverged { .. } | SolveError::InverseNewtonNotConverged { .. })) => {
            match &last {
                Some((u, a)) => {
                    Err(RunError::Incomplete { source, partial: Box::new(result(u, a, records, kappa_err)) })
                }
                None => Err(source.into()),
            }
        }
        Err(e) => Err(e.into()),
    }
}

/// Run `case` in the Rust engine. `progress(done, total)` is called per step/iteration.
///
/// An inverse case generates its data in memory (identical to what `data.csv` holds, since the
/// file round-trips `f64` exactly); [`run`] goes through the file.
pub fn run_rust(case: &Case, mut progress: impl FnMut(usize, usize)) -> Result<RunResult, RunError> {
    let problem = Problem::from_case(case);
    let start = Instant::now();
    match case.analysis {
        Analysis::Inverse(_) => {
            let data = generate_data(case)?;
            run_rust_inverse(case, &data, progress)
        }
        Analysis::Static { method, tolerance, max_iterations, continuation_steps } => {
            let method = match method {
                StaticMethod::FixedPoint { relaxation } => Method::FixedPoint { relaxation },
                StaticMethod::Newton => Method::Newton,
            };
            let params = StaticParams { method, tolerance, max_iterations, continuation_steps };
            let sol = statics::solve(&problem, &params, |r| progress(r.iteration, max_iterations))?;
            Ok(RunResult {
                engine: Engine::Rust,
                nodes: NodalState::from_vector(case, &sol.u),
                history: sol.history,
                tip: Vec::new(),
                stats: SolverStats {
                    iterations: sol.iterations,
                    last_change: Some(sol.last_change),
                    residual: Some(sol.residual),
                    max_newton_iterations: None,
                    wall_time_s: start.elapsed().as_secs_f64(),
                },
                inverse: None,
            })
        }
        Analysis::Dynamic { end_time_s, steps, tolerance, max_iterations } => {
            let params =
                DynamicParams { end_time_s, steps, newton_tolerance: tolerance, newton_max_iterations: max_iterations };
            let sol = dynamics::solve(&problem, &params, &mut progress)?;
            Ok(RunResult {
                engine: Engine::Rust,
                nodes: NodalState::from_vector(case, &sol.u),
                history: Vec::new(),
                tip: sol.tip,
                stats: SolverStats {
                    iterations: sol.total_newton_iterations,
                    last_change: None,
                    residual: None,
                    max_newton_iterations: Some(sol.max_newton_iterations),
                    wall_time_s: start.elapsed().as_secs_f64(),
                },
                inverse: None,
            })
        }
    }
}

/// Run `case` in the chosen engine; FreeFEM works in `workdir`. An inverse case first writes
/// its data to `workdir/data.csv` (Rust forward engine) and then runs on that file.
pub fn run(
    case: &Case,
    engine: Engine,
    workdir: &Path,
    progress: impl FnMut(usize, usize),
) -> Result<RunResult, RunError> {
    if case.inverse().is_some() {
        let path = workdir.join("data.csv");
        write_data(&path, &generate_data(case)?)?;
        return run_inverse_on(case, engine, &path, workdir, progress);
    }
    match engine {
        Engine::Rust => run_rust(case, progress),
        Engine::Freefem => Ok(freefem::run(case, workdir)?),
    }
}

/// Run an inverse case in the chosen engine on the data file `data_path` (I7); FreeFEM works in
/// `workdir`. Both engines read the same file.
pub fn run_inverse_on(
    case: &Case,
    engine: Engine,
    data_path: &Path,
    workdir: &Path,
    progress: impl FnMut(usize, usize),
) -> Result<RunResult, RunError> {
    let data = read_data(data_path, &case.mesh)?;
    match engine {
        Engine::Rust => run_rust_inverse(case, &data, progress),
        Engine::Freefem => Ok(freefem::run_inverse(case, data, data_path, workdir)?),
    }
}

/// Read the clip of a clip case: kymograms become spline centrelines with the mesh's node
/// count and the rod's length in the x–z plane; recordings must have that node count. The
/// frame range of the case is applied.
pub fn load_clip(case: &Case) -> Result<Clip, RunError> {
    Ok(load_clip_with_truth(case)?.0)
}

/// [`load_clip`], and for a synthetic clip (`kind = "roll_3d"`) its ground truth: frames,
/// curvature and roll per frame (`crate::clip::synthetic`), with the same frame range and
/// orientation as the positions.
pub fn load_clip_with_truth(case: &Case) -> Result<(Clip, Option<GroundTruth>), RunError> {
    let settings = case.inverse().ok_or_else(|| SolveError::NotInverse(case.name.clone()))?;
    let DataSource::Clip(src) = &settings.data else { return Err(SolveError::NotInverse(case.name.clone()).into()) };
    if !src.file.is_file() {
        return Err(RunError::ClipShape(format!("{} does not exist (the elegansbot kymograms are fetched and checksum-verified by scripts/fetch_worm_data.sh)", src.file.display())));
    }
    let (mut clip, mut truth) = match (src.kind, &src.synthetic) {
        (ClipKind::Kymogram, _) => {
            let params = KymogramParams {
                length_m: case.mesh.length_m,
                nodes: case.mesh.nodes(),
                dt_s: src.frame_interval_s,
                plane: src.plane,
                scale_to_length: true,
            };
            (read_kymogram(&src.file, &params)?, None)
        }
        (ClipKind::Recording, _) => (read_recording(&src.file, src.frame_interval_s)?, None),
        (ClipKind::Roll3d, Some(params)) => {
            let a = crate::clip::read_npy(&src.file)?;
            let &[_, joints] = a.shape.as_slice() else {
                return Err(RunError::ClipShape(format!(
                    "{}: kymogram of shape {:?}, expected frames × joint angles",
                    src.file.display(),
                    a.shape
                )));
            };
            let rows: Vec<Vec<f64>> = a.data.chunks_exact(joints.max(1)).map(<[f64]>::to_vec).collect();
            let (clip, truth) = roll_clip(&rows, None, params)?;
            (clip, Some(truth))
        }
        (ClipKind::Roll3d, None) => return Err(RunError::ClipShape("roll_3d clip without parameters".into())),
    };
    if clip.node_count() != case.mesh.nodes() {
        return Err(RunError::ClipShape(format!(
            "{}: {} nodes per frame, but the case's mesh has {} (rod.elements + 1)",
            src.file.display(),
            clip.node_count(),
            case.mesh.nodes()
        )));
    }
    if let Some((a, b)) = src.frames {
        if b > clip.frame_count() {
            return Err(RunError::ClipShape(format!(
                "{}: clip.frames = [{a}, {b}) but the clip has {} frames",
                src.file.display(),
                clip.frame_count()
            )));
        }
        clip.frames = clip.frames[a..b].to_vec();
        if let Some(t) = &mut truth {
            t.frames = t.frames[a..b].to_vec();
        }
    }
    let r = src.orientation;
    if r != nalgebra::Matrix3::identity() {
        for frame in &mut clip.frames {
            frame.iter_mut().for_each(|x| *x = r * *x);
        }
        // Directors rotate with the data: Q → Q Rᵀ (rows are the directors).
        for f in truth.iter_mut().flat_map(|t| t.frames.iter_mut()) {
            f.q.iter_mut().for_each(|q| *q *= r.transpose());
        }
    }
    Ok((clip, truth))
}

/// Curvature at the nodes from element-midpoint values: the mean of the adjacent elements
/// (the end element at the ends).
pub fn nodal_curvature(kappa: &[(f64, Vector3<f64>)]) -> Vec<Vector3<f64>> {
    let m = kappa.len();
    (0..=m).map(|i| (kappa[i.saturating_sub(1).min(m - 1)].1 + kappa[i.min(m - 1)].1) * 0.5).collect()
}

/// Summary of a clip run.
#[derive(Clone, Debug)]
pub struct ClipRun {
    pub reports: Vec<FrameReport>,
    /// per frame: sign alternation of the recovered κ2 and of the data's planar curvature
    /// (`output::sign_alternation`)
    pub roughness: Vec<(f64, f64)>,
    /// per frame: recovered κ2 at element midpoints and the data's planar curvature at the
    /// interior nodes [1/m] (x–z clips: the bending curvature; `output::planar_xz_curvature`)
    pub kappa2: Vec<Vec<f64>>,
    pub data_kappa: Vec<Vec<f64>>,
    /// synthetic clips: per frame the errors against the ground truth (end nodes skipped:
    /// [`TRUTH_SKIP_NODES`]), and the true and recovered bending `κ1² + κ2²` [1/m²] per node
    pub truth: Option<TruthRun>,
    pub wall_time_s: f64,
    pub source: String,
}

/// Ground-truth scores of a synthetic clip run.
#[derive(Clone, Debug, Default)]
pub struct TruthRun {
    pub comparisons: Vec<FrameComparison>,
    /// true roll ψ of the bending plane per frame [rad]
    pub roll_rad: Vec<f64>,
    /// true twist κ3 per frame (mean over nodes) [rad/m]
    pub twist_per_m: Vec<f64>,
    pub bending_true: Vec<Vec<f64>>,
    pub bending_recovered: Vec<Vec<f64>>,
}

/// Nodes skipped at each end when scoring curvature against a ground truth (the curvature of
/// the inverse solution is least reliable at the free ends; as `metrics::INNER_SKIP_ELEMENTS`).
pub const TRUTH_SKIP_NODES: usize = INNER_SKIP_ELEMENTS;

/// Solve a clip case frame by frame in the Rust engine, streaming every converged frame into
/// `out` (`output::ClipWriter`). On failure the converged frames stay on disk and the error
/// names the frame.
pub fn run_clip(case: &Case, out: &Path, mut progress: impl FnMut(usize, usize)) -> Result<ClipRun, RunError> {
    let settings = case.inverse().ok_or_else(|| SolveError::NotInverse(case.name.clone()))?;
    let DataSource::Clip(src) = &settings.data else { return Err(SolveError::NotInverse(case.name.clone()).into()) };
    let (clip, truth) = load_clip_with_truth(case)?;
    let problem = Problem::from_case(case);
    let params = inverse_params(settings);
    let method = match settings.method {
        InverseMethod::FixedPoint { .. } => FrameMethod::FixedPoint,
        InverseMethod::Newton { warm_start_tolerance, .. } => FrameMethod::Newton { warm_start_tolerance },
    };
    let first_frame = src.frames.map(|f| f.0).unwrap_or(0);
    let sp = SequenceParams {
        frame: InverseParams { dt: src.frame_interval_s, ..params },
        method,
        min_cos_beta: src.min_cos_beta,
        frame_offset: first_frame,
        start: src.start,
        rotation: src.rotation,
        gauge: src.gauge,
    };
    let mut writer = ClipWriter::create(out)?;
    let mut truth_writer = truth.as_ref().map(|_| crate::output::TruthWriter::create(out)).transpose()?;
    let mut truth_run = truth.as_ref().map(|_| TruthRun::default());
    let total = clip.frame_count();
    let h = case.mesh.h();
    let start = Instant::now();
    let mut rough = Vec::new();
    let (mut kappa2, mut data_kappa) = (Vec::new(), Vec::new());
    // The files are formatted and written on a second thread, in frame order, while the next
    // frame is solved; a write error stops the clip at the next frame.
    type Job = (FrameReport, f64, NodalState, Vec<Vector3<f64>>, Vec<Vector3<f64>>, Vec<Vector3<f64>>, (f64, f64));
    let (tx, rx) = std::sync::mpsc::sync_channel::<Job>(8);
    let (result, written) = std::thread::scope(|scope| {
        let io = scope.spawn(move || -> Result<(), OutputError> {
            for (rep, t, nodes, force, torque, data, roughness) in rx {
                writer.frame(&rep, t, &nodes, &force, &torque, &data, roughness)?;
            }
            writer.finish().map(|_| ())
        });
        let result = solve_sequence(
            &problem,
            &sp,
            &clip.frames,
            None,
            |_, _| {},
            |rep, frame| {
                let sol = frame.solution;
                let nodes = NodalState { chart: frame.chart, ..NodalState::from_vector(case, &sol.u) };
                let (force, torque): (Vec<_>, Vec<_>) = (0..nodes.s.len())
                    .map(|i| {
                        let (xh, ah) = node_values(&sol.adjoint, i);
                        (xh / params.lambda_f, ah / params.lambda_l)
                    })
                    .unzip();
                let data = &clip.frames[rep.frame - first_frame];
                let kappa = nodes.element_curvature();
                let k2: Vec<f64> = kappa.iter().map(|(_, k)| k[1]).collect();
                // The data's curvature in the plane normal to the chart's axis (exactly the x–z
                // curvature for an x–z clip; rotates with the data, R5).
                let in_chart: Vec<Vector3<f64>> = data.iter().map(|x| frame.chart.to_chart(x)).collect();
                let kd = planar_xz_curvature(&in_chart, h);
                if let (Some(t), Some(tw), Some(tr)) = (&truth, &mut truth_writer, &mut truth_run) {
                    let ft = &t.frames[rep.frame - first_frame];
                    let q: Vec<nalgebra::Matrix3<f64>> = nodes.alpha.iter().map(|a| nodes.chart.rotation(a)).collect();
                    let kn = nodal_curvature(&kappa);
                    let c =
                        compare_frame(data, ft, &RecoveredFrame { x: &nodes.x, q: &q, kappa: &kn }, TRUTH_SKIP_NODES)
                            .map_err(|e| e.to_string())?;
                    let twist = ft.kappa.iter().map(|k| k.z).sum::<f64>() / ft.kappa.len() as f64;
                    tw.frame(rep.frame, rep.frame as f64 * clip.dt_s, ft.roll_rad, twist, &c)
                        .map_err(|e| e.to_string())?;
                    let bend = |k: &Vector3<f64>| k.x * k.x + k.y * k.y;
                    tr.comparisons.push(c);
                    tr.roll_rad.push(ft.roll_rad);
                    tr.twist_per_m.push(twist);
                    tr.bending_true.push(ft.kappa.iter().map(bend).collect());
                    tr.bending_recovered.push(kn.iter().map(bend).collect());
                }
                let roughness = (sign_alternation(&k2), sign_alternation(&kd));
                rough.push(roughness);
                kappa2.push(k2);
                data_kappa.push(kd);
                tx.send((*rep, rep.frame as f64 * clip.dt_s, nodes, force, torque, data.clone(), roughness))
                    .map_err(|_| "the output thread stopped (see the write error)".to_string())?;
                progress(rep.frame - first_frame + 1, total);
                Ok(())
            },
        );
        drop(tx);
        let written = io.join().unwrap_or_else(|_| {
            Err(OutputError::Plot { path: out.to_path_buf(), reason: "the output thread panicked".into() })
        });
        (result, written)
    });
    // A write error explains a stopped clip better than the stop itself.
    written?;
    let reports = result?;
    Ok(ClipRun {
        reports,
        roughness: rough,
        kappa2,
        data_kappa,
        truth: truth_run,
        wall_time_s: start.elapsed().as_secs_f64(),
        source: clip.source,
    })
}
