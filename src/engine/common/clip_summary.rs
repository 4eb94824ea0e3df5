//! The summary of a clip run, built frame by frame on the output thread of
//! [`super::clip::run_clip`] and bounded by what its figures draw, not by its frames: per frame
//! a few numbers (the report, the roughness, the errors against a ground truth); per node only
//! for the frames a kymograph draws ([`Kymograph`], at most [`KYMOGRAPH_COLUMNS`] of them).
//! Everything else of a frame goes to its files as it is solved, and is not held.
use nalgebra::Vector3;

use super::clip_frame::ClipFrame;
use crate::clip::synthetic::FrameComparison;
use crate::solve::sequence::FrameReport;

/// Most frames a kymograph draws (its columns): a clip's frames are sampled every
/// `⌈frames / KYMOGRAPH_COLUMNS⌉`-th.
pub const KYMOGRAPH_COLUMNS: usize = 150;

/// Summary of a clip run.
#[derive(Clone, Debug)]
pub struct ClipRun {
    pub reports: Vec<FrameReport>,
    /// per frame: sign alternation of the recovered κ2 and of the data's planar curvature
    /// ([`super::clip_frame::sign_alternation`])
    pub roughness: Vec<(f64, f64)>,
    /// the per-node fields of the frames the kymographs draw
    pub kymograph: Kymograph,
    /// synthetic clips: per frame the errors against the ground truth (end nodes skipped:
    /// [`super::clip_frame::TRUTH_SKIP_NODES`]), the true roll and twist
    pub truth: Option<TruthRun>,
    pub wall_time_s: f64,
    pub source: String,
    /// the weights `[inverse] weights = "auto"` chose (`super::weights`)
    pub weights: Option<ChosenWeights>,
}

/// Ground-truth scores of a synthetic clip run, per frame.
#[derive(Clone, Debug, Default)]
pub struct TruthRun {
    pub comparisons: Vec<FrameComparison>,
    /// true roll ψ of the bending plane per frame [rad]
    pub roll_rad: Vec<f64>,
    /// true twist κ3 per frame (mean over nodes) [rad/m]
    pub twist_per_m: Vec<f64>,
}

/// The frames of a clip run its kymographs draw: every `stride`-th frame of the run from its
/// first, `stride = ⌈frames of the clip / KYMOGRAPH_COLUMNS⌉` (every frame of a clip of at most
/// [`KYMOGRAPH_COLUMNS`]). Column `c` stands for the frames `c·stride .. (c+1)·stride` of the
/// run ([`Kymograph::span`]).
#[derive(Clone, Debug, Default)]
pub struct Kymograph {
    pub stride: usize,
    pub columns: Vec<KymographColumn>,
}

/// One frame drawn by the kymographs.
#[derive(Clone, Debug)]
pub struct KymographColumn {
    /// the frame's index among the run's frames (its report is `ClipRun::reports[index]`)
    pub index: usize,
    /// recovered κ2 at the element midpoints and the data's planar curvature at the interior
    /// nodes [1/m] (`ClipFrame::planar`)
    pub kappa2: Vec<f64>,
    pub data_kappa: Vec<f64>,
    /// the angular velocity ωˡ per node [rad/s] (`ClipFrame::omega`); zeros on the first frame
    pub omega: Vec<Vector3<f64>>,
    /// synthetic clips: the true and the recovered bending `κ1² + κ2²` per node [1/m²]
    pub bending: Option<[Vec<f64>; 2]>,
}

impl Kymograph {
    /// The sampling of a clip of `frames` frames.
    pub fn new(frames: usize) -> Self {
        Kymograph { stride: frames.div_ceil(KYMOGRAPH_COLUMNS).max(1), columns: Vec::new() }
    }

    /// Frame `index` of the run: kept if it is drawn.
    fn push(&mut self, index: usize, f: &ClipFrame) {
        if !index.is_multiple_of(self.stride) {
            return;
        }
        self.columns.push(KymographColumn {
            index,
            kappa2: f.planar.kappa2.clone(),
            data_kappa: f.planar.data_kappa.clone(),
            omega: f.omega.clone().unwrap_or_else(|| vec![Vector3::zeros(); f.nodes.alpha.len()]),
            bending: f.truth.as_ref().map(|t| [t.bending_true.clone(), t.bending_recovered.clone()]),
        });
    }

    /// The frames (indices into the reports, of `frames` in all) that column `c` stands for.
    pub fn span(&self, c: usize, frames: usize) -> std::ops::Range<usize> {
        (c * self.stride).min(frames)..((c + 1) * self.stride).min(frames)
    }
}

/// The summary of a clip run, frame by frame.
pub(crate) struct Summary {
    run: ClipRun,
}

impl Summary {
    /// The summary of a run of a clip of `frames` frames without a ground truth.
    pub(crate) fn new(frames: usize) -> Self {
        Summary::of(frames, None)
    }

    /// The summary of a run of a clip of `frames` frames with a ground truth to score against
    /// (a synthetic recording's sidecar).
    pub(crate) fn with_truth(frames: usize) -> Self {
        Summary::of(frames, Some(TruthRun::default()))
    }

    fn of(frames: usize, truth: Option<TruthRun>) -> Self {
        Summary {
            run: ClipRun {
                reports: Vec::new(),
                roughness: Vec::new(),
                kymograph: Kymograph::new(frames),
                truth,
                wall_time_s: 0.0,
                source: String::new(),
                weights: None,
            },
        }
    }

    pub(crate) fn push(&mut self, f: &ClipFrame) {
        let r = &mut self.run;
        r.kymograph.push(r.reports.len(), f);
        r.reports.push(f.report);
        r.roughness.push(f.planar.roughness);
        if let (Some(tr), Some(t)) = (&mut r.truth, &f.truth) {
            tr.comparisons.push(t.comparison);
            tr.roll_rad.push(t.roll_rad);
            tr.twist_per_m.push(t.twist_per_m);
        }
    }

    pub(crate) fn finish(mut self, wall_time_s: f64, source: String) -> ClipRun {
        self.run.wall_time_s = wall_time_s;
        self.run.source = source;
        self.run
    }
}

/// The weights `"auto"` chose, for run.json and the batch summary.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChosenWeights {
    /// the recording's noise level σ̂ per coordinate [m]
    pub noise_m: f64,
    /// the chosen tracking weight λg
    pub lambda_g: f64,
    /// the case's `lambda_g`: the largest allowed
    pub lambda_g_max: f64,
    /// the fit's RMS distance to the data per coordinate at the chosen λg, `r` [m]
    pub fit_residual_m: f64,
    /// frames of the clip's start the choice was calibrated on
    pub calibration_frames: usize,
    /// calibration solves
    pub solves: usize,
    /// the stabilisation ε of the λd term's rule (I11) the run used
    /// (`crate::engine::weights::auto_stabilisation`)
    #[serde(default)]
    pub stabilisation: f64,
}
