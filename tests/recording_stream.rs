//! An NPY recording is streamed from its file into the solve (`engine::input::recording_stream`:
//! a survey pass, a pass for the lengths and the noise level, then the solve's own pass), so
//! that a clip run does not hold the recording. The frames it solves must be bit for bit those
//! of the same recording read whole, with the same automatic weights, frame range and
//! orientation; the body length estimated from it the same; a recording the stream cannot take
//! (untracked nodes) read whole; a file that changes under the run an error that says so.
//!
//! The whole-read reference is the same positions written as a CSV recording (every number
//! written in its shortest round-trip form, so read back to the bit), which is never streamed.
//! A `cosserat synth` recording of 33 nodes and 14 frames; needs the omega-turn kymogram.
mod common;

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use common::{frame_bits, worm_data_present, Collect};
use cosserat::case::Case;
use cosserat::engine::clip::{ClipFrame, ClipOutcome};
use cosserat::engine::input::clip_files::ClipFileError;
use cosserat::engine::input::corpus::{write_corpus, CorpusParams};
use cosserat::engine::input::resolve::resolve_recording;
use cosserat::engine::input::truth_file::truth_sidecar;
use cosserat::engine::{run_clip_into, ClipInput, RunError};
use cosserat::io::npy::{read_npy, write_npy};

const NODES: usize = 33;
const FRAMES: usize = 14;

/// A recording of `FRAMES` frames (noise 1e-7 m) as NPY and as CSV, without its truth sidecar
/// (a lab recording has none); `None` without the worm data.
fn recording(test: &str, dir: &Path) -> Option<(PathBuf, PathBuf)> {
    if !worm_data_present(test) {
        return None;
    }
    let corpus = dir.join("corpus");
    let kymogram = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/elegansbot/kymogram_omega-turn.npy");
    let params = CorpusParams { count: 1, frames: FRAMES, nodes: NODES, seed: 11, ..CorpusParams::default() };
    write_corpus(&corpus, &kymogram, &params).expect("corpus");
    let npy = corpus.join("roll_000.npy");
    std::fs::remove_file(truth_sidecar(&npy)).expect("the corpus writes a truth sidecar");
    let a = read_npy(&npy).expect("recording");
    assert_eq!(a.shape, [FRAMES, NODES, 3]);
    let mut text = String::from("frame,node,x_m,y_m,z_m\n");
    for (k, p) in a.data.chunks_exact(3).enumerate() {
        text += &format!("{},{},{:?},{:?},{:?}\n", k / NODES, k % NODES, p[0], p[1], p[2]);
    }
    let csv = corpus.join("roll_000.csv");
    std::fs::write(&csv, text).expect("csv");
    Some((npy, csv))
}

/// The batch case (`weights = "auto"`) on `file`, with `clip_keys` added to `[clip]` and the
/// body length `length` (TOML), resolved against its recording as `cosserat run` does.
fn case_on(file: &Path, clip_keys: &str, length: &str) -> Case {
    try_case_on(file, clip_keys, length).expect("resolved")
}

/// [`case_on`], or the error of resolving it.
fn try_case_on(file: &Path, clip_keys: &str, length: &str) -> Result<Case, ClipFileError> {
    let text = std::fs::read_to_string(common::cases_dir().join("batch/roll_recording.toml")).expect("batch case");
    let text = common::edit(
        &text,
        "file = \"../../data/corpus/roll_000.npy\"",
        &format!("file = {:?}\n{clip_keys}", file.display().to_string()),
    );
    let text = common::edit(&text, "length_m = \"L\"", &format!("length_m = {length}"));
    resolve_recording(&common::case_from(&text, "recording_stream"))
}

/// `cosserat run`'s clip solve of `case`: whether its recording was streamed, the outcome and
/// every frame handed to the sink.
fn run(case: &Case) -> (bool, ClipOutcome, Vec<ClipFrame>) {
    let input = ClipInput::of(case).expect("clip input");
    let streamed = matches!(input, ClipInput::Recorded { .. });
    let got = Arc::new(Mutex::new(Vec::new()));
    let out = run_clip_into(case, input, &mut std::iter::empty(), Collect(got.clone()), |_, _| {}).expect("clip runs");
    let got = got.lock().expect("frames").clone();
    (streamed, out, got)
}

#[test]
fn a_streamed_recording_gives_the_frames_of_the_recording_read_whole_bit_for_bit() {
    let test = "a_streamed_recording_gives_the_frames_of_the_recording_read_whole_bit_for_bit";
    let dir = tempfile::tempdir().expect("tempdir");
    let Some((npy, csv)) = recording(test, dir.path()) else { return };
    // a range that leaves frames out at both ends, and a rotation of the data
    let keys = "frames = [2, 13]\norientation = [0.3, -0.2, 0.5]";
    let (s_npy, a, fa) = run(&case_on(&npy, keys, "\"L\""));
    let (s_csv, b, fb) = run(&case_on(&csv, keys, "\"L\""));
    assert!(s_npy && !s_csv, "the NPY recording is streamed ({s_npy}), the CSV one read whole ({s_csv})");
    assert!(a.stopped.is_none() && b.stopped.is_none(), "{:?} {:?}", a.stopped, b.stopped);
    assert_eq!((fa.len(), a.total), (11, 11));
    assert_eq!(fb.len(), 11);
    let (wa, wb) = (a.run.weights.expect("auto weights"), b.run.weights.expect("auto weights"));
    assert_eq!(wa.noise_m.to_bits(), wb.noise_m.to_bits(), "noise level {} vs {}", wa.noise_m, wb.noise_m);
    assert_eq!(wa.lambda_g.to_bits(), wb.lambda_g.to_bits(), "λg {} vs {}", wa.lambda_g, wb.lambda_g);
    assert_eq!((wa.solves, wa.calibration_frames), (wb.solves, wb.calibration_frames));
    assert!(wa.noise_m > 0.5e-7 && wa.noise_m < 2e-7, "the recording's noise is 1e-7 m: {}", wa.noise_m);
    for (x, y) in fa.iter().zip(&fb) {
        assert_eq!(x.report.frame, y.report.frame);
        assert!(frame_bits(x) == frame_bits(y), "frame {} differs from the recording read whole", x.report.frame);
    }
    assert_eq!(fa[0].report.frame, 2, "frames keep the file's numbers");
}

#[test]
fn the_body_length_of_a_streamed_recording_is_that_of_the_recording_read_whole() {
    let test = "the_body_length_of_a_streamed_recording_is_that_of_the_recording_read_whole";
    let dir = tempfile::tempdir().expect("tempdir");
    let Some((npy, csv)) = recording(test, dir.path()) else { return };
    let keys = "frames = [1, 12]";
    let (a, b) = (case_on(&npy, keys, "\"from_data\""), case_on(&csv, keys, "\"from_data\""));
    assert_eq!(a.mesh.length_m.to_bits(), b.mesh.length_m.to_bits(), "{} vs {}", a.mesh.length_m, b.mesh.length_m);
    assert_eq!(a.rod.length, b.rod.length);
    assert!((a.mesh.length_m / 1e-3 - 1.0).abs() < 0.02, "a 1 mm worm: {} m", a.mesh.length_m);
}

#[test]
fn a_recording_with_untracked_nodes_is_read_whole_and_a_changed_file_stops_the_run() {
    let test = "a_recording_with_untracked_nodes_is_read_whole_and_a_changed_file_stops_the_run";
    let dir = tempfile::tempdir().expect("tempdir");
    let Some((npy, _)) = recording(test, dir.path()) else { return };
    let a = read_npy(&npy).expect("recording");
    // a lost node in frame 5: filled from its neighbours, which needs the clip read whole
    let mut lost = a.data.clone();
    lost[(5 * NODES + 7) * 3..(5 * NODES + 8) * 3].fill(f64::NAN);
    let holes = dir.path().join("holes.npy");
    write_npy(&holes, &a.shape, &lost).expect("npy");
    let input = ClipInput::of(&case_on(&holes, "missing = \"nan\"", "\"L\"")).expect("read whole");
    assert!(matches!(input, ClipInput::Loaded { .. }), "a recording with a lost node is read whole");
    // without clip.missing the NaN is refused before any frame is solved, naming frame and node
    let e = try_case_on(&holes, "", "\"L\"").expect_err("a NaN is refused");
    let chain = common::error_chain(&e);
    assert!(chain.contains("frame 5") && chain.contains("node 7"), "{chain}");

    // the file cut to 6 frames after the clip was read through: the frames read are solved,
    // then the run stops and says why
    let case = case_on(&npy, "", "\"L\"");
    let input = ClipInput::of(&case).expect("streamed");
    assert!(matches!(input, ClipInput::Recorded { .. }));
    write_npy(&npy, &[6, NODES, 3], &a.data[..6 * NODES * 3]).expect("npy");
    let got = Arc::new(Mutex::new(Vec::new()));
    let out = run_clip_into(&case, input, &mut std::iter::empty(), Collect(got.clone()), |_, _| {}).expect("runs");
    assert_eq!(got.lock().expect("frames").len(), 6);
    match &out.stopped {
        Some(e @ RunError::Recording { received: 6, total: FRAMES, .. }) => {
            let chain = common::error_chain(e);
            assert!(chain.contains("has 6 frames now") && chain.contains("changed"), "{chain}");
        }
        other => panic!("expected the recording's read error after 6 of {FRAMES} frames, got {other:?}"),
    }
}
