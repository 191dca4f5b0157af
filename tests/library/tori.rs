//! The torus kind: its f32 kernel against the twin's independent f64 method (closed-form quartic, Newton
//! polish) on the same values, every packet width against the one-lane bits, the departure rule (re-hits
//! through the tube and across the hole) and the TOML reader's errors; whole renders at every width and
//! thread count, through the binary, are in `tests/tori.rs`.

use super::common::wide::wide_ray;
use bareray::geometry::Ray;
use bareray::kinds::torus::{intersect_torus, rehit_torus, twin, TorusDesc, TorusShape};
use bareray::kinds::Stray;
use bareray::math::{SplitMix64, V3};
use bareray::simd::Lanes;
use glam::DVec3;
use wide::{f32x16, f32x4, f32x8};

/// A ray grazes when a nudge of its line by this many f32 roundings of the torus's scale
/// (`|C − o| + R + r`) can change hit or miss (the twin's `grazing`): 2⁻¹⁶ is 256 roundings.
const GRAZE: f64 = 1.0 / 65536.0;

/// The bound enforced on `|t32 − t64|·|d|` for rays that do not graze, in f32 roundings (2⁻²⁴) of
/// `t64·|d| + |o − C| + R + r`. Measured over the 200 000 rays below (184 700 hits): median 0.31, 99.9th
/// percentile 4.1, largest 48 (a thin torus, minor/major 0.05, hit near the inner equator); 100 leaves
/// twice the largest.
const UNITS_BOUND: f64 = 100.0;

fn unit(rng: &mut SplitMix64) -> DVec3 {
    loop {
        let v = DVec3::new(rng.unit(), rng.unit(), rng.unit()) * 2.0 - DVec3::ONE;
        if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
            return v.normalize();
        }
    }
}

fn random_torus(rng: &mut SplitMix64) -> TorusDesc {
    let centre = (DVec3::new(rng.unit(), rng.unit(), rng.unit()) - 0.5) * 20.0;
    let major = 0.5 + 4.5 * rng.unit();
    let minor = major * (0.03 + 0.6 * rng.unit());
    TorusDesc { centre, axis: unit(rng), major, minor, material: 0 }
}

/// A ray aimed at a point near the torus (on its centre circle's neighbourhood, its hole, or its outside),
/// from 1 to 40 units away, or started inside the tube.
fn random_ray(rng: &mut SplitMix64, t: &TorusShape<f64>) -> Ray<f32> {
    let f = &t.frame;
    let c = DVec3::from(f.origin);
    let (e1, e2, u) = (DVec3::from(f.e1), DVec3::from(f.e2), DVec3::from(f.axis));
    let angle = std::f64::consts::TAU * rng.unit();
    let ring = c + (e1 * angle.cos() + e2 * angle.sin()) * t.major;
    let target = ring + unit(rng) * t.minor * 1.6 * rng.unit() + u * (rng.unit() - 0.5) * t.minor;
    let origin = if rng.unit() < 0.1 {
        ring + unit(rng) * t.minor * 0.9 * rng.unit()
    } else {
        target + unit(rng) * (1.0 + 39.0 * rng.unit())
    };
    let dir = (target - origin).normalize_or(unit(rng));
    Ray::new(V3::from(origin).to_f32(), V3::from(dir).to_f32())
}

#[test]
fn f32_kernel_agrees_with_the_twins_independent_method() {
    let mut rng = SplitMix64::new(0x7041_5eed);
    let eps = f64::from(f32::EPSILON) * 0.5;
    let (mut hits, mut misses, mut grazing, mut grazing_flips) = (0, 0, 0, 0);
    let mut flips = Vec::new();
    let mut units = Vec::new();
    let mut worst = (0.0, String::new());
    for i in 0..10_000 {
        let t32 = random_torus(&mut rng).shape(DVec3::ZERO).map(|v| v as f32);
        let t64 = t32.map(f64::from);
        for _ in 0..20 {
            let ray32 = random_ray(&mut rng, &t64);
            let ray64 = wide_ray(&ray32);
            let (h32, s32) = intersect_torus(&t32, &ray32, f32::INFINITY);
            let first = twin::roots(&t64, &ray64).into_iter().find(|&s| s >= 0.0);
            let (h64, s64) = (first.is_some(), first.unwrap_or(f64::INFINITY));
            let len = DVec3::from(ray64.dir).length();
            let scale = (t64.frame.origin - ray64.origin).length() + t64.major + t64.minor;
            let case = || format!("torus {i} {t64:?} ray {ray64:?} t32 {s32:e} ({h32}) t64 {s64:e} ({h64})");
            if twin::grazing(&t64, &ray64, GRAZE * scale, Stray::default()) {
                grazing += 1;
                grazing_flips += usize::from(h32 != h64);
                continue;
            }
            if h32 != h64 {
                flips.push(case());
                continue;
            }
            if !h64 {
                misses += 1;
                continue;
            }
            hits += 1;
            let u = (f64::from(s32) - s64).abs() * len / (eps * (s64 * len + scale));
            units.push(u);
            if u > worst.0 {
                worst = (u, case());
            }
        }
    }
    units.sort_by(f64::total_cmp);
    let at = |q: f64| units[((units.len() - 1) as f64 * q) as usize];
    eprintln!(
        "{hits} hits, {misses} misses, {grazing} grazing ({grazing_flips} of them flip), {} other flips\n\
         error in roundings of the scale: median {:.3}, 99.9% {:.2}, max {:.2}\n  {}",
        flips.len(),
        at(0.5),
        at(0.999),
        worst.0,
        worst.1
    );
    assert!(
        flips.is_empty(),
        "{} hit/miss disagreements on rays that do not graze: {:#?}",
        flips.len(),
        &flips[..flips.len().min(5)]
    );
    assert!(worst.0 <= UNITS_BOUND, "{} roundings > {UNITS_BOUND}: {}", worst.0, worst.1);
    assert!(hits > 50_000 && misses > 10_000, "{hits} hits, {misses} misses");
}

/// Lane `i` of every width is the one-lane call's bits, for the first hit and for the re-hit.
fn widths_match<F: Lanes>(rng: &mut SplitMix64) {
    for _ in 0..2_000 {
        let t = random_torus(rng).shape(DVec3::ZERO);
        let t32 = t.map(|v| v as f32);
        let rays: Vec<Ray<f32>> = (0..F::K).map(|_| random_ray(rng, &t)).collect();
        let lanes = |f: fn(&Ray<f32>) -> f32| F::from_lanes(&rays.iter().map(f).collect::<Vec<_>>());
        let packet = Ray::new(
            V3::new(lanes(|r| r.origin.x), lanes(|r| r.origin.y), lanes(|r| r.origin.z)),
            V3::new(lanes(|r| r.dir.x), lanes(|r| r.dir.y), lanes(|r| r.dir.z)),
        );
        let t_max = F::splat_f32(30.0);
        let tl = t32.map(F::splat_f32);
        for (name, packed, one) in [
            (
                "intersect",
                intersect_torus(&tl, &packet, t_max),
                intersect_torus as fn(&_, &_, f32) -> (bool, f32),
            ),
            ("rehit", rehit_torus(&tl, &packet, t_max), rehit_torus),
        ] {
            let bits = F::move_mask(packed.0);
            let ts = packed.1.to_array();
            for (i, ray) in rays.iter().enumerate() {
                let (h, s) = one(&t32, ray, 30.0);
                assert_eq!(
                    (bits >> i & 1 == 1, ts.as_ref()[i].to_bits()),
                    (h, s.to_bits()),
                    "{name} K={} lane {i}",
                    F::K
                );
            }
        }
    }
}

#[test]
fn every_width_gives_the_one_lane_bits() {
    let mut rng = SplitMix64::new(0x7041_1a9e);
    widths_match::<f32x4>(&mut rng);
    widths_match::<f32x8>(&mut rng);
    widths_match::<f32x16>(&mut rng);
}

fn ring() -> TorusShape<f32> {
    TorusDesc { centre: DVec3::ZERO, axis: DVec3::Z, major: 2.0, minor: 0.5, material: 0 }
        .shape(DVec3::ZERO)
        .map(|v| v as f32)
}

fn ray(o: [f32; 3], d: [f32; 3]) -> Ray<f32> {
    Ray::new(V3::new(o[0], o[1], o[2]), V3::new(d[0], d[1], d[2]))
}

#[test]
fn known_hits_misses_and_rehits() {
    let t = ring();
    let close = |got: (bool, f32), want: f32| got.0 && (got.1 - want).abs() <= 1e-5 * want.max(1.0);
    // Through the hole along the axis: a miss.
    assert!(!intersect_torus(&t, &ray([0.0, 0.0, -5.0], [0.0, 0.0, 1.0]), f32::INFINITY).0);
    // In the plane from outside: the outer wall at x = 2.5.
    let from_outside = intersect_torus(&t, &ray([-6.0, 0.0, 0.0], [1.0, 0.0, 0.0]), f32::INFINITY);
    assert!(close(from_outside, 3.5), "{from_outside:?}");
    // t_max is exclusive.
    assert!(!intersect_torus(&t, &ray([-6.0, 0.0, 0.0], [1.0, 0.0, 0.0]), 3.5).0);
    // Leaving the outer wall into the tube: its far wall at x = −1.5.
    let through_tube = rehit_torus(&t, &ray([-2.5, 0.0, 0.0], [1.0, 0.0, 0.0]), f32::INFINITY);
    assert!(close(through_tube, 1.0), "{through_tube:?}");
    // Leaving the inner wall into the hole: across it at x = 1.5.
    let across_hole = rehit_torus(&t, &ray([-1.5, 0.0, 0.0], [1.0, 0.0, 0.0]), f32::INFINITY);
    assert!(close(across_hole, 3.0), "{across_hole:?}");
    // Leaving the outer wall outward: never again.
    assert!(!rehit_torus(&t, &ray([-2.5, 0.0, 0.0], [-1.0, 0.0, 0.0]), f32::INFINITY).0);
    // Over the top of the tube, tangent at z = 0.5: the twin calls it grazing.
    let over = ray([-6.0, 0.0, 0.5], [1.0, 0.0, 0.0]);
    assert!(twin::grazing(&t.map(f64::from), &wide_ray(&over), 1e-9, Stray::default()));
    // NaN and zero directions miss.
    assert!(!intersect_torus(&t, &ray([f32::NAN, 0.0, 0.0], [1.0, 0.0, 0.0]), f32::INFINITY).0);
    assert!(!intersect_torus(&t, &ray([-6.0, 0.0, 0.0], [0.0, 0.0, 0.0]), f32::INFINITY).0);
    // The normal points away from the centre circle.
    let n = t.normal(V3::new(2.5, 0.0, 0.0));
    assert!((n.x - 1.0).abs() < 1e-6 && n.y.abs() < 1e-6 && n.z.abs() < 1e-6, "{n:?}");
}
