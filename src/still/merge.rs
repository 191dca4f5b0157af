//! Regions rendered separately (`render --region`, `--crop`), pasted back into one image: each part
//! records where it belongs (PNG `Region` text, EXR data window, PPM header comment); [`merge`] checks that
//! the parts come from one render and tile its image exactly once, then streams the rows into the output,
//! reading each part row by row. The stored bytes pass through untouched, so the merged file is the bytes
//! the whole render writes.

use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

use exr::block::reader::ChunksReader;
use thiserror::Error;

use crate::output::{self, BitDepth, BoxError, Format, Frame, OutputError, WriteOptions};
use crate::scene::desc::Transfer;

/// Why parts could not be merged.
#[derive(Debug, Error)]
pub enum MergeError {
    /// A part could not be read, or is not a part bareray wrote.
    #[error("{path}: {why}")]
    Part {
        /// The part's path.
        path: PathBuf,
        /// What is wrong with it.
        why: String,
    },
    /// The parts do not make one image.
    #[error("{0}")]
    Tiling(String),
    /// The merged image could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// What a part holds, read from its header.
#[derive(Clone, Debug, PartialEq)]
struct Header {
    format: Format,
    frame: Frame,
    bit_depth: BitDepth,
    transfer: Transfer,
    /// PNG text chunks after `Transfer` (not `Region`); EXR's software name and comments.
    text: Vec<(String, String)>,
}

/// Merges `parts` into `output` (the format its extension names, which must be the parts'). Returns the
/// full image's size.
pub fn merge(parts: &[PathBuf], output_path: &Path) -> Result<Frame, MergeError> {
    let format = Format::from_path(output_path)?;
    let headers: Vec<Header> = parts.iter().map(|p| read_header(p)).collect::<Result<_, _>>()?;
    let first = headers.first().ok_or_else(|| MergeError::Tiling("no parts to merge".to_owned()))?;
    for (path, h) in parts.iter().zip(&headers) {
        let same = |a: &Header| Header { frame: Frame::whole(1, 1), ..a.clone() };
        if h.format != format {
            return Err(part(
                path,
                format!(
                    "is {}, the output is {}: merge keeps the parts' format",
                    h.format.name(),
                    format.name()
                ),
            ));
        }
        if (h.frame.full_width, h.frame.full_height) != (first.frame.full_width, first.frame.full_height)
            || same(h) != same(first)
        {
            return Err(part(path, format!("is not from the same render as {}", parts[0].display())));
        }
    }
    check_tiling(parts, &headers)?;
    let full = Frame::whole(first.frame.full_width, first.frame.full_height);
    let options =
        WriteOptions { transfer: first.transfer, bit_depth: first.bit_depth, text: first.text.clone() };
    let mut rows = Rows { parts: parts.to_vec(), headers, open: Vec::new(), y: 0, failure: None };
    let written = output::write_rows(output_path, format, &options, full, &mut rows);
    match (rows.failure, written) {
        (Some(e), _) => Err(e),
        (None, Err(e)) => Err(e.into()),
        (None, Ok(())) => Ok(full),
    }
}

fn part(path: &Path, why: impl Into<String>) -> MergeError {
    MergeError::Part { path: path.to_owned(), why: why.into() }
}

/// Every pixel of the full image in exactly one part.
fn check_tiling(parts: &[PathBuf], headers: &[Header]) -> Result<(), MergeError> {
    let f = headers[0].frame;
    let area = |h: &Header| u64::from(h.frame.width) * u64::from(h.frame.height);
    for (i, a) in headers.iter().enumerate() {
        for (j, b) in headers.iter().enumerate().skip(i + 1) {
            let (a, b) = (a.frame, b.frame);
            let apart = a.x0 + a.width <= b.x0
                || b.x0 + b.width <= a.x0
                || a.y0 + a.height <= b.y0
                || b.y0 + b.height <= a.y0;
            if !apart {
                return Err(MergeError::Tiling(format!(
                    "{} ({}) and {} ({}) overlap",
                    parts[i].display(),
                    a.region_text(),
                    parts[j].display(),
                    b.region_text()
                )));
            }
        }
    }
    let covered: u64 = headers.iter().map(area).sum();
    let full = u64::from(f.full_width) * u64::from(f.full_height);
    if covered != full {
        return Err(MergeError::Tiling(format!(
            "the parts cover {covered} of the {}x{} image's {full} pixels",
            f.full_width, f.full_height
        )));
    }
    Ok(())
}

/// The header of a part: by its first bytes, a PNG, PPM or EXR; a file without a region is the whole image.
fn read_header(path: &Path) -> Result<Header, MergeError> {
    let fail = |why: String| part(path, why);
    let mut magic = [0u8; 4];
    File::open(path).and_then(|mut f| f.read_exact(&mut magic)).map_err(|e| fail(e.to_string()))?;
    match &magic {
        [0x89, b'P', b'N', b'G'] => png_header(path).map_err(|e| fail(e.to_string())),
        [b'P', b'6', ..] => ppm_header(path).map(|(h, _)| h).map_err(|e| fail(e.to_string())),
        [0x76, 0x2f, 0x31, 0x01] => exr_header(path).map_err(|e| fail(e.to_string())),
        _ => Err(fail("not a PNG, PPM (P6) or EXR file".to_owned())),
    }
}

fn png_reader(path: &Path) -> Result<png::Reader<BufReader<File>>, BoxError> {
    let mut decoder = png::Decoder::new(BufReader::new(File::open(path)?));
    decoder.set_transformations(png::Transformations::IDENTITY);
    Ok(decoder.read_info()?)
}

fn png_header(path: &Path) -> Result<Header, BoxError> {
    let reader = png_reader(path)?;
    let info = reader.info();
    let bit_depth = match (info.color_type, info.bit_depth) {
        (png::ColorType::Rgb, png::BitDepth::Eight) => BitDepth::Eight,
        (png::ColorType::Rgb, png::BitDepth::Sixteen) => BitDepth::Sixteen,
        (c, d) => return Err(format!("a {d:?}-bit {c:?} PNG; bareray writes 8- or 16-bit RGB").into()),
    };
    let (mut transfer, mut region, mut text) = (None, None, Vec::new());
    for chunk in &info.uncompressed_latin1_text {
        match chunk.keyword.as_str() {
            "Transfer" => transfer = Some(chunk.text.clone()),
            "Region" => region = Some(parse_region(&chunk.text)?),
            _ => text.push((chunk.keyword.clone(), chunk.text.clone())),
        }
    }
    let transfer = match transfer.as_deref() {
        Some("linear") => Transfer::Linear,
        Some("srgb") => Transfer::Srgb,
        _ => return Err("no Transfer text chunk: not a PNG bareray wrote".into()),
    };
    let frame = region.unwrap_or(Frame::whole(info.width, info.height));
    check_size(frame, info.width, info.height)?;
    Ok(Header { format: Format::Png, frame, bit_depth, transfer, text })
}

fn parse_region(text: &str) -> Result<Frame, BoxError> {
    Frame::parse_region_text(text).ok_or_else(|| format!("region `{text}` is not X0,Y0,X1,Y1 of WxH").into())
}

fn check_size(frame: Frame, width: u32, height: u32) -> Result<(), BoxError> {
    if (frame.width, frame.height) != (width, height) {
        return Err(
            format!("its region {} does not match its {width}x{height} pixels", frame.region_text()).into()
        );
    }
    Ok(())
}

/// A PPM part's header and the reader left at its first pixel.
fn ppm_header(path: &Path) -> Result<(Header, BufReader<File>), BoxError> {
    let mut reader = BufReader::new(File::open(path)?);
    let mut line = String::new();
    let mut next_line = |reader: &mut BufReader<File>| -> Result<String, BoxError> {
        line.clear();
        reader.read_line(&mut line)?;
        Ok(line.trim_end_matches('\n').to_owned())
    };
    let magic = next_line(&mut reader)?;
    let mut size = next_line(&mut reader)?;
    let mut region = None;
    if let Some(text) = size.strip_prefix(output::PPM_REGION_COMMENT) {
        region = Some(parse_region(text)?);
        size = next_line(&mut reader)?;
    }
    let max = next_line(&mut reader)?;
    let dims: Vec<u32> = size.split_whitespace().filter_map(|v| v.parse().ok()).collect();
    let (&[width, height], "P6", "255") = (&dims[..], magic.as_str(), max.as_str()) else {
        return Err("not a PPM header bareray writes (P6, one size line, 255)".into());
    };
    let frame = region.unwrap_or(Frame::whole(width, height));
    check_size(frame, width, height)?;
    let header = Header {
        format: Format::Ppm,
        frame,
        bit_depth: BitDepth::Eight,
        transfer: Transfer::Srgb,
        text: Vec::new(),
    };
    Ok((header, reader))
}

fn exr_header(path: &Path) -> Result<Header, BoxError> {
    let meta = exr::meta::MetaData::read_from_file(path, false)?;
    let [h] = &meta.headers[..] else { return Err("a multi-part EXR; bareray writes one part".into()) };
    let names: Vec<String> = h.channels.list.iter().map(|c| c.name.to_string()).collect();
    if names != ["B", "G", "R"]
        || h.channels.list.iter().any(|c| c.sample_type != exr::meta::attribute::SampleType::F32)
    {
        return Err("not an R, G, B float EXR".into());
    }
    let display = h.shared_attributes.display_window;
    let at = h.own_attributes.layer_position;
    if display.position != exr::math::Vec2(0, 0) || at.0 < 0 || at.1 < 0 {
        return Err("its windows are not those of a bareray image or region".into());
    }
    let frame = Frame {
        width: h.layer_size.0 as u32,
        height: h.layer_size.1 as u32,
        x0: at.0 as u32,
        y0: at.1 as u32,
        full_width: display.size.0 as u32,
        full_height: display.size.1 as u32,
    };
    let mut text = Vec::new();
    if let Some(software) = &h.own_attributes.software_name {
        text.push(("Software".to_owned(), String::from_utf8_lossy(software.bytes()).into_owned()));
    }
    if let Some(comments) = &h.own_attributes.comments {
        text.push((String::new(), String::from_utf8_lossy(comments.bytes()).into_owned()));
    }
    Ok(Header { format: Format::Exr, frame, bit_depth: BitDepth::Eight, transfer: Transfer::Srgb, text })
}

/// One part's rows, read in order.
enum PartRows {
    Png(Box<png::Reader<BufReader<File>>>),
    Ppm(BufReader<File>, usize),
    Exr {
        blocks: Box<dyn Iterator<Item = exr::error::Result<exr::block::UncompressedBlock>>>,
        rows: std::collections::VecDeque<Vec<u8>>,
        width: usize,
    },
}

impl PartRows {
    fn open(path: &Path, h: &Header) -> Result<Self, BoxError> {
        Ok(match h.format {
            Format::Png => PartRows::Png(Box::new(png_reader(path)?)),
            Format::Ppm => PartRows::Ppm(ppm_header(path)?.1, 3 * h.frame.width as usize),
            Format::Exr => {
                let reader = exr::block::read(BufReader::new(File::open(path)?), false)?;
                let blocks = reader.all_chunks(false)?.sequential_decompressor(false);
                PartRows::Exr {
                    blocks: Box::new(blocks),
                    rows: Default::default(),
                    width: h.frame.width as usize,
                }
            }
            Format::Hdr | Format::Tiff | Format::Jpeg => {
                return Err("only PNG, EXR and PPM parts are merged".into())
            }
        })
    }

    fn next_row(&mut self) -> Result<Vec<u8>, BoxError> {
        match self {
            PartRows::Png(reader) => Ok(reader.next_row()?.ok_or("the PNG ends early")?.data().to_vec()),
            PartRows::Ppm(reader, bytes) => {
                let mut row = vec![0; *bytes];
                reader.read_exact(&mut row)?;
                Ok(row)
            }
            PartRows::Exr { blocks, rows, width } => {
                if rows.is_empty() {
                    let block = blocks.next().ok_or("the EXR ends early")??;
                    rows.extend(exr_rows(&block.data, *width));
                }
                Ok(rows.pop_front().expect("a block holds rows"))
            }
        }
    }
}

/// A block's lines (per row: B, G, R, each `width` native-endian f32) as rows of R, G, B little-endian.
fn exr_rows(data: &[u8], width: usize) -> Vec<Vec<u8>> {
    data.chunks_exact(12 * width)
        .map(|line| {
            let channel = |c: usize, x: usize| &line[(c * width + x) * 4..][..4];
            let mut row = Vec::with_capacity(12 * width);
            for x in 0..width {
                for c in [2, 1, 0] {
                    let v = channel(c, x);
                    row.extend_from_slice(&u32::from_ne_bytes([v[0], v[1], v[2], v[3]]).to_le_bytes());
                }
            }
            row
        })
        .collect()
}

/// The full image's rows, each assembled from the parts that cover it, left to right; a read error ends
/// the rows early and is kept in `failure`.
struct Rows {
    parts: Vec<PathBuf>,
    headers: Vec<Header>,
    /// Open parts covering the current row: (left column, part index, reader).
    open: Vec<(u32, usize, PartRows)>,
    y: u32,
    failure: Option<MergeError>,
}

impl Rows {
    fn row(&mut self) -> Result<Vec<u8>, MergeError> {
        let y = self.y;
        self.open.retain(|&(_, i, _)| y < self.headers[i].frame.y0 + self.headers[i].frame.height);
        for (i, h) in self.headers.iter().enumerate() {
            if h.frame.y0 == y {
                let reader =
                    PartRows::open(&self.parts[i], h).map_err(|e| part(&self.parts[i], e.to_string()))?;
                self.open.push((h.frame.x0, i, reader));
            }
        }
        self.open.sort_by_key(|&(x0, _, _)| x0);
        let mut row = Vec::new();
        for (_, i, reader) in &mut self.open {
            row.extend(reader.next_row().map_err(|e| part(&self.parts[*i], e.to_string()))?);
        }
        self.y += 1;
        Ok(row)
    }
}

impl Iterator for Rows {
    type Item = Vec<u8>;
    fn next(&mut self) -> Option<Vec<u8>> {
        if self.failure.is_some() || self.y == self.headers[0].frame.full_height {
            return None;
        }
        match self.row() {
            Ok(row) => Some(row),
            Err(e) => {
                self.failure = Some(e);
                None
            }
        }
    }
}
