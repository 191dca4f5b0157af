//! Planar polygons: the ray/triangle kernel, and the triangulation that turns an NFF polygon into triangles.
//!
//! A polygon is stored as triangles that all carry the polygon's primitive id, so the self-intersection rule
//! ("a ray leaving a planar primitive never re-tests it") covers every triangle of it at once.
//!
//! The kernel is Möller–Trumbore (1997): with edges `e1 = v1 − v0`, `e2 = v2 − v0`, `p = d × e2`,
//! `det = e1·p`, `s = o − v0`, `q = s × e1`, the hit has barycentrics `u = (s·p)/det`, `v = (d·q)/det` and
//! parameter `t = (e2·q)/det`. It needs no precomputed plane, works for unnormalised directions, and a ray
//! parallel to the triangle gives `det = 0`, which the mask rejects. Edges are inclusive (`u, v ≥ 0`,
//! `u + v ≤ 1`), and `v` is computed as `−(s·(d × e1))/det` (equal to `(d·q)/det` in exact arithmetic): the
//! operations of `u`'s numerator for the edge `e1`. A fan's neighbouring triangles share `v0`, and one's
//! `e2` is the other's `e1`, so along their shared diagonal the two numerators are exact negatives and a
//! ray through it hits at least one of the two. With Möller–Trumbore's own `v` the two round differently:
//! far from `v0` relative to the triangle and at a grazing angle, both could miss (a crack in the polygon).

use glam::{DVec2, DVec3};

use crate::math::{Mask, Real, V3};

use crate::geometry::Ray;

/// Closest hit of each lane's ray with the triangle `(v0, v0 + e1, v0 + e2)` in `[0, t_max)`, both sides:
/// the lanes hit and their t (`t_max` in the rest).
///
/// Every condition is a mask, so a lane evaluates the same IEEE operations as the scalar form; the only
/// branches stop the test once no lane is left (after u, then after v), which changes no lane's answer.
/// One reciprocal (a true division, not an approximation) is shared by u, v and t.
#[inline(always)]
pub(crate) fn intersect_triangle<F: Real>(
    v0: V3<F>,
    e1: V3<F>,
    e2: V3<F>,
    ray: &Ray<F>,
    t_max: F,
) -> (F::Mask, F) {
    let zero = F::splat(0.0);
    let p = ray.dir.cross(e2);
    let det = e1.dot(p);
    // det ≠ 0 written as two comparisons: NaN fails both, so NaN rays miss.
    let facing = det.lt(zero) | det.gt(zero);
    let inv = F::splat(1.0) / det;
    let s = ray.origin - v0;
    let u = s.dot(p) * inv;
    // Most tests miss on a barycentric: the test stops once every lane has (a single ray at once), before
    // the next coordinate is computed.
    let open = facing & u.ge(zero);
    if !open.any() {
        return (open, t_max);
    }
    let v = -s.dot(ray.dir.cross(e1)) * inv;
    let open = open & v.ge(zero) & (u + v).le(F::splat(1.0));
    if !open.any() {
        return (open, t_max);
    }
    let q = s.cross(e1);
    let t = e2.dot(q) * inv;
    let hit = open & t.ge(zero) & t.lt(t_max);
    (hit, F::select(hit, t, t_max))
}

/// Rounding allowance of [`stays_off_plane`] per unit of the coordinates it sums: its heights are a few
/// products and sums of values within that 1-norm, each rounded by at most ε/2.
const PLANE_ROUNDING: f64 = 16.0 * f32::EPSILON as f64;

/// Lanes whose ray stays on one side of a plane over its `[0, reach)`: at both ends it is farther than
/// `thickness`, plus an allowance for this test's rounding, from the plane through `anchor` with unit
/// normal `normal`, on the same side. Such a ray cannot meet a polygon that lies within `thickness` of the
/// plane, so its triangle tests can be skipped; a lane that grazes the plane is never culled. The same
/// operations at every width, so every width culls the same lanes.
#[inline(always)]
pub(crate) fn stays_off_plane<F: Real>(
    anchor: V3<F>,
    normal: V3<F>,
    thickness: F,
    ray: &Ray<F>,
    reach: F,
) -> F::Mask {
    let zero = F::splat(0.0);
    let rounding = F::splat(PLANE_ROUNDING);
    let norm1 = |v: V3<F>| v.x.abs() + v.y.abs() + v.z.abs();
    let rel = ray.origin - anchor;
    let (start, rate) = (normal.dot(rel), normal.dot(ray.dir));
    let near = norm1(rel);
    let start_tol = thickness + rounding * near;
    // With an infinite reach the end's height is ±inf or NaN, and its tolerance inf: only `rate` decides.
    let end = start + rate * reach;
    let end_tol = thickness + rounding * (near + reach * norm1(ray.dir));
    let above = start.gt(start_tol) & (rate.ge(zero) | end.gt(end_tol));
    let below = start.lt(-start_tol) & (rate.le(zero) | end.lt(-end_tol));
    above | below
}

/// Why a list of vertices is not a usable polygon.
/// Why a list of vertices is not a usable polygon.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum PolygonError {
    /// Fewer than three vertices.
    TooFew(usize),
    /// A coordinate is NaN or infinite.
    NotFinite,
    /// All vertices on one line or point (zero area).
    Degenerate,
    /// A vertex lies off the polygon's plane by more than the tolerance.
    NotPlanar,
    /// Ear clipping found no ear: the outline crosses itself.
    SelfIntersecting,
}

impl std::fmt::Display for PolygonError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PolygonError::TooFew(n) => write!(f, "a polygon needs at least 3 vertices, got {n}"),
            PolygonError::NotFinite => write!(f, "polygon vertex is not a finite number"),
            PolygonError::Degenerate => write!(f, "polygon has zero area (its vertices are collinear)"),
            PolygonError::NotPlanar => write!(f, "polygon is not planar"),
            PolygonError::SelfIntersecting => write!(f, "polygon outline crosses itself"),
        }
    }
}

/// The area-weighted normal of a polygon (Newell's method): robust for any planar polygon, convex or not,
/// and its length is twice the area. Follows the right-hand rule: counter-clockwise seen from its tip.
pub(crate) fn newell_normal(vertices: &[DVec3]) -> DVec3 {
    let n = vertices.len();
    (0..n).fold(DVec3::ZERO, |acc, i| {
        let (a, b) = (vertices[i], vertices[(i + 1) % n]);
        acc + DVec3::new((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y))
    })
}

/// Barycentric coordinates of `p` (assumed in the plane) in the triangle `(v0, v0 + e1, v0 + e2)`: the f32
/// store's shading normals and the twin's f64 ones interpolate with the same operations.
pub(crate) fn barycentric<F: Real>(v0: V3<F>, e1: V3<F>, e2: V3<F>, p: V3<F>) -> [F; 3] {
    let w = p - v0;
    let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d20, d21) = (w.dot(e1), w.dot(e2));
    let denom = d00 * d11 - d01 * d01;
    let b1 = (d11 * d20 - d01 * d21) / denom;
    let b2 = (d00 * d21 - d01 * d20) / denom;
    [F::splat(1.0) - b1 - b2, b1, b2]
}

/// The triangles compile and the twin make of a polygon's `vertices`: [`triangulate`]'s, or for a polygon
/// the readers would have rejected (a description built by hand), a fan of possibly degenerate triangles,
/// which the kernel can only miss or hit harmlessly, so that the polygon still gets its id.
pub(crate) fn triangles_or_fan(vertices: &[DVec3]) -> Vec<[u32; 3]> {
    let n = vertices.len() as u32;
    triangulate(vertices).unwrap_or_else(|_| (1..n.max(2) - 1).map(|i| [0, i, i + 1]).collect())
}

/// Splits a planar polygon into triangles (vertex index triples, each wound like the polygon).
///
/// Convex polygons become a fan from vertex 0. Non-convex simple polygons are ear-clipped in the plane of
/// their Newell normal (O(n²), fine for the small polygons of NFF files). Planarity is checked with a
/// tolerance of 1e-4 of the polygon's extent, because SPD prints coordinates to 6 significant digits.
pub(crate) fn triangulate(vertices: &[DVec3]) -> Result<Vec<[u32; 3]>, PolygonError> {
    let n = vertices.len();
    if n < 3 {
        return Err(PolygonError::TooFew(n));
    }
    if !vertices.iter().all(|v| v.is_finite()) {
        return Err(PolygonError::NotFinite);
    }
    let normal = newell_normal(vertices);
    let extent = vertices.iter().map(|v| (*v - vertices[0]).length()).fold(0.0, f64::max);
    // Vertices are finite here, so the length is a number.
    if normal.length() <= 1e-12 * extent * extent {
        return Err(PolygonError::Degenerate);
    }
    let unit = normal.normalize();
    if vertices.iter().any(|v| (*v - vertices[0]).dot(unit).abs() > 1e-4 * extent) {
        return Err(PolygonError::NotPlanar);
    }
    let flat = project(vertices, unit);
    let corner = |a: usize, b: usize, c: usize| (flat[b] - flat[a]).perp_dot(flat[c] - flat[b]);
    if (0..n).all(|i| corner(i, (i + 1) % n, (i + 2) % n) >= 0.0) {
        return Ok((1..n as u32 - 1).map(|i| [0, i, i + 1]).collect());
    }
    ear_clip(&flat)
}

/// 2D coordinates in the polygon's plane, oriented so that the polygon winds counter-clockwise.
fn project(vertices: &[DVec3], unit_normal: DVec3) -> Vec<DVec2> {
    let u = unit_normal.any_orthonormal_vector();
    let v = unit_normal.cross(u);
    vertices.iter().map(|p| DVec2::new(p.dot(u), p.dot(v))).collect()
}

/// Ear clipping of a counter-clockwise simple polygon: repeatedly cut off a convex corner whose triangle
/// contains no other remaining vertex.
fn ear_clip(flat: &[DVec2]) -> Result<Vec<[u32; 3]>, PolygonError> {
    let mut left: Vec<usize> = (0..flat.len()).collect();
    let mut out = Vec::with_capacity(flat.len() - 2);
    while left.len() > 3 {
        let m = left.len();
        let ear = (0..m).find(|&i| {
            let (a, b, c) = (left[(i + m - 1) % m], left[i], left[(i + 1) % m]);
            is_ear(flat, &left, a, b, c)
        });
        let Some(i) = ear else { return Err(PolygonError::SelfIntersecting) };
        out.push([left[(i + m - 1) % m] as u32, left[i] as u32, left[(i + 1) % m] as u32]);
        left.remove(i);
    }
    out.push([left[0] as u32, left[1] as u32, left[2] as u32]);
    Ok(out)
}

fn is_ear(flat: &[DVec2], left: &[usize], a: usize, b: usize, c: usize) -> bool {
    let (pa, pb, pc) = (flat[a], flat[b], flat[c]);
    if (pb - pa).perp_dot(pc - pb) <= 0.0 {
        return false;
    }
    // No other remaining vertex may lie in (or on) the candidate triangle.
    left.iter().filter(|&&k| k != a && k != b && k != c).all(|&k| {
        let p = flat[k];
        let inside = (pb - pa).perp_dot(p - pa) >= 0.0
            && (pc - pb).perp_dot(p - pb) >= 0.0
            && (pa - pc).perp_dot(p - pc) >= 0.0;
        !inside
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plane cull never drops a ray the triangle test hits within its reach (rays not within 1e-3 of
    /// parallel to the plane, from near and far), and it drops rays that stay clearly on one side.
    #[test]
    fn plane_cull_keeps_every_hit_and_drops_rays_that_stay_off() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (state >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        let (mut hits, mut culled) = (0, 0);
        for case in 0..20_000 {
            let scale = [1e-2f32, 1.0, 1e3][case % 3];
            let v = |next: &mut dyn FnMut() -> f32| V3::new(next(), next(), next()) * scale;
            let (v0, e1, e2) = (v(&mut next), v(&mut next), v(&mut next));
            let n = e1.cross(e2);
            let normal = n * (1.0 / n.length());
            // Aimed at a point of the triangle's plane (inside or a little outside it), with a reach from
            // well short of it to well past it, or none.
            let (a, b) = (next() * 0.6 + 0.4, next() * 0.6 + 0.4);
            let target = v0 + e1 * a + e2 * b;
            let origin = v(&mut next) * 3.0;
            let ray = Ray::new(origin, target - origin);
            let reach = [f32::INFINITY, 1.0 + next() * 0.5, 1.0 + next() * 1e-3][case / 3 % 3];
            let off = stays_off_plane(v0, normal, 0.0, &ray, reach);
            let (hit, _) = intersect_triangle(v0, e1, e2, &ray, reach);
            let grazing = normal.dot(ray.dir).abs() < 1e-3 * ray.dir.length();
            if hit && !grazing {
                hits += 1;
                assert!(!off, "case {case}: culled a hit: {ray:?} reach {reach}");
            }
            culled += usize::from(off);
        }
        assert!(hits > 1000 && culled > 5000, "{hits} hits, {culled} culled");
    }

    fn square() -> Vec<DVec3> {
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]].map(DVec3::from).to_vec()
    }

    #[test]
    fn convex_polygons_become_fans() {
        assert_eq!(triangulate(&square()).unwrap(), vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn concave_polygon_is_ear_clipped_into_n_minus_2_triangles() {
        // An L shape: six vertices, reflex corner at (1, 1).
        let l = [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0], [1.0, 2.0], [0.0, 2.0]]
            .map(|[x, y]| DVec3::new(x, y, 3.0))
            .to_vec();
        let tris = triangulate(&l).unwrap();
        assert_eq!(tris.len(), 4);
        let area: f64 = tris
            .iter()
            .map(|t| newell_normal(&[l[t[0] as usize], l[t[1] as usize], l[t[2] as usize]]).z / 2.0)
            .sum();
        assert!((area - 3.0).abs() < 1e-12, "triangles cover the L's area 3, got {area}");
    }

    #[test]
    fn bad_polygons_are_rejected() {
        let mut s = square();
        assert_eq!(triangulate(&s[..2]), Err(PolygonError::TooFew(2)));
        s[2].z = 0.5;
        assert_eq!(triangulate(&s), Err(PolygonError::NotPlanar));
        let line = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]].map(DVec3::from);
        assert_eq!(triangulate(&line), Err(PolygonError::Degenerate));
        let bow = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]].map(DVec3::from);
        assert_eq!(triangulate(&bow), Err(PolygonError::Degenerate), "a symmetric bow tie has zero net area");
        let nan = [[0.0, 0.0, 0.0], [1.0, f64::NAN, 0.0], [1.0, 1.0, 0.0]].map(DVec3::from);
        assert_eq!(triangulate(&nan), Err(PolygonError::NotFinite));
    }

    #[test]
    fn kernel_hits_inside_and_misses_outside() {
        let (v0, e1, e2) = (V3::new(0.0f64, 0.0, 0.0), V3::new(1.0, 0.0, 0.0), V3::new(0.0, 1.0, 0.0));
        let down = |x: f64, y: f64| Ray::new(V3::new(x, y, 2.0), V3::new(0.0, 0.0, -1.0));
        assert_eq!(intersect_triangle(v0, e1, e2, &down(0.25, 0.25), f64::INFINITY), (true, 2.0));
        assert!(!intersect_triangle(v0, e1, e2, &down(0.75, 0.75), f64::INFINITY).0);
        assert!(!intersect_triangle(v0, e1, e2, &down(0.25, 0.25), 2.0).0, "t_max is exclusive");
    }
}
