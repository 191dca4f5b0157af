//! One tile's camera hits gathered in a small buffer, then written to the frame row by row: a tile row that
//! fills a whole cache line of the frame goes there by non-temporal stores. Written packet by packet, each
//! line of the frame was first read for ownership and then written back, twice the frame's size in memory
//! traffic for lines that are only ever overwritten; a whole line written by non-temporal stores is not read.
//! The bits written are the same either way.

use super::{Block, TILE};

/// Pixels of a tile.
const AREA: usize = (TILE * TILE) as usize;

/// A tile's hit distances and primitive ids, row by row with rows [`TILE`] apart.
pub(super) struct TileRows {
    t: [f32; AREA],
    prim: [u32; AREA],
}

impl Default for TileRows {
    fn default() -> Self {
        Self { t: [0.0; AREA], prim: [0; AREA] }
    }
}

impl TileRows {
    /// Stores block `b`'s hits: lane `r · b.bw + c` is the pixel `(b.x + c, b.y + r)` of the tile.
    #[inline(always)]
    pub(super) fn put(&mut self, b: &Block, ts: &[f32], ids: &[u32]) {
        for r in 0..b.h as usize {
            let lane = r * b.bw as usize;
            let at = (b.y as usize + r) * TILE as usize + b.x as usize;
            let n = b.w as usize;
            copy_row(&mut self.t[at..at + n], &ts[lane..]);
            copy_row(&mut self.prim[at..at + n], &ids[lane..]);
        }
    }

    /// Writes the tile's `w × h` pixels to the frame, its row `r` to `t[r · stride..]` and `prim[r ·
    /// stride..]` (`stride` the frame's width).
    pub(super) fn write(&self, (w, h): (usize, usize), stride: usize, t: &mut [f32], prim: &mut [u32]) {
        for r in 0..h {
            let (from, to) = (r * TILE as usize, r * stride);
            write_row(&mut t[to..to + w], &self.t[from..from + w]);
            write_row(&mut prim[to..to + w], &self.prim[from..from + w]);
        }
    }
}

/// Copies the first `dst.len()` values of `src` into `dst`: a whole 4-pixel row as one fixed-size copy (a
/// `memmove` call per short row showed in a small field's profile: docs/perf-log/2026-11.md,
/// "Where the time went (before)"), a partial one as a slice.
#[inline(always)]
fn copy_row<T: Copy>(dst: &mut [T], src: &[T]) {
    match (<&mut [T; 4]>::try_from(&mut *dst), src.first_chunk::<4>()) {
        (Ok(whole), Some(row)) => *whole = *row,
        _ => dst.copy_from_slice(&src[..dst.len()]),
    }
}

/// Copies `src` into `dst`: by non-temporal stores where `dst` is one whole 64-byte line, else plainly.
#[inline(always)]
fn write_row<T: Copy>(dst: &mut [T], src: &[T]) {
    const LINE: usize = 64;
    let whole = size_of_val(dst) == LINE && (dst.as_ptr() as usize).is_multiple_of(LINE);
    if whole && cfg!(target_arch = "x86_64") {
        stream_line(dst, src);
    } else {
        dst.copy_from_slice(src);
    }
}

/// `dst` (one 64-byte line, aligned) from `src` by non-temporal stores.
#[inline(always)]
fn stream_line<T: Copy>(dst: &mut [T], src: &[T]) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{__m128i, _mm_loadu_si128, _mm_stream_si128};
        assert!(
            dst.len() == src.len() && size_of_val(dst) == 64 && (dst.as_ptr() as usize).is_multiple_of(64)
        );
        let (d, s) = (dst.as_mut_ptr().cast::<__m128i>(), src.as_ptr().cast::<__m128i>());
        for k in 0..4 {
            // SAFETY: both slices hold 64 bytes and `dst` is 64-byte aligned (checked above), so each
            // 16-byte store is aligned; SSE2 is part of x86-64.
            unsafe { _mm_stream_si128(d.add(k), _mm_loadu_si128(s.add(k))) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    dst.copy_from_slice(src);
}

/// Orders the non-temporal stores made so far before any later store (one that tells another thread the
/// frame is written): they are not ordered by the usual release of a lock or an atomic.
pub(super) fn fence() {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE is part of x86-64.
    unsafe {
        std::arch::x86_64::_mm_sfence()
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Blocks of 4×4 (the last ones cut at the tile's edge) put into the buffer and written to frames at
    /// every offset from a 64-byte line (whole lines streamed, the rest copied) give each pixel its value.
    #[test]
    fn every_pixel_lands_in_its_place_at_any_alignment() {
        let stride = 37;
        for (w, h) in [(16, 16), (16, 5), (7, 16), (3, 2)] {
            let mut rows = TileRows::default();
            for by in (0..h).step_by(4) {
                for bx in (0..w).step_by(4) {
                    let b = Block { x: bx, y: by, w: 4.min(w - bx), h: 4.min(h - by), bw: 4 };
                    let ids: Vec<u32> = (0..16).map(|l| (by + l / 4) * 100 + bx + l % 4).collect();
                    let ts: Vec<f32> = ids.iter().map(|&i| i as f32 + 0.5).collect();
                    rows.put(&b, &ts, &ids);
                }
            }
            // 64-byte aligned storage, written from each of the first 16 offsets.
            #[repr(align(64))]
            struct Lines<T>([T; 16 * 64]);
            for offset in 0..16 {
                let (mut t, mut prim) = (Box::new(Lines([-1.0f32; 1024])), Box::new(Lines([u32::MAX; 1024])));
                let (t, prim) = (&mut t.0[offset..], &mut prim.0[offset..]);
                rows.write((w as usize, h as usize), stride, t, prim);
                fence();
                for y in 0..h as usize {
                    for x in 0..w as usize {
                        let want = (y * 100 + x) as u32;
                        assert_eq!(prim[y * stride + x], want, "{w}x{h} at {offset}: ({x}, {y})");
                        assert_eq!(t[y * stride + x], want as f32 + 0.5);
                    }
                    assert_eq!(prim[y * stride + w as usize], u32::MAX, "past the row");
                }
            }
        }
    }
}
