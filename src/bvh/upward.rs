//! The links that let a walk start at an item's leaf and climb to the root: each node's parent and each
//! item's leaf. An occlusion ray leaving an item (an ambient-occlusion or shadow ray from a sphere) is often
//! blocked by the items around it, which a walk from the root reaches only after descending the tree; from the
//! leaf up, it tests them first and may stop there. Every node a walk from the root would visit is still
//! visited, each once (the ancestors without their own box tests), so the answer is the same; and since every
//! ancestor's box holds the ray's start, a walk from the root visits them all too: an unblocked ray does the
//! same work either way. A closest-hit walk from the leaf up drops a box only when it is entered beyond the
//! best hit so far, as from the root, so its answer is the same too; its work differs (the hits near the start
//! come first and prune the rest, which pays where rays meet the neighbours of what they leave).

use super::node::RayNode;

/// A link to a child slot: its node's index times 8 plus the slot.
const SLOT_BITS: u32 = 3;

/// Parent links of a tree of `RayNode`s (at most 8 wide) and the leaf of every item.
#[derive(Clone, Debug, Default)]
pub(crate) struct Upward {
    /// For each node, the link to the slot that refers to it in its parent (the root's is unused).
    parent: Vec<u32>,
    /// For each item, the link to the leaf slot holding it.
    leaf: Vec<u32>,
}

impl Upward {
    /// The links of `nodes` (depth-first, `nodes[0]` the root) whose leaves hold `items` items.
    pub(super) fn of<T: RayNode>(nodes: &[T], items: usize) -> Self {
        assert!(T::WIDTH <= 1 << SLOT_BITS && nodes.len() < (1 << (32 - SLOT_BITS)), "links fit in a u32");
        let mut parent = vec![0u32; nodes.len()];
        let mut leaf = vec![0u32; items];
        for (p, n) in nodes.iter().enumerate() {
            for c in 0..T::WIDTH {
                let (child, count) = n.child(c);
                let link = (p as u32) << SLOT_BITS | c as u32;
                if count > 0 {
                    let first = child as usize;
                    leaf[first..first + usize::from(count)].fill(link);
                } else if n.leaves() >> c & 1 == 0 && child != 0 {
                    parent[child as usize] = link;
                }
            }
        }
        Self { parent, leaf }
    }

    /// The leaf holding `item`: its node and slot, or `None` for an item the tree does not hold.
    #[inline(always)]
    pub(crate) fn leaf_of(&self, item: usize) -> Option<(usize, usize)> {
        self.leaf.get(item).map(|&l| split(l))
    }

    /// The parent of node `node` (not the root) and the slot that refers to it there.
    #[inline(always)]
    pub(crate) fn parent_of(&self, node: usize) -> (usize, usize) {
        split(self.parent[node])
    }

    /// The number of nodes of the tree these links are of.
    pub(crate) fn nodes(&self) -> usize {
        self.parent.len()
    }

    /// Bytes of the links.
    pub(crate) fn bytes(&self) -> usize {
        (self.parent.len() + self.leaf.len()) * size_of::<u32>()
    }
}

fn split(link: u32) -> (usize, usize) {
    ((link >> SLOT_BITS) as usize, (link & ((1 << SLOT_BITS) - 1)) as usize)
}
