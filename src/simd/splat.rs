//! Scalar scene data copied into every lane, so packet code runs the generic kernels on it unchanged.
//!
//! These are inherent methods on the f32 types, kept here beside the lane types rather than in each type's
//! module, because they exist only for packets.

use crate::camera::Camera;
use crate::geometry::Shape;
use crate::math::Affine;

use super::Lanes;

impl Affine<f32> {
    /// The same map in every lane.
    pub fn to_lanes<F: Lanes>(&self) -> Affine<F> {
        Affine { cols: self.cols.map(F::splat_v3), translation: F::splat_v3(self.translation) }
    }
}

impl Shape<f32> {
    /// The same shape in every lane.
    pub fn to_lanes<F: Lanes>(&self) -> Shape<F> {
        Shape {
            kind: self.kind,
            center: F::splat_v3(self.center),
            object_from_world: self.object_from_world.to_lanes(),
            normal_to_world: self.normal_to_world.to_lanes(),
            material: self.material,
        }
    }
}

impl Camera<f32> {
    /// The same camera in every lane: `to_lanes::<F>().ray(sx, sy)` generates K primary rays at once, by the
    /// formula the scalar camera uses.
    pub fn to_lanes<F: Lanes>(&self) -> Camera<F> {
        let s = F::splat_f32;
        Camera {
            eye: F::splat_v3(self.eye),
            forward: F::splat_v3(self.forward),
            right: F::splat_v3(self.right),
            up: F::splat_v3(self.up),
            half_w: s(self.half_w),
            half_h: s(self.half_h),
            u_scale: s(self.u_scale),
            u_offset: s(self.u_offset),
            v_scale: s(self.v_scale),
            v_offset: s(self.v_offset),
            distance: s(self.distance),
            width: self.width,
            height: self.height,
        }
    }
}
