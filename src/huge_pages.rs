//! The system allocator, with large blocks mapped straight onto transparent huge pages (Linux, where THP is
//! in `madvise` mode as on Debian's defaults). A large field first-touches gigabytes; in 4 KiB pages that is
//! one fault per page, and under a hypervisor those faults were a large share of the build's wall time
//! (PERF.md, Register: "The binary's allocator"). Huge pages change only how the kernel backs memory, never
//! its contents.
//!
//! The exception is a guest whose virtio balloon reports free pages: it hands free 2 MiB blocks back to the
//! host, and huge pages come from exactly those, so each huge-page fault is paid on the host too. There the
//! advice is left out ([`choose`]) and the blocks get 4 KiB pages (PERF.md, Register: "The binary's
//! allocator").

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, Ordering};

/// Whether mapped blocks are advised onto huge pages; [`choose`] decides once, before any large block.
static ADVISE: AtomicBool = AtomicBool::new(true);

/// Leaves huge pages out where a virtio balloon reports free pages to the host (Linux's sysfs lists each
/// virtio device's id and feature bits). Called once at start-up, before any large allocation.
pub(crate) fn choose() {
    #[cfg(target_os = "linux")]
    if let Ok(devices) = std::fs::read_dir("/sys/bus/virtio/devices") {
        let read =
            |dir: &std::path::Path, name: &str| std::fs::read_to_string(dir.join(name)).unwrap_or_default();
        let reporting = devices
            .flatten()
            .any(|d| reports_free_pages(&read(&d.path(), "device"), &read(&d.path(), "features")));
        ADVISE.store(!reporting, Ordering::Relaxed);
    }
}

/// Whether a virtio device with sysfs `device` id and `features` bit string (bit 0 first) is a balloon
/// (id 5) with free page reporting (feature bit 5, `VIRTIO_BALLOON_F_REPORTING`).
#[cfg_attr(not(target_os = "linux"), allow(dead_code))]
fn reports_free_pages(device: &str, features: &str) -> bool {
    device.trim() == "0x0005" && features.as_bytes().get(5) == Some(&b'1')
}

/// [`System`] for small blocks; blocks of 2 MiB or more get a mapping of their own, aligned to a huge page,
/// rounded up to whole huge pages and advised onto them (`madvise(MADV_HUGEPAGE)`), so that every page of
/// the block comes from a huge-page fault, unless [`choose`] left the advice out. Blocks from `System` kept
/// 4 KiB faults on their unaligned ends, and those below its mmap threshold came from the heap in 4 KiB
/// pages, a render's sRGB buffer among them (docs/perf-log/2026-11.md, "Kept": huge pages without partial
/// ends). Fresh mappings are zero, so zeroed blocks cost no writes on the allocating thread. Installed in
/// the `bareray` binary only (`main.rs`): tests and benchmarks use the plain system allocator.
pub(crate) struct HugePages;

// SAFETY: small blocks are forwarded to `System` with the same arguments; large ones are whole private
// anonymous mappings of at least the requested size at the requested alignment (a huge page is stricter
// than any alignment `is_mapped` admits), unmapped or remapped only through the same size rule.
unsafe impl GlobalAlloc for HugePages {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        match is_mapped(layout) {
            true => map(layout.size()),
            // SAFETY: the caller's contract for `alloc`, passed on.
            false => unsafe { System.alloc(layout) },
        }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        match is_mapped(layout) {
            true => map(layout.size()),
            // SAFETY: as for `alloc`.
            false => unsafe { System.alloc_zeroed(layout) },
        }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        match is_mapped(layout) {
            true => unmap(ptr, layout.size()),
            // SAFETY: `ptr` came from `System` through this allocator, with this layout.
            false => unsafe { System.dealloc(ptr, layout) },
        }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: `new_size` with the block's alignment is a valid layout (the caller's contract).
        let new = unsafe { Layout::from_size_align_unchecked(new_size, layout.align()) };
        match (is_mapped(layout), is_mapped(new)) {
            // SAFETY: as for `dealloc`; `new_size` is the caller's.
            (false, false) => unsafe { System.realloc(ptr, layout, new_size) },
            (true, true) => remap(ptr, layout.size(), new_size),
            _ => {
                // SAFETY: `new` is valid and non-zero in size (the caller's contract).
                let moved = unsafe { self.alloc(new) };
                if !moved.is_null() {
                    // SAFETY: both blocks are live, distinct and at least as long as the bytes copied.
                    unsafe { std::ptr::copy_nonoverlapping(ptr, moved, layout.size().min(new_size)) };
                    // SAFETY: `ptr` came from this allocator with `layout`.
                    unsafe { self.dealloc(ptr, layout) };
                }
                moved
            }
        }
    }
}

/// The size of a transparent huge page on x86-64 and the alignment the kernel needs to use one.
#[cfg(target_os = "linux")]
const HUGE_PAGE: usize = 2 << 20;

/// Whether a block with `layout` gets a mapping of its own.
#[cfg(target_os = "linux")]
fn is_mapped(layout: Layout) -> bool {
    layout.size() >= HUGE_PAGE && layout.align() <= HUGE_PAGE
}

/// Elsewhere every block comes from `System`.
#[cfg(not(target_os = "linux"))]
fn is_mapped(_: Layout) -> bool {
    false
}

/// The length mapped for a block of `size` bytes: whole huge pages.
#[cfg(target_os = "linux")]
fn mapped_len(size: usize) -> usize {
    size.next_multiple_of(HUGE_PAGE)
}

/// A fresh zeroed mapping for `size` bytes, aligned to a huge page and advised onto huge pages; null if
/// the kernel refuses. A kernel without THP refuses only the advice, which changes nothing.
#[cfg(target_os = "linux")]
fn map(size: usize) -> *mut u8 {
    let len = mapped_len(size);
    let prot = libc::PROT_READ | libc::PROT_WRITE;
    let flags = libc::MAP_PRIVATE | libc::MAP_ANONYMOUS;
    // One huge page more than needed, so an aligned run of `len` bytes lies inside; the ends are returned.
    // SAFETY: a new anonymous mapping touches no existing memory.
    let raw = unsafe { libc::mmap(std::ptr::null_mut(), len + HUGE_PAGE, prot, flags, -1, 0) };
    if raw == libc::MAP_FAILED {
        return std::ptr::null_mut();
    }
    let (at, start) = (raw as usize, (raw as usize).next_multiple_of(HUGE_PAGE));
    // SAFETY: both ranges lie inside the mapping just made and outside the `len` bytes kept; `start` keeps
    // the mapping's provenance; MADV_HUGEPAGE changes no contents.
    unsafe {
        let block = raw.cast::<u8>().wrapping_add(start - at);
        if start > at {
            libc::munmap(raw, start - at);
        }
        if at + HUGE_PAGE > start {
            libc::munmap(block.wrapping_add(len).cast(), at + HUGE_PAGE - start);
        }
        if ADVISE.load(Ordering::Relaxed) {
            libc::madvise(block.cast(), len, libc::MADV_HUGEPAGE);
        }
        block
    }
}

/// Unmaps a block [`map`]ped (or [`remap`]ped) for `size` bytes.
#[cfg(target_os = "linux")]
fn unmap(block: *mut u8, size: usize) {
    // SAFETY: the block is a whole mapping of `mapped_len(size)` bytes that nothing refers to any more.
    unsafe { libc::munmap(block.cast(), mapped_len(size)) };
}

/// Grows or shrinks a mapped block from `old` to `new` bytes, moving it if need be (without copying: the
/// kernel moves the pages); null if the kernel refuses, the block then left as it was. A moved block may lose
/// its huge-page alignment; its aligned huge pages are advised again.
#[cfg(target_os = "linux")]
fn remap(block: *mut u8, old: usize, new: usize) -> *mut u8 {
    let (old_len, new_len) = (mapped_len(old), mapped_len(new));
    if old_len == new_len {
        return block;
    }
    // SAFETY: the block is a whole mapping of `old_len` bytes; MREMAP_MAYMOVE keeps its contents.
    let moved = unsafe { libc::mremap(block.cast(), old_len, new_len, libc::MREMAP_MAYMOVE) };
    if moved == libc::MAP_FAILED {
        return std::ptr::null_mut();
    }
    if ADVISE.load(Ordering::Relaxed) {
        // SAFETY: the advice covers the new mapping only and changes no contents.
        unsafe { libc::madvise(moved, new_len, libc::MADV_HUGEPAGE) };
    }
    moved.cast()
}

#[cfg(not(target_os = "linux"))]
fn map(_: usize) -> *mut u8 {
    unreachable!("no block is mapped off Linux")
}

#[cfg(not(target_os = "linux"))]
fn unmap(_: *mut u8, _: usize) {
    unreachable!("no block is mapped off Linux")
}

#[cfg(not(target_os = "linux"))]
fn remap(_: *mut u8, _: usize, _: usize) -> *mut u8 {
    unreachable!("no block is mapped off Linux")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fills `n` bytes at `p` with a pattern of `seed`.
    fn fill(p: *mut u8, n: usize, seed: u8) {
        // SAFETY: the callers pass live blocks of at least `n` bytes.
        let bytes = unsafe { std::slice::from_raw_parts_mut(p, n) };
        bytes.iter_mut().enumerate().for_each(|(i, b)| *b = (i % 251) as u8 ^ seed);
    }

    /// Whether the first `n` bytes at `p` hold the pattern of `seed`.
    fn holds(p: *const u8, n: usize, seed: u8) -> bool {
        // SAFETY: as for `fill`.
        let bytes = unsafe { std::slice::from_raw_parts(p, n) };
        bytes.iter().enumerate().all(|(i, &b)| b == (i % 251) as u8 ^ seed)
    }

    #[test]
    fn only_a_balloon_with_free_page_reporting_counts() {
        // This host's balloon: bits 1, 2, 5 and 7.
        let balloon = "0110010100000000000000000000000010000000";
        assert!(reports_free_pages("0x0005\n", balloon));
        assert!(!reports_free_pages("0x0005\n", "0110000100000000"), "a balloon without bit 5");
        assert!(!reports_free_pages("0x0002\n", balloon), "a block device with the same bits");
        assert!(!reports_free_pages("0x0005", "01100"), "too few bits");
        assert!(!reports_free_pages("", ""));
    }

    #[test]
    fn blocks_keep_their_contents_across_sizes_and_zeroed_ones_start_zero() {
        const MB: usize = 1 << 20;
        let a = HugePages;
        // Small to large to larger to small: System → mapping → remapped mapping → System.
        let sizes = [MB / 2, 3 * MB, 9 * MB + 123, 4 * MB, 1000];
        let mut layout = Layout::from_size_align(sizes[0], 64).unwrap();
        // SAFETY: every call passes the block with the layout it was (re)allocated with.
        unsafe {
            let mut p = a.alloc(layout);
            fill(p, layout.size(), 7);
            for &size in &sizes[1..] {
                p = a.realloc(p, layout, size);
                assert!(!p.is_null() && (p as usize).is_multiple_of(64));
                assert!(holds(p, layout.size().min(size), 7), "{} → {size} bytes", layout.size());
                layout = Layout::from_size_align(size, 64).unwrap();
                fill(p, size, 7);
            }
            a.dealloc(p, layout);
            let big = Layout::from_size_align(5 * MB, 4096).unwrap();
            let z = a.alloc_zeroed(big);
            assert!(is_mapped(big) == cfg!(target_os = "linux"));
            assert!(std::slice::from_raw_parts(z, big.size()).iter().all(|&b| b == 0));
            a.dealloc(z, big);
        }
    }
}
