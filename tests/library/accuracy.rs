//! `bareray accuracy`: the f32 renderer against its f64 twin.
//!
//! 1. A sphere straight ahead: the twin's t is the closed form, the report counts every pixel, and the
//!    secondary rays of a lone convex sphere behave as they must.
//! 2. The binary's `--json` output: one object with every documented key (in `tests/accuracy.rs`).
//! 3. Every stress scene (scenes/stress/) against the accuracy bounds: no unexplained disagreement, no
//!    self-hit, primary relative t error p99 ≤ 2e-6. Expected to fail on kernels that lose accuracy (a huge
//!    ground sphere seen from close by, scenes far from the origin) until they are fixed; the measured
//!    numbers are printed either way (`--nocapture`).
//! 4. The twin's BVH returns brute force's hits bit for bit.
//! 5. The explanations the random-scene campaign's failures needed: "tie" at a slant (a moved ray's hits on
//!    planes move by 1/|cos| of the move), and the sphere contact rule's entry at t = 0, which is no self-hit.

use super::common;

use std::path::{Path, PathBuf};

use bareray::accuracy::{run, Hit64, Options, Slack, Twin, EPS32, K_TIE};
use bareray::geometry::{first_root, sphere_roots, Departure, Ray, ShapeKind, NO_PRIM};
use bareray::kinds::cone::ConeDesc;
use bareray::kinds::sphere::SphereDesc;
use bareray::kinds::KindDescs;
use bareray::math::SplitMix64;
use bareray::math::V3;
use bareray::scene::desc::{LightDesc, Material, SceneDesc};
use common::camera;
use glam::{DAffine3, DMat3, DVec3};

fn opts(secondary: bool) -> Options {
    Options { lanes: 8, secondary, threads: Some(2), ..Options::default() }
}

/// A unit sphere at (0.3, −0.2, 7) seen from (0.1, 0.2, −3) filling most of a 64×48 image, one light behind
/// the eye. The twin's camera-relative t for every pixel is the closed form `proj − sqrt(r² − l²)` (relative
/// 1e-14); the report traces one ray per pixel; f32 t agrees to a few ε32; the mirror rays of a lone convex
/// sphere hit nothing, and its shadow rays are never blocked.
#[test]
fn sphere_straight_ahead_matches_the_closed_form() {
    let (eye, centre, r) = (DVec3::new(0.1, 0.2, -3.0), DVec3::new(0.3, -0.2, 7.0), 1.0);
    let desc = SceneDesc {
        camera: camera(eye, centre, DVec3::Y, 9.0, 64, 48),
        spheres: vec![SphereDesc { center: centre, radius: r, material: 0 }],
        lights: vec![LightDesc {
            position: DVec3::new(0.0, 1.0, -6.0),
            color: V3::all(1.0),
            falloff: Default::default(),
        }],
        ..SceneDesc::default()
    };
    let twin = Twin::new(&desc).expect("twin");
    let mut hits = 0;
    for y in 0..48 {
        for x in 0..64 {
            let ray = twin.camera_ray(f64::from(x) + 0.5, f64::from(y) + 0.5);
            assert_eq!(ray.origin, V3::all(0.0), "camera rays start at the eye, 0 in the twin's space");
            let d = DVec3::new(ray.dir.x, ray.dir.y, ray.dir.z);
            assert!((d.length() - 1.0).abs() < 1e-15);
            let c = centre - eye;
            let proj = c.dot(d);
            let l2 = (c - d * proj).length_squared();
            let hit = twin.intersect(&ray, Departure::CAMERA, f64::INFINITY);
            if l2 < r * r * (1.0 - 1e-9) {
                let exact = proj - (r * r - l2).sqrt();
                assert_eq!(hit.prim, 0, "pixel ({x}, {y})");
                assert!((hit.t - exact).abs() <= 1e-14 * exact, "pixel ({x}, {y}): {} vs {exact}", hit.t);
                hits += 1;
            } else if l2 > r * r * (1.0 + 1e-9) {
                assert_eq!(hit.prim, NO_PRIM, "pixel ({x}, {y})");
            }
        }
    }
    assert!(hits > 64 * 48 / 4, "the sphere covers the image: {hits} hits");

    let report = run("sphere", &desc, &opts(true)).expect("report");
    eprintln!("{}", report.table());
    let p = &report.primary;
    assert_eq!(p.rays, 64 * 48);
    assert_eq!((report.width, report.height, report.lanes), (64, 48, 8));
    assert_eq!(p.hits_agree + p.misses_agree + p.disagree(), p.rays);
    assert!(p.hits_agree.abs_diff(hits) <= 20, "{} hits agree, {hits} inside the rim", p.hits_agree);
    assert_eq!(p.t_rel_err.count, p.hits_agree);
    assert!(p.t_rel_err.max <= 1e-6, "{:?}", p.t_rel_err);
    assert!(p.t_rel_err.p50 <= p.t_rel_err.p99 && p.t_rel_err.p99 <= p.t_rel_err.max);
    assert_eq!(report.unexplained(), 0);
    assert_eq!(report.self_hits(), 0);
    let refl = report.reflection.expect("secondary");
    assert_eq!(refl.rays, p.hits_agree);
    assert_eq!(refl.misses_agree, refl.rays, "mirror rays leave a lone convex sphere: {refl:?}");
    let shadow = report.shadow.expect("secondary");
    assert!(shadow.rays > 0 && shadow.disagree() == 0, "{shadow:?}");
    assert_eq!(report.refraction.expect("secondary").rays, 0, "the default material does not transmit");
}

/// The same sphere in glass (ior 1.5): every camera hit refracts into the sphere (from outside there is no
/// total internal reflection), and every refraction ray meets the sphere's own far side in both precisions,
/// at the chord's length: no self-hit, no disagreement, t within a few ε32 of the twin's.
#[test]
fn glass_sphere_refracts_to_its_far_side() {
    let (eye, centre) = (DVec3::new(0.1, 0.2, -3.0), DVec3::new(0.3, -0.2, 7.0));
    let glass = Material { transmit: 0.9, ior: 1.5, ..Material::default() };
    let desc = SceneDesc {
        camera: camera(eye, centre, DVec3::Y, 9.0, 64, 48),
        materials: vec![glass],
        spheres: vec![SphereDesc { center: centre, radius: 1.0, material: 0 }],
        ..SceneDesc::default()
    };
    let report = run("glass sphere", &desc, &opts(true)).expect("report");
    eprintln!("{}", report.table());
    let p = &report.primary;
    let refr = report.refraction.expect("secondary");
    assert!(p.hits_agree > 64 * 48 / 4, "{p:?}");
    assert_eq!(refr.rays, p.hits_agree, "every hit from outside refracts: {refr:?}");
    assert_eq!(refr.hits_agree, refr.rays, "every refraction ray meets the far side: {refr:?}");
    assert_eq!((refr.disagree(), refr.unexplained, refr.self_hits), (0, 0, 0), "{refr:?}");
    assert!(refr.t_rel_err.p99 <= 1e-5, "{:?}", refr.t_rel_err);
    assert_eq!((report.unexplained(), report.self_hits()), (0, 0));
}

/// A vertical cylinder of radius 1 at x = 0.25, z = 6 seen from (0.25, 0.5, −4) along +z: the twin counts it
/// (its id follows the spheres), its t on the middle row is the closed form `d − sqrt(1 − x²)` for the ray's
/// offset x from the axis, and the f32 renderer agrees with it on every pixel up to the explanations.
#[test]
fn cylinder_in_the_twin_matches_the_closed_form() {
    let eye = DVec3::new(0.25, 0.5, -4.0);
    let desc = SceneDesc {
        camera: camera(eye, DVec3::new(0.25, 0.5, 6.0), DVec3::Y, 20.0, 64, 48),
        kinds: KindDescs {
            cones: vec![ConeDesc {
                base: DVec3::new(0.25, -1.0, 6.0),
                base_radius: 1.0,
                apex: DVec3::new(0.25, 2.0, 6.0),
                apex_radius: 1.0,
                material: 0,
            }],
            ..KindDescs::default()
        },
        lights: vec![LightDesc {
            position: DVec3::new(-3.0, 4.0, -2.0),
            color: V3::all(1.0),
            falloff: Default::default(),
        }],
        ..SceneDesc::default()
    };
    let twin = Twin::new(&desc).expect("twin");
    assert_eq!(twin.len(), 1);
    let mut hits = 0;
    for x in 0..64 {
        let ray = twin.camera_ray(f64::from(x) + 0.5, 24.0);
        let d = DVec3::new(ray.dir.x, ray.dir.y, ray.dir.z);
        // The middle row's rays lie in the plane y = 0.5 (camera-relative y = 0): a circle in x, z.
        let (c, dx) = (10.0 * DVec3::Z, d.x);
        let proj = c.dot(d);
        let l = (c - d * proj).length();
        let hit = twin.intersect(&ray, Departure::CAMERA, f64::INFINITY);
        if l < 1.0 - 1e-9 {
            let exact = proj - (1.0 - l * l).sqrt();
            assert_eq!(hit.prim, 0, "pixel {x} ({dx})");
            assert!((hit.t - exact).abs() <= 1e-13 * exact, "pixel {x}: {} vs {exact}", hit.t);
            hits += 1;
        } else if l > 1.0 + 1e-9 {
            assert_eq!(hit.prim, NO_PRIM, "pixel {x}");
        }
    }
    assert!(hits > 10, "{hits} hits on the middle row");
    let report = run("cylinder", &desc, &opts(true)).expect("report");
    eprintln!("{}", report.table());
    assert_eq!(report.primitives, 1);
    assert!(report.primary.hits_agree > 0);
    assert_eq!(report.unexplained(), 0);
    assert!(report.primary.t_rel_err.p99 <= 2e-6, "{:?}", report.primary.t_rel_err);
}

/// Nearest-rank percentiles: the p-th of n sorted values is the ⌈p·n⌉-th.
#[test]
fn percentiles_are_nearest_rank() {
    use bareray::accuracy::Percentiles;
    let p = Percentiles::of((1..=200).rev().map(f64::from).collect());
    assert_eq!((p.count, p.p50, p.p99, p.p999, p.max), (200, 100.0, 198.0, 200.0, 200.0));
    let one = Percentiles::of(vec![3.0]);
    assert_eq!((one.p50, one.p99, one.max), (3.0, 3.0, 3.0));
    assert!(Percentiles::of(Vec::new()).p50.is_nan());
}

/// The stress scenes of scenes/stress/ (each must be there); any other scene file there is checked too.
const STRESS_SCENES: [&str; 14] = [
    "cones-grazing.toml",
    "distant-100.toml",
    "distant-4100.toml",
    "distant-1e5.toml",
    "distant-1e6.toml",
    "eye-inside.toml",
    "flake-1e5.nff",
    "glass.toml",
    "grazing.toml",
    "ground-1e6-below.toml",
    "huge-ground.toml",
    "huge-ground-ellipsoid.toml",
    "radii-1e-6-to-1e6.toml",
    "touching-nested.toml",
];

/// The stress scenes with glass: their refraction rays are compared (the bounds below hold them too).
const GLASS_SCENES: [&str; 2] = ["glass.toml", "touching-nested.toml"];

/// Every stress scene against the accuracy bounds, with secondary rays: 0 unexplained disagreements, 0
/// self-hits (primary, shadow, reflection and refraction rays), primary relative t error p99 ≤ 2e-6; the
/// scenes with glass trace refraction rays. All numbers are printed before any bound is checked.
/// `ACCURACY_STRESS_DIR=dir` reads the scenes from `dir` instead.
#[test]
fn stress_scenes_meet_the_accuracy_bounds() {
    // `ACCURACY_STRESS_DIR` points the test at another copy of the scenes.
    let dir = std::env::var_os("ACCURACY_STRESS_DIR")
        .map_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/stress"), PathBuf::from);
    let mut scenes: Vec<PathBuf> = STRESS_SCENES.iter().map(|s| dir.join(s)).collect();
    if let Ok(entries) = std::fs::read_dir(&dir) {
        for e in entries.flatten() {
            let p = e.path();
            let scene = p.extension().is_some_and(|x| x == "toml" || x == "nff" || x == "xyzr");
            if scene && !scenes.contains(&p) {
                scenes.push(p);
            }
        }
    }
    let mut failures = Vec::new();
    let mut checked = 0;
    for path in &scenes {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        assert!(path.exists(), "{name}: the stress scene is missing");
        let desc = bareray::io::load(path).unwrap_or_else(|e| panic!("{name}: {e}"));
        let r = run(&name, &desc, &opts(true)).expect("report");
        checked += 1;
        eprint!("{}", r.table());
        let p99 = r.primary.t_rel_err.p99;
        let refr = r.refraction.expect("secondary");
        if GLASS_SCENES.contains(&name.as_str()) && refr.rays < 1000 {
            failures.push(format!("{name}: only {} refraction rays compared", refr.rays));
        }
        if refr.unexplained != 0 || refr.self_hits != 0 {
            failures.push(format!(
                "{name}: refraction: {} unexplained, {} self-hits",
                refr.unexplained, refr.self_hits
            ));
        }
        if r.unexplained() != 0 || r.self_hits() != 0 || p99 > 2e-6 {
            failures.push(format!(
                "{name}: {} unexplained, {} self-hits, primary t rel err p99 {p99:.3e}",
                r.unexplained(),
                r.self_hits()
            ));
        }
    }
    eprintln!("{checked} stress scenes checked");
    assert!(checked >= STRESS_SCENES.len());
    assert!(failures.is_empty(), "bounds not met:\n{}", failures.join("\n"));
}

/// The twin's sphere BVH gives brute force's closest hits bit for bit (t and id), for camera-like rays,
/// rays from inside spheres, rays aimed at sphere rims (a relative 1e-9 inside and outside), and secondary
/// rays leaving a sphere outward (skipped) or inward (its exit root), with and without a t_max.
#[test]
fn twin_bvh_equals_brute_force() {
    let mut rng = SplitMix64::new(21);
    let mut u = move || rng.unit();
    let mut spheres = Vec::new();
    for k in 0..3000 {
        let scale = [1.0, 1e-3, 1e3][k % 3];
        let c = DVec3::new(u() - 0.5, u() - 0.5, u() - 0.5) * 20.0 * scale;
        spheres.push(SphereDesc { center: c, radius: (0.01 + 0.5 * u()) * scale, material: 0 });
    }
    // Exact duplicates and touching pairs: ties in t go to the lower id.
    for k in 0..50 {
        spheres.push(spheres[k]);
        let s = spheres[k + 100];
        spheres.push(SphereDesc { center: s.center + DVec3::X * (2.0 * s.radius), ..s });
    }
    let desc = SceneDesc {
        camera: camera(DVec3::new(1.0, 2.0, -40.0), DVec3::ZERO, DVec3::Y, 50.0, 8, 8),
        spheres,
        ..SceneDesc::default()
    };
    let (bvh, brute) = (Twin::with_bvh(&desc, true).unwrap(), Twin::with_bvh(&desc, false).unwrap());
    assert!(bvh.has_bvh() && !brute.has_bvh());
    let eye = desc.camera.eye;
    let v = |p: DVec3| V3::new(p.x, p.y, p.z);
    let (mut hits, mut rays) = (0, 0);
    for case in 0..30_000 {
        let n = desc.spheres.len();
        let target = desc.spheres[(u() * n as f64) as usize % n];
        let c = target.center - eye;
        let (origin, dir, from) = match case % 4 {
            // From the eye toward a random point of the field.
            0 => (DVec3::ZERO, (DVec3::new(u() - 0.5, u() - 0.5, u() - 0.5) * 20.0 - eye).normalize(), None),
            // At a sphere's rim: a relative 1e-9 inside or outside the tangent line.
            1 => {
                let d = c.normalize();
                let side = d.any_orthonormal_vector();
                let off = target.radius * (1.0 + (u() - 0.5) * 2e-9);
                (DVec3::ZERO, (c + side * off).normalize(), None)
            }
            // From inside a sphere (its centre), any direction.
            2 => (c, DVec3::new(u() - 0.5, u() - 0.5, u() - 0.5).normalize(), None),
            // From a point on a sphere, leaving it outward or inward.
            _ => {
                let k = (u() * n as f64) as usize % n;
                let s = desc.spheres[k];
                let normal = DVec3::new(u() - 0.5, u() - 0.5, u() - 0.5).normalize();
                let p = s.center - eye + normal * s.radius;
                let d = DVec3::new(u() - 0.5, u() - 0.5, u() - 0.5).normalize();
                (p, d, Some(Departure { prim: k as u32, inward: d.dot(normal) < 0.0 }))
            }
        };
        let ray = Ray::new(v(origin), v(dir));
        let from = from.unwrap_or(Departure::CAMERA);
        let t_max = if case % 7 == 0 { 5.0 + 30.0 * u() } else { f64::INFINITY };
        let (a, b) = (bvh.intersect(&ray, from, t_max), brute.intersect(&ray, from, t_max));
        assert_eq!((a.prim, a.t.to_bits()), (b.prim, b.t.to_bits()), "case {case}: {a:?} vs {b:?}");
        assert_eq!(bvh.occluded(&ray, from, t_max), brute.occluded(&ray, from, t_max));
        rays += 1;
        hits += usize::from(a.prim != NO_PRIM);
    }
    assert!(hits > rays / 3, "{hits} of {rays} rays hit");
}

fn v3(p: DVec3) -> V3<f64> {
    V3::new(p.x, p.y, p.z)
}

/// Explanation "tie" at a slant (seed 786 of the campaign, scenes/stress/random-786-slant-planes.toml: a
/// reflection ray far from the eye, meeting two planes near the line where they cross at cosines 0.19 and
/// 0.30, found them in the other order in f32). Two planes crossing along a line about 1000 units from the
/// eye, rays aimed within a few units of that line at cosines of incidence from 0.1 to 1, each ray moved by
/// a random stray (origin by up to 0.05, direction by up to 2e-4): wherever the moved ray meets the planes
/// in the other order, [`Twin::tie`] with that stray as its slack explains it. The rule without the
/// cosines, `|ta − tb| ≤ K_TIE·ε32·(|o| + t) + slack`, leaves some of those flips unexplained, so the test
/// can fail.
#[test]
fn tie_explains_order_flips_of_a_strayed_ray_at_a_slant() {
    let mut rng = common::rng::Rng::new(786);
    let eye = DVec3::new(0.75, -0.5, 1.25);
    let plane = |point: DVec3, n: DVec3| {
        let e1 = n.any_orthonormal_vector();
        let frame = DMat3::from_cols(e1, n.cross(e1), n);
        common::shape(ShapeKind::Plane, DAffine3::from_mat3_translation(frame, eye + point))
    };
    let (mut flips, mut old_misses, mut unexplained) = (0, 0, Vec::new());
    for case in 0..10_000 {
        let na = rng.dir();
        let nb = (na + rng.tangent(na) * rng.range(0.2, 3.0)).normalize();
        let line = na.cross(nb).normalize();
        let at = rng.dir() * rng.range(500.0, 1500.0);
        let desc = SceneDesc {
            camera: camera(eye, eye + DVec3::Z, DVec3::Y, 40.0, 4, 4),
            kinds: common::shapes([plane(at, na), plane(at, nb)]),
            ..SceneDesc::default()
        };
        let twin = Twin::new(&desc).expect("twin");
        let target = at + line * rng.range(-50.0, 50.0) + rng.dir() * rng.range(0.0, 1.0);
        let d = target.normalize();
        if na.dot(d).abs() < 0.1 || nb.dot(d).abs() < 0.1 {
            continue;
        }
        let ray = Ray::new(V3::all(0.0), v3(d));
        let from = Departure::CAMERA;
        let (Some(ta), Some(tb)) = (twin.hit_of(0, &ray, from), twin.hit_of(1, &ray, from)) else { continue };
        let moved_origin = rng.dir() * rng.range(0.0, 0.05);
        let moved_dir = (d + rng.dir() * rng.range(0.0, 2e-4)).normalize();
        let moved = Ray::new(v3(moved_origin), v3(moved_dir));
        let (Some(ma), Some(mb)) = (twin.hit_of(0, &moved, from), twin.hit_of(1, &moved, from)) else {
            continue;
        };
        if ta == tb || (ta < tb) == (ma < mb) {
            continue;
        }
        flips += 1;
        let slack = Slack { origin: moved_origin.length(), dir: (moved_dir - d).length() };
        if !twin.tie(0, 1, &ray, from, K_TIE, slack) {
            unexplained.push(format!("case {case}: t {ta} {tb}, moved {ma} {mb}, {slack:?}"));
        }
        let t = ta.max(tb);
        old_misses += usize::from((ta - tb).abs() > K_TIE * EPS32 * t + slack.at(t));
    }
    eprintln!(
        "{flips} order flips, {} unexplained, {old_misses} beyond the rule without cosines",
        unexplained.len()
    );
    assert!(flips >= 300, "only {flips} flips: the test checks too little");
    assert!(unexplained.is_empty(), "{}", unexplained.join("\n"));
    assert!(old_misses > 0, "the rule without cosines explains every flip: the test cannot fail");
}

/// The sphere contact rule's entry (seed 7538 of the campaign, scenes/stress/random-7538-contact-band.toml:
/// a shadow ray from a plane 2.7e-5 inside a mirror sphere of radius 52, within the rule's band, entered
/// the sphere at t = 0 in f32, and the report counted it a self-hit). Spheres of radius 1e-3 to 1e3 up to
/// 1e4 from the eye, f32 origins within a few bands of their surfaces (inside and outside), any direction:
/// every hit the f32 kernel reports at exactly t = 0 is [`Twin::contact_entry`]; and origins 4 of the
/// twin's bands or more from the surface never are, so the explanation cannot excuse a far t = 0 hit.
#[test]
fn contact_entries_of_the_f32_kernel_are_recognised() {
    let mut rng = common::rng::Rng::new(7538);
    let eye = DVec3::new(-2.25, 0.5, 3.75);
    let (mut entries, mut far) = (0, 0);
    for case in 0..40_000 {
        let r = rng.log(-3.0, 3.0);
        let centre = eye + rng.dir() * rng.log(-1.0, 4.0).max(2.0 * r);
        // A speck just behind the eye keeps the eye's rendering frame (a lone sphere far from the eye would be
        // compiled around its centre): the large coordinates near the eye are what this checks.
        let speck = SphereDesc { center: eye + (eye - centre).normalize() * 0.01, radius: 1e-4, material: 0 };
        let desc = SceneDesc {
            camera: camera(eye, centre, DVec3::Y, 40.0, 4, 4),
            spheres: vec![SphereDesc { center: centre, radius: r, material: 0 }, speck],
            ..SceneDesc::default()
        };
        let twin = Twin::new(&desc).expect("twin");
        assert_eq!(twin.origin, eye, "case {case}: the eye's frame");
        let c = centre - eye;
        // The renderer's band in distance from the surface, about: 8 roundings of (|oc|² + r² + 2r·|o|∞)/(2r).
        let n = rng.dir();
        let band = 8.0 * EPS32 * (r + (c + n * r).abs().max_element());
        let off = band * rng.range(-12.0, 12.0);
        let origin = (c + n * (r + off)).as_vec3();
        let ray = Ray::new(V3::new(origin.x, origin.y, origin.z), v3(rng.dir()).to_f32());
        let (c32, r32) = (V3::new(c.x as f32, c.y as f32, c.z as f32), r as f32);
        let (hit, t) = first_root(&sphere_roots(c32, r32, &ray), f32::INFINITY);
        let zero = Hit64 { t: 0.0, prim: 0 };
        if hit && t == 0.0 {
            entries += 1;
            let o = origin.as_dvec3();
            let oc = c - o;
            assert!(
                twin.contact_entry(zero, &ray),
                "case {case}: an f32 contact entry not recognised: r {r:e}, |c| {:e}, off {:e} bands, oc·d/|oc| {:e}",
                c.length(),
                ((o - c).length() - r) / band,
                oc.dot(ray.dir.to_f64().into()) / oc.length()
            );
        }
        let o = origin.as_dvec3();
        let exact = (o - c).length() - r;
        if exact.abs() >= 4.0 * 2.0 * band {
            far += 1;
            assert!(
                !twin.contact_entry(zero, &ray),
                "case {case}: {exact:e} from the surface taken as contact"
            );
        }
    }
    eprintln!("{entries} contact entries, {far} origins beyond the band");
    assert!(entries > 1000 && far > 1000, "{entries} entries, {far} far origins");
}
