//! Primitives and their intersection kernels. Each kernel is generic over [`crate::math::Real`]: the f32
//! instance serves single rays (K = 1, the scalar path among them), the f64 instance the accuracy oracle.

mod ellipse;
mod frame;
mod packet;
mod plane;
mod ray;
mod round;
mod shape;
mod sphere;
mod spheres;

pub(crate) use ellipse::Ellipse;
pub(crate) use frame::Frame;
pub(crate) use packet::HitPacket;
pub(crate) use packet::Pyramid;
pub use packet::{intersect_spheres_1, intersect_spheres_k, DeparturePacket, RayPacket};
pub(crate) use plane::intersect_plane;
pub use ray::{Departure, Hit, Ray, NO_PRIM};
pub(crate) use round::{round_down, round_up};
pub(crate) use shape::{Shape, ShapeKind};
pub(crate) use sphere::{at_eye, far_root, sphere_roots, sphere_roots_of, EyeLanes, CONTACT_ROUNDINGS};
pub use sphere::{first_root, intersect_sphere, sphere_approach, Approach, Roots, SphereRay};
pub use spheres::Spheres;
pub(crate) use spheres::{eye_side, eye_term};

/// `v` in a new order, `order[j]` being the old index of new item `j`: how the kinds' stores follow their
/// BVH's leaf order. Large stores are gathered on the thread pool.
fn gathered<T: Copy + Send + Sync>(v: &[T], order: &[u32]) -> Vec<T> {
    use rayon::prelude::*;
    order.par_iter().with_min_len(1 << 14).map(|&i| v[i as usize]).collect()
}
