//! The memory a run will need, estimated from the case before anything is allocated, and the
//! refusal of a run above a limit (`cosserat … --max-memory-gib`). The estimate counts the
//! arrays the solvers allocate: per forward unknown the band LU (`linalg::band`, `2 kl + ku + 1`
//! rows, `kl = ku = 2 b − 1` for blocks of `b` unknowns per node), per element the pattern's
//! values, scaled copy and slots (`linalg::pattern`), a few dozen work vectors; a clip's frames
//! (all of a clip read from a file, a window of a streamed one) and per-frame summary
//! (`engine::rust::clip::ClipRun`); the dense matrices of the modal model
//! (`solve::modes`, about twelve `n × n`). Checked against the peak resident size of real runs in
//! `docs/results.md`: it errs high, never low by more than the process's fixed few MB.
use super::clip::STREAM_AHEAD;
use crate::case::{Analysis, Case, ClipKind, WeightsRule};

/// Bytes in a GiB.
pub const GIB: f64 = 1024.0 * 1024.0 * 1024.0;

/// What part of the program will run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Footprint {
    /// `run`, `sweep` points, `compare`: the case's solver
    Run,
    /// `modes`: the lowest `count` modes by shift-invert block Lanczos (D28)
    Modes { count: usize },
}

/// A run refused before it started.
#[derive(Debug, thiserror::Error)]
#[error(
    "{case}: {what} would need about {:.3e} GiB of memory (estimated from {basis}), above {}",
    .bytes / GIB,
    limit_text(*.limit, *.limit_source, key)
)]
pub struct BudgetError {
    /// the case file (or the case's name)
    pub case: String,
    pub what: &'static str,
    pub bytes: f64,
    pub limit: f64,
    pub basis: String,
    pub key: &'static str,
    /// which limit the estimate exceeds
    pub limit_source: LimitSource,
}

/// Which limit a [`BudgetError`]'s estimate exceeds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LimitSource {
    /// the one asked for (`--max-memory-gib`, or its default)
    Asked,
    /// the process's address-space limit (`ulimit -v`), below the one asked for
    AddressSpace,
}

/// The limit of a [`BudgetError`] and how to raise it.
fn limit_text(limit: f64, source: LimitSource, key: &str) -> String {
    if source == LimitSource::AddressSpace {
        format!(
            "the process's address-space limit of {:.1} MiB (ulimit -v); reduce {key} or raise that limit",
            limit / (1024.0 * 1024.0)
        )
    } else {
        // a limit below 0.1 GiB with its digits (0.001 GiB printed as "0.0 GiB" read as no limit)
        let gib = limit / GIB;
        let gib = if gib >= 0.1 { format!("{gib:.1}") } else { format!("{gib:.2e}") };
        format!("the limit of {gib} GiB; reduce {key} or raise the limit with --max-memory-gib")
    }
}

/// The soft limit of the process's address space (`ulimit -v`, `RLIMIT_AS`) [bytes], if it has
/// one (from `/proc/self/limits`).
pub fn address_space_limit() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/self/limits").ok()?;
    let line = text.lines().find(|l| l.starts_with("Max address space"))?;
    line.trim_start_matches("Max address space").split_whitespace().next()?.parse::<f64>().ok()
}

/// Fixed cost of a process [bytes] (binary, allocator, thread stacks).
const FIXED_BYTES: f64 = 32.0 * 1024.0 * 1024.0;

/// Bytes per element of a banded solve with `b` unknowns per node: band LU over `b` unknowns
/// (`ld = 3 kl + 1`... with pivots), pattern values + equilibrated copy + slots of the two
/// nodes' `(2b)²` entries, and about 40 work vectors of `b` entries.
fn banded_bytes_per_element(b: f64) -> f64 {
    let kl = 2.0 * b - 1.0;
    let band = (3.0 * kl + 1.0) * b * 8.0 + b * 8.0;
    let pattern = (2.0 * b).powi(2) * (8.0 + 8.0 + 8.0);
    let vectors = 40.0 * b * 8.0;
    band + pattern + vectors
}

/// Bytes per node-frame of a clip held in memory: positions (3) + κ2, data κ, ω (3), truth (2),
/// twice over while it is read.
const CLIP_BYTES_PER_NODE_FRAME: f64 = 12.0 * 8.0;
/// Bytes a solved frame leaves in the clip's summary (its report, roughness and truth scores,
/// `engine::rust::clip_summary`; about 0.4 KB measured by `tests/memory_growth.rs`).
const SUMMARY_BYTES_PER_FRAME: f64 = 1024.0;
/// Frames a streamed clip holds at most: twice [`STREAM_AHEAD`] received (the run being solved
/// and those waiting) and the output thread's 64 converged frames.
const STREAMED_FRAMES_HELD: usize = 2 * STREAM_AHEAD + 64;

/// Bytes of a clip case's frames and summary, from its settings or the size of its file, and
/// what they were estimated from. A synthetic roll_3d clip with fixed weights is streamed
/// (`crate::engine::ClipInput`): a window of its frames is held, not all of them.
fn clip_bytes(case: &Case) -> Option<(f64, String)> {
    let c = case.clip()?;
    let nodes = case.mesh.nodes() as f64;
    let frames = match (&c.kind, c.frames) {
        (_, Some((a, b))) => Some((b.saturating_sub(a) as f64, format!("clip.frames = [{a}, {b}]"))),
        (ClipKind::Roll3d(s), None) => Some((s.frames as f64, format!("clip.clip_frames = {}", s.frames))),
        _ => None,
    };
    let streamed =
        matches!(c.kind, ClipKind::Roll3d(_)) && case.inverse().is_some_and(|s| s.weights_rule != WeightsRule::Auto);
    let (frames, basis) = match frames {
        Some((f, key)) => (f, format!("{key} × {nodes} nodes")),
        None => {
            // a recording or kymogram: every number takes at least 8 bytes in the file; a
            // node-frame of a recording 3 numbers, a kymogram's frame of `nodes` nodes one
            // angle per joint
            let size = std::fs::metadata(&c.file).map(|m| m.len() as f64).unwrap_or(0.0);
            let frames = match c.kind {
                ClipKind::Kymogram => size / 8.0,
                _ => size / 24.0 / nodes,
            };
            (frames, format!("{} ({:.0} MB)", c.file.display(), size / 1e6))
        }
    };
    let held = if streamed { frames.min(STREAMED_FRAMES_HELD as f64) } else { frames };
    let basis = if streamed { format!("{basis}, streamed: at most {held} frames held") } else { basis };
    Some((held * nodes * CLIP_BYTES_PER_NODE_FRAME + frames * SUMMARY_BYTES_PER_FRAME, basis))
}

/// Bytes per time step of a dynamic run's records (`solve::dynamics::TipRecord`, about 210 with
/// its balance and chart) and their rows in `tip_history.csv` and `balance.csv` (9 and 11 numbers
/// of about 24 characters, written from memory).
const TIP_RECORD_BYTES: f64 = 720.0;

/// Estimated peak memory [bytes] of `what` on `case`, with what it was estimated from and the
/// keys that scale it.
pub fn estimate(case: &Case, what: Footprint) -> (f64, String, &'static str) {
    let elements = case.mesh.elements;
    let e = elements as f64;
    let n_forward = 6.0 * (e + 1.0);
    let basis = format!("rod.elements = {elements}");
    match what {
        Footprint::Modes { count } => {
            // the banded LU of K and the Lanczos basis (each vector and its M-image), grown
            // twice by 4 (count + block) vectors (`linalg::largest_symmetric`)
            let vectors = 2.0 * 8.0 * (count + crate::solve::modes::LANCZOS_BLOCK) as f64;
            (
                FIXED_BYTES + e * banded_bytes_per_element(6.0) + 2.0 * vectors * n_forward * 8.0,
                format!("{basis}: {n_forward} unknowns, a Lanczos basis of {vectors} vectors"),
                "rod.elements",
            )
        }
        Footprint::Run => match &case.analysis {
            Analysis::Static(_) => (FIXED_BYTES + e * banded_bytes_per_element(6.0), basis, "rod.elements"),
            Analysis::Dynamic(p) => (
                FIXED_BYTES + e * banded_bytes_per_element(6.0) + (p.steps as f64 + 1.0) * TIP_RECORD_BYTES,
                format!("{basis}, time.steps = {}", p.steps),
                "rod.elements or time.steps",
            ),
            Analysis::Inverse(_) => {
                // the KKT system (12 unknowns per node), the forward data solve beside it
                let mut bytes = FIXED_BYTES + e * (banded_bytes_per_element(12.0) + banded_bytes_per_element(6.0));
                let mut basis = basis;
                if let Some((clip, what)) = clip_bytes(case) {
                    bytes += clip;
                    basis = format!("{basis}, {what}");
                }
                (bytes, basis, "rod.elements or the clip's frames")
            }
        },
    }
}

/// Refuse `what` on `case` if its estimate exceeds `limit_bytes`, or the process's
/// address-space limit where that is lower (an allocation beyond it would fail mid-run).
pub fn check(case: &Case, what: Footprint, limit_bytes: f64) -> Result<(), BudgetError> {
    let (bytes, basis, key) = estimate(case, what);
    let (limit_bytes, limit_source) = match address_space_limit() {
        Some(a) if a < limit_bytes => (a, LimitSource::AddressSpace),
        _ => (limit_bytes, LimitSource::Asked),
    };
    if bytes > limit_bytes {
        let what = match what {
            Footprint::Run => "the run",
            Footprint::Modes { .. } => "the modal analysis",
        };
        let case = case.origin.source.as_ref().map(|p| p.display().to_string()).unwrap_or_else(|| case.name.clone());
        return Err(BudgetError { case, what, bytes, limit: limit_bytes, basis, key, limit_source });
    }
    Ok(())
}

/// The default limit: half of the machine's memory (`/proc/meminfo`), 4 GiB where unknown.
pub fn default_limit_bytes() -> f64 {
    let total_kib = std::fs::read_to_string("/proc/meminfo").ok().and_then(|s| {
        s.lines().find(|l| l.starts_with("MemTotal:")).and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
    });
    total_kib.map(|k| k * 1024.0 / 2.0).unwrap_or(4.0 * GIB)
}
