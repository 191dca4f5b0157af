//! Open truncated cones and cylinders (NFF `c`): the lateral surface between two end planes, no caps.
//!
//! A cone runs from its base point `B` (radius `r0`) to its apex point `A` (radius `r1`); either radius may
//! be 0 (a pointed cone), both equal gives a cylinder. Each cone is stored with an orthonormal frame at the
//! base, `(e1, e2, u)` with `u` the unit axis towards the apex, its height `h = |A − B|` and the radius
//! slope `k = (r1 − r0)/h`, all computed in f64 and rounded once. In that frame the surface is
//! `x² + y² = (r0 + k·z)²` for `0 ≤ z ≤ h`; on that range the radius `r0 + k·z` is never negative, so the
//! height range alone keeps the quadric's other nappe out.
//!
//! # The kernel
//!
//! The ray is carried into the frame: `w = origin − B`, then `(x, y, z)` and `(dx, dy, dz)` are the dot
//! products of `w` and the direction with `e1`, `e2`, `u`. With `ρ = r0 + k·z` (the radius at the origin's
//! height) and `g = k·dz` (how fast the radius changes along the ray), the surface's equation along the ray
//! is `a·t² + 2b·t + c = 0` with
//!
//! - `a = dx² + dy² − g²`,
//! - `b = x·dx + y·dy − g·ρ`,
//! - `c = x² + y² − ρ²`.
//!
//! Both roots are found and each is kept only where it lies in `[0, t_max)` and its height `z + t·dz` in
//! `[0, h]` (both ends inclusive); the smaller kept root is the hit.
//!
//! Three choices keep the f32 results close to the f64 instance of the same kernel:
//!
//! - **Perpendicular discriminant.** The textbook `b² − a·c` subtracts two nearly equal large numbers for a
//!   thin cone far away (the same loss as the sphere's `b² − 4ac`). Expanding it, the `(x·dx + y·dy)²` and
//!   `(x² + y²)(dx² + dy²)` terms combine by Lagrange's identity, leaving
//!   `Δ = (ρ·dx − g·x)² + (ρ·dy − g·y)² − (x·dy − y·dx)²`: the squared length of a vector of the size of
//!   `ρ·|d|` against the squared distance-times-speed of the line from the axis. Its rounding is a few ε of
//!   those two terms, which are of the size of `Δ` itself unless the ray grazes the surface.
//! - **Vieta's second root.** Only the root of larger magnitude is computed directly, `q/a` with
//!   `q = −(b + sign(b)·√Δ)` (a sum of two numbers of one sign, so no cancellation); the other is `c/q`
//!   (the product of the roots is `c/a`). The difference `−b ∓ √Δ` would cancel for a large cone seen from
//!   close by, and `q/a` alone would be `0/0` or huge for a ray parallel to a generator line (`a = 0`),
//!   where the one finite root is exactly `c/q`. A double root (`q = 0`) is taken as `q/a` for both.
//! - **The frame at the base.** Coordinates relative to `B` are small where the cone is, so `ρ`, `c` and
//!   the heights carry the rounding of the cone's own size, not of its distance from the rendering space's
//!   origin. `ρ` and the heights are each one fused multiply-add (one rounding).
//!
//! What remains is the conditioning of the problem itself: `a` loses relative accuracy for rays within a few
//! ε of parallel to a generator line, `c` for origins within a few ε of the surface, and a root near an end
//! plane may fall on either side of it. Away from such grazing rays the f32 result is the exact result of a
//! ray nudged by a few roundings: `tests/library/cones.rs` holds `|t32 − t64|·|d|` against the f64 instance to 150
//! roundings (2⁻²⁴) of `t·|d| + |origin − B|` and the relative error of `t` to 2e-5 where the hit is at least
//! as far as the base point, with hit/miss disagreeing only on grazing rays (what it measured:
//! docs/perf-log/2026-11-accuracy.md, "The cone kernel against its f64 instance"). The `|origin − B|` term is
//! the rounding of the ray's coordinates in the frame.
//!
//! Every condition is a mask and every choice a [`Real::select`], so a lane instance evaluates the same
//! IEEE operations in the same order as the scalar one: packet results are bit-identical to scalar ones.

use glam::DVec3;

use crate::geometry::{round_down, round_up, Frame, Ray};
use crate::math::{Real, Vec3f, V3};

/// One cone's values, ready to intersect: a scalar cone, one splatted over lanes, or a widened one for the
/// f64 oracle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Cone<F> {
    /// The frame: origin at the base point `B`, axis from the base towards the apex.
    pub(crate) frame: Frame<F>,
    /// Distance from base to apex, `h > 0`.
    pub(crate) height: F,
    /// Radius at the base, `r0 ≥ 0`.
    pub(crate) base_radius: F,
    /// Radius change per unit of height, `(r1 − r0)/h`.
    pub(crate) slope: F,
}

impl Cone<f64> {
    /// The cone from `base` (radius `base_radius`) to `apex` (radius `apex_radius`), in f64. `None` when the
    /// two points coincide, a radius is negative, both are zero, or a value is not finite.
    pub(crate) fn new(base: DVec3, base_radius: f64, apex: DVec3, apex_radius: f64) -> Option<Self> {
        let axis = apex - base;
        let height = axis.length();
        let finite =
            base.is_finite() && apex.is_finite() && base_radius.is_finite() && apex_radius.is_finite();
        let radii = base_radius >= 0.0 && apex_radius >= 0.0 && base_radius.max(apex_radius) > 0.0;
        if !(finite && radii && height > 0.0 && height.is_finite()) {
            return None;
        }
        Some(Cone {
            frame: Frame::about(base, axis / height),
            height,
            base_radius,
            slope: (apex_radius - base_radius) / height,
        })
    }

    /// Every value rounded to f32 once.
    #[allow(clippy::wrong_self_convention)] // &self: callers hold references, and the wide forms are large
    pub(crate) fn to_f32(&self) -> Cone<f32> {
        self.map(|v| v as f32)
    }

    /// An axis-aligned box around the whole lateral surface: the union of the two end discs' exact boxes
    /// (the surface lies in their convex hull), a disc of radius `r` across unit axis `u` reaching
    /// `r·sqrt(1 − u_i²)` along axis `i`.
    pub(crate) fn exact_bounds(&self) -> (DVec3, DVec3) {
        let u = DVec3::from(self.frame.axis);
        let base = DVec3::from(self.frame.origin);
        let apex = base + u * self.height;
        let apex_radius = self.base_radius + self.slope * self.height;
        let across = (DVec3::ONE - u * u).max(DVec3::ZERO).map(f64::sqrt);
        let (r0, r1) = (across * self.base_radius, across * apex_radius.max(0.0));
        ((base - r0).min(apex - r1), (base + r0).max(apex + r1))
    }
}

impl<F: Copy> Cone<F> {
    /// The same cone with every value mapped by `f` (splatted over lanes, or widened): no arithmetic, so
    /// every instance starts from the same values.
    #[inline(always)]
    pub(crate) fn map<G: Copy>(&self, f: impl Fn(F) -> G + Copy) -> Cone<G> {
        Cone {
            frame: self.frame.map(f),
            height: f(self.height),
            base_radius: f(self.base_radius),
            slope: f(self.slope),
        }
    }
}

impl<F: Real> Cone<F> {
    /// The outward unit normal (away from the axis) at a point on the surface, in the cone's frame:
    /// `(x/ρ, y/ρ, −k)/sqrt(1 + k²)` with `ρ = sqrt(x² + y²)`, the gradient of `x² + y² − (r0 + k·z)²`
    /// scaled by `1/(2ρ)`. Taking `ρ` from the point rather than from `r0 + k·z` gives a unit normal for a
    /// point a little off the surface too. On the axis (a pointed cone's tip) the normal is along the axis,
    /// on the side the cone opens away from.
    #[inline(always)]
    pub(crate) fn object_normal(&self, p: V3<F>) -> V3<F> {
        let zero = F::splat(0.0);
        let rho = (p.x * p.x + p.y * p.y).sqrt();
        let off_axis = rho.gt(zero);
        let n = V3::new(p.x / rho, p.y / rho, -self.slope);
        let tip = V3::new(zero, zero, F::select(self.slope.gt(zero), F::splat(-1.0), F::splat(1.0)));
        V3::select(off_axis, n, tip).normalize()
    }

    /// The outward unit normal at a world point on the surface, in world (rendering-space) coordinates.
    #[inline(always)]
    pub(crate) fn normal(&self, p: V3<F>) -> V3<F> {
        self.frame.vector_to_world(self.object_normal(self.frame.to_object(p))).normalize()
    }
}

/// Both roots of the ray's line with the cone's quadric, in the cone's frame: the root of larger magnitude
/// `t1 = q/a`, the other `t2 = c/q` (Vieta), where the line meets the quadric (`Δ ≥ 0`), and the ray's
/// origin height and direction along the axis for the height test.
#[inline(always)]
fn cone_roots<F: Real>(cone: &Cone<F>, ray: &Ray<F>) -> (F, F, F::Mask, F, F) {
    let zero = F::splat(0.0);
    let local = cone.frame.ray_to_object(ray);
    let (o, d) = (local.origin, local.dir);
    let rho = cone.slope.mul_add(o.z, cone.base_radius);
    let g = cone.slope * d.z;
    let a = (-g).mul_add(g, d.x * d.x + d.y * d.y);
    let b = (-g).mul_add(rho, o.x * d.x + o.y * d.y);
    let c = (-rho).mul_add(rho, o.x * o.x + o.y * o.y);
    let (px, py) = ((-g).mul_add(o.x, rho * d.x), (-g).mul_add(o.y, rho * d.y));
    let cross = o.x * d.y - o.y * d.x;
    let disc = (-cross).mul_add(cross, px * px + py * py);
    let root = disc.sqrt();
    // −(b + sign(b)·√Δ): both terms of one sign.
    let q = F::select(b.ge(zero), -(b + root), root - b);
    let t1 = q / a;
    let double = !(q.lt(zero) | q.gt(zero));
    let t2 = F::select(double, t1, c / q);
    (t1, t2, disc.ge(zero), o.z, d.z)
}

/// Where root `t` lies in `[0, t_max)` and between the end planes.
#[inline(always)]
fn kept<F: Real>(cone: &Cone<F>, t: F, z0: F, dz: F, t_max: F) -> F::Mask {
    let zero = F::splat(0.0);
    let z = t.mul_add(dz, z0);
    t.ge(zero) & t.lt(t_max) & z.ge(zero) & z.le(cone.height)
}

/// The smallest `t` in `[0, t_max)` where `ray` meets the open lateral surface of `cone` between its end
/// planes, and the lanes that meet it there; `t` is `t_max` in the others. Both roots of the quadric are
/// checked against the height range (a ray may pass through an open end and hit the inside wall). Rays
/// with a NaN, and zero directions, miss. The module documentation gives the formulation and its rounding.
#[inline(always)]
pub(crate) fn intersect_cone<F: Real>(cone: &Cone<F>, ray: &Ray<F>, t_max: F) -> (F::Mask, F) {
    let (t1, t2, meets, z0, dz) = cone_roots(cone, ray);
    let (k1, k2) = (meets & kept(cone, t1, z0, dz, t_max), meets & kept(cone, t2, z0, dz, t_max));
    let first = k1 & !(k2 & t2.lt(t1));
    let hit = k1 | k2;
    (hit, F::select(hit, F::select(first, t1, t2), t_max))
}

/// For a ray that starts on `cone`'s surface (a secondary ray leaving it): where it meets the cone again,
/// if it does within `[0, t_max)` and between the end planes. The solid a cone bounds is convex, so a ray
/// leaving the surface outward never meets it again, but one heading inside (across a tube or a cup) meets
/// the far wall unless it leaves through an open end. The start is the root
/// nearest 0, so the other hit is the root of larger magnitude, `t1`; a start rounded to a small negative
/// or positive `t` leaves that choice unchanged.
#[inline(always)]
pub(crate) fn rehit_cone<F: Real>(cone: &Cone<F>, ray: &Ray<F>, t_max: F) -> (F::Mask, F) {
    let (t1, _, meets, z0, dz) = cone_roots(cone, ray);
    let hit = meets & kept(cone, t1, z0, dz, t_max);
    (hit, F::select(hit, t1, t_max))
}

/// Cones in structure-of-arrays layout: the values of [`Cone`] rounded once from f64, the material, and a
/// box around each for the BVH.
#[derive(Clone, Debug, Default)]
pub(crate) struct Cones {
    /// Base points.
    pub(crate) bx: Vec<f32>,
    /// Base points, y.
    pub(crate) by: Vec<f32>,
    /// Base points, z.
    pub(crate) bz: Vec<f32>,
    /// Frame vectors `e1`, `e2` and the axis, one triple of arrays each: `frame[0..3]` is `e1`'s x, y, z.
    pub(crate) frame: [Vec<f32>; 9],
    /// Heights.
    pub(crate) height: Vec<f32>,
    /// Base radii.
    pub(crate) base_radius: Vec<f32>,
    /// Radius slopes.
    pub(crate) slope: Vec<f32>,
    /// Material indices.
    pub(crate) material: Vec<u32>,
    /// Boxes around the surfaces, low corners.
    lo: Vec<Vec3f>,
    /// Boxes around the surfaces, high corners.
    hi: Vec<Vec3f>,
}

/// The boxes' margin beyond the exact f64 box, in units of 2⁻²⁴ (f32's unit roundoff) of the cone's scale
/// `|B|∞ + h + max(r0, r1)`. The stored f32 cone's surface differs from the f64 one by the rounding of its
/// base, frame, height and radii: within about 4 units of that scale. 64 covers it with room to spare. A
/// hit the f32 kernel reports is the exact hit of a slightly nudged ray (see the module documentation), so
/// its ray passes the box within that kernel error, which the BVH's own ray-box padding must cover.
pub(crate) const BOUNDS_ROUNDINGS: f64 = 64.0;

impl Cones {
    /// Adds a cone given in f64 rendering-space values (rounded to f32 once) and returns its index, or
    /// `None` for a cone [`Cone::new`] rejects.
    pub(crate) fn push(
        &mut self,
        base: DVec3,
        base_radius: f64,
        apex: DVec3,
        apex_radius: f64,
        material: u32,
    ) -> Option<usize> {
        let exact = Cone::new(base, base_radius, apex, apex_radius)?;
        let c = exact.to_f32();
        let f = &c.frame;
        self.bx.push(f.origin.x);
        self.by.push(f.origin.y);
        self.bz.push(f.origin.z);
        for (k, v) in [f.e1, f.e2, f.axis].iter().enumerate() {
            self.frame[3 * k].push(v.x);
            self.frame[3 * k + 1].push(v.y);
            self.frame[3 * k + 2].push(v.z);
        }
        self.height.push(c.height);
        self.base_radius.push(c.base_radius);
        self.slope.push(c.slope);
        self.material.push(material);
        let (lo, hi) = exact.exact_bounds();
        let scale = base.abs().max_element() + exact.height + base_radius.max(apex_radius);
        let pad = BOUNDS_ROUNDINGS * f64::from(f32::EPSILON) * 0.5 * scale;
        self.lo.push(V3::from(lo - pad).map(round_down));
        self.hi.push(V3::from(hi + pad).map(round_up));
        Some(self.len() - 1)
    }

    /// The number of cones.
    pub(crate) fn len(&self) -> usize {
        self.height.len()
    }

    /// Cone `i`'s values.
    #[inline(always)]
    pub(crate) fn cone(&self, i: usize) -> Cone<f32> {
        let f = &self.frame;
        Cone {
            frame: Frame {
                origin: V3::new(self.bx[i], self.by[i], self.bz[i]),
                e1: V3::new(f[0][i], f[1][i], f[2][i]),
                e2: V3::new(f[3][i], f[4][i], f[5][i]),
                axis: V3::new(f[6][i], f[7][i], f[8][i]),
            },
            height: self.height[i],
            base_radius: self.base_radius[i],
            slope: self.slope[i],
        }
    }

    /// An axis-aligned box `(lo, hi)` containing cone `i`'s surface, as described in f64 and as stored in
    /// f32: the exact f64 box padded by [`BOUNDS_ROUNDINGS`] and rounded outwards to f32.
    pub(crate) fn bounds(&self, i: usize) -> (Vec3f, Vec3f) {
        (self.lo[i], self.hi[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::SplitMix64;

    const INF: f64 = f64::INFINITY;

    fn cone(base: [f64; 3], r0: f64, apex: [f64; 3], r1: f64) -> Cone<f64> {
        Cone::new(DVec3::from(base), r0, DVec3::from(apex), r1).expect("a valid cone")
    }

    fn ray(o: [f64; 3], d: [f64; 3]) -> Ray<f64> {
        Ray::new(V3::new(o[0], o[1], o[2]), V3::new(d[0], d[1], d[2]))
    }

    /// A cylinder of radius 1 along z from 0 to 10; its frame is the identity, so these cases are exact.
    fn cylinder() -> Cone<f64> {
        cone([0.0, 0.0, 0.0], 1.0, [0.0, 0.0, 10.0], 1.0)
    }

    #[test]
    fn cylinder_hit_from_the_side_at_the_known_distance() {
        let c = cylinder();
        assert_eq!(intersect_cone(&c, &ray([-5.0, 0.0, 5.0], [1.0, 0.0, 0.0]), INF), (true, 4.0));
        // Direction of length 2: t is in units of the direction.
        assert_eq!(intersect_cone(&c, &ray([0.0, -5.0, 3.0], [0.0, 2.0, 0.0]), INF), (true, 2.0));
        let f = c.to_f32();
        let r = Ray::new(V3::new(-5.0f32, 0.0, 5.0), V3::new(1.0, 0.0, 0.0));
        assert_eq!(intersect_cone(&f, &r, f32::INFINITY), (true, 4.0));
        let n = c.normal(V3::new(-1.0, 0.0, 5.0));
        assert_eq!(n, V3::new(-1.0, 0.0, 0.0), "outward, away from the axis");
    }

    #[test]
    fn ray_along_the_axis_passes_through_an_open_cylinder() {
        let c = cylinder();
        for o in [[0.0, 0.0, -5.0], [0.5, 0.0, -5.0], [0.0, -0.7, 20.0]] {
            for d in [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]] {
                assert!(!intersect_cone(&c, &ray(o, d), INF).0, "{o:?} {d:?}");
            }
        }
    }

    #[test]
    fn ray_inside_hits_the_far_wall() {
        let c = cylinder();
        assert_eq!(intersect_cone(&c, &ray([0.0, 0.0, 5.0], [1.0, 0.0, 0.0]), INF), (true, 1.0));
        assert_eq!(intersect_cone(&c, &ray([0.5, 0.0, 5.0], [-1.0, 0.0, 0.0]), INF), (true, 1.5));
    }

    #[test]
    fn ray_through_an_open_end_hits_the_inside_wall() {
        // The line meets the quadric at x = −1 (t = 1, z = 11: above the top) and x = 1 (t = 5, z = 7).
        let c = cylinder();
        assert_eq!(intersect_cone(&c, &ray([-1.5, 0.0, 12.0], [0.5, 0.0, -1.0]), INF), (true, 5.0));
    }

    #[test]
    fn rays_past_the_end_planes_miss() {
        let c = cylinder();
        for z in [-0.25, 10.25, 1e3] {
            assert!(!intersect_cone(&c, &ray([-5.0, 0.0, z], [1.0, 0.0, 0.0]), INF).0, "z = {z}");
        }
        // The end planes are part of the surface's range (inclusive).
        assert_eq!(intersect_cone(&c, &ray([-5.0, 0.0, 10.0], [1.0, 0.0, 0.0]), INF), (true, 4.0));
        assert_eq!(intersect_cone(&c, &ray([-5.0, 0.0, 0.0], [1.0, 0.0, 0.0]), INF), (true, 4.0));
    }

    #[test]
    fn pointed_cone_hit_and_normal() {
        // Radius 1 at z = 0 narrowing to a point at z = 2: radius 0.5 at z = 1.
        let c = cone([0.0, 0.0, 0.0], 1.0, [0.0, 0.0, 2.0], 0.0);
        assert_eq!(intersect_cone(&c, &ray([-5.0, 0.0, 1.0], [1.0, 0.0, 0.0]), INF), (true, 4.5));
        let n = c.normal(V3::new(-0.5, 0.0, 1.0));
        let want = V3::new(-2.0, 0.0, 1.0) * (1.0 / 5f64.sqrt());
        assert!((n - want).length() < 1e-15, "{n:?}");
        // Above the tip, and down through the tip along the axis: misses (the other nappe is cut off).
        assert!(!intersect_cone(&c, &ray([-5.0, 0.0, 2.5], [1.0, 0.0, 0.0]), INF).0);
        assert!(!intersect_cone(&c, &ray([-5.0, 0.0, 3.0], [1.0, 0.0, 0.0]), INF).0);
        // Pointed at the base instead: the normal at the tip is along the axis, on the outer side.
        let up = cone([0.0, 0.0, 0.0], 0.0, [0.0, 0.0, 2.0], 1.0);
        assert_eq!(up.object_normal(V3::new(0.0, 0.0, 0.0)), V3::new(0.0, 0.0, -1.0));
        assert_eq!(c.object_normal(V3::new(0.0, 0.0, 2.0)), V3::new(0.0, 0.0, 1.0));
        // A ray from below, parallel to the axis, enters through the open base and meets the inside wall.
        let (hit, t) = intersect_cone(&c, &ray([0.25, 0.0, -1.0], [0.0, 0.0, 1.0]), INF);
        assert!(hit);
        assert!((t - 2.5).abs() < 1e-15, "radius 0.25 at z = 1.5: t = {t}");
    }

    #[test]
    fn t_max_is_exclusive_and_misses_report_it() {
        let c = cylinder();
        let r = ray([-5.0, 0.0, 5.0], [1.0, 0.0, 0.0]);
        assert_eq!(intersect_cone(&c, &r, 4.0), (false, 4.0));
        assert_eq!(intersect_cone(&c, &r, 4.5), (true, 4.0));
        assert_eq!(intersect_cone(&c, &r, 0.0), (false, 0.0));
    }

    #[test]
    fn nan_infinite_and_zero_rays_miss() {
        let c = cylinder();
        for d in [[f64::NAN, 0.0, 0.0], [0.0, 0.0, 0.0], [INF, 0.0, 0.0], [1.0, INF, 0.0]] {
            assert!(!intersect_cone(&c, &ray([-5.0, 0.0, 5.0], d), INF).0, "{d:?}");
        }
        assert!(!intersect_cone(&c, &ray([f64::NAN, 0.0, 5.0], [1.0, 0.0, 0.0]), INF).0);
        assert!(!intersect_cone(&c, &ray([-5.0, 0.0, 5.0], [1.0, 0.0, 0.0]), f64::NAN).0);
    }

    #[test]
    fn bad_cones_are_rejected() {
        let p = DVec3::new(1.0, 2.0, 3.0);
        assert!(Cone::new(p, 1.0, p, 1.0).is_none(), "base == apex");
        assert!(Cone::new(p, -1.0, p + DVec3::X, 1.0).is_none(), "negative radius");
        assert!(Cone::new(p, 0.0, p + DVec3::X, 0.0).is_none(), "no radius at either end");
        assert!(Cone::new(p, 1.0, DVec3::new(f64::NAN, 0.0, 0.0), 1.0).is_none());
        assert!(Cones::default().push(p, 1.0, p, 2.0, 0).is_none());
    }

    /// Random cones in f64: base, apex and radii (sometimes pointed, sometimes a cylinder).
    fn random_cone(rng: &mut SplitMix64) -> (DVec3, f64, DVec3, f64) {
        let mut v = |s: f64| DVec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5) * s;
        let far = if v(1.0).x > 0.4 { 1e3 } else { 1.0 };
        let base = v(20.0) * far;
        let apex = base + v(2.0) * 10f64.powf(v(4.0).x);
        let r0 = 10f64.powf(v(4.0).y) * 0.3;
        let kind = v(1.0).z;
        let r1 = if kind < -0.3 {
            0.0
        } else if kind < 0.0 {
            r0
        } else {
            10f64.powf(v(4.0).x) * 0.3
        };
        if kind > 0.4 {
            (base, 0.0, apex, r1.max(0.01))
        } else {
            (base, r0, apex, r1)
        }
    }

    #[test]
    fn bounds_contain_the_surface_and_every_f32_hit_point() {
        let mut rng = SplitMix64::new(0x0c0e_5eed);
        let mut cones = Cones::default();
        let (mut hits, mut samples) = (0, 0);
        for i in 0..2000 {
            let (base, r0, apex, r1) = random_cone(&mut rng);
            assert_eq!(cones.push(base, r0, apex, r1, 7), Some(i));
            let (lo, hi) = cones.bounds(i);
            let (lo, hi) = (DVec3::from(lo.to_f64()), DVec3::from(hi.to_f64()));
            let inside = |p: DVec3| p.cmpge(lo).all() && p.cmple(hi).all();
            let exact = Cone::new(base, r0, apex, r1).unwrap();
            let (e1, e2) = (DVec3::from(exact.frame.e1), DVec3::from(exact.frame.e2));
            for _ in 0..64 {
                let (s, angle) = (rng.unit(), rng.unit() * std::f64::consts::TAU);
                let s = if samples % 8 == 0 { s.round() } else { s };
                let r = r0 + (r1 - r0) * s;
                let p = base + (apex - base) * s + (e1 * angle.cos() + e2 * angle.sin()) * r;
                assert!(inside(p), "cone {i}: surface point {p} outside {lo}..{hi}");
                samples += 1;
                // A ray at that point from a random direction: the f32 kernel's hit point is inside too.
                let d = DVec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5);
                let o = p - d * (10.0 * (1.0 + (apex - base).length()));
                let ray = Ray::new(V3::from(o).to_f32(), V3::from(d).to_f32());
                let (hit, t) = intersect_cone(&cones.cone(i), &ray, f32::INFINITY);
                if hit {
                    hits += 1;
                    let q = DVec3::from(ray.origin.to_f64()) + DVec3::from(ray.dir.to_f64()) * f64::from(t);
                    assert!(inside(q), "cone {i}: hit point {q} outside {lo}..{hi}");
                }
            }
            assert_eq!(cones.material[i], 7);
        }
        assert!(hits > 50_000, "{hits} hits");
    }
}
