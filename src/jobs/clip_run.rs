//! A clip case run into its output folder: the Rust engine ([`crate::engine::run_clip_into`])
//! streams every converged frame to a [`ClipWriter`] (rows, fields, VTK file, the resume
//! journal), fresh or resumed after the journal's frames. The one place where a clip's engine
//! meets its files: `output/` writes them and runs no engine; the summary figures are
//! [`crate::output::clip_figures::write_clip_figures`].
use std::path::Path;

use crate::case::Case;
use crate::engine::clip::{ClipFrame, ClipOutcome, ClipRun, FrameSink};
use crate::engine::{run_clip_into, ClipInput, EngineError};
use crate::io::compact::OutputFormat;
use crate::io::files::{JournalError, OutputError};
use crate::output::clip_output::{ClipWriter, WriterOptions};
use crate::output::journal::{journal_records, scan_journal, JournalScan};

/// Solve the clip of a clip case frame by frame in the Rust engine, streaming every converged
/// frame into `dir` ([`ClipWriter`]); on failure the converged frames stay there and the error
/// names the frame. The summary figures are the caller's
/// ([`crate::output::clip_figures::write_clip_figures`]).
pub fn run_clip_case(case: &Case, dir: &Path, progress: impl FnMut(usize, usize)) -> Result<ClipRun, EngineError> {
    run_clip_case_observed(case, dir, |_| {}, progress)
}

/// [`run_clip_case`] with `observer` called on every converged frame, in order, after it was
/// written (on the output thread).
pub fn run_clip_case_observed(
    case: &Case,
    dir: &Path,
    observer: impl FnMut(&ClipFrame) + Send,
    progress: impl FnMut(usize, usize),
) -> Result<ClipRun, EngineError> {
    let out = run_clip_to(case, dir, ClipOptions::default(), observer, progress)?;
    match out.stopped {
        Some(e) => Err(e.into()),
        None => Ok(out.run),
    }
}

/// How [`run_clip_to`] treats the folder.
#[derive(Clone, Copy, Debug, Default)]
pub struct ClipOptions {
    /// keep the resume journal (`super::journal`) while the clip runs
    pub journal: bool,
    /// continue the run whose journal `dir` holds, after its last complete frame
    pub resume: bool,
    /// how the per-node fields are written (`crate::io::compact`)
    pub format: OutputFormat,
}

/// The clip of a clip case in the Rust engine, streamed into `dir` (as [`run_clip_case`]), fresh
/// or resumed after the frames of the journal in `dir` ([`ClipOptions`]). `Err`: the clip could
/// not be started; otherwise the outcome's summary covers every frame in `dir` (resumed ones
/// included) and `stopped` says why it ended early, if it did.
pub fn run_clip_to(
    case: &Case,
    dir: &Path,
    opts: ClipOptions,
    observer: impl FnMut(&ClipFrame) + Send,
    progress: impl FnMut(usize, usize),
) -> Result<ClipOutcome, EngineError> {
    let input = ClipInput::of(case)?;
    let writer = WriterOptions { truth: input.has_truth(), journal: opts.journal, format: opts.format };
    let (scan, sink) = if opts.resume {
        // a run killed before its first frame has no journal yet: it resumes from the start
        let scan = match scan_journal(dir) {
            Err(JournalError::Missing { .. }) => JournalScan::default(),
            read => read?,
        };
        let sink = ClipWriter::resume(dir, &scan, writer)?;
        (scan, sink)
    } else {
        (JournalScan::default(), ClipWriter::create(dir, writer)?)
    };
    // the records of the resumed frames, read again one at a time while they are summarised
    let mut records: Box<dyn Iterator<Item = _>> = match scan.frames.len() {
        0 => Box::new(std::iter::empty()),
        n => Box::new(journal_records(dir, n)?),
    };
    run_clip_into(case, input, &mut records, Observed { sink, observer }, progress)
}

/// A [`FrameSink`] that writes each frame and then shows it to an observer.
struct Observed<F> {
    sink: ClipWriter,
    observer: F,
}

impl<F: FnMut(&ClipFrame) + Send> FrameSink for Observed<F> {
    type Error = OutputError;
    fn frame(&mut self, frame: &ClipFrame) -> Result<(), OutputError> {
        self.sink.frame(frame)?;
        (self.observer)(frame);
        Ok(())
    }
    fn finish(&mut self) -> Result<(), OutputError> {
        self.sink.finish()
    }
}
