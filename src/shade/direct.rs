//! Direct light: Lambert and Phong from every point light each lane sees, by one occlusion packet per light.

use crate::accel::{traced, RayKind};
use crate::geometry::{DeparturePacket, RayPacket};
use crate::math::{Mask, V3};
use crate::scene::desc::Falloff;
use crate::simd::{set_bits, Lanes};

use super::{lanes_set, splat_rgb, Surface, Tracer};

impl<F: Lanes> Tracer<'_, F> {
    /// Lambert and Phong from every light each lane sees, by one occlusion packet per light.
    ///
    /// A light at the eye needs no shadow ray from the lanes of `clear`, camera rays' closest hits: the way
    /// back to the eye is the camera ray's own segment, on which it found nothing nearer. (The shadow ray
    /// from the rounded hit point would retrace it only up to rounding, so where it reported a blocker, a
    /// surface grazed or left, the light was in fact seen.) Particle files and arrays light their spheres so
    /// by default, and those shadow rays cost as much as the camera rays, all of them unblocked.
    pub(super) fn direct(
        &mut self,
        s: &Surface<F>,
        view: V3<F>,
        lanes: F::Mask,
        from: &DeparturePacket<F>,
        clear: F::Mask,
    ) -> V3<F> {
        let zero = F::splat_f32(0.0);
        let mut sum = V3::all(zero);
        for (k, light) in self.scene.lights.iter().enumerate() {
            let to_light = F::splat_v3(light.position) - s.point;
            let dist2 = to_light.dot(to_light);
            let dist = dist2.sqrt();
            let l = to_light * (F::splat_f32(1.0) / dist);
            let cos = s.normal.dot(l);
            // Lights behind the surface (or a NaN normal) contribute nothing.
            let lit = lanes & cos.gt(zero);
            if !lit.any() {
                continue;
            }
            let seen = match light.at_eye() {
                true => lit & clear,
                false => F::mask_from_bits(0),
            };
            let asked = lit & !seen;
            let mut visible = seen;
            if asked.any() {
                self.counts.shadow += lanes_set::<F>(asked);
                let shadow = RayPacket::new(s.point, l, dist, asked);
                let hint = &mut self.shadow_hints[k];
                let geometry = &self.scene.geometry;
                let blocked = traced(RayKind::Shadow, || geometry.shadowed_k(&shadow, from, hint, k));
                visible = visible | (asked & !blocked);
            }
            let intensity = match light.falloff {
                Falloff::None => splat_rgb::<F>(light.color),
                Falloff::InverseSquare => splat_rgb::<F>(light.color) * (F::splat_f32(1.0) / dist2),
            };
            let mut reflected = s.base * (s.diffuse * cos);
            let phong = visible & s.specular.gt(zero);
            if phong.any() {
                let mirror = s.normal * (F::splat_f32(2.0) * cos) - l;
                let along = mirror.dot(view);
                // powf only where it matters: lanes outside `phong` are discarded by the select below, and
                // 0^n is +0 for n > 0 without the call.
                let mut highlight = F::splat_f32(0.0).to_array();
                for i in set_bits(F::move_mask(phong)) {
                    let (base, n) = (along.lane(i).max(0.0), s.shininess.lane(i));
                    if base != 0.0 || n <= 0.0 {
                        highlight.as_mut()[i] = base.powf(n);
                    }
                }
                let highlight = F::from_lanes(highlight.as_ref());
                reflected = V3::select(phong, reflected + V3::all(s.specular * highlight), reflected);
            }
            sum = V3::select(visible, sum + reflected.mul_elem(intensity), sum);
        }
        sum
    }
}
