//! NFF's tokens: words separated by ASCII whitespace, each with its line, `#` comments removed.

/// A token and its 1-based line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Tok<'a> {
    pub(super) text: &'a str,
    pub(super) line: usize,
}

/// The tokens of a text, one of look-ahead. One pass over the bytes: a word is a run of bytes that are not
/// ASCII whitespace (`u8::is_ascii_whitespace`: space, tab, line feed, form feed, carriage return); a word
/// that starts with `#` drops the rest of its line. Lines are numbered as `str::lines` counts them (a final
/// line feed ends the last line rather than starting another), so [`Tokens::line`] at the end of the text is
/// the last line's number, which end-of-file errors name. One pass, where splitting the text into lines and
/// then words would read every byte twice.
pub(super) struct Tokens<'a> {
    source: &'a str,
    /// The next byte to read.
    at: usize,
    /// The line of the last token read, or of the last line reached.
    line: usize,
    peeked: Option<Tok<'a>>,
}

impl<'a> Tokens<'a> {
    pub(super) fn new(source: &'a str) -> Self {
        Self { source, at: 0, line: usize::from(!source.is_empty()), peeked: None }
    }

    /// The line of the last token read (or peeked), or at the end of the text its last line.
    pub(super) fn line(&self) -> usize {
        self.line
    }

    pub(super) fn next(&mut self) -> Option<Tok<'a>> {
        if let Some(t) = self.peeked.take() {
            return Some(t);
        }
        let bytes = self.source.as_bytes();
        let mut i = self.at;
        loop {
            match bytes.get(i) {
                None => {
                    self.at = i;
                    return None;
                }
                Some(b'\n') => {
                    i += 1;
                    self.line += usize::from(i < bytes.len());
                }
                Some(b) if b.is_ascii_whitespace() => i += 1,
                // A comment runs to the end of its line; the line feed is read as above.
                Some(b'#') => i += bytes[i..].iter().position(|&b| b == b'\n').unwrap_or(bytes.len() - i),
                Some(_) => {
                    let start = i;
                    i = word_end(bytes, i);
                    self.at = i;
                    // Cut at ASCII bytes, so at character boundaries.
                    return Some(Tok { text: &self.source[start..i], line: self.line });
                }
            }
        }
    }

    pub(super) fn peek(&mut self) -> Option<Tok<'a>> {
        if self.peeked.is_none() {
            self.peeked = self.next();
        }
        self.peeked
    }
}

/// The first ASCII whitespace byte at or after `i`, or the text's end. Eight bytes at a time: one
/// subtraction flags every byte below 0x21 (and may flag bytes above the first flagged one, after its
/// borrow), and the flagged bytes are checked in order, since control bytes other than whitespace belong
/// to words. A loop of one byte per turn took twice the time in one build as in another, by where the
/// compiler placed it (docs/perf-log/2026-11-zen3.md, "balls6's load and build").
fn word_end(bytes: &[u8], mut i: usize) -> usize {
    const ONES: u64 = u64::from_ne_bytes([1; 8]);
    const HIGH: u64 = u64::from_ne_bytes([0x80; 8]);
    while let Some(chunk) = bytes.get(i..i + 8) {
        let x = u64::from_le_bytes(chunk.try_into().expect("eight bytes"));
        let mut flagged = x.wrapping_sub(ONES * 0x21) & !x & HIGH;
        while flagged != 0 {
            let at = i + flagged.trailing_zeros() as usize / 8;
            if bytes[at].is_ascii_whitespace() {
                return at;
            }
            flagged &= flagged - 1;
        }
        i += 8;
    }
    i + bytes[i..].iter().position(u8::is_ascii_whitespace).unwrap_or(bytes.len() - i)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::SplitMix64;

    /// The definition the tokens follow: `str::lines`, then each line's ASCII-whitespace words, a `#` word
    /// ending the line; the line after each token and, last, at the end.
    fn by_lines(source: &str) -> (Vec<Tok<'_>>, usize) {
        let (mut out, mut line) = (Vec::new(), 0);
        for (i, l) in source.lines().enumerate() {
            line = i + 1;
            for w in l.split_ascii_whitespace() {
                if w.starts_with('#') {
                    break;
                }
                out.push(Tok { text: w, line });
            }
        }
        (out, line)
    }

    /// Texts of words, numbers, comments, every ASCII whitespace byte, CRLF and lone CR, vertical tab (not
    /// whitespace), multi-byte characters, empty lines, with and without a final line feed.
    fn texts() -> Vec<String> {
        const PARTS: [&str; 16] = [
            "s", "1.5e-3", "#", "# c", "x#y", " ", "\t", "\n", "\r\n", "\r", "\x0c", "\x0b", "é", "\n\n",
            "pp", "  ",
        ];
        let mut rng = SplitMix64::new(7);
        let mut texts: Vec<String> =
            ["", "\n", "a", "a\n", "\na", "#", "# x\n", "\r\n", "a\r\n\r\n"].map(String::from).into();
        for _ in 0..3000 {
            let n = (rng.next_u64() % 24) as usize;
            texts.push((0..n).map(|_| PARTS[(rng.next_u64() % 16) as usize]).collect());
        }
        texts
    }

    #[test]
    fn tokens_and_lines_are_those_of_lines_then_words() {
        for text in texts() {
            let (expected, last_line) = by_lines(&text);
            let mut tokens = Tokens::new(&text);
            let mut got = Vec::new();
            while let Some(t) = tokens.next() {
                assert_eq!(tokens.line(), t.line, "{text:?}");
                got.push(t);
            }
            assert_eq!(got, expected, "{text:?}");
            assert_eq!(tokens.line(), last_line, "{text:?}: the line at the end");
        }
    }

    #[test]
    fn peeking_changes_nothing() {
        for text in texts() {
            let (expected, last_line) = by_lines(&text);
            let mut tokens = Tokens::new(&text);
            for want in &expected {
                assert_eq!(tokens.peek().as_ref(), Some(want), "{text:?}");
                assert_eq!(tokens.line(), want.line, "{text:?}");
                assert_eq!(tokens.next().as_ref(), Some(want), "{text:?}");
            }
            assert_eq!((tokens.peek(), tokens.next(), tokens.line()), (None, None, last_line), "{text:?}");
        }
    }

    #[test]
    fn word_end_finds_the_first_whitespace_byte() {
        // Every byte value, whitespace rare or common, from every start, against the plain definition.
        let mut rng = SplitMix64::new(3);
        for common in [false, true] {
            for _ in 0..2000 {
                let n = (rng.next_u64() % 40) as usize;
                let bytes: Vec<u8> = (0..n)
                    .map(|_| match (common, rng.next_u64() % 8) {
                        (true, 0) => b" \t\n\x0c\r"[(rng.next_u64() % 5) as usize],
                        _ => rng.next_u64() as u8,
                    })
                    .collect();
                for start in 0..=n {
                    let plain = (start..n).find(|&k| bytes[k].is_ascii_whitespace()).unwrap_or(n);
                    assert_eq!(word_end(&bytes, start), plain, "{bytes:?} from {start}");
                }
            }
        }
    }
}
