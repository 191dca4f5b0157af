//! The lecture's camera against hand-computed image-plane points, for both parameterisations and both sweeps.
//!
//! Set-up for every case: eye O = (1, 2, 3) looking down −z (Z_v = (0, 0, −1)) with up (0, 1, 0), image plane at
//! d = 2, 4 × 2 pixels. bareray's X_v = Z_v × Y_v = (1, 0, 0), so column 0 is at −x: the viewer's left.

use bareray::camera::{Camera, CameraError};
use bareray::math::V3;
use bareray::scene::desc::{Aim, CameraDesc, Field, Sweep};
use glam::DVec3;

fn desc(field: Field, sweep: Sweep) -> CameraDesc {
    CameraDesc {
        eye: DVec3::new(1.0, 2.0, 3.0),
        aim: Aim::Direction(DVec3::new(0.0, 0.0, -7.0)),
        up: DVec3::new(0.0, 1.0, 0.0),
        distance: 2.0,
        field,
        width: 4,
        height: 2,
        sweep,
    }
}

/// The image-plane point of pixel (j, k) (its centre at (j + ½, k + ½) in pixel space).
fn p(cam: &Camera<f64>, j: u32, k: u32) -> V3<f64> {
    cam.image_plane_point(f64::from(j) + 0.5, f64::from(k) + 0.5)
}

fn assert_close(a: V3<f64>, b: [f64; 3]) {
    let err = ((a.x - b[0]).abs()).max((a.y - b[1]).abs()).max((a.z - b[2]).abs());
    assert!(err < 1e-12, "{a:?} != {b:?}");
}

// θ = 90°: s_j = 2·d·tan(45°) = 4, s_k = s_j·v_res/h_res = 2. The window's top-left corner is
// O + d·Z_v − (s_j/2)·X_v + (s_k/2)·Y_v = (1, 2, 3) + (0, 0, −2) − (2, 0, 0) + (0, 1, 0) = (−1, 3, 1).

#[test]
fn angle_with_window_edges_puts_p00_on_the_corner() {
    let cam = Camera::new(&desc(Field::HorizontalAngle(90.0), Sweep::WindowEdges)).unwrap();
    assert_close(p(&cam, 0, 0), [-1.0, 3.0, 1.0]);
    // Steps s_j/(h_res − 1) = 4/3 across and s_k/(v_res − 1) = 2 down.
    assert_close(p(&cam, 1, 0), [-1.0 + 4.0 / 3.0, 3.0, 1.0]);
    assert_close(p(&cam, 3, 0), [3.0, 3.0, 1.0]);
    assert_close(p(&cam, 0, 1), [-1.0, 1.0, 1.0]);
    assert_close(p(&cam, 3, 1), [3.0, 1.0, 1.0]);
}

#[test]
fn angle_with_pixel_centres_insets_p00_by_half_a_pixel() {
    let cam = Camera::new(&desc(Field::HorizontalAngle(90.0), Sweep::PixelCentre)).unwrap();
    // Pixels are s_j/h_res = 1 wide and s_k/v_res = 1 high: centres half a pixel in from the corner.
    assert_close(p(&cam, 0, 0), [-0.5, 2.5, 1.0]);
    assert_close(p(&cam, 3, 0), [2.5, 2.5, 1.0]);
    assert_close(p(&cam, 0, 1), [-0.5, 1.5, 1.0]);
    assert_close(p(&cam, 3, 1), [2.5, 1.5, 1.0]);
}

#[test]
fn corner_rays_are_unit_and_point_through_the_pixels() {
    let cam = Camera::new(&desc(Field::HorizontalAngle(90.0), Sweep::PixelCentre)).unwrap();
    let r = cam.ray(0.5, 0.5);
    assert_eq!(r.origin, V3::new(1.0, 2.0, 3.0));
    // P_0,0 − O = (−1.5, 0.5, −2), length sqrt(6.5).
    let n = 6.5f64.sqrt();
    assert_close(r.dir, [-1.5 / n, 0.5 / n, -2.0 / n]);
    let r = cam.ray(3.5, 1.5);
    assert_close(r.dir, [1.5 / n, -0.5 / n, -2.0 / n]);
    // The f32 camera agrees with the f64 one to f32 precision.
    let r32 = cam.to_f32().ray(3.5f32, 1.5f32);
    assert!((r32.dir.to_f64() - r.dir).length() < 1e-6);
}

#[test]
fn pixel_size_sets_the_spacing_of_pixel_centres() {
    // s = 0.5 at d = 2: neighbouring centres are 0.5 apart in both sweeps, and P_0,0 is the same:
    // O + d·Z_v − (s·h_res/2 − s/2)·X_v + (s·v_res/2 − s/2)·Y_v = (0.25, 2.25, 1).
    for sweep in [Sweep::PixelCentre, Sweep::WindowEdges] {
        let cam = Camera::new(&desc(Field::PixelSize(0.5), sweep)).unwrap();
        assert_close(p(&cam, 0, 0), [0.25, 2.25, 1.0]);
        assert_close(p(&cam, 1, 0), [0.75, 2.25, 1.0]);
        assert_close(p(&cam, 3, 1), [1.75, 1.75, 1.0]);
    }
}

#[test]
fn field_of_view_grows_with_pixel_size_and_resolution() {
    let half = |s: f64, w: u32| {
        let mut d = desc(Field::PixelSize(s), Sweep::PixelCentre);
        d.width = w;
        Camera::new(&d).unwrap().half_w
    };
    assert_eq!(half(0.5, 4), 0.5);
    assert_eq!(half(1.0, 4), 1.0);
    assert_eq!(half(0.5, 8), 1.0);
}

#[test]
fn up_need_not_be_unit_or_perpendicular() {
    let mut d = desc(Field::HorizontalAngle(90.0), Sweep::WindowEdges);
    d.up = DVec3::new(0.0, 5.0, -3.0);
    let cam = Camera::new(&d).unwrap();
    assert_close(cam.up, [0.0, 1.0, 0.0]);
    assert_close(p(&cam, 0, 0), [-1.0, 3.0, 1.0]);
}

#[test]
fn look_at_matches_direction() {
    let mut d = desc(Field::HorizontalAngle(90.0), Sweep::PixelCentre);
    d.aim = Aim::LookAt(DVec3::new(1.0, 2.0, -10.0));
    assert_close(p(&Camera::new(&d).unwrap(), 0, 0), [-0.5, 2.5, 1.0]);
}

#[test]
fn unusable_cameras_are_errors() {
    let mut d = desc(Field::HorizontalAngle(90.0), Sweep::PixelCentre);
    d.up = DVec3::new(0.0, 0.0, 2.0);
    assert_eq!(Camera::new(&d), Err(CameraError::UpParallel));
    d = desc(Field::HorizontalAngle(180.0), Sweep::PixelCentre);
    assert!(matches!(Camera::new(&d), Err(CameraError::Field(_))));
    d = desc(Field::PixelSize(0.0), Sweep::PixelCentre);
    assert!(matches!(Camera::new(&d), Err(CameraError::Field(_))));
    d = desc(Field::HorizontalAngle(60.0), Sweep::PixelCentre);
    d.aim = Aim::LookAt(d.eye);
    assert_eq!(Camera::new(&d), Err(CameraError::NoDirection));
    d.aim = Aim::Direction(DVec3::Z);
    d.width = 0;
    assert_eq!(Camera::new(&d), Err(CameraError::Resolution(0, 2)));
}

#[test]
fn single_column_window_edges_sweep_looks_straight_ahead() {
    let mut d = desc(Field::HorizontalAngle(90.0), Sweep::WindowEdges);
    d.width = 1;
    d.height = 1;
    let cam = Camera::new(&d).unwrap();
    assert_close(cam.ray(0.5, 0.5).dir, [0.0, 0.0, -1.0]);
}

/// The benchmark contract's camera (bench-peers/README.md, "Embree harness"), its ray for pixel (i, j)
/// computed by the contract's own formula in f64.
fn contract_dir(i: u32, j: u32, w: u32, h: u32) -> DVec3 {
    let f = DVec3::new(0.0, 0.0, 4.0).normalize();
    let r = f.cross(DVec3::Y).normalize();
    let u = r.cross(f);
    let th = (45f64.to_radians() / 2.0).tan();
    let px = (2.0 * (f64::from(i) + 0.5) / f64::from(w) - 1.0) * th;
    let py = (1.0 - 2.0 * (f64::from(j) + 0.5) / f64::from(h)) * th * f64::from(h) / f64::from(w);
    (f + px * r + py * u).normalize()
}

#[test]
fn camera_rays_are_the_contract_rays_rounded_once_at_every_width() {
    use bareray::simd::Lanes;
    use wide::{f32x16, f32x4, f32x8};
    let (w, h) = (1920, 1080);
    let desc = CameraDesc {
        eye: DVec3::new(0.0, 0.0, -4.0),
        aim: Aim::LookAt(DVec3::ZERO),
        up: DVec3::Y,
        distance: 1.0,
        field: Field::HorizontalAngle(45.0),
        width: w,
        height: h,
        sweep: Sweep::PixelCentre,
    };
    let cam = Camera::new(&desc).unwrap();
    let (mut rounded_alike, mut total) = (0, 0);
    for j in (0..h).step_by(7) {
        for i in (0..w).step_by(5) {
            let ray = cam.ray_f32(i as f32 + 0.5, j as f32 + 0.5);
            assert_eq!(ray.origin, V3::new(0.0, 0.0, -4.0));
            let d = contract_dir(i, j, w, h);
            let want = [d.x as f32, d.y as f32, d.z as f32];
            let got = [ray.dir.x, ray.dir.y, ray.dir.z];
            // Each component is the f64 contract direction rounded to f32, or (when that f64 value lies
            // within an f64 ulp or two of a rounding boundary) its neighbour.
            for (g, w) in got.iter().zip(want) {
                assert!(
                    (g.to_bits() as i64 - w.to_bits() as i64).abs() <= 1,
                    "pixel ({i}, {j}): {got:?} vs {want:?}"
                );
            }
            rounded_alike += usize::from(got == want);
            total += 1;
        }
    }
    assert!(
        rounded_alike * 10_000 >= total * 9_999,
        "{rounded_alike} of {total} rays rounded as the contract's"
    );

    // Every width generates the same rays as the scalar call.
    fn lanes_match<F: Lanes>(cam: &Camera<f64>) {
        let sx = F::from_fn(|i| 100.5 + i as f32);
        let sy = F::from_fn(|i| 7.5 + (i / 4) as f32);
        let rays = cam.rays(sx, sy);
        for i in 0..F::K {
            let one = cam.ray_f32(sx.lane(i), sy.lane(i));
            assert_eq!(
                [rays.dir.x.lane(i), rays.dir.y.lane(i), rays.dir.z.lane(i)],
                [one.dir.x, one.dir.y, one.dir.z]
            );
        }
    }
    lanes_match::<f32x4>(&cam);
    lanes_match::<f32x8>(&cam);
    lanes_match::<f32x16>(&cam);
}

/// `n · d` in f64: exact products of f32 values, so its sign is the exact one unless d lies within about
/// 1e-16 of the plane.
fn side(n: &[f32; 3], d: &V3<f32>) -> f64 {
    f64::from(n[0]) * f64::from(d.x) + f64::from(n[1]) * f64::from(d.y) + f64::from(n[2]) * f64::from(d.z)
}

#[test]
fn block_pyramids_enclose_their_rays_and_exclude_the_next_pixels() {
    use proptest::prelude::*;
    use proptest::test_runner::{Config, TestRunner};
    let angle = prop_oneof![0.001f64..1.0, 1.0f64..170.0, 170.0f64..179.9];
    let vector = || [-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0];
    let cameras = (vector(), vector(), vector(), -1e4f64..1e4, angle, 1u32..5000, 1u32..5000, 0.0f32..1.0);
    let mut runner = TestRunner::new(Config { cases: 1000, ..Config::default() });
    runner
        .run(&cameras, |(eye, aim, up, scale, theta, width, height, offset)| {
            let v = |a: [f64; 3]| DVec3::from_array(a);
            let desc = CameraDesc {
                eye: v(eye) * scale,
                aim: Aim::Direction(v(aim)),
                up: v(up),
                distance: 1.0,
                field: Field::HorizontalAngle(theta),
                width,
                height,
                sweep: Sweep::PixelCentre,
            };
            let Ok(cam) = Camera::new(&desc) else { return Ok(()) };
            // 4 × 4 blocks at the corners and the middle of the image, sampled at `offset` in the pixel.
            let (w, h) = (width as f32, height as f32);
            for (x0, y0) in [(0.0, 0.0), (w - 4.0, h - 4.0), ((w / 2.0).floor(), (h / 2.0).floor())] {
                // Sample positions as the renderer forms them: (block corner + lane) + offset, in f32.
                let at = |i: f32, j: f32| ((x0 + i) + offset, (y0 + j) + offset);
                let (sx, sy) = ([at(0.0, 0.0).0, at(3.0, 0.0).0], [at(0.0, 0.0).1, at(0.0, 3.0).1]);
                let Some(p) = cam.pyramid(sx, sy) else {
                    // Only where the window is too wide: 1 + |U| + |V| beyond 1000 (Camera::pyramid).
                    let u = |s: f32| ((f64::from(s) * cam.u_scale + cam.u_offset) * cam.half_w).abs();
                    let v = |s: f32| ((f64::from(s) * cam.v_scale + cam.v_offset) * cam.half_h).abs();
                    let (u, v) = (u(sx[0]).max(u(sx[1])), v(sy[0]).max(v(sy[1])));
                    prop_assert!(1.0 + u + v > 1e3, "no pyramid for a block at |U| {u}, |V| {v}");
                    continue;
                };
                for (i, j) in (0..4).flat_map(|j| (0..4).map(move |i| (i as f32, j as f32))) {
                    let (x, y) = at(i, j);
                    let ray = cam.ray_f32(x, y);
                    prop_assert_eq!([ray.origin.x, ray.origin.y, ray.origin.z], p.apex);
                    for n in &p.normals {
                        prop_assert!(side(n, &ray.dir) >= 0.0, "ray ({i}, {j}) outside {n:?}");
                    }
                    prop_assert!(side(&p.axis, &ray.dir) > 0.0, "ray ({i}, {j}) behind {:?}", p.axis);
                }
                // Tight: the next pixel beyond each side is outside it, wherever a pixel is at least four
                // times wider than the widening (Camera::pyramid's bound, over windows a little past the
                // image for blocks at its edge).
                let (wf, hf) = (f64::from(width), f64::from(height));
                let (u_max, v_max) = (cam.half_w * (1.0 + 8.0 / wf), cam.half_h * (1.0 + 8.0 / hf));
                let widening =
                    8.0 * f64::from(f32::EPSILON) * (1.0 + u_max.max(v_max)) * (1.0 + u_max + v_max);
                if 4.0 * widening < (2.0 * cam.half_w / wf).min(2.0 * cam.half_h / hf) {
                    // Window v falls as the row rises: the third side bounds the bottom row, the fourth the top.
                    let beyond = [(-1.0, 0.0), (4.0, 0.0), (0.0, 4.0), (0.0, -1.0)];
                    for (n, (i, j)) in p.normals.iter().zip(beyond) {
                        let (x, y) = at(i, j);
                        let ray = cam.ray_f32(x, y);
                        prop_assert!(side(n, &ray.dir) < 0.0, "pixel ({i}, {j}) beyond {n:?} is inside");
                    }
                }
            }
            Ok(())
        })
        .unwrap();
}
