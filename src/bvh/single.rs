//! Single-ray traversal, SIMD over a node's children: one ray's slab test against all of a node's boxes in one
//! pass (`f32x4` over the 4-wide packet nodes, `f32x8` over the 8-wide single-ray tree; the walk is generic
//! over [`RayNode`]). It serves K = 1 (over the 8-wide tree when the scene has one: from the root, or for a
//! ray leaving an item from that item's leaf up, [`Bvh::intersect_from`], [`Bvh::occluded_from`]) and every
//! subtree of the 4-wide tree that a packet enters with few live lanes (incoherent secondary rays after a
//! bounce, and camera packets that have spread over many small spheres deep in the tree), where the packet
//! traversal would carry mostly dead lanes: each live lane then walks the subtree alone, and its result is
//! merged back into its lane (Embree's "hybrid" traversal). Such a subtree is walked in the 8-wide tree where
//! the scene has one and [`super::wide_starts`] places it there, else in the 4-wide tree. Scattered secondary
//! packets may walk this way over the whole tree too (`Bvh::intersect_lanes`).

use super::collapse::MAX_WIDTH;
use super::node::{far_to_near, RayNode};
use super::slab::{near_side, slab_entry_ordered, SlabRay, Stack};
use super::upward::Upward;
use super::work::{count_work, Work};
use super::{Bvh, LeafQuery, SingleLeafQuery};
use crate::geometry::HitPacket;
use crate::math::{Real, V3};
use crate::simd::{set_bits, IdLanes, Lanes};

/// A pending subtree of the single-ray traversal and the ray's entry distance.
#[derive(Clone, Copy)]
struct Entry {
    child: u32,
    count: u8,
    near: f32,
}

/// Where a single-ray walk starts: a node and the slots of it to walk (all of them, or those that hold a subtree
/// of the packet tree, [`super::wide_starts`]).
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) struct Subtree {
    /// The node the walk starts at.
    pub(super) node: u32,
    /// Bit c set for each of its slots to walk; `u32::MAX` for all of them.
    pub(super) slots: u32,
}

impl Subtree {
    /// The whole tree.
    pub(super) const WHOLE: Subtree = Subtree { node: 0, slots: u32::MAX };

    /// All of node `node`'s subtree.
    pub(super) fn whole_of(node: u32) -> Self {
        Subtree { node, slots: u32::MAX }
    }
}

/// One ray prepared for slab tests against a node's boxes at once (one per lane of `L`): lane `i` of a
/// prepared packet (whose lanes hold the bits a scalar ray's preparation gives) splatted.
struct SlabRayN<L: Lanes> {
    ray: SlabRay<L>,
    /// Per axis, the side of the near plane ([`near_side`]).
    near: [usize; 3],
}

impl<L: Lanes> SlabRayN<L> {
    fn lane<F: Lanes>(packet: &SlabRay<F>, i: usize) -> Self {
        let lane = |v: &V3<F>| [v.x.lane(i), v.y.lane(i), v.z.lane(i)];
        let (inv, neg_o_inv) = (lane(&packet.inv_dir), lane(&packet.neg_o_inv));
        let splat = |v: [f32; 3]| V3::new(L::splat_f32(v[0]), L::splat_f32(v[1]), L::splat_f32(v[2]));
        Self { ray: SlabRay { inv_dir: splat(inv), neg_o_inv: splat(neg_o_inv) }, near: inv.map(near_side) }
    }

    /// The ray's entry distance into each child of `n`, `inf` where it misses the child or enters beyond
    /// `limit`: the packet traversal's slab test, one child per lane.
    #[inline(always)]
    fn enter<T: RayNode<Lanes = L>>(&self, n: &T, limit: f32) -> L {
        let planes = |side: [usize; 3]| [0, 1, 2].map(|a| n.planes(side[a], a));
        let far = self.near.map(|s| 1 - s);
        slab_entry_ordered(planes(self.near), planes(far), &self.ray, L::splat_f32(limit))
    }
}

impl Bvh {
    /// Of the children of `n` (but the slots of `skip_slots`) the ray enters within `limit`, pushes all but
    /// the nearest (farthest first) and returns that one, to be visited next.
    #[inline(always)]
    fn push_but_nearest<T: RayNode>(
        &self,
        n: &T,
        ray: &SlabRayN<T::Lanes>,
        limit: f32,
        stack: &mut Stack<Entry>,
        skip_slots: u32,
    ) -> Option<Entry> {
        let near = ray.enter(n, limit);
        // Bit c for each child entered; empty slots (boxes at +inf) never are.
        let entered = T::Lanes::move_mask(near.lt(T::Lanes::splat_f32(f32::INFINITY))) & !skip_slots;
        let near = near.to_array();
        let near = near.as_ref();
        let entry = |c: usize| {
            let (child, count) = n.child(c);
            Entry { child, count, near: near[c] }
        };
        // One entered child is the common case deep in the tree: no ordering, no stack.
        if entered & entered.wrapping_sub(1) == 0 {
            return (entered != 0).then(|| entry(entered.trailing_zeros() as usize));
        }
        // Two: one comparison orders them.
        if entered.count_ones() == 2 {
            let (a, b) =
                (entered.trailing_zeros() as usize, (entered & (entered - 1)).trailing_zeros() as usize);
            let (nearest, farther) = if near[b] < near[a] { (b, a) } else { (a, b) };
            stack.push(entry(farther));
            return Some(entry(nearest));
        }
        let mut order = [(0.0, 0); MAX_WIDTH];
        let mut hits = 0;
        for c in set_bits(entered) {
            order[hits] = (near[c], c);
            hits += 1;
        }
        far_to_near(&mut order[..hits]);
        let (nearest, farther) = order[..hits].split_last()?;
        farther.iter().for_each(|&(_, c)| stack.push(entry(c)));
        Some(entry(nearest.1))
    }

    /// The closest hit of one ray from `start` (whose node the ray enters), merged into `best`: the slots of
    /// its node, then, with links, each ancestor's other children (each subtree walked down as from the root)
    /// up to the root. An entry is dropped only when its box is entered beyond the best hit so far, so no node
    /// that could hold the closest hit, or a hit at the same t with a lower key, is left out: whatever the
    /// start, the answer is the same; the start decides the order of visits and the work.
    #[inline(always)]
    fn intersect_from<T: RayNode, Q: SingleLeafQuery>(
        &self,
        nodes: &[T],
        start: Start,
        q: &Q,
        slab: &SlabRayN<T::Lanes>,
        best: &mut HitPacket<f32>,
    ) {
        let mut stack = Stack::<Entry>::new();
        let (mut node, mut skip_slots, mut work) = (start.root.node as usize, !start.root.slots, (0, 0));
        loop {
            work.0 += 1;
            let limit = best.t.min(q.t_max());
            let next = self.push_but_nearest(&nodes[node], slab, limit, &mut stack, skip_slots);
            self.intersect_below(nodes, next, &mut stack, q, slab, best, &mut work);
            let Some(up) = start.up.filter(|_| node != 0) else { break };
            let (parent, slot) = up.parent_of(node);
            (node, skip_slots) = (parent, 1 << slot);
        }
        count_work(|| Work::single(work.1, T::WIDTH * work.0));
    }

    /// The closest-hit walk from `next` and the subtrees on `stack`, nearest first, until both are done;
    /// `work` counts node visits and items tested.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn intersect_below<T: RayNode, Q: SingleLeafQuery>(
        &self,
        nodes: &[T],
        mut next: Option<Entry>,
        stack: &mut Stack<Entry>,
        q: &Q,
        slab: &SlabRayN<T::Lanes>,
        best: &mut HitPacket<f32>,
        work: &mut (usize, usize),
    ) {
        while let Some(e) = next.take().or_else(|| stack.pop()) {
            if e.near > best.t {
                continue;
            }
            if e.count > 0 {
                let first = e.child as usize;
                work.1 += usize::from(e.count);
                q.intersect_leaf(first, usize::from(e.count), best);
            } else {
                work.0 += 1;
                let n = &nodes[e.child as usize];
                next = self.push_but_nearest(n, slab, best.t.min(q.t_max()), stack, 0);
            }
        }
    }

    /// Whether one ray is blocked within `t_max`, walked from `start`: the slots of its node (those of
    /// `start.first_slots` first), then, with links, each ancestor's other children (each subtree walked down
    /// as from the root) up to the root. Stops at the first blocker found, left in `blocker`. Any hit will do,
    /// so a node's entered leaves are tested on the spot, before its entered inner children are pushed, and
    /// nothing is ordered by distance. From a leaf up, every node a walk from the root would visit is visited
    /// (the ancestors without their own box tests), each once, so the answer is the same; the blockers around
    /// the item come first.
    #[inline(always)]
    fn occluded_from<T: RayNode, Q: SingleLeafQuery>(
        &self,
        nodes: &[T],
        start: Start,
        q: &Q,
        slab: &SlabRayN<T::Lanes>,
        blocker: &mut u32,
    ) -> bool {
        let mut stack = Stack::<u32>::new();
        let mut work = (0, 0);
        let (mut node, mut first_slots, mut skip_slots) =
            (start.root.node as usize, start.first_slots, !start.root.slots);
        let blocked = loop {
            work.0 += 1;
            let n = &nodes[node];
            if occluded_visit(n, first_slots, skip_slots, q, slab, &mut stack, blocker, &mut work.1)
                || occluded_below(nodes, &mut stack, q, slab, blocker, &mut work)
            {
                break true;
            }
            let Some(up) = start.up.filter(|_| node != 0) else { break false };
            let (parent, slot) = up.parent_of(node);
            (node, first_slots, skip_slots) = (parent, 0, 1 << slot);
        };
        count_work(|| Work::single(work.1, T::WIDTH * work.0));
        blocked
    }

    /// The lanes of `lanes` walk the subtree `root` of `nodes` one ray at a time; their hits are merged into
    /// `best`. `slab` is the packet prepared for slab tests. Over the whole tree ([`Subtree::WHOLE`]) with
    /// `up`, the links of `nodes`, a lane that leaves an item of the tree starts at that item's leaf
    /// ([`Bvh::intersect_from`]).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn intersect_each<F: Lanes, T: RayNode, Q: LeafQuery<F>>(
        &self,
        nodes: &[T],
        up: Option<&Upward>,
        root: Subtree,
        q: &Q,
        slab: &SlabRay<F>,
        lanes: F::Mask,
        best: &mut HitPacket<F>,
    ) {
        debug_assert!(up.is_none_or(|up| up.nodes() == nodes.len()), "the links of another tree");
        let bits = F::move_mask(lanes);
        for i in set_bits(bits) {
            let mut hit = HitPacket { t: best.t.lane(i), prim: best.prim.lane(i), key: best.key.lane(i) };
            let (one, ray) = (q.lane(i), SlabRayN::lane(slab, i));
            self.intersect_from(nodes, Start::of(up, root, &one), &one, &ray, &mut hit);
            let at = F::mask_from_bits(1 << i);
            best.t = F::select(at, F::splat_f32(hit.t), best.t);
            best.prim = F::select_ids(at, F::Ids::splat(hit.prim), best.prim);
            best.key = F::select_ids(at, F::Ids::splat(hit.key), best.key);
        }
    }

    /// The lanes of `lanes` blocked within their `t_max` in the subtree `root` of `nodes`, one ray at a time;
    /// over the whole tree ([`Subtree::WHOLE`]) with its links `up`, each lane that leaves an item of the tree
    /// from that item's leaf up ([`Bvh::occluded_from`]).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn occluded_each<F: Lanes, T: RayNode, Q: LeafQuery<F>>(
        &self,
        nodes: &[T],
        up: Option<&Upward>,
        root: Subtree,
        q: &Q,
        slab: &SlabRay<F>,
        lanes: F::Mask,
        blocker: &mut u32,
    ) -> F::Mask {
        debug_assert!(up.is_none_or(|up| up.nodes() == nodes.len()), "the links of another tree");
        let bits = F::move_mask(lanes);
        let blocked = set_bits(bits)
            .filter(|&i| {
                let (one, ray) = (q.lane(i), SlabRayN::lane(slab, i));
                self.occluded_from(nodes, Start::of(up, root, &one), &one, &ray, blocker)
            })
            .fold(0, |b, i| b | 1 << i);
        F::mask_from_bits(blocked)
    }
}

/// Where one ray's walk starts: a subtree, the slots of its node to test first (occlusion), and the links to
/// climb by once the subtree is walked (none: the walk ends there).
#[derive(Clone, Copy)]
struct Start<'a> {
    root: Subtree,
    first_slots: u32,
    up: Option<&'a Upward>,
}

impl<'a> Start<'a> {
    /// A lane walked over the whole tree starts at the leaf of the item its ray leaves, when the tree has links
    /// `up` and the item is one of the tree's; any other walk at `root`, without climbing.
    #[inline(always)]
    fn of<Q: SingleLeafQuery>(up: Option<&'a Upward>, root: Subtree, one: &Q) -> Self {
        let leaf =
            up.filter(|_| root == Subtree::WHOLE).and_then(|up| Some((up, up.leaf_of(one.departure(0)?)?)));
        match leaf {
            Some((up, (node, slot))) => {
                Start { root: Subtree::whole_of(node as u32), first_slots: 1 << slot, up: Some(up) }
            }
            None => Start { root, first_slots: 0, up: None },
        }
    }
}

/// Node `n` of an occlusion walk: the leaves among its children the ray enters (but the slots of
/// `skip_slots`) tested on the spot, those of `first_slots` before the others, and its entered inner children
/// pushed. Whether a leaf blocked the ray; `prims` counts the items tested.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn occluded_visit<T: RayNode, Q: SingleLeafQuery>(
    n: &T,
    first_slots: u32,
    skip_slots: u32,
    q: &Q,
    slab: &SlabRayN<T::Lanes>,
    stack: &mut Stack<u32>,
    blocker: &mut u32,
    prims: &mut usize,
) -> bool {
    let near = slab.enter(n, q.t_max());
    // Bit c for each child entered; empty slots (boxes at +inf) never are.
    let entered = T::Lanes::move_mask(near.lt(T::Lanes::splat_f32(f32::INFINITY))) & !skip_slots;
    let leaves = entered & n.leaves();
    for c in set_bits(leaves & first_slots).chain(set_bits(leaves & !first_slots)) {
        let (at, count) = n.child(c);
        *prims += usize::from(count);
        if q.occluded_leaf(at as usize, usize::from(count), blocker) {
            return true;
        }
    }
    for c in set_bits(entered & !n.leaves()) {
        stack.push(n.child(c).0);
    }
    false
}

/// The occlusion walk of the subtrees on `stack`, until it is empty or a leaf blocks the ray; `work` counts
/// node visits and items tested.
#[inline(always)]
fn occluded_below<T: RayNode, Q: SingleLeafQuery>(
    nodes: &[T],
    stack: &mut Stack<u32>,
    q: &Q,
    slab: &SlabRayN<T::Lanes>,
    blocker: &mut u32,
    work: &mut (usize, usize),
) -> bool {
    while let Some(node) = stack.pop() {
        work.0 += 1;
        if occluded_visit(&nodes[node as usize], 0, 0, q, slab, stack, blocker, &mut work.1) {
            return true;
        }
    }
    false
}
