//! Scene readers (TOML, NFF, xyzr, f32r, and the particle files of [`particles`]) and generators: files and parameters become a plain [`SceneDesc`], which
//! [`crate::compile`] turns into the runtime scene.

pub(crate) mod error;
pub mod f32r;
pub mod generate;
pub mod nff;
pub mod particles;
pub(crate) mod pieces;
pub mod random_scene;
pub mod toml;
pub mod xyzr;

pub use error::SceneError;
pub use particles::{ParticleFormat, ParticleOptions as LoadOptions};

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
    /// A particle file (XYZ, PDB, PQR, GRO, LAMMPS dump), maybe compressed: [`particles`].
    Particles(ParticleFormat),
}

impl SceneFormat {
    /// The format a file's extension names (case-insensitive), if any. A particle file may be compressed:
    /// `.xyz.gz`, `.pdb.bz2` and the like name the format before the `.gz` or `.bz2`.
    pub fn from_extension(path: &std::path::Path) -> Option<Self> {
        let ext = |p: &std::path::Path| p.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match ext(path)?.as_str() {
            "gz" | "bz2" => {
                ParticleFormat::from_name(&ext(std::path::Path::new(path.file_stem()?))?).map(Self::Particles)
            }
            name => Self::from_name(name),
        }
    }

    /// The format named `toml`, `nff`, `xyzr`, `f32r` or by a particle file's extension (`xyz`, `pdb`, …).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "toml" => Some(Self::Toml),
            "nff" => Some(Self::Nff),
            "xyzr" => Some(Self::Xyzr),
            "f32r" => Some(Self::F32r),
            _ => ParticleFormat::from_name(name).map(Self::Particles),
        }
    }

    /// Whether the format's files carry no camera, so that the view chooses one.
    pub(crate) fn framed_by_view(self) -> bool {
        matches!(self, Self::Xyzr | Self::F32r | Self::Particles(_))
    }
}

/// A scene read with its warnings (unknown elements, say).
#[derive(Clone, Debug, PartialEq)]
pub struct SceneRead {
    /// The scene.
    pub desc: SceneDesc,
    /// What the reader warns about; the scene renders anyway.
    pub warnings: Vec<String>,
}

/// Parses a scene held in memory (read from standard input, say) in `format`, with `options`: the frame,
/// view and overrides of particle files (an error for formats they do not apply to). Errors name `name`
/// as the file. The text formats must be UTF-8 (bytes that are not are an error at their line and column).
pub fn parse_with(
    format: SceneFormat,
    name: &std::path::Path,
    source: Vec<u8>,
    options: &LoadOptions,
) -> Result<SceneRead, SceneError> {
    check_options(format, name, options)?;
    let desc = match format {
        SceneFormat::Toml => toml::parse(name, &error::text(name, source)?),
        SceneFormat::Nff => nff::parse(name, &error::text(name, source)?),
        SceneFormat::Xyzr => xyzr::parse(name, &error::text(name, source)?),
        SceneFormat::F32r => f32r::parse(name, &source),
        SceneFormat::Particles(p) => {
            let (desc, warnings) = particles::parse(name, p, source, options)?;
            return Ok(SceneRead { desc, warnings });
        }
    }?;
    Ok(SceneRead { desc: viewed(desc, options), warnings: Vec::new() })
}

/// An error when `options` choose what `format` cannot do.
fn check_options(
    format: SceneFormat,
    path: &std::path::Path,
    options: &LoadOptions,
) -> Result<(), SceneError> {
    if options.chooses_particles() && !matches!(format, SceneFormat::Particles(_)) {
        return Err(SceneError::whole_file(
            path,
            "a frame, radii, colours, a types sidecar and a box are for particle files (.xyz, .pdb, .pqr, .gro, \
             .dump, .lammpstrj)",
        ));
    }
    if options.view.is_some() && !format.framed_by_view() {
        return Err(SceneError::whole_file(
            path,
            "a view frames files without a camera (.xyzr, .f32r, particle files); this one has its own",
        ));
    }
    Ok(())
}

/// A sphere list's scene, seen from `options.view` when one is chosen.
fn viewed(mut desc: SceneDesc, options: &LoadOptions) -> SceneDesc {
    if let Some(view) = options.view {
        let (lo, hi) = crate::kinds::sphere::sphere_bounds(&desc.spheres);
        let framed = xyzr::scene_framing(lo, hi, Some(view));
        (desc.camera, desc.lights) = (framed.camera, framed.lights);
    }
    desc
}

/// Reads a scene file, choosing the reader by its extension: `.toml`, `.nff`, `.xyzr`, `.f32r` or a
/// particle file's (`.xyz`, `.pdb`, `.pqr`, `.gro`, `.dump`, `.lammpstrj`, each maybe with `.gz` or `.bz2`;
/// [`load_with`] chooses their frame and overrides and returns their warnings). A directory is an error
/// saying so, whatever its name. The sphere lists are read in parallel on the
/// current rayon pool (the CLI's is the one of `--threads`).
///
/// ```
/// use std::path::Path;
///
/// let desc = bareray::io::load(Path::new("scenes/balls3.nff"))?;
/// println!("{} spheres, {} other primitives", desc.spheres.len(), desc.kinds.len());
/// assert!(!desc.spheres.is_empty() && !desc.lights.is_empty());
///
/// let err = bareray::io::load(Path::new("scenes/whitted.obj")).unwrap_err();
/// assert!(err.to_string().contains("unknown scene format"));
/// # Ok::<(), bareray::io::SceneError>(())
/// ```
pub fn load(path: &std::path::Path) -> Result<SceneDesc, SceneError> {
    Ok(load_with(path, &LoadOptions::default())?.desc)
}

/// [`load`] with `options` (see [`parse_with`]), returning the reader's warnings too.
pub fn load_with(path: &std::path::Path, options: &LoadOptions) -> Result<SceneRead, SceneError> {
    if path.is_dir() {
        return Err(SceneError::whole_file(path, "is a directory"));
    }
    let Some(format) = SceneFormat::from_extension(path) else {
        return Err(SceneError::whole_file(
            path,
            "unknown scene format (expected a .toml, .nff, .xyzr or .f32r file, or particles: .xyz, .pdb, \
             .pqr, .gro, .dump or .lammpstrj, maybe with .gz or .bz2)",
        ));
    };
    check_options(format, path, options)?;
    let desc = match format {
        SceneFormat::Toml => toml::load(path),
        SceneFormat::Nff => nff::load(path),
        SceneFormat::Xyzr => xyzr::load(path),
        SceneFormat::F32r => f32r::load(path),
        SceneFormat::Particles(p) => {
            let (desc, warnings) = particles::load(path, p, options)?;
            return Ok(SceneRead { desc, warnings });
        }
    }?;
    Ok(SceneRead { desc: viewed(desc, options), warnings: Vec::new() })
}
