//! Scenes: read (TOML, NFF, xyzr) or generated into a plain [`desc::SceneDesc`], then compiled into a [`Scene`].

mod compile;
pub mod desc;
pub mod error;
pub mod features;
pub mod generate;
pub mod nff;
pub mod toml;
pub mod xyzr;

pub use compile::{Accel, Light, Scene, BVH_MIN_SPHERES};
pub use desc::SceneDesc;
pub use error::SceneError;
