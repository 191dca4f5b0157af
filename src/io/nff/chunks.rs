//! A large NFF file read in pieces, in parallel (SPD's `balls` at size 6 is 50 MB of text).
//!
//! The file is cut before lines whose first word names an entity (`v`, `b`, `l`, `f`, `s`, `p`, `pp`, `c`).
//! In a file that reads, such a word always starts an entity: numbers never look like one, and the two
//! entities that look ahead (`v` for its keywords, `l` for a colour) stop at it. So each piece reads as it
//! would in one pass, but for the state carried from the pieces before it: the fill in force, whether the
//! view was seen, the lights so far. A piece reads with none of it, marking objects before its first `f`
//! [`INHERITED`], and the pieces are then joined in file order, resolving that state as one pass would.
//! Whenever a piece fails to read or the pieces do not join (a second view), the file is read again in one
//! pass, which reports the file's first error, with its line, exactly.

use std::path::Path;

use rayon::prelude::*;

use super::{parse_sequential, Reader};
use crate::io::error::SceneError;
use crate::io::pieces::{after_newline, cuts};
use crate::kinds::sphere::SphereDesc;
use crate::scene::desc::SceneDesc;

/// Bytes of text per piece.
pub(super) const CHUNK_BYTES: usize = 1 << 20;

/// The material of an object before its piece's first `f`: the fill in force where the piece starts.
pub(super) const INHERITED: u32 = u32::MAX;

/// The words that start an entity.
const ENTITIES: [&str; 8] = ["v", "b", "l", "f", "s", "p", "pp", "c"];

/// [`super::parse`] with pieces of about `chunk_bytes`.
pub(super) fn parse(path: &Path, source: &str, chunk_bytes: usize) -> Result<SceneDesc, SceneError> {
    let pieces = pieces(source, chunk_bytes);
    if pieces.len() < 2 {
        return parse_sequential(path, source);
    }
    match read_pieces(path, &pieces) {
        Some(reader) => reader.finish(),
        None => parse_sequential(path, source),
    }
}

/// The pieces read in parallel and joined; `None` when one does not read or they do not join.
fn read_pieces<'a>(path: &'a Path, pieces: &[&'a str]) -> Option<Reader<'a>> {
    let read: Option<Vec<Reader>> = pieces
        .par_iter()
        .map(|text| {
            let mut reader = Reader::new(path, text, true);
            reader.read_all().ok().map(|()| reader)
        })
        .collect();
    join(path, read?)
}

/// `source` cut into pieces of about `size` bytes (at least a line), each but the first starting with a line
/// whose first word names an entity.
fn pieces(source: &str, size: usize) -> Vec<&str> {
    let bytes = source.as_bytes();
    let entity = |mut from: usize| loop {
        // Just after a '\n', so a char boundary.
        from = after_newline(bytes, from)?;
        if starts_entity(&source[from..]) {
            return Some(from);
        }
    };
    cuts(bytes, size, entity).windows(2).map(|w| &source[w[0]..w[1]]).collect()
}

/// Whether the first word of `text`'s first line names an entity.
fn starts_entity(text: &str) -> bool {
    let line = text.split('\n').next().unwrap_or_default();
    line.split_ascii_whitespace().next().is_some_and(|word| ENTITIES.contains(&word))
}

/// The pieces' readings joined in file order, as one reading of the whole would have left its state; `None`
/// when the file has more than one view.
fn join<'a>(path: &'a Path, pieces: Vec<Reader<'a>>) -> Option<Reader<'a>> {
    let mut all = Reader::new(path, "", false);
    // Each piece's spheres with its materials' mapping, appended together at the end.
    let mut spheres = Vec::with_capacity(pieces.len());
    for piece in pieces {
        let desc = piece.desc;
        if piece.view_seen {
            if all.view_seen {
                return None;
            }
            (all.view_seen, all.desc.camera) = (true, desc.camera);
        }
        if piece.background_seen {
            all.desc.render.background = desc.render.background;
        }
        let lights = all.desc.lights.len();
        all.colourless.extend(piece.colourless.iter().map(|i| i + lights));
        all.desc.lights.extend(desc.lights);
        // The first object without a fill of its own makes the default material, as in one pass.
        let inherits =
            desc.spheres.iter().map(|s| s.material).chain(desc.kinds.cones.iter().map(|c| c.material));
        let inherits = inherits.chain(desc.kinds.polygons.iter().map(|p| p.material)).any(|m| m == INHERITED);
        let inherited = if inherits { all.current_material() } else { INHERITED };
        let offset = all.desc.materials.len() as u32;
        let map = move |m: u32| if m == INHERITED { inherited } else { m + offset };
        let d = &mut all.desc;
        spheres.push((desc.spheres, map));
        d.kinds.cones.extend(desc.kinds.cones.into_iter().map(|mut c| (c.material = map(c.material), c).1));
        let polygons = desc.kinds.polygons.into_iter().map(|mut p| (p.material = map(p.material), p).1);
        d.kinds.polygons.extend(polygons);
        d.materials.extend(desc.materials);
        if let Some(m) = piece.material {
            all.material = Some(m + offset);
        }
    }
    append_mapped(&mut all.desc.spheres, &spheres);
    Some(all)
}

/// Appends each part's spheres to `out` in order, their materials mapped by the part's map. In parallel, each
/// sphere written once into its place: the list is the file's largest (598 000 spheres in SPD's balls at
/// size 6), and one thread appending it, page by fresh page, would be a serial step of the parse.
fn append_mapped(out: &mut Vec<SphereDesc>, parts: &[(Vec<SphereDesc>, impl Fn(u32) -> u32 + Sync)]) {
    // starts[p]: the place of part p's first sphere among the appended ones.
    let starts: Vec<usize> =
        parts.iter().scan(0, |at, (s, _)| Some(std::mem::replace(at, *at + s.len()))).collect();
    let total = parts.iter().map(|(s, _)| s.len()).sum::<usize>();
    out.par_extend((0..total).into_par_iter().map(|k| {
        let p = starts.partition_point(|&start| start <= k) - 1;
        let (spheres, map) = &parts[p];
        let s = spheres[k - starts[p]];
        SphereDesc { material: map(s.material), ..s }
    }));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scene with every entity, objects before the first fill, fills changing mid-file, entities split
    /// over lines, comments, CRLF line ends, two backgrounds and lights with and without colour, `copies`
    /// times over (one view, in the middle).
    fn scene(copies: usize) -> String {
        let block = "s 0 0 0 1\nl 1 2 3\nc 0 0 0 1\n 0 0 2 0.5\n# comment\nf 1 0 0 1 0.5 3 0 1\r\n\
                     s 1 1 1 0.5 # trailing\np 3\n0 0 0\n1 0 0\n0 1 0\nb 0.1 0.2 0.3\n\
                     pp 3 0 0 0 0 0 1\n 1 0 0 0 0 1 0 1 0 0 0 1\nl 4 5 6 0.5 0.5 0.5\n\
                     f 0 1 0 1 0 0 0 0\ns 2\n2 2\n0.25\n   \n";
        let view = "v\nfrom 0 0 -5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 0.01\nresolution 64 48\n";
        let mut text = block.repeat(copies / 2);
        text.push_str(view);
        text.push_str(&block.replace("f 1 0 0", "f 0 0 1").repeat(copies - copies / 2));
        text
    }

    fn sequential(text: &str) -> Result<SceneDesc, SceneError> {
        parse_sequential(Path::new("t.nff"), text)
    }

    #[test]
    fn pieces_read_as_one_pass() {
        let text = scene(9);
        let whole = sequential(&text).unwrap();
        assert!(whole.materials.len() > 9 && whole.spheres[0].material != whole.spheres[1].material);
        for size in [1, 7, 40, 300, 1 << 20] {
            let pieces = pieces(&text, size);
            assert_eq!(pieces.concat(), text, "pieces of {size} bytes lose text");
            assert!(size > text.len() || pieces.len() > 3, "{size} bytes: only {} pieces", pieces.len());
            assert!(pieces[1..].iter().all(|p| starts_entity(p)), "{size} bytes: a cut inside an entity");
            let joined = read_pieces(Path::new("t.nff"), &pieces).expect("the pieces join");
            assert!(joined.finish().unwrap() == whole, "pieces of {size} bytes read differently");
        }
    }

    /// Mutants of a scene (words dropped, repeated or inserted, lines indented, joined or cut short, the
    /// last newline removed) read in pieces as in one pass: the same scene or the same error. A share of
    /// them must still read, so the joins are exercised and not only the fallback.
    #[test]
    fn mutated_scenes_read_as_one_pass() {
        let inserts =
            ["v", "l", "f", "s 1 2 3 0.5", "inf", "nan", "1e40", "-1", "#", "p 3", "from 0 0 0", "b 1 1 1"];
        let mut rng = crate::math::SplitMix64::new(26);
        let mut pick = move |n: usize| (rng.next_u64() % n as u64) as usize;
        let (mut read, mut failed) = (0, 0);
        for _ in 0..300 {
            let mut lines: Vec<String> = scene(4).lines().map(str::to_owned).collect();
            for _ in 0..1 + pick(3) {
                let at = pick(lines.len());
                let mut words: Vec<String> = lines[at].split(' ').map(str::to_owned).collect();
                let w = pick(words.len());
                match pick(6) {
                    0 => drop(words.remove(w)),
                    1 => words.insert(w, words[w].clone()),
                    2 => words.insert(w, inserts[pick(inserts.len())].to_owned()),
                    3 => words.insert(0, " \t".to_owned()),
                    4 if at + 1 < lines.len() => words.push(lines.remove(at + 1)),
                    _ => words.truncate(w),
                }
                lines[at] = words.join(" ");
            }
            let mut text = lines.join("\n");
            if pick(2) == 0 {
                text.push('\n');
            }
            let once = sequential(&text).map_err(|e| e.to_string());
            (read, failed) = if once.is_ok() { (read + 1, failed) } else { (read, failed + 1) };
            for size in [1, 37, 300] {
                let read = parse(Path::new("t.nff"), &text, size).map_err(|e| e.to_string());
                assert!(read == once, "pieces of {size} bytes differ on:\n{text}");
                // A file that reads in one pass reads in pieces, without the fallback.
                let joined = read_pieces(Path::new("t.nff"), &pieces(&text, size)).is_some();
                assert!(joined || once.is_err(), "pieces of {size} bytes fell back on:\n{text}");
            }
        }
        assert!(read >= 30 && failed >= 30, "{read} mutants read and {failed} failed");
    }

    /// Every error is the one-pass reading's, file and line, wherever the pieces are cut.
    #[test]
    fn errors_are_those_of_one_pass() {
        let view = "v\nfrom 0 0 -5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 0.01\nresolution 64 48\n";
        let good = scene(6);
        for text in [
            format!("{good}{view}"),
            format!("{good}s 1 2 x 4\n{good}"),
            format!("{good}s 1 2 3\n"),
            format!("{good}q 1\n"),
            good.replace(view, ""),
        ] {
            let once = sequential(&text).unwrap_err().to_string();
            for size in [1, 50, 1000] {
                let e = parse(Path::new("t.nff"), &text, size).unwrap_err().to_string();
                assert_eq!(e, once, "pieces of {size} bytes");
            }
        }
    }
}
