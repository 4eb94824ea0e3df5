//! A clip case frame by frame in the Rust engine (`solve::sequence`), every converged frame
//! handed to a second thread while the next frame is solved: there it is derived into a
//! [`ClipFrame`] (curvature, truth comparison, summary) and given to a [`FrameSink`] (which
//! `crate::output::clip_output::ClipWriter` implements with the streamed files). The frames themselves may arrive while the
//! clip is solved ([`ClipFrames::Streamed`]).
use std::sync::mpsc::{Receiver, SyncSender};
use std::time::Instant;

use nalgebra::{DVector, Vector3};

use super::clip_frame::{frame_data, ClipFrameError, Converged, Deriver};
pub use super::clip_frame::{
    nodal_curvature, planar_xz_curvature, sign_alternation, ClipFrame, Controls, FrameRecord, PlanarCurvature,
    TruthFrame, TRUTH_SKIP_NODES,
};
use super::RunError;
use crate::case::Case;
use crate::clip::synthetic::{FrameComparison, FrameTruth, GroundTruth};
use crate::clip::Clip;
use crate::model::rotation::Angles;
use crate::solve::inverse::Records;
use crate::solve::sequence::{
    solve_sequence_from, vector_to_space, ClipData, FirstStart, FrameReport, ResumeFrom, SequenceError, SequenceParams,
};
use crate::solve::{Problem, SolveError};

/// Where the frames of a clip go (`crate::engine::input::clip_files::ClipWriter` streams them to disk).
/// Called from a second thread, in frame order.
pub trait FrameSink: Send {
    type Error: std::error::Error + Send + Sync + 'static;
    /// One converged frame.
    fn frame(&mut self, frame: &ClipFrame) -> Result<(), Self::Error>;
    /// After the last frame handed over (also when the clip stopped early).
    fn finish(&mut self) -> Result<(), Self::Error>;
}

/// Summary of a clip run.
#[derive(Clone, Debug)]
pub struct ClipRun {
    pub reports: Vec<FrameReport>,
    /// per frame: sign alternation of the recovered κ2 and of the data's planar curvature
    /// ([`sign_alternation`])
    pub roughness: Vec<(f64, f64)>,
    /// per frame: recovered κ2 at element midpoints and the data's planar curvature at the
    /// interior nodes [1/m] (x–z clips: the bending curvature; [`planar_xz_curvature`])
    pub kappa2: Vec<Vec<f64>>,
    pub data_kappa: Vec<Vec<f64>>,
    /// per frame: the angular velocity ωˡ per node [rad/s] ([`ClipFrame::omega`]); zeros on the
    /// first frame
    pub omega: Vec<Vec<Vector3<f64>>>,
    /// synthetic clips: per frame the errors against the ground truth (end nodes skipped:
    /// [`TRUTH_SKIP_NODES`]), and the true and recovered bending `κ1² + κ2²` [1/m²] per node
    pub truth: Option<TruthRun>,
    pub wall_time_s: f64,
    pub source: String,
    /// the weights `[inverse] weights = "auto"` chose (`super::weights`)
    pub weights: Option<super::weights::ChosenWeights>,
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

/// How a clip run ended: its summary over the frames it solved (all of them, or those before
/// it stopped) and, if it stopped early, why (a frame's error, a write error, or an interrupt:
/// [`RunError::is_interrupted`]).
#[derive(Debug)]
pub struct ClipOutcome {
    pub run: ClipRun,
    pub stopped: Option<RunError>,
    /// frames of the clip
    pub total: usize,
}

/// One frame of a streamed clip ([`ClipFrames::Streamed`]): its node positions [m] and, for a
/// synthetic clip, its ground truth.
pub type StreamedFrame = (Vec<Vector3<f64>>, Option<FrameTruth>);

/// The frames of a clip as [`run_clip`] takes them.
pub enum ClipFrames<'a> {
    /// every frame at hand: the clip and, for a synthetic clip, its ground truth frame for frame
    /// `start`: frame 0's initial iterate in its chart (`None`: the data guess)
    Loaded { clip: &'a Clip, truth: Option<&'a GroundTruth>, start: Option<&'a DVector<f64>> },
    /// `total` frames arriving in order on `frames` (each with its ground truth where `truth`),
    /// e.g. from a generator on another thread: the solve starts with the first frame while
    /// later ones are made. `header`: the clip without its frames (time step, source).
    Streamed { header: Clip, total: usize, truth: bool, frames: Receiver<StreamedFrame> },
}

/// The frames of a [`ClipFrames`] received so far.
struct Arrivals<'a> {
    input: ClipFrames<'a>,
    frames: Vec<Vec<Vector3<f64>>>,
    truth: Vec<FrameTruth>,
}

impl Arrivals<'_> {
    /// The clip (without its frames if streamed), its frame count and whether it has a truth.
    fn header(&self) -> (&Clip, usize, bool) {
        match &self.input {
            ClipFrames::Loaded { clip, truth, .. } => (clip, clip.frame_count(), truth.is_some()),
            ClipFrames::Streamed { header, total, truth, .. } => (header, *total, *truth),
        }
    }

    /// Wait until at least `n` frames are at hand, take every frame that has arrived, and
    /// return how many are at hand.
    fn wait(&mut self, n: usize) -> Result<usize, RunError> {
        let (rx, total) = match &self.input {
            ClipFrames::Loaded { clip, .. } => return Ok(clip.frame_count()),
            ClipFrames::Streamed { frames, total, .. } => (frames, *total),
        };
        while self.frames.len() < n.min(total) {
            let (x, t) = rx.recv().map_err(|_| RunError::Generator { received: self.frames.len(), total })?;
            self.frames.push(x);
            self.truth.extend(t);
        }
        while let Ok((x, t)) = rx.try_recv() {
            self.frames.push(x);
            self.truth.extend(t);
        }
        Ok(self.frames.len())
    }

    /// Which nodes of each frame were tracked (`clip::missing`; `None`: all of them).
    fn tracked(&self) -> Option<&[Vec<bool>]> {
        match &self.input {
            ClipFrames::Loaded { clip, .. } => clip.tracked.as_deref(),
            ClipFrames::Streamed { .. } => None,
        }
    }

    /// The frames at hand and their ground truth.
    fn frames(&self) -> (&[Vec<Vector3<f64>>], Option<&[FrameTruth]>) {
        match &self.input {
            ClipFrames::Loaded { clip, truth, .. } => (&clip.frames, truth.map(|t| &t.frames[..])),
            ClipFrames::Streamed { truth, .. } => (&self.frames, truth.then_some(&self.truth[..])),
        }
    }
}

/// Solve the clip of a clip case frame by frame in the Rust engine, handing every converged
/// frame to `sink` (on a second thread, while the next frame is solved); `frames`: the clip's
/// frames (and the ground truth of a synthetic clip), at hand or streamed. `resume`: the records
/// of the frames `0..n` of an earlier run of the same case ([`FrameRecord`]; empty: from the
/// first frame); they are not handed to the sink again, the summary covers them. On failure or
/// interrupt the sink has every converged frame and the outcome says why it stopped; a sink
/// error stops the clip at the next frame and is reported in its place. A streamed clip is
/// solved in runs of the frames at hand, each resumed from the last two states
/// ([`ResumeFrom`]): bit for bit the frames of one solve.
pub fn run_clip<S: FrameSink>(
    case: &Case,
    frames: ClipFrames<'_>,
    resume: &[FrameRecord],
    sink: S,
    mut progress: impl FnMut(usize, usize),
) -> Result<ClipOutcome, RunError> {
    let sp = case.sequence_params().ok_or_else(|| RunError::Kind { case: case.name.clone(), what: "a clip case" })?;
    // a clip keeps each frame's report, not its iteration history
    let sp = SequenceParams { records: Records::Last, ..sp };
    let problem = case.problem();
    // frame 0's initial iterate, for the first run of frames only
    let frame0_start = match &frames {
        ClipFrames::Loaded { start, .. } => start.cloned(),
        ClipFrames::Streamed { .. } => None,
    };
    let mut arrivals = Arrivals { input: frames, frames: Vec::new(), truth: Vec::new() };
    let (header, total, has_truth) = arrivals.header();
    let (dt_s, source) = (header.dt_s, header.source.clone());
    let deriver = Deriver {
        case,
        dofs: problem.dofs(),
        weights: sp.inverse.weights,
        h: case.mesh.h(),
        dt: sp.inverse.frame_interval_s,
        dt_s,
    };
    let start = Instant::now();
    let mut summary = Summary::new(has_truth);
    resume_summary(&deriver, &mut arrivals, resume, sp.frame_offset, &mut summary)?;
    // room for about 0.1 s of frames: the output thread falls behind while a streamed clip's
    // generator shares its core (the first 0.25 s of worm_roll_3d), and catches up after
    let (tx, rx) = std::sync::mpsc::sync_channel::<Converged>(64);
    let (result, (summary, written)) = std::thread::scope(|scope| {
        let deriver = &deriver;
        // The output thread: each frame derived, summarised and handed to the sink.
        let io = scope.spawn(move || {
            let written = write_frames(deriver, rx, sink, &mut summary);
            (summary, written)
        });
        let runs = Runs { problem: &problem, sp: &sp, total };
        let result = runs.solve(&mut arrivals, frame0_start, resume, tx, &mut progress);
        let written = io.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        (result, written)
    });
    // A write error explains a stopped clip better than the stop itself.
    let stopped = match (written, result) {
        (Err(OutputStop::Sink(e)), _) => Some(RunError::Sink(Box::new(e))),
        (Err(OutputStop::Derive { frame, error }), _) => {
            Some(RunError::Sequence(SequenceError::Callback { frame, stop: Box::new(error) }))
        }
        (Ok(()), Err(e)) => Some(e),
        (Ok(()), Ok(())) => None,
    };
    let run = summary.finish(start.elapsed().as_secs_f64(), source);
    let stopped = stopped.map(|e| with_degradation(e, &run.reports));
    Ok(ClipOutcome { run, stopped, total })
}

/// The frames of an earlier run (`resume`): checked against the case and summarised again
/// from their records.
fn resume_summary(
    deriver: &Deriver,
    arrivals: &mut Arrivals<'_>,
    resume: &[FrameRecord],
    first_frame: usize,
    summary: &mut Summary,
) -> Result<(), RunError> {
    arrivals.wait(resume.len())?;
    let unknowns = deriver.dofs.len();
    for (i, r) in resume.iter().enumerate() {
        if r.report.frame != first_frame + i || r.state.len() != unknowns || r.adjoint.len() != unknowns {
            return Err(RunError::Resume(ResumeError::Record {
                index: i,
                frame: r.report.frame,
                unknowns: r.state.len(),
                expected_frame: first_frame + i,
                expected_unknowns: unknowns,
            }));
        }
        let frame_error = |e: ClipFrameError| RunError::Resume(ResumeError::Frame(e));
        let (data, truth) = frame_data(first_frame, &r.report, arrivals.frames()).map_err(frame_error)?;
        let c = Converged {
            report: r.report,
            u: vector_to_space(&deriver.dofs, &r.chart, &r.state, false),
            adjoint: r.adjoint.clone(),
            chart: r.chart,
            previous: r.previous.clone(),
            state: r.state.clone(),
            data,
            truth,
        };
        summary.push(&deriver.derive(c).map_err(frame_error)?);
    }
    Ok(())
}

/// Where the solve resumes after the frames of `resume` (the last two states).
fn resume_from(resume: &[FrameRecord]) -> Option<ResumeFrom> {
    match resume {
        [] => None,
        [.., a, b] => Some(ResumeFrom {
            next: resume.len(),
            prev: (b.chart, b.state.clone()),
            prev2: Some((a.chart, a.state.clone())),
        }),
        [b] => Some(ResumeFrom { next: 1, prev: (b.chart, b.state.clone()), prev2: None }),
    }
}

/// The output thread's work: each converged frame derived, handed to the sink and summarised
/// (counted once written whole: the frames of the summary are the folder's).
fn write_frames<S: FrameSink>(
    deriver: &Deriver,
    rx: Receiver<Converged>,
    mut sink: S,
    summary: &mut Summary,
) -> Result<(), OutputStop<S::Error>> {
    for c in rx {
        let frame = c.report.frame;
        let f = deriver.derive(c).map_err(|error| OutputStop::Derive { frame, error })?;
        sink.frame(&f).map_err(OutputStop::Sink)?;
        summary.push(&f);
    }
    sink.finish().map_err(OutputStop::Sink)
}

/// The solve of a clip of `total` frames in runs of the frames at hand.
struct Runs<'a, 'p> {
    problem: &'a Problem<'p>,
    sp: &'a SequenceParams,
    total: usize,
}

impl Runs<'_, '_> {
    /// Solve the frames after those of `resume` in runs of the frames at hand, each run resumed
    /// from the last two states of the one before, every converged frame sent on `tx` (dropped
    /// at the end, which ends the output thread).
    fn solve(
        &self,
        arrivals: &mut Arrivals<'_>,
        mut frame0_start: Option<DVector<f64>>,
        resume: &[FrameRecord],
        tx: SyncSender<Converged>,
        progress: &mut impl FnMut(usize, usize),
    ) -> Result<(), RunError> {
        let (first_frame, total) = (self.sp.frame_offset, self.total);
        let mut solved = resume.len();
        let mut from = resume_from(resume);
        // the last two states solved, to resume the next run of frames from
        let (mut last, mut last2) = match &from {
            Some(r) => (Some(r.prev.clone()), r.prev2.clone()),
            None => (None, None),
        };
        while solved < total {
            let at_hand = arrivals.wait(solved + 1)?;
            let view = arrivals.frames();
            let data = ClipData { positions: &view.0[..at_hand], tracked: arrivals.tracked().map(|t| &t[..at_hand]) };
            let run = solve_sequence_from(
                self.problem,
                self.sp,
                data,
                frame0_start.take().as_ref().map_or(FirstStart::DataGuess, FirstStart::Near),
                from.take(),
                |_, _| {},
                |rep, frame| {
                    last2 = last.replace((frame.chart, frame.state.clone()));
                    let (data, truth) = frame_data(first_frame, rep, view)?;
                    let c = Converged {
                        report: *rep,
                        u: frame.solution.u.clone(),
                        adjoint: frame.solution.adjoint.clone(),
                        chart: frame.chart,
                        previous: frame.previous.map(<[Angles]>::to_vec),
                        state: frame.state.clone(),
                        data,
                        truth,
                    };
                    tx.send(c).map_err(|_| ClipFrameError::OutputStopped)?;
                    progress(rep.frame - first_frame + 1, total);
                    Ok(())
                },
            );
            run.map_err(|e| RunError::from(clip_total(e, total)))?;
            solved = at_hand;
            from = last.clone().map(|prev| ResumeFrom { next: solved, prev, prev2: last2.clone() });
        }
        Ok(())
    }
}

/// A chart-guard stop with the frames before it that were over the fit-quality gate, counted
/// over every frame of the clip (a streamed clip is solved in runs, each of which sees only its
/// own frames): `(count, first flagged, first frame)`.
fn with_degradation(e: RunError, reports: &[FrameReport]) -> RunError {
    match e {
        RunError::Sequence(SequenceError::SingularChart { frame, node, cos_beta, guard, axis, .. }) => {
            let flagged: Vec<usize> = reports.iter().filter(|r| r.fit.flagged).map(|r| r.frame).collect();
            let first = reports.first().map_or(frame, |r| r.frame);
            let degraded = flagged.first().map(|&f| (flagged.len(), f, first));
            RunError::Sequence(SequenceError::SingularChart { frame, node, cos_beta, guard, axis, degraded })
        }
        e => e,
    }
}

/// Why the output thread stopped: the sink's error, or a frame that could not be derived.
enum OutputStop<E> {
    Sink(E),
    Derive { frame: usize, error: ClipFrameError },
}

/// Why the frames of an earlier run cannot be resumed from.
#[derive(Debug, thiserror::Error)]
pub enum ResumeError {
    /// A record does not fit the case: another frame, or another number of unknowns.
    #[error("record {index} is frame {frame} with {unknowns} unknowns; expected frame {expected_frame} with {expected_unknowns}")]
    Record { index: usize, frame: usize, unknowns: usize, expected_frame: usize, expected_unknowns: usize },
    /// A recorded frame could not be derived again.
    #[error(transparent)]
    Frame(#[from] ClipFrameError),
}

/// An interrupt of a run of a streamed clip's frames, counted against the whole clip's
/// `total` frames (the run saw only the frames at hand).
fn clip_total(e: SequenceError, total: usize) -> SequenceError {
    match e {
        SequenceError::Solve(SolveError::Interrupted { what, done, .. }) => {
            SequenceError::Solve(SolveError::Interrupted { what, done, total })
        }
        e => e,
    }
}

/// The per-frame summary of a clip run, frame by frame.
struct Summary {
    run: ClipRun,
}

impl Summary {
    fn new(truth: bool) -> Self {
        Summary {
            run: ClipRun {
                reports: Vec::new(),
                roughness: Vec::new(),
                kappa2: Vec::new(),
                data_kappa: Vec::new(),
                omega: Vec::new(),
                truth: truth.then(TruthRun::default),
                wall_time_s: 0.0,
                source: String::new(),
                weights: None,
            },
        }
    }

    fn push(&mut self, f: &ClipFrame) {
        let r = &mut self.run;
        r.reports.push(f.report);
        r.roughness.push(f.planar.roughness);
        r.kappa2.push(f.planar.kappa2.clone());
        r.data_kappa.push(f.planar.data_kappa.clone());
        r.omega.push(f.omega.clone().unwrap_or_else(|| vec![Vector3::zeros(); f.nodes.alpha.len()]));
        if let (Some(tr), Some(t)) = (&mut r.truth, &f.truth) {
            tr.comparisons.push(t.comparison);
            tr.roll_rad.push(t.roll_rad);
            tr.twist_per_m.push(t.twist_per_m);
            tr.bending_true.push(t.bending_true.clone());
            tr.bending_recovered.push(t.bending_recovered.clone());
        }
    }

    fn finish(mut self, wall_time_s: f64, source: String) -> ClipRun {
        self.run.wall_time_s = wall_time_s;
        self.run.source = source;
        self.run
    }
}
