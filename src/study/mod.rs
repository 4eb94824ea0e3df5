//! The noise study (`cosserat noise-study cases/bench/noise_study.toml`, `docs/noise.md`):
//! synthetic recordings with their truth at several noise levels and meshes, reconstructed by
//! the batch case under several weight settings, and scored beside a generic smoothing spline
//! of the same noisy frames, in one run.
//!
//! For each mesh (node count) and noise level σ a corpus is written (`engine::input::corpus`, the same
//! seed for every σ, so the recordings differ only by their noise), each variant of the case
//! (its `set` keys applied to the mesh's case) runs as a batch over it (`jobs::batch`), and every
//! frame is scored ([`score`]). `noise_study.csv` has one row per mesh, σ, method and
//! recording; `noise_study.svg` draws the bending error (median and worst frame, the worst
//! recording) and the reconstructed fraction against σ.
pub mod score;
mod spec;

pub use crate::jobs::depth::Depth;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub use spec::{Mesh, StudySpec, Variant};

use crate::engine::input::clip_files::read_recording;
use crate::engine::input::corpus::{recording_path, write_corpus, CorpusParams};
use crate::engine::input::tracker::{write_tracker_corpus, Losses, TrackerParams};
use crate::engine::input::truth_file::{read_truth, truth_sidecar};
use crate::io::{write_atomic, InputError, OutputError};
use crate::jobs::batch::{run_batch, BatchOptions, Plan};
use score::{
    bending_error, centreline_bending, median_and_worst, read_curvature, read_positions, recovered_nodal,
    spline_bending, truth_bending, truth_bending_nodal, ScoreError,
};

/// Errors of the study.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    #[error(transparent)]
    Spec(#[from] spec::SpecError),
    #[error(transparent)]
    Input(#[from] InputError),
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error(transparent)]
    Score(#[from] ScoreError),
    #[error("corpus: {0}")]
    Corpus(#[from] crate::engine::input::corpus::CorpusError),
    #[error("batch: {0}")]
    Batch(#[from] crate::jobs::batch::BatchError),
    #[error("plot: {0}")]
    Plot(#[from] crate::figures::plot::PlotError),
    #[error("csv: {0}")]
    Csv(#[from] csv::Error),
}

/// The name of the baseline in the table.
pub const SPLINE: &str = "spline";

/// One row of `noise_study.csv`: one recording reconstructed by one method.
#[derive(Debug, Clone, serde::Serialize)]
pub struct StudyRow {
    pub nodes: usize,
    /// the RMS of the smooth changes of shape added to every frame (`Mesh::shape_noise_m`) [m]
    pub shape_noise_m: f64,
    /// the standard deviation of the added noise [m]
    pub noise_m: f64,
    /// a variant's name, or `spline`
    pub method: String,
    pub recording: String,
    pub frames: usize,
    /// frames with a reconstruction (a converged frame, or a fitted spline)
    pub frames_reconstructed: usize,
    /// median over the frames of the bending error [–]
    pub bending_err_median: f64,
    /// the largest bending error of a frame [–]
    pub bending_err_worst: f64,
    /// the noise level the run estimated from the recording, if it did [m]
    pub noise_estimate_m: Option<f64>,
    /// the tracking weight λg the run used [1/m³… as in the case]
    pub lambda_g: Option<f64>,
    /// reconstructed frames per second of wall time (this method's share of the run)
    pub frames_per_s: f64,
}

/// Run the study of `spec` (read from `spec_path`) into `out`, calling `tick` after each batch.
pub fn run_study(spec: &StudySpec, out: &Path, depth: Depth, tick: impl Fn(&str)) -> Result<Vec<StudyRow>, StudyError> {
    let plan = spec.plan(depth);
    let mut rows = Vec::new();
    for mesh in &spec.meshes {
        for &noise_m in &plan.noise_m {
            let kind = match (mesh.planar, mesh.shape_noise_m > 0.0) {
                (true, _) => "_planar".to_string(),
                (false, true) => format!("_shape{}", crate::case::sweep::fmt_value(mesh.shape_noise_m)),
                (false, false) => String::new(),
            };
            let tag = format!("n{}{kind}_s{}", mesh.nodes, crate::case::sweep::fmt_value(noise_m));
            let corpus = out.join("corpora").join(&tag);
            let params = CorpusParams {
                count: plan.recordings,
                frames: plan.frames,
                nodes: mesh.nodes,
                noise_m,
                shape_noise_m: mesh.shape_noise_m,
                seed: spec.seed,
                ..CorpusParams::default()
            };
            let recordings: Vec<PathBuf> = if mesh.planar {
                let tracker = TrackerParams {
                    count: params.count,
                    frames: params.frames,
                    nodes: params.nodes,
                    lengths_m: vec![params.length_m],
                    dt_s: params.dt_s,
                    noise_m,
                    seed: spec.seed,
                    losses: Losses::NONE,
                    first_frame: 0,
                };
                let entries = write_tracker_corpus(&corpus, std::slice::from_ref(&spec.kymogram), &tracker)?;
                entries.iter().map(|e| corpus.join(format!("{}.csv", e.name))).collect()
            } else {
                let entries = write_corpus(&corpus, &spec.kymogram, &params)?;
                entries.iter().map(|e| recording_path(&corpus, &e.name)).collect()
            };
            rows.extend(spline_rows(mesh, noise_m, params.length_m, &recordings, spec.skip_elements)?);
            for variant in &spec.variants {
                let case = spec.variant_case(mesh, variant, &out.join("cases"))?;
                let runs = out.join("runs").join(&tag).join(&variant.name);
                let plan = Plan::new(&case, &recordings, 1);
                plan.begin(&runs)?;
                let ran = run_batch(&plan, &runs, BatchOptions::default(), || {})?;
                for (r, recording) in ran.iter().zip(&recordings) {
                    let dir = runs.join(&r.row.folder);
                    let scored = score_run(mesh, noise_m, variant, recording, &dir, spec.skip_elements)?;
                    for mut row in scored {
                        row.frames_per_s = row.frames_reconstructed as f64 / r.row.wall_time_s.max(1e-9);
                        rows.push(row);
                    }
                }
                tick(&format!("{tag} {}", variant.name));
            }
        }
    }
    write_table(out, &rows)?;
    Ok(rows)
}

/// A recording's noisy frames (node positions [m]) and its truth.
type Recorded = (Vec<Vec<nalgebra::Vector3<f64>>>, crate::clip::synthetic::GroundTruth);

/// The truth of a recording and its noisy frames.
fn recording_and_truth(recording: &Path) -> Result<Recorded, StudyError> {
    let clip = read_recording(recording, 1.0)?;
    let n = clip.node_count();
    let s: Vec<f64> = (0..n).map(|i| i as f64 / (n - 1) as f64).collect();
    let truth = read_truth(&truth_sidecar(recording), clip.frames.len(), &s)?;
    Ok((clip.frames, truth))
}

fn spline_rows(
    mesh: &Mesh,
    noise_m: f64,
    length_m: f64,
    recordings: &[PathBuf],
    skip: usize,
) -> Result<Vec<StudyRow>, StudyError> {
    let mut rows = Vec::new();
    for recording in recordings {
        let started = Instant::now();
        let (frames, truth) = recording_and_truth(recording)?;
        let errors: Vec<f64> = frames
            .iter()
            .zip(&truth.frames)
            .map(|(f, t)| bending_error(&spline_bending(f, length_m), &truth_bending(t), skip))
            .collect();
        let mut r = row(mesh, noise_m, SPLINE, recording, &errors);
        r.frames_per_s = r.frames_reconstructed as f64 / started.elapsed().as_secs_f64().max(1e-9);
        rows.push(r);
    }
    Ok(rows)
}

fn row(mesh: &Mesh, noise_m: f64, method: &str, recording: &Path, errors: &[f64]) -> StudyRow {
    let (median, worst) = median_and_worst(errors);
    StudyRow {
        nodes: mesh.nodes,
        shape_noise_m: mesh.shape_noise_m,
        noise_m,
        method: method.into(),
        recording: recording.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default(),
        frames: errors.len(),
        frames_reconstructed: errors.iter().filter(|e| e.is_finite()).count(),
        bending_err_median: median,
        bending_err_worst: worst,
        noise_estimate_m: None,
        lambda_g: None,
        frames_per_s: f64::NAN,
    }
}

/// The name of a variant's row scored on its reconstructed centreline
/// ([`score::centreline_bending`]).
pub fn centreline_name(variant: &str) -> String {
    format!("{variant}+centreline")
}

/// The name of a variant's row scored with the nodal recovery ([`score::recovered_nodal`]).
pub fn recovered_name(variant: &str) -> String {
    format!("{variant}+nodal")
}

/// Score one recording's run folder (its `curvature.csv`; the weights from `run.json`): the
/// variant's row, and with `recovered` its nodal recovery's.
fn score_run(
    mesh: &Mesh,
    noise_m: f64,
    variant: &Variant,
    recording: &Path,
    dir: &Path,
    skip: usize,
) -> Result<Vec<StudyRow>, StudyError> {
    let (frames, truth) = recording_and_truth(recording)?;
    let curvature = dir.join("curvature.csv");
    let recovered = if curvature.is_file() { read_curvature(&curvature)? } else { Vec::new() };
    let score = |nodal: bool| -> Vec<f64> {
        (0..frames.len())
            .map(|k| match recovered.get(k) {
                Some(b) if !b.is_empty() && nodal => {
                    bending_error(&recovered_nodal(b), &truth_bending_nodal(&truth.frames[k]), skip)
                }
                Some(b) if !b.is_empty() => bending_error(b, &truth_bending(&truth.frames[k]), skip),
                _ => f64::NAN,
            })
            .collect()
    };
    let weights = crate::output::manifest::Manifest::read(dir).ok().flatten().and_then(|m| m.weights);
    let mut rows = vec![row(mesh, noise_m, &variant.name, recording, &score(false))];
    if variant.recovered {
        rows.push(row(mesh, noise_m, &recovered_name(&variant.name), recording, &score(true)));
    }
    if variant.centreline {
        let fields = dir.join("fields.csv");
        let x = if fields.is_file() { read_positions(&fields)? } else { Vec::new() };
        let errors: Vec<f64> = (0..frames.len())
            .map(|k| match x.get(k) {
                Some(x) if !x.is_empty() => {
                    bending_error(&centreline_bending(x), &truth_bending(&truth.frames[k]), skip)
                }
                _ => f64::NAN,
            })
            .collect();
        rows.push(row(mesh, noise_m, &centreline_name(&variant.name), recording, &errors));
    }
    for r in &mut rows {
        r.noise_estimate_m = weights.map(|w| w.noise_m);
        r.lambda_g = weights.map(|w| w.lambda_g);
    }
    Ok(rows)
}

fn write_table(out: &Path, rows: &[StudyRow]) -> Result<(), StudyError> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r)?;
    }
    let bytes = w.into_inner().map_err(|e| csv::Error::from(e.into_error()))?;
    write_atomic(&out.join("noise_study.csv"), &bytes)?;
    Ok(())
}
