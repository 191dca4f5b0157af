//! Ambient occlusion on packets ([`Shade::Ao`](crate::scene::desc::Shade::Ao)): at each camera ray's hit,
//! `samples` cosine-weighted directions over the hemisphere around the shading normal, each an occlusion
//! packet (any hit, early exit) of length `distance` leaving the surface as shadow rays do (from the hit
//! point, skipping the departure primitive); the colour is the surface's times the share that nothing blocks.
//!
//! The directions of a hit are a Fibonacci lattice over the unit square (`((k + ½)/n, k/φ)` mod 1, φ the
//! golden ratio: evenly spread in both coordinates, so in radius and in azimuth) shifted by a random
//! offset (Cranley–Patterson) seeded by the bits of the camera ray's direction. That direction is a function of the sample's position
//! in the image alone (computed in f64 and rounded once, at every width), so each pixel's samples get their
//! own directions whatever the tile, thread or packet width, and every ray of a pixel's antialiasing
//! samples gets its own set. The seed and the directions in the tangent frame are scalar code per lane
//! (`sin`, `cos`); the frame around the normal is lane arithmetic in the scalar operation order.

use crate::geometry::{DeparturePacket, RayPacket};
use crate::math::{Mask, Real, SplitMix64, V3};
use crate::scene::desc::Ao;
use crate::simd::{set_bits, Lanes};

use super::{lanes_set, splat_rgb, Tracer};

impl<F: Lanes> Tracer<'_, F> {
    /// The ambient occlusion of each active camera ray's hit times the surface's colour; the background
    /// where a ray hits nothing, zero in inactive lanes.
    pub(super) fn ambient_occlusion(&mut self, rays: &RayPacket<F>, ao: Ao) -> V3<F> {
        let hit = self.scene.geometry.intersect_k(rays, &DeparturePacket::camera());
        let found = hit.found() & rays.active;
        let zero = V3::all(F::splat_f32(0.0));
        let background = V3::select(rays.active & !found, splat_rgb::<F>(self.scene.render.background), zero);
        if !found.any() {
            return background;
        }
        let s = self.surface(rays, &hit, found);
        let from = DeparturePacket { prim: hit.prim, inward: s.inside };
        let bits = F::move_mask(found);
        let mut shift = [(0.0, 0.0); 16];
        for i in set_bits(bits) {
            shift[i] = rotation(rays.dir.x.lane(i), rays.dir.y.lane(i), rays.dir.z.lane(i));
        }
        let distance = F::splat_f32(ao.distance.map_or(f32::INFINITY, |d| d as f32));
        let one = F::splat_f32(1.0);
        let mut open = F::splat_f32(0.0);
        for k in 0..ao.samples {
            let mut local = [F::splat_f32(0.0).to_array(); 3];
            for i in set_bits(bits) {
                let d = tangent_direction(shift[i], k, ao.samples);
                (local[0].as_mut()[i], local[1].as_mut()[i], local[2].as_mut()[i]) = (d.x, d.y, d.z);
            }
            let local = V3::new(F::from_lanes(local[0].as_ref()), F::from_lanes(local[1].as_ref()), {
                F::from_lanes(local[2].as_ref())
            });
            let probe = RayPacket::new(s.point, around(s.normal, local), distance, found);
            self.counts.ao += lanes_set::<F>(found);
            let blocked = self.scene.geometry.occluded_hinted_k(&probe, &from, &mut self.ao_hint);
            open = F::select(found & !blocked, open + one, open);
        }
        let share = open / F::splat_f32(ao.samples as f32);
        V3::select(found, s.base * share, background)
    }
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
