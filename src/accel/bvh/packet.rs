//! Packet traversal: K rays walk the tree together. A child is entered when any live lane's slab test passes;
//! each stack entry keeps its lanes' entry distances (`inf` for lanes that missed it), so a popped subtree
//! is skipped for every lane that has already hit something nearer. Children are pushed in the node's
//! precomputed order for the octant of the packet's first live lane, so the nearest is popped first.
//!
//! With [`Bvh::interval_culling`], packets whose live lanes share one origin (camera rays) first test each
//! node's children against the whole packet at once by interval arithmetic ([`Interval`]), and run the K-lane
//! slab test only on the children it cannot rule out. It is off by default: on the contract fields the
//! bounds on `1/d` are too loose near the view axis to rule out enough children to pay for themselves.

use wide::f32x4;

use super::super::brute::SphereQuery;
use super::super::count_work;
use super::{slab_entry, slab_entry_ordered, Bvh, Node, SlabRay, Stack, N, WIDEN};
use crate::geometry::{HitPacket, Ray};
use crate::math::{Mask, Real, V3};
use crate::simd::Lanes;

/// A ray packet prepared for slab tests.
struct SlabRays<F: Lanes> {
    slab: SlabRay<F>,
    /// The octant of the first live lane's direction, which orders the children.
    octant: usize,
    /// Per axis, the side of the near plane ([`super::near_side`]), when every live lane's is the same.
    near: Option<[usize; 3]>,
    /// The whole-packet bounds, when asked for and the live lanes share an origin.
    interval: Option<Interval>,
}

impl<F: Lanes> SlabRays<F> {
    fn new(ray: &Ray<F>, live: F::Mask, interval: bool) -> Self {
        let slab = SlabRay::new(ray);
        let first = (F::move_mask(live).trailing_zeros() as usize).min(F::K - 1);
        let negative = |d: F| usize::from(d.lane(first) < 0.0);
        let octant = negative(ray.dir.x) | negative(ray.dir.y) << 1 | negative(ray.dir.z) << 2;
        let interval = if interval { Interval::new(&ray.origin, &slab.inv_dir, live) } else { None };
        let near = Self::shared_near_side(&slab.inv_dir, live);
        Self { slab, octant, near, interval }
    }

    /// The near sides of the live lanes, if they agree on every axis.
    fn shared_near_side(inv: &V3<F>, live: F::Mask) -> Option<[usize; 3]> {
        let bits = F::move_mask(live);
        let side = |v: F| match F::move_mask(v.lt(F::splat_f32(0.0)) & live) {
            0 => Some(0),
            negative if negative == bits => Some(1),
            _ => None,
        };
        Some([side(inv.x)?, side(inv.y)?, side(inv.z)?])
    }

    /// Entry distance of each lane into child `c` of `n`, `inf` where the lane misses it or enters beyond
    /// `limit`.
    #[inline(always)]
    fn enter(&self, n: &Node, c: usize, limit: F) -> F {
        let corner = |v: &[[f32; N]; 3]| [0, 1, 2].map(|a| F::splat_f32(v[a][c]));
        match self.near {
            Some(near) => {
                let plane = |side: [usize; 3]| [0, 1, 2].map(|a| F::splat_f32(n.bounds[side[a]][a][c]));
                slab_entry_ordered(plane(near), plane(near.map(|s| 1 - s)), &self.slab, limit)
            }
            None => slab_entry(corner(n.lo()), corner(n.hi()), &self.slab, limit),
        }
    }
}

/// The packet as one interval ray: a shared origin and, per axis, the range of the live lanes' inverse
/// directions. For a fixed difference `a = lo − o`, the rounded product `a·inv` is monotone in `inv`, so
/// every lane's slab distances lie between the products at the range's ends: a box whose lower bound on
/// entry exceeds its upper bound on exit is missed by every lane, exactly as the
/// lanes' own tests would find. Nothing is culled when a bound is NaN (comparisons are false).
#[derive(Clone, Copy)]
struct Interval {
    origin: [f32; 3],
    inv_lo: [f32; 3],
    inv_hi: [f32; 3],
}

impl Interval {
    fn new<F: Lanes>(origin: &V3<F>, inv: &V3<F>, live: F::Mask) -> Option<Self> {
        let bits = F::move_mask(live);
        if F::K == 1 || bits == 0 {
            return None;
        }
        let first = bits.trailing_zeros() as usize;
        let o = [origin.x.lane(first), origin.y.lane(first), origin.z.lane(first)];
        let same = |v: F, o: f32| v.le(F::splat_f32(o)) & v.ge(F::splat_f32(o));
        if !(same(origin.x, o[0]) & same(origin.y, o[1]) & same(origin.z, o[2]) | !live).all() {
            return None;
        }
        let lo = |v: F| F::select(live, v, F::splat_f32(f32::INFINITY)).reduce_min();
        let hi = |v: F| F::select(live, v, F::splat_f32(f32::NEG_INFINITY)).reduce_max();
        Some(Self {
            origin: o,
            inv_lo: [lo(inv.x), lo(inv.y), lo(inv.z)],
            inv_hi: [hi(inv.x), hi(inv.y), hi(inv.z)],
        })
    }

    /// Bit `c` set for each child of `n` that some lane may enter.
    #[inline(always)]
    fn maybe_entered(&self, n: &Node) -> u32 {
        let mut near = f32x4::splat(0.0);
        let mut far = f32x4::splat(f32::INFINITY);
        for a in 0..3 {
            let o = f32x4::splat(self.origin[a]);
            let (lo, hi) = (f32x4::from(n.lo()[a]) - o, f32x4::from(n.hi()[a]) - o);
            let (i0, i1) = (f32x4::splat(self.inv_lo[a]), f32x4::splat(self.inv_hi[a]));
            let (p0, p1, p2, p3) = (lo * i0, lo * i1, hi * i0, hi * i1);
            near = near.max(p0.min(p1).min(p2.min(p3)));
            far = far.min(p0.max(p1).max(p2.max(p3)));
        }
        !f32x4::move_mask(near.gt(far * f32x4::splat(WIDEN)))
    }
}

/// A pending subtree: its reference and each lane's entry distance.
#[derive(Clone, Copy)]
struct Entry<F: Lanes> {
    child: u32,
    count: u8,
    near: F,
}

impl<F: Lanes> Entry<F> {
    /// The root node, entered by every lane (its box is not tested: its children's are).
    fn root() -> Self {
        Self { child: 0, count: 0, near: F::splat_f32(f32::NEG_INFINITY) }
    }
}

impl Bvh {
    /// Of the children of `n` that some lane enters within its `limit`, pushes all but the nearest (farthest
    /// first) and returns that one, to be visited next without a round trip through the stack. Adds the box
    /// tests to `tests`.
    #[inline(always)]
    fn push_children<F: Lanes>(
        &self,
        n: &Node,
        rays: &SlabRays<F>,
        limit: F,
        stack: &mut Stack<Entry<F>>,
        tests: &mut usize,
    ) -> Option<Entry<F>> {
        let maybe = rays.interval.as_ref().map_or(u32::MAX, |interval| interval.maybe_entered(n));
        let mut nearest = None;
        for c in n.slots_far_to_near(rays.octant).filter(|c| maybe >> c & 1 == 1) {
            *tests += 1;
            let near = rays.enter(n, c, limit);
            if near.lt(F::splat_f32(f32::INFINITY)).any() {
                if let Some(farther) = nearest.replace(Entry { child: n.child[c], count: n.count[c], near }) {
                    stack.push(farther);
                }
            }
        }
        nearest
    }

    /// Closest hits of the spheres for the live lanes, merged into `best`, by packet traversal; subtrees
    /// entered by at most [`Bvh::single_ray_lanes`] live lanes are walked one ray at a time.
    pub(super) fn intersect_packet<F: Lanes>(
        &self,
        q: &SphereQuery<F>,
        live: F::Mask,
        best: &mut HitPacket<F>,
    ) {
        let rays = SlabRays::new(&q.ray, live, self.interval_culling);
        let mut stack = Stack::<Entry<F>>::new();
        let limit = |lanes: F::Mask, best: &HitPacket<F>| {
            F::select(lanes, best.t.min_of(q.t_max), F::splat_f32(f32::NEG_INFINITY))
        };
        // Counted locally and reported once per packet: a shared counter per node costs measurably.
        let (mut boxes, mut prims) = (0, 0);
        let mut next = Some(Entry::root());
        while let Some(e) = next.take().or_else(|| stack.pop()) {
            // Lanes that entered this subtree no farther than their best hit so far.
            let lanes = e.near.le(best.t) & live;
            if !lanes.any() {
                continue;
            }
            if e.count > 0 {
                let first = e.child as usize;
                prims += usize::from(e.count);
                q.intersect(first..first + usize::from(e.count), lanes, best);
            } else if F::move_mask(lanes).count_ones() <= self.single_ray_lanes {
                self.intersect_lanes(e.child, q, &rays.slab, lanes, best);
            } else {
                let n = &self.nodes[e.child as usize];
                next = self.push_children(n, &rays, limit(lanes, best), &mut stack, &mut boxes);
            }
        }
        count_work(prims, boxes);
    }

    /// Lanes of `live` blocked by a sphere within their `t_max`, by packet traversal (subtrees entered by at
    /// most [`Bvh::single_ray_lanes`] unblocked lanes one ray at a time); stops as soon as every live lane is.
    pub(super) fn occluded_packet<F: Lanes>(
        &self,
        q: &SphereQuery<F>,
        live: F::Mask,
        blocker: &mut u32,
    ) -> F::Mask {
        let rays = SlabRays::new(&q.ray, live, self.interval_culling);
        let mut stack = Stack::<Entry<F>>::new();
        let mut blocked = F::mask_from_bits(0);
        let limit = |lanes: F::Mask| F::select(lanes, q.t_max, F::splat_f32(f32::NEG_INFINITY));
        let (mut boxes, mut prims) = (0, 0);
        let mut next = Some(Entry::root());
        while let Some(e) = next.take().or_else(|| stack.pop()) {
            let lanes = e.near.lt(F::splat_f32(f32::INFINITY)) & live & !blocked;
            if !lanes.any() {
                continue;
            }
            if e.count > 0 {
                let first = e.child as usize;
                prims += usize::from(e.count);
                blocked = blocked | q.occluded(first..first + usize::from(e.count), lanes, blocker);
            } else if F::move_mask(lanes).count_ones() <= self.single_ray_lanes {
                blocked = blocked | self.occluded_lanes(e.child, q, &rays.slab, lanes, blocker);
            } else {
                let n = &self.nodes[e.child as usize];
                next = self.push_children(n, &rays, limit(lanes), &mut stack, &mut boxes);
                continue;
            }
            if (blocked | !live).all() {
                break;
            }
        }
        count_work(prims, boxes);
        blocked
    }
}
