//! The scene's geometry laid out for intersection, and the queries over it: `intersect` (closest hit) and
//! `occluded` (any hit). Brute force over SoA arrays for now; the BVH comes with large sphere fields.

pub mod bvh;
mod brute;

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

/// All primitives: spheres have ids `0..spheres.len()`, shapes the ids after them.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    /// Plain spheres.
    pub spheres: Spheres,
    /// Transformed generic shapes.
    pub shapes: Vec<Shape<f32>>,
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
        self.spheres.len() + self.shapes.len()
    }
    /// True when the scene has no primitives.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The shape with primitive id `prim`, if it is a shape rather than a plain sphere.
    fn shape(&self, prim: u32) -> Option<&Shape<f32>> {
        (prim as usize).checked_sub(self.spheres.len()).and_then(|k| self.shapes.get(k))
    }

    /// Position, normal and material of hit `t` on primitive `prim` along `ray`.
    pub fn surface(&self, ray: &Ray<f32>, t: f32, prim: u32) -> SurfacePoint {
        debug_assert_ne!(prim, NO_PRIM);
        let point = ray.at(t);
        match self.shape(prim) {
            None => {
                let i = prim as usize;
                let object_point = point - self.spheres.center(i);
                let normal = object_point.normalize();
                SurfacePoint { point, normal, object_point, material: self.spheres.material[i] }
            }
            Some(shape) => {
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
