//! Scalar math data copied into every lane, so packet code runs the generic kernels on it unchanged.
//!
//! An inherent method of [`Affine`] kept here rather than in `math`, because `simd` sits above `math` (lane
//! types are `Real`s over `V3`) and `math` imports nothing of the crate. Types of higher layers define their
//! own `to_lanes` beside them (`geometry::Shape::to_lanes`).

use crate::math::Affine;

use super::Lanes;

impl Affine<f32> {
    /// The same map in every lane.
    #[allow(clippy::wrong_self_convention)] // &self: callers hold references, and the wide forms are large
    pub(crate) fn to_lanes<F: Lanes>(&self) -> Affine<F> {
        Affine { cols: self.cols.map(F::splat_v3), translation: F::splat_v3(self.translation) }
    }
}
