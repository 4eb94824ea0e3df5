//! `ff_info.csv`, the `key,value` summary every FreeFEM script writes beside its tables
//! (`freefem/forward.edp`, `inverse.edp`, `clip.edp`, `arclength.idp`; the certificate's lines
//! from `inverse_core.idp`'s `writeCertificate`), read once into typed fields. A key the reader
//! does not know is an error: the scripts and this reader then disagree, and a value read by a
//! misspelt name would silently be missing.
use std::path::Path;

use super::FreeFemError;
use crate::io::files::InputError;
use crate::solve::certificate::Certificate;

/// What a script's `ff_info.csv` holds; each field is `None` where the script did not write it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FfInfo {
    pub solve: SolveInfo,
    /// the script's own wall time [s]
    pub wall_time_s: Option<f64>,
    /// the residual certificate of the result (C1) and its four blocks, in the order of
    /// [`Certificate::blocks`] (the forward scripts write the first two)
    pub certificate: Option<f64>,
    pub certificate_blocks: [Option<f64>; 4],
    pub path: PathInfo,
    /// clip frames done
    pub frames: Option<f64>,
    pub failed: FailedFrame,
}

/// The solver's counts.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SolveInfo {
    /// iterations of the last solve (fixed point or Newton)
    pub iterations: Option<f64>,
    /// the last iteration's relative change of the iterate
    pub rel_change: Option<f64>,
    /// the forward solver's last residual
    pub residual: Option<f64>,
    /// the most Newton iterations of one load or time step
    pub max_newton_iterations: Option<f64>,
    /// Newton iterations over the run
    pub newton_iterations: Option<f64>,
    /// CPU time in Newton [s]
    pub newton_time_s: Option<f64>,
    /// load steps (static continuation)
    pub steps: Option<f64>,
}

/// An arc-length path's counts (`arclength.idp`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PathInfo {
    pub continuation_steps: Option<f64>,
    pub path_points: Option<f64>,
    /// 1 where the path reached its end
    pub reached_end: Option<f64>,
}

/// The clip frame that stopped a clip (`clip.edp`): its index, its `solveFrame` code
/// (`clip::FrameCode`), whether Newton (1) or the fixed point (0) ran, its iterations and last
/// relative change.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FailedFrame {
    pub frame: Option<f64>,
    pub status: Option<f64>,
    pub newton: Option<f64>,
    pub iterations: Option<f64>,
    pub rel_change: Option<f64>,
}

impl FfInfo {
    /// Read `path`: every line `key,value` (the header `key,value`, and a value that is not a
    /// number, are skipped).
    pub fn read(path: &Path) -> Result<FfInfo, FreeFemError> {
        let csv_err = |source| InputError::Csv { path: path.to_path_buf(), source };
        let mut info = FfInfo::default();
        let mut rdr = csv::ReaderBuilder::new().trim(csv::Trim::All).from_path(path).map_err(csv_err)?;
        for rec in rdr.records() {
            let rec = rec.map_err(csv_err)?;
            let (Some(key), Some(value)) = (rec.get(0), rec.get(1).and_then(|v| v.parse::<f64>().ok())) else {
                continue;
            };
            let field = info.field(key).ok_or_else(|| FreeFemError::BadOutput {
                path: path.to_path_buf(),
                reason: format!("unknown key `{key}` (the script and engine/freefem/info.rs disagree)"),
            })?;
            *field = Some(value);
        }
        Ok(info)
    }

    /// The field of `key`, the one place where the scripts' key names are spelt.
    fn field(&mut self, key: &str) -> Option<&mut Option<f64>> {
        Some(match key {
            "iterations" => &mut self.solve.iterations,
            "rel_change" => &mut self.solve.rel_change,
            "residual" => &mut self.solve.residual,
            "max_newton_iterations" => &mut self.solve.max_newton_iterations,
            "newton_iterations" => &mut self.solve.newton_iterations,
            "newton_time_s" => &mut self.solve.newton_time_s,
            "wall_time_s" => &mut self.wall_time_s,
            "certificate" => &mut self.certificate,
            "certificate_x_rows" => &mut self.certificate_blocks[0],
            "certificate_alpha_rows" => &mut self.certificate_blocks[1],
            "certificate_xhat_rows" => &mut self.certificate_blocks[2],
            "certificate_ahat_rows" => &mut self.certificate_blocks[3],
            "steps" => &mut self.solve.steps,
            "continuation_steps" => &mut self.path.continuation_steps,
            "path_points" => &mut self.path.path_points,
            "reached_end" => &mut self.path.reached_end,
            "frames" => &mut self.frames,
            "failed_frame" => &mut self.failed.frame,
            "failed_status" => &mut self.failed.status,
            "failed_newton" => &mut self.failed.newton,
            "failed_iterations" => &mut self.failed.iterations,
            "failed_rel_change" => &mut self.failed.rel_change,
            _ => return None,
        })
    }

    /// The certificate of the result with its blocks (a block not written counts 0).
    pub fn certificate(&self) -> Option<Certificate> {
        let value = self.certificate?;
        Some(Certificate { value, blocks: self.certificate_blocks.map(|b| b.unwrap_or(0.0)) })
    }

    /// The iterations of the last solve (0 where not written).
    pub fn iterations(&self) -> usize {
        self.solve.iterations.map_or(0, |v| v as usize)
    }

    /// The script's wall time [s] (NaN where not written).
    pub fn wall_time_s(&self) -> f64 {
        self.wall_time_s.unwrap_or(f64::NAN)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<FfInfo, FreeFemError> {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("ff_info.csv");
        std::fs::write(&path, text).expect("write");
        FfInfo::read(&path)
    }

    /// Every key a script writes is read into its field; the header and `nan` are skipped.
    #[test]
    fn the_scripts_keys_are_read_into_their_fields() {
        let info = read(
            "key,value\niterations,12\nrel_change,3.5e-11\ncertificate,2e-14\ncertificate_x_rows,1e-14\n\
             certificate_ahat_rows,2e-14\nwall_time_s,0.25\nreached_end,1\nfailed_status,4\nresidual,-\n",
        )
        .expect("reads");
        assert_eq!(info.iterations(), 12);
        assert_eq!(info.solve.rel_change, Some(3.5e-11));
        assert_eq!(info.certificate(), Some(Certificate { value: 2e-14, blocks: [1e-14, 0.0, 0.0, 2e-14] }));
        assert_eq!(info.wall_time_s(), 0.25);
        assert_eq!((info.path.reached_end, info.failed.status, info.solve.residual), (Some(1.0), Some(4.0), None));
    }

    /// A key nobody reads is refused, naming it.
    #[test]
    fn an_unknown_key_is_refused() {
        let err = read("key,value\niteratons,12\n").expect_err("refused").to_string();
        assert!(err.contains("iteratons"), "{err}");
    }

    /// Every key the scripts of `freefem/` write (a literal `"KEY,"` after `<<`) is one this
    /// reader knows.
    #[test]
    fn every_key_the_scripts_write_is_known() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("freefem");
        let mut keys = Vec::new();
        for entry in std::fs::read_dir(&dir).expect("freefem/") {
            let text = std::fs::read_to_string(entry.expect("entry").path()).unwrap_or_default();
            for piece in text.split("<< \"").skip(1) {
                let key: String = piece.chars().take_while(|c| c.is_ascii_lowercase() || *c == '_').collect();
                if piece[key.len()..].starts_with(",\"") && !key.is_empty() {
                    keys.push(key);
                }
            }
        }
        assert!(keys.len() >= 20, "keys found: {keys:?}");
        let mut info = FfInfo::default();
        let unknown: Vec<&String> = keys.iter().filter(|k| info.field(k).is_none()).collect();
        assert!(unknown.is_empty(), "keys the scripts write that FfInfo does not know: {unknown:?}");
    }
}
