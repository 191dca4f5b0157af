//! Morton order over binned SAH: the items sorted once by the Morton code of their box centres on a 1024³ grid
//! over the centres' box (Lauterbach et al., "Fast BVH Construction on GPUs", 2009), each range of more than
//! [`SAH_BELOW`] items split where its codes' highest differing bit changes (a spatial midpoint found by binary
//! search: nothing is binned or moved), a range whose items share one code halved at its median, and the
//! ranges of at most [`SAH_BELOW`] items split by the binned SAH (`sah.rs`) down to the leaves.
//!
//! The top levels are where the SAH builder spends most of its time (every level bins and moves every item)
//! and where a spatial midpoint splits about as well; near the leaves the SAH's choices matter: by Morton order
//! down to the leaves balls6 traced 1.13x slower, with the SAH below 512 to 4096 items within 4% of the SAH's
//! tree (PERF.md, "Tree builder"). It shares the SAH builder's references, driver and layout
//! ([`super::sah::build_with`]), so the tree does not depend on the thread count either.

use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::bvh2::node::Bvh2Node;
use rayon::prelude::*;

use super::sah::{self, build_with, median, references, Extent, Ref, MAX_LEAF};

/// Ranges of at most this many items are split by the SAH.
pub(super) const SAH_BELOW: usize = 1024;

/// Grid cells along each axis: 10 bits a coordinate, 30 bits a code.
const CELLS: f32 = 1024.0;

/// The binary tree over the boxes `item_box` gives for items `0..n`, by Morton order above [`SAH_BELOW`]
/// items and by the SAH below (a binary node costing `node_cost` item tests), in obvhs's layout (as
/// [`super::sah::build_sah`] returns it). `n` ≥ 1.
pub(super) fn build_morton(
    n: usize,
    item_box: impl Fn(usize) -> Aabb + Sync,
    node_cost: f32,
) -> (Vec<Bvh2Node>, Vec<u32>) {
    let (refs, extent) = sorted_references(n, item_box);
    build_with(refs, extent, &|refs: &mut [Ref], extent: &Extent, depth: u32| match refs.len() {
        n if n <= SAH_BELOW => sah::split(refs, extent, depth, node_cost),
        _ => split(refs, extent),
    })
}

/// One reference per item, each holding its Morton code, sorted by code and item; and their extent.
fn sorted_references(n: usize, item_box: impl Fn(usize) -> Aabb + Sync) -> (Vec<Ref>, Extent) {
    let (mut refs, extent) = references(n, item_box);
    let grid = Grid::new(&extent.centres);
    // The code goes in the reference's spare `hi.w` lane; the sort by code and item is a total order, so
    // the order (and the tree) is the same on any number of threads.
    refs.par_iter_mut().for_each(|r| r.hi.w = f32::from_bits(grid.code(r.centre2())));
    refs.par_sort_unstable_by_key(|r| (u64::from(code(r)) << 32) | u64::from(r.item()));
    (refs, extent)
}

/// The Morton code stored in a reference.
fn code(r: &Ref) -> u32 {
    r.hi.w.to_bits()
}

/// The grid over a box of (doubled) centres.
struct Grid {
    min: Vec3A,
    scale: Vec3A,
}

impl Grid {
    fn new(centres: &Aabb) -> Self {
        Grid { min: centres.min, scale: sah::cells_per_unit(centres, CELLS) }
    }

    /// The Morton code of the cell holding `centre2`: x, y and z bits interleaved, x highest. A NaN centre
    /// (a box infinite both ways on an axis) gets cell 0 on that axis: any cell will do, as long as it is one.
    fn code(&self, centre2: Vec3A) -> u32 {
        let at = ((centre2 - self.min) * self.scale).to_array();
        let cell = at.map(|x| (x as u32).min(CELLS as u32 - 1));
        (spread_bits(cell[0]) << 2) | (spread_bits(cell[1]) << 1) | spread_bits(cell[2])
    }
}

/// The low 10 bits of `x` moved to every third bit (bit i to bit 3i).
fn spread_bits(x: u32) -> u32 {
    let mut x = x & 0x3ff;
    x = (x | (x << 16)) & 0x0300_00ff;
    x = (x | (x << 8)) & 0x0300_f00f;
    x = (x | (x << 4)) & 0x030c_30c3;
    (x | (x << 2)) & 0x0924_9249
}

/// Splits a range of references sorted by code (see [`super::sah::SplitRange`]): a leaf at up to
/// [`MAX_LEAF`] items; else where the highest bit in which its first and last codes differ turns to 1, or
/// at its median when all its codes are equal. At most 30 bit levels, then medians.
fn split(refs: &mut [Ref], extent: &Extent) -> Option<(usize, Extent, Extent)> {
    let n = refs.len();
    if n <= MAX_LEAF {
        return None;
    }
    let (first, last) = (code(&refs[0]), code(&refs[n - 1]));
    if first == last {
        return Some(median(refs, extent));
    }
    let bit = 31 - (first ^ last).leading_zeros();
    // The codes share every bit above `bit`, so those with it clear come first.
    let mid = refs.partition_point(|r| code(r) >> bit & 1 == 0);
    let (left, right) = refs.split_at(mid);
    Some((mid, Extent::of(left), Extent::of(right)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::sah::tests::{box_sets, check_tree, fields, overflowed_boxes};

    #[test]
    fn spread_bits_interleaves() {
        assert_eq!(spread_bits(0b1), 0b1);
        assert_eq!(spread_bits(0b11), 0b1001);
        assert_eq!(spread_bits(0x3ff), 0x0924_9249);
        let grid = Grid::new(&Aabb { min: Vec3A::ZERO, max: Vec3A::splat(1.0) });
        assert_eq!(grid.code(Vec3A::ZERO), 0);
        assert_eq!(grid.code(Vec3A::splat(1.0)), (1 << 30) - 1, "the far corner is in the last cell");
        // Cell 512 along x (0.5006 × 1024 × 0.9999 = 512.6): x's top bit, the code's highest.
        assert_eq!(grid.code(Vec3A::new(0.5006, 0.0, 0.0)), 1 << 29, "x is the highest bit");
        assert_eq!(grid.code(Vec3A::new(0.0, 0.0, 0.5006)), 1 << 27, "z is the lowest of the three");
    }

    /// Over every box set, with the SAH below SAH_BELOW items and by Morton order down to the leaves.
    #[test]
    fn every_item_is_in_one_leaf_under_boxes_that_enclose_it() {
        for (name, boxes) in box_sets() {
            let log = boxes.len().ilog2() as usize;
            let (nodes, order) = build_morton(boxes.len(), |i| boxes[i], 6.0);
            // Bit levels and medians of ranges sharing a code, then the SAH's levels to its depth cap and
            // medians past it.
            check_tree(name, &nodes, &order, &boxes, sah::MAX_SAH_DEPTH as usize + 2 * log + 2);
            let (refs, extent) = sorted_references(boxes.len(), |i| boxes[i]);
            let (nodes, order) =
                build_with(refs, extent, &|refs: &mut [Ref], extent: &Extent, _| split(refs, extent));
            check_tree(name, &nodes, &order, &boxes, 30 + log + 2);
        }
    }

    /// Boxes infinite both ways (centres NaN, so one cell) still build, each item in one leaf: 3000 of them, so
    /// that Morton order splits the top.
    #[test]
    fn boxes_with_overflowed_corners_build() {
        let boxes = overflowed_boxes(3000);
        let (nodes, order) = build_morton(boxes.len(), |i| boxes[i], 6.0);
        check_tree("overflowed", &nodes, &order, &boxes, sah::MAX_SAH_DEPTH as usize + 2 * 12 + 2);
    }

    #[test]
    fn the_tree_does_not_depend_on_the_threads() {
        // 20 000 boxes: Morton order splits the top, the SAH the rest.
        let (_, boxes) = box_sets().into_iter().find(|(name, _)| *name == "uniform").unwrap();
        let on = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            fields(pool.install(|| build_morton(boxes.len(), |i| boxes[i], 6.0)))
        };
        assert!(on(1) == on(4), "the tree differs between 1 and 4 threads");
    }
}
