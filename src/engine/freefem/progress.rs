//! What a running FreeFEM script has done, read from its work folder while it runs, for a
//! command that shows progress (`compare`): the clip driver's frames (`ff_clip_frames.csv`, a
//! row appended per converged frame) and the dynamic forward run's time steps (`ff_tip.csv`, a
//! row per step after the initial state), the arc-length path's steps (`ff_path.csv`, a row per
//! point after the reference). Other runs (static, a single inverse frame) have no
//! count and report nothing.
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::include::RunOptions;
use crate::case::{Analysis, Case};
use crate::solve::statics::StaticParams;

/// What a count counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unit {
    Frames,
    Steps,
    /// steps of an arc-length path (D25)
    PathSteps,
}

/// `done` of `total` frames or time steps of the running script.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Count {
    pub done: usize,
    pub total: usize,
    pub unit: Unit,
}

/// A function told each new count of a running FreeFEM script.
pub type Observer = Arc<dyn Fn(Count) + Send + Sync>;

static OBSERVER: Mutex<Option<Observer>> = Mutex::new(None);

/// Sets (or, with `None`, removes) the function told the counts of the FreeFEM runs that
/// follow, in any thread.
pub fn observe(observer: Option<Observer>) {
    *OBSERVER.lock().unwrap_or_else(|e| e.into_inner()) = observer;
}

/// How often the work folder is read.
const POLL: Duration = Duration::from_millis(500);

/// The count of one run of `script`, polled while it runs.
pub(super) struct Watch {
    file: PathBuf,
    /// rows of the file that are not a frame or step (header, initial state)
    skip: usize,
    total: usize,
    unit: Unit,
    observer: Observer,
    last: Option<usize>,
    polled: Instant,
}

impl Watch {
    /// A watch of `script` run on `case` in `workdir`, if it has a count and an observer is set.
    pub(super) fn new(case: &Case, script: &str, workdir: &Path, opts: &RunOptions) -> Option<Watch> {
        let observer = OBSERVER.lock().unwrap_or_else(|e| e.into_inner()).clone()?;
        let (file, skip, total, unit) = match (script, &opts.clip, &case.analysis) {
            ("clip.edp", Some(clip), _) => ("ff_clip_frames.csv", 1, clip.frames, Unit::Frames),
            ("forward.edp", _, Analysis::Dynamic(p)) => ("ff_tip.csv", 2, p.steps, Unit::Steps),
            ("forward.edp", _, Analysis::Static(StaticParams { path: Some(p), .. })) => {
                ("ff_path.csv", 2, p.steps, Unit::PathSteps)
            }
            _ => return None,
        };
        let watch =
            Watch { file: workdir.join(file), skip, total, unit, observer, last: None, polled: Instant::now() - POLL };
        (watch.observer)(Count { done: 0, total, unit });
        Some(watch)
    }

    /// Reads the count ([`Watch::read`]) if [`POLL`] has passed since the last read.
    pub(super) fn poll(&mut self) {
        if self.polled.elapsed() >= POLL {
            self.read();
        }
    }

    /// Reads the count now and tells the observer a new one.
    pub(super) fn read(&mut self) {
        self.polled = Instant::now();
        // a missing file (not yet written) counts nothing
        let rows = std::fs::read(&self.file).map(|b| b.iter().filter(|&&c| c == b'\n').count()).unwrap_or(0);
        let done = rows.saturating_sub(self.skip).min(self.total);
        if self.last != Some(done) {
            self.last = Some(done);
            (self.observer)(Count { done, total: self.total, unit: self.unit });
        }
    }
}
