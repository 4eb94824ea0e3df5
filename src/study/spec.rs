//! The noise study's spec file (`cases/bench/noise_study.toml`), read and checked once.
use std::path::{Path, PathBuf};

use serde::Deserialize;

/// Errors of reading a study spec or writing a variant's case.
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    #[error("{path}: {source}")]
    Read { path: PathBuf, source: crate::io::InputError },
    #[error("{path}: {message}")]
    Parse { path: PathBuf, message: String },
    #[error("{path}: {reason}")]
    Invalid { path: PathBuf, reason: String },
    #[error("variant `{variant}` on {nodes} nodes: {reason}")]
    Variant { variant: String, nodes: usize, reason: String },
}

/// A mesh of the study: recordings of `nodes` nodes reconstructed by `case` with
/// `rod.elements = nodes − 1`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mesh {
    pub nodes: usize,
    /// the batch case (relative to the spec's folder)
    pub case: PathBuf,
    /// the recordings as a single-camera tracker writes them (`engine::input::tracker`: 2D, in
    /// µm, noise in x and y only; no frame or point lost) instead of 3D `roll_3d` clips
    #[serde(default)]
    pub planar: bool,
    /// RMS of smooth, frame-independent changes of shape added to the 3D recordings
    /// (`engine::input::corpus::shape_change`: the first three sine and cosine modes along the
    /// body) [m]; the truth stays the clean clip's
    #[serde(default)]
    pub shape_noise_m: f64,
}

/// A way of reconstructing: keys of the case set to values (`"inverse.weights" = "auto"`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Variant {
    pub name: String,
    /// what the variant is, for the legend
    pub label: String,
    #[serde(default)]
    pub set: toml::Table,
    /// also score the curvature recovered at the nodes (`score::recovered_nodal`), as the
    /// method `NAME+nodal`
    #[serde(default)]
    pub recovered: bool,
    /// also score the curvature of the reconstructed centreline (its nodes' Menger curvature,
    /// `score::centreline_bending`) instead of the frame's, as the method `NAME+centreline`
    #[serde(default)]
    pub centreline: bool,
    /// drawn in noise_study.svg (every variant is in the table)
    #[serde(default = "yes")]
    pub plot: bool,
}

fn yes() -> bool {
    true
}

/// The smaller plan of `--quick`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Quick {
    pub noise_m: Vec<f64>,
    pub recordings: usize,
    pub frames: usize,
}

/// A noise study.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudySpec {
    pub title: String,
    /// noise levels σ [m]
    pub noise_m: Vec<f64>,
    /// recordings per mesh and σ
    pub recordings: usize,
    /// frames per recording
    pub frames: usize,
    pub seed: u64,
    /// elements left out at each end of the bending error
    pub skip_elements: usize,
    /// the kymogram the recordings play (relative to the spec's folder)
    pub kymogram: PathBuf,
    pub quick: Quick,
    pub meshes: Vec<Mesh>,
    pub variants: Vec<Variant>,
}

/// What one run of the study does.
pub struct Plan {
    pub noise_m: Vec<f64>,
    pub recordings: usize,
    pub frames: usize,
}

impl StudySpec {
    /// Read and check `path`; paths in it are made relative to its folder.
    pub fn read(path: &Path) -> Result<Self, SpecError> {
        let text = crate::io::files::read_capped_text(path, 1 << 20, "noise study spec")
            .map_err(|source| SpecError::Read { path: path.into(), source })?;
        let mut spec: StudySpec = toml::from_str(&text).map_err(|e| SpecError::Parse {
            path: path.into(),
            message: match crate::case::is_case_text(&text) {
                true => format!(
                    "this is a case file ([rod], [solver]), not a noise study spec: `cosserat run {}` runs it; \
                     `cosserat noise-study` takes a spec such as cases/bench/noise_study.toml",
                    path.display()
                ),
                false => e.to_string(),
            },
        })?;
        let dir = path.parent().unwrap_or(Path::new("."));
        spec.kymogram = dir.join(&spec.kymogram);
        spec.meshes.iter_mut().for_each(|m| m.case = dir.join(&m.case));
        let invalid = |reason: String| Err(SpecError::Invalid { path: path.into(), reason });
        if let Some(s) = spec.noise_m.iter().chain(&spec.quick.noise_m).find(|s| !(s.is_finite() && **s >= 0.0)) {
            return invalid(format!("noise level {s} m is not finite and >= 0"));
        }
        if spec.recordings == 0 || spec.quick.recordings == 0 || spec.frames < 2 || spec.quick.frames < 2 {
            return invalid("recordings must be >= 1 and frames >= 2 (also in [quick])".into());
        }
        if let Some(m) = spec.meshes.iter().find(|m| !(m.shape_noise_m.is_finite() && m.shape_noise_m >= 0.0)) {
            return invalid(format!("shape_noise_m = {} m is not finite and >= 0", m.shape_noise_m));
        }
        if let Some(m) = spec.meshes.iter().find(|m| m.planar && m.shape_noise_m > 0.0) {
            return invalid(format!(
                "the planar mesh of {} nodes has shape_noise_m = {} m: shape changes are added to 3D recordings only",
                m.nodes, m.shape_noise_m
            ));
        }
        if let Some(m) = spec.meshes.iter().find(|m| m.nodes < 2 * spec.skip_elements + 3) {
            return invalid(format!(
                "{} nodes leave no element after skipping {} at each end",
                m.nodes, spec.skip_elements
            ));
        }
        let mut names: Vec<&str> = spec.variants.iter().map(|v| v.name.as_str()).collect();
        names.sort_unstable();
        if names.windows(2).any(|w| w[0] == w[1]) || names.contains(&super::SPLINE) || names.is_empty() {
            return invalid(format!(
                "variant names must be distinct, not `{}`, and at least one: {names:?}",
                super::SPLINE
            ));
        }
        Ok(spec)
    }

    /// The noise levels, recordings and frames of a run at `depth`.
    pub fn plan(&self, depth: crate::jobs::depth::Depth) -> Plan {
        if depth.is_quick() {
            Plan { noise_m: self.quick.noise_m.clone(), recordings: self.quick.recordings, frames: self.quick.frames }
        } else {
            Plan { noise_m: self.noise_m.clone(), recordings: self.recordings, frames: self.frames }
        }
    }

    /// Write the case of `variant` on `mesh` into `dir` (the mesh's case with `rod.elements` and
    /// the variant's keys set, checked by reading it back) and return its path.
    pub fn variant_case(&self, mesh: &Mesh, variant: &Variant, dir: &Path) -> Result<PathBuf, SpecError> {
        let fail = |reason: String| SpecError::Variant { variant: variant.name.clone(), nodes: mesh.nodes, reason };
        let base = crate::case::Case::from_file(&mesh.case).map_err(|e| fail(e.to_string()))?;
        let mut overrides = vec![("rod.elements".to_string(), toml::Value::Integer(mesh.nodes as i64 - 1))];
        overrides.extend(variant.set.iter().map(|(k, v)| (k.clone(), v.clone())));
        let case = base.with_overrides(&overrides).map_err(|e| fail(e.to_string()))?;
        let table = case.toml_table().cloned().ok_or_else(|| fail("the case has no TOML".into()))?;
        let text = toml::to_string(&table).map_err(|e| fail(e.to_string()))?;
        let path = dir.join(format!("n{}_{}.toml", mesh.nodes, variant.name));
        std::fs::create_dir_all(dir).map_err(|e| fail(e.to_string()))?;
        crate::io::write_atomic(&path, text.as_bytes()).map_err(|e| fail(e.to_string()))?;
        crate::case::Case::from_file(&path).map_err(|e| fail(e.to_string()))?;
        Ok(path)
    }
}
