//! Where each subtree of the 4-wide packet tree lies in the 8-wide single-ray tree. Both trees are collapsed
//! from one binary tree, so every packet node is some binary node; in the single-ray tree that binary node is
//! either a node of its own or one collapsed inside a node, whose children under it then make up the same
//! subtree. A packet walk that hands a sparse subtree to its lanes one ray at a time
//! (`Bvh::single_ray_lanes`; [`Bvh::intersect_subtree`], [`Bvh::occluded_subtree`]) can so walk it over
//! 8-wide nodes (about three binary levels a node against the 4-wide tree's two), over the same leaves; which
//! of them a ray tests depends on the order of visits, its answer does not (the `LeafQuery` contract).
//!
//! Subtrees are matched by their item ranges. Where the binary tree's leaves hold the items in depth-first
//! order (bareray's builders split ranges in place, and so does the balanced fallback), a binary node's
//! items are one range, and no two binary nodes have the same range (an inner node has two non-empty
//! children). Where they are not (obvhs's PLOC orders them by its clustering), there is no table and such
//! walks stay in the packet tree.

use rayon::prelude::*;

use super::node::RayNode;
use super::single::Subtree;
use super::slab::SlabRay;
use super::{Bvh, LeafQuery, Node, WideNode};
use crate::geometry::HitPacket;
use crate::simd::Lanes;

/// For each node of a packet tree, the node of the single-ray tree and its slots that hold the same subtree.
#[derive(Clone, Debug, Default)]
pub(crate) struct WideStarts {
    /// The single-ray node of each packet node.
    node: Vec<u32>,
    /// Bit c set for each of that node's slots under the packet node.
    slots: Vec<u8>,
}

impl WideStarts {
    /// The starts of every node of `packet` in `single`, two trees collapsed from one binary tree; `None` where
    /// a subtree's items are not one range.
    pub(super) fn of<P: RayNode, S: RayNode>(packet: &[P], single: &[S]) -> Option<Self> {
        assert!(S::WIDTH <= 8, "slot masks fit in a byte");
        let (packet_ranges, single_ranges) = rayon::join(|| ranges(packet), || ranges(single));
        let (packet_ranges, single_ranges) = (packet_ranges?, single_ranges?);
        let (node, slots) =
            packet_ranges.par_iter().map(|&range| start(single, &single_ranges, range)).unzip();
        Some(Self { node, slots })
    }

    /// Where the subtree of packet node `node` lies in the single-ray tree: a node and its slots.
    #[inline(always)]
    pub(crate) fn of_node(&self, node: u32) -> (u32, u32) {
        (self.node[node as usize], u32::from(self.slots[node as usize]))
    }

    /// Bytes of the table.
    pub(crate) fn bytes(&self) -> usize {
        self.node.len() * (size_of::<u32>() + size_of::<u8>())
    }
}

/// The item range of each node's subtree, or `None` where some subtree's items are not one range. Nodes are
/// stored depth first, so children come after their parent and one pass from the last node up sees every
/// child's range before its parent's.
fn ranges<T: RayNode>(nodes: &[T]) -> Option<Vec<(u32, u32)>> {
    let mut out = vec![(0, 0); nodes.len()];
    for i in (0..nodes.len()).rev() {
        let n = &nodes[i];
        let (mut lo, mut hi, mut items) = (u32::MAX, 0, 0);
        for c in 0..n.occupied() {
            let (child, count) = n.child(c);
            let (a, b) = if count > 0 {
                (child, child + u32::from(count))
            } else {
                assert!(child as usize > i, "children are stored after their parent");
                out[child as usize]
            };
            (lo, hi, items) = (lo.min(a), hi.max(b), items + (b - a));
        }
        if hi - lo != items {
            return None;
        }
        out[i] = (lo, hi);
    }
    Some(out)
}

/// The deepest node of `single` whose subtree holds the items `range`, and its slots under `range` (all of them
/// where the node's own range is `range`).
fn start<S: RayNode>(single: &[S], ranges: &[(u32, u32)], range: (u32, u32)) -> (u32, u8) {
    let within = |r: (u32, u32)| range.0 <= r.0 && r.1 <= range.1;
    let mut at = 0;
    loop {
        let n = &single[at];
        let slot_range = |c: usize| match n.child(c) {
            (child, 0) => ranges[child as usize],
            (first, count) => (first, first + u32::from(count)),
        };
        let holds = |c: usize| {
            let r = slot_range(c);
            n.leaves() >> c & 1 == 0 && r.0 <= range.0 && range.1 <= r.1
        };
        match (0..n.occupied()).find(|&c| holds(c)) {
            Some(c) => at = n.child(c).0 as usize,
            None => {
                let slots = (0..n.occupied()).filter(|&c| within(slot_range(c))).fold(0, |m, c| m | 1 << c);
                debug_assert!(slots != 0, "a subtree of the packet tree lies in the single-ray tree");
                return (at as u32, slots);
            }
        }
    }
}

impl Bvh {
    /// Where the subtree of packet node `node` is walked one ray at a time: in the single-ray tree where it is
    /// built ([`Bvh::wide_starts`]), else in the packet tree.
    #[inline(always)]
    fn subtree_nodes(&self, node: u32) -> SubtreeIn<'_> {
        match (&self.wide, &self.wide_starts) {
            (Some(wide), Some(starts)) => {
                let (node, slots) = starts.of_node(node);
                SubtreeIn::Single(wide, Subtree { node, slots })
            }
            _ => SubtreeIn::Packet(&self.nodes, Subtree::whole_of(node)),
        }
    }

    /// The lanes of `lanes` walk the subtree of packet node `node` one ray at a time ([`Bvh::intersect_each`]),
    /// over 8-wide nodes where the single-ray tree is built.
    pub(super) fn intersect_subtree<F: Lanes, Q: LeafQuery<F>>(
        &self,
        node: u32,
        q: &Q,
        slab: &SlabRay<F>,
        lanes: F::Mask,
        best: &mut HitPacket<F>,
    ) {
        match self.subtree_nodes(node) {
            SubtreeIn::Single(nodes, root) => self.intersect_each(nodes, None, root, q, slab, lanes, best),
            SubtreeIn::Packet(nodes, root) => self.intersect_each(nodes, None, root, q, slab, lanes, best),
        }
    }

    /// The lanes of `lanes` blocked in the subtree of packet node `node`, one ray at a time
    /// ([`Bvh::occluded_each`]), over 8-wide nodes where the single-ray tree is built.
    pub(super) fn occluded_subtree<F: Lanes, Q: LeafQuery<F>>(
        &self,
        node: u32,
        q: &Q,
        slab: &SlabRay<F>,
        lanes: F::Mask,
        blocker: &mut u32,
    ) -> F::Mask {
        match self.subtree_nodes(node) {
            SubtreeIn::Single(nodes, root) => self.occluded_each(nodes, None, root, q, slab, lanes, blocker),
            SubtreeIn::Packet(nodes, root) => self.occluded_each(nodes, None, root, q, slab, lanes, blocker),
        }
    }
}

/// A subtree of the packet tree, in the tree whose nodes walk it.
enum SubtreeIn<'a> {
    Single(&'a [WideNode], Subtree),
    Packet(&'a [Node], Subtree),
}

#[cfg(test)]
mod tests {
    use obvhs::aabb::Aabb;
    use obvhs::BvhBuildParams;

    use super::*;
    use crate::bvh::collapse::collapse;
    use crate::bvh::median::balanced;
    use crate::bvh::{binary, morton, sah, Node, WideNode};

    /// Items of every leaf under slot `c` of `nodes[n]`.
    fn items<T: RayNode>(nodes: &[T], n: usize, c: usize, out: &mut Vec<u32>) {
        match nodes[n].child(c) {
            (child, 0) => {
                (0..nodes[child as usize].occupied()).for_each(|c| items(nodes, child as usize, c, out))
            }
            (first, count) => out.extend(first..first + u32::from(count)),
        }
    }

    /// Every packet node's start holds exactly its items, from the deepest single-ray node that holds them
    /// all: all of that node's slots exactly where the two nodes are the same binary node.
    /// Checks the table, if built, and returns whether it was (the items of every subtree one range).
    fn check(src: &[obvhs::bvh2::node::Bvh2Node]) -> bool {
        let (packet, _) = collapse::<Node>(src);
        let (single, _) = collapse::<WideNode>(src);
        let Some(starts) = WideStarts::of(&packet, &single) else {
            return false;
        };
        let single_ranges = ranges(&single).unwrap();
        let (mut partial, mut whole) = (0, 0);
        for p in 0..packet.len() {
            let mut want = Vec::new();
            (0..packet[p].occupied()).for_each(|c| items(&packet, p, c, &mut want));
            let (node, slots) = starts.of_node(p as u32);
            let mut got = Vec::new();
            let n = node as usize;
            (0..single[n].occupied())
                .filter(|&c| slots >> c & 1 == 1)
                .for_each(|c| items(&single, n, c, &mut got));
            got.sort_unstable();
            want.sort_unstable();
            assert_eq!(got, want, "packet node {p}: single-ray node {node}, slots {slots:#b}");
            let all = (1u32 << single[n].occupied()) - 1;
            let own = single_ranges[n] == (want[0], want[want.len() - 1] + 1);
            assert_eq!(slots == all, own, "packet node {p}: slots {slots:#b} of node {node}");
            // No child of the start holds them all: it is the deepest.
            assert!(slots.count_ones() > 1 || packet.len() == 1, "packet node {p}: one slot {slots:#b}");
            (partial, whole) = if own { (partial, whole + 1) } else { (partial + 1, whole) };
        }
        // Both cases occur in trees deeper than a node or two (the root always starts whole).
        assert!(whole > 0, "the root starts whole");
        assert!(packet.len() < 8 || partial > 0, "{partial} partial starts of {} nodes", packet.len());
        true
    }

    fn boxes(n: usize, seed: u64) -> Vec<Aabb> {
        let mut state = seed;
        let mut next = || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n)
            .map(|_| {
                let c = glam::Vec3A::new(next(), next(), next()) * 10.0;
                Aabb { min: c - 0.01, max: c + 0.01 }
            })
            .collect()
    }

    #[test]
    fn packet_subtrees_start_where_the_single_ray_tree_holds_the_same_items() {
        for (n, seed) in [(1, 1), (5, 2), (9, 3), (40, 4), (1000, 5), (30_000, 6)] {
            let boxes = boxes(n, seed);
            let (sah_tree, _) = sah::build_sah(n, |i| boxes[i], 6.0);
            assert!(check(&sah_tree), "{n} boxes: the SAH tree's subtrees hold ranges of items");
            let (morton_tree, _) = morton::build_morton(n, |i| boxes[i], 6.0);
            assert!(check(&morton_tree), "{n} boxes: the Morton-order tree's too");
            assert!(check(&balanced(&boxes).0), "{n} boxes: the balanced tree's too");
            // obvhs's trees get a table only where their items happen to lie in ranges.
            for leaf in [1, 8] {
                let params = BvhBuildParams { max_prims_per_leaf: leaf, ..BvhBuildParams::fast_build() };
                check(&binary::build_binary(&boxes, params).nodes);
            }
        }
    }

    /// A tree whose leaves do not hold their items in depth-first order (the left half's leaves hold the even
    /// items, the right half's the odd ones) gets no table; the same tree with its leaves in order gets one.
    #[test]
    fn leaves_out_of_order_get_no_table() {
        use obvhs::bvh2::node::Bvh2Node;
        // obvhs's layout: inner node i's children at nodes 2i + 1 and 2i + 2 here; leaves 7 to 14.
        let tree = |items: [u32; 8]| -> Vec<Bvh2Node> {
            let unit = Aabb { min: glam::Vec3A::ZERO, max: glam::Vec3A::ONE };
            let inner = (0..7).map(|i| Bvh2Node::new(unit, 0, 2 * i + 1));
            inner.chain(items.map(|item| Bvh2Node::new(unit, 1, item))).collect()
        };
        let src = tree([0, 2, 4, 6, 1, 3, 5, 7]);
        let (packet, _) = collapse::<Node>(&src);
        let (single, _) = collapse::<WideNode>(&src);
        assert!(packet.len() > 1, "the packet tree has nodes below the root");
        assert!(WideStarts::of(&packet, &single).is_none(), "items out of order taken as ranges");
        assert!(check(&tree([0, 1, 2, 3, 4, 5, 6, 7])), "leaves in order get a table");
    }
}
