//! A clip case frame by frame in the Rust engine (`solve::sequence`), every converged frame
//! handed to a second thread while the next frame is solved: there it is derived into a
//! [`ClipFrame`] (curvature, truth comparison, summary) and given to a [`FrameSink`] (which
//! `crate::output::clip_output::ClipWriter` implements with the streamed files). The frames themselves may arrive while the
//! clip is solved ([`ClipFrames::Streamed`]).
use std::sync::mpsc::{Receiver, SyncSender};
use std::time::Instant;

use nalgebra::{DVector, Vector3};

use super::derive::{frame_data, ClipFrameError, Converged, Deriver};
use super::RunError;
use crate::case::Case;
use crate::clip::synthetic::{FrameTruth, GroundTruth};
use crate::clip::Clip;
use crate::engine::common::clip_frame::{FrameRecord, FrameSink};
use crate::engine::common::clip_summary::{ClipRun, Summary};
use crate::io::files::JournalError;
use crate::model::chart::Chart;
use crate::model::rotation::Angles;
use crate::solve::inverse::kkt::Part;
use crate::solve::inverse::Records;
use crate::solve::sequence::{
    solve_sequence_from, vector_to_space, ClipData, FirstStart, FrameReport, ResumeFrom, SequenceError, SequenceParams,
    SequenceStart,
};
use crate::solve::{Problem, SolveError};

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

/// Frames a streamed clip's generator may be ahead of the solve (`crate::engine::run_clip_into`):
/// with the frames of the run at hand, a streamed clip holds at most about twice this many.
pub const STREAM_AHEAD: usize = 256;

/// One frame of a streamed clip ([`ClipFrames::Streamed`]): its node positions [m] and, for a
/// synthetic clip, its ground truth.
pub type StreamedFrame = (Vec<Vector3<f64>>, Option<FrameTruth>);

/// The frames of a clip as [`run_clip`] takes them.
pub enum ClipFrames<'a> {
    /// every frame at hand: the clip and, for a synthetic clip, its ground truth frame for frame
    /// `start`: frame 0's initial iterate in its chart (`None`: the data guess)
    Loaded { clip: &'a Clip, truth: Option<&'a GroundTruth>, start: Option<&'a DVector<f64>> },
    /// `total` frames arriving in order on `frames` (each with its ground truth where `truth`),
    /// e.g. from a generator or a file's reader on another thread: the solve starts with the
    /// first frame while later ones are made. `header`: the clip without its frames (time step,
    /// source); `start` as for a loaded clip.
    Streamed {
        header: Clip,
        total: usize,
        truth: bool,
        frames: Receiver<StreamedFrame>,
        start: Option<&'a DVector<f64>>,
    },
}

/// The frames of a [`ClipFrames`] at hand: all of a loaded clip; of a streamed one those
/// received and not yet released (a window: the frames of a run and the one before, so that
/// memory does not grow with the clip).
struct Arrivals<'a> {
    input: ClipFrames<'a>,
    /// streamed: the frames received and not released, the first of them frame `base` of the
    /// clip, and their ground truth
    frames: Vec<Vec<Vector3<f64>>>,
    truth: Vec<FrameTruth>,
    base: usize,
}

impl Arrivals<'_> {
    /// The clip (without its frames if streamed), its frame count and whether it has a truth.
    fn header(&self) -> (&Clip, usize, bool) {
        match &self.input {
            ClipFrames::Loaded { clip, truth, .. } => (clip, clip.frame_count(), truth.is_some()),
            ClipFrames::Streamed { header, total, truth, .. } => (header, *total, *truth),
        }
    }

    /// Wait until at least the frames `..n` of the clip have arrived, take every frame that has
    /// arrived, and return the end of the frames at hand (they are the frames `base..end`).
    fn wait(&mut self, n: usize) -> Result<usize, RunError> {
        let (rx, total) = match &self.input {
            ClipFrames::Loaded { clip, .. } => return Ok(clip.frame_count()),
            ClipFrames::Streamed { frames, total, .. } => (frames, *total),
        };
        while self.base + self.frames.len() < n.min(total) {
            let received = self.base + self.frames.len();
            let (x, t) = rx.recv().map_err(|_| RunError::Generator { received, total })?;
            self.frames.push(x);
            self.truth.extend(t);
        }
        while let Ok((x, t)) = rx.try_recv() {
            self.frames.push(x);
            self.truth.extend(t);
        }
        Ok(self.base + self.frames.len())
    }

    /// Release the streamed frames before frame `upto` of the clip (no longer solved or derived).
    fn release(&mut self, upto: usize) {
        if let ClipFrames::Streamed { .. } = &self.input {
            let k = upto.saturating_sub(self.base).min(self.frames.len());
            self.frames.drain(..k);
            self.truth.drain(..k.min(self.truth.len()));
            self.base += k;
        }
    }

    /// Which nodes of each frame of the clip were tracked (`clip::missing`; `None`: all).
    fn tracked(&self) -> Option<&[Vec<bool>]> {
        match &self.input {
            ClipFrames::Loaded { clip, .. } => clip.tracked.as_deref(),
            ClipFrames::Streamed { .. } => None,
        }
    }

    /// The frames at hand and their ground truth, the first of them frame [`Arrivals::base`].
    fn frames(&self) -> (&[Vec<Vector3<f64>>], Option<&[FrameTruth]>) {
        match &self.input {
            ClipFrames::Loaded { clip, truth, .. } => (&clip.frames, truth.map(|t| &t.frames[..])),
            ClipFrames::Streamed { truth, .. } => (&self.frames, truth.then_some(&self.truth[..])),
        }
    }

    /// The clip's index of the first frame at hand.
    fn base(&self) -> usize {
        match &self.input {
            ClipFrames::Loaded { .. } => 0,
            ClipFrames::Streamed { .. } => self.base,
        }
    }
}

/// The records of an earlier run's frames, in order, read one at a time
/// (`crate::output::journal` reads them from its file): none are held.
pub type ResumeRecords<'r> = &'r mut dyn Iterator<Item = Result<FrameRecord, JournalError>>;

/// [`run_clip_resumed`] after the records `resume` at hand.
pub fn run_clip<S: FrameSink>(
    case: &Case,
    frames: ClipFrames<'_>,
    resume: &[FrameRecord],
    sink: S,
    progress: impl FnMut(usize, usize),
) -> Result<ClipOutcome, RunError> {
    run_clip_resumed(case, frames, &mut resume.iter().cloned().map(Ok), sink, progress)
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
pub fn run_clip_resumed<S: FrameSink>(
    case: &Case,
    frames: ClipFrames<'_>,
    resume: ResumeRecords<'_>,
    sink: S,
    mut progress: impl FnMut(usize, usize),
) -> Result<ClipOutcome, RunError> {
    let sp = case.sequence_params().ok_or_else(|| RunError::Kind { case: case.name.clone(), what: "a clip case" })?;
    // a clip keeps each frame's report, not its iteration history
    let sp = SequenceParams { records: Records::Last, ..sp };
    let problem = case.problem();
    // frame 0's initial iterate, for the first run of frames only
    let frame0_start = match &frames {
        ClipFrames::Loaded { start, .. } | ClipFrames::Streamed { start, .. } => start.cloned(),
    };
    let mut arrivals = Arrivals { input: frames, frames: Vec::new(), truth: Vec::new(), base: 0 };
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
    let mut summary = if has_truth { Summary::with_truth(total) } else { Summary::new(total) };
    let resumed = resume_summary(&deriver, &mut arrivals, resume, sp.frame_offset, &mut summary)?;
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
        let result = runs.solve(&mut arrivals, frame0_start, resumed, tx, &mut progress);
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

/// The frames of an earlier run (`resume`, read one at a time): checked against the case and
/// summarised again from their records; how many there were and the last two states, to
/// resume the solve from.
fn resume_summary(
    deriver: &Deriver,
    arrivals: &mut Arrivals<'_>,
    resume: ResumeRecords<'_>,
    first_frame: usize,
    summary: &mut Summary,
) -> Result<Resumed, RunError> {
    let unknowns = deriver.dofs.len();
    let mut resumed = Resumed::default();
    for (i, r) in resume.enumerate() {
        let r = r.map_err(|e| RunError::Resume(ResumeError::Journal(e)))?;
        if r.report.frame != first_frame + i || r.state.len() != unknowns || r.adjoint.len() != unknowns {
            return Err(RunError::Resume(ResumeError::Record {
                index: i,
                frame: r.report.frame,
                unknowns: r.state.len(),
                expected_frame: first_frame + i,
                expected_unknowns: unknowns,
            }));
        }
        arrivals.wait(i + 1)?;
        let frame_error = |e: ClipFrameError| RunError::Resume(ResumeError::Frame(e));
        let (data, truth) =
            frame_data(first_frame + arrivals.base(), &r.report, arrivals.frames()).map_err(frame_error)?;
        let c = Converged {
            report: r.report,
            u: vector_to_space(&deriver.dofs, &r.chart, &r.state, Part::State),
            adjoint: r.adjoint.clone(),
            chart: r.chart,
            previous: r.previous.clone(),
            state: r.state.clone(),
            data,
            truth,
        };
        summary.push(&deriver.derive(c).map_err(frame_error)?);
        arrivals.release(i);
        resumed.prev2 = resumed.prev.replace((r.chart, r.state));
        resumed.count = i + 1;
    }
    Ok(resumed)
}

/// The frames of an earlier run: how many, and the last two states (each in its chart) to
/// resume the solve from (`ResumeFrom`).
#[derive(Default)]
struct Resumed {
    count: usize,
    prev: Option<(Chart, DVector<f64>)>,
    prev2: Option<(Chart, DVector<f64>)>,
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
    /// Solve the frames after the `resumed` ones in runs of the frames at hand, each run resumed
    /// from the last two states of the one before and given only its own frames and the one
    /// before it (a streamed clip's earlier frames are released), every converged frame sent on
    /// `tx` (dropped at the end, which ends the output thread).
    fn solve(
        &self,
        arrivals: &mut Arrivals<'_>,
        mut frame0_start: Option<DVector<f64>>,
        resumed: Resumed,
        tx: SyncSender<Converged>,
        progress: &mut impl FnMut(usize, usize),
    ) -> Result<(), RunError> {
        let (first_frame, total) = (self.sp.frame_offset, self.total);
        let mut solved = resumed.count;
        // the last two states solved, to resume the next run of frames from
        let (mut last, mut last2) = (resumed.prev, resumed.prev2);
        while solved < total {
            let at_hand = arrivals.wait(solved + 1)?;
            let base = arrivals.base();
            let view = arrivals.frames();
            let tracked = arrivals.tracked().map(|t| &t[base..at_hand]);
            let data = ClipData { positions: &view.0[..at_hand - base], tracked };
            // the frames of the run counted from the first at hand
            let sp = SequenceParams { frame_offset: first_frame + base, ..*self.sp };
            let from = last.clone().map(|prev| ResumeFrom { next: solved - base, prev, prev2: last2.clone() });
            let run = solve_sequence_from(
                self.problem,
                &sp,
                data,
                SequenceStart {
                    first: frame0_start.take().as_ref().map_or(FirstStart::DataGuess, FirstStart::Near),
                    resume: from,
                },
                |_, _| {},
                |rep, frame| {
                    last2 = last.replace((frame.chart, frame.state.clone()));
                    let (data, truth) = frame_data(first_frame + base, rep, view)?;
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
            run.map_err(|e| RunError::from(clip_total(e, base, total)))?;
            solved = at_hand;
            // the next run starts after the last frame solved, which stays at hand
            arrivals.release(solved - 1);
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
    /// The records could not be read.
    #[error(transparent)]
    Journal(#[from] JournalError),
}

/// An interrupt of a run of a clip's frames (the frames at hand, the first of them frame
/// `base` of the clip), counted against the whole clip's `total` frames.
fn clip_total(e: SequenceError, base: usize, total: usize) -> SequenceError {
    match e {
        SequenceError::Solve(SolveError::Interrupted { what, done, .. }) => {
            SequenceError::Solve(SolveError::Interrupted { what, done: done + base, total })
        }
        e => e,
    }
}
