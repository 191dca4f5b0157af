//! Mirror reflection and refraction (Snell, total internal reflection, optional Fresnel) as masked packets,
//! to the depth limit.

use crate::accel::RayKind;
use crate::geometry::{DeparturePacket, RayPacket};
use crate::math::{Mask, Real, V3};
use crate::simd::Lanes;

use super::{lanes_set, Surface, Tracer};

/// Secondary rays whose contribution to the pixel would be below this weight are not traced.
const MIN_WEIGHT: f32 = 1.0 / 1024.0;

impl<F: Lanes> Tracer<'_, F> {
    /// Mirror and transmitted contributions, as masked packets.
    pub(super) fn secondary(
        &mut self,
        s: &Surface<F>,
        rays: &RayPacket<F>,
        found: F::Mask,
        prim: F::Ids,
        depth: u32,
        weight: F,
    ) -> V3<F> {
        let zero = F::splat_f32(0.0);
        let one = F::splat_f32(1.0);
        let mut kr = s.reflect;
        let mut kt = s.transmit;
        let transmitting = found & kt.gt(zero);
        let mut refracted = None;
        if transmitting.any() {
            let eta = F::select(s.inside, s.ior, one / s.ior);
            let (through, dir, fresnel) = refract(rays.ray.dir, s.normal, eta);
            let through = transmitting & through;
            let split = through & s.fresnel;
            kr = F::select(split, kr + kt * fresnel, kr);
            kt = F::select(split, kt * (one - fresnel), kt);
            // Total internal reflection: all transmitted energy is reflected.
            let tir = transmitting & !through;
            kr = F::select(tir, kr + kt, kr);
            kt = F::select(tir, zero, kt);
            refracted = Some((through, dir));
        }
        let min_weight = F::splat_f32(MIN_WEIGHT);
        let mut color = V3::all(zero);
        let mirror = found & (kr * weight).gt(min_weight);
        if mirror.any() {
            self.counts.reflection += lanes_set::<F>(mirror);
            let d = rays.ray.dir;
            let dir = (d - s.normal * (F::splat_f32(2.0) * d.dot(s.normal))).normalize();
            let next = RayPacket::new(s.point, dir, F::splat_f32(f32::INFINITY), mirror);
            let from = DeparturePacket { prim, inward: s.inside };
            let c = self.trace(RayKind::Reflection, &next, &from, depth + 1, weight * kr);
            color = V3::select(mirror, color + c * kr, color);
        }
        if let Some((through, dir)) = refracted {
            let glass = through & (kt * weight).gt(min_weight);
            if glass.any() {
                self.counts.refraction += lanes_set::<F>(glass);
                let next = RayPacket::new(s.point, dir, F::splat_f32(f32::INFINITY), glass);
                let from = DeparturePacket { prim, inward: !s.inside };
                let c = self.trace(RayKind::Refraction, &next, &from, depth + 1, weight * kt);
                color = V3::select(glass, color + c * kt, color);
            }
        }
        color
    }
}

/// Snell refraction of unit direction `d` through unit normal `n` (facing against `d`) with
/// `eta = n_incident / n_transmitted`. Returns the lanes that refract (not totally internally reflected),
/// the unit transmitted direction and the unpolarised dielectric Fresnel reflectance.
fn refract<F: Real>(d: V3<F>, n: V3<F>, eta: F) -> (F::Mask, V3<F>, F) {
    let one = F::splat(1.0);
    let cos_i = -d.dot(n);
    let sin2_t = eta * eta * (one - cos_i * cos_i);
    let through = sin2_t.le(one);
    let cos_t = (one - sin2_t).sqrt();
    let dir = (d * eta + n * (eta * cos_i - cos_t)).normalize();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (through, dir, F::splat(0.5) * (rs * rs + rp * rp))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refraction_obeys_snell_and_fresnel_at_normal_incidence() {
        let n = V3::new(0.0, 1.0, 0.0);
        let d = V3::new(0.6f32, -0.8, 0.0);
        let (ok, t, f) = refract(d, n, 1.0 / 1.5);
        assert!(ok);
        // sin θ_t = sin θ_i / 1.5
        assert!((t.x - 0.6 / 1.5).abs() < 1e-6);
        assert!(f > 0.0 && f < 1.0);
        let (_, _, f0) = refract(V3::new(0.0, -1.0, 0.0), n, 1.0 / 1.5);
        assert!((f0 - 0.04).abs() < 1e-6, "normal-incidence reflectance of glass is 4%: {f0}");
    }

    #[test]
    fn total_internal_reflection_past_the_critical_angle() {
        let n = V3::new(0.0, 1.0, 0.0);
        // Leaving glass (eta = 1.5) at 60° from the normal: sin θ_t = 1.3 > 1.
        assert!(!refract(V3::new(0.866_025_4f32, -0.5, 0.0), n, 1.5).0);
        assert!(refract(V3::new(0.5f32, -0.866_025_4, 0.0), n, 1.5).0);
    }
}
