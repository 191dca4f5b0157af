//! Ray/sphere intersection: the lecture's five cases in a numerically stable form, and the exact eye terms
//! of spheres (`eye_term`, `eye_side`: the sign that says whether the eye is inside).
//!
//! With `oc = centre − origin`, `proj = (oc·d)/(d·d)` is the parameter of the point on the line closest to
//! the centre and `l² = |oc − proj·d|²` its squared distance. The line misses when `l² > r²` (case 1),
//! touches when equal (case 2), and otherwise has roots `proj ± td`, `td = sqrt((r² − l²)/(d·d))`. Of the
//! roots, the smallest one at or after the ray's start is taken: both ahead (case 3) gives the near one,
//! origin inside (case 4) the far one (an exit hit, whose normal the shader flips), both behind (case 5) a
//! miss.
//!
//! Four choices keep the f32 results accurate at every scale (ARCHITECTURE.md, "Numerics"):
//!
//! - **Perpendicular discriminant.** `r² − l²` instead of the textbook `b² − 4ac`, which subtracts two
//!   nearly equal large numbers for small distant spheres (Haines et al., Ray Tracing Gems ch. 7). Each
//!   component of `oc − d·proj` is one fused multiply-add: a separately rounded product leaves about
//!   `ε·|oc|·r` of error in `l²`, a large share of a small distant sphere's `r²`.
//! - **Vieta's near root.** Only the root of larger magnitude, `proj + sign(proj)·td`, is computed directly;
//!   the other is `c/(d·d)` divided by it, with `c = |oc|² − r²` (the product of the roots is `c/(d·d)`).
//!   `proj − td` would cancel for a large sphere seen from close by.
//! - **Exact eye terms.** Compile computes each sphere's `c_eye = |centre|² − r²` (the eye is the rendering
//!   space's origin) in f64 from the scene file's values and rounds it once. For a camera ray it is `c`
//!   itself; for a ray from `o` it gives `c = c_eye − (2·centre·o − |o|²)`, whose rounding is about
//!   `ε·(|c_eye| + |centre|·|o|)` against `ε·(|oc|² + r²)` for `|oc|² − r²` in f32: far smaller near a large
//!   sphere close to the eye (a ground sphere), where `|oc|²` is huge. In scenes with such a sphere each
//!   lane takes the `c` with the smaller bound ([`Approach::roots_with_eye_term`]); elsewhere the direct
//!   one always is, within a small factor ([`sphere_roots_of`] applies the rule).
//! - **Discriminant by bound.** With an accurate `c`, `proj² − c/(d·d)` is also available; in scenes with a
//!   sphere near the eye each lane takes it where its rounding bound `ε·(proj²·(d·d) + bound(c))` is below
//!   the perpendicular form's `ε·|oc|·r` (compared squared). That is a ray from near a large sphere, whose
//!   `l²` carries the f32 rounding of a far-away centre (in `oc` itself: the stored centre and `centre −
//!   origin`, which the fused `perp` does not remove).
//!
//! For rays that do not start at the eye, a sphere whose surface passes within `c`'s rounding bound of the
//! ray's origin is treated as touching it there (the **contact rule**): a ray heading into it enters at
//! `t = 0`, a ray heading away misses it. At the contact point of touching spheres the origin is then on the
//! neighbour's surface, never a few ulps inside it.

use crate::math::{Real, V3};

use super::Ray;

/// The contact rule's tolerance on `c = |oc|² − r²`, in units of the float format's rounding (2⁻²⁴ in f32) of
/// `bound(c) + 2·r·|origin|∞`, where `bound(c)` is the magnitude whose rounding `c` carries (`|oc|² + r²`
/// computed directly; `|c_eye| + 8·|centre|·|o| + 2·|o|²` from the eye term). The evaluation of `c` is off by
/// about 5 roundings of its bound; a hit point used as the origin (`o + t·d` in f32) is off by a few
/// roundings of its own size, which moves `c` by up to `2·r` per unit near the surface. 8 covers both with
/// room to spare and keeps the band at a contact point a few ulps wide.
pub(crate) const CONTACT_ROUNDINGS: f64 = 8.0;

/// A ray with the per-ray terms every sphere test shares, computed once per query.
#[derive(Clone, Copy, Debug)]
pub struct SphereRay<F: Real> {
    /// The ray.
    pub(crate) ray: Ray<F>,
    dd: F,
    inv_dd: F,
    /// `|origin|²` and the origin's absolute coordinates, for `c` from the eye term.
    oo: F,
    abs_origin: V3<F>,
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
        let abs_origin = V3::new(o.x.abs(), o.y.abs(), o.z.abs());
        let reach = abs_origin.x.max_of(abs_origin.y).max_of(abs_origin.z);
        Self {
            ray,
            dd,
            inv_dd: F::splat(1.0) / dd,
            oo: o.dot(o),
            abs_origin,
            contact: F::splat(CONTACT_ROUNDINGS * F::UNIT_ROUNDOFF),
            reach2: reach + reach,
        }
    }

    /// The same terms with every value mapped by `f` (a lane of a packet's, or a single ray's splatted):
    /// no arithmetic, so the mapped terms are the bits the mapped ray's own would be.
    #[inline(always)]
    pub(crate) fn map<G: Real>(&self, f: impl Fn(F) -> G + Copy) -> SphereRay<G> {
        SphereRay {
            ray: Ray::new(self.ray.origin.map(f), self.ray.dir.map(f)),
            dd: f(self.dd),
            inv_dd: f(self.inv_dd),
            oo: f(self.oo),
            abs_origin: self.abs_origin.map(f),
            contact: f(self.contact),
            reach2: f(self.reach2),
        }
    }

    /// The lanes whose ray starts exactly at the origin of the rendering space (the eye).
    #[inline(always)]
    #[allow(clippy::wrong_self_convention)] // asks whether the rays start at the eye: not a constructor
    pub(crate) fn from_eye(&self) -> F::Mask {
        at_eye(self.ray.origin)
    }

    /// The same direction terms for a ray from `origin` (only the origin's terms are recomputed).
    #[inline(always)]
    pub(crate) fn with_origin(&self, origin: V3<F>) -> Self {
        let abs_origin = V3::new(origin.x.abs(), origin.y.abs(), origin.z.abs());
        let reach = abs_origin.x.max_of(abs_origin.y).max_of(abs_origin.z);
        Self {
            ray: Ray::new(origin, self.ray.dir),
            oo: origin.dot(origin),
            abs_origin,
            reach2: reach + reach,
            ..*self
        }
    }
}

/// The lanes where `origin` is exactly the origin of the rendering space (the eye).
#[inline(always)]
pub(crate) fn at_eye<F: Real>(origin: V3<F>) -> F::Mask {
    let zero = F::splat(0.0);
    let at_zero = |v: F| v.le(zero) & v.ge(zero);
    at_zero(origin.x) & at_zero(origin.y) & at_zero(origin.z)
}

/// Which lanes of a query start at the eye and take [`Approach::roots_from_eye`].
#[derive(Clone, Copy, Debug)]
pub(crate) enum EyeLanes<M> {
    /// No lane.
    None,
    /// Every live lane (camera rays).
    All,
    /// Some lanes (a secondary ray starting exactly at the eye): both forms are evaluated and chosen per
    /// lane, so each lane gets what it gets alone.
    Some(M),
}

impl<M: crate::math::Mask> EyeLanes<M> {
    /// Classifies the lanes `eye` of the `live` ones.
    #[inline(always)]
    pub(crate) fn of(eye: M, live: M) -> Self {
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
    pub(crate) hit: F::Mask,
    /// The entry parameter.
    pub(crate) near: F,
    /// The exit parameter.
    pub(crate) far: F,
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
    pub(crate) fn meets(&self) -> F::Mask {
        self.l2.le(self.r2)
    }

    /// The two roots with `c = |oc|² − r²` computed directly (ellipsoids in object space, and spheres in
    /// scenes where the eye term cannot help: [`crate::kinds::sphere::Spheres::eye_terms_help`]). The
    /// perpendicular discriminant: with this `c` its bound is always the smaller one, so this is
    /// [`Approach::roots_with_eye_term`]'s result whenever that one takes the direct `c`.
    #[inline(always)]
    pub(crate) fn roots(&self) -> Roots<F> {
        let oo = self.oc.dot(self.oc);
        let (c, bound) = (oo - self.r2, oo + self.r2);
        let (on_surface, ahead) = self.contact(c, bound, self.reach2);
        self.roots_with(c, (self.r2 - self.l2) * self.inv_dd, on_surface, ahead)
    }

    /// The two roots for a ray from anywhere, given the sphere's centre and exact eye term `c_eye =
    /// |centre|² − r²`: `c` from the eye term or computed directly, whichever has the smaller rounding
    /// bound.
    #[inline(always)]
    pub(crate) fn roots_with_eye_term(&self, centre: V3<F>, c_eye: F, ray: &SphereRay<F>) -> Roots<F> {
        let co = centre.dot(ray.ray.origin);
        let abs_co = V3::new(centre.x.abs(), centre.y.abs(), centre.z.abs()).dot(ray.abs_origin);
        let c = c_eye - ((co + co) - ray.oo);
        let bound = c_eye.abs() + F::splat(8.0) * abs_co + F::splat(2.0) * ray.oo;
        let oo = self.oc.dot(self.oc);
        let direct_bound = oo + self.r2;
        let from_eye_term = bound.le(direct_bound);
        let c = F::select(from_eye_term, c, oo - self.r2);
        // The origin whose rounding the contact rule allows for: the one `c` was computed from.
        let reach2 = F::select(from_eye_term, ray.reach2, self.reach2);
        self.roots_from(c, F::select(from_eye_term, bound, direct_bound), oo, reach2)
    }

    /// The two roots for a ray that starts exactly at the eye: `c = c_eye`. `choose` (the scene's
    /// `Spheres::eye_terms_help`) lets each lane take `proj² − c/(d·d)` where its bound is
    /// the smaller; without a sphere that near the eye the perpendicular form always is (the textbook bound
    /// `ε·|c_eye|` alone exceeds `ε·|C|·r` once the eye is 1.6 radii from the centre). No contact rule: the
    /// eye is a point the scene places, not a rounded hit point.
    #[inline(always)]
    pub fn roots_from_eye(&self, c_eye: F, choose: bool) -> Roots<F> {
        let zero = F::splat(0.0);
        let perp = (self.r2 - self.l2) * self.inv_dd;
        let disc = if choose {
            let pp = self.proj * self.proj;
            let textbook_err = pp * self.dd + c_eye.abs();
            // `|C|² = c_eye + r²`: the eye is the origin.
            let textbook = (textbook_err * textbook_err).lt((c_eye + self.r2) * self.r2);
            F::select(textbook, pp - c_eye * self.inv_dd, perp)
        } else {
            perp
        };
        self.roots_with(c_eye, disc, zero.lt(zero), self.proj.ge(zero))
    }

    /// [`Approach::roots_from_eye`] in the lanes of `eye`, `other` (the roots of the other lanes' rays) in
    /// the rest.
    #[inline(always)]
    pub(crate) fn select_eye_lanes(eye: F::Mask, from_eye: Roots<F>, other: Roots<F>) -> Roots<F> {
        Roots {
            hit: (eye & from_eye.hit) | (!eye & other.hit),
            near: F::select(eye, from_eye.near, other.near),
            far: F::select(eye, from_eye.far, other.far),
        }
    }

    /// The roots from `c` (rounding bound `bound`; `oo = |oc|²`; `reach2` as [`Approach::contact`] takes it):
    /// the discriminant with the smaller bound, the contact rule, then [`Approach::roots_with`].
    #[inline(always)]
    fn roots_from(&self, c: F, bound: F, oo: F, reach2: F) -> Roots<F> {
        let (on_surface, ahead) = self.contact(c, bound, reach2);
        let pp = self.proj * self.proj;
        let textbook_err = pp * self.dd + bound;
        let textbook = (textbook_err * textbook_err).lt(oo * self.r2);
        let disc = F::select(textbook, pp - c * self.inv_dd, (self.r2 - self.l2) * self.inv_dd);
        self.roots_with(c, disc, on_surface, ahead)
    }

    /// The contact rule's two facts: the origin is on the surface within `c`'s rounding (`bound`, and
    /// `reach2` = 2·|origin|∞ of the origin `c` was computed from), and the ray heads toward the centre's
    /// side (`proj ≥ 0`).
    #[inline(always)]
    fn contact(&self, c: F, bound: F, reach2: F) -> (F::Mask, F::Mask) {
        let tol = self.contact * (bound + self.r * reach2);
        (c.abs().le(tol), self.proj.ge(F::splat(0.0)))
    }

    /// The roots from `c` and the discriminant `td² = disc`: the root of larger magnitude directly, the
    /// other by Vieta (`near·far = c/(d·d)`); a ray starting on the surface (`on_surface`) enters at 0 when
    /// heading in and misses when heading away.
    #[inline(always)]
    fn roots_with(&self, c: F, disc: F, on_surface: F::Mask, ahead: F::Mask) -> Roots<F> {
        let c = F::select(on_surface, F::splat(0.0), c);
        let td = disc.sqrt();
        let big = F::select(ahead, self.proj + td, self.proj - td);
        // A tangent line has the double root `proj` (Vieta's quotient would round it differently, or be
        // 0/0 for a ray tangent at its own origin).
        let small = F::select(td.gt(F::splat(0.0)), (c * self.inv_dd) / big, big);
        Roots {
            hit: self.meets() & !(on_surface & !ahead),
            near: F::select(ahead, small, big),
            far: F::select(ahead, big, small),
        }
    }
}

/// The closest approach of the ray's line to the sphere's centre.
#[inline(always)]
pub fn sphere_approach<F: Real>(centre: V3<F>, radius: F, ray: &SphereRay<F>) -> Approach<F> {
    let d = ray.ray.dir;
    let oc = centre - ray.ray.origin;
    let proj = oc.dot(d) * ray.inv_dd;
    // Each component rounded once: with the product `d·proj` rounded on its own, `l` carries about ε·|oc| of
    // error, a large share of a small distant sphere's radius (see the module documentation).
    let perp = V3::new((-d.x).mul_add(proj, oc.x), (-d.y).mul_add(proj, oc.y), (-d.z).mul_add(proj, oc.z));
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

/// A stored sphere's roots for the rays of a query, the one rule every sphere query follows: lanes from the
/// eye take [`Approach::roots_from_eye`] (choosing the discriminant when `help`, the scene's
/// `Spheres::eye_terms_help`, says a sphere is near the eye), the others `Approach::roots_with_eye_term`
/// in such scenes and `Approach::roots` elsewhere. `centre` is only evaluated where it is needed.
#[inline(always)]
pub(crate) fn sphere_roots_of<F: Real>(
    help: bool,
    line: &Approach<F>,
    centre: impl Fn() -> V3<F>,
    c_eye: F,
    ray: &SphereRay<F>,
    eye: EyeLanes<F::Mask>,
) -> Roots<F> {
    let other = || if help { line.roots_with_eye_term(centre(), c_eye, ray) } else { line.roots() };
    match eye {
        EyeLanes::All => line.roots_from_eye(c_eye, help),
        EyeLanes::None => other(),
        EyeLanes::Some(m) => Approach::select_eye_lanes(m, line.roots_from_eye(c_eye, help), other()),
    }
}

/// The roots of `|origin + t·dir − centre|² = radius²` for a ray from anywhere, with no eye term
/// (`Approach::roots`).
#[inline(always)]
pub(crate) fn sphere_roots<F: Real>(centre: V3<F>, radius: F, ray: &Ray<F>) -> Roots<F> {
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
pub(crate) fn far_root<F: Real>(roots: &Roots<F>, t_max: F) -> (F::Mask, F) {
    let zero = F::splat(0.0);
    (roots.hit & roots.far.ge(zero) & roots.far.lt(t_max), roots.far)
}

/// Closest hit of one ray with one sphere in `[0, t_max)`.
#[inline(always)]
pub fn intersect_sphere<F: Real>(centre: V3<F>, radius: F, ray: &Ray<F>, t_max: F) -> (F::Mask, F) {
    first_root(&sphere_roots(centre, radius, ray), t_max)
}

/// `|centre|² − r²` for a sphere in rendering space (the eye at the origin), as
/// `(|centre| − r)(|centre| + r)` in f64: no cancellation between two large squares when the eye is close
/// to a large sphere.
pub(crate) fn eye_term(center: V3<f64>, radius: f64) -> f64 {
    let d = center.length();
    (d - radius) * (d + radius)
}

/// Whether the eye is inside a solid by the sign of its eye term: `Some(true)` below 0, `Some(false)` above,
/// `None` at 0 (the eye on the surface) and for NaN, as the shader's lanes decide it.
pub(crate) fn eye_side(c_eye: f64) -> Option<bool> {
    match c_eye.partial_cmp(&0.0)? {
        std::cmp::Ordering::Less => Some(true),
        std::cmp::Ordering::Greater => Some(false),
        std::cmp::Ordering::Equal => None,
    }
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
        // 1e5 radii away: lost in f32 by the textbook discriminant, kept by the perpendicular form.
        let c = V3::new(0.0f32, 0.0, 1.0e5);
        let r = Ray::new(V3::new(0.0f32, 0.5, 0.0), V3::new(0.0, 0.0, 1.0));
        let (hit, t) = intersect_sphere(c, 1.0, &r, f32::INFINITY);
        assert!(hit);
        let exact = 1.0e5 - (1.0f64 - 0.25).sqrt();
        assert!(((t as f64) - exact).abs() / exact < 1e-6, "t = {t}");
    }

    /// `l²` for f32 rays aimed at the rims of spheres 10 to 1000 radii away, against `l²` in f64 from the
    /// same f32 inputs: within 16 ε of `r²` (each component of `oc − d·proj` rounded once; `proj`'s own
    /// error only moves the foot point along the line, which changes `l²` in second order). With the
    /// product rounded on its own the error is about `ε·|oc|·r`: the same rays show it exceeding the bound.
    #[test]
    fn perpendicular_distance_is_accurate_for_small_distant_spheres() {
        use crate::math::SplitMix64;
        let mut rng = SplitMix64::new(3);
        let (mut worst, mut worst_separate) = (0.0f64, 0.0f64);
        for _ in 0..20_000 {
            let distance = 10f64.powf(1.0 + 2.0 * rng.unit());
            let r = 0.001 + rng.unit();
            let dir = V3::new(rng.unit() - 0.5, rng.unit() - 0.5, 1.0).normalize();
            let centre = (dir * (distance * r)).to_f32();
            // Aim a ray at a point a relative 1e-3 inside or outside the rim, off the centre's line.
            let side = V3::new(-dir.y, dir.x, 0.0).normalize();
            let target = dir * (distance * r) + side * (r * (1.0 + 2e-3 * (rng.unit() - 0.5)));
            let ray = Ray::new(V3::all(0.0f32), target.normalize().to_f32());
            let line = sphere_approach(centre, r as f32, &SphereRay::new(ray));
            let (oc, d) = (centre.to_f64(), ray.dir.to_f64());
            let proj = oc.dot(d) / d.dot(d);
            let exact = (oc - d * proj).dot(oc - d * proj);
            let r2 = f64::from(r as f32).powi(2);
            worst = worst.max((f64::from(line.l2) - exact).abs() / r2);
            let (oc32, d32) = (centre, ray.dir);
            let perp_separate = oc32 - d32 * (oc32.dot(d32) * (1.0 / d32.dot(d32)));
            worst_separate =
                worst_separate.max((f64::from(perp_separate.dot(perp_separate)) - exact).abs() / r2);
        }
        let eps = f64::from(f32::EPSILON) / 2.0;
        assert!(worst <= 16.0 * eps, "l² off by {:.1} ε of r²", worst / eps);
        assert!(
            worst_separate > 16.0 * eps,
            "the separately rounded form stays within {:.1} ε",
            worst_separate / eps
        );
    }
}
