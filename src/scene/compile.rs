//! Compile: a validated [`SceneDesc`] becomes the immutable [`Scene`] every render thread shares — camera frame
//! precomputed, spheres in SoA arrays, transforms inverted once, everything rounded to f32 once.

use crate::accel::Geometry;
use crate::camera::{Camera, CameraError};
use crate::geometry::Shape;
use crate::math::affine::normal_to_world;
use crate::math::{Affine, Rgb, Vec3f, V3};

use super::desc::{Falloff, Material, RenderDesc, SceneDesc};

/// A point light ready for shading.
#[derive(Clone, Copy, Debug)]
pub struct Light {
    /// Position.
    pub position: Vec3f,
    /// Colour times intensity.
    pub color: Rgb,
    /// Distance falloff.
    pub falloff: Falloff,
}

/// What a render reads: immutable, shared by all threads.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The f32 camera rays are generated from.
    pub camera: Camera<f32>,
    /// The same camera in f64 (for the accuracy oracle and reports).
    pub camera_f64: Camera<f64>,
    /// Sampling, depth, background, ambient.
    pub render: RenderDesc,
    /// All primitives.
    pub geometry: Geometry,
    /// Materials by index.
    pub materials: Vec<Material>,
    /// Point lights.
    pub lights: Vec<Light>,
}

impl Scene {
    /// Compiles a description. Fails only on a camera that cannot form an image; everything else was
    /// validated by the reader.
    pub fn compile(desc: &SceneDesc) -> Result<Scene, CameraError> {
        let camera_f64 = Camera::new(&desc.camera)?;
        let mut geometry = Geometry::default();
        for s in &desc.spheres {
            geometry.spheres.push(V3::from(s.center).to_f32(), s.radius as f32, s.material);
        }
        geometry.shapes = desc
            .shapes
            .iter()
            .map(|s| Shape {
                kind: s.kind,
                object_from_world: Affine::from_glam(&s.world_from_object.inverse()).to_f32(),
                normal_to_world: normal_to_world(&s.world_from_object).to_f32(),
                material: s.material,
            })
            .collect();
        let lights = desc
            .lights
            .iter()
            .map(|l| Light { position: V3::from(l.position).to_f32(), color: l.color, falloff: l.falloff })
            .collect();
        let mut materials = desc.materials.clone();
        if materials.is_empty() {
            materials.push(Material::default());
        }
        Ok(Scene {
            camera: camera_f64.to_f32(),
            camera_f64,
            render: desc.render,
            geometry,
            materials,
            lights,
        })
    }
}
