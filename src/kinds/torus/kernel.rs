//! The ray–torus kernel, generic over [`Real`] (f32, f32 lanes, f64).
//!
//! A ring torus of major radius `R` and minor radius `r < R` about the unit axis `u` through its centre `C`
//! is, in its frame `(e1, e2, u)` at `C`, the set where `h(p) = (ρ − R)² + z² − r² = 0`, `ρ = √(x² + y²)`:
//! the points at distance `r` from the circle of radius `R` in the plane `z = 0`. Along a ray the
//! polynomial form `g = (|p|² + R² − r²)² − 4R²ρ²` is a quartic in `t`, and `g = h·G` with
//! `G = (ρ + R)² + z² − r² > 0` for `r < R`: `g` and `h` have the same sign everywhere.
//!
//! # The method: the derivative cascade, then bisection on the well-conditioned form
//!
//! 1. **Clip and shift.** The ray is clipped to the bounding sphere `|p| ≤ R + r` (widened by 2⁻¹⁶ of the
//!    scale, as the torus touches the sphere along its outer equator) and its origin moved to where it
//!    enters it (or kept, when it starts inside): the quartic's coefficients are then formed from
//!    coordinates no larger than the torus, not from a distant origin.
//! 2. **Isolate.** `g''` is a quadratic: its roots (closed form) cut the search range into at most three
//!    pieces on which `g'` is monotone; in each, a sign change of `g'` is bisected to its root, the critical
//!    points of `g`. They cut the range into four pieces on which `g` is monotone, so each holds at most
//!    one root.
//! 3. **Solve.** The first piece whose ends differ in the sign of `h` (evaluated in the factored form,
//!    which does not cancel the way `g` does) holds the hit, which bisection on `h` brackets to the
//!    resolution of the range.
//!
//! Every step runs a fixed number of iterations and chooses by masks and [`Real::select`], so each lane
//! evaluates the same IEEE operations in the same order as the one-lane call: every width gives the same
//! bits.
//!
//! **Error.** Bisection ends within `L·2⁻ᴺ` (`N` = `bisections`: 26 in f32) of a sign change of the
//! computed `h`, with `L ≤ 2(R + r)/|d|` the clipped range; the computed `h` is the exact `h` of a point
//! moved by a few roundings of the torus's size. So away from tangency the f32 `t` is the exact hit of a
//! ray nudged by a few ε of `|t·d| + |C − o| + R + r`, the same form of bound as the sphere's and the
//! cone's (`tests/library/tori.rs` measures it against the twin's independent f64 method). Near tangency two roots
//! merge: the isolation's critical point carries the same few roundings, and hit or miss can go either way
//! for a ray within that distance of grazing (the twin's explanation "graze").

use crate::geometry::{sphere_roots, Frame, Ray};
use crate::math::{Real, V3};

/// A torus's values, ready to intersect: a scalar torus, one splatted over lanes, or a widened one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TorusShape<F> {
    /// The frame: origin at the centre `C`, axis the unit axis `u`.
    pub(crate) frame: Frame<F>,
    /// The major radius `R`: the tube's centre circle.
    pub(crate) major: F,
    /// The minor radius `r < R`: the tube's.
    pub(crate) minor: F,
}

impl<F: Copy> TorusShape<F> {
    /// The same torus with every value mapped by `f` (splatted over lanes, or widened).
    #[inline(always)]
    pub(crate) fn map<G: Copy>(&self, f: impl Fn(F) -> G + Copy) -> TorusShape<G> {
        TorusShape { frame: self.frame.map(f), major: f(self.major), minor: f(self.minor) }
    }
}

/// The number of bisection steps for lanes of type `F`: enough to bring a range to about one unit roundoff
/// of its length (26 for f32, 55 for f64).
pub(crate) fn bisections<F: Real>() -> usize {
    (-F::UNIT_ROUNDOFF.log2()).ceil() as usize + 2
}

impl<F: Real> TorusShape<F> {
    /// `h` at a point of the frame: `(ρ − R)² + z² − r²`, negative inside the tube.
    #[inline(always)]
    pub(crate) fn tube(&self, p: V3<F>) -> F {
        let rho = (p.x * p.x + p.y * p.y).sqrt();
        let off = rho - self.major;
        (-self.minor).mul_add(self.minor, off.mul_add(off, p.z * p.z))
    }

    /// The outward unit normal at a point of the frame: away from the nearest point of the centre circle.
    /// On the axis (no nearest point; never on the surface of a ring torus) it is the axis.
    #[inline(always)]
    pub(crate) fn object_normal(&self, p: V3<F>) -> V3<F> {
        let rho = (p.x * p.x + p.y * p.y).sqrt();
        let zero = F::splat(0.0);
        let shrink = F::select(rho.gt(zero), self.major / rho, zero);
        let n = V3::new(p.x - p.x * shrink, p.y - p.y * shrink, p.z);
        n.normalize()
    }

    /// The outward unit normal at a world point on the surface.
    #[inline(always)]
    pub(crate) fn normal(&self, p: V3<F>) -> V3<F> {
        self.frame.vector_to_world(self.object_normal(self.frame.to_object(p))).normalize()
    }
}

/// The quartic `g(s) = c4·s⁴ + c3·s³ + c2·s² + c1·s + c0` along the shifted ray.
#[derive(Clone, Copy)]
struct Quartic<F> {
    c: [F; 5],
}

impl<F: Real> Quartic<F> {
    /// `g'(s)`, by Horner's rule in fused steps.
    #[inline(always)]
    fn slope(&self, s: F) -> F {
        let [c0, c1, c2, c3, c4] = self.c;
        let _ = c0;
        let a = (F::splat(4.0) * c4).mul_add(s, F::splat(3.0) * c3);
        let b = a.mul_add(s, F::splat(2.0) * c2);
        b.mul_add(s, c1)
    }
}

/// The torus's quartic along the ray `o + s·d` (frame coordinates).
#[inline(always)]
fn quartic<F: Real>(torus: &TorusShape<F>, o: V3<F>, d: V3<F>) -> Quartic<F> {
    let (big, small) = (torus.major, torus.minor);
    let k = (-small).mul_add(small, big * big);
    let four_r2 = F::splat(4.0) * big * big;
    let a = d.dot(d);
    let b = o.dot(d);
    let c = o.dot(o) + k;
    let a_xy = d.x.mul_add(d.x, d.y * d.y);
    let b_xy = o.x.mul_add(d.x, o.y * d.y);
    let c_xy = o.x.mul_add(o.x, o.y * o.y);
    let two = F::splat(2.0);
    let four = F::splat(4.0);
    Quartic {
        c: [
            (-four_r2).mul_add(c_xy, c * c),
            (-two * four_r2).mul_add(b_xy, four * b * c),
            (-four_r2).mul_add(a_xy, (two * a).mul_add(c, four * b * b)),
            four * a * b,
            a * a,
        ],
    }
}

/// The root in `[lo, hi]` of the monotone `f` where its sign changes, bisected `n` times: `(changes, s)`,
/// with `s` the bracket's midpoint, and `changes` false where the ends have one sign (then `s` is `hi`).
#[inline(always)]
fn bisect<F: Real>(f: impl Fn(F) -> F, lo: F, hi: F, n: usize) -> (F::Mask, F) {
    let zero = F::splat(0.0);
    let (f_lo, f_hi) = (f(lo), f(hi));
    let lo_neg = f_lo.lt(zero);
    let changes = (lo_neg & f_hi.ge(zero)) | (!lo_neg & f_hi.lt(zero));
    let (mut a, mut b) = (lo, hi);
    for _ in 0..n {
        let mid = F::splat(0.5).mul_add(b - a, a);
        let same = f(mid).lt(zero);
        let same = (same & lo_neg) | (!same & !lo_neg);
        a = F::select(same, mid, a);
        b = F::select(same, b, mid);
    }
    let mid = F::splat(0.5).mul_add(b - a, a);
    (changes, F::select(changes, mid, hi))
}

/// The roots of `h` along the ray in order, as the pieces that hold them: the shifted origin's `t`, the
/// shifted ray, the four piece ends after `0`, and the lanes where the ray meets the bounding sphere.
struct Isolated<F: Real> {
    start: F,
    origin: V3<F>,
    dir: V3<F>,
    ends: [F; 4],
    meets: F::Mask,
}

/// Steps 1 and 2 of the method (module documentation).
#[inline(always)]
fn isolate<F: Real>(torus: &TorusShape<F>, ray: &Ray<F>, t_max: F) -> Isolated<F> {
    let zero = F::splat(0.0);
    let o = torus.frame.to_object(ray.origin);
    let d = torus.frame.vector_to_object(ray.dir);
    let radius = torus.major + torus.minor;
    let bound = sphere_roots(V3::all(zero), radius, &Ray::new(o, d));
    // The torus touches the bounding sphere along its outer equator and hugs it nearby, so a hit can lie
    // within rounding of either end: the range is widened by 2⁻¹⁶ of the scale, to ends that lie outside
    // the torus by far more than h's rounding (h > 0 beyond the sphere).
    let margin = (radius + o.dot(o).sqrt()) * F::splat(1.0 / 65536.0) / d.dot(d).sqrt();
    let start = (bound.near - margin).max_of(zero);
    let stop = (bound.far + margin).min_of(t_max);
    let meets = bound.hit & bound.far.ge(zero) & start.lt(t_max);
    // Lanes that miss search an empty range, so that nothing in them is NaN or infinite.
    let start = F::select(meets, start, zero);
    let length = F::select(meets, stop - start, zero);
    let origin = V3::new(start.mul_add(d.x, o.x), start.mul_add(d.y, o.y), start.mul_add(d.z, o.z));
    let g = quartic(torus, origin, d);
    // g''(s)/2 = 6·c4·s² + 3·c3·s + c2: its roots by the stable quadratic formula.
    let [_, _, c2, c3, c4] = g.c;
    let (qa, qb) = (F::splat(6.0) * c4, F::splat(1.5) * c3);
    let disc = (-qa).mul_add(c2, qb * qb);
    let root = disc.max_of(zero).sqrt();
    let q = F::select(qb.ge(zero), -(qb + root), root - qb);
    let (u1, u2) = (q / qa, c2 / q);
    let real = disc.ge(zero) & qa.gt(zero);
    let clamp = |u: F| F::select(real & u.ge(zero), u.min_of(length), F::select(real, zero, length));
    let (u1, u2) = (clamp(u1.min_of(u2)), clamp(u1.max_of(u2)));
    let n = bisections::<F>();
    let slope = |s: F| g.slope(s);
    let v1 = bisect(slope, zero, u1, n).1;
    let v2 = bisect(slope, u1, u2, n).1.max_of(v1);
    let v3 = bisect(slope, u2, length, n).1.max_of(v2);
    Isolated { start, origin, dir: d, ends: [v1, v2, v3, length], meets }
}

/// The first root of `h` in the search range, as `(hit, t)` in `[0, t_max)` (`t_max` where none); with
/// `skip_start`, the pieces that begin at the range's start (the empty ones and the first one that is not)
/// are passed over.
#[inline(always)]
fn first_root<F: Real>(torus: &TorusShape<F>, ray: &Ray<F>, t_max: F, skip_start: bool) -> (F::Mask, F) {
    let zero = F::splat(0.0);
    let iso = isolate(torus, ray, t_max);
    let h = |s: F| {
        let (o, d) = (iso.origin, iso.dir);
        torus.tube(V3::new(s.mul_add(d.x, o.x), s.mul_add(d.y, o.y), s.mul_add(d.z, o.z)))
    };
    let sign = |s: F| h(s).lt(zero);
    // The first piece whose ends differ in sign, chosen from the last to the first.
    let starts = [zero, iso.ends[0], iso.ends[1], iso.ends[2]];
    let (mut lo, mut hi) = (zero, zero);
    let mut found = zero.lt(zero);
    for piece in (0..4).rev() {
        let (a, b) = (starts[piece], iso.ends[piece]);
        let (sa, sb) = (sign(a), sign(b));
        let taken = if skip_start { a.gt(zero) } else { a.ge(zero) };
        let changes = ((sa & !sb) | (!sa & sb)) & taken;
        lo = F::select(changes, a, lo);
        hi = F::select(changes, b, hi);
        found = found | changes;
    }
    let (_, s) = bisect(h, lo, hi, bisections::<F>());
    let t = iso.start + s;
    let hit = iso.meets & found & t.ge(zero) & t.lt(t_max);
    (hit, F::select(hit, t, t_max))
}

/// The smallest `t` in `[0, t_max)` where `ray` meets the torus, and the lanes that meet it there (`t_max`
/// in the others). Rays with a NaN, and zero directions, miss.
#[inline(always)]
pub(crate) fn intersect_torus<F: Real>(torus: &TorusShape<F>, ray: &Ray<F>, t_max: F) -> (F::Mask, F) {
    first_root(torus, ray, t_max, false)
}

/// For a ray that starts on the torus (a secondary ray leaving it): where it meets the torus again in
/// `[0, t_max)`. The start is the root in the first non-empty monotone piece of the search range (`g` is
/// monotone there, so it holds no other root), which is skipped; a torus is not convex, so a ray leaving it
/// outward can meet it again across the hole, and one heading into the tube meets its far wall.
#[inline(always)]
pub(crate) fn rehit_torus<F: Real>(torus: &TorusShape<F>, ray: &Ray<F>, t_max: F) -> (F::Mask, F) {
    first_root(torus, ray, t_max, true)
}
