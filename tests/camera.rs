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
