//! Images out: the format follows the file extension (PNG 8- or 16-bit, PPM 8-bit, EXR linear float, Radiance
//! HDR linear RGBE, TIFF 8- or 16-bit, JPEG). Integer values follow the scene's [`Transfer`]: the sRGB curve, or the values as they
//! are (clamped, scaled, rounded); EXR and HDR hold the values as they are, whatever the transfer. PNG records
//! the transfer in a `tEXt` chunk, keyword `Transfer`, text `srgb` or `linear`, and any further text the
//! caller gives ([`WriteOptions::text`]: the renderer, scene, size, sampling); PPM's header stays minimal.
//! The file is written under a temporary name in the same directory and renamed into place, so a failed
//! run never leaves half a file and never destroys an existing one.

use std::fs;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use thiserror::Error;

use crate::film::Image;
use crate::math::Rgb;
use crate::scene::desc::Transfer;

pub(crate) mod exr;
pub(crate) mod held;
mod netpbm;
mod png;
mod radiance;
mod srgb;

pub(crate) use netpbm::REGION_COMMENT as PPM_REGION_COMMENT;
pub use srgb::{linear8, srgb8, to_rgb8};

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
    /// TIFF (`.tif`, `.tiff`): uncompressed 8- or 16-bit RGB, encoded whole at the end.
    Tiff,
    /// JPEG (`.jpg`, `.jpeg`): baseline 8-bit, quality 92, encoded whole at the end.
    Jpeg,
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

/// How `write_image_with` writes: the transfer of integer formats, PNG's bit depth, and PNG text chunks.
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
    #[error("{path}: unknown image format (use .png, .exr, .ppm, .hdr, .tif or .jpg)")]
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
    /// The format's usual name: `PNG`, `EXR`, `PPM`, `HDR`.
    pub fn name(self) -> &'static str {
        match self {
            Format::Png => "PNG",
            Format::Exr => "EXR",
            Format::Ppm => "PPM",
            Format::Hdr => "HDR",
            Format::Tiff => "TIFF",
            Format::Jpeg => "JPEG",
        }
    }

    /// Whether the file is encoded whole at the end (its rows held in memory until then): TIFF and JPEG.
    pub(crate) fn held_whole(self) -> bool {
        matches!(self, Format::Tiff | Format::Jpeg)
    }

    /// The format named by `path`'s extension (case-insensitive): `.png`, `.exr`, `.ppm` or `.pnm`, `.hdr`;
    /// PPM for `-` (standard output).
    pub fn from_extension(path: &Path) -> Result<Format, OutputError> {
        if is_stdout(path) {
            return Ok(Format::Ppm);
        }
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(Format::Png),
            Some("exr") => Ok(Format::Exr),
            Some("ppm") | Some("pnm") => Ok(Format::Ppm),
            Some("hdr") => Ok(Format::Hdr),
            Some("tif") | Some("tiff") => Ok(Format::Tiff),
            Some("jpg") | Some("jpeg") => Ok(Format::Jpeg),
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

/// Whether `path` names standard output: `-`.
pub fn is_stdout(path: &Path) -> bool {
    path == Path::new("-")
}

/// Whether a file can be written at `path` the way [`write_atomic`] writes it: `path` is not a directory,
/// and a temporary file can be created (and is removed again) in its directory. Standard output (`-`)
/// always can.
pub fn check_writable(path: &Path) -> Result<(), OutputError> {
    if is_stdout(path) {
        return Ok(());
    }
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

/// A boxed error from an encoder or the file system.
pub(crate) type BoxError = Box<dyn std::error::Error + Send + Sync>;

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
/// assert!(output::write_image(&img, &dir.join("bareray-doc-write.gif"), Transfer::Srgb).is_err());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_image(img: &Image, path: &Path, transfer: Transfer) -> Result<(), OutputError> {
    write_image_with(img, path, &WriteOptions { transfer, ..WriteOptions::default() })
}

/// [`write_image`] with a PNG bit depth and text chunks.
pub(crate) fn write_image_with(img: &Image, path: &Path, options: &WriteOptions) -> Result<(), OutputError> {
    let format = Format::from_path(path)?;
    let frame = Frame::whole(img.width, img.height);
    let samples = to_samples(&img.pixels, img.width, format, options);
    write_rows(path, format, options, frame, &mut std::iter::once(samples).filter(|s| !s.is_empty()))
}

/// Runs `write` on a temporary file beside `path`, then renames it to `path`; on failure the temporary
/// file is removed and `path` is left as it was.
pub fn write_atomic(path: &Path, write: impl FnOnce(&Path) -> Result<(), BoxError>) -> Result<(), BoxError> {
    let tmp = Pending::new(temp_path(path));
    write(&tmp.0)?;
    fs::rename(&tmp.0, path)?;
    Ok(())
}

/// The temporary files being written, for `remove_temporaries` (built with the `mpi` feature).
static PENDING: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

/// A temporary file being written: removed when dropped (an error or a panic unwinding past it; after the
/// rename there is nothing left to remove) and listed in [`PENDING`] while it lives.
struct Pending(PathBuf);

impl Pending {
    fn new(path: PathBuf) -> Self {
        PENDING.lock().unwrap_or_else(|e| e.into_inner()).push(path.clone());
        Pending(path)
    }
}

impl Drop for Pending {
    fn drop(&mut self) {
        let _ = fs::remove_file(&self.0);
        let mut list = PENDING.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(i) = list.iter().position(|p| *p == self.0) {
            list.swap_remove(i);
        }
    }
}

/// Removes the temporary files of writes still under way: for a panic hook that ends the process without
/// unwinding (an MPI abort), so that no temporary file is left beside an output.
#[cfg(feature = "mpi")]
pub(crate) fn remove_temporaries() {
    if let Ok(list) = PENDING.try_lock() {
        for path in list.iter() {
            let _ = fs::remove_file(path);
        }
    }
}

/// Where an image file sits in the full image: it holds `width × height` pixels from column `x0`, row `y0`
/// of a `full_width × full_height` image — the whole of it, unless it was rendered by region.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frame {
    /// Columns in the file.
    pub width: u32,
    /// Rows in the file.
    pub height: u32,
    /// The file's first column in the full image.
    pub(crate) x0: u32,
    /// The file's first row in the full image.
    pub(crate) y0: u32,
    /// Columns of the full image.
    pub(crate) full_width: u32,
    /// Rows of the full image.
    pub(crate) full_height: u32,
}

impl Frame {
    /// A whole image of `width × height`.
    pub(crate) fn whole(width: u32, height: u32) -> Self {
        Self { width, height, x0: 0, y0: 0, full_width: width, full_height: height }
    }

    /// Whether the file holds less than the full image.
    pub(crate) fn is_region(&self) -> bool {
        *self != Self::whole(self.full_width, self.full_height)
    }

    /// `X0,Y0,X1,Y1 of WxH` (X1, Y1 exclusive): the text of PNG's `Region` chunk and of PPM's header comment.
    pub(crate) fn region_text(&self) -> String {
        let (x1, y1) = (self.x0 + self.width, self.y0 + self.height);
        format!("{},{},{x1},{y1} of {}x{}", self.x0, self.y0, self.full_width, self.full_height)
    }

    /// Reads [`Frame::region_text`] back; `None` unless it is one, of a rectangle inside its image.
    pub(crate) fn parse_region_text(text: &str) -> Option<Self> {
        let (corners, full) = text.trim().split_once(" of ")?;
        let c: Vec<u32> = corners.split(',').map(|v| v.trim().parse().ok()).collect::<Option<_>>()?;
        let (w, h) = full.split_once('x')?;
        let (full_width, full_height) = (w.trim().parse().ok()?, h.trim().parse().ok()?);
        let [x0, y0, x1, y1] = c[..] else { return None };
        // `then`, not `then_some`: the differences are only taken once the corners are in order.
        (x0 < x1 && y0 < y1 && x1 <= full_width && y1 <= full_height).then(|| Self {
            width: x1 - x0,
            height: y1 - y0,
            x0,
            y0,
            full_width,
            full_height,
        })
    }
}

/// Bytes a file of `format` stores per pixel, as [`write_rows`] takes them: 3 for 8-bit PNG and PPM
/// (R, G, B), 6 for 16-bit PNG (big-endian), 12 for EXR (R, G, B as little-endian f32), 4 for HDR (RGBE).
pub(crate) fn pixel_bytes(format: Format, depth: BitDepth) -> usize {
    match (format, depth) {
        (Format::Png | Format::Tiff, BitDepth::Sixteen) => 6,
        (Format::Png | Format::Ppm | Format::Tiff | Format::Jpeg, _) => 3,
        (Format::Exr, _) => 12,
        (Format::Hdr, _) => 4,
    }
}

/// Whole rows of linear pixels (`width` each) as the bytes `format` stores ([`pixel_bytes`]), under the
/// options' transfer and bit depth; rows in parallel on the current rayon pool.
pub(crate) fn to_samples(pixels: &[Rgb], width: u32, format: Format, options: &WriteOptions) -> Vec<u8> {
    use rayon::prelude::*;
    let size = pixel_bytes(format, options.bit_depth);
    let width = (width as usize).max(1);
    let mut out = vec![0u8; pixels.len() * size];
    out.par_chunks_mut(width * size).zip(pixels.par_chunks(width)).for_each(|(out, row)| {
        match (format, options.bit_depth) {
            (Format::Png | Format::Ppm | Format::Tiff | Format::Jpeg, BitDepth::Eight)
            | (Format::Ppm | Format::Jpeg, _) => srgb::encode8_row(row, options.transfer, out),
            (Format::Png | Format::Tiff, BitDepth::Sixteen) => png::encode16_row(row, options.transfer, out),
            (Format::Exr, _) => {
                for (o, v) in out.chunks_exact_mut(4).zip(row.iter().flat_map(|p| [p.x, p.y, p.z])) {
                    o.copy_from_slice(&v.to_le_bytes());
                }
            }
            (Format::Hdr, _) => {
                for (o, p) in out.chunks_exact_mut(4).zip(row) {
                    o.copy_from_slice(&radiance::rgbe(p));
                }
            }
        }
    });
    out
}

/// Writes `path` atomically from rows of stored bytes ([`pixel_bytes`] per pixel, `frame.width` pixels per
/// row), top row first: each item of `rows` is one or more whole rows. Only the rows in hand are held, so an
/// image of any height streams through a fixed amount of memory. The source must give exactly
/// `frame.height` rows; if it ends early (its producer failed) the write fails and `path` is left as it was.
pub(crate) fn write_rows(
    path: &Path,
    format: Format,
    options: &WriteOptions,
    frame: Frame,
    rows: &mut dyn Iterator<Item = Vec<u8>>,
) -> Result<(), OutputError> {
    let fail = |cause| OutputError::Write { path: path.to_owned(), cause };
    if frame.is_region() && matches!(format, Format::Hdr | Format::Tiff | Format::Jpeg) {
        return Err(fail(format!("regions are written as PNG, EXR or PPM, not {}", format.name()).into()));
    }
    if is_stdout(path) {
        // A stream cannot be written atomically: a failure leaves what was written so far.
        let mut out = std::io::BufWriter::with_capacity(1 << 20, std::io::stdout().lock());
        let rows = Rows::new(rows, frame, pixel_bytes(format, options.bit_depth));
        let written = match format {
            Format::Ppm => netpbm::write_ppm(&mut out, frame, rows),
            _ => Err(format!("standard output takes PPM, not {}", format.name()).into()),
        };
        return written.and_then(|()| Ok(std::io::Write::flush(&mut out)?)).map_err(fail);
    }
    write_atomic(path, |tmp| {
        let mut out = BufWriter::with_capacity(1 << 20, fs::File::create(tmp)?);
        let rows = Rows::new(rows, frame, pixel_bytes(format, options.bit_depth));
        match format {
            Format::Png => png::write(&mut out, frame, options, rows)?,
            Format::Exr => exr::write(&mut out, frame, &exr::rgb_channels(), &options.text, rows)?,
            Format::Ppm => netpbm::write_ppm(&mut out, frame, rows)?,
            Format::Hdr => radiance::write(&mut out, frame, rows)?,
            Format::Tiff | Format::Jpeg => held::write(&mut out, format, options.bit_depth, frame, rows)?,
        }
        out.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        Ok(())
    })
    .map_err(fail)
}

/// Writes an EXR of `channels` to `path` atomically from rows of their samples (per pixel one little-endian
/// 4-byte sample per channel, in the order of `channels`), streamed as [`write_rows`] streams; `text` as
/// [`WriteOptions::text`].
pub(crate) fn write_channels(
    path: &Path,
    frame: Frame,
    channels: &[exr::Channel],
    text: &[(String, String)],
    rows: &mut dyn Iterator<Item = Vec<u8>>,
) -> Result<(), OutputError> {
    write_atomic(path, |tmp| {
        let mut out = BufWriter::with_capacity(1 << 20, fs::File::create(tmp)?);
        exr::write(&mut out, frame, channels, text, Rows::new(rows, frame, 4 * channels.len()))?;
        out.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        Ok(())
    })
    .map_err(|cause| OutputError::Write { path: path.to_owned(), cause })
}

/// The rows of a [`write_rows`] source one at a time, checked: every item whole rows, `frame.height` rows
/// in all.
pub(crate) struct Rows<'a> {
    source: &'a mut dyn Iterator<Item = Vec<u8>>,
    row_bytes: usize,
    height: u32,
    taken: u32,
    chunk: Vec<u8>,
    at: usize,
}

impl<'a> Rows<'a> {
    /// The rows of `source` for a file of `frame`, `pixel_bytes` per pixel.
    pub(crate) fn new(
        source: &'a mut dyn Iterator<Item = Vec<u8>>,
        frame: Frame,
        pixel_bytes: usize,
    ) -> Self {
        let row_bytes = frame.width as usize * pixel_bytes;
        Self { source, row_bytes, height: frame.height, taken: 0, chunk: Vec::new(), at: 0 }
    }

    /// The next row, or an error if the source ended before the image did or gave a partial row.
    pub(crate) fn next_row(&mut self) -> Result<&[u8], BoxError> {
        if self.taken == self.height {
            return Err("the image has no more rows".into());
        }
        if self.at == self.chunk.len() {
            self.chunk = match self.source.next() {
                Some(c) if c.len() % self.row_bytes.max(1) == 0 && !c.is_empty() => c,
                Some(_) => return Err("the pixels do not come in whole rows".into()),
                None => {
                    return Err(format!("the image ended after {} of {} rows", self.taken, self.height).into())
                }
            };
            self.at = 0;
        }
        self.taken += 1;
        self.at += self.row_bytes;
        Ok(&self.chunk[self.at - self.row_bytes..self.at])
    }

    /// Fails if the source holds more rows than the image.
    pub(crate) fn finish(self) -> Result<(), BoxError> {
        if self.at < self.chunk.len() || self.source.next().is_some() {
            return Err(format!("the source gave more than the image's {} rows", self.height).into());
        }
        Ok(())
    }
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
