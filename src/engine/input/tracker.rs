//! Synthetic recordings as a single-camera tracker writes them (`cosserat synth --tracker`):
//! 2D midlines in micrometres, frames numbered from 1, tracking noise in x and y, frames lost
//! (written as empty cells, as `NaN`, or left out) and a run of frames whose last tail points
//! are lost, each with its ground truth, so that what a reconstruction of them gets right can
//! be measured.
//!
//! Recording `k` plays kymogram `k mod K` of those given (the elegansbot omega and delta turns,
//! `crate::clip`) at the tracker's frame rate from a seeded first row: its shapes are the
//! `roll_3d` clip of those rows with no roll and no twist (`crate::clip::synthetic`: the
//! bending in the body plane is κ2, the truth exact to the integrator's 4th order), placed in
//! the x–y plane (d2 along +e3) with a seeded heading and a position on a 10 mm plate. It is
//! written as `worm_KKK.csv` with the header `frame,node,x_um,y_um` (micrometres with 4
//! decimals) and its truth as `worm_KKK.truth.npy` (`super::truth_file`: every frame from the
//! first to the last, the lost ones too). `corpus.json` lists the parameters and, per
//! recording, its length, kymogram rows, heading, lost frames and tail gap. One seed decides
//! every choice: the same seed writes the same bytes.
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Rotation3, Vector3};

use super::clip_files::kymogram_rows;
use super::corpus::{CorpusError, SplitMix64, LISTING};
use super::truth_file::{truth_sidecar, write_truth};
use crate::clip::synthetic::{roll_clip, RollClipParams, TimeMapping};
use crate::clip::KYMOGRAM_FPS;
use crate::io::files::{write_atomic, OutputError};

/// What `cosserat synth --tracker` writes.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TrackerParams {
    /// recordings (≥ 1)
    pub count: usize,
    /// frames per recording (≥ 2), numbered from [`TrackerParams::first_frame`]
    pub frames: usize,
    /// midline points per frame (≥ 12: the clip measures leave 5 elements at each end)
    pub nodes: usize,
    /// body lengths [m]: recording `k` has `lengths_m[k mod len]`
    pub lengths_m: Vec<f64>,
    /// time between frames Δt [s]
    pub dt_s: f64,
    /// standard deviation of the Gaussian noise on x and on y [m]
    pub noise_m: f64,
    /// the seed of every random choice
    pub seed: u64,
    /// what the tracker loses
    pub losses: Losses,
    /// the number of the first frame in the file
    pub first_frame: usize,
}

impl Default for TrackerParams {
    /// The trial of a single-camera tracker: 49 points at 30 frames/s with 1 µm of noise.
    fn default() -> Self {
        TrackerParams {
            count: 2,
            frames: 300,
            nodes: 49,
            lengths_m: vec![1.1e-3, 0.85e-3],
            dt_s: 1.0 / 30.0,
            noise_m: 1e-6,
            seed: 41,
            losses: Losses { lost_frames: 6, tail_lost_frames: 16, tail_lost_nodes: 5 },
            first_frame: 1,
        }
    }
}

/// What a tracker loses in each recording.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Losses {
    /// frames lost whole, written in turn as empty cells, as `NaN` and as no rows at all
    pub lost_frames: usize,
    /// consecutive frames whose last `tail_lost_nodes` points are lost (empty cells)
    pub tail_lost_frames: usize,
    pub tail_lost_nodes: usize,
}

impl Losses {
    /// Nothing lost.
    pub const NONE: Losses = Losses { lost_frames: 0, tail_lost_frames: 0, tail_lost_nodes: 0 };
}

/// One recording: its name and what was drawn for it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TrackerEntry {
    pub name: String,
    pub length_m: f64,
    pub kymogram: String,
    /// the kymogram rows played, `[first, end)`
    pub rows: [usize; 2],
    /// the body's heading on the plate [rad]
    pub heading_rad: f64,
    /// the file's numbers of the frames lost whole, and how each is written
    pub lost_frames: Vec<(usize, &'static str)>,
    /// the file's numbers of the frames `[first, end)` whose tail points are lost
    pub tail_lost: [usize; 2],
    pub noise_seed: u64,
}

fn check(name: &'static str, value: f64, ok: bool, requirement: &'static str) -> Result<(), CorpusError> {
    if ok {
        Ok(())
    } else {
        Err(CorpusError::Parameter { name, value, requirement })
    }
}

/// Write the recordings of `p` into `dir` from the kymograms `kymograms` (module doc).
pub fn write_tracker_corpus(
    dir: &Path,
    kymograms: &[PathBuf],
    p: &TrackerParams,
) -> Result<Vec<TrackerEntry>, CorpusError> {
    check("count", p.count as f64, p.count >= 1, "at least one recording")?;
    check("frames", p.frames as f64, p.frames >= 2, "at least 2 frames")?;
    check("nodes", p.nodes as f64, p.nodes >= 12, "at least 12 points")?;
    check("noise_m", p.noise_m, p.noise_m.is_finite() && p.noise_m >= 0.0, "finite and >= 0")?;
    check("dt_s", p.dt_s, p.dt_s.is_finite() && p.dt_s > 0.0, "finite and > 0")?;
    check("lengths", p.lengths_m.len() as f64, !p.lengths_m.is_empty(), "at least one length")?;
    if let Some(&l) = p.lengths_m.iter().find(|l| !(l.is_finite() && **l > 0.0)) {
        check("length_m", l, false, "finite and > 0")?;
    }
    check("kymograms", kymograms.len() as f64, !kymograms.is_empty(), "at least one kymogram")?;
    check(
        "tail_lost_nodes",
        p.losses.tail_lost_nodes as f64,
        p.losses.tail_lost_nodes + 3 <= p.nodes,
        "leaves 3 points",
    )?;
    check(
        "lost_frames",
        p.losses.lost_frames as f64,
        p.losses.lost_frames + 2 <= p.frames,
        "leaves the first and last frame",
    )?;
    check(
        "tail_lost_frames",
        p.losses.tail_lost_frames as f64,
        p.losses.tail_lost_frames <= p.frames,
        "at most the frames",
    )?;
    let rows: Vec<Vec<Vec<f64>>> = kymograms
        .iter()
        .map(|k| kymogram_rows(k))
        .collect::<Result<_, _>>()
        .map_err(super::clip_files::ClipFileError::from)?;
    std::fs::create_dir_all(dir).map_err(|source| OutputError::Io { path: dir.to_path_buf(), source })?;
    let mut rng = SplitMix64(p.seed);
    let width = (p.count - 1).to_string().len().max(3);
    let mut entries = Vec::with_capacity(p.count);
    for k in 0..p.count {
        let which = k % kymograms.len();
        let played = Played { rows: &rows[which], file: &kymograms[which] };
        let entry = write_recording(dir, played, format!("worm_{k:0width$}"), k, p, &mut rng)?;
        entries.push(entry);
    }
    let listing = serde_json::json!({ "params": p, "recordings": entries });
    let path = dir.join(LISTING);
    let text = serde_json::to_string_pretty(&listing)
        .map_err(|e| OutputError::Invalid { path: path.clone(), reason: e.to_string() })?;
    write_atomic(&path, format!("{text}\n").as_bytes())?;
    Ok(entries)
}

/// The rotation that takes a clip in the x–z plane (d2 = e2) into the x–y plane with d2 along
/// +e3, heading `heading` [rad] about e3: `Rz(heading) Rx(π/2)`.
pub fn onto_plate(heading: f64) -> Matrix3<f64> {
    let rx = Rotation3::from_axis_angle(&Vector3::x_axis(), PI / 2.0);
    let rz = Rotation3::from_axis_angle(&Vector3::z_axis(), heading);
    (rz * rx).into_inner()
}

/// The kymogram a recording plays: its rows and the file they were read from.
#[derive(Clone, Copy)]
struct Played<'a> {
    rows: &'a [Vec<f64>],
    file: &'a Path,
}

/// Recording `k` (module doc), named `name`, playing `kymogram`.
fn write_recording(
    dir: &Path,
    kymogram: Played,
    name: String,
    k: usize,
    p: &TrackerParams,
    rng: &mut SplitMix64,
) -> Result<TrackerEntry, CorpusError> {
    let rows = kymogram.rows;
    let length_m = p.lengths_m[k % p.lengths_m.len()];
    // the kymogram at the tracker's rate: (frames − 1) Δt of the kymogram's time
    let played = (((p.frames - 1) as f64 * p.dt_s * KYMOGRAM_FPS).round() as usize + 1).clamp(2, rows.len());
    let span = rows.len() - played;
    let first_row = ((span + 1) as f64 * rng.uniform()) as usize;
    let first_row = first_row.min(span);
    let heading = 2.0 * PI * rng.uniform();
    let offset = Vector3::new(3e-3 + 4e-3 * rng.uniform(), 3e-3 + 4e-3 * rng.uniform(), 0.0);
    let noise_seed = rng.next_u64();
    // lost frames: distinct, never the first or the last
    let mut lost: Vec<usize> = Vec::new();
    while lost.len() < p.losses.lost_frames {
        let f = 1 + ((p.frames - 2) as f64 * rng.uniform()) as usize;
        if !lost.contains(&f) {
            lost.push(f);
        }
    }
    lost.sort_unstable();
    let tail_start = p.frames / 3 + ((p.frames / 3) as f64 * rng.uniform()) as usize;
    let tail =
        [tail_start.min(p.frames - p.losses.tail_lost_frames), (tail_start + p.losses.tail_lost_frames).min(p.frames)];
    let gen = RollClipParams {
        length_m,
        nodes: p.nodes,
        frames: p.frames,
        dt_s: p.dt_s,
        roll_total_rad: 0.0,
        twist_per_m: 0.0,
        time_mapping: TimeMapping::StretchOmega,
        ..RollClipParams::default()
    };
    gen.validate()?;
    let (clip, mut truth) = roll_clip(&rows[first_row..first_row + played], None, &gen)?;
    let r = onto_plate(heading);
    truth.rotate(&r);
    const HOW: [&str; 3] = ["empty", "NaN", "dropped"];
    let how = |f: usize| lost.iter().position(|&l| l == f).map(|i| HOW[i % 3]);
    let mut noise = SplitMix64(noise_seed);
    let mut text = String::from("frame,node,x_um,y_um\n");
    for (f, frame) in clip.frames.iter().enumerate() {
        let number = p.first_frame + f;
        let tail_lost = (tail[0]..tail[1]).contains(&f);
        for (i, x) in frame.iter().enumerate() {
            // the noise is drawn for every point, written or not: the same seed, the same noise
            let (nx, ny) = (noise.normal(), noise.normal());
            let y = r * x + offset;
            let cells = match how(f) {
                Some("dropped") => continue,
                Some("NaN") => "NaN,NaN".to_string(),
                Some(_) => ",".to_string(),
                None if tail_lost && i + p.losses.tail_lost_nodes >= p.nodes => ",".to_string(),
                None => format!("{:.4},{:.4}", (y.x + p.noise_m * nx) * 1e6, (y.y + p.noise_m * ny) * 1e6),
            };
            let _ = writeln!(text, "{number},{i},{cells}");
        }
    }
    let path = dir.join(format!("{name}.csv"));
    write_truth(&truth_sidecar(&path), &truth)?;
    write_atomic(&path, text.as_bytes())?;
    Ok(TrackerEntry {
        name,
        length_m,
        kymogram: kymogram.file.display().to_string(),
        rows: [first_row, first_row + played],
        heading_rad: heading,
        lost_frames: lost.iter().map(|&f| (p.first_frame + f, how(f).unwrap_or(""))).collect(),
        tail_lost: [p.first_frame + tail[0], p.first_frame + tail[1]],
        noise_seed,
    })
}
