//! The FreeFEM clip driver (`freefem/clip.edp`): consecutive frames of a clip case, warm-started
//! and re-based by the same rules as the Rust engine (`crate::solve::sequence`). The Rust side
//! hands it the frames' data (space coordinates) and each frame's chart base `B`
//! ([`clip_charts`], docs/rotation.md R4: a function of the data alone); everything else, the
//! data guess, the carried states, the re-expressed angles of the Λω term, the restarts and the
//! chart guard, FreeFEM does itself.
use std::fmt::Write as _;
use std::path::Path;

use nalgebra::Vector3;

use crate::case::Case;
use crate::engine::common::frames::{frame_result, FrameSolution, SolvedFrame};
use crate::engine::common::result::{Engine, NodalState};
use crate::engine::freefem::info::FfInfo;
use crate::engine::freefem::{execute, io, read_table, ClipInclude, FreeFemError, RunOptions, FAILED_STATUS};
use crate::model::chart::Chart;
use crate::solve::certificate::{Certificate, System};
use crate::solve::inverse::{InverseRecord, ObjectiveTerms};
use crate::solve::sequence::{clip_charts, ClipData, FrameStart};
use crate::solve::SolveError;

/// Frames solved by FreeFEM, and its failure message if it stopped early.
#[derive(Debug)]
pub struct FreeFemFrames {
    pub frames: Vec<SolvedFrame>,
    /// the driver's `FAILED: frame K: …` message when it stopped before the last frame
    pub error: Option<String>,
    /// when it stopped because a frame stalled (its stopping rule met, its certificate above the
    /// tolerance, `docs/certificate.md`): the error the Rust engine gives for that frame
    pub stalled: Option<SolveError>,
    /// FreeFEM's own clock for the whole clip [s]
    pub wall_time_s: f64,
}

/// Run `freefem/clip.edp` on `frames` (space coordinates, from the clip's first frame) of the
/// clip case `case` in `workdir`. `follow`: per frame, the number of fixed-point iterations to
/// run instead of the tolerance (0: the tolerance) and whether to solve it from its data guess
/// as a restart, for a comparison at the same iterates as another engine's run (a fixed point
/// stopped at an equal count cannot see that the other engine's attempt from the previous
/// frame failed). A failing frame is not an error here: the frames before it are returned with
/// the message.
pub fn run_clip(
    case: &Case,
    clip: ClipData<'_>,
    follow: Option<&[(usize, bool)]>,
    workdir: &Path,
) -> Result<FreeFemFrames, FreeFemError> {
    let sp = case.sequence_params().ok_or_else(|| FreeFemError::NotInverse(case.name.clone()))?;
    std::fs::create_dir_all(workdir).map_err(io(workdir))?;
    let frames = clip.positions;
    let charts = clip_charts(&sp, frames, case.mesh.length_m);
    let mut data = String::from("frame,s_m,x_m,y_m,z_m,w\n");
    for (f, x) in frames.iter().enumerate() {
        let w = clip.weights(f);
        for (i, p) in x.iter().enumerate() {
            let (k, s) = (f + sp.frame_offset, case.mesh.node_s(i));
            let wi = w.as_ref().map_or(1.0, |w| w[i]);
            let _ = writeln!(data, "{k},{s:e},{:e},{:e},{:e},{wi:e}", p[0], p[1], p[2]);
        }
    }
    let mut bases = String::from("frame,b11,b12,b13,b21,b22,b23,b31,b32,b33,exact_iterations,restarted\n");
    for (f, c) in charts.iter().enumerate() {
        let b = c.base;
        let _ = write!(bases, "{}", f + sp.frame_offset);
        for i in 0..3 {
            for j in 0..3 {
                let _ = write!(bases, ",{:e}", b[(i, j)]);
            }
        }
        let (n, restart) = follow.and_then(|e| e.get(f)).copied().unwrap_or((0, false));
        let _ = writeln!(bases, ",{n},{}", u8::from(restart));
    }
    for (name, text) in [("clip_data.csv", &data), ("clip_charts.csv", &bases)] {
        let path = workdir.join(name);
        std::fs::write(&path, text).map_err(io(&path))?;
    }
    let opts = RunOptions {
        exact_iterations: None,
        clip: Some(ClipInclude {
            frames: frames.len(),
            frame_offset: sp.frame_offset,
            start_data_guess: sp.start == FrameStart::DataGuess,
            min_cos_beta: sp.min_cos_beta,
        }),
    };
    let outputs = ["ff_clip_nodes.csv", "ff_clip_frames.csv", "ff_info.csv"];
    match execute(case, workdir, "clip.edp", &outputs, &opts) {
        Ok(()) | Err(FreeFemError::Failed { status: FAILED_STATUS, .. }) => read_clip_run(case, frames, workdir),
        Err(e) => Err(e),
    }
}

/// What `freefem/clip.edp` left in `workdir` after a run on `frames` (as [`run_clip`] returns it):
/// the frames it solved, its failure message and, for a stalled frame, the Rust engine's error.
pub fn read_clip_run(case: &Case, frames: &[Vec<Vector3<f64>>], workdir: &Path) -> Result<FreeFemFrames, FreeFemError> {
    let sp = case.sequence_params().ok_or_else(|| FreeFemError::NotInverse(case.name.clone()))?;
    let charts = clip_charts(&sp, frames, case.mesh.length_m);
    let frames_out = read_frames(case, sp.frame_offset, frames, &charts, workdir)?;
    let info = FfInfo::read(&workdir.join("ff_info.csv")).ok().unwrap_or_default();
    // the driver's `FAILED: frame K: …` line (its output, `execute`'s log)
    let output = std::fs::read_to_string(workdir.join("freefem_output.txt")).unwrap_or_default();
    let error = output.lines().find(|l| l.starts_with("FAILED")).map(str::to_string);
    let stalled = match info.failed.frame {
        Some(frame) if info.failed.status.and_then(FrameCode::from_info) == Some(FrameCode::Stalled) => {
            let c = info.certificate().unwrap_or(Certificate { value: f64::NAN, blocks: [f64::NAN; 4] });
            let solver = if info.failed.newton == Some(1.0) { "Newton" } else { "fixed point" };
            Some(SolveError::Stalled(Box::new(crate::solve::Stall {
                solver: format!("inverse {solver} of frame {}", frame as usize),
                iterations: info.failed.iterations.unwrap_or(0.0) as usize,
                rel_change: info.failed.rel_change.unwrap_or(f64::NAN),
                certificate: c.value,
                tolerance: case.certificate_tolerance(),
                block: c.worst_block(System::Kkt),
            })))
        }
        _ => None,
    };
    let wall_time_s = info.wall_time_s.unwrap_or_else(|| frames_out.iter().map(|f| f.result.stats.wall_time_s).sum());
    Ok(FreeFemFrames { frames: frames_out, error, stalled, wall_time_s })
}

/// The return code of `solveFrame` (`freefem/inverse_core.idp`) that stopped a clip, its
/// `failed_status` in `ff_info.csv` (`freefem/clip.edp`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum FrameCode {
    Converged = 0,
    IterationLimit = 1,
    /// the message in `failMsg`
    Diverged = 2,
    NonFiniteSolve = 3,
    /// the stopping rule met, the certificate above its tolerance ([`crate::solve::Stop::Stalled`])
    Stalled = 4,
    /// the angle chart's guard (`min_cos_beta`)
    ChartGuard = 5,
}

impl FrameCode {
    /// The code of a `failed_status` value, if it is one.
    fn from_info(value: f64) -> Option<FrameCode> {
        use FrameCode::*;
        [Converged, IterationLimit, Diverged, NonFiniteSolve, Stalled, ChartGuard]
            .into_iter()
            .find(|c| *c as i32 as f64 == value)
    }
}

/// Columns of `ff_clip_frames.csv` (the contract of `freefem/clip.edp`).
fn frame_header() -> Vec<&'static str> {
    let mut h = vec!["frame", "iterations", "rel_change", "x_err_rel", "tangent_misfit"];
    h.extend(ObjectiveTerms::NAMES);
    h.extend(["min_cos_beta", "min_cos_beta_node", "restarted", "wall_time_s", "certificate"]);
    h
}

fn read_frames(
    case: &Case,
    offset: usize,
    frames: &[Vec<Vector3<f64>>],
    charts: &[Chart],
    workdir: &Path,
) -> Result<Vec<SolvedFrame>, FreeFemError> {
    let n = case.mesh.nodes();
    let frames_path = workdir.join("ff_clip_frames.csv");
    let nodes_path = workdir.join("ff_clip_nodes.csv");
    if !frames_path.is_file() {
        return Ok(Vec::new());
    }
    let reports = read_table(&frames_path, &frame_header())?;
    let mut header = vec!["frame", "s_m", "x_m", "y_m", "z_m", "alpha_rad", "beta_rad", "gamma_rad"];
    header.extend(["xhat_1", "xhat_2", "xhat_3", "ahat_1", "ahat_2", "ahat_3"]);
    let rows = read_table(&nodes_path, &header)?;
    if rows.len() < reports.len() * n {
        return Err(FreeFemError::BadOutput {
            path: nodes_path,
            reason: format!("{} rows for {} frames of {n} nodes", rows.len(), reports.len()),
        });
    }
    let v3 = |r: &Vec<f64>, k: usize| Vector3::new(r[k], r[k + 1], r[k + 2]);
    let mut out = Vec::with_capacity(reports.len());
    for (f, rep) in reports.iter().enumerate() {
        let frame = rep[0] as usize;
        let local = frame.checked_sub(offset).filter(|&l| l == f && l < frames.len()).ok_or_else(|| {
            FreeFemError::BadOutput { path: frames_path.clone(), reason: format!("row {}: frame {frame}", f + 1) }
        })?;
        let block = &rows[f * n..(f + 1) * n];
        if block.iter().any(|r| r[0] as usize != frame) {
            return Err(FreeFemError::BadOutput {
                path: nodes_path,
                reason: format!("frame {frame}: node rows out of order"),
            });
        }
        let nodes = NodalState {
            s: block.iter().map(|r| r[1]).collect(),
            x: block.iter().map(|r| v3(r, 2)).collect(),
            alpha: block.iter().map(|r| v3(r, 5)).collect(),
            chart: charts[local],
            reference_x: None,
        };
        let objective = ObjectiveTerms {
            tracking: rep[5],
            force: rep[6],
            torque: rep[7],
            shear: rep[8],
            bending: rep[9],
            angular: rep[10],
        };
        let last = InverseRecord {
            iteration: rep[1] as usize,
            rel_change: rep[2],
            x_err_rel: rep[3],
            tangent_misfit: rep[4],
            objective,
            residual: None,
            // the certificate of the frame's solution (`FrameReport::certificate`)
            certificate: Some(rep[16]),
        };
        let solution = FrameSolution {
            nodes,
            data: &frames[local],
            xhat: block.iter().map(|r| v3(r, 8)).collect(),
            ahat: block.iter().map(|r| v3(r, 11)).collect(),
            last,
            iterations: rep[1] as usize,
            wall_time_s: rep[15],
        };
        let result = frame_result(case, Engine::Freefem, solution);
        out.push(SolvedFrame { frame, restarted: rep[14] != 0.0, result });
    }
    Ok(out)
}
