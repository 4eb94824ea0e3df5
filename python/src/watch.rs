//! A solve on a worker thread with the GIL released, watched from the calling thread: the
//! caller's progress callback is called there (under the GIL), and a signal (Ctrl-C) found by
//! `Python::check_signals` asks the engine to stop (`cosserat::interrupt`) and is raised once the
//! worker has ended.
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::time::Duration;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

/// How often the calling thread looks for signals while a solve runs [s]: a Ctrl-C is seen
/// within this time, and the engine stops at its next check (between iterations of a frame).
const TICK_S: f64 = 0.02;

/// Progress messages of the worker: (done, total).
pub type Progress = Sender<(usize, usize)>;
/// Where the calling thread receives them.
type Reports = Receiver<(usize, usize)>;

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

/// Run `work` on a worker thread with the GIL released; `work` reports its progress on the
/// sender it is given, and `progress(done, total)` is called with the newest report on this
/// thread. A signal's exception (KeyboardInterrupt) or an exception of `progress` stops the
/// engine (`cosserat::interrupt::request`) and is returned after the worker has ended (the
/// stop request is then cleared).
pub fn run_watched<T, F>(py: Python<'_>, progress: Option<&Bound<'_, PyAny>>, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce(Progress) -> T + Send,
{
    let (tx, mut rx) = mpsc::channel();
    let mut raised: Option<PyErr> = None;
    let out = std::thread::scope(|s| {
        let worker = s.spawn(move || work(tx));
        loop {
            let (back, latest, open) = py.detach(move || wait(rx));
            rx = back;
            if let (Some((done, total)), Some(cb), None) = (latest, progress, &raised) {
                if let Err(e) = cb.call1((done, total)) {
                    cosserat::interrupt::request();
                    raised = Some(e);
                }
            }
            if raised.is_none() {
                if let Err(e) = py.check_signals() {
                    cosserat::interrupt::request();
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
        cosserat::interrupt::clear();
        return Err(e);
    }
    out.map_err(|_| PyRuntimeError::new_err("the solve panicked (a bug of cosserat: please report it)"))
}
