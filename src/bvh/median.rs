//! The median-split binary tree in obvhs's layout: the fallback for scenes whose first tree is too deep, the
//! leaves of the piles builder, and the node slots every binary builder reserves.

use obvhs::aabb::Aabb;
use obvhs::bvh2::node::Bvh2Node;

/// Items per leaf of [`balanced`].
pub(super) const BALANCED_LEAF: usize = 4;

/// A binary tree over `boxes` in obvhs's layout (nodes, and the primitive order its leaves index), split at
/// the median centre along the widest spread of centres: about log2(n / 4) levels whatever the boxes, for
/// scenes whose obvhs tree is too deep.
pub(super) fn balanced(boxes: &[Aabb]) -> (Vec<Bvh2Node>, Vec<u32>) {
    let (mut nodes, mut order) = tree_for(boxes.len());
    balanced_into(boxes, 0..boxes.len() as u32, &mut nodes, &mut order, 0);
    (nodes, order)
}

/// [`balanced`] over the boxes `items`, written as the subtree at `nodes[at]`: its nodes appended to
/// `nodes`, its leaves' primitives to `order`. Built without recursion.
pub(super) fn balanced_into(
    boxes: &[Aabb],
    items: impl IntoIterator<Item = u32>,
    nodes: &mut Vec<Bvh2Node>,
    order: &mut Vec<u32>,
    at: usize,
) {
    let base = order.len();
    order.extend(items);
    let mut pending = vec![(at, base, order.len())];
    while let Some((at, lo, hi)) = pending.pop() {
        let part = &mut order[lo..hi];
        let bounds = part.iter().fold(Aabb::empty(), |b, &i| b.union(&boxes[i as usize]));
        if part.len() <= BALANCED_LEAF {
            nodes[at] = Bvh2Node::new(bounds, part.len() as u32, lo as u32);
            continue;
        }
        let mut centres = Aabb::empty();
        part.iter().for_each(|&i| _ = centres.extend(boxes[i as usize].center()));
        let axis = centres.largest_axis();
        let key = |i: &u32| boxes[*i as usize].center_axis(axis);
        let mid = part.len() / 2;
        part.select_nth_unstable_by(mid, |a, b| key(a).total_cmp(&key(b)));
        let first = nodes.len();
        nodes.extend([unset(); 2]);
        nodes[at] = Bvh2Node::new(bounds, 0, first as u32);
        pending.extend([(first, lo, lo + mid), (first + 1, lo + mid, hi)]);
    }
}

/// A node slot reserved for a node written later (the root, or an inner node's two children).
pub(super) fn unset() -> Bvh2Node {
    Bvh2Node::new(Aabb::empty(), 0, 0)
}

/// An obvhs-layout tree to be built over `n` boxes: the root's slot, and room for the leaves' order.
pub(super) fn tree_for(n: usize) -> (Vec<Bvh2Node>, Vec<u32>) {
    (vec![unset()], Vec::with_capacity(n))
}
