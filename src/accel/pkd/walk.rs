//! Walking the particle tree with a packet of K rays (K = 1: one ray, in plain f32): closest hits and
//! occlusion. Each stack entry is a range with its box, computed on the way down (the parent's box cut at the
//! split plane widened by the largest radius and twice the padding), and each lane's distances into and out
//! of that box. A child's box differs from its parent's in one plane, so its distances are the parent's
//! clipped by that one plane's: the slab test of the whole box, plane by plane, in two fused multiply-adds
//! per node (the same plane distances, so the same conservative bound, [`WIDEN`]). A box is tested against
//! the packet's frustum first when it has one (camera rays: [`Frustum`]); a popped range is skipped by every
//! lane that has found a hit nearer than its entry. The near child is popped first, by the sign of the first
//! live lane's direction on the node's axis.

use super::{eye_term_of, place, with_records, Particles, Record, Records, LEAF};
use crate::accel::{add_work, counting, Work};
use crate::bvh::{Frustum, SlabRays, Stack, WIDEN};
use crate::geometry::{
    first_root, sphere_approach, sphere_roots_of, DeparturePacket, EyeLanes, HitPacket, RayPacket, SphereRay,
};
use crate::math::{Mask, Vec3f};
use crate::simd::{IdLanes, Lanes};

/// One pending range: positions `lo..hi`, its box, and each lane's distances into and out of the box
/// (`enter` is `inf` in lanes that do not enter it).
#[derive(Clone, Copy)]
struct Entry<F> {
    lo: u32,
    hi: u32,
    min: [f32; 3],
    max: [f32; 3],
    enter: F,
    exit: F,
}

/// A packet's query of the tree: the rays prepared for sphere and slab tests.
pub(super) struct Query<'a, F: Lanes, R> {
    tree: &'a Particles,
    recs: &'a [R],
    terms: SphereRay<F>,
    eye: EyeLanes<F::Mask>,
    /// Whether the kernel reads eye terms for these rays (they are computed only then).
    eye_terms: bool,
    slab: SlabRays<F>,
    frustum: Option<Frustum>,
    t_max: F,
    /// The departure primitive of each lane.
    skip: F::Ids,
    /// The id of position 0.
    base: u32,
}

impl<'a, F: Lanes, R: Record> Query<'a, F, R> {
    pub(super) fn new(
        tree: &'a Particles,
        recs: &'a [R],
        rays: &RayPacket<F>,
        from: &DeparturePacket<F>,
        base: u32,
    ) -> Self {
        let ray = rays.ray();
        let terms = SphereRay::new(*ray);
        let eye = EyeLanes::of(terms.from_eye(), rays.active);
        Self {
            tree,
            recs,
            terms,
            eye,
            eye_terms: tree.eye_terms_help || !matches!(eye, EyeLanes::None),
            slab: SlabRays::new(ray),
            frustum: rays.pyramid.map(|p| Frustum::new(&p, tree.extent())),
            t_max: rays.t_max,
            skip: from.prim,
            base,
        }
    }

    /// The sphere at position `i` (centre `c` in rendering space, radius `r`: [`place`]) for the lanes of
    /// `live`: the lanes it is hit in (the departure sphere excluded) and their t; `None` when no live
    /// lane's line meets it. The sphere kernel's operations, as [`crate::accel::SphereQuery`] runs them.
    #[inline(always)]
    pub(super) fn placed_sphere(&self, i: usize, c: Vec3f, r: f32, live: F::Mask) -> Option<(F::Mask, F)> {
        // A sphere wholly outside the packet's frustum is missed by every lane (the BVH's leaf test).
        if self.frustum.as_ref().is_some_and(|f| !f.may_meet(c, r + self.tree.pad)) {
            return None;
        }
        let centre = F::splat_v3(c);
        let line = sphere_approach(centre, F::splat_f32(r), &self.terms);
        if !(line.meets() & live).any() {
            return None;
        }
        let c_eye = if self.eye_terms { eye_term_of(&self.recs[i], self.tree.origin) as f32 } else { 0.0 };
        let roots = sphere_roots_of(
            self.tree.eye_terms_help,
            &line,
            || centre,
            F::splat_f32(c_eye),
            &self.terms,
            self.eye,
        );
        let (hit, t) = first_root(&roots, self.t_max);
        Some((live & hit & !F::ids_eq(F::Ids::splat(self.base + i as u32), self.skip), t))
    }

    /// The root's entry, if some live lane enters its box: the slab test, plane by plane.
    fn root(&self, live: F::Mask) -> Option<Entry<F>> {
        let [min, max] = self.tree.bounds;
        let (inv, neg) = (&self.slab.inv_dir, &self.slab.neg_o_inv);
        let axes = [(inv.x, neg.x), (inv.y, neg.y), (inv.z, neg.z)];
        let (mut enter, mut exit) = (F::splat_f32(0.0), F::splat_f32(f32::INFINITY));
        for (a, (inv, neg)) in axes.into_iter().enumerate() {
            let t_min = F::splat_f32(min[a]).mul_add(inv, neg);
            let t_max = F::splat_f32(max[a]).mul_add(inv, neg);
            enter = enter.fast_max(t_min.fast_min(t_max));
            exit = exit.fast_min(t_min.fast_max(t_max));
        }
        let e = Entry { lo: 0, hi: self.recs.len() as u32, min, max, enter, exit };
        self.admit(e, self.t_max, live)
    }

    /// `e` with `enter` set to `inf` in the lanes that are not live or do not enter its box before `limit`;
    /// `None` when no lane does, the range is empty or the frustum rules the box out.
    #[inline(always)]
    fn admit(&self, mut e: Entry<F>, limit: F, live: F::Mask) -> Option<Entry<F>> {
        if e.lo >= e.hi || self.frustum.as_ref().is_some_and(|f| !f.may_enter(e.min, e.max)) {
            return None;
        }
        let inside = live & e.enter.le((e.exit * F::splat_f32(WIDEN)).fast_min(limit));
        e.enter = F::select(inside, e.enter, F::splat_f32(f32::INFINITY));
        inside.any().then_some(e)
    }

    /// The two children of the node of `e` (its middle position `mid`), near one last.
    #[inline(always)]
    fn children(
        &self,
        e: &Entry<F>,
        mid: usize,
        c: Vec3f,
        limit: F,
        live: F::Mask,
        stack: &mut Stack<Entry<F>>,
    ) {
        let axis = self.tree.axis(mid);
        let (plane, inv, neg, dir) = match axis {
            0 => (c.x, self.slab.inv_dir.x, self.slab.neg_o_inv.x, self.terms.ray.dir.x),
            1 => (c.y, self.slab.inv_dir.y, self.slab.neg_o_inv.y, self.terms.ray.dir.y),
            _ => (c.z, self.slab.inv_dir.z, self.slab.neg_o_inv.z, self.terms.ray.dir.z),
        };
        let reach = self.tree.split_reach();
        let (top, bottom) = (plane + reach, plane - reach);
        // The lower child's upper plane and the upper child's lower plane, each inside the parent's box.
        let (mut below, mut above) = (*e, *e);
        below.hi = mid as u32;
        above.lo = mid as u32 + 1;
        below.max[axis] = below.max[axis].min(top);
        above.min[axis] = above.min[axis].max(bottom);
        let t_top = F::splat_f32(top).mul_add(inv, neg);
        let t_bottom = F::splat_f32(bottom).mul_add(inv, neg);
        // Where the ray runs up the axis it leaves the lower child at its top and enters the upper one at
        // its bottom; running down, it enters the lower child at its top and leaves the upper one at its bottom.
        let up = inv.ge(F::splat_f32(0.0));
        below.exit = F::select(up, e.exit.fast_min(t_top), e.exit);
        below.enter = F::select(up, e.enter, e.enter.fast_max(t_top));
        above.enter = F::select(up, e.enter.fast_max(t_bottom), e.enter);
        above.exit = F::select(up, e.exit, e.exit.fast_min(t_bottom));
        let below = self.admit(below, limit, live);
        let above = self.admit(above, limit, live);
        let first = (F::move_mask(live).trailing_zeros() as usize).min(F::K - 1);
        let (near, far) = if dir.lane(first) < 0.0 { (above, below) } else { (below, above) };
        for e in [far, near].into_iter().flatten() {
            stack.push(e);
        }
    }

    /// Closest hits of the lanes of `live`, merged into `best`.
    fn intersect(&self, live: F::Mask, best: &mut HitPacket<F>) {
        let mut stack = Stack::new();
        stack.push_some(self.root(live));
        let (mut spheres, mut boxes) = (0, 1);
        // Live rays are summed only when counting (a mask count per visit otherwise spent).
        let counting = counting();
        let (mut sphere_lanes, mut box_lanes) = (0, F::move_mask(live).count_ones() as usize);
        while let Some(e) = stack.pop() {
            let open = live & e.enter.lt(F::splat_f32(f32::INFINITY)) & e.enter.le(best.t);
            if !open.any() {
                continue;
            }
            let lane_count = if counting { F::move_mask(open).count_ones() as usize } else { 0 };
            let (lo, hi) = (e.lo as usize, e.hi as usize);
            let mut test = |i: usize, c: Vec3f, r: f32| {
                if let Some((hit, t)) = self.placed_sphere(i, c, r, open) {
                    let key = self.tree.key(i);
                    best.update(hit, t, F::Ids::splat(self.base + i as u32), F::Ids::splat(key));
                }
            };
            if hi - lo <= LEAF {
                for i in lo..hi {
                    let (c, r) = place(&self.recs[i], self.tree.origin);
                    test(i, c, r);
                }
                spheres += hi - lo;
                sphere_lanes += (hi - lo) * lane_count;
                continue;
            }
            let mid = lo + (hi - lo) / 2;
            let (c, r) = place(&self.recs[mid], self.tree.origin);
            test(mid, c, r);
            spheres += 1;
            boxes += 2;
            sphere_lanes += lane_count;
            box_lanes += 2 * lane_count;
            self.children(&e, mid, c, best.t.fast_min(self.t_max), open, &mut stack);
        }
        if counting {
            add_work(Work::lanes(spheres, sphere_lanes, boxes, box_lanes));
        }
    }

    /// Lanes of `live` blocked by some sphere; stops when every live lane is.
    fn occluded(&self, live: F::Mask) -> F::Mask {
        let mut blocked = F::mask_from_bits(0);
        let mut stack = Stack::new();
        stack.push_some(self.root(live));
        let (mut spheres, mut boxes) = (0, 1);
        // Live rays are summed only when counting (a mask count per visit otherwise spent).
        let counting = counting();
        let (mut sphere_lanes, mut box_lanes) = (0, F::move_mask(live).count_ones() as usize);
        while let Some(e) = stack.pop() {
            let open = live & !blocked & e.enter.lt(F::splat_f32(f32::INFINITY));
            if !open.any() {
                continue;
            }
            let lane_count = if counting { F::move_mask(open).count_ones() as usize } else { 0 };
            let (lo, hi) = (e.lo as usize, e.hi as usize);
            let leaf = hi - lo <= LEAF;
            let mid = lo + (hi - lo) / 2;
            let tested = if leaf { lo..hi } else { mid..mid + 1 };
            spheres += tested.len();
            sphere_lanes += tested.len() * lane_count;
            let mut centre = None;
            for i in tested {
                let (c, r) = place(&self.recs[i], self.tree.origin);
                centre = Some(c);
                if let Some((hit, _)) = self.placed_sphere(i, c, r, open) {
                    blocked = blocked | hit;
                }
            }
            if (blocked | !live).all() {
                break;
            }
            if let (false, Some(c)) = (leaf, centre) {
                boxes += 2;
                box_lanes +=
                    2 * if counting { F::move_mask(live & !blocked).count_ones() as usize } else { 0 };
                self.children(&e, mid, c, self.t_max, live & !blocked, &mut stack);
            }
        }
        if counting {
            add_work(Work::lanes(spheres, sphere_lanes, boxes, box_lanes));
        }
        blocked
    }
}

impl<E: Copy> Stack<E> {
    /// Pushes `e` if there is one.
    #[inline(always)]
    fn push_some(&mut self, e: Option<E>) {
        if let Some(e) = e {
            self.push(e);
        }
    }
}

impl Particles {
    /// Closest hits of the packet's active lanes with the tree's spheres (ids from `base`), merged into
    /// `best`; the departure sphere of each lane (`from.prim`) is never reported.
    pub(crate) fn intersect_k<F: Lanes>(
        &self,
        rays: &RayPacket<F>,
        from: &DeparturePacket<F>,
        base: u32,
        best: &mut HitPacket<F>,
    ) {
        if self.is_empty() || !rays.active.any() {
            return;
        }
        with_records!(&self.records, |recs| Query::new(self, recs, rays, from, base)
            .intersect(rays.active, best))
    }

    /// Lanes of `live` blocked by one of the tree's spheres (ids from `base`) in `[0, t_max)`.
    pub(crate) fn occluded_k<F: Lanes>(
        &self,
        rays: &RayPacket<F>,
        from: &DeparturePacket<F>,
        base: u32,
        live: F::Mask,
    ) -> F::Mask {
        if self.is_empty() || !live.any() {
            return F::mask_from_bits(0);
        }
        with_records!(&self.records, |recs| Query::new(self, recs, rays, from, base).occluded(live))
    }
}
