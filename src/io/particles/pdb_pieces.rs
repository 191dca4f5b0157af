//! A large PDB or PQR text's frame read in pieces in parallel, with the particles, kinds and box that one
//! pass ([`super::pdb`]) reads. A first parallel pass cuts the text into pieces of whole lines and marks in
//! each the records that shape frames (`MODEL`, `ENDMDL`, `END`, `CRYST1`) with the number of atom records
//! before each; replaying the marks in order, as one pass steps through the records, finds the byte range of
//! the wanted frame, its atoms in each piece, and the `CRYST1` records one pass would read. The frame's atom
//! records are then read piece by piece ([`frame_lines::read_pieces`]: kinds named in the order one pass
//! meets them). Whatever would stop one pass (a bad record, a missing or empty frame) gives `None`, and one
//! pass reads the text again to report it at its line.

use rayon::prelude::*;

use super::frame_lines;
use super::pdb::{self, Record};
use super::{Frame, Unit};
use crate::io::pieces::line_pieces;

/// Texts of at least this many bytes (about 26 000 atom records) are read in pieces.
pub(super) const PIECES_FROM_BYTES: usize = 2 << 20;

/// A record that shapes frames, where its line starts in the text, and the atom records between the
/// previous mark (or its piece's start) and it.
#[derive(Clone, Copy, Debug)]
struct Mark {
    at: usize,
    record: Record,
    atoms_before: usize,
}

/// A piece's marks, and its atom records after the last one.
#[derive(Debug, Default)]
struct Marks {
    marks: Vec<Mark>,
    atoms_after: usize,
}

/// Frame `wanted` of a PDB (or, when `pqr`, PQR) text, read in pieces of about `piece_bytes`; `None` where
/// one pass must read it.
pub(super) fn read<'a>(source: &'a str, wanted: usize, pqr: bool, piece_bytes: usize) -> Option<Frame> {
    let pieces = line_pieces(source, piece_bytes);
    let marks: Vec<Marks> = pieces.par_iter().map(|p| marks(source, p, pqr)).collect();
    let found = replay(&marks, wanted)?;
    let mut frame = Frame::new(Unit::Angstrom);
    for &at in &found.cells {
        frame.cell = pdb::cryst1(source[at..].lines().next()?, pqr).ok()?;
    }
    let start = |p: &str| p.as_ptr() as usize - source.as_ptr() as usize;
    let clipped: Vec<&str> = pieces
        .iter()
        .map(|p| {
            let (from, to) = (start(p).max(found.start), (start(p) + p.len()).min(found.end));
            &source[from..to.max(from)]
        })
        .collect();
    let keep = |line: &str| matches!(pdb::record(line, pqr), Record::Atom { .. });
    let read_line = |_: usize, line: &'a str, _: &mut Vec<&'a str>| match pdb::record(line, pqr) {
        Record::Atom { hetatm } => pdb::atom(line, pqr, hetatm),
        _ => Err(String::new()),
    };
    let name = |key| pdb::kind_of(&mut frame, key);
    let particles = frame_lines::read_pieces(&clipped, &found.atoms, keep, &read_line, &mut { name })?;
    frame.particles = particles;
    Some(frame)
}

/// The marks of `piece`, a slice of `source` of whole lines.
fn marks(source: &str, piece: &str, pqr: bool) -> Marks {
    let mut out = Marks::default();
    for line in piece.lines() {
        match pdb::record(line, pqr) {
            Record::Atom { .. } => out.atoms_after += 1,
            Record::Other => {}
            record => {
                let at = line.as_ptr() as usize - source.as_ptr() as usize;
                out.marks.push(Mark { at, record, atoms_before: std::mem::take(&mut out.atoms_after) });
            }
        }
    }
    out
}

/// Where the wanted frame lies, as [`replay`] finds it.
#[derive(Debug, PartialEq)]
struct Found {
    /// The byte range its atom records lie in (no other frame's atom record inside).
    start: usize,
    end: usize,
    /// Its atom records in each piece.
    atoms: Vec<usize>,
    /// Where the `CRYST1` records one pass reads before the frame ends start, in order.
    cells: Vec<usize>,
}

/// The marks stepped through as one pass steps through records (`pdb::one_pass`): frame `wanted`'s range,
/// its atoms per piece and the `CRYST1` records met; `None` where one pass finds no such frame or an empty one.
fn replay(pieces: &[Marks], wanted: usize) -> Option<Found> {
    let mut found = Found { start: 0, end: usize::MAX, atoms: vec![0; pieces.len()], cells: Vec::new() };
    // The frame the next atoms belong to, and whether it has begun, as in one pass.
    let (mut current, mut open) = (0usize, false);
    'text: for (p, piece) in pieces.iter().enumerate() {
        for mark in &piece.marks {
            open |= mark.atoms_before > 0;
            if current == wanted {
                found.atoms[p] += mark.atoms_before;
            }
            match mark.record {
                Record::Model | Record::EndModel => {
                    if open {
                        if current == wanted {
                            found.end = mark.at;
                            break 'text;
                        }
                        current += 1;
                        if current == wanted {
                            found.start = mark.at;
                        }
                    }
                    open = mark.record == Record::Model;
                }
                Record::Cryst1 => found.cells.push(mark.at),
                Record::End => {
                    found.end = mark.at;
                    break 'text;
                }
                Record::Atom { .. } | Record::Other => unreachable!("not a mark"),
            }
        }
        open |= piece.atoms_after > 0;
        if current == wanted {
            found.atoms[p] += piece.atoms_after;
        }
    }
    let some = open && current == wanted && found.atoms.iter().any(|&n| n > 0);
    some.then_some(found)
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::io::particles::frame_lines::How;
    use crate::io::particles::pdb::parse_as;

    fn atom(i: usize, hetatm: bool) -> String {
        let record = if hetatm { "HETATM" } else { "ATOM" };
        let (name, element) =
            [(" CA ", " C"), (" N  ", " N"), ("FE  ", "  "), (" O  ", " O"), ("HG21", "  ")][i % 5];
        let (x, y, z) = ((i % 1000) as f64 * 0.013, (i % 37) as f64 * 0.1, -((i % 7) as f64));
        format!(
            "{record:<6}{:>5} {name} ALA A   1    {x:8.3}{y:8.3}{z:8.3}  1.00  0.00          {element}",
            i % 100_000
        )
    }

    /// Texts of many models, `CRYST1` records between and inside them, `TER` records, `\n` and `\r\n`, with
    /// and without `END`: every frame read in pieces of 1 KB to 64 KB is the frame one pass reads, and a
    /// missing frame, an empty one or a bad record gives `None` (one pass then reports it).
    #[test]
    fn frames_in_pieces_are_those_of_one_pass() {
        let path = Path::new("t.pdb");
        let cryst = |a: f64| format!("CRYST1{a:9.3}   20.000   30.000  90.00  90.00  90.00 P 1           1");
        for end in ["\n", "\r\n"] {
            let mut lines = vec![cryst(5.0), "REMARK a model-less frame follows".to_owned()];
            let mut i = 0;
            let mut block = |lines: &mut Vec<String>, n: usize| {
                for _ in 0..n {
                    lines.push(atom(i, i % 11 == 0));
                    if i % 97 == 0 {
                        lines.push("TER".to_owned());
                    }
                    i += 1;
                }
            };
            block(&mut lines, 300);
            for (m, n) in [(1, 2000), (2, 7), (3, 1500)] {
                lines.push(format!("MODEL     {m:>4}"));
                if m == 3 {
                    lines.push(cryst(7.0));
                }
                block(&mut lines, n);
                lines.push("ENDMDL".to_owned());
            }
            let text = lines.join(end);
            for (with_end, text) in [(false, text.clone()), (true, format!("{text}{end}END{end}"))] {
                for wanted in 0..5 {
                    let one = parse_as(path, &text, wanted, false, How::OnePass);
                    for piece_bytes in [1 << 10, 5000, 1 << 16] {
                        let pieces = read(&text, wanted, false, piece_bytes);
                        match &one {
                            Ok(frame) => assert_eq!(
                                pieces.as_ref(),
                                Some(frame),
                                "{wanted}, {piece_bytes}, {with_end}"
                            ),
                            Err(_) => assert_eq!(pieces, None, "frame {wanted}"),
                        }
                    }
                    assert_eq!(parse_as(path, &text, wanted, false, How::Auto), one);
                }
                let frame = read(&text, 3, false, 1 << 10).unwrap();
                assert_eq!((frame.particles.len(), frame.cell.unwrap().edges[0].x), (1500, 7.0));
            }
            // A bad record in the wanted frame stops the pieces; in another frame it is not read.
            let bad = text.replace(&atom(2100, false), &atom(2100, false).replace('.', "x"));
            assert_eq!(read(&bad, 1, false, 1 << 10), None);
            assert_eq!(read(&bad, 2, false, 1 << 10), parse_as(path, &bad, 2, false, How::OnePass).ok());
        }
    }

    /// PQR records in pieces: whitespace-separated, radius read from the end.
    #[test]
    fn pqr_in_pieces() {
        let line = |i: usize| {
            format!("ATOM {i} {} MET {} {}.5 -2 3 0.1 {}.25", ["N", "CA", "OW"][i % 3], i, i % 9, 1 + i % 2)
        };
        let text: Vec<String> = (0..4000).map(line).collect();
        let text = format!("CRYST1 5 5 5 90 90 90\n{}\n", text.join("\n"));
        let one = parse_as(Path::new("t.pqr"), &text, 0, true, How::OnePass).unwrap();
        assert_eq!(read(&text, 0, true, 3000), Some(one));
    }
    /// Texts cut, reordered and salted with frame records at random: wherever one pass reads the frame, the
    /// pieces read the same frame, and where it does not, they give `None`.
    #[test]
    fn mutated_texts_in_pieces_read_as_one_pass() {
        let path = Path::new("t.pdb");
        let records = [
            "MODEL        1",
            "ENDMDL",
            "END",
            "TER",
            "CRYST1   10.000   20.000   30.000  90.00  90.00  90.00",
        ];
        let mut base: Vec<String> = (0..600).map(|i| atom(i, i % 13 == 0)).collect();
        for (at, r) in [(100, 0), (250, 1), (251, 0), (400, 4), (500, 1)] {
            base.insert(at, records[r].to_owned());
        }
        let mut rng = crate::math::SplitMix64::new(7);
        let mut pick = |n: usize| (rng.unit() * n as f64) as usize % n;
        let (mut frames, mut errors) = (0, 0);
        for round in 0..400 {
            let mut lines = base.clone();
            for _ in 0..1 + pick(6) {
                let at = pick(lines.len());
                match pick(4) {
                    0 => lines.insert(at, records[pick(records.len())].to_owned()),
                    1 => drop(lines.remove(at)),
                    2 => {
                        let other = pick(lines.len());
                        lines.swap(at, other)
                    }
                    _ => lines[at] = lines[at].replacen('.', "x", 1),
                }
            }
            let text = lines.join(if round % 2 == 0 { "\n" } else { "\r\n" });
            for wanted in 0..3 {
                let one = parse_as(path, &text, wanted, false, How::OnePass).ok();
                assert_eq!(read(&text, wanted, false, 700), one, "round {round}, frame {wanted}");
                (frames, errors) = if one.is_some() { (frames + 1, errors) } else { (frames, errors + 1) };
            }
        }
        // Both outcomes are common: the test sees frames found and frames one pass refuses.
        assert!(frames > 300 && errors > 100, "{frames} frames read, {errors} refused");
    }
}
