//! Errors of scene readers: every one names the file, and the line and column where the reader could tell.

use std::fmt;
use std::path::{Path, PathBuf};

/// A scene that could not be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SceneError {
    /// The file (or a name such as `<built-in demo>`).
    pub path: PathBuf,
    /// 1-based line, 0 when the error is about the whole file.
    pub line: usize,
    /// 1-based column, 0 when unknown.
    pub column: usize,
    /// What was wrong and what was expected.
    pub message: String,
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

/// The text of a scene file. Bytes that are not UTF-8 are an error at the line and column where they start;
/// `what` names the file's kind in the error when it cannot be read at all.
pub(crate) fn read_text(path: &Path, what: &str) -> Result<String, SceneError> {
    let bytes =
        std::fs::read(path).map_err(|e| SceneError::whole_file(path, format!("cannot read {what}: {e}")))?;
    text(path, bytes)
}

/// `bytes` as text, or an error at the line and column where bytes that are not UTF-8 start.
pub fn text(path: &Path, bytes: Vec<u8>) -> Result<String, SceneError> {
    String::from_utf8(bytes).map_err(|e| {
        let valid = e.utf8_error().valid_up_to();
        let before = std::str::from_utf8(&e.as_bytes()[..valid]).expect("valid up to there");
        SceneError::at_offset(path, before, valid, "not UTF-8 text: invalid byte sequence")
    })
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

    #[test]
    fn line_and_column_are_one_based() {
        let src = "ab\ncd\n\nxyz";
        assert_eq!(line_column(src, 0), (1, 1));
        assert_eq!(line_column(src, 4), (2, 2));
        assert_eq!(line_column(src, 7), (4, 1));
        assert_eq!(line_column(src, 99), (4, 4));
    }
}
