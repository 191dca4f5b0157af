//! A frame's particle lines, read in one pass or, for a large frame, in pieces on the current rayon pool,
//! with the same particles and kinds either way. A reader (XYZ, GRO, LAMMPS; PDB and PQR through
//! [`read_pieces`], once `pdb::pieces` has found the frame) gives the read of one line, which yields a
//! particle and the key of its kind (an element name, a LAMMPS type, a GRO atom and residue name), and the
//! naming of a key as a kind of the frame. Keys are named once each, in the order one pass first meets
//! them, so kinds are numbered as one pass numbers them.

use std::collections::HashMap;
use std::hash::Hash;

use rayon::prelude::*;

use super::text::{self, Lines};
use super::Particle;
use crate::io::pieces::{line_pieces, slices_of};
use crate::io::SceneError;

/// Frames of at least this many particles are read in pieces.
pub(super) const PIECES_FROM: usize = 1 << 15;

/// Bytes of text per piece.
pub(super) const PIECE_BYTES: usize = 1 << 20;

/// How [`read`] reads a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum How {
    /// In pieces from [`PIECES_FROM`] lines on, else (or where the pieces do not read) in one pass.
    Auto,
    /// In one pass.
    #[cfg_attr(not(test), allow(dead_code))]
    OnePass,
    /// In pieces, whatever the count; an error where the pieces do not read (the tests compare the ways).
    #[cfg_attr(not(test), allow(dead_code))]
    Pieces,
}

/// The `count` particle lines that `lines` holds next, each read by `read_line` (`(k, line, words)`: `k` the
/// line's place in the frame, from 0, for messages; `words` a scratch list for its words) into a particle
/// (its kind unset) and the key of its kind; each key is named once by `name`, which gives its kind's index
/// in the frame, in the order one pass meets the keys. By [`How::Auto`], a frame of [`PIECES_FROM`] lines or more
/// is read in pieces; where the text ends first or a line does not read, it is read again in one pass, which
/// reports the first error at its line (`noun` names the lines: "expected 9 atom lines").
pub(super) fn read<'a, K: Copy + Eq + Hash + Send + Sync>(
    lines: &mut Lines<'a>,
    count: usize,
    noun: &str,
    how: How,
    read_line: impl Fn(usize, &'a str, &mut Vec<&'a str>) -> Result<(Particle, K), String> + Sync,
    mut name: impl FnMut(K) -> u32,
) -> Result<Vec<Particle>, SceneError> {
    if how == How::Pieces || (how == How::Auto && count >= PIECES_FROM) {
        match (in_pieces(lines, count, &read_line, &mut name), how) {
            (Some(particles), _) => return Ok(particles),
            (None, How::Pieces) => return Err(lines.error("not read in pieces")),
            (None, _) => {}
        }
    }
    one_pass(lines, count, noun, &read_line, &mut name)
}

/// [`read`] one line after another.
fn one_pass<'a, K: Copy + Eq + Hash>(
    lines: &mut Lines<'a>,
    count: usize,
    noun: &str,
    read_line: &impl Fn(usize, &'a str, &mut Vec<&'a str>) -> Result<(Particle, K), String>,
    name: &mut impl FnMut(K) -> u32,
) -> Result<Vec<Particle>, SceneError> {
    let mut particles = Vec::with_capacity(text::capacity(count, lines.rest().len()));
    let mut kinds: HashMap<K, u32> = HashMap::new();
    let mut words = Vec::new();
    for k in 0..count {
        let line = lines.expect_with(|| format!("{count} {noun} lines"))?;
        let (particle, key) = read_line(k, line, &mut words).map_err(|m| lines.error(m))?;
        let kind = *kinds.entry(key).or_insert_with(|| name(key));
        particles.push(Particle { kind, ..particle });
    }
    Ok(particles)
}

/// [`read`] in pieces: `None`, with nothing taken from `lines` and no key named, when the text ends
/// before `count` lines or a line does not read. The frame's pieces ([`frame_pieces`]) are read by
/// [`read_pieces`].
fn in_pieces<'a, K: Copy + Eq + Hash + Send + Sync>(
    lines: &mut Lines<'a>,
    count: usize,
    read_line: &(impl Fn(usize, &'a str, &mut Vec<&'a str>) -> Result<(Particle, K), String> + Sync),
    name: &mut impl FnMut(K) -> u32,
) -> Option<Vec<Particle>> {
    let (pieces, counts) = frame_pieces(lines.rest(), count)?;
    let particles = read_pieces(&pieces, &counts, |_| true, read_line, name)?;
    lines.skip(pieces.iter().map(|p| p.len()).sum(), count);
    Some(particles)
}

/// The pieces of `rest` that hold its first `count` lines, and each one's lines: pieces of
/// the text have their lines counted a few pieces at a time in parallel until they hold `count`, and the
/// last is cut after the frame's last line ([`frame_end`], within that piece alone). `None` where the text
/// has fewer lines, or `count` is 0.
fn frame_pieces(rest: &str, count: usize) -> Option<(Vec<&str>, Vec<usize>)> {
    if count == 0 {
        return None;
    }
    let all = line_pieces(rest, PIECE_BYTES);
    let batch = 2 * rayon::current_num_threads();
    let (mut counts, mut before) = (Vec::new(), 0);
    for group in all.chunks(batch) {
        let from = counts.len();
        counts.par_extend(group.par_iter().map(|p| p.lines().count()));
        for k in from..counts.len() {
            if before + counts[k] >= count {
                let need = count - before;
                let mut pieces = all[..=k].to_vec();
                pieces[k] = &all[k][..frame_end(all[k], need - 1)?];
                counts.truncate(k + 1);
                counts[k] = need;
                return Some((pieces, counts));
            }
            before += counts[k];
        }
    }
    None
}

/// The particles of `pieces` (whole lines each, in order), read in parallel: piece `p` holds `counts[p]`
/// lines that `keep` takes (the others are skipped), each read by `read_line` (`k` its place among the kept
/// lines of all the pieces). Each piece's particles are read straight into their places in one list, each
/// kind as the place of its key among the piece's keys in order of first sight; the keys are then named
/// piece by piece (the order of one pass) and the kinds renumbered. `None`, no key named, where a piece's
/// kept lines are not its count or a line does not read.
pub(super) fn read_pieces<'a, K: Copy + Eq + Hash + Send + Sync>(
    pieces: &[&'a str],
    counts: &[usize],
    keep: impl Fn(&str) -> bool + Sync,
    read_line: &(impl Fn(usize, &'a str, &mut Vec<&'a str>) -> Result<(Particle, K), String> + Sync),
    name: &mut impl FnMut(K) -> u32,
) -> Option<Vec<Particle>> {
    let firsts: Vec<usize> = counts.iter().scan(0, |at, n| Some(std::mem::replace(at, *at + n))).collect();
    let count = counts.iter().sum();
    let unset = Particle { center: glam::DVec3::ZERO, kind: 0, radius: None, color: None };
    let mut particles: Vec<Particle> = (0..count).into_par_iter().map(|_| unset).collect();
    let keys: Vec<Vec<K>> = slices_of(&mut particles, counts)
        .into_par_iter()
        .zip(pieces.par_iter().zip(&firsts))
        .map(|(out, (text, &first))| piece(text, first, out, &keep, read_line))
        .collect::<Option<_>>()?;
    let mut kinds: HashMap<K, u32> = HashMap::new();
    let renumber: Vec<Vec<u32>> = keys
        .iter()
        .map(|keys| keys.iter().map(|&key| *kinds.entry(key).or_insert_with(|| name(key))).collect())
        .collect();
    slices_of(&mut particles, counts).into_par_iter().zip(&renumber).for_each(|(out, kinds)| {
        out.iter_mut().for_each(|p| p.kind = kinds[p.kind as usize]);
    });
    Some(particles)
}

/// The byte offset in `rest` where its line `last` (from 0) ends (after its `\n`, or the text's end for
/// a last line without one); `None` when it has fewer lines.
fn frame_end(rest: &str, last: usize) -> Option<usize> {
    match rest.match_indices('\n').map(|(i, _)| i + 1).nth(last) {
        Some(end) => Some(end),
        None => {
            let last_unended = !rest.is_empty() && !rest.ends_with('\n');
            (last_unended && rest.matches('\n').count() == last).then_some(rest.len())
        }
    }
}

/// The lines of one piece that `keep` takes, the first being line `first` of the frame, read into `out`
/// (which they must fill exactly) with kinds numbered by first sight among the piece's keys, which it
/// returns; `None` where a line does not read or the kept lines do not fill `out`.
fn piece<'a, K: Copy + Eq + Hash>(
    text: &'a str,
    first: usize,
    out: &mut [Particle],
    keep: &impl Fn(&str) -> bool,
    read_line: &impl Fn(usize, &'a str, &mut Vec<&'a str>) -> Result<(Particle, K), String>,
) -> Option<Vec<K>> {
    let (mut keys, mut local) = (Vec::new(), HashMap::new());
    let mut words = Vec::new();
    let mut kept = text.lines().filter(|line| keep(line));
    for (k, slot) in out.iter_mut().enumerate() {
        let (particle, key) = read_line(first + k, kept.next()?, &mut words).ok()?;
        let kind = *local.entry(key).or_insert_with(|| (keys.push(key), keys.len() as u32 - 1).1);
        *slot = Particle { kind, ..particle };
    }
    kept.next().is_none().then_some(keys)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where line `last` ends: after its `\n`, or at the end of a last line without one; never in a text
    /// with fewer lines (an empty text has none, and a frame asked of it in pieces is an error, not a
    /// particle made up).
    #[test]
    fn frame_pieces_hold_the_frame_and_its_lines() {
        let text = "a\nbb\r\n\nccc\nd\ne".repeat(100_000);
        let lines: Vec<&str> = text.lines().collect();
        for count in [1, 2, 3, 5, 99_999, 250_001, 500_000, lines.len()] {
            let (pieces, counts) = frame_pieces(&text, count).unwrap();
            assert_eq!(counts.iter().sum::<usize>(), count);
            assert!(pieces.iter().zip(&counts).all(|(p, &n)| p.lines().count() == n), "{count}");
            let frame = pieces.concat();
            assert!(text.starts_with(&frame) && frame.lines().eq(lines[..count].iter().copied()), "{count}");
        }
        assert_eq!(frame_pieces(&text, lines.len() + 1), None);
        assert_eq!(frame_pieces(&text, 0), None);
        assert_eq!(frame_pieces("", 1), None);
    }

    #[test]
    fn frame_ends_after_the_last_line() {
        assert_eq!(frame_end("", 0), None);
        assert_eq!(frame_end("a", 0), Some(1));
        assert_eq!(frame_end("a\n", 0), Some(2));
        assert_eq!(frame_end("a\nb", 1), Some(3));
        assert_eq!(frame_end("a\n", 1), None);
        assert_eq!(frame_end("a\r\nb\r\nc", 1), Some(6));
        assert_eq!(frame_end("a\nb\r", 1), Some(4));
        let particle = Particle { center: glam::DVec3::ZERO, kind: 0, radius: None, color: None };
        let read_line = |_: usize, _: &str, _: &mut Vec<&str>| Ok((particle, ()));
        let mut lines = Lines::new(std::path::Path::new("t"), "");
        assert!(read(&mut lines, 1, "test", How::Pieces, read_line, |()| 0).is_err());
        let mut lines = Lines::new(std::path::Path::new("t"), "x");
        assert_eq!(read(&mut lines, 1, "test", How::Pieces, read_line, |()| 0), Ok(vec![particle]));
    }
}
