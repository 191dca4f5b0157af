//! The system allocator, with large blocks advised onto transparent huge pages (Linux, where THP is in
//! `madvise` mode as on Debian's defaults). A 1e7-sphere field first-touches about 3 GB; in 4 KiB pages that is
//! 1.4 million page faults, at a few µs each under a hypervisor: a third of the build's wall time (PERF.md,
//! session 9). Advice changes only how the kernel backs the pages, never their contents.

use std::alloc::{GlobalAlloc, Layout, System};

/// The size of a transparent huge page on x86-64 and of the alignment the kernel needs to use one.
#[cfg(target_os = "linux")]
const HUGE_PAGE: usize = 2 << 20;

/// Blocks of at least this size are advised: smaller ones hold at most one whole huge page.
#[cfg(target_os = "linux")]
const ADVISED: usize = 2 * HUGE_PAGE;

/// [`System`], advising every block of at least 4 MiB onto huge pages (`madvise(MADV_HUGEPAGE)` on the whole
/// 2 MiB-aligned pages inside it). The advice helps pages not yet touched: a fresh block's, or a grown
/// block's new part; memory that glibc hands out again from its heap keeps the advice after it is freed, so
/// later blocks there may also get huge pages. Installed in the `bareray` binary only (`main.rs`): tests and
/// benchmarks use the plain system allocator.
pub struct HugePages;

// SAFETY: every call is forwarded to `System` with the same arguments; `advise` only gives the kernel advice
// about pages the returned block covers.
unsafe impl GlobalAlloc for HugePages {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract for `alloc`, passed on.
        advise(unsafe { System.alloc(layout) }, layout.size())
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as for `alloc`.
        advise(unsafe { System.alloc_zeroed(layout) }, layout.size())
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System` through this allocator, with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: as for `dealloc`; `new_size` is the caller's.
        advise(unsafe { System.realloc(ptr, layout, new_size) }, new_size)
    }
}

/// Advises the whole huge pages inside the `size` bytes at `block` (nothing for small or null blocks); returns
/// `block`. A kernel without THP refuses the advice, which changes nothing.
#[cfg(target_os = "linux")]
fn advise(block: *mut u8, size: usize) -> *mut u8 {
    if !block.is_null() && size >= ADVISED {
        let at = block as usize;
        let start = at.next_multiple_of(HUGE_PAGE);
        let end = (at + size) / HUGE_PAGE * HUGE_PAGE;
        if end > start {
            // SAFETY: [start, end) lies inside the block just allocated (the pointer keeps the block's
            // provenance); MADV_HUGEPAGE changes no contents.
            unsafe { libc::madvise(block.wrapping_add(start - at).cast(), end - start, libc::MADV_HUGEPAGE) };
        }
    }
    block
}

/// Elsewhere there is no advice to give.
#[cfg(not(target_os = "linux"))]
fn advise(block: *mut u8, _size: usize) -> *mut u8 {
    block
}
