//! XYZ files: frames of a count line, a comment line and one `element x y z` line per particle (further
//! columns ignored). Extended XYZ names its columns in the comment line, `Properties=NAME:TYPE:COUNT:...`
//! (types `S` string, `R` real, `I` integer, `L` logical): `species` (or `element`) gives the kind, `Z` an
//! atomic number, `pos` the centre, `radius` (or `radii`) a radius and `color` (or `colors`) an RGB colour
//! with channels in [0, 1]; other columns are skipped. The element may be a symbol or an atomic number.
//! `Lattice="ax ay az bx by bz cx cy cz"` in the comment line gives the periodic box's edge vectors, from
//! the origin or from `Origin="x y z"`.

use std::path::Path;

use glam::DVec3;

use super::frame_lines::{self, How};
use super::text::{self, Lines};
use super::{Cell, Frame, Particle, Unit};
use crate::io::SceneError;
use crate::math::Rgb;

/// Where the columns of interest are on a particle line.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Columns {
    kind: Option<usize>,
    pos: usize,
    radius: Option<usize>,
    color: Option<usize>,
    /// How many words a line has at least.
    words: usize,
}

const PLAIN: Columns = Columns { kind: Some(0), pos: 1, radius: None, color: None, words: 4 };

/// Reads frame `wanted` (from 0) of an XYZ text.
pub(crate) fn parse(path: &Path, source: &str, wanted: usize) -> Result<Frame, SceneError> {
    parse_as(path, source, wanted, How::Auto)
}

/// [`parse`], the frame's lines read as `how` says.
fn parse_as(path: &Path, source: &str, wanted: usize, how: How) -> Result<Frame, SceneError> {
    let mut lines = Lines::new(path, source);
    let mut index = 0;
    while lines.more() {
        let count_line = lines.expect("a particle count")?;
        let count = text::count(count_line, "a particle count").map_err(|m| lines.error(m))?;
        let comment = lines.expect("the comment line")?;
        if index == wanted {
            let columns = columns(comment).map_err(|m| lines.error(m))?;
            let cell = lattice(comment).map_err(|m| lines.error(m))?;
            let mut frame = frame(&mut lines, count, columns, how)?;
            frame.cell = cell;
            return Ok(frame);
        }
        for _ in 0..count {
            lines.expect_with(|| format!("{count} particle lines (frame {index})"))?;
        }
        index += 1;
    }
    match index {
        0 => Err(SceneError::whole_file(
            path,
            "no particles: expected a count line, a comment and `element x y z` lines",
        )),
        n => Err(super::missing_frame(path, wanted, n)),
    }
}

/// The columns a comment line names (extended XYZ), or the plain ones.
fn columns(comment: &str) -> Result<Columns, String> {
    let Some(at) = find_key(comment, "properties=") else { return Ok(PLAIN) };
    let value = comment[at..].split_ascii_whitespace().next().unwrap_or("").trim_matches('"');
    let parts: Vec<&str> = value.split(':').collect();
    if !parts.len().is_multiple_of(3) || parts.is_empty() {
        return Err(format!("Properties=`{value}`: expected NAME:TYPE:COUNT triples"));
    }
    let (mut kind, mut pos, mut radius, mut color, mut at) = (None, None, None, None, 0usize);
    for triple in parts.chunks(3) {
        let (name, kind_of, n) = (triple[0], triple[1].to_ascii_uppercase(), triple[2]);
        let n: usize = match n.parse() {
            Ok(n) if (1..=1000).contains(&n) => n,
            _ => return Err(format!("Properties: column `{name}` has count `{n}`, expected 1 to 1000")),
        };
        let want = |ok: bool, spec: &str| match ok {
            true => Ok(Some(at)),
            false => Err(format!("Properties: column `{name}` is {}:{n}, expected {spec}", triple[1])),
        };
        match name.to_ascii_lowercase().as_str() {
            "species" | "element" => kind = want(kind_of == "S" && n == 1, "S:1")?,
            "z" if kind.is_none() => kind = want(kind_of == "I" && n == 1, "I:1")?,
            "pos" => pos = want(kind_of == "R" && n == 3, "R:3")?,
            "radius" | "radii" => radius = want(kind_of == "R" && n == 1, "R:1")?,
            "color" | "colors" => color = want(kind_of == "R" && n == 3, "R:3")?,
            _ => {}
        }
        at += n;
    }
    let pos = pos.ok_or("Properties has no `pos:R:3` column")?;
    Ok(Columns { kind, pos, radius, color, words: at })
}

/// The box a comment line's `Lattice=` (and `Origin=`) give, if it has one.
fn lattice(comment: &str) -> Result<Option<Cell>, String> {
    let Some(value) = key_value(comment, "lattice") else { return Ok(None) };
    let v = numbers(value).filter(|v| v.len() == 9);
    let v = v.ok_or_else(|| {
        format!("Lattice=\"{value}\": expected 9 finite numbers (the box's 3 edge vectors)")
    })?;
    let origin = match key_value(comment, "origin") {
        Some(o) => match numbers(o).filter(|v| v.len() == 3) {
            Some(o) => DVec3::new(o[0], o[1], o[2]),
            None => return Err(format!("Origin=\"{o}\": expected 3 finite numbers")),
        },
        None => DVec3::ZERO,
    };
    let edges = [0, 3, 6].map(|k| DVec3::new(v[k], v[k + 1], v[k + 2]));
    Ok(Some(Cell { origin, edges }))
}

/// The words of `text` as finite numbers, or `None` if one is not.
fn numbers(text: &str) -> Option<Vec<f64>> {
    text.split_ascii_whitespace().map(|w| text::number(w, "").ok()).collect()
}

/// The value of `key=` (matched without regard to case, at the start of a word) in a comment line: the text
/// between the quotes after it, or the word after it.
fn key_value<'a>(comment: &'a str, key: &str) -> Option<&'a str> {
    let lower = comment.to_ascii_lowercase();
    let pattern = format!("{key}=");
    let at = lower
        .match_indices(&pattern)
        .map(|(i, _)| i)
        .find(|&i| i == 0 || lower.as_bytes()[i - 1].is_ascii_whitespace())?;
    let rest = &comment[at + pattern.len()..];
    match rest.strip_prefix('"') {
        Some(quoted) => Some(quoted.split('"').next().unwrap_or("")),
        None => rest.split_ascii_whitespace().next(),
    }
}

/// Byte offset just after `key` (matched without regard to case) in `text`.
fn find_key(text: &str, key: &str) -> Option<usize> {
    let lower = text.to_ascii_lowercase();
    lower.find(key).map(|i| i + key.len())
}

/// The `count` particle lines of a frame ([`frame_lines::read`]; kinds named by element, a frame without
/// a kind column all of kind `?`, which is named first in any case).
fn frame<'a>(lines: &mut Lines<'a>, count: usize, columns: Columns, how: How) -> Result<Frame, SceneError> {
    let mut frame = Frame::new(Unit::Angstrom);
    let unnamed = frame.element_kind("?");
    let read = |_: usize, line: &'a str, words: &mut Vec<&'a str>| particle(line, columns, words);
    let name = |key: Option<&str>| key.map_or(unnamed, |name| frame.element_kind(name));
    frame.particles = frame_lines::read(lines, count, "particle", how, read, name)?;
    if count == 0 {
        return Err(lines.error("a frame of 0 particles"));
    }
    Ok(frame)
}

/// One particle line and its element name (`None` without a kind column).
fn particle<'a>(
    line: &'a str,
    c: Columns,
    words: &mut Vec<&'a str>,
) -> Result<(Particle, Option<&'a str>), String> {
    words.clear();
    words.extend(line.split_ascii_whitespace());
    if words.len() < c.words {
        return Err(format!("expected {} columns, got {}", c.words, words.len()));
    }
    let v = |i: usize, what: &str| text::number(words[i], what);
    let center = DVec3::new(v(c.pos, "x")?, v(c.pos + 1, "y")?, v(c.pos + 2, "z")?);
    let radius = c.radius.map(|i| text::radius(words[i], "radius")).transpose()?;
    let color = match c.color {
        Some(i) => {
            let rgb = [v(i, "red")?, v(i + 1, "green")?, v(i + 2, "blue")?];
            if rgb.iter().any(|x| !(0.0..=1.0).contains(x)) {
                return Err(format!("colour {rgb:?}: channels run from 0 to 1"));
            }
            Some(Rgb::new(rgb[0] as f32, rgb[1] as f32, rgb[2] as f32))
        }
        None => None,
    };
    Ok((Particle { center, kind: 0, radius, color }, c.kind.map(|k| words[k])))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extended_columns_are_found_in_any_order() {
        let c = columns(
            r#"Lattice="1 0 0 0 1 0 0 0 1" Properties=id:I:1:pos:R:3:color:R:3:species:S:1:radius:R:1 t=0"#,
        );
        assert_eq!(c, Ok(Columns { kind: Some(7), pos: 1, radius: Some(8), color: Some(4), words: 9 }));
        assert_eq!(columns("just a comment"), Ok(PLAIN));
        assert!(columns("Properties=species:S:1").unwrap_err().contains("pos"));
        assert!(columns("Properties=pos:R:2").is_err());
        assert!(columns("Properties=pos:R").is_err());
    }

    #[test]
    fn frames_are_chosen_and_counted() {
        let text = "2\nfirst\nC 0 0 0\nO 1.2 0 0\n1\nsecond\nH 0 0 1\n";
        let path = Path::new("t.xyz");
        let f = parse(path, text, 1).unwrap();
        assert_eq!(f.particles.len(), 1);
        assert_eq!(f.kinds[f.particles[0].kind as usize].name, "H");
        let e = parse(path, text, 2).unwrap_err();
        assert!(e.message.contains("has 2 frames (0 to 1)"), "{e}");
        let e = parse(path, "3\nc\nC 0 0 0\nC 1 x 0\n", 0).unwrap_err();
        assert_eq!(e.line, 4, "{e}");
        let e = parse(path, "3\nc\nC 0 0 0\n", 0).unwrap_err();
        assert_eq!(e.line, 3, "{e}");
    }

    #[test]
    fn lattice_and_origin_give_the_box() {
        let path = Path::new("t.xyz");
        let text = "1\npbc=\"T T T\" Lattice=\"2 0 0 0 3 0 1 0 4\" Properties=species:S:1:pos:R:3\nC 0 0 0\n";
        let cell = parse(path, text, 0).unwrap().cell.unwrap();
        assert_eq!(
            (cell.origin, cell.edges),
            (DVec3::ZERO, [DVec3::X * 2.0, DVec3::Y * 3.0, DVec3::new(1.0, 0.0, 4.0)])
        );
        let with_origin = text.replace("pbc=", "Origin=\"-1 -1 -1\" pbc=");
        assert_eq!(parse(path, &with_origin, 0).unwrap().cell.unwrap().origin, DVec3::NEG_ONE);
        assert_eq!(parse(path, "1\nplain\nC 0 0 0\n", 0).unwrap().cell, None);
        // Only a key at the start of a word counts.
        assert_eq!(parse(path, "1\nsuperlattice=1\nC 0 0 0\n", 0).unwrap().cell, None);
        let e = parse(path, &text.replace("1 0 4", "1 0"), 0).unwrap_err();
        assert!(e.line == 2 && e.message.contains("expected 9"), "{e}");
        let e = parse(path, &with_origin.replace("-1 -1 -1", "nan 0 0"), 0).unwrap_err();
        assert!(e.line == 2 && e.message.contains("Origin"), "{e}");
    }

    /// Frames read in pieces give one pass's particles and kinds (kinds in order of first sight, names
    /// that are one element merged, no kind column), for line ends `\n` and `\r\n` and a last line with or
    /// without one; a bad line anywhere, or a file that ends early, gives one pass's error at its line.
    #[test]
    fn frames_in_pieces_read_as_one_pass() {
        let path = Path::new("t.xyz");
        let n = 3 * frame_lines::PIECES_FROM + 7;
        let names = ["Zz", "C", "O", "8", "Xx", "c"];
        // A kind first seen only in the last piece, and the rest cycling.
        let name = |i: usize| if i == n - 2 { "Qq" } else { names[(i * 7 + i / 1000) % names.len()] };
        let line = |i: usize| {
            let (x, y, z, r) = (i % 97, i % 13, i % 11, 1 + i % 5);
            format!("{} {i} {x}.5 -{y}e-3 {z} {r} 0.{} 0.5 1", name(i), i % 10)
        };
        let extended = "Properties=species:S:1:id:I:1:pos:R:3:radius:R:1:color:R:3";
        let one_pass = |text: &str| parse_as(path, text, 0, How::OnePass);
        // Line ends; the text after the frame (a second frame, a bare '\r', nothing); a non-ASCII comment
        // column on every line, so that piece cuts fall inside characters.
        let next_frame = "\n2\nnext\nC 0 0 0\nO 1 1 1\n";
        for (comment, end, last, note) in [
            (extended, "\n", next_frame, " # café ∂x"),
            ("plain", "\r\n", "", ""),
            ("plain", "\n", "\r", " ∂"),
            ("Properties=pos:R:3", "\n", "", ""),
        ] {
            let body: Vec<String> = (0..n)
                .map(|i| match comment {
                    "plain" => line(i)
                        .split(' ')
                        .enumerate()
                        .filter(|(k, _)| *k != 1)
                        .map(|(_, w)| w)
                        .collect::<Vec<_>>()
                        .join(" "),
                    "Properties=pos:R:3" => line(i).split(' ').skip(2).take(3).collect::<Vec<_>>().join(" "),
                    _ => line(i),
                } + note)
                .collect();
            let text = format!("{n}{end}{comment}{end}{}{last}", body.join(end));
            let read = parse(path, &text, 0).unwrap();
            assert!(read == one_pass(&text).unwrap(), "{comment}: the frames differ");
            let pieces = parse_as(path, &text, 0, How::Pieces);
            assert!(pieces.is_ok_and(|f| f == read), "{comment}: not read in pieces");
            assert_eq!(read.particles.len(), n);
            for bad in [5, frame_lines::PIECES_FROM + 3, n - 1] {
                let mut lines: Vec<String> = body.clone();
                lines[bad] = lines[bad].replacen(".5 ", ".5x ", 1);
                let text = format!("{n}{end}{comment}{end}{}{last}", lines.join(end));
                let e = parse(path, &text, 0).unwrap_err();
                assert_eq!(e, one_pass(&text).unwrap_err());
                assert_eq!(e.line, bad + 3, "{e}");
            }
            let short = format!("{n}{end}{comment}{end}{}", body[..n - 1].join(end));
            assert_eq!(parse(path, &short, 0).unwrap_err(), one_pass(&short).unwrap_err());
        }
    }
}
