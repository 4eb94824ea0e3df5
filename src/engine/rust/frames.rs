//! A clip's frames solved in the Rust engine for a comparison with another engine
//! ([`SolvedFrames`], the shape the FreeFEM clip driver's frames are read into).
use std::time::Instant;

use super::{Engine, NodalState, RunError};
use crate::case::Case;
use crate::engine::common::frames::{frame_result, FrameSolution, SolvedFrame, SolvedFrames};
use crate::model::mesh::Field;
use crate::solve::sequence::{solve_sequence, ClipData, FirstStart, SequenceError};

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
            let solution = FrameSolution {
                nodes,
                data: &frames[rep.frame - sp.frame_offset],
                xhat: dofs.field(&sol.adjoint, Field::X),
                ahat: dofs.field(&sol.adjoint, Field::Alpha),
                last,
                iterations: rep.convergence.iterations,
                wall_time_s: rep.wall_time_s,
            };
            let result = frame_result(case, Engine::Rust, solution);
            out.push(SolvedFrame { frame: rep.frame, restarted: rep.restarted, result });
            Ok(())
        },
    );
    Ok(SolvedFrames { frames: out, error: result.err(), wall_time_s: start.elapsed().as_secs_f64() })
}
