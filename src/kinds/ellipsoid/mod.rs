//! Ellipsoids (TOML `[[ellipsoids]]`, and `[[spheres]]` with a `transform`): the unit sphere placed by an
//! affine map, intersected in object space ([`Shape`]). Convex and closed: a ray leaving one toward its
//! inside meets it again at its exit ([`Kind::rehit`]), and camera rays take their side from the exact eye
//! term, as spheres do.

use glam::{DAffine3, DVec3};
use serde::Deserialize;
use toml::Spanned;

use super::placed::{spread, stretch, Placed, PlacedDesc};
use super::placement::{transform, TransformOp};
use super::{Kind, KindError, Stray};
use crate::geometry::{far_root, Ray, Shape, ShapeKind};
use crate::math::{Vec3f, V3};
use crate::simd::Lanes;

/// The ellipsoid kind.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Ellipsoid;

/// An `[[ellipsoids]]` table: the unit sphere scaled by `radii` along the axes, then transformed, then
/// moved to `center`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct EllipsoidToml {
    center: Spanned<[f64; 3]>,
    radii: Spanned<[f64; 3]>,
    material: Option<Spanned<String>>,
    transform: Option<Vec<Spanned<TransformOp>>>,
}

/// The ellipsoid `center + user·(unit sphere scaled by radii)`.
pub(crate) fn placed(center: DVec3, user: DAffine3, radii: DVec3, material: u32) -> PlacedDesc {
    let world_from_object = DAffine3::from_translation(center) * user * DAffine3::from_scale(radii);
    PlacedDesc { world_from_object, material }
}

/// The unit sphere's box under `world_from_object` as centre and half extent per axis: `centre ±
/// Σ|column entries|` per axis.
fn extent(world_from_object: &DAffine3) -> (DVec3, DVec3) {
    let m = world_from_object.matrix3;
    let half = DVec3::new(
        m.x_axis.x.abs() + m.y_axis.x.abs() + m.z_axis.x.abs(),
        m.x_axis.y.abs() + m.y_axis.y.abs() + m.z_axis.y.abs(),
        m.x_axis.z.abs() + m.y_axis.z.abs() + m.z_axis.z.abs(),
    );
    (world_from_object.translation, half)
}

impl Kind for Ellipsoid {
    const SINGULAR: &'static str = "ellipsoid";
    const PLURAL: &'static str = "ellipsoids";
    const MEETS_AGAIN: bool = false;

    type Desc = PlacedDesc;
    type Toml = EllipsoidToml;
    type Store = Placed;
    type Twin = Shape<f64>;

    fn from_toml(e: &EllipsoidToml, material: u32) -> Result<PlacedDesc, KindError> {
        let err = |span, message: String| KindError { span, message };
        if !e.center.get_ref().iter().all(|x| (*x as f32).is_finite()) {
            let message = format!("center must be finite (within f32 range), got {:?}", e.center.get_ref());
            return Err(err(e.center.span(), message));
        }
        if !e.radii.get_ref().iter().all(|r| *r > 0.0 && (*r as f32).is_finite()) {
            let message = format!("radii must be positive (within f32 range), got {:?}", e.radii.get_ref());
            return Err(err(e.radii.span(), message));
        }
        let user = match &e.transform {
            None => DAffine3::IDENTITY,
            Some(ops) => transform(ops)?,
        };
        Ok(placed(DVec3::from(*e.center.get_ref()), user, DVec3::from(*e.radii.get_ref()), material))
    }

    fn toml_material(e: &EllipsoidToml) -> Option<&Spanned<String>> {
        e.material.as_ref()
    }

    fn world_box(d: &PlacedDesc) -> Option<[DVec3; 2]> {
        let (c, half) = extent(&d.world_from_object);
        Some([c - half, c + half])
    }

    /// With its box in rendering space, in f64 and rounded to f32 (the BVH's padding covers the rounding).
    fn push(store: &mut Placed, d: &PlacedDesc, origin: DVec3) {
        let (c, half) = extent(&d.world_from_object);
        let c = c - origin;
        let (lo, hi) = ((c - half).as_vec3(), (c + half).as_vec3());
        let bounds = (V3::new(lo.x, lo.y, lo.z), V3::new(hi.x, hi.y, hi.z));
        store.push(ShapeKind::Sphere, d, origin, bounds);
    }

    fn len(store: &Placed) -> usize {
        store.shapes.len()
    }

    fn bounds(store: &Placed, k: usize) -> (Vec3f, Vec3f) {
        store.bounds[k]
    }

    #[inline(always)]
    fn test<F: Lanes>(store: &Placed, k: usize, ray: &Ray<F>, t_max: F) -> (F::Mask, F) {
        store.shapes[k].to_lanes::<F>().intersect_unit_sphere(ray, t_max)
    }

    /// The exit: the far root with the unit sphere in object space.
    fn rehit(store: &Placed, k: usize, ray: &Ray<f32>, t_max: f32) -> Option<f32> {
        let s = &store.shapes[k];
        let (hit, t) = far_root(&s.unit_sphere_roots(&s.to_object(ray)), t_max);
        hit.then_some(t)
    }

    /// The normal from the object-space hit point, the ray carried into object space and run to `t`.
    fn surface(store: &Placed, k: usize, ray: &Ray<f32>, t: f32, _point: Vec3f) -> (Vec3f, Vec3f) {
        let s = &store.shapes[k];
        let object_point = s.to_object(ray).at(t);
        (s.world_normal(object_point), object_point)
    }

    fn has_surface_k(_store: &Placed, _k: usize) -> bool {
        true
    }

    fn surface_k<F: Lanes>(store: &Placed, k: usize, ray: &Ray<F>, t: F) -> Option<(V3<F>, V3<F>)> {
        let s = store.shapes[k].to_lanes::<F>();
        let object_point = s.to_object(ray).at(t);
        Some((s.normal_to_world.vector(object_point).normalize(), object_point))
    }

    fn eye_term(store: &Placed, k: usize) -> Option<f32> {
        Some(store.shapes[k].c_eye)
    }

    fn item_material(store: &Placed, k: usize) -> u32 {
        store.shapes[k].material
    }

    fn twin(d: &PlacedDesc, origin: DVec3) -> Shape<f64> {
        d.shape(ShapeKind::Sphere, origin)
    }

    #[cfg(test)]
    fn widen(store: &Placed, k: usize) -> Shape<f64> {
        store.shapes[k].widen()
    }

    fn intersect64(s: &Shape<f64>, ray: &Ray<f64>, t_max: f64) -> Option<f64> {
        let (hit, t) = s.intersect(ray, t_max);
        hit.then_some(t)
    }

    fn rehit64(s: &Shape<f64>, ray: &Ray<f64>, t_max: f64) -> Option<f64> {
        let (hit, t) = far_root(&s.unit_sphere_roots(&s.to_object(ray)), t_max);
        hit.then_some(t)
    }

    fn normal64(s: &Shape<f64>, ray: &Ray<f64>, t: f64, _point: V3<f64>) -> V3<f64> {
        s.normal_to_world.vector(s.to_object(ray).at(t)).normalize()
    }

    fn eye_term64(s: &Shape<f64>) -> Option<f64> {
        Some(s.c_eye)
    }

    /// The sphere's rule in object space: the line's closest approach to the centre is within
    /// `tol·(spread + 1)` of 1, `spread` the scale the object-space ray is rounded at
    /// ([`super::placed::spread`]), plus the stray stretched by the map.
    fn grazing64(s: &Shape<f64>, ray: &Ray<f64>, tol: f64, stray: Stray) -> bool {
        let local = s.to_object(ray);
        let (centre, d) = (V3::all(0.0) - local.origin, local.dir);
        let proj = centre.dot(d) / d.dot(d);
        let l = (centre - d * proj).length();
        let slack = stretch(s) * stray.at((s.center - ray.origin).length());
        (l - 1.0).abs() <= tol * (spread(s, ray.origin) + 1.0) + slack
    }

    fn near64(s: &Shape<f64>, p: V3<f64>, tol: f64, slack: f64) -> bool {
        let q = s.object_from_world.vector(p - s.center);
        (q.length() - 1.0).abs() <= tol * (spread(s, p) + 1.0) + stretch(s) * slack
    }
}
