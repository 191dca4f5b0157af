//! The exit from the solid a ray leaves toward its inside, which no kind's query finds (the departure
//! primitive is skipped there).

use crate::geometry::{far_root, sphere_roots, DeparturePacket, Ray, RayPacket};
use crate::math::Mask;
use crate::simd::{set_bits, IdLanes, Lanes};

use super::{Geometry, PrimRef};

impl Geometry {
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
