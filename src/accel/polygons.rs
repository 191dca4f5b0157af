//! Planar polygons (NFF `p` and `pp`), stored as triangles that carry their polygon's id.

use crate::math::Vec3f;

/// Planar polygons, stored as triangles that carry their polygon's index: one primitive id per polygon.
#[derive(Clone, Debug, Default)]
pub struct Polygons {
    /// Per triangle: first vertex.
    pub v0: Vec<Vec3f>,
    /// Per triangle: second vertex minus the first.
    pub e1: Vec<Vec3f>,
    /// Per triangle: third vertex minus the first.
    pub e2: Vec<Vec3f>,
    /// Per triangle: the polygon it belongs to (`0..len()`).
    pub polygon: Vec<u32>,
    /// Per triangle: unit vertex normals to interpolate (NFF `pp`), or `None` for flat polygons.
    pub vertex_normals: Vec<Option<[Vec3f; 3]>>,
    /// Per polygon: its triangles are `first[k]..first[k + 1]` (one more entry than polygons).
    pub first: Vec<u32>,
    /// Per polygon: unit geometric normal (right-hand rule over the vertex order).
    pub normal: Vec<Vec3f>,
    /// Per polygon: a vertex, on the plane through which `normal` is taken.
    pub anchor: Vec<Vec3f>,
    /// Per polygon: how far (at most) its vertices lie off that plane, rounded up: polygons need only be
    /// planar to a tolerance.
    pub thickness: Vec<f32>,
    /// Per polygon: material index.
    pub material: Vec<u32>,
}

impl Polygons {
    /// Number of polygons.
    pub fn len(&self) -> usize {
        self.normal.len()
    }
    /// True when there are none.
    pub fn is_empty(&self) -> bool {
        self.normal.is_empty()
    }
    /// Number of triangles.
    pub fn triangles(&self) -> usize {
        self.v0.len()
    }
    /// Appends a polygon given as triangles `[a, b, c]` over `vertices`, with optional per-vertex normals.
    pub fn push(
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
            self.v0.push(vertices[a]);
            self.e1.push(vertices[b] - vertices[a]);
            self.e2.push(vertices[c] - vertices[a]);
            self.polygon.push(k);
            self.vertex_normals.push(normals.map(|n| [n[a], n[b], n[c]]));
        }
        self.first.push(self.v0.len() as u32);
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

    /// The shading normal of polygon `k` at `point`: interpolated over the triangle that contains the point
    /// (the one whose smallest barycentric is largest, robust to rounding at shared edges), else geometric.
    pub(super) fn shading_normal(&self, k: usize, point: Vec3f) -> Vec3f {
        let (lo, hi) = (self.first[k] as usize, self.first[k + 1] as usize);
        let best = (lo..hi)
            .filter_map(|j| {
                self.vertex_normals[j].map(|n| (barycentric(self.v0[j], self.e1[j], self.e2[j], point), n))
            })
            .max_by(|(a, _), (b, _)| min3(*a).total_cmp(&min3(*b)));
        let Some(([b0, b1, b2], [n0, n1, n2])) = best else { return self.normal[k] };
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

/// Barycentric coordinates of `p` (assumed in the plane) in the triangle `(v0, v0 + e1, v0 + e2)`.
fn barycentric(v0: Vec3f, e1: Vec3f, e2: Vec3f, p: Vec3f) -> [f32; 3] {
    let w = p - v0;
    let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d20, d21) = (w.dot(e1), w.dot(e2));
    let denom = d00 * d11 - d01 * d01;
    let b1 = (d11 * d20 - d01 * d21) / denom;
    let b2 = (d00 * d21 - d01 * d20) / denom;
    [1.0 - b1 - b2, b1, b2]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{intersect_triangle, stays_off_plane, Ray};
    use crate::math::V3;

    /// A polygon that is planar only to a tolerance gets a thickness that covers its vertices, so the plane
    /// cull keeps a ray that hits it near its lifted corner.
    #[test]
    fn thickness_covers_a_lifted_vertex() {
        let lift = 5e-5;
        let vertices =
            [V3::new(0.0, 0.0, 0.0), V3::new(1.0, 0.0, 0.0), V3::new(1.0, 1.0, lift), V3::new(0.0, 1.0, 0.0)];
        let mut p = Polygons::default();
        p.push(&vertices, None, &[[0, 1, 2], [0, 2, 3]], V3::new(0.0, 0.0, 1.0), 0);
        assert!(p.thickness[0] >= lift, "thickness {}", p.thickness[0]);
        // Just above the plane z = 0, ending just below the lifted corner's triangle.
        let ray = Ray::new(V3::new(0.9, 0.8, 1e-3), V3::new(0.0, 0.0, -1.0));
        let reach = 1e-3 - 0.5 * lift;
        let (hit, _) = intersect_triangle(p.v0[0], p.e1[0], p.e2[0], &ray, reach);
        assert!(hit, "the lifted triangle is hit within reach");
        assert!(!stays_off_plane(p.anchor[0], p.normal[0], p.thickness[0], &ray, reach));
        assert!(
            stays_off_plane(p.anchor[0], p.normal[0], 0.0, &ray, reach),
            "without thickness it would be culled"
        );
    }
}
