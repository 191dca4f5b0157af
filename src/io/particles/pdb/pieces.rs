//! A large PDB or PQR text's frame read in pieces in parallel, with the particles, kinds and box that one
//! pass ([`super`]) reads. The text is cut into pieces of whole lines, marked a few pieces at a time in
//! parallel: in each piece the records that shape frames (`MODEL`, `ENDMDL`, `END`, `CRYST1`) with the number
//! of atom records before each. The marks are replayed in order as one pass steps through the records (the
//! `CRYST1` records parsed as it meets them), which gives the wanted frame's byte range and its atoms in each
//! piece, and stops where the frame ends: the rest of the text is not read, and the marks held are a few
//! pieces' worth. The frame's atom records are then read piece by piece ([`frame_lines::read_pieces`]: kinds
//! named in the order one pass meets them). Whatever would stop one pass (a bad record, a missing or empty
//! frame) gives `None`, and one pass reads the text again to report it at its line.

use rayon::prelude::*;

use super::super::{frame_lines, Frame, Unit};
use super::{atom, cryst1, kind_of, record, Record};
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

/// A piece's marks up to its first `END` (one pass reads nothing after it), and its atom records after the
/// last mark.
#[derive(Debug, Default)]
struct Marks {
    marks: Vec<Mark>,
    atoms_after: usize,
}

/// Frame `wanted` of a PDB (or, when `pqr`, PQR) text, read in pieces of about `piece_bytes`; `None` where
/// one pass must read it.
pub(super) fn read<'a>(source: &'a str, wanted: usize, pqr: bool, piece_bytes: usize) -> Option<Frame> {
    let pieces = line_pieces(source, piece_bytes);
    let mut frame = Frame::new(Unit::Angstrom);
    let mut replay = Replay {
        source,
        pqr,
        wanted,
        current: 0,
        open: false,
        range: (0, source.len()),
        atoms: vec![0; pieces.len()],
    };
    let batch = 2 * rayon::current_num_threads();
    'text: for (b, group) in pieces.chunks(batch).enumerate() {
        let marks: Vec<Marks> = group.par_iter().map(|p| marks(source, p, pqr)).collect();
        for (k, piece) in marks.iter().enumerate() {
            if replay.step(b * batch + k, piece, &mut frame)? {
                break 'text;
            }
        }
    }
    let ((start, end), atoms) = replay.found()?;
    let offset = |p: &str| p.as_ptr() as usize - source.as_ptr() as usize;
    let clipped: Vec<&str> = pieces
        .iter()
        .map(|p| {
            let (from, to) = (offset(p).max(start), (offset(p) + p.len()).min(end));
            &source[from..to.max(from)]
        })
        .collect();
    let keep = |line: &str| matches!(record(line, pqr), Record::Atom { .. });
    let read_line = |_: usize, line: &'a str, _: &mut Vec<&'a str>| match record(line, pqr) {
        Record::Atom { hetatm } => atom(line, pqr, hetatm),
        _ => Err(String::new()),
    };
    let mut name = |key| kind_of(&mut frame, key);
    let particles = frame_lines::read_pieces(&clipped, &atoms, keep, &read_line, &mut name)?;
    frame.particles = particles;
    Some(frame)
}

/// The marks of `piece`, a slice of `source` of whole lines.
fn marks(source: &str, piece: &str, pqr: bool) -> Marks {
    let mut out = Marks::default();
    for line in piece.lines() {
        match record(line, pqr) {
            Record::Atom { .. } => out.atoms_after += 1,
            Record::Other => {}
            record => {
                let at = line.as_ptr() as usize - source.as_ptr() as usize;
                out.marks.push(Mark { at, record, atoms_before: std::mem::take(&mut out.atoms_after) });
                if record == Record::End {
                    break;
                }
            }
        }
    }
    out
}

/// The marks stepped through as one pass steps through records (`one_pass`).
struct Replay<'a> {
    source: &'a str,
    pqr: bool,
    wanted: usize,
    /// The frame the next atoms belong to, and whether it has begun, as in one pass.
    current: usize,
    open: bool,
    /// The byte range the wanted frame's atom records lie in (no other frame's atom record inside).
    range: (usize, usize),
    /// The wanted frame's atom records in each piece.
    atoms: Vec<usize>,
}

impl Replay<'_> {
    /// Steps through the marks of piece `p`, the `CRYST1` records' boxes into `frame`: `Some(true)` where the
    /// wanted frame ends (at the record closing it, or `END`), `None` at a `CRYST1` record one pass stops at.
    fn step(&mut self, p: usize, piece: &Marks, frame: &mut Frame) -> Option<bool> {
        for mark in &piece.marks {
            self.atoms(p, mark.atoms_before);
            match mark.record {
                Record::Model | Record::EndModel => {
                    if self.open {
                        if self.current == self.wanted {
                            self.range.1 = mark.at;
                            return Some(true);
                        }
                        self.current += 1;
                        if self.current == self.wanted {
                            self.range.0 = mark.at;
                        }
                    }
                    self.open = mark.record == Record::Model;
                }
                Record::Cryst1 => {
                    frame.cell = cryst1(self.source[mark.at..].lines().next()?, self.pqr).ok()?
                }
                Record::End => {
                    self.range.1 = mark.at;
                    return Some(true);
                }
                Record::Atom { .. } | Record::Other => unreachable!("not a mark"),
            }
        }
        self.atoms(p, piece.atoms_after);
        Some(false)
    }

    /// `n` atom records of piece `p` met.
    fn atoms(&mut self, p: usize, n: usize) {
        self.open |= n > 0;
        if self.current == self.wanted {
            self.atoms[p] += n;
        }
    }

    /// The wanted frame's byte range and atoms per piece; `None` where one pass finds no such frame or an
    /// empty one.
    fn found(self) -> Option<((usize, usize), Vec<usize>)> {
        let some = self.open && self.current == self.wanted && self.atoms.iter().any(|&n| n > 0);
        some.then_some((self.range, self.atoms))
    }
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
                    if one.is_ok() {
                        assert_eq!(parse_as(path, &text, wanted, false, How::Pieces), one);
                    }
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

    /// PQR records in pieces (whitespace-separated, radius read from the end), in models and with `END`.
    #[test]
    fn pqr_in_pieces() {
        let line = |i: usize| {
            format!("ATOM {i} {} MET {} {}.5 -2 3 0.1 {}.25", ["N", "CA", "OW"][i % 3], i, i % 9, 1 + i % 2)
        };
        let atoms = |from: usize, n: usize| (from..from + n).map(line).collect::<Vec<_>>().join("\n");
        let text = format!("CRYST1 5 5 5 90 90 90\n{}\n", atoms(0, 4000));
        let one = parse_as(Path::new("t.pqr"), &text, 0, true, How::OnePass).unwrap();
        assert_eq!(read(&text, 0, true, 3000), Some(one));
        let models = format!(
            "MODEL 1\n{}\nENDMDL\nMODEL 2\n{}\nCRYST1 7 7 7 90 90 90\nENDMDL\nMODEL 3\n{}\nEND\n{}\n",
            atoms(0, 900),
            atoms(900, 1100),
            atoms(2000, 50),
            atoms(3000, 10)
        );
        for wanted in 0..4 {
            let one = parse_as(Path::new("t.pqr"), &models, wanted, true, How::OnePass).ok();
            assert_eq!(read(&models, wanted, true, 2000), one, "frame {wanted}");
            assert_eq!(one.is_some(), wanted < 3);
        }
    }

    /// A text of 2 MiB or more is read in pieces: the frame one pass reads, or where a record is bad, one
    /// pass's error at its line.
    #[test]
    fn large_texts_are_read_in_pieces_or_again_in_one_pass() {
        let path = Path::new("t.pdb");
        let lines: Vec<String> = (0..PIECES_FROM_BYTES / 70).map(|i| atom(i, i % 5 == 0)).collect();
        let text = lines.join("\n");
        assert!(text.len() >= PIECES_FROM_BYTES);
        let pieces = parse_as(path, &text, 0, false, How::Pieces).unwrap();
        assert_eq!(parse_as(path, &text, 0, false, How::Auto), Ok(pieces.clone()));
        assert_eq!(Ok(pieces), parse_as(path, &text, 0, false, How::OnePass));
        let bad = text.replace(&lines[20_000], &lines[20_000].replacen('.', "x", 1));
        let e = parse_as(path, &bad, 0, false, How::Auto).unwrap_err();
        assert_eq!((e.line, Err(e.clone())), (20_001, parse_as(path, &bad, 0, false, How::OnePass)));
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
