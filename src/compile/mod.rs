//! Compile: a validated [`SceneDesc`] becomes the immutable [`Scene`] every render thread shares — camera frame
//! precomputed, spheres in SoA arrays, transforms inverted once, everything rounded to f32 once.
//!
//! **Rendering space.** The compiled scene lives in a space whose origin is the eye (pbrt-v4's
//! "camera-world" space, without its rotation): every position is `p − eye` computed in f64 from the scene
//! file's values and rounded once to f32. Near the eye, where the image is made, f32 then resolves the
//! scene as finely as it can anywhere, however far from the world origin the scene sits, and camera rays
//! start at exactly zero, which lets each sphere carry an exact eye term (`crate::geometry::eye_term`).
//! A scene far from the eye instead gets its origin at its own centre, and camera rays start just short of
//! it (`RenderingFrame`). Directions, distances along rays and normals do not depend on the origin, so
//! images and ids mean what they meant in world space; [`Scene::origin`] maps points back.

pub(crate) mod features;
mod frame;
pub mod load;
pub mod memory;

use crate::accel::{Geometry, LightBuffer, Particles};
use crate::bvh::{self, BuildOptions, BuildStats, Builder, Bvh, SINGLE_RAY_MAX_LANES};
use crate::camera::{Camera, CameraError};
use crate::io::f32r::MappedRecords;
use crate::kinds::sphere::{SphereDesc, Spheres};
use crate::math::{Rgb, Vec3f, V3};
use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::BvhBuildParams;
use rayon::prelude::*;

use crate::scene::desc::{Ao, Falloff, Material, RenderDesc, SceneDesc, Shade};
pub(crate) use frame::RenderingFrame;

/// A point light ready for shading.
#[derive(Clone, Copy, Debug)]
pub struct Light {
    /// Position.
    pub(crate) position: Vec3f,
    /// Colour times intensity.
    pub(crate) color: Rgb,
    /// Distance falloff.
    pub(crate) falloff: Falloff,
    /// The light is exactly at the eye (a headlight) in a scene rendered in the eye's frame, where camera
    /// rays start at the rendering space's origin: their hits then see it without a shadow ray
    /// (`shade::Tracer::direct`).
    at_eye: bool,
}

impl Light {
    /// Whether camera rays' hits see the light without shadow rays: it is exactly at the eye, in the eye's
    /// frame.
    pub(crate) fn at_eye(&self) -> bool {
        self.at_eye
    }
}

/// What a render reads: immutable, shared by all threads.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The camera's frame rounded to f32 (resolution, and f32 points on the image plane).
    pub camera: Camera<f32>,
    /// The camera in f64, in rendering space (its eye is the origin but in a far scene, `RenderingFrame`):
    /// camera rays are computed from it and rounded once (`Camera::rays`).
    pub camera_f64: Camera<f64>,
    /// Where the rendering space's origin (the eye, or a far scene's centre) is in the scene file's world
    /// space: a world point is `origin + p` for a rendering-space point `p`.
    pub origin: glam::DVec3,
    /// Sampling, depth, background, ambient.
    pub render: RenderDesc,
    /// All primitives.
    pub geometry: Geometry,
    /// Materials by index.
    pub materials: Vec<Material>,
    /// Point lights.
    pub lights: Vec<Light>,
    /// What building the BVH (and the particle tree) cost (zero without one).
    pub build: BuildStats,
    /// Why the spheres are in the particle tree, when `--accel auto` put them there for lack of memory.
    pub(crate) accel_note: Option<String>,
    /// The scene has spheres and some item of a registered kind with a lane form of its surface and a plain
    /// (unchecked) material: only
    /// then can a packet's surface be split into its spheres' and that item's lane forms
    /// (`shade::Tracer::split_surface`); elsewhere shading does not look for such packets.
    pub(crate) split_surfaces: bool,
}

/// How a scene is compiled: the search structures and how their walks run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CompileOptions {
    /// BVH or brute force.
    pub accel: Accel,
    /// obvhs's build preset.
    pub preset: BvhPreset,
    /// Packet walks first test nodes and leaf items against a shared-origin packet's frustum
    /// (`crate::bvh::Bvh::frustum_culling`).
    pub frustum_culling: bool,
    /// Subtrees entered by at most this many live lanes are walked one ray at a time
    /// (`crate::bvh::SINGLE_RAY_MAX_LANES` by default; 0 never switches).
    pub single_ray_lanes: u32,
    /// Keep each BVH's binary tree and have single rays (K = 1) walk it one box and one primitive at a time:
    /// the scalar path (`--lanes scalar`, `crate::accel::Geometry::set_scalar_walk`). Off by default, so
    /// other renders pay nothing for it.
    pub scalar: bool,
}

impl Default for CompileOptions {
    fn default() -> Self {
        CompileOptions {
            accel: Accel::Auto,
            preset: BvhPreset::default(),
            frustum_culling: true,
            single_ray_lanes: SINGLE_RAY_MAX_LANES,
            scalar: false,
        }
    }
}

/// How primitives are searched.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Accel {
    /// A BVH for each kind with `BVH_MIN_SPHERES` items or more, brute force below.
    #[default]
    Auto,
    /// A BVH for every kind with items.
    Bvh,
    /// Always brute force.
    Brute,
    /// Spheres in the particle tree (`crate::accel::pkd`: 5 bytes per sphere beside the spheres), other
    /// kinds as [`Accel::Auto`].
    Particles,
}

/// How the BVHs are built: bareray's builders (Morton order over binned SAH, or binned SAH alone), or obvhs
/// with one of its `BvhBuildParams` presets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BvhPreset {
    /// The default: the spheres' tree split by Morton order down to ranges of 1024 spheres, by the binned SAH
    /// below (`bvh/morton.rs`); the other kinds' trees by the SAH alone. Its BVH build takes 0.68–0.89 of the
    /// SAH's time (1e5 to 1e7 spheres, balls6) and its tree traces within 4% of the SAH's (PERF.md, "Tree
    /// builder").
    #[default]
    Morton,
    /// bareray's binned SAH builder at every level: the default's memory, a longer build.
    Sah,
    /// obvhs `fastest_build`: leaves of one sphere, no reinsertion.
    Fastest,
    /// obvhs `very_fast_build`: the quickest build; on uniform random fields it also traces faster than
    /// `fast`, on sphereflakes slower (docs/perf-log/2026-11.md, "Tried, measured, not kept").
    VeryFast,
    /// obvhs `fast_build`.
    Fast,
    /// obvhs `medium_build`.
    Medium,
    /// obvhs `slow_build`.
    Slow,
}

impl BvhPreset {
    /// The builder.
    pub(crate) fn builder(self) -> Builder {
        let params = match self {
            BvhPreset::Morton => return Builder::MORTON_SPHERES,
            BvhPreset::Sah => return Builder::SAH_SPHERES,
            BvhPreset::Fastest => BvhBuildParams::fastest_build(),
            BvhPreset::VeryFast => BvhBuildParams::very_fast_build(),
            BvhPreset::Fast => BvhBuildParams::fast_build(),
            BvhPreset::Medium => BvhBuildParams::medium_build(),
            BvhPreset::Slow => BvhBuildParams::slow_build(),
        };
        Builder::Obvhs(params)
    }
}

/// Below this many spheres brute force is used: with 2–3 spheres brute force measured faster, from 4
/// spheres on the BVH (PERF.md, Register: "No BVH for a kind with fewer than 4 items"; docs/perf-log/
/// 2026-11.md, "BVH crossover").
pub(crate) const BVH_MIN_SPHERES: usize = 4;

/// The largest coordinate magnitude in rendering space (origin `origin`) a ray can start from or pass near:
/// spheres' far sides, lights, where camera rays start (the eye, or a far scene's start points: those
/// through the image's corners bound them).
fn reach(
    desc: &SceneDesc,
    extra: Option<[glam::DVec3; 2]>,
    origin: glam::DVec3,
    camera: &Camera<f64>,
) -> f32 {
    let mag = |p: glam::DVec3| (p - origin).abs().max_element();
    let extra = extra.into_iter().flatten().map(mag);
    // A maximum is exact and (NaN ignored) independent of order: the same reach however the list is cut.
    let sphere = |s: &SphereDesc| mag(s.center) + s.radius;
    let spheres = desc.spheres.par_iter().with_min_len(1 << 14).map(sphere).reduce(|| 0.0, f64::max);
    let spheres = std::iter::once(spheres).chain(extra);
    let (w, h) = (f64::from(camera.width), f64::from(camera.height));
    let corner = |(x, y): (f64, f64)| {
        let o = camera.ray(x, y).origin;
        o.x.abs().max(o.y.abs()).max(o.z.abs())
    };
    let starts = [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)].map(corner);
    let lights = desc.lights.iter().map(|l| mag(l.position)).chain(starts);
    let kinds = desc.kinds.world_boxes().into_iter().flatten().map(mag);
    spheres.chain(lights).chain(kinds).fold(0.0, f64::max) as f32
}

impl Scene {
    /// A world-space point (the scene file's coordinates) in rendering space, rounded once to f32: where a
    /// ray made from world coordinates starts.
    pub fn to_rendering(&self, world: glam::DVec3) -> Vec3f {
        V3::from(world - self.origin).to_f32()
    }

    /// Memory per sphere of the spheres' arrays and their BVH's nodes, or of the particle tree's records and
    /// keys (what `--stats` and `bench` report).
    pub fn bytes_per_sphere(&self) -> f64 {
        let (s, p) = (&self.geometry.spheres, &self.geometry.particles);
        if !p.is_empty() {
            return (p.record_bytes() + p.overhead_bytes()) as f64 / p.len() as f64;
        }
        let nodes = self.geometry.sphere_bvh.as_ref().map_or(0, Bvh::bytes);
        (s.bytes() + nodes) as f64 / s.len().max(1) as f64
    }

    /// Compiles a description. Fails only on a camera that cannot form an image; everything else was
    /// validated by the reader.
    ///
    /// A scene built in code, compiled:
    ///
    /// ```
    /// use bareray::compile::Scene;
    /// use bareray::kinds::sphere::SphereDesc;
    /// use bareray::math::Rgb;
    /// use bareray::scene::desc::{LightDesc, Material, SceneDesc};
    /// use glam::DVec3;
    ///
    /// let desc = SceneDesc {
    ///     materials: vec![Material { color: Rgb::new(0.9, 0.3, 0.2), ..Material::default() }],
    ///     lights: vec![LightDesc { position: DVec3::new(5.0, 5.0, -5.0), color: Rgb::all(1.0), falloff: Default::default() }],
    ///     spheres: (0..10)
    ///         .map(|i| SphereDesc { center: DVec3::new(i as f64 - 4.5, 0.0, 0.0), radius: 0.4, material: 0 })
    ///         .collect(),
    ///     ..SceneDesc::default() // camera at (0, 0, −5) looking at the origin, 640×480
    /// };
    /// let scene = Scene::compile(&desc)?;
    /// assert_eq!(scene.geometry.len(), 10);
    /// # Ok::<(), bareray::camera::CameraError>(())
    /// ```
    pub fn compile(desc: &SceneDesc) -> Result<Scene, CameraError> {
        Self::compile_with_options(desc, CompileOptions::default())
    }

    /// Compiles with the given options.
    pub fn compile_with_options(desc: &SceneDesc, options: CompileOptions) -> Result<Scene, CameraError> {
        let (mut scene, job) = Self::assemble(desc, options, None)?;
        scene.build_bvh(job);
        Ok(scene)
    }

    /// Compiles `desc` (whose own spheres, if any, are compiled as usual) with the spheres of a mapped
    /// `.f32r` file in the particle tree, built in the mapping's private pages: no copy of the records is
    /// made. Their bounds (the mapping's, [`MappedRecords::bounds`]) count for the culling padding and the
    /// default ambient occlusion distance.
    pub(crate) fn compile_mapped(
        desc: SceneDesc,
        records: MappedRecords,
        options: CompileOptions,
    ) -> Result<Scene, CameraError> {
        let (mut scene, job) = Self::assemble(&desc, options, Some(records.bounds()))?;
        drop(desc);
        let clock = std::time::Instant::now();
        let mut particles = Particles::from_store(Box::new(records), scene.origin, job.options.pad);
        particles.frustum_culling = options.frustum_culling;
        scene.build +=
            BuildStats { seconds: clock.elapsed().as_secs_f64(), node_bytes: particles.overhead_bytes() };
        scene.geometry.particles = particles;
        scene.build_bvh(job);
        Ok(scene)
    }

    /// [`Scene::compile_with_options`] taking the description, which is freed before the BVH build: the
    /// build is the peak of a large scene's memory, and the description's spheres (40 bytes each, in f64)
    /// are no longer needed then.
    pub(crate) fn compile_owned(desc: SceneDesc, options: CompileOptions) -> Result<Scene, CameraError> {
        let (mut scene, job) = Self::assemble(&desc, options, None)?;
        drop(desc);
        scene.build_bvh(job);
        Ok(scene)
    }

    /// Everything but the BVH: the scene without one, and the build it needs, if any.
    /// `extra` is the world box of spheres compiled apart (a mapped field's).
    fn assemble(
        desc: &SceneDesc,
        options: CompileOptions,
        extra: Option<[glam::DVec3; 2]>,
    ) -> Result<(Scene, BvhJob), CameraError> {
        let CompileOptions { accel, preset, frustum_culling, single_ray_lanes, scalar } = options;
        let frame = RenderingFrame::of(desc, extra);
        let origin = frame.origin;
        let mut camera_f64 = Camera::new(&desc.camera)?;
        camera_f64.eye = V3::from(desc.camera.eye - origin);
        camera_f64.start = frame.start;
        let mut geometry = Geometry::default();
        let pad = bvh::padding(reach(desc, extra, origin, &camera_f64));
        let mut build = BuildStats::default();
        // Per-sphere colours go with the spheres, whichever structure holds them; a list of another length
        // (a description built by hand) is ignored, as `SceneDesc::sphere_colors` says.
        let colors = match desc.sphere_colors.len() == desc.spheres.len() {
            true => desc.sphere_colors.clone(),
            false => Vec::new(),
        };
        if accel == Accel::Particles {
            let clock = std::time::Instant::now();
            let records =
                desc.spheres.par_iter().map(|s| [s.center.x, s.center.y, s.center.z, s.radius]).collect();
            let material = desc.spheres.par_iter().map(|s| s.material).collect();
            geometry.particles = Particles::from_f64(records, material, colors, origin, pad);
            geometry.particles.frustum_culling = frustum_culling;
            build.seconds = clock.elapsed().as_secs_f64();
            build.node_bytes = geometry.particles.overhead_bytes();
        } else {
            let sphere = |i: usize| {
                let s = &desc.spheres[i];
                (V3::from(s.center - origin), s.radius, s.material)
            };
            geometry.spheres = Spheres::from_exact(desc.spheres.len(), sphere);
            geometry.spheres.color = colors;
        }
        // obvhs cannot order boxes with infinite or NaN corners; readers reject such input, and a scene built
        // by hand with them falls back to brute force rather than failing.
        let sp = &geometry.spheres;
        let finite_slice = |v: &[f32]| v.iter().fold(true, |all, x| all & x.is_finite());
        let finite = [&sp.cx, &sp.cy, &sp.cz, &sp.r].iter().all(|v| v.par_chunks(1 << 14).all(finite_slice));
        geometry.kinds = desc.kinds.compile(origin);
        let wants = |items: usize| wants_tree(accel, items);
        let mut materials = desc.materials.clone();
        if materials.is_empty() {
            materials.push(Material::default());
        }
        let lights = desc
            .lights
            .iter()
            .map(|l| {
                let position = V3::from(l.position - origin).to_f32();
                let at_eye = frame.start == 0.0 && position == Vec3f::default();
                Light { position, color: l.color, falloff: l.falloff, at_eye }
            })
            .collect::<Vec<_>>();
        let bounces = features::bounces(desc.render.max_depth, &materials);
        let job = BvhJob {
            accel,
            spheres: finite && wants(geometry.spheres.len()),
            shadows: light_buffers_pay(desc, &materials),
            bounces,
            options: BuildOptions {
                pad,
                builder: preset.builder(),
                // The 8-wide single-ray trees serve the K = 1 tracer's secondary and ambient occlusion
                // rays: only scenes that trace them pay for their build.
                single_ray_tree: features::casts_shadows(&lights, &materials, desc.render.max_depth)
                    || bounces
                    || matches!(desc.render.shade, Shade::Ao(_)),
                leaf_links: true,
                scalar_tree: scalar,
                frustum_culling,
                single_ray_lanes,
            },
        };
        let plain = |k: usize| {
            let material = geometry.kinds.material_in_lanes(k).and_then(|m| materials.get(m as usize));
            material.is_some_and(|m| m.checker.is_none())
        };
        let split_surfaces = !geometry.spheres.is_empty() && (0..geometry.kinds.len()).any(plain);
        let scene = Scene {
            camera: camera_f64.to_f32(),
            camera_f64,
            origin,
            render: RenderDesc { shade: resolved_shade(desc, extra), ..desc.render },
            geometry,
            materials,
            lights,
            build,
            accel_note: None,
            split_surfaces,
        };
        Ok((scene, job))
    }

    /// Builds the BVHs `job` asks for, reordering each kind's items into its leaf order.
    fn build_bvh(&mut self, job: BvhJob) {
        let g = &mut self.geometry;
        if job.spheres {
            let pad = job.options.pad;
            let s = &g.spheres;
            let item_box = |i: usize| {
                let c = Vec3A::new(s.cx[i], s.cy[i], s.cz[i]);
                let r = Vec3A::splat(s.r[i] + pad);
                Aabb { min: c - r, max: c + r }
            };
            let (tree, spheres, stats) =
                bvh::build(s.len(), item_box, job.options, |order| s.permuted(order));
            (g.spheres, g.sphere_bvh) = (spheres, Some(tree));
            self.build += stats;
            if job.shadows {
                let clock = std::time::Instant::now();
                let spheres = &g.spheres;
                let serves = |l: &Light| job.bounces || !l.at_eye();
                g.light_buffers = (self.lights.par_iter())
                    .map(|l| serves(l).then(|| LightBuffer::new(l.position, spheres, pad)).flatten())
                    .collect();
                let bytes = g.light_buffers.iter().flatten().map(LightBuffer::bytes).sum();
                self.build += BuildStats { seconds: clock.elapsed().as_secs_f64(), node_bytes: bytes };
            }
        }
        // The registered kinds' items (triangles, ellipsoids, …) cost more to test than a sphere: their trees
        // split smaller ranges.
        let dearer = BuildOptions {
            builder: job.options.builder.for_dearer_items(),
            leaf_links: false,
            ..job.options
        };
        let build = &mut self.build;
        g.kinds.build_trees(
            |n| wants_tree(job.accel, n),
            |n, bounds| {
                let item_box = |j: usize| padded(bounds(j), job.options.pad);
                let (tree, order, stats) = bvh::build(n, item_box, dearer, |order| order.to_vec());
                *build += stats;
                (tree, order)
            },
        );
    }
}

/// Whether the spheres get a light buffer per point light ([`LightBuffer`]): when shading casts shadow rays
/// toward lights, the camera rays are at least [`LIGHT_BUFFER_MIN_RAYS_PER_SPHERE`] times the spheres, and
/// there are at most [`LIGHT_BUFFER_MAX_SPHERES`].
fn light_buffers_pay(desc: &SceneDesc, materials: &[Material]) -> bool {
    let camera_rays =
        f64::from(desc.camera.width) * f64::from(desc.camera.height) * desc.render.pattern.rays_per_pixel();
    features::lights_shade(!desc.lights.is_empty(), materials)
        && !matches!(desc.render.shade, Shade::Ao(_))
        && desc.spheres.len() <= LIGHT_BUFFER_MAX_SPHERES
        && desc.spheres.len() as f64 * LIGHT_BUFFER_MIN_RAYS_PER_SPHERE <= camera_rays
}

/// Below this many camera rays a sphere, building a light's buffer costs more than its shadow rays save
/// (balls5, 2 threads: 15.8 rays a sphere gains 4%, 8.9 loses 2%: PERF.md, "Register", light buffers).
const LIGHT_BUFFER_MIN_RAYS_PER_SPHERE: f64 = 12.0;

/// Light buffers hold up to 8 entries (64 bytes) a sphere a light: past this many spheres (a supersampled
/// still of a large field) they could outweigh the spheres' tree, which serves shadow rays without them.
const LIGHT_BUFFER_MAX_SPHERES: usize = 1 << 20;

/// The scene's shading mode with ambient occlusion's default distance filled in: [`Ao::DEFAULT_REACH`] times
/// the diagonal of the box around every bounded primitive (spheres, ellipsoids, polygons, cones; planes
/// are unbounded), or unlimited when there is none.
fn resolved_shade(desc: &SceneDesc, extra: Option<[glam::DVec3; 2]>) -> Shade {
    match desc.render.shade {
        Shade::Ao(Ao { samples, distance: None }) => {
            let reach = bounded_diagonal(desc, extra) * Ao::DEFAULT_REACH;
            let distance = if reach > 0.0 { reach } else { f64::INFINITY };
            Shade::Ao(Ao { samples, distance: Some(distance) })
        }
        shade => shade,
    }
}

/// The diagonal of the box around every bounded primitive and the box `extra` (0 without any), in f64.
fn bounded_diagonal(desc: &SceneDesc, extra: Option<[glam::DVec3; 2]>) -> f64 {
    frame::bounded_box(desc, extra).map_or(0.0, |(lo, hi)| (hi - lo).length())
}

/// The box `(lo, hi)` widened by `pad` on every side, for the BVH build.
fn padded((lo, hi): (Vec3f, Vec3f), pad: f32) -> Aabb {
    let pad = Vec3A::splat(pad);
    Aabb { min: Vec3A::new(lo.x, lo.y, lo.z) - pad, max: Vec3A::new(hi.x, hi.y, hi.z) + pad }
}

/// Whether a kind with `items` items gets a BVH under `accel`.
fn wants_tree(accel: Accel, items: usize) -> bool {
    match accel {
        Accel::Auto | Accel::Particles => items >= BVH_MIN_SPHERES,
        Accel::Bvh => items > 0,
        Accel::Brute => false,
    }
}

/// The BVH builds that [`Scene::assemble`] found the scene needs.
struct BvhJob {
    /// The acceleration asked for: the registered kinds' trees follow it.
    accel: Accel,
    /// Whether to build the spheres' BVH.
    spheres: bool,
    /// Padding, obvhs preset and single-ray tree, alike for both.
    options: BuildOptions,
    /// Whether the spheres' tree gets a light buffer per point light ([`light_buffers_pay`]).
    shadows: bool,
    /// Whether rays bounce ([`features::bounces`]): else a light at the eye gets no buffer, since only
    /// camera rays' hits shade, and they see it without shadow rays ([`Light::at_eye`]).
    bounces: bool,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::nff;

    /// The default preset builds spheres by Morton order over the SAH; every other kind keeps the SAH.
    #[test]
    fn spheres_default_to_morton_order_and_other_kinds_to_the_sah() {
        assert!(matches!(BvhPreset::default().builder(), Builder::Morton { .. }));
        assert!(matches!(BvhPreset::Sah.builder(), Builder::Sah { .. }));
        for builder in [BvhPreset::Morton.builder(), BvhPreset::Sah.builder()] {
            assert!(matches!(builder.for_dearer_items(), Builder::Sah { node_cost: 1.0 }));
        }
    }

    /// Compiling from a moved description (freed before the build) gives the scene compiling from a borrowed
    /// one gives: the same spheres in the same order, the same trees, lights and materials.
    #[test]
    fn owned_and_borrowed_descriptions_compile_alike() {
        let text = crate::io::generate::flake_nff(2).expect("flake");
        let desc = nff::parse(std::path::Path::new("flake.nff"), &text).expect("parse");
        let borrowed = Scene::compile_with_options(&desc, CompileOptions::default()).expect("compile");
        let owned = Scene::compile_owned(desc, CompileOptions::default()).expect("compile");
        let (a, b) = (&borrowed.geometry, &owned.geometry);
        let arrays = |s: &Spheres| {
            (s.cx.clone(), s.cy.clone(), s.cz.clone(), s.r.clone(), s.material.clone(), s.key.clone())
        };
        assert!(a.spheres.len() > 90, "a level-2 flake has 91 spheres");
        assert_eq!(arrays(&a.spheres), arrays(&b.spheres));
        let (ta, tb) = (a.sphere_bvh.as_ref().expect("bvh"), b.sphere_bvh.as_ref().expect("bvh"));
        assert_eq!(ta.nodes, tb.nodes);
        assert!(ta.wide.is_some(), "a shaded flake gets the single-ray tree");
        assert_eq!(ta.wide, tb.wide);
        assert_eq!(borrowed.build.node_bytes, owned.build.node_bytes);
        assert_eq!(borrowed.lights.len(), owned.lights.len());
        assert_eq!(borrowed.materials, owned.materials);
    }
}
