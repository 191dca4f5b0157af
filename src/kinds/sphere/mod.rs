//! The sphere kind: its description ([`SphereDesc`]) and the bounds of a list of them, its store in
//! structure-of-arrays layout ([`Spheres`]), the brute-force kernels over the store (`brute.rs`), its leaf
//! query for the trees (`query.rs`) and its f64 form for the accuracy twin (`twin.rs`). The ray/sphere kernel
//! itself is [`crate::geometry`]'s, shared with the kinds that reduce to a sphere (an ellipsoid in its own
//! frame, a torus's bounding shells) and with the f64 twin.
//!
//! Spheres are not in the registry's list ([`crate::kinds`]): their compiled form and queries are the
//! scene's own paths, which the registered kinds' generated loops do not have — a BVH or the particle tree
//! (`crate::accel::pkd`) chosen by size, large packets of camera rays, exact eye terms, shadow hints and
//! light buffers, per-sphere colours, and ids first (`0..n`, before the registered kinds').
//!
//! ```
//! use bareray::geometry::{Ray, RayPacket};
//! use bareray::kinds::sphere::{intersect_spheres_1, intersect_spheres_k, Spheres};
//! use bareray::math::V3;
//! // Two spheres on the z axis; a ray from the origin along +z meets the nearer at t = 4.
//! let mut spheres = Spheres::default();
//! spheres.push(V3::new(0.0, 0.0, 10.0), 1.0, 0);
//! spheres.push(V3::new(0.0, 0.0, 5.0), 1.0, 0);
//! let ray = Ray::new(V3::new(0.0, 0.0, 0.0), V3::new(0.0, 0.0, 1.0));
//! let hit = intersect_spheres_1::<wide::f32x8>(&spheres, &ray, f32::INFINITY);
//! assert_eq!((hit.prim, hit.t), (1, 4.0));
//! // The packet kernel gives the same hit in every lane of a packet of that ray.
//! let packet = RayPacket::<wide::f32x8>::from_rays(&[ray; 8], f32::INFINITY);
//! assert_eq!(intersect_spheres_k(&spheres, &packet).lane(3), hit);
//! ```

mod brute;
mod query;
mod store;
#[cfg(test)]
mod tests;
pub(crate) mod twin;

use glam::DVec3;

use crate::geometry::box_union;

pub use brute::{intersect_spheres_1, intersect_spheres_k};
pub(crate) use query::SphereQuery;
pub use store::Spheres;

/// A sphere as described: centre and radius in world space, f64, and its material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereDesc {
    /// Centre.
    pub center: DVec3,
    /// Radius (> 0).
    pub radius: f64,
    /// Index into `SceneDesc::materials`.
    pub material: u32,
}

/// The box around `spheres` (each centre ± radius), `(+∞, −∞)` for none: a parallel reduction by
/// [`crate::geometry::box_union`], so the same box however the list is cut.
pub(crate) fn sphere_bounds(spheres: &[SphereDesc]) -> (DVec3, DVec3) {
    use rayon::prelude::*;
    // Both corners on both sides, so a sphere built by hand with a negative radius still spans its box.
    let ball = |s: &SphereDesc| {
        let (a, b) = (s.center - s.radius, s.center + s.radius);
        box_union((a, a), (b, b))
    };
    let empty = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    spheres.par_iter().with_min_len(1 << 14).map(ball).reduce(|| empty, box_union)
}
