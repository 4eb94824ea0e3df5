//! A request to stop, read by the long loops: a clip stops before its next frame, a static solve
//! before its next iteration, a dynamic solve before its next time step, a FreeFEM child is
//! killed. Two sources, both read by [`requested`]:
//! - the process's flag ([`request`]), set by SIGINT/SIGTERM (the `cosserat` binary installs the
//!   handler): a signal is one for the process, so it stops every solve in it;
//! - a [`StopToken`] of one solve, installed for the thread that runs it ([`StopToken::scope`]):
//!   setting it stops that solve only (the Python package gives each call its own, so that a
//!   cancelled call leaves the calls of other threads running).
//!
//! The token is the thread's, not passed down: every loop that polls [`requested`] runs on the
//! thread that called the engine (a clip's reader and writer threads do not poll it), so the
//! solvers' `stopped_by(interrupt::requested)` needs no argument more.
use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

static REQUESTED: AtomicBool = AtomicBool::new(false);

thread_local! {
    /// The token of the solve this thread runs, if one was installed.
    static TOKEN: RefCell<Option<StopToken>> = const { RefCell::new(None) };
}

/// Ask every running loop of the process to stop at its next check (what the signal handler
/// calls).
pub fn request() {
    REQUESTED.store(true, Ordering::SeqCst);
}

/// Has a stop been requested, for the whole process or for the solve of this thread?
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst) || TOKEN.with(|t| t.borrow().as_ref().is_some_and(StopToken::is_set))
}

/// Clear the process's request (tests that run several interrupted jobs in one process).
pub fn clear() {
    REQUESTED.store(false, Ordering::SeqCst);
}

/// A stop request for one solve: shared by the thread that may ask for the stop and the thread
/// that runs the solve (clones are the same token). Once set it stays set.
#[derive(Clone, Debug, Default)]
pub struct StopToken(Arc<AtomicBool>);

impl StopToken {
    /// A token not set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Ask the solve that runs under this token to stop at its next check.
    pub fn set(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    /// Has the stop been asked for?
    pub fn is_set(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }

    /// Run `work` on this thread with this token installed: [`requested`] is true inside it once
    /// the token is set (or the process's flag is). The thread's previous token is put back
    /// afterwards, also when `work` panics.
    pub fn scope<T>(&self, work: impl FnOnce() -> T) -> T {
        struct Restore(Option<StopToken>);
        impl Drop for Restore {
            fn drop(&mut self) {
                let previous = self.0.take();
                TOKEN.with(|t| *t.borrow_mut() = previous);
            }
        }
        let _restore = Restore(TOKEN.with(|t| t.borrow_mut().replace(self.clone())));
        work()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_token_stops_its_own_thread_only() {
        let (mine, other) = (StopToken::new(), StopToken::new());
        let theirs = other.clone();
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::scope(|s| {
            // the other solve: waits until this thread's token is set, then reports what it sees
            s.spawn(move || {
                other.scope(|| {
                    rx.recv().unwrap();
                    assert!(!requested(), "a token set for another thread stopped this one");
                })
            });
            mine.scope(|| {
                assert!(!requested());
                mine.set();
                assert!(requested());
                tx.send(()).unwrap();
            });
        });
        // outside its scope, the thread has no token again
        assert!(mine.is_set() && !theirs.is_set());
        assert!(!requested());
    }

    #[test]
    fn scopes_nest_and_restore_the_outer_token() {
        let (outer, inner) = (StopToken::new(), StopToken::new());
        outer.set();
        outer.scope(|| {
            assert!(requested());
            inner.scope(|| assert!(!requested()));
            assert!(requested());
        });
        assert!(!requested());
    }
}
