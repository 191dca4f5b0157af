//! Planar polygons (TOML `[[polygons]]`, NFF `p` and `pp`): convex or not, flat or with vertex normals to
//! interpolate. Each polygon is one primitive made of triangles ([`Kind::item_id`]): the triangles are the
//! items its tree and its leaf tests take, and a ray leaving a polygon never meets any of them again. The
//! triangle kernel and the triangulation: [`kernel`]; the stored form: [`store`]; the twin: [`twin`].

pub(crate) mod kernel;
pub(crate) mod store;
pub(crate) mod twin;

use glam::DVec3;
use serde::Deserialize;
use toml::Spanned;

pub(crate) use kernel::{intersect_triangle, newell_normal, stays_off_plane, triangles_or_fan, triangulate};
pub(crate) use store::Polygons;
use twin::Polygon64;

use super::{Kind, KindError, Stray};
use crate::geometry::Ray;
use crate::math::{Vec3f, V3};
use crate::simd::Lanes;

/// The polygon kind.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Polygon;

/// A planar polygon as described: world space, f64.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PolygonDesc {
    /// Vertices in order around the outline; the geometric normal follows the right-hand rule.
    pub(crate) vertices: Vec<DVec3>,
    /// One normal per vertex, interpolated across the polygon for shading (any length; normalised by
    /// compile), or `None` for a flat polygon.
    pub(crate) normals: Option<Vec<DVec3>>,
    /// Index into `SceneDesc::materials`.
    pub(crate) material: u32,
}

/// A `[[polygons]]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct PolygonToml {
    vertices: Spanned<Vec<[f64; 3]>>,
    normals: Option<Spanned<Vec<[f64; 3]>>>,
    material: Option<Spanned<String>>,
}

impl PolygonDesc {
    /// The vertex normals to interpolate, each of unit length (zero for a zero vector), when there is one
    /// per vertex.
    pub(crate) fn unit_normals(&self) -> Option<Vec<DVec3>> {
        let normals = self.normals.as_ref().filter(|ns| ns.len() == self.vertices.len())?;
        Some(normals.iter().map(|v| v.normalize_or_zero()).collect())
    }
}

impl Kind for Polygon {
    const SINGULAR: &'static str = "polygon";
    const PLURAL: &'static str = "polygons";
    const MEETS_AGAIN: bool = false;
    const INLINE_QUERIES: bool = true;

    type Desc = PolygonDesc;
    type Toml = PolygonToml;
    type Store = Polygons;
    type Twin = Polygon64;

    /// At least three finite vertices (within f32 range) that triangulate (NFF's `p` rule), and as many
    /// normals as vertices if normals are given (NFF's `pp`).
    fn from_toml(p: &PolygonToml, material: u32) -> Result<PolygonDesc, KindError> {
        let finite = |vs: &[[f64; 3]]| vs.iter().flatten().all(|x| x.is_finite() && (*x as f32).is_finite());
        let vs = p.vertices.get_ref();
        if vs.len() < 3 || !finite(vs) {
            let message =
                format!("vertices must be at least three finite points (within f32 range), got {vs:?}");
            return Err(KindError { span: p.vertices.span(), message });
        }
        let vertices: Vec<DVec3> = vs.iter().map(|&v| DVec3::from(v)).collect();
        triangulate(&vertices).map_err(|e| KindError { span: p.vertices.span(), message: e.to_string() })?;
        let normals = match &p.normals {
            None => None,
            Some(ns) if ns.get_ref().len() == vs.len() && finite(ns.get_ref()) => {
                Some(ns.get_ref().iter().map(|&v| DVec3::from(v)).collect())
            }
            Some(ns) => {
                let message = format!("normals must be {} finite vectors, one per vertex", vs.len());
                return Err(KindError { span: ns.span(), message });
            }
        };
        Ok(PolygonDesc { vertices, normals, material })
    }

    fn toml_material(p: &PolygonToml) -> Option<&Spanned<String>> {
        p.material.as_ref()
    }

    /// The box of the vertices; a polygon without any (built by hand) gets a NaN box, which every fold of
    /// boxes (`min`, `max`) passes over.
    fn world_box(d: &PolygonDesc) -> Option<[DVec3; 2]> {
        let fold = |(lo, hi): (DVec3, DVec3), &v: &DVec3| (lo.min(v), hi.max(v));
        match d.vertices.first() {
            None => Some([DVec3::NAN; 2]),
            Some(&v) => Some(d.vertices.iter().fold((v, v), fold).into()),
        }
    }

    /// Triangulated in f64, moved to rendering space by `−origin`, then rounded once.
    fn push(store: &mut Polygons, d: &PolygonDesc, origin: DVec3) {
        let vertices: Vec<Vec3f> = d.vertices.iter().map(|v| V3::from(*v - origin).to_f32()).collect();
        let unit = |v: DVec3| V3::from(v.normalize_or_zero()).to_f32();
        let normals = d.unit_normals().map(|ns| ns.iter().map(|&v| V3::from(v).to_f32()).collect::<Vec<_>>());
        let normal = unit(newell_normal(&d.vertices));
        store.push(&vertices, normals.as_deref(), &triangles_or_fan(&d.vertices), normal, d.material);
        store.origin = V3::from(origin).to_f32();
    }

    fn len(store: &Polygons) -> usize {
        store.triangles()
    }

    fn ids(store: &Polygons) -> usize {
        store.len()
    }

    #[inline(always)]
    fn item_id(store: &Polygons, k: usize) -> u32 {
        store.polygon[k]
    }

    fn bounds(store: &Polygons, k: usize) -> (Vec3f, Vec3f) {
        store.triangle_box(k)
    }

    #[inline(always)]
    fn test<F: Lanes>(store: &Polygons, k: usize, ray: &Ray<F>, t_max: F) -> (F::Mask, F) {
        let (v0, e1, e2) = (F::splat_v3(store.v0[k]), F::splat_v3(store.e1[k]), F::splat_v3(store.e2[k]));
        intersect_triangle(v0, e1, e2, ray, t_max)
    }

    /// The rays that stay off the triangle's polygon's plane up to their reach ([`stays_off_plane`]): worth
    /// it without a tree, where every triangle meets every packet (a floor under a sphere field is passed
    /// over by the rays that hit a sphere first and by those heading up).
    #[inline(always)]
    fn culled<F: Lanes>(store: &Polygons, k: usize, ray: &Ray<F>, reach: F) -> F::Mask {
        let p = store.polygon[k] as usize;
        let (anchor, normal) = (F::splat_v3(store.anchor[p]), F::splat_v3(store.normal[p]));
        stays_off_plane(anchor, normal, F::splat_f32(store.thickness[p]), ray, reach)
    }

    /// The interpolated vertex normal (else the plane's), and the world-space point for solid textures,
    /// moved onto the polygon's plane first: the rounded hit points scatter an ulp or so either side of it,
    /// and a checker's cells at an integer height (a floor at y = 0) would flip pixel by pixel. On an
    /// axis-aligned polygon the moved point's height is the anchor's exactly.
    fn surface(store: &Polygons, k: usize, _ray: &Ray<f32>, _t: f32, point: Vec3f) -> (Vec3f, Vec3f) {
        let (normal, anchor) = (store.normal[k], store.anchor[k]);
        let on_plane = point - normal * normal.dot(point - anchor);
        (store.shading_normal(k, point), on_plane + store.origin)
    }

    /// Flat polygons only (no vertex normals): the plane's normal in every lane, the point moved onto the
    /// plane as [`Kind::surface`] moves it, in the same operations.
    fn surface_k<F: Lanes>(store: &Polygons, k: usize, ray: &Ray<F>, t: F) -> Option<(V3<F>, V3<F>)> {
        flat_surface_k(store, k, ray, t)
    }

    fn has_surface_k(store: &Polygons, k: usize) -> bool {
        store.is_flat(k)
    }

    fn item_material(store: &Polygons, k: usize) -> u32 {
        store.material[k]
    }

    fn twin(d: &PolygonDesc, origin: DVec3) -> Polygon64 {
        Polygon64::new(d, origin)
    }

    #[cfg(test)]
    fn widen(store: &Polygons, k: usize) -> Polygon64 {
        Polygon64::widened(store, k)
    }

    #[inline(always)]
    fn intersect64(p: &Polygon64, ray: &Ray<f64>, t_max: f64) -> Option<f64> {
        p.intersect(ray, t_max)
    }

    fn normal64(p: &Polygon64, _ray: &Ray<f64>, _t: f64, point: V3<f64>) -> V3<f64> {
        p.shading_normal(point)
    }

    fn geometric_normal64(p: &Polygon64, _ray: &Ray<f64>, _t: f64, _point: V3<f64>) -> V3<f64> {
        p.normal
    }

    fn grazing64(p: &Polygon64, ray: &Ray<f64>, tol: f64, stray: Stray) -> bool {
        p.grazing(ray, tol, stray)
    }

    fn near64(p: &Polygon64, point: V3<f64>, tol: f64, slack: f64) -> bool {
        p.near(point, tol, slack)
    }
}

/// [`Kind::surface_k`] of polygon `k` when it is flat, out of line: the loop over kinds that dispatches to it
/// stays as small as without it.
#[inline(never)]
fn flat_surface_k<F: Lanes>(store: &Polygons, k: usize, ray: &Ray<F>, t: F) -> Option<(V3<F>, V3<F>)> {
    if !store.is_flat(k) {
        return None;
    }
    let point = ray.at(t);
    let (normal, anchor) = (F::splat_v3(store.normal[k]), F::splat_v3(store.anchor[k]));
    let on_plane = point - normal * normal.dot(point - anchor);
    Some((normal, on_plane + F::splat_v3(store.origin)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::SplitMix64;

    /// Hit points an ulp or so off a floor at y = 0 (and one at y = 2) all read the floor's height as the
    /// solid texture's, so a checker's cells do not flip between neighbouring pixels; x and z stay the hit's.
    #[test]
    fn an_axis_aligned_floor_reads_one_height() {
        let origin = DVec3::new(0.3, 1.6, -7.1);
        for height in [0.0, 2.0] {
            let square = [[-5.0, -5.0], [5.0, -5.0], [5.0, 5.0], [-5.0, 5.0]];
            let vertices = square.iter().map(|&[x, z]| DVec3::new(x, height, z)).collect();
            let mut store = Polygons::default();
            Polygon::push(&mut store, &PolygonDesc { vertices, normals: None, material: 0 }, origin);
            let plane_y = (height - origin.y) as f32;
            let mut rng = SplitMix64::new(9);
            let mut heights = std::collections::BTreeSet::new();
            for _ in 0..1000 {
                let (x, z) = ((rng.unit() * 10.0 - 5.0) as f32, (rng.unit() * 10.0 - 5.0) as f32);
                let ulps = (rng.unit() * 8.0) as u32;
                let y = match rng.unit() < 0.5 {
                    true => f32::from_bits(plane_y.to_bits() + ulps),
                    false => f32::from_bits(plane_y.to_bits().wrapping_sub(ulps)),
                };
                let point = V3::new(x, y, z);
                let ray = Ray { origin: point, dir: V3::new(0.0, -1.0, 0.0) };
                let (_, object) = Polygon::surface(&store, 0, &ray, 0.0, point);
                heights.insert(object.y.to_bits());
                assert_eq!((object.x, object.z), (x + store.origin.x, z + store.origin.z));
            }
            assert_eq!(heights.len(), 1, "floor at {height}: heights {heights:?}");
        }
    }
}
