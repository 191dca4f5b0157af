//! Affine maps (a 3×3 linear part and a translation) generic over [`Real`].
//!
//! Scenes build their transforms in f64 with glam; compile rounds them once to the working type.

use super::real::Real;
use super::vec3::V3;

/// `p ↦ L·p + t`, with `L` stored by columns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Affine<F> {
    /// The columns of the linear part.
    pub(crate) cols: [V3<F>; 3],
    /// The translation.
    pub(crate) translation: V3<F>,
}

impl<F: Real> Affine<F> {
    /// Maps a direction (linear part only); lengths change, so ray parameters t are preserved.
    #[inline(always)]
    pub(crate) fn vector(&self, v: V3<F>) -> V3<F> {
        self.cols[0] * v.x + self.cols[1] * v.y + self.cols[2] * v.z
    }
}

impl Affine<f64> {
    /// From glam's f64 affine map.
    pub(crate) fn from_glam(a: &glam::DAffine3) -> Self {
        Self {
            cols: [a.matrix3.x_axis.into(), a.matrix3.y_axis.into(), a.matrix3.z_axis.into()],
            translation: a.translation.into(),
        }
    }
    /// Rounds every entry to f32.
    #[allow(clippy::wrong_self_convention)] // &self: callers hold references, and the wide forms are large
    pub(crate) fn to_f32(&self) -> Affine<f32> {
        Affine { cols: self.cols.map(V3::to_f32), translation: self.translation.to_f32() }
    }
}

/// The linear map that carries object-space normals to world space: the inverse transpose of
/// `world_from_object`'s linear part (no translation), as an [`Affine`] with zero translation.
pub(crate) fn normal_to_world(world_from_object: &glam::DAffine3) -> Affine<f64> {
    let m = world_from_object.matrix3.inverse().transpose();
    Affine::from_glam(&glam::DAffine3 { matrix3: m, translation: glam::DVec3::ZERO })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DAffine3, DVec3};

    #[test]
    fn normals_stay_perpendicular_under_non_uniform_scale() {
        // A plane tilted 45° and squashed in x: its tangent maps with the matrix, its normal with the
        // inverse transpose, and the two must stay perpendicular.
        let m = DAffine3::from_scale(DVec3::new(0.25, 1.0, 1.0)) * DAffine3::from_rotation_y(0.7);
        let tangent = m.transform_vector3(DVec3::X);
        let n = normal_to_world(&m).vector(V3::new(0.0, 0.0, 1.0));
        assert!(DVec3::from(n).dot(tangent).abs() < 1e-12);
    }
}
