//! Errors of scene readers: every one names the file, and the line and column where the reader could tell.

use std::fmt;
use std::path::{Path, PathBuf};

/// A scene that could not be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SceneError {
    /// The file (or a name such as `<built-in demo>`).
    pub(crate) path: PathBuf,
    /// 1-based line, 0 when the error is about the whole file.
    pub(crate) line: usize,
    /// 1-based column, 0 when unknown.
    pub(crate) column: usize,
    /// What was wrong and what was expected.
    pub(crate) message: String,
}

impl SceneError {
    /// An error at a byte offset of `source`.
    pub(crate) fn at_offset(path: &Path, source: &str, offset: usize, message: impl Into<String>) -> Self {
        let (line, column) = line_column(source, offset);
        Self { path: path.to_owned(), line, column, message: message.into() }
    }
    /// An error at a 1-based line (column unknown).
    pub(crate) fn at_line(path: &Path, line: usize, message: impl Into<String>) -> Self {
        Self { path: path.to_owned(), line, column: 0, message: message.into() }
    }
    /// An error about the whole file.
    pub(crate) fn whole_file(path: &Path, message: impl Into<String>) -> Self {
        Self { path: path.to_owned(), line: 0, column: 0, message: message.into() }
    }
}

/// Files from this size up are mapped rather than read ([`read_text`]).
const MAP_BYTES: u64 = 1 << 20;

/// A scene file's text: read into memory, or for large files the file's pages mapped read-only (a 50 MB NFF
/// read is 50 MB copied into fresh pages before any parsing starts; the mapping hands over the page
/// cache's own pages). Derefs to `str`.
#[derive(Debug)]
pub(crate) enum Text {
    /// Read into a string.
    Read(String),
    /// Mapped, checked to be UTF-8 once.
    Mapped(memmap2::Mmap),
}

impl std::ops::Deref for Text {
    type Target = str;
    fn deref(&self) -> &str {
        match self {
            Text::Read(s) => s,
            // SAFETY: checked to be UTF-8 when mapped ([`read_text`]), and the mapping is read-only.
            Text::Mapped(m) => unsafe { std::str::from_utf8_unchecked(m) },
        }
    }
}

/// The text of a scene file. Bytes that are not UTF-8 are an error at the line and column where they start;
/// `what` names the file's kind in the error when it cannot be read at all. Regular files of at least
/// [`MAP_BYTES`] are mapped (and their pages faulted in by one call) instead of read; like any mapped input,
/// such a file must not be truncated by another process while it is being parsed. Where mapping fails the
/// file is read.
pub(crate) fn read_text(path: &Path, what: &str) -> Result<Text, SceneError> {
    let cannot = |e: std::io::Error| SceneError::whole_file(path, format!("cannot read {what}: {e}"));
    let file = std::fs::File::open(path).map_err(cannot)?;
    let large = file.metadata().is_ok_and(|m| m.is_file() && m.len() >= MAP_BYTES);
    // SAFETY: a read-only private mapping of a regular file; see the documentation above on truncation.
    let mapped =
        large.then(|| unsafe { memmap2::MmapOptions::new().populate().map(&file) }).and_then(Result::ok);
    match mapped {
        Some(map) => match is_utf8(&map) {
            true => Ok(Text::Mapped(map)),
            false => Err(not_utf8(path, &map, std::str::from_utf8(&map).expect_err("not UTF-8"))),
        },
        None => {
            let mut bytes = Vec::new();
            std::io::Read::read_to_end(&mut &file, &mut bytes).map_err(cannot)?;
            text(path, bytes).map(Text::Read)
        }
    }
}

/// Files from this size up are read in parallel pieces ([`read_bytes`]).
const PARALLEL_READ_BYTES: u64 = 1 << 22;

/// Bytes a thread of [`read_bytes`] reads at a time.
const READ_PIECE_BYTES: usize = 1 << 21;

/// A file's bytes, as `std::fs::read` gives them. A regular file of [`PARALLEL_READ_BYTES`] or more is read
/// in pieces at their offsets by the current rayon pool's threads into zeroed memory, so that the new pages'
/// faults and the copies from the page cache are shared out instead of paid on one thread; what the file
/// grew by meanwhile is read after, and a file that shrank meanwhile is read again whole.
pub(crate) fn read_bytes(path: &Path) -> std::io::Result<Vec<u8>> {
    let file = std::fs::File::open(path)?;
    let len = file.metadata().ok().filter(|m| m.is_file()).map_or(0, |m| m.len());
    #[cfg(unix)]
    if len >= PARALLEL_READ_BYTES {
        use rayon::prelude::*;
        use std::io::{Read, Seek, SeekFrom};
        use std::os::unix::fs::FileExt;
        let mut bytes = vec![0u8; usize::try_from(len).map_err(std::io::Error::other)?];
        let read = bytes
            .par_chunks_mut(READ_PIECE_BYTES)
            .enumerate()
            .try_for_each(|(k, piece)| file.read_exact_at(piece, (k * READ_PIECE_BYTES) as u64));
        match read {
            Ok(()) => {
                (&file).seek(SeekFrom::Start(len))?;
                (&file).read_to_end(&mut bytes)?;
                return Ok(bytes);
            }
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return std::fs::read(path),
            Err(e) => return Err(e),
        }
    }
    let mut bytes = Vec::with_capacity(usize::try_from(len).unwrap_or(0));
    std::io::Read::read_to_end(&mut &file, &mut bytes)?;
    Ok(bytes)
}

/// Whether `bytes` are UTF-8, checked in pieces on the current rayon pool. A piece ends just before an
/// ASCII byte, which is never inside a character, so the pieces are UTF-8 exactly when the whole is.
fn is_utf8(bytes: &[u8]) -> bool {
    use rayon::prelude::*;
    let ascii = |from: usize| bytes[from..].iter().position(u8::is_ascii).map(|i| from + i);
    let cuts = super::pieces::cuts(bytes, 1 << 20, ascii);
    cuts.par_windows(2).all(|w| std::str::from_utf8(&bytes[w[0]..w[1]]).is_ok())
}

/// Texts in memory from this size up are checked in parallel pieces ([`text`]).
const PARALLEL_CHECK_BYTES: usize = 1 << 20;

/// `bytes` as text, or an error at the line and column where bytes that are not UTF-8 start. A text of
/// [`PARALLEL_CHECK_BYTES`] or more is checked in parallel pieces ([`is_utf8`]), not on one thread.
pub(crate) fn text(path: &Path, bytes: Vec<u8>) -> Result<String, SceneError> {
    if bytes.len() < PARALLEL_CHECK_BYTES || !is_utf8(&bytes) {
        return String::from_utf8(bytes).map_err(|e| not_utf8(path, e.as_bytes(), e.utf8_error()));
    }
    // SAFETY: `is_utf8` found every piece, and so the whole, to be UTF-8.
    Ok(unsafe { String::from_utf8_unchecked(bytes) })
}

/// The error for `bytes` that are UTF-8 only up to where `e` says.
fn not_utf8(path: &Path, bytes: &[u8], e: std::str::Utf8Error) -> SceneError {
    let valid = e.valid_up_to();
    let before = std::str::from_utf8(&bytes[..valid]).expect("valid up to there");
    SceneError::at_offset(path, before, valid, "not UTF-8 text: invalid byte sequence")
}

/// 1-based line and column (in characters) of byte `offset` in `source`.
fn line_column(source: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(source.len());
    let before = &source[..source.floor_char_boundary(offset)];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if self.line > 0 {
            write!(f, ":{}", self.line)?;
            if self.column > 0 {
                write!(f, ":{}", self.column)?;
            }
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for SceneError {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_utf8_is_an_error_at_its_line_and_column() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.nff");
        std::fs::write(&path, b"v\nfrom 0 0 \xE2\x82\n").unwrap();
        let e = read_text(&path, "scene").unwrap_err();
        assert_eq!((e.line, e.column), (2, 10), "{e}");
        assert!(e.to_string().starts_with(&format!("{}:2:10: not UTF-8", path.display())), "{e}");
    }

    /// Files read in parallel pieces (sizes around the piece and the threshold, a last piece of one byte)
    /// give `std::fs::read`'s bytes, as do small files and a file that is not regular.
    #[test]
    fn files_read_in_pieces_are_their_bytes() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.xyz");
        let (piece, from) = (READ_PIECE_BYTES, PARALLEL_READ_BYTES as usize);
        for len in [0, 10, from - 1, from, from + 1, 3 * piece, 3 * piece + 1] {
            let bytes: Vec<u8> = (0..len).map(|i| (i * 7 + i / 4093) as u8).collect();
            std::fs::write(&path, &bytes).unwrap();
            assert!(read_bytes(&path).unwrap() == bytes, "{len} bytes");
        }
        assert_eq!(read_bytes(Path::new("/dev/null")).unwrap(), b"");
        assert!(read_bytes(&dir.path().join("missing")).is_err());
    }

    /// A file large enough to be mapped reads as the same text, and bad bytes in it give the same error as
    /// in a file that is read.
    #[test]
    fn large_files_are_mapped_with_the_same_text_and_errors() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("big.nff");
        let line = "s 1 2 3 0.5\n";
        let body = line.repeat(MAP_BYTES as usize / line.len() + 1);
        std::fs::write(&path, &body).unwrap();
        let text = read_text(&path, "scene").unwrap();
        assert!(matches!(text, Text::Mapped(_)), "a {} byte file was not mapped", body.len());
        assert!(*text == *body);
        let mut bad = body.clone().into_bytes();
        let at = bad.len() - 3;
        bad[at] = 0xE2;
        std::fs::write(&path, &bad).unwrap();
        let e = read_text(&path, "scene").unwrap_err();
        let lines = body.matches('\n').count();
        assert_eq!((e.line, e.column), (lines, line.len() - 2), "{e}");
    }

    /// Pieces end before ASCII bytes: characters straddling a megabyte boundary, long runs without ASCII and
    /// bad bytes at, before or after a boundary give the whole text's answer.
    #[test]
    fn utf8_in_pieces_agrees_with_the_whole() {
        const MB: usize = 1 << 20;
        let base = vec![b'a'; 3 * MB + 5];
        let euro = "€".as_bytes();
        let mut cases: Vec<Vec<u8>> = vec![Vec::new(), base.clone()];
        for at in [MB - 2, MB - 1, MB, MB + 1, 2 * MB - 1] {
            let mut ok = base.clone();
            ok[at..at + 3].copy_from_slice(euro);
            cases.push(ok.clone());
            for (cut, byte) in [(1, b'a'), (2, b'a'), (0, 0x82), (1, 0xFF)] {
                let mut bad = ok.clone();
                bad[at + cut] = byte;
                cases.push(bad);
            }
        }
        // Two megabytes of three-byte characters: one piece longer than the rest, then a truncated one.
        let wide: Vec<u8> = euro.iter().copied().cycle().take(3 * (2 * MB / 3)).chain(*b"tail").collect();
        cases.push(wide.clone());
        cases.push(wide[..wide.len() - 5].to_vec());
        for (i, bytes) in cases.iter().enumerate() {
            assert_eq!(is_utf8(bytes), std::str::from_utf8(bytes).is_ok(), "case {i}");
        }
        assert!(cases.iter().filter(|b| !is_utf8(b)).count() >= 20, "the bad cases are bad");
        // Bytes in memory (a particle file, read or decompressed) give the same text or error as one check.
        let path = Path::new("t.xyz");
        for bytes in cases {
            let one =
                String::from_utf8(bytes.clone()).map_err(|e| not_utf8(path, e.as_bytes(), e.utf8_error()));
            assert_eq!(text(path, bytes), one);
        }
    }

    #[test]
    fn line_and_column_are_one_based() {
        let src = "ab\ncd\n\nxyz";
        assert_eq!(line_column(src, 0), (1, 1));
        assert_eq!(line_column(src, 4), (2, 2));
        assert_eq!(line_column(src, 7), (4, 1));
        assert_eq!(line_column(src, 99), (4, 4));
    }
}
