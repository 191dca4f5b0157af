//! The TOML `transform` list (translate, scale, rotate steps, applied in order) as an affine map: read by
//! the scene reader for spheres (a transformed sphere is an ellipsoid), and by the kinds whose tables take a
//! transform (ellipsoids, planes, tori).

use glam::{DAffine3, DVec3};
use serde::Deserialize;
use toml::Spanned;

use super::KindError;

/// One step of a TOML `transform` list.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename_all = "lowercase")]
pub(crate) enum TransformOp {
    /// Move by a vector.
    Translate([f64; 3]),
    /// Scale about the origin.
    Scale(Scale),
    /// Rotate about an axis through the origin.
    Rotate(Rotation),
}

/// A scale step: one factor, or one per axis.
#[derive(Deserialize)]
#[serde(untagged, expecting = "a number or an array of three numbers")]
pub(crate) enum Scale {
    /// The same factor on every axis.
    Uniform(f64),
    /// A factor per axis.
    Axes([f64; 3]),
}

/// A rotation step: right-handed, by `degrees` about `axis`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Rotation {
    /// The axis (any non-zero length).
    pub(crate) axis: [f64; 3],
    /// The angle in degrees.
    pub(crate) degrees: f64,
}

/// The steps composed in order (the first applied first); an error names the step that is singular or not
/// finite, or a rotation about a zero axis.
pub(crate) fn transform(ops: &[Spanned<TransformOp>]) -> Result<DAffine3, KindError> {
    let mut m = DAffine3::IDENTITY;
    for op in ops {
        let err = |message: &str| KindError { span: op.span(), message: message.into() };
        let step = match op.get_ref() {
            TransformOp::Translate(t) => DAffine3::from_translation((*t).into()),
            TransformOp::Scale(Scale::Uniform(s)) => DAffine3::from_scale(DVec3::splat(*s)),
            TransformOp::Scale(Scale::Axes(s)) => DAffine3::from_scale((*s).into()),
            TransformOp::Rotate(r) => {
                let axis = DVec3::from(r.axis);
                if axis.length().is_nan() || axis.length() <= 0.0 {
                    return Err(err("rotation axis must be a non-zero vector"));
                }
                DAffine3::from_axis_angle(axis.normalize(), r.degrees.to_radians())
            }
        };
        let det = step.matrix3.determinant();
        if !(det.abs() > 1e-12 && det.is_finite() && step.translation.is_finite()) {
            return Err(err("transform step is singular or not finite (zero scale?)"));
        }
        m = step * m;
    }
    Ok(m)
}
