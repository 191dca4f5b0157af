//! The torus in f64 for the accuracy twin, by a method independent of the f32 kernel's: the quartic along
//! the ray solved in closed form (Ferrari's resolvent cubic), each real root then polished by Newton's
//! method on the quartic. A root the kernel's isolation misses would show as a disagreement here.

use crate::geometry::Ray;
use crate::math::V3;

use super::super::Stray;
use super::TorusShape;

/// The ray in the torus's frame, moved along itself to the point nearest the centre (`s = 0` there; `t` of
/// the original ray is `shift + s`), so that the quartic's coefficients are of the torus's size.
fn line(t: &TorusShape<f64>, ray: &Ray<f64>) -> (f64, V3<f64>, V3<f64>) {
    let o = t.frame.to_object(ray.origin);
    let d = t.frame.vector_to_object(ray.dir);
    let shift = -o.dot(d) / d.dot(d);
    (shift, o + d * shift, d)
}

/// The quartic `c[4]·s⁴ + … + c[0]` of the torus along `o + s·d`.
fn quartic(t: &TorusShape<f64>, o: V3<f64>, d: V3<f64>) -> [f64; 5] {
    let k = t.major * t.major - t.minor * t.minor;
    let r2 = 4.0 * t.major * t.major;
    let (a, b, c) = (d.dot(d), o.dot(d), o.dot(o) + k);
    let (axy, bxy, cxy) = (d.x * d.x + d.y * d.y, o.x * d.x + o.y * d.y, o.x * o.x + o.y * o.y);
    [c * c - r2 * cxy, 4.0 * b * c - 2.0 * r2 * bxy, 2.0 * a * c + 4.0 * b * b - r2 * axy, 4.0 * a * b, a * a]
}

fn eval(c: &[f64; 5], s: f64) -> (f64, f64) {
    let g = (((c[4] * s + c[3]) * s + c[2]) * s + c[1]) * s + c[0];
    let dg = ((4.0 * c[4] * s + 3.0 * c[3]) * s + 2.0 * c[2]) * s + c[1];
    (g, dg)
}

/// The real roots of the monic cubic `x³ + a·x² + b·x + c`, by the trigonometric form or Cardano's.
fn cubic_roots(a: f64, b: f64, c: f64) -> Vec<f64> {
    let p = b - a * a / 3.0;
    let q = 2.0 * a * a * a / 27.0 - a * b / 3.0 + c;
    let shift = -a / 3.0;
    let disc = q * q / 4.0 + p * p * p / 27.0;
    if disc > 0.0 {
        let s = disc.sqrt();
        vec![(-q / 2.0 + s).cbrt() + (-q / 2.0 - s).cbrt() + shift]
    } else if p == 0.0 {
        vec![shift]
    } else {
        let m = 2.0 * (-p / 3.0).sqrt();
        let theta = (3.0 * q / (p * m)).clamp(-1.0, 1.0).acos() / 3.0;
        (0..3).map(|k| m * (theta - 2.0 * std::f64::consts::PI * k as f64 / 3.0).cos() + shift).collect()
    }
}

/// The real roots of `y² + b·y + c`.
fn quadratic_roots(b: f64, c: f64) -> Vec<f64> {
    let disc = b * b - 4.0 * c;
    if disc < 0.0 {
        return Vec::new();
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    if q == 0.0 {
        return vec![0.0];
    }
    vec![q, c / q]
}

/// The real roots of the quartic (Ferrari), unpolished.
fn ferrari(c: &[f64; 5]) -> Vec<f64> {
    let [e, d, cc, b, lead] = *c;
    let (a, b, cc, d) = (b / lead, cc / lead, d / lead, e / lead);
    // x = y − a/4: y⁴ + p·y² + q·y + r.
    let p = b - 3.0 * a * a / 8.0;
    let q = cc - a * b / 2.0 + a * a * a / 8.0;
    let r = d - a * cc / 4.0 + a * a * b / 16.0 - 3.0 * a.powi(4) / 256.0;
    let shift = -a / 4.0;
    let ys = if q.abs() <= 1e-14 * (p.abs() + r.abs().sqrt()).powi(3).max(f64::MIN_POSITIVE) {
        // Biquadratic: y² = z with z² + p·z + r = 0.
        quadratic_roots(p, r).into_iter().filter(|&z| z >= 0.0).flat_map(|z| [z.sqrt(), -z.sqrt()]).collect()
    } else {
        // 8m³ + 8p·m² + (2p² − 8r)·m − q² = 0, the largest real root (positive, as q ≠ 0).
        let m = cubic_roots(p, p * p / 4.0 - r, -q * q / 8.0).into_iter().fold(f64::NEG_INFINITY, f64::max);
        let m = polish_cubic(p, p * p / 4.0 - r, -q * q / 8.0, m);
        if m <= 0.0 {
            return Vec::new();
        }
        let s = (2.0 * m).sqrt();
        let mut ys = quadratic_roots(-s, p / 2.0 + m + q / (2.0 * s));
        ys.extend(quadratic_roots(s, p / 2.0 + m - q / (2.0 * s)));
        ys
    };
    ys.into_iter().map(|y| y + shift).collect()
}

/// `steps` Newton steps from `x` on the function whose value and slope `f` gives, stopping early where the
/// slope is zero or a step would leave the finite numbers.
fn newton(f: impl Fn(f64) -> (f64, f64), mut x: f64, steps: usize) -> f64 {
    for _ in 0..steps {
        let (value, slope) = f(x);
        let next = x - value / slope;
        if slope == 0.0 || !next.is_finite() {
            break;
        }
        x = next;
    }
    x
}

/// A few Newton steps on the monic cubic `x³ + a·x² + b·x + c` from `m`.
fn polish_cubic(a: f64, b: f64, c: f64, m: f64) -> f64 {
    newton(|m| (((m + a) * m + b) * m + c, (3.0 * m + 2.0 * a) * m + b), m, 4)
}

/// Every real root `t` of the ray's line with the torus, ascending, each polished by Newton's method.
pub(crate) fn roots(t: &TorusShape<f64>, ray: &Ray<f64>) -> Vec<f64> {
    let (shift, o, d) = line(t, ray);
    if d.dot(d).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        || !o.x.is_finite()
        || !o.y.is_finite()
        || !o.z.is_finite()
    {
        return Vec::new();
    }
    let c = quartic(t, o, d);
    let mut out: Vec<f64> = ferrari(&c).into_iter().map(|s| shift + newton(|s| eval(&c, s), s, 3)).collect();
    out.sort_by(f64::total_cmp);
    out
}

/// Where a ray that starts on the torus meets it again in `[0, t_max)`: the first root after the one
/// nearest 0 (the start).
pub(crate) fn rehit(t: &TorusShape<f64>, ray: &Ray<f64>, t_max: f64) -> Option<f64> {
    let all = roots(t, ray);
    let start = (0..all.len()).min_by(|&i, &j| all[i].abs().total_cmp(&all[j].abs()))?;
    all[start + 1..].iter().copied().find(|&s| s >= 0.0 && s < t_max)
}

/// The distance from `p` (rendering space) to the torus's surface.
pub(crate) fn distance(t: &TorusShape<f64>, p: V3<f64>) -> f64 {
    let q = t.frame.to_object(p);
    let rho = (q.x * q.x + q.y * q.y).sqrt();
    ((rho - t.major).hypot(q.z) - t.minor).abs()
}

/// Whether moving the line by `nudge` plus `stray` can change whether it meets the torus: at a critical
/// point of the quartic along the line (where two roots merge or appear) the line is within that distance
/// of the surface.
pub(crate) fn grazing(t: &TorusShape<f64>, ray: &Ray<f64>, nudge: f64, stray: Stray) -> bool {
    let (shift, o, d) = line(t, ray);
    let len = d.dot(d).sqrt();
    if len.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return false;
    }
    let c = quartic(t, o, d);
    let lead = 4.0 * c[4];
    let critical = cubic_roots(3.0 * c[3] / lead, 2.0 * c[2] / lead, c[1] / lead);
    critical.into_iter().any(|s| {
        let p = o + d * s;
        let rho = (p.x * p.x + p.y * p.y).sqrt();
        let off = ((rho - t.major).hypot(p.z) - t.minor).abs();
        off <= nudge + stray.at((shift + s) * len)
    })
}
