//! Transformed generic shapes: the unit sphere (ellipsoids) and the plane z = 0 (any plane), placed by an
//! affine map. The ray is carried into object space, where the generic test runs; t is unchanged by the map
//! because the direction is mapped without renormalising. Normals go back by the inverse transpose.

use crate::math::{Affine, Mask, Real, Vec3f, V3};
use crate::simd::Lanes;

use super::{at_eye, intersect_plane, sphere_approach, sphere_roots, Approach, Ray, Roots, SphereRay};

/// Which generic shape an instance places.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ShapeKind {
    /// The unit sphere at the origin.
    Sphere,
    /// The plane z = 0, normal +z.
    Plane,
}

/// A generic shape under an affine map, ready to intersect.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Shape<F> {
    /// The generic shape.
    pub(crate) kind: ShapeKind,
    /// Where the object's origin is in the world (`world_from_object`'s translation).
    pub(crate) center: V3<F>,
    /// Carries world rays into object space (its linear part is applied to `origin − center`).
    pub(crate) object_from_world: Affine<F>,
    /// Carries object-space normals to world space (inverse transpose of `world_from_object`).
    pub(crate) normal_to_world: Affine<F>,
    /// Index into the scene's materials.
    pub(crate) material: u32,
    /// The eye term in object space, `|o_eye|² − 1` with `o_eye` the eye (the rendering space's origin)
    /// carried into object space, computed in f64 and rounded once: camera rays use it for the unit
    /// sphere's `c`, as spheres use theirs ([`super::Approach::roots_from_eye`]). Unused for planes.
    pub(crate) c_eye: F,
}

impl Shape<f64> {
    /// A generic shape placed by `world_from_object` (in rendering space), in f64.
    pub(crate) fn placed(kind: ShapeKind, world_from_object: &glam::DAffine3, material: u32) -> Self {
        let object_from_world = world_from_object.inverse();
        let d = object_from_world.translation.length();
        Shape {
            kind,
            center: world_from_object.translation.into(),
            object_from_world: Affine::from_glam(&object_from_world),
            normal_to_world: crate::math::affine::normal_to_world(world_from_object),
            material,
            c_eye: (d - 1.0) * (d + 1.0),
        }
    }

    /// Every value rounded to f32 once.
    #[allow(clippy::wrong_self_convention)] // &self: callers hold references, and the wide forms are large
    pub(crate) fn to_f32(&self) -> Shape<f32> {
        Shape {
            kind: self.kind,
            center: self.center.to_f32(),
            object_from_world: self.object_from_world.to_f32(),
            normal_to_world: self.normal_to_world.to_f32(),
            material: self.material,
            c_eye: self.c_eye as f32,
        }
    }
}

impl<F: Real> Shape<F> {
    /// The ray in object space. The origin is taken relative to the shape's centre before the linear map:
    /// `L⁻¹·(o − c)` rather than `L⁻¹·o − L⁻¹·c`, whose two terms cancel for a small shape far from the
    /// world origin (measured on the stress suite: PERF.md, Register: "Transformed shapes").
    #[inline(always)]
    #[allow(clippy::wrong_self_convention)] // &self: callers hold references, and the wide forms are large
    pub(crate) fn to_object(&self, ray: &Ray<F>) -> Ray<F> {
        Ray::new(
            self.object_from_world.vector(ray.origin - self.center),
            self.object_from_world.vector(ray.dir),
        )
    }

    /// Closest hit in `[0, t_max)`: [`Shape::intersect_unit_sphere`] or [`Shape::intersect_plane`] by the
    /// shape's kind.
    #[inline(always)]
    pub(crate) fn intersect(&self, ray: &Ray<F>, t_max: F) -> (F::Mask, F) {
        match self.kind {
            ShapeKind::Sphere => self.intersect_unit_sphere(ray, t_max),
            ShapeKind::Plane => self.intersect_plane(ray, t_max),
        }
    }

    /// Closest hit in `[0, t_max)` of the placed unit sphere (an ellipsoid). Its `c = |o'|² − 1` cancels
    /// for a large ellipsoid seen from close by, so it comes from the exact eye term as for spheres: lanes
    /// whose ray starts at the eye take it as it is, the others as `c_eye + 2·o_eye·v + |v|²` (`v = L⁻¹·o`,
    /// the origin seen from the eye in object space) where that has the smaller rounding bound
    /// (`Approach::roots_with_eye_term` with the centre seen from the eye, `L⁻¹·centre`). Shapes are few;
    /// every lane computes both forms.
    #[inline(always)]
    pub(crate) fn intersect_unit_sphere(&self, ray: &Ray<F>, t_max: F) -> (F::Mask, F) {
        let local = self.to_object(ray);
        let terms = SphereRay::new(local);
        let line = sphere_approach(V3::all(F::splat(0.0)), F::splat(1.0), &terms);
        if !line.meets().any() {
            return (line.meets(), t_max);
        }
        let others = || {
            let seen_from_eye = terms.with_origin(self.object_from_world.vector(ray.origin));
            let centre = self.object_from_world.vector(self.center);
            line.roots_with_eye_term(centre, self.c_eye, &seen_from_eye)
        };
        let eye = at_eye(ray.origin);
        let roots = if eye.all() {
            line.roots_from_eye(self.c_eye, true)
        } else if eye.any() {
            Approach::select_eye_lanes(eye, line.roots_from_eye(self.c_eye, true), others())
        } else {
            others()
        };
        // Misses report `t_max` whichever way they were found (the early return above).
        let (hit, t) = super::first_root(&roots, t_max);
        (hit, F::select(hit, t, t_max))
    }

    /// Closest hit in `[0, t_max)` of the placed plane z = 0.
    #[inline(always)]
    pub(crate) fn intersect_plane(&self, ray: &Ray<F>, t_max: F) -> (F::Mask, F) {
        intersect_plane(&self.to_object(ray), t_max)
    }

    /// Both roots with the unit sphere, for an object-space ray.
    #[inline(always)]
    pub(crate) fn unit_sphere_roots(&self, local: &Ray<F>) -> Roots<F> {
        sphere_roots(V3::all(F::splat(0.0)), F::splat(1.0), local)
    }
}

impl Shape<f32> {
    /// The unit world-space normal at an object-space point on the shape.
    pub(crate) fn world_normal(&self, object_point: Vec3f) -> Vec3f {
        let n = match self.kind {
            ShapeKind::Sphere => object_point,
            ShapeKind::Plane => V3::new(0.0, 0.0, 1.0),
        };
        self.normal_to_world.vector(n).normalize()
    }

    /// Every value widened exactly to f64 (an oracle over the compiled scene).
    #[cfg(test)]
    pub(crate) fn widen(&self) -> Shape<f64> {
        let wide =
            |a: &Affine<f32>| Affine { cols: a.cols.map(V3::to_f64), translation: a.translation.to_f64() };
        Shape {
            kind: self.kind,
            center: self.center.to_f64(),
            object_from_world: wide(&self.object_from_world),
            normal_to_world: wide(&self.normal_to_world),
            material: self.material,
            c_eye: f64::from(self.c_eye),
        }
    }

    /// The same shape in every lane.
    #[allow(clippy::wrong_self_convention)] // &self: callers hold references, and the wide forms are large
    pub(crate) fn to_lanes<F: Lanes>(&self) -> Shape<F> {
        Shape {
            kind: self.kind,
            center: F::splat_v3(self.center),
            object_from_world: self.object_from_world.to_lanes(),
            normal_to_world: self.normal_to_world.to_lanes(),
            material: self.material,
            c_eye: F::splat_f32(self.c_eye),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DAffine3, DVec3};

    fn shape(kind: ShapeKind, world_from_object: DAffine3) -> Shape<f64> {
        Shape::placed(kind, &world_from_object, 0)
    }

    #[test]
    fn ellipsoid_hit_distance_is_in_world_units() {
        // Unit sphere stretched to semi-axis 3 along x, moved to x = 10: a ray along +x from the origin
        // enters at x = 7.
        let m = DAffine3::from_translation(DVec3::new(10.0, 0.0, 0.0))
            * DAffine3::from_scale(DVec3::new(3.0, 1.0, 1.0));
        let s = shape(ShapeKind::Sphere, m);
        let ray = Ray::new(V3::new(0.0, 0.0, 0.0), V3::new(1.0, 0.0, 0.0));
        let (hit, t) = s.intersect(&ray, f64::INFINITY);
        assert!(hit);
        assert!((t - 7.0).abs() < 1e-12);
    }

    #[test]
    fn tilted_plane_hit_and_normal() {
        // z = 0 rotated 90° about x becomes y = 0 with normal −y... rotate by −90° to get +y, then lift to y = −1.
        let m = DAffine3::from_translation(DVec3::new(0.0, -1.0, 0.0))
            * DAffine3::from_rotation_x(-std::f64::consts::FRAC_PI_2);
        let s = shape(ShapeKind::Plane, m);
        let ray = Ray::new(V3::new(0.0, 2.0, 0.0), V3::new(0.0, -1.0, 0.0));
        let (hit, t) = s.intersect(&ray, f64::INFINITY);
        assert!(hit);
        assert!((t - 3.0).abs() < 1e-12);
        let n = s.normal_to_world.vector(V3::new(0.0, 0.0, 1.0)).normalize();
        assert!((n.y - 1.0).abs() < 1e-12, "{n:?}");
    }
}
