//! Exact widening of the renderer's f32 data to f64 (every f32 is an f64), and the conversions between the
//! library's `V3` and glam's `DVec3`, for f64 instances of the same kernels.

use bareray::geometry::{Ray, Shape};
use bareray::math::{Affine, Vec3f, V3};
use glam::DVec3;

pub fn wide(v: Vec3f) -> V3<f64> {
    v.to_f64()
}

pub fn dv(v: V3<f64>) -> DVec3 {
    DVec3::new(v.x, v.y, v.z)
}

/// Rounds each coordinate to f32.
pub fn f32v(v: DVec3) -> Vec3f {
    V3::new(v.x as f32, v.y as f32, v.z as f32)
}

pub fn wide_ray(r: &Ray<f32>) -> Ray<f64> {
    Ray::new(wide(r.origin), wide(r.dir))
}

pub fn wide_affine(a: &Affine<f32>) -> Affine<f64> {
    Affine { cols: a.cols.map(wide), translation: wide(a.translation) }
}

pub fn wide_shape(s: &Shape<f32>) -> Shape<f64> {
    Shape {
        kind: s.kind,
        center: wide(s.center),
        object_from_world: wide_affine(&s.object_from_world),
        normal_to_world: wide_affine(&s.normal_to_world),
        material: s.material,
        c_eye: f64::from(s.c_eye),
    }
}
