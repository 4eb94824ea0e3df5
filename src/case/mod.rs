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
mod raw;
pub mod sweep;
mod toml_error;
mod validate;

use crate::clip::synthetic::{RollClipParams, TimeMapping};
use crate::clip::{ClipPlane, KymogramParams};
use crate::model::loads::Loads;
use crate::model::material::{CrossSection, Material, RodProperties};
use crate::model::mesh::{Mesh, QuadratureScheme};
use crate::solve::dynamics::DynamicParams;
use crate::solve::inverse::{InverseParams, Records};
use crate::solve::sequence::{FrameStart, RotationTreatment, SequenceParams};
use crate::solve::statics::StaticParams;
use crate::solve::Problem;
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
/// real case and stops `cosserat run /dev/zero` at once instead of reading forever.
pub const CASE_FILE_CAP_BYTES: u64 = 1 << 20;

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
    /// magnitude `force_n` [N] along −e2 (see `run::metrics`).
    TipLoadedCantilever { force_n: f64 },
}

/// A validated case.
#[derive(Clone, Debug)]
pub struct Case {
    pub name: String,
    pub description: String,
    pub source: Option<PathBuf>,
    /// the SHA-256 (hex) of the case file's bytes as they were read (also of a case piped in)
    pub source_sha256: Option<String>,
    pub constants: BTreeMap<String, f64>,
    pub mesh: Mesh,
    pub material: Material,
    pub section: CrossSection,
    pub props: RodProperties,
    pub quadrature: QuadratureScheme,
    pub loads: Loads,
    pub analysis: Analysis,
    pub compare: CompareSpec,
    pub reference: Option<Reference>,
    /// whether the case file gave `material.density_kg_m3` (static and inverse analyses run
    /// with 1 kg/m³ when it does not: their equations never use it)
    density_given: bool,
    /// the case file's tables and the path it was validated with, for [`sweep`]'s overrides
    raw: Option<(toml::Table, PathBuf)>,
}

impl Case {
    /// Read and validate a case file (at most [`CASE_FILE_CAP_BYTES`]).
    pub fn from_file(path: &Path) -> Result<Case, CaseError> {
        let text = file::read_case_file(path)?;
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("case").to_string();
        let mut case = Case::from_toml(&text, &name, path)?;
        case.source = Some(path.to_path_buf());
        case.source_sha256 = Some(file::sha256_hex(text.as_bytes()));
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
        case.raw = Some((toml::from_str(text).map_err(syntax)?, path.to_path_buf()));
        Ok(case)
    }

    /// The discrete forward problem of the case (`[rod]`, `[material]`, `[cross_section]`,
    /// `[loads]`, `solver.quadrature`).
    pub fn problem(&self) -> Problem<'_> {
        Problem::new(self.mesh, self.props, self.quadrature, &self.loads)
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

    /// The clip of a clip case.
    /// Whether the case file gave `material.density_kg_m3` ([`Case::material`] holds 1 kg/m³
    /// otherwise, which only a static or inverse analysis may use: their equations never
    /// involve the density).
    pub fn density_given(&self) -> bool {
        self.density_given
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
            plane: clip.plane,
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
            gauge: clip.gauge,
            records: Records::Every,
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
    use crate::solve::statics::Method;

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
frames = 4
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
            matches!(c.analysis, Analysis::Static(StaticParams { method: Method::FixedPoint { relaxation }, .. }) if relaxation == 0.5)
        );
        assert_eq!(c.compare.frames, 4);
        assert_eq!(c.compare.overrides, CompareOverrides::default());
    }

    #[test]
    fn compare_overrides_need_a_reason() {
        let text = GOOD.replace("frames = 4", "frames = 4\nangles_rel = 1e-6");
        expect_key(&text, "compare.angles_rel");
        let ok =
            parse(&text.replace("frames = 4", "frames = 4\nreason = \"measured: the twist is held by 1e-10 only\""));
        assert_eq!(ok.unwrap().compare.overrides.angles_rel, Some(1e-6));
        expect_key(&GOOD.replace("frames = 4", "frames = 0"), "compare.frames");
        expect_key(&GOOD.replace("frames = 4", "metric_abs = -1\nreason = \"x\""), "compare.metric_abs");
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

    fn reason(text: &str) -> String {
        match parse(text) {
            Err(e @ CaseError::Invalid { .. }) => e.to_string(),
            other => panic!("expected an invalid key, got {other:?}"),
        }
    }

    #[test]
    fn case_files_are_read_within_the_cap() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("big.toml");
        std::fs::File::create(&p).unwrap().set_len(CASE_FILE_CAP_BYTES + 1).unwrap();
        let e = Case::from_file(&p).unwrap_err().to_string();
        let cap = "1048576 bytes (1 MiB), the cap for case files";
        assert_eq!(e, format!("{}: case file of 1048577 bytes is larger than {cap}", p.display()));
        if cfg!(unix) {
            let e = Case::from_file(Path::new("/dev/zero")).unwrap_err().to_string();
            assert!(e.starts_with("/dev/zero: the case file is a character device, not a regular file"), "{e}");
            // a named pipe with no writer: refused at once, never opened (the open would block)
            let fifo = dir.path().join("pipe.toml");
            if std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success()) {
                let e = Case::from_file(&fifo).unwrap_err().to_string();
                assert!(e.contains("is a named pipe (FIFO), not a regular file"), "{e}");
            }
            let e = Case::from_file(dir.path()).unwrap_err().to_string();
            assert!(e.contains("the case file is a folder"), "{e}");
        }
    }

    /// A load that is not finite on the mesh (or at a time step) is refused at load, naming the
    /// key, the expression as written, s and t.
    #[test]
    fn non_finite_loads_are_refused_at_load() {
        let with_force = |f: &str| GOOD.replace("[loads]", &format!("[loads]\nforce_n_per_m = [0, \"{f}\", 0]"));
        let tail = "a load must be finite at every node and load quadrature point of the rod";
        assert_eq!(
            reason(&with_force("1/(s-s)")),
            format!("t.toml: key `loads.force_n_per_m[1]`: `1/(s-s)` is not finite (inf) at s = 0 m, t = 0 s: {tail}")
        );
        assert_eq!(
            reason(&with_force("1/(s - L0)")),
            format!("t.toml: key `loads.force_n_per_m[1]`: `1/(s - L0)` is not finite (inf) at s = 0.001 m, t = 0 s: {tail}")
        );
        // A load quadrature point, not a node: the first Gauss point of element 3.
        let mesh = Mesh::new(1e-3, 10);
        let s = mesh.node_s(3) + crate::model::mesh::GAUSS2.points[0] * mesh.h();
        let e = reason(&with_force(&format!("1/(s - {s:e})")));
        assert!(e.contains(&format!("is not finite (inf) at s = {s} m, t = 0 s")), "{e}");
        let dynamic = GOOD
            .replace("analysis = \"static\"\nrelaxation = 0.5", "analysis = \"dynamic\"\nmethod = \"newton\"")
            .replace("[compare]", "[time]\nend_s = 1\nsteps = 10\n[compare]")
            .replace("shear_correction", "density_kg_m3 = 1e3\nshear_correction");
        assert!(parse(&dynamic).is_ok());
        let e = reason(&dynamic.replace("end_force_n = [0, \"-F\", 0]", "end_force_n = [0, \"-F*sqrt(0.35 - t)\", 0]"));
        assert_eq!(
            e,
            format!(
                "t.toml: key `loads.end_force_n[1]`: `-F*sqrt(0.35 - t)` is not finite (NaN) at s = L = 0.001 m, t = 0.4 s: {tail} \
                 and at every time step"
            )
        );
        let e = reason(&dynamic.replace("[loads]", "[loads]\ntorque_nm_per_m = [\"s/(t - 0.5)\", 0, 0]"));
        assert!(
            e.contains("`loads.torque_nm_per_m[0]`: `s/(t - 0.5)` is not finite (NaN) at s = 0 m, t = 0.5 s"),
            "{e}"
        );
    }

    /// NaN and infinity, as TOML numbers or as names, and names a key does not have.
    #[test]
    fn non_numbers_and_unknown_names_say_what_is_allowed() {
        let e = reason(&GOOD.replace("end_force_n = [0, \"-F\", 0]", "end_force_n = [0, nan, 0]"));
        assert_eq!(
            e,
            "t.toml: key `loads.end_force_n[1]`: NaN is not a number of the expression language (NaN and infinity \
             are not: every load must be finite); write a finite number or an expression of pi and the [constants] \
             F, L0"
        );
        let e = reason(&GOOD.replace("[loads]", "[loads]\nforce_n_per_m = [\"NaN\", 0, 0]"));
        assert_eq!(
            e,
            "t.toml: key `loads.force_n_per_m[0]`: unknown name `NaN` in `NaN` (NaN and infinity are not numbers of \
             the expression language: every value must be finite); allowed names: s, pi and the [constants] F, L0"
        );
        let e = reason(&GOOD.replace("\"-F\"", "\"-F*s\""));
        assert!(
            e.ends_with(
                "unknown name `s` in `-F*s` (s, the arc length [m], is defined in distributed loads only: end loads \
                 act at s = L); allowed names: pi and the [constants] F, L0"
            ),
            "{e}"
        );
        let e = reason(
            &GOOD.replace("[constants]\nF = 1e-8\nL0 = 1e-3", "").replace("L0", "1e-3").replace("\"-F\"", "\"inf\""),
        );
        assert!(e.ends_with("every value must be finite); allowed names: pi (no [constants] are defined)"), "{e}");
        let e = reason(&GOOD.replace("radius_m = \"L0/40\"", "radius_m = \"L0/t\""));
        assert!(e.contains("`cross_section.radius_m`: unknown name `t` in `L0/t` (t, the time [s], is defined in the loads of a dynamic analysis only); allowed names: pi and the [constants] F, L0"), "{e}");
    }

    #[test]
    fn constants_resolve_in_dependency_order_and_cycles_are_named() {
        let c = parse(&GOOD.replace("F = 1e-8", "F = 1e-8\nza = 2\nyb = \"za*2\"\nxc = \"yb*2\"")).unwrap();
        assert_eq!(c.constants["xc"], 8.0);
        let e = reason(&GOOD.replace("F = 1e-8", "F = \"G\"\nG = \"2*F\""));
        let cycle = "refer to themselves or to one another in a cycle";
        assert_eq!(e, format!("t.toml: key `constants.F`: cannot be evaluated: the constants F, G {cycle}"));
        let e = reason(&GOOD.replace("F = 1e-8", "F = \"2*F\""));
        assert_eq!(e, format!("t.toml: key `constants.F`: cannot be evaluated: the constants F {cycle}"));
        let e = reason(&GOOD.replace("F = 1e-8", "F = 1e-8\nk = \"x*2\""));
        assert_eq!(
            e,
            "t.toml: key `constants.k`: unknown name `x` in `x*2`; allowed names: pi and the [constants] F, L0, k"
        );
        for name in ["\"(a)\"", "\"-a\"", "sin", "pi", "s"] {
            let e = reason(&GOOD.replace("F = 1e-8", &format!("F = 1e-8\n{name} = 1")));
            assert!(e.contains("not a valid constant name"), "{name}: {e}");
        }
    }

    #[test]
    fn meshes_clip_meshes_and_clip_vectors_are_bounded() {
        let e = reason(&GOOD.replace("elements = 10", "elements = 1000001"));
        assert_eq!(e, "t.toml: key `rod.elements`: at most 1000000 elements, got 1000001");
        let worm =
            std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/worm_omega_turn.toml")).unwrap();
        let e = reason(&worm.replace("elements = 127", "elements = 2"));
        assert_eq!(
            e,
            "t.toml: key `rod.elements`: a clip case needs at least 11 elements (12 nodes per frame of clip.file \
             `../data/elegansbot/kymogram_omega-turn.npy`), got 2 (3 nodes): the clip's measures leave out 5 elements at \
             each end (curvature errors, ground truth) and the roughness needs 3 curvature values"
        );
        assert!(parse(&worm.replace("elements = 127", "elements = 11")).is_ok());
        let e = reason(&worm.replace("start = \"data_guess\"", "start = \"data_guess\"\ngauge = [1e308, 1e308, 0]"));
        assert!(e.contains("key `clip.gauge`: must be a finite non-zero vector"), "{e}");
        let e = reason(
            &worm.replace("start = \"data_guess\"", "start = \"data_guess\"\norientation = [1e308, 1e308, 1e308]"),
        );
        assert!(e.contains("key `clip.orientation`: rotation vector"), "{e}");
    }
}
