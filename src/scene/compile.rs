//! Compile: a validated [`SceneDesc`] becomes the immutable [`Scene`] every render thread shares — camera frame
//! precomputed, spheres in SoA arrays, transforms inverted once, everything rounded to f32 once.
//!
//! **Rendering space.** The compiled scene lives in a space whose origin is the eye (pbrt-v4's
//! "camera-world" space, without its rotation): every position is `p − eye` computed in f64 from the scene
//! file's values and rounded once to f32. Near the eye, where the image is made, f32 then resolves the
//! scene as finely as it can anywhere, however far from the world origin the scene sits, and camera rays
//! start at exactly zero, which lets each sphere carry an exact eye term ([`crate::accel::eye_term`]).
//! Directions, distances along rays and normals do not depend on the origin, so images, depths and ids
//! mean what they meant in world space; [`Scene::origin`] maps points back.

use crate::accel::bvh::{self, BuildStats};
use crate::accel::{Geometry, Polygons};
use crate::camera::{Camera, CameraError};
use crate::geometry::polygon::{newell_normal, triangulate};
use crate::geometry::Shape;
use crate::math::{Rgb, Vec3f, V3};
use glam::DAffine3;
use obvhs::BvhBuildParams;

use super::desc::{Falloff, Material, PolygonDesc, RenderDesc, SceneDesc};
use super::features;

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
    /// The camera's frame rounded to f32 (resolution, and f32 points on the image plane).
    pub camera: Camera<f32>,
    /// The camera in f64 (in rendering space: its eye is the origin): camera rays are computed from it and
    /// rounded once ([`Camera::rays`]); the f64 accuracy twin uses it as it is.
    pub camera_f64: Camera<f64>,
    /// Where the rendering space's origin (the eye) is in the scene file's world space: a world point is
    /// `origin + p` for a rendering-space point `p`.
    pub origin: glam::DVec3,
    /// Sampling, depth, background, ambient.
    pub render: RenderDesc,
    /// All primitives.
    pub geometry: Geometry,
    /// Materials by index.
    pub materials: Vec<Material>,
    /// Point lights.
    pub lights: Vec<Light>,
    /// What building the BVH cost (zero without one).
    pub build: BuildStats,
}

/// How spheres are searched.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Accel {
    /// BVH from [`BVH_MIN_SPHERES`] spheres on, brute force below.
    #[default]
    Auto,
    /// Always a BVH.
    Bvh,
    /// Always brute force.
    Brute,
}

/// The obvhs build preset for the BVH over the spheres (its `BvhBuildParams` presets).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum BvhPreset {
    /// obvhs `fastest_build`: leaves of one sphere, no reinsertion.
    Fastest,
    /// obvhs `very_fast_build`: the quickest build; on uniform random fields it also traces faster than
    /// `fast`, on sphereflakes 8–10% slower (docs/perf-log/2026-11.md).
    VeryFast,
    /// obvhs `fast_build`, the default: the best traced speed on structured scenes.
    #[default]
    Fast,
    /// obvhs `medium_build`.
    Medium,
    /// obvhs `slow_build`.
    Slow,
}

impl BvhPreset {
    /// The obvhs parameters.
    pub fn params(self) -> BvhBuildParams {
        match self {
            BvhPreset::Fastest => BvhBuildParams::fastest_build(),
            BvhPreset::VeryFast => BvhBuildParams::very_fast_build(),
            BvhPreset::Fast => BvhBuildParams::fast_build(),
            BvhPreset::Medium => BvhBuildParams::medium_build(),
            BvhPreset::Slow => BvhBuildParams::slow_build(),
        }
    }
}

/// Below this many spheres brute force is used: with 2–3 spheres brute force measured 8–13% faster, from 4
/// spheres on the BVH was already faster (docs/perf-log/2026-11.md, "BVH crossover").
pub const BVH_MIN_SPHERES: usize = 4;

/// The largest coordinate magnitude in rendering space a ray can start from or pass near: spheres' far
/// sides, lights (the eye is the origin).
fn reach(desc: &SceneDesc) -> f32 {
    let eye = desc.camera.eye;
    let spheres = desc.spheres.iter().map(|s| (s.center - eye).abs().max_element() + s.radius);
    let lights = desc.lights.iter().map(|l| (l.position - eye).abs().max_element());
    spheres.chain(lights).fold(0.0, f64::max) as f32
}

impl Scene {
    /// A world-space point (the scene file's coordinates) in rendering space, rounded once to f32: where a
    /// ray made from world coordinates starts.
    pub fn to_rendering(&self, world: glam::DVec3) -> Vec3f {
        V3::from(world - self.origin).to_f32()
    }

    /// Memory per sphere of the spheres' arrays and the BVH nodes (what `--stats` and `bench` report).
    pub fn bytes_per_sphere(&self) -> f64 {
        let s = &self.geometry.spheres;
        (s.bytes() + self.build.node_bytes) as f64 / s.len().max(1) as f64
    }

    /// Compiles a description. Fails only on a camera that cannot form an image; everything else was
    /// validated by the reader.
    pub fn compile(desc: &SceneDesc) -> Result<Scene, CameraError> {
        Self::compile_with(desc, Accel::Auto)
    }

    /// Compiles with a chosen acceleration structure for the spheres.
    pub fn compile_with(desc: &SceneDesc, accel: Accel) -> Result<Scene, CameraError> {
        Self::compile_with_preset(desc, accel, BvhPreset::default())
    }

    /// Compiles with a chosen acceleration structure and BVH build preset.
    pub fn compile_with_preset(
        desc: &SceneDesc,
        accel: Accel,
        preset: BvhPreset,
    ) -> Result<Scene, CameraError> {
        let (mut scene, job) = Self::assemble(desc, accel, preset)?;
        scene.build_bvh(job);
        Ok(scene)
    }

    /// [`Scene::compile_with_preset`] taking the description, which is freed before the BVH build: the
    /// build is the peak of a large scene's memory, and the description's spheres (40 bytes each, in f64)
    /// are no longer needed then.
    pub fn compile_owned(desc: SceneDesc, accel: Accel, preset: BvhPreset) -> Result<Scene, CameraError> {
        let (mut scene, job) = Self::assemble(&desc, accel, preset)?;
        drop(desc);
        scene.build_bvh(job);
        Ok(scene)
    }

    /// Everything but the BVH: the scene without one, and the build it needs, if any.
    fn assemble(
        desc: &SceneDesc,
        accel: Accel,
        preset: BvhPreset,
    ) -> Result<(Scene, Option<BvhJob>), CameraError> {
        // The readers produce cones, and `geometry::Cones` and `geometry::intersect_cone` can store and
        // intersect them, but no query (brute force, BVH, packets) or shader visits them yet: rendering
        // such a scene would silently drop them.
        if !desc.cones.is_empty() {
            return Err(CameraError::Field(format!(
                "the scene has {} cone(s)/cylinder(s) (NFF `c`, TOML [[cones]]), which bareray reads but \
                 cannot render yet",
                desc.cones.len()
            )));
        }
        let origin = desc.camera.eye;
        let mut camera_f64 = Camera::new(&desc.camera)?;
        camera_f64.eye = V3::all(0.0);
        let mut geometry = Geometry { origin: V3::from(origin).to_f32(), ..Geometry::default() };
        geometry.spheres.reserve_exact(desc.spheres.len());
        for s in &desc.spheres {
            geometry.spheres.push_exact(V3::from(s.center - origin), s.radius, s.material);
        }
        let to_rendering = DAffine3::from_translation(-origin);
        geometry.shapes = desc
            .shapes
            .iter()
            .map(|s| Shape::placed(s.kind, &(to_rendering * s.world_from_object), s.material).to_f32())
            .collect();
        for p in &desc.polygons {
            push_polygon(&mut geometry.polygons, p, origin);
        }
        // obvhs cannot order boxes with infinite or NaN corners; readers reject such spheres, and a scene
        // built by hand with them falls back to brute force rather than failing.
        let sp = &geometry.spheres;
        let finite = [&sp.cx, &sp.cy, &sp.cz, &sp.r].iter().all(|v| v.iter().all(|x| x.is_finite()));
        let use_bvh = finite
            && match accel {
                Accel::Auto => geometry.spheres.len() >= BVH_MIN_SPHERES,
                Accel::Bvh => !geometry.spheres.is_empty(),
                Accel::Brute => false,
            };
        let mut materials = desc.materials.clone();
        if materials.is_empty() {
            materials.push(Material::default());
        }
        let job = use_bvh.then(|| BvhJob {
            pad: bvh::padding(reach(desc)),
            params: preset.params(),
            // The 8-wide single-ray tree serves the scalar tracer's secondary rays: only scenes that
            // trace them pay for its build.
            single_ray_tree: features::lights_shade(!desc.lights.is_empty(), &materials)
                || features::bounces(desc.render.max_depth, &materials),
        });
        let lights = desc
            .lights
            .iter()
            .map(|l| Light {
                position: V3::from(l.position - origin).to_f32(),
                color: l.color,
                falloff: l.falloff,
            })
            .collect();
        let scene = Scene {
            camera: camera_f64.to_f32(),
            camera_f64,
            origin,
            render: desc.render,
            geometry,
            materials,
            lights,
            build: BuildStats::default(),
        };
        Ok((scene, job))
    }

    /// Builds the BVH over the spheres (reordering them) when `job` asks for one.
    fn build_bvh(&mut self, job: Option<BvhJob>) {
        if let Some(job) = job {
            let (tree, stats) =
                bvh::build(&mut self.geometry.spheres, job.pad, job.params, job.single_ray_tree);
            self.geometry.bvh = Some(tree);
            self.build = stats;
        }
    }
}

/// A BVH build that [`Scene::assemble`] found the scene needs.
struct BvhJob {
    /// Box padding for the scene's extent ([`bvh::padding`]).
    pad: f32,
    /// obvhs's settings for the chosen preset.
    params: obvhs::BvhBuildParams,
    /// Whether to build the 8-wide single-ray tree too.
    single_ray_tree: bool,
}

/// Triangulates one polygon into `out` (in f64, moved to rendering space by `−origin`, then rounded). A polygon
/// the readers would have rejected (a `SceneDesc` built by hand) still gets its id, with a fan of possibly
/// degenerate triangles, which the kernel can only miss or hit harmlessly: ids must not shift.
fn push_polygon(out: &mut Polygons, p: &PolygonDesc, origin: glam::DVec3) {
    let n = p.vertices.len() as u32;
    let triangles =
        triangulate(&p.vertices).unwrap_or_else(|_| (1..n.max(2) - 1).map(|i| [0, i, i + 1]).collect());
    let vertices: Vec<Vec3f> = p.vertices.iter().map(|v| V3::from(*v - origin).to_f32()).collect();
    let unit = |v: glam::DVec3| V3::from(v.normalize_or_zero()).to_f32();
    let normals = p
        .normals
        .as_ref()
        .filter(|ns| ns.len() == p.vertices.len())
        .map(|ns| ns.iter().map(|v| unit(*v)).collect::<Vec<_>>());
    out.push(&vertices, normals.as_deref(), &triangles, unit(newell_normal(&p.vertices)), p.material);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::nff;

    /// Cones are read but not yet rendered: compile says so rather than dropping them.
    #[test]
    fn scenes_with_cones_are_refused_with_a_message() {
        let text =
            "v\nfrom 0 0 -5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 0\nresolution 8 8\nc 0 0 0 1 0 1 0 1\n";
        let desc = nff::parse(std::path::Path::new("c.nff"), text).expect("parse");
        let e = Scene::compile(&desc).expect_err("cones are refused");
        assert!(e.to_string().contains("1 cone(s)/cylinder(s)"), "{e}");
        assert!(Scene::compile(&crate::scene::SceneDesc { cones: vec![], ..desc }).is_ok());
    }

    /// Compiling from a moved description (freed before the build) gives the scene compiling from a borrowed
    /// one gives: the same spheres in the same order, the same trees, lights and materials.
    #[test]
    fn owned_and_borrowed_descriptions_compile_alike() {
        let text = crate::scene::generate::flake_nff(2).expect("flake");
        let desc = nff::parse(std::path::Path::new("flake.nff"), &text).expect("parse");
        let borrowed = Scene::compile_with_preset(&desc, Accel::Auto, BvhPreset::default()).expect("compile");
        let owned = Scene::compile_owned(desc, Accel::Auto, BvhPreset::default()).expect("compile");
        let (a, b) = (&borrowed.geometry, &owned.geometry);
        let arrays = |s: &crate::accel::Spheres| {
            (s.cx.clone(), s.cy.clone(), s.cz.clone(), s.r.clone(), s.material.clone(), s.key.clone())
        };
        assert!(a.spheres.len() > 90, "a level-2 flake has 91 spheres");
        assert_eq!(arrays(&a.spheres), arrays(&b.spheres));
        let (ta, tb) = (a.bvh.as_ref().expect("bvh"), b.bvh.as_ref().expect("bvh"));
        assert_eq!(ta.nodes, tb.nodes);
        assert!(ta.wide.is_some(), "a shaded flake gets the single-ray tree");
        assert_eq!(ta.wide, tb.wide);
        assert_eq!(borrowed.build.node_bytes, owned.build.node_bytes);
        assert_eq!(borrowed.lights.len(), owned.lights.len());
        assert_eq!(borrowed.materials, owned.materials);
    }
}
