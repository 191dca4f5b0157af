//! Ray packets, hit packets and departure packets: K rays, their hits and the primitives they leave, in
//! structure-of-arrays layout.

use crate::math::V3;
use crate::simd::{IdLanes, Lanes};

use super::{Hit, Ray, NO_PRIM};

/// K rays in structure-of-arrays layout: lane `i` of every field belongs to ray `i`.
///
/// With `F = f32x8`, `origin.x` holds the eight origins' x coordinates in one register, `origin.y` the y
/// coordinates, and so on: 6 vectors for the rays, 1 for the ranges and 1 for the mask, so a kernel reads
/// whole registers and never shuffles. `F = f32` is a packet of one ray.
#[derive(Clone, Copy, Debug)]
pub struct RayPacket<F: Lanes> {
    /// The rays: origins and directions (not necessarily unit length). Queries borrow them rather than copy
    /// them (at K = 16 they are 384 bytes).
    pub(crate) ray: Ray<F>,
    /// Exclusive upper end of each ray's range `[0, t_max)`.
    pub(crate) t_max: F,
    /// Lanes that carry a ray; the others are ignored by every kernel and report misses.
    pub(crate) active: F::Mask,
    /// Planes enclosing every active ray, when the packet's maker knows them (camera blocks): the BVH culls
    /// a node's children for the whole packet by them. `None` leaves it to the BVH to find its own.
    pub(crate) pyramid: Option<Pyramid>,
}

/// Four planes through a point that enclose a packet's rays, and an axis the rays run along: every active
/// lane's origin is `apex`, and its direction `d` satisfies `n · d ≥ 0` for each normal `n` and
/// `axis · d > 0`, evaluated exactly on the stored f32 values (whoever builds one widens it past the rounding
/// of the rays and of the normals).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Pyramid {
    /// The rays' shared origin.
    pub(crate) apex: [f32; 3],
    /// Inward normals of the four sides.
    pub(crate) normals: [[f32; 3]; 4],
    /// A direction within 90° of every ray, with room far above rounding: the plane through the apex normal
    /// to it has every ray in front. The four sides are tested one by one against a box's corner farthest
    /// along each, so a large box behind the apex passes all four; this plane rules it out.
    pub(crate) axis: [f32; 3],
}

impl<F: Lanes> RayPacket<F> {
    /// Rays over `[0, t_max)` in the `active` lanes, with no known pyramid.
    #[inline(always)]
    pub(crate) fn new(origin: V3<F>, dir: V3<F>, t_max: F, active: F::Mask) -> Self {
        Self { ray: Ray::new(origin, dir), t_max, active, pyramid: None }
    }

    /// The rays as a [`Ray`] of lanes, the form the generic kernels take.
    #[inline(always)]
    pub(crate) fn ray(&self) -> &Ray<F> {
        &self.ray
    }

    /// Lane `i` gets `f(i) = (ray, t_max, active)`.
    pub(crate) fn from_fn(mut f: impl FnMut(usize) -> (Ray<f32>, f32, bool)) -> Self {
        let lanes: Vec<_> = (0..F::K).map(&mut f).collect();
        let get = |g: fn(&(Ray<f32>, f32, bool)) -> f32| F::from_fn(|i| g(&lanes[i]));
        Self::new(
            V3::new(get(|l| l.0.origin.x), get(|l| l.0.origin.y), get(|l| l.0.origin.z)),
            V3::new(get(|l| l.0.dir.x), get(|l| l.0.dir.y), get(|l| l.0.dir.z)),
            get(|l| l.1),
            F::mask_from_fn(|i| lanes[i].2),
        )
    }

    /// Up to K rays sharing one `t_max`; lanes past `rays.len()` are inactive (and zero).
    pub fn from_rays(rays: &[Ray<f32>], t_max: f32) -> Self {
        assert!(rays.len() <= F::K, "{} rays for {} lanes", rays.len(), F::K);
        let zero = Ray::new(V3::all(0.0), V3::all(0.0));
        Self::from_fn(|i| (rays.get(i).copied().unwrap_or(zero), t_max, i < rays.len()))
    }

    /// Lane `i` as a scalar ray, its `t_max` and whether it is active.
    pub(crate) fn lane(&self, i: usize) -> (Ray<f32>, f32, bool) {
        let v = |p: V3<F>| V3::new(p.x.lane(i), p.y.lane(i), p.z.lane(i));
        (Ray::new(v(self.ray.origin), v(self.ray.dir)), self.t_max.lane(i), F::mask_lane(self.active, i))
    }
}

/// The closest hits of a packet: lane `i` is ray `i`'s [`Hit`] (`t = inf`, `prim = NO_PRIM` on a miss or an
/// inactive lane).
#[derive(Clone, Copy, Debug)]
pub struct HitPacket<F: Lanes> {
    /// Ray parameter of each hit.
    pub(crate) t: F,
    /// Primitive id of each hit.
    pub prim: F::Ids,
    /// The hit primitive's scene-file id, which breaks ties in t: the same order whatever order the
    /// primitives are stored and visited in (a BVH stores spheres in leaf order).
    pub(crate) key: F::Ids,
}

impl<F: Lanes> HitPacket<F> {
    /// No hits in any lane.
    pub(crate) fn miss() -> Self {
        Self { t: F::splat_f32(f32::INFINITY), prim: F::Ids::splat(NO_PRIM), key: F::Ids::splat(NO_PRIM) }
    }

    /// Lanes that hit something. A hit's t is below its `t_max ≤ inf`, so "finite" is "hit".
    #[inline(always)]
    pub fn found(&self) -> F::Mask {
        self.t.lt(F::splat_f32(f32::INFINITY))
    }

    /// Lane `i` as a scalar hit.
    pub fn lane(&self, i: usize) -> Hit {
        Hit { t: self.t.lane(i), prim: self.prim.lane(i) }
    }

    /// Takes the hit `(t, id)` of the primitive with scene-file id `key` in the lanes of `valid` where it is
    /// closer: smaller t, or equal t and a lower file id. The order is total and independent of storage
    /// order, so the closest hit does not depend on the order primitives are stored or visited in — what lets
    /// a packet traversal, which visits nodes in its own order, agree bit for bit with a single ray's, and a
    /// BVH with brute force, ids included.
    #[inline(always)]
    pub(crate) fn update(&mut self, valid: F::Mask, t: F, id: F::Ids, key: F::Ids) {
        let closer = valid & (t.lt(self.t) | (t.le(self.t) & F::ids_lt(key, self.key)));
        self.t = F::select_stored(closer, t, self.t);
        self.prim = F::select_ids(closer, id, self.prim);
        self.key = F::select_ids(closer, key, self.key);
    }
}

/// Where each lane's ray starts: the packet form of [`super::Departure`].
#[derive(Clone, Copy, Debug)]
pub struct DeparturePacket<F: Lanes> {
    /// The primitive each ray leaves ([`NO_PRIM`] for camera rays).
    pub(crate) prim: F::Ids,
    /// Lanes whose ray heads into its primitive's interior.
    pub(crate) inward: F::Mask,
}

impl<F: Lanes> DeparturePacket<F> {
    /// Camera rays: no departure surface.
    pub fn camera() -> Self {
        Self { prim: F::Ids::splat(NO_PRIM), inward: F::mask_from_bits(0) }
    }
    /// Lane `i` as a scalar departure.
    pub(crate) fn lane(&self, i: usize) -> super::Departure {
        super::Departure { prim: self.prim.lane(i), inward: F::mask_lane(self.inward, i) }
    }
}
