//! A clip's frames as both engines give them for a comparison: each frame as a [`RunResult`]
//! (positions and adjoints in space coordinates, angles in the frame's chart), so that one
//! comparison ([`super::metrics::differences`]) serves single runs and clips.
use nalgebra::Vector3;

use super::result::{Engine, InverseOutput, NodalState, RunResult, SolverStats};
use crate::case::Case;
use crate::solve::inverse::InverseRecord;
use crate::solve::sequence::SequenceError;

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

/// What an engine reports of one solved frame of a clip.
#[derive(Clone, Debug)]
pub struct FrameSolution<'a> {
    /// positions [m] in space, angles [rad] in the frame's chart
    pub nodes: NodalState,
    /// the frame's data positions [m]
    pub data: &'a [Vector3<f64>],
    /// the adjoints x̂, α̂ per node, in space coordinates
    pub xhat: Vec<Vector3<f64>>,
    pub ahat: Vec<Vector3<f64>>,
    /// the frame's last iteration record
    pub last: InverseRecord,
    pub iterations: usize,
    pub wall_time_s: f64,
}

/// The [`RunResult`] of one frame of the clip case `case` solved by `engine`.
pub fn frame_result(case: &Case, engine: Engine, solution: FrameSolution<'_>) -> RunResult {
    let FrameSolution { nodes, data, xhat, ahat, last, iterations, wall_time_s } = solution;
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
