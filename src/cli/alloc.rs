//! The allocator of the `cosserat` binary: the system's, except that an allocation that fails
//! (the address space capped by `ulimit -v`, the machine's memory exhausted) ends the process
//! with an error saying so and exit status 1, where Rust would abort (exit status 134). The
//! output folder is then as a SIGKILL leaves it: the previous folder in place, a clip's
//! converged frames in its staging folder for `--resume`.
//!
//! Under an address-space limit, glibc's malloc is also kept to one arena: each further arena
//! reserves 64 MiB of address space, which such a limit is soon out of (`worm_roll_3d` needs
//! about 58 MB with one arena and failed under a 146 MB limit with several).
use std::alloc::{GlobalAlloc, Layout, System};
use std::io::Write;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// [`System`], with a failed allocation ending the process cleanly ([`out_of_memory`]).
pub struct Guarded;

/// The address-space limit [bytes] read at start (0: none): the message cannot read it once
/// an allocation has failed.
static LIMIT: AtomicU64 = AtomicU64::new(0);
/// One message, whichever thread fails first.
static FAILED: AtomicBool = AtomicBool::new(false);

/// Read the address-space limit, and keep malloc to one arena under it. Call first in `main`,
/// before any other thread starts.
pub fn at_start() {
    let Some(limit) = cosserat::engine::budget::address_space_limit() else { return };
    LIMIT.store(limit as u64, Ordering::SeqCst);
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        extern "C" {
            fn mallopt(param: std::ffi::c_int, value: std::ffi::c_int) -> std::ffi::c_int;
        }
        const M_ARENA_MAX: std::ffi::c_int = -8;
        // SAFETY: mallopt only sets an allocator parameter; no other thread runs yet.
        unsafe {
            mallopt(M_ARENA_MAX, 1);
        }
    }
}

// SAFETY: every method forwards to `System` with the caller's arguments unchanged, so the
// caller's contract of each `GlobalAlloc` method is `System`'s; a null result never returns.
unsafe impl GlobalAlloc for Guarded {
    /// # Safety
    /// The contract of [`GlobalAlloc::alloc`], passed on to [`System`] unchanged.
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the contract of `GlobalAlloc::alloc`, passed on (see the impl).
        let p = unsafe { System.alloc(layout) };
        if p.is_null() {
            out_of_memory(layout.size());
        }
        p
    }

    /// # Safety
    /// The contract of [`GlobalAlloc::alloc_zeroed`], passed on to [`System`] unchanged.
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the contract of `GlobalAlloc::alloc_zeroed`, passed on.
        let p = unsafe { System.alloc_zeroed(layout) };
        if p.is_null() {
            out_of_memory(layout.size());
        }
        p
    }

    /// # Safety
    /// The contract of [`GlobalAlloc::dealloc`], passed on to [`System`] unchanged.
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` was allocated by `System` (through this allocator) with `layout`.
        unsafe { System.dealloc(ptr, layout) }
    }

    /// # Safety
    /// The contract of [`GlobalAlloc::realloc`], passed on to [`System`] unchanged.
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: `ptr` was allocated by `System` with `layout`; the rest is the caller's.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if p.is_null() {
            out_of_memory(new_size);
        }
        p
    }
}

/// Say that an allocation of `size` bytes failed, without allocating (the text is formatted
/// into a buffer on the stack), and exit with status 1.
#[cold]
fn out_of_memory(size: usize) -> ! {
    if !FAILED.swap(true, Ordering::SeqCst) {
        let mut buf = [0u8; 640];
        let mut w = std::io::Cursor::new(&mut buf[..]);
        let limit = LIMIT.load(Ordering::SeqCst);
        let _ = write!(w, "error: out of memory: an allocation of {size} bytes failed");
        let _ = if limit > 0 {
            write!(w, " under the process's address-space limit of {:.1} MiB (ulimit -v)", limit as f64 / 1048576.0)
        } else {
            write!(w, " (the machine's memory is exhausted)")
        };
        let _ = writeln!(
            w,
            "; the output folder keeps its previous state (a clip's converged frames stay in its staging folder for --resume). Raise the limit or run a smaller case"
        );
        let n = w.position() as usize;
        let _ = std::io::stderr().write_all(&buf[..n]);
    }
    std::process::exit(1)
}
