//! Single-ray traversal over the same 4-wide nodes, SIMD over the children: one ray's slab test against all
//! four boxes of a node in one `f32x4` pass. It serves K = 1 and packets with few live lanes (incoherent
//! secondary rays after a bounce), where the packet traversal would carry mostly dead lanes: each live lane
//! then walks the tree alone, and its result is merged back into its lane.

use wide::f32x4;

use super::super::brute::{spheres_intersect_k, spheres_occluded_k};
use super::super::{count_work, Spheres};
use super::packet::{inverse, WIDEN};
use super::{far_to_near, Bvh, Node, Stack, N};
use crate::geometry::{HitPacket, Ray};
use crate::math::{Real, V3};
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

/// One ray prepared for slab tests against four boxes at once.
struct SlabRay {
    origin: [f32x4; 3],
    inv_dir: [f32x4; 3],
}

impl SlabRay {
    fn new(ray: &Ray<f32>) -> Self {
        let (o, d) = (ray.origin, ray.dir);
        Self {
            origin: [o.x, o.y, o.z].map(f32x4::splat),
            inv_dir: [inverse(d.x), inverse(d.y), inverse(d.z)].map(f32x4::splat),
        }
    }

    /// The ray's entry distance into each child of `n`, `inf` where it misses the child or enters beyond
    /// `limit`: the packet traversal's slab test, one child per lane.
    #[inline(always)]
    fn enter(&self, n: &Node, limit: f32) -> [f32; N] {
        let mut near = f32x4::splat(0.0);
        let mut far = f32x4::splat(f32::INFINITY);
        for a in 0..3 {
            let t0 = (f32x4::from(n.lo[a]) - self.origin[a]) * self.inv_dir[a];
            let t1 = (f32x4::from(n.hi[a]) - self.origin[a]) * self.inv_dir[a];
            near = near.fast_max(t0.fast_min(t1));
            far = far.fast_min(t0.fast_max(t1));
        }
        let inside = near.le(far * f32x4::splat(WIDEN)) & near.le(f32x4::splat(limit));
        <f32x4 as Real>::select(inside, near, f32x4::splat(f32::INFINITY)).to_array()
    }
}

impl Bvh {
    /// Pushes the children of `n` the ray enters within `limit`, the nearest last.
    #[inline(always)]
    fn push_near_last(&self, n: &Node, ray: &SlabRay, limit: f32, stack: &mut Stack<Entry>) {
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
        for &(near, c) in &order[..hits] {
            stack.push(Entry { child: n.child[c], count: n.count[c], near });
        }
    }

    /// The closest hit of one ray, merged into `best`.
    fn intersect_1(&self, s: &Spheres, ray: &Ray<f32>, t_max: f32, skip: u32, best: &mut HitPacket<f32>) {
        let slab = SlabRay::new(ray);
        let mut stack = Stack::<Entry>::new();
        self.push_near_last(&self.nodes[0], &slab, best.t.min(t_max), &mut stack);
        let (mut nodes, mut prims) = (1, 0);
        while let Some(e) = stack.pop() {
            if e.near > best.t {
                continue;
            }
            if e.count > 0 {
                let first = e.child as usize;
                prims += usize::from(e.count);
                spheres_intersect_k(s, first..first + usize::from(e.count), ray, t_max, true, skip, best);
            } else {
                nodes += 1;
                self.push_near_last(&self.nodes[e.child as usize], &slab, best.t.min(t_max), &mut stack);
            }
        }
        count_work(prims, N * nodes);
    }

    /// Whether one ray is blocked within `t_max`; stops at the first blocker found.
    fn occluded_1(&self, s: &Spheres, ray: &Ray<f32>, t_max: f32, skip: u32, blocker: &mut u32) -> bool {
        let slab = SlabRay::new(ray);
        let mut stack = Stack::<Entry>::new();
        self.push_near_last(&self.nodes[0], &slab, t_max, &mut stack);
        let (mut nodes, mut prims, mut blocked) = (1, 0, false);
        while let Some(e) = stack.pop() {
            if e.count > 0 {
                let first = e.child as usize;
                prims += usize::from(e.count);
                if spheres_occluded_k(s, first..first + usize::from(e.count), ray, t_max, true, skip, blocker)
                {
                    blocked = true;
                    break;
                }
            } else {
                nodes += 1;
                self.push_near_last(&self.nodes[e.child as usize], &slab, t_max, &mut stack);
            }
        }
        count_work(prims, N * nodes);
        blocked
    }

    /// Closest hits of the spheres for the live lanes, merged into `best`: packet traversal, or one ray at a
    /// time when at most [`SINGLE_RAY_MAX_LANES`] lanes are live.
    pub fn intersect_k<F: Lanes>(
        &self,
        s: &Spheres,
        ray: &Ray<F>,
        t_max: F,
        live: F::Mask,
        skip: F::Ids,
        best: &mut HitPacket<F>,
    ) {
        let bits = F::move_mask(live);
        if F::K > 1 && bits.count_ones() > SINGLE_RAY_MAX_LANES {
            return self.intersect_packet(s, ray, t_max, live, skip, best);
        }
        for i in (0..F::K).filter(|i| bits >> i & 1 == 1) {
            let mut hit = HitPacket { t: best.t.lane(i), prim: best.prim.lane(i), key: best.key.lane(i) };
            self.intersect_1(s, &lane_ray(ray, i), t_max.lane(i), skip.lane(i), &mut hit);
            let at = F::mask_from_bits(1 << i);
            best.t = F::select(at, F::splat_f32(hit.t), best.t);
            best.prim = F::select_ids(at, F::Ids::splat(hit.prim), best.prim);
            best.key = F::select_ids(at, F::Ids::splat(hit.key), best.key);
        }
    }

    /// Lanes of `live` blocked by a sphere within their `t_max`: packet traversal, or one ray at a time when
    /// at most [`SINGLE_RAY_MAX_LANES`] lanes are live. `blocker` is set to a sphere that blocked a lane.
    pub fn occluded_k<F: Lanes>(
        &self,
        s: &Spheres,
        ray: &Ray<F>,
        t_max: F,
        live: F::Mask,
        skip: F::Ids,
        blocker: &mut u32,
    ) -> F::Mask {
        let bits = F::move_mask(live);
        if F::K > 1 && bits.count_ones() > SINGLE_RAY_MAX_LANES {
            return self.occluded_packet(s, ray, t_max, live, skip, blocker);
        }
        let blocked = (0..F::K)
            .filter(|i| bits >> i & 1 == 1)
            .filter(|&i| self.occluded_1(s, &lane_ray(ray, i), t_max.lane(i), skip.lane(i), blocker))
            .fold(0, |b, i| b | 1 << i);
        F::mask_from_bits(blocked)
    }
}

/// Lane `i` of a ray packet.
fn lane_ray<F: Lanes>(ray: &Ray<F>, i: usize) -> Ray<f32> {
    let v = |p: V3<F>| V3::new(p.x.lane(i), p.y.lane(i), p.z.lane(i));
    Ray::new(v(ray.origin), v(ray.dir))
}
