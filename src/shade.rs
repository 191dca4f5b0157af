//! Whitted shading: ambient + Lambert + Phong from coloured point lights, hard shadows by occlusion rays,
//! mirror reflection and refraction (Snell, total internal reflection, optional Fresnel), to a depth limit.

use std::ops::AddAssign;

use crate::geometry::{Departure, Ray};
use crate::math::{Rgb, Vec3f};
use crate::scene::desc::{Falloff, Material};
use crate::scene::Scene;

/// Secondary rays whose contribution to the pixel would be below this weight are not traced.
const MIN_WEIGHT: f32 = 1.0 / 1024.0;

/// How many rays of each kind were traced.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    /// Camera rays.
    pub primary: u64,
    /// Occlusion rays toward lights.
    pub shadow: u64,
    /// Mirror rays.
    pub reflection: u64,
    /// Transmitted rays.
    pub refraction: u64,
}

impl RayCounts {
    /// All rays.
    pub fn total(&self) -> u64 {
        self.primary + self.shadow + self.reflection + self.refraction
    }
}

impl AddAssign for RayCounts {
    fn add_assign(&mut self, o: Self) {
        self.primary += o.primary;
        self.shadow += o.shadow;
        self.reflection += o.reflection;
        self.refraction += o.refraction;
    }
}

/// Traces rays through one scene, counting them. One per thread.
pub struct Tracer<'a> {
    scene: &'a Scene,
    /// Rays traced so far.
    pub counts: RayCounts,
}

impl<'a> Tracer<'a> {
    /// A tracer over `scene` with zero counts.
    pub fn new(scene: &'a Scene) -> Self {
        Self { scene, counts: RayCounts::default() }
    }

    /// Radiance along a camera ray.
    pub fn primary(&mut self, ray: &Ray<f32>) -> Rgb {
        self.counts.primary += 1;
        self.trace(ray, Departure::CAMERA, 0, 1.0)
    }

    fn trace(&mut self, ray: &Ray<f32>, from: Departure, depth: u32, weight: f32) -> Rgb {
        let hit = self.scene.geometry.intersect(ray, from, f32::INFINITY);
        if !hit.is_hit() {
            return self.scene.render.background;
        }
        let sp = self.scene.geometry.surface(ray, hit.t, hit.prim);
        let mat = &self.scene.materials[sp.material as usize];
        // Turn the normal toward the ray: a hit from inside (the lecture's case 4) flips it.
        let inside = sp.normal.dot(ray.dir) > 0.0;
        let n = if inside { -sp.normal } else { sp.normal };
        let base = surface_color(mat, sp.object_point);
        let view = -ray.dir;
        let mut color = base.mul_elem(self.scene.render.ambient) * mat.ambient;
        // Rays leaving on the normal's side head inside exactly when the hit was from inside.
        let same_side = Departure { prim: hit.prim, inward: inside };
        if mat.diffuse > 0.0 || mat.specular > 0.0 {
            color = color + self.direct(mat, base, sp.point, n, view, same_side);
        }
        if depth < self.scene.render.max_depth {
            color = color + self.secondary(mat, ray, sp.point, n, inside, hit.prim, depth, weight);
        }
        color
    }

    /// Lambert and Phong from every light that the point sees.
    fn direct(&mut self, mat: &Material, base: Rgb, p: Vec3f, n: Vec3f, view: Vec3f, from: Departure) -> Rgb {
        let mut sum = Rgb::default();
        for light in &self.scene.lights {
            let to_light = light.position - p;
            let dist2 = to_light.dot(to_light);
            let dist = dist2.sqrt();
            let l = to_light * (1.0 / dist);
            let cos = n.dot(l);
            // Lights behind the surface (or a NaN normal) contribute nothing.
            if cos.is_nan() || cos <= 0.0 {
                continue;
            }
            self.counts.shadow += 1;
            if self.scene.geometry.occluded(&Ray::new(p, l), from, dist) {
                continue;
            }
            let intensity = match light.falloff {
                Falloff::None => light.color,
                Falloff::InverseSquare => light.color * (1.0 / dist2),
            };
            let mut reflected = base * (mat.diffuse * cos);
            if mat.specular > 0.0 {
                let mirror = n * (2.0 * cos) - l;
                let highlight = mirror.dot(view).max(0.0).powf(mat.shininess);
                reflected = reflected + Rgb::all(mat.specular * highlight);
            }
            sum = sum + reflected.mul_elem(intensity);
        }
        sum
    }

    /// Mirror and transmitted contributions.
    #[allow(clippy::too_many_arguments)]
    fn secondary(
        &mut self,
        mat: &Material,
        ray: &Ray<f32>,
        p: Vec3f,
        n: Vec3f,
        inside: bool,
        prim: u32,
        depth: u32,
        weight: f32,
    ) -> Rgb {
        let mut kr = mat.reflect;
        let mut kt = mat.transmit;
        let mut refracted = None;
        if kt > 0.0 {
            let eta = if inside { mat.ior } else { 1.0 / mat.ior };
            match refract(ray.dir, n, eta) {
                Some((dir, fresnel)) => {
                    if mat.fresnel {
                        kr += kt * fresnel;
                        kt *= 1.0 - fresnel;
                    }
                    refracted = Some(dir);
                }
                None => {
                    // Total internal reflection: all transmitted energy is reflected.
                    kr += kt;
                    kt = 0.0;
                }
            }
        }
        let mut color = Rgb::default();
        if kr * weight > MIN_WEIGHT {
            self.counts.reflection += 1;
            let dir = (ray.dir - n * (2.0 * ray.dir.dot(n))).normalize();
            let from = Departure { prim, inward: inside };
            color = color + self.trace(&Ray::new(p, dir), from, depth + 1, weight * kr) * kr;
        }
        if let Some(dir) = refracted.filter(|_| kt * weight > MIN_WEIGHT) {
            self.counts.refraction += 1;
            let from = Departure { prim, inward: !inside };
            color = color + self.trace(&Ray::new(p, dir), from, depth + 1, weight * kt) * kt;
        }
        color
    }
}

/// The material's colour at an object-space point: plain, or a solid checkerboard.
fn surface_color(mat: &Material, object_point: Vec3f) -> Rgb {
    match mat.checker {
        None => mat.color,
        Some(ch) => {
            let cell = |v: f32| (v / ch.size).floor() as i64;
            let parity = cell(object_point.x) + cell(object_point.y) + cell(object_point.z);
            if parity.rem_euclid(2) == 0 {
                mat.color
            } else {
                ch.color
            }
        }
    }
}

/// Snell refraction of unit direction `d` through unit normal `n` (facing against `d`) with
/// `eta = n_incident / n_transmitted`. Returns the unit transmitted direction and the unpolarised dielectric
/// Fresnel reflectance, or `None` under total internal reflection.
pub fn refract(d: Vec3f, n: Vec3f, eta: f32) -> Option<(Vec3f, f32)> {
    let cos_i = -d.dot(n);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t > 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let dir = (d * eta + n * (eta * cos_i - cos_t)).normalize();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    Some((dir, 0.5 * (rs * rs + rp * rp)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::V3;

    #[test]
    fn refraction_obeys_snell_and_fresnel_at_normal_incidence() {
        let n = V3::new(0.0, 1.0, 0.0);
        let d = V3::new(0.6f32, -0.8, 0.0);
        let (t, f) = refract(d, n, 1.0 / 1.5).unwrap();
        // sin θ_t = sin θ_i / 1.5
        assert!((t.x - 0.6 / 1.5).abs() < 1e-6);
        assert!(f > 0.0 && f < 1.0);
        let (_, f0) = refract(V3::new(0.0, -1.0, 0.0), n, 1.0 / 1.5).unwrap();
        assert!((f0 - 0.04).abs() < 1e-6, "normal-incidence reflectance of glass is 4%: {f0}");
    }

    #[test]
    fn total_internal_reflection_past_the_critical_angle() {
        let n = V3::new(0.0, 1.0, 0.0);
        // Leaving glass (eta = 1.5) at 60° from the normal: sin θ_t = 1.3 > 1.
        let d = V3::new(0.866_025_4f32, -0.5, 0.0);
        assert!(refract(d, n, 1.5).is_none());
        assert!(refract(V3::new(0.5f32, -0.866_025_4, 0.0), n, 1.5).is_some());
    }

    #[test]
    fn checker_alternates_across_cells_and_zero() {
        let m = Material {
            checker: Some(crate::scene::desc::Checker { color: Rgb::all(0.0), size: 1.0 }),
            ..Material::default()
        };
        assert_eq!(surface_color(&m, V3::new(0.5, 0.5, 0.0)), m.color);
        assert_eq!(surface_color(&m, V3::new(1.5, 0.5, 0.0)), Rgb::all(0.0));
        assert_eq!(surface_color(&m, V3::new(-0.5, 0.5, 0.0)), Rgb::all(0.0));
    }
}
