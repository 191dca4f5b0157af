//! Single-ray traversal over the same 4-wide nodes, SIMD over the children: one ray's slab test against all
//! four boxes of a node in one `f32x4` pass. It serves K = 1 and every subtree that a packet enters with few
//! live lanes (incoherent secondary rays after a bounce, and camera packets that have spread over many small
//! spheres deep in the tree), where the packet traversal would carry mostly dead lanes: each live lane then
//! walks the subtree alone, and its result is merged back into its lane (Embree's "hybrid" traversal).

use wide::f32x4;

use super::super::brute::SphereQuery;
use super::super::count_work;
use super::{far_to_near, near_side, slab_entry_ordered, Bvh, Node, SlabRay, Stack, N};
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

/// One ray prepared for slab tests against four boxes at once: lane `i` of a prepared packet (whose lanes
/// hold the bits a scalar ray's preparation gives) splatted.
struct SlabRay4 {
    ray: SlabRay<f32x4>,
    /// Per axis, the side of the near plane ([`near_side`]).
    near: [usize; 3],
}

impl SlabRay4 {
    fn lane<F: Lanes>(packet: &SlabRay<F>, i: usize) -> Self {
        let lane = |v: &V3<F>| [v.x.lane(i), v.y.lane(i), v.z.lane(i)];
        let (inv, neg_o_inv) = (lane(&packet.inv_dir), lane(&packet.neg_o_inv));
        let splat = |v: [f32; 3]| V3::new(f32x4::splat(v[0]), f32x4::splat(v[1]), f32x4::splat(v[2]));
        Self { ray: SlabRay { inv_dir: splat(inv), neg_o_inv: splat(neg_o_inv) }, near: inv.map(near_side) }
    }

    /// The ray's entry distance into each child of `n`, `inf` where it misses the child or enters beyond
    /// `limit`: the packet traversal's slab test, one child per lane.
    #[inline(always)]
    fn enter(&self, n: &Node, limit: f32) -> f32x4 {
        let planes = |side: [usize; 3]| [0, 1, 2].map(|a| f32x4::from(n.bounds[side[a]][a]));
        let far = self.near.map(|s| 1 - s);
        slab_entry_ordered(planes(self.near), planes(far), &self.ray, f32x4::splat(limit))
    }
}

impl Bvh {
    /// Of the children of `n` the ray enters within `limit`, pushes all but the nearest (farthest first) and
    /// returns that one, to be visited next.
    #[inline(always)]
    fn push_but_nearest(
        &self,
        n: &Node,
        ray: &SlabRay4,
        limit: f32,
        stack: &mut Stack<Entry>,
    ) -> Option<Entry> {
        let near = ray.enter(n, limit);
        // Bit c for each child entered; empty slots (boxes at +inf) never are.
        let entered = f32x4::move_mask(Real::lt(near, f32x4::splat(f32::INFINITY)));
        let near = near.to_array();
        let entry = |c: usize| Entry { child: n.child[c], count: n.count[c], near: near[c] };
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
        let mut order = [(0.0, 0); N];
        let mut hits = 0;
        for c in (0..N).filter(|c| entered >> c & 1 == 1) {
            order[hits] = (near[c], c);
            hits += 1;
        }
        far_to_near(&mut order[..hits]);
        let (nearest, farther) = order[..hits].split_last()?;
        farther.iter().for_each(|&(_, c)| stack.push(entry(c)));
        Some(entry(nearest.1))
    }

    /// The closest hit of one ray in the subtree of node `root` (which the ray enters), merged into `best`.
    fn intersect_1(&self, root: u32, q: &SphereQuery<f32>, slab: &SlabRay4, best: &mut HitPacket<f32>) {
        let mut stack = Stack::<Entry>::new();
        let mut next =
            self.push_but_nearest(&self.nodes[root as usize], slab, best.t.min(q.t_max), &mut stack);
        let (mut nodes, mut prims) = (1, 0);
        while let Some(e) = next.take().or_else(|| stack.pop()) {
            if e.near > best.t {
                continue;
            }
            if e.count > 0 {
                let first = e.child as usize;
                prims += usize::from(e.count);
                q.intersect_leaf(first, usize::from(e.count), best);
            } else {
                nodes += 1;
                let n = &self.nodes[e.child as usize];
                next = self.push_but_nearest(n, slab, best.t.min(q.t_max), &mut stack);
            }
        }
        count_work(prims, N * nodes);
    }

    /// Whether one ray is blocked within `t_max` in the subtree of node `root`; stops at the first blocker
    /// found, left in `blocker`.
    fn occluded_1(&self, root: u32, q: &SphereQuery<f32>, slab: &SlabRay4, blocker: &mut u32) -> bool {
        let mut stack = Stack::<Entry>::new();
        let mut next = self.push_but_nearest(&self.nodes[root as usize], slab, q.t_max, &mut stack);
        let (mut nodes, mut prims, mut blocked) = (1, 0, false);
        while let Some(e) = next.take().or_else(|| stack.pop()) {
            if e.count > 0 {
                let first = e.child as usize;
                prims += usize::from(e.count);
                if q.occluded_leaf(first, usize::from(e.count), blocker) {
                    blocked = true;
                    break;
                }
            } else {
                nodes += 1;
                next = self.push_but_nearest(&self.nodes[e.child as usize], slab, q.t_max, &mut stack);
            }
        }
        count_work(prims, N * nodes);
        blocked
    }

    /// The lanes of `lanes` walk the subtree of node `root` one ray at a time; their hits are merged into
    /// `best`. `slab` is the packet prepared for slab tests.
    pub(super) fn intersect_lanes<F: Lanes>(
        &self,
        root: u32,
        q: &SphereQuery<F>,
        slab: &SlabRay<F>,
        lanes: F::Mask,
        best: &mut HitPacket<F>,
    ) {
        let bits = F::move_mask(lanes);
        for i in set_bits(bits) {
            let mut hit = HitPacket { t: best.t.lane(i), prim: best.prim.lane(i), key: best.key.lane(i) };
            self.intersect_1(root, &q.lane(i), &SlabRay4::lane(slab, i), &mut hit);
            let at = F::mask_from_bits(1 << i);
            best.t = F::select(at, F::splat_f32(hit.t), best.t);
            best.prim = F::select_ids(at, F::Ids::splat(hit.prim), best.prim);
            best.key = F::select_ids(at, F::Ids::splat(hit.key), best.key);
        }
    }

    /// The lanes of `lanes` blocked within their `t_max` in the subtree of node `root`, one ray at a time.
    pub(super) fn occluded_lanes<F: Lanes>(
        &self,
        root: u32,
        q: &SphereQuery<F>,
        slab: &SlabRay<F>,
        lanes: F::Mask,
        blocker: &mut u32,
    ) -> F::Mask {
        let bits = F::move_mask(lanes);
        let blocked = set_bits(bits)
            .filter(|&i| self.occluded_1(root, &q.lane(i), &SlabRay4::lane(slab, i), blocker))
            .fold(0, |b, i| b | 1 << i);
        F::mask_from_bits(blocked)
    }
}
