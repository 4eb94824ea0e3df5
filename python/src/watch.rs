//! A solve on a worker thread with the GIL released, watched from the calling thread: the
//! caller's progress callback is called there (under the GIL), and a signal (Ctrl-C) found by
//! `Python::check_signals` stops the solve and is raised once the worker has ended.
//!
//! Each call has its own stop token (`cosserat::interrupt::StopToken`, installed for the worker
//! thread): a `cosserat.Cancel` the caller passes, or a fresh one. What sets it:
//! - Ctrl-C: Python runs signal handlers in the main thread only, so `check_signals` raises
//!   KeyboardInterrupt in the call of the main thread, and that call's solve stops; calls in
//!   other threads run on (the exception, raised in the main thread, is the user's to forward);
//! - `Cancel.set()`, from any thread: the calls given that `Cancel` stop, and raise
//!   `cosserat.Cancelled`;
//! - an exception of the progress callback: its call stops, and raises it.
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::time::Duration;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

use cosserat::interrupt::StopToken;

/// How often the calling thread looks for signals while a solve runs [s]: a Ctrl-C is seen
/// within this time, and the engine stops at its next check (between iterations of a frame).
const TICK_S: f64 = 0.02;

/// Progress messages of the worker: (done, total).
pub type Progress = Sender<(usize, usize)>;
/// Where the calling thread receives them.
type Reports = Receiver<(usize, usize)>;

/// A request to stop the calls it is given to (`cosserat.Cancel`): `set()` from any thread
/// stops them at their next check (within an iteration), and they raise `cosserat.Cancelled`.
/// Once set it stays set; a fresh `Cancel` is needed for the next calls.
#[pyclass(module = "cosserat", name = "Cancel", frozen)]
#[derive(Default)]
pub struct Cancel {
    token: StopToken,
}

#[pymethods]
impl Cancel {
    #[new]
    fn py_new() -> Self {
        Self::default()
    }

    /// Stop the calls given this object (at their next check).
    fn set(&self) {
        self.token.set();
    }

    /// Has `set()` been called?
    fn is_set(&self) -> bool {
        self.token.is_set()
    }

    fn __repr__(&self) -> String {
        format!("Cancel(set={})", if self.token.is_set() { "True" } else { "False" })
    }
}

/// The stop token of a call: the given `Cancel`'s, or a new one.
pub fn token_of(cancel: Option<&Bound<'_, Cancel>>) -> StopToken {
    cancel.map(|c| c.get().token.clone()).unwrap_or_default()
}

/// The newest message waiting on `rx` after at most one tick, and whether the worker may send
/// more (false: it has ended). Takes and gives back `rx`, so that it can run without the GIL.
fn wait(rx: Reports) -> (Reports, Option<(usize, usize)>, bool) {
    match rx.recv_timeout(Duration::from_secs_f64(TICK_S)) {
        Ok(first) => {
            let latest = rx.try_iter().last().unwrap_or(first);
            (rx, Some(latest), true)
        }
        Err(RecvTimeoutError::Timeout) => (rx, None, true),
        Err(RecvTimeoutError::Disconnected) => (rx, None, false),
    }
}

/// Run `work` on a worker thread with the GIL released and `token` installed there; `work`
/// reports its progress on the sender it is given, and `progress(done, total)` is called with
/// the newest report on this thread. A signal's exception (KeyboardInterrupt, main thread only)
/// or an exception of `progress` sets `token` and is returned after the worker has ended.
pub fn run_watched<T, F>(py: Python<'_>, progress: Option<&Bound<'_, PyAny>>, token: StopToken, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce(Progress) -> T + Send,
{
    let (tx, mut rx) = mpsc::channel();
    let mut raised: Option<PyErr> = None;
    let worker_token = token.clone();
    let out = std::thread::scope(|s| {
        let worker = s.spawn(move || worker_token.scope(|| work(tx)));
        loop {
            let (back, latest, open) = py.detach(move || wait(rx));
            rx = back;
            if let (Some((done, total)), Some(cb), None) = (latest, progress, &raised) {
                if let Err(e) = cb.call1((done, total)) {
                    token.set();
                    raised = Some(e);
                }
            }
            if raised.is_none() {
                if let Err(e) = py.check_signals() {
                    token.set();
                    raised = Some(e);
                }
            }
            if !open {
                break;
            }
        }
        py.detach(|| worker.join())
    });
    if let Some(e) = raised {
        return Err(e);
    }
    out.map_err(|_| PyRuntimeError::new_err("the solve panicked (a bug of cosserat: please report it)"))
}
