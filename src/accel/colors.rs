//! The per-sphere colour of a hit primitive, from the BVH's sphere store or the particle tree, whichever
//! holds the spheres (each keeps its colours in its own order, [`crate::kinds::sphere::Spheres::color`]).

use super::{Geometry, PrimRef};
use crate::math::Rgb8;

impl Geometry {
    /// The colour of primitive `prim` when it is a sphere with a colour of its own (it replaces the
    /// material's); `None` for other primitives and in scenes without per-sphere colours.
    #[inline]
    pub(crate) fn sphere_color(&self, prim: u32) -> Option<Rgb8> {
        match self.prim(prim) {
            PrimRef::Sphere(i) => self.spheres.color_of(i),
            PrimRef::Particle(i) => self.particles.color(i),
            _ => None,
        }
    }

    /// How many spheres have a colour of their own, in the BVH's store and the particle tree.
    pub(crate) fn sphere_colors(&self) -> usize {
        self.spheres.color.len() + self.particles.colors()
    }
}
