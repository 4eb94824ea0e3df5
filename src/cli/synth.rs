//! `cosserat synth`: a corpus of synthetic recordings (`engine::input::corpus`) written into a folder of
//! its own under the output-folder contract (staged, `run.json`), from the omega-turn kymogram
//! of the source tree wherever the command runs.
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};

use cosserat::engine::input::corpus::{write_corpus, CorpusParams};
use cosserat::engine::input::tracker::{write_tracker_corpus, Losses, TrackerParams};
use cosserat::output::run_folder::{input_file_as, Manifest, Mode, RunFolder, Status};

/// `cosserat synth`.
#[derive(clap::Args, Debug)]
pub struct SynthArgs {
    /// Output folder for the recordings (roll_KKK.npy, or worm_KKK.csv with --tracker), their
    /// truth sidecars, corpus.json and run.json; it must be new or empty unless --force
    #[arg(long)]
    out: PathBuf,
    /// Number of recordings [required; with --tracker default 2]
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..), required_unless_present = "tracker")]
    count: Option<u64>,
    /// Frames per recording (>= 2) [required; with --tracker default 300]
    #[arg(long, value_parser = clap::value_parser!(u64).range(2..), required_unless_present = "tracker")]
    frames: Option<u64>,
    /// Seed of the rolls, twists, kymogram excerpts, losses and noise [default: 0; with
    /// --tracker 41]
    #[arg(long)]
    seed: Option<u64>,
    /// Nodes per frame: the batch case's rod.elements + 1 [default: 33; with --tracker 49]
    #[arg(long, value_parser = clap::value_parser!(u64).range(3..))]
    nodes: Option<u64>,
    /// Body length of the recorded worm [m], or several comma-separated (recording k has the
    /// (k mod n)-th; a batch case with rod.length_m = "from_data" measures it from each
    /// recording) [default: 1e-3; with --tracker 1.1e-3,0.85e-3]
    #[arg(long, value_delimiter = ',')]
    length_m: Vec<f64>,
    /// Standard deviation of the noise added to every coordinate (x and y with --tracker) [m]
    /// [default: 1e-7; with --tracker 1e-6]
    #[arg(long)]
    noise_m: Option<f64>,
    /// Time between frames [s] [default: 0.04; with --tracker 1/30]
    #[arg(long)]
    frame_interval_s: Option<f64>,
    /// What the recordings play and how they are written
    #[command(flatten)]
    shape: TrackerArgs,
    /// Replace a folder that is not empty (an earlier corpus, anything) whole
    #[arg(long)]
    force: bool,
}

/// What `synth`'s recordings play, and the tracker's recordings' losses.
#[derive(clap::Args, Debug)]
pub struct TrackerArgs {
    /// The kymogram whose curvature the recordings play (repeat for several: recording k plays
    /// the (k mod n)-th) [default: data/elegansbot/kymogram_omega-turn.npy
    /// (scripts/fetch_worm_data.sh) of the working folder, else of the source tree the program
    /// was built in; with --tracker also kymogram_delta-turn.npy]
    #[arg(long)]
    kymogram: Vec<PathBuf>,
    /// RMS of a smooth change of shape added to every frame independently (3D recordings): the
    /// first three sine and cosine modes along the body, per coordinate [m] [default: 0]
    #[arg(long, conflicts_with = "tracker")]
    shape_noise_m: Option<f64>,
    /// Write the recordings as a single-camera tracker does: 2D midlines (CSV frame,node,x_um,y_um
    /// in micrometres, frames numbered from 1) with lost frames and lost tail points, each with
    /// its truth (worm_KKK.csv, worm_KKK.truth.npy)
    #[arg(long)]
    tracker: bool,
    /// With --tracker: frames lost whole per recording (written in turn as empty cells, NaN and
    /// missing rows)
    #[arg(long, default_value_t = 6, requires = "tracker")]
    lost_frames: usize,
    /// With --tracker: consecutive frames whose last tail points are lost
    #[arg(long, default_value_t = 16, requires = "tracker")]
    tail_lost_frames: usize,
    /// With --tracker: tail points lost on those frames
    #[arg(long, default_value_t = 5, requires = "tracker")]
    tail_lost_nodes: usize,
}

/// The omega- and delta-turn kymograms of `scripts/fetch_worm_data.sh`, relative to its
/// source tree.
const KYMOGRAMS: [&str; 2] = ["data/elegansbot/kymogram_omega-turn.npy", "data/elegansbot/kymogram_delta-turn.npy"];

/// A default kymogram: in the working folder, else beside an ancestor of the executable
/// (`target/release/cosserat` of a source tree), else in the source tree it was built from.
fn default_kymogram(name: &str) -> Result<PathBuf> {
    let mut tried = vec![PathBuf::from(name)];
    if let Ok(exe) = std::env::current_exe().and_then(std::fs::canonicalize) {
        tried.extend(exe.ancestors().skip(1).map(|a| a.join(name)));
    }
    tried.push(Path::new(env!("CARGO_MANIFEST_DIR")).join(name));
    if let Some(found) = tried.iter().find(|p| p.is_file()) {
        return Ok(found.clone());
    }
    anyhow::bail!(
        "the kymogram {name} is neither in the working folder, nor beside the executable, nor in the source tree {}: run scripts/fetch_worm_data.sh there, or give one with --kymogram FILE",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// A folder that exists and holds anything: up to three of its names.
fn not_empty(dir: &Path) -> Option<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(dir).ok()?.flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    (!names.is_empty()).then(|| names.into_iter().take(3).collect::<Vec<_>>().join(", "))
}

pub fn cmd_synth(a: SynthArgs) -> Result<ExitCode> {
    if a.shape.tracker {
        return cmd_synth_tracker(a);
    }
    let d = CorpusParams::default();
    anyhow::ensure!(a.length_m.len() <= 1, "synth: one --length-m for 3D recordings (several with --tracker)");
    let params = CorpusParams {
        // clap requires both without --tracker
        count: a.count.context("synth: --count is required")? as usize,
        frames: a.frames.context("synth: --frames is required")? as usize,
        nodes: a.nodes.map_or(d.nodes, |n| n as usize),
        length_m: a.length_m.first().copied().unwrap_or(d.length_m),
        dt_s: a.frame_interval_s.unwrap_or(d.dt_s),
        noise_m: a.noise_m.unwrap_or(d.noise_m),
        shape_noise_m: a.shape.shape_noise_m.unwrap_or(d.shape_noise_m),
        seed: a.seed.unwrap_or(d.seed),
        ..d
    };
    anyhow::ensure!(a.shape.kymogram.len() <= 1, "synth: one --kymogram for 3D recordings (several with --tracker)");
    let kymogram = match a.shape.kymogram.first() {
        Some(k) => k.clone(),
        None => default_kymogram(KYMOGRAMS[0])?,
    };
    let settings = [
        ("count", params.count as f64),
        ("frames", params.frames as f64),
        ("nodes", params.nodes as f64),
        ("length_m", params.length_m),
        ("seed", params.seed as f64),
        ("noise_m", params.noise_m),
        ("shape_noise_m", params.shape_noise_m),
        ("frame_interval_s", params.dt_s),
    ];
    let written =
        write_staged(&a, std::slice::from_ref(&kymogram), &settings, |dir| write_corpus(dir, &kymogram, &params))?;
    println!(
        "wrote {} recordings ({} frames x {} nodes, with truth sidecars) and corpus.json to {}",
        written.len(),
        params.frames,
        params.nodes,
        a.out.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// `cosserat synth --tracker` (`engine::input::tracker`).
fn cmd_synth_tracker(a: SynthArgs) -> Result<ExitCode> {
    let d = TrackerParams::default();
    let params = TrackerParams {
        count: a.count.map_or(d.count, |c| c as usize),
        frames: a.frames.map_or(d.frames, |f| f as usize),
        nodes: a.nodes.map_or(d.nodes, |n| n as usize),
        lengths_m: if a.length_m.is_empty() { d.lengths_m } else { a.length_m.clone() },
        dt_s: a.frame_interval_s.unwrap_or(d.dt_s),
        noise_m: a.noise_m.unwrap_or(d.noise_m),
        seed: a.seed.unwrap_or(d.seed),
        losses: Losses {
            lost_frames: a.shape.lost_frames,
            tail_lost_frames: a.shape.tail_lost_frames,
            tail_lost_nodes: a.shape.tail_lost_nodes,
        },
        first_frame: 1,
    };
    let kymograms = if a.shape.kymogram.is_empty() {
        KYMOGRAMS.iter().map(|k| default_kymogram(k)).collect::<Result<Vec<_>>>()?
    } else {
        a.shape.kymogram.clone()
    };
    let settings = [
        ("count", params.count as f64),
        ("frames", params.frames as f64),
        ("nodes", params.nodes as f64),
        ("seed", params.seed as f64),
        ("noise_m", params.noise_m),
        ("frame_interval_s", params.dt_s),
        ("lost_frames", params.losses.lost_frames as f64),
        ("tail_lost_frames", params.losses.tail_lost_frames as f64),
        ("tail_lost_nodes", params.losses.tail_lost_nodes as f64),
    ];
    let written = write_staged(&a, &kymograms, &settings, |dir| write_tracker_corpus(dir, &kymograms, &params))?;
    println!(
        "wrote {} tracker recordings ({} frames x {} points in um, with lost frames and truth sidecars) and corpus.json to {}",
        written.len(),
        params.frames,
        params.nodes,
        a.out.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// A corpus written by `write` into `a.out` under the output-folder contract: a folder that is
/// not empty refused unless `--force`, the files staged, `run.json` naming the kymograms and
/// `settings`, and on a failure the previous folder left as it was.
fn write_staged<T, E>(
    a: &SynthArgs,
    kymograms: &[PathBuf],
    settings: &[(&str, f64)],
    write: impl FnOnce(&Path) -> Result<T, E>,
) -> Result<T>
where
    E: std::error::Error + Send + Sync + 'static,
{
    if !a.force {
        refuse_not_empty(&a.out)?;
    }
    let mut manifest = Manifest::new("synth");
    for k in kymograms {
        manifest.input.inputs.push(input_file_as(k, "kymogram")?);
    }
    for (k, v) in settings {
        manifest.input.settings.insert((*k).into(), (*v).into());
    }
    let folder = RunFolder::begin(&a.out, manifest, Mode::Fresh { force: a.force })
        .with_context(|| format!("synth into {}", a.out.display()))?;
    match write(folder.dir()) {
        Ok(written) => {
            folder.finish(Status::Complete, None)?;
            Ok(written)
        }
        Err(e) => {
            folder.abandon();
            Err(anyhow::Error::new(e).context(format!("synth into {}", a.out.display())))
        }
    }
}

/// A corpus is written into a folder of its own: refuse one that holds anything, unless
/// `--force` (which the caller checks).
fn refuse_not_empty(out: &Path) -> Result<()> {
    if let Some(names) = not_empty(out) {
        anyhow::bail!(
            "synth: {} is not empty ({names}, …): a corpus is written into a folder of its own, and a batch runs every recording of it; choose a new --out, or pass --force to replace the folder whole",
            out.display()
        );
    }
    Ok(())
}
