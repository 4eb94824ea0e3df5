//! A clip's frames solved in the Rust engine for a comparison with another engine: each frame
//! as a [`RunResult`] (positions and adjoints in space coordinates, angles in the frame's
//! chart), the same shape the FreeFEM clip driver's frames are read into, so that one
//! comparison ([`super::metrics::differences`]) serves single runs and clips.
use std::time::Instant;

use nalgebra::Vector3;

use super::{Engine, InverseOutput, NodalState, RunError, RunResult, SolverStats};
use crate::case::Case;
use crate::model::mesh::Field;
use crate::solve::inverse::InverseRecord;
use crate::solve::sequence::{solve_sequence, ClipData, FirstStart, SequenceError};

/// One solved frame of a clip.
#[derive(Clone, Debug)]
pub struct SolvedFrame {
    /// frame number (the clip's range offset included)
    pub frame: usize,
    /// the frame was solved again from the data guess after failing from the previous frame
    pub restarted: bool,
    /// positions [m] and adjoints in space coordinates, angles [rad] in the frame's chart
    /// (`result.nodes.chart`), the frame's last record as the history
    pub result: RunResult,
}

/// The frames of a clip solved so far, and the error that stopped the clip, if any.
#[derive(Debug)]
pub struct SolvedFrames {
    pub frames: Vec<SolvedFrame>,
    pub error: Option<SequenceError>,
    pub wall_time_s: f64,
}

/// The [`RunResult`] of one frame: `nodes` (positions in space, angles in their chart), the
/// adjoints in space and the frame's last record; `data` the frame's data positions.
#[allow(clippy::too_many_arguments)]
pub fn frame_result(
    case: &Case,
    engine: Engine,
    nodes: NodalState,
    data: &[Vector3<f64>],
    xhat: Vec<Vector3<f64>>,
    ahat: Vec<Vector3<f64>>,
    last: InverseRecord,
    iterations: usize,
    wall_time_s: f64,
) -> RunResult {
    let w = case.inverse().map(|i| i.params.weights);
    let data = NodalState {
        s: nodes.s.clone(),
        x: data.to_vec(),
        alpha: vec![Vector3::zeros(); data.len()],
        chart: nodes.chart,
        reference_x: None,
    };
    RunResult {
        engine,
        nodes,
        history: Vec::new(),
        tip: Vec::new(),
        stats: SolverStats {
            iterations,
            last_change: Some(last.rel_change),
            residual: None,
            max_newton_iterations: None,
            certificate: last.certificate,
            wall_time_s,
        },
        inverse: Some(InverseOutput {
            data,
            angles_known: false,
            xhat,
            ahat,
            history: vec![last],
            kappa_err: Vec::new(),
            lambda_f: w.map_or(1.0, |w| w.lambda_f),
            lambda_l: w.map_or(1.0, |w| w.lambda_l),
        }),
        path: None,
        stability: None,
    }
}

/// Solve `data` (space coordinates, the clip's frames from its first) of the clip case
/// `case` in order, exactly as `cosserat run` does ([`solve_sequence`]), keeping every frame.
/// A failing frame ends the list and is returned as the error.
pub fn solve_frames<'a>(case: &Case, data: impl Into<ClipData<'a>>) -> Result<SolvedFrames, RunError> {
    let data = data.into();
    let frames = data.positions;
    let sp = case.sequence_params().ok_or_else(|| RunError::kind(case, "a clip case"))?;
    let problem = case.problem();
    let dofs = problem.dofs();
    let start = Instant::now();
    let mut out = Vec::new();
    let result = solve_sequence(
        &problem,
        &sp,
        data,
        FirstStart::DataGuess,
        |_, _| {},
        |rep, f| {
            let sol = f.solution;
            let nodes = NodalState { chart: f.chart, ..NodalState::from_vector(&case.mesh, &sol.u) };
            let last = *sol.history.last().ok_or(SequenceError::NoIteration { frame: rep.frame })?;
            let result = frame_result(
                case,
                Engine::Rust,
                nodes,
                &frames[rep.frame - sp.frame_offset],
                dofs.field(&sol.adjoint, Field::X),
                dofs.field(&sol.adjoint, Field::Alpha),
                last,
                rep.convergence.iterations,
                rep.wall_time_s,
            );
            out.push(SolvedFrame { frame: rep.frame, restarted: rep.restarted, result });
            Ok(())
        },
    );
    Ok(SolvedFrames { frames: out, error: result.err(), wall_time_s: start.elapsed().as_secs_f64() })
}
