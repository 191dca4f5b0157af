//! Stress: the textbook ray/sphere discriminant `b² − 4ac` against the perpendicular form the kernels use,
//! both in f32, on a unit sphere moved away from the ray origin in steps of √2: the distance at which each
//! first gets the near root wrong and first loses a hit. The textbook form cancels catastrophically once the
//! sphere is a few thousand radii away; the perpendicular form lasts until its own rounding of the line's
//! distance from the centre reaches the radius (≈ 1/(2ε) radii). The textbook form is the foil and is never
//! used by the renderer (ARCHITECTURE.md "Numerics").
//!
//! `--nocapture` prints the distances; `STRESS_MEASURE=1` prints them without asserting the bounds.

use super::common;

use bareray::geometry::{first_root, sphere_roots, Ray};
use bareray::math::{Vec3f, V3};
use common::rng::Rng;
use common::wide::{dv, f32v, wide, wide_ray};
use common::{measuring, EPS32};
use glam::DVec3;

/// The textbook ray/sphere test in f32 (the foil; never used by the renderer): `a = d·d`, `b = 2 d·(o − c)`,
/// `cc = (o − c)·(o − c) − r²`, `Δ = b² − 4·a·cc`, near root `(−b − √Δ)/(2a)`.
fn textbook_near(c: Vec3f, r: f32, ray: &Ray<f32>) -> Option<f32> {
    let oc = ray.origin - c;
    let a = ray.dir.dot(ray.dir);
    let b = 2.0 * ray.dir.dot(oc);
    let cc = oc.dot(oc) - r * r;
    let disc = b * b - 4.0 * a * cc;
    (disc >= 0.0).then(|| (-b - disc.sqrt()) / (2.0 * a))
}

/// A unit sphere at distance D (2 .. 2^28) in a fixed oblique direction, and 64 f32 rays from the origin
/// aimed at points up to 0.7 of the radius from its centre (so the exact line always crosses it well inside
/// the silhouette). A method breaks at D when some ray misses or its near root is off the f64 root by more
/// than r/10 + 16 ε·t (a tenth of the radius, or 16 roundings where t itself is coarser). Rays whose widened
/// line does not cross the sphere well inside (beyond ~1/ε radii the f32 direction cannot aim that finely)
/// are skipped. Proves the perpendicular form survives about three orders of magnitude farther than
/// b² − 4ac. Measured: the textbook form is off by > r/10 from D = 2^10.5 ≈ 1.4e3 r and loses its first hit
/// at 2^12.5 ≈ 5.8e3 r; the perpendicular form does both only at 2^23 ≈ 8.4e6 r (≈ 1/(2ε): the
/// perpendicular distance's own rounding reaches r). Bounds: the textbook breaks within
/// [2^9.5, 2^13] and loses a hit within [2^11, 2^14]; the perpendicular form does neither before 2^21 nor
/// within 2^8 times the textbook's distances.
#[test]
fn textbook_discriminant_breaks_long_before_the_perpendicular_form() {
    let axis = DVec3::new(0.36, -0.48, 0.8).normalize();
    let side = axis.cross(DVec3::Y).normalize();
    let up = side.cross(axis);
    let mut rng = Rng::new(16);
    let offsets: Vec<(f64, f64)> = (0..64)
        .map(|_| loop {
            let (x, y) = (rng.range(-0.7, 0.7), rng.range(-0.7, 0.7));
            if x * x + y * y <= 0.49 {
                break (x, y);
            }
        })
        .collect();
    let (mut textbook_breaks, mut stable_breaks) = (None, None);
    let (mut textbook_loses, mut stable_loses) = (None, None);
    for step in 2..=56 {
        let dist = 2f64.powf(f64::from(step) / 2.0);
        let c = f32v(axis * dist);
        let c64 = wide(c);
        let (mut tb_ok, mut st_ok, mut valid) = (true, true, 0);
        let (mut tb_hits, mut st_hits) = (true, true);
        for &(x, y) in &offsets {
            let aim = dv(c64) + side * x + up * y;
            let ray = Ray::new(V3::all(0.0f32), f32v(aim.normalize()));
            let r64 = wide_ray(&ray);
            // Far away the f32 direction itself cannot aim within the radius: keep only rays whose exact
            // line (the f32 ray widened) crosses the sphere well inside its silhouette.
            let roots = sphere_roots(c64, 1.0, &r64);
            let l =
                (dv(c64) - dv(r64.dir) * (dv(c64).dot(dv(r64.dir)) / dv(r64.dir).length_squared())).length();
            if !(roots.hit && l <= 0.8) {
                continue;
            }
            valid += 1;
            let t64 = roots.near;
            // Good: a hit within a tenth of the radius, or within 16 roundings of t where t itself cannot
            // be represented that closely.
            let good =
                |t: Option<f32>| t.is_some_and(|t| (f64::from(t) - t64).abs() <= 0.1 + 16.0 * EPS32 * t64);
            let tb = textbook_near(c, 1.0, &ray);
            let (h, t) = first_root(&sphere_roots(c, 1.0f32, &ray), f32::INFINITY);
            let st = h.then_some(t);
            tb_ok &= good(tb);
            st_ok &= good(st);
            tb_hits &= tb.is_some();
            st_hits &= st.is_some();
        }
        if valid < 8 {
            eprintln!(
                "textbook: only {valid} f32 rays can aim at the sphere at D = 2^{}",
                f64::from(step) / 2.0
            );
            break;
        }
        if !tb_hits && textbook_loses.is_none() {
            textbook_loses = Some(step);
        }
        if !st_hits && stable_loses.is_none() {
            stable_loses = Some(step);
        }
        if !tb_ok && textbook_breaks.is_none() {
            textbook_breaks = Some(step);
        }
        if !st_ok && stable_breaks.is_none() {
            stable_breaks = Some(step);
        }
    }
    let show = |s: Option<u32>| {
        s.map_or("never (≤ 2^28)".to_string(), |s| {
            format!("2^{} = {:.3e}", f64::from(s) / 2.0, 2f64.powf(f64::from(s) / 2.0))
        })
    };
    eprintln!(
        "textbook breaks at D = {}, perpendicular at D = {}",
        show(textbook_breaks),
        show(stable_breaks)
    );
    eprintln!(
        "first lost hit: textbook at D = {}, perpendicular at D = {}",
        show(textbook_loses),
        show(stable_loses)
    );
    if measuring() {
        return;
    }
    let tb = textbook_breaks.expect("the textbook form breaks");
    let tl = textbook_loses.expect("the textbook form loses hits");
    assert!((19..=26).contains(&tb), "textbook breaks at 2^{}", f64::from(tb) / 2.0);
    assert!((22..=28).contains(&tl), "textbook loses a hit at 2^{}", f64::from(tl) / 2.0);
    let st = stable_breaks.unwrap_or(57);
    let sl = stable_loses.unwrap_or(57);
    assert!(st >= 42 && st >= tb + 16, "perpendicular breaks at 2^{}", f64::from(st) / 2.0);
    assert!(sl >= 42 && sl >= tl + 16, "perpendicular loses a hit at 2^{}", f64::from(sl) / 2.0);
}
