//! Texts cut into pieces of about a given size, each starting at a boundary the reader chooses (a line's
//! start, an ASCII byte, an entity's line), for the readers' parallel passes.

/// Offsets `0 = c₀ < c₁ < … < cₙ = bytes.len()` cutting `bytes` into pieces: each cut is
/// `boundary(from)`, `from` being `size` bytes past the previous cut (at most the end), or the end where
/// `boundary` gives `None`. `boundary(from)` must be at or after `from`; `size` is at least 1. An empty
/// text has no pieces (`[0]`).
pub(crate) fn cuts(bytes: &[u8], size: usize, boundary: impl Fn(usize) -> Option<usize>) -> Vec<usize> {
    assert!(size > 0, "pieces of 0 bytes");
    let end = bytes.len();
    let mut cuts = vec![0];
    while let Some(&at) = cuts.last().filter(|&&at| at < end) {
        let from = at.saturating_add(size).min(end);
        let cut = boundary(from).map_or(end, |cut| cut.min(end));
        debug_assert!(cut >= from, "a boundary before where it was asked from");
        cuts.push(cut);
    }
    cuts
}

/// The offset just after the first `\n` at or after `from`: a line's start, so a character boundary in
/// UTF-8 text. `None` when no `\n` follows.
pub(crate) fn after_newline(bytes: &[u8], from: usize) -> Option<usize> {
    bytes.get(from..)?.iter().position(|&b| b == b'\n').map(|i| from + i + 1)
}

/// `text` cut after a `\n` every `size` bytes or so (each piece whole lines).
pub(crate) fn line_pieces(text: &str, size: usize) -> Vec<&str> {
    let bytes = text.as_bytes();
    let cuts = cuts(bytes, size, |from| after_newline(bytes, from));
    // Every cut follows a '\n' or is the end, so it is a character boundary.
    cuts.windows(2).map(|w| &text[w[0]..w[1]]).collect()
}

/// `all` cut into consecutive slices of `counts[i]` items each, for the pieces to fill in parallel (the
/// counts sum to at most `all.len()`).
pub(crate) fn slices_of<'a, T>(mut all: &'a mut [T], counts: &[usize]) -> Vec<&'a mut [T]> {
    counts
        .iter()
        .map(|&n| {
            let (mine, rest) = std::mem::take(&mut all).split_at_mut(n);
            all = rest;
            mine
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pieces cover the text in order, each but the last longer than `size` bytes and ending at a boundary.
    #[test]
    fn cuts_fall_on_boundaries_and_cover_the_text() {
        for text in ["", "a", "a\n", "\n\n\n", "ab\ncd\r\nef", "∂x\né\n\n€€€\nlast"] {
            for size in [1, 2, 3, 5, 100] {
                let pieces = line_pieces(text, size);
                assert_eq!(pieces.concat(), text, "{text:?} in pieces of {size}");
                assert!(pieces.iter().all(|p| !p.is_empty()), "{text:?}: an empty piece");
                for p in &pieces[..pieces.len().saturating_sub(1)] {
                    // The first '\n' from `size` bytes in ends the piece.
                    let newlines = |b: &[u8]| b.iter().filter(|&&b| b == b'\n').count();
                    assert!(p.len() > size && p.ends_with('\n'), "{text:?}, {size}: piece {p:?}");
                    assert_eq!(newlines(p.as_bytes()), 1 + newlines(&p.as_bytes()[..size]), "{p:?}");
                }
            }
        }
        // Before ASCII bytes: no cut inside a character.
        let text = "é∂€x".repeat(50);
        let bytes = text.as_bytes();
        let ascii = cuts(bytes, 7, |from| bytes[from..].iter().position(u8::is_ascii).map(|i| from + i));
        assert!(ascii.len() > 5 && ascii.iter().all(|&c| text.is_char_boundary(c)));
        assert_eq!((ascii[0], *ascii.last().unwrap()), (0, text.len()));
        assert!(ascii.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(after_newline(b"ab\ncd", 3), None);
        assert_eq!(after_newline(b"ab\ncd", 9), None);
        assert_eq!(after_newline(b"ab\ncd", 0), Some(3));
        let mut all = [1, 2, 3, 4, 5, 6];
        let parts: Vec<Vec<i32>> = slices_of(&mut all, &[2, 0, 3]).into_iter().map(|s| s.to_vec()).collect();
        assert_eq!(parts, [vec![1, 2], vec![], vec![3, 4, 5]]);
    }
}
