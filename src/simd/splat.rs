//! Scalar scene data copied into every lane, so packet code runs the generic kernels on it unchanged.
//!
//! These are inherent methods on the f32 types, kept here beside the lane types rather than in each type's
//! module, because they exist only for packets.

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
            c_eye: F::splat_f32(self.c_eye),
        }
    }
}
