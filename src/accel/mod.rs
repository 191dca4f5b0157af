//! The scene's geometry laid out for intersection, and the queries over it: `intersect` (closest hit) and
//! `occluded` (any hit). Brute force over SoA arrays for now; the BVH comes with large sphere fields.

mod brute;
pub mod bvh;

use crate::geometry::{Ray, Shape, NO_PRIM};
use crate::math::{Vec3f, V3};

/// Spheres in structure-of-arrays layout: one array per coordinate, so lanes load contiguous values.
#[derive(Clone, Debug, Default)]
pub struct Spheres {
    /// Centre x.
    pub cx: Vec<f32>,
    /// Centre y.
    pub cy: Vec<f32>,
    /// Centre z.
    pub cz: Vec<f32>,
    /// Radius.
    pub r: Vec<f32>,
    /// Material index.
    pub material: Vec<u32>,
}

impl Spheres {
    /// Number of spheres.
    pub fn len(&self) -> usize {
        self.r.len()
    }
    /// True when there are none.
    pub fn is_empty(&self) -> bool {
        self.r.is_empty()
    }
    /// Centre of sphere `i`.
    #[inline(always)]
    pub fn center(&self, i: usize) -> Vec3f {
        V3::new(self.cx[i], self.cy[i], self.cz[i])
    }
    /// The spheres in a new order: `order[j]` is the old index of new sphere `j`.
    pub fn permuted(&self, order: &[u32]) -> Spheres {
        let pick = |v: &[f32]| order.iter().map(|&i| v[i as usize]).collect();
        Spheres {
            cx: pick(&self.cx),
            cy: pick(&self.cy),
            cz: pick(&self.cz),
            r: pick(&self.r),
            material: order.iter().map(|&i| self.material[i as usize]).collect(),
        }
    }
    /// Appends a sphere.
    pub fn push(&mut self, center: Vec3f, radius: f32, material: u32) {
        self.cx.push(center.x);
        self.cy.push(center.y);
        self.cz.push(center.z);
        self.r.push(radius);
        self.material.push(material);
    }
}

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
        self.normal.push(normal);
        self.material.push(material);
    }

    /// The shading normal of polygon `k` at `point`: interpolated over the triangle that contains the point
    /// (the one whose smallest barycentric is largest, robust to rounding at shared edges), else geometric.
    fn shading_normal(&self, k: usize, point: Vec3f) -> Vec3f {
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

/// All primitives: spheres have ids `0..spheres.len()`, then the shapes, then the polygons.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    /// Plain spheres.
    pub spheres: Spheres,
    /// Transformed generic shapes.
    pub shapes: Vec<Shape<f32>>,
    /// Planar polygons.
    pub polygons: Polygons,
}

/// What a primitive id refers to.
#[derive(Clone, Copy, Debug)]
pub enum PrimRef<'a> {
    /// Index into [`Geometry::spheres`].
    Sphere(usize),
    /// A transformed shape.
    Shape(&'a Shape<f32>),
    /// Index into [`Geometry::polygons`].
    Polygon(usize),
}

/// What shading needs to know about a hit point.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// World-space hit point.
    pub point: Vec3f,
    /// Unit geometric normal, pointing out of the primitive (not yet turned toward the ray).
    pub normal: Vec3f,
    /// The hit point in the primitive's own frame (centre-relative for spheres, z = 0 for planes), for
    /// solid textures.
    pub object_point: Vec3f,
    /// Material index.
    pub material: u32,
}

impl Geometry {
    /// Total number of primitives.
    pub fn len(&self) -> usize {
        self.spheres.len() + self.shapes.len() + self.polygons.len()
    }
    /// True when the scene has no primitives.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The id of the first polygon (polygon k has id `polygon_base() + k`).
    pub fn polygon_base(&self) -> usize {
        self.spheres.len() + self.shapes.len()
    }

    /// What primitive id `prim` (< `len()`) refers to.
    pub fn prim(&self, prim: u32) -> PrimRef<'_> {
        let i = prim as usize;
        if i < self.spheres.len() {
            PrimRef::Sphere(i)
        } else if i < self.polygon_base() {
            PrimRef::Shape(&self.shapes[i - self.spheres.len()])
        } else {
            PrimRef::Polygon(i - self.polygon_base())
        }
    }

    /// Position, normal and material of hit `t` on primitive `prim` along `ray`.
    pub fn surface(&self, ray: &Ray<f32>, t: f32, prim: u32) -> SurfacePoint {
        debug_assert_ne!(prim, NO_PRIM);
        let point = ray.at(t);
        match self.prim(prim) {
            PrimRef::Sphere(i) => {
                let object_point = point - self.spheres.center(i);
                let normal = object_point.normalize();
                SurfacePoint { point, normal, object_point, material: self.spheres.material[i] }
            }
            PrimRef::Polygon(k) => {
                let p = &self.polygons;
                SurfacePoint {
                    point,
                    normal: p.shading_normal(k, point),
                    object_point: point,
                    material: p.material[k],
                }
            }
            PrimRef::Shape(shape) => {
                let mut object_point = shape.to_object(ray).at(t);
                if !shape.kind.is_solid() {
                    object_point.z = 0.0;
                }
                SurfacePoint {
                    point,
                    normal: shape.world_normal(object_point),
                    object_point,
                    material: shape.material,
                }
            }
        }
    }
}
