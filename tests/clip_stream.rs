//! A clip whose frames arrive while it is solved (`ClipFrames::Streamed`, what `cosserat run`
//! does with a synthetic `worm_roll_3d` clip: the frames are integrated on a second thread) is
//! solved in runs of the frames at hand, each resumed from the last two states. The frames must
//! be bit for bit those of the clip solved in one run from all its frames, however the frames
//! arrive; a generator that stops early stops the clip with an error naming how far it got.
//! On a 20-frame `worm_roll_3d` with 16 nodes; needs the omega-turn kymogram.
mod common;

use std::sync::mpsc::{channel, Sender};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use common::{frame_bits as bits, short_roll_case, worm_data_present, Collect};
use cosserat::case::Case;
use cosserat::clip::synthetic::{FrameTruth, GroundTruth};
use cosserat::clip::Clip;
use cosserat::engine::clip::{ClipFrame, ClipOutcome};
use cosserat::engine::input::clip_files::load_clip;
use cosserat::engine::rust::clip::{run_clip, ClipFrames, StreamedFrame};
use cosserat::engine::RunError;

const FRAMES: usize = 20;
const NODES: usize = 16;

/// The short clip as a case, its frames and their ground truth (`None` without the worm data).
fn short_clip(test: &str) -> Option<(tempfile::TempDir, Case, Clip, GroundTruth)> {
    if !worm_data_present(test) {
        return None;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let case = Case::from_file(&short_roll_case(dir.path(), "roll_stream.toml", FRAMES, NODES)).expect("case");
    let (clip, truth) = load_clip(&case).expect("clip");
    Some((dir, case, clip, truth.expect("a synthetic clip has a ground truth")))
}

/// The clip without its frames, as a stream's header.
fn header(clip: &Clip) -> Clip {
    Clip { frames: Vec::new(), ..clip.clone() }
}

/// Run the clip of `case` on `frames`; the outcome and the frames the sink received.
fn solve(case: &Case, frames: ClipFrames<'_>) -> (ClipOutcome, Vec<ClipFrame>) {
    let got = Arc::new(Mutex::new(Vec::new()));
    let out = run_clip(case, frames, &[], Collect(got.clone()), |_, _| {}).expect("clip runs");
    let got = got.lock().expect("frames").clone();
    (out, got)
}

/// Send frames `0..count` of the loaded clip, waiting `pause` before each.
fn feed(tx: Sender<StreamedFrame>, clip: &Clip, truth: &[FrameTruth], count: usize, pause: Duration) {
    for i in 0..count {
        std::thread::sleep(pause);
        if tx.send((clip.frames[i].clone(), Some(truth[i].clone()))).is_err() {
            return;
        }
    }
}

#[test]
fn a_streamed_clip_gives_the_frames_of_one_solve_bit_for_bit() {
    let Some((_dir, case, clip, truth)) = short_clip("a_streamed_clip_gives_the_frames_of_one_solve_bit_for_bit")
    else {
        return;
    };
    let (whole, reference) = solve(&case, ClipFrames::Loaded { clip: &clip, truth: Some(&truth), start: None });
    assert!(whole.stopped.is_none(), "{:?}", whole.stopped);
    assert_eq!(reference.len(), FRAMES);
    // Frames one at a time, slower than they are solved (runs of one frame: the second state
    // to resume from comes from the run before), then all at once (one run).
    for pause in [Duration::from_millis(30), Duration::ZERO] {
        let (tx, rx) = channel();
        let (out, got) = std::thread::scope(|s| {
            s.spawn(|| feed(tx, &clip, &truth.frames, FRAMES, pause));
            solve(
                &case,
                ClipFrames::Streamed { header: header(&clip), total: FRAMES, truth: true, frames: rx, start: None },
            )
        });
        assert!(out.stopped.is_none(), "pause {pause:?}: {:?}", out.stopped);
        assert_eq!(got.len(), FRAMES);
        for (a, b) in reference.iter().zip(&got) {
            assert_eq!(a.report.frame, b.report.frame);
            assert!(bits(a) == bits(b), "pause {pause:?}: frame {} differs from the one-run solve", a.report.frame);
        }
        assert_eq!(out.run.source, whole.run.source);
        assert_eq!(out.total, FRAMES);
    }
}

#[test]
fn a_stream_that_ends_early_stops_the_clip_with_an_error() {
    let Some((_dir, case, clip, truth)) = short_clip("a_stream_that_ends_early_stops_the_clip_with_an_error") else {
        return;
    };
    let (tx, rx) = channel();
    feed(tx, &clip, &truth.frames, 5, Duration::ZERO);
    let (out, got) = solve(
        &case,
        ClipFrames::Streamed { header: header(&clip), total: FRAMES, truth: true, frames: rx, start: None },
    );
    assert_eq!(got.len(), 5, "the frames that arrived are solved and handed over");
    match out.stopped {
        Some(RunError::Generator { received: 5, total: FRAMES }) => {}
        other => panic!("expected the generator error after 5 of {FRAMES} frames, got {other:?}"),
    }
    assert_eq!(out.run.reports.len(), 5);
}
