//! Open cones and cylinders (TOML `[[cones]]`, NFF `c`): the lateral surface of a truncated cone between
//! its two end discs, without caps. An open surface: a ray leaving one can meet it again through an open end
//! or across the axis ([`Kind::MEETS_AGAIN`]). The kernel, generic over lanes and precision: [`kernel`]; the
//! twin runs it at f64, with its own grazing and distance rules (`twin`).

pub(crate) mod kernel;
pub(crate) mod twin;

use glam::DVec3;
use serde::Deserialize;
use toml::Spanned;

pub(crate) use kernel::{intersect_cone, rehit_cone, Cone, Cones};

use super::{nudge, Kind, KindError, Stray};
use crate::geometry::Ray;
use crate::math::{Vec3f, V3};
use crate::simd::Lanes;

/// The open-cone kind.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct OpenCone;

/// An open truncated cone as described: the lateral surface between two end discs, no caps; a cylinder
/// when the radii are equal, pointed when one is 0. World space, f64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ConeDesc {
    /// Centre of the base end.
    pub(crate) base: DVec3,
    /// Radius at the base (≥ 0).
    pub(crate) base_radius: f64,
    /// Centre of the other end (≠ `base`).
    pub(crate) apex: DVec3,
    /// Radius at the apex end (≥ 0; not both radii 0).
    pub(crate) apex_radius: f64,
    /// Index into `SceneDesc::materials`.
    pub(crate) material: u32,
}

/// A `[[cones]]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ConeToml {
    base: Spanned<[f64; 3]>,
    base_radius: Spanned<f64>,
    apex: Spanned<[f64; 3]>,
    apex_radius: Spanned<f64>,
    material: Option<Spanned<String>>,
}

impl ConeDesc {
    /// The cone in f64, moved by `−origin`. A cone the readers would have rejected (a description built by
    /// hand) becomes a needle no ray can see, so that ids never shift.
    pub(crate) fn cone(&self, origin: DVec3) -> Cone<f64> {
        let (base, apex) = (self.base - origin, self.apex - origin);
        Cone::new(base, self.base_radius, apex, self.apex_radius).unwrap_or_else(|| {
            Cone::new(base, 0.0, needle_tip(base), f64::MIN_POSITIVE).expect("a needle is a valid cone")
        })
    }
}

/// The tip of the needle (radius 0 at `base`, the least positive radius at the tip) that stands for a
/// cone [`Cone::new`] rejects.
fn needle_tip(base: DVec3) -> DVec3 {
    base + DVec3::X * base.abs().max_element().max(1.0) * 1e-6
}

/// A point of a `[[cones]]` table: finite and within f32 range.
fn point(v: &Spanned<[f64; 3]>, key: &str) -> Result<DVec3, KindError> {
    match v.get_ref().iter().all(|x| x.is_finite() && (*x as f32).is_finite()) {
        true => Ok(DVec3::from(*v.get_ref())),
        false => Err(KindError {
            span: v.span(),
            message: format!("{key} must be finite (within f32 range), got {:?}", v.get_ref()),
        }),
    }
}

/// A radius of a `[[cones]]` table: not negative, finite within f32 range.
fn radius(v: &Spanned<f64>, key: &str) -> Result<f64, KindError> {
    let r = *v.get_ref();
    match r >= 0.0 && (r as f32).is_finite() && r.is_finite() {
        true => Ok(r),
        false => Err(KindError {
            span: v.span(),
            message: format!("{key} must be a non-negative number, got {r}"),
        }),
    }
}

/// The base point's distance, the height and the larger end radius: the scale a cone's stored f32 values
/// and its frame coordinates `origin − B` are rounded at, for a ray from `origin`.
fn scale(cone: &Cone<f64>, origin: V3<f64>) -> f64 {
    let apex_radius = cone.base_radius + cone.slope * cone.height;
    (cone.frame.origin - origin).length() + cone.height + cone.base_radius.max(apex_radius)
}

impl Kind for OpenCone {
    const SINGULAR: &'static str = "cone";
    const PLURAL: &'static str = "cones";
    const MEETS_AGAIN: bool = true;

    type Desc = ConeDesc;
    type Toml = ConeToml;
    type Store = Cones;
    type Twin = Cone<f64>;

    fn from_toml(c: &ConeToml, material: u32) -> Result<ConeDesc, KindError> {
        let (base, apex) = (point(&c.base, "base")?, point(&c.apex, "apex")?);
        let (base_radius, apex_radius) =
            (radius(&c.base_radius, "base_radius")?, radius(&c.apex_radius, "apex_radius")?);
        if base_radius == 0.0 && apex_radius == 0.0 {
            let message = "a cone needs a positive radius at one end at least".into();
            return Err(KindError { span: c.base_radius.span(), message });
        }
        if base == apex {
            let message = format!("cone apex must differ from its base, both are {base}");
            return Err(KindError { span: c.apex.span(), message });
        }
        Ok(ConeDesc { base, base_radius, apex, apex_radius, material })
    }

    fn toml_material(c: &ConeToml) -> Option<&Spanned<String>> {
        c.material.as_ref()
    }

    /// The balls of the end discs' radii around the two end centres: they hold both discs, so the surface.
    /// For a cone [`Cone::new`] rejects, the box of the needle that stands for it.
    fn world_box(d: &ConeDesc) -> Option<[DVec3; 2]> {
        if Cone::new(d.base, d.base_radius, d.apex, d.apex_radius).is_none() {
            let tip = needle_tip(d.base);
            return Some([d.base.min(tip), d.base.max(tip)]);
        }
        let ball = |c: DVec3, r: f64| [c - DVec3::splat(r), c + DVec3::splat(r)];
        let ([a, b], [c, e]) = (ball(d.base, d.base_radius), ball(d.apex, d.apex_radius));
        Some([a.min(c), b.max(e)])
    }

    fn push(store: &mut Cones, d: &ConeDesc, origin: DVec3) {
        let (base, apex) = (d.base - origin, d.apex - origin);
        if store.push(base, d.base_radius, apex, d.apex_radius, d.material).is_none() {
            store.push(base, 0.0, needle_tip(base), f64::MIN_POSITIVE, d.material);
        }
    }

    fn len(store: &Cones) -> usize {
        store.len()
    }

    fn bounds(store: &Cones, k: usize) -> (Vec3f, Vec3f) {
        store.bounds(k)
    }

    #[inline(always)]
    fn test<F: Lanes>(store: &Cones, k: usize, ray: &Ray<F>, t_max: F) -> (F::Mask, F) {
        intersect_cone(&store.cone(k).map(F::splat_f32), ray, t_max)
    }

    fn rehit(store: &Cones, k: usize, ray: &Ray<f32>, t_max: f32) -> Option<f32> {
        let (hit, t) = rehit_cone(&store.cone(k), ray, t_max);
        hit.then_some(t)
    }

    fn surface(store: &Cones, k: usize, _ray: &Ray<f32>, _t: f32, point: Vec3f) -> (Vec3f, Vec3f) {
        let cone = store.cone(k);
        (cone.normal(point), cone.frame.to_object(point))
    }

    fn item_material(store: &Cones, k: usize) -> u32 {
        store.material[k]
    }

    fn twin(d: &ConeDesc, origin: DVec3) -> Cone<f64> {
        d.cone(origin)
    }

    #[cfg(test)]
    fn widen(store: &Cones, k: usize) -> Cone<f64> {
        store.cone(k).map(f64::from)
    }

    fn intersect64(cone: &Cone<f64>, ray: &Ray<f64>, t_max: f64) -> Option<f64> {
        let (hit, t) = intersect_cone(cone, ray, t_max);
        hit.then_some(t)
    }

    fn rehit64(cone: &Cone<f64>, ray: &Ray<f64>, t_max: f64) -> Option<f64> {
        let (hit, t) = rehit_cone(cone, ray, t_max);
        hit.then_some(t)
    }

    fn normal64(cone: &Cone<f64>, _ray: &Ray<f64>, _t: f64, point: V3<f64>) -> V3<f64> {
        cone.normal(point)
    }

    fn grazing64(cone: &Cone<f64>, ray: &Ray<f64>, tol: f64, stray: Stray) -> bool {
        twin::grazing(cone, ray, nudge(ray.origin, scale(cone, ray.origin), tol), stray)
    }

    fn near64(cone: &Cone<f64>, p: V3<f64>, tol: f64, slack: f64) -> bool {
        twin::distance(cone, p) <= nudge(p, scale(cone, p), tol) + slack
    }
}
