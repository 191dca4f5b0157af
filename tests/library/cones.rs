//! The cone kernel in f32 against its own f64 instance on the same values (the f32 cone and ray widened
//! exactly), so the difference is the f32 arithmetic alone: many seeded random cones and rays, aimed at
//! the surface, started inside, and sent through the open ends.

use super::common;

use bareray::geometry::Ray;
use bareray::kinds::cone::{intersect_cone, Cone, Cones};
use bareray::math::SplitMix64;
use bareray::math::V3;
use common::wide::wide_ray;
use glam::DVec3;

/// A ray grazes a cone when some nudge of the ray changes the f64 kernel's answer from hit to miss or back,
/// or moves its hit point by more than [`GRAZE_AMP`] times the nudge: its origin moved by
/// `GRAZE·(|origin − base| + h + max radius)` along one of the cone's frame vectors, or its direction turned
/// by `GRAZE` (relative) along one. That is a ray within about a degree of tangent, a hit within the nudge
/// of a rim (the answer jumps to the other root or to a miss), or a ray within that angle of parallel to a
/// generator line. 2⁻¹⁶ is 256 f32 roundings.
const GRAZE: f64 = 1.0 / 65536.0;

/// How much farther than a nudge a non-grazing ray's hit point may move.
const GRAZE_AMP: f64 = 64.0;

/// The bound enforced on `|t32 − t64|·|d|` for rays that do not graze, in f32 roundings (2⁻²⁴) of the
/// scale `t64·|d| + |origin − base|`: the distance to the hit plus the origin's distance from the cone's
/// base point, whose rounding the ray's coordinates in the cone's frame carry. Measured over the 400 000
/// rays below: median 0.45, 99.9th percentile 27, largest 74. The error follows the ray's conditioning
/// (it is the error of an exactly solved, slightly nudged ray): with [`GRAZE_AMP`] at 16 the largest is 33,
/// at 256 it is 290, about 1.2 roundings per unit of amplification. 150 leaves twice the measured largest.
const UNITS_BOUND: f64 = 150.0;

/// The bound enforced on the relative error `|t32 − t64| / t64` for rays that do not graze and whose hit
/// is at least as far from their origin as the cone's base point is (then the scale above is at most twice
/// the distance to the hit). Measured: largest 8.4e-6 (140 roundings, a ray close to both tangent and
/// parallel to a generator line, just inside the graze tolerance); 2e-5 leaves 2.4× margin.
const REL_BOUND: f64 = 2e-5;

fn random_cone(rng: &mut SplitMix64) -> (DVec3, f64, DVec3, f64) {
    let mut u = || rng.unit() - 0.5;
    let far = if u() > 0.4 { 1e3 } else { 1.0 };
    let base = DVec3::new(u(), u(), u()) * 20.0 * far;
    let apex = base + DVec3::new(u(), u(), u()) * 2.0 * 10f64.powf(4.0 * u());
    let r0 = 0.3 * 10f64.powf(4.0 * u());
    let r1 = 0.3 * 10f64.powf(4.0 * u());
    match (u() * 5.0).floor() as i32 {
        -3 => (base, r0, apex, 0.0),
        -2 => (base, 0.0, apex, r1),
        -1 => (base, r0, apex, r0),
        _ => (base, r0, apex, r1),
    }
}

/// A ray for cone `c` (f64 values): aimed at a point on or near the surface from near or far, started
/// inside, or sent through an open end.
fn random_ray(rng: &mut SplitMix64, c: &Cone<f64>) -> Ray<f64> {
    let mut u = || rng.unit() - 0.5;
    let f = &c.frame;
    let (b, e1, e2, ax) = (DVec3::from(f.origin), DVec3::from(f.e1), DVec3::from(f.e2), DVec3::from(f.axis));
    let (h, r0, k) = (c.height, c.base_radius, c.slope);
    let local = |x: f64, y: f64, z: f64| b + e1 * x + e2 * y + ax * z;
    let angle = (u() + 0.5) * std::f64::consts::TAU;
    let z = (u() + 0.5) * h;
    let r = r0 + k * z;
    let scale = h + r0.max(r0 + k * h);
    let dir = DVec3::new(u(), u(), u());
    let (o, d) = match (u() * 3.0 + 1.5) as i32 {
        0 => {
            // Aimed at a surface point displaced by up to 10% of the radius, from 0.1 to 1e3 sizes away.
            let target = local(angle.cos() * r * (1.0 + 0.2 * u()), angle.sin() * r * (1.0 + 0.2 * u()), z);
            let o = target - dir * (scale * 10f64.powf(4.0 * u() - 1.0) / dir.length());
            (o, target - o)
        }
        1 => {
            let f = 0.9 * (u() + 0.5);
            (local(angle.cos() * r * f, angle.sin() * r * f, z), dir)
        }
        _ => {
            // From beyond an end towards a point inside.
            let end = if u() > 0.0 { h + scale * (u() + 0.6) } else { -scale * (u() + 0.6) };
            let target = local(angle.cos() * r * 0.8 * (u() + 0.5), angle.sin() * r * 0.8 * (u() + 0.5), z);
            let o = local(u() * r, u() * r, end);
            (o, target - o)
        }
    };
    Ray::new(V3::from(o), V3::from(d))
}

/// Whether some nudge of the ray (see [`GRAZE`]) changes the f64 answer.
fn grazes(c: &Cone<f64>, ray: &Ray<f64>, answer: (bool, f64)) -> bool {
    let (o, d) = (DVec3::from(ray.origin), DVec3::from(ray.dir));
    let top = c.base_radius + c.slope * c.height;
    let reach = (o - DVec3::from(c.frame.origin)).length() + c.height + c.base_radius.max(top);
    let dist = if answer.0 { answer.1 * d.length() } else { 0.0 };
    let nudge = GRAZE * (reach + dist);
    let frame = [c.frame.e1, c.frame.e2, c.frame.axis].map(DVec3::from);
    let mut nudged = Vec::new();
    for v in frame {
        for s in [-1.0, 1.0] {
            nudged.push((o + v * (s * GRAZE * reach), d));
            nudged.push((o, d + v * (s * GRAZE * d.length())));
        }
    }
    nudged.iter().any(|&(o2, d2)| {
        let (hit, t) = intersect_cone(c, &Ray::new(V3::from(o2), V3::from(d2)), f64::INFINITY);
        hit != answer.0 || (hit && ((o2 + d2 * t) - (o + d * answer.1)).length() > GRAZE_AMP * nudge)
    })
}

/// What the comparison found.
#[derive(Default)]
struct Tally {
    hits: usize,
    misses: usize,
    grazing: usize,
    grazing_flips: usize,
    flips: Vec<String>,
    /// Largest `|t32 − t64|·|d| / (ε·(t64·|d| + |origin − base|))` and its case.
    worst_units: (f64, String),
    /// Largest `|t32 − t64| / t64` where `t64·|d| ≥ |origin − base|`, and its case.
    worst_rel: (f64, String),
    units: Vec<f64>,
}

#[test]
fn f32_kernel_agrees_with_f64_within_the_measured_bound() {
    let mut rng = SplitMix64::new(0x000c_04e5_5eed);
    let mut store = Cones::default();
    let mut tally = Tally::default();
    let eps = f64::from(f32::EPSILON) * 0.5;
    for i in 0..20_000 {
        let (base, r0, apex, r1) = random_cone(&mut rng);
        store.push(base, r0, apex, r1, 0).expect("valid cone");
        let c32 = store.cone(i);
        let c64 = c32.map(f64::from);
        for _ in 0..20 {
            let ray32 = {
                let r = random_ray(&mut rng, &c64);
                Ray::new(r.origin.to_f32(), r.dir.to_f32())
            };
            let ray64 = wide_ray(&ray32);
            let (h32, t32) = intersect_cone(&c32, &ray32, f32::INFINITY);
            let (h64, t64) = intersect_cone(&c64, &ray64, f64::INFINITY);
            let case = || format!("cone {i} {c64:?} ray {ray64:?} t32 {t32:e} ({h32}) t64 {t64:e} ({h64})");
            if grazes(&c64, &ray64, (h64, t64)) {
                tally.grazing += 1;
                tally.grazing_flips += usize::from(h32 != h64);
                continue;
            }
            if h32 != h64 {
                tally.flips.push(case());
                continue;
            }
            if !h64 {
                tally.misses += 1;
                continue;
            }
            tally.hits += 1;
            let dist = t64 * DVec3::from(ray64.dir).length();
            let from_base = (DVec3::from(ray64.origin) - DVec3::from(c64.frame.origin)).length();
            let err = (f64::from(t32) - t64).abs();
            let units = err * DVec3::from(ray64.dir).length() / (eps * (dist + from_base));
            tally.units.push(units);
            if units > tally.worst_units.0 {
                tally.worst_units = (units, case());
            }
            if dist >= from_base && err / t64 > tally.worst_rel.0 {
                tally.worst_rel = (err / t64, case());
            }
        }
    }
    let Tally { hits, misses, grazing, grazing_flips, flips, worst_units, worst_rel, mut units } = tally;
    units.sort_by(f64::total_cmp);
    let at = |q: f64| units[((units.len() - 1) as f64 * q) as usize];
    eprintln!(
        "{hits} hits, {misses} misses, {grazing} grazing ({grazing_flips} of them flip), {} other flips\n\
         error in roundings of the scale: median {:.3}, 99.9% {:.2}, max {:.2}\n  {}\n\
         relative t error where the hit is farther than the base: max {:e}\n  {}",
        flips.len(),
        at(0.5),
        at(0.999),
        worst_units.0,
        worst_units.1,
        worst_rel.0,
        worst_rel.1
    );
    assert!(flips.is_empty(), "hit/miss disagreements on rays that do not graze: {flips:#?}");
    assert!(worst_units.0 <= UNITS_BOUND, "{} roundings > {UNITS_BOUND}: {}", worst_units.0, worst_units.1);
    assert!(worst_rel.0 <= REL_BOUND, "relative t error {:e} > {REL_BOUND:e}: {}", worst_rel.0, worst_rel.1);
    assert!(hits > 150_000 && misses > 50_000, "{hits} hits, {misses} misses");
}
