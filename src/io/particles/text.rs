//! Lines with their numbers, and the number and count parsing the particle readers share.

use std::path::Path;

use crate::io::SceneError;

/// The lines of a text, numbered from 1 as they are taken. Lines end at `\n` or `\r\n`, the last one
/// with or without it, as [`str::lines`] cuts them.
pub(crate) struct Lines<'a> {
    path: &'a Path,
    /// The text not yet taken.
    rest: &'a str,
    /// The number of the last line taken (0 before the first).
    pub(crate) number: usize,
}

impl<'a> Lines<'a> {
    /// The lines of `text`, which errors call `path`.
    pub(crate) fn new(path: &'a Path, text: &'a str) -> Self {
        Self { path, rest: text, number: 0 }
    }

    /// The next line and the text after it, if any.
    fn cut(&self) -> Option<(&'a str, &'a str)> {
        if self.rest.is_empty() {
            return None;
        }
        Some(match self.rest.find('\n') {
            Some(i) => {
                let line = &self.rest[..i];
                (line.strip_suffix('\r').unwrap_or(line), &self.rest[i + 1..])
            }
            None => (self.rest, ""),
        })
    }

    /// The next line, if any.
    #[allow(clippy::should_implement_trait)]
    pub(crate) fn next(&mut self) -> Option<&'a str> {
        let (line, rest) = self.cut()?;
        (self.rest, self.number) = (rest, self.number + 1);
        Some(line)
    }

    /// The text not yet taken.
    pub(crate) fn rest(&self) -> &'a str {
        self.rest
    }

    /// Takes the first `bytes` bytes of [`Lines::rest`], which hold `count` whole lines.
    pub(crate) fn skip(&mut self, bytes: usize, count: usize) {
        (self.rest, self.number) = (&self.rest[bytes..], self.number + count);
    }

    /// The next line, or an error saying the file ends where `what` was expected.
    pub(crate) fn expect(&mut self, what: &str) -> Result<&'a str, SceneError> {
        self.expect_with(|| what.to_owned())
    }

    /// [`Lines::expect`] with the expected thing's name made only for an error, not for every line taken.
    pub(crate) fn expect_with(&mut self, what: impl FnOnce() -> String) -> Result<&'a str, SceneError> {
        self.next().ok_or_else(|| {
            let what = what();
            SceneError::at_line(self.path, self.number.max(1), format!("the file ends here; expected {what}"))
        })
    }

    /// The next line without taking it.
    pub(crate) fn peek(&mut self) -> Option<&'a str> {
        self.cut().map(|(line, _)| line)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Lines cut as `str::lines` cuts them, numbered, with what is left after skipping.
    #[test]
    fn lines_are_those_of_str_lines() {
        let path = Path::new("t");
        for text in ["", "a", "a\n", "a\r\nb", "a\n\nb\r", "\r\n\r\n", "x\ry\n z \r\n\n"] {
            let mut lines = Lines::new(path, text);
            let mut taken = Vec::new();
            while let Some(peeked) = lines.peek() {
                assert_eq!(lines.next(), Some(peeked));
                taken.push(peeked);
            }
            assert_eq!(taken, text.lines().collect::<Vec<_>>(), "{text:?}");
            assert_eq!((lines.number, lines.next(), lines.rest()), (taken.len(), None, ""));
        }
        let mut lines = Lines::new(path, "a\nb\nc\n");
        lines.skip(4, 2);
        assert_eq!((lines.rest(), lines.number, lines.next(), lines.number), ("c\n", 2, Some("c"), 3));
    }
}
