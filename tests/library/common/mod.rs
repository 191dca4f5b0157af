//! Helpers shared by the library's tests: scene builders, the one call of the renderer, scene-file listing,
//! seeded random numbers ([`rng`]), small particle files ([`samples`]), exact f32 → f64 widening ([`wide`]),
//! the f64 oracle the stress tests measure the f32 kernels against ([`oracle`]) and the generated-input
//! runs' hang watchdog ([`watchdog`]). `files`, `samples` and `watchdog` serve the binary's tests too
//! (`tests/common/`).

mod files;
pub mod oracle;
pub mod rng;
pub mod samples;
pub mod watchdog;
pub mod wide;

pub use files::scene_files;

use std::path::Path;

use bareray::camera::CameraError;
use bareray::compile::{Accel, BvhPreset, CompileOptions, Scene};
use bareray::film::Image;
use bareray::geometry::ShapeKind;
use bareray::io::toml;
use bareray::kinds::sphere::SphereDesc;
use bareray::kinds::KindDescs;
use bareray::render::{render_lanes, thread_pool};
use bareray::scene::desc::{CameraDesc, SceneDesc};
use glam::{DAffine3, DVec3};

/// f32 unit roundoff (half an ulp of 1).
pub const EPS32: f64 = f32::EPSILON as f64 / 2.0;

/// True when `STRESS_MEASURE` is set: the stress tests then print their measurements without asserting
/// their bounds, for re-measuring after a kernel change.
pub fn measuring() -> bool {
    std::env::var("STRESS_MEASURE").is_ok()
}

/// A camera looking from `eye` at `look` with a horizontal field of view of `hfov` degrees, rays through
/// pixel centres.
pub fn camera(eye: DVec3, look: DVec3, up: DVec3, hfov: f64, width: u32, height: u32) -> CameraDesc {
    CameraDesc::looking_at(eye, look, up, hfov, width, height)
}

/// A sphere of material 0.
pub fn sphere(c: DVec3, r: f64) -> SphereDesc {
    SphereDesc { center: c, radius: r, material: 0 }
}

/// A generic shape placed by an affine map (an ellipsoid or a plane, material 0), for [`shapes`].
pub fn shape(kind: ShapeKind, world_from_object: DAffine3) -> (ShapeKind, DAffine3) {
    (kind, world_from_object)
}

/// The registered kinds' descriptions holding these shapes (ellipsoids and planes) alone.
pub fn shapes(list: impl IntoIterator<Item = (ShapeKind, DAffine3)>) -> KindDescs {
    let mut kinds = KindDescs::default();
    list.into_iter().for_each(|(kind, m)| kinds.push_shape(kind, m));
    kinds
}

pub fn compile(desc: &SceneDesc) -> Scene {
    Scene::compile(desc).expect("scene compiles")
}

/// The scene compiled with `accel` (every other option at its default).
pub fn compile_with(desc: &SceneDesc, accel: Accel) -> Result<Scene, CameraError> {
    Scene::compile_with_options(desc, CompileOptions { accel, ..CompileOptions::default() })
}

/// The scene with BVHs by bareray's two builders in turn: the binned SAH's and the Morton order's.
pub fn compile_by_each_builder(desc: &SceneDesc) -> [(&'static str, Scene); 2] {
    let with = |preset| {
        let options = CompileOptions { accel: Accel::Bvh, preset, ..CompileOptions::default() };
        Scene::compile_with_options(desc, options).expect("the scene compiles")
    };
    [("sah", with(BvhPreset::Sah)), ("morton", with(BvhPreset::Morton))]
}

pub fn parse_toml(src: &str) -> SceneDesc {
    toml::parse(Path::new("test.toml"), src).expect("scene parses")
}

/// The one place the renderer is called (8 lanes), so an API change (lanes, options) is adapted here only.
pub fn render(scene: &Scene, threads: usize) -> Image {
    render_lanes(scene, 8, &thread_pool(Some(threads)).expect("thread pool"), &()).image
}
