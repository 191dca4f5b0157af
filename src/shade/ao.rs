//! Ambient occlusion on packets ([`Shade::Ao`](crate::scene::desc::Shade::Ao)): at each camera ray's hit,
//! `samples` cosine-weighted directions over the hemisphere around the shading normal, each an occlusion
//! packet (any hit, early exit) of length `distance` leaving the surface as shadow rays do (from the hit
//! point, skipping the departure primitive); the colour is the surface's times the share that nothing blocks.
//! With K or more samples a packet holds K directions of one hit (one origin: coherent walks), unless the
//! camera packet's hits lie within a sphere's diameter of each other; then, and with fewer samples than K,
//! all the camera packet's rays are regrouped by the primitive they leave and by direction into full packets
//! (`ao_stream.rs`). Each ray is the same in both, and each ray's answer is exact, so the counts are the same
//! bits either way.
//!
//! The directions of a hit are a Fibonacci lattice over the unit square (`((k + ½)/n, k/φ)` mod 1, φ the
//! golden ratio: evenly spread in both coordinates, so in radius and in azimuth) shifted by a random
//! offset (Cranley–Patterson) seeded by the bits of the camera ray's direction. That direction is a function of the sample's position
//! in the image alone (computed in f64 and rounded once, at every width), so each pixel's samples get their
//! own directions whatever the tile, thread or packet width, and every ray of a pixel's antialiasing
//! samples gets its own set. The seed is scalar code per lane; the directions in the tangent frame are
//! computed four at a time in f64 lanes, sine and cosine by their series (cheaper than libm's `sin_cos` per
//! direction: PERF.md, Register); the frame around the normal is lane arithmetic in the scalar operation
//! order.

use crate::accel::{traced, RayKind};
use crate::geometry::{DeparturePacket, HitPacket, RayPacket};
use crate::math::{Mask, Real, SplitMix64, V3};
use crate::scene::desc::Ao;
use crate::simd::{set_bits, IdLanes, Lanes};
use wide::f64x4;

use super::{Surface, Tracer};

impl<F: Lanes> Tracer<'_, F> {
    /// The ambient occlusion of each active camera ray's hit times the surface's colour; the background
    /// where a ray hits nothing, zero in inactive lanes.
    pub(super) fn ambient_occlusion(&mut self, rays: &RayPacket<F>, hit: &HitPacket<F>, ao: Ao) -> V3<F> {
        let (found, background) = self.found_or_background(rays, hit);
        if !found.any() {
            return background;
        }
        let s = self.surface(rays, hit, found, true);
        let distance = F::splat_f32(ao.distance.map_or(f32::INFINITY, |d| d as f32));
        // One hit's directions share an origin, so its packets share the start of their walks; where the hits
        // lie close together, rays of one direction from all of them run side by side instead, and walk
        // further together (PERF.md, Register).
        let open = if ao.samples as usize >= F::K && !self.hits_are_close(hit, &s, found) {
            self.open_by_hit(rays, hit, &s, found, ao, distance)
        } else {
            self.open_by_direction(rays, hit, &s, found, ao, distance)
        };
        let share = open / F::splat_f32(ao.samples as f32);
        V3::select(found, s.base * share, background)
    }

    /// Whether the packet has lanes to regroup (K > 1), its found lanes all hit spheres, and their hit points
    /// lie within the smallest of those spheres' diameters of each other (a box of that diagonal).
    fn hits_are_close(&self, hit: &HitPacket<F>, s: &Surface<F>, found: F::Mask) -> bool {
        if F::K == 1 {
            return false;
        }
        let spheres = &self.scene.geometry.spheres;
        let mut r_min = f32::INFINITY;
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for i in set_bits(F::move_mask(found)) {
            let p = hit.prim.lane(i) as usize;
            if p >= spheres.len() {
                return false;
            }
            r_min = r_min.min(spheres.r[p]);
            let q = [s.point.x.lane(i), s.point.y.lane(i), s.point.z.lane(i)];
            for a in 0..3 {
                (lo[a], hi[a]) = (lo[a].min(q[a]), hi[a].max(q[a]));
            }
        }
        let d2: f32 = (0..3).map(|a| (hi[a] - lo[a]) * (hi[a] - lo[a])).sum();
        d2 < 4.0 * r_min * r_min
    }

    /// How many of each found lane's `ao.samples` occlusion rays nothing blocks, traced K directions of one
    /// hit at a time (one origin per packet): for sample counts of K and more.
    fn open_by_hit(
        &mut self,
        rays: &RayPacket<F>,
        hit: &HitPacket<F>,
        s: &Surface<F>,
        found: F::Mask,
        ao: Ao,
        distance: F,
    ) -> F {
        let mut open = [0u32; 16];
        let mut directions = std::mem::take(&mut self.ao_directions);
        for i in set_bits(F::move_mask(found)) {
            let shift = rotation(rays.ray.dir.x.lane(i), rays.ray.dir.y.lane(i), rays.ray.dir.z.lane(i));
            let lane = |v: &V3<F>| F::splat_v3(V3::new(v.x.lane(i), v.y.lane(i), v.z.lane(i)));
            let (point, normal) = (lane(&s.point), lane(&s.normal));
            let inward = F::mask_from_bits(if F::mask_lane(s.inside, i) { u32::MAX } else { 0 });
            let from = DeparturePacket { prim: F::Ids::splat(hit.prim.lane(i)), inward };
            tangent_set(shift, ao.samples, &mut directions);
            for set in directions.chunks(F::K) {
                // Lanes past the set's end repeat its last direction (inactive, never traced).
                let count = set.len();
                let at = |j: usize| set[j.min(count - 1)];
                let local =
                    V3::new(F::from_fn(|j| at(j).x), F::from_fn(|j| at(j).y), F::from_fn(|j| at(j).z));
                let live = F::lanes_below(count);
                let probe = RayPacket::new(point, around(normal, local), distance, live);
                self.counts.ao += count as u64;
                let (geometry, hint) = (&self.scene.geometry, &mut self.ao_hint);
                let blocked = traced(RayKind::Ao, || geometry.occluded_hinted_k(&probe, &from, hint));
                open[i] += F::move_mask(live & !blocked).count_ones();
            }
        }
        self.ao_directions = directions;
        F::from_fn(|i| open[i] as f32)
    }
}

/// The packet of local directions whose lane `i` is direction `k` of `n` in the set shifted by `shift`
/// ([`tangent_directions`], four at a time), for each `(i, shift, k)` given; the other lanes hold 0.
pub(super) fn local_directions<F: Lanes>(
    lanes: impl Iterator<Item = (usize, (f64, f64), u32)>,
    n: u32,
) -> V3<F> {
    let mut items = [(0, (0.0, 0.0), 0); 16];
    let mut count = 0;
    for item in lanes {
        items[count] = item;
        count += 1;
    }
    let mut local = [F::splat_f32(0.0).to_array(); 3];
    for batch in items[..count].chunks(4) {
        let at = |j: usize| batch[j.min(batch.len() - 1)];
        let dirs = tangent_directions(std::array::from_fn(|j| at(j).1), std::array::from_fn(|j| at(j).2), n);
        for (&(i, _, _), d) in batch.iter().zip(dirs) {
            (local[0].as_mut()[i], local[1].as_mut()[i], local[2].as_mut()[i]) = (d.x, d.y, d.z);
        }
    }
    let [x, y, z] = local.map(|c| F::from_lanes(c.as_ref()));
    V3::new(x, y, z)
}

/// Every direction of a hit's set of `n` shifted by `shift` ([`tangent_directions`]), into `out`.
fn tangent_set(shift: (f64, f64), n: u32, out: &mut Vec<V3<f32>>) {
    out.clear();
    for first in (0..n).step_by(4) {
        let four = tangent_directions([shift; 4], std::array::from_fn(|j| first + j as u32), n);
        out.extend_from_slice(&four[..(n - first).min(4) as usize]);
    }
}

/// 1/φ, φ the golden ratio: the azimuth step of the lattice, the irrational with the evenest multiples mod 1.
const GOLDEN_STEP: f64 = 0.618_033_988_749_894_8;

/// The random shift of a hit's lattice, in [0, 1)², from the bits of its camera ray's direction.
pub(super) fn rotation(x: f32, y: f32, z: f32) -> (f64, f64) {
    let packed =
        (u64::from(x.to_bits()) << 32 | u64::from(y.to_bits())) ^ u64::from(z.to_bits()).rotate_left(45);
    let mut rng = SplitMix64::new(SplitMix64::new(packed).next_u64());
    (rng.unit(), rng.unit())
}

/// Directions `k[i]` of `n` in the sets shifted by `shift[i]`, four at a time, each in its tangent frame (z
/// along the normal): the lattice point `k` shifted by `shift`, mapped to the hemisphere with density cos θ /
/// π (Malley: a uniform point on the unit disc lifted to the hemisphere). Computed in f64 lanes, rounded
/// once. Every operation is an IEEE one on each lane (no fused multiply-add, which some builds have and
/// others emulate), so a lane's bits depend neither on its neighbours nor on the build.
fn tangent_directions(shift: [(f64, f64); 4], k: [u32; 4], n: u32) -> [V3<f32>; 4] {
    let k = f64x4::new(k.map(f64::from));
    let fract = |x: f64x4| x - x.floor();
    let u = fract(f64x4::new(shift.map(|s| s.0)) + (k + f64x4::splat(0.5)) / f64x4::splat(f64::from(n)));
    let v = fract(f64x4::new(shift.map(|s| s.1)) + k * f64x4::splat(GOLDEN_STEP));
    let r = u.sqrt();
    let (sin, cos) = sin_cos_turns(v);
    let (x, y, z) = ((r * cos).to_array(), (r * sin).to_array(), (f64x4::splat(1.0) - u).sqrt().to_array());
    std::array::from_fn(|i| V3::new(x[i] as f32, y[i] as f32, z[i] as f32))
}

/// `(sin 2πv, cos 2πv)` for v in [0, 1): 4v split into whole quarter turns `q` and a part `f` in about
/// [−½, ½] (both exact), the sine and cosine of `y = f·π/2` (|y| ≤ π/4) by their Taylor series to the terms
/// of degree 17 and 18 (the first term left out is below 1e-19), then turned by `q` quarters. Each result is
/// within 4ε of libm's `sin_cos` of `2π·v` (tests): rounded to f32, the directions are libm's bits, except
/// where an f64 value lies within that of an f32 rounding boundary (none in 2·10^7 tried).
fn sin_cos_turns(v: f64x4) -> (f64x4, f64x4) {
    let w = v * f64x4::splat(4.0);
    let q = (w + f64x4::splat(0.5)).floor();
    let y = (w - q) * f64x4::splat(std::f64::consts::FRAC_PI_2);
    let z = y * y;
    let horner = |terms: &[f64]| terms.iter().fold(f64x4::splat(0.0), |p, &c| p * z + f64x4::splat(c));
    let sin = y + y * z * horner(&SIN_TERMS);
    let cos = f64x4::splat(1.0) + z * horner(&COS_TERMS);
    let quarter = q - (q * f64x4::splat(0.25)).floor() * f64x4::splat(4.0);
    let is = |k: f64| quarter.simd_eq(f64x4::splat(k));
    // sin and cos of y + qπ/2 for q = 0, 1, 2, 3: (s, c), (c, −s), (−s, −c), (−c, s).
    let (odd, half) = (is(1.0) | is(3.0), is(2.0) | is(3.0));
    let (s, c) = (odd.select(cos, sin), odd.select(-sin, cos));
    (half.select(-s, s), half.select(-c, c))
}

/// The Taylor terms of sin after the first, for `sin y = y + y·z·p(z)` with z = y²: −1/3!, 1/5!, …, 1/17!,
/// highest degree first.
const SIN_TERMS: [f64; 8] = [
    1.0 / 355_687_428_096_000.0,
    -1.0 / 1_307_674_368_000.0,
    1.0 / 6_227_020_800.0,
    -1.0 / 39_916_800.0,
    1.0 / 362_880.0,
    -1.0 / 5040.0,
    1.0 / 120.0,
    -1.0 / 6.0,
];

/// The Taylor terms of cos after the first, for `cos y = 1 + z·p(z)`: −1/2!, 1/4!, …, −1/18!, highest degree
/// first.
const COS_TERMS: [f64; 9] = [
    -1.0 / 6_402_373_705_728_000.0,
    1.0 / 20_922_789_888_000.0,
    -1.0 / 87_178_291_200.0,
    1.0 / 479_001_600.0,
    -1.0 / 3_628_800.0,
    1.0 / 40_320.0,
    -1.0 / 720.0,
    1.0 / 24.0,
    -0.5,
];

/// `local` (z along `n`) in the frame around the unit normal `n` (Duff et al. 2017, "Building an
/// orthonormal basis, revisited"), normalised.
pub(crate) fn around<F: Real>(n: V3<F>, local: V3<F>) -> V3<F> {
    let one = F::splat(1.0);
    let sign = F::select(n.z.lt(F::splat(0.0)), -one, one);
    let a = -one / (sign + n.z);
    let b = n.x * n.y * a;
    let t = V3::new(one + sign * n.x * n.x * a, sign * b, -(sign * n.x));
    let bitangent = V3::new(b, sign + n.y * n.y * a, -n.y);
    (t * local.x + bitangent * local.y + n * local.z).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Direction `k` of `n` in the set shifted by `shift`: one lane of [`tangent_directions`].
    fn tangent_direction(shift: (f64, f64), k: u32, n: u32) -> V3<f32> {
        tangent_directions([shift; 4], [k; 4], n)[0]
    }

    /// The same direction by libm's `sin_cos` of `2π·v`.
    fn by_libm(shift: (f64, f64), k: u32, n: u32) -> V3<f32> {
        let u = (shift.0 + (f64::from(k) + 0.5) / f64::from(n)).fract();
        let v = (shift.1 + f64::from(k) * GOLDEN_STEP).fract();
        let (r, (sin, cos)) = (u.sqrt(), (std::f64::consts::TAU * v).sin_cos());
        V3::new(r * cos, r * sin, (1.0 - u).sqrt()).to_f32()
    }

    /// The series' sine and cosine of a turn are within 4ε of libm's over [0, 1) (3.1ε seen), and the
    /// directions round to libm's f32 bits: none of 2·10^5 random ones differs (nor of 2·10^7 in a longer run).
    #[test]
    fn turns_and_directions_agree_with_libm() {
        let mut rng = SplitMix64::new(11);
        let mut worst = 0.0f64;
        for _ in 0..50_000 {
            let v = std::array::from_fn(|_| rng.unit());
            let (sin, cos) = sin_cos_turns(f64x4::new(v));
            for (i, (s, c)) in sin.to_array().into_iter().zip(cos.to_array()).enumerate() {
                let (ls, lc) = (std::f64::consts::TAU * v[i]).sin_cos();
                worst = worst.max(((s - ls).abs() / f64::EPSILON).max((c - lc).abs() / f64::EPSILON));
            }
        }
        assert!(worst <= 4.0, "{worst} ulps");
        let mut differ = 0;
        for k in 0..200_000u32 {
            let (shift, n) = ((rng.unit(), rng.unit()), 1 + k % 97);
            differ += usize::from(tangent_direction(shift, k % n, n) != by_libm(shift, k % n, n));
        }
        assert_eq!(differ, 0, "directions that differ from libm's");
    }

    /// Each lane of the four-at-a-time form is that direction alone, whatever its neighbours.
    #[test]
    fn lanes_are_independent() {
        let mut rng = SplitMix64::new(12);
        for _ in 0..10_000 {
            let n = 1 + (rng.next_u64() % 64) as u32;
            let shift = std::array::from_fn(|_| (rng.unit(), rng.unit()));
            let k = std::array::from_fn(|_| (rng.next_u64() % u64::from(n)) as u32);
            let four = tangent_directions(shift, k, n);
            for i in 0..4 {
                assert_eq!(four[i], tangent_direction(shift[i], k[i], n));
            }
        }
    }

    /// Directions lie in the hemisphere and are unit; their mean cosine is 2/3, the cosine-weighted
    /// hemisphere's (a uniform one's is 1/2).
    #[test]
    fn directions_are_cosine_weighted_around_the_normal() {
        let normals = [V3::new(0.0f32, 0.0, 1.0), V3::new(0.0, 0.0, -1.0), V3::new(0.6, -0.8, 0.0)];
        for n in normals.into_iter().chain([V3::new(0.3f32, 0.4, -0.5).normalize()]) {
            let count = 4096;
            let mut sum = 0.0f64;
            for k in 0..count {
                let d = around(n, tangent_direction((0.3, 0.7), k, count));
                assert!((d.length() - 1.0).abs() < 1e-6, "{d:?}");
                let cos = d.dot(n);
                assert!(cos >= -1e-6, "below the surface: {cos}");
                sum += f64::from(cos);
            }
            let mean = sum / f64::from(count);
            assert!((mean - 2.0 / 3.0).abs() < 0.005, "{n:?}: mean cosine {mean}");
        }
    }

    /// Different camera directions get unrelated shifts; one direction always the same.
    #[test]
    fn shifts_depend_on_every_bit_of_the_direction() {
        let a = rotation(0.1, 0.2, 0.97);
        assert_eq!(a, rotation(0.1, 0.2, 0.97));
        assert_ne!(a, rotation(f32::from_bits(0.1f32.to_bits() + 1), 0.2, 0.97));
        assert_ne!(a, rotation(0.1, 0.2, f32::from_bits(0.97f32.to_bits() + 1)));
    }
}
