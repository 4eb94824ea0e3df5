//! `cosserat synth`: a corpus of synthetic recordings (`engine::input::corpus`) written into a folder of
//! its own under the output-folder contract (staged, `run.json`), from the omega-turn kymogram
//! of the source tree wherever the command runs.
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};

use cosserat::engine::input::corpus::{write_corpus, CorpusParams};
use cosserat::output::run_folder::{input_file_as, Manifest, Mode, RunFolder, Status};

/// `cosserat synth`.
#[derive(clap::Args, Debug)]
pub struct SynthArgs {
    /// Output folder for the recordings (roll_KKK.npy), their truth sidecars, corpus.json and
    /// run.json; it must be new or empty unless --force
    #[arg(long)]
    out: PathBuf,
    /// Number of recordings
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    count: u64,
    /// Frames per recording (>= 2)
    #[arg(long, value_parser = clap::value_parser!(u64).range(2..))]
    frames: u64,
    /// Seed of the rolls, twists, kymogram excerpts and noise
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Nodes per frame: the batch case's rod.elements + 1
    #[arg(long, default_value_t = 33, value_parser = clap::value_parser!(u64).range(3..))]
    nodes: u64,
    /// Body length of the recorded worm [m] (a batch case with rod.length_m = "from_data"
    /// measures it from each recording)
    #[arg(long, default_value_t = cosserat::clip::WORM_LENGTH_M)]
    length_m: f64,
    /// Standard deviation of the noise added to every coordinate [m]
    #[arg(long, default_value_t = 1e-7)]
    noise_m: f64,
    /// Time between frames [s]
    #[arg(long, default_value_t = 0.04)]
    frame_interval_s: f64,
    /// The kymogram whose curvature the recordings play [default: data/elegansbot/
    /// kymogram_omega-turn.npy (scripts/fetch_worm_data.sh) of the working folder, else of
    /// the source tree the program was built in]
    #[arg(long)]
    kymogram: Option<PathBuf>,
    /// Replace a folder that is not empty (an earlier corpus, anything) whole
    #[arg(long)]
    force: bool,
}

/// The omega-turn kymogram of `scripts/fetch_worm_data.sh`, relative to its source tree.
const KYMOGRAM: &str = "data/elegansbot/kymogram_omega-turn.npy";

/// The default kymogram: in the working folder, else beside an ancestor of the executable
/// (`target/release/cosserat` of a source tree), else in the source tree it was built from.
fn default_kymogram() -> Result<PathBuf> {
    let mut tried = vec![PathBuf::from(KYMOGRAM)];
    if let Ok(exe) = std::env::current_exe().and_then(std::fs::canonicalize) {
        tried.extend(exe.ancestors().skip(1).map(|a| a.join(KYMOGRAM)));
    }
    tried.push(Path::new(env!("CARGO_MANIFEST_DIR")).join(KYMOGRAM));
    if let Some(found) = tried.iter().find(|p| p.is_file()) {
        return Ok(found.clone());
    }
    anyhow::bail!(
        "the kymogram {KYMOGRAM} is neither in the working folder, nor beside the executable, nor in the source tree {}: run scripts/fetch_worm_data.sh there, or give one with --kymogram FILE",
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
    let params = CorpusParams {
        count: a.count as usize,
        frames: a.frames as usize,
        nodes: a.nodes as usize,
        length_m: a.length_m,
        dt_s: a.frame_interval_s,
        noise_m: a.noise_m,
        seed: a.seed,
        ..CorpusParams::default()
    };
    let kymogram = match a.kymogram {
        Some(k) => k,
        None => default_kymogram()?,
    };
    if let (false, Some(names)) = (a.force, not_empty(&a.out)) {
        anyhow::bail!(
            "synth: {} is not empty ({names}, …): a corpus is written into a folder of its own, and a batch runs every recording of it; choose a new --out, or pass --force to replace the folder whole",
            a.out.display()
        );
    }
    let mut manifest = Manifest::new("synth");
    manifest.input.inputs.push(input_file_as(&kymogram, "kymogram")?);
    for (k, v) in [
        ("count", params.count as f64),
        ("frames", params.frames as f64),
        ("nodes", params.nodes as f64),
        ("length_m", params.length_m),
        ("seed", params.seed as f64),
        ("noise_m", params.noise_m),
        ("frame_interval_s", params.dt_s),
    ] {
        manifest.input.settings.insert(k.into(), v.into());
    }
    let folder = RunFolder::begin(&a.out, manifest, Mode::Fresh { force: a.force })
        .with_context(|| format!("synth into {}", a.out.display()))?;
    let entries = match write_corpus(folder.dir(), &kymogram, &params) {
        Ok(e) => e,
        Err(e) => {
            // the previous folder stays as it was
            folder.abandon();
            return Err(anyhow::Error::new(e).context(format!("synth into {}", a.out.display())));
        }
    };
    folder.finish(Status::Complete, None)?;
    println!(
        "wrote {} recordings ({} frames x {} nodes, with truth sidecars) and corpus.json to {}",
        entries.len(),
        params.frames,
        params.nodes,
        a.out.display()
    );
    Ok(ExitCode::SUCCESS)
}
