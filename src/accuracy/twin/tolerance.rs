//! The twin's tolerances: how far f32 rounding can move a ray near a primitive, and the rules that
//! explain an f32/f64 disagreement by it (grazing, ties in t, contact entries, starts near a surface).

use super::{len, Hit64, Slack, Twin, EPS32};
use crate::geometry::{Departure, Ray, NO_PRIM};
use crate::kinds::sphere;
use crate::math::V3;

impl Twin {
    /// True when `ray` passes within tolerance of tangency with `prim` — where an f32 and an f64 kernel may
    /// legitimately disagree on hit or miss (explanation "graze"):
    ///
    /// - spheres: the line's closest approach l to the centre satisfies `|l − r| ≤ k·ε32·(|c − o| + r)` plus
    ///   `slack` at that distance;
    /// - polygons: the direction is within that of parallel to the plane, or the line meets the plane within
    ///   `k·ε32·(|o| + |p|)` (plus slack, over the cosine of incidence) of the outline;
    /// - cones: a nudge of the line by `δ = k·ε32·(|o| + |B − o| + h + max(r0, r1))` plus slack can change
    ///   hit or miss, in one of two ways (`cone_grazing`): the line is within `δ` of tangency with the
    ///   quadric where its roots would lie between the end planes (two roots merge or appear), or it meets
    ///   the quadric in front of the origin within `δ` (over the cosine of incidence) of an end plane (a root
    ///   crosses the rim, as a polygon's hit crosses an edge);
    /// - the other registered kinds: their own rules ([`crate::kinds::Kind::grazing64`]; ellipsoids: the
    ///   sphere's test in object space, with the scale `Σ|L_i|·(|o_i| + |c_i|) + 1`, L the object-from-world
    ///   map, whose f32 rounding the object-space ray carries; planes: the object-space direction is within
    ///   `k·ε32`, plus the direction slack, of parallel).
    pub(crate) fn grazing(&self, prim: u32, ray: &Ray<f64>, k: f64, slack: Slack) -> bool {
        if prim == NO_PRIM || prim as usize >= self.len() {
            return false;
        }
        let tol = k * EPS32;
        if let Some(&(c, r)) = self.spheres.get(prim as usize) {
            return sphere::twin::grazing(c, r, ray, tol, slack);
        }
        match self.kind(prim) {
            Some(k) => self.kinds.grazing(k, ray, tol, slack).unwrap_or(false),
            None => false,
        }
    }

    /// True when `ray` (leaving `from`) meets both `a` and `b` in f64 so close together that a ray moved by
    /// rounding, `k·ε32·(|o| + t)`, plus `slack` (how far the f32 ray strays) can meet them in the other
    /// order (explanation "tie").
    ///
    /// To first order, moving a ray by `δ` (its point at `t` by `δ(t)`) moves its hit on a surface with unit
    /// normal `n` by `−(n·δ)/(n·d)` along it: by up to `|δ|/|cos|`, `cos` the cosine of incidence. A common
    /// displacement (the stray of the f32 ray from the f64 one) moves `ta − tb` by `δ·g`, `g = n_a/(n_a·d) −
    /// n_b/(n_b·d)`; each kernel's own rounding, a displacement of its own, moves its `t` by it over its
    /// `|cos|`. So the order can change when `|ta − tb| ≤ (k·ε32·(|o| + t) + slack)·w`, with the weight
    /// `w = max(|g|, mean of 1/|cos_a| and 1/|cos_b|)`: 1 where both are met head on; at a slant on planes
    /// crossing near the hits `t` moves by many times the displacement (graze takes over where a cosine is
    /// within rounding of 0).
    pub(crate) fn tie(&self, a: u32, b: u32, ray: &Ray<f64>, from: Departure, k: f64, slack: Slack) -> bool {
        let (Some(ta), Some(tb)) = (self.hit_of(a, ray, from), self.hit_of(b, ray, from)) else {
            return false;
        };
        let t = ta.max(tb);
        // n/(n·d): the hit's move along the ray per unit displacement, as a vector.
        let rate = |prim: u32, tp: f64| {
            let n = self.geometric_normal(ray, tp, prim);
            n * (1.0 / n.dot(ray.dir))
        };
        let (ga, gb) = (rate(a, ta), rate(b, tb));
        let w = len(ga - gb).max(0.5 * (len(ga) + len(gb)));
        (ta - tb).abs() <= (k * EPS32 * (len(ray.origin) + t) + slack.at(t)) * w
    }

    /// True when the f32 renderer's `hit` along its own f32 `ray` is the sphere contact rule's entry
    /// ([`sphere::twin::contact_entry`]): a sphere met at exactly `t = 0` by a ray heading toward its centre
    /// from within the rule's band of its surface. Such a hit is the renderer treating the origin as on that
    /// sphere, not a re-hit of the surface the ray leaves.
    pub(crate) fn contact_entry(&self, hit: Hit64, ray: &Ray<f32>) -> bool {
        let Some(&(centre, r)) = self.spheres.get(hit.prim as usize) else { return false };
        hit.t == 0.0 && sphere::twin::contact_entry(centre, r, ray.origin.to_f64(), ray.dir.to_f64())
    }

    /// True when point `p` lies within tolerance of `prim`'s surface: `k·ε32·(|p| + |c − p| + r)` plus
    /// `slack` for spheres, the distance to the plane for polygons, and each registered kind's own rule
    /// ([`crate::kinds::Kind::near64`]: the object-space equivalent for ellipsoids and planes; for cones the
    /// distance to the lateral surface within `k·ε32` of their scale). This is where a ray that starts at `p`
    /// (a secondary ray's origin on another primitive, explanation "start"), or a shadow ray that ends there
    /// (the light, explanation "light"), can find or miss `prim` by rounding.
    pub(crate) fn near_surface(&self, prim: u32, p: V3<f64>, k: f64, slack: f64) -> bool {
        if prim == NO_PRIM || prim as usize >= self.len() {
            return false;
        }
        let tol = k * EPS32;
        if let Some(&(c, r)) = self.spheres.get(prim as usize) {
            return sphere::twin::near(c, r, p, tol, slack);
        }
        self.kind(prim).and_then(|k| self.kinds.near(k, p, tol, slack)).unwrap_or(false)
    }
}
