//! Tori (TOML `[[tori]]`): ring tori, the surface at distance `minor` from a circle of radius `major`
//! (`0 < minor < major`) about an axis. Not convex: a ray leaving one can meet it again across the hole or
//! through the tube ([`Kind::MEETS_AGAIN`]). The kernel and its error: [`kernel`]; the twin's independent
//! f64 method: [`twin`].

pub(crate) mod kernel;
pub(crate) mod twin;

use glam::{DAffine3, DVec3};
use serde::Deserialize;
use toml::Spanned;

pub(crate) use kernel::{intersect_torus, rehit_torus, TorusShape};

use super::placement::{transform, TransformOp};
use super::{nudge, Kind, KindError, Stray};
use crate::geometry::{round_down, round_up, Frame, Ray};
use crate::math::{Vec3f, V3};
use crate::simd::Lanes;

/// The torus kind.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Torus;

/// A torus as described: world space, f64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TorusDesc {
    /// The centre.
    pub(crate) centre: DVec3,
    /// The unit axis.
    pub(crate) axis: DVec3,
    /// The radius of the tube's centre circle.
    pub(crate) major: f64,
    /// The tube's radius, `0 < minor < major`.
    pub(crate) minor: f64,
    /// Index into `SceneDesc::materials`.
    pub(crate) material: u32,
}

/// A `[[tori]]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct TorusToml {
    center: Spanned<[f64; 3]>,
    #[serde(default)]
    axis: Option<Spanned<[f64; 3]>>,
    major_radius: Spanned<f64>,
    minor_radius: Spanned<f64>,
    material: Option<Spanned<String>>,
    transform: Option<Vec<Spanned<TransformOp>>>,
}

/// The tori of a scene in rendering space, rounded once, with their boxes.
#[derive(Clone, Debug, Default)]
pub(crate) struct Tori {
    /// The tori.
    pub(crate) shapes: Vec<TorusShape<f32>>,
    /// Material indices.
    pub(crate) material: Vec<u32>,
    /// Boxes around the surfaces: low and high corners.
    bounds: Vec<(Vec3f, Vec3f)>,
}

/// The boxes' margin beyond the exact f64 box, in units of 2⁻²⁴ of the torus's scale `|C|∞ + R + r`: the
/// stored f32 values differ from the f64 torus by a few such units, and the kernel's hits are exact hits
/// of rays nudged by a few more (the [`kernel`] documentation).
pub(crate) const BOUNDS_ROUNDINGS: f64 = 64.0;

impl TorusDesc {
    /// The torus in f64 with its frame, moved by `−origin`. A torus the readers would reject (a description
    /// built by hand) becomes a tiny one no ray is likely to see, so that ids never shift.
    pub(crate) fn shape(&self, origin: DVec3) -> TorusShape<f64> {
        let good = self.centre.is_finite()
            && self.axis.is_finite()
            && self.axis.length() > 0.0
            && self.minor > 0.0
            && self.minor < self.major
            && self.major.is_finite();
        let (axis, major, minor) = match good {
            true => (self.axis.normalize(), self.major, self.minor),
            false => (DVec3::Z, f64::MIN_POSITIVE * 4.0, f64::MIN_POSITIVE),
        };
        let centre = if self.centre.is_finite() { self.centre - origin } else { DVec3::ZERO };
        TorusShape { frame: Frame::about(centre, axis), major, minor }
    }
}

/// The exact box of a torus: about each coordinate axis `i`, the centre ± (`R·√(1 − u_i²) + r`).
fn exact_box(t: &TorusShape<f64>) -> (DVec3, DVec3) {
    let u = DVec3::from(t.frame.axis);
    let half = (DVec3::ONE - u * u).max(DVec3::ZERO).map(f64::sqrt) * t.major + DVec3::splat(t.minor);
    let c = DVec3::from(t.frame.origin);
    (c - half, c + half)
}

/// The torus about `axis` through the origin moved by the similarity `m` (transform steps about its own
/// centre), then to `centre`: its centre, axis and radii; `None` when `m` is not a similarity.
fn placed(
    m: &DAffine3,
    centre: DVec3,
    axis: DVec3,
    major: f64,
    minor: f64,
) -> Option<(DVec3, DVec3, f64, f64)> {
    let scale = m.matrix3.determinant().abs().cbrt();
    let gram = m.matrix3.transpose() * m.matrix3;
    let similar = (0..3).all(|i| {
        (0..3).all(|j| {
            let want = if i == j { scale * scale } else { 0.0 };
            (gram.col(i)[j] - want).abs() <= 1e-9 * scale * scale
        })
    });
    let moved = centre + m.translation;
    similar.then(|| (moved, m.transform_vector3(axis).normalize(), major * scale, minor * scale))
}

/// The centre's distance and both radii: the scale a torus's stored f32 values and a ray's coordinates in
/// its frame are rounded at, for a ray from `origin`.
fn scale(t: &TorusShape<f64>, origin: V3<f64>) -> f64 {
    (t.frame.origin - origin).length() + t.major + t.minor
}

impl Kind for Torus {
    const SINGULAR: &'static str = "torus";
    const PLURAL: &'static str = "tori";
    const MEETS_AGAIN: bool = true;

    type Desc = TorusDesc;
    type Toml = TorusToml;
    type Store = Tori;
    type Twin = TorusShape<f64>;

    fn from_toml(t: &TorusToml, material: u32) -> Result<TorusDesc, KindError> {
        let err = |span, message: String| KindError { span, message };
        let centre = DVec3::from(*t.center.get_ref());
        if !t.center.get_ref().iter().all(|x| (*x as f32).is_finite()) {
            return Err(err(
                t.center.span(),
                format!("center must be finite (within f32 range), got {centre}"),
            ));
        }
        let axis = t.axis.as_ref().map_or(DVec3::Z, |a| DVec3::from(*a.get_ref()));
        if !(axis.is_finite() && axis.length() > 0.0) {
            let span = t.axis.as_ref().map_or(t.center.span(), Spanned::span);
            return Err(err(span, format!("axis must be a finite non-zero vector, got {axis}")));
        }
        let (major, minor) = (*t.major_radius.get_ref(), *t.minor_radius.get_ref());
        if !(major > 0.0 && (major as f32).is_finite()) {
            return Err(err(t.major_radius.span(), format!("major_radius must be positive, got {major}")));
        }
        if !(minor > 0.0 && minor < major) {
            let message =
                format!("minor_radius must be positive and below major_radius ({major}), got {minor}");
            return Err(err(t.minor_radius.span(), message));
        }
        let (centre, axis, major, minor) = match &t.transform {
            None => (centre, axis.normalize(), major, minor),
            Some(ops) => {
                let m = transform(ops)?;
                let span = ops.first().map_or(t.center.span(), Spanned::span);
                let message = "a torus's transform may only rotate, translate and scale uniformly";
                placed(&m, centre, axis, major, minor).ok_or_else(|| err(span, message.into()))?
            }
        };
        Ok(TorusDesc { centre, axis, major, minor, material })
    }

    fn toml_material(t: &TorusToml) -> Option<&Spanned<String>> {
        t.material.as_ref()
    }

    fn world_box(d: &TorusDesc) -> Option<[DVec3; 2]> {
        let (lo, hi) = exact_box(&d.shape(DVec3::ZERO));
        Some([lo, hi])
    }

    fn push(store: &mut Tori, d: &TorusDesc, origin: DVec3) {
        let exact = d.shape(origin);
        let (lo, hi) = exact_box(&exact);
        let scale = DVec3::from(exact.frame.origin).abs().max_element() + exact.major + exact.minor;
        let pad = BOUNDS_ROUNDINGS * f64::from(f32::EPSILON) * 0.5 * scale;
        store.bounds.push((V3::from(lo - pad).map(round_down), V3::from(hi + pad).map(round_up)));
        store.shapes.push(exact.map(|v| v as f32));
        store.material.push(d.material);
    }

    fn len(store: &Tori) -> usize {
        store.shapes.len()
    }

    fn bounds(store: &Tori, k: usize) -> (Vec3f, Vec3f) {
        store.bounds[k]
    }

    #[inline(always)]
    fn test<F: Lanes>(store: &Tori, k: usize, ray: &Ray<F>, t_max: F) -> (F::Mask, F) {
        intersect_torus(&store.shapes[k].map(F::splat_f32), ray, t_max)
    }

    fn rehit(store: &Tori, k: usize, ray: &Ray<f32>, t_max: f32) -> Option<f32> {
        let (hit, t) = rehit_torus(&store.shapes[k], ray, t_max);
        hit.then_some(t)
    }

    fn surface(store: &Tori, k: usize, _ray: &Ray<f32>, _t: f32, point: Vec3f) -> (Vec3f, Vec3f) {
        let torus = &store.shapes[k];
        (torus.normal(point), torus.frame.to_object(point))
    }

    fn item_material(store: &Tori, k: usize) -> u32 {
        store.material[k]
    }

    fn twin(d: &TorusDesc, origin: DVec3) -> TorusShape<f64> {
        d.shape(origin)
    }

    #[cfg(test)]
    fn widen(store: &Tori, k: usize) -> TorusShape<f64> {
        store.shapes[k].map(f64::from)
    }

    fn intersect64(t: &TorusShape<f64>, ray: &Ray<f64>, t_max: f64) -> Option<f64> {
        twin::roots(t, ray).into_iter().find(|&s| s >= 0.0 && s < t_max)
    }

    fn rehit64(t: &TorusShape<f64>, ray: &Ray<f64>, t_max: f64) -> Option<f64> {
        twin::rehit(t, ray, t_max)
    }

    fn normal64(t: &TorusShape<f64>, _ray: &Ray<f64>, _at: f64, point: V3<f64>) -> V3<f64> {
        t.normal(point)
    }

    fn grazing64(t: &TorusShape<f64>, ray: &Ray<f64>, tol: f64, stray: Stray) -> bool {
        twin::grazing(t, ray, nudge(ray.origin, scale(t, ray.origin), tol), stray)
    }

    fn near64(t: &TorusShape<f64>, p: V3<f64>, tol: f64, slack: f64) -> bool {
        twin::distance(t, p) <= nudge(p, scale(t, p), tol) + slack
    }
}
