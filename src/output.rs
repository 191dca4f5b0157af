//! Images out: the format follows the file extension (PNG 8- or 16-bit, PPM 8-bit, EXR linear float, Radiance
//! HDR linear RGBE). Integer values follow the scene's [`Transfer`]: the sRGB curve, or the values as they
//! are (clamped, scaled, rounded); EXR and HDR hold the values as they are, whatever the transfer. PNG records
//! the transfer in a `tEXt` chunk, keyword `Transfer`, text `srgb` or `linear`, and any further text the
//! caller gives ([`WriteOptions::text`]: the renderer, scene, size, sampling); PPM's header stays minimal.
//! The file is written under a temporary name in the same directory and renamed into place, so a failed
//! run never leaves half a file and never destroys an existing one.

use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use image::{ImageFormat, Rgb32FImage, RgbImage};
use thiserror::Error;

use crate::film::Image;
use crate::scene::desc::Transfer;

/// An image file format bareray writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// 8-bit PNG (sRGB or linear transfer, recorded in a `tEXt` chunk).
    Png,
    /// Linear 32-bit float OpenEXR.
    Exr,
    /// 8-bit binary PPM (`P6`; sRGB or linear transfer, not recorded); `.pnm` names it too.
    Ppm,
    /// Radiance HDR (`.hdr`): linear RGBE, 8-bit mantissas sharing an exponent, flat scanlines.
    Hdr,
}

/// Bits per PNG channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BitDepth {
    /// 8 bits (0–255).
    #[default]
    Eight,
    /// 16 bits (0–65535), big-endian as PNG stores them.
    Sixteen,
}

/// How [`write_image_with`] writes: the transfer of integer formats, PNG's bit depth, and PNG text chunks.
#[derive(Clone, Debug, Default)]
pub struct WriteOptions {
    /// Linear values to integers.
    pub transfer: Transfer,
    /// PNG's bits per channel (other formats ignore it; the CLI refuses 16 for them).
    pub bit_depth: BitDepth,
    /// PNG `tEXt` chunks (keyword, text) written after `Transfer`, e.g. `Software`, `Source`.
    pub text: Vec<(String, String)>,
}

/// Why an image could not be written.
#[derive(Debug, Error)]
pub enum OutputError {
    /// Extension not recognised.
    #[error("{path}: unknown image format (use .png, .exr or .ppm)")]
    UnknownFormat {
        /// The output path.
        path: PathBuf,
    },
    /// The target cannot be written: it is a directory, its directory is missing, or not writable.
    #[error("{path}: {reason}")]
    Unwritable {
        /// The output path.
        path: PathBuf,
        /// Why, in a few words.
        reason: String,
    },
    /// Encoding or I/O failure.
    #[error("{path}: {cause}")]
    Write {
        /// The output path.
        path: PathBuf,
        /// What went wrong (not a `source`: the message already says it, and error chains would repeat it).
        cause: BoxError,
    },
}

impl Format {
    /// The format named by `path`'s extension (case-insensitive): `.png`, `.exr`, `.ppm` or `.pnm`.
    pub fn from_extension(path: &Path) -> Result<Format, OutputError> {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(Format::Png),
            Some("exr") => Ok(Format::Exr),
            Some("ppm") | Some("pnm") => Ok(Format::Ppm),
            Some("hdr") => Ok(Format::Hdr),
            _ => Err(OutputError::UnknownFormat { path: path.to_owned() }),
        }
    }

    /// [`Format::from_extension`], and [`check_writable`]: checked before rendering so that a bad name
    /// fails at once rather than after the render.
    pub fn from_path(path: &Path) -> Result<Format, OutputError> {
        let format = Format::from_extension(path)?;
        check_writable(path)?;
        Ok(format)
    }
}

/// Whether a file can be written at `path` the way [`write_atomic`] writes it: `path` is not a directory,
/// and a temporary file can be created (and is removed again) in its directory.
pub fn check_writable(path: &Path) -> Result<(), OutputError> {
    let fail = |reason: String| Err(OutputError::Unwritable { path: path.to_owned(), reason });
    if path.is_dir() {
        return fail("is a directory".to_owned());
    }
    let dir = parent_dir(path);
    if !dir.is_dir() {
        let what = if dir.exists() { "is not a directory" } else { "does not exist" };
        return fail(format!("cannot write: directory {} {what}", dir.display()));
    }
    let probe = temp_path(path);
    // The name the write will use; a stale file of that name (an earlier process with this id) is reused.
    match fs::OpenOptions::new().write(true).create(true).truncate(true).open(&probe) {
        Ok(_) => {
            let _ = fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => fail(format!("cannot write in {}: {}", dir.display(), io_reason(&e))),
    }
}

/// An I/O error's description without Rust's "(os error N)" suffix.
fn io_reason(e: &std::io::Error) -> String {
    let text = e.to_string();
    match text.find(" (os error") {
        Some(i) => text[..i].to_owned(),
        None => text,
    }
}

/// The temporary file beside `path` that [`write_atomic`] writes first.
fn temp_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    parent_dir(path).join(format!(".{name}.{}.tmp", std::process::id()))
}

fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_owned(),
        _ => PathBuf::from("."),
    }
}

/// Linear to sRGB-encoded 8-bit, clamped: the definition, one `powf` per value. [`srgb8`] gives the same
/// bits from a table.
pub fn srgb8_formula(linear: f32) -> u8 {
    let c = if linear.is_nan() { 0.0 } else { linear.clamp(0.0, 1.0) };
    let s = if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

/// Linear to sRGB-encoded 8-bit, clamped: [`srgb8_formula`] by table, bit for bit (checked over every f32
/// in [0, 1] by a test). The formula took most of a 1080p image's write time.
pub fn srgb8(linear: f32) -> u8 {
    SrgbTable::get().encode(linear)
}

/// Buckets of equal width over [0, 1]: the curve's steepest slope is 12.92·255 ≈ 3295 codes per unit, so
/// a bucket 1/4096 wide holds at most one code boundary (checked when the table is built).
const SRGB_BUCKETS: usize = 4096;

/// [`srgb8_formula`], which never decreases, per bucket: `first[b]` is its code at the bucket's start and
/// `next[b]` the smallest f32 it maps to the code above (+inf past 255), so a value in bucket b encodes to
/// `first[b]`, plus one from `next[b]` on.
struct SrgbTable {
    first: [u8; SRGB_BUCKETS],
    next: [f32; SRGB_BUCKETS],
}

impl SrgbTable {
    /// The table, built on first use (about 12 000 `powf`, well under a millisecond).
    fn get() -> &'static Self {
        static TABLE: std::sync::OnceLock<SrgbTable> = std::sync::OnceLock::new();
        TABLE.get_or_init(Self::new)
    }

    fn new() -> Self {
        // threshold[k]: the smallest f32 in [0, 1] encoded as k or above, by bisection over the bit
        // patterns of [0, 1], which order like the values.
        let mut threshold = [f32::INFINITY; 257];
        threshold[0] = 0.0;
        for (k, t) in threshold.iter_mut().enumerate().take(256).skip(1) {
            let (mut lo, mut hi) = (0u32, 1.0f32.to_bits());
            while hi - lo > 1 {
                let mid = lo + (hi - lo) / 2;
                if usize::from(srgb8_formula(f32::from_bits(mid))) >= k {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            *t = f32::from_bits(hi);
        }
        let start = |b: usize| b as f32 / SRGB_BUCKETS as f32;
        let first: [u8; SRGB_BUCKETS] = std::array::from_fn(|b| srgb8_formula(start(b)));
        let next = std::array::from_fn(|b| {
            let code = usize::from(first[b]);
            let after_next = threshold.get(code + 2).copied().unwrap_or(f32::INFINITY);
            assert!(after_next >= start(b + 1), "two sRGB code boundaries in bucket {b}");
            threshold[code + 1]
        });
        Self { first, next }
    }

    /// [`SrgbTable::encode`] of 8 values into `out`: the clamp and the bucket in SIMD (the scalar rounding:
    /// NaN to 0, then max and min, then an exact product and truncation), the look-ups per value. A third
    /// of the scalar encode's instructions.
    #[inline(always)]
    fn encode8(&self, values: [f32; 8], out: &mut [u8]) {
        use wide::{f32x8, i32x8};
        let v = f32x8::from(values);
        let (zero, one) = (f32x8::splat(0.0), f32x8::splat(1.0));
        let c = v.is_nan().select(zero, v.fast_max(zero).fast_min(one));
        let bucket = (c * f32x8::splat(SRGB_BUCKETS as f32))
            .fast_trunc_int()
            .min(i32x8::splat(SRGB_BUCKETS as i32 - 1));
        let (c, bucket) = (c.to_array(), bucket.to_array());
        for ((o, c), b) in out.iter_mut().zip(c).zip(bucket) {
            // The mask keeps the index in range for the compiler (the bucket already is).
            let b = b as usize & (SRGB_BUCKETS - 1);
            *o = self.first[b] + u8::from(c >= self.next[b]);
        }
    }

    #[inline(always)]
    fn encode(&self, linear: f32) -> u8 {
        let c = if linear.is_nan() { 0.0 } else { linear.clamp(0.0, 1.0) };
        // c·4096 is exact (a power of two), so c lies in bucket b's [b, b + 1)/4096 (1.0 in the last).
        let b = ((c * SRGB_BUCKETS as f32) as usize).min(SRGB_BUCKETS - 1);
        self.first[b] + u8::from(c >= self.next[b])
    }
}

/// 8-bit sRGB copy of the image, a row per task, 8 pixels (24 values) per step.
pub fn to_srgb8(img: &Image) -> RgbImage {
    use rayon::prelude::*;
    let (table, width) = (SrgbTable::get(), img.width as usize);
    let mut raw = vec![0u8; img.pixels.len() * 3];
    raw.par_chunks_mut(3 * width.max(1)).zip(img.pixels.par_chunks(width.max(1))).for_each(|(out, row)| {
        let (pixels, rest) = row.split_at(row.len() - row.len() % 8);
        for (o, p) in out.chunks_exact_mut(24).zip(pixels.chunks_exact(8)) {
            let mut values = [0.0f32; 24];
            for (v, q) in values.chunks_exact_mut(3).zip(p) {
                v.copy_from_slice(&[q.x, q.y, q.z]);
            }
            for (o, v) in o.chunks_exact_mut(8).zip(values.chunks_exact(8)) {
                table.encode8(v.try_into().expect("8 values"), o);
            }
        }
        for (o, p) in out[3 * pixels.len()..].chunks_exact_mut(3).zip(rest) {
            o.copy_from_slice(&[table.encode(p.x), table.encode(p.y), table.encode(p.z)]);
        }
    });
    RgbImage::from_raw(img.width, img.height, raw).expect("buffer size matches the image")
}

/// Linear transfer to 8-bit: clamped to [0, 1] (NaN to 0), times 255, rounded to nearest, as classic
/// tracers write their values.
pub fn linear8(value: f32) -> u8 {
    let c = if value.is_nan() { 0.0 } else { value.clamp(0.0, 1.0) };
    (c * 255.0 + 0.5) as u8
}

/// 8-bit copy of the image under `transfer`: [`to_srgb8`], or [`linear8`] per value.
pub fn to_rgb8(img: &Image, transfer: Transfer) -> RgbImage {
    use rayon::prelude::*;
    match transfer {
        Transfer::Srgb => to_srgb8(img),
        Transfer::Linear => {
            let width = (img.width as usize).max(1);
            let mut raw = vec![0u8; img.pixels.len() * 3];
            raw.par_chunks_mut(3 * width).zip(img.pixels.par_chunks(width)).for_each(|(out, row)| {
                for (o, p) in out.chunks_exact_mut(3).zip(row) {
                    o.copy_from_slice(&[linear8(p.x), linear8(p.y), linear8(p.z)]);
                }
            });
            RgbImage::from_raw(img.width, img.height, raw).expect("buffer size matches the image")
        }
    }
}

/// A boxed error from an encoder or the file system.
pub type BoxError = Box<dyn std::error::Error + Send + Sync>;

/// Writes `img` to `path` in the format its extension names, atomically; 8-bit formats under `transfer`.
///
/// ```
/// use bareray::{film::Image, math::Rgb, output, scene::desc::Transfer};
///
/// let mut img = Image::new(4, 2);
/// img.pixels[0] = Rgb::new(1.0, 0.5, 0.0);
/// let dir = std::env::temp_dir();
/// for name in ["bareray-doc-write.png", "bareray-doc-write.exr", "bareray-doc-write.ppm"] {
///     output::write_image(&img, &dir.join(name), Transfer::Srgb)?;
/// #   std::fs::remove_file(dir.join(name))?;
/// }
/// assert!(output::write_image(&img, &dir.join("bareray-doc-write.jpg"), Transfer::Srgb).is_err());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_image(img: &Image, path: &Path, transfer: Transfer) -> Result<(), OutputError> {
    write_image_with(img, path, &WriteOptions { transfer, ..WriteOptions::default() })
}

/// [`write_image`] with a PNG bit depth and text chunks.
pub fn write_image_with(img: &Image, path: &Path, options: &WriteOptions) -> Result<(), OutputError> {
    let format = Format::from_path(path)?;
    write_atomic(path, |tmp| encode(img, format, options, tmp))
        .map_err(|cause| OutputError::Write { path: path.to_owned(), cause })
}

/// Runs `write` on a temporary file beside `path`, then renames it to `path`; on failure the temporary
/// file is removed and `path` is left as it was.
pub fn write_atomic(path: &Path, write: impl FnOnce(&Path) -> Result<(), BoxError>) -> Result<(), BoxError> {
    let tmp = temp_path(path);
    let result = write(&tmp).and_then(|()| fs::rename(&tmp, path).map_err(Into::into));
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

fn encode(img: &Image, format: Format, options: &WriteOptions, tmp: &Path) -> Result<(), BoxError> {
    let mut file = BufWriter::new(fs::File::create(tmp)?);
    let transfer = options.transfer;
    match format {
        Format::Png if options.bit_depth == BitDepth::Sixteen => write_png16(img, options, &mut file)?,
        Format::Png => write_png(&to_rgb8(img, transfer), options, &mut file)?,
        Format::Ppm => write_ppm(&to_rgb8(img, transfer), &mut file)?,
        Format::Hdr => write_hdr(img, &mut file)?,
        Format::Exr => {
            let raw = img.pixels.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
            let buf =
                Rgb32FImage::from_raw(img.width, img.height, raw).expect("buffer size matches the image");
            buf.write_to(&mut file, ImageFormat::OpenExr)?;
        }
    }
    file.into_inner().map_err(|e| e.into_error())?.sync_all()?;
    Ok(())
}

/// 8-bit RGB PNG with a `tEXt` chunk `Transfer` = `srgb` or `linear`. The `png` crate directly (the
/// `image` crate's encoder writes no text chunks), with that encoder's settings here: fast deflate and Paeth
/// on every row rather than the adaptive choice per row (on balls4 at 1024², 3.4 against 4.2 ms to encode
/// and a smaller file; docs/perf-log/2026-11.md).
fn write_png(img: &RgbImage, options: &WriteOptions, out: impl Write) -> Result<(), BoxError> {
    png_with(img.width(), img.height(), png::BitDepth::Eight, options, img.as_raw(), out)
}

/// 16-bit RGB PNG: each value under the transfer at 16 bits (the sRGB curve in f64, or the value clamped),
/// ×65535, rounded, stored big-endian.
fn write_png16(img: &Image, options: &WriteOptions, out: impl Write) -> Result<(), BoxError> {
    let encode = |v: f32| -> u16 {
        let c = if v.is_nan() { 0.0 } else { f64::from(v).clamp(0.0, 1.0) };
        let s = match options.transfer {
            Transfer::Linear => c,
            Transfer::Srgb if c <= 0.003_130_8 => 12.92 * c,
            Transfer::Srgb => 1.055 * c.powf(1.0 / 2.4) - 0.055,
        };
        (s * 65535.0 + 0.5) as u16
    };
    let raw: Vec<u8> =
        img.pixels.iter().flat_map(|p| [p.x, p.y, p.z]).flat_map(|v| encode(v).to_be_bytes()).collect();
    png_with(img.width, img.height, png::BitDepth::Sixteen, options, &raw, out)
}

/// An RGB PNG of `depth` from its raw bytes, with the `Transfer` chunk and the options' text chunks.
fn png_with(
    width: u32,
    height: u32,
    depth: png::BitDepth,
    options: &WriteOptions,
    raw: &[u8],
    out: impl Write,
) -> Result<(), BoxError> {
    let mut encoder = png::Encoder::new(out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(depth);
    encoder.set_compression(png::Compression::Fast);
    encoder.set_filter(png::Filter::Paeth);
    encoder.add_text_chunk("Transfer".to_owned(), options.transfer.name().to_owned())?;
    for (keyword, text) in &options.text {
        encoder.add_text_chunk(keyword.clone(), text.clone())?;
    }
    let mut writer = encoder.write_header()?;
    writer.write_image_data(raw)?;
    writer.finish()?;
    Ok(())
}

/// Radiance HDR: the header (`#?RADIANCE`, `FORMAT=32-bit_rle_rgbe`, the resolution line `-Y h +X w`: rows
/// top to bottom), then each pixel as RGBE — three 8-bit mantissas and a shared exponent — in flat
/// (uncompressed) scanlines, which every reader takes. Negative and NaN values are written as 0.
fn write_hdr(img: &Image, out: &mut impl Write) -> std::io::Result<()> {
    write!(out, "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {} +X {}\n", img.height, img.width)?;
    let rgbe = |p: &crate::math::Rgb| -> [u8; 4] {
        let clean = |v: f32| if v.is_nan() || v < 0.0 { 0.0 } else { v.min(f32::MAX) };
        let (r, g, b) = (clean(p.x), clean(p.y), clean(p.z));
        let m = r.max(g).max(b);
        if m < 1e-32 {
            return [0; 4];
        }
        // m = f·2^e with f in [0.5, 1): the mantissas are v·256/2^e, rounded (the largest clamped to 255).
        let e = m.log2().floor() as i32 + 1;
        let scale = 256.0 / 2f32.powi(e);
        let q = |v: f32| (v * scale + 0.5).min(255.0) as u8;
        [q(r), q(g), q(b), (e + 128).clamp(0, 255) as u8]
    };
    for p in &img.pixels {
        out.write_all(&rgbe(p))?;
    }
    Ok(())
}

/// Binary 8-bit PPM: the header `P6\n<width> <height>\n255\n`, then the RGB bytes row by row, top row
/// first (netpbm's `P6`, which every PPM reader takes; the `image` crate's PNM encoder writes PAM `P7`).
fn write_ppm(img: &RgbImage, out: &mut impl Write) -> std::io::Result<()> {
    write!(out, "P6\n{} {}\n255\n", img.width(), img.height())?;
    out.write_all(img.as_raw())
}

/// Streams a file atomically: `fill` writes into a buffered temporary file in the same directory, which
/// replaces `path` only once everything was written (for generated scenes too large to hold in memory).
pub fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<fs::File>) -> std::io::Result<()>,
) -> std::io::Result<()> {
    write_atomic(path, |tmp| {
        let mut w = BufWriter::with_capacity(1 << 20, fs::File::create(tmp)?);
        fill(&mut w)?;
        w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        Ok(())
    })
    .map_err(std::io::Error::other)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ppm_is_p6_with_a_minimal_header() {
        let img = RgbImage::from_raw(2, 1, vec![1, 2, 3, 4, 5, 6]).unwrap();
        let mut out = Vec::new();
        write_ppm(&img, &mut out).unwrap();
        assert_eq!(out, b"P6\n2 1\n255\n\x01\x02\x03\x04\x05\x06");
    }

    #[test]
    fn linear_transfer_clamps_scales_and_rounds() {
        assert_eq!(
            [linear8(0.0), linear8(1.0), linear8(2.0), linear8(-1.0), linear8(f32::NAN)],
            [0, 255, 255, 0, 0]
        );
        assert_eq!([linear8(0.5), linear8(0.498), linear8(0.753)], [128, 127, 192]);
        let mut img = Image::new(11, 2);
        for (k, p) in img.pixels.iter_mut().enumerate() {
            *p = crate::math::V3::new(k as f32 / 21.0, 0.25, 1.5);
        }
        let out = to_rgb8(&img, Transfer::Linear);
        for (k, p) in img.pixels.iter().enumerate() {
            assert_eq!(&out.as_raw()[3 * k..3 * k + 3], &[linear8(p.x), 64, 255], "pixel {k}");
        }
        assert_eq!(to_rgb8(&img, Transfer::Srgb), to_srgb8(&img));
    }

    #[test]
    fn png_records_the_transfer_in_a_text_chunk() {
        let img = RgbImage::from_raw(2, 1, vec![1, 2, 3, 4, 5, 6]).unwrap();
        for transfer in [Transfer::Srgb, Transfer::Linear] {
            let mut out = Vec::new();
            write_png(&img, &WriteOptions { transfer, ..WriteOptions::default() }, &mut out).unwrap();
            let reader = png::Decoder::new(std::io::Cursor::new(&out)).read_info().unwrap();
            let text = &reader.info().uncompressed_latin1_text;
            assert_eq!(text.len(), 1);
            assert_eq!((text[0].keyword.as_str(), text[0].text.as_str()), ("Transfer", transfer.name()));
            let decoded = image::load_from_memory(&out).unwrap().into_rgb8();
            assert_eq!(decoded, img);
        }
    }

    #[test]
    fn srgb_curve_endpoints_and_midpoint() {
        assert_eq!(srgb8(0.0), 0);
        assert_eq!(srgb8(1.0), 255);
        assert_eq!(srgb8(2.0), 255);
        assert_eq!(srgb8(-1.0), 0);
        assert_eq!(srgb8(f32::NAN), 0);
        // sRGB 0.5 is linear 0.21404.
        assert_eq!(srgb8(0.2141), 128);
    }

    /// The image conversion (8 values at a time, then the row's rest) gives each value's scalar code, NaN,
    /// signed zeros, out-of-range and subnormal values included.
    #[test]
    fn image_conversion_is_the_scalar_encode() {
        // Edge values, and the table's code boundaries and the floats just below them.
        let next = &SrgbTable::get().next;
        let boundaries = (1..64).map(|k| next[k * 64]).filter(|t| t.is_finite());
        let special: Vec<f32> =
            [f32::NAN, -0.0, 0.0, -1.0, 2.0, f32::INFINITY, f32::NEG_INFINITY, 1e-40, 1.0]
                .into_iter()
                .chain(boundaries.flat_map(|t| [t, f32::from_bits(t.to_bits() - 1)]))
                .collect();
        let mut state = 7u32;
        let mut random = move || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1u32 << 24) as f32 * 1.2 - 0.1
        };
        // 13 columns: one step of 8 pixels and a rest of 5; the special values, then as many random ones.
        let mut img = Image::new(13, 9);
        let n = special.len();
        for (k, p) in img.pixels.iter_mut().enumerate() {
            let mut v = |j: usize| special.get((3 * k + j) % (2 * n)).copied().unwrap_or_else(&mut random);
            *p = crate::math::V3::new(v(0), v(1), v(2));
        }
        let out = to_srgb8(&img);
        for (k, p) in img.pixels.iter().enumerate() {
            assert_eq!(
                &out.as_raw()[3 * k..3 * k + 3],
                &[srgb8(p.x), srgb8(p.y), srgb8(p.z)],
                "pixel {k}: {p:?}"
            );
        }
    }

    /// The table is the formula, bit for bit, on every f32 from 0 to 1 (and clamps like it outside).
    #[test]
    fn srgb_table_matches_the_formula_on_every_f32_in_range() {
        use rayon::prelude::*;
        let one = 1.0f32.to_bits();
        let bad = (0..=one / 65536)
            .into_par_iter()
            .map(|hi| {
                (hi * 65536..=(hi * 65536 + 65535).min(one))
                    .map(f32::from_bits)
                    .filter(|&c| srgb8(c) != srgb8_formula(c))
                    .count()
            })
            .sum::<usize>();
        assert_eq!(bad, 0, "values the table encodes differently");
        for c in [-0.0, -1e-30, f32::NEG_INFINITY, 1.5, f32::INFINITY, f32::NAN, f32::MIN_POSITIVE / 2.0] {
            assert_eq!(srgb8(c), srgb8_formula(c), "{c}");
        }
    }
}
