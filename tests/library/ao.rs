//! Ambient occlusion (`--shade ao`): the same bits at every packet width and thread count under every
//! sampling pattern, each packet lane the single-ray tracer's value, and values checked against cases with
//! known answers (a point far from everything, a floor beside a wall, the inside of a closed sphere, a
//! sphere resting on a floor against an f64 Monte Carlo estimate).

use super::common;

use bareray::compile::Scene;
use bareray::film::Image;
use bareray::geometry::{Ray, RayPacket};
use bareray::math::{Rgb, SplitMix64, V3};
use bareray::render::{render_lanes, thread_pool};
use bareray::scene::desc::{Ao, Pattern, SceneDesc, Shade};
use bareray::shade::Tracer;
use bareray::simd::Lanes;
use common::parse_toml;

fn ao(samples: u32, distance: Option<f64>) -> Shade {
    Shade::Ao(Ao { samples, distance })
}

fn image(desc: &SceneDesc, lanes: usize, threads: usize) -> (Image, u64) {
    let scene = Scene::compile(desc).expect("scene compiles");
    let r = render_lanes(&scene, lanes, &thread_pool(Some(threads)).unwrap(), &());
    (r.image, r.counts.ao)
}

fn bits(img: &Image) -> Vec<u32> {
    img.pixels.iter().flat_map(|p| [p.x, p.y, p.z]).map(f32::to_bits).collect()
}

fn scene_file(name: &str, width: u32, height: u32) -> SceneDesc {
    let mut desc = bareray::io::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(name)).unwrap();
    (desc.camera.width, desc.camera.height) = (width, height);
    desc
}

/// AO renders are the same bits (and count the same rays) at 1, 4, 8 and 16 lanes and on 1 and 2 threads,
/// under each sampling pattern (every antialiasing sample gets its own occlusion rays), on the Whitted scene
/// (spheres over a plane, brute force; 5 directions: fewer than K but at K = 4) and on a sphere field (BVH
/// walks; 21 directions, more than K).
#[test]
fn ao_is_the_same_bits_at_every_width_and_thread_count() {
    let adaptive = Pattern::Adaptive { threshold: 0.05, depth: 2 };
    let patterns = [Pattern::Grid(1), Pattern::Stratified(2), Pattern::R2(3), adaptive, Pattern::Coverage];
    let mut cases: Vec<(String, SceneDesc)> = Vec::new();
    for pattern in patterns {
        let mut d = scene_file("scenes/whitted.toml", 48, 40);
        (d.render.pattern, d.render.shade) = (pattern, ao(5, None));
        cases.push((format!("whitted {pattern:?}"), d));
    }
    let mut field = scene_file("scenes/field1k.xyzr", 48, 40);
    field.render.shade = ao(21, None);
    cases.push(("field1k".into(), field));
    for (name, desc) in &cases {
        let (reference, rays) = image(desc, 1, 1);
        assert!(rays > 0, "{name}: no occlusion rays");
        for (lanes, threads) in [(1, 2), (4, 1), (4, 2), (8, 1), (8, 2), (16, 1), (16, 2)] {
            let (img, n) = image(desc, lanes, threads);
            assert!(bits(&img) == bits(&reference), "{name} at {lanes} lanes, {threads} threads");
            assert_eq!(n, rays, "{name} at {lanes} lanes, {threads} threads: ray counts");
        }
    }
}

/// Every lane of an AO packet is what the single-ray tracer (K = 1) computes for that ray alone, bit for bit,
/// with the same ray counts: random rays from the eye into a sphere field over a plane, some lanes off.
#[test]
fn packet_lanes_are_the_single_ray_tracer() {
    let mut desc = scene_file("scenes/field1k.xyzr", 32, 32);
    add_floor(&mut desc);
    // 7 directions: one per pixel's hit in each packet at K = 8 and 16, a hit's own packets at K = 4; 20:
    // a hit's own packets at every K, the last one part full.
    // Rays spread over 0.6 of the field or within 1e-4 of one direction: the second's hits lie close
    // together on one sphere, whose packets regroup their directions at every sample count.
    for samples in [7, 20] {
        desc.render.shade = ao(samples, None);
        let scene = Scene::compile(&desc).unwrap();
        for spread in [0.6, 1e-4] {
            check_lanes::<wide::f32x4>(&scene, 1, spread);
            check_lanes::<wide::f32x8>(&scene, 2, spread);
            check_lanes::<wide::f32x16>(&scene, 3, spread);
        }
    }
}

/// A plane under the field, so that rays also hit a primitive that is not a sphere.
fn add_floor(desc: &mut SceneDesc) {
    use bareray::geometry::ShapeKind;
    let floor = glam::DAffine3::from_rotation_translation(
        glam::DQuat::from_rotation_arc(glam::DVec3::Z, glam::DVec3::Y),
        glam::DVec3::new(0.0, -1.0, 0.0),
    );
    desc.kinds.push_shape(ShapeKind::Plane, floor);
}

fn check_lanes<F: Lanes>(scene: &Scene, seed: u64, spread: f32) {
    let mut rng = SplitMix64::new(seed);
    let mut packets = Tracer::<F>::new(scene);
    let mut single = Tracer::<f32>::new(scene);
    let mut hits = 0;
    for p in 0..300 {
        let rays = RayPacket::<F>::from_fn(|i| {
            let mut u = || rng.unit() as f32 * 2.0 - 1.0;
            let look = scene.to_rendering(glam::DVec3::ZERO);
            let dir = V3::new(look.x + u() * spread, look.y + u() * spread, look.z + u() * spread);
            (Ray::new(V3::new(0.0, 0.0, 0.0), dir.normalize()), f32::INFINITY, (p + i) % 5 != 0)
        });
        let c = packets.primary(&rays);
        for i in 0..F::K {
            let (ray, t_max, active) = rays.lane(i);
            let got = [c.x.lane(i), c.y.lane(i), c.z.lane(i)].map(f32::to_bits);
            if !active {
                assert_eq!(got, [0; 3], "inactive lane {i} of packet {p}");
                continue;
            }
            let one = single.primary(&RayPacket::<f32>::new(ray.origin, ray.dir, t_max, true));
            assert_eq!(got, [one.x, one.y, one.z].map(f32::to_bits), "K = {} packet {p} lane {i}", F::K);
            hits += usize::from(one != V3::all(0.0));
        }
    }
    assert_eq!(packets.counts, single.counts, "K = {}", F::K);
    assert!(packets.counts.ao > 1000 && hits > 500, "{:?}, {hits} lanes shaded", packets.counts);
}

/// The shade of one camera ray from the eye toward the world point `at`.
fn shade_toward(scene: &Scene, at: glam::DVec3) -> Rgb {
    let dir = scene.to_rendering(at).normalize();
    let c = Tracer::<f32>::new(scene).primary(&RayPacket::<f32>::new(
        V3::new(0.0, 0.0, 0.0),
        dir,
        f32::INFINITY,
        true,
    ));
    Rgb::new(c.x, c.y, c.z)
}

const FLOOR_AND_BALL: &str = r#"
    [camera]
    eye = [0.0, 0.6, -5.0]
    look_at = [0.0, 0.0, 0.0]
    [render]
    background = [0.2, 0.3, 0.4]
    [materials.floor]
    color = [1.0, 0.5, 0.25]
    [materials.ball]
    color = [0.0, 1.0, 0.0]
    [[planes]]
    point = [0.0, 0.0, 0.0]
    normal = [0.0, 1.0, 0.0]
    material = "floor"
    [[spheres]]
    center = [0.0, 1.0, 0.0]
    radius = 1.0
    material = "ball"
"#;

/// The probability that a cosine-weighted direction from the floor point `(x, 0, z)` meets the unit sphere at
/// (0, 1, 0) within `reach`: an f64 Monte Carlo estimate of `samples` directions, independent of the renderer
/// (its own random numbers, its own hemisphere mapping and ray-sphere test).
fn blocked_by_ball(x: f64, z: f64, reach: f64, samples: u32) -> f64 {
    let mut rng = SplitMix64::new(99);
    let mut blocked = 0;
    for _ in 0..samples {
        let (u, v) = (rng.unit(), rng.unit());
        let phi = std::f64::consts::TAU * v;
        let d = glam::DVec3::new(u.sqrt() * phi.cos(), (1.0 - u).sqrt(), u.sqrt() * phi.sin());
        let oc = glam::DVec3::new(x, 0.0, z) - glam::DVec3::Y;
        let (b, c) = (oc.dot(d), oc.length_squared() - 1.0);
        let disc = b * b - c;
        if disc >= 0.0 {
            let t = -b - disc.sqrt();
            blocked += u32::from(t > 0.0 && t <= reach);
        }
    }
    f64::from(blocked) / f64::from(samples)
}

/// A unit sphere resting on a floor, occlusion rays of length 0.5: floor points farther from the contact
/// than √(1.5² − 1) ≈ 1.118 have nothing in reach and are the floor's colour exactly; nearer ones are darker
/// by the share of the cosine-weighted hemisphere the sphere covers within reach, which an independent f64
/// Monte Carlo estimate gives to within 0.01 (1024 rays); the top of the sphere sees nothing but sky.
#[test]
fn a_sphere_on_a_floor_darkens_the_floor_by_the_hemisphere_it_covers() {
    let mut desc = parse_toml(FLOOR_AND_BALL);
    desc.render.shade = ao(1024, Some(0.5));
    let scene = Scene::compile(&desc).unwrap();
    let floor = Rgb::new(1.0, 0.5, 0.25);
    for x in [1.2, 1.5, 3.0, -2.0] {
        assert_eq!(shade_toward(&scene, glam::DVec3::new(x, 0.0, -0.2)), floor, "floor at x = {x}");
    }
    assert_eq!(shade_toward(&scene, glam::DVec3::new(0.0, 2.0, 0.0)), Rgb::new(0.0, 1.0, 0.0), "the top");
    let mut darkest: f64 = 1.0;
    for (x, z) in [(0.0, -0.35), (0.3, -0.5), (-0.6, -0.6), (0.0, -1.0), (0.9, -0.4)] {
        let got = f64::from(shade_toward(&scene, glam::DVec3::new(x, 0.0, z)).x);
        let want = 1.0 - blocked_by_ball(x, z, 0.5, 400_000);
        assert!((got - want).abs() < 0.01, "floor at ({x}, {z}): {got}, Monte Carlo {want}");
        assert!(got < 0.98, "floor at ({x}, {z}) is not darker: {got}");
        darkest = darkest.min(got);
    }
    assert!(darkest < 0.7, "the contact region is darker: {darkest}");
}

/// Occlusion rays shorter than every gap between primitives meet nothing: the image is the flat base
/// colours (and the background), exactly; a little longer, and the floor under the spheres darkens.
#[test]
fn a_distance_below_every_gap_gives_the_flat_colours() {
    let src = FLOOR_AND_BALL.replace("center = [0.0, 1.0, 0.0]", "center = [0.0, 1.5, 0.0]");
    let mut desc = parse_toml(&format!(
        "{src}\n[[spheres]]\ncenter = [2.6, 1.5, 0.5]\nradius = 1.0\nmaterial = \"ball\"\n"
    ));
    (desc.camera.width, desc.camera.height) = (64, 48);
    desc.render.shade = ao(8, Some(0.45));
    let (flat, _) = image(&desc, 8, 2);
    let allowed = [Rgb::new(1.0, 0.5, 0.25), Rgb::new(0.0, 1.0, 0.0), Rgb::new(0.2, 0.3, 0.4)];
    for (i, p) in flat.pixels.iter().enumerate() {
        assert!(allowed.contains(p), "pixel {i}: {p:?}");
    }
    for c in allowed {
        assert!(flat.pixels.iter().filter(|&&p| p == c).count() > 100, "{c:?} is on screen");
    }
    desc.render.shade = ao(8, Some(0.55));
    let (reaching, _) = image(&desc, 8, 2);
    let darker = reaching.pixels.iter().filter(|p| p.x < 1.0 && p.y > 0.0 && p.y < 0.5).count();
    assert!(darker > 20, "rays of 0.55 reach the spheres from the floor below them: {darker} pixels");
}

/// A floor beside an infinite wall, with the default distance (only planes: unlimited): every direction
/// toward the wall meets it, so each floor point is open to exactly the half of the cosine-weighted
/// hemisphere that faces away, and each wall point likewise: AO = 1/2, for each pixel to within the
/// azimuths' discrepancy at 64 directions (at most 2/64 for golden-ratio steps), and on average closer.
#[test]
fn a_floor_beside_a_wall_sees_half_the_sky() {
    let src = r#"
        [camera]
        eye = [-2.0, 3.0, -4.0]
        look_at = [0.0, 0.0, 0.0]
        width = 40
        height = 30
        [materials.floor]
        color = [1.0, 0.0, 0.0]
        [materials.wall]
        color = [0.0, 1.0, 0.0]
        [[planes]]
        point = [0.0, 0.0, 0.0]
        normal = [0.0, 1.0, 0.0]
        material = "floor"
        [[planes]]
        point = [1.0, 0.0, 0.0]
        normal = [-1.0, 0.0, 0.0]
        material = "wall"
    "#;
    let mut desc = parse_toml(src);
    desc.render.shade = ao(64, None);
    let (img, _) = image(&desc, 16, 2);
    let (mut floor, mut wall, mut sum) = (0, 0, 0.0);
    for p in &img.pixels {
        let (v, n) = if p.y == 0.0 { (p.x, &mut floor) } else { (p.y, &mut wall) };
        assert!((v - 0.5).abs() <= 2.0 / 64.0, "{p:?}");
        sum += f64::from(v);
        *n += 1;
    }
    assert!(floor > 200 && wall > 200, "floor {floor}, wall {wall} pixels");
    let mean = sum / f64::from(floor + wall);
    assert!((mean - 0.5).abs() < 0.005, "mean {mean}");
}

/// Inside a closed sphere every occlusion ray meets the far side within its diameter: with a distance
/// longer than that every pixel is black. The rays leave the inside of the sphere they start on, which
/// the query must not skip.
#[test]
fn inside_a_closed_sphere_everything_is_occluded() {
    let src = r#"
        [camera]
        eye = [0.3, -0.2, 0.1]
        look_at = [1.0, 0.5, 2.0]
        hfov = 100
        width = 32
        height = 24
        [[spheres]]
        center = [0, 0, 0]
        radius = 2.0
    "#;
    let mut desc = parse_toml(src);
    desc.render.shade = ao(16, Some(4.5));
    let (img, rays) = image(&desc, 8, 2);
    assert_eq!(rays, 32 * 24 * 16);
    assert!(img.pixels.iter().all(|p| *p == Rgb::all(0.0)), "some ray escaped");
}
