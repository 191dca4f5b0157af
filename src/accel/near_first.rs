//! A walk over one kind's items nearest first: the boxes and items a caller's test keeps come out of a
//! priority queue in increasing order of a key the caller gives (a lower bound of the items' distances, say),
//! and the walk ends once the caller's cut-off is reached. The coverage pattern finds the spheres that reach
//! into a pixel this way and stops once nearer ones hide everything behind them.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use crate::bvh::Bvh;

/// What a queue entry stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum What {
    /// An item, by its index in storage order.
    Item(u32),
    /// A leaf: `count` items from `first`.
    Leaf { first: u32, count: u8 },
    /// An inner node, by index.
    Node(u32),
}

#[derive(Clone, Copy, Debug)]
struct Entry {
    key: f64,
    what: What,
}

impl Entry {
    /// Ties in the key go to items before leaves before nodes, then to the lower index: the order is total,
    /// so the walk does not depend on the queue's inner layout.
    fn rank(&self) -> (u8, u32) {
        match self.what {
            What::Item(i) => (0, i),
            What::Leaf { first, .. } => (1, first),
            What::Node(n) => (2, n),
        }
    }
}

impl PartialEq for Entry {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Entry {
    /// Reversed, so that the max-heap pops the smallest key first.
    fn cmp(&self, o: &Self) -> Ordering {
        o.key.total_cmp(&self.key).then_with(|| o.rank().cmp(&self.rank()))
    }
}

/// The queue of a nearest-first walk, kept between walks so that each one does not allocate.
#[derive(Debug, Default)]
pub(crate) struct NearFirst {
    heap: BinaryHeap<Entry>,
}

impl NearFirst {
    /// An empty queue.
    pub(crate) fn new() -> Self {
        Self::default()
    }

    /// Visits the `items` items (storage order) under `bvh`, or all of them without a tree, in increasing
    /// order of `item_key`, skipping those it gives `None` and every subtree whose box `box_key` (lower and
    /// upper corners) gives `None`. A box's key must not exceed the key of any item below it, so that items
    /// come out in order. `visit(item, key)` returns the cut-off: the walk ends before the first entry whose
    /// key reaches it (`f64::INFINITY` to go on).
    pub(crate) fn walk(
        &mut self,
        bvh: Option<&Bvh>,
        items: usize,
        mut box_key: impl FnMut([f32; 3], [f32; 3]) -> Option<f64>,
        mut item_key: impl FnMut(usize) -> Option<f64>,
        mut visit: impl FnMut(usize, f64) -> f64,
    ) {
        let heap = &mut self.heap;
        heap.clear();
        match bvh {
            Some(bvh) if !bvh.nodes.is_empty() => {
                heap.push(Entry { key: f64::NEG_INFINITY, what: What::Node(0) })
            }
            _ => {
                for i in 0..items {
                    if let Some(key) = item_key(i) {
                        heap.push(Entry { key, what: What::Item(i as u32) });
                    }
                }
            }
        }
        let mut cut = f64::INFINITY;
        while let Some(e) = heap.pop() {
            if e.key >= cut {
                break;
            }
            match e.what {
                What::Item(i) => cut = visit(i as usize, e.key),
                What::Leaf { first, count } => {
                    for i in first..first + u32::from(count) {
                        if let Some(key) = item_key(i as usize) {
                            heap.push(Entry { key, what: What::Item(i) });
                        }
                    }
                }
                What::Node(n) => {
                    let node = &bvh.expect("nodes come from a tree").nodes[n as usize];
                    for c in 0..usize::from(node.slots) {
                        let corner = |side: usize| [0, 1, 2].map(|a| node.bounds[side][a][c]);
                        let Some(key) = box_key(corner(0), corner(1)) else { continue };
                        let (child, count) = (node.child[c], node.count[c]);
                        let what =
                            if count > 0 { What::Leaf { first: child, count } } else { What::Node(child) };
                        heap.push(Entry { key, what });
                    }
                }
            }
        }
        heap.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{build, BuildOptions};
    use crate::math::SplitMix64;

    /// Points on a line, keyed by their coordinate: the walk gives them in order, with or without a tree,
    /// and a cut-off ends it.
    #[test]
    fn items_come_nearest_first_and_the_cut_off_ends_the_walk() {
        let mut rng = SplitMix64::new(5);
        let xs: Vec<f32> = (0..500).map(|_| (rng.unit() * 100.0) as f32).collect();
        let options = BuildOptions {
            pad: 0.0,
            builder: crate::bvh::Builder::SAH_SPHERES,
            single_ray_tree: false,
            leaf_links: false,
            scalar_tree: false,
            frustum_culling: true,
            single_ray_lanes: 2,
        };
        let item_box = |i: usize| {
            let p = glam::Vec3A::new(xs[i], 0.0, 0.0);
            obvhs::aabb::Aabb { min: p, max: p }
        };
        let (tree, order, _) = build(xs.len(), item_box, options, |o: &[u32]| o.to_vec());
        let stored: Vec<f32> = order.iter().map(|&i| xs[i as usize]).collect();
        let mut sorted = xs.clone();
        sorted.sort_by(f32::total_cmp);
        let mut q = NearFirst::new();
        for bvh in [Some(&tree), None] {
            let keep = |x: f32| (20.0..=80.0).contains(&x);
            let mut seen = Vec::new();
            q.walk(
                bvh,
                stored.len(),
                |lo, hi| (hi[0] >= 20.0 && lo[0] <= 80.0).then_some(f64::from(lo[0])),
                |i| keep(stored[i]).then_some(f64::from(stored[i])),
                |i, key| {
                    assert_eq!(key, f64::from(stored[i]));
                    seen.push(stored[i]);
                    f64::INFINITY
                },
            );
            let want: Vec<f32> = sorted.iter().copied().filter(|&x| keep(x)).collect();
            assert_eq!(seen, want);
            let mut first = Vec::new();
            q.walk(
                bvh,
                stored.len(),
                |lo, _| Some(f64::from(lo[0])),
                |i| Some(f64::from(stored[i])),
                |i, _| {
                    first.push(stored[i]);
                    if first.len() == 10 {
                        f64::from(stored[i])
                    } else {
                        f64::INFINITY
                    }
                },
            );
            assert_eq!(first, sorted[..10]);
        }
    }
}
