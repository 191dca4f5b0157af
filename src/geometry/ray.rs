//! Rays and hits.

use crate::math::{Real, V3};

/// A ray `origin + t·dir`. Directions need not be unit length: object-space rays of scaled shapes are not,
/// and every kernel divides by `dir·dir` where it matters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray<F> {
    /// Where the ray starts (t = 0).
    pub origin: V3<F>,
    /// Where it goes.
    pub dir: V3<F>,
}

impl<F: Real> Ray<F> {
    /// A ray from its origin and direction.
    #[inline(always)]
    pub fn new(origin: V3<F>, dir: V3<F>) -> Self {
        Self { origin, dir }
    }
    /// The point at parameter `t`.
    #[inline(always)]
    pub fn at(&self, t: F) -> V3<F> {
        self.origin + self.dir * t
    }
}

/// Primitive id meaning "none": a miss, or a ray that starts on no surface.
pub const NO_PRIM: u32 = u32::MAX;

/// The closest hit found so far: its parameter (`inf` on a miss) and primitive id ([`NO_PRIM`] on a miss).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Spheres are numbered from 0 in scene order, other shapes after them.
    pub prim: u32,
}

impl Hit {
    /// No hit yet.
    pub(crate) const MISS: Hit = Hit { t: f32::INFINITY, prim: NO_PRIM };

    /// True when something was hit.
    pub fn is_hit(&self) -> bool {
        self.prim != NO_PRIM
    }
}

/// Where a secondary ray leaves a surface, so it never re-hits that surface at t ≈ 0 (see ARCHITECTURE.md,
/// "Self-intersection"). Every primitive is convex or planar, so a ray leaving it toward the outside cannot
/// hit it again, and a ray leaving it toward the inside can only hit its far side.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Departure {
    /// The primitive the ray starts on, or [`NO_PRIM`] for camera rays.
    pub(crate) prim: u32,
    /// True when the ray heads into the primitive's interior (refraction in, reflection inside).
    pub(crate) inward: bool,
}

impl Departure {
    /// Camera rays start on no surface.
    pub const CAMERA: Departure = Departure { prim: NO_PRIM, inward: false };
}
