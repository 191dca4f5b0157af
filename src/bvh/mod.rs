//! A 4-wide BVH over boxes, built as a binary tree (bareray's binned SAH or Morton order, or obvhs's PLOC) and collapsed into
//! bareray's own node layout: each node holds the boxes of up to `N` children in SoA form (two 64-byte cache
//! lines), so one node visit tests all its children — K rays against each child in the packet walk
//! (`packet.rs`), one ray against all children at once in the single-ray walk (`single.rs`).
//!
//! The tree knows nothing of primitives. It is built over one box per item (`build()`), returns the leaf
//! order of the items (their owner stores them in that order, so leaves index the arrays directly), and its
//! walks ask a `LeafQuery` to test the items of a leaf: spheres, triangles and the registered kinds each implement it, and
//! each kind's walk is monomorphised over its own query.
//!
//! Culling is conservative: boxes are padded by a bound on the kernels' rounding error (`padding`), and every
//! slab test widens its exit distance by 6ε, which covers the fused slab distances' rounding
//! (`slab::WIDEN`). With the (t, id) order of `crate::geometry::HitPacket::update` this makes every lane's
//! result equal, bit for bit, to brute force over the same items, whatever order the nodes are visited in and
//! whichever walk runs.
//!
//! Files: `node` (the 4-wide node layout), `wide_node` (the 8-wide single-ray layout), `build` (the
//! builders and the fallbacks for piles and deep trees), `sah.rs` (the binned SAH builder), `morton.rs` (the
//! Morton-order builder on the SAH builder's driver), `binary.rs`
//! (obvhs), `median.rs` (the median-split fallback tree), `collapse.rs` (binary tree to wide nodes), `slab.rs` (slab tests and the traversal stack),
//! `packet.rs` and `single.rs` (the walks), `scalar.rs` (the scalar walk over the binary tree, when built),
//! `upward.rs` (parent links, for walks that start at the leaf of the item a ray leaves), `wide_starts.rs`
//! (where each packet subtree lies in the 8-wide tree, for its lanes walked alone).

mod binary;
pub(crate) mod build;
mod collapse;
pub(crate) mod item_query;
mod large;
mod median;
mod morton;
pub(crate) mod node;
mod packet;
mod piles;
mod sah;
mod scalar;
mod single;
mod slab;
mod upward;
pub(crate) mod wide_node;
mod wide_starts;
pub(crate) mod work;

pub(crate) use build::{build, BuildOptions, Builder};
pub(crate) use large::MAX_PACKETS;
pub(crate) use node::Node;
pub(crate) use scalar::PairNode;
pub(crate) use wide_node::WideNode;

use crate::geometry::{HitPacket, Pyramid, Ray};
use crate::math::Vec3f;
use crate::simd::Lanes;
use single::Subtree;
use slab::SlabRay;

// The slab test and the frustum, shared with the particle tree's walk (`crate::accel::pkd`).
pub(crate) use large::{farthest, members, MemberSides};
pub(crate) use packet::Frustum;
pub(crate) use slab::{SlabRay as SlabRays, Stack, WIDEN};

/// What a walk asks of the items in its leaves, for a packet of K rays (`F`): the tree holds only boxes and
/// item ranges, and every kind of primitive answers for its own items. Implementations must give each lane the
/// result its K = 1 (`f32`) instance gives, and combine hits by [`HitPacket::update`]'s (t, id) order, so the
/// walk's order of visits cannot change a result.
pub(crate) trait LeafQuery<F: Lanes> {
    /// The query of one lane's ray alone, for the single-ray walk.
    type One: SingleLeafQuery;
    /// The rays.
    fn ray(&self) -> &Ray<F>;
    /// Exclusive end of each ray's range.
    fn t_max(&self) -> F;
    /// Planes enclosing the live rays, when the packet's maker knows them.
    fn pyramid(&self) -> Option<Pyramid>;
    /// Lane `i` as a one-ray query, with the bits the packet's lane has.
    fn lane(&self, i: usize) -> Self::One;
    /// A ball (centre, radius) enclosing item `i`, for the packet walk's frustum test of single items; `None`
    /// where the kind has no cheap one (the item is then always tested).
    fn ball(&self, i: usize) -> Option<(Vec3f, f32)>;
    /// Closest hits of `items` for the lanes of `live`, merged into `best`.
    fn intersect(&self, items: impl Iterator<Item = usize>, live: F::Mask, best: &mut HitPacket<F>);
    /// Lanes of `live` blocked by an item of `items`; `blocker` is set to an item that blocked some lane, if
    /// any did. May stop as soon as every live lane is blocked.
    fn occluded(&self, items: std::ops::Range<usize>, live: F::Mask, blocker: &mut u32) -> F::Mask;
    /// The item lane `i`'s ray leaves, when it is one of the tree's: the walk may then start from that item's
    /// leaf.
    #[inline(always)]
    fn departure(&self, _i: usize) -> Option<usize> {
        None
    }
    /// Asks for items `first..first + count` to be brought into cache ahead of their tests (a hint).
    #[inline(always)]
    fn prefetch(&self, _first: usize, _count: usize) {}
}

/// The one-ray leaf tests of the single-ray walk: a leaf's items against one ray, which a kind may run with
/// its items across the lanes (spheres do). They must give the bits of [`LeafQuery::intersect`] and
/// [`LeafQuery::occluded`] on the same items; `blocker` is the lowest blocking item, as the scalar loop
/// finds it.
pub(crate) trait SingleLeafQuery: LeafQuery<f32> {
    /// The closest hit among items `first..first + count`, merged into `best`.
    fn intersect_leaf(&self, first: usize, count: usize, best: &mut HitPacket<f32>);
    /// Whether an item among `first..first + count` blocks the ray.
    fn occluded_leaf(&self, first: usize, count: usize, blocker: &mut u32) -> bool;
}

/// Subtrees that a packet enters with at most this many live lanes are walked one ray at a time (measured:
/// docs/perf-log/2026-11.md, "Single-ray switch").
pub(crate) const SINGLE_RAY_MAX_LANES: u32 = 2;

/// The BVH: `nodes[0]` is the root.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    /// Flattened nodes, depth-first.
    pub(crate) nodes: Vec<Node>,
    /// Subtrees entered by at most this many live lanes of a packet are walked one ray at a time
    /// (`SINGLE_RAY_MAX_LANES` by default; 0 never switches).
    pub(crate) single_ray_lanes: u32,
    /// Test each node's children and each leaf's spheres against a shared-origin packet as a whole (its
    /// frustum) before their lanes. On by default (docs/perf-log/2026-11.md, "Frustum culling").
    pub(crate) frustum_culling: bool,
    /// The largest coordinate magnitude of any box: bounds the frustum test's rounding.
    pub(crate) extent: f32,
    /// The padding the spheres' boxes were built with ([`padding`]): the frustum's sphere test pads by it too.
    pub(crate) pad: f32,
    /// The same tree in 8-wide nodes for rays walked alone ([`WideNode`]), when the scene traces secondary or
    /// ambient-occlusion rays.
    pub(crate) wide: Option<Vec<WideNode>>,
    /// Parent links of [`Bvh::nodes`] and of [`Bvh::wide`], and the leaf of every item in each, for walks
    /// that start at the leaves of the items their rays leave; built with the single-ray tree.
    pub(crate) up: Option<(upward::Upward, upward::Upward)>,
    /// Where each subtree of [`Bvh::nodes`] lies in [`Bvh::wide`], so that a packet walk's lanes walk a sparse
    /// subtree alone over the 8-wide nodes; built with the single-ray tree.
    pub(crate) wide_starts: Option<wide_starts::WideStarts>,
    /// The binary tree before the collapse, in nodes of the scalar walk ([`PairNode`]), when the build was
    /// asked for it (`BuildOptions::scalar_tree`).
    pub(crate) scalar: Option<Vec<PairNode>>,
    /// Single rays (K = 1) walk [`Bvh::scalar`], one box and one item at a time, instead of the wide nodes
    /// (`--lanes scalar`). Has no effect without that tree.
    pub(crate) scalar_walk: bool,
}

impl Bvh {
    /// Bytes of the node arrays (the packet tree, and the single-ray and scalar trees, if built), of the
    /// trees' parent and leaf links ([`Bvh::up`]) and of [`Bvh::wide_starts`], if built.
    pub(crate) fn bytes(&self) -> usize {
        let wide = self.wide.as_ref().map_or(0, |w| w.len() * size_of::<WideNode>());
        let links = self.up.as_ref().map_or(0, |(packet, single)| packet.bytes() + single.bytes())
            + self.wide_starts.as_ref().map_or(0, |w| w.bytes());
        let scalar = self.scalar.as_ref().map_or(0, |s| s.len() * size_of::<PairNode>());
        self.nodes.len() * size_of::<Node>() + wide + links + scalar
    }

    /// The links of the single-ray tree ([`Bvh::up`]), when built.
    fn single_links(&self) -> Option<&upward::Upward> {
        self.up.as_ref().map(|(_, single)| single)
    }

    /// Whether single rays walk the scalar tree ([`Bvh::scalar_walk`]): one item at a time.
    pub(crate) fn walks_scalar(&self) -> bool {
        self.scalar_nodes().is_some()
    }

    /// The scalar tree, when single rays walk it ([`Bvh::scalar_walk`]).
    fn scalar_nodes(&self) -> Option<&[PairNode]> {
        self.scalar.as_deref().filter(|_| self.scalar_walk)
    }

    /// Closest hits of the spheres for the live lanes, merged into `best`: one ray at a time for K = 1 (the
    /// scalar walk when set, [`Bvh::scalar_walk`]), else the packet traversal, which switches to single rays
    /// in sparse subtrees.
    pub(crate) fn intersect_k<F: Lanes, Q: LeafQuery<F>>(
        &self,
        q: &Q,
        live: F::Mask,
        best: &mut HitPacket<F>,
    ) {
        if F::K == 1 {
            if let Some(nodes) = self.scalar_nodes() {
                return self.intersect_scalar(nodes, q, live, best);
            }
            return self.intersect_lanes(q, live, best);
        }
        self.intersect_packet(q, live, best)
    }

    /// Closest hits with every live lane walked alone (over the 8-wide tree when the scene has one: from the
    /// leaf of the item a lane leaves where the tree has links, else from the root): K = 1's walk, and for
    /// wider packets the same bits as [`Bvh::intersect_k`], for packets whose lanes go apart at once.
    pub(crate) fn intersect_lanes<F: Lanes, Q: LeafQuery<F>>(
        &self,
        q: &Q,
        live: F::Mask,
        best: &mut HitPacket<F>,
    ) {
        let slab = SlabRay::new(q.ray());
        match &self.wide {
            Some(wide) => {
                self.intersect_each(wide, self.single_links(), Subtree::WHOLE, q, &slab, live, best)
            }
            None => self.intersect_each(&self.nodes, None, Subtree::WHOLE, q, &slab, live, best),
        }
    }

    /// Lanes of `live` blocked by a sphere within their `t_max`, like [`Bvh::intersect_k`]. `blocker` is set
    /// to a sphere that blocked a lane.
    pub(crate) fn occluded_k<F: Lanes, Q: LeafQuery<F>>(
        &self,
        q: &Q,
        live: F::Mask,
        blocker: &mut u32,
    ) -> F::Mask {
        if F::K == 1 {
            if let Some(nodes) = self.scalar_nodes() {
                return self.occluded_scalar(nodes, q, live, blocker);
            }
            let slab = SlabRay::new(q.ray());
            return match &self.wide {
                Some(wide) => {
                    self.occluded_each(wide, self.single_links(), Subtree::WHOLE, q, &slab, live, blocker)
                }
                None => self.occluded_each(&self.nodes, None, Subtree::WHOLE, q, &slab, live, blocker),
            };
        }
        self.occluded_packet(q, live, blocker)
    }
}

/// What building cost.
#[derive(Clone, Copy, Debug, Default)]
pub struct BuildStats {
    /// Seconds building the binary tree, collapsing it and reordering the items.
    pub seconds: f64,
    /// Bytes of the node array.
    pub(crate) node_bytes: usize,
}

impl std::ops::AddAssign for BuildStats {
    fn add_assign(&mut self, o: BuildStats) {
        self.seconds += o.seconds;
        self.node_bytes += o.node_bytes;
    }
}

/// The padding that keeps culling conservative: the sphere kernel may accept a ray passing up to a few ulps
/// of the ray's distance outside the sphere, and that distance is at most about the scene's extent `reach`
/// (the largest coordinate magnitude of any sphere, light or camera ray start); the fused slab test may move
/// a box plane by up to one more ulp of it (`slab::WIDEN`). 64 ulps is ample and far below any sphere the
/// scene can resolve.
pub(crate) fn padding(reach: f32) -> f32 {
    reach * (64.0 * f32::EPSILON)
}
