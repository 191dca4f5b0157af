//! The render settings ([`RenderDesc`]): the sampling pattern, the reconstruction filter and the postfilter,
//! the depth, the background and ambient colours, and how values become 8-bit pixels.

use super::shade::Shade;
use crate::math::Rgb;

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
