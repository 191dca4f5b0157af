//! Numbers, vectors, affine maps and the random generator, shared by every stage.

pub(crate) mod affine;
pub(crate) mod color;
pub(crate) mod real;
pub(crate) mod rng;
pub(crate) mod vec3;

pub(crate) use affine::Affine;
pub use color::Rgb8;
pub use real::{Mask, Real};
pub use rng::SplitMix64;
pub(crate) use vec3::Vec3f;
pub use vec3::{Rgb, V3};
