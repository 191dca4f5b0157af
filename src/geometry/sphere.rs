//! Ray/sphere intersection: the lecture's five cases in a numerically stable form.
//!
//! With `oc = centre − origin`, `proj = (oc·d)/(d·d)` is the parameter of the point on the line closest to
//! the centre and `l² = |oc − proj·d|²` its squared distance. The line misses when `l² > r²` (case 1),
//! touches when equal (case 2), and otherwise has roots `proj ± td`, `td = sqrt((r² − l²)/(d·d))`. Of the
//! roots, the smallest one at or after the ray's start is taken: both ahead (case 3) gives the near one,
//! origin inside (case 4) the far one (an exit hit, whose normal the shader flips), both behind (case 5) a
//! miss.
//!
//! Three choices keep the f32 results accurate at every scale (ARCHITECTURE.md, "Numerics"):
//!
//! - **Perpendicular discriminant.** `r² − l²` instead of the textbook `b² − 4ac`, which subtracts two
//!   nearly equal large numbers for small distant spheres (Haines et al., Ray Tracing Gems ch. 7).
//! - **Vieta's near root.** Only the root of larger magnitude, `proj + sign(proj)·td`, is computed directly;
//!   the other is `c/(d·d)` divided by it, with `c = |oc|² − r²`, the product of the roots times `d·d`.
//!   `proj − td` would cancel for a large sphere seen from close by.
//! - **Exact eye terms.** Camera rays start at the rendering space's origin (the eye), so `c` does not
//!   depend on the ray: compile computes it per sphere in f64 from the scene file's values and rounds it
//!   once ([`roots_from_eye`](Approach::roots_from_eye)). With an exact `c` the discriminant
//!   `proj² − c/(d·d)` is also available; it is chosen per lane where its rounding bound is the smaller one
//!   (the eye close to a large sphere, where `l²` carries the f32 rounding of a far-away centre).
//!
//! For rays from anywhere else (secondary rays) `c` is computed in f32, and a sphere whose surface passes
//! within `c`'s rounding bound of the ray's origin is treated as touching it there (the **contact rule**):
//! a ray heading into it enters at `t = 0`, a ray heading away misses it. At the contact point of touching
//! spheres the origin is then on the neighbour's surface, never a few ulps inside it.

use crate::math::{Mask, Real, V3};

use super::Ray;

/// The contact rule's tolerance on `c = |oc|² − r²`, in units of the float format's rounding (2⁻²⁴ in f32) of
/// `|oc|² + r² + 2·r·|origin|∞`. The f32 evaluation of `c` (rounding `oc`, its dot product, `r²` and the
/// difference) is off by about 5 roundings of `|oc|² + r²`; a hit point used as the origin (`o + t·d` in
/// f32) is off by a few roundings of its own size, which moves `c` by up to `2·r` per unit near the
/// surface. 8 covers both with room to spare and keeps the band at a contact point a few ulps wide.
pub const CONTACT_ROUNDINGS: f64 = 8.0;

/// A ray with the per-ray terms every sphere test shares, computed once per query.
#[derive(Clone, Copy, Debug)]
pub struct SphereRay<F: Real> {
    /// The ray.
    pub ray: Ray<F>,
    dd: F,
    inv_dd: F,
    /// `CONTACT_ROUNDINGS` units of roundoff, splatted once.
    contact: F,
    /// `2·|origin|∞`, the origin's share of the contact tolerance.
    reach2: F,
}

impl<F: Real> SphereRay<F> {
    /// The terms of `ray`.
    #[inline(always)]
    pub fn new(ray: Ray<F>) -> Self {
        let d = ray.dir;
        let dd = d.dot(d);
        let o = ray.origin;
        let reach = o.x.abs().max_of(o.y.abs()).max_of(o.z.abs());
        Self {
            ray,
            dd,
            inv_dd: F::splat(1.0) / dd,
            contact: F::splat(CONTACT_ROUNDINGS * F::UNIT_ROUNDOFF),
            reach2: reach + reach,
        }
    }

    /// The lanes whose ray starts exactly at the origin of the rendering space (the eye).
    #[inline(always)]
    pub fn from_eye(&self) -> F::Mask {
        let zero = F::splat(0.0);
        let at_zero = |v: F| v.le(zero) & v.ge(zero);
        let o = self.ray.origin;
        at_zero(o.x) & at_zero(o.y) & at_zero(o.z)
    }
}

/// Which lanes of a query start at the eye and may use the spheres' exact eye terms.
#[derive(Clone, Copy, Debug)]
pub enum EyeLanes<M> {
    /// No lane: every `c` is computed.
    None,
    /// Every live lane (camera rays).
    All,
    /// Some lanes: both forms are evaluated and chosen per lane.
    Some(M),
}

impl<M: Mask> EyeLanes<M> {
    /// Classifies the lanes `eye` of the `live` ones.
    #[inline(always)]
    pub fn of(eye: M, live: M) -> Self {
        if (eye | !live).all() {
            EyeLanes::All
        } else if (eye & live).any() {
            EyeLanes::Some(eye)
        } else {
            EyeLanes::None
        }
    }
}

/// The two roots of a ray and a sphere, valid only where `hit` is set.
#[derive(Clone, Copy, Debug)]
pub struct Roots<F: Real> {
    /// The line meets the sphere (`l² ≤ r²`) and the contact rule does not rule it out; NaN inputs give
    /// false.
    pub hit: F::Mask,
    /// The entry parameter.
    pub near: F,
    /// The exit parameter.
    pub far: F,
}

/// Where a ray's line passes a sphere: enough to know whether it meets it, before any square root.
#[derive(Clone, Copy, Debug)]
pub struct Approach<F: Real> {
    oc: V3<F>,
    proj: F,
    l2: F,
    r: F,
    r2: F,
    dd: F,
    inv_dd: F,
    contact: F,
    reach2: F,
}

impl<F: Real> Approach<F> {
    /// The line meets the sphere (`l² ≤ r²`); NaN inputs give false.
    #[inline(always)]
    pub fn meets(&self) -> F::Mask {
        self.l2.le(self.r2)
    }

    /// The two roots for a ray from anywhere: `c` computed in f32, the perpendicular discriminant, the
    /// contact rule.
    #[inline(always)]
    pub fn roots(&self) -> Roots<F> {
        let oo = self.oc.dot(self.oc);
        let c = oo - self.r2;
        let tol = self.contact * (oo + self.r2 + self.r * self.reach2);
        let on_surface = c.abs().le(tol);
        let ahead = self.proj.ge(F::splat(0.0));
        let c = F::select(on_surface, F::splat(0.0), c);
        let roots = self.roots_with(c, (self.r2 - self.l2) * self.inv_dd, ahead);
        Roots { hit: roots.hit & !(on_surface & !ahead), ..roots }
    }

    /// The two roots for a ray that starts exactly at the eye, given the sphere's exact `c_eye =
    /// |centre − eye|² − r²`: of the two discriminants, `(r² − l²)/(d·d)` and `proj² − c/(d·d)`, the one whose
    /// rounding bound is smaller — `ε·|oc|·r` against `ε·(proj²·(d·d) + |c|)`, compared squared (`|oc|² = c +
    /// r²`).
    #[inline(always)]
    pub fn roots_from_eye(&self, c_eye: F) -> Roots<F> {
        let ahead = self.proj.ge(F::splat(0.0));
        let pp = self.proj * self.proj;
        let textbook_err = pp * self.dd + c_eye.abs();
        let textbook = (textbook_err * textbook_err).lt((c_eye + self.r2) * self.r2);
        let disc = F::select(textbook, pp - c_eye * self.inv_dd, (self.r2 - self.l2) * self.inv_dd);
        self.roots_with(c_eye, disc, ahead)
    }

    /// [`Approach::roots_from_eye`] in the lanes of `eye`, [`Approach::roots`] in the others.
    #[inline(always)]
    pub fn roots_for(&self, c_eye: F, eye: EyeLanes<F::Mask>) -> Roots<F> {
        match eye {
            EyeLanes::None => self.roots(),
            EyeLanes::All => self.roots_from_eye(c_eye),
            EyeLanes::Some(m) => {
                let (a, b) = (self.roots_from_eye(c_eye), self.roots());
                Roots {
                    hit: (m & a.hit) | (!m & b.hit),
                    near: F::select(m, a.near, b.near),
                    far: F::select(m, a.far, b.far),
                }
            }
        }
    }

    /// The roots from `c` and the discriminant `td² = disc`: the root of larger magnitude directly, the
    /// other by Vieta (`near·far = c/(d·d)`).
    #[inline(always)]
    fn roots_with(&self, c: F, disc: F, ahead: F::Mask) -> Roots<F> {
        let td = disc.sqrt();
        let big = F::select(ahead, self.proj + td, self.proj - td);
        // A tangent line has the double root `proj` (Vieta's quotient would round it differently, or be
        // 0/0 for a ray tangent at its own origin).
        let small = F::select(td.gt(F::splat(0.0)), (c * self.inv_dd) / big, big);
        Roots { hit: self.meets(), near: F::select(ahead, small, big), far: F::select(ahead, big, small) }
    }
}

/// The closest approach of the ray's line to the sphere's centre.
#[inline(always)]
pub fn sphere_approach<F: Real>(centre: V3<F>, radius: F, ray: &SphereRay<F>) -> Approach<F> {
    let d = ray.ray.dir;
    let oc = centre - ray.ray.origin;
    let proj = oc.dot(d) * ray.inv_dd;
    let perp = oc - d * proj;
    Approach {
        oc,
        proj,
        l2: perp.dot(perp),
        r: radius,
        r2: radius * radius,
        dd: ray.dd,
        inv_dd: ray.inv_dd,
        contact: ray.contact,
        reach2: ray.reach2,
    }
}

/// The roots of `|origin + t·dir − centre|² = radius²` for a ray from anywhere ([`Approach::roots`]).
#[inline(always)]
pub fn sphere_roots<F: Real>(centre: V3<F>, radius: F, ray: &Ray<F>) -> Roots<F> {
    sphere_approach(centre, radius, &SphereRay::new(*ray)).roots()
}

/// The smallest root in `[0, t_max)`, or `None` (the mask is false): cases 3 and 4 hit, 1 and 5 miss.
#[inline(always)]
pub fn first_root<F: Real>(roots: &Roots<F>, t_max: F) -> (F::Mask, F) {
    let zero = F::splat(0.0);
    let t = F::select(roots.near.ge(zero), roots.near, roots.far);
    (roots.hit & t.ge(zero) & t.lt(t_max), t)
}

/// The exit root in `[0, t_max)`: for a ray that starts on the sphere and heads inside, whose entry root is
/// its own origin.
#[inline(always)]
pub fn far_root<F: Real>(roots: &Roots<F>, t_max: F) -> (F::Mask, F) {
    let zero = F::splat(0.0);
    (roots.hit & roots.far.ge(zero) & roots.far.lt(t_max), roots.far)
}

/// Closest hit of one ray with one sphere in `[0, t_max)`.
#[inline(always)]
pub fn intersect_sphere<F: Real>(centre: V3<F>, radius: F, ray: &Ray<F>, t_max: F) -> (F::Mask, F) {
    first_root(&sphere_roots(centre, radius, ray), t_max)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ray(o: [f64; 3], d: [f64; 3]) -> Ray<f64> {
        Ray::new(V3::new(o[0], o[1], o[2]), V3::new(d[0], d[1], d[2]))
    }
    const C: V3<f64> = V3::new(0.0, 0.0, 5.0);
    const INF: f64 = f64::INFINITY;

    #[test]
    fn case1_line_misses() {
        let (hit, _) = intersect_sphere(C, 1.0, &ray([0.0, 2.0, 0.0], [0.0, 0.0, 1.0]), INF);
        assert!(!hit);
    }

    #[test]
    fn case2_tangent_line_touches_once() {
        let r = sphere_roots(C, 1.0, &ray([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]));
        assert!(r.hit);
        assert_eq!(r.near, 5.0);
        assert_eq!(r.far, 5.0);
    }

    #[test]
    fn case3_both_roots_ahead_gives_the_near_one() {
        // Direction of length 2: t is in units of the direction, so the hit at distance 4 is t = 2.
        let (hit, t) = intersect_sphere(C, 1.0, &ray([0.0, 0.0, 0.0], [0.0, 0.0, 2.0]), INF);
        assert!(hit);
        assert_eq!(t, 2.0);
    }

    #[test]
    fn case4_origin_inside_gives_the_exit() {
        let (hit, t) = intersect_sphere(C, 1.0, &ray([0.0, 0.0, 5.5], [0.0, 0.0, 1.0]), INF);
        assert!(hit);
        assert_eq!(t, 0.5);
        let (hit, t) = intersect_sphere(C, 1.0, &ray([0.0, 0.0, 5.5], [0.0, 0.0, -1.0]), INF);
        assert!(hit);
        assert_eq!(t, 1.5);
    }

    #[test]
    fn case5_sphere_behind_misses() {
        let (hit, _) = intersect_sphere(C, 1.0, &ray([0.0, 0.0, 7.0], [0.0, 0.0, 1.0]), INF);
        assert!(!hit);
    }

    #[test]
    fn t_max_excludes_farther_hits() {
        let r = ray([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
        assert!(!intersect_sphere(C, 1.0, &r, 4.0).0);
        assert!(intersect_sphere(C, 1.0, &r, 4.000001).0);
    }

    #[test]
    fn nan_and_zero_directions_miss() {
        for d in [[f64::NAN, 0.0, 1.0], [0.0, 0.0, 0.0], [INF, 0.0, 0.0]] {
            assert!(!intersect_sphere(C, 1.0, &ray([0.0, 0.0, 0.0], d), INF).0, "{d:?}");
        }
    }

    #[test]
    fn small_distant_sphere_survives_in_f32() {
        // 1e5 radii away: the textbook discriminant loses this sphere in f32, the perpendicular form keeps it.
        let c = V3::new(0.0f32, 0.0, 1.0e5);
        let r = Ray::new(V3::new(0.0f32, 0.5, 0.0), V3::new(0.0, 0.0, 1.0));
        let (hit, t) = intersect_sphere(c, 1.0, &r, f32::INFINITY);
        assert!(hit);
        let exact = 1.0e5 - (1.0f64 - 0.25).sqrt();
        assert!(((t as f64) - exact).abs() / exact < 1e-6, "t = {t}");
    }
}
