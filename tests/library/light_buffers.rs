//! Light buffers (`accel/light_buffer.rs`): shadow rays through a light's buffer are blocked exactly where the
//! sphere tree says, at every width and on the scalar path, for lights far off, close by, on the cube's edges
//! and inside a sphere; and a scene with few camera rays for its spheres builds none.

use bareray::compile::{CompileOptions, Scene};
use bareray::geometry::{DeparturePacket, RayPacket, NO_PRIM};
use bareray::math::{SplitMix64, Vec3f, V3};
use bareray::scene::desc::LightDesc;
use bareray::simd::{IdLanes, Lanes};
use glam::DVec3;

/// A level-3 sphereflake with lights far off, close to the flake, on a cube diagonal (where faces
/// meet), in a plane through sphere centres, and inside the central sphere, compiled so that every
/// light has a buffer (with the scalar tree too, when `scalar`).
fn flake(scalar: bool) -> Scene {
    let text = bareray::io::generate::flake_nff(3).expect("flake");
    let mut desc = bareray::io::nff::parse(std::path::Path::new("flake.nff"), &text).expect("parse");
    let at = [(10.0, -12.0, 9.0), (0.3, 0.9, 0.2), (2.0, 2.0, 2.0), (1.3, 0.0, 0.0), (0.0, 0.0, 0.05)];
    desc.lights =
        at.iter().map(|&(x, y, z)| LightDesc { position: DVec3::new(x, y, z), ..desc.lights[0] }).collect();
    (desc.camera.width, desc.camera.height) = (512, 512);
    let options = CompileOptions { scalar, ..CompileOptions::default() };
    let scene = Scene::compile_with_options(&desc, options).expect("compile");
    let buffers = &scene.geometry.light_buffers;
    assert!(buffers.len() == at.len() && buffers.iter().all(Option::is_some), "every light has a buffer");
    scene
}

/// Shadow rays toward each light from points on the spheres (leaving their sphere) and from anywhere
/// around the flake: rays `(origin, unit direction, distance, departure sphere)`.
fn shadow_rays(scene: &Scene, light: Vec3f, count: usize, seed: u64) -> Vec<(Vec3f, Vec3f, f32, u32)> {
    let mut rng = SplitMix64::new(seed);
    let s = &scene.geometry.spheres;
    let centre = scene.to_rendering(DVec3::ZERO);
    (0..count)
        .map(|k| {
            let mut unit = || rng.unit() as f32 * 2.0 - 1.0;
            let around = V3::new(unit(), unit(), unit());
            let (origin, from) = match k % 4 {
                // Neighbouring points of one sphere, as a packet of nearby pixels gives.
                0..=2 => {
                    let i = (k / 16 * 7919) % s.len();
                    let jitter = V3::new(unit(), unit(), unit()) * 0.05;
                    let n = (around * 0.1 + V3::new(1.0, 0.5, 0.25) + jitter).normalize();
                    (s.center(i) + n * s.r[i], i as u32)
                }
                _ => (centre + around * 1.5, NO_PRIM),
            };
            let to = light - origin;
            let dist = to.length();
            (origin, to * (1.0 / dist), dist, from)
        })
        .collect()
}

/// Each ray's answer from the sphere tree (no light buffer, no hint).
fn by_tree(scene: &Scene, rays: &[(Vec3f, Vec3f, f32, u32)]) -> Vec<bool> {
    rays.iter()
        .map(|&(o, d, t, from)| {
            let packet = RayPacket::<f32>::new(o, d, t, true);
            let departure = DeparturePacket { prim: from, inward: false };
            scene.geometry.occluded_hinted_k(&packet, &departure, &mut NO_PRIM.clone())
        })
        .collect()
}

/// The rays through light `light`'s buffer, `F::K` at a time, one hint carried from packet to packet as
/// shading carries it.
fn by_buffer<F: Lanes>(scene: &Scene, light: usize, rays: &[(Vec3f, Vec3f, f32, u32)]) -> Vec<bool> {
    let mut hint = NO_PRIM;
    let mut out = Vec::new();
    for chunk in rays.chunks(F::K) {
        let lane = |i: usize| chunk.get(i).copied().unwrap_or(chunk[0]);
        let packet = RayPacket::<F>::from_fn(|i| {
            let (o, d, t, _) = lane(i);
            (bareray::geometry::Ray::new(o, d), t, i < chunk.len())
        });
        let departure =
            DeparturePacket { prim: F::Ids::from_fn(|i| lane(i).3), inward: F::mask_from_bits(0) };
        let blocked = scene.geometry.shadowed_k(&packet, &departure, &mut hint, light);
        out.extend((0..chunk.len()).map(|i| F::mask_lane(blocked, i)));
    }
    out
}

/// Through the buffers, every lane of every width (and the scalar path) is blocked exactly where the
/// tree says: the lists hold every sphere that can block a ray toward their light.
#[test]
fn buffers_give_the_tree_answer_at_every_width() {
    for scalar in [false, true] {
        let scene = flake(scalar);
        let (mut blocked, mut open) = (0, 0);
        for (k, light) in scene.lights.iter().enumerate() {
            let rays = shadow_rays(&scene, light.position, 4000, 17 + k as u64);
            let tree = by_tree(&scene, &rays);
            blocked += tree.iter().filter(|&&b| b).count();
            open += tree.iter().filter(|&&b| !b).count();
            let agree = |got: Vec<bool>, what: &str| {
                let wrong: Vec<usize> = (0..got.len()).filter(|&i| got[i] != tree[i]).collect();
                assert!(
                    wrong.is_empty(),
                    "light {k}, {what}: {} rays differ, first {:?}",
                    wrong.len(),
                    wrong.first()
                );
            };
            agree(by_buffer::<f32>(&scene, k, &rays), &format!("K = 1, scalar {scalar}"));
            if !scalar {
                agree(by_buffer::<wide::f32x4>(&scene, k, &rays), "K = 4");
                agree(by_buffer::<wide::f32x8>(&scene, k, &rays), "K = 8");
                agree(by_buffer::<wide::f32x16>(&scene, k, &rays), "K = 16");
            }
        }
        assert!(blocked > 4000 && open > 4000, "{blocked} blocked, {open} open");
    }
}

/// A scene whose lists would be too long gets no buffers: here few camera rays for its spheres.
#[test]
fn few_camera_rays_build_no_buffers() {
    let text = bareray::io::generate::flake_nff(3).expect("flake");
    let mut desc = bareray::io::nff::parse(std::path::Path::new("flake.nff"), &text).expect("parse");
    (desc.camera.width, desc.camera.height) = (64, 64);
    let scene = Scene::compile(&desc).expect("compile");
    assert!(scene.geometry.light_buffers.is_empty());
}
