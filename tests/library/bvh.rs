//! The BVH gives exactly the brute-force answer: every lane's hit t (bits) and scene-file primitive id, at every packet
//! width, for closest hits and occlusion, over random sphere fields and rays (including rays starting inside
//! spheres, grazing rays and axis-parallel rays), and through whole renders.

use super::common;

use bareray::bvh::Bvh;
use bareray::compile::{Accel, Scene};
use bareray::geometry::{Departure, DeparturePacket, Ray, RayPacket};
use bareray::kinds::sphere::SphereDesc;
use bareray::math::{Rgb, V3};
use bareray::scene::desc::SceneDesc;
use bareray::simd::{IdLanes, Lanes};
use common::rng::Rng;
use glam::DVec3;
use wide::{f32x16, f32x4, f32x8};

fn field(n: usize, seed: u64) -> SceneDesc {
    let mut rng = Rng::new(seed);
    let mut desc = SceneDesc::default();
    for _ in 0..n {
        let c = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        desc.spheres.push(SphereDesc { center: c, radius: rng.range(0.01, 0.12), material: 0 });
    }
    // Exact duplicates force ties between ids.
    let dup = |i: usize| desc.spheres[i % n];
    desc.spheres.extend([dup(3), dup(7)]);
    desc
}

/// Random rays: from outside the field, from inside spheres, axis-parallel ones.
fn rays(desc: &SceneDesc, count: usize, seed: u64) -> Vec<Ray<f32>> {
    let mut rng = Rng::new(seed);
    (0..count)
        .map(|i| {
            let o = match i % 3 {
                0 => V3::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0), -4.0),
                1 => V3::from(desc.spheres[i % desc.spheres.len()].center),
                _ => V3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)),
            };
            let d = if i % 7 == 0 {
                V3::new(0.0, 0.0, 1.0)
            } else {
                V3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-0.2, 1.0))
            };
            Ray::new(o.to_f32(), d.to_f32())
        })
        .collect()
}

/// Camera-like packets: per packet one origin and directions within a narrow cone (K consecutive rays).
fn coherent_rays(count: usize, k: usize, seed: u64) -> Vec<Ray<f32>> {
    let mut rng = Rng::new(seed);
    let mut out = Vec::with_capacity(count);
    while out.len() < count {
        let o = V3::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0), -4.0);
        let aim = V3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)) - o;
        for _ in 0..k {
            let d = aim + V3::new(rng.range(-0.05, 0.05), rng.range(-0.05, 0.05), 0.0);
            out.push(Ray::new(o.to_f32(), d.to_f32()));
        }
    }
    out
}

/// Checks packets of `F::K` rays, and packets of 1 and 2 live lanes (the single-ray path at K > 1).
fn check_width<F: Lanes>(bvh: &Scene, brute: &Scene, rays: &[Ray<f32>]) {
    check_packets::<F>(bvh, brute, rays, F::K);
    check_packets::<F>(bvh, brute, &rays[..rays.len() / 4], 1);
    check_packets::<F>(bvh, brute, &rays[..rays.len() / 4], 2);
}

fn check_packets<F: Lanes>(bvh: &Scene, brute: &Scene, rays: &[Ray<f32>], live: usize) {
    if live > F::K {
        return;
    }
    for chunk in rays.chunks(live) {
        let packet = RayPacket::<F>::from_rays(chunk, f32::INFINITY);
        let hits = bvh.geometry.intersect_k(&packet, &DeparturePacket::camera());
        let shadow = RayPacket::<F>::from_rays(chunk, 2.0);
        let blocked = bvh.geometry.occluded_k(&shadow, &DeparturePacket::camera());
        // A shadow-cache hint changes only what is tested first: any sphere, none, or an out-of-range id.
        let n = bvh.geometry.spheres.len() as u32;
        for mut hint in [0, n / 2, n - 1, n, u32::MAX] {
            let hinted = bvh.geometry.occluded_hinted_k(&shadow, &DeparturePacket::camera(), &mut hint);
            assert_eq!(F::move_mask(hinted), F::move_mask(blocked), "K={} hint {hint}", F::K);
            // Spheres only here: a blocked lane leaves a blocking sphere as the next hint.
            if F::move_mask(blocked) != 0 {
                assert!(hint < n, "K={} no blocker recorded: {hint}", F::K);
            }
        }
        for (i, ray) in chunk.iter().enumerate() {
            let want = brute.geometry.intersect(ray, Departure::CAMERA, f32::INFINITY);
            let got = hits.lane(i);
            assert_eq!(got.t.to_bits(), want.t.to_bits(), "K={} {ray:?}: {got:?} vs {want:?}", F::K);
            // Ties in t go to the lower scene-file id, whatever the storage order: even between the exact
            // duplicates in the field, the BVH reports the sphere brute force does.
            assert_eq!(
                bvh.geometry.file_id(got.prim),
                brute.geometry.file_id(want.prim),
                "K={} {ray:?}: {got:?} vs {want:?}",
                F::K
            );
            let occluded = brute.geometry.occluded(ray, Departure::CAMERA, 2.0);
            assert_eq!(F::mask_lane(blocked, i), occluded, "K={} occlusion {ray:?}", F::K);
        }
    }
}

/// By either builder's tree (binned SAH, Morton order).
#[test]
fn bvh_equals_brute_force_at_every_width() {
    for (n, seed) in [(1, 1), (2, 2), (17, 3), (300, 4), (2000, 5)] {
        let desc = field(n, seed);
        let brute = common::compile_with(&desc, Accel::Brute).unwrap();
        let rays = rays(&desc, 2000, seed + 100);
        for (_, bvh) in common::compile_by_each_builder(&desc) {
            assert!(bvh.geometry.sphere_bvh.is_some() && brute.geometry.sphere_bvh.is_none());
            check_width::<f32>(&bvh, &brute, &rays);
            check_width::<f32x4>(&bvh, &brute, &rays);
            check_width::<f32x8>(&bvh, &brute, &rays);
            check_width::<f32x16>(&bvh, &brute, &rays);
        }
    }
}

/// A scene that traces shadow rays gets the 8-wide single-ray tree, which K = 1 walks from the root, and in
/// which packets walk the subtrees they enter with few lanes one ray at a time; packets walk the 4-wide tree.
/// All give brute force's answer, bit for bit.
#[test]
fn single_ray_tree_equals_brute_force() {
    use bareray::scene::desc::{Falloff, LightDesc};
    for (n, seed) in [(1, 11), (9, 12), (300, 13), (2000, 14), (20_000, 15)] {
        let mut desc = field(n, seed);
        let light =
            LightDesc { position: DVec3::new(0.0, 3.0, -3.0), color: Rgb::all(1.0), falloff: Falloff::None };
        desc.lights.push(light);
        let brute = common::compile_with(&desc, Accel::Brute).unwrap();
        let rays = rays(&desc, 3000, seed + 100);
        for (_, bvh) in common::compile_by_each_builder(&desc) {
            let tree = bvh.geometry.sphere_bvh.as_ref().unwrap();
            assert!(tree.wide.is_some(), "a lit scene builds the single-ray tree");
            check_width::<f32>(&bvh, &brute, &rays);
            check_width::<f32x16>(&bvh, &brute, &rays);
        }
    }
    // Without lights or mirrors nothing walks one ray from the root: no single-ray tree.
    let plain = common::compile_with(&field(300, 4), Accel::Bvh).unwrap();
    assert!(plain.geometry.sphere_bvh.as_ref().unwrap().wide.is_none());
}

/// Scattered secondary packets may walk the sphere tree lane by lane instead of as a packet
/// (`Geometry::intersect_walked`; the renderer picks whichever is faster): both give every lane's
/// brute-force hit, bit for bit, over the single-ray tree and without it, at every width. Over the single-ray
/// tree each lane starts at the node of the leaf of the sphere it leaves (`bvh/upward.rs`): the same hits as
/// from the root, by another order of visits.
#[test]
fn lanes_walked_alone_equal_the_packet_walk() {
    use bareray::scene::desc::{Falloff, LightDesc};
    for (n, seed, lit) in [(300, 21, false), (2000, 22, true), (20_000, 23, true)] {
        let mut desc = field(n, seed);
        if lit {
            let light = LightDesc {
                position: DVec3::new(0.0, 3.0, -3.0),
                color: Rgb::all(1.0),
                falloff: Falloff::None,
            };
            desc.lights.push(light);
        }
        let bvh = common::compile_with(&desc, Accel::Bvh).unwrap();
        let brute = common::compile_with(&desc, Accel::Brute).unwrap();
        assert_eq!(bvh.geometry.sphere_bvh.as_ref().unwrap().wide.is_some(), lit);
        assert_eq!(bvh.geometry.sphere_bvh.as_ref().unwrap().up.is_some(), lit);
        let mut root = bvh.clone();
        root.geometry.sphere_bvh.as_mut().unwrap().up = None;
        let rays = coherent_rays(1600, 16, seed + 100);
        check_lanes_alone::<f32x4>(&bvh, &root, &brute, &rays);
        check_lanes_alone::<f32x8>(&bvh, &root, &brute, &rays);
        check_lanes_alone::<f32x16>(&bvh, &root, &brute, &rays);
    }
}

/// Camera packets of `rays`, then their mirror rays leaving the spheres hit, walked both ways; the lanes
/// walked alone must have had one live ray in every box test. `root` is `bvh` without the leaf links: its
/// lanes walked alone start at the root, and must find the same hits; where `bvh` has links, its walks visit
/// in another order, so their work differs (closest hits prune by the best so far: not always less).
fn check_lanes_alone<F: Lanes>(bvh: &Scene, root: &Scene, brute: &Scene, rays: &[Ray<f32>]) {
    let _counting = bareray::accel::Probe::counting();
    let (mut packed_work, mut alone_work, mut root_work) =
        (bareray::accel::Work::default(), bareray::accel::Work::default(), bareray::accel::Work::default());
    let mut scattered = 0;
    for chunk in rays.chunks(F::K) {
        let packet = RayPacket::<F>::from_rays(chunk, f32::INFINITY);
        let hits = bvh.geometry.intersect_k(&packet, &DeparturePacket::camera());
        let from = DeparturePacket::<F> { prim: hits.prim, inward: F::mask_from_bits(0) };
        let next = RayPacket::<F>::from_fn(|i| {
            let (r, hit) = (chunk.get(i).copied().unwrap_or(chunk[0]), hits.lane(i.min(chunk.len() - 1)));
            let live = i < chunk.len() && hit.t.is_finite();
            if !live {
                return (r, f32::INFINITY, false);
            }
            let p = r.at(hit.t);
            let sp = bvh.geometry.surface(&r, hit.t, hit.prim);
            let d = r.dir - sp.normal * (2.0 * r.dir.dot(sp.normal));
            (Ray::new(p, d), f32::INFINITY, true)
        });
        let ids: std::collections::BTreeSet<u32> =
            (0..chunk.len()).filter(|&i| next.lane(i).2).map(|i| hits.lane(i).prim).collect();
        scattered += usize::from(ids.len() > 2);
        let _ = bareray::accel::take_work();
        let packed = bvh.geometry.intersect_walked(&next, &from, false);
        packed_work += bareray::accel::take_work();
        let alone = bvh.geometry.intersect_walked(&next, &from, true);
        alone_work += bareray::accel::take_work();
        let from_root = root.geometry.intersect_walked(&next, &from, true);
        root_work += bareray::accel::take_work();
        for (i, camera_ray) in chunk.iter().enumerate() {
            let (ray, _, live) = next.lane(i);
            if !live {
                continue;
            }
            let (a, b, c) = (packed.lane(i), alone.lane(i), from_root.lane(i));
            assert_eq!((a.t.to_bits(), a.prim), (b.t.to_bits(), b.prim), "K={} {ray:?}", F::K);
            assert_eq!((c.t.to_bits(), c.prim), (b.t.to_bits(), b.prim), "K={} {ray:?}", F::K);
            assert_eq!(packed.key.lane(i), alone.key.lane(i), "K={} {ray:?}", F::K);
            let first = brute.geometry.intersect(camera_ray, Departure::CAMERA, f32::INFINITY);
            let want =
                brute.geometry.intersect(&ray, Departure { prim: first.prim, inward: false }, f32::INFINITY);
            assert_eq!(b.t.to_bits(), want.t.to_bits(), "K={} {ray:?}", F::K);
            assert_eq!(bvh.geometry.file_id(b.prim), brute.geometry.file_id(want.prim), "K={}", F::K);
        }
    }
    // The packets the choice is for: lanes leaving more than two spheres.
    assert!(scattered > 0, "K={}: no scattered packet", F::K);
    let (p, a) = (&packed_work, &alone_work);
    assert!(a.box_tests > 0 && a.box_lanes == a.box_tests, "K={}: lanes alone {a:?}", F::K);
    assert!(p.box_lanes > p.box_tests, "K={}: the packet walk {p:?}", F::K);
    let linked = bvh.geometry.sphere_bvh.as_ref().unwrap().up.is_some();
    let r = &root_work;
    let differs = (a.box_tests, a.prim_tests) != (r.box_tests, r.prim_tests);
    assert_eq!(linked, differs, "K={}: {a:?}, {r:?}", F::K);
}

/// Occlusion rays leaving a sphere walk from that sphere's leaf up to the root (`bvh/upward.rs`): at K = 1,
/// and in packets whose live lanes all leave one sphere (an ambient-occlusion packet of one hit). Every live
/// lane gets brute force's answer, at every width and ray length, for those packets (all lanes live, or one
/// or two with the others inactive and leaving another sphere) and for packets walked from the root (lanes
/// leaving two spheres, or a lane leaving none); over the same rays the walk from the leaves does fewer box
/// tests than the walk from the root, but on a tree that is one leaf.
#[test]
fn occlusion_from_the_departure_leaf_equals_brute_force() {
    use bareray::scene::desc::{Falloff, LightDesc};
    for (n, seed, hits) in [(6, 30, 40), (300, 31, 300), (2000, 32, 300), (20_000, 33, 300)] {
        let mut desc = field(n, seed);
        // A light makes the scene trace secondary rays, so the single-ray tree and the links are built.
        let light =
            LightDesc { position: DVec3::new(0.0, 3.0, -3.0), color: Rgb::all(1.0), falloff: Falloff::None };
        desc.lights.push(light);
        let brute = common::compile_with(&desc, Accel::Brute).unwrap();
        for (builder, up) in common::compile_by_each_builder(&desc) {
            let mut root = up.clone();
            let bvh = up.geometry.sphere_bvh.as_ref().unwrap();
            assert!(bvh.up.is_some(), "{builder}, {n} spheres: no links");
            let one_leaf = bvh.nodes.len() == 1;
            assert_eq!(one_leaf, n == 6, "{builder}, {n} spheres: {} nodes", bvh.nodes.len());
            root.geometry.sphere_bvh.as_mut().unwrap().up = None;
            let starts = occlusion_starts(&up, &brute, hits, seed + 100);
            assert!(starts.len() == hits, "{builder}, {n} spheres: {} hits", starts.len());
            let fewer = !one_leaf;
            check_occlusion_up::<f32>(&up, &root, &brute, &starts, seed, fewer);
            check_occlusion_up::<f32x4>(&up, &root, &brute, &starts, seed, fewer);
            check_occlusion_up::<f32x8>(&up, &root, &brute, &starts, seed, fewer);
            check_occlusion_up::<f32x16>(&up, &root, &brute, &starts, seed, fewer);
        }
    }
}

/// Where the first `count` of some camera-like rays that hit the field's spheres hit: the point, the normal,
/// the sphere's index in `bvh` and in `brute` (whose spheres are stored in another order).
fn occlusion_starts(bvh: &Scene, brute: &Scene, count: usize, seed: u64) -> Vec<Start> {
    let hits = coherent_rays(400 * count, 4, seed).into_iter().filter_map(|r| {
        let hit = bvh.geometry.intersect(&r, Departure::CAMERA, f32::INFINITY);
        let want = brute.geometry.intersect(&r, Departure::CAMERA, f32::INFINITY);
        assert_eq!(hit.t.to_bits(), want.t.to_bits());
        let normal = || bvh.geometry.surface(&r, hit.t, hit.prim).normal;
        hit.t.is_finite().then(|| Start {
            point: r.at(hit.t),
            normal: normal(),
            prim: hit.prim,
            brute: want.prim,
        })
    });
    hits.take(count).collect()
}

/// Where occlusion rays start: a point on a sphere, its normal, the sphere's index in the BVH's scene and in
/// the brute-force one.
#[derive(Clone, Copy)]
struct Start {
    point: V3<f32>,
    normal: V3<f32>,
    prim: u32,
    brute: u32,
}

/// Occlusion packets from pairs of `starts`, by turns: K directions over the normal's side of the first hit;
/// lanes alternating between the two hits; lanes 0 and 1 of the first hit live and the rest inactive, leaving
/// the second; and the first hit's lanes with lane 0 leaving no primitive. Lengths short, middling and
/// unbounded in every case. Checks each live lane against brute force, both trees' answers alike, and, with
/// `fewer`, that the walk from the leaves does fewer box tests than the walk from the root.
fn check_occlusion_up<F: Lanes>(
    up: &Scene,
    root: &Scene,
    brute: &Scene,
    starts: &[Start],
    seed: u64,
    fewer: bool,
) {
    let _counting = bareray::accel::Probe::counting();
    let mut rng = Rng::new(seed + 7);
    let (mut up_work, mut root_work) = (bareray::accel::Work::default(), bareray::accel::Work::default());
    let (mut blocked, mut open, mut shared) = (0, 0, 0);
    for (k, pair) in starts.windows(2).enumerate() {
        let case = (k / 3) % 4;
        let t_max = [0.05, 0.3, f32::INFINITY][k % 3];
        let (two, few, none) = (case == 1 && pair[0].prim != pair[1].prim, case == 2, case == 3);
        let lanes: Vec<(Ray<f32>, Start, bool)> = (0..F::K)
            .map(|i| {
                let live = !few || i < 2;
                let mut start = pair[usize::from(two && i % 2 == 1 || !live)];
                let d = V3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)).to_f32();
                let d = if d.dot(start.normal) < 0.0 { d * -1.0 } else { d };
                if none && i == 0 {
                    (start.prim, start.brute) = (Departure::CAMERA.prim, Departure::CAMERA.prim);
                }
                (Ray::new(start.point, d), start, live)
            })
            .collect();
        shared += usize::from(!two && !none);
        let packet = RayPacket::<F>::from_fn(|i| (lanes[i].0, t_max, lanes[i].2));
        let from =
            DeparturePacket::<F> { prim: F::Ids::from_fn(|i| lanes[i].1.prim), inward: F::mask_from_bits(0) };
        let _ = bareray::accel::take_work();
        let a = up.geometry.occluded_k(&packet, &from);
        up_work += bareray::accel::take_work();
        let b = root.geometry.occluded_k(&packet, &from);
        root_work += bareray::accel::take_work();
        for (i, &(ray, start, live)) in lanes.iter().enumerate() {
            let want =
                live && brute.geometry.occluded(&ray, Departure { prim: start.brute, inward: false }, t_max);
            assert_eq!(F::mask_lane(a, i), want, "K={} from the leaf: {ray:?} t_max {t_max}", F::K);
            assert_eq!(F::mask_lane(b, i), want, "K={} from the root: {ray:?} t_max {t_max}", F::K);
            (blocked, open) = if want { (blocked + 1, open) } else { (blocked, open + 1) };
        }
    }
    // A tree of one leaf holds too few spheres to block many rays: there only the other cases must occur.
    assert!((blocked > 0 || !fewer) && open > 0 && shared > 0, "K={}: {blocked} blocked, {open} open", F::K);
    let (a, b) = (up_work.box_tests, root_work.box_tests);
    assert!(
        if fewer { a < b } else { a <= b },
        "K={}: from the leaves {up_work:?}, from the root {root_work:?}",
        F::K
    );
}

#[test]
fn coincident_spheres_get_a_tree_the_walks_can_hold() {
    use bareray::scene::desc::{Falloff, LightDesc};
    // A pile of copies of one sphere made obvhs's tree a chain as long as the pile: at 400 copies the
    // traversal stacks overflowed (a panic), at 20 000 the collapse's recursion overflowed the thread's stack.
    // 400 and 1500 are caught by the stack check after the collapse; 5000 is built over one box per distinct
    // sphere, since obvhs's build slows down with the square of a pile (`bvh/piles.rs`).
    for (copies, seed) in [(400, 31), (1500, 32), (5000, 33)] {
        let mut desc = field(300, seed);
        let pile = SphereDesc { center: DVec3::new(0.1, -0.2, 0.3), radius: 0.05, material: 0 };
        desc.spheres.extend(std::iter::repeat_n(pile, copies));
        let position = DVec3::new(0.0, 3.0, -3.0);
        desc.lights.push(LightDesc { position, color: Rgb::all(1.0), falloff: Falloff::None });
        let bvh = common::compile_with(&desc, Accel::Bvh).unwrap();
        let brute = common::compile_with(&desc, Accel::Brute).unwrap();
        assert!(bvh.geometry.sphere_bvh.as_ref().unwrap().wide.is_some());
        // A third of the rays start at sphere centres, most of them inside the pile.
        let rays = rays(&desc, 3000, seed + 100);
        check_width::<f32>(&bvh, &brute, &rays);
        check_width::<f32x4>(&bvh, &brute, &rays);
        check_width::<f32x16>(&bvh, &brute, &rays);
    }
}

/// Box tests of `packets` (K = 16, closest hit) after `setting` the BVH's switches.
fn packet_box_tests(bvh: &mut Scene, packets: &[Ray<f32>], setting: impl Fn(&mut Bvh)) -> u64 {
    setting(bvh.geometry.sphere_bvh.as_mut().unwrap());
    let _counting = bareray::accel::Probe::counting();
    bareray::accel::take_work();
    for chunk in packets.chunks(16) {
        let packet = RayPacket::<f32x16>::from_rays(chunk, f32::INFINITY);
        bvh.geometry.intersect_k(&packet, &DeparturePacket::camera());
    }
    bareray::accel::take_work().box_tests
}

#[test]
fn frustum_culling_keeps_the_brute_force_answer() {
    for (n, seed) in [(17, 6), (300, 7), (2000, 8)] {
        let desc = field(n, seed);
        let mut bvh = common::compile_with(&desc, Accel::Bvh).unwrap();
        let brute = common::compile_with(&desc, Accel::Brute).unwrap();
        // The frustum must rule children out, or this test would not be testing it.
        let packets = coherent_rays(2000, 16, seed + 100);
        let all = packet_box_tests(&mut bvh, &packets, |b| b.frustum_culling = false);
        let culled = packet_box_tests(&mut bvh, &packets, |b| b.frustum_culling = true);
        assert!(culled < all, "{n} spheres: {culled} box tests with frustum culling, {all} without");
        check_width::<f32x4>(&bvh, &brute, &coherent_rays(2000, 4, seed + 100));
        check_width::<f32x8>(&bvh, &brute, &coherent_rays(2000, 8, seed + 100));
        check_width::<f32x16>(&bvh, &brute, &packets);
    }
}

/// Camera packets whose rays graze sphere silhouettes (aimed at points a few ulps inside and outside the
/// rim), from near and from far away, in tight and in wide cones: the frustum's margins must keep every
/// box an exact ray enters, so each lane still equals brute force bit for bit.
#[test]
fn frustum_culling_keeps_grazing_rays_from_near_and_far() {
    let desc = field(400, 11);
    let bvh = common::compile_with(&desc, Accel::Bvh).unwrap();
    let brute = common::compile_with(&desc, Accel::Brute).unwrap();
    let mut rng = Rng::new(12);
    // Arc: the packet's rays aim around the whole silhouette, or all at one point of it (a thin pyramid
    // tangent to the sphere, which the leaf's sphere test must not rule out).
    let cases =
        [(4.0, 0.0), (4.0, 0.3), (1e3, 0.0), (1e5, 0.0), (4.0, 2.0)].map(|c| (c, std::f64::consts::TAU));
    for ((distance, spread), arc) in cases.into_iter().chain([((4.0, 0.0), 1e-6), ((1e3, 0.0), 1e-6)]) {
        let mut rays = Vec::new();
        for packet in 0..120 {
            let aim = desc.spheres[packet * 3 % desc.spheres.len()];
            let dir =
                DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)).normalize();
            let o = aim.center - dir * distance;
            let start = rng.range(0.0, std::f64::consts::TAU);
            for _ in 0..16 {
                // A point on the silhouette circle (seen from o), nudged by a relative 1e-7 either way.
                let side = dir.any_orthonormal_pair();
                let angle = start + rng.range(0.0, arc);
                let rim = side.0 * angle.cos() + side.1 * angle.sin();
                let target = aim.center + rim * aim.radius * (1.0 + rng.range(-1e-7, 1e-7));
                let jitter = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
                let d = (target - o).normalize() + jitter * spread;
                rays.push(Ray::new(V3::from(o).to_f32(), V3::from(d).to_f32()));
            }
        }
        check_packets::<f32x16>(&bvh, &brute, &rays, 16);
        check_packets::<f32x8>(&bvh, &brute, &rays, 8);
    }
}

/// Packets walk sparse subtrees one ray at a time (`Bvh::single_ray_lanes`): at every threshold, from never
/// to always, the answer is brute force's; unlit, in the 4-wide tree, and lit, in the 8-wide single-ray tree
/// (`bvh/wide_starts.rs`).
#[test]
fn single_ray_switch_keeps_the_brute_force_answer() {
    use bareray::scene::desc::{Falloff, LightDesc};
    for (n, seed, lit) in [(300, 9, false), (2000, 10, false), (300, 11, true), (2000, 12, true)] {
        let mut desc = field(n, seed);
        if lit {
            let position = DVec3::new(0.0, 3.0, -3.0);
            desc.lights.push(LightDesc { position, color: Rgb::all(1.0), falloff: Falloff::None });
        }
        let mut bvh = common::compile_with(&desc, Accel::Bvh).unwrap();
        let tree = bvh.geometry.sphere_bvh.as_ref().unwrap();
        assert_eq!(tree.wide_starts.is_some(), lit, "{n} spheres: subtrees placed in the 8-wide tree");
        let brute = common::compile_with(&desc, Accel::Brute).unwrap();
        let packets = coherent_rays(2000, 16, seed + 100);
        // Full packets start above the threshold: a difference can only come from switching inside the tree.
        let never = packet_box_tests(&mut bvh, &packets, |b| b.single_ray_lanes = 0);
        let some = packet_box_tests(&mut bvh, &packets, |b| b.single_ray_lanes = 3);
        assert_ne!(never, some, "{n} spheres: no subtree was walked by single rays");
        for lanes in [0, 1, 3, 8, 16] {
            bvh.geometry.sphere_bvh.as_mut().unwrap().single_ray_lanes = lanes;
            let random = rays(&desc, 2000, seed + 200);
            check_width::<f32x4>(&bvh, &brute, &random);
            check_width::<f32x8>(&bvh, &brute, &random);
            check_width::<f32x16>(&bvh, &brute, &random);
            check_width::<f32x16>(&bvh, &brute, &packets);
        }
    }
}

/// Camera packets bring their own pyramid (`Camera::pyramid`, normals up to |n| ≈ 1 + |U| on wide views),
/// which culls boxes and leaf spheres, and walk the tree as large packets (a tile of packets with the tile's
/// pyramid, culled by distance from the eye): every pixel's hit equals brute force's with scalar rays (no
/// pyramid), at every packet width, on wide and narrow views from inside and outside the field, with tiles
/// cut short at the image's edges (203×157).
#[test]
fn camera_pyramids_keep_the_brute_force_answer() {
    use bareray::scene::desc::{Aim, Field};
    let mut desc = field(3000, 21);
    for (eye, theta) in [
        (DVec3::new(0.3, -0.2, -4.0), 120.0),
        (DVec3::new(0.0, 0.1, 0.05), 150.0),
        (DVec3::new(-3.0, 2.0, -3.0), 8.0),
    ] {
        desc.camera.eye = eye;
        desc.camera.aim = Aim::LookAt(DVec3::ZERO);
        desc.camera.field = Field::HorizontalAngle(theta);
        (desc.camera.width, desc.camera.height) = (203, 157);
        let mut bvh = common::compile_with(&desc, Accel::Bvh).unwrap();
        let brute = common::compile_with(&desc, Accel::Brute).unwrap();
        let pool = |threads| bareray::render::thread_pool(Some(threads)).unwrap();
        let want = bareray::render::primary_hits_lanes(&brute, 1, &pool(1));
        let (hits, prims) = (want.prim.iter().filter(|&&p| p != u32::MAX).count(), want.prim.len());
        assert!(hits > prims / 50, "only {hits} of {prims} pixels hit something");
        // Without frustum culling every camera packet walks on its own: the same answer.
        for (lanes, culling) in [(4, true), (8, true), (16, true), (16, false)] {
            bvh.geometry.sphere_bvh.as_mut().unwrap().frustum_culling = culling;
            let got = bareray::render::primary_hits_lanes(&bvh, lanes, &pool(2));
            let bits = |t: &[f32]| t.iter().map(|t| t.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&got.t), bits(&want.t), "t differs, eye {eye}, θ {theta}, K = {lanes}");
            // Ids: brute force stores spheres in file order, the BVH in leaf order.
            let file_ids: Vec<u32> = got.prim.iter().map(|&p| bvh.geometry.file_id(p)).collect();
            assert_eq!(file_ids, want.prim, "ids differ, eye {eye}, θ {theta}, K = {lanes}");
        }
    }
}

/// Large packets with other kinds in the scene: the tile's spheres come from the large walk, the polygons
/// from each packet's own walk, and every pixel is brute force's answer over both.
#[test]
fn large_packets_merge_the_other_kinds() {
    use bareray::scene::desc::{Aim, Field};
    let mut desc = polygon_field(400, 23);
    desc.camera.eye = DVec3::new(0.2, 0.3, -3.5);
    desc.camera.aim = Aim::LookAt(DVec3::ZERO);
    desc.camera.field = Field::HorizontalAngle(50.0);
    (desc.camera.width, desc.camera.height) = (131, 97);
    let bvh = common::compile_with(&desc, Accel::Bvh).unwrap();
    let brute = common::compile_with(&desc, Accel::Brute).unwrap();
    let pool = bareray::render::thread_pool(Some(2)).unwrap();
    let want = bareray::render::primary_hits_lanes(&brute, 1, &pool);
    let kinds = |hits: &bareray::render::PrimaryHits, scene: &Scene| {
        let spheres = scene.geometry.spheres.len() as u32;
        let on = |p: &&u32| **p != u32::MAX;
        (
            hits.prim.iter().filter(|p| on(p) && **p < spheres).count(),
            hits.prim.iter().filter(|p| on(p) && **p >= spheres).count(),
        )
    };
    let (spheres, others) = kinds(&want, &brute);
    assert!(spheres > 500 && others > 500, "{spheres} sphere and {others} polygon pixels");
    for lanes in [4, 8, 16] {
        let got = bareray::render::primary_hits_lanes(&bvh, lanes, &pool);
        let bits = |t: &[f32]| t.iter().map(|t| t.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&got.t), bits(&want.t), "t differs at K = {lanes}");
        let file_ids: Vec<u32> = got.prim.iter().map(|&p| bvh.geometry.file_id(p)).collect();
        let want_ids: Vec<u32> = want.prim.iter().map(|&p| brute.geometry.file_id(p)).collect();
        assert_eq!(file_ids, want_ids, "ids differ at K = {lanes}");
    }
}

/// A tile of packets walking together tests fewer boxes than its packets walking one by one: the tree's
/// upper levels are visited once per tile. (Counts, not time: the work counters of one thread.)
#[test]
fn large_packets_share_the_walk() {
    let mut desc = field(20000, 25);
    desc.camera = common::camera(DVec3::new(0.0, 0.0, -4.0), DVec3::ZERO, DVec3::Y, 45.0, 256, 192);
    let scene = common::compile_with(&desc, Accel::Bvh).unwrap();
    let (tile, separate) = (camera_work(&scene, true), camera_work(&scene, false));
    assert!(
        tile.box_tests * 10 < separate.box_tests * 8,
        "large packets: {} box tests, separate packets: {}",
        tile.box_tests,
        separate.box_tests
    );
}

/// The box and sphere tests of a camera's primary rays, large packets (`large`) or packet by packet, on one
/// thread.
fn camera_work(scene: &Scene, large: bool) -> bareray::accel::Work {
    let pool = bareray::render::thread_pool(Some(1)).unwrap();
    let _counting = bareray::accel::Probe::counting();
    pool.install(|| {
        let _ = bareray::accel::take_work();
        let (w, h) = (scene.camera.width, scene.camera.height);
        if large {
            bareray::render::primary_hits_lanes(scene, 16, &pool);
        } else {
            let from = bareray::geometry::DeparturePacket::camera();
            for tile in bareray::render::tiles(w, h) {
                bareray::render::for_each_packet::<f32x16>(
                    &scene.camera_f64,
                    tile,
                    (0.5, 0.5),
                    true,
                    |rays, _| {
                        scene.geometry.intersect_k(rays, &from);
                    },
                );
            }
        }
        bareray::accel::take_work()
    })
}

/// A camera looking away from a field tests none of its boxes: each side of the frustum alone has some
/// corner of a large box behind the eye on its inner side, so only the plane across the frustum's axis
/// rules those boxes out.
#[test]
fn a_view_away_from_the_field_tests_no_box() {
    let mut desc = field(20000, 26);
    desc.camera =
        common::camera(DVec3::new(0.0, 0.0, -4.0), DVec3::new(0.0, 0.0, -8.0), DVec3::Y, 60.0, 256, 192);
    let scene = common::compile_with(&desc, Accel::Bvh).unwrap();
    for large in [true, false] {
        let work = camera_work(&scene, large);
        assert_eq!((work.box_tests, work.prim_tests), (0, 0), "large packets {large}");
    }
}

/// Random planar polygons (triangles and quads, some with vertex normals) among the spheres of a field.
fn polygon_field(n: usize, seed: u64) -> SceneDesc {
    let mut desc = field(n / 4 + 1, seed);
    let mut rng = Rng::new(seed ^ 0xa5a5);
    for k in 0..n {
        let c = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        let size = rng.range(0.02, 0.3);
        let (u, v) = (DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)), DVec3::Z);
        let (u, w) = (u.normalize() * size, u.cross(v).normalize() * size);
        let vertices = match k % 2 {
            0 => vec![c, c + u, c + w],
            _ => vec![c, c + u, c + u + w, c + w],
        };
        let normals = (k % 3 == 0).then(|| vec![u.cross(w).normalize(); vertices.len()]);
        desc.kinds.polygons.push(bareray::kinds::polygon::PolygonDesc { vertices, normals, material: 0 });
    }
    // A large floor, entered by most rays that reach the bottom, and an exact copy: ties between polygon ids.
    let floor = [[-3.0, -1.2, -3.0], [3.0, -1.2, -3.0], [3.0, -1.2, 3.0], [-3.0, -1.2, 3.0]].map(DVec3::from);
    for _ in 0..2 {
        desc.kinds.polygons.push(bareray::kinds::polygon::PolygonDesc {
            vertices: floor.to_vec(),
            normals: None,
            material: 0,
        });
    }
    desc
}

/// Polygons' triangles live in their own BVH: closest hits (t bits and file id) and occlusion equal brute
/// force at every width, for rays from outside, from inside the field and from polygon surfaces.
#[test]
fn polygon_bvh_equals_brute_force_at_every_width() {
    for (n, seed) in [(3, 11), (40, 12), (1500, 13)] {
        let desc = polygon_field(n, seed);
        let bvh = common::compile_with(&desc, Accel::Bvh).unwrap();
        let brute = common::compile_with(&desc, Accel::Brute).unwrap();
        assert!(bvh.geometry.kinds.polygons.bvh.is_some() && brute.geometry.kinds.polygons.bvh.is_none());
        let rays = rays(&desc, 3000, seed + 100);
        let hits = rays.iter().filter(|r| {
            let h = brute.geometry.intersect(r, Departure::CAMERA, f32::INFINITY);
            h.prim as usize >= brute.geometry.kinds_base()
        });
        assert!(hits.count() > rays.len() / 5, "{n} polygons: too few rays hit a polygon");
        check_kind_at_every_width(&bvh, &brute, &rays);
    }
}

/// [`check_kind`] at K = 1, 4, 8 and 16.
fn check_kind_at_every_width(bvh: &Scene, brute: &Scene, rays: &[Ray<f32>]) {
    check_kind::<f32>(bvh, brute, rays);
    check_kind::<f32x4>(bvh, brute, rays);
    check_kind::<f32x8>(bvh, brute, rays);
    check_kind::<f32x16>(bvh, brute, rays);
}

fn check_kind<F: Lanes>(bvh: &Scene, brute: &Scene, rays: &[Ray<f32>]) {
    for chunk in rays.chunks(F::K) {
        let packet = RayPacket::<F>::from_rays(chunk, f32::INFINITY);
        let hits = bvh.geometry.intersect_k(&packet, &DeparturePacket::camera());
        let shadow = RayPacket::<F>::from_rays(chunk, 1.5);
        let blocked = bvh.geometry.occluded_k(&shadow, &DeparturePacket::camera());
        for (i, ray) in chunk.iter().enumerate() {
            let want = brute.geometry.intersect(ray, Departure::CAMERA, f32::INFINITY);
            let got = hits.lane(i);
            assert_eq!(got.t.to_bits(), want.t.to_bits(), "K={} {ray:?}: {got:?} vs {want:?}", F::K);
            assert_eq!(
                bvh.geometry.file_id(got.prim),
                brute.geometry.file_id(want.prim),
                "K={} {ray:?}",
                F::K
            );
            let occluded = brute.geometry.occluded(ray, Departure::CAMERA, 1.5);
            assert_eq!(F::mask_lane(blocked, i), occluded, "K={} occlusion {ray:?}", F::K);
        }
        // Secondary rays leave the polygon they hit: that polygon is skipped, the others are found.
        let from = DeparturePacket::<F> { prim: hits.prim, inward: F::mask_from_bits(0) };
        let next = RayPacket::<F>::from_fn(|i| {
            let (r, hit) = (chunk.get(i).copied().unwrap_or(chunk[0]), hits.lane(i.min(chunk.len() - 1)));
            let live = i < chunk.len() && hit.t.is_finite();
            let at = if live { r.at(hit.t) } else { r.origin };
            (Ray::new(at, V3::new(r.dir.y, r.dir.z, -r.dir.x)), f32::INFINITY, live)
        });
        let again = bvh.geometry.intersect_k(&next, &from);
        for (i, camera_ray) in chunk.iter().enumerate() {
            let (ray, _, live) = next.lane(i);
            if !live {
                continue;
            }
            // The brute-force scene stores spheres in file order: its own first hit names the same primitive.
            let first = brute.geometry.intersect(camera_ray, Departure::CAMERA, f32::INFINITY);
            let want =
                brute.geometry.intersect(&ray, Departure { prim: first.prim, inward: false }, f32::INFINITY);
            let got = again.lane(i);
            assert_eq!(got.t.to_bits(), want.t.to_bits(), "K={} secondary {ray:?}", F::K);
            assert_eq!(
                bvh.geometry.file_id(got.prim),
                brute.geometry.file_id(want.prim),
                "K={} secondary",
                F::K
            );
        }
    }
}

/// `n` random ellipsoids and a floor plane beside three spheres (and their two duplicates).
fn shape_field(n: usize, seed: u64) -> SceneDesc {
    use bareray::geometry::ShapeKind;
    use glam::{DAffine3, DQuat};
    let mut desc = field(3, seed);
    let mut rng = Rng::new(seed);
    for _ in 0..n {
        let c = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        let size = if n < 10 { 0.6 } else { 0.2 };
        let scale = DVec3::new(rng.range(0.01, size), rng.range(0.01, size), rng.range(0.01, size));
        let turn = DQuat::from_euler(glam::EulerRot::XYZ, rng.range(0.0, 3.0), rng.range(0.0, 3.0), 0.0);
        let world_from_object = DAffine3::from_scale_rotation_translation(scale, turn, c);
        desc.kinds.push_shape(ShapeKind::Sphere, world_from_object);
    }
    let floor = DAffine3::from_translation(DVec3::new(0.0, -1.3, 0.0))
        * DAffine3::from_rotation_x(-std::f64::consts::FRAC_PI_2);
    desc.kinds.push_shape(ShapeKind::Plane, floor);
    desc
}

/// Bounded shapes (ellipsoids) live in a BVH, planes beside it: closest hits and occlusion equal brute force
/// at every width.
#[test]
fn ellipsoid_bvh_equals_brute_force_at_every_width() {
    for (n, seed) in [(5, 21), (200, 22)] {
        let desc = shape_field(n, seed);
        let bvh = common::compile_with(&desc, Accel::Bvh).unwrap();
        let brute = common::compile_with(&desc, Accel::Brute).unwrap();
        let (tree, brute_tree) = (&bvh.geometry.kinds, &brute.geometry.kinds);
        assert!(tree.ellipsoids.bvh.is_some() && brute_tree.ellipsoids.bvh.is_none());
        assert_eq!((tree.ellipsoids.order.len(), tree.planes.len(), tree.planes.bvh.is_none()), (n, 1, true));
        let rays = rays(&desc, 3000, seed + 100);
        let base = brute.geometry.spheres.len() as u32;
        let ellipsoid_hits = rays.iter().filter(|r| {
            let h = brute.geometry.intersect(r, Departure::CAMERA, f32::INFINITY);
            h.prim >= base && h.prim < base + n as u32
        });
        let hits = ellipsoid_hits.count();
        assert!(hits > rays.len() / 40, "{n} ellipsoids: only {hits} rays hit one");
        check_kind_at_every_width(&bvh, &brute, &rays);
    }
}

/// `n` random open cones and cylinders beside three spheres (and their two duplicates).
fn cone_field(n: usize, seed: u64) -> SceneDesc {
    use bareray::kinds::cone::ConeDesc;
    let mut desc = field(3, seed);
    let mut rng = Rng::new(seed);
    for k in 0..n {
        let base = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        let size = if n < 10 { 0.8 } else { 0.25 };
        let axis = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)) * size;
        let r0 = rng.range(0.01, 0.3) * size;
        // Cylinders, pointed cones and truncated ones.
        let r1 = [r0, 0.0, rng.range(0.01, 0.3) * size][k % 3];
        desc.kinds.cones.push(ConeDesc {
            base,
            base_radius: r0,
            apex: base + axis,
            apex_radius: r1,
            material: 0,
        });
    }
    desc
}

/// Open cones and cylinders live in their own BVH: closest hits and occlusion equal brute force at every
/// width, camera rays and rays leaving a cone (which may meet it again).
#[test]
fn cone_bvh_equals_brute_force_at_every_width() {
    for (n, seed) in [(4, 31), (300, 32)] {
        let desc = cone_field(n, seed);
        let bvh = common::compile_with(&desc, Accel::Bvh).unwrap();
        let brute = common::compile_with(&desc, Accel::Brute).unwrap();
        assert!(bvh.geometry.kinds.cones.bvh.is_some() && brute.geometry.kinds.cones.bvh.is_none());
        let rays = rays(&desc, 3000, seed + 100);
        let base = brute.geometry.kinds_base() as u32;
        let cone_hits = rays.iter().filter(|r| {
            let h = brute.geometry.intersect(r, Departure::CAMERA, f32::INFINITY);
            h.prim >= base && h.prim != u32::MAX
        });
        let hits = cone_hits.count();
        assert!(hits > rays.len() / 40, "{n} cones: only {hits} rays hit one");
        check_kind_at_every_width(&bvh, &brute, &rays);
    }
}

/// A ray that leaves an open cylinder's wall meets the same cylinder again: inward across the tube at the far
/// wall, outward never (the solid a cone bounds is convex); inside a flaring cone, across the cup.
#[test]
fn rays_leaving_a_cone_meet_it_again() {
    use bareray::kinds::cone::ConeDesc;
    let mut desc = field(1, 41);
    desc.spheres.clear();
    let tube =
        ConeDesc { base: DVec3::ZERO, base_radius: 1.0, apex: DVec3::Z * 4.0, apex_radius: 1.0, material: 0 };
    let flare = ConeDesc {
        base: DVec3::X * 10.0,
        base_radius: 0.1,
        apex: DVec3::new(10.0, 0.0, 4.0),
        apex_radius: 3.0,
        material: 0,
    };
    desc.kinds.cones.extend([tube, flare]);
    for accel in [Accel::Bvh, Accel::Brute] {
        let scene = common::compile_with(&desc, accel).unwrap();
        let g = &scene.geometry;
        let (tube_id, flare_id) = (g.kinds_base() as u32, g.kinds_base() as u32 + 1);
        let origin = scene.to_rendering(DVec3::new(1.0, 0.0, 2.0));
        let across = Ray::new(origin, V3::new(-1.0, 0.0, 0.0));
        let hit = g.intersect(&across, Departure { prim: tube_id, inward: true }, f32::INFINITY);
        assert_eq!(hit.prim, tube_id, "{accel:?}: the far wall");
        assert!((hit.t - 2.0).abs() < 1e-5, "{accel:?}: t {}", hit.t);
        let away = Ray::new(origin, V3::new(1.0, 1.0, 0.0));
        let miss = g.intersect(&away, Departure { prim: tube_id, inward: false }, f32::INFINITY);
        assert_eq!(miss.prim, u32::MAX, "{accel:?}: leaving outward meets nothing");
        // On the flaring cone's wall near its narrow end, heading across the cup and up.
        let low = scene.to_rendering(DVec3::new(10.0 + 0.1 + 2.9 * 0.25, 0.0, 1.0));
        let across = Ray::new(low, V3::new(-1.0, 0.0, 0.5));
        let again = g.intersect(&across, Departure { prim: flare_id, inward: true }, f32::INFINITY);
        assert_eq!(again.prim, flare_id, "{accel:?}: the far side of the cup");
        // Up along the inside, flaring away faster than the ray: out through the open end.
        let up = Ray::new(low, V3::new(0.3, 0.0, 1.0));
        let out = g.intersect(&up, Departure { prim: flare_id, inward: true }, f32::INFINITY);
        assert_eq!(out.prim, u32::MAX, "{accel:?}: out through the open end");
    }
}

/// The scalar walk (`--lanes scalar`: each BVH's binary tree, one box and one primitive at a time) gives brute
/// force's closest hit (t bits and scene-file id) and occlusion, for every kind: spheres (from one leaf to
/// 20 000, with exact duplicates, and a pile of coincident copies, whose tree is a fallback), polygons'
/// triangles, ellipsoids beside a plane, and cones; camera rays, rays from inside spheres and rays leaving
/// a polygon, shape or cone (`check_kind`'s secondary rays).
#[test]
fn scalar_walk_equals_brute_force_for_every_kind() {
    use bareray::compile::CompileOptions;
    use bareray::scene::desc::{Falloff, LightDesc};
    let scalar = |desc: &SceneDesc| {
        let options = CompileOptions { accel: Accel::Bvh, scalar: true, ..CompileOptions::default() };
        let scene = Scene::compile_with_options(desc, options).unwrap();
        assert!(scene.geometry.bvhs().count() > 0);
        for bvh in scene.geometry.bvhs() {
            assert!(bvh.scalar.is_some() && bvh.scalar_walk, "every BVH keeps its binary tree and walks it");
        }
        scene
    };
    let mut pile = field(300, 33);
    let copy = SphereDesc { center: DVec3::new(0.1, -0.2, 0.3), radius: 0.05, material: 0 };
    pile.spheres.extend(std::iter::repeat_n(copy, 1500));
    let spheres =
        [(field(1, 1), 1), (field(17, 3), 3), (field(2000, 5), 5), (field(20_000, 15), 15), (pile, 33)];
    for (mut desc, seed) in spheres {
        // With a light the scene also has the 8-wide single-ray tree: the scalar walk is chosen over it.
        let light =
            LightDesc { position: DVec3::new(0.0, 3.0, -3.0), color: Rgb::all(1.0), falloff: Falloff::None };
        desc.lights.push(light);
        let brute = common::compile_with(&desc, Accel::Brute).unwrap();
        let rays = rays(&desc, 3000, seed + 100);
        check_packets::<f32>(&scalar(&desc), &brute, &rays, 1);
    }
    for desc in [polygon_field(40, 12), polygon_field(1500, 13), shape_field(200, 22), cone_field(300, 32)] {
        let brute = common::compile_with(&desc, Accel::Brute).unwrap();
        check_kind::<f32>(&scalar(&desc), &brute, &rays(&desc, 3000, 7));
    }
}

/// The scalar walk visits boxes two at a time and the single-ray SIMD walk a wide node's at once: the work
/// counters tell them apart, so a scene compiled for the scalar walk really takes it, and
/// `Geometry::set_scalar_walk` switches between them.
#[test]
fn scalar_walk_is_taken_and_can_be_switched_off() {
    use bareray::compile::CompileOptions;
    let desc = field(2000, 5);
    let options = CompileOptions { accel: Accel::Bvh, scalar: true, ..CompileOptions::default() };
    let mut scene = Scene::compile_with_options(&desc, options).unwrap();
    let rays = rays(&desc, 500, 105);
    let trace = |scene: &Scene| {
        let _counting = bareray::accel::Probe::counting();
        bareray::accel::take_work();
        for ray in &rays {
            scene.geometry.intersect(ray, Departure::CAMERA, f32::INFINITY);
        }
        bareray::accel::take_work()
    };
    let scalar = trace(&scene);
    assert!(scene.geometry.set_scalar_walk(false));
    let simd = trace(&scene);
    // Two boxes per scalar visit; 4 per 4-wide node visit (no 8-wide tree without lights).
    assert_eq!(scalar.box_tests % 2, 0);
    assert_eq!(simd.box_tests % 4, 0);
    assert_ne!(scalar, simd);
    assert!(scene.geometry.set_scalar_walk(true));
    assert_eq!(trace(&scene), scalar);
    // Without the binary trees the switch cannot turn the scalar walk on.
    let mut plain = common::compile_with(&desc, Accel::Bvh).unwrap();
    assert!(!plain.geometry.set_scalar_walk(true));
    assert_eq!(trace(&plain), simd);
}
