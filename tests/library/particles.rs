//! The particle tree (`--accel pkd`) against brute force: the same closest hits (t bits and scene-file ids)
//! and the same occlusion, lane by lane, at every packet width, on fields built to be hard for a k-d tree —
//! radii from 1e-8 to 1e-2 of the box mixed in one field, duplicated centres, collinear runs in file order —
//! for camera rays, rays from outside and inside the field, and secondary rays leaving a sphere's surface.

use super::common;

use bareray::compile::{Accel, Scene};
use bareray::geometry::{Departure, DeparturePacket, HitPacket, Ray, RayPacket, NO_PRIM};
use bareray::kinds::sphere::SphereDesc;
use bareray::math::V3;
use bareray::scene::desc::{Material, SceneDesc};
use bareray::simd::{IdLanes, Lanes};
use common::rng::Rng;
use glam::DVec3;
use wide::{f32x16, f32x4, f32x8};

/// A field of `n` spheres in the box [-1, 1]³ of one of the hard kinds.
fn field(kind: usize, n: usize, rng: &mut Rng) -> Vec<SphereDesc> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let c = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        let (center, radius) = match kind {
            // Radii from 1e-8 to 1e-2 of the box, log-uniform.
            0 => (c, 2.0 * 10f64.powf(rng.range(-8.0, -2.0))),
            // Every centre three times (ties in t broken by file index), one radius.
            1 => {
                let j = i / 3;
                let mut r = Rng::new(j as u64 + 7);
                (DVec3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0)), 0.03)
            }
            // Collinear runs along the axes, sorted in file order, touching neighbours.
            _ => {
                let t = (i % 50) as f64 / 25.0 - 1.0;
                let lane = (i / 50) as f64 * 0.37 % 2.0 - 1.0;
                let p = [DVec3::new(t, lane, 0.1), DVec3::new(lane, t, -0.2), DVec3::new(0.3, lane, t)]
                    [i / 50 % 3];
                (p, 0.02)
            }
        };
        out.push(SphereDesc { center, radius, material: (i % 3) as u32 });
    }
    out
}

/// The rays of one test: camera rays, rays from outside and from inside the field, and rays leaving the
/// surface of a sphere of the brute-force scene (with their departure), each with its `t_max`.
fn rays(
    scene: &Scene,
    spheres: &[SphereDesc],
    rng: &mut Rng,
    count: usize,
) -> Vec<(Ray<f32>, Departure, f32)> {
    let g = &scene.geometry;
    let (w, h) = (scene.camera.width as f32, scene.camera.height as f32);
    let mut out = Vec::with_capacity(count);
    for k in 0..count {
        let t_max = if k % 4 == 3 { rng.range(0.1, 2.0) as f32 } else { f32::INFINITY };
        let ray = match k % 5 {
            4 => {
                // From outside at a sphere's centre: hits the tiniest.
                let s = &spheres[(rng.unit() * spheres.len() as f64) as usize % spheres.len()];
                let o = DVec3::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0), -3.0);
                let d = V3::from(s.center - o).to_f32();
                (Ray::new(scene.to_rendering(o), d), Departure::CAMERA)
            }
            0 => (
                scene.camera_f64.ray_f32(rng.range(0.0, w as f64) as f32, rng.range(0.0, h as f64) as f32),
                Departure::CAMERA,
            ),
            1 => {
                let o = scene.to_rendering(DVec3::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0), -3.0));
                let d = V3::new(rng.range(-0.5, 0.5) as f32, rng.range(-0.5, 0.5) as f32, 1.0);
                (Ray::new(o, d), Departure::CAMERA)
            }
            2 => {
                let o = scene.to_rendering(DVec3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                ));
                let d = V3::new(
                    rng.range(-1.0, 1.0) as f32,
                    rng.range(-1.0, 1.0) as f32,
                    rng.range(-1.0, 1.0) as f32,
                );
                (Ray::new(o, d), Departure::CAMERA)
            }
            _ => {
                // A surface point of the sphere a camera ray hits, leaving outward or inward.
                let cam = scene
                    .camera_f64
                    .ray_f32(rng.range(0.0, w as f64) as f32, rng.range(0.0, h as f64) as f32);
                let hit = g.intersect(&cam, Departure::CAMERA, f32::INFINITY);
                if !hit.is_hit() {
                    out.push((cam, Departure::CAMERA, t_max));
                    continue;
                }
                let p = cam.at(hit.t);
                let d = V3::new(
                    rng.range(-1.0, 1.0) as f32,
                    rng.range(-1.0, 1.0) as f32,
                    rng.range(-1.0, 1.0) as f32,
                );
                let n = g.surface(&cam, hit.t, hit.prim).normal;
                let inward = n.dot(d) < 0.0;
                (Ray::new(p, d), Departure { prim: g.file_id(hit.prim), inward })
            }
        };
        out.push((ray.0, ray.1, t_max));
    }
    out
}

/// `scene`'s primitive id for scene-file id `file` (departures are given by file id).
fn prim_of(scene: &Scene, file: u32) -> u32 {
    if file == NO_PRIM {
        return NO_PRIM;
    }
    (0..scene.geometry.len() as u32).find(|&p| scene.geometry.file_id(p) == file).expect("a primitive")
}

/// Checks every ray of `rays` through the tree at width `F` against brute force, lane by lane.
fn check_width<F: Lanes>(tree: &Scene, brute: &Scene, rays: &[(Ray<f32>, Departure, f32)]) -> (usize, usize) {
    let (mut hits, mut blocked) = (0, 0);
    for chunk in rays.chunks(F::K) {
        let lane = |i: usize| chunk[i.min(chunk.len() - 1)];
        let packet = RayPacket::<F>::from_fn(|i| (lane(i).0, lane(i).2, i < chunk.len()));
        let depart = |scene: &Scene| DeparturePacket::<F> {
            prim: F::Ids::from_fn(|i| prim_of(scene, lane(i).1.prim)),
            inward: F::mask_from_bits(
                (0..chunk.len()).filter(|&i| lane(i).1.inward).fold(0, |b, i| b | 1 << i),
            ),
        };
        let got: HitPacket<F> = tree.geometry.intersect_k(&packet, &depart(tree));
        let occluded = F::move_mask(tree.geometry.occluded_k(&packet, &depart(tree)));
        for (i, &(ray, from, t_max)) in chunk.iter().enumerate() {
            let from_brute = Departure { prim: prim_of(brute, from.prim), ..from };
            let want = brute.geometry.intersect(&ray, from_brute, t_max);
            let have = got.lane(i);
            assert_eq!(have.t.to_bits(), want.t.to_bits(), "t of lane {i} at K = {}: {ray:?}", F::K);
            let file = |s: &Scene, p: u32| if p == NO_PRIM { NO_PRIM } else { s.geometry.file_id(p) };
            assert_eq!(file(tree, have.prim), file(brute, want.prim), "id of lane {i} at K = {}", F::K);
            let blocks = brute.geometry.occluded(&ray, from_brute, t_max);
            assert_eq!(occluded >> i & 1 == 1, blocks, "occlusion of lane {i} at K = {}: {ray:?}", F::K);
            hits += usize::from(want.is_hit());
            blocked += usize::from(blocks);
        }
    }
    (hits, blocked)
}

#[test]
fn the_particle_tree_finds_brute_forces_hits_at_every_width() {
    let mut rng = Rng::new(40);
    for kind in 0..3 {
        for n in [1usize, 9, 300, 3000] {
            let desc = SceneDesc {
                camera: common::camera(DVec3::new(0.2, 0.3, -4.0), DVec3::ZERO, DVec3::Y, 40.0, 64, 48),
                spheres: field(kind, n, &mut rng),
                materials: vec![Material::default(); 3],
                ..SceneDesc::default()
            };
            let tree = common::compile_with(&desc, Accel::Particles).unwrap();
            let brute = common::compile_with(&desc, Accel::Brute).unwrap();
            assert_eq!(tree.geometry.particles.len(), n);
            assert!(tree.geometry.spheres.is_empty() && tree.geometry.sphere_bvh.is_none());
            let rays = rays(&brute, &desc.spheres, &mut rng, 1024);
            let one = check_width::<f32>(&tree, &brute, &rays);
            assert_eq!(check_width::<f32x4>(&tree, &brute, &rays), one);
            assert_eq!(check_width::<f32x8>(&tree, &brute, &rays), one);
            assert_eq!(check_width::<f32x16>(&tree, &brute, &rays), one);
            if n >= 300 {
                assert!(
                    one.0 > 100 && one.1 > 100,
                    "field {kind}, {n} spheres: only {one:?} hits and blocks"
                );
            }
        }
    }
}

/// Camera rays of a whole image through the tree's tile path give the BVH's hits (the tile walk of the BVH
/// and the per-packet walk of the tree, with their frusta).
#[test]
fn camera_tiles_match_the_bvh() {
    let mut rng = Rng::new(41);
    let desc = SceneDesc {
        camera: common::camera(DVec3::new(0.0, 0.0, -3.5), DVec3::ZERO, DVec3::Y, 50.0, 160, 120),
        spheres: field(0, 20_000, &mut rng)
            .into_iter()
            .map(|s| SphereDesc { radius: s.radius.max(0.004), ..s })
            .collect(),
        materials: vec![Material::default(); 3],
        ..SceneDesc::default()
    };
    let tree = common::render(&common::compile_with(&desc, Accel::Particles).unwrap(), 2);
    let bvh = common::render(&common::compile_with(&desc, Accel::Bvh).unwrap(), 2);
    let bits = |p: &bareray::math::Rgb| [p.x, p.y, p.z].map(f32::to_bits);
    assert!(tree.pixels.iter().zip(&bvh.pixels).all(|(a, b)| bits(a) == bits(b)));
    assert!(bvh.pixels.iter().any(|p| bits(p) != bits(&bvh.pixels[0])), "the image shows something");
}

/// Camera tiles of K-ray packets (K = 4, 8, 16), each packet with its pyramid, walked through the tree as one
/// large packet ([`bareray::accel::Geometry::intersect_tile`]) give every lane the bits of its packet walked
/// alone: on each hard field, from a view inside the field (where members are done early and late) and one
/// outside it, with packets part empty and whole packets inactive.
#[test]
fn large_packets_through_the_tree_give_each_packets_hits() {
    fn check<F: Lanes>(scene: &Scene, rng: &mut Rng) -> usize {
        use bareray::render::{for_each_packet, large_packets, tile_pyramid, Tile};
        let (w, h) = (scene.camera.width, scene.camera.height);
        let mut found = 0;
        for piece in large_packets::<F>(Tile { x0: 0, y0: 0, w, h }) {
            let mut packets = Vec::new();
            for_each_packet::<F>(&scene.camera_f64, piece, (0.5, 0.5), true, |rays, _| packets.push(*rays));
            // Some lanes and some whole packets inactive.
            for rays in packets.iter_mut() {
                let keep = match rng.unit() {
                    u if u < 0.1 => 0,
                    u if u < 0.3 => (rng.unit() * 65536.0) as u32,
                    _ => u32::MAX,
                };
                rays.active = rays.active & F::mask_from_bits(keep);
            }
            let pyramid = tile_pyramid(&scene.camera_f64, piece, (0.5, 0.5));
            let mut hits = vec![HitPacket::<F>::miss(); packets.len()];
            scene.geometry.intersect_tile(&packets, pyramid.as_ref(), &mut hits);
            for (rays, large) in packets.iter().zip(&hits) {
                let alone = scene.geometry.intersect_k(rays, &DeparturePacket::camera());
                for i in (0..F::K).filter(|&i| F::mask_lane(rays.active, i)) {
                    let (a, b) = (large.lane(i), alone.lane(i));
                    assert_eq!((a.t.to_bits(), a.prim), (b.t.to_bits(), b.prim), "lane {i} of {piece:?}");
                    found += usize::from(a.is_hit());
                }
            }
        }
        found
    }
    for kind in 0..3 {
        let mut rng = Rng::new(97 + kind as u64);
        let spheres = field(kind, 6000, &mut rng);
        for eye in [DVec3::new(0.1, 0.2, -3.0), DVec3::new(0.05, -0.1, 0.02)] {
            let desc = SceneDesc {
                camera: common::camera(eye, DVec3::new(0.0, 0.0, 1.0), DVec3::Y, 60.0, 96, 72),
                spheres: spheres.clone(),
                materials: vec![Material::default(); 3],
                ..SceneDesc::default()
            };
            let scene = common::compile_with(&desc, Accel::Particles).unwrap();
            assert!(scene.geometry.culls_by_pyramid(), "the tree's camera packets carry pyramids");
            let found = [check::<f32x4>(&scene, &mut rng), check::<f32x8>(&scene, &mut rng)];
            let found16 = check::<f32x16>(&scene, &mut rng);
            assert!(found.iter().chain([&found16]).all(|&n| n > 50), "kind {kind}: hits {found:?} {found16}");
        }
    }
}
