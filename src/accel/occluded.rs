//! Any-hit queries over the geometry (`occluded`): shadow rays toward point lights (through a light's buffer
//! where it has one) and other occlusion packets with a sphere hint, and the K = 1 instances; spheres,
//! particles, then the registered kinds, until every lane is blocked.

use crate::bvh::{Bvh, LeafQuery};
use crate::geometry::{Departure, DeparturePacket, Ray, RayPacket, NO_PRIM};
use crate::kinds::{Kind, KindItems, VisitItems};
use crate::math::Mask;
use crate::simd::Lanes;

use super::{count_work, Geometry, LightBuffer, Work};

/// Lanes of `live` blocked by one of the `n` items of one kind, like intersect.rs's `intersect_items`;
/// `blocker` is set to an item that blocked a lane.
#[inline(always)]
fn occluded_items<F: Lanes, Q: LeafQuery<F>>(
    bvh: Option<&Bvh>,
    q: &Q,
    n: usize,
    live: F::Mask,
    blocker: &mut u32,
) -> F::Mask {
    if !live.any() {
        return live;
    }
    match bvh {
        Some(bvh) => bvh.occluded_k(q, live, blocker),
        None => {
            // Counted as every item, as a visited BVH leaf counts all of its items (the test may stop early).
            count_work(|| Work::lanes(n, n * F::move_mask(live).count_ones() as usize, 0, 0));
            q.occluded(0..n, live, blocker)
        }
    }
}

impl Geometry {
    /// Lanes of the packet whose ray meets anything in its `[0, t_max)` (the departure surface's near side
    /// excluded); inactive lanes are false. The renderer asks through [`Geometry::occluded_hinted_k`] and
    /// [`Geometry::shadowed_k`]; the tests ask here.
    #[cfg(test)]
    pub(crate) fn occluded_k<F: Lanes>(&self, rays: &RayPacket<F>, from: &DeparturePacket<F>) -> F::Mask {
        let mut hint = NO_PRIM;
        self.occluded_hinted_k(rays, from, &mut hint)
    }

    /// Lanes of the packet whose ray meets anything in its `[0, t_max)` (the departure surface's near side
    /// excluded; inactive lanes are false). The sphere `hint` is tested first (a blocker of an earlier, nearby
    /// packet: neighbouring shadow rays tend to be blocked by the same sphere), and `hint` is left holding a
    /// sphere that blocked some lane this time. The answer is the same whatever the hint: it only decides
    /// what is tested first.
    pub(crate) fn occluded_hinted_k<F: Lanes>(
        &self,
        rays: &RayPacket<F>,
        from: &DeparturePacket<F>,
        hint: &mut u32,
    ) -> F::Mask {
        self.occluded_through(rays, from, hint, None)
    }

    /// [`Geometry::occluded_hinted_k`] for shadow rays toward point light `light` (rays from their hit
    /// points, `t_max` the distance to the light): the spheres are found through the light's buffer when it
    /// has one ([`LightBuffer`]), with the same answer.
    pub(crate) fn shadowed_k<F: Lanes>(
        &self,
        rays: &RayPacket<F>,
        from: &DeparturePacket<F>,
        hint: &mut u32,
        light: usize,
    ) -> F::Mask {
        self.occluded_through(rays, from, hint, self.light_buffers.get(light).and_then(Option::as_ref))
    }

    /// [`Geometry::occluded_hinted_k`], the spheres through `buffer` when given.
    #[inline(always)]
    fn occluded_through<F: Lanes>(
        &self,
        rays: &RayPacket<F>,
        from: &DeparturePacket<F>,
        hint: &mut u32,
        buffer: Option<&LightBuffer>,
    ) -> F::Mask {
        let live = rays.active;
        if !live.any() {
            return live;
        }
        let mut blocked = F::mask_from_bits(0);
        if !self.spheres.is_empty() {
            let q = self.sphere_query(rays, from);
            if (*hint as usize) < self.spheres.len() {
                let h = *hint as usize;
                count_work(|| Work::lanes(1, F::move_mask(live).count_ones() as usize, 0, 0));
                blocked = q.occluded(h..h + 1, live, hint);
                if (blocked | !live).all() {
                    return blocked;
                }
            }
            let open = live & !blocked;
            blocked = blocked
                | match (buffer, self.sphere_bvh.as_ref()) {
                    (Some(buffer), Some(bvh)) => buffer.occluded(&q, open, bvh.walks_scalar(), hint),
                    (_, bvh) => occluded_items(bvh, &q, self.spheres.len(), open, hint),
                };
            if (blocked | !live).all() {
                return blocked;
            }
        }
        if !self.particles.is_empty() {
            let base = self.spheres.len() as u32;
            blocked = blocked | self.particles.occluded_k(rays, from, base, live & !blocked);
            if (blocked | !live).all() {
                return blocked;
            }
        }
        if self.kinds.has_items() && !(blocked | !live).all() {
            let base = self.kinds_base() as u32;
            let mut visit = OccludedKinds { rays, from, live, blocked, base };
            self.kinds.visit(&mut visit);
            blocked = visit.blocked;
        }
        blocked | self.departure_exits_k(rays, from).0
    }

    /// Whether one ray meets anything in `[0, t_max)`: the K = 1 instance of [`Geometry::occluded_k`].
    #[cfg(test)]
    pub(crate) fn occluded(&self, ray: &Ray<f32>, from: Departure, t_max: f32) -> bool {
        let rays = RayPacket::<f32>::new(ray.origin, ray.dir, t_max, true);
        self.occluded_k(&rays, &DeparturePacket { prim: from.prim, inward: from.inward })
    }

    /// Whether one shadow ray toward point light `light` (from its hit point, `t_max` the distance to the
    /// light) is blocked: the K = 1 instance of [`Geometry::shadowed_k`], through the light's buffer.
    pub(crate) fn shadowed(&self, ray: &Ray<f32>, from: Departure, t_max: f32, light: usize) -> bool {
        let rays = RayPacket::<f32>::new(ray.origin, ray.dir, t_max, true);
        let (from, mut hint) = (DeparturePacket { prim: from.prim, inward: from.inward }, NO_PRIM);
        self.shadowed_k(&rays, &from, &mut hint, light)
    }
}

/// The lanes of a packet the registered kinds block, added to `blocked`, kind by kind until all are.
struct OccludedKinds<'a, F: Lanes> {
    rays: &'a RayPacket<F>,
    from: &'a DeparturePacket<F>,
    live: F::Mask,
    blocked: F::Mask,
    /// The id of the kinds' first primitive.
    base: u32,
}

impl<F: Lanes> VisitItems for OccludedKinds<'_, F> {
    #[inline(always)]
    fn visit<K: Kind>(&mut self, items: &KindItems<K>, first: u32) {
        let (open, base) = (self.live & !self.blocked, self.base + first);
        if open.any() {
            let blocked = match K::INLINE_QUERIES {
                true => occluded_kind_here(items, base, self.rays, self.from, open),
                false => occluded_kind(items, base, self.rays, self.from, open),
            };
            self.blocked = self.blocked | blocked;
        }
    }
}

/// The lanes of `open` one kind blocks: a function of each kind's own, its tree walk another, as for
/// intersect.rs's `intersect_kind`.
#[inline(never)]
fn occluded_kind<F: Lanes, K: Kind>(
    items: &KindItems<K>,
    base: u32,
    rays: &RayPacket<F>,
    from: &DeparturePacket<F>,
    open: F::Mask,
) -> F::Mask {
    let q = || Geometry::item_query(items.items(base), rays, from);
    let mut item = 0;
    match &items.bvh {
        Some(bvh) => occluded_tree(bvh, &q(), open),
        None => occluded_items(None, &q(), items.len(), open, &mut item),
    }
}

/// [`occluded_kind`] inlined where it is asked, for a kind whose queries are small
/// ([`Kind::INLINE_QUERIES`]).
#[inline(always)]
fn occluded_kind_here<F: Lanes, K: Kind>(
    items: &KindItems<K>,
    base: u32,
    rays: &RayPacket<F>,
    from: &DeparturePacket<F>,
    open: F::Mask,
) -> F::Mask {
    let (q, mut item) = (Geometry::item_query(items.items(base), rays, from), 0);
    occluded_items(items.bvh.as_ref(), &q, items.len(), open, &mut item)
}

/// [`occluded_kind`]'s tree walk.
#[inline(never)]
fn occluded_tree<F: Lanes, Q: LeafQuery<F>>(bvh: &Bvh, q: &Q, open: F::Mask) -> F::Mask {
    let mut item = 0;
    bvh.occluded_k(q, open, &mut item)
}
