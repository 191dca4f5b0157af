//! Planes (TOML `[[planes]]`): the plane z = 0 placed by an affine map, intersected in object space
//! ([`Shape`]). Unbounded, so never in a tree: every ray is tested against every plane. A ray leaving a
//! plane cannot meet it again.

use glam::{DAffine3, DQuat, DVec3};
use serde::Deserialize;
use toml::Spanned;

use super::placed::{spread, stretch, Placed, PlacedDesc};
use super::placement::{transform, TransformOp};
use super::{Kind, KindError, Stray};
use crate::geometry::{Ray, Shape, ShapeKind};
use crate::math::{Vec3f, V3};
use crate::simd::Lanes;

/// The plane kind.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Plane;

/// A `[[planes]]` table: through `point` (the origin by default) with unit normal along `normal` (+z by
/// default), after `transform` (applied to the plane z = 0 first).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct PlaneToml {
    point: Option<[f64; 3]>,
    normal: Option<Spanned<[f64; 3]>>,
    material: Option<Spanned<String>>,
    transform: Option<Vec<Spanned<TransformOp>>>,
}

impl Kind for Plane {
    const SINGULAR: &'static str = "plane";
    const PLURAL: &'static str = "planes";
    const MEETS_AGAIN: bool = false;

    type Desc = PlacedDesc;
    type Toml = PlaneToml;
    type Store = Placed;
    type Twin = Shape<f64>;

    fn from_toml(p: &PlaneToml, material: u32) -> Result<PlacedDesc, KindError> {
        let normal = match &p.normal {
            None => DVec3::Z,
            Some(n) => {
                let v = DVec3::from(*n.get_ref());
                if !(v.length() > 0.0 && v.is_finite()) {
                    let message = "normal must be a non-zero vector".into();
                    return Err(KindError { span: n.span(), message });
                }
                v.normalize()
            }
        };
        let user = match &p.transform {
            None => DAffine3::IDENTITY,
            Some(ops) => transform(ops)?,
        };
        let world_from_object = DAffine3::from_translation(DVec3::from(p.point.unwrap_or([0.0; 3])))
            * DAffine3::from_quat(DQuat::from_rotation_arc(DVec3::Z, normal))
            * user;
        Ok(PlacedDesc { world_from_object, material })
    }

    fn toml_material(p: &PlaneToml) -> Option<&Spanned<String>> {
        p.material.as_ref()
    }

    fn world_box(_: &PlacedDesc) -> Option<[DVec3; 2]> {
        None
    }

    fn push(store: &mut Placed, d: &PlacedDesc, origin: DVec3) {
        let everywhere = (V3::all(f32::NEG_INFINITY), V3::all(f32::INFINITY));
        store.push(ShapeKind::Plane, d, origin, everywhere);
    }

    fn len(store: &Placed) -> usize {
        store.shapes.len()
    }

    fn bounds(store: &Placed, k: usize) -> (Vec3f, Vec3f) {
        store.bounds[k]
    }

    #[inline(always)]
    fn test<F: Lanes>(store: &Placed, k: usize, ray: &Ray<F>, t_max: F) -> (F::Mask, F) {
        store.shapes[k].to_lanes::<F>().intersect_plane(ray, t_max)
    }

    /// The object-space hit point has z = 0 exactly (for solid textures); the normal is the same
    /// everywhere.
    fn surface(store: &Placed, k: usize, ray: &Ray<f32>, t: f32, _point: Vec3f) -> (Vec3f, Vec3f) {
        let s = &store.shapes[k];
        let mut object_point = s.to_object(ray).at(t);
        object_point.z = 0.0;
        (s.world_normal(object_point), object_point)
    }

    fn has_surface_k(_store: &Placed, _k: usize) -> bool {
        true
    }

    fn surface_k<F: Lanes>(store: &Placed, k: usize, ray: &Ray<F>, t: F) -> Option<(V3<F>, V3<F>)> {
        let s = &store.shapes[k];
        let mut object_point = s.to_lanes::<F>().to_object(ray).at(t);
        object_point.z = F::splat_f32(0.0);
        Some((F::splat_v3(s.world_normal(V3::all(0.0))), object_point))
    }

    fn item_material(store: &Placed, k: usize) -> u32 {
        store.shapes[k].material
    }

    fn twin(d: &PlacedDesc, origin: DVec3) -> Shape<f64> {
        d.shape(ShapeKind::Plane, origin)
    }

    #[cfg(test)]
    fn widen(store: &Placed, k: usize) -> Shape<f64> {
        store.shapes[k].widen()
    }

    fn intersect64(s: &Shape<f64>, ray: &Ray<f64>, t_max: f64) -> Option<f64> {
        let (hit, t) = s.intersect(ray, t_max);
        hit.then_some(t)
    }

    fn normal64(s: &Shape<f64>, _ray: &Ray<f64>, _t: f64, _point: V3<f64>) -> V3<f64> {
        s.normal_to_world.vector(V3::new(0.0, 0.0, 1.0)).normalize()
    }

    /// The object-space direction is within `tol` (plus the stray's direction, stretched by the map) of
    /// parallel to the plane.
    fn grazing64(s: &Shape<f64>, ray: &Ray<f64>, tol: f64, stray: Stray) -> bool {
        let d = s.to_object(ray).dir;
        d.z.abs() <= (tol + stretch(s) * stray.dir) * d.length()
    }

    fn near64(s: &Shape<f64>, p: V3<f64>, tol: f64, slack: f64) -> bool {
        let q = s.object_from_world.vector(p - s.center);
        q.z.abs() <= tol * (spread(s, p) + 1.0) + stretch(s) * slack
    }
}
