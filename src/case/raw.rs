//! The serde layer of a case file: the TOML tables as written, before any validation
//! (`deny_unknown_fields` everywhere). Numbers may be TOML numbers or strings holding an
//! expression of the case's `[constants]` ([`Scalar`]).
use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::Deserialize;

#[derive(Debug, Deserialize, Clone)]
#[serde(untagged)]
pub(super) enum Scalar {
    Number(f64),
    Text(String),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCase {
    pub(super) description: String,
    #[serde(default)]
    pub(super) constants: BTreeMap<String, Scalar>,
    pub(super) rod: RawRod,
    pub(super) material: RawMaterial,
    pub(super) cross_section: RawSection,
    #[serde(default)]
    pub(super) loads: RawLoads,
    pub(super) solver: RawSolver,
    pub(super) time: Option<RawTime>,
    #[serde(default)]
    pub(super) compare: RawCompare,
    pub(super) reference: Option<RawReference>,
    /// inverse cases: the forward solve that generates the data from `[loads]`
    pub(super) data: Option<RawData>,
    /// inverse cases: the weights of eq. (41)
    pub(super) inverse: Option<RawInverse>,
    /// inverse cases on a recorded clip (instead of `[data]`)
    pub(super) clip: Option<RawClip>,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(super) enum RawClipKind {
    Kymogram,
    Recording,
    #[serde(rename = "roll_3d")]
    Roll3d,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawClip {
    pub(super) kind: RawClipKind,
    pub(super) file: PathBuf,
    pub(super) frame_interval_s: Scalar,
    /// `[first, end)` frame range
    pub(super) frames: Option<[usize; 2]>,
    pub(super) min_cos_beta: f64,
    /// "previous_frame" (default) or "data_guess"
    #[serde(default)]
    pub(super) start: RawStart,
    /// "rebased" (default) or "global_euler"
    #[serde(default)]
    pub(super) rotation: RawRotation,
    /// kymograms: "xz" (default) or "xy"
    #[serde(default)]
    pub(super) plane: RawPlane,
    /// rotation vector [rad] applied to every frame after the placement
    pub(super) orientation: Option<[f64; 3]>,
    /// first frame's roll gauge vector (before `orientation`)
    pub(super) gauge: Option<[f64; 3]>,
    /// roll_3d: total roll of the bending plane over the clip [rad]
    pub(super) roll_total_rad: Option<Scalar>,
    /// roll_3d: constant twist κ3 [rad/m]
    pub(super) twist_per_m: Option<Scalar>,
    /// roll_3d: number of frames to build
    pub(super) clip_frames: Option<usize>,
    /// roll_3d: integration steps per element
    pub(super) substeps: Option<usize>,
    /// fit-quality gate (`solve::fit`): noise levels a misfit may reach
    pub(super) gate_noise_multiple: Option<f64>,
    /// fit-quality gate: position misfit [body lengths] never flagged
    pub(super) gate_position: Option<f64>,
    /// fit-quality gate: tangent misfit never flagged
    pub(super) gate_tangent: Option<f64>,
    /// what marks a node that was not tracked in a recording (`clip::missing`); absent: a NaN
    /// is an error
    pub(super) missing: Option<RawMissing>,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(super) enum RawMissing {
    Nan,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub(super) enum RawRotation {
    #[default]
    Rebased,
    GlobalEuler,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub(super) enum RawPlane {
    #[default]
    Xz,
    Xy,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub(super) enum RawStart {
    #[default]
    PreviousFrame,
    DataGuess,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawData {
    #[serde(default = "default_method")]
    pub(super) method: RawMethod,
    pub(super) relaxation: Option<f64>,
    pub(super) tolerance: f64,
    pub(super) max_iterations: usize,
    #[serde(default = "one")]
    pub(super) continuation_steps: usize,
    /// the residual certificate a converged result must meet (docs/certificate.md)
    pub(super) certificate_tolerance: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawInverse {
    pub(super) lambda_g: Scalar,
    pub(super) lambda_f: Scalar,
    pub(super) lambda_l: Scalar,
    pub(super) lambda_d: Scalar,
    pub(super) lambda_kappa: [Scalar; 3],
    #[serde(default)]
    pub(super) lambda_omega: Option<[Scalar; 3]>,
    pub(super) frame_interval_s: Option<Scalar>,
    #[serde(default)]
    pub(super) alpha0_rad: Option<Scalar>,
    #[serde(default)]
    pub(super) stabilisation: Option<Scalar>,
    /// how λg is chosen: as given, or from the recording's noise (`docs/noise.md`)
    #[serde(default)]
    pub(super) weights: super::WeightsRule,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "snake_case")]
pub(super) enum RawReference {
    /// Planar cantilever clamped at s = 0 under a dead end force of magnitude `force_n` along −e2.
    TipLoadedCantilever { force_n: Scalar },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRod {
    pub(super) length_m: Scalar,
    pub(super) elements: usize,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMaterial {
    pub(super) young_modulus_pa: Scalar,
    pub(super) shear_modulus_pa: Scalar,
    pub(super) density_kg_m3: Option<Scalar>,
    pub(super) shear_correction: Scalar,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, tag = "shape", rename_all = "snake_case")]
pub(super) enum RawSection {
    Circle { radius_m: Scalar },
    Rectangle { width_m: Scalar, height_m: Scalar },
}

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawLoads {
    #[serde(default = "default_frame")]
    pub(super) frame: RawFrame,
    pub(super) force_n_per_m: Option<[Scalar; 3]>,
    pub(super) torque_nm_per_m: Option<[Scalar; 3]>,
    pub(super) end_force_n: Option<[Scalar; 3]>,
    pub(super) end_torque_nm: Option<[Scalar; 3]>,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub(super) enum RawFrame {
    #[default]
    Global,
    Local,
}
pub(super) fn default_frame() -> RawFrame {
    RawFrame::Global
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(super) enum RawAnalysis {
    Static,
    Dynamic,
    Inverse,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(super) enum RawMethod {
    FixedPoint,
    Newton,
}

#[derive(Debug, Deserialize, Clone, Copy)]
#[serde(rename_all = "snake_case")]
pub(super) enum RawQuadrature {
    Selective,
    Full,
    Reduced,
    Midpoint,
    Gauss2,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSolver {
    pub(super) analysis: RawAnalysis,
    #[serde(default = "default_method")]
    pub(super) method: RawMethod,
    #[serde(default = "default_quadrature")]
    pub(super) quadrature: RawQuadrature,
    pub(super) relaxation: Option<f64>,
    pub(super) tolerance: f64,
    pub(super) max_iterations: usize,
    #[serde(default = "one")]
    pub(super) continuation_steps: usize,
    /// inverse Newton: the fixed point runs until this relative change before Newton starts
    pub(super) warm_start_tolerance: Option<f64>,
    /// the residual certificate a converged result must meet (docs/certificate.md)
    pub(super) certificate_tolerance: Option<f64>,
}
pub(super) fn one() -> usize {
    1
}
pub(super) fn default_method() -> RawMethod {
    RawMethod::FixedPoint
}
pub(super) fn default_quadrature() -> RawQuadrature {
    RawQuadrature::Selective
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTime {
    pub(super) end_s: Scalar,
    pub(super) steps: usize,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCompare {
    pub(super) frames: Option<usize>,
    pub(super) displacement_rel: Option<f64>,
    pub(super) angles_rel: Option<f64>,
    pub(super) metric_rel: Option<f64>,
    pub(super) metric_abs: Option<f64>,
    pub(super) iterations_abs: Option<f64>,
    pub(super) adjoint_rel: Option<f64>,
    pub(super) reason: Option<String>,
}
