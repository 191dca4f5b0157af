//! Stress: the f32 renderer path against the f64 oracle ([`common::oracle`]) over whole primary-ray sets of
//! stress scenes — a dense contract field, small spheres far from the eye, a planet seen from just above its
//! surface, the touching spheres of a sphereflake, ellipsoids of extreme aspect and planes at grazing
//! incidence. Checked: the relative `t` error where both agree on the primitive, and the fraction of pixels
//! whose primitive differs, every one of which must be explained by tangency or a near-tie. This is what
//! proves the f32 kernels keep their accuracy where their formulas are stressed (ARCHITECTURE.md "Numerics").
//!
//! Bounds were set by measuring first (run with `--nocapture` to see the numbers printed by each test) and
//! then leaving the margin stated in each test's comment. `STRESS_MEASURE=1 cargo test --lib stress_ --
//! --nocapture` prints the measurements without asserting the bounds.

use super::common;

use bareray::compile::Scene;
use bareray::geometry::{Departure, ShapeKind, NO_PRIM};
use bareray::io::generate::{flake, FieldParams};
use bareray::kinds::polygon::PolygonDesc;
use bareray::kinds::KindDescs;
use bareray::scene::desc::SceneDesc;
use common::oracle::Oracle;
use common::rng::Rng;
use common::wide::{dv, wide_ray};
use common::{camera, compile, measuring, shape, shapes, sphere, EPS32};
use glam::{DAffine3, DQuat, DVec3};

/// What one primary-ray comparison found.
#[derive(Debug, Default)]
struct Agreement {
    pixels: usize,
    hits_agree: usize,
    max_rel_t: f64,
    /// Largest relative t error among agreeing pixels that are not grazing.
    max_rel_t_clear: f64,
    mismatches: usize,
    unexplained: usize,
}

/// Traces every pixel centre's camera ray (the renderer's, [`bareray::camera::Camera::ray_f32`]) with the f32
/// query and the same rays widened through the oracle. A primitive mismatch is explained when either primitive is grazed (see [`Oracle::grazing`] with
/// `k_graze`) or both primitives are hit in f64 within `k_tie·ε·(|o| + t)` of each other (a near-tie, such as
/// the contact point of touching spheres).
fn compare_primary(scene: &Scene, k_graze: f64, k_tie: f64) -> Agreement {
    let g = &scene.geometry;
    let oracle = Oracle::new(g);
    let cam = &scene.camera_f64;
    let mut a = Agreement::default();
    for j in 0..cam.height {
        for i in 0..cam.width {
            let ray = cam.ray_f32(i as f32 + 0.5, j as f32 + 0.5);
            let hit = g.intersect(&ray, Departure::CAMERA, f32::INFINITY);
            let r64 = wide_ray(&ray);
            let (p64, t64) = oracle.closest(&r64, NO_PRIM);
            a.pixels += 1;
            if hit.prim == p64 {
                if p64 != NO_PRIM {
                    a.hits_agree += 1;
                    // Relative to the ray's scale, |o| + t: t itself for rays from the eye (the origin), and
                    // for a far scene's rays, which start just short of it, the size f32 resolves there.
                    let rel = (f64::from(hit.t) - t64).abs() / (dv(r64.origin).length() + t64);
                    a.max_rel_t = a.max_rel_t.max(rel);
                    if !oracle.grazing(p64, &r64, k_graze) {
                        a.max_rel_t_clear = a.max_rel_t_clear.max(rel);
                    }
                }
                continue;
            }
            a.mismatches += 1;
            let grazed = oracle.grazing(hit.prim, &r64, k_graze) || oracle.grazing(p64, &r64, k_graze);
            let tie = match (oracle.hit_of(hit.prim.min(p64), &r64), oracle.hit_of(hit.prim.max(p64), &r64)) {
                (Some(ta), Some(tb)) if hit.prim != NO_PRIM && p64 != NO_PRIM => {
                    (ta - tb).abs() <= k_tie * EPS32 * (dv(r64.origin).length() + ta.max(tb))
                }
                _ => false,
            };
            if !(grazed || tie) {
                a.unexplained += 1;
                eprintln!(
                    "  unexplained mismatch at ({i},{j}): f32 {} t={} / f64 {p64} t={t64}",
                    hit.prim, hit.t
                );
            }
        }
    }
    a
}

/// Checks one scene's agreement against its bounds, printing the measurement.
fn check_agreement(name: &str, scene: &Scene, max_rel_t: f64, max_rel_t_clear: f64, max_mismatch: f64) {
    let a = compare_primary(scene, 16.0, 64.0);
    let frac = a.mismatches as f64 / a.pixels as f64;
    eprintln!(
        "{name}: {} pixels, {} hits agree, max rel t err {:.3e} (non-grazing {:.3e}), {} mismatches \
         ({:.3e}), {} unexplained",
        a.pixels, a.hits_agree, a.max_rel_t, a.max_rel_t_clear, a.mismatches, frac, a.unexplained
    );
    if measuring() {
        return;
    }
    assert!(a.hits_agree > a.pixels / 20, "{name}: the scene must cover the image: {a:?}");
    assert_eq!(a.unexplained, 0, "{name}: primitive mismatches away from tangency or ties: {a:?}");
    assert!(a.max_rel_t <= max_rel_t, "{name}: relative t error {:.3e} > {max_rel_t:.1e}", a.max_rel_t);
    assert!(
        a.max_rel_t_clear <= max_rel_t_clear,
        "{name}: non-grazing relative t error {:.3e} > {max_rel_t_clear:.1e}",
        a.max_rel_t_clear
    );
    assert!(frac <= max_mismatch, "{name}: mismatch fraction {frac:.3e} > {max_mismatch:.1e}");
}

/// The contract's 1000-sphere field (splitmix64, `bareray::io::generate`) under the contract camera at
/// 384×216. Proves the f32 path's hits match the f64 oracle on a dense field: t to a few ulps, and ids differ
/// only at silhouettes (tangency) or where two spheres overlap at the same depth. Measured: max relative t
/// error 3.0e-7 (5 ε) over 33480 hits, no id mismatch. Bounds (about 3×): 2e-6; mismatches ≤ 1e-3 of the
/// pixels, none unexplained.
#[test]
fn oracle_contract_sphere_field() {
    let field = FieldParams::default();
    let desc = SceneDesc {
        camera: camera(DVec3::new(0.0, 0.0, -4.0), DVec3::ZERO, DVec3::Y, 45.0, 384, 216),
        spheres: field
            .spheres()
            .unwrap()
            .map(|[x, y, z, r]| sphere(DVec3::new(x.into(), y.into(), z.into()), r.into()))
            .collect(),
        ..SceneDesc::default()
    };
    check_agreement("field", &compile(&desc), 2e-6, 2e-6, 1e-3);
}

/// A cluster of unit spheres 1e2..1e5 radii from the eye, off-axis, with a narrow field of view so that they
/// fill the image. Proves small distant spheres keep t accurate to a few ulps of the ray's scale at every
/// distance: the perpendicular form from the eye at 1e2, the far-scene frame from 1e3 on (compile's
/// `RenderingFrame`: rays start just short of the cluster). Measured: max relative t error 2.4e-7, 1.4e-6,
/// 3.3e-7, 2.8e-7 at 1e2, 1e3, 1e4, 1e5, no id mismatch (with the eye as origin at every distance: 0, 1, 2
/// and 32 pixels of 19200). Bounds: 3e-6 (non-grazing 2e-6), mismatches ≤ 5e-3 of the pixels.
#[test]
fn oracle_distant_small_spheres() {
    for dist in [1e2, 1e3, 1e4, 1e5] {
        let axis = DVec3::new(0.3, 0.2, 1.0).normalize();
        let centre = axis * dist;
        let side = axis.cross(DVec3::Y).normalize();
        let up = side.cross(axis);
        let mut spheres = Vec::new();
        for a in -1..=1 {
            for b in -1..=1 {
                spheres.push(sphere(centre + side * (2.05 * a as f64) + up * (2.05 * b as f64), 1.0));
            }
        }
        spheres.push(sphere(centre + axis * 3.0 + side * 0.7, 2.5));
        let hfov = 2.0 * (4.0 / dist).atan().to_degrees();
        let desc = SceneDesc {
            camera: camera(DVec3::new(0.1, -0.2, 0.3), centre, DVec3::Y, hfov, 160, 120),
            spheres,
            ..SceneDesc::default()
        };
        check_agreement(&format!("distant {dist:e}"), &compile(&desc), 3e-6, 2e-6, 5e-3);
    }
}

/// A planet (r = 1e4) with the eye 1 unit above its surface looking at the horizon, with small spheres resting
/// on it (touching it). The near root of the planet is the small difference of two numbers near 1e4 that
/// the perpendicular form's `proj − td` cancelled (1.2e-3 relative error); with the exact eye term and
/// Vieta's near root it is as accurate as any other hit. Measured: max relative t error 3.0e-7, no id
/// mismatch. Bounds: 2e-6 relative (the primary-ray bound tests/library/accuracy.rs holds every stress scene to;
/// 6.7×), mismatches ≤ 1e-3.
#[test]
fn oracle_planet_close_to_the_surface() {
    let r = 1.0e4;
    let mut spheres = vec![sphere(DVec3::new(0.0, -r, 0.0), r)];
    let mut rng = Rng::new(7);
    for _ in 0..20 {
        let rr = rng.range(0.2, 2.0);
        let at = DVec3::new(rng.range(-20.0, 20.0), 0.0, rng.range(3.0, 60.0));
        let n = (at - DVec3::new(0.0, -r, 0.0)).normalize();
        spheres.push(sphere(DVec3::new(0.0, -r, 0.0) + n * (r + rr), rr));
    }
    let desc = SceneDesc {
        camera: camera(DVec3::new(0.123, 1.0, 0.456), DVec3::new(0.0, 0.2, 30.0), DVec3::Y, 70.0, 240, 160),
        spheres,
        ..SceneDesc::default()
    };
    check_agreement("planet", &compile(&desc), 2e-6, 2e-6, 1e-3);
}

/// SPD's sphereflake at level 2 (91 spheres, every child touching its parent) with its floor polygon, from
/// SPD's viewpoint. Proves contact points do not produce mismatches other than near-ties and tangency.
/// Measured: max relative t error 2.5e-7 over 65536 hits, no id mismatch. Bounds: 2e-5, mismatches ≤ 1e-3.
#[test]
fn oracle_sphereflake_contacts() {
    let desc = SceneDesc {
        camera: camera(DVec3::new(2.1, 1.3, 1.7), DVec3::ZERO, DVec3::Z, 45.0, 256, 256),
        spheres: flake(2).unwrap().iter().map(|s| sphere(DVec3::new(s[0], s[1], s[2]), s[3])).collect(),
        kinds: KindDescs {
            polygons: vec![PolygonDesc {
                vertices: [[12.0, 12.0], [-12.0, 12.0], [-12.0, -12.0], [12.0, -12.0]]
                    .map(|[x, y]| DVec3::new(x, y, -0.5))
                    .to_vec(),
                normals: None,
                material: 0,
            }],
            ..KindDescs::default()
        },
        ..SceneDesc::default()
    };
    check_agreement("flake", &compile(&desc), 2e-5, 2e-5, 1e-3);
}

/// Ellipsoids of extreme aspect (semi-axes 1e-3 against 1e3) and tilted: a huge flat pancake under the eye,
/// a thin tilted disc, a needle close to the eye. Proves the transformed kernel (ray carried into object space
/// by the f32 inverse) keeps t accurate and loses hits only at the rim. Measured: max relative t error 6.3e-7
/// along the renderer's rays (8.7e-5, non-grazing 2.7e-5, along rays generated in f32: the object-space
/// origin `L·o + t` is a cancellation, amplified by L up to 1e3), no id mismatch. Bounds: 3e-4 (non-grazing 1e-4), mismatches ≤ 1e-3.
#[test]
fn oracle_extreme_ellipsoids() {
    let tilt = |deg: f64, axis: DVec3| {
        DAffine3::from_quat(DQuat::from_axis_angle(axis.normalize(), deg.to_radians()))
    };
    let desc = SceneDesc {
        camera: camera(DVec3::new(0.2, 1.0, -4.0), DVec3::new(0.0, 0.0, 0.0), DVec3::Y, 60.0, 240, 160),
        kinds: shapes([
            // Pancake: 1e3 × 1e-3 × 1e3, its top at y = −0.5.
            shape(
                ShapeKind::Sphere,
                DAffine3::from_translation(DVec3::new(0.0, -0.501, 0.0))
                    * DAffine3::from_scale(DVec3::new(1e3, 1e-3, 1e3)),
            ),
            // Thin disc 1.5 × 1.5 × 1e-3, tilted 70° about x.
            shape(
                ShapeKind::Sphere,
                DAffine3::from_translation(DVec3::new(-0.8, 0.6, 0.5))
                    * tilt(70.0, DVec3::new(1.0, 0.2, 0.0))
                    * DAffine3::from_scale(DVec3::new(1.5, 1.5, 1e-3)),
            ),
            // Needle 1e-3 × 1e-3 × 1, 0.05 from the eye.
            shape(
                ShapeKind::Sphere,
                DAffine3::from_translation(DVec3::new(0.21, 1.0, -3.95))
                    * tilt(30.0, DVec3::new(0.0, 1.0, 0.3))
                    * DAffine3::from_scale(DVec3::new(1e-3, 1e-3, 1.0)),
            ),
            // An elongated 1e3 × 1 × 1 bar across the view.
            shape(
                ShapeKind::Sphere,
                DAffine3::from_translation(DVec3::new(0.0, 1.3, 2.0))
                    * tilt(10.0, DVec3::Z)
                    * DAffine3::from_scale(DVec3::new(1e3, 0.3, 0.3)),
            ),
        ]),
        ..SceneDesc::default()
    };
    check_agreement("ellipsoids", &compile(&desc), 3e-4, 1e-4, 1e-3);
}

/// Planes tilted by small angles seen from 1e-2 above them, so most rays meet them at grazing angles out to
/// t ~ 1e4 and beyond, with a sphere resting on one. Proves the plane kernel (t = −o_z/d_z in object space)
/// keeps its relative accuracy at grazing incidence and that pixels near the horizon differ only where the
/// direction is within ulps of parallel. Measured: max relative t error 2.3e-6, no id mismatch. Bounds:
/// 1e-5 (4×), mismatches ≤ 1e-3.
#[test]
fn oracle_grazing_tilted_planes() {
    let plane = |p: DVec3, n: DVec3| {
        shape(
            ShapeKind::Plane,
            DAffine3::from_translation(p)
                * DAffine3::from_quat(DQuat::from_rotation_arc(DVec3::Z, n.normalize())),
        )
    };
    let desc = SceneDesc {
        camera: camera(DVec3::new(0.3, 0.01, 0.2), DVec3::new(0.0, 0.0, 100.0), DVec3::Y, 40.0, 240, 120),
        spheres: vec![sphere(DVec3::new(0.5, 0.2, 5.0), 0.2)],
        kinds: shapes([
            plane(DVec3::ZERO, DVec3::new(0.0, 1.0, 0.0).normalize() + DVec3::new(0.017, 0.0, 0.0)),
            plane(DVec3::new(0.0, 3.0, 0.0), DVec3::new(0.001, -1.0, 0.0003)),
            plane(DVec3::new(4.0, 0.0, 0.0), DVec3::new(-1.0, 0.001, 0.01)),
        ]),
        ..SceneDesc::default()
    };
    check_agreement("planes", &compile(&desc), 1e-5, 1e-5, 1e-3);
}

/// The registered kinds (open cones and tori) against the oracle, which widens them through the registry:
/// the cone and torus scenes of `scenes/` and `scenes/stress/` at their own cameras, 160×120. Proves the f32
/// kernels' hits match their f64 forms (the cone kernel at f64; for tori the independent closed-form
/// quartic): same primitive on every pixel, t within the kernels' stated bounds. Measured, max relative t
/// error: cones 1.8e-6, cones-grazing 2.0e-5 (the cone kernel's bound near tangency, `kinds::cone::kernel`), tori
/// 1.3e-6, torus-inside 1.1e-5 (t short against the ray's scale inside the tube), tori-distant 7.9e-7; no id
/// mismatch. Bounds about 2.5× those; mismatches ≤ 1e-3 of the pixels, none unexplained.
#[test]
fn oracle_registered_kinds() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    for (name, max_rel_t) in [
        ("scenes/cones.toml", 5e-6),
        ("scenes/stress/cones-grazing.toml", 5e-5),
        ("scenes/stress/tori.toml", 3e-6),
        ("scenes/stress/torus-inside.toml", 3e-5),
        ("scenes/stress/tori-distant.toml", 2e-6),
    ] {
        let mut desc = bareray::io::load(&root.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        (desc.camera.width, desc.camera.height) = (160, 120);
        let scene = compile(&desc);
        assert!(scene.geometry.kinds.widened().len() > 0, "{name}: no registered kind");
        check_agreement(name, &scene, max_rel_t, max_rel_t, 1e-3);
    }
}
