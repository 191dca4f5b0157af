//! `SceneDesc`: a scene as plain, validated data in f64, whatever file format it came from.
//! Compile (`crate::compile`) turns it into the immutable [`crate::compile::Scene`] the renderer reads.
//!
//! This file holds `SceneDesc`, the spheres' `SphereDesc` and the bounds of a list of them; the camera, the
//! render settings, the shading and the materials and lights have a file each, their items all named
//! `scene::desc::Name`.

mod camera;
mod materials_lights;
mod render;
mod shade;
#[cfg(test)]
mod tests;

use glam::DVec3;

pub use self::{
    camera::{Aim, CameraDesc, CameraOverrides, Field, Sweep},
    materials_lights::{Checker, Falloff, LightDesc, Material},
    render::{Filter, FilterKind, Pattern, PostFilter, RenderDesc, Transfer},
    shade::{Ao, Shade},
};
use crate::kinds::KindDescs;
use crate::math::Rgb8;

/// A sphere kept in the fast SoA layout.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereDesc {
    /// Centre.
    pub center: DVec3,
    /// Radius (> 0).
    pub radius: f64,
    /// Index into `SceneDesc::materials`.
    pub material: u32,
}

/// The box around `spheres` (each centre ± radius), `(+∞, −∞)` for none: a parallel reduction by
/// [`box_union`], so the same box however the list is cut.
pub(crate) fn sphere_bounds(spheres: &[SphereDesc]) -> (DVec3, DVec3) {
    use rayon::prelude::*;
    // Both corners on both sides, so a sphere built by hand with a negative radius still spans its box.
    let ball = |s: &SphereDesc| {
        let (a, b) = (s.center - s.radius, s.center + s.radius);
        box_union((a, a), (b, b))
    };
    let empty = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    spheres.par_iter().with_min_len(1 << 14).map(ball).reduce(|| empty, box_union)
}

/// The union of two boxes `(lo, hi)`, component by component with `f64::min` and `f64::max`: exact,
/// associative and commutative, a NaN ignored (glam's `min` and `max` are neither for NaN), so a reduction
/// gives the same box in any order.
pub(crate) fn box_union((lo, hi): (DVec3, DVec3), (l, h): (DVec3, DVec3)) -> (DVec3, DVec3) {
    let min = DVec3::new(lo.x.min(l.x), lo.y.min(l.y), lo.z.min(l.z));
    (min, DVec3::new(hi.x.max(h.x), hi.y.max(h.y), hi.z.max(h.z)))
}

/// A whole scene as data.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct SceneDesc {
    /// The camera.
    pub camera: CameraDesc,
    /// Sampling, depth, background.
    pub render: RenderDesc,
    /// Materials; primitives refer to them by index.
    pub materials: Vec<Material>,
    /// Point lights.
    pub lights: Vec<LightDesc>,
    /// Plain spheres: ids 0.. in this order.
    pub spheres: Vec<SphereDesc>,
    /// Per-sphere colours: empty, or one per sphere of `spheres` in its order, each replacing its sphere's
    /// material colour (the ambient and diffuse base; a checker's odd cells keep theirs). Particle files
    /// and arrays of spheres give every sphere its colour this way, beside one shared material, rather
    /// than a material per colour. Compile ignores a list of another length (a description built by hand),
    /// as it degrades other inconsistent hand-built input: the spheres keep their materials' colours.
    pub sphere_colors: Vec<Rgb8>,
    /// The registered kinds' primitives ([`crate::kinds`]: polygons, ellipsoids, planes, open cones, tori):
    /// ids after the spheres, kind by kind in the registry's order (a polygon one id however it is
    /// triangulated).
    pub kinds: KindDescs,
}
