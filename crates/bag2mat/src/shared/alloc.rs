//! Out of memory is an error like any other: `<tool>: error: out of memory …`, exit 1, the
//! temporary outputs removed — not Rust's `memory allocation of N bytes failed` and SIGABRT.
//!
//! Stable Rust has no hook for a failed allocation, so each binary installs
//! [`ExitOnOom`] as its global allocator: the system allocator, which, when an allocation
//! fails, writes the message with `write(2)` from a stack buffer (nothing is allocated),
//! removes the live temporary paths (best effort; a second failure there exits at once) and
//! exits with status 1. A failed allocation never returns, so `try_reserve` cannot recover
//! from one either: the tools have no allocation whose failure they could work around.
//! [`start_threads`] starts the worker threads up front, so that an address space too small
//! for their stacks is the same error rather than rayon's panic.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, Ordering};

/// Set once an allocation failed: a failure during the cleanup exits at once.
static FAILING: AtomicBool = AtomicBool::new(false);

/// The system allocator, reporting a failed allocation the workspace's way (see the module
/// doc). `#[global_allocator] static A: ExitOnOom = ExitOnOom::new("tool");`
pub struct ExitOnOom {
    tool: &'static str,
}

impl ExitOnOom {
    /// For the binary named `tool`.
    pub const fn new(tool: &'static str) -> ExitOnOom {
        ExitOnOom { tool }
    }

    #[cold]
    fn fail(&self, size: usize) -> ! {
        if !FAILING.swap(true, Ordering::SeqCst) {
            let mut buf = StackText::<320>::new();
            let _ = std::fmt::Write::write_fmt(
                &mut buf,
                format_args!(
                    "{}: error: out of memory: {} more bytes could not be allocated (the input needs more memory than this process may use)\n",
                    self.tool, size
                ),
            );
            // SAFETY: writes the initialised part of a stack buffer to stderr.
            unsafe {
                libc::write(2, buf.bytes().as_ptr().cast(), buf.bytes().len());
            }
            super::live::remove_live_paths();
        }
        // SAFETY: ends the process without running anything else (no unwinding out of the
        // allocator, which must not).
        unsafe { libc::_exit(1) }
    }
}

// SAFETY: every call goes to the system allocator with the same arguments; a null result
// (failure) does not return.
unsafe impl GlobalAlloc for ExitOnOom {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded as given.
        let p = unsafe { System.alloc(layout) };
        if p.is_null() {
            self.fail(layout.size());
        }
        huge_pages(p, layout.size());
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded as given.
        let p = unsafe { System.alloc_zeroed(layout) };
        if p.is_null() {
            self.fail(layout.size());
        }
        huge_pages(p, layout.size());
        p
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: forwarded as given.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if p.is_null() {
            self.fail(new_size);
        }
        huge_pages(p, new_size);
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded as given.
        unsafe { System.dealloc(ptr, layout) }
    }
}

/// Blocks from this size on are asked to be backed by huge pages.
const HUGE_FROM: usize = 8 << 20;
/// The huge page size of x86-64 and most arm64 kernels.
const HUGE_PAGE: usize = 2 << 20;

/// Asks the kernel to back the whole huge pages inside a large block (`p`, `size` bytes)
/// with transparent huge pages (`madvise(MADV_HUGEPAGE)`; a no-op where they are off). The
/// readers fill columns of hundreds of MB: with 4 KiB pages the page faults and their
/// bookkeeping cost as much as the parsing (issue 20's ULog profile).
fn huge_pages(p: *mut u8, size: usize) {
    if size < HUGE_FROM {
        return;
    }
    let start = (p as usize).next_multiple_of(HUGE_PAGE);
    let end = (p as usize + size) & !(HUGE_PAGE - 1);
    if end > start {
        // SAFETY: advice on pages of a block this allocator just handed out; it changes
        // how they are backed, never their contents. A failure (an old kernel) is ignored.
        unsafe {
            libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
        }
    }
}

/// A message formatted without allocating (cut at `N` bytes).
struct StackText<const N: usize> {
    buf: [u8; N],
    len: usize,
}

impl<const N: usize> StackText<N> {
    fn new() -> Self {
        StackText {
            buf: [0; N],
            len: 0,
        }
    }

    fn bytes(&self) -> &[u8] {
        &self.buf[..self.len]
    }
}

impl<const N: usize> std::fmt::Write for StackText<N> {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        let n = s.len().min(N - self.len);
        self.buf[self.len..self.len + n].copy_from_slice(&s.as_bytes()[..n]);
        self.len += n;
        Ok(())
    }
}

/// Starts the global worker threads (rayon), each binary first thing: an address space too
/// small for their stacks is reported the same way as a failed allocation (exit 1), not as
/// rayon's panic at the first parallel step.
pub fn start_threads(tool: &str) {
    if rayon::ThreadPoolBuilder::new().build_global().is_err() {
        eprintln!(
            "{tool}: error: out of memory: the worker threads cannot be started (the process may not use enough memory)"
        );
        std::process::exit(1);
    }
}
