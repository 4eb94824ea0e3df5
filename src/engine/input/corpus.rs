//! A corpus of synthetic recordings for `cosserat batch` (`cosserat synth`): `roll_3d` clips
//! (`crate::clip::synthetic`) with a different roll, twist, excerpt of the kymogram and
//! position noise each, written as recordings (`NAME.npy`, frames × nodes × 3 [m]) with their
//! ground truth (`NAME.truth.npy`, [`super::truth_file`]) and `corpus.json` listing the
//! parameters of each. Everything is derived from one seed: the same seed writes the same
//! bytes.
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use super::clip_files::{kymogram_rows, ClipFileError};
use super::truth_file::{truth_sidecar, write_truth};
use crate::clip::synthetic::{roll_clip, RollClipParams, TimeMapping};
use crate::clip::ClipError;
use crate::io::files::{write_atomic, OutputError};
use crate::io::npy::write_npy;

/// Frames per kymogram row played.
const ROWS_PER_FRAME_INV: usize = 2;

/// The listing of a corpus: its parameters and each recording's.
pub const LISTING: &str = "corpus.json";

/// Errors of writing a corpus.
#[derive(Debug, thiserror::Error)]
pub enum CorpusError {
    #[error("kymogram")]
    Kymogram(#[from] ClipFileError),
    #[error(transparent)]
    Generator(#[from] ClipError),
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error("{name} = {value}: {requirement}")]
    Parameter { name: &'static str, value: f64, requirement: &'static str },
}

/// What `cosserat synth` writes.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CorpusParams {
    /// recordings to write (≥ 1)
    pub count: usize,
    /// frames per recording (≥ 2)
    pub frames: usize,
    /// nodes per frame (the batch case's `rod.elements + 1`)
    pub nodes: usize,
    /// body length L [m]
    pub length_m: f64,
    /// time between frames Δt [s]
    pub dt_s: f64,
    /// standard deviation of the Gaussian noise added to every coordinate [m]
    pub noise_m: f64,
    /// RMS over the body of a smooth change of shape added to every coordinate of every frame,
    /// drawn independently per frame: the first [`SHAPE_MODES`] sine and cosine modes along
    /// the body ([`shape_change`]) [m]; 0 adds none
    pub shape_noise_m: f64,
    /// the seed of every random choice
    pub seed: u64,
    /// largest total roll of the bending plane [rad]; each recording draws from `[0, max]`
    pub max_roll_rad: f64,
    /// largest twist [rad/m]; each recording draws from `[−max, max]`
    pub max_twist_per_m: f64,
}

impl Default for CorpusParams {
    fn default() -> Self {
        CorpusParams {
            count: 8,
            frames: 20,
            nodes: 33,
            length_m: crate::clip::WORM_LENGTH_M,
            dt_s: 0.04,
            noise_m: 1e-7,
            shape_noise_m: 0.0,
            seed: 0,
            max_roll_rad: PI / 2.0,
            max_twist_per_m: 500.0,
        }
    }
}

/// One recording of a corpus: its name and the parameters it was drawn with.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CorpusEntry {
    pub name: String,
    pub roll_total_rad: f64,
    pub twist_per_m: f64,
    /// first kymogram row played (then one row every two frames)
    pub first_row: usize,
    /// the seed of its noise
    pub noise_seed: u64,
}

/// SplitMix64 (Steele, Lea and Flood 2014): a small, seeded, portable generator.
pub(crate) struct SplitMix64(pub(crate) u64);

impl SplitMix64 {
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub(crate) fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal (Box–Muller).
    pub(crate) fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform(); // (0, 1]
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
    }
}

fn check(name: &'static str, value: f64, ok: bool, requirement: &'static str) -> Result<(), CorpusError> {
    if ok {
        Ok(())
    } else {
        Err(CorpusError::Parameter { name, value, requirement })
    }
}

/// Write the corpus of `params` into `dir` (created if needed) from the kymogram `kymogram`
/// (the omega turn of `scripts/fetch_worm_data.sh`). Recording `k` is `roll_KKK.npy`: a
/// `roll_3d` clip playing consecutive kymogram rows from a random first row, one row every two
/// frames (the whole kymogram stretched over the clip if it has fewer rows), with a random
/// total roll and twist, plus noise. Returns the recordings written, in order.
pub fn write_corpus(dir: &Path, kymogram: &Path, params: &CorpusParams) -> Result<Vec<CorpusEntry>, CorpusError> {
    let p = params;
    check("count", p.count as f64, p.count >= 1, "at least one recording")?;
    check("frames", p.frames as f64, p.frames >= 2, "at least 2 frames")?;
    check("noise_m", p.noise_m, p.noise_m.is_finite() && p.noise_m >= 0.0, "finite and >= 0")?;
    check("shape_noise_m", p.shape_noise_m, p.shape_noise_m.is_finite() && p.shape_noise_m >= 0.0, "finite and >= 0")?;
    check("max_roll_rad", p.max_roll_rad, p.max_roll_rad.is_finite(), "finite")?;
    check("max_twist_per_m", p.max_twist_per_m, p.max_twist_per_m.is_finite(), "finite")?;
    let rows = kymogram_rows(kymogram).map_err(ClipFileError::from)?;
    std::fs::create_dir_all(dir).map_err(|source| OutputError::Io { path: dir.to_path_buf(), source })?;
    let mut rng = SplitMix64(p.seed);
    let width = (p.count - 1).to_string().len().max(3);
    let mut entries = Vec::with_capacity(p.count);
    for k in 0..p.count {
        // half a kymogram row per frame (as worm_roll_3d, ×2.48 slower than the recording): the
        // time spline fills the frames between rows
        let played_rows = (p.frames - 1).div_ceil(ROWS_PER_FRAME_INV) + 1;
        let span = rows.len().saturating_sub(played_rows);
        let entry = CorpusEntry {
            name: format!("roll_{k:0width$}"),
            roll_total_rad: p.max_roll_rad * rng.uniform(),
            twist_per_m: p.max_twist_per_m * (2.0 * rng.uniform() - 1.0),
            first_row: ((span + 1) as f64 * rng.uniform()) as usize,
            noise_seed: rng.next_u64(),
        };
        let played = &rows[entry.first_row.min(span)..(entry.first_row + played_rows).min(rows.len())];
        let gen = RollClipParams {
            length_m: p.length_m,
            nodes: p.nodes,
            frames: p.frames,
            dt_s: p.dt_s,
            roll_total_rad: entry.roll_total_rad,
            twist_per_m: entry.twist_per_m,
            time_mapping: TimeMapping::StretchOmega,
            ..RollClipParams::default()
        };
        gen.validate()?;
        let (clip, truth) = roll_clip(played, None, &gen)?;
        let mut noise = SplitMix64(entry.noise_seed);
        let data: Vec<f64> = clip.frames.iter().flatten().flat_map(|x| [x.x, x.y, x.z]).collect();
        let mut data: Vec<f64> = data.into_iter().map(|v| v + p.noise_m * noise.normal()).collect();
        if p.shape_noise_m > 0.0 {
            // a generator of its own, so that corpora without shape changes keep their bytes
            let mut shapes = SplitMix64(entry.noise_seed ^ SHAPE_SEED);
            for frame in data.chunks_exact_mut(3 * p.nodes) {
                shape_change(frame, p.shape_noise_m, &mut shapes);
            }
        }
        let path = recording_path(dir, &entry.name);
        write_truth(&truth_sidecar(&path), &truth)?;
        write_npy(&path, &[p.frames, p.nodes, 3], &data)?;
        entries.push(entry);
    }
    let listing = serde_json::json!({ "params": p, "kymogram": kymogram.display().to_string(), "recordings": entries });
    let path = dir.join(LISTING);
    let text = serde_json::to_string_pretty(&listing)
        .map_err(|e| OutputError::Invalid { path: path.clone(), reason: e.to_string() })?;
    write_atomic(&path, format!("{text}\n").as_bytes())?;
    Ok(entries)
}

/// Sine and cosine modes of a smooth change of shape ([`shape_change`]).
pub const SHAPE_MODES: usize = 3;

/// Mixed into a recording's noise seed for its shape changes.
const SHAPE_SEED: u64 = 0x5348_4150_455f_4d4f;

/// Add to `frame` (nodes × 3 coordinates, nodes uniform in arc length s ∈ [0, L]) a smooth
/// change of shape: for each coordinate, Σ_{m=1..M} a_m sin(mπs/L) + b_m cos(mπs/L) with a_m,
/// b_m independent N(0, c²), M = [`SHAPE_MODES`]. Each mode's mean square over the body is
/// about 1/2, so c = rms_m/√M gives an expected mean square of rms_m² per coordinate.
pub(crate) fn shape_change(frame: &mut [f64], rms_m: f64, rng: &mut SplitMix64) {
    let nodes = frame.len() / 3;
    let c = rms_m / (SHAPE_MODES as f64).sqrt();
    for axis in 0..3 {
        let coefficients: Vec<(f64, f64)> = (0..SHAPE_MODES).map(|_| (c * rng.normal(), c * rng.normal())).collect();
        for (j, node) in frame.chunks_exact_mut(3).enumerate() {
            let s = j as f64 / (nodes - 1).max(1) as f64;
            node[axis] += coefficients
                .iter()
                .enumerate()
                .map(|(m, (a, b))| {
                    let k = (m + 1) as f64 * PI * s;
                    a * k.sin() + b * k.cos()
                })
                .sum::<f64>();
        }
    }
}

/// The recording file of corpus entry `name` in `dir`.
pub fn recording_path(dir: &Path, name: &str) -> PathBuf {
    dir.join(format!("{name}.npy"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generator_is_seeded_and_normal_has_unit_variance() {
        let (mut a, mut b) = (SplitMix64(7), SplitMix64(7));
        assert_eq!(a.next_u64(), b.next_u64());
        let mut g = SplitMix64(1);
        let n = 20_000;
        let v: Vec<f64> = (0..n).map(|_| g.normal()).collect();
        let mean = v.iter().sum::<f64>() / n as f64;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.03 && (var - 1.0).abs() < 0.05, "mean {mean}, variance {var}");
    }

    /// A smooth change of shape has the RMS asked for per coordinate (over 400 frames of 33
    /// nodes, within 5 %), and is smooth: the noise estimate of the fourth differences
    /// (`solve::fit::noise_level`) sees under 2 % of it.
    #[test]
    fn a_shape_change_has_its_rms_and_is_smooth() {
        let (nodes, rms) = (33, 5e-6);
        let mut rng = SplitMix64(3);
        let (mut sum2, mut count, mut seen) = (0.0, 0usize, Vec::new());
        for _ in 0..400 {
            let mut frame = vec![0.0; 3 * nodes];
            shape_change(&mut frame, rms, &mut rng);
            sum2 += frame.iter().map(|v| v * v).sum::<f64>();
            count += frame.len();
            let x: Vec<nalgebra::Vector3<f64>> =
                frame.chunks_exact(3).map(|c| nalgebra::Vector3::new(c[0], c[1], c[2])).collect();
            seen.push(crate::recorded::fit::noise_level(&x));
        }
        let measured = (sum2 / count as f64).sqrt();
        assert!((measured / rms - 1.0).abs() < 0.05, "RMS {measured:e}");
        let worst = seen.iter().copied().fold(0.0, f64::max);
        assert!(worst < 0.02 * rms, "noise estimate {worst:e}");
    }
}
