//! Particle files as simulation codes write them: XYZ and extended XYZ (`xyz`), PDB and PQR (`pdb`),
//! GROMACS `.gro` (`gro`) and LAMMPS dumps (`lammps`), each also gzip- or bzip2-compressed. A reader
//! turns one frame of a file into a `Frame`: centres, a kind per particle (an element or a LAMMPS type)
//! the radii or colours the file gives, and its periodic box (`Cell`) if it has one. `scene` then
//! chooses radii and colours by kind (the tables in `elements`, a types sidecar (`types`) and the
//! overrides of [`ParticleOptions`]), gives every particle one material and its own colour
//! ([`crate::scene::SceneDesc::sphere_colors`]), draws the box if asked and frames the particles; [`arrays`]
//! does the same for spheres given as arrays. Every error names the file and, where there is one, the line
//! (of the decompressed text).

pub mod arrays;
pub(crate) mod elements;
mod frame_lines;
pub(crate) mod gro;
pub(crate) mod lammps;
pub(crate) mod pdb;
pub(crate) mod scene;
pub(crate) mod text;
pub(crate) mod types;
pub(crate) mod xyz;

use std::io::Read;
use std::path::{Path, PathBuf};

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
    pub(crate) fn from_name(ext: &str) -> Option<Self> {
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
    /// A types sidecar (`types`) to read radii and colours by kind from, beaten by `radius` and `color`;
    /// when `None`, `load` reads the particle file's own sidecar if there is one (`types::sidecar_of`).
    pub types: Option<PathBuf>,
    /// Draw the file's periodic box as thin cylinders (`scene::box_radius`).
    pub draw_box: bool,
}

impl ParticleOptions {
    /// Whether any choice besides the view is made (those apply to particle files only).
    pub(crate) fn chooses_particles(&self) -> bool {
        self.frame.is_some()
            || !self.radius.is_empty()
            || !self.color.is_empty()
            || self.radius_scale.is_some()
            || self.types.is_some()
            || self.draw_box
    }
}

/// The unit of a file's lengths, which decides how the Å radii of the table are scaled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Unit {
    /// Ångström (XYZ, PDB, PQR, LAMMPS `real` and `metal` units).
    Angstrom,
    /// Nanometre (GROMACS).
    Nanometre,
}

/// What particles are: an element of the table, a name that is none, or a LAMMPS type number.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Kind {
    /// The element's symbol as the table writes it, the name as the file writes it, or the type number.
    pub(crate) name: String,
    /// The element, when the name is one.
    pub(crate) element: Option<&'static elements::Element>,
    /// A LAMMPS type without an element: radius 0.5 and a colour of [`scene::TYPE_COLORS`] by default.
    pub(crate) lammps_type: bool,
}

/// One particle as read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Particle {
    /// Centre, in the file's unit.
    pub(crate) center: DVec3,
    /// Index into [`Frame::kinds`].
    pub(crate) kind: u32,
    /// The file's radius for it, if the file has one.
    pub(crate) radius: Option<f64>,
    /// The file's colour for it, if the file has one.
    pub(crate) color: Option<Rgb>,
}

/// One frame of a particle file.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Frame {
    /// The particles in file order.
    pub(crate) particles: Vec<Particle>,
    /// The distinct kinds, in order of first appearance.
    pub(crate) kinds: Vec<Kind>,
    /// The unit of the file's lengths.
    pub(crate) unit: Unit,
    /// The periodic box the file gives for this frame, if any.
    pub(crate) cell: Option<Cell>,
}

/// A periodic box: a parallelepiped with a corner and three edge vectors, in the file's unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Cell {
    /// The corner the edges start from.
    pub(crate) origin: DVec3,
    /// The edge vectors a, b, c.
    pub(crate) edges: [DVec3; 3],
}

impl Cell {
    /// The point of scaled (fractional) coordinates `s`: origin + s.x·a + s.y·b + s.z·c.
    pub(crate) fn point(&self, s: DVec3) -> DVec3 {
        self.origin + s.x * self.edges[0] + s.y * self.edges[1] + s.z * self.edges[2]
    }

    /// The eight corners, corner `i` at the scaled coordinates of `i`'s bits (bit 0 for a, 1 for b, 2 for c).
    pub(crate) fn corners(&self) -> [DVec3; 8] {
        std::array::from_fn(|i| self.point(DVec3::new((i & 1) as f64, (i >> 1 & 1) as f64, (i >> 2) as f64)))
    }

    /// The twelve edges as pairs of [`Cell::corners`] indices.
    pub(crate) fn edge_corners() -> [(usize, usize); 12] {
        let mut out = [(0, 0); 12];
        let mut n = 0;
        for i in 0..8 {
            for bit in [1, 2, 4] {
                if i & bit == 0 {
                    out[n] = (i, i | bit);
                    n += 1;
                }
            }
        }
        out
    }

    /// Whether the box can be drawn: finite, with a volume that is not vanishingly small next to its edges
    /// (a GRO box line of zeros, say, gives none).
    pub(crate) fn is_solid(&self) -> bool {
        let [a, b, c] = self.edges;
        let volume = a.dot(b.cross(c)).abs();
        let scale = a.length() * b.length() * c.length();
        self.origin.is_finite() && volume.is_finite() && scale.is_finite() && volume > 1e-6 * scale
    }

    /// The box of the crystallographic cell lengths `a, b, c` and angles `alpha, beta, gamma` (degrees), with
    /// a along x and b in the xy plane, as PDB's CRYST1 record gives them; `None` for angles that close no
    /// box.
    pub(crate) fn from_lengths_angles(lengths: [f64; 3], angles: [f64; 3]) -> Option<Cell> {
        let [a, b, c] = lengths;
        // Right angles exactly, so that an orthogonal cell's edges lie on the axes.
        let [cos_a, cos_b, cos_g] = angles.map(|d| if d == 90.0 { 0.0 } else { d.to_radians().cos() });
        let sin_g = if angles[2] == 90.0 { 1.0 } else { angles[2].to_radians().sin() };
        if sin_g.abs() < 1e-9 {
            return None;
        }
        let cy = (cos_a - cos_b * cos_g) / sin_g;
        let cz2 = 1.0 - cos_b * cos_b - cy * cy;
        if cz2.is_nan() || cz2 <= 0.0 {
            return None;
        }
        let edges = [
            DVec3::new(a, 0.0, 0.0),
            DVec3::new(b * cos_g, b * sin_g, 0.0),
            DVec3::new(c * cos_b, c * cy, c * cz2.sqrt()),
        ];
        Some(Cell { origin: DVec3::ZERO, edges })
    }
}

impl Frame {
    /// An empty frame in `unit`, without a box.
    pub(crate) fn new(unit: Unit) -> Self {
        Self { particles: Vec::new(), kinds: Vec::new(), unit, cell: None }
    }

    /// The index of `kind`, added on first sight (kinds are few, so a search is enough).
    pub(crate) fn kind(&mut self, kind: Kind) -> u32 {
        match self.kinds.iter().position(|k| k.name == kind.name && k.lammps_type == kind.lammps_type) {
            Some(i) => i as u32,
            None => {
                self.kinds.push(kind);
                self.kinds.len() as u32 - 1
            }
        }
    }

    /// The index of the element named `name` (or of `name` itself when no element has it).
    pub(crate) fn element_kind(&mut self, name: &str) -> u32 {
        let element = elements::lookup(name);
        let name = element.map_or(name, |e| e.0).to_owned();
        self.kind(Kind { name, element, lammps_type: false })
    }
}

/// Reads frame `options.frame` of a particle file and makes its scene; the strings are warnings. The types
/// sidecar is `options.types`, else the file's own ([`types::sidecar_of`]) when it exists.
pub(crate) fn load(
    path: &Path,
    format: ParticleFormat,
    options: &ParticleOptions,
) -> Result<(SceneDesc, Vec<String>), SceneError> {
    // Read, not mapped as large scene files are: simulations rewrite their dump files as they run, and a
    // mapped file cut short under the reader would stop the process with SIGBUS instead of an error.
    let bytes = crate::io::error::read_bytes(path)
        .map_err(|e| SceneError::whole_file(path, format!("cannot read particle file: {e}")))?;
    let sidecar = match &options.types {
        Some(types) => Some(types::read(types)?),
        None => types::sidecar_of(path).map(|p| types::read(&p)).transpose()?,
    };
    parsed(path, format, bytes, options, sidecar.as_ref())
}

/// [`load`] of a file's bytes, gzip- or bzip2-compressed or not (told by their first bytes); the types
/// sidecar is `options.types` only (bytes have no file beside them).
pub(crate) fn parse(
    path: &Path,
    format: ParticleFormat,
    bytes: Vec<u8>,
    options: &ParticleOptions,
) -> Result<(SceneDesc, Vec<String>), SceneError> {
    let sidecar = options.types.as_deref().map(types::read).transpose()?;
    parsed(path, format, bytes, options, sidecar.as_ref())
}

/// The scene of a particle file's bytes, decompressed where they are compressed (the compressed bytes freed
/// before the parse), with a sidecar's types.
fn parsed(
    path: &Path,
    format: ParticleFormat,
    bytes: Vec<u8>,
    options: &ParticleOptions,
    sidecar: Option<&types::Types>,
) -> Result<(SceneDesc, Vec<String>), SceneError> {
    let plain = match decompress(path, &bytes)? {
        Some(plain) => {
            drop(bytes);
            plain
        }
        None => bytes,
    };
    build(path, format, &super::error::text(path, plain)?, options, sidecar)
}

/// The scene of a particle file's text with a sidecar's types.
fn build(
    path: &Path,
    format: ParticleFormat,
    source: &str,
    options: &ParticleOptions,
    sidecar: Option<&types::Types>,
) -> Result<(SceneDesc, Vec<String>), SceneError> {
    let wanted = options.frame.unwrap_or(0);
    let frame = match format {
        ParticleFormat::Xyz => xyz::parse(path, source, wanted),
        ParticleFormat::Pdb => pdb::parse(path, source, wanted, false),
        ParticleFormat::Pqr => pdb::parse(path, source, wanted, true),
        ParticleFormat::Gro => gro::parse(path, source, wanted),
        ParticleFormat::Lammps => lammps::parse(path, source, wanted),
    }?;
    scene::scene(frame, options, sidecar).map_err(|m| SceneError::whole_file(path, m))
}

/// `bytes` decompressed when they start as gzip (`1f 8b`) or bzip2 (`BZh`) data does, else `None`; a name
/// ending in `.gz` or `.bz2` must hold such data.
pub(crate) fn decompress(path: &Path, bytes: &[u8]) -> Result<Option<Vec<u8>>, SceneError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let mut out = Vec::new();
    let result = if bytes.starts_with(&[0x1f, 0x8b]) {
        flate2::read::MultiGzDecoder::new(bytes).read_to_end(&mut out).map_err(|e| ("gzip", e))
    } else if bytes.starts_with(b"BZh") {
        bzip2::read::MultiBzDecoder::new(bytes).read_to_end(&mut out).map_err(|e| ("bzip2", e))
    } else {
        return match ext.as_deref() {
            Some(e @ ("gz" | "bz2")) => {
                let what = if e == "gz" { "gzip" } else { "bzip2" };
                // A tar archive says so at byte 257 (POSIX `ustar`).
                let tar = match bytes.get(257..262) == Some(b"ustar") {
                    true => " (it is a tar archive: unpack it first)",
                    false => "",
                };
                Err(SceneError::whole_file(path, format!("named .{e} but does not hold {what} data{tar}")))
            }
            _ => Ok(None),
        };
    };
    result.map_err(|(what, e)| SceneError::whole_file(path, format!("bad {what} data: {e}")))?;
    Ok(Some(out))
}

/// The error for a frame past the end: how many frames the file has.
pub(crate) fn missing_frame(path: &Path, wanted: usize, count: usize) -> SceneError {
    let has = match count {
        0 => "no frames".to_owned(),
        1 => "1 frame (frame 0)".to_owned(),
        n => format!("{n} frames (0 to {})", n - 1),
    };
    SceneError::whole_file(path, format!("frame {wanted} asked for, but the file has {has}"))
}
