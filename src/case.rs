//! Case files: TOML → serde structs (`deny_unknown_fields`) → one validated, typed [`Case`].
//!
//! Numbers may be written as TOML numbers or as strings holding an expression of the case's
//! `[constants]` (e.g. `radius_m = "L/40"`); load components are expressions of the reference
//! arc length `s` [m], time `t` [s] and the constants (see `src/expr.rs`). Solvers never see
//! TOML: they receive the [`Case`] built here.
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::expr::Expr;
use crate::loads::{LoadFrame, Loads};
use crate::material::{CrossSection, Material, RodProperties};
use crate::mesh::{Mesh, QuadratureScheme};

/// Errors at the case-file boundary. Every variant names the file; `Invalid` names the key.
#[derive(Debug, thiserror::Error)]
pub enum CaseError {
    #[error("cannot read case file {path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{path}: {message}")]
    Syntax { path: PathBuf, message: String },
    #[error("{path}: key `{key}`: {reason}")]
    Invalid { path: PathBuf, key: String, reason: String },
}

// ---------------------------------------------------------------- raw (serde) layer

#[derive(Debug, Deserialize, Clone)]
#[serde(untagged)]
enum Scalar {
    Number(f64),
    Text(String),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCase {
    description: String,
    #[serde(default)]
    constants: BTreeMap<String, Scalar>,
    rod: RawRod,
    material: RawMaterial,
    cross_section: RawSection,
    #[serde(default)]
    loads: RawLoads,
    solver: RawSolver,
    time: Option<RawTime>,
    compare: RawCompare,
    reference: Option<RawReference>,
    /// inverse cases: the forward solve that generates the data from `[loads]`
    data: Option<RawData>,
    /// inverse cases: the weights of eq. (41)
    inverse: Option<RawInverse>,
    /// inverse cases on a recorded clip (instead of `[data]`)
    clip: Option<RawClip>,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
enum RawClipKind {
    Kymogram,
    Recording,
    #[serde(rename = "roll_3d")]
    Roll3d,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawClip {
    kind: RawClipKind,
    file: PathBuf,
    frame_interval_s: Scalar,
    /// `[first, end)` frame range
    frames: Option<[usize; 2]>,
    min_cos_beta: f64,
    /// "previous_frame" (default) or "data_guess"
    #[serde(default)]
    start: RawStart,
    /// "rebased" (default) or "global_euler"
    #[serde(default)]
    rotation: RawRotation,
    /// kymograms: "xz" (default) or "xy"
    #[serde(default)]
    plane: RawPlane,
    /// rotation vector [rad] applied to every frame after the placement
    orientation: Option<[f64; 3]>,
    /// first frame's roll gauge vector (before `orientation`)
    gauge: Option<[f64; 3]>,
    /// roll_3d: total roll of the bending plane over the clip [rad]
    roll_total_rad: Option<Scalar>,
    /// roll_3d: constant twist κ3 [rad/m]
    twist_per_m: Option<Scalar>,
    /// roll_3d: number of frames to build
    clip_frames: Option<usize>,
    /// roll_3d: integration steps per element
    substeps: Option<usize>,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
enum RawRotation {
    #[default]
    Rebased,
    GlobalEuler,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
enum RawPlane {
    #[default]
    Xz,
    Xy,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
enum RawStart {
    #[default]
    PreviousFrame,
    DataGuess,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawData {
    #[serde(default = "default_method")]
    method: RawMethod,
    relaxation: Option<f64>,
    tolerance: f64,
    max_iterations: usize,
    #[serde(default = "one")]
    continuation_steps: usize,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawInverse {
    lambda_g: Scalar,
    lambda_f: Scalar,
    lambda_l: Scalar,
    lambda_d: Scalar,
    lambda_kappa: [Scalar; 3],
    #[serde(default)]
    lambda_omega: Option<[Scalar; 3]>,
    frame_interval_s: Option<Scalar>,
    #[serde(default)]
    alpha0_rad: Option<Scalar>,
    #[serde(default)]
    stabilisation: Option<Scalar>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "snake_case")]
enum RawReference {
    /// Planar cantilever clamped at s = 0 under a dead end force of magnitude `force_n` along −e2.
    TipLoadedCantilever { force_n: Scalar },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRod {
    length_m: Scalar,
    elements: usize,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    young_modulus_pa: Scalar,
    shear_modulus_pa: Scalar,
    density_kg_m3: Option<Scalar>,
    shear_correction: Scalar,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, tag = "shape", rename_all = "snake_case")]
enum RawSection {
    Circle { radius_m: Scalar },
    Rectangle { width_m: Scalar, height_m: Scalar },
}

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawLoads {
    #[serde(default = "default_frame")]
    frame: RawFrame,
    force_n_per_m: Option<[Scalar; 3]>,
    torque_nm_per_m: Option<[Scalar; 3]>,
    end_force_n: Option<[Scalar; 3]>,
    end_torque_nm: Option<[Scalar; 3]>,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
enum RawFrame {
    #[default]
    Global,
    Local,
}
fn default_frame() -> RawFrame {
    RawFrame::Global
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
enum RawAnalysis {
    Static,
    Dynamic,
    Inverse,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
enum RawMethod {
    FixedPoint,
    Newton,
}

#[derive(Debug, Deserialize, Clone, Copy)]
#[serde(rename_all = "snake_case")]
enum RawQuadrature {
    Selective,
    Full,
    Reduced,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSolver {
    analysis: RawAnalysis,
    #[serde(default = "default_method")]
    method: RawMethod,
    #[serde(default = "default_quadrature")]
    quadrature: RawQuadrature,
    relaxation: Option<f64>,
    tolerance: f64,
    max_iterations: usize,
    #[serde(default = "one")]
    continuation_steps: usize,
    /// inverse Newton: the fixed point runs until this relative change before Newton starts
    warm_start_tolerance: Option<f64>,
}
fn one() -> usize {
    1
}
fn default_method() -> RawMethod {
    RawMethod::FixedPoint
}
fn default_quadrature() -> RawQuadrature {
    RawQuadrature::Selective
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTime {
    end_s: Scalar,
    steps: usize,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCompare {
    displacement_rel: f64,
    angles_rel: f64,
    metric_rel: f64,
    #[serde(default)]
    metric_abs: f64,
    #[serde(default)]
    iterations_abs: f64,
    adjoint_rel: Option<f64>,
}

// ---------------------------------------------------------------- validated layer

/// Static nonlinear solver (D5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StaticMethod {
    /// The paper's relaxed fixed point (§4, Remark 10) with relaxation w ∈ (0, 1].
    FixedPoint { relaxation: f64 },
    /// Newton with the exact Jacobian (Rust engine only).
    Newton,
}

/// Nonlinear solver of the inverse problem of one frame (`docs/inverse.md`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InverseMethod {
    /// The paper's scheme (eq. 61, Remark 10), relaxation w ∈ (0, 1]; FreeFEM mirrors it.
    FixedPoint { relaxation: f64 },
    /// Newton on the same discrete equations (Rust engine only, I8), started from the fixed
    /// point (relaxation `relaxation`) run until its relative change is ≤ `warm_start_tolerance`.
    Newton { relaxation: f64, warm_start_tolerance: f64 },
}

/// Regularisation weights of eq. (41).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InverseWeights {
    pub lambda_g: f64,
    pub lambda_f: f64,
    pub lambda_l: f64,
    pub lambda_d: f64,
    /// Λκ diagonal
    pub lambda_kappa: [f64; 3],
    /// Λω diagonal (frames after the first only, Remark 6)
    pub lambda_omega: [f64; 3],
}

/// Static forward solve that generates the data of an inverse case from its `[loads]` (I7).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DataSolve {
    pub method: StaticMethod,
    pub tolerance: f64,
    pub max_iterations: usize,
    pub continuation_steps: usize,
}

/// Where the centreline data of an inverse case come from.
#[derive(Clone, Debug, PartialEq)]
pub enum DataSource {
    /// a static forward solve of the case's own `[loads]` (synthetic data, I7)
    Forward(DataSolve),
    /// a recorded clip (`[clip]`), solved frame by frame
    Clip(ClipSource),
}

/// File format of a clip.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClipKind {
    /// joint-angle kymogram (.npy, frames × joint angles [rad]) of the `elegansbot` package,
    /// turned into a spline centreline of the rod's length with `elements + 1` nodes, placed
    /// in the x–z plane
    Kymogram,
    /// positions: CSV `frame,node,x_m,y_m,z_m` or NPY frames × nodes × 3 [m]
    Recording,
    /// the 3D ground-truth clip built from a kymogram's curvature with a rolling bending plane
    /// and a twist (`crate::clip::synthetic`); `file` is the omega-turn kymogram
    Roll3d,
}

/// A recorded clip.
#[derive(Clone, Debug, PartialEq)]
pub struct ClipSource {
    pub kind: ClipKind,
    /// resolved against the case file's directory
    pub file: PathBuf,
    /// Δt between frames [s]
    pub frame_interval_s: f64,
    /// `[first, end)` frame range, all frames if `None`
    pub frames: Option<(usize, usize)>,
    /// chart guard: stop when |cos β| < this at any node (`solve::sequence`)
    pub min_cos_beta: f64,
    /// initial iterate of the frames after the first (D13)
    pub start: crate::solve::sequence::FrameStart,
    /// angle chart per frame (`docs/rotation.md`)
    pub rotation: crate::solve::sequence::RotationTreatment,
    /// plane of a kymogram's placement (`crate::clip`)
    pub plane: crate::clip::ClipPlane,
    /// rigid rotation applied to every frame after the placement (`clip.orientation`, a
    /// rotation vector [rad]; identity if absent)
    pub orientation: nalgebra::Matrix3<f64>,
    /// unit gauge vector of the first frame in space coordinates (R7): `clip.gauge` rotated by
    /// `orientation`; default the placement plane's normal (e2 for x–z, e3 for x–y)
    pub gauge: nalgebra::Vector3<f64>,
    /// [`ClipKind::Roll3d`]: the synthetic clip's parameters (nodes and length are the mesh's)
    pub synthetic: Option<crate::clip::synthetic::RollClipParams>,
}

/// An inverse analysis (Problem 2, eq. 61): one frame of synthetic data, or a clip.
#[derive(Clone, Debug, PartialEq)]
pub struct InverseSettings {
    pub method: InverseMethod,
    /// stopping rule: relative change of (x, α) (D5) ≤ tolerance
    pub tolerance: f64,
    pub max_iterations: usize,
    pub weights: InverseWeights,
    /// Δt between frames [s] (Λω term)
    pub frame_interval_s: f64,
    /// Dirichlet value of the first angle at s = 0 [rad] (Remark 6: 0)
    pub alpha0_rad: f64,
    /// weight of the two-point rule in the λd term (docs/inverse.md, I11); 0 = the paper's element
    pub stabilisation: f64,
    pub data: DataSource,
}

/// What is solved.
#[derive(Clone, Debug, PartialEq)]
pub enum Analysis {
    /// `continuation_steps` ≥ 1: all loads ramped by k/steps, each step solved from the last.
    Static { method: StaticMethod, tolerance: f64, max_iterations: usize, continuation_steps: usize },
    /// Appendix A time stepping (D6), Newton per step.
    Dynamic { end_time_s: f64, steps: usize, tolerance: f64, max_iterations: usize },
    /// Recover α, f, l from the centreline of a forward solution of the case's `[loads]`.
    Inverse(InverseSettings),
}

/// Rust–FreeFEM comparison tolerances (D8).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompareTolerances {
    /// max node-wise |Δ(x − x0)| / max |x − x0|
    pub displacement_rel: f64,
    /// max node-wise |Δα| / max |α|
    pub angles_rel: f64,
    /// scalar metrics: |Δ| ≤ metric_rel·|rust| + metric_abs
    pub metric_rel: f64,
    pub metric_abs: f64,
    /// allowed difference of iteration counts
    pub iterations_abs: f64,
    /// inverse cases: max node-wise |Δ(x̂, α̂)| / max |(x̂, α̂)| (per field)
    pub adjoint_rel: f64,
}

/// Independent theory a case is checked against (metrics `*_rel_error` in `metrics.json`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reference {
    /// Eq. (63), the Kirchhoff elastica and the planar Reissner rod for a dead end force of
    /// magnitude `force_n` [N] along −e2 (see `src/theory.rs`).
    TipLoadedCantilever { force_n: f64 },
}

/// A validated case.
#[derive(Clone, Debug)]
pub struct Case {
    pub name: String,
    pub description: String,
    pub source: Option<PathBuf>,
    pub constants: BTreeMap<String, f64>,
    pub mesh: Mesh,
    pub material: Material,
    pub section: CrossSection,
    pub props: RodProperties,
    pub quadrature: QuadratureScheme,
    pub loads: Loads,
    pub analysis: Analysis,
    pub compare: CompareTolerances,
    pub reference: Option<Reference>,
}

impl Case {
    /// Read and validate a case file.
    pub fn from_file(path: &Path) -> Result<Case, CaseError> {
        let text =
            std::fs::read_to_string(path).map_err(|source| CaseError::Io { path: path.to_path_buf(), source })?;
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("case").to_string();
        let mut case = Case::from_toml(&text, &name, path)?;
        case.source = Some(path.to_path_buf());
        Ok(case)
    }

    /// Parse and validate TOML text; `path` is only used in messages.
    pub fn from_toml(text: &str, name: &str, path: &Path) -> Result<Case, CaseError> {
        let raw: RawCase =
            toml::from_str(text).map_err(|e| CaseError::Syntax { path: path.to_path_buf(), message: e.to_string() })?;
        Validator { path }.case(raw, name)
    }

    /// The same dynamic case cut to its first `steps` time steps (same Δt): the short but real
    /// subset that `cargo test` runs through FreeFEM. Static cases are returned unchanged.
    pub fn time_prefix(&self, steps: usize) -> Case {
        let mut c = self.clone();
        if let Analysis::Dynamic { end_time_s, steps: n, tolerance, max_iterations } = self.analysis {
            let k = steps.min(n).max(1);
            c.analysis =
                Analysis::Dynamic { end_time_s: end_time_s * k as f64 / n as f64, steps: k, tolerance, max_iterations };
        }
        c
    }

    /// Is this a dynamic case?
    pub fn is_dynamic(&self) -> bool {
        matches!(self.analysis, Analysis::Dynamic { .. })
    }

    /// The settings of an inverse case.
    pub fn inverse(&self) -> Option<&InverseSettings> {
        match &self.analysis {
            Analysis::Inverse(s) => Some(s),
            _ => None,
        }
    }

    /// The static forward case that generates an inverse case's data (same rod and loads).
    pub fn data_case(&self) -> Option<Case> {
        let inv = self.inverse()?;
        let DataSource::Forward(d) = inv.data else { return None };
        let mut c = self.clone();
        c.analysis = Analysis::Static {
            method: d.method,
            tolerance: d.tolerance,
            max_iterations: d.max_iterations,
            continuation_steps: d.continuation_steps,
        };
        Some(c)
    }
}

struct Validator<'a> {
    path: &'a Path,
}

fn rc_adjoint_missing(rc: &RawCompare) -> bool {
    rc.adjoint_rel.is_none()
}

impl Validator<'_> {
    /// `method` (+ `relaxation`) of a static solve in table `table`.
    fn static_method(
        &self,
        table: &str,
        method: RawMethod,
        relaxation: Option<f64>,
    ) -> Result<StaticMethod, CaseError> {
        match method {
            RawMethod::FixedPoint => {
                let key = format!("{table}.relaxation");
                let w = relaxation.ok_or_else(|| self.err(&key, "required by method = \"fixed_point\""))?;
                if !(w > 0.0 && w <= 1.0) {
                    return Err(self.err(&key, format!("must lie in (0, 1], got {w}")));
                }
                Ok(StaticMethod::FixedPoint { relaxation: w })
            }
            RawMethod::Newton => {
                if relaxation.is_some() {
                    return Err(self.err(&format!("{table}.relaxation"), "not used by method = \"newton\""));
                }
                Ok(StaticMethod::Newton)
            }
        }
    }

    fn err(&self, key: &str, reason: impl Into<String>) -> CaseError {
        CaseError::Invalid { path: self.path.to_path_buf(), key: key.to_string(), reason: reason.into() }
    }

    fn scalar(&self, key: &str, v: &Scalar, constants: &BTreeMap<String, f64>) -> Result<f64, CaseError> {
        let x = match v {
            Scalar::Number(x) => *x,
            Scalar::Text(s) => crate::expr::eval_const(s, constants).map_err(|e| self.err(key, e.to_string()))?,
        };
        if !x.is_finite() {
            return Err(self.err(key, format!("value is not finite ({x})")));
        }
        Ok(x)
    }

    fn positive(&self, key: &str, v: &Scalar, constants: &BTreeMap<String, f64>) -> Result<f64, CaseError> {
        let x = self.scalar(key, v, constants)?;
        if x <= 0.0 {
            return Err(self.err(key, format!("must be > 0, got {x}")));
        }
        Ok(x)
    }

    fn expr(
        &self,
        key: &str,
        v: &Scalar,
        allowed: &[&str],
        constants: &BTreeMap<String, f64>,
    ) -> Result<Expr, CaseError> {
        let text = match v {
            Scalar::Number(x) => format!("{x:e}"),
            Scalar::Text(s) => s.clone(),
        };
        let e = Expr::parse(&text).map_err(|e| self.err(key, format!("cannot parse `{text}`: {e}")))?;
        for var in e.variables() {
            if !allowed.contains(&var.as_str()) && !constants.contains_key(&var) {
                return Err(self.err(
                    key,
                    format!(
                        "unknown name `{var}` in `{text}` (allowed: {}, or a [constants] entry)",
                        allowed.join(", ")
                    ),
                ));
            }
        }
        Ok(e)
    }

    fn vector(
        &self,
        key: &str,
        v: &Option<[Scalar; 3]>,
        allowed: &[&str],
        constants: &BTreeMap<String, f64>,
    ) -> Result<[Expr; 3], CaseError> {
        let zero = Scalar::Number(0.0);
        let items = v.clone().unwrap_or([zero.clone(), zero.clone(), zero]);
        let mut out = Vec::with_capacity(3);
        for (i, item) in items.iter().enumerate() {
            out.push(self.expr(&format!("{key}[{i}]"), item, allowed, constants)?);
        }
        Ok([out[0].clone(), out[1].clone(), out[2].clone()])
    }

    fn case(&self, raw: RawCase, name: &str) -> Result<Case, CaseError> {
        // Constants are evaluated in order of appearance-independent dependency: allow each to use
        // earlier (alphabetically resolved) ones by iterating until no progress.
        let mut constants = BTreeMap::new();
        let mut pending: Vec<(String, Scalar)> = raw.constants.into_iter().collect();
        for (k, _) in &pending {
            if matches!(k.as_str(), "s" | "t" | "pi")
                || Expr::parse(k).map(|e| e.variables().len() != 1).unwrap_or(true)
            {
                return Err(
                    self.err(&format!("constants.{k}"), "not a valid constant name (identifier other than s, t, pi)")
                );
            }
        }
        while !pending.is_empty() {
            let before = pending.len();
            let mut rest = Vec::new();
            for (k, v) in pending {
                match self.scalar(&format!("constants.{k}"), &v, &constants) {
                    Ok(x) => {
                        constants.insert(k, x);
                    }
                    Err(e) => rest.push((k, v, e)),
                }
            }
            if rest.len() == before {
                return Err(rest.into_iter().next().map(|(_, _, e)| e).expect("non-empty"));
            }
            pending = rest.into_iter().map(|(k, v, _)| (k, v)).collect();
        }
        let c = &constants;

        let length = self.positive("rod.length_m", &raw.rod.length_m, c)?;
        if raw.rod.elements < 2 {
            return Err(self.err("rod.elements", format!("need at least 2 elements, got {}", raw.rod.elements)));
        }
        let mesh = Mesh::new(length, raw.rod.elements);

        let analysis_kind = raw.solver.analysis;
        let density = match (&raw.material.density_kg_m3, analysis_kind) {
            (Some(d), _) => self.positive("material.density_kg_m3", d, c)?,
            (None, RawAnalysis::Static | RawAnalysis::Inverse) => 1.0,
            (None, RawAnalysis::Dynamic) => {
                return Err(self.err("material.density_kg_m3", "required for a dynamic analysis"))
            }
        };
        let material = Material {
            young_modulus_pa: self.positive("material.young_modulus_pa", &raw.material.young_modulus_pa, c)?,
            shear_modulus_pa: self.positive("material.shear_modulus_pa", &raw.material.shear_modulus_pa, c)?,
            density_kg_m3: density,
            shear_correction: self.positive("material.shear_correction", &raw.material.shear_correction, c)?,
        };
        let section = match &raw.cross_section {
            RawSection::Circle { radius_m } => {
                CrossSection::Circle { radius_m: self.positive("cross_section.radius_m", radius_m, c)? }
            }
            RawSection::Rectangle { width_m, height_m } => CrossSection::Rectangle {
                width_m: self.positive("cross_section.width_m", width_m, c)?,
                height_m: self.positive("cross_section.height_m", height_m, c)?,
            },
        };
        let props = RodProperties::new(&material, &section);

        let vars: &[&str] = match analysis_kind {
            RawAnalysis::Static | RawAnalysis::Inverse => &["s"],
            RawAnalysis::Dynamic => &["s", "t"],
        };
        let end_vars: &[&str] = match analysis_kind {
            RawAnalysis::Static | RawAnalysis::Inverse => &[],
            RawAnalysis::Dynamic => &["t"],
        };
        let frame = match raw.loads.frame {
            RawFrame::Global => LoadFrame::Global,
            RawFrame::Local => LoadFrame::Local,
        };
        let loads = Loads::new(
            frame,
            self.vector("loads.force_n_per_m", &raw.loads.force_n_per_m, vars, c)?,
            self.vector("loads.torque_nm_per_m", &raw.loads.torque_nm_per_m, vars, c)?,
            self.vector("loads.end_force_n", &raw.loads.end_force_n, end_vars, c)?,
            self.vector("loads.end_torque_nm", &raw.loads.end_torque_nm, end_vars, c)?,
            c,
        )
        .map_err(|e| self.err("loads", e.to_string()))?;

        let s = &raw.solver;
        if !(s.tolerance > 0.0 && s.tolerance < 1.0) {
            return Err(self.err("solver.tolerance", format!("must lie in (0, 1), got {}", s.tolerance)));
        }
        if s.max_iterations == 0 {
            return Err(self.err("solver.max_iterations", "must be ≥ 1"));
        }
        if analysis_kind != RawAnalysis::Inverse {
            if raw.data.is_some() {
                return Err(self.err("data", "only allowed when solver.analysis = \"inverse\""));
            }
            if raw.clip.is_some() {
                return Err(self.err("clip", "only allowed when solver.analysis = \"inverse\""));
            }
            if raw.inverse.is_some() {
                return Err(self.err("inverse", "only allowed when solver.analysis = \"inverse\""));
            }
        }
        if analysis_kind != RawAnalysis::Dynamic && raw.time.is_some() {
            return Err(self.err("time", "only allowed when solver.analysis = \"dynamic\""));
        }
        let analysis = match analysis_kind {
            RawAnalysis::Static | RawAnalysis::Dynamic if s.warm_start_tolerance.is_some() => {
                return Err(self.err("solver.warm_start_tolerance", "only used by an inverse analysis"));
            }
            RawAnalysis::Static => {
                let method = self.static_method("solver", s.method, s.relaxation)?;
                if s.continuation_steps == 0 {
                    return Err(self.err("solver.continuation_steps", "must be ≥ 1"));
                }
                Analysis::Static {
                    method,
                    tolerance: s.tolerance,
                    max_iterations: s.max_iterations,
                    continuation_steps: s.continuation_steps,
                }
            }
            RawAnalysis::Inverse => {
                // Both modes need the relaxation: Newton starts from the fixed point (I8).
                let relaxation = match self.static_method("solver", RawMethod::FixedPoint, s.relaxation)? {
                    StaticMethod::FixedPoint { relaxation } => relaxation,
                    StaticMethod::Newton => unreachable!("asked for the fixed point"),
                };
                let method = match s.method {
                    RawMethod::FixedPoint => {
                        if s.warm_start_tolerance.is_some() {
                            return Err(self.err("solver.warm_start_tolerance", "only used by method = \"newton\""));
                        }
                        InverseMethod::FixedPoint { relaxation }
                    }
                    RawMethod::Newton => {
                        let w = s.warm_start_tolerance.ok_or_else(|| self.err("solver.warm_start_tolerance", "required by method = \"newton\" (Newton starts from the fixed point's iterate at this relative change, I8)"))?;
                        if !(w > 0.0 && w < 1.0) {
                            return Err(self.err("solver.warm_start_tolerance", format!("must lie in (0, 1), got {w}")));
                        }
                        InverseMethod::Newton { relaxation, warm_start_tolerance: w }
                    }
                };
                if s.continuation_steps != 1 {
                    return Err(self.err("solver.continuation_steps", "not used by an inverse analysis"));
                }
                let data = match (&raw.data, &raw.clip) {
                    (Some(d), None) => {
                        if !(d.tolerance > 0.0 && d.tolerance < 1.0) {
                            return Err(self.err("data.tolerance", format!("must lie in (0, 1), got {}", d.tolerance)));
                        }
                        if d.max_iterations == 0 || d.continuation_steps == 0 {
                            return Err(self.err("data.max_iterations", "max_iterations and continuation_steps must be ≥ 1"));
                        }
                        DataSource::Forward(DataSolve { method: self.static_method("data", d.method, d.relaxation)?, tolerance: d.tolerance, max_iterations: d.max_iterations, continuation_steps: d.continuation_steps })
                    }
                    (None, Some(cl)) => {
                        let base = self.path.parent().unwrap_or(Path::new(""));
                        let frames = match cl.frames {
                            Some([a, b]) if a < b => Some((a, b)),
                            Some([a, b]) => return Err(self.err("clip.frames", format!("expected [first, end) with first < end, got [{a}, {b}]"))),
                            None => None,
                        };
                        if !(cl.min_cos_beta >= 0.0 && cl.min_cos_beta < 1.0) {
                            return Err(self.err("clip.min_cos_beta", format!("must lie in [0, 1), got {}", cl.min_cos_beta)));
                        }
                        let plane = match cl.plane {
                            RawPlane::Xz => crate::clip::ClipPlane::Xz,
                            RawPlane::Xy => crate::clip::ClipPlane::Xy,
                        };
                        if let Some(v) = cl.orientation.iter().flatten().find(|v| !v.is_finite()) {
                            return Err(self.err("clip.orientation", format!("must be a finite rotation vector [rad], got {v}")));
                        }
                        let orientation = nalgebra::Rotation3::new(nalgebra::Vector3::from(cl.orientation.unwrap_or([0.0; 3]))).into_inner();
                        let gauge = match cl.gauge {
                            Some(g) => nalgebra::Vector3::from(g)
                                .try_normalize(1e-12)
                                .filter(|v| v.iter().all(|c| c.is_finite()))
                                .ok_or_else(|| self.err("clip.gauge", format!("must be a finite non-zero vector, got {g:?}")))?,
                            None => match plane {
                                crate::clip::ClipPlane::Xz => nalgebra::Vector3::y(),
                                crate::clip::ClipPlane::Xy => nalgebra::Vector3::z(),
                            },
                        };
                        let frame_interval_s = self.positive("clip.frame_interval_s", &cl.frame_interval_s, c)?;
                        let synthetic = match cl.kind {
                            RawClipKind::Roll3d => {
                                let d = crate::clip::synthetic::RollClipParams::default();
                                let p = crate::clip::synthetic::RollClipParams {
                                    length_m: length,
                                    nodes: raw.rod.elements + 1,
                                    frames: cl.clip_frames.unwrap_or(d.frames),
                                    dt_s: frame_interval_s,
                                    roll_total_rad: cl.roll_total_rad.as_ref().map(|v| self.scalar("clip.roll_total_rad", v, c)).transpose()?.unwrap_or(d.roll_total_rad),
                                    twist_per_m: cl.twist_per_m.as_ref().map(|v| self.scalar("clip.twist_per_m", v, c)).transpose()?.unwrap_or(d.twist_per_m),
                                    time_mapping: d.time_mapping,
                                    substeps: cl.substeps.unwrap_or(d.substeps),
                                };
                                p.validate().map_err(|e| self.err("clip", e.to_string()))?;
                                Some(p)
                            }
                            _ => {
                                if cl.roll_total_rad.is_some() || cl.twist_per_m.is_some() || cl.clip_frames.is_some() || cl.substeps.is_some() {
                                    return Err(self.err("clip", "roll_total_rad, twist_per_m, clip_frames and substeps apply to kind = \"roll_3d\" only"));
                                }
                                None
                            }
                        };
                        DataSource::Clip(ClipSource {
                            kind: match cl.kind {
                                RawClipKind::Kymogram => ClipKind::Kymogram,
                                RawClipKind::Recording => ClipKind::Recording,
                                RawClipKind::Roll3d => ClipKind::Roll3d,
                            },
                            synthetic,
                            file: base.join(&cl.file),
                            frame_interval_s,
                            frames,
                            min_cos_beta: cl.min_cos_beta,
                            start: match cl.start {
                                RawStart::PreviousFrame => crate::solve::sequence::FrameStart::PreviousFrame,
                                RawStart::DataGuess => crate::solve::sequence::FrameStart::DataGuess,
                            },
                            rotation: match cl.rotation {
                                RawRotation::Rebased => crate::solve::sequence::RotationTreatment::Rebased,
                                RawRotation::GlobalEuler => crate::solve::sequence::RotationTreatment::GlobalEuler,
                            },
                            plane,
                            orientation,
                            gauge: orientation * gauge,
                        })
                    }
                    (Some(_), Some(_)) => return Err(self.err("clip", "give either [data] (synthetic) or [clip] (recorded), not both")),
                    (None, None) => return Err(self.err("data", "an inverse case needs [data] (a forward solve generating the centreline) or [clip] (a recorded clip)")),
                };
                let inv = raw.inverse.as_ref().ok_or_else(|| {
                    self.err("inverse", "required when solver.analysis = \"inverse\" (the weights of eq. 41)")
                })?;
                let nonneg = |key: &str, v: &Scalar| -> Result<f64, CaseError> {
                    let x = self.scalar(key, v, c)?;
                    if x < 0.0 {
                        return Err(self.err(key, format!("must be ≥ 0, got {x}")));
                    }
                    Ok(x)
                };
                let diag = |key: &str, v: &Option<[Scalar; 3]>| -> Result<[f64; 3], CaseError> {
                    match v {
                        None => Ok([0.0; 3]),
                        Some(items) => {
                            let mut out = [0.0; 3];
                            for (i, item) in items.iter().enumerate() {
                                out[i] = nonneg(&format!("{key}[{i}]"), item)?;
                            }
                            Ok(out)
                        }
                    }
                };
                let weights = InverseWeights {
                    lambda_g: self.positive("inverse.lambda_g", &inv.lambda_g, c)?,
                    lambda_f: self.positive("inverse.lambda_f", &inv.lambda_f, c)?,
                    lambda_l: self.positive("inverse.lambda_l", &inv.lambda_l, c)?,
                    lambda_d: nonneg("inverse.lambda_d", &inv.lambda_d)?,
                    lambda_kappa: diag("inverse.lambda_kappa", &Some(inv.lambda_kappa.clone()))?,
                    lambda_omega: diag("inverse.lambda_omega", &inv.lambda_omega)?,
                };
                let frame_interval_s = match (&inv.frame_interval_s, &raw.clip) {
                    (Some(_), Some(_)) => {
                        return Err(
                            self.err("inverse.frame_interval_s", "a clip case takes Δt from clip.frame_interval_s")
                        )
                    }
                    (Some(v), None) => self.positive("inverse.frame_interval_s", v, c)?,
                    (None, Some(cl)) => self.positive("clip.frame_interval_s", &cl.frame_interval_s, c)?,
                    (None, None) if weights.lambda_omega.iter().any(|&w| w > 0.0) => {
                        return Err(self.err("inverse.frame_interval_s", "required when lambda_omega is non-zero"));
                    }
                    (None, None) => 1.0,
                };
                let alpha0_rad = match &inv.alpha0_rad {
                    Some(v) => self.scalar("inverse.alpha0_rad", v, c)?,
                    None => 0.0,
                };
                let stabilisation = match &inv.stabilisation {
                    Some(v) => {
                        let e = self.scalar("inverse.stabilisation", v, c)?;
                        if !(0.0..=1.0).contains(&e) {
                            return Err(self.err("inverse.stabilisation", format!("must lie in [0, 1], got {e}")));
                        }
                        e
                    }
                    None => 0.0,
                };
                if rc_adjoint_missing(&raw.compare) {
                    return Err(
                        self.err("compare.adjoint_rel", "required for an inverse case (tolerance on the adjoint x̂, α̂)")
                    );
                }
                Analysis::Inverse(InverseSettings {
                    method,
                    tolerance: s.tolerance,
                    max_iterations: s.max_iterations,
                    weights,
                    frame_interval_s,
                    alpha0_rad,
                    stabilisation,
                    data,
                })
            }
            RawAnalysis::Dynamic => {
                if s.method != RawMethod::Newton {
                    return Err(self.err("solver.method", "a dynamic analysis is solved by \"newton\" per step (D6)"));
                }
                if s.relaxation.is_some() {
                    return Err(self.err("solver.relaxation", "not used by a dynamic analysis"));
                }
                if s.continuation_steps != 1 {
                    return Err(self.err("solver.continuation_steps", "only for a static analysis"));
                }
                let t =
                    raw.time.as_ref().ok_or_else(|| self.err("time", "required when solver.analysis = \"dynamic\""))?;
                if t.steps == 0 {
                    return Err(self.err("time.steps", "must be ≥ 1"));
                }
                Analysis::Dynamic {
                    end_time_s: self.positive("time.end_s", &t.end_s, c)?,
                    steps: t.steps,
                    tolerance: s.tolerance,
                    max_iterations: s.max_iterations,
                }
            }
        };
        let quadrature = match s.quadrature {
            RawQuadrature::Selective => QuadratureScheme::Selective,
            RawQuadrature::Full => QuadratureScheme::Full,
            RawQuadrature::Reduced => QuadratureScheme::Reduced,
        };
        let rc = &raw.compare;
        for (k, v) in [
            ("compare.displacement_rel", rc.displacement_rel),
            ("compare.angles_rel", rc.angles_rel),
            ("compare.metric_rel", rc.metric_rel),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(self.err(k, format!("must be > 0, got {v}")));
            }
        }
        if let Some(v) = rc.adjoint_rel {
            if !(v > 0.0 && v.is_finite()) {
                return Err(self.err("compare.adjoint_rel", format!("must be > 0, got {v}")));
            }
        }
        for (k, v) in [("compare.metric_abs", rc.metric_abs), ("compare.iterations_abs", rc.iterations_abs)] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(self.err(k, format!("must be ≥ 0, got {v}")));
            }
        }
        let reference = match &raw.reference {
            None => None,
            Some(RawReference::TipLoadedCantilever { force_n }) => {
                if analysis_kind != RawAnalysis::Static {
                    return Err(self.err("reference.kind", "\"tip_loaded_cantilever\" needs a static analysis"));
                }
                Some(Reference::TipLoadedCantilever { force_n: self.positive("reference.force_n", force_n, c)? })
            }
        };
        Ok(Case {
            reference,
            name: name.to_string(),
            description: raw.description,
            source: None,
            constants,
            mesh,
            material,
            section,
            props,
            quadrature,
            loads,
            analysis,
            compare: CompareTolerances {
                displacement_rel: rc.displacement_rel,
                angles_rel: rc.angles_rel,
                metric_rel: rc.metric_rel,
                metric_abs: rc.metric_abs,
                iterations_abs: rc.iterations_abs,
                adjoint_rel: rc.adjoint_rel.unwrap_or(f64::INFINITY),
            },
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
mod tests {
    use super::*;

    const GOOD: &str = r#"
description = "test"
[constants]
F = 1e-8
L0 = 1e-3
[rod]
length_m = "L0"
elements = 10
[material]
young_modulus_pa = 1.1e5
shear_modulus_pa = 5e4
shear_correction = "4/3"
[cross_section]
shape = "circle"
radius_m = "L0/40"
[loads]
end_force_n = [0, "-F", 0]
[solver]
analysis = "static"
relaxation = 0.5
tolerance = 1e-10
max_iterations = 100
[compare]
displacement_rel = 1e-6
angles_rel = 1e-6
metric_rel = 1e-6
"#;

    fn parse(text: &str) -> Result<Case, CaseError> {
        Case::from_toml(text, "t", Path::new("t.toml"))
    }

    #[test]
    fn good_case_parses() {
        let c = parse(GOOD).unwrap();
        assert_eq!(c.mesh.elements, 10);
        assert!((c.mesh.length_m - 1e-3).abs() < 1e-18);
        assert!((c.material.shear_correction - 4.0 / 3.0).abs() < 1e-15);
        assert!(
            matches!(c.analysis, Analysis::Static { method: StaticMethod::FixedPoint { relaxation }, .. } if relaxation == 0.5)
        );
    }

    fn expect_key(text: &str, key: &str) {
        match parse(text) {
            Err(CaseError::Invalid { key: k, .. }) => assert_eq!(k, key),
            other => panic!("expected invalid {key}, got {other:?}"),
        }
    }

    #[test]
    fn bad_values_name_the_key() {
        expect_key(&GOOD.replace("elements = 10", "elements = 1"), "rod.elements");
        expect_key(&GOOD.replace("young_modulus_pa = 1.1e5", "young_modulus_pa = -1"), "material.young_modulus_pa");
        expect_key(&GOOD.replace("\"-F\"", "\"-G*s\""), "loads.end_force_n[1]");
        expect_key(&GOOD.replace("relaxation = 0.5", "relaxation = 1.5"), "solver.relaxation");
        expect_key(&GOOD.replace("radius_m = \"L0/40\"", "radius_m = \"L0/(\""), "cross_section.radius_m");
        expect_key(&GOOD.replace("analysis = \"static\"", "analysis = \"dynamic\""), "material.density_kg_m3");
    }

    #[test]
    fn unknown_keys_are_rejected() {
        let e = parse(&GOOD.replace("elements = 10", "elements = 10\nelement = 3")).unwrap_err();
        assert!(e.to_string().contains("unknown field `element`"), "{e}");
    }
}
