//! The order tiles are traced in. Where the core's L2 is small, rows of tiles go together, column by column,
//! so that a tile's neighbours above and below are traced just before and after it rather than a whole row of
//! tiles away, while the tree nodes and spheres their rays share are still in the cache; where it is large,
//! row by row ([`tile_group`]; PERF.md, "Register", tiles column by column). Every tile's pixels are the same
//! bits in any order.

use super::{Tile, TILE};

/// The most rows of tiles traced together: four gave most of what eight did in simulated 512 KB caches
/// (PERF.md, "Register", tiles column by column).
pub(super) const ROWS_TOGETHER: u32 = 4;

/// An L2 cache per core this large or larger keeps what a row of tiles shares with the next: rows of tiles
/// are then traced one by one, left to right. The column order paid where the L2 was 512 KB (Zen 3); with
/// 1 MB (Zen 5) and 2 MB (Intel) it cost camera rays time, since each tile's writes to the frame then start
/// lines the prefetcher has not seen coming (PERF.md, "Register", tiles column by column). Sizes between
/// 512 KB and 1 MB were not measured and keep the column order.
const LARGE_L2: u64 = 1 << 20;

/// The rows of tiles traced together on this machine: [`ROWS_TOGETHER`], or 1 where the first core's L2
/// holds at least [`LARGE_L2`] (Linux's sysfs tells; where it does not, [`ROWS_TOGETHER`]). Where an L2 is
/// shared by a cluster of cores, its whole size is taken.
pub(super) fn tile_group() -> u32 {
    static GROUP: std::sync::OnceLock<u32> = std::sync::OnceLock::new();
    *GROUP.get_or_init(|| group_for(l2_bytes()))
}

/// [`tile_group`] for an L2 of `l2` bytes per core (`None`: unknown).
fn group_for(l2: Option<u64>) -> u32 {
    match l2 {
        Some(bytes) if bytes >= LARGE_L2 => 1,
        _ => ROWS_TOGETHER,
    }
}

/// The size of the first core's level-2 data or unified cache, from `/sys/devices/system/cpu/cpu0/cache`.
fn l2_bytes() -> Option<u64> {
    let dir = std::fs::read_dir("/sys/devices/system/cpu/cpu0/cache").ok()?;
    dir.flatten().find_map(|entry| {
        let read = |name: &str| std::fs::read_to_string(entry.path().join(name)).ok();
        let level = read("level")?;
        let kind = read("type")?;
        (level.trim() == "2" && kind.trim() != "Instruction").then(|| cache_size(&read("size")?))?
    })
}

/// A sysfs cache size (`2048K`, `1M`, `524288`) in bytes.
fn cache_size(text: &str) -> Option<u64> {
    let text = text.trim();
    let (digits, unit) = match text.char_indices().find(|(_, c)| !c.is_ascii_digit()) {
        Some((i, _)) => text.split_at(i),
        None => (text, ""),
    };
    let scale = match unit {
        "" => 1,
        "K" => 1 << 10,
        "M" => 1 << 20,
        "G" => 1 << 30,
        _ => return None,
    };
    digits.parse::<u64>().ok()?.checked_mul(scale)
}

/// The rows of tiles to trace together over `height` rows of the image on `threads` threads: at most
/// [`tile_group`], and fewer where a job per group of rows would leave fewer than four jobs a thread.
pub(super) fn rows_together(height: u32, threads: usize) -> u32 {
    rows_for(height, threads, tile_group())
}

/// [`rows_together`] with at most `group` rows.
pub(super) fn rows_for(height: u32, threads: usize, group: u32) -> u32 {
    let rows_of_tiles = height.div_ceil(TILE);
    (rows_of_tiles / (4 * threads.max(1) as u32).max(1)).clamp(1, group.max(1))
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
        let rows = |height, threads| rows_for(height, threads, ROWS_TOGETHER);
        assert_eq!(rows(1080, 2), 4);
        assert_eq!(rows(1080, 16), 1);
        assert_eq!(rows(256, 2), 2);
        assert_eq!(rows(16, 1), 1);
        assert_eq!(rows(1, 64), 1);
        for threads in 1..40 {
            let r = rows(1080, threads);
            assert!((1..=ROWS_TOGETHER).contains(&r));
            assert!(r == 1 || 1080u32.div_ceil(TILE * r) >= 4 * threads as u32, "{threads} threads: {r}");
            assert_eq!(rows_for(1080, threads, 1), 1);
        }
        assert!([1, ROWS_TOGETHER].contains(&rows_together(1080, 2)));
    }

    /// Rows of tiles go one by one where the L2 is 1 MiB or more, and sysfs sizes read as bytes.
    #[test]
    fn the_group_follows_the_l2() {
        assert_eq!(group_for(Some(512 << 10)), ROWS_TOGETHER);
        assert_eq!(group_for(None), ROWS_TOGETHER);
        assert_eq!(
            [768 << 10, 1 << 20, 2 << 20, 32 << 20].map(|b| group_for(Some(b))),
            [ROWS_TOGETHER, 1, 1, 1]
        );
        assert_eq!(cache_size("2048K\n"), Some(2 << 20));
        assert_eq!(cache_size("1M"), Some(1 << 20));
        assert_eq!(cache_size("524288"), Some(512 << 10));
        assert_eq!([cache_size("2 KB"), cache_size(""), cache_size("K")], [None, None, None]);
        assert_eq!(cache_size("99999999999999999999G"), None);
        assert_eq!(cache_size("9999999999999G"), None);
    }
}
