//! Single-ray traversal over the same 4-wide nodes, SIMD over the children: one ray's slab test against all
//! four boxes of a node in one `f32x4` pass. It serves K = 1 and packets with few live lanes (incoherent
//! secondary rays after a bounce), where the packet traversal would carry mostly dead lanes: each live lane
//! then walks the tree alone, and its result is merged back into its lane.

use wide::f32x4;

use super::super::brute::SphereQuery;
use super::super::count_work;
use super::{far_to_near, near_side, slab_entry_ordered, Bvh, Node, SlabRay, Stack, N};
use crate::geometry::{HitPacket, Ray};
use crate::simd::{IdLanes, Lanes};

/// Packets with at most this many live lanes are traced one ray at a time (measured: PERF.md, "Single-ray
/// switch").
pub const SINGLE_RAY_MAX_LANES: u32 = 2;

/// A pending subtree of the single-ray traversal and the ray's entry distance.
#[derive(Clone, Copy)]
struct Entry {
    child: u32,
    count: u8,
    near: f32,
}

/// One ray prepared for slab tests against four boxes at once: prepared as a scalar ray (the packet
/// traversal's lanes get the same values) and splatted.
struct SlabRay4 {
    ray: SlabRay<f32x4>,
    /// Per axis, the side of the near plane ([`near_side`]).
    near: [usize; 3],
}

impl SlabRay4 {
    fn new(ray: &Ray<f32>) -> Self {
        let s = SlabRay::new(&ray.origin, &ray.dir);
        let inv = s.inv_dir;
        Self {
            ray: SlabRay { inv_dir: inv.map(f32x4::splat), neg_o_inv: s.neg_o_inv.map(f32x4::splat) },
            near: [near_side(inv.x), near_side(inv.y), near_side(inv.z)],
        }
    }

    /// The ray's entry distance into each child of `n`, `inf` where it misses the child or enters beyond
    /// `limit`: the packet traversal's slab test, one child per lane.
    #[inline(always)]
    fn enter(&self, n: &Node, limit: f32) -> [f32; N] {
        let planes = |side: [usize; 3]| [0, 1, 2].map(|a| f32x4::from(n.bounds[side[a]][a]));
        let far = self.near.map(|s| 1 - s);
        slab_entry_ordered(planes(self.near), planes(far), &self.ray, f32x4::splat(limit)).to_array()
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
        let mut order = [(0.0, 0); N];
        let mut hits = 0;
        for (c, &t) in near.iter().enumerate().take(n.slots as usize) {
            if t < f32::INFINITY {
                order[hits] = (t, c);
                hits += 1;
            }
        }
        far_to_near(&mut order[..hits]);
        let entry = |&(near, c): &(f32, usize)| Entry { child: n.child[c], count: n.count[c], near };
        let (nearest, farther) = order[..hits].split_last()?;
        farther.iter().for_each(|e| stack.push(entry(e)));
        Some(entry(nearest))
    }

    /// The closest hit of one ray, merged into `best`.
    fn intersect_1(&self, q: &SphereQuery<f32>, best: &mut HitPacket<f32>) {
        let slab = SlabRay4::new(&q.ray);
        let mut stack = Stack::<Entry>::new();
        let mut next = self.push_but_nearest(&self.nodes[0], &slab, best.t.min(q.t_max), &mut stack);
        let (mut nodes, mut prims) = (1, 0);
        while let Some(e) = next.take().or_else(|| stack.pop()) {
            if e.near > best.t {
                continue;
            }
            if e.count > 0 {
                let first = e.child as usize;
                prims += usize::from(e.count);
                q.intersect(first..first + usize::from(e.count), true, best);
            } else {
                nodes += 1;
                let n = &self.nodes[e.child as usize];
                next = self.push_but_nearest(n, &slab, best.t.min(q.t_max), &mut stack);
            }
        }
        count_work(prims, N * nodes);
    }

    /// Whether one ray is blocked within `t_max`; stops at the first blocker found, left in `blocker`.
    fn occluded_1(&self, q: &SphereQuery<f32>, blocker: &mut u32) -> bool {
        let slab = SlabRay4::new(&q.ray);
        let mut stack = Stack::<Entry>::new();
        let mut next = self.push_but_nearest(&self.nodes[0], &slab, q.t_max, &mut stack);
        let (mut nodes, mut prims, mut blocked) = (1, 0, false);
        while let Some(e) = next.take().or_else(|| stack.pop()) {
            if e.count > 0 {
                let first = e.child as usize;
                prims += usize::from(e.count);
                if q.occluded(first..first + usize::from(e.count), true, blocker) {
                    blocked = true;
                    break;
                }
            } else {
                nodes += 1;
                next = self.push_but_nearest(&self.nodes[e.child as usize], &slab, q.t_max, &mut stack);
            }
        }
        count_work(prims, N * nodes);
        blocked
    }

    /// Closest hits of the spheres for the live lanes, merged into `best`: packet traversal, or one ray at a
    /// time when at most [`SINGLE_RAY_MAX_LANES`] lanes are live.
    pub fn intersect_k<F: Lanes>(&self, q: &SphereQuery<F>, live: F::Mask, best: &mut HitPacket<F>) {
        let bits = F::move_mask(live);
        if F::K > 1 && bits.count_ones() > SINGLE_RAY_MAX_LANES {
            return self.intersect_packet(q, live, best);
        }
        for i in (0..F::K).filter(|i| bits >> i & 1 == 1) {
            let mut hit = HitPacket { t: best.t.lane(i), prim: best.prim.lane(i), key: best.key.lane(i) };
            self.intersect_1(&q.lane(i), &mut hit);
            let at = F::mask_from_bits(1 << i);
            best.t = F::select(at, F::splat_f32(hit.t), best.t);
            best.prim = F::select_ids(at, F::Ids::splat(hit.prim), best.prim);
            best.key = F::select_ids(at, F::Ids::splat(hit.key), best.key);
        }
    }

    /// Lanes of `live` blocked by a sphere within their `t_max`: packet traversal, or one ray at a time when
    /// at most [`SINGLE_RAY_MAX_LANES`] lanes are live. `blocker` is set to a sphere that blocked a lane.
    pub fn occluded_k<F: Lanes>(&self, q: &SphereQuery<F>, live: F::Mask, blocker: &mut u32) -> F::Mask {
        let bits = F::move_mask(live);
        if F::K > 1 && bits.count_ones() > SINGLE_RAY_MAX_LANES {
            return self.occluded_packet(q, live, blocker);
        }
        let blocked = (0..F::K)
            .filter(|i| bits >> i & 1 == 1)
            .filter(|&i| self.occluded_1(&q.lane(i), blocker))
            .fold(0, |b, i| b | 1 << i);
        F::mask_from_bits(blocked)
    }
}
