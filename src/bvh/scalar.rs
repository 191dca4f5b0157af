//! The scalar walk (`--lanes scalar`): one ray against one box at a time, one primitive at a time, over the
//! binary tree the builder made before the collapse into wide nodes. No lane type wider than one `f32` takes
//! part: the slab test and the leaf tests are the generic kernels instantiated at `f32`.
//!
//! **Same bits as every other path.** The binary tree's boxes are the ones the collapse copies into the wide
//! nodes (each the union of its items' padded boxes, [`super::padding`]), its leaves index the items in the
//! same leaf order, and each box is tested by the same slab formula ([`slab_entry_ordered`] at `f32`, fused
//! and widened by `WIDEN`), so culling is exactly as conservative as in the wide walks. Leaves are tested by
//! the kind's [`LeafQuery`] at `f32` (the scalar loop over the items, merged by the (t, id) order), so the
//! result is brute force's, bit for bit, whatever order the boxes are visited in.
//!
//! **Layout.** Each [`PairNode`] holds the boxes of both children of a binary node (one 64-byte cache line):
//! a visit tests both boxes, goes on into the nearer child by entry distance and pushes the other with its
//! entry distance. Closest hits skip a pending child whose entry lies beyond the best hit so far and test
//! later boxes only up to it; occlusion stops at the first blocker.

use obvhs::bvh2::node::Bvh2Node;

use super::slab::{near_side, slab_entry_ordered, SlabRay, Stack};
use super::work::{count_work, Work};
use super::{Bvh, LeafQuery};
use crate::geometry::{HitPacket, Ray};
use crate::simd::{set_bits, IdLanes, Lanes};

/// One child of a [`PairNode`]: its box and what it holds.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub(crate) struct PairChild {
    /// The box's lower corner (x, y, z).
    pub(crate) lo: [f32; 3],
    /// The box's upper corner.
    pub(crate) hi: [f32; 3],
    /// An inner child: the index of its node; a leaf: its first item in leaf order.
    pub(crate) first: u32,
    /// A leaf's item count; 0 for an inner child.
    pub(crate) count: u32,
}

/// A child slot no ray enters: a box at +inf, whose slab distances are never a finite entry (the wide nodes'
/// empty slots are the same box). Only a root that is a single leaf has one.
const EMPTY: PairChild = PairChild { lo: [f32::INFINITY; 3], hi: [f32::INFINITY; 3], first: 0, count: 0 };

/// One node of the scalar walk's binary tree: the boxes of its two children, read in one cache line.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct PairNode {
    /// The two children.
    pub(crate) children: [PairChild; 2],
}

const _: () = assert!(size_of::<PairNode>() == 64, "a pair node is one cache line");

/// The scalar walk's tree from a binary tree in obvhs's layout (inner node `i`'s children at
/// `first_index` and `first_index + 1`; a leaf's items at `first_index..first_index + prim_count` of the
/// leaf order), with the most stack entries a walk of it holds: its depth in inner nodes. The root is
/// `nodes[0]`; a binary tree that is one leaf becomes a root with that leaf and an empty slot. Siblings'
/// nodes are allocated together, subtrees depth first. Built without recursion (a fallback tree may be deep).
pub(super) fn pair_tree(src: &[Bvh2Node]) -> (Vec<PairNode>, usize) {
    let child = |n: &Bvh2Node, first: u32| PairChild {
        lo: n.aabb.min.to_array(),
        hi: n.aabb.max.to_array(),
        first,
        count: n.prim_count,
    };
    if src[0].prim_count > 0 {
        return (vec![PairNode { children: [child(&src[0], src[0].first_index), EMPTY] }], 1);
    }
    let mut nodes = vec![PairNode { children: [EMPTY; 2] }];
    // (obvhs node, its pair node, its depth)
    let (mut pending, mut need) = (vec![(0usize, 0usize, 1usize)], 0);
    while let Some((i, at, depth)) = pending.pop() {
        need = need.max(depth);
        let first = src[i].first_index as usize;
        let mut children = [EMPTY; 2];
        for (k, slot) in children.iter_mut().enumerate() {
            let c = &src[first + k];
            *slot = if c.prim_count > 0 {
                child(c, c.first_index)
            } else {
                nodes.push(PairNode { children: [EMPTY; 2] });
                pending.push((first + k, nodes.len() - 1, depth + 1));
                child(c, (nodes.len() - 1) as u32)
            };
        }
        nodes[at] = PairNode { children };
    }
    (nodes, need)
}

/// One ray prepared for the scalar slab test: `1/d`, `−o·(1/d)` and, per axis, which side's plane it meets
/// first.
struct ScalarRay {
    slab: SlabRay<f32>,
    near: [usize; 3],
}

impl ScalarRay {
    fn new(ray: &Ray<f32>) -> Self {
        let slab = SlabRay::new(ray);
        let inv = [slab.inv_dir.x, slab.inv_dir.y, slab.inv_dir.z];
        Self { slab, near: inv.map(near_side) }
    }

    /// The entry distance into `c`'s box, `inf` where the ray misses it or enters beyond `limit`.
    #[inline(always)]
    fn enter(&self, c: &PairChild, limit: f32) -> f32 {
        let corners = [c.lo, c.hi];
        let near = [0, 1, 2].map(|a| corners[self.near[a]][a]);
        let far = [0, 1, 2].map(|a| corners[1 - self.near[a]][a]);
        slab_entry_ordered::<f32>(near, far, &self.slab, limit)
    }
}

/// A child still to be walked, with the ray's entry distance into its box.
#[derive(Clone, Copy)]
struct Entry {
    first: u32,
    count: u32,
    near: f32,
}

/// The entered children of `n`, nearer first (`None` for a child not entered).
#[inline(always)]
fn children_by_distance(n: &PairNode, ray: &ScalarRay, limit: f32) -> [Option<Entry>; 2] {
    let entry = |c: &PairChild| {
        let near = ray.enter(c, limit);
        (near < f32::INFINITY).then_some(Entry { first: c.first, count: c.count, near })
    };
    let (a, b) = (entry(&n.children[0]), entry(&n.children[1]));
    match (a, b) {
        (Some(x), Some(y)) if y.near < x.near => [b, a],
        (None, _) => [b, None],
        _ => [a, b],
    }
}

impl Bvh {
    /// The closest hit of one ray over the tree `nodes`, merged into `best`, tested by `q` one item at a time.
    fn intersect_scalar_1<Q: LeafQuery<f32>>(&self, nodes: &[PairNode], q: &Q, best: &mut HitPacket<f32>) {
        let ray = ScalarRay::new(q.ray());
        let t_max = q.t_max();
        let mut stack = Stack::<Entry>::new();
        let (mut visits, mut prims) = (0, 0);
        let mut next = Some(Entry { first: 0, count: 0, near: 0.0 });
        while let Some(e) = next.take().or_else(|| stack.pop()) {
            // A box entered beyond the best hit holds nothing nearer (entered at exactly its t, it may hold
            // a tie of lower id).
            if e.near > best.t {
                continue;
            }
            if e.count > 0 {
                let first = e.first as usize;
                prims += e.count as usize;
                q.intersect(first..first + e.count as usize, true, best);
                continue;
            }
            visits += 1;
            let [nearer, farther] = children_by_distance(&nodes[e.first as usize], &ray, best.t.min(t_max));
            if let Some(f) = farther {
                stack.push(f);
            }
            next = nearer;
        }
        count_work(|| Work::single(prims, 2 * visits));
    }

    /// Whether one ray is blocked within its `t_max` over the tree `nodes`; stops at the first blocker, left
    /// in `blocker`.
    fn occluded_scalar_1<Q: LeafQuery<f32>>(&self, nodes: &[PairNode], q: &Q, blocker: &mut u32) -> bool {
        let ray = ScalarRay::new(q.ray());
        let t_max = q.t_max();
        let mut stack = Stack::<Entry>::new();
        let (mut visits, mut prims, mut blocked) = (0, 0, false);
        let mut next = Some(Entry { first: 0, count: 0, near: 0.0 });
        while let Some(e) = next.take().or_else(|| stack.pop()) {
            if e.count > 0 {
                let first = e.first as usize;
                prims += e.count as usize;
                if q.occluded(first..first + e.count as usize, true, blocker) {
                    blocked = true;
                    break;
                }
                continue;
            }
            visits += 1;
            let [nearer, farther] = children_by_distance(&nodes[e.first as usize], &ray, t_max);
            if let Some(f) = farther {
                stack.push(f);
            }
            next = nearer;
        }
        count_work(|| Work::single(prims, 2 * visits));
        blocked
    }

    /// The lanes of `lanes` walk the scalar tree `nodes` one ray at a time (K = 1: the one ray); their hits
    /// are merged into `best`.
    pub(super) fn intersect_scalar<F: Lanes, Q: LeafQuery<F>>(
        &self,
        nodes: &[PairNode],
        q: &Q,
        lanes: F::Mask,
        best: &mut HitPacket<F>,
    ) {
        for i in set_bits(F::move_mask(lanes)) {
            let mut hit = HitPacket { t: best.t.lane(i), prim: best.prim.lane(i), key: best.key.lane(i) };
            self.intersect_scalar_1(nodes, &q.lane(i), &mut hit);
            let at = F::mask_from_bits(1 << i);
            best.t = F::select(at, F::splat_f32(hit.t), best.t);
            best.prim = F::select_ids(at, F::Ids::splat(hit.prim), best.prim);
            best.key = F::select_ids(at, F::Ids::splat(hit.key), best.key);
        }
    }

    /// The lanes of `lanes` blocked within their `t_max` over the scalar tree `nodes`, one ray at a time.
    pub(super) fn occluded_scalar<F: Lanes, Q: LeafQuery<F>>(
        &self,
        nodes: &[PairNode],
        q: &Q,
        lanes: F::Mask,
        blocker: &mut u32,
    ) -> F::Mask {
        let blocked = set_bits(F::move_mask(lanes))
            .filter(|&i| self.occluded_scalar_1(nodes, &q.lane(i), blocker))
            .fold(0, |b, i| b | 1 << i);
        F::mask_from_bits(blocked)
    }
}
