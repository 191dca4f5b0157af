//! A three-component vector generic over [`Real`], so one formula serves f32, f64 and SIMD lanes.
//!
//! glam's vectors are fixed to one float type; the kernels need the same operation order at every type,
//! so they use this small type. Every operation here spells out its evaluation order (`dot` sums x, y, z
//! left to right) because bit-exact agreement between instances depends on it.

use super::real::Real;
use std::ops::{Add, Mul, Neg, Sub};

/// A vector, a point or an RGB colour. Laid out as C lays out its three fields, in order: an image of
/// [`Rgb`] is its channels' `f32`s one after another ([`crate::film::Image::into_rgb_values`]).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[repr(C)]
pub struct V3<F> {
    /// First component (red for colours).
    pub x: F,
    /// Second component (green).
    pub y: F,
    /// Third component (blue).
    pub z: F,
}

/// A 32-bit vector, the renderer's working type.
pub(crate) type Vec3f = V3<f32>;
/// A linear RGB colour.
pub type Rgb = V3<f32>;

impl<F: Copy> V3<F> {
    /// A vector from its components.
    #[inline(always)]
    pub const fn new(x: F, y: F, z: F) -> Self {
        Self { x, y, z }
    }
    /// All three components equal to `v`.
    #[inline(always)]
    pub const fn all(v: F) -> Self {
        Self { x: v, y: v, z: v }
    }
    /// Applies `f` to each component.
    #[inline(always)]
    pub(crate) fn map<G>(self, f: impl Fn(F) -> G) -> V3<G> {
        V3 { x: f(self.x), y: f(self.y), z: f(self.z) }
    }
}

impl<F: Real> V3<F> {
    /// The dot product, summed x + y + z from the left.
    #[inline(always)]
    pub fn dot(self, o: Self) -> F {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    /// The cross product.
    #[inline(always)]
    pub(crate) fn cross(self, o: Self) -> Self {
        Self::new(self.y * o.z - self.z * o.y, self.z * o.x - self.x * o.z, self.x * o.y - self.y * o.x)
    }
    /// The Euclidean length.
    #[inline(always)]
    pub(crate) fn length(self) -> F {
        self.dot(self).sqrt()
    }
    /// The unit vector along `self` (each component divided by the length, not multiplied by a reciprocal,
    /// so that the result is as accurate as one rounding per component allows).
    #[inline(always)]
    pub(crate) fn normalize(self) -> Self {
        let len = self.length();
        Self::new(self.x / len, self.y / len, self.z / len)
    }
    /// Component-wise product (colour filtering).
    #[inline(always)]
    pub(crate) fn mul_elem(self, o: Self) -> Self {
        Self::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }
    /// Component-wise choice between two vectors.
    #[inline(always)]
    pub(crate) fn select(mask: F::Mask, a: Self, b: Self) -> Self {
        Self::new(F::select(mask, a.x, b.x), F::select(mask, a.y, b.y), F::select(mask, a.z, b.z))
    }
}

impl V3<f32> {
    /// Widens to f64 exactly.
    pub fn to_f64(self) -> V3<f64> {
        self.map(f64::from)
    }
}

impl V3<f64> {
    /// Rounds each component to the nearest f32.
    pub(crate) fn to_f32(self) -> V3<f32> {
        self.map(|v| v as f32)
    }
}

impl From<glam::DVec3> for V3<f64> {
    fn from(v: glam::DVec3) -> Self {
        Self::new(v.x, v.y, v.z)
    }
}

impl From<V3<f64>> for glam::DVec3 {
    fn from(v: V3<f64>) -> Self {
        glam::DVec3::new(v.x, v.y, v.z)
    }
}

impl<F: Real> Add for V3<F> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl<F: Real> Sub for V3<F> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl<F: Real> Neg for V3<F> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y, -self.z)
    }
}

impl<F: Real> Mul<F> for V3<F> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: F) -> Self {
        Self::new(self.x * s, self.y * s, self.z * s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cross_follows_the_right_hand_rule() {
        let x = V3::new(1.0f32, 0.0, 0.0);
        let y = V3::new(0.0f32, 1.0, 0.0);
        assert_eq!(x.cross(y), V3::new(0.0, 0.0, 1.0));
        assert_eq!(y.cross(x), V3::new(0.0, 0.0, -1.0));
    }

    #[test]
    fn normalize_gives_unit_length() {
        let v = V3::new(3.0f64, 4.0, 12.0).normalize();
        assert!((v.length() - 1.0).abs() < 1e-15);
        assert_eq!(v, V3::new(3.0 / 13.0, 4.0 / 13.0, 12.0 / 13.0));
    }
}
