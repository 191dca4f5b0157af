//! Planar polygons (NFF `p` and `pp`), stored as triangles that carry their polygon's id: the triangles are the
//! items of the polygons' BVH, and each polygon keeps the list of its triangles for shading.

use super::kernel::barycentric;
use crate::math::{Vec3f, V3};

/// Planar polygons, stored as triangles that carry their polygon's index: one primitive id per polygon.
#[derive(Clone, Debug, Default)]
pub(crate) struct Polygons {
    /// Per triangle: first vertex.
    pub(crate) v0: Vec<Vec3f>,
    /// Per triangle: second vertex minus the first.
    pub(crate) e1: Vec<Vec3f>,
    /// Per triangle: third vertex minus the first.
    pub(crate) e2: Vec<Vec3f>,
    /// Per triangle: the polygon it belongs to (`0..len()`).
    pub(crate) polygon: Vec<u32>,
    /// Per triangle: unit vertex normals to interpolate (NFF `pp`), or `None` for flat polygons.
    pub(crate) vertex_normals: Vec<Option<[Vec3f; 3]>>,
    /// The triangles of every polygon, grouped by polygon: polygon k's are `members[first[k]..first[k + 1]]`.
    pub(crate) members: Vec<u32>,
    /// Per polygon: where its triangles start in `members` (one more entry than polygons).
    pub(crate) first: Vec<u32>,
    /// Per polygon: unit geometric normal (right-hand rule over the vertex order).
    pub(crate) normal: Vec<Vec3f>,
    /// Per polygon: a vertex, on the plane through which `normal` is taken.
    pub(crate) anchor: Vec<Vec3f>,
    /// Per polygon: how far (at most) its vertices lie off that plane, rounded up: polygons need only be
    /// planar to a tolerance.
    pub(crate) thickness: Vec<f32>,
    /// Per polygon: material index.
    pub(crate) material: Vec<u32>,
    /// The rendering space's origin in world space, rounded to f32: polygons' solid textures are in world
    /// space (a hit's object point is the point plus it).
    pub(crate) origin: Vec3f,
}

impl Polygons {
    /// Number of polygons.
    pub(crate) fn len(&self) -> usize {
        self.normal.len()
    }
    /// Number of triangles.
    pub(crate) fn triangles(&self) -> usize {
        self.v0.len()
    }

    /// Appends a polygon given as triangles `[a, b, c]` over `vertices`, with optional per-vertex normals.
    pub(crate) fn push(
        &mut self,
        vertices: &[Vec3f],
        normals: Option<&[Vec3f]>,
        triangles: &[[u32; 3]],
        normal: Vec3f,
        material: u32,
    ) {
        if self.first.is_empty() {
            self.first.push(0);
        }
        let k = self.len() as u32;
        for t in triangles {
            let [a, b, c] = t.map(|i| i as usize);
            self.members.push(self.v0.len() as u32);
            self.v0.push(vertices[a]);
            self.e1.push(vertices[b] - vertices[a]);
            self.e2.push(vertices[c] - vertices[a]);
            self.polygon.push(k);
            self.vertex_normals.push(normals.map(|n| [n[a], n[b], n[c]]));
        }
        self.first.push(self.members.len() as u32);
        let anchor = vertices[0];
        // Each vertex's offset from the anchor, in f64 from the stored f32 values.
        let offsets = vertices.iter().map(|v| {
            [(v.x, anchor.x), (v.y, anchor.y), (v.z, anchor.z)].map(|(a, b)| f64::from(a) - f64::from(b))
        });
        let n = [normal.x, normal.y, normal.z].map(f64::from);
        let (height, far) = offsets.fold((0.0f64, 0.0f64), |(height, far), d| {
            let h = (0..3).map(|i| n[i] * d[i]).sum::<f64>().abs();
            (height.max(h), far.max(d.iter().map(|x| x.abs()).sum()))
        });
        // The triangles' edges are stored rounded (ε/2 of their 1-norm, at most twice the farthest vertex's
        // `far`); the factor rounds the f64 heights up.
        let thickness = (height + f64::from(f32::EPSILON) * 2.0 * far) * (1.0 + 1e-6);
        self.anchor.push(anchor);
        self.thickness.push((thickness as f32).max(f32::MIN_POSITIVE));
        self.normal.push(normal);
        self.material.push(material);
    }

    /// The box of triangle `j` over its vertices `v0`, `v0 + e1`, `v0 + e2` (the sums rounded: the BVH's
    /// padding covers that ulp).
    pub(crate) fn triangle_box(&self, j: usize) -> (Vec3f, Vec3f) {
        let (a, b, c) = (self.v0[j], self.v0[j] + self.e1[j], self.v0[j] + self.e2[j]);
        let pick =
            |f: fn(f32, f32) -> f32| V3::new(f(f(a.x, b.x), c.x), f(f(a.y, b.y), c.y), f(f(a.z, b.z), c.z));
        (pick(f32::min), pick(f32::max))
    }

    /// Whether polygon `k` has no vertex normals (its shading normal is its plane's everywhere).
    pub(crate) fn is_flat(&self, k: usize) -> bool {
        let members = &self.members[self.first[k] as usize..self.first[k + 1] as usize];
        members.iter().all(|&j| self.vertex_normals[j as usize].is_none())
    }

    /// The shading normal of polygon `k` at `point`: interpolated over the triangle that contains the point
    /// (the one whose smallest barycentric is largest, robust to rounding at shared edges; the first of equal
    /// ones, as the f64 twin chooses), else geometric.
    pub(crate) fn shading_normal(&self, k: usize, point: Vec3f) -> Vec3f {
        let members = &self.members[self.first[k] as usize..self.first[k + 1] as usize];
        let mut best: Option<(f32, [f32; 3], [Vec3f; 3])> = None;
        for &j in members {
            let j = j as usize;
            let Some(normals) = self.vertex_normals[j] else { continue };
            let b = barycentric(self.v0[j], self.e1[j], self.e2[j], point);
            let score = min3(b);
            if best.is_none_or(|(s, _, _)| score > s) {
                best = Some((score, b, normals));
            }
        }
        let Some((_, [b0, b1, b2], [n0, n1, n2])) = best else { return self.normal[k] };
        let n = (n0 * b0 + n1 * b1 + n2 * b2).normalize();
        if n.x.is_finite() && n.y.is_finite() && n.z.is_finite() {
            n
        } else {
            self.normal[k]
        }
    }
}

fn min3(b: [f32; 3]) -> f32 {
    b[0].min(b[1]).min(b[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles on the same vertices score alike at every point: the first one's normals are taken,
    /// as the f64 twin takes them (`Polygon64::shading_normal`), not the last.
    #[test]
    fn equal_scores_take_the_first_triangle() {
        let (a, b, c) = (V3::new(0.0, 0.0, 0.0), V3::new(1.0, 0.0, 0.0), V3::new(0.0, 1.0, 0.0));
        let (up, tilted) = (V3::new(0.0, 0.0, 1.0), V3::new(0.0, 0.6, 0.8));
        let mut store = Polygons::default();
        let normals = [up, up, up, tilted, tilted, tilted];
        store.push(&[a, b, c, a, b, c], Some(&normals), &[[0, 1, 2], [3, 4, 5]], up, 0);
        for point in [V3::new(0.25, 0.25, 0.0), V3::new(0.1, 0.7, 0.0), V3::new(0.5, 0.0, 0.0)] {
            assert_eq!(store.shading_normal(0, point), up, "{point:?}");
        }
    }
}
