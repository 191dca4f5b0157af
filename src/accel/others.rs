//! The primitives outside the BVHs: transformed shapes (planes are unbounded; the few ellipsoids of a TOML
//! scene are tested with them), brute force for every packet; and the exit from the solid a ray leaves
//! toward its inside, which no tree query can find (the departure primitive is skipped there).

use crate::geometry::{far_root, sphere_roots, DeparturePacket, HitPacket, Ray, RayPacket};
use crate::math::Mask;
use crate::simd::{set_bits, IdLanes, Lanes};

use super::{Geometry, PrimRef};

impl Geometry {
    /// Calls `f(hit, t, id)` for each transformed shape with the lanes of `live` it is hit in within `t_max`,
    /// the departure primitive `skip` excluded.
    fn shapes_each<F: Lanes>(
        &self,
        rays: &RayPacket<F>,
        live: F::Mask,
        skip: F::Ids,
        mut f: impl FnMut(F::Mask, F, F::Ids),
    ) {
        let ray = rays.ray();
        let base = self.spheres.len() as u32;
        for (k, shape) in self.shapes.iter().enumerate() {
            let id = F::Ids::splat(base + k as u32);
            let (hit, t) = shape.to_lanes::<F>().intersect(&ray, rays.t_max);
            f(live & hit & !F::ids_eq(id, skip), t, id);
        }
        super::count_work(self.shapes.len(), 0);
    }

    /// Closest hits of the transformed shapes, merged into `best` (their ids are their file ids).
    pub(super) fn shapes_intersect_k<F: Lanes>(
        &self,
        rays: &RayPacket<F>,
        skip: F::Ids,
        best: &mut HitPacket<F>,
    ) {
        self.shapes_each(rays, rays.active, skip, |hit, t, id| best.update(hit, t, id, id));
    }

    /// Lanes of `live` blocked by a transformed shape.
    pub(super) fn shapes_occluded_k<F: Lanes>(
        &self,
        rays: &RayPacket<F>,
        live: F::Mask,
        skip: F::Ids,
    ) -> F::Mask {
        let mut blocked = F::mask_from_bits(0);
        self.shapes_each(rays, live, skip, |hit, _, _| blocked = blocked | hit);
        blocked
    }

    /// For lanes whose ray heads into the solid it leaves: its exit from that solid, as a candidate hit.
    /// Computed lane by lane with the scalar kernel (each lane's solid differs), so every width gets the
    /// scalar bits.
    pub(super) fn departure_exits_k<F: Lanes>(
        &self,
        rays: &RayPacket<F>,
        from: &DeparturePacket<F>,
    ) -> (F::Mask, F) {
        let inward = from.inward & rays.active;
        if !inward.any() {
            return (inward, F::splat_f32(f32::INFINITY));
        }
        let mut t = F::splat_f32(f32::INFINITY).to_array();
        let mut found = 0u32;
        for i in set_bits(F::move_mask(inward)) {
            let (ray, t_max, _) = rays.lane(i);
            if let Some(exit) = self.exit_of_departure(&ray, from.prim.lane(i), t_max) {
                t.as_mut()[i] = exit;
                found |= 1 << i;
            }
        }
        (F::mask_from_bits(found), F::from_lanes(t.as_ref()))
    }

    /// For a ray that leaves a solid primitive toward its inside: where it leaves the primitive again.
    /// Planar primitives (planes, polygons) have no inside, so nothing.
    fn exit_of_departure(&self, ray: &Ray<f32>, prim: u32, t_max: f32) -> Option<f32> {
        let roots = match self.prim(prim) {
            PrimRef::Sphere(i) => sphere_roots(self.spheres.center(i), self.spheres.r[i], ray),
            PrimRef::Shape(shape) if shape.kind.is_solid() => shape.unit_sphere_roots(&shape.to_object(ray)),
            PrimRef::Shape(_) | PrimRef::Polygon(_) => return None,
        };
        let (hit, t) = far_root(&roots, t_max);
        hit.then_some(t)
    }
}
