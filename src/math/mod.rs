//! Numbers, vectors and affine maps shared by every stage.

pub mod affine;
pub mod real;
pub mod vec3;

pub use affine::Affine;
pub use real::{Mask, Real};
pub use vec3::{Rgb, Vec3f, V3};
