//! Polygons' triangles as the items of BVH leaves ([`LeafQuery`]) and of brute force: the triangle kernel over
//! a range of triangles, each hit reported under its polygon's id, generic over the lane type (the K = 1
//! instance is the scalar reference path).

use crate::geometry::{intersect_triangle, HitPacket, Pyramid, Ray};
use crate::math::{Mask, Vec3f};
use crate::simd::{IdLanes, Lanes};

use super::bvh::{LeafQuery, SingleLeafQuery};
use super::Polygons;

/// A query of rays against the triangles of [`Polygons`]: the rays, each ray's exclusive end `t_max`, and the
/// primitive each ray leaves (`skip`: a polygon's id, never reported).
#[derive(Clone, Copy)]
pub struct TriangleQuery<'a, F: Lanes> {
    /// The polygons and their triangles.
    pub polygons: &'a Polygons,
    /// The id of polygon 0: polygon k is primitive `base + k`.
    pub base: u32,
    /// The rays.
    pub ray: Ray<F>,
    /// Exclusive end of each ray's range.
    pub t_max: F,
    /// The departure primitive of each ray.
    pub skip: F::Ids,
    /// Planes enclosing the live rays, from the packet's maker.
    pub pyramid: Option<Pyramid>,
}

impl<F: Lanes> TriangleQuery<'_, F> {
    /// Triangle `j`'s hits for the lanes of `live` (its polygon's departure lanes excluded), its t, and the
    /// polygon's id.
    #[inline(always)]
    fn triangle(&self, j: usize, live: F::Mask) -> (F::Mask, F, F::Ids) {
        let p = self.polygons;
        let id = F::Ids::splat(self.base + p.polygon[j]);
        let (v0, e1, e2) = (F::splat_v3(p.v0[j]), F::splat_v3(p.e1[j]), F::splat_v3(p.e2[j]));
        let (hit, t) = intersect_triangle(v0, e1, e2, &self.ray, self.t_max);
        (live & hit & !F::ids_eq(id, self.skip), t, id)
    }
}

impl<'a, F: Lanes> LeafQuery<F> for TriangleQuery<'a, F> {
    type One = TriangleQuery<'a, f32>;

    #[inline(always)]
    fn ray(&self) -> &Ray<F> {
        &self.ray
    }
    #[inline(always)]
    fn t_max(&self) -> F {
        self.t_max
    }
    #[inline(always)]
    fn pyramid(&self) -> Option<Pyramid> {
        self.pyramid
    }
    #[inline(always)]
    fn ball(&self, _: usize) -> Option<(Vec3f, f32)> {
        None
    }

    #[inline(always)]
    fn lane(&self, i: usize) -> TriangleQuery<'a, f32> {
        let lane = |v: &crate::math::V3<F>| crate::math::V3::new(v.x.lane(i), v.y.lane(i), v.z.lane(i));
        TriangleQuery {
            polygons: self.polygons,
            base: self.base,
            ray: Ray { origin: lane(&self.ray.origin), dir: lane(&self.ray.dir) },
            t_max: self.t_max.lane(i),
            skip: self.skip.lane(i),
            pyramid: None,
        }
    }

    #[inline(always)]
    fn intersect(&self, items: impl Iterator<Item = usize>, live: F::Mask, best: &mut HitPacket<F>) {
        for j in items {
            let (hit, t, id) = self.triangle(j, live);
            best.update(hit, t, id, id);
        }
    }

    #[inline(always)]
    fn occluded(&self, items: std::ops::Range<usize>, live: F::Mask, blocker: &mut u32) -> F::Mask {
        let mut blocked = F::mask_from_bits(0);
        for j in items {
            let (hit, _, _) = self.triangle(j, live);
            if hit.any() {
                *blocker = j as u32;
                blocked = blocked | hit;
                if (blocked | !live).all() {
                    break;
                }
            }
        }
        blocked
    }
}

impl SingleLeafQuery for TriangleQuery<'_, f32> {
    #[inline(always)]
    fn intersect_leaf(&self, first: usize, count: usize, best: &mut HitPacket<f32>) {
        self.intersect(first..first + count, true, best);
    }
    #[inline(always)]
    fn occluded_leaf(&self, first: usize, count: usize, blocker: &mut u32) -> bool {
        self.occluded(first..first + count, true, blocker)
    }
}
