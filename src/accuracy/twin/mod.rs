//! The f64 twin: an independent f64 tracer over the exact scene description, the reference the f32
//! renderer is measured against.
//!
//! It reads the [`SceneDesc`] (already f64) and never the compiled f32 scene, and works in the renderer's
//! rendering space ([`RenderingFrame`]: origin at the eye, or at a far scene's centre): every position `p`
//! is stored as `p − origin`, computed in f64 (sphere centres, polygon vertices, the registered kinds'
//! items, lights), and camera rays start where the renderer's do (at exactly 0, or a far scene's start
//! distance along the ray) with f64 unit directions from [`Camera<f64>::ray`], not rounded to f32.
//! Intersections run the sphere kernel of [`crate::geometry`] instantiated at f64 ([`sphere::twin::hit`])
//! and each registered kind's f64 form ([`crate::kinds::Kind::intersect64`]), with
//! the renderer's rules: closest hit by the total order (smaller t, then lower id), and a ray that leaves a
//! primitive ([`Departure`]) never hits it again except, for a solid left toward its inside, at its exit
//! root, and for a kind that says so (an open cone, a torus), wherever it meets that item again
//! ([`crate::kinds::Kind::rehit64`], as `accel/departure.rs` rules).
//!
//! Ids are scene-file ids: spheres `0..` in file order, then the registered kinds' primitives (polygons
//! first, one id per polygon). Spheres are searched through the twin's own BVH ([`super::bvh64`]) from
//! [`TWIN_BVH_MIN_SPHERES`] on; the rest brute force (planes are unbounded).

use glam::DVec3;

use crate::camera::{Camera, CameraError};
use crate::compile::RenderingFrame;
use crate::geometry::{Departure, Ray, NO_PRIM};
use crate::kinds::{sphere, KindTwins};
use crate::math::V3;
use crate::scene::desc::SceneDesc;

use super::bvh64::Bvh64;
pub(crate) use super::hit64::Hit64;

mod tolerance;

/// ε32 = 2⁻²⁴, the f32 unit roundoff: every tolerance of the accuracy report is a multiple of it.
pub(crate) const EPS32: f64 = <f32 as crate::math::Real>::UNIT_ROUNDOFF;

/// From this many spheres on the twin searches them through its own BVH; below, brute force.
pub(crate) const TWIN_BVH_MIN_SPHERES: usize = 16;

/// How far the f32 ray under test may stray from the twin's f64 ray, measured per ray: the explanations
/// widen their tolerances by it (a secondary ray starts from each precision's own hit point, along its own
/// normal). Zero for camera rays.
pub(crate) use crate::kinds::Stray as Slack;

/// The f64 reference scene: see the module documentation.
#[derive(Clone, Debug)]
pub(crate) struct Twin {
    /// The camera in f64, in the twin's space.
    pub(crate) camera: Camera<f64>,
    /// The origin of the twin's space in world space: the f32 scene's ([`RenderingFrame`]).
    // Read by the tests (the twin's frame).
    #[cfg_attr(not(test), allow(dead_code))]
    pub(crate) origin: DVec3,
    /// Light positions in the twin's space.
    pub(crate) lights: Vec<V3<f64>>,
    spheres: Vec<(V3<f64>, f64)>,
    /// The registered kinds' primitives (polygons among them), ids after the spheres.
    kinds: KindTwins,
    bvh: Option<Bvh64>,
}

fn v(p: DVec3) -> V3<f64> {
    V3::from(p)
}

fn len(p: V3<f64>) -> f64 {
    p.dot(p).sqrt()
}

impl Twin {
    /// The twin of `desc`, with a sphere BVH from [`TWIN_BVH_MIN_SPHERES`] spheres on.
    pub(crate) fn new(desc: &SceneDesc) -> Result<Self, CameraError> {
        Self::with_bvh(desc, desc.spheres.len() >= TWIN_BVH_MIN_SPHERES)
    }

    /// The twin of `desc`, searching spheres through its BVH when `bvh` is true (and every sphere is finite),
    /// else brute force: the two give the same hits bit for bit (tests/library/accuracy.rs).
    pub(crate) fn with_bvh(desc: &SceneDesc, bvh: bool) -> Result<Self, CameraError> {
        // The f32 scene's rendering space (compile's frame): tolerances then scale with the magnitudes f32
        // rounds at, and camera rays start where the f32 ones do.
        let frame = RenderingFrame::of(desc, None);
        let origin = frame.origin;
        let mut camera = Camera::new(&desc.camera)?;
        (camera.eye, camera.start) = (v(desc.camera.eye - origin), frame.start);
        let spheres: Vec<(V3<f64>, f64)> =
            desc.spheres.iter().map(|s| (v(s.center - origin), s.radius)).collect();
        let finite = spheres
            .iter()
            .all(|(c, r)| c.x.is_finite() && c.y.is_finite() && c.z.is_finite() && r.is_finite());
        let bvh = (bvh && finite && !spheres.is_empty()).then(|| Bvh64::build(&spheres));
        Ok(Self {
            camera,
            origin,
            lights: desc.lights.iter().map(|l| v(l.position - origin)).collect(),
            spheres,
            kinds: desc.kinds.twins(origin),
            bvh,
        })
    }

    /// Number of primitives.
    pub(crate) fn len(&self) -> usize {
        self.kinds_base() + self.kinds.len()
    }

    /// Whether a ray leaving primitive `prim` can meet it again away from its origin whichever way it heads:
    /// a registered kind's that says so (an open cone's far wall, a torus; a solid's exit needs the ray to
    /// head inward).
    pub(crate) fn meets_again(&self, prim: u32) -> bool {
        self.kind(prim).is_some_and(|k| self.kinds.meets_again(k))
    }

    /// The id of the registered kinds' first item.
    fn kinds_base(&self) -> usize {
        self.spheres.len()
    }

    /// Primitive `prim`'s index over the registered kinds' items, when it is one.
    fn kind(&self, prim: u32) -> Option<usize> {
        (prim as usize).checked_sub(self.kinds_base()).filter(|&k| k < self.kinds.len())
    }

    /// Whether spheres are searched through the twin's BVH.
    pub(crate) fn has_bvh(&self) -> bool {
        self.bvh.is_some()
    }

    /// The camera ray through pixel-space point (sx, sy) (column j's centre is j + ½): [`Camera<f64>::ray`],
    /// not rounded (from the eye, or from where a far scene's camera rays start).
    pub(crate) fn camera_ray(&self, sx: f64, sy: f64) -> Ray<f64> {
        self.camera.ray(sx, sy)
    }

    /// Closest hit of `ray` in `[0, t_max)`, never on the near side of its departure surface.
    pub(crate) fn intersect(&self, ray: &Ray<f64>, from: Departure, t_max: f64) -> Hit64 {
        let mut best = Hit64::MISS;
        match &self.bvh {
            Some(bvh) => bvh.closest(ray, from.prim, t_max, &mut best),
            None => {
                for (i, &(c, r)) in self.spheres.iter().enumerate() {
                    if i as u32 != from.prim {
                        if let Some(t) = sphere::twin::hit(c, r, ray, t_max) {
                            best.update(i as u32, t);
                        }
                    }
                }
            }
        }
        let mut kinds = (best.prim, best.t);
        self.kinds.intersect(self.kinds_base() as u32, from.prim, ray, t_max, &mut kinds);
        best.update(kinds.0, kinds.1);
        if let Some(t) = self.departure_hit(from, ray, t_max) {
            best.update(from.prim, t);
        }
        best
    }

    /// Where `ray` meets the primitive it leaves again, in `[0, t_max)`: for a solid left toward its inside,
    /// its exit root (a registered kind's [`crate::kinds::Kind::rehit64`]: an ellipsoid's); for a registered
    /// kind that meets again (an open cone, a torus) left to either side, where it meets the item again.
    fn departure_hit(&self, from: Departure, ray: &Ray<f64>, t_max: f64) -> Option<f64> {
        match self.kind(from.prim) {
            Some(k) if from.inward || self.kinds.meets_again(k) => self.kinds.rehit(k, ray, t_max),
            Some(_) => None,
            None if from.inward => self.exit(from.prim, ray, t_max),
            None => None,
        }
    }

    /// Whether `ray` meets anything in `[0, t_max)` (its departure surface's near side excluded).
    #[cfg(test)]
    pub(crate) fn occluded(&self, ray: &Ray<f64>, from: Departure, t_max: f64) -> bool {
        self.intersect(ray, from, t_max).is_hit()
    }

    /// The exit root in `[0, t_max)` of a ray leaving sphere `prim` toward its inside.
    fn exit(&self, prim: u32, ray: &Ray<f64>, t_max: f64) -> Option<f64> {
        let &(centre, radius) = self.spheres.get(prim as usize)?;
        sphere::twin::exit(centre, radius, ray, t_max)
    }

    /// Where `ray` (leaving `from`) hits primitive `prim` alone, in `[0, inf)`.
    pub(crate) fn hit_of(&self, prim: u32, ray: &Ray<f64>, from: Departure) -> Option<f64> {
        let i = prim as usize;
        if prim == NO_PRIM || i >= self.len() {
            return None;
        }
        if prim == from.prim {
            return self.departure_hit(from, ray, f64::INFINITY);
        }
        if let Some(k) = self.kind(prim) {
            return self.kinds.hit_of(k, ray);
        }
        let (centre, radius) = self.spheres[i];
        sphere::twin::hit(centre, radius, ray, f64::INFINITY)
    }

    /// Whether a camera ray meets primitive `prim` from inside, where that is known exactly (a sphere or a
    /// kind with an eye term, an ellipsoid: the sign of its eye term in f64, when not zero); `None`
    /// otherwise. The f32 scene's `crate::accel::Geometry::eye_inside`.
    pub(crate) fn eye_inside(&self, prim: u32) -> Option<bool> {
        let c_eye = match self.spheres.get(prim as usize) {
            Some(&(centre, radius)) => crate::geometry::eye_term(centre, radius),
            None => self.kinds.eye_term(self.kind(prim)?)?,
        };
        crate::geometry::eye_side(c_eye)
    }

    /// The hit point of `ray` at `t` on `prim` and the unit outward normal there (a polygon's interpolated
    /// vertex normal when it has them, a cone's normal away from its axis), computed as
    /// [`crate::accel::Geometry::surface`] computes them in f32.
    pub(crate) fn surface(&self, ray: &Ray<f64>, t: f64, prim: u32) -> (V3<f64>, V3<f64>) {
        let point = ray.at(t);
        let normal = match self.spheres.get(prim as usize) {
            Some(&(centre, _)) => sphere::twin::normal(centre, point),
            None => self.kind(prim).and_then(|k| self.kinds.normal(k, ray, t, point)).expect("a primitive"),
        };
        (point, normal)
    }

    /// The unit normal of the surface the hit's `t` is measured on: [`Twin::surface`]'s, but a polygon's
    /// plane normal rather than its interpolated vertex normals.
    fn geometric_normal(&self, ray: &Ray<f64>, t: f64, prim: u32) -> V3<f64> {
        match self.kind(prim) {
            Some(k) => self.kinds.geometric_normal(k, ray, t, ray.at(t)).expect("a primitive"),
            None => self.surface(ray, t, prim).1,
        }
    }
}
