//! Scene readers (TOML, NFF, xyzr) and generators: files and parameters become a plain [`SceneDesc`], which
//! [`crate::compile`] turns into the runtime scene.

pub mod error;
pub mod generate;
pub mod nff;
pub mod toml;
pub mod xyzr;

pub use error::SceneError;

use crate::scene::SceneDesc;

/// Reads a scene file, choosing the reader by its extension: `.toml`, `.nff` or `.xyzr` (a directory is an
/// error saying so, whatever its name).
///
/// ```
/// use std::path::Path;
///
/// let desc = bareray::io::load(Path::new("scenes/balls3.nff"))?;
/// println!("{} spheres, {} polygons", desc.spheres.len(), desc.polygons.len());
/// assert!(!desc.spheres.is_empty() && !desc.lights.is_empty());
///
/// let err = bareray::io::load(Path::new("scenes/whitted.obj")).unwrap_err();
/// assert!(err.to_string().contains("unknown scene format"));
/// # Ok::<(), bareray::io::SceneError>(())
/// ```
pub fn load(path: &std::path::Path) -> Result<SceneDesc, SceneError> {
    if path.is_dir() {
        return Err(SceneError::whole_file(path, "is a directory"));
    }
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("toml") => toml::load(path),
        Some("nff") => nff::load(path),
        Some("xyzr") => xyzr::load(path),
        _ => Err(SceneError::whole_file(path, "unknown scene format (expected a .toml, .nff or .xyzr file)")),
    }
}
