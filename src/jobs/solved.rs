//! One run of a case into a folder, the core shared by `cosserat run` ([`super::job`]), the
//! points of a sweep or an audit ([`super::sweep`]) and a batch of recordings: a forward or
//! single-frame inverse run writes its files (the last iterate's too, when it stops at its
//! iteration limit), a clip streams its frames and then its figures over the frames solved.
//! The caller owns the folder and its `run.json` ([`crate::output::run_folder`]).
use std::path::Path;

use crate::case::Case;
use crate::clip::missing::MIN_TRACKED;
use crate::engine::clip::{ClipFrame, ClipRun};
use crate::engine::clip_metrics::clip_metrics;
use crate::engine::metrics::{all_metrics, Metric, Metrics};
use crate::engine::{run_case, run_inverse_on, stage_data, EngineError};
use crate::engine::{Engine, RunError, RunResult};
use crate::jobs::clip_run::{run_clip_to, ClipOptions};
use crate::output::clip_figures::write_clip_figures;
use crate::output::clip_output::remove_raw;
use crate::output::journal::remove_journal;
use crate::output::manifest::{FrameDataNote, PlanarNote, RecordingNotes};
use crate::output::run_files::write_run;
use crate::output::run_folder::CertificateSummary;
use crate::solve::sequence::FrameReport;
use crate::solve::{Outcome, SolveError};

/// What one run left in its folder.
pub struct Solved {
    pub status: Outcome,
    /// why it failed or stopped (the error and its causes, prefixed by the case)
    pub error: Option<String>,
    /// the metrics of a single run (also of the last iterate of one that did not converge) or
    /// of a complete clip (`engine::clip_metrics`)
    pub metrics: Option<Metrics>,
    /// a single run's result
    pub single: Option<RunResult>,
    /// a clip's summary over the frames it holds
    pub clip: Option<ClipRun>,
    /// clips: frames in the folder and frames of the clip
    pub frames: Option<(usize, usize)>,
    /// it stopped because the disk (or quota) was full (`crate::io::disk`)
    pub disk_full: bool,
}

impl Solved {
    /// The residual certificate of the result for `run.json` (`docs/certificate.md`): the
    /// `certificate` metric (a clip's: the largest of its frames) against the case's tolerance.
    pub fn certificate(&self, case: &Case) -> Option<CertificateSummary> {
        let value = match (&self.metrics, &self.single, &self.clip) {
            (Some(m), _, _) if m.contains(Metric::Certificate) => m.get(Metric::Certificate)?,
            (_, Some(r), _) => r.stats.certificate?,
            (_, _, Some(c)) if !c.reports.is_empty() => c.reports.iter().map(|r| r.certificate).fold(0.0, f64::max),
            _ => return None,
        };
        let flagged_frames = self.clip.as_ref().map(|c| c.reports.iter().filter(|r| r.fit.flagged).count());
        Some(CertificateSummary { value, tolerance: case.certificate_tolerance(), flagged_frames })
    }

    /// What the case's recording said of itself and of the frames solved, for `run.json`.
    pub fn recording_notes(&self, case: &Case) -> RecordingNotes {
        let frame_data = self.clip.as_ref().filter(|c| !c.reports.is_empty()).map(|c| {
            let nodes = case.mesh.nodes();
            let reports = &c.reports;
            FrameDataNote {
                lost: reports.iter().filter(|r| r.nodes_tracked < MIN_TRACKED).map(|r| r.frame).collect(),
                filled: reports.iter().filter(|r| (MIN_TRACKED..nodes).contains(&r.nodes_tracked)).count(),
                resolved: reports.iter().filter(|r| r.fit.resolved).map(|r| r.frame).collect(),
            }
        });
        RecordingNotes {
            body_length: case.body_length(),
            planar: case.clip().and_then(|c| c.recording.data_plane).map(|n| PlanarNote::new(&n)),
            frame_data,
        }
    }

    /// A run that produced nothing, with its error.
    pub fn failed(error: String) -> Self {
        Solved {
            status: Outcome::Failed,
            error: Some(error),
            metrics: None,
            single: None,
            clip: None,
            frames: None,
            disk_full: false,
        }
    }

    /// A run that produced nothing, with its error `e` described as `error`.
    fn failed_by(error: String, e: &(dyn std::error::Error + 'static)) -> Self {
        Solved { disk_full: crate::io::disk::is_full(e), ..Solved::failed(error) }
    }

    /// A run stopped (or not started) by a signal.
    pub fn interrupted() -> Self {
        Solved { status: Outcome::Interrupted, ..Solved::failed("interrupted by a signal".into()) }
    }
}

/// Run `case` in `engine` into the folder `dir` (which the caller has claimed). A clip runs in
/// the Rust engine only, with `clip` (journal, resume); its frames are shown to `observer`.
/// `progress(done, total)` follows iterations, time steps or frames.
pub fn solve_into(
    case: &Case,
    engine: Engine,
    dir: &Path,
    clip: ClipOptions,
    observer: impl FnMut(&ClipFrame) + Send,
    progress: impl FnMut(usize, usize),
) -> Solved {
    if crate::interrupt::requested() {
        return Solved::interrupted();
    }
    if case.clip().is_some() {
        solve_clip(case, engine, dir, clip, observer, progress)
    } else {
        solve_single(case, engine, dir, progress)
    }
}

fn solve_single(case: &Case, engine: Engine, dir: &Path, progress: impl FnMut(usize, usize)) -> Solved {
    if let Some(why) = unsupported(case, engine) {
        return Solved::failed(why);
    }
    let work = dir.join("freefem_work");
    let result = if case.inverse().is_some() {
        let path = dir.join("data.csv");
        match stage_data(case, &path) {
            Ok(()) => run_inverse_on(case, engine, &path, &work, progress),
            Err(e) => {
                let status = if interrupted(&e) { Outcome::Interrupted } else { Outcome::Failed };
                let error = format!("{}: generating the data: {}", case_label(case), chain(&e));
                return Solved { status, ..Solved::failed_by(error, &e) };
            }
        }
    } else {
        run_case(case, engine, &work, progress)
    };
    let (status, r, error) = match result {
        Ok(r) => (Outcome::Converged, r, None),
        Err(EngineError::Run(RunError::Incomplete { source, partial })) => (
            if matches!(source, SolveError::Stalled(_)) { Outcome::Stalled } else { Outcome::IterationLimit },
            *partial,
            Some(format!("{}: {source}; the files here hold the last iterate", case_label(case))),
        ),
        Err(e) => {
            let status = if interrupted(&e) { Outcome::Interrupted } else { Outcome::Failed };
            return Solved { status, ..Solved::failed_by(format!("{}: {}", case_label(case), chain(&e)), &e) };
        }
    };
    let m = match all_metrics(case, &r) {
        Ok(m) => m,
        Err(e) => return Solved::failed(format!("{}: {}", case_label(case), chain(&e))),
    };
    let (status, error) = match unstable_message(case, &m) {
        Some(message) if status == Outcome::Converged => (Outcome::CompleteWithWarnings, Some(message)),
        _ => (status, error),
    };
    match write_run(case, &r, &m, dir) {
        Ok(_) => {
            Solved { status, error, metrics: Some(m), single: Some(r), clip: None, frames: None, disk_full: false }
        }
        Err(e) => Solved::failed_by(format!("{}: {}", case_label(case), chain(&e)), &e),
    }
}

/// The warning of a static result that is not stable (D27): the smallest eigenvalue `μ` of its
/// tangent against the unloaded rod's is not positive.
fn unstable_message(case: &Case, m: &Metrics) -> Option<String> {
    let w2 = m.get(Metric::TangentSmallestEigenvalue)?;
    (m.get(Metric::Stable) == Some(0.0)).then(|| {
        format!(
            "{}: UNSTABLE: the static state returned is not stable: the rod linearised about it has omega^2 = {w2:.4e} 1/s^2 < 0 (the smallest eigenvalue of its tangent against its mass, D27): the loads exceed a critical load and the rod would leave this state; follow the path with solver.continuation = \"arc_length\" (and an imperfection) for the buckled one",
            case_label(case)
        )
    })
}

/// Did the engine stop because a stop was requested (`crate::interrupt`)?
fn interrupted(e: &EngineError) -> bool {
    match e {
        EngineError::Run(r) => r.is_interrupted(),
        EngineError::FreeFem(f) => f.is_interrupted(),
        _ => false,
    }
}

fn solve_clip(
    case: &Case,
    engine: Engine,
    dir: &Path,
    opts: ClipOptions,
    observer: impl FnMut(&ClipFrame) + Send,
    progress: impl FnMut(usize, usize),
) -> Solved {
    let fail =
        |e: &(dyn std::error::Error + 'static)| Solved::failed_by(format!("{}: {}", case_label(case), chain(e)), e);
    if let Some(why) = unsupported(case, engine) {
        return Solved::failed(why);
    }
    let out = match run_clip_to(case, dir, opts, observer, progress) {
        Ok(out) => out,
        Err(e) => return fail(&e),
    };
    let (done, total) = (out.run.reports.len(), out.total);
    let flagged: Vec<&FrameReport> = out.run.reports.iter().filter(|r| r.fit.flagged).collect();
    let mut disk_full = out.stopped.as_ref().is_some_and(|e| crate::io::disk::is_full(e));
    let (mut status, mut error) = match &out.stopped {
        None if !flagged.is_empty() => (Outcome::CompleteWithWarnings, Some(flag_message(case, &flagged, done))),
        None => (Outcome::Converged, None),
        Some(e) if e.is_interrupted() => (Outcome::Interrupted, Some(format!("{}: {}", case_label(case), chain(e)))),
        // where its converged frames are (the output folder, a staging folder beside it, or
        // nowhere) is the caller's to say: it decides which
        Some(e) => (Outcome::Failed, Some(format!("{}: {}", case_label(case), chain(e)))),
    };
    // A clip whose figures cannot be written keeps its frames (and says so).
    let figures = if done > 0 { write_clip_figures(case, &out.run, dir) } else { Ok(()) };
    if let Err(e) = figures {
        disk_full |= crate::io::disk::is_full(&e);
        error = Some(match error {
            Some(m) => format!("{m}; then {}", chain(&e)),
            None => format!("{}: {}", case_label(case), chain(&e)),
        });
        status = Outcome::Failed;
    }
    if status.is_complete() && opts.journal {
        if let Err(e) = remove_journal(dir).and_then(|_| remove_raw(dir)) {
            return Solved::failed_by(chain(&e), &e);
        }
    }
    let metrics = status.is_complete().then(|| clip_metrics(case, &out.run));
    Solved { status, error, metrics, single: None, clip: Some(out.run), frames: Some((done, total)), disk_full }
}

/// The message of a clip whose frames `flagged` (of `done`) are over the fit-quality gate.
fn flag_message(case: &Case, flagged: &[&FrameReport], done: usize) -> String {
    let first = flagged[0];
    let (h, length) = (case.mesh.h(), case.mesh.length_m);
    let gate = case.clip().map(|c| c.gate).unwrap_or_default();
    format!(
        "{}: {} of {done} frames are over the fit-quality gate (`flagged` in frames.csv; docs/certificate.md C5): each is certified, but does not follow its data. The first is frame {}: {}",
        case_label(case),
        flagged.len(),
        first.frame,
        first.fit.reason(&gate, length, h)
    )
}

/// The case's name and file, for messages.
/// Why `engine` cannot solve `case` into a folder, if it cannot: a published value the run
/// cannot compute (`engine::published::unavailable`), a clip in FreeFEM (`run` solves
/// clips in the Rust engine; `compare` runs FreeFEM's clip script frame by frame against it). A
/// command checks this before it prepares any folder.
pub fn unsupported(case: &Case, engine: Engine) -> Option<String> {
    if let Some(why) = crate::engine::published::unavailable(case) {
        return Some(why);
    }
    (engine != Engine::Rust && case.clip().is_some()).then(|| {
        format!(
            "{}: `run` solves clips in the Rust engine (`--engine rust`); to run a clip in FreeFEM against it, use `cosserat compare CASE --frames N` (or `--frames all`)",
            case_label(case)
        )
    })
}

pub fn case_label(case: &Case) -> String {
    match &case.origin.source {
        Some(p) => format!("case {} ({})", case.name, p.display()),
        None => format!("case {}", case.name),
    }
}

/// An error and its causes, `: `-separated.
pub fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut src = e.source();
    while let Some(c) = src {
        s += &format!(": {c}");
        src = c.source();
    }
    s
}
