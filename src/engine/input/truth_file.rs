//! The ground-truth sidecar of a synthetic recording: `NAME.truth.npy` next to `NAME.npy` (or
//! `NAME.csv`), written by `cosserat synth` ([`super::corpus`]). When a recording has one, the
//! clip is scored against it exactly as the `roll_3d` clip is against its generator
//! (`crate::engine::common::clip_frame::TruthRun`): recovered curvature, frames and positions.
//!
//! Layout: float64, frames × nodes × 13, per node the rows of the frame `Q` (`d1`, `d2`, `d3`:
//! 9 values [–]), the local curvature `κˡ` (3 values [1/m]) and the frame's roll angle `ψ` of
//! the bending plane [rad] (the same for every node of a frame).
use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Vector3};

use crate::clip::synthetic::{FrameTruth, GroundTruth};
use crate::io::files::{InputError, OutputError};
use crate::io::npy::{read_npy, write_npy};

/// Values per node in a truth sidecar.
pub const TRUTH_VALUES_PER_NODE: usize = 13;

/// Suffix that replaces a recording's extension in its truth sidecar's name.
pub const TRUTH_SUFFIX: &str = ".truth.npy";

/// The truth sidecar of the recording `path` (`a/b.npy` → `a/b.truth.npy`).
pub fn truth_sidecar(path: &Path) -> PathBuf {
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    path.with_file_name(format!("{stem}{TRUTH_SUFFIX}"))
}

/// Is `path` a truth sidecar (by its name)?
pub fn is_truth_sidecar(path: &Path) -> bool {
    path.file_name().is_some_and(|n| n.to_string_lossy().ends_with(TRUTH_SUFFIX))
}

/// Write `truth` to `path` (atomically).
pub fn write_truth(path: &Path, truth: &GroundTruth) -> Result<(), OutputError> {
    let nodes = truth.node_s_m.len();
    let mut data = Vec::with_capacity(truth.frames.len() * nodes * TRUTH_VALUES_PER_NODE);
    for f in &truth.frames {
        for (q, k) in f.q.iter().zip(&f.kappa) {
            for r in 0..3 {
                data.extend((0..3).map(|c| q[(r, c)]));
            }
            data.extend([k.x, k.y, k.z, f.roll_rad]);
        }
    }
    write_npy(path, &[truth.frames.len(), nodes, TRUTH_VALUES_PER_NODE], &data)
}

/// Read the truth sidecar `path` of a recording of `frames` frames at the arc lengths
/// `node_s_m` [m]; its shape must match the recording's.
pub fn read_truth(path: &Path, frames: usize, node_s_m: &[f64]) -> Result<GroundTruth, InputError> {
    let a = read_npy(path)?;
    let nodes = node_s_m.len();
    if a.shape != [frames, nodes, TRUTH_VALUES_PER_NODE] {
        return Err(InputError::Shape {
            path: path.to_path_buf(),
            reason: format!(
                "truth sidecar of shape {:?}, expected {:?} (frames × nodes of its recording × {TRUTH_VALUES_PER_NODE})",
                a.shape,
                [frames, nodes, TRUTH_VALUES_PER_NODE]
            ),
        });
    }
    if let Some(i) = a.data.iter().position(|v| !v.is_finite()) {
        let (frame, node) = (i / (nodes * TRUTH_VALUES_PER_NODE), (i / TRUTH_VALUES_PER_NODE) % nodes);
        return Err(InputError::Shape {
            path: path.to_path_buf(),
            reason: format!("frame {frame}, node {node}: value {} is not finite", a.data[i]),
        });
    }
    let frames = a
        .data
        .chunks_exact(nodes * TRUTH_VALUES_PER_NODE)
        .map(|frame| {
            let per_node = frame.chunks_exact(TRUTH_VALUES_PER_NODE);
            FrameTruth {
                q: per_node.clone().map(|v| Matrix3::from_row_slice(&v[..9])).collect(),
                kappa: per_node.clone().map(|v| Vector3::new(v[9], v[10], v[11])).collect(),
                roll_rad: frame[12],
            }
        })
        .collect();
    Ok(GroundTruth { frames, node_s_m: node_s_m.to_vec() })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sidecar_round_trip_and_names() {
        assert_eq!(truth_sidecar(Path::new("a/b.npy")), Path::new("a/b.truth.npy"));
        assert_eq!(truth_sidecar(Path::new("b.csv")), Path::new("b.truth.npy"));
        assert!(is_truth_sidecar(Path::new("x/b.truth.npy")) && !is_truth_sidecar(Path::new("b.npy")));
        let q = Matrix3::new(1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0);
        let frame = |r: f64| FrameTruth { q: vec![q; 2], kappa: vec![Vector3::new(1.0, -2.0, r); 2], roll_rad: r };
        let truth = GroundTruth { frames: vec![frame(0.5), frame(0.25)], node_s_m: vec![0.0, 1e-3] };
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.truth.npy");
        write_truth(&path, &truth).unwrap();
        assert_eq!(read_truth(&path, 2, &truth.node_s_m).unwrap(), truth);
        let e = read_truth(&path, 3, &truth.node_s_m).unwrap_err().to_string();
        assert!(e.contains("expected [3, 2, 13]"), "{e}");
    }
}
