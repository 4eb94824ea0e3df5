//! A clip case frame by frame in the Rust engine (`solve::sequence`), every converged frame
//! handed to a second thread while the next frame is solved: there it is derived into a
//! [`ClipFrame`] (curvature, truth comparison, summary) and given to a [`FrameSink`] (which
//! `crate::io` implements with the streamed files). The frames themselves may arrive while the
//! clip is solved ([`ClipFrames::Streamed`]).
use std::sync::mpsc::Receiver;
use std::time::Instant;

use nalgebra::{DVector, Matrix3, Vector3};

use super::metrics::INNER_SKIP_ELEMENTS;
use super::{NodalState, RunError};
use crate::case::Case;
use crate::clip::synthetic::{compare_frame, FrameComparison, FrameTruth, GroundTruth, RecoveredFrame};
use crate::clip::Clip;
use crate::model::chart::Chart;
use crate::model::mesh::Field;
use crate::model::rotation::Angles;
use crate::solve::inverse::measures::angular_velocity;
use crate::solve::inverse::Records;
use crate::solve::sequence::{
    solve_sequence_from, vector_to_space, ClipData, FirstStart, FrameReport, ResumeFrom, SequenceError, SequenceParams,
};
use crate::solve::SolveError;

/// Nodes skipped at each end when scoring curvature against a ground truth (the curvature of
/// the inverse solution is least reliable at the free ends; as `metrics::INNER_SKIP_ELEMENTS`).
pub const TRUTH_SKIP_NODES: usize = INNER_SKIP_ELEMENTS;

/// One converged frame of a clip, in space coordinates.
#[derive(Clone, Debug)]
pub struct ClipFrame {
    pub report: FrameReport,
    /// frame time [s]
    pub time_s: f64,
    /// the recovered state (angles in the frame's chart)
    pub nodes: NodalState,
    /// controls f = x̂/λf [N/m] and l = α̂/λl [N m/m] per node (eq. 54)
    pub force: Vec<Vector3<f64>>,
    pub torque: Vec<Vector3<f64>>,
    /// the frame's data positions [m]
    pub data: Vec<Vector3<f64>>,
    /// angular velocity ωˡ = A(α)(α − α_{n−1})/Δt per node [rad/s], components in the local
    /// frame (d1, d2, d3) as κ (eq. 27; [`angular_velocity`]): exactly what the Λω term of (41)
    /// penalised, α_{n−1} the previous frame's angles in this frame's chart. `None` on the
    /// first frame, which has no previous frame (Remark 6)
    pub omega: Option<Vec<Vector3<f64>>>,
    /// element-midpoint curvature `(s [m], κ = A ∂sα [1/m])` (eq. 28), computed once for every
    /// consumer of the frame
    pub kappa: Vec<(f64, Vector3<f64>)>,
    /// recovered κ2 at the element midpoints and the data's planar curvature at the interior
    /// nodes [1/m] ([`ClipRun::kappa2`], [`ClipRun::data_kappa`])
    pub kappa2: Vec<f64>,
    pub data_kappa: Vec<f64>,
    /// sign alternation of the recovered κ2 and of the data's planar curvature
    pub roughness: (f64, f64),
    /// synthetic clips: the frame against its ground truth
    pub truth: Option<TruthFrame>,
    /// what the frame is derived from (the resume journal)
    pub record: FrameRecord,
}

/// A frame of a synthetic clip against its ground truth.
#[derive(Clone, Debug)]
pub struct TruthFrame {
    /// true roll ψ of the bending plane [rad]
    pub roll_rad: f64,
    /// true twist κ3, mean over the nodes [rad/m]
    pub twist_per_m: f64,
    pub comparison: FrameComparison,
    /// true and recovered bending `κ1² + κ2²` per node [1/m²]
    pub bending_true: Vec<f64>,
    pub bending_recovered: Vec<f64>,
}

/// Where the frames of a clip go (`crate::io::clip_files::ClipWriter` streams them to disk).
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

/// Curvature at the nodes from element-midpoint values: the mean of the adjacent elements
/// (the end element at the ends).
pub fn nodal_curvature(kappa: &[(f64, Vector3<f64>)]) -> Vec<Vector3<f64>> {
    let m = kappa.len();
    (0..=m).map(|i| (kappa[i.saturating_sub(1).min(m - 1)].1 + kappa[i.min(m - 1)].1) * 0.5).collect()
}

/// Planar curvature of a centreline in the x–z plane at interior nodes [1/m]:
/// `(θ_e − θ_{e−1})/h`, θ the tangent angle from e3 towards e1. For a frame with α = β = 0 this
/// is κ2 of eq. (28) (κ = A ∂sα with A(0) gives κ2 = −∂sγ = ∂sθ).
pub fn planar_xz_curvature(x: &[Vector3<f64>], h: f64) -> Vec<f64> {
    let theta: Vec<f64> = x.windows(2).map(|w| (w[1][0] - w[0][0]).atan2(w[1][2] - w[0][2])).collect();
    theta
        .windows(2)
        .map(|t| {
            let d = t[1] - t[0];
            let d = (d + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI) - std::f64::consts::PI;
            d / h
        })
        .collect()
}

/// Roughness of a sequence: the fraction of interior points where the first difference changes
/// sign (a local extremum). A smooth curvature profile of a worm has a handful of extrema; a
/// nodal zig-zag has one at almost every point (roughness → 1).
pub fn sign_alternation(k: &[f64]) -> f64 {
    if k.len() < 3 {
        return 0.0;
    }
    let d: Vec<f64> = k.windows(2).map(|w| w[1] - w[0]).collect();
    let flips = d.windows(2).filter(|w| w[0] * w[1] < 0.0).count();
    flips as f64 / (k.len() - 2) as f64
}

/// Everything a converged frame of a clip is derived from, exactly (the resume journal of
/// `crate::io` stores one per frame): with the records of frames `0..n` a clip resumes at frame
/// `n` and continues bit for bit as the uninterrupted solve (`solve::sequence::ResumeFrom`),
/// and the summary of frames `0..n` is derived again from them without solving.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct FrameRecord {
    pub report: FrameReport,
    pub chart: Chart,
    /// the state `(x, α)` in the frame's chart (forward layout)
    pub state: DVector<f64>,
    /// the adjoint `(x̂, α̂)` in space coordinates (forward layout)
    pub adjoint: DVector<f64>,
    /// the previous frame's angles in this frame's chart (`None` on the first frame)
    pub previous: Option<Vec<Angles>>,
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
    mut sink: S,
    mut progress: impl FnMut(usize, usize),
) -> Result<ClipOutcome, RunError> {
    let sp = case.sequence_params().ok_or_else(|| RunError::Kind { case: case.name.clone(), what: "a clip case" })?;
    // a clip keeps each frame's report, not its iteration history
    let sp = SequenceParams { records: Records::Last, ..sp };
    let problem = case.problem();
    let dofs = problem.dofs();
    let w8 = sp.inverse.weights;
    let first_frame = sp.frame_offset;
    // frame 0's initial iterate, for the first run of frames only
    let mut frame0_start = match &frames {
        ClipFrames::Loaded { start, .. } => start.cloned(),
        ClipFrames::Streamed { .. } => None,
    };
    let mut arrivals = Arrivals { input: frames, frames: Vec::new(), truth: Vec::new() };
    let (header, total, has_truth) = arrivals.header();
    let (dt_s, source) = (header.dt_s, header.source.clone());
    let h = case.mesh.h();
    let start = Instant::now();
    let dt = sp.inverse.frame_interval_s;
    let mut summary = Summary::new(has_truth);
    // A converged frame in space coordinates with everything its consumers need (on the
    // output thread).
    let derive = |c: Converged| -> Result<ClipFrame, String> {
        let Converged { report: rep, u, adjoint, chart, previous, state, data, truth } = c;
        let nodes = NodalState { chart, ..NodalState::from_vector(&case.mesh, &u) };
        let (force, torque): (Vec<_>, Vec<_>) = (0..nodes.s.len())
            .map(|i| {
                let (xh, ah) = (dofs.get(&adjoint, i, Field::X), dofs.get(&adjoint, i, Field::Alpha));
                (xh / w8.lambda_f, ah / w8.lambda_l)
            })
            .unzip();
        let kappa = nodes.element_curvature();
        let k2: Vec<f64> = kappa.iter().map(|(_, k)| k[1]).collect();
        // The data's curvature in the plane normal to the chart's axis (exactly the x–z
        // curvature for an x–z clip; rotates with the data, R5).
        let in_chart: Vec<Vector3<f64>> = data.iter().map(|x| chart.to_chart(x)).collect();
        let kd = planar_xz_curvature(&in_chart, h);
        let mut truth_frame = None;
        if let Some(ft) = &truth {
            let q: Vec<Matrix3<f64>> = nodes.alpha.iter().map(|a| nodes.chart.rotation(a)).collect();
            let kn = nodal_curvature(&kappa);
            let c = compare_frame(&data, ft, &RecoveredFrame { x: &nodes.x, q: &q, kappa: &kn }, TRUTH_SKIP_NODES)
                .map_err(|e| e.to_string())?;
            let twist = ft.kappa.iter().map(|k| k.z).sum::<f64>() / ft.kappa.len() as f64;
            let bend = |k: &Vector3<f64>| k.x * k.x + k.y * k.y;
            truth_frame = Some(TruthFrame {
                roll_rad: ft.roll_rad,
                twist_per_m: twist,
                comparison: c,
                bending_true: ft.kappa.iter().map(bend).collect(),
                bending_recovered: kn.iter().map(bend).collect(),
            });
        }
        let omega: Option<Vec<Vector3<f64>>> = previous
            .as_ref()
            .map(|prev| nodes.alpha.iter().zip(prev).map(|(a, p)| angular_velocity(a, p, dt)).collect());
        let roughness = (sign_alternation(&k2), sign_alternation(&kd));
        Ok(ClipFrame {
            report: rep,
            time_s: rep.frame as f64 * dt_s,
            nodes,
            force,
            torque,
            data,
            omega,
            kappa,
            kappa2: k2,
            data_kappa: kd,
            roughness,
            truth: truth_frame,
            record: FrameRecord { report: rep, chart, state, adjoint, previous },
        })
    };
    // The data (and ground truth) of frame `rep.frame` among the frames at hand.
    let frame_data = |rep: &FrameReport,
                      (frames, truth): (&[Vec<Vector3<f64>>], Option<&[FrameTruth]>)|
     -> Result<(Vec<Vector3<f64>>, Option<FrameTruth>), String> {
        let index = rep.frame.checked_sub(first_frame).filter(|i| *i < frames.len());
        let index = index.ok_or_else(|| format!("frame {} is outside the clip", rep.frame))?;
        Ok((frames[index].clone(), truth.map(|t| t[index].clone())))
    };
    // The frames of an earlier run: their summary again, from their records.
    arrivals.wait(resume.len())?;
    for (i, r) in resume.iter().enumerate() {
        if r.report.frame != first_frame + i || r.state.len() != dofs.len() || r.adjoint.len() != dofs.len() {
            return Err(RunError::Resume(format!(
                "record {i} is frame {} with {} unknowns; expected frame {} with {}",
                r.report.frame,
                r.state.len(),
                first_frame + i,
                dofs.len()
            )));
        }
        let (data, truth) = frame_data(&r.report, arrivals.frames()).map_err(RunError::Resume)?;
        let c = Converged {
            report: r.report,
            u: vector_to_space(&dofs, &r.chart, &r.state, false),
            adjoint: r.adjoint.clone(),
            chart: r.chart,
            previous: r.previous.clone(),
            state: r.state.clone(),
            data,
            truth,
        };
        summary.push(&derive(c).map_err(RunError::Resume)?);
    }
    let mut from = match resume {
        [] => None,
        [.., a, b] => Some(ResumeFrom {
            next: resume.len(),
            prev: (b.chart, b.state.clone()),
            prev2: Some((a.chart, a.state.clone())),
        }),
        [b] => Some(ResumeFrom { next: 1, prev: (b.chart, b.state.clone()), prev2: None }),
    };
    // room for about 0.1 s of frames: the output thread falls behind while a streamed clip's
    // generator shares its core (the first 0.25 s of worm_roll_3d), and catches up after
    let (tx, rx) = std::sync::mpsc::sync_channel::<Converged>(64);
    let (result, (summary, written)) = std::thread::scope(|scope| {
        let derive = &derive;
        // The output thread: each frame derived, summarised and handed to the sink.
        let io = scope.spawn(move || {
            let out = || -> Result<(), OutputStop<S::Error>> {
                for c in rx {
                    let frame = c.report.frame;
                    let f = derive(c).map_err(|message| OutputStop::Derive { frame, message })?;
                    // counted once written whole: the frames of the summary are the folder's
                    sink.frame(&f).map_err(OutputStop::Sink)?;
                    summary.push(&f);
                }
                sink.finish().map_err(OutputStop::Sink)
            };
            let written = out();
            (summary, written)
        });
        let mut result = Ok(());
        let mut solved = resume.len();
        // the last two states solved, to resume the next run of frames from
        let (mut last, mut last2) = match &from {
            Some(r) => (Some(r.prev.clone()), r.prev2.clone()),
            None => (None, None),
        };
        while solved < total {
            let at_hand = match arrivals.wait(solved + 1) {
                Ok(n) => n,
                Err(e) => {
                    result = Err(e);
                    break;
                }
            };
            let view = arrivals.frames();
            let data = ClipData { positions: &view.0[..at_hand], tracked: arrivals.tracked().map(|t| &t[..at_hand]) };
            let run = solve_sequence_from(
                &problem,
                &sp,
                data,
                frame0_start.take().as_ref().map_or(FirstStart::DataGuess, FirstStart::Near),
                from.take(),
                |_, _| {},
                |rep, frame| {
                    last2 = last.replace((frame.chart, frame.state.clone()));
                    let (data, truth) = frame_data(rep, view)?;
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
                    tx.send(c).map_err(|_| "the output thread stopped (see the write error)".to_string())?;
                    progress(rep.frame - first_frame + 1, total);
                    Ok(())
                },
            );
            if let Err(e) = run {
                result = Err(RunError::from(clip_total(e, total)));
                break;
            }
            solved = at_hand;
            from = last.clone().map(|prev| ResumeFrom { next: solved, prev, prev2: last2.clone() });
        }
        drop(tx);
        let written = io.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        (result, written)
    });
    // A write error explains a stopped clip better than the stop itself.
    let stopped = match (written, result) {
        (Err(OutputStop::Sink(e)), _) => Some(RunError::Sink(Box::new(e))),
        (Err(OutputStop::Derive { frame, message }), _) => {
            Some(RunError::Sequence(SequenceError::Callback { frame, message }))
        }
        (Ok(()), Err(e)) => Some(e),
        (Ok(()), Ok(())) => None,
    };
    let run = summary.finish(start.elapsed().as_secs_f64(), source);
    let stopped = stopped.map(|e| with_degradation(e, &run.reports));
    Ok(ClipOutcome { run, stopped, total })
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

/// A converged frame as the solve hands it over (owned: the output thread derives the
/// [`ClipFrame`] from it while the next frame is solved).
struct Converged {
    report: FrameReport,
    /// state and adjoint in space coordinates (forward layout; angles in the frame's chart)
    u: DVector<f64>,
    adjoint: DVector<f64>,
    chart: Chart,
    /// the previous frame's angles in this frame's chart (`None` on the first frame)
    previous: Option<Vec<Angles>>,
    /// the state in the frame's chart
    state: DVector<f64>,
    /// the frame's data positions [m] and, for a synthetic clip, its ground truth
    data: Vec<Vector3<f64>>,
    truth: Option<FrameTruth>,
}

/// Why the output thread stopped: the sink's error, or a frame that could not be derived.
enum OutputStop<E> {
    Sink(E),
    Derive { frame: usize, message: String },
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
        r.roughness.push(f.roughness);
        r.kappa2.push(f.kappa2.clone());
        r.data_kappa.push(f.data_kappa.clone());
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
