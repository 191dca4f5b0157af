//! Ambient occlusion on packets ([`Shade::Ao`](crate::scene::desc::Shade::Ao)): at each camera ray's hit,
//! `samples` cosine-weighted directions over the hemisphere around the shading normal, each an occlusion
//! packet (any hit, early exit) of length `distance` leaving the surface as shadow rays do (from the hit
//! point, skipping the departure primitive); the colour is the surface's times the share that nothing blocks.
//! With K or more samples a packet holds K directions of one hit (one origin: coherent walks); with fewer, it
//! holds one direction of each of the K pixels' hits, so that packets run full. Each ray is the same in
//! both, and each ray's answer is exact, so the counts are the same bits either way.
//!
//! The directions of a hit are a Fibonacci lattice over the unit square (`((k + ½)/n, k/φ)` mod 1, φ the
//! golden ratio: evenly spread in both coordinates, so in radius and in azimuth) shifted by a random
//! offset (Cranley–Patterson) seeded by the bits of the camera ray's direction. That direction is a function of the sample's position
//! in the image alone (computed in f64 and rounded once, at every width), so each pixel's samples get their
//! own directions whatever the tile, thread or packet width, and every ray of a pixel's antialiasing
//! samples gets its own set. The seed and the directions in the tangent frame are scalar code per lane
//! (`sin`, `cos`); the frame around the normal is lane arithmetic in the scalar operation order.

use crate::accel::{traced, RayKind};
use crate::geometry::{DeparturePacket, HitPacket, RayPacket};
use crate::math::{Mask, Real, SplitMix64, V3};
use crate::scene::desc::Ao;
use crate::simd::{set_bits, IdLanes, Lanes};

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
        let open = if ao.samples as usize >= F::K {
            self.open_by_hit(rays, hit, &s, found, ao, distance)
        } else {
            self.open_by_pixel(rays, hit, &s, found, ao, distance)
        };
        let share = open / F::splat_f32(ao.samples as f32);
        V3::select(found, s.base * share, background)
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
        for i in set_bits(F::move_mask(found)) {
            let shift = rotation(rays.ray.dir.x.lane(i), rays.ray.dir.y.lane(i), rays.ray.dir.z.lane(i));
            let lane = |v: &V3<F>| F::splat_v3(V3::new(v.x.lane(i), v.y.lane(i), v.z.lane(i)));
            let (point, normal) = (lane(&s.point), lane(&s.normal));
            let inward = F::mask_from_bits(if F::mask_lane(s.inside, i) { u32::MAX } else { 0 });
            let from = DeparturePacket { prim: F::Ids::splat(hit.prim.lane(i)), inward };
            for first in (0..ao.samples).step_by(F::K) {
                let count = F::K.min((ao.samples - first) as usize);
                let local =
                    local_directions::<F>((0..count).map(|j| (j, shift, first + j as u32)), ao.samples);
                let live = F::lanes_below(count);
                let probe = RayPacket::new(point, around(normal, local), distance, live);
                self.counts.ao += count as u64;
                let (geometry, hint) = (&self.scene.geometry, &mut self.ao_hint);
                let blocked = traced(RayKind::Ao, || geometry.occluded_hinted_k(&probe, &from, hint));
                open[i] += F::move_mask(live & !blocked).count_ones();
            }
        }
        F::from_fn(|i| open[i] as f32)
    }

    /// [`Tracer::open_by_hit`] traced one direction of every found lane at a time (lanes = pixels): for
    /// fewer samples than K, where a hit's own packets would run part empty. Every ray is the same as there,
    /// so the counts are the same bits.
    fn open_by_pixel(
        &mut self,
        rays: &RayPacket<F>,
        hit: &HitPacket<F>,
        s: &Surface<F>,
        found: F::Mask,
        ao: Ao,
        distance: F,
    ) -> F {
        let from = DeparturePacket { prim: hit.prim, inward: s.inside };
        let bits = F::move_mask(found);
        let mut shift = [(0.0, 0.0); 16];
        for i in set_bits(bits) {
            shift[i] = rotation(rays.ray.dir.x.lane(i), rays.ray.dir.y.lane(i), rays.ray.dir.z.lane(i));
        }
        let one = F::splat_f32(1.0);
        let mut open = F::splat_f32(0.0);
        for k in 0..ao.samples {
            let local = local_directions::<F>(set_bits(bits).map(|i| (i, shift[i], k)), ao.samples);
            let probe = RayPacket::new(s.point, around(s.normal, local), distance, found);
            self.counts.ao += u64::from(bits.count_ones());
            let (geometry, hint) = (&self.scene.geometry, &mut self.ao_hint);
            let blocked = traced(RayKind::Ao, || geometry.occluded_hinted_k(&probe, &from, hint));
            open = F::select(found & !blocked, open + one, open);
        }
        open
    }
}

/// The packet of local directions whose lane `i` is direction `k` of `n` in the set shifted by `shift`
/// ([`tangent_direction`]), for each `(i, shift, k)` given; the other lanes hold 0.
fn local_directions<F: Lanes>(lanes: impl Iterator<Item = (usize, (f64, f64), u32)>, n: u32) -> V3<F> {
    let mut local = [F::splat_f32(0.0).to_array(); 3];
    for (i, shift, k) in lanes {
        let d = tangent_direction(shift, k, n);
        (local[0].as_mut()[i], local[1].as_mut()[i], local[2].as_mut()[i]) = (d.x, d.y, d.z);
    }
    let [x, y, z] = local.map(|c| F::from_lanes(c.as_ref()));
    V3::new(x, y, z)
}

/// 1/φ, φ the golden ratio: the azimuth step of the lattice, the irrational with the evenest multiples mod 1.
const GOLDEN_STEP: f64 = 0.618_033_988_749_894_8;

/// The random shift of a hit's lattice, in [0, 1)², from the bits of its camera ray's direction.
fn rotation(x: f32, y: f32, z: f32) -> (f64, f64) {
    let packed =
        (u64::from(x.to_bits()) << 32 | u64::from(y.to_bits())) ^ u64::from(z.to_bits()).rotate_left(45);
    let mut rng = SplitMix64::new(SplitMix64::new(packed).next_u64());
    (rng.unit(), rng.unit())
}

/// Direction `k` of `n` in a hit's set, in its tangent frame (z along the normal): the lattice point `k`
/// shifted by `shift`, mapped to the hemisphere with density cos θ / π (Malley: a uniform point on the unit
/// disc lifted to the hemisphere). Computed in f64, rounded once.
pub(crate) fn tangent_direction(shift: (f64, f64), k: u32, n: u32) -> V3<f32> {
    let u = (shift.0 + (f64::from(k) + 0.5) / f64::from(n)).fract();
    let v = (shift.1 + f64::from(k) * GOLDEN_STEP).fract();
    let (r, phi) = (u.sqrt(), std::f64::consts::TAU * v);
    V3::new(r * phi.cos(), r * phi.sin(), (1.0 - u).sqrt()).to_f32()
}

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
