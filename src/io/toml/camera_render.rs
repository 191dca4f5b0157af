//! The `[camera]` and `[render]` tables: the camera's position, aim, field and resolution, and the render
//! settings (sampling pattern, filters, depth, shading, colours, transfer), read into their descriptions.

use ::toml::Spanned;
use glam::DVec3;
use serde::Deserialize;

use super::{grid_side, Reader, Vec3};
use crate::camera::Camera;
use crate::io::error::SceneError;
use crate::scene::desc::{
    Aim, CameraDesc, Field, Filter, FilterKind, Pattern, PostFilter, RenderDesc, Shade, Sweep, Transfer,
};

/// The `[camera]` table.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraToml {
    eye: Option<Vec3>,
    look_at: Option<Vec3>,
    direction: Option<Vec3>,
    up: Option<Vec3>,
    distance: Option<f64>,
    hfov: Option<f64>,
    pixel_size: Option<f64>,
    width: Option<u32>,
    height: Option<u32>,
    sweep: Option<SweepToml>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "kebab-case")]
enum SweepToml {
    PixelCentre,
    WindowEdges,
}

/// The `[render]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RenderToml {
    samples: Option<Spanned<u32>>,
    pattern: Option<PatternToml>,
    postfilter: Option<PostFilterToml>,
    filter: Option<FilterToml>,
    filter_radius: Option<Spanned<f64>>,
    max_depth: Option<u32>,
    shade: Option<Spanned<String>>,
    background: Option<Spanned<Vec3>>,
    ambient: Option<Spanned<Vec3>>,
    transfer: Option<TransferToml>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "kebab-case")]
enum TransferToml {
    Srgb,
    Linear,
}

#[derive(Deserialize, Clone, Copy, PartialEq)]
#[serde(rename_all = "kebab-case")]
enum PatternToml {
    Grid,
    HalfPixel,
    Stratified,
    R2,
    Sobol,
    Coverage,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "kebab-case")]
enum FilterToml {
    Box,
    Tent,
    Gaussian,
    Mitchell,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "kebab-case")]
enum PostFilterToml {
    None,
    #[serde(rename = "lecture-3x3")]
    Lecture3x3,
}

impl Reader<'_> {
    /// The camera of the table, or the default camera without one; checked by building a [`Camera`].
    pub(super) fn camera(&self, cam: Option<Spanned<CameraToml>>) -> Result<CameraDesc, SceneError> {
        let Some(cam) = cam else {
            return Ok(CameraDesc::default());
        };
        let span = cam.span();
        let c = cam.into_inner();
        let d = CameraDesc::default();
        let aim = match (c.look_at, c.direction) {
            (Some(_), Some(_)) => return Err(self.err(span, "camera: give look_at or direction, not both")),
            (Some(p), None) => Aim::LookAt(p.into()),
            (None, Some(v)) => Aim::Direction(v.into()),
            (None, None) => d.aim,
        };
        let field = match (c.hfov, c.pixel_size) {
            (Some(_), Some(_)) => return Err(self.err(span, "camera: give hfov or pixel_size, not both")),
            (Some(a), None) => Field::HorizontalAngle(a),
            (None, Some(s)) => Field::PixelSize(s),
            (None, None) => d.field,
        };
        let desc = CameraDesc {
            eye: c.eye.map_or(d.eye, DVec3::from),
            aim,
            up: c.up.map_or(d.up, DVec3::from),
            distance: c.distance.unwrap_or(d.distance),
            field,
            width: c.width.unwrap_or(d.width),
            height: c.height.unwrap_or(d.height),
            sweep: match c.sweep {
                None => d.sweep,
                Some(SweepToml::PixelCentre) => Sweep::PixelCentre,
                Some(SweepToml::WindowEdges) => Sweep::WindowEdges,
            },
        };
        // Catch unusable cameras here, where the error can point at the table.
        Camera::new(&desc).map_err(|e| self.err(span, format!("camera: {e}")))?;
        Ok(desc)
    }

    /// The render settings of the table, the defaults for what it leaves out.
    pub(super) fn render(&self, r: Option<RenderToml>) -> Result<RenderDesc, SceneError> {
        let d = RenderDesc::default();
        let Some(r) = r else { return Ok(d) };
        let pattern = match (r.pattern.unwrap_or(PatternToml::Grid), &r.samples) {
            (PatternToml::HalfPixel, Some(s)) if *s.get_ref() != 9 => {
                return Err(self.err(s.span(), "the half-pixel pattern takes 9 samples per pixel"));
            }
            (PatternToml::HalfPixel, _) => Pattern::HalfPixel,
            (PatternToml::Grid, None) => d.pattern,
            (PatternToml::Grid, Some(s)) => {
                Pattern::Grid(grid_side(*s.get_ref()).map_err(|m| self.err(s.span(), m))?)
            }
            (PatternToml::Stratified, None) => Pattern::Stratified(1),
            (PatternToml::Stratified, Some(s)) => {
                Pattern::Stratified(grid_side(*s.get_ref()).map_err(|m| self.err(s.span(), m))?)
            }
            (PatternToml::R2, None) => Pattern::R2(1),
            (PatternToml::R2, Some(s)) if *s.get_ref() == 0 => {
                return Err(self.err(s.span(), "the R2 pattern takes at least 1 sample per pixel"));
            }
            (PatternToml::R2, Some(s)) => Pattern::R2(*s.get_ref()),
            (PatternToml::Sobol, None) => Pattern::Sobol(1),
            (PatternToml::Sobol, Some(s)) if *s.get_ref() == 0 => {
                return Err(self.err(s.span(), "the Sobol pattern takes at least 1 sample per pixel"));
            }
            (PatternToml::Sobol, Some(s)) => Pattern::Sobol(*s.get_ref()),
            (PatternToml::Coverage, Some(s)) => {
                return Err(self.err(s.span(), "the coverage pattern computes areas and takes no samples"));
            }
            (PatternToml::Coverage, None) => Pattern::Coverage,
        };
        let filter = match (r.filter, &r.filter_radius) {
            (None, None) => None,
            (None, Some(radius)) => return Err(self.err(radius.span(), "filter_radius needs a filter")),
            (Some(kind), radius) => {
                let kind = match kind {
                    FilterToml::Box => FilterKind::Box,
                    FilterToml::Tent => FilterKind::Tent,
                    FilterToml::Gaussian => FilterKind::Gaussian,
                    FilterToml::Mitchell => FilterKind::Mitchell,
                };
                let radius = match radius {
                    None => Filter::default_radius(kind),
                    Some(r) => match *r.get_ref() {
                        v if v > 0.0 && v <= f64::from(Filter::MAX_RADIUS) => v as f32,
                        _ => {
                            let max = Filter::MAX_RADIUS;
                            return Err(
                                self.err(r.span(), format!("filter_radius runs above 0 up to {max} pixels"))
                            );
                        }
                    },
                };
                Some(Filter { kind, radius })
            }
        };
        Ok(RenderDesc {
            pattern,
            filter,
            postfilter: match r.postfilter {
                None => d.postfilter,
                Some(PostFilterToml::None) => PostFilter::None,
                Some(PostFilterToml::Lecture3x3) => PostFilter::Lecture3x3,
            },
            max_depth: r.max_depth.unwrap_or(d.max_depth),
            shade: match &r.shade {
                None => d.shade,
                Some(m) => {
                    Shade::parse(m.get_ref()).map_err(|e| self.err(m.span(), format!("shade: {e}")))?
                }
            },
            background: r.background.as_ref().map_or(Ok(d.background), |c| self.color(c, "background"))?,
            ambient: r.ambient.as_ref().map_or(Ok(d.ambient), |c| self.color(c, "ambient"))?,
            transfer: match r.transfer {
                None => d.transfer,
                Some(TransferToml::Srgb) => Transfer::Srgb,
                Some(TransferToml::Linear) => Transfer::Linear,
            },
        })
    }
}
