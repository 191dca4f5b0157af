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
    pub fn at_offset(path: &Path, source: &str, offset: usize, message: impl Into<String>) -> Self {
        let (line, column) = line_column(source, offset);
        Self { path: path.to_owned(), line, column, message: message.into() }
    }
    /// An error at a 1-based line (column unknown).
    pub fn at_line(path: &Path, line: usize, message: impl Into<String>) -> Self {
        Self { path: path.to_owned(), line, column: 0, message: message.into() }
    }
    /// An error about the whole file.
    pub fn whole_file(path: &Path, message: impl Into<String>) -> Self {
        Self { path: path.to_owned(), line: 0, column: 0, message: message.into() }
    }
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
    fn line_and_column_are_one_based() {
        let src = "ab\ncd\n\nxyz";
        assert_eq!(line_column(src, 0), (1, 1));
        assert_eq!(line_column(src, 4), (2, 2));
        assert_eq!(line_column(src, 7), (4, 1));
        assert_eq!(line_column(src, 99), (4, 4));
    }
}
