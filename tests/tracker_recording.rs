//! A single-camera tracker's recording as it comes (`cosserat synth --tracker`): a 1.1 mm worm,
//! 49 points, 2D CSV in micrometres from frame 1, 1 µm of noise in x and y, 3 frames lost (an
//! empty frame, a NaN frame, a dropped one) and 8 frames without their last 5 tail points,
//! reconstructed by the template `cases/worm_2d_recording.toml` as a user would run it. Numbers
//! against the truth the generator wrote:
//! - the body length from the data (with the gaps) within 0.5 % of 1.1 mm; the noise estimated
//!   in the plane within 15 % of 1 µm (the 3D pooled estimate was 0.46 µm);
//! - every frame's frame d2 along the plate's normal (the truth's roll offset below 1e-6 rad):
//!   the bending is κ2 on every frame;
//! - the bending error (docs/noise.md N5) of the fully tracked frames, median and 90th
//!   percentile, at or below the GCV smoothing spline's of the same frames;
//! - no frame's curvature above the physical bound unflagged; the lost frames reported lost;
//! - a frame whose solution from the previous frame is over the curvature bound is solved again
//!   from its own data (`resolved`) and stays flagged while still over it; its solution is the
//!   one a clip solved from the data on every frame (`start = "data_guess"`) finds.
//!
//! Needs the elegansbot kymograms (`scripts/fetch_worm_data.sh`; `common::worm_data_present`).
mod common;

use std::path::{Path, PathBuf};

use cosserat::case::Case;
use cosserat::clip::missing::MIN_TRACKED;
use cosserat::engine::input::clip_files::load_clip;
use cosserat::engine::input::resolve::resolve_recording;
use cosserat::engine::input::tracker::{write_tracker_corpus, Losses, TrackerParams};
use cosserat::jobs::clip_run::run_clip_case;
use cosserat::study::score::{bending_error, spline_bending, truth_bending};
use nalgebra::Vector3;

fn percentiles(mut v: Vec<f64>) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let median = if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) };
    (median, v[((0.9 * n as f64).ceil() as usize).max(1) - 1])
}

/// The omega-turn kymogram, `None` (with a notice) when absent.
fn omega_kymogram() -> Option<PathBuf> {
    let omega = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/elegansbot/kymogram_omega-turn.npy");
    common::worm_data_present("tracker_recording").then_some(omega)
}

/// `cases/worm_2d_recording.toml` on `recording`, its `[clip]` table given the lines `extra`
/// (`clip.start` replaced), read as `cosserat run` reads it.
fn template_on(dir: &Path, name: &str, recording: &Path, extra: &str) -> Case {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("cases/worm_2d_recording.toml")).unwrap();
    let text = common::edit(&text, "../data/tracker/worm_000.csv", &recording.display().to_string());
    let text = match extra.contains("start = ") {
        true => common::edit(&text, "start = \"previous_frame\"\n", ""),
        false => text,
    };
    let text = common::edit(&text, "missing = \"nan\"\n", &format!("missing = \"nan\"\n{extra}"));
    let case_path = dir.join(format!("{name}.toml"));
    std::fs::write(&case_path, &text).unwrap();
    resolve_recording(&Case::from_file(&case_path).unwrap()).unwrap()
}

#[test]
fn a_planar_tracker_recording_is_reconstructed_as_it_comes() {
    let Some(omega) = omega_kymogram() else { return };
    let dir = tempfile::tempdir().unwrap();
    let params = TrackerParams {
        count: 1,
        frames: 40,
        lengths_m: vec![1.1e-3],
        losses: Losses { lost_frames: 3, tail_lost_frames: 8, tail_lost_nodes: 5 },
        seed: 7,
        ..TrackerParams::default()
    };
    let entries = write_tracker_corpus(dir.path(), &[omega], &params).unwrap();
    let recording = dir.path().join("worm_000.csv");
    let case = template_on(dir.path(), "worm_2d_recording", &recording, "");
    let src = case.clip().unwrap();
    assert_eq!(src.recording.data_plane, Some(Vector3::z()));
    assert_eq!(src.placement.gauge, Vector3::z());
    assert_eq!(src.frames, Some((1, 41)), "reported under the file's frame numbers");
    let length = case.body_length().unwrap().length_m;
    assert!((length / 1.1e-3 - 1.0).abs() < 5e-3, "body length {length:e}");
    // the section scaled to the worm: 2e-5 m at 1 mm
    let radius = match case.section {
        cosserat::case::Section::Shape(cosserat::model::material::CrossSection::Circle { radius_m }) => radius_m,
        other => panic!("the worm's section is a circle, got {other:?}"),
    };
    assert!((radius / (2e-5 * length / 1e-3) - 1.0).abs() < 1e-12, "radius {radius:e}");

    let out = dir.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    let run = run_clip_case(&case, &out, |_, _| {}).unwrap();
    let w = run.weights.unwrap();
    assert!((w.noise_m / 1e-6 - 1.0).abs() < 0.15, "noise estimated {:e}", w.noise_m);
    assert_eq!(run.reports.len(), 40);
    let truth = run.truth.as_ref().unwrap();
    let roll = truth.comparisons.iter().map(|c| c.roll_offset_rad.abs()).fold(0.0, f64::max);
    assert!(roll < 1e-6, "roll offset {roll:e} rad: the bending is not all κ2");

    // bending errors of the fully tracked frames, recovered (κ1 = 0: |κ2|) and spline
    let (clip, gt) = load_clip(&case).unwrap();
    let gt = gt.unwrap();
    let full: Vec<usize> = (0..clip.frame_count()).filter(|&k| clip.nodes_tracked(k) == clip.node_count()).collect();
    // the frames the generator wrote whole (a lost frame may fall in the tail gap)
    let entry = &entries[0];
    let whole = (1..41)
        .filter(|f| {
            !entry.lost_frames.iter().any(|l| l.0 == *f) && !(entry.tail_lost[0]..entry.tail_lost[1]).contains(f)
        })
        .count();
    assert_eq!(full.len(), whole);
    assert!(whole < 40 - 3, "the tail gap is in the clip");
    let recovered: Vec<f64> = full
        .iter()
        .map(|&k| {
            let b: Vec<f64> = kappa2_of(&run, k).iter().map(|v| v.abs()).collect();
            bending_error(&b, &truth_bending(&gt.frames[k]), 5)
        })
        .collect();
    let spline: Vec<f64> = full
        .iter()
        .map(|&k| bending_error(&spline_bending(&clip.frames[k], length), &truth_bending(&gt.frames[k]), 5))
        .collect();
    let (r, s) = (percentiles(recovered), percentiles(spline));
    println!("bending error median / p90: recovered {:.3} / {:.3}, spline {:.3} / {:.3}", r.0, r.1, s.0, s.1);
    assert!(r.0 <= s.0 && r.1 <= s.1, "recovered {r:?} against the spline's {s:?}");

    // the gate: no curvature above the bound unflagged; the lost frames are the generator's
    let bound = src.gate.max_curvature_per_m;
    assert!(run.reports.iter().all(|r| r.fit.curvature_max_per_m <= bound || r.fit.flagged));
    let lost: Vec<usize> = run.reports.iter().filter(|r| r.nodes_tracked < MIN_TRACKED).map(|r| r.frame).collect();
    let written: Vec<usize> = entries[0].lost_frames.iter().map(|l| l.0).collect();
    assert_eq!(lost, written);
}

/// The re-solve of a carried solution (docs/decisions.md D26), made to happen: with
/// `clip.max_curvature_per_m` at the median of the frames' largest curvature, the frames whose solution
/// from the previous frame exceeds it are solved again from their data guess. Each frame over
/// the bound is flagged; a frame solved from the previous frame and over the gate is
/// `resolved` (unless it had restarted from its data already), and no frame within the gate
/// is; the re-solved frame's curvature is the one the clip solved from the data on every frame
/// finds (the same data guess; the two differ only through the previous frame's angles in the
/// time coupling Λω: by 1e-6 1/m, 1e-10 of the bound).
#[test]
fn a_carried_frame_over_the_curvature_bound_is_solved_again_from_its_data() {
    let Some(omega) = omega_kymogram() else { return };
    let dir = tempfile::tempdir().unwrap();
    let params = TrackerParams { count: 1, frames: 30, losses: Losses::NONE, seed: 3, ..TrackerParams::default() };
    let entries = write_tracker_corpus(dir.path(), &[omega], &params).unwrap();
    let recording = dir.path().join("worm_000.csv");
    // the bound: the median over the frames of the largest curvature of the clip solved without one
    let run_with = |name: &str, extra: &str| {
        let case = template_on(dir.path(), name, &recording, extra);
        let out = dir.path().join(name);
        std::fs::create_dir_all(&out).unwrap();
        run_clip_case(&case, &out, |_, _| {}).unwrap()
    };
    let free = run_with("free", "max_curvature_per_m = 1e9\n");
    let mut largest: Vec<f64> = free.reports.iter().map(|r| r.fit.curvature_max_per_m).collect();
    largest.sort_by(f64::total_cmp);
    let bound = largest[largest.len() / 2];
    assert!(bound > 5e3 && bound < 5e4, "median largest |κ| {bound:e} 1/m ({} mm long)", entries[0].length_m * 1e3);
    let carried = run_with("carried", &format!("max_curvature_per_m = {bound:e}\n"));
    let fresh = run_with("fresh", &format!("max_curvature_per_m = {bound:e}\nstart = \"data_guess\"\n"));
    let (mut resolved, mut worst) = (0, 0.0f64);
    for (k, (c, f)) in carried.reports.iter().zip(&fresh.reports).enumerate() {
        let over = c.fit.curvature_max_per_m > bound;
        assert!(
            !over || c.fit.flagged,
            "frame {}: |κ| {:e} over the bound {bound:e} unflagged",
            c.frame,
            c.fit.curvature_max_per_m
        );
        assert!(c.fit.flagged || !c.fit.resolved, "frame {} resolved but within the gate", c.frame);
        // a frame kept from the previous frame's solution is within the bound
        assert!(k == 0 || !over || c.restarted, "frame {}: a carried solution over the bound kept", c.frame);
        assert!(!f.fit.resolved, "frame {}: a frame solved from its data is never solved again", f.frame);
        if !c.fit.resolved {
            continue;
        }
        resolved += 1;
        assert!(k > 0, "the first frame is solved from its data guess");
        let diff =
            kappa2_of(&carried, k).iter().zip(kappa2_of(&fresh, k)).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        worst = worst.max(diff);
        assert!(
            diff < 1e-7 * bound,
            "frame {}: re-solved κ2 differs from the data-guess solve by {diff:e} 1/m",
            c.frame
        );
    }
    // the bound is below the truth on some frames: the mechanism ran
    let over = free.reports.iter().skip(1).filter(|r| r.fit.curvature_max_per_m > bound).count();
    println!("{over} frames over the bound {bound:.3e} 1/m without it; {resolved} re-solved with it, κ2 within {worst:.1e} 1/m of the data-guess solve");
    assert!(over > 0 && resolved > 0, "{over} frames over the bound, {resolved} re-solved");
}

/// The recovered κ2 [1/m] of frame `k` of a clip short enough that the kymographs draw every
/// frame (at most 150).
fn kappa2_of(run: &cosserat::engine::clip::ClipRun, k: usize) -> &[f64] {
    let column = run.kymograph.columns.iter().find(|c| c.index == k);
    &column.unwrap_or_else(|| panic!("frame {k} is not drawn (stride {})", run.kymograph.stride)).kappa2
}
