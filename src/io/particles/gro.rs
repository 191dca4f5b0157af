//! GROMACS `.gro` files: frames of a title line, a count line, one fixed-column line per atom and a box
//! line (3 or 9 numbers, kept as the frame's box). Atom lines are `%5d%-5s%5s%5d` (residue number and
//! name, atom name and number) then x, y, z in nm, each as wide as the distance between the first two decimal points (8 characters at
//! the usual 3 decimals); velocities after them are ignored. The element comes from the atom name (an ion
//! named as its residue, `NA` in residue `NA`, else the name's first letter: `OW` is oxygen).

use std::path::Path;

use glam::DVec3;

use super::elements;
use super::frame_lines::{self, How};
use super::text::{self, columns, Lines};
use super::{Cell, Frame, Kind, Particle, Unit};
use crate::io::SceneError;

/// Reads frame `wanted` (from 0) of a `.gro` text.
pub(crate) fn parse(path: &Path, source: &str, wanted: usize) -> Result<Frame, SceneError> {
    parse_as(path, source, wanted, How::Auto)
}

/// [`parse`], the frame's atom lines read as `how` says.
fn parse_as(path: &Path, source: &str, wanted: usize, how: How) -> Result<Frame, SceneError> {
    let mut lines = Lines::new(path, source);
    let mut index = 0;
    while lines.more() {
        lines.expect("a title line")?;
        let count_line = lines.expect("an atom count")?;
        let count = text::count(count_line, "an atom count").map_err(|m| lines.error(m))?;
        if index == wanted {
            return frame(&mut lines, count, how);
        }
        for _ in 0..count {
            lines.expect_with(|| format!("{count} atom lines (frame {index})"))?;
        }
        box_line(&mut lines)?;
        index += 1;
    }
    match index {
        0 => {
            Err(SceneError::whole_file(path, "no particles: expected a title, an atom count and atom lines"))
        }
        n => Err(super::missing_frame(path, wanted, n)),
    }
}

/// The atoms of a frame and its box line.
fn frame<'a>(lines: &mut Lines<'a>, count: usize, how: How) -> Result<Frame, SceneError> {
    if count == 0 {
        return Err(lines.error("a frame of 0 atoms"));
    }
    let mut frame = Frame::new(Unit::Nanometre);
    let width = lines.peek().map_or(8, field_width);
    let read = |_: usize, line: &'a str, _: &mut Vec<&'a str>| atom(line, width);
    let name = |(name, residue): (&str, &str)| match elements::from_atom_name(name, residue, false) {
        Some(e) => frame.kind(Kind { name: e.0.to_owned(), element: Some(e), lammps_type: false }),
        None => frame.element_kind(name.trim()),
    };
    frame.particles = frame_lines::read(lines, count, "atom", how, read, name)?;
    frame.cell = Some(box_line(lines)?);
    Ok(frame)
}

/// One atom line, its coordinates `w` wide from column 21, and its atom and residue names (the key of its
/// kind).
fn atom(line: &str, w: usize) -> Result<(Particle, (&str, &str)), String> {
    let v = |k: usize, what| text::number(columns(line, 20 + k * w, 20 + (k + 1) * w), what);
    let xyz = (|| Ok::<_, String>(DVec3::new(v(0, "x")?, v(1, "y")?, v(2, "z")?)))();
    let center = xyz.map_err(|m| format!("{m} (columns from 21, {w} wide)"))?;
    let particle = Particle { center, kind: 0, radius: None, color: None };
    Ok((particle, (columns(line, 10, 15), columns(line, 5, 10))))
}

/// The width of the coordinate fields of an atom line: the distance between the decimal points of x and
/// y, or 8 where that is not plausible.
fn field_width(line: &str) -> usize {
    let rest = columns(line, 20, line.len()).as_bytes();
    let mut dots = rest.iter().enumerate().filter(|(_, &b)| b == b'.').map(|(i, _)| i);
    match (dots.next(), dots.next()) {
        (Some(a), Some(b)) if (4..=20).contains(&(b - a)) => b - a,
        _ => 8,
    }
}

/// A box line: 3 or 9 numbers (nm), `v1(x) v2(y) v3(z)` and then `v1(y) v1(z) v2(x) v2(z) v3(x) v3(y)`,
/// the box vectors from the origin; separated by spaces, or run together ([`run_together`]).
fn box_line(lines: &mut Lines) -> Result<Cell, SceneError> {
    let line = lines.expect("the box line (3 or 9 numbers)")?;
    let mut words: Vec<&str> = line.split_ascii_whitespace().collect();
    if words.len() != 3 && words.len() != 9 {
        words = run_together(line).unwrap_or(words);
    }
    if words.len() != 3 && words.len() != 9 {
        return Err(
            lines.error(format!("expected the box line (3 or 9 numbers), got {} fields", words.len()))
        );
    }
    let mut v = [0.0; 9];
    for (k, word) in words.iter().enumerate() {
        v[k] = text::number(word, "a box length").map_err(|m| lines.error(m))?;
    }
    let edges = [DVec3::new(v[0], v[3], v[4]), DVec3::new(v[5], v[1], v[6]), DVec3::new(v[7], v[8], v[2])];
    Ok(Cell { origin: DVec3::ZERO, edges })
}

/// The fields of a box line whose numbers run together, as GROMACS' `%10.5f` writes them from 10 000 nm
/// on (`40000.0000040000.0000040000.00000`): each ends as many digits after its decimal point as the last
/// one has. `None` unless that cuts the line into 3 or 9 fields exactly.
fn run_together(line: &str) -> Option<Vec<&str>> {
    let t = line.trim();
    let dots: Vec<usize> = t.match_indices('.').map(|(i, _)| i).collect();
    if !t.is_ascii() || !matches!(dots.len(), 3 | 9) {
        return None;
    }
    let decimals = t.len() - dots[dots.len() - 1] - 1;
    let mut fields = Vec::with_capacity(dots.len());
    let mut start = 0;
    for dot in dots {
        let end = dot + decimals + 1;
        if dot < start || end > t.len() {
            return None;
        }
        fields.push(&t[start..end]);
        start = end;
    }
    (start == t.len()).then_some(fields)
}

#[cfg(test)]
mod tests {
    use super::*;

    const WATER: &str = concat!(
        "water\n    3\n",
        "    1SOL     OW    1   0.126   1.624   1.679  0.1227 -0.0580  0.0434\n",
        "    1SOL    HW1    2   0.190   1.661   1.747\n",
        "    1SOL    HW2    3   0.177   1.568   1.613\n",
        "   1.86206   1.86206   1.86206\n"
    );

    #[test]
    fn atoms_in_nm_with_elements_from_names() {
        let f = parse(Path::new("t.gro"), WATER, 0).unwrap();
        assert_eq!(f.unit, Unit::Nanometre);
        assert_eq!(f.particles[0].center, DVec3::new(0.126, 1.624, 1.679));
        let names: Vec<&str> = f.particles.iter().map(|p| f.kinds[p.kind as usize].name.as_str()).collect();
        assert_eq!(names, ["O", "H", "H"]);
        assert_eq!(f.cell.unwrap().edges, [DVec3::X, DVec3::Y, DVec3::Z].map(|e| e * 1.86206));
    }

    #[test]
    fn triclinic_box_lines() {
        let text = WATER.replace("   1.86206   1.86206   1.86206", " 1 2 3 0.1 0.2 0.3 0.4 0.5 0.6");
        let cell = parse(Path::new("t.gro"), &text, 0).unwrap().cell.unwrap();
        let edges = [DVec3::new(1.0, 0.1, 0.2), DVec3::new(0.3, 2.0, 0.4), DVec3::new(0.5, 0.6, 3.0)];
        assert_eq!(cell.edges, edges);
        let huge = WATER.replace("   1.86206   1.86206   1.86206", "40000.0000040000.0000040000.00000");
        let cell = parse(Path::new("t.gro"), &huge, 0).unwrap().cell.unwrap();
        assert_eq!(cell.edges, [DVec3::X, DVec3::Y, DVec3::Z].map(|e| e * 40000.0));
    }

    #[test]
    fn frames_and_wider_fields() {
        let wide = "t\n1\n    1NA      NA    1   1.23456   2.00000  -3.00000\n 1 1 1\n";
        let text = format!("{WATER}{wide}");
        let f = parse(Path::new("t.gro"), &text, 1).unwrap();
        assert_eq!(f.particles[0].center, DVec3::new(1.23456, 2.0, -3.0));
        assert_eq!(f.kinds[0].name, "Na");
        assert!(parse(Path::new("t.gro"), &text, 2).unwrap_err().message.contains("2 frames"));
        let e = parse(Path::new("t.gro"), &WATER.replace("1.661", "1.6x1"), 0).unwrap_err();
        assert_eq!(e.line, 4, "{e}");
        let e = parse(Path::new("t.gro"), &WATER.replace("    3\n", "    4\n"), 0).unwrap_err();
        assert_eq!(e.line, 6, "{e}");
    }

    /// A large frame read in pieces gives one pass's atoms, kinds (an ion first seen in the last piece)
    /// and box, with `\n` or `\r\n` line ends; a bad coordinate in any piece, or a file that ends early,
    /// gives one pass's error at its line.
    #[test]
    fn large_frames_in_pieces_read_as_one_pass() {
        let path = Path::new("t.gro");
        let n = 2 * frame_lines::PIECES_FROM + 5;
        let names = [("SOL", "OW"), ("SOL", "HW1"), ("SOL", "HW2"), ("LIG", "C1"), ("LIG", "N2")];
        let line = |i: usize| {
            let (residue, name) =
                if i == n - 3 { ("NA", "NA") } else { names[(i * 3 + i / 777) % names.len()] };
            let (x, y, z) = ((i % 1000) as f64 * 0.013, (i % 37) as f64 * 0.1, -((i % 7) as f64));
            format!("{:>5}{residue:<5}{name:>5}{:>5}{x:8.3}{y:8.3}{z:8.3}", i % 100_000, i % 100_000)
        };
        for end in ["\n", "\r\n"] {
            let body: Vec<String> = (0..n).map(line).collect();
            let text =
                |body: &[String]| format!("big{end}{n}{end}{}{end}   2.0   3.0   4.0{end}", body.join(end));
            let whole = text(&body);
            let read = parse(path, &whole, 0).unwrap();
            assert!(read == parse_as(path, &whole, 0, How::OnePass).unwrap(), "{end:?}: the frames differ");
            assert!(parse_as(path, &whole, 0, How::Pieces).is_ok_and(|f| f == read), "{end:?}: no pieces");
            assert_eq!((read.particles.len(), read.kinds.last().map(|k| k.name.as_str())), (n, Some("Na")));
            for bad in [3, frame_lines::PIECES_FROM + 1, n - 1] {
                let mut broken = body.clone();
                broken[bad].replace_range(24..25, "x");
                let e = parse(path, &text(&broken), 0).unwrap_err();
                assert_eq!(e, parse_as(path, &text(&broken), 0, How::OnePass).unwrap_err());
                assert_eq!(e.line, bad + 3, "{e}");
            }
            let short = format!("big{end}{n}{end}{}", body[..n - 1].join(end));
            assert_eq!(
                parse(path, &short, 0).unwrap_err(),
                parse_as(path, &short, 0, How::OnePass).unwrap_err()
            );
        }
    }
}
