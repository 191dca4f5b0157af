//! A sphere seen from the eye: the camera's frame in f64 ([`View`]), and a sphere's depth along a ray and
//! its silhouette as an ellipse in pixel space ([`Ball`]).

use crate::camera::Camera;
use crate::geometry::Ellipse;
use crate::kinds::sphere::Spheres;

use super::CLEARANCE;

/// A vector of the camera's frame coordinates: x along the image's columns, y up, z forward.
pub(super) type V = [f64; 3];

pub(super) fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The camera as coverage needs it: the frame, and pixel space ↔ window.
pub(super) struct View {
    /// The eye in rendering space (the origin but in a far scene, `crate::compile::RenderingFrame`).
    eye: V,
    right: V,
    up: V,
    forward: V,
    /// Window `u = sx·au + bu`, `v = sy·av + bv` (directions `(u, v, 1)` in the frame).
    pub(super) au: f64,
    bu: f64,
    pub(super) av: f64,
    bv: f64,
}

impl View {
    pub(super) fn new(camera: &Camera<f64>) -> View {
        let v = |p: crate::math::V3<f64>| [p.x, p.y, p.z];
        View {
            eye: v(camera.eye),
            right: v(camera.right),
            up: v(camera.up),
            forward: v(camera.forward),
            au: camera.u_scale * camera.half_w,
            bu: camera.u_offset * camera.half_w,
            av: camera.v_scale * camera.half_h,
            bv: camera.v_offset * camera.half_h,
        }
    }

    /// The direction (in the frame, not unit) toward pixel-space point `p`.
    pub(super) fn dir(&self, p: [f64; 2]) -> V {
        [p[0] * self.au + self.bu, p[1] * self.av + self.bv, 1.0]
    }

    /// A rendering-space point as a vector from the eye, in f64.
    pub(super) fn eye_to(&self, p: [f32; 3]) -> V {
        [0, 1, 2].map(|a| f64::from(p[a]) - self.eye[a])
    }

    /// A rendering-space vector in the frame.
    pub(super) fn to_frame(&self, c: V) -> V {
        [dot(c, self.right), dot(c, self.up), dot(c, self.forward)]
    }
}

/// The largest coordinate magnitude of `spheres`' boxes (a tree's `extent`, for spheres kept without one).
pub(super) fn spheres_extent(spheres: &Spheres) -> f32 {
    (0..spheres.len())
        .map(|i| {
            let (c, r) = (spheres.center(i), spheres.r[i]);
            c.x.abs().max(c.y.abs()).max(c.z.abs()) + r
        })
        .fold(0.0, f32::max)
}

/// A sphere in the camera's frame (from the eye), in f64 from its stored f32 values.
#[derive(Clone, Copy, Debug)]
pub(super) struct Ball {
    c: V,
    pub(super) r: f64,
    /// `|C|² − r²`, as `(|C| − r)(|C| + r)`: positive when the eye is outside.
    pub(super) k: f64,
    /// `|C|`.
    pub(super) dist: f64,
    /// `|C|·cos(α + CLEARANCE)` (sin α = r/|C|): a direction `t` with `t·C ≤ |t|·rim` passes outside the
    /// silhouette by at least [`CLEARANCE`]; −∞ for a sphere holding the eye.
    rim: f64,
}

impl Ball {
    pub(super) fn new(c: V, r: f64) -> Ball {
        let dist = dot(c, c).sqrt();
        let k = (dist - r) * (dist + r);
        let (sin, cos) = CLEARANCE.sin_cos();
        let rim = if k > 0.0 { k.sqrt() * cos - r * sin } else { f64::NEG_INFINITY };
        Ball { c, r, k, dist, rim }
    }

    /// Whether `t` (of length `len`) passes outside the silhouette by at least [`CLEARANCE`].
    pub(super) fn clear_of(&self, t: V, len: f64) -> bool {
        dot(t, self.c) <= len * self.rim
    }

    /// The distance (along the unit direction) to the surface the eye sees along `t`: the entry point, or
    /// the exit point from inside; `None` where the ray misses.
    pub(super) fn depth(&self, t: V) -> Option<f64> {
        let (b, tt) = (dot(t, self.c), dot(t, t));
        let disc = b * b - tt * self.k;
        if self.k > 0.0 {
            (b > 0.0 && disc >= 0.0).then(|| self.k / (b + disc.sqrt()) * tt.sqrt())
        } else {
            Some((b + disc.max(0.0).sqrt()) / tt.sqrt())
        }
    }

    /// The silhouette in pixel space when the sphere lies wholly in front of the eye's plane.
    pub(super) fn ellipse(&self, view: &View) -> Option<Ellipse> {
        let [cu, cv, cz] = self.c;
        if !(self.k > 0.0 && cz > self.r) || view.au == 0.0 || view.av == 0.0 {
            return None;
        }
        // In the window (u, v): centre cz·c/(cz² − r²), semi-axes r√k/(cz² − r²) along c = (cu, cv) and
        // r/√(cz² − r²) across it.
        let g = (cz - self.r) * (cz + self.r);
        let m = [cz * cu / g, cz * cv / g];
        let (along, across) = (self.r * self.k.sqrt() / g, self.r / g.sqrt());
        let len = cu.hypot(cv);
        let (ex, ey) = if len > 0.0 { (cu / len, cv / len) } else { (1.0, 0.0) };
        // Rows of the map onto the unit disc, composed with window = (au·sx + bu, av·sy + bv).
        let to_unit =
            [[ex / along * view.au, ey / along * view.av], [-ey / across * view.au, ex / across * view.av]];
        let centre = [(m[0] - view.bu) / view.au, (m[1] - view.bv) / view.av];
        Some(Ellipse { centre, to_unit })
    }
}
