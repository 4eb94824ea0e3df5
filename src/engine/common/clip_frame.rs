//! One converged frame of a clip as every consumer sees it ([`ClipFrame`]: the controls,
//! curvature, angular velocity and the comparison with a ground truth), what it is derived from
//! ([`FrameRecord`], the resume journal's entry), and where frames go ([`FrameSink`]). The Rust
//! engine derives the frames (`crate::engine::rust`); the output folder's writer is a sink.
use nalgebra::{DVector, Vector3};

use super::metrics::INNER_SKIP_ELEMENTS;
use super::result::NodalState;
use crate::clip::synthetic::FrameComparison;
use crate::model::chart::Chart;
use crate::model::resultants::Resultants;
use crate::model::rotation::Angles;
#[cfg(doc)]
use crate::solve::inverse::measures::angular_velocity;
use crate::solve::sequence::FrameReport;

/// Nodes skipped at each end when scoring curvature against a ground truth (the curvature of
/// the inverse solution is least reliable at the free ends; as `metrics::INNER_SKIP_ELEMENTS`).
pub const TRUTH_SKIP_NODES: usize = INNER_SKIP_ELEMENTS;

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
/// `crate::output::journal` stores one per frame): with the records of frames `0..n` a clip resumes at frame
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

/// One converged frame of a clip, in space coordinates.
#[derive(Clone, Debug)]
pub struct ClipFrame {
    pub report: FrameReport,
    /// frame time [s]
    pub time_s: f64,
    /// the recovered state (angles in the frame's chart)
    pub nodes: NodalState,
    /// controls f and l per node (eq. 54)
    pub controls: Controls,
    /// the frame's data positions [m]
    pub data: Vec<Vector3<f64>>,
    /// angular velocity ωˡ = A(α)(α − α_{n−1})/Δt per node [rad/s], components in the local
    /// frame (d1, d2, d3) as κ (eq. 27; [`angular_velocity`]): exactly what the Λω term of (41)
    /// penalised, α_{n−1} the previous frame's angles in this frame's chart. `None` on the
    /// first frame, which has no previous frame (Remark 6)
    pub omega: Option<Vec<Vector3<f64>>>,
    /// per element: the curvature and the stress resultants
    pub elements: ElementFields,
    /// recovered κ2 and the data's planar curvature, and their roughness
    pub planar: PlanarCurvature,
    /// synthetic clips: the frame against its ground truth
    pub truth: Option<TruthFrame>,
    /// what the frame is derived from (the resume journal)
    pub record: FrameRecord,
}

/// The per-element values of a frame, computed once for every consumer of the frame.
#[derive(Clone, Debug)]
pub struct ElementFields {
    /// element-midpoint curvature `(s [m], κ = A ∂sα [1/m])` (eq. 28)
    pub kappa: Vec<(f64, Vector3<f64>)>,
    /// internal force n [N] and moment m [N m] (eqs. 13, 15; [`NodalState::resultants`])
    pub resultants: Vec<Resultants>,
}

/// The controls of a frame per node: f = x̂/λf [N/m] and l = α̂/λl [N m/m] (eq. 54).
#[derive(Clone, Debug)]
pub struct Controls {
    pub force: Vec<Vector3<f64>>,
    pub torque: Vec<Vector3<f64>>,
}

/// A frame's planar curvature: the recovered κ2 at the element midpoints and the data's planar
/// curvature at the interior nodes [1/m] (the kymographs' [`super::clip_summary::KymographColumn`]),
/// and the sign alternation of each ([`sign_alternation`]).
#[derive(Clone, Debug)]
pub struct PlanarCurvature {
    pub kappa2: Vec<f64>,
    pub data_kappa: Vec<f64>,
    /// sign alternation of the recovered κ2 and of the data's planar curvature
    pub roughness: (f64, f64),
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

/// Where the frames of a clip go (`crate::output::clip_output::ClipWriter` streams them to
/// disk). Called from a second thread, in frame order.
pub trait FrameSink: Send {
    type Error: std::error::Error + Send + Sync + 'static;
    /// One converged frame.
    fn frame(&mut self, frame: &ClipFrame) -> Result<(), Self::Error>;
    /// After the last frame handed over (also when the clip stopped early).
    fn finish(&mut self) -> Result<(), Self::Error>;
}
