//! Reading kymograms and recordings: good files, malformed ones (every message names the file
//! and what is wrong), hostile indices and sizes, and the clip cases' lengths.
use super::*;
use crate::clip::tests::{menger_curvature, planar, wave};
use crate::clip::{kymogram_joints, ClipPlane, Spline, PAPER_NODES, WORM_LENGTH_M};
use crate::engine::input::resolve::resolve_recording;
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
    assert!(matches!(e, ClipFileError::Input(InputError::Open { .. })), "{e}");
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
    assert_eq!((clip.frames.clone(), clip.dt_s, clip.frame_count(), clip.node_count()), (frames.clone(), 0.04, 3, 4));
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
    check("header.csv", &good.replace("x_m", "x"), "column `x` is not `x_` and a unit; expected frame,node,x_U,y_U");
    check(
        "missing.csv",
        &[&lines[..6], &lines[7..]].concat().join("\n"),
        "frame 1, node 1: no row (nodes are numbered",
    );
    check("dup.csv", &[&lines[..], &[lines[6]]].concat().join("\n"), "row 13: frame 1, node 1 already given in row 6");
    // a node beyond the others': every other frame lacks it
    check("count.csv", &[&lines[..], &["1,4,0,0,0"]].concat().join("\n"), "frame 0, node 4: no row");
    check(
        "gap.csv",
        &good.replace("\n1,", "\n3,"),
        "frame 2 comes where frame 1 was expected: frame 1 has no rows (a dropped frame?",
    );
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
    npy("two.npy", &[3, 4, 2], &[0.0; 24], "frame 0 has zero length");
    npy("four.npy", &[3, 4, 4], &[0.0; 48], "shape [3, 4, 4], expected frames × nodes × 3 (or × 2)");
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

/// The real clips of `scripts/fetch_worm_data.sh` (`crate::clip::tests::worm_data`).
#[test]
fn elegansbot_clips_load_when_fetched() {
    let Some(dir) =
        crate::clip::tests::worm_data("kymogram_omega-turn.npy").and_then(|p| p.parent().map(Path::to_path_buf))
    else {
        return;
    };
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
        let xy = read_kymogram(&path, &KymogramParams { plane: ClipPlane::Xy, ..KymogramParams::default() }).unwrap();
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

/// Indices far beyond the rows of the file: no overflow, no allocation by index, the first
/// missing row named.
#[test]
fn huge_and_overflowing_indices_name_the_missing_row() {
    let dir = tempfile::tempdir().unwrap();
    let good = csv_text(&sample_frames());
    let check = |name: &str, text: &str, wanted: &str| {
        let p = write(dir.path(), name, text);
        let e = read_recording(&p, 0.04).unwrap_err().to_string();
        assert!(e.contains(name) && e.ends_with(wanted), "expected `{wanted}` in: {e}");
    };
    let last_frame = |f: &str| format!("{good}{f},0,0,0,0\n");
    let gap = "frame 3 has no rows (a dropped frame? with clip.missing = \"nan\" it is a lost frame, bridged from its \
               neighbours; or is the frame column a timestamp, or a -1 written unsigned?)";
    check("max.csv", &last_frame("18446744073709551615"), gap);
    check("tera.csv", &last_frame("1000000000000"), gap);
    check(
        "node.csv",
        &format!("{good}0,18446744073709551615,0,0,0\n"),
        "frame 0, node 4: no row (nodes are numbered contiguously from 0 or 1; if the tracker leaves untracked nodes \
         out, set clip.missing = \"nan\" in the case)",
    );
    // frames may start anywhere: one row of frame 2⁶⁴ − 1 is one frame of one node
    check("first.csv", "frame,node,x_m,y_m,z_m\n18446744073709551615,0,0,0,0\n", "1 nodes per frame, need at least 3");
    check(
        "wide.csv",
        &last_frame("18446744073709551616"),
        "frame `18446744073709551616` is not a non-negative integer",
    );
    check("minus.csv", &last_frame("-1"), "frame `-1` is not a non-negative integer");
}

/// A kymogram whose frames × mesh nodes exceed [`MAX_CLIP_POSITIONS`] is refused before the
/// clip is built (2 MB of angles would have made 800 MB of positions).
#[test]
fn kymograms_beyond_the_position_limit_are_refused_before_building() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("long.npy");
    let frames = MAX_CLIP_POSITIONS / PAPER_NODES + 1;
    write_npy(&p, &[frames, 1], &vec![0.1; frames]).unwrap();
    let e = read_kymogram(&p, &KymogramParams::default()).unwrap_err().to_string();
    assert!(
        e.ends_with(
            "long.npy: 262145 frames × 128 nodes are 33554560 positions, more than the 33554432 a clip may hold; use a \
             shorter clip"
        ),
        "{e}"
    );
}

/// A recording case on a temporary directory: `elements` elements of a 1 mm rod, the
/// recording `file` there.
pub(crate) fn recording_case(dir: &Path, file: &str, elements: usize, frames: Option<[usize; 2]>) -> Case {
    let frames = frames.map(|[a, b]| format!("frames = [{a}, {b}]\n")).unwrap_or_default();
    let text = format!(
        "description = \"recording\"\n[rod]\nlength_m = 1e-3\nelements = {elements}\n[material]\n\
         young_modulus_pa = 1.1e5\nshear_modulus_pa = 5e4\nshear_correction = 1\n[cross_section]\nshape = \"circle\"\n\
         radius_m = 2e-5\n[clip]\nkind = \"recording\"\nfile = \"{file}\"\nframe_interval_s = 0.04\n\
         min_cos_beta = 1e-3\n{frames}[inverse]\nlambda_g = 1e9\nlambda_f = 1e-3\nlambda_l = 1e-6\nlambda_d = 1\n\
         lambda_kappa = [0, 0, 0]\n[solver]\nanalysis = \"inverse\"\nmethod = \"fixed_point\"\nrelaxation = 0.5\n\
         tolerance = 1e-6\nmax_iterations = 10\n"
    );
    Case::from_toml(&text, "rec", &dir.join("rec.toml")).unwrap()
}

/// Straight frames along e3 on `nodes` nodes, frame `f` of length `lengths[f]` [m].
fn straight_frames(lengths: &[f64], nodes: usize) -> Vec<Vec<Vector3<f64>>> {
    lengths
        .iter()
        .map(|l| (0..nodes).map(|i| Vector3::new(0.0, 0.0, l * i as f64 / (nodes - 1) as f64)).collect())
        .collect()
}

/// Recorded frames far from the rod length are refused at load, naming the file, the frame,
/// its measured and corrected lengths, the noise level, the rod length, the ratio and the band;
/// within the band they load. Straight noiseless frames: the corrected length is the polyline's.
#[test]
fn recordings_must_have_the_rod_length() {
    let dir = tempfile::tempdir().unwrap();
    let case = recording_case(dir.path(), "rec.csv", 11, None);
    let run = |ratios: &[f64]| {
        let lengths: Vec<f64> = ratios.iter().map(|r| r * 1e-3).collect();
        std::fs::write(dir.path().join("rec.csv"), csv_text(&straight_frames(&lengths, 12))).unwrap();
        load_clip(&case).map(|(c, _)| c.frame_count()).map_err(|e| e.to_string())
    };
    let tail = "scale the recording to metres of this rod, or set rod.length_m to the length of the recorded body \
                (\"from_data\" estimates it)";
    let e = run(&[1.0, 1000.0]).unwrap_err();
    assert!(
        e.ends_with(&format!(
            "rec.csv, frame 1: the centreline is 1.0000e0 m long after the noise correction (measured: 1.0000e0 m as \
             the polyline of its nodes, noise level 0.00e0 m per coordinate, chords of 1 node spacing(s); \
             docs/decisions.md D18), 1000.000× the rod length rod.length_m = 1e-3 m (allowed: 0.900× to 1.100×, \
             ±10 %); {tail}"
        )),
        "{e}"
    );
    let e = run(&[0.5, 1.0]).unwrap_err();
    assert!(e.contains("rec.csv, frame 0: the centreline is 5.0000e-4 m long after the noise correction"), "{e}");
    assert!(e.contains("0.500× the rod length"), "{e}");
    let e = run(&[1.0, 1.0, 1.2]).unwrap_err();
    assert!(e.contains("frame 2: the centreline is 1.2000e-3 m long") && e.contains("1.200× the rod"), "{e}");
    assert_eq!(run(&[1.0, 1.09, 0.91]), Ok(3));
    // The frames solved are checked, named by their index in the file.
    let part = recording_case(dir.path(), "rec.csv", 11, Some([1, 3]));
    std::fs::write(dir.path().join("rec.csv"), csv_text(&straight_frames(&[2e-3, 1e-3, 1.3e-3], 12))).unwrap();
    let e = load_clip(&part).unwrap_err().to_string();
    assert!(e.contains("rec.csv, frame 2: the centreline is 1.3000e-3 m long") && e.contains("1.300×"), "{e}");
}

/// `rod.length_m = "from_data"`: the case cannot be loaded before its length is resolved; the
/// resolved case has the median corrected length of the frames in its range, their spread
/// (1.4826 × the median absolute deviation 5e-5 m over 1.2e-3 m) and range, and loads.
#[test]
fn from_data_is_resolved_from_the_frames_of_the_recording() {
    let dir = tempfile::tempdir().unwrap();
    let frames = straight_frames(&[2e-3, 1.25e-3, 1.15e-3, 1.2e-3], 12);
    std::fs::write(dir.path().join("rec.csv"), csv_text(&frames)).unwrap();
    let from_data = [("rod.length_m".to_string(), toml::Value::String("from_data".into()))];
    let case = recording_case(dir.path(), "rec.csv", 11, Some([1, 4])).with_overrides(&from_data).unwrap();
    let e = load_clip(&case).unwrap_err().to_string();
    assert!(e.starts_with("case `rec`: rod.length_m = \"from_data\" is the body length of the recording"), "{e}");
    let resolved = resolve_recording(&case).unwrap();
    let b = resolved.body_length().unwrap();
    assert!((resolved.mesh.length_m / 1.2e-3 - 1.0).abs() < 1e-14, "{b:?}");
    assert_eq!((b.length_m, b.frames), (resolved.mesh.length_m, 3));
    assert!((b.spread_rel / (1.482_602_218_505_602 * 5e-5 / 1.2e-3) - 1.0).abs() < 1e-9, "{b:?}");
    assert!((b.min_m / 1.15e-3 - 1.0).abs() < 1e-14 && (b.max_m / 1.25e-3 - 1.0).abs() < 1e-14, "{b:?}");
    assert_eq!(load_clip(&resolved).map(|(c, _)| c.frame_count()).map_err(|e| e.to_string()), Ok(3));
    // resolved once: returned as it is; a sweep point of it keeps the estimate
    assert_eq!(resolve_recording(&resolved).unwrap().rod.length, resolved.rod.length);
    let point = resolved.with_values(&[("lambda_d", 2.0.into())]).unwrap();
    assert_eq!(point.body_length(), Some(b));
    // the whole file: frame 0 is 2e-3 m, 1.67× the median of the four (1.225e-3 m)
    let whole = recording_case(dir.path(), "rec.csv", 11, None).with_overrides(&from_data).unwrap();
    let e = load_clip(&resolve_recording(&whole).unwrap()).unwrap_err().to_string();
    assert!(e.contains("frame 0: the centreline is 2.0000e-3 m long") && e.contains("1.633×"), "{e}");
}

/// The ratio `R` of a length error's "R× the rod length".
fn ratio_in(e: &str) -> f64 {
    let head = &e[..e.find("× the rod length").expect("a length error")];
    head.rsplit(' ').next().and_then(|r| r.parse().ok()).expect("a ratio")
}

/// `cosserat synth`'s recordings (1 mm body, 100 frames, seed 11) at every noise level from 0
/// to 10 µm, at 33 and 128 nodes, pass the length check (the raw polyline at 10 µm is 35 % and
/// 240 % too long); the same recordings in mm read as m, or on a rod of 0.5× or 1.2× their
/// length, are refused. Needs the elegansbot data (`crate::clip::tests::worm_data`).
#[test]
fn synthetic_recordings_pass_the_length_check_at_any_noise() {
    use crate::engine::input::corpus::{recording_path, write_corpus, CorpusParams};
    let Some(kymogram) = crate::clip::tests::worm_data("kymogram_omega-turn.npy") else { return };
    let dir = tempfile::tempdir().unwrap();
    for nodes in [33usize, 128] {
        for noise_m in [0.0, 0.3e-6, 1e-6, 3e-6, 10e-6] {
            let params = CorpusParams { count: 2, frames: 100, nodes, noise_m, seed: 11, ..CorpusParams::default() };
            let corpus = dir.path().join(format!("c{nodes}_{noise_m:e}"));
            let entries = write_corpus(&corpus, &kymogram, &params).unwrap();
            for e in &entries {
                let file = recording_path(&corpus, &e.name);
                let case = recording_case(&corpus, file.to_str().unwrap(), nodes - 1, None);
                let loaded = load_clip(&case).map(|(c, _)| c.frame_count());
                assert_eq!(loaded.map_err(|e| e.to_string()), Ok(100), "{nodes} nodes, σ = {noise_m:e}");
                if noise_m != 10e-6 {
                    continue;
                }
                // wrong units and wrong rod lengths are still refused
                let clip = read_recording(&file, 0.04).unwrap();
                let mm: Vec<f64> =
                    clip.frames.iter().flatten().flat_map(|p| [p.x, p.y, p.z]).map(|v| v * 1e3).collect();
                let in_mm = corpus.join(format!("{}_mm.npy", e.name));
                write_npy(&in_mm, &[100, nodes, 3], &mm).unwrap();
                let case_mm = recording_case(&corpus, in_mm.to_str().unwrap(), nodes - 1, None);
                let e_mm = load_clip(&case_mm).unwrap_err().to_string();
                assert!((ratio_in(&e_mm) / 1000.0 - 1.0).abs() < 0.1, "{e_mm}");
                for (rod, ratio) in [("5e-4", 2.0), ("1.2e-3", 1.0 / 1.2)] {
                    let wrong =
                        case.with_overrides(&[("rod.length_m".into(), toml::Value::String(rod.into()))]).unwrap();
                    let e = load_clip(&wrong).unwrap_err().to_string();
                    assert!(e.contains(&format!("rod.length_m = {rod} m")), "{e}");
                    assert!((ratio_in(&e) / ratio - 1.0).abs() < 0.1, "{e}");
                }
            }
        }
    }
}

/// The fetch script is named for the elegansbot kymograms only; a user's file is named with
/// the case key that points to it.
#[test]
fn a_missing_clip_file_names_the_case_key() {
    let dir = tempfile::tempdir().unwrap();
    let e = load_clip(&recording_case(dir.path(), "mine.csv", 11, None)).unwrap_err().to_string();
    assert_eq!(e, format!("{} does not exist (the clip.file of case `rec`)", dir.path().join("mine.csv").display()));
    let e = load_clip(&recording_case(dir.path(), "../data/elegansbot/gone.npy", 11, None)).unwrap_err().to_string();
    assert!(
        e.ends_with(
            "gone.npy does not exist (the clip.file of case `rec`); the elegansbot kymograms are fetched and \
             checksum-verified by scripts/fetch_worm_data.sh"
        ),
        "{e}"
    );
}

/// The clip measures' skips of `run` are the ones `case` validates the mesh for, and a mesh of
/// [`MIN_CLIP_ELEMENTS`] keeps one element inside them and 3 data curvature values.
#[test]
fn the_minimum_clip_mesh_matches_the_measures() {
    use crate::clip::{CLIP_SKIP_ELEMENTS, MIN_CLIP_ELEMENTS};
    use crate::engine::common::clip_frame::{planar_xz_curvature, sign_alternation, TRUTH_SKIP_NODES};
    use crate::engine::common::metrics::INNER_SKIP_ELEMENTS;
    assert_eq!((CLIP_SKIP_ELEMENTS, TRUTH_SKIP_NODES), (INNER_SKIP_ELEMENTS, INNER_SKIP_ELEMENTS));
    assert_eq!((MIN_CLIP_ELEMENTS, 2 * INNER_SKIP_ELEMENTS + 1, 2 * TRUTH_SKIP_NODES + 1), (11, 11, 11));
    // A zig-zag centreline on the smallest mesh: its data curvature alternates in sign.
    let n = MIN_CLIP_ELEMENTS + 1;
    let x: Vec<Vector3<f64>> = (0..n).map(|i| Vector3::new(1e-6 * (i % 2) as f64, 0.0, 1e-4 * i as f64)).collect();
    let k = planar_xz_curvature(&x, 1e-4);
    assert_eq!((k.len(), sign_alternation(&k)), (MIN_CLIP_ELEMENTS - 1, 1.0));
    assert_eq!(sign_alternation(&k[..2]), 0.0, "fewer than 3 values: no roughness at all");
}

/// max |L_frame / L − 1| of every clip case of `cases/` on its own mesh (the numbers in the
/// doc of [`MAX_LENGTH_DEVIATION`]), and of the kymograms without the scaling to the body
/// length; skipped with a notice when the elegansbot data are absent.
#[test]
fn length_ratios_of_the_clip_cases() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    if !root.join("data/elegansbot").is_dir() {
        println!("SKIPPED: data/elegansbot is absent (run scripts/fetch_worm_data.sh)");
        return;
    }
    // over the fully tracked frames: a frame with lost nodes is filled from its neighbours
    // (`clip::missing`), so its length is not the tracker's
    let deviation = |c: &Clip, l: f64| {
        let whole = |i: usize| c.tracked.as_ref().is_none_or(|t| t[i].iter().all(|&k| k));
        c.frames
            .iter()
            .enumerate()
            .filter(|(i, _)| whole(*i))
            .map(|(_, f)| (polyline_length(f) / l - 1.0).abs())
            .fold(0.0, f64::max)
    };
    for path in crate::case::case_files(&root.join("cases")).unwrap() {
        let case = Case::from_file(&path).unwrap();
        let Some(src) = case.clip() else { continue };
        if src.kind == ClipKind::Recording && !src.file.is_file() {
            // a template for the user's recordings (`cosserat synth --tracker` writes one)
            println!("{}: SKIPPED, its recording {} is absent", case.name, src.file.display());
            continue;
        }
        let case = resolve_recording(&case).unwrap();
        let (clip, _) = load_clip(&case).unwrap();
        let dev = deviation(&clip, case.mesh.length_m);
        let mut line = format!("{}: {} frames, max |L_frame/L − 1| = {dev:.2e}", case.name, clip.frame_count());
        if src.kind == ClipKind::Kymogram {
            let params = KymogramParams { scale_to_length: false, ..case.kymogram_params().unwrap() };
            let unscaled = deviation(&read_kymogram(&src.file, &params).unwrap(), case.mesh.length_m);
            line += &format!(", unscaled {unscaled:.2e}");
            assert!(unscaled < MAX_LENGTH_DEVIATION / 10.0, "{line}");
        }
        println!("{line}");
        // a tracker's recording carries its noise into the polyline (1 µm on 49 nodes: 5e-3,
        // the table of MAX_LENGTH_DEVIATION); the clips of the paper have none
        let bound =
            if src.kind == ClipKind::Recording { MAX_LENGTH_DEVIATION / 10.0 } else { MAX_LENGTH_DEVIATION / 100.0 };
        assert!(dev < bound, "{line}");
    }
}
