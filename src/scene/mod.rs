//! Scenes: read (TOML, later NFF and xyzr) into a plain [`desc::SceneDesc`], then compiled into a [`Scene`].

mod compile;
pub mod desc;
pub mod error;
pub mod toml;

pub use compile::{Light, Scene};
pub use desc::SceneDesc;
pub use error::SceneError;
