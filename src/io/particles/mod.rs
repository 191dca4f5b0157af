//! Particle files as simulation codes write them: XYZ and extended XYZ ([`xyz`]), PDB and PQR ([`pdb`]),
//! GROMACS `.gro` ([`gro`]) and LAMMPS dumps ([`lammps`]), each also gzip- or bzip2-compressed. A reader
//! turns one frame of a file into a [`Frame`]: centres, a kind per particle (an element or a LAMMPS type)
//! and the radii or colours the file gives. [`scene`] then chooses radii and colours by kind (the tables in
//! [`elements`] and the overrides of [`ParticleOptions`]), gives every particle one material and its own
//! colour ([`crate::scene::SceneDesc::sphere_colors`]) and frames the particles; [`arrays`] does the same for
//! spheres given as arrays. Every error names the file and, where there is one, the line (of the decompressed text).

pub mod arrays;
pub mod elements;
pub mod gro;
pub mod lammps;
pub mod pdb;
pub mod scene;
pub mod text;
pub mod xyz;

use std::io::Read;
use std::path::Path;

use glam::DVec3;

use super::error::SceneError;
use crate::math::Rgb;
use crate::scene::SceneDesc;

/// A particle file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParticleFormat {
    /// XYZ and extended XYZ (`.xyz`, `.extxyz`).
    Xyz,
    /// Protein Data Bank (`.pdb`, `.ent`).
    Pdb,
    /// PDB with charge and radius columns (`.pqr`).
    Pqr,
    /// GROMACS coordinates (`.gro`), in nm.
    Gro,
    /// LAMMPS text dump (`.dump`, `.lammpstrj`).
    Lammps,
}

impl ParticleFormat {
    /// The format an extension (lower case, without the dot) names.
    pub fn from_name(ext: &str) -> Option<Self> {
        match ext {
            "xyz" | "extxyz" => Some(Self::Xyz),
            "pdb" | "ent" => Some(Self::Pdb),
            "pqr" => Some(Self::Pqr),
            "gro" => Some(Self::Gro),
            "dump" | "lammpstrj" => Some(Self::Lammps),
            _ => None,
        }
    }
}

/// Choices for reading a particle file; the default reads the first frame with the tables' radii and
/// colours, seen from +z.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParticleOptions {
    /// The frame to read, from 0 (the first when `None`).
    pub frame: Option<usize>,
    /// The direction from which the particles are seen: the eye sits on this side of them, looking back
    /// along it (+z when `None`).
    pub view: Option<DVec3>,
    /// Radii by kind (element symbol or LAMMPS type), beating the file's and the table's.
    pub radius: Vec<(String, f64)>,
    /// Colours by kind, channels in [0, 1], beating the file's and the table's.
    pub color: Vec<(String, Rgb)>,
    /// Every radius is multiplied by this (1 when `None`).
    pub radius_scale: Option<f64>,
}

impl ParticleOptions {
    /// Whether any choice besides the view is made (those apply to particle files only).
    pub fn chooses_particles(&self) -> bool {
        self.frame.is_some()
            || !self.radius.is_empty()
            || !self.color.is_empty()
            || self.radius_scale.is_some()
    }
}

/// The unit of a file's lengths, which decides how the Å radii of the table are scaled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unit {
    /// Ångström (XYZ, PDB, PQR, LAMMPS `real` and `metal` units).
    Angstrom,
    /// Nanometre (GROMACS).
    Nanometre,
}

/// What particles are: an element of the table, a name that is none, or a LAMMPS type number.
#[derive(Clone, Debug, PartialEq)]
pub struct Kind {
    /// The element's symbol as the table writes it, the name as the file writes it, or the type number.
    pub name: String,
    /// The element, when the name is one.
    pub element: Option<&'static elements::Element>,
    /// A LAMMPS type without an element: radius 0.5 and a colour of [`scene::TYPE_COLORS`] by default.
    pub lammps_type: bool,
}

/// One particle as read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Particle {
    /// Centre, in the file's unit.
    pub center: DVec3,
    /// Index into [`Frame::kinds`].
    pub kind: u32,
    /// The file's radius for it, if the file has one.
    pub radius: Option<f64>,
    /// The file's colour for it, if the file has one.
    pub color: Option<Rgb>,
}

/// One frame of a particle file.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// The particles in file order.
    pub particles: Vec<Particle>,
    /// The distinct kinds, in order of first appearance.
    pub kinds: Vec<Kind>,
    /// The unit of the file's lengths.
    pub unit: Unit,
}

impl Frame {
    /// An empty frame in `unit`.
    pub fn new(unit: Unit) -> Self {
        Self { particles: Vec::new(), kinds: Vec::new(), unit }
    }

    /// The index of `kind`, added on first sight (kinds are few, so a search is enough).
    pub fn kind(&mut self, kind: Kind) -> u32 {
        match self.kinds.iter().position(|k| k.name == kind.name && k.lammps_type == kind.lammps_type) {
            Some(i) => i as u32,
            None => {
                self.kinds.push(kind);
                self.kinds.len() as u32 - 1
            }
        }
    }

    /// The index of the element named `name` (or of `name` itself when no element has it).
    pub fn element_kind(&mut self, name: &str) -> u32 {
        let element = elements::lookup(name);
        let name = element.map_or(name, |e| e.0).to_owned();
        self.kind(Kind { name, element, lammps_type: false })
    }
}

/// Reads frame `options.frame` of a particle file and makes its scene; the strings are warnings.
pub fn load(
    path: &Path,
    format: ParticleFormat,
    options: &ParticleOptions,
) -> Result<(SceneDesc, Vec<String>), SceneError> {
    let bytes = std::fs::read(path)
        .map_err(|e| SceneError::whole_file(path, format!("cannot read particle file: {e}")))?;
    parse(path, format, bytes, options)
}

/// [`load`] of a file's bytes, gzip- or bzip2-compressed or not (told by their first bytes).
pub fn parse(
    path: &Path,
    format: ParticleFormat,
    bytes: Vec<u8>,
    options: &ParticleOptions,
) -> Result<(SceneDesc, Vec<String>), SceneError> {
    let source = super::error::text(path, decompress(path, bytes)?)?;
    let wanted = options.frame.unwrap_or(0);
    let frame = match format {
        ParticleFormat::Xyz => xyz::parse(path, &source, wanted),
        ParticleFormat::Pdb => pdb::parse(path, &source, wanted, false),
        ParticleFormat::Pqr => pdb::parse(path, &source, wanted, true),
        ParticleFormat::Gro => gro::parse(path, &source, wanted),
        ParticleFormat::Lammps => lammps::parse(path, &source, wanted),
    }?;
    scene::scene(frame, options).map_err(|m| SceneError::whole_file(path, m))
}

/// `bytes` decompressed when they start as gzip (`1f 8b`) or bzip2 (`BZh`) data does; a name ending in
/// `.gz` or `.bz2` must hold such data.
pub fn decompress(path: &Path, bytes: Vec<u8>) -> Result<Vec<u8>, SceneError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let mut out = Vec::new();
    let result = if bytes.starts_with(&[0x1f, 0x8b]) {
        flate2::read::MultiGzDecoder::new(&bytes[..]).read_to_end(&mut out).map_err(|e| ("gzip", e))
    } else if bytes.starts_with(b"BZh") {
        bzip2::read::MultiBzDecoder::new(&bytes[..]).read_to_end(&mut out).map_err(|e| ("bzip2", e))
    } else {
        return match ext.as_deref() {
            Some(e @ ("gz" | "bz2")) => {
                Err(SceneError::whole_file(path, format!("named .{e} but does not hold {e} data")))
            }
            _ => Ok(bytes),
        };
    };
    result.map_err(|(what, e)| SceneError::whole_file(path, format!("bad {what} data: {e}")))?;
    Ok(out)
}

/// The error for a frame past the end: how many frames the file has.
pub fn missing_frame(path: &Path, wanted: usize, count: usize) -> SceneError {
    let has = match count {
        0 => "no frames".to_owned(),
        1 => "1 frame (frame 0)".to_owned(),
        n => format!("{n} frames (0 to {})", n - 1),
    };
    SceneError::whole_file(path, format!("frame {wanted} asked for, but the file has {has}"))
}

/// Kinds by the word a file names them with, so that each word is looked up in the table once.
#[derive(Default)]
pub struct KindCache<'a>(std::collections::HashMap<&'a str, u32>);

impl<'a> KindCache<'a> {
    /// The kind of the element (or unknown name) `word`.
    pub fn element(&mut self, frame: &mut Frame, word: &'a str) -> u32 {
        *self.0.entry(word).or_insert_with(|| frame.element_kind(word))
    }
}
