//! The 4-wide node of the packet walk ([`Node`]) and what every node width shares: the SoA child slots, the
//! reference to a child, and the `RayNode` interface the collapse and the single-ray walk use.

use crate::simd::Lanes;

/// Children per node (Embree's N).
pub(crate) const N: usize = 4;

/// One node: the boxes of its children and where each child's content is. Occupied slots come first.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct Node {
    /// `bounds[0]` the lower corner, `bounds[1]` the upper, per axis (x, y, z), per child: indexed by side
    /// so a ray picks its near and far planes by the signs of its direction.
    pub(crate) bounds: [[[f32; N]; 3]; 2],
    /// Inner child: index of its node; leaf child: index of its first sphere.
    pub(crate) child: [u32; N],
    /// Number of spheres of a leaf child (M ≤ obvhs's leaf size, at most 255); 0 for an inner child.
    pub(crate) count: [u8; N],
    /// Front-to-back order of the occupied slots for rays in each octant (index: bit a set when the
    /// direction's axis-a component is negative), 2 bits per slot, nearest in the low bits.
    pub(crate) order: [u8; 8],
    /// Occupied slots (2 to N, 1 only for a root that is a leaf).
    pub(crate) slots: u8,
    /// Bit c set where slot c is a leaf (`count[c]` not 0).
    pub(crate) leaves: u8,
}

const _: () = assert!(size_of::<Node>() == 128, "a node is two cache lines");

/// A child slot's box and content, while flattening.
#[derive(Clone, Copy)]
pub(super) struct ChildRef {
    pub(super) lo: [f32; 3],
    pub(super) hi: [f32; 3],
    pub(super) child: u32,
    pub(super) count: u8,
}

/// A slot no ray can enter: a box at +inf, whose slab distances are +inf or −inf, never a finite entry. (An
/// inverted box, lo = +inf and hi = −inf, would give every slab (−inf, +inf) and be entered by every ray.)
pub(super) const EMPTY: ChildRef =
    ChildRef { lo: [f32::INFINITY; 3], hi: [f32::INFINITY; 3], child: 0, count: 0 };

/// The SoA slots of a `W`-wide node over `children`: boxes (`[side][axis][slot]`), references and sphere
/// counts, with [`EMPTY`] past the last child.
pub(super) type Slots<const W: usize> = ([[[f32; W]; 3]; 2], [u32; W], [u8; W]);

pub(super) fn slots<const W: usize>(children: &[ChildRef]) -> Slots<W> {
    assert!(children.len() <= W);
    let c = |i: usize| children.get(i).copied().unwrap_or(EMPTY);
    let bounds = [
        std::array::from_fn(|a| std::array::from_fn(|i| c(i).lo[a])),
        std::array::from_fn(|a| std::array::from_fn(|i| c(i).hi[a])),
    ];
    (bounds, std::array::from_fn(|i| c(i).child), std::array::from_fn(|i| c(i).count))
}

/// Bit c set where `count[c]` is not 0: the leaf slots (empty slots have count 0 and are never entered).
/// Kept in each node: the single-ray occlusion walk asks for it at every visit, and computing it there
/// showed in balls4's instruction counts (docs/perf-log/2026-11.md, "Leaf bits kept in the
/// nodes").
pub(super) fn leaf_bits(count: &[u8]) -> u8 {
    count.iter().enumerate().fold(0, |bits, (c, &n)| bits | u8::from(n != 0) << c)
}

impl Node {
    fn new(children: &[ChildRef]) -> Node {
        let (bounds, child, count) = slots::<N>(children);
        let order = std::array::from_fn(|octant| front_to_back(children, octant));
        Node { bounds, child, count, order, slots: children.len() as u8, leaves: leaf_bits(&count) }
    }

    /// Lower corners per axis, per child.
    #[inline(always)]
    pub(crate) fn lo(&self) -> &[[f32; N]; 3] {
        &self.bounds[0]
    }
    /// Upper corners per axis, per child.
    #[inline(always)]
    pub(crate) fn hi(&self) -> &[[f32; N]; 3] {
        &self.bounds[1]
    }

    /// The occupied slots farthest first for rays in `octant` (the order to push them in), from
    /// [`Node::order`].
    #[inline(always)]
    pub(crate) fn slots_far_to_near(&self, octant: usize) -> impl Iterator<Item = usize> {
        let order = self.order[octant];
        (0..usize::from(self.slots)).rev().map(move |k| usize::from(order >> (2 * k) & 3))
    }
}

/// The [`RayNode`] methods that only read or shift the SoA slots (`bounds`, `child`, `count`, `slots`), alike
/// for every node width; `$lanes` holds one child per lane.
macro_rules! slot_access {
    ($lanes:ty) => {
        #[inline(always)]
        fn planes(&self, side: usize, axis: usize) -> $lanes {
            <$lanes>::from(self.bounds[side][axis])
        }
        #[inline(always)]
        fn child(&self, c: usize) -> (u32, u8) {
            (self.child[c], self.count[c])
        }
        #[inline(always)]
        fn leaves(&self) -> u32 {
            u32::from(self.leaves)
        }
        #[inline(always)]
        fn occupied(&self) -> usize {
            usize::from(self.slots)
        }
    };
}
pub(super) use slot_access;

/// A node as the collapse builds it and the single-ray walk reads it: up to `WIDTH` children, one per lane of
/// `Lanes` in the walk's slab test. Implemented by the 4-wide packet [`Node`] and the 8-wide
/// [`WideNode`](super::wide_node::WideNode).
pub(super) trait RayNode: Copy + Send + Sync {
    /// Children per node.
    const WIDTH: usize;
    /// One lane per child.
    type Lanes: Lanes;
    /// A node over `children` (at most `WIDTH`).
    fn new(children: &[ChildRef]) -> Self;
    /// The `side` (0 lower, 1 upper) planes on `axis` of every child.
    fn planes(&self, side: usize, axis: usize) -> Self::Lanes;
    /// Child `c`'s reference and sphere count (0 for an inner node).
    fn child(&self, c: usize) -> (u32, u8);
    /// Bit c set for each leaf child.
    fn leaves(&self) -> u32;
    /// The number of occupied slots (they come first).
    fn occupied(&self) -> usize;
}

impl RayNode for Node {
    const WIDTH: usize = N;
    type Lanes = wide::f32x4;

    fn new(children: &[ChildRef]) -> Self {
        Node::new(children)
    }
    slot_access!(wide::f32x4);
}

/// The children sorted by the projection of their box centres on the octant's diagonal direction: the
/// order a ray in that octant meets well-separated boxes. Packed 2 bits per slot, nearest first.
pub(super) fn front_to_back(children: &[ChildRef], octant: usize) -> u8 {
    let sign = |a: usize| if octant >> a & 1 == 1 { -1.0 } else { 1.0 };
    let key = |c: &ChildRef| (0..3).map(|a| sign(a) * (c.lo[a] + c.hi[a])).sum::<f32>();
    // Farthest first by the negated key is nearest first by the key (negation is exact).
    let mut order = [(0.0, 0); N];
    for (slot, c) in children.iter().enumerate() {
        order[slot] = (-key(c), slot);
    }
    far_to_near(&mut order[..children.len()]);
    order[..children.len()].iter().enumerate().fold(0, |bits, (k, &(_, slot))| bits | (slot as u8) << (2 * k))
}

/// Sorts up to N (key, slot) pairs so that the largest key comes first: pushed in this order, the nearest
/// child is popped first.
#[inline(always)]
pub(super) fn far_to_near(order: &mut [(f32, usize)]) {
    for i in 1..order.len() {
        let mut j = i;
        while j > 0 && order[j - 1].0 < order[j].0 {
            order.swap(j - 1, j);
            j -= 1;
        }
    }
}
