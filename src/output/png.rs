//! PNG, written as a stream: the signature, `IHDR`, the `tEXt` chunks, then the rows, each Paeth-filtered
//! and fed to fdeflate's fast compressor, whose zlib stream goes out in `IDAT` chunks as it is made. A
//! chunk's length comes before its data, so each `IDAT` is started with a placeholder and its length is
//! written in once the chunk is full (2^31 − 1 bytes, PNG's limit) or the stream ends: memory stays at two
//! rows and the compressor's window whatever the image's size. The chunks, filter and compressor are the
//! `png` crate's choices at `Compression::Fast` and `Filter::Paeth`, so the bytes are that crate's, except
//! where its whole-image encoder would fall back to stored blocks for incompressible data.

use std::io::{Seek, SeekFrom, Write};

use super::{BitDepth, BoxError, Frame, Rows, WriteOptions};
use crate::math::Rgb;
use crate::scene::desc::Transfer;

/// The most data one PNG chunk may hold.
const MAX_CHUNK: u32 = u32::MAX >> 1;

/// Writes a PNG of `frame` from `rows` (3 or 6 bytes per pixel, by `options.bit_depth`): `Transfer`, then
/// the options' text chunks, then `Region` when the frame is one ([`Frame::region_text`]).
pub(super) fn write<W: Write + Seek>(
    out: &mut W,
    frame: Frame,
    options: &WriteOptions,
    mut rows: Rows,
) -> Result<(), BoxError> {
    let depth = match options.bit_depth {
        BitDepth::Eight => 8u8,
        BitDepth::Sixteen => 16,
    };
    out.write_all(b"\x89PNG\r\n\x1a\n")?;
    let mut header = Vec::with_capacity(13);
    header.extend_from_slice(&frame.width.to_be_bytes());
    header.extend_from_slice(&frame.height.to_be_bytes());
    // Bit depth, colour type 2 (RGB), deflate, adaptive filtering, no interlace.
    header.extend_from_slice(&[depth, 2, 0, 0, 0]);
    write_chunk(out, b"IHDR", &header)?;
    let mut text = vec![("Transfer".to_owned(), options.transfer.name().to_owned())];
    text.extend(options.text.iter().cloned());
    if frame.is_region() {
        text.push(("Region".to_owned(), frame.region_text()));
    }
    for (keyword, value) in &text {
        write_chunk(out, b"tEXt", &latin1_text(keyword, value)?)?;
    }
    let bpp = 3 * usize::from(depth / 8);
    let row_bytes = frame.width as usize * bpp;
    let mut compressor = fdeflate::Compressor::new(Idat::new(out))?;
    let (mut previous, mut filtered) = (vec![0u8; row_bytes], vec![0u8; row_bytes + 1]);
    for _ in 0..frame.height {
        let row = rows.next_row()?;
        filtered[0] = 4; // Paeth
        paeth(bpp, &previous, row, &mut filtered[1..]);
        compressor.write_data(&filtered)?;
        previous.copy_from_slice(row);
    }
    rows.finish()?;
    compressor.finish()?.close()?;
    write_chunk(out, b"IEND", &[])?;
    Ok(())
}

/// A `tEXt` chunk's data: the keyword (1–79 Latin-1 characters), a zero byte, the text in Latin-1
/// (characters beyond it become `?`).
fn latin1_text(keyword: &str, text: &str) -> Result<Vec<u8>, BoxError> {
    let latin1 = |s: &str| s.chars().map(|c| u8::try_from(u32::from(c)).unwrap_or(b'?')).collect::<Vec<u8>>();
    let key = latin1(keyword);
    if key.is_empty() || key.len() > 79 || key.contains(&0) {
        return Err(format!("PNG text keyword `{keyword}` must be 1 to 79 Latin-1 characters").into());
    }
    let mut data = key;
    data.push(0);
    data.extend(latin1(text).into_iter().map(|b| if b == 0 { b'?' } else { b }));
    Ok(data)
}

/// One whole chunk: length, type, data, CRC of type and data.
fn write_chunk(out: &mut impl Write, kind: &[u8; 4], data: &[u8]) -> std::io::Result<()> {
    out.write_all(&(data.len() as u32).to_be_bytes())?;
    out.write_all(kind)?;
    out.write_all(data)?;
    let mut crc = crc32fast::Hasher::new();
    crc.update(kind);
    crc.update(data);
    out.write_all(&crc.finalize().to_be_bytes())
}

/// PNG's Paeth filter of `row` against the row above (`previous`; zeros for the first row), `bpp` bytes
/// per pixel: each byte minus the neighbour (left, above or upper left) nearest to left + above − upper left,
/// ties to left, then above. In the first pixel left and upper left are zero, so the predictor is the byte
/// above; past it the loop has no branches on the index and the compiler turns it into vector code (the
/// filter is otherwise the costliest part of a PNG write).
fn paeth(bpp: usize, previous: &[u8], row: &[u8], out: &mut [u8]) {
    let n = row.len();
    let head = bpp.min(n);
    for ((o, &x), &b) in out[..head].iter_mut().zip(&row[..head]).zip(&previous[..head]) {
        *o = x.wrapping_sub(b);
    }
    if n <= bpp {
        return;
    }
    let (left, upper_left) = (&row[..n - bpp], &previous[..n - bpp]);
    let (this, above) = (&row[bpp..], &previous[bpp..n]);
    let neighbours = left.iter().zip(above).zip(upper_left);
    for ((o, &x), ((&a, &b), &c)) in out[bpp..n].iter_mut().zip(this).zip(neighbours) {
        let (ai, bi, ci) = (i16::from(a), i16::from(b), i16::from(c));
        // With p = a + b − c: |p − a| = |b − c|, |p − b| = |a − c|, |p − c| = |a + b − 2c|.
        let (pa, pb, pc) = ((bi - ci).abs(), (ai - ci).abs(), (ai + bi - 2 * ci).abs());
        let predictor = if pa <= pb && pa <= pc {
            a
        } else if pb <= pc {
            b
        } else {
            c
        };
        *o = x.wrapping_sub(predictor);
    }
}

/// The zlib stream into `IDAT` chunks: a chunk is opened with a placeholder length on the first byte it
/// gets, and closed (length written in place, CRC appended) when full or at the end.
struct Idat<'a, W: Write + Seek> {
    out: &'a mut W,
    open: Option<(u64, u32, crc32fast::Hasher)>,
}

impl<'a, W: Write + Seek> Idat<'a, W> {
    fn new(out: &'a mut W) -> Self {
        Self { out, open: None }
    }

    fn close(&mut self) -> std::io::Result<()> {
        if let Some((start, len, crc)) = self.open.take() {
            let end = self.out.stream_position()?;
            self.out.seek(SeekFrom::Start(start))?;
            self.out.write_all(&len.to_be_bytes())?;
            self.out.seek(SeekFrom::Start(end))?;
            self.out.write_all(&crc.finalize().to_be_bytes())?;
        }
        Ok(())
    }
}

impl<W: Write + Seek> Write for Idat<'_, W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if buf.is_empty() {
            return Ok(0);
        }
        if self.open.is_none() {
            let start = self.out.stream_position()?;
            self.out.write_all(&[0; 4])?;
            self.out.write_all(b"IDAT")?;
            let mut crc = crc32fast::Hasher::new();
            crc.update(b"IDAT");
            self.open = Some((start, 0, crc));
        }
        let (_, len, crc) = self.open.as_mut().expect("a chunk is open");
        let take = buf.len().min((MAX_CHUNK - *len) as usize);
        self.out.write_all(&buf[..take])?;
        crc.update(&buf[..take]);
        *len += take as u32;
        if *len == MAX_CHUNK {
            self.close()?;
        }
        Ok(take)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.out.flush()
    }
}

/// One row as 16-bit R, G, B, big-endian (6 bytes per pixel in `out`): each value under the transfer at 16
/// bits (the sRGB curve in f64, or the value clamped), ×65535, rounded.
pub(super) fn encode16_row(row: &[Rgb], transfer: Transfer, out: &mut [u8]) {
    let encode = |v: f32| -> u16 {
        let c = if v.is_nan() { 0.0 } else { f64::from(v).clamp(0.0, 1.0) };
        let s = match transfer {
            Transfer::Linear => c,
            Transfer::Srgb if c <= 0.003_130_8 => 12.92 * c,
            Transfer::Srgb => 1.055 * c.powf(1.0 / 2.4) - 0.055,
        };
        (s * 65535.0 + 0.5) as u16
    };
    for (o, v) in out.chunks_exact_mut(2).zip(row.iter().flat_map(|p| [p.x, p.y, p.z])) {
        o.copy_from_slice(&encode(v).to_be_bytes());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::{to_samples, Format};

    fn encode(frame: Frame, options: &WriteOptions, samples: Vec<u8>) -> Vec<u8> {
        let mut out = std::io::Cursor::new(Vec::new());
        let size = crate::output::pixel_bytes(Format::Png, options.bit_depth);
        let mut source = samples
            .chunks(3 * frame.width as usize * size)
            .map(<[u8]>::to_vec)
            .collect::<Vec<_>>()
            .into_iter();
        write(&mut out, frame, options, Rows::new(&mut source, frame, size)).unwrap();
        out.into_inner()
    }

    /// The filter gives, byte for byte, the Paeth predictor as the PNG specification writes it, on rows of
    /// every length from 0 to 40 at 3 and 6 bytes per pixel, random bytes and the extremes.
    #[test]
    fn paeth_is_the_specifications_predictor() {
        fn reference(bpp: usize, previous: &[u8], row: &[u8]) -> Vec<u8> {
            (0..row.len())
                .map(|i| {
                    let a = if i >= bpp { i16::from(row[i - bpp]) } else { 0 };
                    let c = if i >= bpp { i16::from(previous[i - bpp]) } else { 0 };
                    let b = i16::from(previous[i]);
                    let p = a + b - c;
                    let (pa, pb, pc) = ((p - a).abs(), (p - b).abs(), (p - c).abs());
                    let predictor = if pa <= pb && pa <= pc {
                        a
                    } else if pb <= pc {
                        b
                    } else {
                        c
                    };
                    row[i].wrapping_sub(predictor as u8)
                })
                .collect()
        }
        let mut state = 7u64;
        let mut byte = move || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            match state >> 61 {
                0 => 0,
                1 => 255,
                _ => (state >> 33) as u8,
            }
        };
        for bpp in [3, 6] {
            for n in 0..=40 {
                for _ in 0..50 {
                    let previous: Vec<u8> = (0..n).map(|_| byte()).collect();
                    let row: Vec<u8> = (0..n).map(|_| byte()).collect();
                    let mut out = vec![0; n];
                    paeth(bpp, &previous, &row, &mut out);
                    assert_eq!(out, reference(bpp, &previous, &row), "bpp {bpp}, {n} bytes");
                }
            }
        }
    }

    /// The stream is what the `png` crate's whole-image encoder writes with the same settings, byte for
    /// byte, at both depths, and decodes to the rows given.
    #[test]
    fn matches_the_png_crate_and_decodes_to_the_rows() {
        let mut state = 3u32;
        let mut next = move || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 9) as f32 / (1u32 << 23) as f32
        };
        // Smooth gradients with noise: filters and matches both matter.
        let (w, h) = (37u32, 23u32);
        let pixels: Vec<Rgb> = (0..w * h)
            .map(|i| Rgb::new((i % w) as f32 / w as f32, (i / w) as f32 / h as f32, 0.1 * next()))
            .collect();
        for depth in [BitDepth::Eight, BitDepth::Sixteen] {
            let options = WriteOptions {
                transfer: Transfer::Srgb,
                bit_depth: depth,
                text: vec![("Software".into(), "bareray test ×".into())],
            };
            let samples = to_samples(&pixels, w, Format::Png, &options);
            let ours = encode(Frame::whole(w, h), &options, samples.clone());

            let mut theirs = Vec::new();
            let mut encoder = ::png::Encoder::new(&mut theirs, w, h);
            encoder.set_color(::png::ColorType::Rgb);
            encoder.set_depth(if depth == BitDepth::Eight {
                ::png::BitDepth::Eight
            } else {
                ::png::BitDepth::Sixteen
            });
            encoder.set_compression(::png::Compression::Fast);
            encoder.set_filter(::png::Filter::Paeth);
            encoder.add_text_chunk("Transfer".into(), "srgb".into()).unwrap();
            encoder.add_text_chunk("Software".into(), "bareray test ×".into()).unwrap();
            let mut writer = encoder.write_header().unwrap();
            writer.write_image_data(&samples).unwrap();
            writer.finish().unwrap();
            assert_eq!(ours, theirs, "{depth:?}");

            let mut reader = ::png::Decoder::new(std::io::Cursor::new(&ours)).read_info().unwrap();
            let mut decoded = vec![0; reader.output_buffer_size().unwrap()];
            reader.next_frame(&mut decoded).unwrap();
            assert_eq!(decoded, samples);
        }
    }

    #[test]
    fn a_region_is_recorded_and_a_short_source_fails() {
        let frame = Frame { width: 2, height: 1, x0: 3, y0: 4, full_width: 8, full_height: 6 };
        let png = encode(frame, &WriteOptions::default(), vec![7; 6]);
        let reader = ::png::Decoder::new(std::io::Cursor::new(&png)).read_info().unwrap();
        let text = &reader.info().uncompressed_latin1_text;
        let region = text.iter().find(|t| t.keyword == "Region").expect("a Region chunk");
        assert_eq!(Frame::parse_region_text(&region.text), Some(frame));

        let mut out = std::io::Cursor::new(Vec::new());
        let mut source = vec![vec![0u8; 6]].into_iter();
        let tall = Frame { height: 2, ..Frame::whole(2, 2) };
        let err =
            write(&mut out, tall, &WriteOptions::default(), Rows::new(&mut source, tall, 3)).unwrap_err();
        assert!(err.to_string().contains("ended after 1 of 2 rows"), "{err}");
    }
}
