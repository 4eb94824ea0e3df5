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
    /// absent with `cross_section.shape = "stiffness"` (D24)
    pub(super) material: Option<RawMaterial>,
    pub(super) cross_section: RawSection,
    #[serde(default)]
    pub(super) loads: RawLoads,
    pub(super) solver: RawSolver,
    pub(super) time: Option<RawTime>,
    /// path following (`solver.continuation = "arc_length"`, D25)
    pub(super) arc_length: Option<RawArcLength>,
    /// the ends of the rod (D22); default clamped at s = 0, free at s = L
    #[serde(default)]
    pub(super) ends: RawEnds,
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
    /// recordings: the unit of the positions, "m", "mm", "um" or "px" (a CSV header's suffix
    /// says it too)
    pub(super) unit: Option<String>,
    /// recordings in pixels: metres per pixel
    pub(super) scale_m_per_px: Option<Scalar>,
    /// WCON recordings with several worms: the `id` of the one to reconstruct
    pub(super) worm_id: Option<String>,
    /// the tracking noise per coordinate [m], stated instead of estimated from the recording
    pub(super) noise_m: Option<Scalar>,
    /// the largest curvature a frame may have before it is re-solved from its data or flagged
    /// [1/m]; default the inverse of the cross-section's radius
    pub(super) max_curvature_per_m: Option<Scalar>,
    /// the unit normal of the plane a planar recording lies in (set when a 2D recording, or one
    /// with a constant coordinate, is read)
    pub(super) data_plane: Option<[f64; 3]>,
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

/// `[reference]`: an analytic theory (`kind`), published values (`[[reference.values]]`), or both.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawReference {
    pub(super) kind: Option<RawReferenceKind>,
    /// `tip_loaded_cantilever`: the magnitude of the dead end force [N]
    pub(super) force_n: Option<Scalar>,
    #[serde(default)]
    pub(super) values: Vec<RawPublished>,
    /// the shorter variant `cargo test` runs: keys of `cosserat sweep --set` and their values
    #[serde(default)]
    pub(super) short: BTreeMap<String, super::published::Setting>,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(super) enum RawReferenceKind {
    /// Planar cantilever clamped at s = 0 under a dead end force of magnitude `force_n` along −e2.
    TipLoadedCantilever,
}

/// One `[[reference.values]]` row.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPublished {
    pub(super) quantity: String,
    pub(super) value: Scalar,
    pub(super) tolerance_abs: Option<Scalar>,
    pub(super) tolerance_rel: Option<Scalar>,
    pub(super) source: Option<String>,
    pub(super) note: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRod {
    pub(super) length_m: Scalar,
    pub(super) elements: usize,
    /// position of s = 0 [m] (D20)
    pub(super) start_position_m: Option<[Scalar; 3]>,
    /// d3 at s = 0, space components (D20)
    pub(super) start_d3: Option<[Scalar; 3]>,
    /// d1 at s = 0, space components (D20)
    pub(super) start_d1: Option<[Scalar; 3]>,
    /// intrinsic curvature and twist κ̄(s) [1/m], body frame, expressions of s (D20)
    pub(super) intrinsic_curvature_per_m: Option<[Scalar; 3]>,
    /// the singular axis of the angle chart (D21)
    pub(super) chart_axis: Option<[Scalar; 3]>,
    /// with `length_m = "from_data"`: the body length [m] that `[cross_section]` describes;
    /// each recording's section is scaled by its measured length over this
    pub(super) section_length_m: Option<Scalar>,
}

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawEnds {
    pub(super) start: Option<RawEnd>,
    pub(super) end: Option<RawEnd>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawEnd {
    pub(super) kind: RawEndKind,
    /// pinned ends: "free" (default) or "held" (the roll α about d3)
    pub(super) twist: Option<RawTwist>,
    /// a moving end's displacement [m], space components
    pub(super) displacement_m: Option<[Scalar; 3]>,
    /// a moving clamp's rotation vector [rad], space components
    pub(super) rotation_rad: Option<[Scalar; 3]>,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(super) enum RawEndKind {
    Clamped,
    Pinned,
    Free,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(super) enum RawTwist {
    Free,
    Held,
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
    Circle {
        radius_m: Scalar,
    },
    Rectangle {
        width_m: Scalar,
        height_m: Scalar,
    },
    /// the stiffnesses and inertias themselves (D24)
    Stiffness {
        ea_n: Scalar,
        ga1_n: Scalar,
        ga2_n: Scalar,
        ei1_nm2: Scalar,
        ei2_nm2: Scalar,
        gj_nm2: Scalar,
        rho_a_kg_per_m: Option<Scalar>,
        rho_i1_kg_m: Option<Scalar>,
        rho_i2_kg_m: Option<Scalar>,
        rho_j_kg_m: Option<Scalar>,
    },
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
    /// point loads at any s (`[[loads.point]]`, D23)
    #[serde(default)]
    pub(super) point: Vec<RawPointLoad>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPointLoad {
    pub(super) s_m: Scalar,
    pub(super) force_n: Option<[Scalar; 3]>,
    pub(super) torque_nm: Option<[Scalar; 3]>,
    /// "global" (dead, default) or "local" (follower)
    pub(super) frame: Option<RawFrame>,
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
    /// static: "load_steps" (default) or "arc_length" (D25)
    pub(super) continuation: Option<RawContinuation>,
    /// the residual certificate a converged result must meet (docs/certificate.md)
    pub(super) certificate_tolerance: Option<f64>,
    /// static: the lowest critical load factors to compute with their modes (D27)
    pub(super) buckling_modes: Option<usize>,
    /// static: the lowest natural frequencies of the rod about its rest state (D28)
    pub(super) vibration_modes: Option<usize>,
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

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(super) enum RawContinuation {
    LoadSteps,
    ArcLength,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawArcLength {
    pub(super) steps: usize,
    pub(super) initial_increment: f64,
    pub(super) max_load_factor: Option<Scalar>,
    pub(super) min_increment: Option<f64>,
    pub(super) max_increment: Option<f64>,
    pub(super) target_iterations: Option<usize>,
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
