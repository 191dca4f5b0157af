//! Compile: a validated [`SceneDesc`] becomes the immutable [`Scene`] every render thread shares — camera frame
//! precomputed, spheres in SoA arrays, transforms inverted once, everything rounded to f32 once.

use crate::accel::{Geometry, Polygons};
use crate::camera::{Camera, CameraError};
use crate::geometry::polygon::{newell_normal, triangulate};
use crate::geometry::Shape;
use crate::math::affine::normal_to_world;
use crate::math::{Affine, Rgb, Vec3f, V3};

use super::desc::{Falloff, Material, PolygonDesc, RenderDesc, SceneDesc};

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
        for p in &desc.polygons {
            push_polygon(&mut geometry.polygons, p);
        }
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

/// Triangulates one polygon into `out` (in f64, then rounded). A polygon the readers would have rejected
/// (a `SceneDesc` built by hand) still gets its id, with a fan of possibly degenerate triangles, which the
/// kernel can only miss or hit harmlessly: ids must not shift.
fn push_polygon(out: &mut Polygons, p: &PolygonDesc) {
    let n = p.vertices.len() as u32;
    let triangles =
        triangulate(&p.vertices).unwrap_or_else(|_| (1..n.max(2) - 1).map(|i| [0, i, i + 1]).collect());
    let vertices: Vec<Vec3f> = p.vertices.iter().map(|v| V3::from(*v).to_f32()).collect();
    let unit = |v: glam::DVec3| V3::from(v.normalize_or_zero()).to_f32();
    let normals = p
        .normals
        .as_ref()
        .filter(|ns| ns.len() == p.vertices.len())
        .map(|ns| ns.iter().map(|v| unit(*v)).collect::<Vec<_>>());
    out.push(&vertices, normals.as_deref(), &triangles, unit(newell_normal(&p.vertices)), p.material);
}
