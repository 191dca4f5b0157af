//! Resumable stills: with a settings hash in the [`super::Job`], every chunk of finished rows is also
//! appended to a side file beside the output (`.NAME.resume`), compressed, as the bytes the writers took
//! (image and AOVs). A render that stops — Ctrl-C, a kill, a full disk — leaves the side file; the same
//! command run again replays its rows into the writers and traces only the rest, and the file is the bytes
//! an uninterrupted render writes (a window that starts lower gives the same bits). A side file whose hash
//! differs (another scene, size or setting) is not used: it is replaced. Once the output is in place the
//! side file is removed.

use std::fs::{self, File, OpenOptions};
use std::io::{BufReader, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use crate::output::BoxError;

/// First line of a side file, with the format's version.
const MAGIC: &[u8; 16] = b"bareray resume1\n";

/// The side file of a resumable still.
pub(crate) struct Resume {
    path: PathBuf,
    file: File,
    /// Window rows already finished.
    pub(crate) rows: u32,
}

/// The side file of `output`: `.NAME.resume` in the same directory.
pub(crate) fn side_path(output: &Path) -> PathBuf {
    let name = output.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let dir = output.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    dir.join(format!(".{name}.resume"))
}

/// One record: rows, then the image's and the AOVs' stored bytes, each zlib-compressed with its length.
struct Record {
    rows: u32,
    image: Vec<u8>,
    aov: Vec<u8>,
}

impl Resume {
    /// Opens the side file of `output` for settings `hash`: an existing one with the same hash is kept up
    /// to its last whole record, and its records are handed to `replay` in order (image bytes, AOV bytes);
    /// any other is replaced by an empty one.
    pub(crate) fn open(
        output: &Path,
        hash: u64,
        mut replay: impl FnMut(Vec<u8>, Vec<u8>) -> Result<(), BoxError>,
    ) -> Result<Self, BoxError> {
        let path = side_path(output);
        let header = [&MAGIC[..], &hash.to_le_bytes()].concat();
        let mut rows = 0;
        let mut kept = 0;
        if let Ok(file) = File::open(&path) {
            let mut reader = BufReader::new(file);
            let mut head = vec![0; header.len()];
            if reader.read_exact(&mut head).is_ok() && head == header {
                kept = header.len() as u64;
                while let Some((record, size)) = read_record(&mut reader) {
                    replay(inflate(&record.image)?, inflate(&record.aov)?)?;
                    rows += record.rows;
                    kept += size;
                }
            }
        }
        let mut file = OpenOptions::new().read(true).write(true).create(true).truncate(false).open(&path)?;
        if kept == 0 {
            file.set_len(0)?;
            file.write_all(&header)?;
        } else {
            // A record cut short by the interruption is dropped.
            file.set_len(kept)?;
            file.seek(SeekFrom::End(0))?;
        }
        Ok(Self { path, file, rows })
    }

    /// Appends finished rows: `rows` window rows as the image writer's bytes and the AOV writer's (empty
    /// without AOVs). Flushed to the system at once, so a killed process keeps them.
    pub(crate) fn record(&mut self, rows: u32, image: &[u8], aov: &[u8]) -> Result<(), BoxError> {
        let (image, aov) = (deflate(image)?, deflate(aov)?);
        let mut out = Vec::with_capacity(20 + image.len() + aov.len());
        out.extend_from_slice(&rows.to_le_bytes());
        for part in [&image, &aov] {
            out.extend_from_slice(&(part.len() as u64).to_le_bytes());
            out.extend_from_slice(part);
        }
        self.file.write_all(&out)?;
        self.rows += rows;
        Ok(())
    }

    /// The render is complete and its files are in place: the side file goes.
    pub(crate) fn finish(self) -> std::io::Result<()> {
        drop(self.file);
        fs::remove_file(&self.path)
    }

    /// Where the side file is.
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }
}

/// The next whole record and its size in bytes; `None` at the end or at a record cut short.
fn read_record(reader: &mut impl Read) -> Option<(Record, u64)> {
    let mut word = [0u8; 4];
    reader.read_exact(&mut word).ok()?;
    let rows = u32::from_le_bytes(word);
    let mut part = || -> Option<Vec<u8>> {
        let mut len = [0u8; 8];
        reader.read_exact(&mut len).ok()?;
        let len = usize::try_from(u64::from_le_bytes(len)).ok()?;
        let mut bytes = vec![0; len];
        reader.read_exact(&mut bytes).ok()?;
        Some(bytes)
    };
    let (image, aov) = (part()?, part()?);
    let size = 20 + image.len() as u64 + aov.len() as u64;
    Some((Record { rows, image, aov }, size))
}

fn deflate(bytes: &[u8]) -> Result<Vec<u8>, BoxError> {
    let mut compressor = fdeflate::Compressor::new(Vec::new())?;
    compressor.write_data(bytes)?;
    Ok(compressor.finish()?)
}

fn inflate(bytes: &[u8]) -> Result<Vec<u8>, BoxError> {
    fdeflate::decompress_to_vec(bytes).map_err(|e| format!("a resume record is corrupt: {e:?}").into())
}
