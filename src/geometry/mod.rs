//! Rays, packets and the intersection kernels the kinds share (the ray/sphere kernel and its exact eye
//! terms, planes, placed shapes, ellipses for coverage), and `box_union` for world boxes. Each kernel is
//! generic over [`crate::math::Real`]: the f32 instance serves single rays (K = 1, the scalar path among
//! them), the f64 instance the accuracy oracle.

mod ellipse;
mod frame;
mod packet;
mod plane;
mod ray;
mod round;
mod shape;
mod sphere;

use glam::DVec3;

pub(crate) use ellipse::Ellipse;
pub(crate) use frame::Frame;
pub(crate) use packet::HitPacket;
pub(crate) use packet::Pyramid;
pub use packet::{DeparturePacket, RayPacket};
pub(crate) use plane::intersect_plane;
pub use ray::{Departure, Hit, Ray, NO_PRIM};
pub(crate) use round::{round_down, round_up};
pub(crate) use shape::{Shape, ShapeKind};
pub(crate) use sphere::{
    at_eye, eye_side, eye_term, far_root, sphere_roots, sphere_roots_of, EyeLanes, CONTACT_ROUNDINGS,
};
pub use sphere::{first_root, intersect_sphere, sphere_approach, Approach, Roots, SphereRay};

/// The union of two boxes `(lo, hi)`, component by component with `f64::min` and `f64::max`: exact,
/// associative and commutative, a NaN ignored (glam's `min` and `max` are neither for NaN), so a reduction
/// gives the same box in any order.
pub(crate) fn box_union((lo, hi): (DVec3, DVec3), (l, h): (DVec3, DVec3)) -> (DVec3, DVec3) {
    let min = DVec3::new(lo.x.min(l.x), lo.y.min(l.y), lo.z.min(l.z));
    (min, DVec3::new(hi.x.max(h.x), hi.y.max(h.y), hi.z.max(h.z)))
}
