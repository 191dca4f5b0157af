//! Scene readers (TOML, NFF, xyzr, f32r) and generators: files and parameters become a plain [`SceneDesc`], which
//! [`crate::compile`] turns into the runtime scene.

pub mod error;
pub mod f32r;
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
    /// Binary sphere records `x y z r` (little-endian f32) after a header: [`f32r`].
    F32r,
}

impl SceneFormat {
    /// The format a file's extension names (case-insensitive), if any.
    pub fn from_extension(path: &std::path::Path) -> Option<Self> {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        Self::from_name(ext.as_deref()?)
    }

    /// The format named `toml`, `nff`, `xyzr` or `f32r`.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "toml" => Some(Self::Toml),
            "nff" => Some(Self::Nff),
            "xyzr" => Some(Self::Xyzr),
            "f32r" => Some(Self::F32r),
            _ => None,
        }
    }
}

/// Parses a scene held in memory (read from standard input, say) in `format`; errors name `name` as the
/// file. The text formats must be UTF-8 (bytes that are not are an error at their line and column).
pub fn parse(format: SceneFormat, name: &std::path::Path, source: Vec<u8>) -> Result<SceneDesc, SceneError> {
    match format {
        SceneFormat::Toml => toml::parse(name, &error::text(name, source)?),
        SceneFormat::Nff => nff::parse(name, &error::text(name, source)?),
        SceneFormat::Xyzr => xyzr::parse(name, &error::text(name, source)?),
        SceneFormat::F32r => f32r::parse(name, &source),
    }
}

/// Reads a scene file, choosing the reader by its extension: `.toml`, `.nff`, `.xyzr` or `.f32r` (a
/// directory is an error saying so, whatever its name). The sphere lists are read in parallel on the
/// current rayon pool (the CLI's is the one of `--threads`).
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
        Some(SceneFormat::F32r) => f32r::load(path),
        None => Err(SceneError::whole_file(
            path,
            "unknown scene format (expected a .toml, .nff, .xyzr or .f32r file)",
        )),
    }
}
