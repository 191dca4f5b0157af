//! `.f32r` sphere lists: the spheres of an `.xyzr` list in binary, for fields too large to read quickly as
//! text (1e6 spheres are 16 MB instead of 46 MB, and need no number parsing). The scene around them is the
//! one an `.xyzr` list gets (`super::xyzr::scene_around`).
//!
//! The file, all little-endian:
//!
//! | bytes        | what                                                                   |
//! |--------------|------------------------------------------------------------------------|
//! | 0..8         | magic `MAGIC`: `89 'F' '3' '2' 'R' 0D 0A 1A`                          |
//! | 8..12        | version, u32: `VERSION` (1)                                          |
//! | 12..16       | count, u32: the number of records (≥ 1)                                |
//! | 16 + 16·i .. | record `i` (from 0): x, y, z, r as IEEE 754 binary32                    |
//!
//! The file is exactly `16 + 16·count` bytes. As in PNG's signature, the magic's high byte and its CR LF and
//! ^Z show a file mangled by a 7-bit or text-mode transfer. Each of these is an error naming the file: a
//! wrong magic (a file of another kind), an unknown version, a count of 0, a file that ends inside the
//! header or inside a record (naming that record and its byte offset), bytes after the last record, and a
//! record with a value that is not finite or a radius that is not positive (naming the first such record
//! and its byte offset; the rules of the `.xyzr` reader).

use std::io::{self, Write};
use std::path::Path;

use glam::DVec3;
use rayon::prelude::*;

use super::error::SceneError;
use crate::kinds::sphere::SphereDesc;
use crate::scene::desc::SceneDesc;

/// The file's first 8 bytes.
pub(crate) const MAGIC: [u8; 8] = *b"\x89F32R\r\n\x1a";
/// The layout version this reader reads and the writer writes.
pub(crate) const VERSION: u32 = 1;
/// Bytes before the first record: magic, version, count.
pub(crate) const HEADER_BYTES: usize = 16;
/// Bytes per record: x, y, z, r.
pub(crate) const RECORD_BYTES: usize = 16;

/// Reads an `.f32r` file.
pub(crate) fn load(path: &Path) -> Result<SceneDesc, SceneError> {
    let bytes = std::fs::read(path)
        .map_err(|e| SceneError::whole_file(path, format!("cannot read sphere list: {e}")))?;
    parse(path, &bytes)
}

/// Parses `.f32r` bytes; `path` names them in errors.
pub(crate) fn parse(path: &Path, bytes: &[u8]) -> Result<SceneDesc, SceneError> {
    Ok(super::xyzr::scene_around(spheres(path, bytes)?))
}

/// The spheres of `.f32r` bytes, in file order, checked as the module documentation says. Records are
/// converted in parallel (on the current rayon pool).
pub(crate) fn spheres(path: &Path, bytes: &[u8]) -> Result<Vec<SphereDesc>, SceneError> {
    let records = records(bytes).map_err(|m| SceneError::whole_file(path, m))?;
    let chunks = records.par_chunks_exact(RECORD_BYTES);
    if let Some(i) = chunks.clone().position_first(|r| problem(values(r)).is_some()) {
        let what = problem(values(&records[i * RECORD_BYTES..])).expect("the record has a problem");
        let at = HEADER_BYTES + i * RECORD_BYTES;
        return Err(SceneError::whole_file(path, format!("record {i} (byte {at}): {what}")));
    }
    let mut out = Vec::new();
    chunks
        .map(|r| {
            let [x, y, z, r] = values(r).map(f64::from);
            SphereDesc { center: DVec3::new(x, y, z), radius: r, material: 0 }
        })
        .collect_into_vec(&mut out);
    Ok(out)
}

/// An `.f32r` file mapped privately (copy-on-write): its records are read where they lie, with no copy, and
/// writes to them (the particle tree reorders them in place, `crate::accel::Particles`) go to private
/// pages of this process, never to the file. Records are checked as `spheres` checks them.
///
/// The mapping assumes the file is not changed by another process while it is mapped.
pub struct MappedRecords {
    map: memmap2::MmapMut,
    count: usize,
    /// The world box of the spheres (centres widened by radii).
    bounds: [DVec3; 2],
}

impl MappedRecords {
    /// The records `x, y, z, r`, in file order until something reorders them.
    pub(crate) fn records(&self) -> &[[f32; 4]] {
        // SAFETY: the map holds `HEADER_BYTES + count·RECORD_BYTES` bytes (checked by `map`); the map starts
        // on a page boundary, so the records, 16 bytes after it, are 4-byte aligned; any bits are valid f32s,
        // and the host is little-endian (checked by `map`), the file's order.
        unsafe { std::slice::from_raw_parts(self.map.as_ptr().add(HEADER_BYTES).cast(), self.count) }
    }

    /// The records, to reorder them (in private pages: the file is not changed).
    pub(crate) fn records_mut(&mut self) -> &mut [[f32; 4]] {
        // SAFETY: as in `records`, and the map is private to this process.
        unsafe { std::slice::from_raw_parts_mut(self.map.as_mut_ptr().add(HEADER_BYTES).cast(), self.count) }
    }

    /// Number of records.
    pub(crate) fn len(&self) -> usize {
        self.count
    }

    /// The world box of the spheres, `[lo, hi]`: every centre widened by its radius.
    pub(crate) fn bounds(&self) -> [DVec3; 2] {
        self.bounds
    }

    /// True when there are none (never, for a mapped file: the reader refuses a count of 0).
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }
}

impl crate::accel::pkd::RecordStore for MappedRecords {
    fn records(&self) -> &[[f32; 4]] {
        MappedRecords::records(self)
    }
    fn records_mut(&mut self) -> &mut [[f32; 4]] {
        MappedRecords::records_mut(self)
    }
}

impl std::fmt::Debug for MappedRecords {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "MappedRecords({} records within {:?})", self.count, self.bounds)
    }
}

/// Maps an `.f32r` file privately and checks it as [`load`] does (header, length, every record's values in
/// parallel on the current rayon pool), without reading it into memory first: the records stay in the
/// page cache, and only pages written later become this process's own.
pub(crate) fn map(path: &Path) -> Result<MappedRecords, SceneError> {
    let fail = |m: String| SceneError::whole_file(path, m);
    if cfg!(target_endian = "big") {
        return Err(fail("mapping .f32r records needs a little-endian machine".into()));
    }
    let file = std::fs::File::open(path).map_err(|e| fail(format!("cannot read sphere list: {e}")))?;
    let len = file.metadata().map_err(|e| fail(format!("cannot read sphere list: {e}")))?.len();
    if len < HEADER_BYTES as u64 {
        // Too short to map usefully (and an empty file cannot be mapped): the reader's own message.
        let bytes = std::fs::read(path).map_err(|e| fail(format!("cannot read sphere list: {e}")))?;
        return Err(fail(records(&bytes).err().unwrap_or_else(|| "the file changed while read".into())));
    }
    // SAFETY: a private mapping; the file is assumed not to change while mapped (see `MappedRecords`).
    let map = unsafe { memmap2::MmapOptions::new().map_copy(&file) }
        .map_err(|e| fail(format!("cannot map sphere list: {e}")))?;
    let body = records(&map).map_err(fail)?;
    // One pass: the first bad record, and the bounds of all of them.
    type Acc = (usize, DVec3, DVec3);
    let empty = || -> Acc { (usize::MAX, DVec3::INFINITY, DVec3::NEG_INFINITY) };
    let (bad, lo, hi) = body
        .par_chunks_exact(RECORD_BYTES)
        .enumerate()
        .with_min_len(1 << 16)
        .fold(empty, |(bad, lo, hi), (i, r)| {
            let v = values(r);
            if bad != usize::MAX || problem(v).is_some() {
                return (bad.min(i), lo, hi);
            }
            let (c, r) = (DVec3::new(v[0].into(), v[1].into(), v[2].into()), f64::from(v[3]));
            (bad, lo.min(c - r), hi.max(c + r))
        })
        .reduce(empty, |a, b| (a.0.min(b.0), a.1.min(b.1), a.2.max(b.2)));
    if bad != usize::MAX {
        let what = problem(values(&body[bad * RECORD_BYTES..])).expect("the record has a problem");
        let at = HEADER_BYTES + bad * RECORD_BYTES;
        return Err(fail(format!("record {bad} (byte {at}): {what}")));
    }
    let count = body.len() / RECORD_BYTES;
    Ok(MappedRecords { map, count, bounds: [lo, hi] })
}

/// The count an `.f32r` file's header states, read from its first 16 bytes alone (for a memory check before
/// loading); the header is checked as [`load`] checks it, the length and records are not.
pub(crate) fn header_count(path: &Path) -> Result<u64, SceneError> {
    use std::io::Read;
    let fail = |m: String| SceneError::whole_file(path, m);
    let mut head = Vec::with_capacity(HEADER_BYTES);
    std::fs::File::open(path)
        .and_then(|f| f.take(HEADER_BYTES as u64).read_to_end(&mut head))
        .map_err(|e| fail(format!("cannot read sphere list: {e}")))?;
    if head.len() < HEADER_BYTES || !head.starts_with(&MAGIC) {
        return Err(fail(records(&head).err().unwrap_or_else(|| "the header is cut short".into())));
    }
    let word = |at: usize| u32::from_le_bytes(head[at..at + 4].try_into().expect("4 bytes"));
    match (word(8), word(12)) {
        (VERSION, 0) => Err(fail("no spheres: the header's count is 0".into())),
        (VERSION, count) => Ok(u64::from(count)),
        (v, _) => {
            Err(fail(format!("version {v} is not one this bareray reads (it reads version {VERSION})")))
        }
    }
}

/// The record bytes after a checked header, or what is wrong with the header or the length.
fn records(bytes: &[u8]) -> Result<&[u8], String> {
    let len = bytes.len();
    if !bytes.starts_with(&MAGIC[..len.min(MAGIC.len())]) {
        return Err(format!("not an .f32r sphere list: the first 8 bytes are not {}", hex(&MAGIC)));
    }
    if len < HEADER_BYTES {
        return Err(format!("the file ends inside the {HEADER_BYTES}-byte header, after {len} bytes"));
    }
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    let (version, count) = (word(8), word(12));
    if version != VERSION {
        return Err(format!("version {version} is not one this bareray reads (it reads version {VERSION})"));
    }
    if count == 0 {
        return Err("no spheres: the header's count is 0".into());
    }
    let body = len - HEADER_BYTES;
    let expected = count as u64 * RECORD_BYTES as u64;
    if (body as u64) < expected {
        let i = body / RECORD_BYTES;
        return Err(format!(
            "the file ends inside record {i} (byte {}): the header's count is {count}, which needs {} \
             bytes, the file has {len}",
            HEADER_BYTES + i * RECORD_BYTES,
            HEADER_BYTES as u64 + expected
        ));
    }
    if body as u64 > expected {
        return Err(format!(
            "{} bytes follow the last of the header's {count} records (the file has {len} bytes, {} expected)",
            body as u64 - expected,
            HEADER_BYTES as u64 + expected
        ));
    }
    Ok(&bytes[HEADER_BYTES..])
}

/// The four values of the record starting `r`.
fn values(r: &[u8]) -> [f32; 4] {
    std::array::from_fn(|k| f32::from_le_bytes(r[4 * k..4 * k + 4].try_into().expect("4 bytes")))
}

/// What is wrong with a record's values, if anything: the `.xyzr` reader's rules.
fn problem(v: [f32; 4]) -> Option<String> {
    if let Some(k) = v.iter().position(|x| !x.is_finite()) {
        return Some(format!("{} is not finite ({})", ["x", "y", "z", "r"][k], v[k]));
    }
    (v[3] <= 0.0).then(|| format!("radius must be positive, got {}", v[3]))
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect::<Vec<_>>().join(" ")
}

/// Converts an `.xyzr` file into `.f32r` in bounded memory: each line is read, checked as `parse` checks
/// it, rounded to f32 and written as it comes (a radius that rounds to 0 is an error: the file would be
/// refused), and the header's count is written last. Returns the number of spheres. Errors name the file
/// and line; an I/O error on `out` is reported as itself.
pub fn from_xyzr<W: std::io::Write + std::io::Seek>(path: &Path, out: &mut W) -> Result<u64, StreamError> {
    use std::io::BufRead;
    let file = std::fs::File::open(path).map_err(|e| {
        StreamError::Scene(SceneError::whole_file(path, format!("cannot read sphere list: {e}")))
    })?;
    let mut reader = std::io::BufReader::with_capacity(1 << 20, file);
    write_header(out, 0)?;
    let (mut count, mut line, mut text) = (0u64, 0usize, String::new());
    loop {
        text.clear();
        let read = reader.read_line(&mut text).map_err(|e| {
            let what = format!("cannot read line {}: {e}", line + 1);
            StreamError::Scene(SceneError::whole_file(path, what))
        })?;
        if read == 0 {
            break;
        }
        line += 1;
        let trimmed = text.trim();
        if !super::xyzr::is_sphere(trimmed) {
            continue;
        }
        let fail = |m: String| StreamError::Scene(SceneError::at_line(path, line, m));
        let s = super::xyzr::sphere(trimmed).map_err(fail)?;
        let v = [s.center.x, s.center.y, s.center.z, s.radius].map(|x| x as f32);
        if v[3] <= 0.0 {
            return Err(fail(format!("radius {} is 0 as an f32", s.radius)));
        }
        if count == u64::from(u32::MAX) {
            return Err(fail(format!("more than {} spheres, the most an .f32r file holds", u32::MAX)));
        }
        for x in v {
            out.write_all(&x.to_le_bytes())?;
        }
        count += 1;
    }
    if count == 0 {
        return Err(StreamError::Scene(SceneError::whole_file(
            path,
            "no spheres: expected lines of `x y z r`",
        )));
    }
    out.seek(std::io::SeekFrom::Start(0))?;
    write_header(out, count as u32)?;
    Ok(count)
}

/// Why [`from_xyzr`] stopped: the input's fault, or the output's.
#[derive(Debug, thiserror::Error)]
pub enum StreamError {
    /// A bad or unreadable input line.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Writing the output failed.
    #[error(transparent)]
    Write(#[from] std::io::Error),
}

/// Writes the 16-byte header of an `.f32r` file of `count` records (a streaming writer writes it again
/// once it knows the count).
pub(crate) fn write_header(w: &mut impl Write, count: u32) -> io::Result<()> {
    w.write_all(&MAGIC)?;
    w.write_all(&VERSION.to_le_bytes())?;
    w.write_all(&count.to_le_bytes())
}

/// Writes an `.f32r` file of `count` spheres `[x, y, z, r]`. The caller vouches for the values (finite,
/// radius positive); a `count` of 0, above `u32::MAX`, or not matching the spheres given is an
/// `InvalidInput` error (the count is written before the records).
pub fn write(w: &mut impl Write, count: u64, spheres: impl IntoIterator<Item = [f32; 4]>) -> io::Result<()> {
    let invalid = |m: String| io::Error::new(io::ErrorKind::InvalidInput, m);
    let n = u32::try_from(count)
        .ok()
        .filter(|&n| n > 0)
        .ok_or_else(|| invalid(format!("an .f32r file holds 1 to {} spheres, not {count}", u32::MAX)))?;
    w.write_all(&MAGIC)?;
    w.write_all(&VERSION.to_le_bytes())?;
    w.write_all(&n.to_le_bytes())?;
    let mut written = 0u64;
    let mut block = Vec::with_capacity(RECORD_BYTES * 4096);
    for s in spheres {
        if written == count {
            return Err(invalid(format!("{count} spheres announced, more given")));
        }
        written += 1;
        block.extend(s.iter().flat_map(|v| v.to_le_bytes()));
        if block.len() == block.capacity() {
            w.write_all(&block)?;
            block.clear();
        }
    }
    w.write_all(&block)?;
    if written != count {
        return Err(invalid(format!("{count} spheres announced, {written} given")));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(spheres: &[[f32; 4]]) -> Vec<u8> {
        let mut out = Vec::new();
        write(&mut out, spheres.len() as u64, spheres.iter().copied()).unwrap();
        out
    }

    fn err(bytes: &[u8]) -> String {
        spheres(Path::new("t.f32r"), bytes).unwrap_err().to_string()
    }

    #[test]
    fn round_trips_every_value_exactly() {
        let v = [[1.5, -2.0, 3.0e-30, 0.25], [f32::MAX, f32::MIN, -0.0, f32::MIN_POSITIVE / 4.0]];
        let bytes = file(&v);
        assert_eq!(bytes.len(), HEADER_BYTES + 2 * RECORD_BYTES);
        assert_eq!(&bytes[..16], b"\x89F32R\r\n\x1a\x01\0\0\0\x02\0\0\0");
        let got = spheres(Path::new("t.f32r"), &bytes).unwrap();
        for (s, v) in got.iter().zip(v) {
            let back = [s.center.x, s.center.y, s.center.z, s.radius].map(|x| x as f32);
            assert_eq!(back.map(f32::to_bits), v.map(f32::to_bits));
        }
    }

    #[test]
    fn header_and_length_errors_say_what_and_where() {
        let good = file(&[[0.0, 0.0, 0.0, 1.0], [1.0, 1.0, 1.0, 1.0]]);
        assert!(err(b"0 0 0 1\n").starts_with("t.f32r: not an .f32r sphere list"), "{}", err(b"0 0 0 1\n"));
        assert!(err(&good[..5]).contains("ends inside the 16-byte header, after 5 bytes"));
        assert!(err(&[]).contains("after 0 bytes"));
        let mut v2 = good.clone();
        v2[8] = 2;
        assert!(err(&v2).contains("version 2 is not"), "{}", err(&v2));
        let mut none = good[..16].to_vec();
        none[12] = 0;
        assert!(err(&none).contains("no spheres"));
        assert!(err(&good[..16 + 16 + 3]).contains("ends inside record 1 (byte 32)"), "{}", err(&good[..35]));
        assert!(err(&good[..16]).contains("ends inside record 0 (byte 16)"));
        let mut long = good.clone();
        long.push(0);
        assert!(err(&long).contains("1 bytes follow the last of the header's 2 records"), "{}", err(&long));
    }

    #[test]
    fn the_first_bad_record_is_named() {
        let mut v = vec![[0.0f32, 0.0, 0.0, 1.0]; 5000];
        v[3000][3] = -1.0;
        v[4000][0] = f32::NAN;
        assert_eq!(err(&file(&v)), "t.f32r: record 3000 (byte 48016): radius must be positive, got -1");
        v[1234][2] = f32::INFINITY;
        assert_eq!(err(&file(&v)), "t.f32r: record 1234 (byte 19760): z is not finite (inf)");
        v[7][3] = -0.0;
        assert!(err(&file(&v)).starts_with("t.f32r: record 7 (byte 128): radius must be positive"));
    }

    #[test]
    fn writer_refuses_counts_that_do_not_fit_or_match() {
        let one = [[0.0f32, 0.0, 0.0, 1.0]];
        for (count, given) in [(0u64, 0usize), (1 << 32, 1), (2, 1), (1, 0)] {
            let e = write(&mut Vec::new(), count, one.iter().copied().cycle().take(given)).unwrap_err();
            assert_eq!(e.kind(), io::ErrorKind::InvalidInput, "{count} {given}");
        }
        let e = write(&mut Vec::new(), 1, one.iter().copied().cycle().take(2)).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
    }
}
