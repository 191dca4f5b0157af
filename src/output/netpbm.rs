//! Binary 8-bit PPM (netpbm's `P6`, which every PPM reader takes): the header `P6\n<width> <height>\n255\n`,
//! then the RGB bytes row by row, top row first. A region adds one comment line after `P6`,
//! `# bareray region <Frame::region_text>`, which netpbm readers skip.

use std::io::Write;

use super::{BoxError, Frame, Rows};

/// The comment that places a PPM region in its full image.
pub(crate) const REGION_COMMENT: &str = "# bareray region ";

/// Writes a PPM of `frame` from `rows` (3 bytes per pixel).
pub(super) fn write_ppm(out: &mut impl Write, frame: Frame, mut rows: Rows) -> Result<(), BoxError> {
    out.write_all(b"P6\n")?;
    if frame.is_region() {
        writeln!(out, "{REGION_COMMENT}{}", frame.region_text())?;
    }
    write!(out, "{} {}\n255\n", frame.width, frame.height)?;
    for _ in 0..frame.height {
        out.write_all(rows.next_row()?)?;
    }
    rows.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ppm_is_p6_with_a_minimal_header() {
        let mut out = Vec::new();
        let mut source = vec![vec![1, 2, 3, 4, 5, 6]].into_iter();
        let frame = Frame::whole(2, 1);
        write_ppm(&mut out, frame, Rows::new(&mut source, frame, 3)).unwrap();
        assert_eq!(out, b"P6\n2 1\n255\n\x01\x02\x03\x04\x05\x06");
    }
}
