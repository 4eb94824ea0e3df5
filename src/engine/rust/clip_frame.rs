//! One converged frame of a clip, derived on the output thread of [`super::clip::run_clip`]
//! from what the solve hands over ([`Converged`]): the controls, curvature, angular velocity and
//! the comparison with a ground truth ([`ClipFrame`]).
use nalgebra::{DVector, Matrix3, Vector3};

use super::metrics::INNER_SKIP_ELEMENTS;
use super::NodalState;
use crate::case::Case;
use crate::clip::synthetic::{compare_frame, FrameComparison, FrameTruth, RecoveredFrame};
use crate::clip::ClipError;
use crate::model::chart::Chart;
use crate::model::mesh::{DofMap, Field};
use crate::model::resultants::Resultants;
use crate::model::rotation::Angles;
use crate::solve::inverse::measures::angular_velocity;
use crate::solve::inverse::Weights;
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
/// curvature at the interior nodes [1/m] (the kymographs' `super::clip_summary::KymographColumn`),
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

/// A converged frame as the solve hands it over (owned: the output thread derives the
/// [`ClipFrame`] from it while the next frame is solved).
pub(super) struct Converged {
    pub(super) report: FrameReport,
    /// state and adjoint in space coordinates (forward layout; angles in the frame's chart)
    pub(super) u: DVector<f64>,
    pub(super) adjoint: DVector<f64>,
    pub(super) chart: Chart,
    /// the previous frame's angles in this frame's chart (`None` on the first frame)
    pub(super) previous: Option<Vec<Angles>>,
    /// the state in the frame's chart
    pub(super) state: DVector<f64>,
    /// the frame's data positions [m] and, for a synthetic clip, its ground truth
    pub(super) data: Vec<Vector3<f64>>,
    pub(super) truth: Option<FrameTruth>,
}

/// Why a frame of a clip could not be handed on: the numbers of the frame at fault.
#[derive(Debug, thiserror::Error)]
pub enum ClipFrameError {
    /// A report names a frame that is not among the frames at hand.
    #[error("frame {frame} is outside the clip (frames {first}..{end} at hand)")]
    OutsideClip { frame: usize, first: usize, end: usize },
    /// The frame's comparison with its ground truth failed (mismatched lengths).
    #[error(transparent)]
    Truth(#[from] ClipError),
    /// The output thread stopped (its own error says why) while the solve went on.
    #[error("the output thread stopped (see the write error)")]
    OutputStopped,
}

/// The data (and ground truth) of frame `rep.frame` among the frames at hand, the first of
/// which is frame `first_frame`.
pub(super) fn frame_data(
    first_frame: usize,
    rep: &FrameReport,
    (frames, truth): (&[Vec<Vector3<f64>>], Option<&[FrameTruth]>),
) -> Result<(Vec<Vector3<f64>>, Option<FrameTruth>), ClipFrameError> {
    let index = rep.frame.checked_sub(first_frame).filter(|i| *i < frames.len());
    let outside = ClipFrameError::OutsideClip { frame: rep.frame, first: first_frame, end: first_frame + frames.len() };
    let index = index.ok_or(outside)?;
    Ok((frames[index].clone(), truth.map(|t| t[index].clone())))
}

/// What deriving a [`ClipFrame`] needs of the case: mesh, weights and the clip's time steps.
pub(super) struct Deriver<'a> {
    pub(super) case: &'a Case,
    pub(super) dofs: DofMap,
    pub(super) weights: Weights,
    /// element length [m]
    pub(super) h: f64,
    /// frame interval of the inverse problem's Λω term [s]
    pub(super) dt: f64,
    /// the clip's time step [s] (frame times)
    pub(super) dt_s: f64,
}

impl Deriver<'_> {
    /// A converged frame in space coordinates with everything its consumers need (on the
    /// output thread).
    pub(super) fn derive(&self, c: Converged) -> Result<ClipFrame, ClipFrameError> {
        let Converged { report: rep, u, adjoint, chart, previous, state, data, truth } = c;
        let (dofs, w8) = (&self.dofs, &self.weights);
        let nodes = NodalState { chart, ..NodalState::from_vector(&self.case.mesh, &u) };
        let (force, torque): (Vec<_>, Vec<_>) = (0..nodes.s.len())
            .map(|i| {
                let (xh, ah) = (dofs.get(&adjoint, i, Field::X), dofs.get(&adjoint, i, Field::Alpha));
                (xh / w8.lambda_f, ah / w8.lambda_l)
            })
            .unzip();
        let kappa = nodes.element_curvature();
        let resultants = nodes.resultants(&self.case.props, self.case.quadrature, None);
        let k2: Vec<f64> = kappa.iter().map(|(_, k)| k[1]).collect();
        // The data's curvature in the plane normal to the chart's axis (exactly the x–z
        // curvature for an x–z clip; rotates with the data, R5).
        let in_chart: Vec<Vector3<f64>> = data.iter().map(|x| chart.to_chart(x)).collect();
        let kd = planar_xz_curvature(&in_chart, self.h);
        let truth_frame = match &truth {
            Some(ft) => Some(truth_frame(&nodes, &kappa, &data, ft)?),
            None => None,
        };
        let omega: Option<Vec<Vector3<f64>>> = previous
            .as_ref()
            .map(|prev| nodes.alpha.iter().zip(prev).map(|(a, p)| angular_velocity(a, p, self.dt)).collect());
        let roughness = (sign_alternation(&k2), sign_alternation(&kd));
        Ok(ClipFrame {
            report: rep,
            time_s: rep.frame as f64 * self.dt_s,
            nodes,
            controls: Controls { force, torque },
            data,
            omega,
            elements: ElementFields { kappa, resultants },
            planar: PlanarCurvature { kappa2: k2, data_kappa: kd, roughness },
            truth: truth_frame,
            record: FrameRecord { report: rep, chart, state, adjoint, previous },
        })
    }
}

/// A recovered frame against its ground truth `ft` (`kappa`: the element-midpoint curvature).
fn truth_frame(
    nodes: &NodalState,
    kappa: &[(f64, Vector3<f64>)],
    data: &[Vector3<f64>],
    ft: &FrameTruth,
) -> Result<TruthFrame, ClipError> {
    let q: Vec<Matrix3<f64>> = nodes.alpha.iter().map(|a| nodes.chart.rotation(a)).collect();
    let kn = nodal_curvature(kappa);
    let c = compare_frame(data, ft, &RecoveredFrame { x: &nodes.x, q: &q, kappa: &kn }, TRUTH_SKIP_NODES)?;
    let twist = ft.kappa.iter().map(|k| k.z).sum::<f64>() / ft.kappa.len() as f64;
    let bend = |k: &Vector3<f64>| k.x * k.x + k.y * k.y;
    Ok(TruthFrame {
        roll_rad: ft.roll_rad,
        twist_per_m: twist,
        comparison: c,
        bending_true: ft.kappa.iter().map(bend).collect(),
        bending_recovered: kn.iter().map(bend).collect(),
    })
}
