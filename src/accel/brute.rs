//! Brute-force queries: every primitive, in id order. Ties go to the lower id (strict `<` on t).

use crate::geometry::{far_root, intersect_sphere, intersect_triangle, sphere_roots, Departure, Hit, Ray};

use super::{Geometry, PrimRef};

impl Geometry {
    /// Closest hit in `[0, t_max)`, never on the departure surface's near side.
    pub fn intersect(&self, ray: &Ray<f32>, from: Departure, t_max: f32) -> Hit {
        let mut best = Hit { t: t_max, prim: from.prim };
        let s = &self.spheres;
        for i in 0..s.len() {
            if i as u32 == from.prim {
                continue;
            }
            let (hit, t) = intersect_sphere(s.center(i), s.r[i], ray, best.t);
            if hit {
                best = Hit { t, prim: i as u32 };
            }
        }
        for (k, shape) in self.shapes.iter().enumerate() {
            let prim = (s.len() + k) as u32;
            if prim == from.prim {
                continue;
            }
            let (hit, t) = shape.intersect(ray, best.t);
            if hit {
                best = Hit { t, prim };
            }
        }
        let p = &self.polygons;
        let base = self.polygon_base() as u32;
        for j in 0..p.triangles() {
            let prim = base + p.polygon[j];
            if prim == from.prim {
                continue;
            }
            let (hit, t) = intersect_triangle(p.v0[j], p.e1[j], p.e2[j], ray, best.t);
            if hit {
                best = Hit { t, prim };
            }
        }
        // `best.prim == from.prim` here means nothing else was hit (ids are never reused).
        let found = best.prim != from.prim;
        if from.inward {
            if let Some(t) = self.exit_of_departure(ray, from.prim, best.t) {
                return Hit { t, prim: from.prim };
            }
        }
        if found {
            best
        } else {
            Hit::MISS
        }
    }

    /// True when anything lies in `[0, t_max)`, the departure surface's near side excluded.
    pub fn occluded(&self, ray: &Ray<f32>, from: Departure, t_max: f32) -> bool {
        let s = &self.spheres;
        let spheres = (0..s.len())
            .filter(|&i| i as u32 != from.prim)
            .any(|i| intersect_sphere(s.center(i), s.r[i], ray, t_max).0);
        spheres
            || self
                .shapes
                .iter()
                .enumerate()
                .any(|(k, shape)| (s.len() + k) as u32 != from.prim && shape.intersect(ray, t_max).0)
            || self.polygons_occlude(ray, from, t_max)
            || (from.inward && self.exit_of_departure(ray, from.prim, t_max).is_some())
    }

    /// True when a polygon other than the departure one lies in `[0, t_max)`.
    fn polygons_occlude(&self, ray: &Ray<f32>, from: Departure, t_max: f32) -> bool {
        let p = &self.polygons;
        let base = self.polygon_base() as u32;
        (0..p.triangles()).any(|j| {
            base + p.polygon[j] != from.prim && intersect_triangle(p.v0[j], p.e1[j], p.e2[j], ray, t_max).0
        })
    }

    /// For a ray that leaves a solid primitive toward its inside: where it leaves the primitive again.
    /// Planar primitives (planes, polygons) have no inside, so nothing.
    fn exit_of_departure(&self, ray: &Ray<f32>, prim: u32, t_max: f32) -> Option<f32> {
        let roots = match self.prim(prim) {
            PrimRef::Sphere(i) => sphere_roots(self.spheres.center(i), self.spheres.r[i], ray),
            PrimRef::Shape(shape) if shape.kind.is_solid() => shape.unit_sphere_roots(&shape.to_object(ray)),
            PrimRef::Shape(_) | PrimRef::Polygon(_) => return None,
        };
        let (hit, t) = far_root(&roots, t_max);
        hit.then_some(t)
    }
}
