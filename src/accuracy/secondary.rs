//! The secondary rays of one pixel whose two primary hits agree: shadow rays, the mirror ray and the
//! refraction ray, each built by each precision from its own hit point and facing normal, with the shade
//! module's constructions replicated operation for operation.

use super::report::Reason;
use super::{is_self_hit, len, Acc, Comparer, EPS32, K_GRAZE, K_START};
use crate::accuracy::{Hit64, Slack};
use crate::geometry::{Departure, Ray, NO_PRIM};
use crate::math::{Real, V3};
use crate::scene::desc::Material;

/// Where one pixel's secondary rays start, in each precision.
pub(super) struct Start {
    pub(crate) pixel: (u32, u32),
    /// The primitive hit (scene-file id, the same in both).
    pub(crate) prim: u32,
    pub(crate) point32: V3<f32>,
    /// The f32 camera ray's direction.
    pub(crate) dir32: V3<f32>,
    /// The f32 normal, turned toward the camera ray.
    pub(crate) normal32: V3<f32>,
    /// The f32 hit was from inside.
    pub(crate) inside32: bool,
    /// Departure of the f32 rays that leave on the camera ray's side.
    pub(crate) from32: Departure,
    /// The f32 camera ray starts at the eye (shading then sends no shadow ray toward a light there).
    pub(crate) from_eye32: bool,
    pub(crate) point64: V3<f64>,
    pub(crate) dir64: V3<f64>,
    pub(crate) normal64: V3<f64>,
    pub(crate) inside64: bool,
    pub(crate) from64: Departure,
    /// Distance between the two hit points.
    pub(crate) origin_slack: f64,
    /// Hits this close to the origin are re-hits of the surface left.
    pub(crate) self_tol: f64,
    /// The primitive's material.
    pub(crate) material: Material,
}

/// One shadow ray toward `light` from `point` with the facing `normal`: shade/direct.rs's `Tracer::direct`
/// construction (private there), replicated with the same operations in the same order: `to_light = light −
/// point`, `dist = sqrt(to_light·to_light)`, unit `l = to_light · (1 / dist)`, `cos = normal·l`; a ray is
/// traced only where `cos > 0`, over `[0, dist)`.
fn shadow_ray<F: Real>(point: V3<F>, normal: V3<F>, light: V3<F>) -> (Ray<F>, F, F) {
    let to_light = light - point;
    let dist2 = to_light.dot(to_light);
    let dist = dist2.sqrt();
    let l = to_light * (F::splat(1.0) / dist);
    (Ray::new(point, l), dist, normal.dot(l))
}

/// The mirror ray's direction: shade/secondary.rs's `Tracer::secondary` construction (private there),
/// replicated: `normalize(d − n·(2·(d·n)))` with the facing normal.
fn mirror<F: Real>(d: V3<F>, n: V3<F>) -> V3<F> {
    (d - n * (F::splat(2.0) * d.dot(n))).normalize()
}

/// Snell refraction of unit `d` through the facing unit normal `n` with `eta = n_incident / n_transmitted`:
/// shade/secondary.rs's `refract` (private there), replicated with the same operations: whether the ray
/// passes (no total internal reflection), its unit direction, and `sin²` of the transmitted angle (1 at the
/// critical angle).
fn refract<F: Real>(d: V3<F>, n: V3<F>, eta: F) -> (bool, V3<F>, F)
where
    F::Mask: Into<bool>,
{
    let one = F::splat(1.0);
    let cos_i = -d.dot(n);
    let sin2_t = eta * eta * (one - cos_i * cos_i);
    let through = sin2_t.le(one).into();
    let cos_t = (one - sin2_t).sqrt();
    let dir = (d * eta + n * (eta * cos_i - cos_t)).normalize();
    (through, dir, sin2_t)
}

impl Comparer<'_> {
    /// One shadow ray per light in front of the surface, compared as occluded or not.
    pub(super) fn shadows(&self, s: &Start, acc: &mut Acc) {
        let g = &self.scene.geometry;
        let pixel = s.pixel;
        let meets_again = self.twin.meets_again(s.prim) || s.from64.inward;
        for (k, light32) in self.scene.lights.iter().enumerate() {
            let (s32, dist32, cos32) = shadow_ray(s.point32, s.normal32, light32.position);
            let (s64, dist64, cos64) = shadow_ray(s.point64, s.normal64, self.twin.lights[k]);
            let (lit32, lit64) = (cos32 > 0.0, cos64 > 0.0);
            if !lit32 && !lit64 {
                continue;
            }
            let dir_slack = len(s32.dir.to_f64() - s64.dir) + len(s.normal32.to_f64() - s.normal64);
            if lit32 != lit64 {
                acc.shadow.lit_disagree += 1;
                if cos64.abs() <= K_GRAZE * EPS32 {
                    acc.shadow.explained.count(Reason::Facing);
                } else if cos64.abs() <= K_GRAZE * EPS32 + dir_slack {
                    acc.shadow.explained.count(Reason::Diverge);
                } else {
                    acc.shadow.unexplained += 1;
                    let (a, b) =
                        (Hit64 { t: f64::from(cos32), prim: NO_PRIM }, Hit64 { t: cos64, prim: NO_PRIM });
                    acc.example("shadow facing", pixel, Some(k), a, b);
                }
                continue;
            }
            acc.shadow.rays += 1;
            // As shading asks: not at all from a camera ray's hit toward a light at the eye (`Tracer::direct`:
            // seen; the twin's ray below checks it), else through the light's buffer, where it has one.
            let (blocked32, b32) = match s.from_eye32 && light32.at_eye() {
                true => {
                    acc.shadow.seen_from_eye += 1;
                    (false, Hit64::MISS)
                }
                false => {
                    let b32 = g.intersect(&s32, s.from32, dist32);
                    let b32 = Hit64 { t: f64::from(b32.t), prim: self.file_id(b32.prim) };
                    (g.shadowed(&s32, s.from32, dist32, k), b32)
                }
            };
            let b64 = self.twin.intersect(&s64, s.from64, dist64);
            let contact = self.twin.contact_entry(b32, &s32);
            if is_self_hit(b32, b64, s.prim, s.self_tol, meets_again, contact) {
                acc.shadow.self_hits += 1;
                acc.example("shadow self-hit", pixel, Some(k), b32, b64);
            }
            if blocked32 == b64.is_hit() {
                continue;
            }
            acc.shadow.occluded_disagree += 1;
            let slack = Slack { origin: s.origin_slack, dir: len(s32.dir.to_f64() - s64.dir) };
            let light64 = self.twin.lights[k];
            let why = |sl: Slack| {
                let prims = [b32.prim, b64.prim];
                if prims.iter().any(|&p| self.twin.grazing(p, &s64, K_GRAZE, sl)) {
                    Some(Reason::Graze)
                } else if prims.iter().any(|&p| self.twin.near_surface(p, s64.origin, K_START, sl.origin)) {
                    Some(Reason::Start)
                } else if prims.iter().any(|&p| self.twin.near_surface(p, light64, K_START, sl.at(dist64))) {
                    Some(Reason::Light)
                } else {
                    None
                }
            };
            match why(Slack::default()).or_else(|| why(slack).map(|_| Reason::Diverge)) {
                Some(r) => acc.shadow.explained.count(r),
                None => {
                    acc.shadow.unexplained += 1;
                    acc.example("shadow", pixel, Some(k), b32, b64);
                }
            }
        }
    }

    /// The mirror ray of every hit, whatever its material, compared like a camera ray.
    pub(super) fn reflection(&self, s: &Start, acc: &mut Acc) {
        let r32 = Ray::new(s.point32, mirror(s.dir32, s.normal32));
        let r64 = Ray::new(s.point64, mirror(s.dir64, s.normal64));
        self.secondary_ray(s, acc, "reflection", (r32, s.from32), (r64, s.from64));
    }

    /// The refraction ray of a hit on a transmitting material (`transmit > 0`) where both precisions refract,
    /// leaving into the other side (shade/secondary.rs: `eta` is `ior` from inside, `1/ior` from outside),
    /// compared like a camera ray. Where one precision refracts and the other reflects totally, the ray is
    /// traced in neither and the disagreement is counted (`tir_disagree`): explained as a graze when `sin²`
    /// of the f64 transmitted angle is within `K_GRAZE·ε32` of 1 (the critical angle), as a divergence when
    /// within that plus `2·eta²` times how far the f32 direction and normal stray from the f64 ones.
    pub(super) fn refraction(&self, s: &Start, acc: &mut Acc) {
        let (transmit, ior) = (s.material.transmit, s.material.ior);
        if transmit <= 0.0 {
            return;
        }
        let eta32 = if s.inside32 { ior } else { 1.0 / ior };
        let (through32, t32, sin2_32) = refract(s.dir32, s.normal32, eta32);
        let ior64 = f64::from(ior);
        let eta64 = if s.inside64 { ior64 } else { 1.0 / ior64 };
        let (through64, t64, sin2_64) = refract(s.dir64, s.normal64, eta64);
        if through32 != through64 {
            let st = &mut acc.refraction;
            st.tir_disagree += 1;
            let stray = len(s.dir32.to_f64() - s.dir64) + len(s.normal32.to_f64() - s.normal64);
            let off = (sin2_64 - 1.0).abs();
            if off <= K_GRAZE * EPS32 {
                st.explained.count(Reason::Graze);
            } else if s.inside32 == s.inside64 && off <= K_GRAZE * EPS32 + 2.0 * eta64 * eta64 * stray {
                st.explained.count(Reason::Diverge);
            } else {
                st.unexplained += 1;
                let (a, b) =
                    (Hit64 { t: f64::from(sin2_32), prim: NO_PRIM }, Hit64 { t: sin2_64, prim: NO_PRIM });
                acc.example("refraction tir", s.pixel, None, a, b);
            }
            return;
        }
        if !through64 {
            return;
        }
        let from32 = Departure { prim: s.from32.prim, inward: !s.inside32 };
        let from64 = Departure { prim: s.from64.prim, inward: !s.inside64 };
        let (r32, r64) = (Ray::new(s.point32, t32), Ray::new(s.point64, t64));
        self.secondary_ray(s, acc, "refraction", (r32, from32), (r64, from64));
    }

    /// Traces one secondary ray in both precisions, compares the closest hits and counts a self-hit.
    fn secondary_ray(
        &self,
        s: &Start,
        acc: &mut Acc,
        kind: &str,
        (r32, from32): (Ray<f32>, Departure),
        (r64, from64): (Ray<f64>, Departure),
    ) {
        let m32 = self.scene.geometry.intersect(&r32, from32, f32::INFINITY);
        let m32 = Hit64 { t: f64::from(m32.t), prim: self.file_id(m32.prim) };
        let m64 = self.twin.intersect(&r64, from64, f64::INFINITY);
        let slack = Slack { origin: s.origin_slack, dir: len(r32.dir.to_f64() - r64.dir) };
        let st = if kind == "reflection" { &mut acc.reflection } else { &mut acc.refraction };
        self.compare_hits(st, &mut acc.examples, kind, s.pixel, &r64, from64, m32, m64, slack);
        // A ray leaving a solid inward meets its far side: only a hit at the origin is a re-hit.
        let meets_again = self.twin.meets_again(s.prim) || from64.inward;
        let contact = self.twin.contact_entry(m32, &r32);
        if is_self_hit(m32, m64, s.prim, s.self_tol, meets_again, contact) {
            st.self_hits += 1;
            push_self_hit(&mut acc.examples, kind, s.pixel, m32, m64);
        }
    }
}

fn push_self_hit(examples: &mut Vec<super::Example>, kind: &str, pixel: (u32, u32), a: Hit64, b: Hit64) {
    super::push_example(examples, &format!("{kind} self-hit"), pixel, None, a, b);
}
