//! The f64 oracle: a scene's f32 geometry (centres, radii, the f32 inverse transforms, triangle edges)
//! widened exactly to f64 and intersected by the f64 instances of the same kernels, brute force. What it
//! measures against the f32 path is the f32 arithmetic of the kernels, not the rounding of the scene
//! description. Primitive ids are indices into `Geometry`'s arrays in id order (spheres, then the registered
//! kinds' primitives: polygons, ellipsoids, planes, cones, tori), as `Geometry::intersect` reports them. The
//! registered kinds come from the kind registry ([`bareray::kinds::Kind::widen`] and the kinds' f64 forms),
//! so a kind is covered here as soon as it is registered; spheres take their kind's f64 rules
//! (`bareray::kinds::sphere::twin`), as the accuracy twin does.

use bareray::accel::Geometry;
use bareray::geometry::{sphere_roots, Ray, NO_PRIM};
use bareray::kinds::{sphere, KindTwins, Stray};
use bareray::math::V3;

use super::wide::{dv, wide};
use super::EPS32;

/// The scene's f32 geometry widened exactly to f64, intersected by the f64 instances of the same kernels,
/// brute force, ties to the lower id (the renderer's rule).
pub struct Oracle {
    spheres: Vec<(V3<f64>, f64)>,
    /// The registered kinds' primitives (polygons among them), widened, with ids from `kinds_base`.
    kinds: KindTwins,
    kinds_base: u32,
}

impl Oracle {
    pub fn new(g: &Geometry) -> Self {
        let s = &g.spheres;
        Self {
            spheres: (0..s.len()).map(|i| (wide(s.center(i)), f64::from(s.r[i]))).collect(),
            kinds: g.kinds.widened(),
            kinds_base: g.kinds_base() as u32,
        }
    }

    /// Primitive `prim`'s index over the registered kinds' items, when it is one.
    fn kind(&self, prim: u32) -> Option<usize> {
        let k = prim.checked_sub(self.kinds_base)? as usize;
        (k < self.kinds.len()).then_some(k)
    }

    /// The hit of `ray` with primitive `prim` alone, in `[0, inf)`.
    pub fn hit_of(&self, prim: u32, ray: &Ray<f64>) -> Option<f64> {
        let i = prim as usize;
        if let Some(k) = self.kind(prim) {
            return self.kinds.hit_of(k, ray);
        }
        let &(centre, radius) = self.spheres.get(i)?;
        sphere::twin::hit(centre, radius, ray, f64::INFINITY)
    }

    /// Closest hit `(prim, t)`, skipping `skip` entirely (an outward departure), `NO_PRIM` on a miss.
    pub fn closest(&self, ray: &Ray<f64>, skip: u32) -> (u32, f64) {
        let mut best = (NO_PRIM, f64::INFINITY);
        for (i, &(c, r)) in self.spheres.iter().enumerate() {
            match sphere::twin::hit(c, r, ray, best.1) {
                Some(t) if i as u32 != skip => best = (i as u32, t),
                _ => {}
            }
        }
        self.kinds.intersect(self.kinds_base, skip, ray, f64::INFINITY, &mut best);
        best
    }

    /// True when `ray` starts within `k` f32 roundings of the surface of solid `prim` (its near root is
    /// within `k·ε·(|c − o| + r)/|d|` of zero): at the contact point of touching spheres a ray leaving one
    /// sphere starts on the other, and whether it enters at t ≈ 0 or is already inside is decided by
    /// rounding. For a registered kind's item: the origin lies within `k` roundings of its scale of the
    /// surface.
    pub fn starts_on(&self, prim: u32, ray: &Ray<f64>, k: f64) -> bool {
        if let Some(item) = self.kind(prim) {
            return self.kinds.near(item, ray.origin, k * EPS32, 0.0).unwrap_or(false);
        }
        let i = prim as usize;
        if prim == NO_PRIM || i >= self.spheres.len() {
            return false;
        }
        let (c, r) = self.spheres[i];
        let roots = sphere_roots(c, r, ray);
        let scale = ((dv(c) - dv(ray.origin)).length() + r) / dv(ray.dir).length();
        roots.hit && roots.near.abs() <= k * EPS32 * scale
    }

    /// True when `ray` passes within `k` f32 roundings (of the coordinates involved) of tangency with `prim`:
    /// for a sphere, the line's distance l from the centre differs from the radius by at most
    /// `k·ε·(|c − o| + r)`; a registered kind's item (ellipsoids and planes among them): its own rule
    /// ([`bareray::kinds::Kind::grazing64`]) for `k` roundings. That is where the f32 and f64 kernels may
    /// legitimately disagree on hit or miss.
    pub fn grazing(&self, prim: u32, ray: &Ray<f64>, k: f64) -> bool {
        if prim == NO_PRIM {
            return false;
        }
        if let Some(item) = self.kind(prim) {
            return self.kinds.grazing(item, ray, k * EPS32, Stray::default()).unwrap_or(false);
        }
        let Some(&(c, r)) = self.spheres.get(prim as usize) else { return false };
        sphere::twin::grazing(c, r, ray, k * EPS32, Stray::default())
    }
}
