//! `cosserat run` on a case, under the output-folder contract ([`crate::output::run_folder`]): the run
//! writes into its staging folder, and whatever happens after the folder was claimed — success,
//! a solver failure, a write error, an interrupt — ends in a `run.json` saying so and the folder
//! put in place. A clip keeps its converged frames with figures over exactly them and a resume
//! journal ([`crate::output::journal`]); a single run (forward, one inverse frame) keeps its result
//! only when it has one: on an interrupt nothing but `run.json` (and an inverse case's
//! `data.csv`), on non-convergence the last iterate with `run.json` saying failed.
use std::path::{Path, PathBuf};

pub use super::solved::case_label;
use super::solved::solve_into;
use crate::case::Case;
use crate::engine::clip::{ClipFrame, ClipRun};
use crate::engine::{Engine, RunResult};
use crate::io::compact::OutputFormat;
use crate::jobs::clip_run::ClipOptions;
use crate::output::run_folder::{
    input_file_as, Beside, FolderError, InputFile, Manifest, Mode, Placed, RunFolder, Status,
};

/// How a run ended.
#[derive(Debug)]
pub struct JobEnd {
    pub status: Status,
    /// the output folder
    pub dir: PathBuf,
    /// why it failed or stopped (the error and its causes)
    pub message: Option<String>,
    /// a single run's result (also the last iterate of one that did not converge)
    pub single: Option<RunResult>,
    /// a clip's summary over the frames it holds
    pub clip: Option<ClipRun>,
    /// clips: frames written and frames of the clip
    pub frames: Option<(usize, usize)>,
    /// files in the folder, `run.json` included
    pub files: usize,
    /// what was done around the folder (stale staging folders), for the user
    pub notes: Vec<String>,
    /// a run stopped by a full disk: the output folder is the previous one, and this staging
    /// folder keeps the converged frames of a clip for `--resume` (`None`: nothing was kept)
    pub disk_full: Option<Option<PathBuf>>,
    /// a run that failed or was interrupted into a folder holding a complete run: that folder
    /// is left as it was, and this run is kept beside it (or removed) as this says
    pub beside: Option<Placed>,
}

impl JobEnd {
    /// The summary of a complete run for the terminal: the tip and iterations of a single
    /// run; frames, iterations, fit (and ground-truth errors) of a clip.
    pub fn summary(&self, name: &str, engine: Engine) -> String {
        let mut out = String::new();
        if let Some(r) = &self.single {
            let tip = r.nodes.x.last().copied().unwrap_or_default();
            out += &format!(
                "{name} [{engine}]: tip = ({:.6e}, {:.6e}, {:.6e}) m, {} iterations, {:.3} s; wrote {} files to {}\n",
                tip[0],
                tip[1],
                tip[2],
                r.stats.iterations,
                r.stats.wall_time_s,
                self.files,
                self.dir.display()
            );
        }
        let Some(run) = &self.clip else { return out };
        if let Some(t) = &run.truth {
            let max = |f: &dyn Fn(&crate::clip::synthetic::FrameComparison) -> f64| {
                t.comparisons.iter().map(f).fold(0.0, f64::max)
            };
            out += &format!(
                "{name} ground truth (all frames, max): |x - x_true|/|x_true| {:.2e}; bending k1^2+k2^2 rel. L2 {:.2e}; angle(d3, true d3) {:.2e} rad; |roll offset| {:.3} rad; kappa_3 rms error {:.1} rad/m (true twist {:.1} rad/m); see truth.csv, truth.svg, truth_errors.svg\n",
                max(&|c| c.position_rel_l2),
                max(&|c| c.bending_rel_l2),
                max(&|c| c.max_tangent_angle_rad),
                max(&|c| c.roll_offset_rad.abs()),
                max(&|c| c.twist_rms_error_per_m),
                t.twist_per_m.first().copied().unwrap_or(0.0)
            );
        }
        if let Some(w) = &run.weights {
            out += &format!(
                "{name} weights = \"auto\": noise level {:.3e} m per coordinate (median over the frames); lambda_g = {:.3e} (at most {:.1e}): the fit's RMS distance to the data {:.3e} m on the first {} frames ({} calibration solves); stabilisation {:.3e} (docs/noise.md)\n",
                w.noise_m, w.lambda_g, w.lambda_g_max, w.fit_residual_m, w.calibration_frames, w.solves, w.stabilisation
            );
        }
        let n = run.reports.len();
        let its: Vec<usize> = run.reports.iter().map(|r| r.convergence.iterations).collect();
        // in body lengths (solve::fit): ‖x − x_g‖/‖x_g‖ would depend on where the clip sits
        let worst = run.reports.iter().map(|r| r.fit.position).fold(0.0, f64::max);
        let jmax = run.reports.iter().map(|r| r.conditioning.max_stretch_deviation).fold(0.0, f64::max);
        out += &format!(
            "{name} [rust]: {n} frames in {:.2} s ({:.1} frames/s; solving {:.2} s); iterations per frame min {} / mean {:.1} / max {}; max position misfit {worst:.3e} body lengths; max |j - 1| {jmax:.3e}; wrote {}\n",
            run.wall_time_s,
            n as f64 / run.wall_time_s,
            run.reports.iter().map(|r| r.wall_time_s).sum::<f64>(),
            its.iter().min().copied().unwrap_or(0),
            its.iter().sum::<usize>() as f64 / n.max(1) as f64,
            its.iter().max().copied().unwrap_or(0),
            self.dir.display()
        );
        out
    }
}

/// A run stopped by a full disk leaves the output folder `out` as it was: the converged frames
/// of a clip stay in its staging folder, which `--resume` continues once there is space; a
/// run with nothing to keep removes it (and so frees its space).
fn stopped_by_full_disk(folder: RunFolder, mut end: JobEnd, out: &Path) -> JobEnd {
    end.status = Status::Failed;
    end.message = Some(format!("{}: {}", crate::io::disk::full_text(out), end.message.unwrap_or_default()));
    end.disk_full = Some(match end.frames {
        Some((n, _)) if n > 0 => Some(folder.keep_staging(Status::Failed, end.message.clone())),
        _ => {
            folder.abandon();
            None
        }
    });
    end
}

/// The `run.json` of `cosserat run` on `case` in `engine`.
pub fn run_manifest(case: &Case, engine: Engine) -> Result<Manifest, FolderError> {
    let mut m = Manifest::new("run");
    m.input.case_name = Some(case.name.clone());
    m.input.case = case_file(case)?;
    m.input.inputs = case_inputs(case)?;
    if case.clip().is_some() {
        // a clip's folder counts frames from the start (what makes it resumable)
        m.frames.frames_done = Some(0);
    }
    m.input.engine = Some(engine.to_string());
    m.recording.body_length = case.body_length();
    Ok(m)
}

/// The case file with the SHA-256 of the bytes that were read (also of a case piped in through
/// standard input), or hashed now for a case that was not read from a file by `Case::from_file`.
pub fn case_file(case: &Case) -> Result<Option<InputFile>, FolderError> {
    let Some(path) = &case.origin.source else { return Ok(None) };
    Ok(Some(match &case.origin.source_sha256 {
        Some(sha256) => InputFile { path: path.display().to_string(), sha256: sha256.clone() },
        None => input_file_as(path, "case file")?,
    }))
}

/// The files a case reads besides its case file, with their SHA-256: a clip's file (the
/// recording, or the kymogram of a kymogram or `roll_3d` clip) and a recording's ground-truth
/// sidecar. A file that is there but is not a regular file (a pipe, a device, a folder) is
/// refused here, before any folder is claimed; a missing one is left to the run, whose error
/// names it.
pub fn case_inputs(case: &Case) -> Result<Vec<InputFile>, FolderError> {
    let mut inputs = Vec::new();
    let Some(c) = case.clip() else { return Ok(inputs) };
    if std::fs::metadata(&c.file).is_ok() {
        inputs.push(input_file_as(&c.file, "clip file")?);
        let sidecar = crate::engine::input::truth_file::truth_sidecar(&c.file);
        if c.kind == crate::case::ClipKind::Recording && sidecar.is_file() {
            inputs.push(input_file_as(&sidecar, "ground-truth sidecar")?);
        }
    }
    Ok(inputs)
}

/// Run `case` in `engine` into the folder `out` ([`Mode`]: fresh, or resuming a clip; a clip's
/// per-node fields in `format`). `Err`: the folder could not be claimed (nothing written);
/// otherwise the folder holds the run, whatever its end.
pub fn run_into(
    case: &Case,
    engine: Engine,
    out: &Path,
    mode: (Mode, OutputFormat),
    progress: impl FnMut(usize, usize),
) -> Result<JobEnd, FolderError> {
    run_into_observed(case, engine, out, mode, |_| {}, progress)
}

/// [`run_into`], with each frame of a clip shown to `observer` once it is written (what a
/// caller that keeps the frames in memory as well, the Python package, collects).
pub fn run_into_observed(
    case: &Case,
    engine: Engine,
    out: &Path,
    (mode, format): (Mode, OutputFormat),
    observer: impl FnMut(&ClipFrame) + Send,
    progress: impl FnMut(usize, usize),
) -> Result<JobEnd, FolderError> {
    let mut folder = RunFolder::begin(out, run_manifest(case, engine)?, mode)?;
    let dir = folder.dir().to_path_buf();
    let mut end = JobEnd {
        status: Status::Complete,
        dir: out.to_path_buf(),
        message: None,
        single: None,
        clip: None,
        frames: None,
        files: 0,
        notes: std::mem::take(&mut folder.notes),
        disk_full: None,
        beside: None,
    };
    if case.clip().is_some_and(|c| c.recording.data_plane.is_some()) {
        end.notes.push(format!(
            "{}: a planar recording: its twist is {} (run.json: planar)",
            case.name,
            crate::output::manifest::PLANAR_TWIST
        ));
    }
    let clip = ClipOptions { journal: true, resume: mode == Mode::Resume, format };
    let solved = solve_into(case, engine, &dir, clip, observer, progress);
    folder.manifest.certificate = solved.certificate(case);
    folder.manifest.recording = solved.recording_notes(case);
    end.status = solved.status.into();
    end.message = solved.error;
    end.single = solved.single;
    end.clip = solved.clip;
    folder.manifest.weights = end.clip.as_ref().and_then(|c| c.weights);
    end.frames = solved.frames;
    folder.manifest.frames.frames_done = end.frames.map(|f| f.0);
    folder.manifest.frames.frames_total = end.frames.map(|f| f.1);
    if solved.disk_full {
        return Ok(stopped_by_full_disk(folder, end, out));
    }
    // a clip keeps its converged frames for --resume; a single run's run.json alone is nothing
    let beside = if end.frames.is_some_and(|(n, _)| n > 0) { Beside::Kept } else { Beside::Removed };
    match folder.finish_keeping(end.status, end.message.clone(), beside)? {
        Placed::InPlace(target) => {
            // the manifest lists every file but itself
            end.files = Manifest::read(&target)?.map(|m| m.files.len() + 1).unwrap_or(0);
        }
        beside => end.beside = Some(beside),
    }
    Ok(end)
}
