//! The orthonormal frame of a shape with an axis (cones, tori): an origin and three unit vectors, the third
//! along the axis. Points and directions move into it by dot products, so `t` along a ray is unchanged.

use glam::DVec3;

use super::Ray;
use crate::math::{Real, V3};

/// An origin and a right-handed orthonormal basis `e1, e2, axis` (`e2 = axis × e1`): a shape's frame, scalar,
/// splatted over lanes or widened.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Frame<F> {
    /// The frame's origin in rendering space.
    pub(crate) origin: V3<F>,
    /// First unit vector across the axis.
    pub(crate) e1: V3<F>,
    /// Second unit vector across the axis.
    pub(crate) e2: V3<F>,
    /// The unit axis.
    pub(crate) axis: V3<F>,
}

impl Frame<f64> {
    /// The frame at `origin` about the unit vector `axis`, the cross vectors chosen from it alone (glam's
    /// `any_orthonormal_pair`), so equal axes give equal frames.
    pub(crate) fn about(origin: DVec3, axis: DVec3) -> Self {
        let (e1, e2) = axis.any_orthonormal_pair();
        Frame { origin: origin.into(), e1: e1.into(), e2: e2.into(), axis: axis.into() }
    }
}

impl<F: Copy> Frame<F> {
    /// The same frame with every value mapped by `f` (splatted over lanes, or widened): no arithmetic.
    #[inline(always)]
    pub(crate) fn map<G: Copy>(&self, f: impl Fn(F) -> G + Copy) -> Frame<G> {
        Frame { origin: self.origin.map(f), e1: self.e1.map(f), e2: self.e2.map(f), axis: self.axis.map(f) }
    }
}

impl<F: Real> Frame<F> {
    /// A rendering-space point in the frame: `(x, y)` across the axis, `z` along it from the origin.
    #[inline(always)]
    #[allow(clippy::wrong_self_convention)] // &self: callers hold references, and the wide forms are large
    pub(crate) fn to_object(&self, p: V3<F>) -> V3<F> {
        let w = p - self.origin;
        V3::new(w.dot(self.e1), w.dot(self.e2), w.dot(self.axis))
    }

    /// A direction in the frame (no translation).
    #[inline(always)]
    pub(crate) fn vector_to_object(&self, v: V3<F>) -> V3<F> {
        V3::new(v.dot(self.e1), v.dot(self.e2), v.dot(self.axis))
    }

    /// The ray in the frame; `t` is unchanged (the frame is a rotation and a translation).
    #[inline(always)]
    pub(crate) fn ray_to_object(&self, ray: &Ray<F>) -> Ray<F> {
        Ray::new(self.to_object(ray.origin), self.vector_to_object(ray.dir))
    }

    /// A frame vector back in rendering space.
    #[inline(always)]
    pub(crate) fn vector_to_world(&self, v: V3<F>) -> V3<F> {
        self.e1 * v.x + self.e2 * v.y + self.axis * v.z
    }
}
