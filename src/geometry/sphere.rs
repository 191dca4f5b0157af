//! Ray/sphere intersection: the lecture's five cases in the numerically stable perpendicular form.
//!
//! With `c = centre − origin`, `proj = (c·d)/(d·d)` is the parameter of the point on the line closest to the
//! centre and `l² = |c − proj·d|²` its squared distance. The line misses when `l² > r²` (case 1), touches when
//! equal (case 2), and otherwise has roots `proj ± sqrt((r² − l²)/(d·d))`. The textbook `b² − 4ac` subtracts
//! two nearly equal large numbers for small distant spheres; `r² − l²` does not (Haines et al., Ray Tracing
//! Gems ch. 7, the form Embree and pbrt use). Of the roots, the smallest one at or after the ray's start is
//! taken: both ahead (case 3) gives the near one, origin inside (case 4) the far one (an exit hit, whose normal
//! the shader flips), both behind (case 5) a miss.

use crate::math::{Real, V3};

use super::Ray;

/// The two roots of a ray and a sphere, valid only where `hit` is set.
#[derive(Clone, Copy, Debug)]
pub struct Roots<F: Real> {
    /// The line meets the sphere (`l² ≤ r²`); NaN inputs give false.
    pub hit: F::Mask,
    /// The entry parameter.
    pub near: F,
    /// The exit parameter.
    pub far: F,
}

/// Where a ray's line passes a sphere: enough to know whether it meets it, before any square root.
#[derive(Clone, Copy, Debug)]
pub struct Approach<F: Real> {
    dd: F,
    proj: F,
    l2: F,
    r2: F,
}

impl<F: Real> Approach<F> {
    /// The line meets the sphere (`l² ≤ r²`); NaN inputs give false.
    #[inline(always)]
    pub fn meets(&self) -> F::Mask {
        self.l2.le(self.r2)
    }

    /// The two roots.
    #[inline(always)]
    pub fn roots(&self) -> Roots<F> {
        let td = ((self.r2 - self.l2) / self.dd).sqrt();
        Roots { hit: self.meets(), near: self.proj - td, far: self.proj + td }
    }
}

/// The closest approach of the ray's line to the sphere's centre.
#[inline(always)]
pub fn sphere_approach<F: Real>(centre: V3<F>, radius: F, ray: &Ray<F>) -> Approach<F> {
    let d = ray.dir;
    let c = centre - ray.origin;
    let dd = d.dot(d);
    let proj = c.dot(d) / dd;
    let perp = c - d * proj;
    Approach { dd, proj, l2: perp.dot(perp), r2: radius * radius }
}

/// The roots of `|origin + t·dir − centre|² = radius²`.
#[inline(always)]
pub fn sphere_roots<F: Real>(centre: V3<F>, radius: F, ray: &Ray<F>) -> Roots<F> {
    sphere_approach(centre, radius, ray).roots()
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
