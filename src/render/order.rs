//! The order tiles are traced in: rows of tiles together, column by column, so that a tile's neighbours above
//! and below are traced just before and after it rather than a whole row of tiles away, while the tree nodes
//! and spheres their rays share are still in the core's cache (PERF.md, "Register", tiles column by column).
//! Every tile's pixels are the same bits in any order.

use super::{Tile, TILE};

/// The most rows of tiles traced together: four gave most of what eight did in simulated 512 KB caches
/// (PERF.md, "Register", tiles column by column).
pub(super) const ROWS_TOGETHER: u32 = 4;

/// The rows of tiles to trace together over `height` rows of the image on `threads` threads: at most
/// [`ROWS_TOGETHER`], and fewer where a job per group of rows would leave fewer than four jobs a thread.
pub(super) fn rows_together(height: u32, threads: usize) -> u32 {
    let rows_of_tiles = height.div_ceil(TILE);
    (rows_of_tiles / (4 * threads.max(1) as u32).max(1)).clamp(1, ROWS_TOGETHER)
}

/// Where `tile` (one of [`super::tiles`]) comes in the order: groups of `rows` rows of tiles from the top,
/// each column by column. Sorting a band's tiles by it gives the order they are traced in.
pub(super) fn column_key(tile: &Tile, rows: u32) -> (u32, u32, u32) {
    (tile.y0 / (TILE * rows), tile.x0, tile.y0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::tiles;

    /// Each tile's index in `tiles`, in the order [`column_key`] sorts them.
    fn column_order(tiles: &[Tile], rows: u32) -> Vec<usize> {
        let mut order: Vec<usize> = (0..tiles.len()).collect();
        order.sort_by_key(|&i| column_key(&tiles[i], rows));
        order
    }

    /// Every tile once; groups of `rows` rows of tiles from the top; inside a group, column by column and
    /// top to bottom in each column.
    #[test]
    fn tiles_go_column_by_column_in_groups_of_rows() {
        for (width, height, rows) in [(100, 70, 4), (33, 200, 2), (16, 16, 4), (1920, 1080, 4), (50, 50, 1)] {
            let all = tiles(width, height);
            let order = column_order(&all, rows);
            let mut seen = order.clone();
            seen.sort_unstable();
            assert_eq!(seen, (0..all.len()).collect::<Vec<_>>(), "{width}x{height}");
            for pair in order.windows(2) {
                let (a, b) = (all[pair[0]], all[pair[1]]);
                let group = |t: Tile| t.y0 / (TILE * rows);
                let same = group(a) == group(b);
                assert!(group(a) <= group(b), "{a:?} then {b:?}");
                assert!(!same || (a.x0, a.y0) < (b.x0, b.y0), "{a:?} then {b:?}");
                assert!(!same || a.x0 == b.x0 || b.y0 == group(b) * TILE * rows, "{a:?} then {b:?}");
            }
        }
        // One row of tiles per group is the row-by-row order of `tiles`.
        assert_eq!(column_order(&tiles(100, 70), 1), (0..35).collect::<Vec<_>>());
    }

    /// Four rows of tiles together where each thread still gets four jobs; fewer on tall pools or short
    /// images, never none.
    #[test]
    fn rows_together_leave_each_thread_four_jobs() {
        assert_eq!(rows_together(1080, 2), 4);
        assert_eq!(rows_together(1080, 16), 1);
        assert_eq!(rows_together(256, 2), 2);
        assert_eq!(rows_together(16, 1), 1);
        assert_eq!(rows_together(1, 64), 1);
        for threads in 1..40 {
            let r = rows_together(1080, threads);
            assert!((1..=ROWS_TOGETHER).contains(&r));
            assert!(r == 1 || 1080u32.div_ceil(TILE * r) >= 4 * threads as u32, "{threads} threads: {r}");
        }
    }
}
