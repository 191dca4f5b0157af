//! `SceneDesc`: a scene as plain, validated data in f64, whatever file format it came from.
//! Compile (`crate::compile`) turns it into the immutable [`crate::compile::Scene`] the renderer reads.
//!
//! This file holds `SceneDesc`; the camera, the render settings, the shading and the materials and lights
//! have a file each, their items all named `scene::desc::Name`. A sphere's description is its kind's
//! ([`crate::kinds::sphere::SphereDesc`]).

mod camera;
mod materials_lights;
mod render;
mod shade;

pub use self::{
    camera::{Aim, CameraDesc, CameraOverrides, Field, Sweep},
    materials_lights::{Checker, Falloff, LightDesc, Material},
    render::{Filter, FilterKind, Pattern, PostFilter, RenderDesc, Transfer},
    shade::{Ao, Shade},
};
use crate::kinds::sphere::SphereDesc;
use crate::kinds::KindDescs;
use crate::math::Rgb8;

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
