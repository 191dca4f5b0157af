//! `bench`'s split by ray kind (`bareray::bench::profile`): live rays per test are exactly K where every
//! lane of every packet is live, every query is tagged with its kind (the kinds' work sums to the render's
//! own count), single-ray paths make one query per secondary ray and the probes change no bits; the
//! command line's table and JSON are tested in `tests/bench_kinds.rs`.

use std::path::Path;

use bareray::accel::{RayKind, Work};
use bareray::bench::{measure, profile, Profile, Trace};
use bareray::compile::{Accel, CompileOptions, Scene};
use bareray::kinds::sphere::SphereDesc;
use bareray::render::thread_pool;
use bareray::scene::desc::SceneDesc;
use glam::DVec3;

use super::common;

/// `n` spheres in front of a camera whose 64×48 image every packet width tiles exactly (no light, no
/// bounce: camera rays only).
fn camera_only(n: usize) -> SceneDesc {
    let mut rng = common::rng::Rng::new(7);
    let mut desc = SceneDesc::default();
    for _ in 0..n {
        let c = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        desc.spheres.push(SphereDesc { center: c, radius: rng.range(0.05, 0.3), material: 0 });
    }
    desc.camera = common::camera(DVec3::new(0.0, 0.0, -4.0), DVec3::ZERO, DVec3::Y, 40.0, 64, 48);
    desc.lights.clear();
    desc.render.max_depth = 0;
    desc
}

fn compiled(desc: &SceneDesc, accel: Accel, scalar: bool) -> Scene {
    let options = CompileOptions { accel, scalar, ..CompileOptions::default() };
    Scene::compile_with_options(desc, options).expect("scene compiles")
}

fn kind(p: &Profile, kind: RayKind) -> bareray::bench::KindProfile {
    *p.kinds.iter().find(|k| k.kind == kind).unwrap_or_else(|| panic!("no {kind:?} in {p:?}"))
}

/// Brute force tests every sphere with every live lane: K rays per primitive test at each width, one for
/// the scalar path. The large packets' member tests also serve whole packets (K = 16 over a BVH).
#[test]
fn full_packets_serve_k_rays_per_test() {
    let pool = thread_pool(Some(2)).unwrap();
    let brute = compiled(&camera_only(3), Accel::Brute, false);
    for k in [1, 4, 8, 16] {
        let camera = kind(&profile(&brute, k, &pool), RayKind::Camera);
        assert_eq!(camera.rays, 64 * 48);
        assert_eq!(camera.rays_per_prim_test(), Some(k as f64), "K = {k}: {camera:?}");
        assert_eq!(camera.work.prim_tests, 3 * 64 * 48 / k as u64, "K = {k}");
        assert_eq!(camera.work.box_tests, 0);
    }
    let bvh = compiled(&camera_only(300), Accel::Bvh, false);
    let camera = kind(&profile(&bvh, 16, &pool), RayKind::Camera);
    assert_eq!(camera.rays_per_prim_test(), Some(16.0), "{camera:?}");
    assert!(camera.rays_per_box_test().unwrap() > 16.0, "a large packet's box test serves its members");
    // The packet walk (no frusta, so no large packets): lanes finish at different depths.
    let options = CompileOptions { accel: Accel::Bvh, frustum_culling: false, ..CompileOptions::default() };
    let packets = Scene::compile_with_options(&camera_only(300), options).unwrap();
    let camera = kind(&profile(&packets, 16, &pool), RayKind::Camera);
    let per_box = camera.rays_per_box_test().unwrap();
    assert!((1.0..=16.0).contains(&per_box), "{camera:?}");
    let mut scalar = compiled(&camera_only(300), Accel::Bvh, true);
    assert!(scalar.geometry.set_scalar_walk(true));
    let camera = kind(&profile(&scalar, 1, &pool), RayKind::Camera);
    assert_eq!((camera.rays_per_box_test(), camera.rays_per_prim_test()), (Some(1.0), Some(1.0)));
}

/// On the Whitted scene (shadows, mirror, glass), under ambient occlusion, and on SPD's balls (a BVH): every test is made inside a
/// query tagged with its kind, so the kinds' work sums to what the render counted tile by tile; the
/// kinds' rays sum to a clean run's; one query per secondary ray on the single-ray paths; same bits.
#[test]
fn every_query_has_a_kind_and_the_probes_change_no_bits() {
    let pool = thread_pool(Some(2)).unwrap();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut whitted = bareray::io::load(&dir.join("whitted.toml")).expect("scene loads");
    (whitted.camera.width, whitted.camera.height) = (80, 60);
    let mut balls = bareray::io::load(&dir.join("balls3.nff")).expect("scene loads");
    (balls.camera.width, balls.camera.height) = (64, 64);
    let mut ao = whitted.clone();
    ao.render.shade =
        bareray::scene::desc::Shade::Ao(bareray::scene::desc::Ao { samples: 6, distance: None });
    for (name, desc, kinds) in [
        (
            "whitted",
            &whitted,
            &[RayKind::Camera, RayKind::Shadow, RayKind::Reflection, RayKind::Refraction][..],
        ),
        ("ao", &ao, &[RayKind::Camera, RayKind::Ao][..]),
        ("balls3", &balls, &[RayKind::Camera, RayKind::Shadow, RayKind::Reflection][..]),
    ] {
        for (k, scalar) in [(1, true), (1, false), (4, false), (8, false), (16, false)] {
            let mut scene = compiled(desc, Accel::Auto, scalar);
            scene.geometry.set_scalar_walk(scalar);
            let clean = measure(&scene, Trace::Render, k, &pool, 1).unwrap();
            let p = profile(&scene, k, &pool);
            let at = format!("{name}, K = {k}, scalar {scalar}");
            assert_eq!(p.checksums, [clean.checksum; 2], "{at}");
            let got: Vec<RayKind> = p.kinds.iter().map(|k| k.kind).collect();
            assert_eq!(got, kinds, "{at}");
            assert_eq!(p.untagged, Work::default(), "{at}");
            let mut sum = Work::default();
            p.kinds.iter().for_each(|k| sum += k.work);
            assert_eq!(sum, p.total, "{at}");
            // whitted.toml's two spheres are tested brute force; balls3 has a BVH.
            assert!(sum.prim_tests > 0 && (name != "balls3" || sum.box_tests > 0), "{at}");
            assert_eq!(p.kinds.iter().map(|k| k.rays).sum::<u64>(), clean.rays, "{at}");
            if k == 1 {
                for kind in p.kinds.iter().filter(|k| k.kind != RayKind::Camera) {
                    assert_eq!(kind.queries, kind.rays, "{at}: {kind:?}");
                }
            }
            assert!(p.kinds.iter().all(|k| k.seconds >= 0.0 && k.queries > 0), "{at}: {p:?}");
            // The shares come from one run, so they and the rest lie in [0, 1] whatever the host's speed
            // did between runs.
            let rest = p.rest_share();
            assert!(p.kinds.iter().all(|k| k.share >= 0.0) && (0.0..=1.0).contains(&rest), "{at}: {p:?}");
        }
    }
}
