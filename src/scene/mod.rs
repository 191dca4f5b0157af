//! The scene description: a scene as plain, validated data ([`SceneDesc`]), whatever reader or generator
//! ([`crate::io`]) made it; [`crate::compile`] turns it into the runtime scene.

pub mod desc;

pub use desc::SceneDesc;
