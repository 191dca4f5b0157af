//! The sphere in f64, for the accuracy twin: its hits, its exit, its normal, and the rules that say where f32
//! rounding can change the renderer's answer (a grazing line, a point near the surface, the contact rule's
//! entry). A sphere here is `(centre, radius)` in the twin's rendering space (`p − origin` in f64). The hits
//! run the kernel of [`crate::geometry`] at f64, the same formula as the f32 path: what the twin measures is
//! the f32 rounding, not a difference of method.

use crate::geometry::{far_root, intersect_sphere, sphere_roots, Ray, CONTACT_ROUNDINGS};
use crate::kinds::Stray;
use crate::math::{Real, V3};

/// ε32 = 2⁻²⁴, the f32 unit roundoff.
const EPS32: f64 = <f32 as Real>::UNIT_ROUNDOFF;

/// The roundings, beyond the contact band's own [`CONTACT_ROUNDINGS`], by which the f32 renderer's
/// `c = |oc|² − r²` can differ from the exact `c` of the same origin and the scene's sphere
/// ([`contact_entry`]).
const CONTACT_C_ROUNDINGS: f64 = 8.0;

/// The first root of `ray` on the sphere in `[0, t_max)`: the kernel's [`intersect_sphere`] at f64.
pub(crate) fn hit(centre: V3<f64>, radius: f64, ray: &Ray<f64>, t_max: f64) -> Option<f64> {
    let (hit, t) = intersect_sphere(centre, radius, ray, t_max);
    hit.then_some(t)
}

/// The exit root in `[0, t_max)` of a ray leaving the sphere toward its inside.
pub(crate) fn exit(centre: V3<f64>, radius: f64, ray: &Ray<f64>, t_max: f64) -> Option<f64> {
    let (hit, t) = far_root(&sphere_roots(centre, radius, ray), t_max);
    hit.then_some(t)
}

/// The unit outward normal at `point`, as the f32 surface computes it (from the centre, normalised).
pub(crate) fn normal(centre: V3<f64>, point: V3<f64>) -> V3<f64> {
    (point - centre).normalize()
}

/// Whether moving the line by rounding can change hit or miss: its closest approach `l` to the centre
/// satisfies `|l − r| ≤ tol·(|c − o| + r)` plus the stray at that distance.
pub(crate) fn grazing(centre: V3<f64>, radius: f64, ray: &Ray<f64>, tol: f64, stray: Stray) -> bool {
    let oc = centre - ray.origin;
    let d = ray.dir;
    let proj = oc.dot(d) / d.dot(d);
    let l = (oc - d * proj).length();
    let dist = oc.length();
    (l - radius).abs() <= tol * (dist + radius) + stray.at(dist)
}

/// Whether point `p` lies within `tol·(|p| + |c − p| + r)` plus `slack` of the surface: the magnitudes the
/// kernel's f32 operations round are `|p|`, the centre's distance and the radius.
pub(crate) fn near(centre: V3<f64>, radius: f64, p: V3<f64>, tol: f64, slack: f64) -> bool {
    ((p - centre).length() - radius).abs() <= tol * (p.length() + (centre - p).length() + radius) + slack
}

/// True when a hit at exactly `t = 0` of the f32 ray from `origin` along `dir` (both as f32 values, widened)
/// is the contact rule's entry (ARCHITECTURE.md, "Self-intersection"; `geometry/sphere.rs`): the ray heads
/// toward the centre from within the rule's band of the surface, so the renderer took the origin as on the
/// sphere.
///
/// The band is `|c| ≤ CONTACT_ROUNDINGS·ε32·(bound + 2r·|o|∞)`, `c = |oc|² − r²` in f32, `bound =
/// |oc|² + r²` (the eye-term form, taken only where its bound is smaller, has a narrower band). This checks
/// the exact `c` of the f32 origin and the scene's sphere against [`CONTACT_C_ROUNDINGS`] more: the f32 `c`
/// is off from it by the centre's rounding to f32 (`2|oc|·ε32·|C|`, `|C| ≤ |oc| + √3·|o|∞`), `oc`'s
/// subtraction (`2ε32·|oc|²`), its square (`3ε32·|oc|²`) and `r²` (`3ε32·r²`): at most `7ε32·(bound +
/// 2r·|o|∞)` near the surface. The heading, `oc·d ≥ 0` in f32, is allowed what the centre's rounding
/// (`ε32·|C|`), `oc`'s and the dot product's (`4ε32·|oc|`) can move it by.
pub(crate) fn contact_entry(centre: V3<f64>, radius: f64, origin: V3<f64>, dir: V3<f64>) -> bool {
    let oc = centre - origin;
    let c = (oc.length() - radius) * (oc.length() + radius);
    let reach = origin.x.abs().max(origin.y.abs()).max(origin.z.abs());
    let bound = oc.dot(oc) + radius * radius + 2.0 * radius * reach;
    let band = (CONTACT_ROUNDINGS + CONTACT_C_ROUNDINGS) * EPS32 * bound;
    let heading_in = oc.dot(dir) >= -EPS32 * (4.0 * oc.length() + centre.length()) * dir.length();
    heading_in && c.abs() <= band
}
