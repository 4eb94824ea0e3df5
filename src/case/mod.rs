//! Case files: TOML → serde structs ([`raw`], `deny_unknown_fields`) → one validated, typed
//! [`Case`] ([`validate`]) that holds the solvers' own params types.
//!
//! Numbers may be written as TOML numbers or as strings holding an expression of the case's
//! `[constants]` (e.g. `radius_m = "L/40"`); load components are expressions of the reference
//! arc length `s` [m], time `t` [s] and the constants (see `crate::expr`). Solvers never see
//! TOML: they receive the params built here. A sweep sets a value in the case file's tables
//! and validates the whole case again ([`sweep`]), so every setting has one validator and one
//! translation to its solver.
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Vector3};

mod file;
pub mod published;
mod raw;
pub mod sweep;
mod toml_error;
mod validate;

use crate::clip::length::BodyLength;
use crate::clip::synthetic::{RollClipParams, TimeMapping};
use crate::clip::{ClipPlane, KymogramParams};
use crate::model::geometry::Rod;
use crate::model::loads::Loads;
use crate::model::material::{CrossSection, Material, RodProperties, Stiffnesses};
use crate::model::mesh::{Mesh, QuadratureScheme};
use crate::recorded::fit::FitGate;
use crate::solve::dynamics::DynamicParams;
use crate::solve::inverse::{InverseParams, Records};
use crate::solve::sequence::{FrameStart, RotationTreatment, SequenceParams};
use crate::solve::statics::StaticParams;
use crate::solve::Problem;
use published::Published;
use validate::Validator;
pub use validate::MAX_ELEMENTS;

/// Errors at the case-file boundary. Every variant names the file; `Invalid` names the key.
#[derive(Debug, thiserror::Error)]
pub enum CaseError {
    #[error("cannot read case file {path}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Syntax { path: PathBuf, message: String },
    #[error("{path}: key `{key}`: {reason}")]
    Invalid { path: PathBuf, key: String, reason: String },
    #[error("{}", crate::file_kind::not_regular_text(path, "case file", *kind))]
    NotRegular { path: PathBuf, kind: crate::file_kind::FileKind },
    #[error("{path}: case file {}", file::too_large_text(*.size))]
    TooLarge {
        path: PathBuf,
        /// the size of a regular file; `None`: more than the cap was read from a stream
        size: Option<u64>,
    },
}

/// Largest case file read [bytes]: 1 MiB. The committed cases and audit specs are 1–11 KiB
/// (the largest, `cases/paper/sec6_worm.toml`, 11 037 bytes), so the cap is ~100× above any
/// Is `text` a case file (TOML with `[rod]` and `[solver]`)? For the readers of other files (audit
/// and study specs) to say "this is a case" rather than name the first key they do not know.
pub fn is_case_text(text: &str) -> bool {
    text.parse::<toml::Table>().is_ok_and(|t| t.contains_key("rod") && t.contains_key("solver"))
}

/// The file a case named `-` is read from (`cosserat run - < case.toml`).
pub const STANDARD_INPUT: &str = "/dev/stdin";

/// real case and stops `cosserat run /dev/zero` at once instead of reading forever.
pub const CASE_FILE_CAP_BYTES: u64 = 1 << 20;

/// The word of `rod.length_m` that asks for the body length of the recording.
pub const FROM_DATA: &str = "from_data";

/// The mesh length of a case whose `rod.length_m = "from_data"` is not resolved yet [m]: a
/// placeholder that nothing solves with (`engine::input::clip_files::load_clip` refuses such a case).
pub const FROM_DATA_PLACEHOLDER_M: f64 = 1.0;

/// Where the rod length `mesh.length_m` comes from (`rod.length_m`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RodLength {
    /// a number or an expression of the case file
    Given,
    /// `"from_data"`: the body length of the recording, estimated when it is read
    /// (`engine::input::resolve::resolve_recording`, `clip::length`); `None` until then, when the mesh's
    /// length is [`FROM_DATA_PLACEHOLDER_M`]
    FromData(Option<BodyLength>),
}

/// Where the centreline data of an inverse case come from.
#[derive(Clone, Debug, PartialEq)]
pub enum DataSource {
    /// a static forward solve of the case's own `[loads]` (synthetic data, I7)
    Forward(StaticParams),
    /// a recorded or synthetic clip (`[clip]`), solved frame by frame
    Clip(Box<ClipSource>),
}

/// The `roll_3d` settings of a synthetic clip (`crate::clip::synthetic`); its nodes, length
/// and Δt are the mesh's and the clip's.
#[derive(Clone, Debug, PartialEq)]
pub struct SyntheticClip {
    pub frames: usize,
    pub roll_total_rad: f64,
    pub twist_per_m: f64,
    pub time_mapping: TimeMapping,
    pub substeps: usize,
}

impl SyntheticClip {
    /// The generator's parameters on `mesh` with frame interval `dt_s` [s].
    pub fn params(&self, mesh: &Mesh, dt_s: f64) -> RollClipParams {
        RollClipParams {
            length_m: mesh.length_m,
            nodes: mesh.nodes(),
            frames: self.frames,
            dt_s,
            roll_total_rad: self.roll_total_rad,
            twist_per_m: self.twist_per_m,
            time_mapping: self.time_mapping,
            substeps: self.substeps,
        }
    }
}

/// File format of a clip.
#[derive(Clone, Debug, PartialEq)]
pub enum ClipKind {
    /// joint-angle kymogram (.npy, frames × joint angles [rad]) of the `elegansbot` package,
    /// turned into a spline centreline of the rod's length with `elements + 1` nodes, placed
    /// in the `plane`
    Kymogram,
    /// positions: CSV `frame,node,x_m,y_m,z_m` or NPY frames × nodes × 3 [m]
    Recording,
    /// the 3D ground-truth clip built from a kymogram's curvature with a rolling bending plane
    /// and a twist (`crate::clip::synthetic`); `file` is the omega-turn kymogram
    Roll3d(SyntheticClip),
}

/// A clip and how its frames are solved.
#[derive(Clone, Debug, PartialEq)]
pub struct ClipSource {
    pub kind: ClipKind,
    /// resolved against the case file's directory
    pub file: PathBuf,
    /// `[first, end)` frame range, all frames if `None`
    pub frames: Option<(usize, usize)>,
    /// chart guard: stop when |cos β| < this at any node (`solve::sequence`)
    pub min_cos_beta: f64,
    /// initial iterate of the frames after the first (D13)
    pub start: FrameStart,
    /// angle chart per frame (`docs/rotation.md`)
    pub rotation: RotationTreatment,
    /// where the frames are placed in space (`clip.plane`, `clip.orientation`, `clip.gauge`)
    pub placement: ClipPlacement,
    /// the fit-quality gate (`clip.gate_*`, `solve::fit`)
    pub gate: FitGate,
    /// what marks an untracked node of a recording (`clip.missing`, `clip::missing`)
    pub missing: crate::clip::missing::MissingData,
    /// how a recording's file is read (its unit, its worm, its plane)
    pub recording: RecordingKeys,
}

/// The keys of a recording's file (`engine::input::recording`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RecordingKeys {
    /// `clip.unit` and `clip.scale_m_per_px`
    pub units: crate::clip::recording::UnitSpec,
    /// `clip.worm_id`: the worm of a WCON file with several
    pub worm_id: Option<String>,
    /// `clip.data_plane`: the unit normal of a planar recording's plane in space coordinates
    /// (after `clip.orientation`); set when a planar recording is read
    /// (`engine::input::resolve::resolve_recording`)
    pub data_plane: Option<Vector3<f64>>,
}

/// Where a clip's frames are placed in space, and the gauge vector placed with them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipPlacement {
    /// plane of a kymogram's placement (`crate::clip`)
    pub plane: ClipPlane,
    /// rigid rotation applied to every frame after the placement (`clip.orientation`, a
    /// rotation vector [rad]; identity if absent)
    pub orientation: Matrix3<f64>,
    /// unit gauge vector of the first frame in space coordinates (R7): `clip.gauge` rotated by
    /// `orientation`; default the placement plane's normal (e2 for x–z, e3 for x–y)
    pub gauge: Vector3<f64>,
}

/// An inverse analysis (Problem 2, eq. 61): the solver's params and the data.
#[derive(Clone, Debug, PartialEq)]
pub struct InverseSettings {
    pub params: InverseParams,
    pub data: DataSource,
    /// how the tracking weight λg of `params` is chosen
    pub weights_rule: WeightsRule,
}

/// `[inverse] weights`: how the tracking weight λg is chosen (`docs/noise.md`, N2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum WeightsRule {
    /// `lambda_g` as the case gives it (the paper's Table 1: 1e9)
    #[default]
    Fixed,
    /// per recording, by the discrepancy principle: the fit's RMS distance to the data per
    /// coordinate equals the noise level estimated from the recording; `lambda_g` is the
    /// largest value allowed (clip cases only)
    Auto,
}

/// What is solved.
#[derive(Clone, Debug, PartialEq)]
pub enum Analysis {
    /// Static solve; `continuation_steps` ≥ 1: all loads ramped by k/steps, each step solved
    /// from the last.
    Static(StaticParams),
    /// Appendix A time stepping (D6), Newton per step.
    Dynamic(DynamicParams),
    /// Recover α, f, l from a centreline: a forward solution of the case's `[loads]`, or a clip.
    Inverse(InverseSettings),
}

/// The Rust–FreeFEM comparison of a case (`[compare]`, docs/decisions.md D14). Tolerances are
/// derived from the case's measured conditioning; a value here overrides the derived one for
/// its group of rows and needs a `reason`.
#[derive(Clone, Debug, PartialEq)]
pub struct CompareSpec {
    /// clip cases: frames compared by default (`--frames` overrides)
    pub frames: usize,
    pub overrides: CompareOverrides,
    /// why the overrides are there (required with any of them)
    pub reason: Option<String>,
}

/// Tolerances that replace the derived ones (D14), each for its group of rows.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CompareOverrides {
    /// max node-wise |Δ(x − x0)| / max |x − x0|, and the tip history
    pub displacement_rel: Option<f64>,
    /// max node-wise |Δα| / max |α|
    pub angles_rel: Option<f64>,
    /// scalar metrics: |Δ| ≤ metric_rel·|rust| + metric_abs
    pub metric_rel: Option<f64>,
    pub metric_abs: Option<f64>,
    /// allowed difference of iteration counts
    pub iterations_abs: Option<f64>,
    /// inverse cases: max node-wise |Δ(x̂, α̂)| / max |(x̂, α̂)| (per field)
    pub adjoint_rel: Option<f64>,
}

/// Clip frames compared when neither `[compare] frames` nor `--frames` says: enough for the
/// warm start, its linear predictor and a change of chart to be exercised.
pub const DEFAULT_COMPARE_FRAMES: usize = 10;

/// Independent theory a case is checked against (metrics `*_rel_error` in `metrics.json`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reference {
    /// Eq. (63), the Kirchhoff elastica and the planar Reissner rod for a dead end force of
    /// magnitude `force_n` [N] along −e2 (see `engine::metrics`).
    TipLoadedCantilever { force_n: f64 },
}

/// A validated case.
#[derive(Clone, Debug)]
pub struct Case {
    pub name: String,
    /// where the case comes from: its file, text and named constants
    pub origin: CaseOrigin,
    pub mesh: Mesh,
    /// how the rod was given: its length's source and its material
    pub rod: RodGiven,
    pub section: Section,
    pub props: RodProperties,
    pub quadrature: QuadratureScheme,
    pub loads: Loads,
    pub analysis: Analysis,
    /// what the case is checked against: FreeFEM and independent theory
    pub checks: CaseChecks,
}

/// What a [`Case`] is checked against.
#[derive(Clone, Debug, PartialEq)]
pub struct CaseChecks {
    /// the Rust–FreeFEM comparison (`[compare]`, D14)
    pub compare: CompareSpec,
    /// independent theory (`[reference]`), if any
    pub reference: Option<Reference>,
    /// published values (`[[reference.values]]`) and the test's shorter variant
    pub published: Published,
}

/// Where a [`Case`] comes from.
#[derive(Clone, Debug)]
pub struct CaseOrigin {
    pub description: String,
    pub source: Option<PathBuf>,
    /// the SHA-256 (hex) of the case file's bytes as they were read (also of a case piped in)
    pub source_sha256: Option<String>,
    pub constants: BTreeMap<String, f64>,
    /// the case file's tables and the path it was validated with, for [`sweep`]'s overrides
    pub(crate) raw: Option<(toml::Table, PathBuf)>,
}

/// How the rod of a [`Case`] was given.
#[derive(Clone, Debug)]
pub struct RodGiven {
    /// where `mesh.length_m` comes from
    pub length: RodLength,
    /// the material of a circle or rectangle section; `None` for a section given by its
    /// stiffnesses (D24)
    pub material: Option<Material>,
    /// whether the case file gave the density (`material.density_kg_m3`, or the inertias of a
    /// stiffness section): static and inverse analyses run with 1 kg/m³ when it does not,
    /// their equations never use it
    pub(crate) density_given: bool,
    /// the reference configuration, chart and ends of a forward case beyond the paper's rod
    /// (D20–D22); `None`: straight along e3 from the origin, clamped at s = 0, free at s = L
    pub general: Option<Rod>,
}

/// The cross section of a [`Case`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Section {
    /// a circle or rectangle of the case's material
    Shape(CrossSection),
    /// the stiffnesses and inertias themselves (D24)
    Stiffness(Stiffnesses),
}

impl Case {
    /// The case file's tables as validated (with any overrides applied), if it was read from
    /// TOML.
    pub fn toml_table(&self) -> Option<&toml::Table> {
        self.origin.raw.as_ref().map(|(t, _)| t)
    }

    /// Read and validate a case file (at most [`CASE_FILE_CAP_BYTES`]).
    pub fn from_file(path: &Path) -> Result<Case, CaseError> {
        // `-`: the standard input, as the shell's convention has it
        let path = if path == Path::new("-") { Path::new(STANDARD_INPUT) } else { path };
        let text = file::read_case_file(path)?;
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("case").to_string();
        let mut case = Case::from_toml(&text, &name, path)?;
        case.origin.source = Some(path.to_path_buf());
        case.origin.source_sha256 = Some(file::sha256_hex(text.as_bytes()));
        Ok(case)
    }

    /// Parse and validate TOML text; `path` names the file in messages and resolves relative
    /// clip files.
    pub fn from_toml(text: &str, name: &str, path: &Path) -> Result<Case, CaseError> {
        let syntax = |e: toml::de::Error| CaseError::Syntax {
            path: path.to_path_buf(),
            message: toml_error::describe(text, &e),
        };
        let raw: raw::RawCase = toml::from_str(text).map_err(syntax)?;
        let mut case = Validator::new(path).case(raw, name)?;
        case.short_variant_keys(path)?;
        case.origin.raw = Some((toml::from_str(text).map_err(syntax)?, path.to_path_buf()));
        Ok(case)
    }

    /// The discrete forward problem of the case (`[rod]`, `[material]`, `[cross_section]`,
    /// `[loads]`, `solver.quadrature`).
    pub fn problem(&self) -> Problem<'_> {
        Problem::new(self.mesh, self.props, self.quadrature, &self.loads).on_rod(self.rod.general.as_ref())
    }

    /// The same dynamic case cut to its first `steps` time steps (same Δt): the short but real
    /// subset that `cargo test` runs through FreeFEM. Other cases are returned unchanged.
    pub fn time_prefix(&self, steps: usize) -> Case {
        let mut c = self.clone();
        if let Analysis::Dynamic(p) = &mut c.analysis {
            let k = steps.min(p.steps).max(1);
            p.end_time_s = p.end_time_s * k as f64 / p.steps as f64;
            p.steps = k;
        }
        c
    }

    /// Is this a dynamic case?
    pub fn is_dynamic(&self) -> bool {
        matches!(self.analysis, Analysis::Dynamic(_))
    }

    /// The tolerance of the residual certificate a converged result must meet
    /// (`solver.certificate_tolerance`, `docs/certificate.md`).
    pub fn certificate_tolerance(&self) -> f64 {
        match &self.analysis {
            Analysis::Static(p) => p.certificate_tolerance,
            Analysis::Dynamic(p) => p.certificate_tolerance,
            Analysis::Inverse(s) => s.params.certificate_tolerance,
        }
    }

    /// The settings of an inverse case.
    pub fn inverse(&self) -> Option<&InverseSettings> {
        match &self.analysis {
            Analysis::Inverse(s) => Some(s),
            _ => None,
        }
    }

    /// The body length estimated from the recording (`rod.length_m = "from_data"`, resolved).
    pub fn body_length(&self) -> Option<BodyLength> {
        match self.rod.length {
            RodLength::FromData(b) => b,
            RodLength::Given => None,
        }
    }

    /// The clip of a clip case.
    /// Whether the case file gave `material.density_kg_m3` ([`Case::material`] holds 1 kg/m³
    /// otherwise, which only a static or inverse analysis may use: their equations never
    /// involve the density).
    pub fn density_given(&self) -> bool {
        self.rod.density_given
    }

    pub fn clip(&self) -> Option<&ClipSource> {
        match &self.inverse()?.data {
            DataSource::Clip(c) => Some(c),
            DataSource::Forward(_) => None,
        }
    }

    /// The static forward case that generates an inverse case's data (same rod and loads).
    pub fn data_case(&self) -> Option<Case> {
        let DataSource::Forward(d) = self.inverse()?.data else { return None };
        let mut c = self.clone();
        c.analysis = Analysis::Static(d);
        Some(c)
    }

    /// How a kymogram clip becomes centrelines on this case's mesh.
    pub fn kymogram_params(&self) -> Option<KymogramParams> {
        let (inv, clip) = (self.inverse()?, self.clip()?);
        Some(KymogramParams {
            length_m: self.mesh.length_m,
            nodes: self.mesh.nodes(),
            dt_s: inv.params.frame_interval_s,
            plane: clip.placement.plane,
            scale_to_length: true,
        })
    }

    /// The generator's parameters of a `roll_3d` clip on this case's mesh.
    pub fn roll_clip_params(&self) -> Option<RollClipParams> {
        let (inv, clip) = (self.inverse()?, self.clip()?);
        match &clip.kind {
            ClipKind::Roll3d(s) => Some(s.params(&self.mesh, inv.params.frame_interval_s)),
            _ => None,
        }
    }

    /// The clip solver's settings of a clip case.
    pub fn sequence_params(&self) -> Option<SequenceParams> {
        let (inv, clip) = (self.inverse()?, self.clip()?);
        Some(SequenceParams {
            inverse: inv.params,
            min_cos_beta: clip.min_cos_beta,
            frame_offset: clip.frames.map(|f| f.0).unwrap_or(0),
            start: clip.start,
            rotation: clip.rotation,
            gauge: clip.placement.gauge,
            records: Records::Every,
            gate: clip.gate,
            plane: clip.recording.data_plane,
        })
    }
}

/// All `*.toml` files of a directory, sorted by name.
pub fn case_files(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().map(|x| x == "toml").unwrap_or(false))
        .collect();
    v.sort();
    Ok(v)
}

#[cfg(test)]
mod tests;
