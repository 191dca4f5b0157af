//! TIFF and JPEG, through the `image` crate's encoders, which take the whole image: the rows are gathered
//! as they arrive (the image's stored bytes: 3 per pixel, 6 for 16-bit TIFF) and encoded at the end.
//! JPEG is baseline 8-bit at quality 92 (no progressive passes, 4:2:0 chroma subsampling as the encoder
//! chooses); TIFF is uncompressed 8- or 16-bit RGB. Neither records the transfer or text; both take the
//! sRGB or linear values as PNG does.

use std::io::{Seek, Write};

use image::{ExtendedColorType, ImageEncoder};

use super::{BitDepth, BoxError, Format, Frame, Rows};

/// JPEG's quality (1–100).
pub(crate) const JPEG_QUALITY: u8 = 92;

/// JPEG's largest side (its header stores 16-bit sizes).
pub(crate) const JPEG_MAX_SIDE: u32 = 65_535;

/// Classic TIFF's largest file: 32-bit offsets.
pub(crate) const TIFF_MAX_BYTES: u64 = u32::MAX as u64;

/// Writes a TIFF or JPEG of `frame` from `rows` (as [`super::pixel_bytes`] gives for the format and depth).
pub(super) fn write<W: Write + Seek>(
    out: &mut W,
    format: Format,
    depth: BitDepth,
    frame: Frame,
    mut rows: Rows,
) -> Result<(), BoxError> {
    let mut raw = Vec::new();
    for _ in 0..frame.height {
        raw.extend_from_slice(rows.next_row()?);
    }
    rows.finish()?;
    let (w, h) = (frame.width, frame.height);
    match (format, depth) {
        (Format::Jpeg, _) => image::codecs::jpeg::JpegEncoder::new_with_quality(out, JPEG_QUALITY).encode(
            &raw,
            w,
            h,
            ExtendedColorType::Rgb8,
        )?,
        (Format::Tiff, BitDepth::Eight) => {
            image::codecs::tiff::TiffEncoder::new(out).write_image(&raw, w, h, ExtendedColorType::Rgb8)?
        }
        (Format::Tiff, BitDepth::Sixteen) => {
            // The stored samples are big-endian (PNG's order); the encoder takes them in the machine's.
            for pair in raw.chunks_exact_mut(2) {
                let v = u16::from_be_bytes([pair[0], pair[1]]);
                pair.copy_from_slice(&v.to_ne_bytes());
            }
            image::codecs::tiff::TiffEncoder::new(out).write_image(&raw, w, h, ExtendedColorType::Rgb16)?
        }
        _ => unreachable!("only TIFF and JPEG are held whole"),
    }
    Ok(())
}
