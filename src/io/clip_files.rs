//! Reading clips: kymograms and user recordings (`crate::clip` turns their content into
//! centrelines), and the clip of a clip case with its frame range, orientation and, for a
//! synthetic clip, its ground truth.
use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{Matrix3, Vector3};

use super::files::{csv_reader, InputError};
use super::npy::read_npy;
use crate::case::{Case, ClipKind};
use crate::clip::synthetic::{roll_clip, GroundTruth};
use crate::clip::{clip_from_angles, polyline_length, Clip, ClipError, KymogramParams};

/// Column names of a CSV recording.
pub const RECORDING_HEADER: [&str; 5] = ["frame", "node", "x_m", "y_m", "z_m"];

/// Errors of reading the clip of a clip case.
#[derive(Debug, thiserror::Error)]
pub enum ClipFileError {
    #[error(transparent)]
    Input(#[from] InputError),
    #[error(transparent)]
    Clip(#[from] ClipError),
    #[error("case `{0}` has no [clip]")]
    NotAClip(String),
    #[error("{path} does not exist{hint}")]
    Missing { path: std::path::PathBuf, hint: &'static str },
    #[error("{path}: {nodes} nodes per frame, but the case's mesh has {expected} (rod.elements + 1)")]
    NodeCount { path: std::path::PathBuf, nodes: usize, expected: usize },
}

/// The clip of a clip case: kymograms become spline centrelines with the mesh's node count
/// and the rod's length in the case's plane; recordings must have that node count; a
/// synthetic clip (`kind = "roll_3d"`) comes with its ground truth. The frame range and the
/// orientation of the case are applied to both.
pub fn load_clip(case: &Case) -> Result<(Clip, Option<GroundTruth>), ClipFileError> {
    let src = case.clip().ok_or_else(|| ClipFileError::NotAClip(case.name.clone()))?;
    if !src.file.is_file() {
        let hint = match src.kind {
            ClipKind::Recording => "",
            _ => " (the elegansbot kymograms are fetched and checksum-verified by scripts/fetch_worm_data.sh)",
        };
        return Err(ClipFileError::Missing { path: src.file.clone(), hint });
    }
    let (mut clip, mut truth) = match &src.kind {
        ClipKind::Kymogram => {
            let params = case.kymogram_params().ok_or_else(|| ClipFileError::NotAClip(case.name.clone()))?;
            (read_kymogram(&src.file, &params)?, None)
        }
        ClipKind::Recording => {
            let dt = case.inverse().map(|i| i.params.frame_interval_s).unwrap_or(f64::NAN);
            (read_recording(&src.file, dt)?, None)
        }
        ClipKind::Roll3d(_) => {
            let params = case.roll_clip_params().ok_or_else(|| ClipFileError::NotAClip(case.name.clone()))?;
            let rows = kymogram_rows(&src.file)?;
            let (clip, truth) = roll_clip(&rows, None, &params)?;
            (clip, Some(truth))
        }
    };
    if clip.node_count() != case.mesh.nodes() {
        return Err(ClipFileError::NodeCount {
            path: src.file.clone(),
            nodes: clip.node_count(),
            expected: case.mesh.nodes(),
        });
    }
    if let Some((a, b)) = src.frames {
        clip.select(a, b)?;
        if let Some(t) = &mut truth {
            t.select(a, b);
        }
    }
    if src.orientation != Matrix3::identity() {
        clip.rotate(&src.orientation);
        if let Some(t) = &mut truth {
            t.rotate(&src.orientation);
        }
    }
    Ok((clip, truth))
}

/// The rows (frames × joint angles [rad]) of a kymogram `.npy`, every angle finite.
pub fn kymogram_rows(path: &Path) -> Result<Vec<Vec<f64>>, InputError> {
    let a = read_npy(path)?;
    let shape = |reason: String| InputError::Shape { path: path.to_path_buf(), reason };
    let &[frames, joints] = a.shape.as_slice() else {
        return Err(shape(format!("kymogram of shape {:?}, expected 2 axes (frames × joint angles)", a.shape)));
    };
    if frames == 0 || joints == 0 {
        return Err(shape(format!("kymogram of shape {:?} is empty", a.shape)));
    }
    if let Some(k) = a.data.iter().position(|v| !v.is_finite()) {
        return Err(InputError::NonFiniteAngle {
            path: path.to_path_buf(),
            frame: k / joints,
            joint: k % joints,
            value: a.data[k],
        });
    }
    Ok(a.data.chunks_exact(joints).map(<[f64]>::to_vec).collect())
}

/// Read a kymogram `.npy` (frames × joints, float64, angles [rad]) into a [`Clip`].
pub fn read_kymogram(path: &Path, params: &KymogramParams) -> Result<Clip, InputError> {
    let rows = kymogram_rows(path)?;
    let (frames, joints) = (rows.len(), rows[0].len());
    let scaled = if params.scale_to_length { ", scaled to the body length" } else { "" };
    let source = format!(
        "{} ({frames} frames × {joints} joint angles; spline resampled to {} nodes{scaled}, {:?} plane)",
        path.display(),
        params.nodes,
        params.plane
    );
    Ok(clip_from_angles(&rows, params, source))
}

/// Read a user recording: `.csv` (header `frame,node,x_m,y_m,z_m`) or `.npy` (frames × nodes × 3,
/// float64) [m]; `dt_s` is the time between frames [s].
pub fn read_recording(path: &Path, dt_s: f64) -> Result<Clip, InputError> {
    let frames = match path.extension().and_then(|e| e.to_str()) {
        Some("npy") => recording_npy(path)?,
        Some("csv") => recording_csv(path)?,
        _ => {
            return Err(InputError::Shape {
                path: path.to_path_buf(),
                reason: "unknown extension, expected .csv or .npy".into(),
            })
        }
    };
    let length_m = polyline_length(&frames[0]);
    if length_m <= 0.0 {
        return Err(InputError::Shape { path: path.to_path_buf(), reason: "frame 0 has zero length".into() });
    }
    let source = format!("{} ({} frames × {} nodes)", path.display(), frames.len(), frames[0].len());
    Ok(Clip { frames, dt_s, source, length_m })
}

fn check_position(path: &Path, frame: usize, node: usize, p: &Vector3<f64>) -> Result<(), InputError> {
    match (0..3).find(|&k| !p[k].is_finite()) {
        Some(k) => Err(InputError::NonFinitePosition {
            path: path.to_path_buf(),
            frame,
            node,
            axis: ['x', 'y', 'z'][k],
            value: p[k],
        }),
        None => Ok(()),
    }
}

fn recording_npy(path: &Path) -> Result<Vec<Vec<Vector3<f64>>>, InputError> {
    let a = read_npy(path)?;
    let shape = |reason: String| InputError::Shape { path: path.to_path_buf(), reason };
    let &[frames, nodes, 3] = a.shape.as_slice() else {
        return Err(shape(format!("recording of shape {:?}, expected frames × nodes × 3", a.shape)));
    };
    if frames == 0 || nodes < 3 {
        return Err(shape(format!("recording of shape {:?}: need at least 1 frame and 3 nodes", a.shape)));
    }
    let mut out = Vec::with_capacity(frames);
    for (f, frame) in a.data.chunks_exact(3 * nodes).enumerate() {
        let pts: Vec<Vector3<f64>> = frame.chunks_exact(3).map(|c| Vector3::new(c[0], c[1], c[2])).collect();
        for (i, p) in pts.iter().enumerate() {
            check_position(path, f, i, p)?;
        }
        out.push(pts);
    }
    Ok(out)
}

fn recording_csv(path: &Path) -> Result<Vec<Vec<Vector3<f64>>>, InputError> {
    let mut rdr = csv_reader(path, &RECORDING_HEADER)?;
    // (frame, node) → (row, position)
    let mut rows: BTreeMap<(usize, usize), (usize, Vector3<f64>)> = BTreeMap::new();
    for (i, rec) in rdr.records().enumerate() {
        let row = i + 1;
        let bad = |reason: String| InputError::Row { path: path.to_path_buf(), row, reason };
        let rec = rec.map_err(|e| bad(e.to_string()))?;
        if rec.len() != 5 {
            return Err(bad(format!("{} columns, expected 5", rec.len())));
        }
        let index = |k: usize| {
            rec[k]
                .parse::<usize>()
                .map_err(|_| bad(format!("{} `{}` is not a non-negative integer", RECORDING_HEADER[k], &rec[k])))
        };
        let (frame, node) = (index(0)?, index(1)?);
        let coord =
            |k: usize| rec[k].parse::<f64>().map_err(|e| bad(format!("{} `{}`: {e}", RECORDING_HEADER[k], &rec[k])));
        let p = Vector3::new(coord(2)?, coord(3)?, coord(4)?);
        check_position(path, frame, node, &p)?;
        if let Some(&(first_row, _)) = rows.get(&(frame, node)) {
            return Err(InputError::DuplicateRow { path: path.to_path_buf(), row, first_row, frame, node });
        }
        rows.insert((frame, node), (row, p));
    }
    let Some(&(last_frame, _)) = rows.keys().next_back() else {
        return Err(InputError::Shape { path: path.to_path_buf(), reason: "no data rows".into() });
    };
    let mut frames: Vec<Vec<Vector3<f64>>> = vec![Vec::new(); last_frame + 1];
    for (&(frame, node), &(_, p)) in &rows {
        if node != frames[frame].len() {
            return Err(InputError::MissingRow { path: path.to_path_buf(), frame, node: frames[frame].len() });
        }
        frames[frame].push(p);
    }
    let expected = frames[0].len();
    for (frame, pts) in frames.iter().enumerate() {
        if pts.is_empty() {
            return Err(InputError::MissingRow { path: path.to_path_buf(), frame, node: 0 });
        }
        if pts.len() != expected {
            return Err(InputError::NodeCount { path: path.to_path_buf(), frame, nodes: pts.len(), expected });
        }
    }
    if expected < 3 {
        return Err(InputError::Shape {
            path: path.to_path_buf(),
            reason: format!("{expected} nodes per frame, need at least 3"),
        });
    }
    Ok(frames)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clip::tests::{menger_curvature, planar, wave};
    use crate::clip::{kymogram_joints, ClipPlane, Spline, WORM_LENGTH_M};
    use crate::io::npy::{npy_bytes, write_npy};
    use std::path::PathBuf;

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn kymogram_npy_reads_and_malformed_ones_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("k.npy");
        let rows = [wave(0.0), wave(0.7)];
        write_npy(&p, &[2, 24], &rows.concat()).unwrap();
        let clip = read_kymogram(&p, &KymogramParams::default()).unwrap();
        assert_eq!(clip, clip_from_angles(&rows, &KymogramParams::default(), clip.source.clone()));
        assert!(clip.source.contains("2 frames × 24 joint angles"), "{}", clip.source);
        let err = |shape: &[usize], data: &[f64]| {
            write_npy(&p, shape, data).unwrap();
            let e = read_kymogram(&p, &KymogramParams::default()).unwrap_err().to_string();
            assert!(e.contains("k.npy"), "{e}");
            e
        };
        let mut bad = rows.concat();
        bad[24 + 5] = f64::NAN;
        assert!(err(&[2, 24], &bad).contains("frame 1, joint 5: angle NaN is not finite"));
        bad[24 + 5] = f64::NEG_INFINITY;
        assert!(err(&[2, 24], &bad).contains("frame 1, joint 5: angle -inf"));
        assert!(err(&[2, 4, 6], &rows.concat()).contains("shape [2, 4, 6], expected 2 axes"));
        assert!(err(&[0, 24], &[]).contains("empty"));
        std::fs::write(&p, npy_bytes(&[2, 24], &rows.concat()).replace_f8_with(">f8")).unwrap();
        let e = read_kymogram(&p, &KymogramParams::default()).unwrap_err().to_string();
        assert!(e.contains("k.npy") && e.contains("dtype '>f8'"), "{e}");
        let full = npy_bytes(&[2, 24], &rows.concat());
        std::fs::write(&p, &full[..full.len() - 8]).unwrap();
        let e = read_kymogram(&p, &KymogramParams::default()).unwrap_err().to_string();
        assert!(e.contains("k.npy") && e.contains("truncated"), "{e}");
        let e = read_kymogram(&dir.path().join("missing.npy"), &KymogramParams::default()).unwrap_err();
        assert!(matches!(e, InputError::Open { .. }), "{e}");
    }

    trait ReplaceDescr {
        fn replace_f8_with(self, descr: &str) -> Vec<u8>;
    }
    impl ReplaceDescr for Vec<u8> {
        fn replace_f8_with(mut self, descr: &str) -> Vec<u8> {
            let at = self.windows(3).position(|w| w == b"<f8").unwrap();
            self.splice(at..at + 3, descr.bytes());
            self
        }
    }

    fn csv_text(frames: &[Vec<Vector3<f64>>]) -> String {
        let mut s = RECORDING_HEADER.join(",") + "\n";
        for (f, pts) in frames.iter().enumerate() {
            for (i, p) in pts.iter().enumerate() {
                s += &format!("{f},{i},{:e},{:e},{:e}\n", p.x, p.y, p.z);
            }
        }
        s
    }

    fn sample_frames() -> Vec<Vec<Vector3<f64>>> {
        (0..3)
            .map(|f| (0..4).map(|i| Vector3::new(1e-5 * f as f64, 2e-5 * (i as f64).sin(), 3e-4 * i as f64)).collect())
            .collect()
    }

    #[test]
    fn recordings_read_from_csv_and_npy() {
        let dir = tempfile::tempdir().unwrap();
        let frames = sample_frames();
        let p = write(dir.path(), "rec.csv", &csv_text(&frames));
        let clip = read_recording(&p, 0.04).unwrap();
        assert_eq!(
            (clip.frames.clone(), clip.dt_s, clip.frame_count(), clip.node_count()),
            (frames.clone(), 0.04, 3, 4)
        );
        assert!((clip.length_m - polyline_length(&frames[0])).abs() == 0.0);
        // Rows in any order.
        let text = csv_text(&frames);
        let mut lines: Vec<&str> = text.lines().collect();
        lines[1..].reverse();
        let p = write(dir.path(), "rev.csv", &lines.join("\n"));
        assert_eq!(read_recording(&p, 0.04).unwrap().frames, frames);
        let p = dir.path().join("rec.npy");
        let flat: Vec<f64> = frames.iter().flatten().flat_map(|v| [v.x, v.y, v.z]).collect();
        write_npy(&p, &[3, 4, 3], &flat).unwrap();
        assert_eq!(read_recording(&p, 0.04).unwrap().frames, frames);
    }

    #[test]
    fn malformed_recordings_name_file_frame_node_and_row() {
        let dir = tempfile::tempdir().unwrap();
        let good = csv_text(&sample_frames());
        let check = |name: &str, text: &str, wanted: &str| {
            let p = write(dir.path(), name, text);
            let e = read_recording(&p, 0.04).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains(wanted), "expected `{wanted}` in: {e}");
        };
        let lines: Vec<&str> = good.lines().collect();
        // line k + 1 of the file is data row k; row 6 is frame 1, node 1.
        check("nan.csv", &good.replace("1,1,1e-5,", "1,1,NaN,"), "frame 1, node 1: x = NaN is not finite");
        check("inf.csv", &good.replacen(",0e0\n", ",inf\n", 1), "frame 0, node 0: z = inf is not finite");
        check("header.csv", &good.replace("x_m", "x"), "expected [\"frame\", \"node\", \"x_m\", \"y_m\", \"z_m\"]");
        check("missing.csv", &[&lines[..6], &lines[7..]].concat().join("\n"), "frame 1, node 1: no row");
        check(
            "dup.csv",
            &[&lines[..], &[lines[6]]].concat().join("\n"),
            "row 13: frame 1, node 1 already given in row 6",
        );
        check("count.csv", &[&lines[..], &["1,4,0,0,0"]].concat().join("\n"), "frame 1: 5 nodes, but frame 0 has 4");
        check("gap.csv", &good.replace("\n2,", "\n3,"), "frame 2, node 0: no row");
        check("few.csv", "frame,node,x_m,y_m,z_m\n0,0,0,0,0\n0,1,0,0,1\n", "2 nodes per frame, need at least 3");
        check("text.csv", &good.replace("\n1,2,", "\n1,two,"), "row 7: node `two` is not a non-negative integer");
        check("cols.csv", &good.replace("\n1,2,", "\n1,2,9,"), "row 7: ");
        check("empty.csv", "frame,node,x_m,y_m,z_m\n", "no data rows");
        check("rec.txt", &good, "unknown extension");
        let npy = |name: &str, shape: &[usize], data: &[f64], wanted: &str| {
            let p = dir.path().join(name);
            write_npy(&p, shape, data).unwrap();
            let e = read_recording(&p, 0.04).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains(wanted), "expected `{wanted}` in: {e}");
        };
        npy("two.npy", &[3, 4, 2], &[0.0; 24], "shape [3, 4, 2], expected frames × nodes × 3");
        npy("flat.npy", &[12, 3], &[0.0; 36], "expected frames × nodes × 3");
        npy("short.npy", &[3, 2, 3], &[0.0; 18], "need at least 1 frame and 3 nodes");
        let mut data = vec![0.0; 36];
        data[3 * 4 + 3 * 2 + 1] = f64::NAN;
        npy("nan.npy", &[3, 4, 3], &data, "frame 1, node 2: y = NaN is not finite");
        let p = dir.path().join("fortran.npy");
        let mut b = npy_bytes(&[3, 4, 3], &[0.0; 36]);
        let at = b.windows(5).position(|w| w == b"False").unwrap();
        b.splice(at..at + 5, b"True ".iter().copied());
        std::fs::write(&p, b).unwrap();
        let e = read_recording(&p, 0.04).unwrap_err().to_string();
        assert!(e.contains("fortran.npy") && e.contains("Fortran-order"), "{e}");
    }

    /// The real clips of `scripts/fetch_worm_data.sh`; skipped with a notice when absent.
    #[test]
    fn elegansbot_clips_load_when_fetched() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/elegansbot");
        if !dir.is_dir() {
            println!("SKIPPED: {} is absent (run scripts/fetch_worm_data.sh)", dir.display());
            return;
        }
        for (name, frames) in [("kymogram_omega-turn.npy", 600), ("kymogram_delta-turn.npy", 300)] {
            let path = dir.join(name);
            let raw = read_npy(&path).unwrap();
            assert_eq!(raw.shape, vec![frames, 24], "{name}");
            let max_angle = raw.data.iter().fold(0.0f64, |m, a| m.max(a.abs()));
            let clip = read_kymogram(&path, &KymogramParams::default()).unwrap();
            assert_eq!((clip.frame_count(), clip.node_count(), clip.dt_s), (frames, 128, 1.0 / 32.0));
            assert!(clip.frames.iter().flatten().all(|p| p.iter().all(|v| v.is_finite()) && p.y == 0.0));
            let (jf, jdev) = clip.max_stretch_deviation();
            let xz = clip.frames_with_tangent_near(&Vector3::y(), 1e-3).len();
            let xy =
                read_kymogram(&path, &KymogramParams { plane: ClipPlane::Xy, ..KymogramParams::default() }).unwrap();
            let xy_near = xy.frames_with_tangent_near(&Vector3::y(), 1e-3).len();
            // elegansbot's own orientation: head segment along +e1 in every frame, no rotation.
            let unrotated = Clip {
                frames: raw
                    .data
                    .chunks_exact(24)
                    .map(|a| Spline::through(&planar(&kymogram_joints(a, WORM_LENGTH_M))).resample_by_arc_length(128).0)
                    .collect(),
                ..clip.clone()
            };
            let unrotated_near = unrotated.frames_with_tangent_near(&Vector3::y(), 1e-3).len();
            // Frames whose continuous tangent passes through ±e2 somewhere: the x-component of
            // the segment tangents changes sign (x–y placements).
            let crossing = |c: &Clip| {
                c.frames.iter().filter(|f| f.windows(3).any(|w| (w[1].x - w[0].x) * (w[2].x - w[1].x) <= 0.0)).count()
            };
            println!(
                "{name}: frames whose tangent passes through ±e2: x–y chord along +e1 {}, x–y head along +e1 {}",
                crossing(&xy),
                crossing(&unrotated)
            );
            let kappa_max = clip.frames.iter().flat_map(|f| menger_curvature(f)).fold(0.0, f64::max);
            let scaled =
                read_kymogram(&path, &KymogramParams { scale_to_length: true, ..KymogramParams::default() }).unwrap();
            let (sf, sdev) = scaled.max_stretch_deviation();
            println!("{name}: scaled to the body length: max |j − 1| {sdev:.3e} (frame {sf})");
            assert!(sdev < 1e-3, "{name}: scaled max |j − 1| = {sdev}");
            println!(
                "{name}: {frames} × 24, max |a_j| {max_angle:.3} rad, max |j − 1| {jdev:.3e} (frame {jf}), max κ {kappa_max:.4e} 1/m; \
                 frames with a tangent within 1e-3 of ±e2: x–z {xz}, x–y chord along +e1 {xy_near}, x–y head along +e1 {unrotated_near}"
            );
            assert_eq!(xz, 0, "{name}: x–z placement keeps tangents off ±e2");
            assert!(jdev < 0.02, "{name}: max |j − 1| = {jdev}");
        }
    }
}
