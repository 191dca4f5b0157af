//! PDB and PQR files: `ATOM` and `HETATM` records, other records skipped; `MODEL` … `ENDMDL` blocks are
//! frames, and a file without them is one frame. PDB records have fixed columns: the atom name in 13–16,
//! the residue in 18–20, x, y, z in 31–38, 39–46, 47–54 and the element in 77–78. Without an element
//! there, it comes from the atom name: an ion named as its residue (`CA` in residue `CA`), else for
//! `HETATM` records a two-letter element written from column 13 (`FE`), else the name's first letter
//! (` CA ` is carbon, `HG21` hydrogen). PQR records are whitespace-separated,
//! `ATOM serial name residue [chain] number x y z charge radius`, read from the end; their radius is used.
//! A `CRYST1` record gives the periodic box (cell lengths in columns 7–33, angles in 34–54; whitespace-
//! separated in PQR), except the `1 1 1 90 90 90` that stands for none.

use std::collections::HashMap;
use std::path::Path;

use glam::DVec3;

use super::elements;
use super::frame_lines::{self, How};
use super::text::{self, columns, Lines};
use super::{Cell, Frame, Kind, Particle, Unit};
use crate::io::SceneError;

mod pieces;

/// Reads frame `wanted` (from 0) of a PDB text, or of a PQR text when `pqr`.
pub(crate) fn parse(path: &Path, source: &str, wanted: usize, pqr: bool) -> Result<Frame, SceneError> {
    parse_as(path, source, wanted, pqr, How::Auto)
}

/// [`parse`], the text read as `how` says: a text of [`pieces::PIECES_FROM_BYTES`] or more in pieces
/// by [`How::Auto`], or again in one pass where the pieces stop (one pass then reports why).
fn parse_as(path: &Path, source: &str, wanted: usize, pqr: bool, how: How) -> Result<Frame, SceneError> {
    if how == How::Pieces || (how == How::Auto && source.len() >= pieces::PIECES_FROM_BYTES) {
        match (pieces::read(source, wanted, pqr, frame_lines::PIECE_BYTES), how) {
            (Some(frame), _) => return Ok(frame),
            (None, How::Pieces) => return Err(SceneError::whole_file(path, "not read in pieces")),
            (None, _) => {}
        }
    }
    one_pass(path, source, wanted, pqr)
}

/// [`parse`] one record after another.
fn one_pass(path: &Path, source: &str, wanted: usize, pqr: bool) -> Result<Frame, SceneError> {
    let mut lines = Lines::new(path, source);
    let mut frame = Frame::new(Unit::Angstrom);
    let mut kinds: HashMap<(Key, bool), u32> = HashMap::new();
    // The frame the next atoms belong to, and whether it has begun (an atom or a MODEL record seen).
    let (mut current, mut open) = (0usize, false);
    while let Some(line) = lines.next() {
        match record(line, pqr) {
            Record::Atom { hetatm } => {
                open = true;
                if current == wanted {
                    let (particle, key) = atom(line, pqr, hetatm).map_err(|m| lines.error(m))?;
                    let kind = *kinds.entry(key).or_insert_with(|| kind_of(&mut frame, key));
                    frame.particles.push(Particle { kind, ..particle });
                }
            }
            // A MODEL record also ends a frame its ENDMDL is missing from.
            r @ (Record::Model | Record::EndModel) => {
                if open {
                    if current == wanted {
                        return finish(&lines, frame, wanted);
                    }
                    current += 1;
                }
                open = r == Record::Model;
            }
            Record::Cryst1 => frame.cell = cryst1(line, pqr).map_err(|m| lines.error(m))?,
            Record::End => break,
            Record::Other => {}
        }
    }
    if open && current == wanted {
        return finish(&lines, frame, wanted);
    }
    let count = current + usize::from(open);
    match count {
        0 => Err(SceneError::whole_file(path, "no particles: no ATOM or HETATM records")),
        n => Err(super::missing_frame(path, wanted, n)),
    }
}

/// What a record does to frames, by its name (a PDB record's columns 1-6, a PQR record's first word).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Record {
    /// `ATOM` or `HETATM`.
    Atom {
        hetatm: bool,
    },
    Model,
    EndModel,
    End,
    Cryst1,
    /// Any other record, skipped.
    Other,
}

/// The record `line` holds.
fn record(line: &str, pqr: bool) -> Record {
    let name = match pqr {
        true => line.split_ascii_whitespace().next().unwrap_or(""),
        false => columns(line, 0, 6).trim_end(),
    };
    match name {
        "ATOM" => Record::Atom { hetatm: false },
        "HETATM" => Record::Atom { hetatm: true },
        "MODEL" => Record::Model,
        "ENDMDL" => Record::EndModel,
        "END" => Record::End,
        "CRYST1" => Record::Cryst1,
        _ => Record::Other,
    }
}

/// An atom record: the particle (kind unset) and the key of its kind.
fn atom(line: &str, pqr: bool, hetatm: bool) -> Result<(Particle, (Key<'_>, bool)), String> {
    let (center, radius, key) = if pqr { pqr_atom(line) } else { pdb_atom(line) }?;
    Ok((Particle { center, kind: 0, radius, color: None }, (key, hetatm)))
}

/// The frame read, unless it has no atoms.
fn finish(lines: &Lines, frame: Frame, wanted: usize) -> Result<Frame, SceneError> {
    match frame.particles.is_empty() {
        true => Err(lines.error(format!("frame {wanted} has no ATOM or HETATM records"))),
        false => Ok(frame),
    }
}

/// What decides an atom's kind: its element columns when they are filled, else its name and residue.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Key<'a> {
    Element(&'a str),
    Name(&'a str, &'a str),
}

/// The kind of an atom, from its key and whether its record is `HETATM`.
fn kind_of(frame: &mut Frame, (key, hetatm): (Key, bool)) -> u32 {
    let (name, residue) = match key {
        Key::Name(name, residue) => (name, residue),
        Key::Element(element) => return frame.element_kind(element),
    };
    let two = hetatm && !name.starts_with(' ');
    match elements::from_atom_name(name, residue, two) {
        Some(e) => frame.kind(Kind { name: e.0.to_owned(), element: Some(e), lammps_type: false }),
        None => frame.element_kind(name.trim()),
    }
}

/// A PDB `ATOM`/`HETATM` record: centre, no radius, and the key of its kind.
fn pdb_atom(line: &str) -> Result<(DVec3, Option<f64>, Key<'_>), String> {
    if line.len() < 54 {
        let record = columns(line, 0, 6).trim_end();
        return Err(format!("{record} record of {} bytes: x, y, z are in columns 31-54", line.len()));
    }
    let v = |from, to, what| text::number(columns(line, from, to), what);
    let center = DVec3::new(
        v(30, 38, "x in columns 31-38")?,
        v(38, 46, "y in columns 39-46")?,
        v(46, 54, "z in columns 47-54")?,
    );
    let element = columns(line, 76, 78);
    let key = match element.trim() {
        "" => Key::Name(columns(line, 12, 16), columns(line, 17, 20)),
        element => Key::Element(element),
    };
    Ok((center, None, key))
}

/// A `CRYST1` record's box: `None` for the unit cube of 90° that PDB writes when there is no box, and for
/// zero lengths or angles that close no box, which other writers put there.
fn cryst1(line: &str, pqr: bool) -> Result<Option<Cell>, String> {
    const FIELDS: [(usize, usize, &str); 6] =
        [(6, 15, "a"), (15, 24, "b"), (24, 33, "c"), (33, 40, "alpha"), (40, 47, "beta"), (47, 54, "gamma")];
    let words: Vec<&str> = line.split_ascii_whitespace().skip(1).collect();
    let mut v = [0.0; 6];
    for (k, &(from, to, name)) in FIELDS.iter().enumerate() {
        v[k] = match pqr {
            true => text::number(words.get(k).copied().unwrap_or(""), &format!("the CRYST1 cell's {name}")),
            false => text::number(
                columns(line, from, to),
                &format!("the CRYST1 cell's {name} in columns {}-{to}", from + 1),
            ),
        }?;
    }
    let (lengths, angles) = ([v[0], v[1], v[2]], [v[3], v[4], v[5]]);
    if lengths == [1.0; 3] && angles == [90.0; 3] {
        return Ok(None);
    }
    // Writers without a box also put zeros here (NAMD, MDAnalysis): a cell that closes no box is none.
    Ok(Cell::from_lengths_angles(lengths, angles).filter(|_| lengths.iter().all(|&l| l > 0.0)))
}

/// A PQR record, whitespace-separated and read from the end: centre, radius and key.
fn pqr_atom(line: &str) -> Result<(DVec3, Option<f64>, Key<'_>), String> {
    let words: Vec<&str> = line.split_ascii_whitespace().collect();
    let n = words.len();
    if n < 10 {
        return Err(format!(
            "expected `ATOM serial name residue [chain] number x y z charge radius`, got {n} fields"
        ));
    }
    let v = |i: usize, what| text::number(words[i], what);
    let center = DVec3::new(v(n - 5, "x")?, v(n - 4, "y")?, v(n - 3, "z")?);
    v(n - 2, "charge")?;
    let radius = text::radius(words[n - 1], "radius")?;
    Ok((center, Some(radius), Key::Name(words[2], words[3])))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn atom(record: &str, name: &str, residue: &str, xyz: [f64; 3], element: &str) -> String {
        format!(
            "{record:<6}{:>5} {name:<4} {residue:>3} A   1    {:>8.3}{:>8.3}{:>8.3}  1.00  0.00          {element:>2}",
            1, xyz[0], xyz[1], xyz[2]
        )
    }

    #[test]
    fn fixed_columns_and_element_guesses() {
        let text = [
            atom("ATOM", " CA", "ALA", [1.0, 2.0, -3.5], ""),
            atom("HETATM", "FE", "HEM", [0.0, 0.0, 0.0], ""),
            atom("ATOM", "HG21", "THR", [0.0, 0.0, 0.0], ""),
            atom("HETATM", "CL", "CL", [0.0, 0.0, 0.0], "CL"),
        ]
        .join("\n");
        let f = parse(Path::new("t.pdb"), &text, 0, false).unwrap();
        let names: Vec<&str> = f.particles.iter().map(|p| f.kinds[p.kind as usize].name.as_str()).collect();
        assert_eq!(names, ["C", "Fe", "H", "Cl"]);
        assert_eq!(f.particles[0].center, DVec3::new(1.0, 2.0, -3.5));
    }

    #[test]
    fn models_are_frames() {
        let a = atom("ATOM", " N", "GLY", [1.0, 0.0, 0.0], "N");
        let text = format!("MODEL 1\n{a}\n{a}\nENDMDL\nMODEL 2\n{a}\nENDMDL\nEND\n");
        let path = Path::new("t.pdb");
        assert_eq!(parse(path, &text, 0, false).unwrap().particles.len(), 2);
        assert_eq!(parse(path, &text, 1, false).unwrap().particles.len(), 1);
        assert!(parse(path, &text, 2, false).unwrap_err().message.contains("2 frames"));
        assert_eq!(parse(path, &a, 0, false).unwrap().particles.len(), 1);
    }

    #[test]
    fn cryst1_gives_the_box() {
        let a = atom("ATOM", " N", "GLY", [1.0, 0.0, 0.0], "N");
        let path = Path::new("t.pdb");
        let cryst = "CRYST1   10.000   20.000   30.000  90.00  90.00  90.00 P 1           1";
        let cell = parse(path, &format!("{cryst}\n{a}\n"), 0, false).unwrap().cell.unwrap();
        assert_eq!(cell.edges, [DVec3::X * 10.0, DVec3::Y * 20.0, DVec3::Z * 30.0]);
        // A monoclinic cell: c leans in the xz plane by beta.
        let tilted = cryst.replace("90.00  90.00  90.00", "90.00 120.00  90.00");
        let c = parse(path, &format!("{tilted}\n{a}\n"), 0, false).unwrap().cell.unwrap().edges[2];
        assert!((c - DVec3::new(-15.0, 0.0, 30.0 * 0.75f64.sqrt())).length() < 1e-9, "{c}");
        let none = "CRYST1    1.000    1.000    1.000  90.00  90.00  90.00 P 1           1";
        assert_eq!(parse(path, &format!("{none}\n{a}\n"), 0, false).unwrap().cell, None);
        let e = parse(path, &format!("{a}\n{}\n", cryst.replace("20.000", "20.0x0")), 0, false).unwrap_err();
        assert!(e.line == 2 && e.message.contains("columns 16-24"), "{e}");
        // Zeros, as NAMD and MDAnalysis write them for no box, are no box.
        for zeros in
            [cryst.replace(" 90.00  90.00  90.00", "  0.00   0.00   0.00"), cryst.replace("10.000", " 0.000")]
        {
            assert_eq!(parse(path, &format!("{zeros}\n{a}\n"), 0, false).unwrap().cell, None, "{zeros}");
        }
        let pqr = "CRYST1 5 5 5 90 90 90\nATOM 1 N MET 1 0 0 0 0.1 1\n";
        let cell = parse(Path::new("t.pqr"), pqr, 0, true).unwrap().cell.unwrap();
        assert_eq!(cell.edges[1], DVec3::Y * 5.0);
    }

    #[test]
    fn pqr_radius_is_read_from_the_end() {
        let text = "ATOM      1  N   MET     1     -1.0   2.0   3.0 -0.3000 1.8240\n\
                    ATOM      2  CA  MET A   1      0.0   0.0   0.0  0.1 1.9\n";
        let f = parse(Path::new("t.pqr"), text, 0, true).unwrap();
        assert_eq!(f.particles[0].radius, Some(1.824));
        assert_eq!(f.particles[1].center, DVec3::ZERO);
        let e = parse(Path::new("t.pqr"), "ATOM 1 N MET 1 0 0 0 0.1 -1\n", 0, true).unwrap_err();
        assert_eq!(e.line, 1);
        assert!(e.message.contains("positive"), "{e}");
    }
}
