//! The two brute-force sphere kernels over [`Spheres`], on ray and hit packets.
//!
//! Both run the `f32` instance's formula ([`sphere_approach`], with each sphere's exact eye term for rays
//! from the eye) at a lane type, so their results are bit-identical to [`crate::accel::Geometry::intersect`]
//! over the same spheres (for camera rays):
//!
//! - [`intersect_spheres_k`]: lanes = rays. K rays against each sphere in turn, the sphere splatted.
//! - [`intersect_spheres_1`]: lanes = spheres. One ray against K spheres at a time, loaded straight from the
//!   SoA arrays, then a reduction over the lanes.
//!
//! Both keep the scalar tie rule: a sphere replaces the best hit only when its t is strictly smaller, so of
//! equal t the lower id wins. They take storage order for file order (no BVH), so a hit's key is its id.

use crate::geometry::{
    first_root, sphere_approach, sphere_roots_of, EyeLanes, Hit, HitPacket, Ray, RayPacket, SphereRay,
    NO_PRIM,
};
use crate::math::Mask;
use crate::simd::{IdLanes, Lanes};

use super::Spheres;

/// Closest hits of a packet of camera rays with every sphere (lanes = rays): the packet twin of
/// [`crate::accel::Geometry::intersect`] over spheres with [`crate::geometry::Departure::CAMERA`].
pub fn intersect_spheres_k<F: Lanes>(spheres: &Spheres, packet: &RayPacket<F>) -> HitPacket<F> {
    let ray = packet.ray();
    let mut best = HitPacket { t: packet.t_max, prim: F::Ids::splat(NO_PRIM), key: F::Ids::splat(NO_PRIM) };
    if !packet.active.any() {
        return HitPacket::miss();
    }
    let mut found = F::mask_from_bits(0);
    let terms = SphereRay::new(*ray);
    let eye = EyeLanes::of(terms.from_eye(), packet.active);
    for i in 0..spheres.len() {
        let centre = F::splat_v3(spheres.center(i));
        let line = sphere_approach(centre, F::splat_f32(spheres.r[i]), &terms);
        let roots = sphere_roots_of(
            spheres.eye_terms_help,
            &line,
            || centre,
            F::splat_f32(spheres.c_eye[i]),
            &terms,
            eye,
        );
        let (hit, t) = first_root(&roots, best.t);
        // `t < best.t` inside the kernel is the strict comparison that lets the lower id keep a tie.
        let hit = hit & packet.active;
        best.t = F::select(hit, t, best.t);
        let id = F::Ids::splat(i as u32);
        (best.prim, best.key) = (F::select_ids(hit, id, best.prim), F::select_ids(hit, id, best.key));
        found = found | hit;
    }
    // Misses report `inf`, not `t_max`, as the scalar query does.
    best.t = F::select(found, best.t, F::splat_f32(f32::INFINITY));
    best
}

/// Closest hit of one camera ray with every sphere, K spheres at a time (lanes = spheres): the transposed
/// twin of [`intersect_spheres_k`], with the same result as the scalar query.
pub fn intersect_spheres_1<F: Lanes>(spheres: &Spheres, ray: &Ray<f32>, t_max: f32) -> Hit {
    let n = spheres.len();
    let ray_k = SphereRay::new(Ray::new(F::splat_v3(ray.origin), F::splat_v3(ray.dir)));
    let mut best =
        HitPacket { t: F::splat_f32(t_max), prim: F::Ids::splat(NO_PRIM), key: F::Ids::splat(NO_PRIM) };
    let mut at = 0;
    while at + F::K <= n {
        sphere_chunk(spheres, &ray_k, at, None, &mut best);
        at += F::K;
    }
    if at < n {
        sphere_chunk(spheres, &ray_k, at, Some(F::lanes_below(n - at)), &mut best);
    }
    closest_lane(&best)
}

/// Spheres `at..at + K` against a splatted ray, updating each lane's best hit; `valid` masks a tail chunk.
#[inline(always)]
fn sphere_chunk<F: Lanes>(
    s: &Spheres,
    ray: &SphereRay<F>,
    at: usize,
    valid: Option<F::Mask>,
    best: &mut HitPacket<F>,
) {
    // A zero-radius sphere at the origin pads the tail; `valid` masks it out whatever it would give.
    let centre = F::load_v3(&s.cx, &s.cy, &s.cz, at, 0.0);
    let line = sphere_approach(centre, F::load_partial(&s.r, at, 0.0), ray);
    // One ray: it starts at the eye in every lane or in none.
    let eye = if ray.from_eye().all() { EyeLanes::All } else { EyeLanes::None };
    let roots =
        sphere_roots_of(s.eye_terms_help, &line, || centre, F::load_partial(&s.c_eye, at, 0.0), ray, eye);
    let (hit, t) = first_root(&roots, best.t);
    let hit = valid.map_or(hit, |v| hit & v);
    best.t = F::select(hit, t, best.t);
    let id = F::Ids::splat(at as u32) + F::lane_ids();
    (best.prim, best.key) = (F::select_ids(hit, id, best.prim), F::select_ids(hit, id, best.key));
}

/// The smallest t over the lanes, of equal t the lowest id: lane `l` saw spheres `l, l + K, …` in order, so
/// it holds their lowest-id closest hit, and this picks the scalar loop's answer among the lanes.
fn closest_lane<F: Lanes>(best: &HitPacket<F>) -> Hit {
    let mut out = Hit::MISS;
    for i in 0..F::K {
        let lane = best.lane(i);
        // Float comparisons, not bits: −0 and +0 tie, as they do in the scalar loop.
        let closer = lane.t < out.t || (lane.t == out.t && lane.prim < out.prim);
        if lane.prim != NO_PRIM && closer {
            out = lane;
        }
    }
    out
}
