//! OpenEXR, written as a stream through the `exr` crate's block writer: scan lines in blocks of 16, ZIP
//! compressed, increasing y; each block is compressed and written as soon as its rows arrive, and the
//! offset table is filled in at the end. A region is an EXR data window inside the full image's display
//! window. The software name and the render settings go into the standard `software` and `comments`
//! attributes (no custom attributes: the crate keeps those in a hash map, whose order would change the
//! bytes from run to run).

use std::io::{Seek, Write};

use exr::block::{self, writer::ChunksWriter, BlockIndex, UncompressedBlock};
use exr::math::Vec2;
use exr::meta::attribute::{ChannelDescription, IntegerBounds, LineOrder, SampleType, Text};
use exr::meta::header::{Header, LayerAttributes};
use exr::meta::{BlockDescription, Headers};
use exr::prelude::{Compression, SmallVec};

use super::{BoxError, Frame, Rows};

/// Scan lines per block under ZIP compression.
const BLOCK_ROWS: usize = 16;

/// One channel of an EXR file and the type of its samples.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Channel {
    /// The channel's name (`R`, `N.X`, `id`, ...).
    pub(crate) name: &'static str,
    /// 32-bit float (`true`) or 32-bit unsigned integer.
    pub(crate) float: bool,
}

/// R, G, B as 32-bit floats: the channels of a rendered image.
pub(crate) fn rgb_channels() -> Vec<Channel> {
    ["R", "G", "B"].into_iter().map(|name| Channel { name, float: true }).collect()
}

/// Writes an EXR of `frame` whose rows hold, per pixel, one little-endian 4-byte sample per channel in the
/// order of `channels`. The `text` entry `Software` becomes the `software` attribute; the others, as
/// `key: value` (or the value alone for an empty key) joined by `; `, the `comments` attribute.
pub(crate) fn write<W: Write + Seek>(
    out: &mut W,
    frame: Frame,
    channels: &[Channel],
    text: &[(String, String)],
    mut rows: Rows,
) -> Result<(), BoxError> {
    let (header, order) = header(frame, channels, text)?;
    let (width, pixel) = (frame.width as usize, 4 * channels.len());
    let mut failure: Option<BoxError> = None;
    let result = block::write(out, smallvec_of(header), true, |meta, writer| {
        let mut compressor = writer.sequential_blocks_compressor(&meta);
        let mut block_rows = Vec::with_capacity(BLOCK_ROWS * width * pixel);
        for (index, y) in (0..frame.height as usize).step_by(BLOCK_ROWS).enumerate() {
            let n = BLOCK_ROWS.min(frame.height as usize - y);
            block_rows.clear();
            for _ in 0..n {
                match rows.next_row() {
                    Ok(row) => block_rows.extend_from_slice(row),
                    Err(e) => {
                        failure = Some(e);
                        return Err(exr::error::Error::Aborted);
                    }
                }
            }
            let at = BlockIndex {
                layer: 0,
                pixel_position: Vec2(0, y),
                pixel_size: Vec2(width, n),
                level: Vec2(0, 0),
            };
            let block = UncompressedBlock::from_lines(&meta.headers[0].channels, at, |line| {
                let (row, c) = (line.location.position.y() - y, order[line.location.channel]);
                let samples = &block_rows[row * width * pixel..][..width * pixel];
                line.write_samples(|x| {
                    let b = &samples[x * pixel + 4 * c..][..4];
                    u32::from_le_bytes([b[0], b[1], b[2], b[3]])
                })
                .expect("a line holds the block's width of 4-byte samples")
            });
            compressor.compress_block(index, block)?;
        }
        Ok(())
    });
    match (failure, result) {
        (Some(e), _) => Err(e),
        (None, Err(e)) => Err(e.into()),
        (None, Ok(())) => rows.finish(),
    }
}

/// The header, and for each channel in the file's (alphabetical) order its index in `channels`.
fn header(
    frame: Frame,
    channels: &[Channel],
    text: &[(String, String)],
) -> Result<(Header, Vec<usize>), BoxError> {
    let mut order: Vec<usize> = (0..channels.len()).collect();
    order.sort_by_key(|&i| channels[i].name);
    let list: SmallVec<[ChannelDescription; 5]> = order
        .iter()
        .map(|&i| {
            let kind = if channels[i].float { SampleType::F32 } else { SampleType::U32 };
            ChannelDescription::new(channels[i].name, kind, true)
        })
        .collect();
    // UTF-8 bytes, as OpenEXR's own tools and bindings read strings (the exr crate's checked
    // constructor would store `×` as the single Latin-1 byte 0xD7, which they reject).
    let to_text = |s: &str| -> Result<Text, String> {
        if s.contains('\0') {
            return Err(format!("EXR attribute text `{s}` holds a NUL character"));
        }
        Ok(Text::from_slice_unchecked(s.as_bytes()))
    };
    let mut comments = Vec::new();
    let mut software = None;
    for (key, value) in text {
        match key.as_str() {
            "Software" => software = Some(to_text(value)?),
            // An entry without a key is comment text as it is (a merge passes a part's comments on).
            "" => comments.push(value.clone()),
            _ => comments.push(format!("{key}: {value}")),
        }
    }
    let attributes = LayerAttributes {
        layer_position: Vec2(frame.x0 as i32, frame.y0 as i32),
        software_name: software,
        comments: if comments.is_empty() { None } else { Some(to_text(&comments.join("; "))?) },
        ..LayerAttributes::default()
    };
    let full = IntegerBounds::new(Vec2(0, 0), Vec2(frame.full_width as usize, frame.full_height as usize));
    let size = Vec2(frame.width as usize, frame.height as usize);
    let header = Header::new(Text::new_or_panic(""), size, list)
        .with_encoding(Compression::ZIP16, BlockDescription::ScanLines, LineOrder::Increasing)
        .with_attributes(attributes)
        .with_display_window(full);
    Ok((header, order))
}

fn smallvec_of(header: Header) -> Headers {
    let mut headers = Headers::new();
    headers.push(header);
    headers
}
