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
pub use vec3::{Rgb, Vec3f, V3};
