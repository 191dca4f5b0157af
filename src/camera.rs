//! The lecture's camera: eye O, view direction Z_v, up Y_v, image-plane distance d, and either a horizontal
//! view angle θ or a pixel size s, at h_res × v_res.
//!
//! Handedness: the lecture takes X_v = Y_v × Z_v and starts at P_0,0 = O + d·Z_v − (s_j/2)·X_v + (s_k/2)·Y_v.
//! In right-handed world coordinates Y_v × Z_v points to the viewer's *left*, so that sweep writes a mirrored
//! image. bareray uses X_v = Z_v × Y_v (the viewer's right, as pbrt and the benchmark contract do) with the
//! same formula, so column 0 is on the left, row 0 at the top, and images are not mirrored.
//!
//! Directions depend on d only through the window size, so rays are generated from the window as seen at
//! unit distance: `dir = normalize(Z_v + u·half_w·X_v + v·half_h·Y_v)` with window coordinates u, v in
//! [−1, 1]. The frame and the formula are generic over [`Real`]; the renderer evaluates them in f64 and
//! rounds each ray once to f32 (`Camera::rays`), four lanes at a time, so every width traces the same rays.

use thiserror::Error;
use wide::f64x4;

use crate::geometry::{Pyramid, Ray};
use crate::math::{Real, V3};
use crate::scene::desc::{Aim, CameraDesc, Field, Sweep};
use crate::simd::Lanes;

/// A camera description that cannot produce an image.
#[derive(Debug, Error, PartialEq)]
pub enum CameraError {
    /// Zero width or height.
    #[error("resolution must be at least 1×1, got {0}×{1}")]
    Resolution(u32, u32),
    /// View direction of zero length (or eye equal to the look-at point).
    #[error("the view direction has zero length (is the eye at the look-at point?)")]
    NoDirection,
    /// Up parallel to the view direction.
    #[error("the up vector is parallel to the view direction")]
    UpParallel,
    /// θ outside (0°, 180°), s or d not positive.
    #[error("{0}")]
    Field(String),
}

/// A ready camera: an orthonormal frame and the map from pixel coordinates to the window.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera<F> {
    /// Eye point O.
    pub(crate) eye: V3<F>,
    /// Unit view direction Z_v.
    pub(crate) forward: V3<F>,
    /// Unit X_v = normalize(Z_v × Y_v): the image's +column direction.
    pub(crate) right: V3<F>,
    /// Unit Y_v' = X_v × Z_v: the true up, the image's −row direction.
    pub(crate) up: V3<F>,
    /// Half the window width over d: tan(θ/2) for an angle.
    pub(crate) half_w: F,
    /// Half the window height over d.
    pub(crate) half_h: F,
    /// Window u = sx·u_scale + u_offset for a pixel-space x coordinate sx (column j's centre is j + ½).
    pub(crate) u_scale: F,
    /// See `u_scale`.
    pub(crate) u_offset: F,
    /// Window v = sy·v_scale + v_offset (row 0 at the top, v = +1).
    pub(crate) v_scale: F,
    /// See `v_scale`.
    pub(crate) v_offset: F,
    /// Image-plane distance d (for points on the image plane; directions do not depend on it).
    pub(crate) distance: F,
    /// h_res.
    pub width: u32,
    /// v_res.
    pub height: u32,
    /// How far from the eye camera rays start: 0 (at the eye) unless the scene lies far from the eye, where
    /// compile makes rays start just short of the geometry so that their f32 origins are as fine as the
    /// geometry's own coordinates (`crate::compile::RenderingFrame`). No geometry is nearer the eye.
    pub start: F,
}

/// Lanes padded to the widest lane type (K ≤ 16) so that every group of four is whole: fixed-size copies and
/// conversions the compiler keeps in vector registers (`f32 → f64 → f32` rounding is the same in a vector
/// instruction as in a scalar one).
#[inline(always)]
fn padded<F: Lanes>(v: F) -> [f32; 16] {
    let mut out = [0.0f32; 16];
    out[..F::K].copy_from_slice(v.to_array().as_ref());
    out
}

/// Lanes `first..first + 4` of `v` in f64.
#[inline(always)]
fn four(v: &[f32; 16], first: usize) -> f64x4 {
    f64x4::new(std::array::from_fn(|i| f64::from(v[first + i])))
}

impl Camera<f64> {
    /// Builds the frame from a description, in f64.
    pub fn new(desc: &CameraDesc) -> Result<Self, CameraError> {
        let (w, h) = (desc.width, desc.height);
        if w == 0 || h == 0 {
            return Err(CameraError::Resolution(w, h));
        }
        if !(desc.distance > 0.0 && desc.distance.is_finite()) {
            return Err(CameraError::Field(format!(
                "image-plane distance must be positive, got {}",
                desc.distance
            )));
        }
        let dir = match desc.aim {
            Aim::LookAt(p) => p - desc.eye,
            Aim::Direction(d) => d,
        };
        if !(dir.length() > 0.0 && dir.is_finite()) {
            return Err(CameraError::NoDirection);
        }
        let forward = dir.normalize();
        let right = forward.cross(desc.up);
        if right.length().is_nan() || right.length() <= 1e-9 * desc.up.length() || !right.is_finite() {
            return Err(CameraError::UpParallel);
        }
        let right = right.normalize();
        let up = right.cross(forward);
        let (wf, hf) = (f64::from(w), f64::from(h));
        let edges = desc.sweep == Sweep::WindowEdges;
        // Window extent over d. With an angle, s_k = s_j·v_res/h_res as in the lecture; with a pixel size,
        // neighbouring pixel centres are s apart in both directions.
        let (half_w, half_h) = match desc.field {
            Field::HorizontalAngle(theta) => {
                if !(theta > 0.0 && theta < 180.0) {
                    return Err(CameraError::Field(format!(
                        "horizontal view angle must be in (0, 180) degrees, got {theta}"
                    )));
                }
                let half_w = (theta.to_radians() / 2.0).tan();
                (half_w, half_w * hf / wf)
            }
            Field::PixelSize(s) => {
                if !(s > 0.0 && s.is_finite()) {
                    return Err(CameraError::Field(format!("pixel size must be positive, got {s}")));
                }
                let span = |n: f64| if edges { (n - 1.0).max(1.0) } else { n };
                (s * span(wf) / (2.0 * desc.distance), s * span(hf) / (2.0 * desc.distance))
            }
        };
        // Pixel-space coordinate (column j's centre at j + ½) to window coordinate in [−1, 1].
        let axis = |n: f64| -> (f64, f64) {
            if !edges {
                (2.0 / n, -1.0)
            } else if n > 1.0 {
                (2.0 / (n - 1.0), -1.0 - 1.0 / (n - 1.0))
            } else {
                (0.0, 0.0)
            }
        };
        let (u_scale, u_offset) = axis(wf);
        let (v_scale, v_offset) = axis(hf);
        Ok(Self {
            eye: desc.eye.into(),
            forward: forward.into(),
            right: right.into(),
            up: up.into(),
            half_w,
            half_h,
            u_scale,
            u_offset,
            v_scale: -v_scale,
            v_offset: -v_offset,
            distance: desc.distance,
            width: w,
            height: h,
            start: 0.0,
        })
    }

    /// The primary ray through pixel-space point (sx, sy), computed in f64 and rounded once to f32: the
    /// benchmark contract's ray (DESIGN.md) to the nearest f32, so bareray traces exactly the rays an f64
    /// reference rounds. Every renderer path generates camera rays through `Camera::rays`, so every width traces
    /// the same rays.
    #[inline]
    pub fn ray_f32(&self, sx: f32, sy: f32) -> Ray<f32> {
        self.rays(sx, sy)
    }

    /// [`Camera::ray_f32`] for each lane of (sx, sy), four lanes at a time in `f64x4` by the same
    /// operations in the same order (IEEE, no fusing), so each lane's ray is bit for bit the scalar one. The
    /// origin is the eye, or in a far scene each lane's start point ([`Camera::start`]).
    #[inline]
    pub(crate) fn rays<F: Lanes>(&self, sx: F, sy: F) -> Ray<F> {
        if self.start != 0.0 {
            self.rays_from_start(sx, sy)
        } else {
            self.rays_from_eye(sx, sy)
        }
    }

    /// [`Camera::rays`] with the choice between the eye and the start points made by the caller: a packet
    /// loop compiled for each `FAR` and chosen once per pass tests nothing per packet. (With the test in
    /// every call, the near path compiled to more instructions: PERF.md, Register, "Camera rays' origin
    /// chosen once per pass".)
    #[inline(always)]
    pub(crate) fn rays_in<F: Lanes, const FAR: bool>(&self, sx: F, sy: F) -> Ray<F> {
        if FAR {
            self.rays_from_start(sx, sy)
        } else {
            self.rays_from_eye(sx, sy)
        }
    }

    /// [`Camera::rays`] from the eye (a camera whose [`Camera::start`] is 0).
    #[inline]
    fn rays_from_eye<F: Lanes>(&self, sx: F, sy: F) -> Ray<F> {
        let (x, y) = (padded(sx), padded(sy));
        let mut dir = [[0.0f32; 16]; 3];
        for first in (0..F::K.max(4)).step_by(4) {
            let d = self.directions4(four(&x, first), four(&y, first));
            for (out, d) in dir.iter_mut().zip(d) {
                out[first..first + 4].copy_from_slice(&d.map(|c| c as f32));
            }
        }
        let lanes = |v: &[f32; 16]| F::load(v, 0);
        Ray::new(F::splat_v3(self.eye.to_f32()), V3::new(lanes(&dir[0]), lanes(&dir[1]), lanes(&dir[2])))
    }

    /// [`Camera::rays`] for a far scene's camera: each lane starts [`Camera::start`] along its f64 unit
    /// direction from the eye, the point computed in f64 (each lane's own operations) and rounded once.
    #[cold]
    #[inline(never)]
    fn rays_from_start<F: Lanes>(&self, sx: F, sy: F) -> Ray<F> {
        let (x, y) = (padded(sx), padded(sy));
        let (mut dir, mut origin) = ([[0.0f32; 16]; 3], [[0.0f32; 16]; 3]);
        let eye = [self.eye.x, self.eye.y, self.eye.z];
        for first in (0..F::K.max(4)).step_by(4) {
            let d = self.directions4(four(&x, first), four(&y, first));
            for (((dir, origin), d), e) in dir.iter_mut().zip(origin.iter_mut()).zip(d).zip(eye) {
                dir[first..first + 4].copy_from_slice(&d.map(|c| c as f32));
                origin[first..first + 4].copy_from_slice(&d.map(|c| (e + c * self.start) as f32));
            }
        }
        let lanes = |v: &[f32; 16]| F::load(v, 0);
        let v3 = |v: &[[f32; 16]; 3]| V3::new(lanes(&v[0]), lanes(&v[1]), lanes(&v[2]));
        Ray::new(v3(&origin), v3(&dir))
    }

    /// Unit directions toward four pixel-space points: [`Camera::ray`]'s `toward`, then scaled by
    /// `1/|d|`, per lane.
    #[inline(always)]
    fn directions4(&self, sx: f64x4, sy: f64x4) -> [[f64; 4]; 3] {
        let s = f64x4::splat;
        let u = (sx * s(self.u_scale) + s(self.u_offset)) * s(self.half_w);
        let v = (sy * s(self.v_scale) + s(self.v_offset)) * s(self.half_h);
        let axis = |f: f64, r: f64, up: f64| s(f) + s(r) * u + s(up) * v;
        let (f, r, up) = (self.forward, self.right, self.up);
        let (x, y, z) = (axis(f.x, r.x, up.x), axis(f.y, r.y, up.y), axis(f.z, r.z, up.z));
        // One division for three components: the f64 result is within an ulp of `x / len`, far below the
        // f32 rounding that follows.
        let inv_len = s(1.0) / (x * x + y * y + z * z).sqrt();
        [(x * inv_len).to_array(), (y * inv_len).to_array(), (z * inv_len).to_array()]
    }

    /// The [`Pyramid`] enclosing the rays [`Camera::rays`] generates toward pixel-space points in
    /// `sx[0]..=sx[1]` × `sy[0]..=sy[1]` (a packet's block), or `None` for a view too wide to bound this way.
    ///
    /// Exactly, the direction toward window point (U, V) is t = Z + U·X + V·Y in the orthonormal frame, so
    /// the normal X − U₀·Z gives t·n = U − U₀ ≥ 0 for every U ≥ U₀, and likewise for the other three sides.
    /// The traced direction is t/|t| rounded to f32, within 2⁻²⁴ of the exact one (the f64 steps add far
    /// less), and the stored normal is rounded too. Widening each normal by m·Z, m = 16·2⁻²⁴·|n|·L with
    /// L ≥ |t|, keeps n·d ≥ 0 with at least five times the room those two roundings need (about 3·2⁻²⁴·|n|),
    /// as Z·d ≥ 1/L − 2⁻²⁴.
    /// Rays that start away from the eye ([`Camera::start`]) get none: their f32 origins are rounded one by
    /// one, so they share no apex.
    pub(crate) fn pyramid(&self, sx: [f32; 2], sy: [f32; 2]) -> Option<Pyramid> {
        if self.start != 0.0 {
            return None;
        }
        self.window_pyramid(sx, sy)
    }

    /// The planes of [`Camera::pyramid`] through the eye (rounded to f32) whether or not the rays start
    /// there: a [`Pyramid`] that encloses every exact direction from the eye toward the window, for tests of
    /// what those directions may reach (coverage's tiles). The widening also covers the apex's rounding
    /// where the eye is not at the origin of rendering space (a far scene): it moves the planes by at most
    /// 2⁻²⁴·|n|₁·|eye|, an angle below 2⁻²³ seen from the eye at the geometry's distance (beyond half of
    /// |eye|), within the room above the normals' own rounding.
    pub(crate) fn window_pyramid(&self, sx: [f32; 2], sy: [f32; 2]) -> Option<Pyramid> {
        // `directions4`'s operations: the edge lanes get these very U and V, and since rounding is
        // monotone every lane between them lies between.
        let window = |s: f32, scale: f64, offset: f64, half: f64| (f64::from(s) * scale + offset) * half;
        let range = |a: f64, b: f64| (a.min(b), a.max(b));
        let u = |s: f32| window(s, self.u_scale, self.u_offset, self.half_w);
        let v = |s: f32| window(s, self.v_scale, self.v_offset, self.half_h);
        let ((u0, u1), (v0, v1)) = (range(u(sx[0]), u(sx[1])), range(v(sy[0]), v(sy[1])));
        // |t| = √(1 + U² + V²) ≤ 1 + |U| + |V| = L; beyond 1000 (θ near 180°) Z·d is too small to lean on.
        let length_bound = 1.0 + u0.abs().max(u1.abs()) + v0.abs().max(v1.abs());
        if length_bound.is_nan() || length_bound > 1e3 {
            return None;
        }
        let (z, x, y) = (self.forward, self.right, self.up);
        // Each side as (a, b) with normal a·X + b·Y + c·Z; |n| ≤ 1 + |c|.
        let sides = [(1.0, 0.0, -u0), (-1.0, 0.0, u1), (0.0, 1.0, -v0), (0.0, -1.0, v1)];
        let normals = sides.map(|(a, b, c): (f64, f64, f64)| {
            let widen = 8.0 * f64::from(f32::EPSILON) * (1.0 + c.abs()) * length_bound;
            let n = x * a + y * b + z * (c + widen);
            [n.x as f32, n.y as f32, n.z as f32]
        });
        let eye = self.eye.to_f32();
        // Z·d ≥ 1/L − 2⁻²⁴ ≥ 10⁻³ − 2⁻²⁴ for the exact Z; rounding Z to f32 moves Z·d by about 2⁻²⁴.
        let axis = [z.x as f32, z.y as f32, z.z as f32];
        Some(Pyramid { apex: [eye.x, eye.y, eye.z], normals, axis })
    }

    /// Rounds the frame to f32 once; f32 rays are generated from these values.
    pub fn to_f32(&self) -> Camera<f32> {
        let f = |v: f64| v as f32;
        Camera {
            eye: self.eye.to_f32(),
            forward: self.forward.to_f32(),
            right: self.right.to_f32(),
            up: self.up.to_f32(),
            half_w: f(self.half_w),
            half_h: f(self.half_h),
            u_scale: f(self.u_scale),
            u_offset: f(self.u_offset),
            v_scale: f(self.v_scale),
            v_offset: f(self.v_offset),
            distance: f(self.distance),
            width: self.width,
            height: self.height,
            start: f(self.start),
        }
    }
}

impl<F: Real> Camera<F> {
    /// The (unnormalised) offset from the eye, at unit distance, toward pixel-space point (sx, sy).
    #[inline(always)]
    fn toward(&self, sx: F, sy: F) -> V3<F> {
        let u = (sx * self.u_scale + self.u_offset) * self.half_w;
        let v = (sy * self.v_scale + self.v_offset) * self.half_h;
        self.forward + self.right * u + self.up * v
    }

    /// The primary ray through pixel-space point (sx, sy): column j's centre is sx = j + ½, row k's
    /// sy = k + ½. The direction is unit length; the origin is [`Camera::start`] along it from the eye.
    #[inline(always)]
    pub fn ray(&self, sx: F, sy: F) -> Ray<F> {
        let dir = self.toward(sx, sy).normalize();
        Ray::new(self.eye + dir * self.start, dir)
    }

    /// The point on the image plane (distance d) that pixel-space point (sx, sy) looks through: P_j,k
    /// (the lecture's formula, which the tests check the rays against).
    #[cfg(test)]
    pub(crate) fn image_plane_point(&self, sx: F, sy: F) -> V3<F> {
        self.eye + self.toward(sx, sy) * self.distance
    }
}
