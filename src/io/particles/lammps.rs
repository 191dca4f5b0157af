//! LAMMPS text dumps (`dump atom` and `dump custom`): frames of `ITEM:` sections, `TIMESTEP`,
//! `NUMBER OF ATOMS`, `BOX BOUNDS` (orthogonal, or triclinic with `xy xz yz` tilts) and `ATOMS`, whose
//! header names its columns in any order. Centres come from `x y z`, else unwrapped `xu yu zu`, else
//! scaled `xs ys zs` or `xsu ysu zsu` mapped through the box (triclinic too); an `element` column gives
//! the kind, else `type` (a LAMMPS type number); `radius` or `diameter` give the radius. Other sections
//! (`UNITS`, `TIME`) are skipped. Frames are counted in file order, whatever their timesteps. The box of
//! the chosen frame is kept (`Frame::cell`).

use std::path::Path;

use glam::DVec3;

use super::frame_lines::{self, How};
use super::text::{self, Lines};
use super::{Cell, Frame, Kind, Particle, Unit};
use crate::io::SceneError;

/// Where the columns of interest are.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Columns {
    pos: [usize; 3],
    scaled: bool,
    element: Option<usize>,
    kind: Option<usize>,
    /// Radius column and the factor to a radius (½ for a diameter).
    radius: Option<(usize, f64)>,
    words: usize,
}

/// Reads frame `wanted` (from 0) of a LAMMPS dump.
pub(crate) fn parse(path: &Path, source: &str, wanted: usize) -> Result<Frame, SceneError> {
    parse_as(path, source, wanted, How::Auto)
}

/// [`parse`], the frame's atom lines read as `how` says.
fn parse_as(path: &Path, source: &str, wanted: usize, how: How) -> Result<Frame, SceneError> {
    let mut lines = Lines::new(path, source);
    let (mut index, mut count, mut cell) = (0usize, None, None);
    while lines.more() {
        let line = lines.expect("an ITEM: line")?;
        let Some(item) = line.trim().strip_prefix("ITEM:").map(str::trim) else {
            return Err(lines.error(format!("expected an `ITEM:` line, got `{}`", line.trim())));
        };
        if item.starts_with("NUMBER OF ATOMS") {
            let n = lines.expect("the number of atoms")?;
            count = Some(text::count(n, "the number of atoms").map_err(|m| lines.error(m))?);
        } else if let Some(flags) = item.strip_prefix("BOX BOUNDS") {
            cell = Some(read_cell(&mut lines, flags)?);
        } else if let Some(names) = item.strip_prefix("ATOMS") {
            let n = count.ok_or_else(|| lines.error("ITEM: ATOMS before ITEM: NUMBER OF ATOMS"))?;
            if index == wanted {
                let columns = columns(names, cell.is_some()).map_err(|m| lines.error(m))?;
                return atoms(&mut lines, n, columns, cell, how);
            }
            for k in 0..n {
                let line = lines.expect_with(|| format!("{n} atom lines (frame {index})"))?;
                if line.trim_start().starts_with("ITEM:") {
                    return Err(
                        lines.error(format!("NUMBER OF ATOMS said {n}, but only {k} atom lines follow"))
                    );
                }
            }
            index += 1;
        } else {
            // TIMESTEP, UNITS, TIME and the like: their values are not needed.
            while lines.peek().is_some_and(|l| !l.trim_start().starts_with("ITEM:")) {
                lines.next();
            }
        }
    }
    match index {
        0 => Err(SceneError::whole_file(path, "no particles: no `ITEM: ATOMS` section")),
        n => Err(super::missing_frame(path, wanted, n)),
    }
}

/// The three lines of a `BOX BOUNDS` section; `flags` is the rest of its header.
fn read_cell(lines: &mut Lines, flags: &str) -> Result<Cell, SceneError> {
    let triclinic = flags.split_ascii_whitespace().any(|f| f == "xy");
    if flags.split_ascii_whitespace().any(|f| f == "abc") {
        return Err(lines.error("general triclinic boxes (`BOX BOUNDS abc origin`) are not supported"));
    }
    let mut v = [[0.0f64; 3]; 3];
    for (axis, row) in ["x", "y", "z"].iter().zip(&mut v) {
        let line = lines.expect(&format!("the box's {axis} bounds"))?;
        let words: Vec<&str> = line.split_ascii_whitespace().collect();
        let want = if triclinic { 3 } else { 2 };
        if words.len() < want {
            return Err(lines
                .error(format!("expected {want} numbers for the box's {axis} bounds, got {}", words.len())));
        }
        for k in 0..want {
            row[k] = text::number(words[k], "a box bound").map_err(|m| lines.error(m))?;
        }
    }
    let (xy, xz, yz) = (v[0][2], v[1][2], v[2][2]);
    // Triclinic bounds are those of the box's bounding box: the tilts are taken back out.
    let x_low = 0f64.min(xy).min(xz).min(xy + xz);
    let x_high = 0f64.max(xy).max(xz).max(xy + xz);
    let lo = DVec3::new(v[0][0] - x_low, v[1][0] - 0f64.min(yz), v[2][0]);
    let hi = DVec3::new(v[0][1] - x_high, v[1][1] - 0f64.max(yz), v[2][1]);
    let len = hi - lo;
    // LAMMPS' restricted triclinic box: a along x, b in the xy plane.
    let edges = [DVec3::new(len.x, 0.0, 0.0), DVec3::new(xy, len.y, 0.0), DVec3::new(xz, yz, len.z)];
    Ok(Cell { origin: lo, edges })
}

/// The columns an `ITEM: ATOMS` header names.
fn columns(names: &str, has_cell: bool) -> Result<Columns, String> {
    let names: Vec<&str> = names.split_ascii_whitespace().collect();
    let find = |name: &str| names.iter().position(|n| *n == name);
    let sets = [
        (["x", "y", "z"], false),
        (["xu", "yu", "zu"], false),
        (["xs", "ys", "zs"], true),
        (["xsu", "ysu", "zsu"], true),
    ];
    let (pos, scaled) = sets
        .iter()
        .find_map(|(set, scaled)| Some(([find(set[0])?, find(set[1])?, find(set[2])?], *scaled)))
        .ok_or("ITEM: ATOMS has no x y z, xu yu zu, xs ys zs or xsu ysu zsu columns")?;
    if scaled && !has_cell {
        return Err("scaled coordinates need the box, but no ITEM: BOX BOUNDS came before".to_owned());
    }
    let radius = find("radius").map(|i| (i, 1.0)).or_else(|| find("diameter").map(|i| (i, 0.5)));
    Ok(Columns { pos, scaled, element: find("element"), kind: find("type"), radius, words: names.len() })
}

/// The `count` atom lines of the chosen frame.
fn atoms<'a>(
    lines: &mut Lines<'a>,
    count: usize,
    c: Columns,
    cell: Option<Cell>,
    how: How,
) -> Result<Frame, SceneError> {
    if count == 0 {
        return Err(lines.error("a frame of 0 atoms"));
    }
    let mut frame = Frame::new(Unit::Angstrom);
    frame.cell = cell;
    let read = |k: usize, line: &'a str, words: &mut Vec<&'a str>| atom((k, count), line, words, c, cell);
    let name = |key: Option<&str>| match (c.element, key) {
        (Some(_), Some(element)) => frame.element_kind(element),
        (None, Some(t)) => frame.kind(Kind { name: t.to_owned(), element: None, lammps_type: true }),
        (_, None) => frame.kind(Kind { name: "1".to_owned(), element: None, lammps_type: true }),
    };
    frame.particles = frame_lines::read(lines, count, "atom", how, read, name)?;
    Ok(frame)
}

/// Atom line `k` of `count` and the key of its kind: its `element` word, else its `type` word, else none.
fn atom<'a>(
    (k, count): (usize, usize),
    line: &'a str,
    words: &mut Vec<&'a str>,
    c: Columns,
    cell: Option<Cell>,
) -> Result<(Particle, Option<&'a str>), String> {
    words.clear();
    words.extend(line.split_ascii_whitespace());
    if words.first().is_some_and(|w| *w == "ITEM:") {
        return Err(format!("NUMBER OF ATOMS said {count}, but only {k} atom lines follow"));
    }
    if words.len() < c.words {
        return Err(format!("expected {} columns, got {}", c.words, words.len()));
    }
    let v = |i: usize, what| text::number(words[i], what);
    let mut center = DVec3::new(v(c.pos[0], "x")?, v(c.pos[1], "y")?, v(c.pos[2], "z")?);
    if c.scaled {
        center = cell.expect("checked with the columns").point(center);
    }
    let radius = match c.radius {
        Some((i, factor)) => Some(text::radius(words[i], "radius")? * factor),
        None => None,
    };
    let key = c.element.or(c.kind).map(|i| words[i]);
    Ok((Particle { center, kind: 0, radius, color: None }, key))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triclinic_scaled_coordinates_map_through_the_box() {
        // A box with xlo 0, lx 10, ly 8, lz 6 and tilts xy 2, xz 1, yz -1, as LAMMPS writes its bounds.
        let text = "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS xy xz yz pp pp pp\n\
                    0 13 2\n-1 8 1\n0 6 -1\nITEM: ATOMS id type zs xs ys\n1 1 0 0 0\n2 2 1 1 1\n";
        let f = parse(Path::new("t.dump"), text, 0).unwrap();
        assert_eq!(f.particles[0].center, DVec3::ZERO);
        // (1,1,1) is a + b + c = (10 + 2 + 1, 8 - 1, 6).
        assert_eq!(f.particles[1].center, DVec3::new(13.0, 7.0, 6.0));
        assert!(f.kinds.iter().all(|k| k.lammps_type));
        let cell = f.cell.unwrap();
        assert_eq!(cell.origin, DVec3::ZERO);
        assert_eq!(
            cell.edges,
            [DVec3::new(10.0, 0.0, 0.0), DVec3::new(2.0, 8.0, 0.0), DVec3::new(1.0, -1.0, 6.0)]
        );
    }

    #[test]
    fn frames_columns_and_lies() {
        let frame = |t: u32, x: f64| {
            format!("ITEM: TIMESTEP\n{t}\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 1\n0 1\nITEM: ATOMS element diameter xu yu zu\nO 3.0 {x} 0 0\n")
        };
        let text = frame(0, 1.0) + &frame(10, 2.0);
        let path = Path::new("t.lammpstrj");
        let f = parse(path, &text, 1).unwrap();
        assert_eq!((f.particles[0].center.x, f.particles[0].radius), (2.0, Some(1.5)));
        assert_eq!(f.kinds[0].name, "O");
        assert_eq!(f.cell, Some(Cell { origin: DVec3::ZERO, edges: [DVec3::X, DVec3::Y, DVec3::Z] }));
        assert!(parse(path, &text, 5).unwrap_err().message.contains("2 frames"));
        let e = parse(path, &text.replacen("ATOMS\n1\n", "ATOMS\n2\n", 1), 0).unwrap_err();
        assert_eq!(e.line, 11, "{e}");
        let e = parse(path, &text.replace("xu yu zu", "a b c"), 0).unwrap_err();
        assert_eq!(e.line, 9, "{e}");
    }

    /// A large frame read in pieces gives one pass's atoms and kinds, by type or by element and with
    /// scaled coordinates through a triclinic box, with `\n` or `\r\n` line ends and a last line with or
    /// without one; a bad line or an `ITEM:` line too early in any piece gives one pass's error at its line.
    #[test]
    fn large_frames_in_pieces_read_as_one_pass() {
        let path = Path::new("t.dump");
        let n = 2 * frame_lines::PIECES_FROM + 9;
        let head = |columns: &str| {
            format!(
                "ITEM: TIMESTEP\n7\nITEM: NUMBER OF ATOMS\n{n}\nITEM: BOX BOUNDS xy xz yz pp pp pp\n\
                     0 13 2\n-1 8 1\n0 6 -1\nITEM: ATOMS {columns}\n"
            )
        };
        let kinds = ["1", "2", "3", "C", "O"];
        let line = |i: usize, element: bool| {
            let kind = if i == n - 2 { "7" } else { kinds[(i * 5 + i / 999) % if element { 5 } else { 3 }] };
            let (x, y, z) = ((i % 101) as f64 / 101.0, (i % 13) as f64 / 13.0, (i % 7) as f64 / 7.0);
            format!("{i} {kind} {x} {y} {z} {}", 1 + i % 3)
        };
        let cases = [
            ("id type xs ys zs diameter", false, "\n", "\n"),
            ("id element xs ys zs radius", true, "\r\n", ""),
        ];
        for (columns, element, end, last) in cases {
            let body: Vec<String> = (0..n).map(|i| line(i, element)).collect();
            let whole = head(columns) + &body.join(end) + last;
            let read = parse(path, &whole, 0).unwrap();
            assert!(read == parse_as(path, &whole, 0, How::OnePass).unwrap(), "{columns}: the frames differ");
            assert!(parse_as(path, &whole, 0, How::Pieces).is_ok_and(|f| f == read), "{columns}: no pieces");
            assert_eq!(read.particles.len(), n);
            assert_eq!(read.kinds.iter().any(|k| k.lammps_type), !element);
            for (bad, with) in
                [(2, "1 1 x 0 0 1"), (frame_lines::PIECES_FROM + 4, "ITEM: ATOMS"), (n - 1, "1 1")]
            {
                let mut broken = body.clone();
                broken[bad] = with.to_owned();
                let text = head(columns) + &broken.join(end) + last;
                let e = parse(path, &text, 0).unwrap_err();
                assert_eq!(e, parse_as(path, &text, 0, How::OnePass).unwrap_err());
                assert_eq!(e.line, bad + 10, "{e}");
            }
        }
    }
}
