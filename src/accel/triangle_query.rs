//! Polygons' triangles as the items of BVH leaves and of brute force ([`ItemQuery`]): the triangle kernel,
//! each hit reported under its polygon's id.

use crate::geometry::{intersect_triangle, stays_off_plane, Polygons, Ray};
use crate::simd::Lanes;

use crate::bvh::item_query::{ItemQuery, ItemTest};

/// The triangles of [`Polygons`], polygon k being primitive `base + k`.
#[derive(Clone, Copy)]
pub(crate) struct Triangles<'a> {
    /// The polygons and their triangles.
    pub(crate) polygons: &'a Polygons,
    /// The id of polygon 0.
    pub(crate) base: u32,
    /// Skip a triangle for the rays that stay off its polygon's plane up to their reach ([`stays_off_plane`]):
    /// worth it without a BVH, where every triangle meets every packet (a floor under a sphere field is
    /// passed over by the rays that hit a sphere first and by those heading up); in a BVH's leaves the boxes
    /// have culled already.
    pub(crate) plane_cull: bool,
}

impl ItemTest for Triangles<'_> {
    #[inline(always)]
    fn test<F: Lanes>(&self, j: usize, ray: &Ray<F>, t_max: F) -> (F::Mask, F, u32) {
        let p = self.polygons;
        let (v0, e1, e2) = (F::splat_v3(p.v0[j]), F::splat_v3(p.e1[j]), F::splat_v3(p.e2[j]));
        let (hit, t) = intersect_triangle(v0, e1, e2, ray, t_max);
        (hit, t, self.base + p.polygon[j])
    }

    #[inline(always)]
    fn culled<F: Lanes>(&self, j: usize, ray: &Ray<F>, reach: F) -> F::Mask {
        if !self.plane_cull {
            return F::mask_from_bits(0);
        }
        let (p, k) = (self.polygons, self.polygons.polygon[j] as usize);
        let (anchor, normal) = (F::splat_v3(p.anchor[k]), F::splat_v3(p.normal[k]));
        stays_off_plane(anchor, normal, F::splat_f32(p.thickness[k]), ray, reach)
    }
}

/// A query of rays against the triangles.
pub(crate) type TriangleQuery<'a, F> = ItemQuery<F, Triangles<'a>, &'a Ray<F>>;
