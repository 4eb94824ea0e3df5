//! A clip run's memory is bounded by what its figures draw, not by its frames: the peak of the
//! heap, counted in process by this binary's allocator, of a run of 2000 frames is that of a
//! run of 500 frames plus a small bound (what a frame leaves behind: its report and a few
//! numbers of the summary, about 0.4 KB). Measured on the whole job of `cosserat run` (solve,
//! streamed files, resume journal, metrics, figures), for a synthetic clip made while it is
//! solved and for an NPY recording streamed from its file (the block of raw rows that the
//! writing of `fields.npz` holds allowed for); and on that writing alone, which reads the raw
//! rows a block at a time. Before, a frame of 33 nodes left about 6 KB behind (the kymographs'
//! fields of every frame, the streamed frames and their truth), 9 MB over these 1500 frames,
//! and a recording was held whole (24 bytes per node and frame).
mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use cosserat::case::Case;
use cosserat::engine::input::corpus::{write_corpus, CorpusParams};
use cosserat::engine::input::truth_file::truth_sidecar;
use cosserat::engine::Engine;
use cosserat::io::compact::{OutputFormat, CURVATURE_COLUMNS, RAW_CURVATURE, RAW_FIELDS};
use cosserat::io::compact_write::{write_compact, BLOCK_BYTES};
use cosserat::jobs::clip_run::ClipOptions;
use cosserat::jobs::solved::solve_into;
use cosserat::solve::Outcome;

/// The system allocator, counting the bytes held now and their peak.
struct Counting;

static NOW: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

fn grew(n: usize) {
    let now = NOW.fetch_add(n, Ordering::SeqCst) + n;
    PEAK.fetch_max(now, Ordering::SeqCst);
}

// SAFETY: every method forwards to `System` with the caller's arguments unchanged; the
// counters are only read.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract of `GlobalAlloc::alloc`, passed on.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` was allocated by `System` with `layout`.
        unsafe { System.dealloc(ptr, layout) };
        NOW.fetch_sub(layout.size(), Ordering::SeqCst);
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: `ptr` was allocated by `System` with `layout`; the rest is the caller's.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            NOW.fetch_sub(layout.size(), Ordering::SeqCst);
            grew(new_size);
        }
        p
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// The heap's peak while `f` runs, above what was held before [bytes].
fn peak_of(f: impl FnOnce()) -> usize {
    let before = NOW.load(Ordering::SeqCst);
    PEAK.store(before, Ordering::SeqCst);
    f();
    PEAK.load(Ordering::SeqCst) - before
}

const NODES: usize = 33;
/// What a frame may leave behind in memory [bytes]: its report (~0.25 KB), its roughness, truth
/// scores and clip.pvd entry (~0.1 KB), with room for the doubling of their vectors.
const PER_FRAME: usize = 1024;
const MIB: usize = 1 << 20;

/// `cosserat run` of `case` into a new folder in `dir` (journal kept while it runs, as there),
/// which must end complete.
fn run(case: &Case, dir: &Path, format: OutputFormat) {
    let out = tempfile::tempdir_in(dir).expect("tempdir");
    let opts = ClipOptions { journal: true, resume: false, format };
    let solved = solve_into(case, Engine::Rust, out.path(), opts, |_| {}, |_, _| {});
    assert!(matches!(solved.status, Outcome::Converged | Outcome::CompleteWithWarnings), "{:?}", solved.error);
}

/// The peaks [bytes] of the runs of `case_of(n)` and `case_of(m)` for `(n, m)` = `frames`.
fn peaks(dir: &Path, case_of: &dyn Fn(usize) -> Case, format: OutputFormat, frames: (usize, usize)) -> (usize, usize) {
    let (a, b) = (case_of(frames.0), case_of(frames.1));
    (peak_of(|| run(&a, dir, format)), peak_of(|| run(&b, dir, format)))
}

/// Raw rows of `frames` frames of `NODES` nodes, and the peak of writing their `fields.npz`.
fn compact_peak(dir: &Path, frames: usize) -> usize {
    let columns: Vec<String> = (0..28).map(|c| format!("c{c}")).collect();
    let names: Vec<&str> = columns.iter().map(String::as_str).collect();
    let write = |name: &str, per: usize, nc: usize| {
        let mut f = std::io::BufWriter::new(std::fs::File::create(dir.join(name)).expect("raw"));
        for i in 0..frames * per * nc {
            std::io::Write::write_all(&mut f, &((i as f64) * 1e-3).sin().to_le_bytes()).expect("write");
        }
    };
    write(RAW_FIELDS, NODES, names.len());
    write(RAW_CURVATURE, NODES - 1, CURVATURE_COLUMNS.len());
    let numbers: Vec<i64> = (0..frames as i64).collect();
    peak_of(|| {
        write_compact(dir, &numbers, &names).expect("fields.npz");
    })
}

#[test]
fn a_clip_run_does_not_grow_with_its_frames() {
    if !common::worm_data_present("a_clip_run_does_not_grow_with_its_frames") {
        return;
    }
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path();
    let mib = |b: usize| b as f64 / MIB as f64;
    let bound = 1500 * PER_FRAME + MIB;

    // 1. a synthetic clip integrated while it is solved (`worm_roll_3d` on 33 nodes, 2000
    // frames, its first 500 or all)
    let roll = |frames: usize| {
        let path = common::short_roll_case(dir, &format!("roll_{frames}.toml"), 2000, NODES);
        let text = std::fs::read_to_string(&path).expect("case");
        std::fs::write(
            &path,
            common::edit(&text, "clip_frames = 2000", &format!("clip_frames = 2000\nframes = [0, {frames}]")),
        )
        .expect("case");
        Case::from_file(&path).expect("case")
    };
    let (a, b) = peaks(dir, &roll, OutputFormat::Csv, (500, 2000));
    eprintln!("streamed roll_3d, CSV: peak {:.2} MiB at 500 frames, {:.2} MiB at 2000", mib(a), mib(b));
    assert!(b <= a + bound, "2000 frames: {:.2} MiB, 500 frames: {:.2} MiB", mib(b), mib(a));

    // 2. recordings streamed from their files (`cosserat synth`, the truth sidecar removed as
    // a lab recording has none), the batch case on 65 nodes with weights = "auto", compact
    // output, 2000 and 5000 frames: both write fields.npz in blocks of raw rows
    // (io::compact_write), which the peak holds alike. Held whole, the recording's positions
    // (24 bytes per node and frame, 4.5 MiB more at 5000 frames) would exceed the bound.
    const REC_NODES: usize = 65;
    let text = std::fs::read_to_string(common::cases_dir().join("batch/roll_recording.toml")).expect("batch case");
    let text = common::edit(&text, "elements = 32 ", &format!("elements = {} ", REC_NODES - 1));
    let recording = |frames: usize| {
        let corpus = dir.join(format!("corpus_{frames}"));
        let params = CorpusParams { count: 1, frames, nodes: REC_NODES, seed: 3, ..CorpusParams::default() };
        let kymogram = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/elegansbot/kymogram_omega-turn.npy");
        write_corpus(&corpus, &kymogram, &params).expect("corpus");
        let file = corpus.join("roll_000.npy");
        std::fs::remove_file(truth_sidecar(&file)).expect("truth sidecar");
        let t = common::edit(
            &text,
            "file = \"../../data/corpus/roll_000.npy\"",
            &format!("file = {:?}", file.display().to_string()),
        );
        common::case_from(&t, &format!("recording_{frames}"))
    };
    let (a, b) = peaks(dir, &recording, OutputFormat::Compact, (2000, 5000));
    // and each frame's noise level, 8 bytes, held for the median of the automatic weights
    let bound = 3000 * (PER_FRAME + 8) + MIB;
    eprintln!("recording, compact: peak {:.2} MiB at 2000 frames, {:.2} MiB at 5000", mib(a), mib(b));
    assert!(b <= a + bound, "5000 frames: {:.2} MiB, 2000 frames: {:.2} MiB", mib(b), mib(a));

    // 3. fields.npz of 2 and of 8 blocks of raw rows
    let frames_per_block = BLOCK_BYTES / (8 * 28 * NODES);
    let (a, b) = (compact_peak(dir, 2 * frames_per_block), compact_peak(dir, 8 * frames_per_block));
    eprintln!("fields.npz: peak {:.2} MiB for 2 blocks, {:.2} MiB for 8", mib(a), mib(b));
    assert!(b <= a + MIB, "8 blocks: {:.2} MiB, 2 blocks: {:.2} MiB", mib(b), mib(a));
}
