//! One converged frame of a clip derived on the output thread of [`super::clip::run_clip`]
//! from what the solve hands over ([`Converged`]) into the engine-neutral
//! [`ClipFrame`] (`crate::engine::common::clip_frame`).
use nalgebra::{DVector, Matrix3, Vector3};

use crate::case::Case;
use crate::clip::synthetic::{compare_frame, FrameTruth, RecoveredFrame};
use crate::clip::ClipError;
use crate::engine::common::clip_frame::{
    nodal_curvature, planar_xz_curvature, sign_alternation, ClipFrame, Controls, ElementFields, FrameRecord,
    PlanarCurvature, TruthFrame, TRUTH_SKIP_NODES,
};
use crate::engine::common::result::NodalState;
use crate::model::chart::Chart;
use crate::model::mesh::{DofMap, Field};
use crate::model::rotation::Angles;
use crate::solve::inverse::measures::angular_velocity;
use crate::solve::inverse::Weights;
use crate::solve::sequence::FrameReport;

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
