//! `SceneDesc`: a scene as plain, validated data in f64, whatever file format it came from.
//! Compile (`crate::compile`) turns it into the immutable [`crate::compile::Scene`] the renderer reads.

use glam::DVec3;

use crate::kinds::KindDescs;
use crate::math::{Rgb, Rgb8};

/// Where the camera looks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Aim {
    /// A point the view direction passes through.
    LookAt(DVec3),
    /// The view direction itself (any length).
    Direction(DVec3),
}

/// How wide the camera sees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Field {
    /// Horizontal view angle θ in degrees: the window is `s_j = 2·d·tan(θ/2)` wide.
    HorizontalAngle(f64),
    /// Pixel size s on the image plane at distance d: the window is `s·h_res` wide, so the field of view grows
    /// with s and with the resolution.
    PixelSize(f64),
}

/// Where pixel (j, k) samples the image plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Sweep {
    /// Pixel centres at `(j + ½)/h_res` across the window (pbrt, Embree, POV-Ray).
    #[default]
    PixelCentre,
    /// The lecture's `j/(h_res − 1)`: the first and last pixel centres lie on the window's edges.
    WindowEdges,
}

/// The lecture's camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraDesc {
    /// Eye point O.
    pub eye: DVec3,
    /// View direction Z_v, or a point it passes through.
    pub aim: Aim,
    /// Up vector Y_v: need be neither unit nor perpendicular to the view direction.
    pub up: DVec3,
    /// Image-plane distance d.
    pub distance: f64,
    /// View angle or pixel size.
    pub field: Field,
    /// Horizontal resolution h_res.
    pub width: u32,
    /// Vertical resolution v_res.
    pub height: u32,
    /// Pixel-centre or window-edge sampling.
    pub sweep: Sweep,
}

impl CameraDesc {
    /// A camera at `eye` looking at `look` with `up` up, a horizontal field of view of `hfov` degrees and
    /// `width` × `height` pixels, rays through the pixel centres (image plane at distance 1).
    pub(crate) fn looking_at(eye: DVec3, look: DVec3, up: DVec3, hfov: f64, width: u32, height: u32) -> Self {
        Self {
            eye,
            aim: Aim::LookAt(look),
            up,
            distance: 1.0,
            field: Field::HorizontalAngle(hfov),
            width,
            height,
            sweep: Sweep::PixelCentre,
        }
    }
}

/// Changes to a camera: the command line's `--eye --look --up --hfov --width --height`, and the Python
/// module's keywords of the same names.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CameraOverrides {
    /// Eye point.
    pub eye: Option<DVec3>,
    /// A point to look at.
    pub look: Option<DVec3>,
    /// Up vector.
    pub up: Option<DVec3>,
    /// Horizontal field of view in degrees (pixel-centre sweep).
    pub hfov: Option<f64>,
    /// Width in pixels; given alone, the height follows the camera's aspect ratio.
    pub width: Option<u32>,
    /// Height in pixels; given alone, the width follows the camera's aspect ratio.
    pub height: Option<u32>,
}

impl CameraOverrides {
    /// Applies the changes to `cam`.
    pub fn apply(&self, cam: &mut CameraDesc) {
        if let Some(eye) = self.eye {
            cam.eye = eye;
        }
        if let Some(look) = self.look {
            cam.aim = Aim::LookAt(look);
        }
        if let Some(up) = self.up {
            cam.up = up;
        }
        if let Some(hfov) = self.hfov {
            cam.field = Field::HorizontalAngle(hfov);
            cam.sweep = Sweep::PixelCentre;
        }
        let aspect = f64::from(cam.width) / f64::from(cam.height);
        match (self.width, self.height) {
            (Some(w), Some(h)) => (cam.width, cam.height) = (w, h),
            (Some(w), None) => (cam.width, cam.height) = (w, ((f64::from(w) / aspect).round() as u32).max(1)),
            (None, Some(h)) => (cam.width, cam.height) = (((f64::from(h) * aspect).round() as u32).max(1), h),
            (None, None) => {}
        }
    }
}

impl Default for CameraDesc {
    fn default() -> Self {
        Self {
            eye: DVec3::new(0.0, 0.0, -5.0),
            aim: Aim::LookAt(DVec3::ZERO),
            up: DVec3::Y,
            distance: 1.0,
            field: Field::HorizontalAngle(45.0),
            width: 640,
            height: 480,
            sweep: Sweep::PixelCentre,
        }
    }
}

/// Where the samples of one pixel go.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pattern {
    /// An n×n regular grid of stratum centres (n² samples, box filter).
    Grid(u32),
    /// The lecture's 9 samples at half-pixel spacing (corners, edge midpoints, centre), shared with the
    /// neighbouring pixels (about 4 rays per pixel), weighted by the trapezoid rule.
    HalfPixel,
    /// An n×n jittered grid: one uniform position in each of the n² strata, different in every pixel (seeded
    /// by the pixel's coordinates, so the image does not depend on tiles or threads); box filter.
    Stratified(u32),
    /// N points of the R2 low-discrepancy sequence, rotated by a per-pixel random shift; box filter.
    R2(u32),
    /// N points of the Sobol' sequence's first two dimensions under an Owen (nested uniform) scramble seeded
    /// per pixel; box filter. Any N from 1; at powers of two each pixel's points form a (0, m, 2)-net in base
    /// 2 (every elementary interval of area 1/N holds one).
    Sobol(u32),
    /// Adaptive supersampling after Whitted's: the pixel corners (shared with the neighbours) are traced, and
    /// a square is split into four where its corners see different primitives or depths more than 3% apart
    /// (down to `depth` levels), or differ by more than `threshold` in some channel (down to `depth − 1`
    /// levels, at least 1); a square's value is its corners' mean, or its quarters' mean when split. Flat
    /// regions cost about one ray per pixel.
    Adaptive {
        /// The largest channel difference between two corners of a square left whole (by colour).
        threshold: f32,
        /// Levels of splitting below the pixel (a square at depth d is 2^−d pixels wide).
        depth: u32,
    },
    /// The lecture's prefiltering: the exact area of the pixel each sphere's silhouette covers (an ellipse
    /// under perspective), the shares shaded by one ray each through their centroids and the uncovered rest
    /// by one more. Exact for the weights where silhouettes do not overlap inside a pixel; overlaps, other
    /// primitives, shading across a part and secondary rays are approximated (`render/coverage/mod.rs` says
    /// how). One ray in a pixel covered by one sphere or by none. Reconstruction filters do not apply.
    Coverage,
}

impl Pattern {
    /// Whether a reconstruction filter ([`RenderDesc::filter`]) applies: to the grid, stratified, R2 and
    /// Sobol' samples; the half-pixel, adaptive and coverage patterns weigh their own rays and ignore it.
    pub fn takes_filter(self) -> bool {
        match self {
            Pattern::Grid(_) | Pattern::Stratified(_) | Pattern::R2(_) | Pattern::Sobol(_) => true,
            Pattern::HalfPixel | Pattern::Adaptive { .. } | Pattern::Coverage => false,
        }
    }

    /// Camera rays per pixel (the half-pixel pattern shares its 9 with the neighbours: about 4).
    pub(crate) fn rays_per_pixel(self) -> f64 {
        match self {
            Pattern::Grid(n) | Pattern::Stratified(n) => f64::from(n * n),
            Pattern::R2(count) | Pattern::Sobol(count) => f64::from(count),
            Pattern::HalfPixel => 4.0,
            // At least the shared corners, or one ray a pixel; how many more depends on the image.
            Pattern::Adaptive { .. } | Pattern::Coverage => 1.0,
        }
    }
}

/// A reconstruction filter's profile.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FilterKind {
    /// Equal weight within the radius.
    Box,
    /// Falling linearly to 0 at the radius.
    Tent,
    /// A Gaussian of standard deviation radius/3, lowered to reach 0 at the radius.
    Gaussian,
    /// Mitchell–Netravali (B = C = 1/3), its [−2, 2] support stretched to the radius; negative lobes.
    Mitchell,
}

/// A reconstruction filter applied to the samples: each sample counts in every pixel whose centre is within
/// `radius` (pixels) on both axes, weighted by the profile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Filter {
    /// The profile.
    pub kind: FilterKind,
    /// Half the support's width, in pixels (positive).
    pub radius: f32,
}

impl Filter {
    /// The largest radius accepted, in pixels.
    pub const MAX_RADIUS: f32 = 4.0;

    /// The radius a profile gets when none is given: box 0.5 (the pixel), tent 1, Gaussian 1.5, Mitchell 2.
    pub fn default_radius(kind: FilterKind) -> f32 {
        match kind {
            FilterKind::Box => 0.5,
            FilterKind::Tent => 1.0,
            FilterKind::Gaussian => 1.5,
            FilterKind::Mitchell => 2.0,
        }
    }
}

/// What a camera ray's hit is shaded with.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum Shade {
    /// Whitted: ambient, Lambert and Phong from the point lights with hard shadows, mirror and refraction.
    #[default]
    Whitted,
    /// Ambient occlusion (Tachyon's and aobench's estimate, with rays of a chosen length where theirs are
    /// unlimited): at each camera ray's hit, `samples` cosine-weighted directions over the hemisphere
    /// around the shading normal, each an occlusion ray of length `distance`; the pixel is the surface's
    /// colour times the share of them that nothing blocks. No lights, no secondary rays; rays that hit
    /// nothing show the background.
    Ao(Ao),
}

/// The settings of [`Shade::Ao`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ao {
    /// Occlusion rays per camera ray's hit, from 1 to `Ao::MAX_SAMPLES`.
    pub samples: u32,
    /// The occlusion rays' length in scene units (positive); `None`: `Ao::DEFAULT_REACH` times the diagonal
    /// of the bounded primitives' box, which compiling fills in.
    pub distance: Option<f64>,
}

impl Ao {
    /// The most occlusion rays per hit.
    pub(crate) const MAX_SAMPLES: u32 = 4096;
    /// Occlusion rays per hit when none are given.
    pub(crate) const DEFAULT_SAMPLES: u32 = 16;
    /// The default distance as a share of the diagonal of the box around every bounded primitive: a quarter,
    /// so that occlusion is local (contacts, creases, cavities) rather than the whole scene's shadow.
    pub(crate) const DEFAULT_REACH: f64 = 0.25;
}

impl Shade {
    /// The forms `--shade` and the TOML key `shade` accept.
    pub(crate) const FORMS: &'static str = "whitted, ao, ao:SAMPLES or ao:SAMPLES,DISTANCE";

    /// Parses `whitted` or `ao[:SAMPLES[,DISTANCE]]` (SAMPLES from 1 to `Ao::MAX_SAMPLES`, default
    /// `Ao::DEFAULT_SAMPLES`; DISTANCE a length above 0 in scene units, default from the scene's size).
    pub fn parse(s: &str) -> Result<Shade, String> {
        let forms = Self::FORMS;
        let (mode, args) = match s.trim().split_once(':') {
            Some((m, a)) => (m.trim(), Some(a)),
            None => (s.trim(), None),
        };
        match (mode, args) {
            ("whitted", None) => return Ok(Shade::Whitted),
            ("whitted", Some(_)) => return Err(format!("`whitted` takes no arguments, got `{s}` ({forms})")),
            ("ao", _) => {}
            _ => return Err(format!("unknown shading `{mode}`: {forms}")),
        }
        let Some(args) = args else {
            return Ok(Shade::Ao(Ao { samples: Ao::DEFAULT_SAMPLES, distance: None }));
        };
        let (n, d) = match args.split_once(',') {
            Some((n, d)) => (n, Some(d)),
            None => (args, None),
        };
        let samples = match n.trim().parse::<u32>() {
            Ok(v) if (1..=Ao::MAX_SAMPLES).contains(&v) => v,
            _ => {
                let max = Ao::MAX_SAMPLES;
                return Err(format!("ao's SAMPLES runs from 1 to {max}, got `{}` ({forms})", n.trim()));
            }
        };
        let distance = match d.map(|d| (d, d.trim().parse::<f64>())) {
            None => None,
            Some((_, Ok(v))) if v > 0.0 && v.is_finite() => Some(v),
            Some((d, _)) => {
                let d = d.trim();
                return Err(format!("ao's DISTANCE is a length above 0 in scene units, got `{d}` ({forms})"));
            }
        };
        Ok(Shade::Ao(Ao { samples, distance }))
    }
}

/// A filter over the finished image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum PostFilter {
    /// None.
    #[default]
    None,
    /// The lecture's 3×3 kernel: ½ at the centre, 1/16 at each of the 8 neighbours.
    Lecture3x3,
}

/// How the rendered values become 8-bit pixels (PNG, PPM); EXR output holds the values as they are,
/// linear floats, whatever the transfer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Transfer {
    /// The values are linear radiance, encoded with the sRGB curve (clamped to [0, 1]): TOML scenes.
    #[default]
    Srgb,
    /// The values are written as they are: clamped to [0, 1], times 255, rounded. What SPD's, POV-Ray's
    /// and Tachyon's renders of NFF scenes do, whose colours are display values: NFF and xyzr scenes.
    Linear,
}

impl Transfer {
    /// The name the command line, the TOML key and the PNG metadata use.
    pub fn name(self) -> &'static str {
        match self {
            Transfer::Srgb => "srgb",
            Transfer::Linear => "linear",
        }
    }
}

/// Everything about a render that is not geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderDesc {
    /// Sampling pattern within each pixel.
    pub pattern: Pattern,
    /// Filter applied after sampling.
    pub postfilter: PostFilter,
    /// Reconstruction filter over the samples; `None`: each pixel averages its own samples (a box of the
    /// pixel's size).
    pub filter: Option<Filter>,
    /// Longest chain of reflection/refraction bounces (0: ray casting only).
    pub max_depth: u32,
    /// Whitted shading or ambient occlusion.
    pub shade: Shade,
    /// Colour of rays that hit nothing.
    pub background: Rgb,
    /// Ambient light, scaled by each material's `ambient`.
    pub ambient: Rgb,
    /// How the values become 8-bit pixels.
    pub transfer: Transfer,
}

impl Default for RenderDesc {
    fn default() -> Self {
        Self {
            pattern: Pattern::Grid(1),
            postfilter: PostFilter::None,
            filter: None,
            max_depth: 5,
            shade: Shade::Whitted,
            background: Rgb::new(0.0, 0.0, 0.0),
            ambient: Rgb::all(1.0),
            transfer: Transfer::Srgb,
        }
    }
}

/// A solid-texture checkerboard in object space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Checker {
    /// The colour of the odd cells (the material's colour fills the even ones).
    pub(crate) color: Rgb,
    /// Edge length of a cell.
    pub(crate) size: f32,
}

/// Whitted surface description.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Base colour (diffuse and ambient).
    pub color: Rgb,
    /// Optional checkerboard.
    pub checker: Option<Checker>,
    /// Ambient coefficient.
    pub ambient: f32,
    /// Lambert coefficient.
    pub diffuse: f32,
    /// Phong highlight coefficient.
    pub specular: f32,
    /// Phong exponent.
    pub shininess: f32,
    /// Mirror reflection weight.
    pub reflect: f32,
    /// Transmission weight.
    pub transmit: f32,
    /// Index of refraction (inside over outside).
    pub ior: f32,
    /// Split the transmitted weight by the dielectric Fresnel reflectance instead of fixed weights.
    pub fresnel: bool,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            color: Rgb::all(0.8),
            checker: None,
            ambient: 0.1,
            diffuse: 0.9,
            specular: 0.0,
            shininess: 32.0,
            reflect: 0.0,
            transmit: 0.0,
            ior: 1.5,
            fresnel: false,
        }
    }
}

/// How a light's intensity falls with distance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Falloff {
    /// Constant (the classic Whitted light).
    #[default]
    None,
    /// 1/r² (a physical point light).
    InverseSquare,
}

/// A coloured point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightDesc {
    /// Where it is.
    pub position: DVec3,
    /// Colour times intensity.
    pub color: Rgb,
    /// Distance falloff.
    pub falloff: Falloff,
}

/// A sphere kept in the fast SoA layout.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereDesc {
    /// Centre.
    pub center: DVec3,
    /// Radius (> 0).
    pub radius: f64,
    /// Index into `SceneDesc::materials`.
    pub material: u32,
}

/// The box around `spheres` (each centre ± radius), `(+∞, −∞)` for none: a parallel reduction by
/// [`box_union`], so the same box however the list is cut.
pub(crate) fn sphere_bounds(spheres: &[SphereDesc]) -> (DVec3, DVec3) {
    use rayon::prelude::*;
    // Both corners on both sides, so a sphere built by hand with a negative radius still spans its box.
    let ball = |s: &SphereDesc| {
        let (a, b) = (s.center - s.radius, s.center + s.radius);
        box_union((a, a), (b, b))
    };
    let empty = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    spheres.par_iter().with_min_len(1 << 14).map(ball).reduce(|| empty, box_union)
}

/// The union of two boxes `(lo, hi)`, component by component with `f64::min` and `f64::max`: exact,
/// associative and commutative, a NaN ignored (glam's `min` and `max` are neither for NaN), so a reduction
/// gives the same box in any order.
pub(crate) fn box_union((lo, hi): (DVec3, DVec3), (l, h): (DVec3, DVec3)) -> (DVec3, DVec3) {
    let min = DVec3::new(lo.x.min(l.x), lo.y.min(l.y), lo.z.min(l.z));
    (min, DVec3::new(hi.x.max(h.x), hi.y.max(h.y), hi.z.max(h.z)))
}

/// A whole scene as data.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct SceneDesc {
    /// The camera.
    pub camera: CameraDesc,
    /// Sampling, depth, background.
    pub render: RenderDesc,
    /// Materials; primitives refer to them by index.
    pub materials: Vec<Material>,
    /// Point lights.
    pub lights: Vec<LightDesc>,
    /// Plain spheres: ids 0.. in this order.
    pub spheres: Vec<SphereDesc>,
    /// Per-sphere colours: empty, or one per sphere of `spheres` in its order, each replacing its sphere's
    /// material colour (the ambient and diffuse base; a checker's odd cells keep theirs). Particle files
    /// and arrays of spheres give every sphere its colour this way, beside one shared material, rather
    /// than a material per colour. Compile ignores a list of another length (a description built by hand),
    /// as it degrades other inconsistent hand-built input: the spheres keep their materials' colours.
    pub sphere_colors: Vec<Rgb8>,
    /// The registered kinds' primitives ([`crate::kinds`]: polygons, ellipsoids, planes, open cones, tori):
    /// ids after the spheres, kind by kind in the registry's order (a polygon one id however it is
    /// triangulated).
    pub kinds: KindDescs,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The box of a list with NaN centres and radii here and there is the box of its other spheres, on one
    /// thread or three (glam's `min` would have kept or dropped a NaN depending on the order).
    #[test]
    fn sphere_bounds_ignore_nan_in_any_order() {
        let sphere = |i: usize| {
            let f = i as f64;
            let center = DVec3::new(f.sin() * 10.0, f * 0.01, -(f.cos() * 3.0));
            SphereDesc { center, radius: 0.5, material: 0 }
        };
        let finite: Vec<SphereDesc> = (0..70_000).map(sphere).collect();
        let mut with_nan = finite.clone();
        for i in [0, 1, 16_383, 16_384, 40_000, 69_999] {
            with_nan.insert(i, SphereDesc { center: DVec3::new(f64::NAN, 1.0, 2.0), ..sphere(i) });
            with_nan.insert(i + 1, SphereDesc { radius: f64::NAN, ..sphere(i) });
        }
        let on = |threads: usize, spheres: &[SphereDesc]| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| sphere_bounds(spheres))
        };
        let expected = on(1, &finite);
        assert!(expected.0.is_finite() && expected.1.is_finite());
        assert_eq!(on(1, &with_nan), expected);
        assert_eq!(on(3, &with_nan), expected);
        assert_eq!(on(3, &[]), (DVec3::INFINITY, DVec3::NEG_INFINITY));
    }
}
