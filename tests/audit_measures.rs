//! The audit's propagation measure (`audit::wave`) on synthetic waves of known speed, direction
//! and reversal and on the substitute's ground truth, and the truth measures of a clip
//! (`audit::truth`) on series whose answer is known.
mod common;

use std::path::Path;

use common::worm_data_present;
use cosserat::audit::truth::{truth_metrics, TruthSeries};
use cosserat::audit::wave::{propagation, windows, Direction};
use cosserat::clip::synthetic::{roll_clip, FrameComparison, RollClipParams};
use cosserat::engine::input::clip_files::kymogram_rows;

/// The substitute plays the omega-turn kymogram (600 rows at 32 frames/s) slowed uniformly over
/// its 1160 frames of 0.04 s (`clip::synthetic`, step 2). So its true bending wave, measured on
/// the integrated 3D curve's curvature √(κ1² + κ2²) at 128 nodes, must run the way the raw
/// kymogram's joint angles (24 joints) run in the same stretch of time, and its speed in body
/// lengths per second must be the raw one over the slowing factor 1159·0.04 s / (599/32 s) =
/// 2.477. Two kymographs made independently of each other (joint angles against the curvature
/// of the framed curve) give the same wave: the measure sees the wave, not its sampling.
#[test]
fn the_truth_kymograph_has_the_recordings_wave() {
    if !worm_data_present("the_truth_kymograph_has_the_recordings_wave") {
        return;
    }
    let rows = kymogram_rows(&Path::new(env!("CARGO_MANIFEST_DIR")).join("data/elegansbot/kymogram_omega-turn.npy"))
        .expect("kymogram");
    let (_, truth) = roll_clip(&rows, None, &RollClipParams::default()).expect("roll_3d");
    let bending: Vec<Vec<f64>> =
        truth.frames.iter().map(|f| f.kappa.iter().map(|k| (k.x * k.x + k.y * k.y).sqrt()).collect()).collect();
    let n = truth.node_s_m.len();
    let s: Vec<f64> = (0..n).map(|i| i as f64 / (n - 1) as f64).collect();
    let clip = propagation(&bending, &s);
    // the raw kymogram: joint j at s = (j + 1)/25 body lengths; the clip's window of 116 frames
    // spans 116·599/1159 = 59.95 rows, so windows of 60 rows are the same stretches of time
    let joints = rows[0].len();
    let sj: Vec<f64> = (0..joints).map(|j| (j + 1) as f64 / (joints + 1) as f64).collect();
    let raw_windows: Vec<Vec<Vec<f64>>> = rows
        .chunks(60)
        .filter(|c| c.len() == 60)
        .map(|c| c.iter().map(|r| r.iter().map(|a| a.abs()).collect()).collect())
        .collect();
    assert_eq!(clip.windows.len(), raw_windows.len());
    let slowing = 1159.0 * 0.04 / (599.0 / 32.0);
    let mut compared = 0;
    for (w, raw) in clip.windows.iter().zip(&raw_windows) {
        let r = propagation(raw, &sj);
        let rw = r.windows[0];
        assert_eq!(w.direction, rw.direction, "clip window at frame {}: {w:?} against the kymogram's {rw:?}", w.first);
        if let (Some(v), Some(vr)) = (w.speed_body_per_frame(), rw.speed_body_per_frame()) {
            // body lengths per second on each clock
            let (v_s, vr_s) = (v / 0.04, vr * 32.0);
            assert!((vr_s / v_s / slowing - 1.0).abs() < 0.15, "window at {}: {v_s} against {vr_s}", w.first);
            compared += 1;
        }
    }
    assert!(compared >= 5, "{compared} windows with a wave in both");
    // the recording: forward crawling (head to tail), a reversal, the omega turn and forward again
    let letters = clip.letters();
    assert!(letters.starts_with(">>"), "{letters}");
    assert!(letters.contains('<'), "{letters}");
    assert!(letters.ends_with('>'), "{letters}");
}

/// The truth measures of a clip on series whose answer is known: a reconstruction equal to the
/// truth agrees with its wave in every window; played backwards, in none that has a direction;
/// the errors are the means and RMS of the frames' comparisons.
#[test]
fn truth_measures_of_known_series() {
    let (frames, nodes) = (400, 65);
    let wave = |t: usize, i: usize| {
        let s = i as f64 / (nodes - 1) as f64;
        (2.0 * std::f64::consts::PI * (s / 0.7 - t as f64 / 100.0)).sin().powi(2)
    };
    let truth: Vec<Vec<f64>> = (0..frames).map(|t| (0..nodes).map(|i| wave(t, i)).collect()).collect();
    let comparison = |b: f64, w: f64| FrameComparison {
        position_rel_l2: 0.0,
        bending_rel_l2: b,
        max_tangent_angle_rad: 0.0,
        twist_mean_per_m: 0.0,
        twist_rms_error_per_m: w,
        roll_offset_rad: 0.0,
    };
    let series = TruthSeries {
        bending_true: truth.clone(),
        bending_recovered: truth.clone(),
        // bending errors 0.1 and 0.3 alternately; twist errors 300 and 400 rad/m against a true 500
        comparisons: (0..frames)
            .map(|t| if t % 2 == 0 { comparison(0.1, 300.0) } else { comparison(0.3, 400.0) })
            .collect(),
        twist_per_m: vec![500.0; frames],
    };
    let m = truth_metrics(&series, 0.04);
    assert!((m.named("truth_bending_err_rel_mean").unwrap() - 0.2).abs() < 1e-12);
    // √((300² + 400²)/2) / 500
    assert!((m.named("truth_twist_err_rel").unwrap() - (125_000.0f64).sqrt() / 500.0).abs() < 1e-12);
    assert_eq!(m.named("bending_wave_truth_agreement"), Some(1.0));
    assert_eq!(m.named("truth_bending_wave_head_to_tail_share"), Some(1.0));
    // 0.7 body lengths per 100 frames of 0.04 s
    let v = m.named("truth_bending_wave_speed_body_per_s").unwrap();
    assert!((v / (0.007 / 0.04) - 1.0).abs() < 0.02, "{v}");
    let backwards = TruthSeries { bending_recovered: truth.iter().rev().cloned().collect(), ..series };
    let m = truth_metrics(&backwards, 0.04);
    assert_eq!(m.named("bending_wave_truth_agreement"), Some(0.0));
    let p = propagation(&truth, &(0..nodes).map(|i| i as f64 / (nodes - 1) as f64).collect::<Vec<_>>());
    assert!(p.windows.iter().all(|w| w.direction == Direction::HeadToTail));
}

/// A sinusoidal wave `sin(2π (s/λ ∓ t/P))` on 101 positions over the body, `sign` +1
/// towards the tail, −1 towards the head, from frame `from`.
fn wave(frames: std::ops::Range<usize>, lambda: f64, period: f64, sign: f64) -> Vec<Vec<f64>> {
    let s: Vec<f64> = (0..=100).map(|i| i as f64 / 100.0).collect();
    frames
        .map(|t| {
            s.iter().map(|s| (2.0 * std::f64::consts::PI * (s / lambda - sign * t as f64 / period)).sin()).collect()
        })
        .collect()
}

fn positions() -> Vec<f64> {
    (0..=100).map(|i| i as f64 / 100.0).collect()
}

/// A wave of wavelength 0.7 body lengths and period 100 frames runs 0.007 body lengths per
/// frame from the head to the tail: every window says so, with the speed within 2 %.
#[test]
fn a_travelling_wave_has_its_direction_and_speed() {
    let k = wave(0..1160, 0.7, 100.0, 1.0);
    let p = propagation(&k, &positions());
    assert_eq!(p.windows.len(), 10);
    for w in &p.windows {
        assert_eq!(w.direction, Direction::HeadToTail, "{w:?}");
        let v = w.speed_body_per_frame().unwrap();
        assert!((v / 0.007 - 1.0).abs() < 0.02, "{v}");
        assert!(w.coherence > 0.95, "{w:?}");
    }
    assert!(p.clarity() > 0.95);
    assert_eq!(p.share(Direction::HeadToTail), 1.0);
    // the same wave played backwards runs from the tail to the head
    let back: Vec<Vec<f64>> = k.iter().rev().cloned().collect();
    let q = propagation(&back, &positions());
    assert_eq!(q.share(Direction::TailToHead), 1.0);
    assert!((q.median_speed_body_per_frame().unwrap() / 0.007 - 1.0).abs() < 0.02);
    assert_eq!(p.agreement(&q), 0.0);
}

/// A wave that reverses at frame 580 (a window boundary): each window says its own direction.
#[test]
fn a_reversal_halfway_is_seen_in_each_window() {
    let mut k = wave(0..580, 0.7, 100.0, 1.0);
    k.extend(wave(580..1160, 0.7, 100.0, -1.0));
    let p = propagation(&k, &positions());
    assert_eq!(p.letters(), ">>>>><<<<<");
    assert_eq!(p.share(Direction::HeadToTail), 0.5);
}

/// A standing wave `sin(2π s/λ) sin(2π t/P)` and a wave faster than the frames resolve have no
/// direction; noise has no clear wave.
#[test]
fn standing_waves_and_noise_do_not_propagate() {
    let s = positions();
    let standing: Vec<Vec<f64>> =
        (0..400).map(|t| s.iter().map(|s| (6.0 * s).sin() * (0.06 * t as f64).sin()).collect()).collect();
    let p = propagation(&standing, &s);
    assert!(p.windows.iter().all(|w| w.direction == Direction::None), "{p:?}");
    assert_eq!(p.clarity(), 0.0);
    // a deterministic pseudo-random field
    let mut x = 12345u64;
    let noise: Vec<Vec<f64>> = (0..400)
        .map(|_| {
            s.iter()
                .map(|_| {
                    x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                    (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5
                })
                .collect()
        })
        .collect();
    let q = propagation(&noise, &s);
    assert!(q.windows.iter().all(|w| w.direction == Direction::None), "{q:?}");
}

/// The windows cover the clip: 1160 frames in ten, 60 frames in one, 10 in none.
#[test]
fn windows_cover_the_clip() {
    assert_eq!(windows(1160).len(), 10);
    assert_eq!(windows(1160).last(), Some(&(1044, 116)));
    assert_eq!(windows(1200).last(), Some(&(1044, 156)));
    assert_eq!(windows(60), vec![(0, 60)]);
    assert!(windows(10).is_empty());
}
