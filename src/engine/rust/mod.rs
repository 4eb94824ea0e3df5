//! Running a case in the Rust engine on data in memory: a forward case, the forward data of a
//! synthetic inverse case, one inverse frame ([`run_inverse`]) or a whole clip
//! ([`clip::run_clip`]), each producing the engine-agnostic [`RunResult`] of [`result`].
//! The files a case runs on are `super::input`'s, the FreeFEM engine `super::freefem`, the output
//! folder `crate::output`'s.
pub mod budget;
pub mod clip;
mod derive;
pub mod frames;
#[cfg(test)]
mod published_tests;
pub mod stability;
pub mod weights;

use std::time::Instant;

use nalgebra::{DVector, Vector3};

use super::common::metrics::{self, INNER_SKIP_ELEMENTS};
use super::common::result::{self, Engine, InverseOutput, NodalState, RunResult, SolverStats};
use super::common::{angles_known, path_record_points};

use crate::case::{Analysis, Case};
use crate::clip::ClipError;
use crate::model::mesh::Field;
use crate::solve::inverse::{Frame, FrameSolver, InverseRecord, Start};
use crate::solve::sequence::{first_chart, SequenceError};
use crate::solve::statics::StaticParams;
use crate::solve::{arclength, dynamics, statics, SolveError};

/// Errors of running a case.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error("rust engine")]
    Solve(#[from] SolveError),
    #[error("clip")]
    Clip(#[from] ClipError),
    #[error("clip")]
    Sequence(#[from] SequenceError),
    #[error("case `{case}` is not {what}")]
    Kind { case: String, what: &'static str },
    #[error(
        "case `{case}`: the single-frame inverse path solves a clip's first frame alone, in the paper's angle chart (eq. 1) from the straight reference state, but this clip's first frame is solved in the rebased chart with singular axis ({:.3}, {:.3}, {:.3}) (clip.rotation = \"rebased\" with clip.gauge or clip.orientation away from e2). `cosserat run` and `cosserat compare` solve the clip frame by frame in its charts; for the single-frame path set clip.rotation = \"global_euler\" or a gauge along e2", axis[0], axis[1], axis[2]
    )]
    Chart { case: String, axis: [f64; 3] },
    #[error("rust engine: the eigen-analysis of the static result (D27)")]
    Stability(#[from] crate::solve::stability::StabilityError),
    #[error("rust engine: the natural frequencies about the rest state (solver.vibration_modes, D28)")]
    Modes(#[from] crate::solve::modes::ModesError),
    #[error("writing the clip")]
    Sink(#[source] Box<dyn std::error::Error + Send + Sync>),
    #[error("resuming the clip: {0}")]
    Resume(clip::ResumeError),
    #[error("the clip's frame generator stopped after {received} of {total} frames")]
    Generator { received: usize, total: usize },
    /// A recording streamed from its file could not be read on (it changed after it was read
    /// through before the solve).
    #[error("reading the recording stopped after {received} of {total} frames")]
    Recording {
        received: usize,
        total: usize,
        #[source]
        source: crate::io::files::InputError,
    },
    /// A forward solve diverged: the error, with the largest load of the case named (a load
    /// far beyond the rod's stiffness is the usual cause).
    #[error("rust engine: the solve could not follow the loads, the largest of which is {key} = \"{expr}\" = {value:e} (check its magnitude and units, or raise solver.continuation_steps of a static case)")]
    Diverged { source: SolveError, key: String, expr: String, value: f64 },
    /// The solver stopped without meeting its rule; `partial` holds the last iterate and the
    /// history up to there (sweeps keep it so that non-converging values still show).
    #[error("rust engine stopped after {} iterations without meeting its stopping rule", .partial.stats.iterations)]
    Incomplete {
        #[source]
        source: SolveError,
        partial: Box<RunResult>,
    },
}

impl RunError {
    /// Did the run stop because a stop was requested (`crate::interrupt`)?
    pub fn is_interrupted(&self) -> bool {
        match self {
            RunError::Solve(e) | RunError::Incomplete { source: e, .. } | RunError::Diverged { source: e, .. } => {
                matches!(e, SolveError::Interrupted { .. })
            }
            RunError::Sequence(SequenceError::Solve(e)) => matches!(e, SolveError::Interrupted { .. }),
            _ => false,
        }
    }

    fn kind(case: &Case, what: &'static str) -> Self {
        RunError::Kind { case: case.name.clone(), what }
    }
}

/// Run a forward (static or dynamic) case in the Rust engine; `progress(done, total)` per
/// iteration or time step. A diverged solve names the case's largest load.
pub fn run_forward(case: &Case, progress: impl FnMut(usize, usize)) -> Result<RunResult, RunError> {
    run_forward_solve(case, progress).map_err(|e| match e {
        RunError::Solve(source @ (SolveError::Diverged { .. } | SolveError::Linear(_))) => {
            let s: Vec<f64> = (0..case.mesh.nodes()).map(|i| case.mesh.node_s(i)).collect();
            let end = match &case.analysis {
                Analysis::Dynamic(p) => p.end_time_s,
                _ => 0.0,
            };
            let big = [0.0, end]
                .iter()
                .filter_map(|&t| case.loads.largest(&s, t))
                .max_by(|a, b| a.2.abs().total_cmp(&b.2.abs()));
            match big {
                Some((key, expr, value)) => RunError::Diverged { source, key, expr, value },
                None => RunError::Solve(source),
            }
        }
        e => e,
    })
}

fn run_forward_solve(case: &Case, mut progress: impl FnMut(usize, usize)) -> Result<RunResult, RunError> {
    let problem = case.problem();
    let start = Instant::now();
    match &case.analysis {
        Analysis::Static(StaticParams { path: Some(path), tolerance, max_iterations, .. }) => {
            let sol = arclength::follow(&problem, path, *tolerance, *max_iterations, &mut progress)?;
            let last = sol.points.last().expect("the path's reference point");
            let at = crate::solve::Problem { load_factor: last.load_factor, ..problem };
            let stability = stability::output(case, &at, &last.u)?;
            Ok(RunResult {
                stability: Some(stability),
                ..path_result(case, &problem, sol, start.elapsed().as_secs_f64())
            })
        }
        Analysis::Static(params) => {
            let sol = statics::solve(&problem, params, |r| progress(r.iteration, params.max_iterations))?;
            // the stability of a solution only (D27): an unconverged iterate has none
            let stability = match sol.stop {
                crate::solve::Stop::Converged => Some(stability::output(case, &problem, &sol.u)?),
                _ => None,
            };
            let result = RunResult {
                engine: Engine::Rust,
                nodes: NodalState::of_forward(case, &sol.u),
                history: sol.history.clone(),
                tip: Vec::new(),
                stats: SolverStats {
                    iterations: sol.iterations,
                    last_change: Some(sol.last_change),
                    residual: Some(sol.residual),
                    max_newton_iterations: None,
                    certificate: Some(sol.certificate.value),
                    wall_time_s: start.elapsed().as_secs_f64(),
                },
                inverse: None,
                path: None,
                stability,
            };
            match sol.converged() {
                Ok(_) => Ok(result),
                Err(source) => Err(RunError::Incomplete { source, partial: Box::new(result) }),
            }
        }
        Analysis::Dynamic(params) => {
            let mut sol = dynamics::solve(&problem, params, &mut progress)?;
            // each record in its own chart (D32)
            sol.tip
                .iter_mut()
                .filter(|t| !t.chart.is_identity())
                .for_each(|t| t.position_m = t.chart.to_space(&t.position_m));
            Ok(RunResult {
                engine: Engine::Rust,
                nodes: NodalState::of_forward_in(case, &sol.u, sol.chart),
                history: Vec::new(),
                tip: sol.tip,
                stats: SolverStats {
                    iterations: sol.total_newton_iterations,
                    last_change: None,
                    residual: None,
                    max_newton_iterations: Some(sol.max_newton_iterations),
                    certificate: Some(sol.max_certificate),
                    wall_time_s: start.elapsed().as_secs_f64(),
                },
                inverse: None,
                path: None,
                stability: None,
            })
        }
        Analysis::Inverse(_) => Err(RunError::kind(case, "a forward case")),
    }
}

/// The result of an arc-length path (D25): the last point's state, every Newton iteration,
/// and the path.
fn path_result(
    case: &Case,
    problem: &crate::solve::Problem,
    sol: arclength::PathSolution,
    wall_time_s: f64,
) -> RunResult {
    let record_s_m = path_record_points(case);
    let points = sol
        .points
        .iter()
        .map(|p| result::PathRecord {
            step: p.step,
            load_factor: p.load_factor,
            arc_length: p.arc_length,
            determinant_sign: p.determinant_sign,
            iterations: p.iterations,
            certificate: p.certificate,
            displacements: record_s_m.iter().map(|&s| arclength::displacement_at(problem, &p.u, s)).collect(),
        })
        .collect();
    let last = sol.points.last().expect("the path's reference point");
    RunResult {
        engine: Engine::Rust,
        nodes: NodalState::of_forward(case, &last.u),
        stats: SolverStats {
            iterations: sol.history.len(),
            last_change: sol.history.last().map(|r| r.change),
            residual: None,
            max_newton_iterations: sol.points.iter().map(|p| p.iterations).max(),
            certificate: Some(last.certificate),
            wall_time_s,
        },
        history: sol.history,
        tip: Vec::new(),
        inverse: None,
        path: Some(result::PathOutput {
            record_s_m,
            points,
            critical: sol.critical,
            reached_end: sol.end == arclength::PathEnd::ReachedLoad,
        }),
        stability: None,
    }
}

/// The data of a synthetic inverse case: the Rust forward engine on [`Case::data_case`] (I7).
pub fn forward_data(case: &Case) -> Result<NodalState, RunError> {
    let data_case = case.data_case().ok_or_else(|| RunError::kind(case, "an inverse case with [data]"))?;
    match run_forward(&data_case, |_, _| {}) {
        Ok(r) => Ok(r.nodes),
        Err(RunError::Incomplete { source, .. }) => Err(source.into()),
        Err(e) => Err(e),
    }
}

/// The single-frame path (`run_inverse`: `compare` and `sweep` on a clip case) solves a clip's
/// first frame in the paper's chart from the straight reference state, as the FreeFEM engine
/// does. A clip whose first frame the clip driver solves in another chart (`clip.rotation =
/// "rebased"` with `clip.gauge` or `clip.orientation` away from e2) is refused: from the straight
/// state in a rotated chart the scheme reaches a spurious root, and in the paper's chart the
/// settings would be ignored.
pub fn check_single_frame(case: &Case) -> Result<(), RunError> {
    match case.sequence_params().map(|sp| first_chart(&sp)) {
        Some(chart) if !chart.is_identity() => {
            Err(RunError::Chart { case: case.name.clone(), axis: chart.axis().into() })
        }
        _ => Ok(()),
    }
}

/// Solve the inverse case `case` as one first frame (Remark 6) in the Rust engine on the data
/// `data` (its positions; for synthetic data also the true angles, for the curvature errors),
/// from the straight reference state in the paper's chart ([`check_single_frame`]).
pub fn run_inverse(
    case: &Case,
    data: &NodalState,
    mut progress: impl FnMut(usize, usize),
) -> Result<RunResult, RunError> {
    let settings = case.inverse().ok_or_else(|| RunError::kind(case, "an inverse case"))?;
    check_single_frame(case)?;
    let params = settings.params;
    let problem = case.problem();
    let start = Instant::now();
    let known = angles_known(case);
    let truth: Vec<Vector3<f64>> = data.element_curvature().into_iter().map(|(_, k)| k).collect();
    let mut kappa_err = Vec::new();
    let observer = |r: &InverseRecord, u: &DVector<f64>, _: &DVector<f64>| {
        if known {
            let k: Vec<Vector3<f64>> =
                NodalState::from_vector(&case.mesh, u).element_curvature().into_iter().map(|(_, k)| k).collect();
            kappa_err.push([
                metrics::relative_error(&k, &truth, 0),
                metrics::relative_error(&k, &truth, INNER_SKIP_ELEMENTS),
            ]);
        }
        progress(r.iteration, params.max_iterations)
    };
    let frame = Frame { index: 0, x_g: &data.x, previous: None, weight: None, fix_roll: false };
    // stopped at its next iteration once a stop is requested (crate::interrupt)
    let sol = FrameSolver::new(&problem, params).stopped_by(crate::interrupt::requested).solve(
        &frame,
        &problem.reference_state(),
        Start::Guess,
        observer,
    )?;
    let dofs = problem.dofs();
    let result = RunResult {
        engine: Engine::Rust,
        nodes: NodalState::from_vector(&case.mesh, &sol.u),
        history: Vec::new(),
        tip: Vec::new(),
        stats: SolverStats {
            iterations: sol.history.len(),
            last_change: sol.history.last().map(|h| h.rel_change),
            residual: None,
            max_newton_iterations: None,
            certificate: Some(sol.certificate.value),
            wall_time_s: start.elapsed().as_secs_f64(),
        },
        inverse: Some(InverseOutput {
            data: data.clone(),
            angles_known: known,
            xhat: dofs.field(&sol.adjoint, Field::X),
            ahat: dofs.field(&sol.adjoint, Field::Alpha),
            history: sol.history.clone(),
            kappa_err,
            lambda_f: params.weights.lambda_f,
            lambda_l: params.weights.lambda_l,
        }),
        path: None,
        stability: None,
    };
    match sol.converged(0) {
        Ok(_) => Ok(result),
        Err(source) => Err(RunError::Incomplete { source, partial: Box::new(result) }),
    }
}

/// Run `case` in the Rust engine from memory: a forward case, or a synthetic inverse case on
/// its forward data generated here (identical to what `data.csv` holds: the file round-trips
/// `f64` exactly). Clips are read from files: `crate::engine`.
pub fn run_rust(case: &Case, progress: impl FnMut(usize, usize)) -> Result<RunResult, RunError> {
    match &case.analysis {
        Analysis::Inverse(_) => run_inverse(case, &forward_data(case)?, progress),
        _ => run_forward(case, progress),
    }
}
