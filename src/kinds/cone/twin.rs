//! The open cone's rules for the accuracy twin: where a nudge of a ray's line can change its hit (tangency
//! or an end rim), and the distance from a point to the surface.

use super::Cone;
use crate::geometry::Ray;
use crate::kinds::Stray;
use crate::math::V3;

/// `ray`'s line against `cone`'s quadric, in f64: the ray in the cone's frame and the kernel's
/// `[a, b, c, Δ]` of `a·t² + 2b·t + c = 0` ([`super::kernel`]; `Δ = b² − a·c` in its perpendicular
/// form).
fn cone_line(cone: &Cone<f64>, ray: &Ray<f64>) -> (Ray<f64>, [f64; 4]) {
    let local = cone.frame.ray_to_object(ray);
    let (o, d) = (local.origin, local.dir);
    let rho = cone.slope.mul_add(o.z, cone.base_radius);
    let g = cone.slope * d.z;
    let a = d.x * d.x + d.y * d.y - g * g;
    let b = o.x * d.x + o.y * d.y - g * rho;
    let c = o.x * o.x + o.y * o.y - rho * rho;
    let (px, py) = (rho * d.x - g * o.x, rho * d.y - g * o.y);
    let cross = o.x * d.y - o.y * d.x;
    (local, [a, b, c, px * px + py * py - cross * cross])
}

/// Whether moving `ray`'s line by `nudge` plus `slack` can change whether it hits `cone` (the twin's `grazing`).
///
/// - **Tangency.** Along the line, `f = x² + y² − ρ(z)²` is `a·t² + 2b·t + c`, whose extremum is `−Δ/a` at
///   `t* = −b/a`. Moving the line by `δ` changes that extremum by at most `|∇f(p*)|·δ` to first order, so
///   two roots can merge or appear when `|Δ/a| ≤ |∇f(p*)|·δ`. It counts where the roots a nudge makes lie
///   within `sqrt(|∇f|·δ/|a|)` of `t*` in t (the quadratic's spread for that change of its extremum), so
///   where that window reaches `[0, ∞)` and, in height, the end planes.
/// - **Rim.** A root in front of the origin moves along the surface by up to `δ / cos` (the cosine of
///   incidence with the outward normal there) when the line moves by `δ`, so it can cross an end plane when
///   its height is within that of 0 or `h`.
pub(crate) fn grazing(cone: &Cone<f64>, ray: &Ray<f64>, nudge: f64, slack: Stray) -> bool {
    let (local, [a, b, c, disc]) = cone_line(cone, ray);
    let d = local.dir;
    let dl = d.length();
    let h = cone.height;
    if a != 0.0 {
        let ts = -b / a;
        let p = local.at(ts);
        let rho = cone.slope.mul_add(p.z, cone.base_radius);
        let grad = 2.0 * (p.x * p.x + p.y * p.y + (cone.slope * rho).powi(2)).sqrt();
        let delta = nudge + slack.at(ts * dl);
        let spread = (grad * delta / a.abs()).sqrt() + delta / dl;
        let reach = d.z.abs() * spread;
        let in_range = ts + spread >= 0.0 && p.z >= -reach && p.z <= h + reach;
        if in_range && (disc / a).abs() <= grad * delta {
            return true;
        }
    }
    if disc.is_nan() || disc < 0.0 {
        return false;
    }
    let root = disc.sqrt();
    let q = if b >= 0.0 { -(b + root) } else { root - b };
    let roots = if q == 0.0 { [q / a; 2] } else { [q / a, c / q] };
    roots.into_iter().filter(|t| t.is_finite() && *t >= 0.0).any(|t| {
        let p = local.at(t);
        let rim = p.z.abs().min((p.z - h).abs());
        let cos = cone.object_normal(p).dot(d).abs() / dl;
        rim * cos <= nudge + slack.at(t * dl)
    })
}

/// The distance from `p` to the lateral surface: to the infinite cone between the end planes, to the
/// nearer rim circle beyond them.
pub(crate) fn distance(cone: &Cone<f64>, p: V3<f64>) -> f64 {
    let q = cone.frame.to_object(p);
    let radial = (q.x * q.x + q.y * q.y).sqrt();
    let z = q.z.clamp(0.0, cone.height);
    let rho = cone.slope.mul_add(z, cone.base_radius);
    if z == q.z {
        (radial - rho).abs() / cone.slope.hypot(1.0)
    } else {
        (q.z - z).hypot(radial - rho)
    }
}
