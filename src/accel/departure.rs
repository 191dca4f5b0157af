//! Where a ray meets the primitive it leaves again, which no kind's query finds (the departure primitive is
//! skipped there): the exit from a solid it heads into, and the next meeting with a registered kind that a
//! departing ray can meet again (an open cone, a torus).

use crate::geometry::{far_root, sphere_roots, DeparturePacket, Ray, RayPacket};
use crate::simd::{set_bits, IdLanes, Lanes};

use super::{Geometry, PrimRef};

impl Geometry {
    /// For lanes whose ray heads into the solid it leaves: its exit from that solid; for lanes whose ray
    /// leaves a kind that [meets again](crate::kinds::Kind::MEETS_AGAIN) (an open cone, a torus): where it
    /// meets that primitive again. A candidate hit either way. Computed lane by lane
    /// with the scalar kernels (each lane's primitive differs), so every width gets the scalar bits.
    pub(super) fn departure_exits_k<F: Lanes>(
        &self,
        rays: &RayPacket<F>,
        from: &DeparturePacket<F>,
    ) -> (F::Mask, F) {
        let inward = F::move_mask(from.inward & rays.active);
        let again = match self.kinds.any_meets_again() {
            false => 0,
            true => set_bits(F::move_mask(rays.active))
                .filter(|&i| self.meets_again(from.prim.lane(i)))
                .fold(0u32, |bits, i| bits | 1 << i),
        };
        if inward | again == 0 {
            return (F::mask_from_bits(0), F::splat_f32(f32::INFINITY));
        }
        let mut t = F::splat_f32(f32::INFINITY).to_array();
        let mut found = 0u32;
        for i in set_bits(inward | again) {
            let (ray, t_max, _) = rays.lane(i);
            if let Some(exit) = self.exit_of_departure(&ray, from.prim.lane(i), t_max) {
                t.as_mut()[i] = exit;
                found |= 1 << i;
            }
        }
        (F::mask_from_bits(found), F::from_lanes(t.as_ref()))
    }

    /// Whether a ray leaving primitive `prim` can meet it again whichever side it heads to: the registered
    /// kinds that say so ([`crate::kinds::Kind::MEETS_AGAIN`]: open cones, tori).
    fn meets_again(&self, prim: u32) -> bool {
        let i = prim as usize;
        i >= self.kinds_base() && self.kinds.meets_again(i - self.kinds_base())
    }

    /// For a ray that leaves a solid primitive toward its inside: where it leaves the primitive again.
    /// For a registered kind: its [`crate::kinds::Kind::rehit`] (an ellipsoid's exit; a polygon's:
    /// nothing, it has no inside; for a kind that meets again, whichever side the shading took the ray to be on: an
    /// open cone is seen from inside through its ends, so the side a ray heads to is decided by the
    /// kernel; a plane's: nothing).
    fn exit_of_departure(&self, ray: &Ray<f32>, prim: u32, t_max: f32) -> Option<f32> {
        let roots = match self.prim(prim) {
            PrimRef::Sphere(i) => sphere_roots(self.spheres.center(i), self.spheres.r[i], ray),
            PrimRef::Particle(i) => {
                let (centre, r) = self.particles.sphere(i);
                sphere_roots(centre, r, ray)
            }
            PrimRef::Kind(k) => return self.kinds.rehit(k, ray, t_max),
        };
        let (hit, t) = far_root(&roots, t_max);
        hit.then_some(t)
    }
}
