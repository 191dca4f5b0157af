//! A light at the eye (the headlight of particle files and arrays): camera rays' hits see it without shadow
//! rays, since the way back to the eye is the camera ray's own segment (`shade::Tracer::direct`).
//!
//! 1. A packed field lit from the eye casts no shadow ray and builds no light buffer, and renders the same
//!    bits and counts at every width, thread count and on the scalar path; with its light moved off the eye
//!    it casts one a lit hit and builds the buffer.
//! 2. With mirror spheres the reflections' hits still send theirs, at every width alike; a scene far enough
//!    to be rendered around its own centre keeps them all.
//! 3. The twin agrees: every camera hit's ray toward the eye, traced in f64, meets nothing.

use super::common;

use bareray::accuracy::{run, Options};
use bareray::compile::{CompileOptions, Scene};
use bareray::kinds::sphere::SphereDesc;
use bareray::math::{SplitMix64, V3};
use bareray::render::{render_lanes, thread_pool, Rendered};
use bareray::scene::desc::{LightDesc, Material, SceneDesc};
use common::camera;
use glam::DVec3;

const EYE: DVec3 = DVec3::new(0.4, 0.3, -6.0);

/// 400 spheres, overlapping in places, in a box the camera at [`EYE`] looks into, at 128×96 (30 camera rays
/// a sphere: enough for light buffers); one light at `light`, a second material (index 1) mirrors when
/// `mirrors`, and every third sphere takes it.
fn field(light: DVec3, mirrors: bool) -> SceneDesc {
    let mut rng = SplitMix64::new(7);
    let mut unit = || rng.unit() * 2.0 - 1.0;
    let spheres = (0..400)
        .map(|i| SphereDesc {
            center: DVec3::new(unit() * 2.0, unit() * 1.5, unit() * 2.0),
            radius: 0.12 + 0.1 * unit().abs(),
            material: u32::from(i % 3 == 0),
        })
        .collect();
    let plain = Material { diffuse: 0.8, specular: 0.3, shininess: 20.0, ..Material::default() };
    let mirror = Material { reflect: if mirrors { 0.6 } else { 0.0 }, ..plain };
    SceneDesc {
        camera: camera(EYE, DVec3::ZERO, DVec3::Y, 50.0, 128, 96),
        materials: vec![plain, mirror],
        spheres,
        lights: vec![LightDesc { position: light, color: V3::all(1.0), falloff: Default::default() }],
        ..SceneDesc::default()
    }
}

/// The render on the scalar path, then at every width and 1 or 2 threads: the same bits and counts each
/// time. Returns the scalar render and the scene.
fn at_every_width(desc: &SceneDesc) -> (Rendered, Scene) {
    let options = CompileOptions { scalar: true, ..CompileOptions::default() };
    let mut scene = Scene::compile_with_options(desc, options).expect("compile");
    let reference = render_lanes(&scene, 1, &thread_pool(Some(2)).unwrap(), &());
    assert!(scene.geometry.set_scalar_walk(false));
    for (lanes, threads) in [(1, 1), (4, 2), (8, 1), (16, 2)] {
        let r = render_lanes(&scene, lanes, &thread_pool(Some(threads)).unwrap(), &());
        assert_eq!(r.counts, reference.counts, "counts at lanes {lanes}, threads {threads}");
        let bits = |p: &V3<f32>| [p.x, p.y, p.z].map(f32::to_bits);
        let same = r.image.pixels.iter().zip(&reference.image.pixels).all(|(a, b)| bits(a) == bits(b));
        assert!(same, "lanes {lanes}, threads {threads} differ from the scalar path");
    }
    (reference, scene)
}

#[test]
fn a_light_at_the_eye_needs_no_shadow_rays_from_camera_hits() {
    let (at_eye, scene) = at_every_width(&field(EYE, false));
    let hits = at_eye.image.pixels.iter().filter(|p| p.x > 0.0).count();
    assert!(hits > 128 * 96 / 4, "the field fills the image: {hits} lit pixels");
    assert_eq!(at_eye.counts.shadow, 0, "{:?}", at_eye.counts);
    assert!(scene.geometry.light_buffers.iter().all(Option::is_none), "a buffer no ray would ask");

    // A millimetre off the eye the hits send their shadow rays, one a lit hit, and the light gets a buffer.
    let (off, scene) = at_every_width(&field(EYE + DVec3::new(1e-3, 0.0, 0.0), false));
    assert!(off.counts.shadow as usize > hits * 9 / 10, "{:?} for {hits} hits", off.counts);
    assert!(off.counts.shadow <= off.counts.primary);
    assert!(scene.geometry.light_buffers[0].is_some());
}

/// Seen from 100 times its size away, the field is rendered around its own centre (camera rays no longer
/// start at the rendering space's origin): a light at the eye keeps its shadow rays there, and the light at
/// the centre, now at that origin, is no headlight.
#[test]
fn a_far_scene_keeps_its_headlights_shadow_rays() {
    let far = DVec3::new(0.0, 0.0, -400.0);
    let mut desc = field(far, false);
    desc.camera = camera(far, DVec3::ZERO, DVec3::Y, 1.2, 128, 96);
    let (r, scene) = at_every_width(&desc);
    assert!(!scene.lights[0].at_eye());
    let hits = r.image.pixels.iter().filter(|p| p.x > 0.0).count();
    assert!(hits > 1000, "the field covers {hits} pixels");
    assert!(r.counts.shadow as usize > hits * 9 / 10, "{:?} for {hits} hits", r.counts);
    // Lit from its centre, the field's far sides face away: some hits send shadow rays.
    desc.lights[0].position = DVec3::ZERO;
    let (r, scene) = at_every_width(&desc);
    assert!(!scene.lights[0].at_eye() && r.counts.shadow > 0, "{:?}", r.counts);
}

#[test]
fn reflections_still_send_shadow_rays_to_a_light_at_the_eye() {
    let (r, scene) = at_every_width(&field(EYE, true));
    let c = r.counts;
    assert!(c.reflection > 500, "{c:?}");
    // One light: at most one shadow ray a secondary hit, none from camera hits.
    assert!(c.shadow > 0 && c.shadow <= c.reflection, "{c:?}");
    assert!(scene.geometry.light_buffers[0].is_some(), "the reflections' shadow rays use the buffer");
}

#[test]
fn the_twin_finds_the_way_to_the_eye_clear() {
    let desc = field(EYE, false);
    let opts = Options { lanes: 8, secondary: true, threads: Some(2), ..Options::default() };
    let report = run("headlight", &desc, &opts).expect("report");
    eprintln!("{}", report.table());
    let shadow = report.shadow.expect("secondary");
    assert!(shadow.seen_from_eye > 128 * 96 / 4, "{shadow:?}");
    assert_eq!(shadow.seen_from_eye, shadow.rays, "every shadow ray is a camera hit's: {shadow:?}");
    assert_eq!(shadow.occluded_disagree, 0, "the f64 rays toward the eye met something: {shadow:?}");
    assert_eq!(report.unexplained(), 0);
}
