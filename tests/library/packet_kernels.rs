//! Every lane of every packet kernel against its scalar twin, at K = 4, 8 and 16: `t` bits and hit masks
//! identical, primitive ids identical. Each check is one generic function instantiated per width.
//!
//! NaN lanes are compared as "both NaN": IEEE and LLVM leave NaN payloads unspecified (x86 keeps the first
//! operand's, and LLVM may commute `a + b`), so only NaN-ness is a property of the formula. Hit lanes never
//! carry a NaN t.

use super::common;

use bareray::accel::Geometry;
use bareray::camera::Camera;
use bareray::geometry::{
    intersect_plane, intersect_sphere, sphere_roots, Departure, Hit, Ray, RayPacket, Shape, ShapeKind,
};
use bareray::kinds::cone::{intersect_cone, Cone};
use bareray::kinds::sphere::{intersect_spheres_1, intersect_spheres_k, Spheres};
use bareray::math::{Vec3f, V3};
use bareray::scene::desc::CameraDesc;
use bareray::simd::{IdLanes, Lanes};
use common::wide::{f32v, wide_ray};
use glam::{DAffine3, DQuat, DVec3};
use proptest::prelude::*;
use proptest::strategy::ValueTree;
use wide::{f32x16, f32x4, f32x8};

// ---------------------------------------------------------------------------------------------------------
// Cases

/// A ray, its `t_max` and whether its lane is active.
type LaneRay = (Ray<f32>, f32, bool);

/// Spheres and rays for one test case.
#[derive(Clone, Debug)]
struct Case {
    spheres: Vec<(Vec3f, f32)>,
    rays: Vec<LaneRay>,
}

impl Case {
    fn spheres(&self) -> Spheres {
        let mut s = Spheres::default();
        for &(c, r) in &self.spheres {
            s.push(c, r, 0);
        }
        s
    }

    /// The rays in packets of K, the last one padded with inactive lanes.
    fn packets<F: Lanes>(&self) -> Vec<(RayPacket<F>, &[LaneRay])> {
        self.rays
            .chunks(F::K)
            .map(|chunk| {
                let packet =
                    RayPacket::from_fn(|i| chunk.get(i).copied().unwrap_or((chunk[0].0, 1.0, false)));
                (packet, chunk)
            })
            .collect()
    }
}

/// Ordinary coordinates, with a few far and a few tiny ones.
fn coord() -> impl Strategy<Value = f32> {
    prop_oneof![
        8 => -10.0f32..10.0,
        1 => (3.0f32..6.0, any::<bool>()).prop_map(|(e, neg)| if neg { -(10f32.powf(e)) } else { 10f32.powf(e) }),
        1 => -1e-4f32..1e-4,
    ]
}

/// Direction components: ordinary, or NaN, ±inf, ±0.
fn dir_component() -> impl Strategy<Value = f32> {
    prop_oneof![
        12 => -1.0f32..1.0,
        1 => Just(f32::NAN),
        1 => Just(f32::INFINITY),
        1 => Just(f32::NEG_INFINITY),
        1 => Just(0.0f32),
        1 => Just(-0.0f32),
    ]
}

fn point() -> impl Strategy<Value = Vec3f> {
    (coord(), coord(), coord()).prop_map(|(x, y, z)| V3::new(x, y, z))
}

fn direction() -> impl Strategy<Value = Vec3f> {
    prop_oneof![
        9 => (dir_component(), dir_component(), dir_component()).prop_map(|(x, y, z)| V3::new(x, y, z)),
        1 => Just(V3::all(0.0f32)),
    ]
}

/// Radii from 1e-4 to 1e4 (log-uniform), and an occasional zero.
fn radius() -> impl Strategy<Value = f32> {
    prop_oneof![10 => (-4.0f32..4.0).prop_map(|e| 10f32.powf(e)), 1 => Just(0.0f32)]
}

fn t_max() -> impl Strategy<Value = f32> {
    prop_oneof![
        4 => Just(f32::INFINITY),
        2 => 0.0f32..50.0,
        1 => Just(0.0f32),
        1 => Just(f32::NAN),
    ]
}

/// How a ray is made; `Aimed` and `Inside` refer to a sphere of the case by index (modulo the count).
#[derive(Clone, Debug)]
enum Recipe {
    Free(Vec3f, Vec3f),
    /// From a point towards the sphere's centre displaced by `1.7·jitter·r` (up to 2r off: some miss).
    Aimed(usize, Vec3f, Vec3f),
    /// From the centre displaced by `frac`·r (inside when |frac| < 1) in any direction.
    Inside(usize, Vec3f, Vec3f),
}

fn recipe() -> impl Strategy<Value = Recipe> {
    let unit = || (-0.7f32..0.7, -0.7f32..0.7, -0.7f32..0.7).prop_map(|(x, y, z)| V3::new(x, y, z));
    prop_oneof![
        (point(), direction()).prop_map(|(o, d)| Recipe::Free(o, d)),
        (any::<usize>(), point(), unit()).prop_map(|(i, o, j)| Recipe::Aimed(i, o, j)),
        (any::<usize>(), unit(), direction()).prop_map(|(i, f, d)| Recipe::Inside(i, f, d)),
    ]
}

/// A sphere with a ray tangent to it, built so every intermediate value is exact in f32: integer centre,
/// radius a multiple of 1/8, direction `(0, 3s, 4s)` and origin `centre + (r, −3ks, −4ks)` (axes rotated).
/// Then `c = (−r, 3ks, 4ks)`, `c·d = 25ks²`, `d·d = 25s²`, `proj = k`, `perp = (−r, 0, 0)` and `l² = r²`
/// bit for bit: the lecture's case 2, a single touching root.
fn tangent() -> impl Strategy<Value = ((Vec3f, f32), Ray<f32>)> {
    (
        (-50i32..50, -50i32..50, -50i32..50),
        1i32..64,
        prop_oneof![Just(1i32), Just(2), Just(4)],
        -20i32..20,
        0usize..3,
    )
        .prop_map(|((x, y, z), r8, s, k, rot)| {
            let centre = [x as f32, y as f32, z as f32];
            let r = r8 as f32 / 8.0;
            let (k, s) = ((k * s) as f32, s as f32);
            let (off, dir) = ([r, -3.0 * k, -4.0 * k], [0.0, 3.0 * s, 4.0 * s]);
            let axis = |v: [f32; 3], i: usize| v[(i + rot) % 3];
            let c = V3::new(centre[0], centre[1], centre[2]);
            let o = V3::new(axis(off, 0), axis(off, 1), axis(off, 2)) + c;
            let d = V3::new(axis(dir, 0), axis(dir, 1), axis(dir, 2));
            ((c, r), Ray::new(o, d))
        })
}

fn case() -> impl Strategy<Value = Case> {
    let sphere = (point(), radius());
    (
        prop::collection::vec((sphere, any::<bool>()), 0..24),
        prop::collection::vec(tangent(), 0..4),
        prop::collection::vec((recipe(), t_max(), prop::bool::weighted(0.8)), 1..40),
    )
        .prop_map(|(random, tangents, recipes)| {
            let mut spheres: Vec<(Vec3f, f32)> = Vec::new();
            for (s, duplicate) in random {
                // Exact duplicates make ties, which the lower id must win.
                spheres.push(if duplicate && !spheres.is_empty() { spheres[spheres.len() - 1] } else { s });
            }
            spheres.extend(tangents.iter().map(|t| t.0));
            let mut rays: Vec<_> =
                recipes.into_iter().map(|(r, t, a)| (realise(&r, &spheres), t, a)).collect();
            rays.extend(tangents.iter().map(|t| (t.1, f32::INFINITY, true)));
            Case { spheres, rays }
        })
}

fn realise(recipe: &Recipe, spheres: &[(Vec3f, f32)]) -> Ray<f32> {
    let sphere = |i: usize| spheres.get(i % spheres.len().max(1)).copied().unwrap_or((V3::all(0.0), 1.0));
    match *recipe {
        Recipe::Free(o, d) => Ray::new(o, d),
        Recipe::Aimed(i, o, jitter) => {
            let (c, r) = sphere(i);
            Ray::new(o, c + jitter * (1.7 * r) - o)
        }
        Recipe::Inside(i, frac, d) => {
            let (c, r) = sphere(i);
            Ray::new(c + frac * r, d)
        }
    }
}

// ---------------------------------------------------------------------------------------------------------
// Comparisons

fn same_t(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

fn check_t(what: &str, k: usize, lane: usize, packet: f32, scalar: f32) -> Result<(), TestCaseError> {
    prop_assert!(
        same_t(packet, scalar),
        "{what} K={k} lane {lane}: {packet:e} ({:#x}) vs scalar {scalar:e} ({:#x})",
        packet.to_bits(),
        scalar.to_bits()
    );
    Ok(())
}

fn check_mask(what: &str, k: usize, lane: usize, packet: bool, scalar: bool) -> Result<(), TestCaseError> {
    prop_assert_eq!(packet, scalar, "{} K={} lane {}: hit mask", what, k, lane);
    Ok(())
}

fn check_hit(what: &str, k: usize, lane: usize, packet: Hit, scalar: Hit) -> Result<(), TestCaseError> {
    check_t(what, k, lane, packet.t, scalar.t)?;
    prop_assert_eq!(packet.prim, scalar.prim, "{} K={} lane {}: prim", what, k, lane);
    Ok(())
}

// ---------------------------------------------------------------------------------------------------------
// Per-primitive kernels: lanes = rays, one primitive splatted

fn check_sphere_kernels<F: Lanes>(case: &Case) -> Result<(), TestCaseError> {
    for (packet, rays) in case.packets::<F>() {
        for &(c, r) in &case.spheres {
            let (ck, rk) = (F::splat_v3(c), F::splat_f32(r));
            let roots = sphere_roots(ck, rk, packet.ray());
            let (hit, t) = intersect_sphere(ck, rk, packet.ray(), packet.t_max);
            for (i, (ray, t_max, _)) in rays.iter().enumerate() {
                let want = sphere_roots(c, r, ray);
                check_mask("sphere_roots", F::K, i, F::mask_lane(roots.hit, i), want.hit)?;
                check_t("sphere_roots near", F::K, i, roots.near.lane(i), want.near)?;
                check_t("sphere_roots far", F::K, i, roots.far.lane(i), want.far)?;
                let (want_hit, want_t) = intersect_sphere(c, r, ray, *t_max);
                check_mask("intersect_sphere", F::K, i, F::mask_lane(hit, i), want_hit)?;
                check_t("intersect_sphere", F::K, i, t.lane(i), want_t)?;
            }
        }
    }
    Ok(())
}

fn check_plane_kernel<F: Lanes>(case: &Case) -> Result<(), TestCaseError> {
    for (packet, rays) in case.packets::<F>() {
        let (hit, t) = intersect_plane(packet.ray(), packet.t_max);
        for (i, (ray, t_max, _)) in rays.iter().enumerate() {
            let (want_hit, want_t) = intersect_plane(ray, *t_max);
            check_mask("intersect_plane", F::K, i, F::mask_lane(hit, i), want_hit)?;
            check_t("intersect_plane", F::K, i, t.lane(i), want_t)?;
        }
    }
    Ok(())
}

fn check_shape_kernel<F: Lanes>(case: &Case, shape: &Shape<f32>) -> Result<(), TestCaseError> {
    let lanes = shape.to_lanes::<F>();
    for (packet, rays) in case.packets::<F>() {
        let (hit, t) = lanes.intersect(packet.ray(), packet.t_max);
        for (i, (ray, t_max, _)) in rays.iter().enumerate() {
            let (want_hit, want_t) = shape.intersect(ray, *t_max);
            check_mask("Shape::intersect", F::K, i, F::mask_lane(hit, i), want_hit)?;
            check_t("Shape::intersect", F::K, i, t.lane(i), want_t)?;
        }
    }
    Ok(())
}

fn check_camera<F: Lanes>(camera: &Camera<f64>, pixels: &[(f32, f32)]) -> Result<(), TestCaseError> {
    for chunk in pixels.chunks(F::K) {
        let at = |i: usize| chunk[i.min(chunk.len() - 1)];
        let rays = camera.rays(F::from_fn(|i| at(i).0), F::from_fn(|i| at(i).1));
        for (i, &(sx, sy)) in chunk.iter().enumerate() {
            let want = camera.ray_f32(sx, sy);
            let got = |v: V3<F>| [v.x.lane(i), v.y.lane(i), v.z.lane(i)];
            let expect = |v: Vec3f| [v.x, v.y, v.z];
            for (axis, (g, w)) in got(rays.dir).iter().zip(expect(want.dir)).enumerate() {
                check_t(&format!("Camera::ray dir[{axis}]"), F::K, i, *g, w)?;
            }
            for (axis, (g, w)) in got(rays.origin).iter().zip(expect(want.origin)).enumerate() {
                check_t(&format!("Camera::ray origin[{axis}]"), F::K, i, *g, w)?;
            }
        }
    }
    Ok(())
}

/// A cone (rounded from f64 once, as the store does) and rays for it: aimed at points on or near its
/// surface (some through the open ends, some tangent-ish), started inside, or free.
fn cone_case() -> impl Strategy<Value = (Cone<f32>, Vec<LaneRay>)> {
    let ends = (point(), point(), radius(), radius(), 0usize..4);
    let aim = (0.0f32..1.0, 0.0f32..std::f32::consts::TAU, 0.8f32..1.2);
    let rays = prop::collection::vec((recipe(), aim, t_max(), prop::bool::weighted(0.8)), 1..40);
    (ends, rays).prop_filter_map("degenerate cone", |((b, a, r0, r1, kind), rays)| {
        let (b, a) = (b.to_f64(), a.to_f64());
        // Pointed at either end, a cylinder, or general.
        let (r0, r1) = match kind {
            0 => (f64::from(r0), 0.0),
            1 => (0.0, f64::from(r1)),
            2 => (f64::from(r0), f64::from(r0)),
            _ => (f64::from(r0), f64::from(r1)),
        };
        let exact = Cone::new(DVec3::new(b.x, b.y, b.z), r0, DVec3::new(a.x, a.y, a.z), r1)?;
        let cone = exact.to_f32();
        let rays = rays
            .into_iter()
            .map(|(recipe, (s, angle, spread), t_max, active)| {
                let z = s * cone.height;
                let r = (cone.base_radius + cone.slope * z) * spread;
                let f = &cone.frame;
                let on = f.origin + f.axis * z + (f.e1 * angle.cos() + f.e2 * angle.sin()) * r;
                let ray = match recipe {
                    Recipe::Free(o, d) => Ray::new(o, d),
                    Recipe::Aimed(_, o, jitter) => Ray::new(o, on + jitter * 1e-3 - o),
                    Recipe::Inside(_, frac, d) => Ray::new(f.origin + f.axis * z + frac * r, d),
                };
                (ray, t_max, active)
            })
            .collect();
        Some((cone, rays))
    })
}

fn check_cone_kernel<F: Lanes>(cone: &Cone<f32>, rays: &[LaneRay]) -> Result<(), TestCaseError> {
    let lanes = cone.map(F::splat_f32);
    for chunk in rays.chunks(F::K) {
        let packet = RayPacket::<F>::from_fn(|i| chunk.get(i).copied().unwrap_or((chunk[0].0, 1.0, false)));
        let (hit, t) = intersect_cone(&lanes, packet.ray(), packet.t_max);
        let local = lanes.frame.to_object(packet.ray().at(t));
        let normal = lanes.object_normal(local);
        for (i, (ray, t_max, _)) in chunk.iter().enumerate() {
            let (want_hit, want_t) = intersect_cone(cone, ray, *t_max);
            check_mask("intersect_cone", F::K, i, F::mask_lane(hit, i), want_hit)?;
            check_t("intersect_cone", F::K, i, t.lane(i), want_t)?;
            let want_local = cone.frame.to_object(ray.at(want_t));
            let want_normal = cone.object_normal(want_local);
            for (what, got, want) in
                [("Frame::to_object", local, want_local), ("Cone::object_normal", normal, want_normal)]
            {
                check_t(what, F::K, i, got.x.lane(i), want.x)?;
                check_t(what, F::K, i, got.y.lane(i), want.y)?;
                check_t(what, F::K, i, got.z.lane(i), want.z)?;
            }
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------------------
// Packet kernels against the scalar brute-force query

fn geometry(case: &Case) -> Geometry {
    Geometry { spheres: case.spheres(), ..Geometry::default() }
}

fn check_packet_kernel<F: Lanes>(case: &Case) -> Result<(), TestCaseError> {
    let geo = geometry(case);
    for (packet, rays) in case.packets::<F>() {
        let hits = intersect_spheres_k(&geo.spheres, &packet);
        for i in 0..F::K {
            let want = match rays.get(i) {
                Some(&(ray, t_max, true)) => geo.intersect(&ray, Departure::CAMERA, t_max),
                _ => Hit::MISS,
            };
            check_hit("intersect_spheres_k", F::K, i, hits.lane(i), want)?;
            check_mask("intersect_spheres_k found", F::K, i, F::mask_lane(hits.found(), i), want.is_hit())?;
        }
    }
    Ok(())
}

fn check_transposed_kernel<F: Lanes>(case: &Case) -> Result<(), TestCaseError> {
    let geo = geometry(case);
    for (i, &(ray, t_max, _)) in case.rays.iter().enumerate() {
        let want = geo.intersect(&ray, Departure::CAMERA, t_max);
        check_hit("intersect_spheres_1", F::K, i, intersect_spheres_1::<F>(&geo.spheres, &ray, t_max), want)?;
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------------------
// Shapes and cameras

fn shape() -> impl Strategy<Value = Shape<f32>> {
    let scale = (-2.0f64..2.0).prop_map(|e| 10f64.powf(e));
    (
        any::<bool>(),
        (scale.clone(), scale.clone(), scale),
        (-3.0f64..3.0, -1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
        (-10.0f64..10.0, -10.0f64..10.0, -10.0f64..10.0),
    )
        .prop_map(|(sphere, (sx, sy, sz), (angle, ax, ay, az), (tx, ty, tz))| {
            let axis = DVec3::new(ax, ay, az + 1e-3).normalize();
            let m = DAffine3::from_scale_rotation_translation(
                DVec3::new(sx, sy, sz),
                DQuat::from_axis_angle(axis, angle),
                DVec3::new(tx, ty, tz),
            );
            Shape::placed(if sphere { ShapeKind::Sphere } else { ShapeKind::Plane }, &m, 0).to_f32()
        })
}

/// A real camera from a description, or an arbitrary frame (the formula does not need an orthonormal one).
fn camera() -> impl Strategy<Value = Camera<f64>> {
    let real = (point(), point(), 1u32..4000, 1u32..4000, 1.0f64..170.0).prop_filter_map(
        "degenerate view",
        |(eye, look, width, height, fov)| {
            let desc = CameraDesc {
                eye: DVec3::new(eye.x.into(), eye.y.into(), eye.z.into()),
                aim: bareray::scene::desc::Aim::LookAt(DVec3::new(
                    look.x.into(),
                    look.y.into(),
                    look.z.into(),
                )),
                width,
                height,
                field: bareray::scene::desc::Field::HorizontalAngle(fov),
                ..CameraDesc::default()
            };
            Camera::new(&desc).ok()
        },
    );
    let arbitrary = (point(), direction(), direction(), direction(), prop::array::uniform6(coord()))
        .prop_map(|(eye, forward, right, up, s)| {
            let mut c = Camera::new(&CameraDesc::default()).unwrap();
            (c.eye, c.forward, c.right, c.up) = (eye.to_f64(), forward.to_f64(), right.to_f64(), up.to_f64());
            let s = s.map(f64::from);
            (c.half_w, c.half_h, c.u_scale, c.u_offset, c.v_scale, c.v_offset) =
                (s[0], s[1], s[2], s[3], s[4], s[5]);
            c
        });
    prop_oneof![3 => real, 1 => arbitrary]
}

fn pixel() -> impl Strategy<Value = (f32, f32)> {
    let c = prop_oneof![10 => 0.0f32..4000.0, 1 => Just(f32::NAN), 1 => Just(f32::INFINITY)];
    (c.clone(), c)
}

// ---------------------------------------------------------------------------------------------------------
// The properties: one generic check, instantiated at every width

macro_rules! at_every_width {
    ($check:ident ( $($arg:expr),* )) => {{
        $check::<f32x4>($($arg),*)?;
        $check::<f32x8>($($arg),*)?;
        $check::<f32x16>($($arg),*)?;
    }};
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn sphere_roots_and_intersect_sphere_match_scalar(case in case()) {
        at_every_width!(check_sphere_kernels(&case));
    }

    #[test]
    fn intersect_plane_matches_scalar(case in case()) {
        at_every_width!(check_plane_kernel(&case));
    }

    #[test]
    fn shape_intersect_matches_scalar(case in case(), shape in shape()) {
        at_every_width!(check_shape_kernel(&case, &shape));
    }

    #[test]
    fn intersect_cone_matches_scalar((cone, rays) in cone_case()) {
        at_every_width!(check_cone_kernel(&cone, &rays));
    }

    #[test]
    fn camera_ray_matches_scalar(camera in camera(), pixels in prop::collection::vec(pixel(), 1..40)) {
        at_every_width!(check_camera(&camera, &pixels));
    }

    #[test]
    fn packet_kernel_matches_brute_force(case in case()) {
        at_every_width!(check_packet_kernel(&case));
        // K = 1 is the same code at the scalar type.
        check_packet_kernel::<f32>(&case)?;
    }

    #[test]
    fn transposed_kernel_matches_brute_force(case in case()) {
        at_every_width!(check_transposed_kernel(&case));
        check_transposed_kernel::<f32>(&case)?;
    }
}

// ---------------------------------------------------------------------------------------------------------
// The generators reach the cases they claim to

#[test]
fn tangent_recipe_gives_exact_touching_roots() {
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    for _ in 0..200 {
        let ((c, r), ray) = tangent().new_tree(&mut runner).unwrap().current();
        let roots = sphere_roots(c, r, &ray);
        assert!(roots.hit, "{c:?} {r} {ray:?}");
        assert_eq!(roots.near.to_bits(), roots.far.to_bits(), "{c:?} {r} {ray:?}");
        // One ulp further out misses.
        let r_less = f32::from_bits(r.to_bits() - 1);
        assert!(!sphere_roots(c, r_less, &ray).hit);
    }
}

/// The cone cases hit and miss in good numbers, pointed cones and cylinders among them.
#[test]
fn cone_cases_cover_hits_misses_and_every_kind() {
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let (mut hits, mut misses, mut pointed, mut cylinders) = (0, 0, 0, 0);
    for _ in 0..200 {
        let (cone, rays) = cone_case().new_tree(&mut runner).unwrap().current();
        pointed += usize::from(cone.base_radius == 0.0 || cone.base_radius + cone.slope * cone.height <= 0.0);
        cylinders += usize::from(cone.slope == 0.0);
        for (ray, t_max, _) in rays {
            let hit = intersect_cone(&cone, &ray, t_max).0;
            hits += usize::from(hit);
            misses += usize::from(!hit);
        }
    }
    assert!(
        hits > 500 && misses > 500 && pointed > 40 && cylinders > 20,
        "{hits} {misses} {pointed} {cylinders}"
    );
}

#[test]
fn cases_cover_hits_inside_starts_ties_and_inactive_lanes() {
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let (mut hits, mut inside, mut ties, mut inactive, mut nan_dirs) = (0, 0, 0, 0, 0);
    for _ in 0..200 {
        let case = case().new_tree(&mut runner).unwrap().current();
        let geo = geometry(&case);
        for &(ray, t_max, active) in &case.rays {
            let hit = geo.intersect(&ray, Departure::CAMERA, t_max);
            hits += usize::from(hit.is_hit());
            inactive += usize::from(!active);
            nan_dirs += usize::from(ray.dir.x.is_nan() || ray.dir.y.is_nan() || ray.dir.z.is_nan());
            let starts_inside = |&(c, r): &(Vec3f, f32)| (ray.origin - c).dot(ray.origin - c) < r * r;
            inside += usize::from(case.spheres.iter().any(starts_inside));
            if hit.is_hit() {
                let same = |&(c, r): &(Vec3f, f32)| intersect_sphere(c, r, &ray, f32::INFINITY).1 == hit.t;
                ties += usize::from(case.spheres.iter().filter(|s| same(s)).count() > 1);
            }
        }
    }
    assert!(
        hits > 500 && inside > 100 && ties > 50 && inactive > 100 && nan_dirs > 50,
        "hits {hits}, inside {inside}, ties {ties}, inactive {inactive}, NaN directions {nan_dirs}"
    );
}

// ---------------------------------------------------------------------------------------------------------
// f64 oracle: the f32 error of the sphere kernel on small, far spheres

/// Bound on |t_f32 − t_f64| / t_f64, for the same f32 inputs evaluated in f32 and in f64 (so it measures the
/// kernel, not the rounding of the ray), on rays that hit well inside the silhouette (offset ≤ 0.9 r from the
/// centre line), spheres 10 to 1e5 radii away at distances 10 to 1e5.
///
/// Why this bound: `proj` carries a few roundings relative to itself (≈ 3ε); `perp = c − proj·d` cancels
/// down to ≤ r but keeps an absolute error ≈ ε·|c|, so `r² − l²` is off by ≈ 2ε·r·|c| and
/// `td = sqrt((r² − l²)/(d·d))` by ≈ ε·r·|c| / td ≤ 2.3ε·|c| when td ≥ 0.44 r. Both relative to t ≈ |c|:
/// ≈ 5ε to first order, whatever the distance; 8ε leaves margin (20 000 samples measure ≈ 2ε). The distance
/// matters for hit or miss instead: the ε·|c| error in `perp` reaches r at ≈ 1e7 radii, where f32 starts to
/// lose spheres the f64 oracle hits (1e5 is safe). Near-tangent rays are excluded on purpose: td → 0 there
/// and its relative error is unbounded in any precision.
const F32_T_REL_ERROR: f64 = 8.0 * f32::EPSILON as f64;

#[test]
fn f64_oracle_bounds_the_f32_sphere_error_on_far_small_spheres() {
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let strategy = (
        (1.0f64..5.0, 1.0f64..5.0),
        (-1.0f64..1.0, -1.0f64..1.0, 0.2f64..1.0),
        (0.0f64..std::f64::consts::TAU, 0.0f64..0.9),
    );
    let mut worst = 0.0f64;
    for _ in 0..20_000 {
        let ((log_dist, log_ratio), (x, y, z), (phi, off)) =
            strategy.new_tree(&mut runner).unwrap().current();
        let (dist, r) = (10f64.powf(log_dist), 10f64.powf(log_dist - log_ratio));
        let centre = f32v(DVec3::new(x, y, z).normalize() * dist);
        let r = r as f32;
        // Aim at a point `off·r` from the centre, perpendicular to the line of sight.
        let los = DVec3::from(centre.to_f64());
        let side = los.normalize().any_orthonormal_pair();
        let target = los + (side.0 * phi.cos() + side.1 * phi.sin()) * off * f64::from(r);
        let ray = Ray::new(V3::all(0.0f32), f32v(target.normalize()));
        let (hit32, t32) = intersect_sphere(centre, r, &ray, f32::INFINITY);
        let ray64 = wide_ray(&ray);
        let (hit64, t64) = intersect_sphere(centre.to_f64(), f64::from(r), &ray64, f64::INFINITY);
        assert!(hit64, "the f64 oracle misses: {centre:?} {r} {ray:?}");
        assert!(hit32, "f32 loses the sphere: {centre:?} {r} {ray:?}");
        let rel = (f64::from(t32) - t64).abs() / t64;
        worst = worst.max(rel);
        assert!(rel < F32_T_REL_ERROR, "relative error {rel:e}: {centre:?} r={r} {ray:?}");
        // The packet kernels compute the same f32 value, so they carry the same error.
        let lanes = intersect_sphere(
            f32x16::splat_v3(centre),
            f32x16::splat_f32(r),
            &splat_ray(&ray),
            f32x16::splat_f32(f32::INFINITY),
        );
        assert_eq!(lanes.1.lane(7).to_bits(), t32.to_bits());
    }
    eprintln!("worst relative f32 error of t: {worst:e} ({:.2} ε)", worst / f64::from(f32::EPSILON));
}

fn splat_ray<F: Lanes>(ray: &Ray<f32>) -> Ray<F> {
    Ray::new(F::splat_v3(ray.origin), F::splat_v3(ray.dir))
}

#[test]
fn id_lanes_round_trip() {
    let ids = <f32x8 as Lanes>::Ids::from_fn(|i| 10 * i as u32);
    assert_eq!((0..8).map(|i| ids.lane(i)).collect::<Vec<_>>(), [0, 10, 20, 30, 40, 50, 60, 70]);
}
