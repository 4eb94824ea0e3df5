//! Scores of a tracker recording (`cosserat synth --tracker`) against its truth sidecar: the
//! GCV smoothing spline of each fully tracked frame (docs/noise.md N4), and each run folder
//! given (its `curvature.csv`, `frames.csv` and `run.json`). The tables of `docs/results.md`
//! ("Tracker recordings") are its output.
//!
//! Usage: `cargo run --release --example tracker_score -- REC.csv [RUN_DIR ...]
//! [--bound-per-m K]` (frames at 1/30 s, untracked cells empty or NaN). A run's frames are
//! matched to the recording's in order from its first (a run of a copy numbered from 0 is
//! scored as one numbered from 1).
//!
//! Per run and over the fully tracked frames (all frames in brackets):
//! - the bending error, the relative L² error of √(κ1² + κ2²) per frame against the truth, 5
//!   elements left out at each end (N5): median and 90th percentile;
//! - the signed error: the relative L² error of κ2 against the truth's signed curvature in the
//!   plate's plane (the sign of the whole run chosen to fit best), median;
//! - κ1's share of the bending, Σκ1² / Σ(κ1² + κ2²) over a frame, its range over the frames;
//! - the frames whose largest bending √(κ1² + κ2²), and whose largest |κ| (κ3 included),
//!   exceeds the bound K [1/m] (default: the inverse radius of `cases/worm_2d_recording.toml`'s
//!   section scaled to the body length, 1/(2e-5 · L/1e-3)): how many, how many of them flagged
//!   in `frames.csv`, the first (the recording's frame number); the run's largest of each;
//! - σ̂ and λg of `run.json` (automatic weights), the frames solved again (`resolved`).
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use cosserat::clip::length::BodyLength;
use cosserat::clip::missing::MissingData;
use cosserat::engine::input::clip_files::read_recording_as;
use cosserat::engine::input::recording::ReadSpec;
use cosserat::engine::input::truth_file::{read_truth, truth_sidecar};
use cosserat::recorded::smoothing::SmoothingSpline;
use cosserat::study::score::{bending_error, spline_bending, truth_bending};
use nalgebra::Vector3;

/// Elements left out at each end (N5).
const SKIP: usize = 5;

fn percentile(v: &[f64], q: f64) -> f64 {
    let mut v: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    if q == 0.5 {
        let n = v.len();
        return if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) };
    }
    v[((q * v.len() as f64).ceil() as usize).max(1) - 1]
}

/// Median and 90th percentile of `e` over the frames of `which`.
fn med_p90(e: &[f64], which: &[usize]) -> (f64, f64) {
    let v: Vec<f64> = which.iter().map(|&k| e[k]).collect();
    (percentile(&v, 0.5), percentile(&v, 0.9))
}

/// Relative L² error of `b` against `truth` over the elements kept.
fn signed_error(b: &[f64], truth: &[f64]) -> f64 {
    bending_error(b, truth, SKIP)
}

/// The truth's signed curvature per element in the plane normal to `n`: κ2 (the bending of the
/// synthetic worm, κ1 = 0) times the orientation of d2 against `n` [1/m].
fn truth_signed(t: &cosserat::clip::synthetic::FrameTruth, n: &Vector3<f64>) -> Vec<f64> {
    let v: Vec<f64> = t.kappa.iter().zip(&t.q).map(|(k, q)| k.y * q.row(1).transpose().dot(n).signum()).collect();
    v.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect()
}

/// The spline's signed curvature `(r' × r'')·n / |r'|³` per element [1/m].
fn spline_signed(frame: &[Vector3<f64>], length_m: f64, n: &Vector3<f64>) -> Vec<f64> {
    let elements = frame.len() - 1;
    let Some(s) = SmoothingSpline::fit_uniform(frame, length_m) else { return vec![f64::NAN; elements] };
    let h = s.t_end() / elements as f64;
    (0..elements)
        .map(|e| {
            let (d1, d2) = s.derivatives((e as f64 + 0.5) * h);
            d1.cross(&d2).dot(n) / d1.norm().powi(3)
        })
        .collect()
}

/// A run's curvature per frame (in the order of its frame numbers, from its first) and element:
/// `(κ1, κ2, κ3)` [1/m].
fn read_run_curvature(dir: &Path) -> Vec<Vec<Vector3<f64>>> {
    let mut r = csv::Reader::from_path(dir.join("curvature.csv")).expect("curvature.csv");
    let mut frames: BTreeMap<i64, Vec<Vector3<f64>>> = BTreeMap::new();
    for rec in r.records() {
        let rec = rec.expect("row");
        let f = |i: usize| rec[i].parse::<f64>().expect("number");
        frames.entry(rec[0].parse().expect("frame")).or_default().push(Vector3::new(f(2), f(3), f(4)));
    }
    frames.into_values().collect()
}

/// A column of a run's `frames.csv` per frame (0 where the column is absent).
fn frames_column(dir: &Path, name: &str) -> Vec<f64> {
    let mut r = csv::Reader::from_path(dir.join("frames.csv")).expect("frames.csv");
    let col = r.headers().expect("header").iter().position(|h| h == name);
    r.records().map(|rec| col.map_or(0.0, |c| rec.expect("row")[c].parse().unwrap_or(0.0))).collect()
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut bound = None;
    if let Some(i) = args.iter().position(|a| a == "--bound-per-m") {
        bound = Some(args[i + 1].parse::<f64>().expect("--bound-per-m K"));
        args.drain(i..i + 2);
    }
    let path = PathBuf::from(args.first().expect("usage: tracker_score REC.csv [RUN_DIR ...] [--bound-per-m K]"));
    let spec = ReadSpec { missing: MissingData::Nan, dt_s: 1.0 / 30.0, ..ReadSpec::default() };
    let clip = read_recording_as(&path, &spec).expect("recording");
    let (n, frames) = (clip.node_count(), clip.frame_count());
    let s: Vec<f64> = (0..n).map(|i| i as f64 / (n - 1) as f64).collect();
    let truth = read_truth(&truth_sidecar(&path), frames, &s).expect("truth");
    let normal = clip.recording.plane_normal.unwrap_or_else(Vector3::z);
    let length = BodyLength::estimate_in(&clip.frames, Some(&normal)).expect("length").length_m;
    let bound = bound.unwrap_or(1.0 / (2e-5 * length / 1e-3));
    let full: Vec<usize> = (0..frames).filter(|&k| clip.nodes_tracked(k) == n).collect();
    let all: Vec<usize> = (0..frames).collect();
    let tb: Vec<Vec<f64>> = truth.frames.iter().map(truth_bending).collect();
    let ts: Vec<Vec<f64>> = truth.frames.iter().map(|t| truth_signed(t, &normal)).collect();
    let truth_max = tb.iter().flatten().fold(0.0f64, |a, b| a.max(*b));
    println!(
        "{}: {frames} frames, {} fully tracked, body length {:.4} mm, truth's largest bending {:.2} /mm, bound {:.2} /mm",
        path.display(),
        full.len(),
        length * 1e3,
        truth_max * 1e-3,
        bound * 1e-3
    );
    let sp: Vec<f64> =
        full.iter().map(|&k| bending_error(&spline_bending(&clip.frames[k], length), &tb[k], SKIP)).collect();
    let ss: Vec<f64> =
        full.iter().map(|&k| signed_error(&spline_signed(&clip.frames[k], length, &normal), &ts[k])).collect();
    let idx: Vec<usize> = (0..full.len()).collect();
    let (m, p) = med_p90(&sp, &idx);
    println!("| spline (GCV) | – | – | {m:.3} | {p:.3} | {:.3} | – | – | – | – |", percentile(&ss, 0.5));
    println!(
        "| run | σ̂ [µm] | λg | bending error median (all frames) | p90 (all frames) | signed error median | κ1 share | frames over the bound (flagged): bending; |κ| | largest bending / |κ| [1/mm] | resolved |"
    );
    for dir in args.iter().skip(1).map(PathBuf::from) {
        score_run(&dir, (&tb, &ts), (&full, &all), (bound, clip.recording.first_frame));
    }
}

/// One run's row (module doc).
fn score_run(
    dir: &Path,
    (tb, ts): (&[Vec<f64>], &[Vec<f64>]),
    (full, all): (&[usize], &[usize]),
    (bound, first_frame): (f64, usize),
) {
    let kappa = read_run_curvature(dir);
    let solved = kappa.len().min(tb.len());
    let bend = |k: usize| -> Vec<f64> { kappa[k].iter().map(|v| v.x.hypot(v.y)).collect() };
    let e: Vec<f64> =
        (0..tb.len()).map(|k| if k < solved { bending_error(&bend(k), &tb[k], SKIP) } else { f64::NAN }).collect();
    let kappa2 = |k: usize, sign: f64| -> Vec<f64> { kappa[k].iter().map(|v| sign * v.y).collect() };
    let signed = |sign: f64| -> Vec<f64> {
        full.iter().filter(|&&k| k < solved).map(|&k| signed_error(&kappa2(k, sign), &ts[k])).collect()
    };
    let (plus, minus) = (signed(1.0), signed(-1.0));
    let sgn = if percentile(&plus, 0.5) <= percentile(&minus, 0.5) { plus } else { minus };
    let share: Vec<f64> = (0..solved)
        .map(|k| {
            let kept = &kappa[k][SKIP..kappa[k].len().saturating_sub(SKIP)];
            let k1: f64 = kept.iter().map(|v| v.x * v.x).sum();
            k1 / (k1 + kept.iter().map(|v| v.y * v.y).sum::<f64>())
        })
        .collect();
    let kmax: Vec<f64> = (0..solved).map(|k| kappa[k].iter().map(|v| v.norm()).fold(0.0, f64::max)).collect();
    let bmax: Vec<f64> = (0..solved).map(|k| bend(k).into_iter().fold(0.0, f64::max)).collect();
    let flagged = frames_column(dir, "flagged");
    let resolved = frames_column(dir, "resolved").iter().filter(|&&r| r > 0.0).count();
    let over_bound = |m: &[f64]| -> String {
        let over: Vec<usize> = (0..solved).filter(|&k| m[k].is_nan() || m[k] > bound).collect();
        let flagged = over.iter().filter(|&&k| flagged.get(k).copied().unwrap_or(0.0) > 0.0).count();
        let first = over.first().map_or(String::new(), |f| format!(" from frame {}", f + first_frame));
        format!("{} ({flagged}){first}", over.len())
    };
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("run.json")).expect("run.json")).expect("json");
    let w = |key: &str| json["weights"][key].as_f64().unwrap_or(f64::NAN);
    let ((m, p), (ma, pa)) = (med_p90(&e, full), med_p90(&e, all));
    let range = (share.iter().copied().fold(f64::INFINITY, f64::min), share.iter().copied().fold(0.0, f64::max));
    println!(
        "| {} ({solved} frames) | {:.3} | {:.1e} | {m:.3} ({ma:.3}) | {p:.3} ({pa:.3}) | {:.3} | {:.2}–{:.2} | {}; {} | {:.1} / {:.1} | {resolved} |",
        dir.display(),
        w("noise_m") * 1e6,
        w("lambda_g"),
        percentile(&sgn, 0.5),
        range.0,
        range.1,
        over_bound(&bmax),
        over_bound(&kmax),
        bmax.iter().copied().fold(0.0, f64::max) * 1e-3,
        kmax.iter().copied().fold(0.0, f64::max) * 1e-3,
    );
}
