//! Tests of the sphere descriptions' bounds.

use super::*;

/// The box of a list with NaN centres and radii here and there is the box of its other spheres, on one
/// thread or three (glam's `min` would have kept or dropped a NaN depending on the order).
#[test]
fn sphere_bounds_ignore_nan_in_any_order() {
    let sphere = |i: usize| {
        let f = i as f64;
        let center = DVec3::new(f.sin() * 10.0, f * 0.01, -(f.cos() * 3.0));
        SphereDesc { center, radius: 0.5, material: 0 }
    };
    let finite: Vec<SphereDesc> = (0..70_000).map(sphere).collect();
    let mut with_nan = finite.clone();
    for i in [0, 1, 16_383, 16_384, 40_000, 69_999] {
        with_nan.insert(i, SphereDesc { center: DVec3::new(f64::NAN, 1.0, 2.0), ..sphere(i) });
        with_nan.insert(i + 1, SphereDesc { radius: f64::NAN, ..sphere(i) });
    }
    let on = |threads: usize, spheres: &[SphereDesc]| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| sphere_bounds(spheres))
    };
    let expected = on(1, &finite);
    assert!(expected.0.is_finite() && expected.1.is_finite());
    assert_eq!(on(1, &with_nan), expected);
    assert_eq!(on(3, &with_nan), expected);
    assert_eq!(on(3, &[]), (DVec3::INFINITY, DVec3::NEG_INFINITY));
}
