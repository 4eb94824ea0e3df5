//! A request to stop, set by SIGINT/SIGTERM (the `cosserat` binary installs the handler) and
//! read by the long loops: a clip stops before its next frame, a static solve before its next
//! iteration, a dynamic solve before its next time step, a FreeFEM child is killed. One flag
//! for the process, because a signal is one for the process.
use std::sync::atomic::{AtomicBool, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Ask every running loop to stop at its next check (what the signal handler calls).
pub fn request() {
    REQUESTED.store(true, Ordering::SeqCst);
}

/// Has a stop been requested?
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}

/// Clear the request (tests that run several interrupted jobs in one process).
pub fn clear() {
    REQUESTED.store(false, Ordering::SeqCst);
}
