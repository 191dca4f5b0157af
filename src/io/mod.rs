//! Scene readers (TOML, NFF, xyzr) and generators: files and parameters become a plain [`SceneDesc`], which
//! [`crate::compile`] turns into the runtime scene.

pub mod error;
pub mod generate;
pub mod nff;
pub mod toml;
pub mod xyzr;

pub use error::SceneError;

use crate::scene::SceneDesc;

/// A scene format bareray reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneFormat {
    /// bareray's TOML format.
    Toml,
    /// SPD's Neutral File Format.
    Nff,
    /// One sphere `x y z r` per line.
    Xyzr,
}

impl SceneFormat {
    /// The format a file's extension names (case-insensitive), if any.
    pub fn from_extension(path: &std::path::Path) -> Option<Self> {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        Self::from_name(ext.as_deref()?)
    }

    /// The format named `toml`, `nff` or `xyzr`.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "toml" => Some(Self::Toml),
            "nff" => Some(Self::Nff),
            "xyzr" => Some(Self::Xyzr),
            _ => None,
        }
    }
}

/// Parses a scene held in memory (read from standard input, say) in `format`; errors name `name` as the
/// file.
pub fn parse(format: SceneFormat, name: &std::path::Path, source: &str) -> Result<SceneDesc, SceneError> {
    match format {
        SceneFormat::Toml => toml::parse(name, source),
        SceneFormat::Nff => nff::parse(name, source),
        SceneFormat::Xyzr => xyzr::parse(name, source),
    }
}

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
    match SceneFormat::from_extension(path) {
        Some(SceneFormat::Toml) => toml::load(path),
        Some(SceneFormat::Nff) => nff::load(path),
        Some(SceneFormat::Xyzr) => xyzr::load(path),
        None => {
            Err(SceneError::whole_file(path, "unknown scene format (expected a .toml, .nff or .xyzr file)"))
        }
    }
}
