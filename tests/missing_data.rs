//! Missing data in a recording (`clip.missing = "nan"`, `clip::missing`): a synthetic recording
//! with ground truth (`cosserat synth`, 33 nodes, noise σ = 1e-7 m) run by the batch case
//! `cases/batch/roll_recording.toml` whole and with NaN in three patterns:
//! (a) 10 % of the nodes at random, (b) the last 10 % of the body (4 nodes) on 20 consecutive
//! frames, (c) 5 consecutive frames entirely.
//!
//! Every frame must reconstruct (certified, the clip complete). Errors against the truth are
//! measured separately on the tracked and the untracked nodes; the bounds:
//! - tracked positions: RMS within 2× that of the same nodes in the run without missing data
//!   (the same data hold them with the same weight; the fill adds a term weighted 1e-3);
//! - untracked positions, first the fill itself (`clip::missing`), within the error bound of
//!   the fill's construction, computed from the truth, plus 5σ for the noise of the tracked
//!   nodes it starts from:
//!   - an interior gap spanning `d` [m] between tracked nodes: `d² κ_max / 8`, the bound of the
//!     linear interpolant of a curve of curvature at most `κ_max` (the cubic the fill uses is
//!     not proven within it; measured on these data, it is);
//!   - an end continued by `d` [m] with the last turn: `κ_max d²`, two arcs of curvature at most
//!     `κ_max` leaving the same point in the same direction differ by at most that;
//!   - a bridged frame, linear in time between frames `τ` frames apart: `τ² max|Δ²x| / 8` with
//!     `Δ²x` the truth's second difference in time (the linear interpolant in time);
//!
//!   then the reconstruction, within twice that: it follows the fill only weakly (weight 1e-3)
//!   and the rod's own constraints (λd: ∂s x = d3 at unit stretch) may move it as far again;
//! - bending `b = κ1² + κ2²` on the tracked region (nodes whose two neighbours were tracked too:
//!   the nodal κ is the mean of the two adjacent elements'; 5 end nodes left out, as the truth
//!   scores do): relative L2 error within 2× that of the same nodes without missing data plus
//!   0.02. On the untracked nodes it is reported against the same nodes without missing data,
//!   and only checked to be finite: nothing bounds what the data do not show.
//!
//! A NaN without the key stays an error naming the frame and the node.
mod common;

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use assert_cmd::Command;
use common::{freefem_required, worm_data_present, Collect};
use cosserat::case::Case;
use cosserat::engine::clip::ClipFrame;
use cosserat::engine::input::clip_files::load_clip;
use cosserat::engine::rust::clip::{run_clip, ClipFrames};
use cosserat::io::npy::{read_npy, write_npy};
use nalgebra::Vector3;

const FRAMES: usize = 60;
const NODES: usize = 33;
/// the noise `cosserat synth` adds to every coordinate by default [m]
const SIGMA_M: f64 = 1e-7;
/// rod length of the batch case [m]
const LENGTH_M: f64 = 1e-3;
/// nodes left out at each end by the bending scores (`engine::clip::TRUTH_SKIP_NODES`)
const SKIP: usize = 5;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn cosserat() -> Command {
    let mut c = Command::cargo_bin("cosserat").expect("binary");
    c.current_dir(root());
    c
}

/// One synthetic recording with its truth sidecar: `dir/corpus/roll_000.npy`.
fn synth(dir: &Path) -> PathBuf {
    let corpus = dir.join("corpus");
    let out = cosserat()
        .args(["synth", "--count", "1", "--frames", &FRAMES.to_string(), "--seed", "1", "--out"])
        .arg(&corpus)
        .output()
        .expect("synth");
    assert!(out.status.success(), "synth: {}", String::from_utf8_lossy(&out.stderr));
    corpus.join("roll_000.npy")
}

/// The batch case on `recording`, with `clip.missing = "nan"` when `missing`.
fn case_file(dir: &Path, recording: &Path, missing: bool) -> PathBuf {
    let text = std::fs::read_to_string(root().join("cases/batch/roll_recording.toml")).expect("batch case");
    let mut key = format!("file = {:?}", recording.display().to_string());
    if missing {
        key += "\nmissing = \"nan\"";
    }
    let text: String = text
        .lines()
        .map(|l| if l.starts_with("file = ") { key.clone() } else { l.to_string() })
        .collect::<Vec<_>>()
        .join("\n");
    let name = recording.file_stem().expect("stem").to_string_lossy();
    let path = dir.join(format!("{name}{}.toml", if missing { "" } else { "_whole" }));
    std::fs::write(&path, text).expect("case");
    path
}

/// Which nodes are tracked in each scenario (a seeded LCG for (a)).
fn tracked(scenario: char) -> Vec<Vec<bool>> {
    let mut t = vec![vec![true; NODES]; FRAMES];
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    match scenario {
        'a' => t.iter_mut().flatten().for_each(|n| {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            *n = (state >> 11) as f64 / (1u64 << 53) as f64 >= 0.1;
        }),
        'b' => t[20..40].iter_mut().for_each(|f| f[NODES - 4..].fill(false)),
        'c' => t[30..35].iter_mut().for_each(|f| f.fill(false)),
        _ => unreachable!(),
    }
    t
}

/// `recording` with NaN at the untracked nodes, as `dst` (with the same truth sidecar).
fn write_masked(recording: &Path, dst: &Path, tracked: &[Vec<bool>]) {
    let mut a = read_npy(recording).expect("recording");
    for (f, frame) in tracked.iter().enumerate() {
        for (i, _) in frame.iter().enumerate().filter(|(_, t)| !**t) {
            a.data[3 * (NODES * f + i)..3 * (NODES * f + i) + 3].fill(f64::NAN);
        }
    }
    write_npy(dst, &a.shape, &a.data).expect("write");
    let truth = |p: &Path| p.with_file_name(format!("{}.truth.npy", p.file_stem().expect("stem").to_string_lossy()));
    std::fs::copy(truth(recording), truth(dst)).expect("truth sidecar");
}

/// Every frame of the case's clip, which must run whole.
fn run(case: &Path) -> Vec<ClipFrame> {
    let case = Case::from_file(case).expect("case");
    let (clip, truth) = load_clip(&case).expect("clip");
    let got = Arc::new(Mutex::new(Vec::new()));
    let frames = ClipFrames::Loaded { clip: &clip, truth: truth.as_ref(), start: None };
    let out = run_clip(&case, frames, &[], Collect(got.clone()), |_, _| {}).expect("clip runs");
    assert!(out.stopped.is_none(), "{}: stopped: {:?}", case.name, out.stopped);
    let got = got.lock().expect("frames").clone();
    got
}

/// Relative L2 error of the bending `b = κ1² + κ2²` over the (frame, node) pairs `keep`.
fn bending_error(frames: &[ClipFrame], keep: impl Fn(usize, usize) -> bool) -> f64 {
    let (mut d, mut b) = (0.0, 0.0);
    for (f, fr) in frames.iter().enumerate() {
        let t = fr.truth.as_ref().expect("truth");
        for i in (0..NODES).filter(|&i| keep(f, i)) {
            d += (t.bending_recovered[i] - t.bending_true[i]).powi(2);
            b += t.bending_true[i].powi(2);
        }
    }
    (d / b).sqrt()
}

/// RMS of `|x − x_true| / L` over the (frame, node) pairs `keep`.
fn position_rms(frames: &[ClipFrame], truth: &[Vec<Vector3<f64>>], keep: impl Fn(usize, usize) -> bool) -> f64 {
    let (mut s, mut n) = (0.0, 0.0);
    for (f, fr) in frames.iter().enumerate() {
        for i in (0..NODES).filter(|&i| keep(f, i)) {
            s += ((fr.nodes.x[i] - truth[f][i]).norm() / LENGTH_M).powi(2);
            n += 1.0;
        }
    }
    (s / n).sqrt()
}

/// The fill's error bound at node `i` of frame `f` (module doc) [m].
fn fill_bound(t: &[Vec<bool>], truth: &[Vec<Vector3<f64>>], kappa_max: &[f64], f: usize, i: usize) -> f64 {
    let h = LENGTH_M / (NODES - 1) as f64;
    let tracked_count = t[f].iter().filter(|x| **x).count();
    if tracked_count < 2 {
        // bridged: linear in time between the nearest frames with two tracked nodes
        let a = (0..f).rev().find(|&k| t[k].iter().filter(|x| **x).count() >= 2).expect("earlier frame");
        let b = (f + 1..FRAMES).find(|&k| t[k].iter().filter(|x| **x).count() >= 2).expect("later frame");
        let acc = (a.max(1)..b.min(FRAMES - 1))
            .map(|k| (truth[k + 1][i] - truth[k][i] * 2.0 + truth[k - 1][i]).norm())
            .fold(0.0, f64::max);
        return ((b - a) as f64).powi(2) * acc / 8.0;
    }
    let before = (0..i).rev().find(|&j| t[f][j]);
    let after = (i + 1..NODES).find(|&j| t[f][j]);
    match (before, after) {
        (Some(a), Some(b)) => (((b - a) as f64) * h).powi(2) * kappa_max[f] / 8.0,
        (Some(a), None) => (((i - a) as f64) * h).powi(2) * kappa_max[f],
        (None, Some(b)) => (((b - i) as f64) * h).powi(2) * kappa_max[f],
        (None, None) => unreachable!("two tracked nodes"),
    }
}

/// The whole run, its truth positions and the measures of one scenario against it.
struct Baseline {
    frames: Vec<ClipFrame>,
    truth_x: Vec<Vec<Vector3<f64>>>,
    kappa_max: Vec<f64>,
}

/// The measures of one scenario and of the whole run on the same nodes.
struct Measured {
    cert_max: f64,
    /// RMS position error [L]: tracked nodes, untracked nodes (and the whole run on each)
    position: [f64; 2],
    position_whole: [f64; 2],
    untracked_max: f64,
    /// worst error / its bound of an untracked node: of the fill, of the reconstruction
    fill_ratio: (f64, usize, usize),
    solution_ratio: (f64, usize, usize),
    /// bending relative L2 error: tracked region, untracked nodes (and the whole run on each)
    bending: [f64; 2],
    bending_whole: [f64; 2],
}

/// The worst ratio of `|x − x_true|` over the untracked nodes to their fill bound (+ 5σ).
fn worst_ratio(t: &[Vec<bool>], base: &Baseline, x: impl Fn(usize, usize) -> Vector3<f64>) -> (f64, usize, usize) {
    let mut worst = (0.0, 0, 0);
    for f in 0..FRAMES {
        for i in (0..NODES).filter(|&i| !t[f][i]) {
            let bound = fill_bound(t, &base.truth_x, &base.kappa_max, f, i) + 5.0 * SIGMA_M;
            let ratio = (x(f, i) - base.truth_x[f][i]).norm() / bound;
            if ratio > worst.0 {
                worst = (ratio, f, i);
            }
        }
    }
    worst
}

/// Run scenario `which` and measure it against the truth and the whole run.
fn scenario(dir: &Path, recording: &Path, base: &Baseline, which: char) -> Measured {
    let t = tracked(which);
    let masked = dir.join(format!("missing_{which}.npy"));
    write_masked(recording, &masked, &t);
    let case_path = case_file(dir, &masked, true);
    let frames = run(&case_path);
    assert_eq!(frames.len(), FRAMES, "({which}) frames reconstructed");
    for (f, fr) in frames.iter().enumerate() {
        assert_eq!(fr.report.nodes_tracked, t[f].iter().filter(|x| **x).count(), "({which}) frame {f}");
    }
    let (clip, _) = load_clip(&Case::from_file(&case_path).expect("case")).expect("clip");
    let tracked = |f: usize, i: usize| t[f][i];
    let untracked = |f: usize, i: usize| !t[f][i];
    // the nodal bending depends on the angles of the node and its two neighbours
    let region = |f: usize, i: usize| (SKIP..NODES - SKIP).contains(&i) && (i - 1..=i + 1).all(|j| t[f][j]);
    let truth = &base.truth_x;
    let t = &t;
    Measured {
        cert_max: frames.iter().map(|f| f.report.certificate).fold(0.0, f64::max),
        position: [position_rms(&frames, truth, tracked), position_rms(&frames, truth, untracked)],
        position_whole: [position_rms(&base.frames, truth, tracked), position_rms(&base.frames, truth, untracked)],
        untracked_max: (0..FRAMES)
            .flat_map(|f| (0..NODES).filter(move |&i| !t[f][i]).map(move |i| (f, i)))
            .map(|(f, i)| (frames[f].nodes.x[i] - truth[f][i]).norm() / LENGTH_M)
            .fold(0.0, f64::max),
        fill_ratio: worst_ratio(t, base, |f, i| clip.frames[f][i]),
        solution_ratio: worst_ratio(t, base, |f, i| frames[f].nodes.x[i]),
        bending: [bending_error(&frames, region), bending_error(&frames, untracked)],
        bending_whole: [bending_error(&base.frames, region), bending_error(&base.frames, untracked)],
    }
}

/// Report scenario `which` and hold it to the bounds of the module doc.
fn check(which: char, m: &Measured) {
    println!(
        "({which}) {FRAMES} frames, certificate max {:.1e}; position RMS [L]: tracked {:.2e} (whole run {:.2e}), \
         untracked {:.2e} (whole run {:.2e}), untracked max {:.2e}; worst error / fill bound: fill {:.2} (frame {}, \
         node {}), reconstruction {:.2} (frame {}, node {}); bending rel. L2: tracked region {:.3} (whole run {:.3}), \
         untracked {:.3} (whole run {:.3})",
        m.cert_max,
        m.position[0],
        m.position_whole[0],
        m.position[1],
        m.position_whole[1],
        m.untracked_max,
        m.fill_ratio.0,
        m.fill_ratio.1,
        m.fill_ratio.2,
        m.solution_ratio.0,
        m.solution_ratio.1,
        m.solution_ratio.2,
        m.bending[0],
        m.bending_whole[0],
        m.bending[1],
        m.bending_whole[1]
    );
    assert!(m.cert_max <= 1e-10, "({which}) certificate max {:e}", m.cert_max);
    assert!(m.position[0] <= 2.0 * m.position_whole[0], "({which}) tracked positions {:?}", m.position);
    assert!(m.fill_ratio.0 <= 1.0, "({which}) a fill over its bound: {:?}", m.fill_ratio);
    assert!(m.solution_ratio.0 <= 2.0, "({which}) an untracked node over twice its fill bound: {:?}", m.solution_ratio);
    assert!(m.bending[0] <= 2.0 * m.bending_whole[0] + 0.02, "({which}) tracked bending {:?}", m.bending);
    assert!(m.bending[1].is_finite(), "({which}) untracked bending {:?}", m.bending);
}

#[test]
fn recordings_with_missing_nodes_and_frames_reconstruct() {
    if !worm_data_present("recordings_with_missing_nodes_and_frames_reconstruct") {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let recording = synth(dir.path());
    let truth_x: Vec<Vec<Vector3<f64>>> = read_npy(&recording)
        .expect("recording")
        .data
        .chunks_exact(3 * NODES)
        .map(|f| f.chunks_exact(3).map(|c| Vector3::new(c[0], c[1], c[2])).collect())
        .collect();
    let frames = run(&case_file(dir.path(), &recording, false));
    assert_eq!(frames.len(), FRAMES);
    let kappa_max: Vec<f64> = frames
        .iter()
        .map(|f| f.truth.as_ref().expect("truth").bending_true.iter().fold(0.0f64, |m, b| m.max(b.sqrt())))
        .collect();
    let base = Baseline { frames, truth_x, kappa_max };
    for which in ['a', 'b', 'c'] {
        check(which, &scenario(dir.path(), &recording, &base, which));
    }
}

/// The FreeFEM engine carries the same weight (a P1 field in the tracking term): `cosserat
/// compare` passes every row, with its derived tolerances, on frames 28–37 of the recording with
/// 10 % of the nodes missing and frames 30–34 missing entirely.
#[test]
fn freefem_agrees_on_a_recording_with_missing_data() {
    if !freefem_required() || !worm_data_present("freefem_agrees_on_a_recording_with_missing_data") {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let recording = synth(dir.path());
    let mut t = tracked('a');
    t[30..35].iter_mut().for_each(|f| f.fill(false));
    let masked = dir.path().join("missing_ac.npy");
    write_masked(&recording, &masked, &t);
    let case = case_file(dir.path(), &masked, true);
    let text = std::fs::read_to_string(&case)
        .expect("case")
        .replace("missing = \"nan\"", "missing = \"nan\"\nframes = [28, 38]");
    std::fs::write(&case, text).expect("case");
    let out = dir.path().join("compare");
    let run =
        cosserat().arg("compare").arg(&case).args(["--frames", "10", "--out"]).arg(&out).output().expect("compare");
    let report = std::fs::read_to_string(out.join("compare.csv")).unwrap_or_default();
    assert!(run.status.success(), "{}\n{report}", String::from_utf8_lossy(&run.stderr));
    let rows: Vec<&str> = report.lines().skip(1).collect();
    assert!(rows.len() > 10 && rows.iter().all(|r| r.contains(",pass,")), "{report}");
}

/// Without `clip.missing`, a NaN in a recording is an error naming its frame and node (and the
/// key that would accept it).
#[test]
fn nan_without_the_key_is_an_error_naming_frame_and_node() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut csv = String::from("frame,node,x_m,y_m,z_m\n");
    for frame in 0..3 {
        for node in 0..NODES {
            let z = if (frame, node) == (2, 7) {
                "NaN".to_string()
            } else {
                format!("{:e}", node as f64 * LENGTH_M / 32.0)
            };
            csv += &format!("{frame},{node},0,0,{z}\n");
        }
    }
    let recording = dir.path().join("nan.csv");
    std::fs::write(&recording, csv).expect("recording");
    let case = case_file(dir.path(), &recording, false);
    let out =
        cosserat().arg("run").arg(&case).arg("--out").arg(dir.path().join("out")).arg("--quiet").output().expect("run");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("frame 2, node 7") && stderr.contains("clip.missing = \"nan\""), "{stderr}");
}
