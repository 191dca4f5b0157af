//! Lines with their numbers, and the number and count parsing the particle readers share.

use std::iter::Peekable;
use std::path::Path;
use std::str::Lines as StrLines;

use crate::io::SceneError;

/// The lines of a text, numbered from 1 as they are taken.
pub(crate) struct Lines<'a> {
    path: &'a Path,
    lines: Peekable<StrLines<'a>>,
    /// The number of the last line taken (0 before the first).
    pub(crate) number: usize,
}

impl<'a> Lines<'a> {
    /// The lines of `text`, which errors call `path`.
    pub(crate) fn new(path: &'a Path, text: &'a str) -> Self {
        Self { path, lines: text.lines().peekable(), number: 0 }
    }

    /// The next line, if any.
    #[allow(clippy::should_implement_trait)]
    pub(crate) fn next(&mut self) -> Option<&'a str> {
        let line = self.lines.next()?;
        self.number += 1;
        Some(line)
    }

    /// The next line, or an error saying the file ends where `what` was expected.
    pub(crate) fn expect(&mut self, what: &str) -> Result<&'a str, SceneError> {
        self.next().ok_or_else(|| {
            SceneError::at_line(self.path, self.number.max(1), format!("the file ends here; expected {what}"))
        })
    }

    /// The next line without taking it.
    pub(crate) fn peek(&mut self) -> Option<&'a str> {
        self.lines.peek().copied()
    }

    /// Skips blank lines; whether any line is left.
    pub(crate) fn more(&mut self) -> bool {
        while self.peek().is_some_and(|l| l.trim().is_empty()) {
            self.next();
        }
        self.peek().is_some()
    }

    /// An error at the last line taken.
    pub(crate) fn error(&self, message: impl Into<String>) -> SceneError {
        SceneError::at_line(self.path, self.number.max(1), message)
    }
}

/// `word` as a finite number within f32 range; `what` names it in the error.
pub(crate) fn number(word: &str, what: &str) -> Result<f64, String> {
    match word.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && (x as f32).is_finite() => Ok(x),
        _ => Err(format!("expected {what} (a finite number), got `{}`", word.trim())),
    }
}

/// `word` as a positive radius.
pub(crate) fn radius(word: &str, what: &str) -> Result<f64, String> {
    let r = number(word, what)?;
    if r > 0.0 {
        Ok(r)
    } else {
        Err(format!("{what} must be positive, got {r}"))
    }
}

/// `word` as a count of particles.
pub(crate) fn count(word: &str, what: &str) -> Result<usize, String> {
    word.trim()
        .parse::<usize>()
        .map_err(|_| format!("expected {what} (a whole number), got `{}`", word.trim()))
}

/// Room to reserve for `count` particles in a text of `bytes` bytes: a count that lies reserves no more
/// than the text could hold.
pub(crate) fn capacity(count: usize, bytes: usize) -> usize {
    count.min(bytes / 8 + 1)
}

/// The characters `from..to` of a fixed-column line (columns from 0, clipped to the line; empty where the
/// line is shorter or the cut falls inside a character).
pub(crate) fn columns(line: &str, from: usize, to: usize) -> &str {
    let to = to.min(line.len());
    line.get(from.min(to)..to).unwrap_or("")
}
