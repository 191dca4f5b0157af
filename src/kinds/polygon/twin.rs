//! A polygon in f64 for the accuracy twin: its triangles (the f32 kernel's operations at f64), its plane
//! normal and outline, and the rules that say where an f32 and an f64 kernel may disagree on it.

use glam::DVec3;

use super::kernel::barycentric;
use super::{intersect_triangle, newell_normal, triangles_or_fan, PolygonDesc};
use crate::geometry::Ray;
use crate::kinds::Stray;
use crate::math::V3;

/// One triangle of a polygon.
#[derive(Clone, Copy, Debug)]
struct Tri64 {
    v0: V3<f64>,
    e1: V3<f64>,
    e2: V3<f64>,
    /// Unit vertex normals (NFF `pp`), to interpolate.
    normals: Option<[V3<f64>; 3]>,
}

/// A polygon in f64: its triangles, unit plane normal (Newell, right-hand rule) and outline, and a ball
/// around the triangles that lets a ray passing far from it skip them.
#[derive(Clone, Debug)]
pub(crate) struct Polygon64 {
    tris: Vec<Tri64>,
    /// The ball's centre (the first triangle's first vertex) and radius.
    ball: (V3<f64>, f64),
    /// Unit geometric normal.
    pub(crate) normal: V3<f64>,
    /// The vertices in order (empty for a polygon widened from its stored triangles).
    outline: Vec<V3<f64>>,
}

fn len(p: V3<f64>) -> f64 {
    p.dot(p).sqrt()
}

impl Polygon64 {
    /// The polygon moved by `−origin`, triangulated there ([`triangles_or_fan`]).
    pub(crate) fn new(d: &PolygonDesc, origin: DVec3) -> Self {
        let vertices: Vec<DVec3> = d.vertices.iter().map(|&x| x - origin).collect();
        let triangles = triangles_or_fan(&vertices);
        let normals: Option<Vec<V3<f64>>> = d.unit_normals().map(|ns| ns.into_iter().map(V3::from).collect());
        let at = |i: u32| V3::from(vertices[i as usize]);
        let tris: Vec<Tri64> = triangles
            .iter()
            .map(|&[a, b, c]| Tri64 {
                v0: at(a),
                e1: at(b) - at(a),
                e2: at(c) - at(a),
                normals: normals.as_ref().map(|ns| [a, b, c].map(|i| ns[i as usize])),
            })
            .collect();
        Self {
            ball: ball(&tris),
            tris,
            normal: V3::from(newell_normal(&vertices).normalize_or_zero()),
            outline: vertices.iter().map(|&x| V3::from(x)).collect(),
        }
    }

    /// Polygon `k` of `store` as stored (f32, rendering space) widened exactly to f64. The store keeps no
    /// outline, so only the parallel part of [`Polygon64::grazing`] and nothing of [`Polygon64::near`]
    /// applies to it.
    #[cfg(test)]
    pub(crate) fn widened(store: &super::Polygons, k: usize) -> Self {
        let members = &store.members[store.first[k] as usize..store.first[k + 1] as usize];
        let wide = |v: crate::math::Vec3f| v.to_f64();
        let tris: Vec<Tri64> = members
            .iter()
            .map(|&j| {
                let j = j as usize;
                let normals = store.vertex_normals[j].map(|ns| ns.map(wide));
                Tri64 { v0: wide(store.v0[j]), e1: wide(store.e1[j]), e2: wide(store.e2[j]), normals }
            })
            .collect();
        Self { ball: ball(&tris), tris, normal: wide(store.normal[k]), outline: Vec::new() }
    }

    /// The closest hit over the triangles in `[0, t_max)`: none where the ray's line passes clear of the
    /// ball by a margin of 10⁻⁹ of the distances involved (the f64 rounding of the triangle kernel and of
    /// this test is about 10⁻¹⁶ of them, so no hit the kernel could report is skipped). Compared squared,
    /// `|oc × d|² > (r + m)²·|d|²`, without a division or a root.
    #[inline(always)]
    pub(crate) fn intersect(&self, ray: &Ray<f64>, t_max: f64) -> Option<f64> {
        let (centre, radius) = self.ball;
        let (oc, d) = (centre - ray.origin, ray.dir);
        let across = oc.cross(d);
        let margin = 1e-9 * (oc.x.abs() + oc.y.abs() + oc.z.abs() + radius);
        if across.dot(across) > (radius + margin) * (radius + margin) * d.dot(d) {
            return None;
        }
        let mut best: Option<f64> = None;
        for tri in &self.tris {
            let (hit, t) = intersect_triangle(tri.v0, tri.e1, tri.e2, ray, best.unwrap_or(t_max));
            if hit {
                best = Some(t);
            }
        }
        best
    }

    /// The shading normal at `point`: the vertex normals interpolated over the triangle that contains the
    /// point best (largest smallest barycentric), else the geometric normal (the f32 rule).
    pub(crate) fn shading_normal(&self, point: V3<f64>) -> V3<f64> {
        let mut best: Option<(f64, V3<f64>)> = None;
        for tri in &self.tris {
            let Some([n0, n1, n2]) = tri.normals else { continue };
            let [b0, b1, b2] = barycentric(tri.v0, tri.e1, tri.e2, point);
            let score = b0.min(b1).min(b2);
            if best.is_none_or(|(s, _)| score > s) {
                best = Some((score, (n0 * b0 + n1 * b1 + n2 * b2).normalize()));
            }
        }
        match best {
            Some((_, n)) if n.x.is_finite() && n.y.is_finite() && n.z.is_finite() => n,
            _ => self.normal,
        }
    }

    /// Whether rounding can change whether (or where) `ray` hits the polygon: its direction is within `tol`
    /// (plus the direction stray) of parallel to the plane, or the line meets the plane within
    /// `tol·(|o| + |p|)` (plus the stray at that distance, over the cosine of incidence) of the outline.
    pub(crate) fn grazing(&self, ray: &Ray<f64>, tol: f64, stray: Stray) -> bool {
        let (n, d) = (self.normal, ray.dir);
        let cos = n.dot(d).abs() / len(d);
        if cos <= tol + stray.dir {
            return true;
        }
        let Some(&anchor) = self.outline.first() else { return false };
        let t = n.dot(anchor - ray.origin) / n.dot(d);
        let p = ray.at(t);
        let m = self.outline.len();
        let edge = (0..m)
            .map(|j| segment_distance(p, self.outline[j], self.outline[(j + 1) % m]))
            .fold(f64::INFINITY, f64::min);
        edge * cos <= tol * (len(ray.origin) + len(p)) + stray.at(t)
    }

    /// Whether `point` lies within `tol·(|p| + |anchor| + extent)` plus `slack` of the plane: where a ray
    /// starting or ending there can find or miss the polygon by rounding.
    pub(crate) fn near(&self, point: V3<f64>, tol: f64, slack: f64) -> bool {
        let Some(&anchor) = self.outline.first() else { return false };
        let extent = self.outline.iter().map(|&x| len(x - anchor)).fold(0.0, f64::max);
        self.normal.dot(point - anchor).abs() <= tol * (len(point) + len(anchor) + extent) + slack
    }
}

/// A ball around the triangles: centred on the first vertex, reaching the farthest corner (NaN corners
/// give a NaN radius, which never skips).
fn ball(tris: &[Tri64]) -> (V3<f64>, f64) {
    let Some(first) = tris.first() else { return (V3::new(0.0, 0.0, 0.0), f64::NAN) };
    let corners = tris.iter().flat_map(|t| [t.v0, t.v0 + t.e1, t.v0 + t.e2]);
    let reach = corners.map(|c| len(c - first.v0)).fold(0.0, |a: f64, b| match a.is_nan() || b.is_nan() {
        true => f64::NAN,
        false => a.max(b),
    });
    (first.v0, reach)
}

/// Distance from `p` to the segment `a..b`.
fn segment_distance(p: V3<f64>, a: V3<f64>, b: V3<f64>) -> f64 {
    let ab = b - a;
    let dd = ab.dot(ab);
    let s = if dd > 0.0 { ((p - a).dot(ab) / dd).clamp(0.0, 1.0) } else { 0.0 };
    len(p - (a + ab * s))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::SplitMix64;

    /// The ball never skips a hit: rays aimed at points on, near and off random polygons (far and near,
    /// grazing included) get from `intersect` exactly what the triangles alone give.
    #[test]
    fn the_ball_never_skips_a_hit() {
        let mut rng = SplitMix64::new(5);
        let mut unit = move || rng.unit();
        let (mut hits, mut rays) = (0, 0);
        for _ in 0..200 {
            let centre =
                DVec3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5) * 10f64.powf(unit() * 8.0 - 2.0);
            let size = 10f64.powf(unit() * 6.0 - 3.0);
            let n = 3 + (unit() * 5.0) as u32;
            let vertices = (0..n)
                .map(|i| {
                    let a = std::f64::consts::TAU * f64::from(i) / f64::from(n);
                    centre + DVec3::new(a.cos(), a.sin() * 0.7, 0.3 * a.cos()) * size
                })
                .collect();
            let p = Polygon64::new(&PolygonDesc { vertices, normals: None, material: 0 }, DVec3::ZERO);
            for _ in 0..50 {
                let target = p.outline[0]
                    + (p.outline[1] - p.outline[0]) * (unit() * 1.2 - 0.1)
                    + (p.outline[2] - p.outline[1]) * (unit() * 1.2 - 0.1);
                let dir = V3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5);
                let origin = target - dir * (10f64.powf(unit() * 6.0 - 2.0) / len(dir));
                let ray = Ray { origin, dir };
                let mut all: Option<f64> = None;
                for tri in &p.tris {
                    let (hit, t) =
                        intersect_triangle(tri.v0, tri.e1, tri.e2, &ray, all.unwrap_or(f64::INFINITY));
                    if hit {
                        all = Some(t);
                    }
                }
                assert_eq!(p.intersect(&ray, f64::INFINITY), all, "{ray:?}");
                (hits, rays) = (hits + usize::from(all.is_some()), rays + 1);
            }
        }
        assert!(hits > rays / 4 && hits < rays, "{hits} of {rays} rays hit: both kinds must be tried");
    }
}
