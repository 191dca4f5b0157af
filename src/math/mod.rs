//! Numbers, vectors, affine maps and the random generator, shared by every stage.

pub mod affine;
pub mod color;
pub mod real;
pub mod rng;
pub mod vec3;

pub use affine::Affine;
pub use color::Rgb8;
pub use real::{Mask, Real};
pub use rng::SplitMix64;
pub use vec3::{Rgb, Vec3f, V3};
