//! `cosserat run` on a case, under the output-folder contract ([`super::run_folder`]): the run
//! writes into its staging folder, and whatever happens after the folder was claimed — success,
//! a solver failure, a write error, an interrupt — ends in a `run.json` saying so and the folder
//! put in place. A clip keeps its converged frames with figures over exactly them and a resume
//! journal ([`super::journal`]); a single run (forward, one inverse frame) keeps its result
//! only when it has one: on an interrupt nothing but `run.json` (and an inverse case's
//! `data.csv`), on non-convergence the last iterate with `run.json` saying failed.
use std::path::{Path, PathBuf};

use super::data::write_data;
use super::engine::{load_data, run_case, run_clip_to, run_inverse_on, write_clip_figures, ClipOptions};
use super::journal::remove_journal;
use super::run_files::write_run;
use super::run_folder::{input_file, FolderError, Manifest, Mode, RunFolder, Status};
pub use super::sweep::case_label;
use super::sweep::chain;
use crate::case::Case;
use crate::run::clip::ClipRun;
use crate::run::metrics::all_metrics;
use crate::run::{Engine, RunError, RunResult};

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
    /// files in the folder (`run.json` excepted)
    pub files: usize,
    /// what was done around the folder (stale staging folders), for the user
    pub notes: Vec<String>,
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
        let n = run.reports.len();
        let its: Vec<usize> = run.reports.iter().map(|r| r.iterations).collect();
        let worst = run.reports.iter().map(|r| r.x_err_rel).fold(0.0, f64::max);
        let jmax = run.reports.iter().map(|r| r.max_stretch_deviation).fold(0.0, f64::max);
        out += &format!(
            "{name} [rust]: {n} frames in {:.2} s ({:.1} frames/s; solving {:.2} s); iterations per frame min {} / mean {:.1} / max {}; max |x - x_g|/|x_g| {worst:.3e}; max |j - 1| {jmax:.3e}; wrote {}\n",
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

/// The `run.json` of `cosserat run` on `case` in `engine`.
pub fn run_manifest(case: &Case, engine: Engine) -> Result<Manifest, FolderError> {
    let mut m = Manifest::new("run");
    m.case_name = Some(case.name.clone());
    m.case = case.source.as_deref().map(input_file).transpose()?;
    if let Some(c) = case.clip() {
        // a clip's folder counts frames from the start (what makes it resumable)
        m.frames_done = Some(0);
        if c.file.is_file() {
            m.inputs.push(input_file(&c.file)?);
        }
    }
    m.engine = Some(engine.to_string());
    Ok(m)
}

/// Run `case` in `engine` into the folder `out` ([`Mode`]: fresh, or resuming a clip).
/// `Err`: the folder could not be claimed (nothing written); otherwise the folder holds the
/// run, whatever its end.
pub fn run_into(
    case: &Case,
    engine: Engine,
    out: &Path,
    mode: Mode,
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
    };
    if case.clip().is_some() {
        clip_job(case, engine, &dir, mode == Mode::Resume, progress, &mut end);
        folder.manifest.frames_done = end.frames.map(|f| f.0);
        folder.manifest.frames_total = end.frames.map(|f| f.1);
    } else {
        single_job(case, engine, &dir, progress, &mut end);
    }
    let target = folder.finish(end.status, end.message.clone())?;
    end.files = Manifest::read(&target)?.map(|m| m.files.len()).unwrap_or(0);
    Ok(end)
}

fn status_of(e: &RunError) -> Status {
    if e.is_interrupted() {
        Status::Interrupted
    } else {
        Status::Failed
    }
}

fn single_job(case: &Case, engine: Engine, dir: &Path, progress: impl FnMut(usize, usize), end: &mut JobEnd) {
    let work = dir.join("freefem_work");
    let result = if case.inverse().is_some() {
        let path = dir.join("data.csv");
        load_data(case)
            .and_then(|d| Ok(write_data(&path, &d)?))
            .and_then(|_| run_inverse_on(case, engine, &path, &work, progress))
    } else {
        run_case(case, engine, &work, progress)
    };
    let (r, failure) = match result {
        Ok(r) => (r, None),
        Err(super::engine::EngineError::Run(RunError::Incomplete { source, partial })) => {
            (*partial, Some(format!("{}: {source}; the files here hold the last iterate", case_label(case))))
        }
        Err(e) => {
            let interrupted = match &e {
                super::engine::EngineError::Run(r) => r.is_interrupted(),
                super::engine::EngineError::FreeFem(f) => f.is_interrupted(),
                _ => false,
            };
            end.status = if interrupted { Status::Interrupted } else { Status::Failed };
            end.message = Some(format!("{}: {}", case_label(case), chain(&e)));
            return;
        }
    };
    let written = all_metrics(case, &r).map_err(|e| chain(&e)).and_then(|m| {
        write_run(case, &r, &m, dir).map_err(|e| chain(&e))?;
        Ok(())
    });
    if let Err(e) = written {
        end.status = Status::Failed;
        end.message = Some(format!("{}: {e}", case_label(case)));
        return;
    }
    if let Some(f) = failure {
        end.status = Status::Failed;
        end.message = Some(f);
    }
    end.single = Some(r);
}

fn clip_job(
    case: &Case,
    engine: Engine,
    dir: &Path,
    resume: bool,
    progress: impl FnMut(usize, usize),
    end: &mut JobEnd,
) {
    if engine != Engine::Rust {
        end.status = Status::Failed;
        end.message = Some(format!(
            "{}: `run` solves clips in the Rust engine (`--engine rust`); to run a clip in FreeFEM against it, use `cosserat compare CASE --frames N` (or `--frames all`)",
            case_label(case)
        ));
        return;
    }
    let out = match run_clip_to(case, dir, ClipOptions { journal: true, resume }, |_| {}, progress) {
        Ok(out) => out,
        Err(e) => {
            end.status = Status::Failed;
            end.message = Some(format!("{}: {}", case_label(case), chain(&e)));
            return;
        }
    };
    let (done, total) = (out.run.reports.len(), out.total);
    if let Some(e) = &out.stopped {
        end.status = status_of(e);
        end.message = Some(format!("{}: {}", case_label(case), chain(e)));
    }
    if done > 0 {
        if let Err(e) = write_clip_figures(case, &out.run, dir) {
            end.status = Status::Failed;
            end.message = Some(format!("{}: {}", case_label(case), chain(&e)));
        }
    }
    if end.status == Status::Complete {
        if let Err(e) = remove_journal(dir) {
            end.status = Status::Failed;
            end.message = Some(chain(&e));
        }
    }
    end.frames = Some((done, total));
    end.clip = Some(out.run);
}
