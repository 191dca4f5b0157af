//! What is checked before a still is traced, so that a render that cannot finish fails at once, with the
//! reason and what would fit, instead of after hours or with an allocation abort.

use std::path::Path;

use super::{Job, StillError};
use crate::compile::Scene;
use crate::output::{self, held, pixel_bytes, Format};
use crate::scene::desc::{Filter, Pattern};

/// The largest image side bareray renders: sample positions are f32 pixel coordinates, exact to the
/// half pixel below 2^23. PNG's limit (2^31 − 1 rows and columns) and EXR's (2^31 − 1, its coordinates
/// are i32) lie beyond it.
pub(crate) const MAX_SIDE: u32 = 1 << 23;

/// Memory a still's render will take beyond the compiled scene, in bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Estimate {
    /// Bands alive at once (traced, held by the postfilter, finished, encoded and queued, being written),
    /// and for TIFF and JPEG, which encode the image whole, its stored bytes.
    pub(crate) bands: u64,
    /// Working memory of the tiles in flight, one per thread (supersampling, filter aprons, adaptive
    /// lattices).
    pub(crate) tiles: u64,
    /// All of it.
    pub(crate) total: u64,
    /// The machine's available memory (`MemAvailable`), where the system tells.
    pub(crate) available: Option<u64>,
}

/// Something a still runs into.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Limit {
    /// An image side past 2²³ pixels (`MAX_SIDE`).
    Side,
    /// More memory than is available.
    Memory,
    /// A file larger than its disk's free space.
    Disk,
}

/// Checks `job` before any tracing, on `threads` render threads: the image's size against 2²³ pixels a side,
/// both output files writable, the memory the bands will take against the memory available, and for the
/// formats whose size is known in advance (PPM, HDR) the file against the free space of its disk. Returns
/// the memory estimate, or the refusal with what would fit.
pub fn check(scene: &Scene, job: &Job, threads: usize) -> Result<Estimate, StillError> {
    check_with(scene, job, threads, available_memory(), free_space(&job.output))
}

/// [`check`] against the given available memory and free disk space (`None`: unknown, not checked).
fn check_with(
    scene: &Scene,
    job: &Job,
    threads: usize,
    available: Option<u64>,
    free_disk: Option<u64>,
) -> Result<Estimate, StillError> {
    let (width, height) = (scene.camera.width, scene.camera.height);
    if width > MAX_SIDE || height > MAX_SIDE {
        return Err(refuse(format!(
            "{width}x{height}: bareray renders images up to {MAX_SIDE} pixels a side (sample positions are \
             f32 pixel coordinates, exact to the half pixel below 2^23); render regions of a smaller camera \
             or lower the resolution"
        )));
    }
    let (w, h) = (u64::from(job.window.width()), u64::from(job.window.height()));
    let stored = w * h * pixel_bytes(job.format, job.write.bit_depth) as u64;
    let side = u64::from(held::JPEG_MAX_SIDE);
    if job.format == Format::Jpeg && (w > side || h > side) {
        return Err(refuse(format!(
            "{}: JPEG stores sizes in 16 bits, at most {side} pixels a side, and the image is {w}x{h}; write \
             PNG, EXR or PPM",
            job.output.display()
        )));
    }
    if job.format == Format::Tiff && stored > held::TIFF_MAX_BYTES {
        return Err(refuse(format!(
            "{}: the image takes {} and a classic TIFF holds at most 4 GiB; write PNG, EXR or PPM",
            job.output.display(),
            bytes(stored)
        )));
    }
    output::check_writable(&job.output)?;
    if let Some((_, path)) = &job.aov {
        output::check_writable(path)?;
    }
    let estimate = Estimate { available, ..estimate(scene, job, threads) };
    if let Some(available) = available {
        if estimate.total > available {
            let per_column = estimate.bands as f64 / f64::from(job.window.width());
            let widest = (available as f64 * 0.8 / per_column) as u64;
            return Err(refuse(format!(
                "{}: the render needs about {} of memory ({} for bands of {} rows, {} for the tiles in \
                 flight), and {} is available; a region or image at most {widest} pixels wide would fit",
                job.output.display(),
                bytes(estimate.total),
                bytes(estimate.bands),
                job.band_rows(),
                bytes(estimate.tiles),
                bytes(available),
            )));
        }
    }
    check_disk(job, free_disk)?;
    Ok(estimate)
}

/// The memory [`check`] compares with the available memory.
pub(crate) fn estimate(scene: &Scene, job: &Job, threads: usize) -> Estimate {
    let postfilter = u64::from(scene.render.postfilter == crate::scene::desc::PostFilter::Lecture3x3);
    let columns = u64::from(job.window.width()) + 2 * postfilter;
    let rows = job.band_rows().min(job.window.height() + 2 * postfilter as u32);
    let band = columns * u64::from(rows);
    let rgb = std::mem::size_of::<crate::math::Rgb>() as u64;
    let stored = pixel_bytes(job.format, job.write.bit_depth) as u64;
    // Traced, held back, finished; stored bytes being made, queued and written.
    let mut per_pixel = 3 * rgb + 3 * stored;
    if let Some((which, _)) = &job.aov {
        let channels = crate::aov::channels(which, scene.geometry.len()).len() as u64;
        // Hits (t and id) and the samples made, queued and written.
        per_pixel += 8 + 3 * 4 * channels;
    }
    // TIFF and JPEG hold the whole image's stored bytes until they encode it.
    let whole = if job.format.held_whole() {
        u64::from(job.window.width()) * u64::from(job.window.height()) * stored
    } else {
        0
    };
    let bands = band * per_pixel + whole;
    let tiles = threads as u64 * tile_bytes(scene.render.pattern, scene.render.filter);
    let total = bands + tiles;
    Estimate { bands, tiles, total, available: available_memory() }
}

/// The largest working set one tile's trace takes, by the sampling pattern and filter.
fn tile_bytes(pattern: Pattern, filter: Option<Filter>) -> u64 {
    let tile = u64::from(crate::render::TILE);
    let rgb = std::mem::size_of::<crate::math::Rgb>() as u64;
    let samples = match pattern {
        Pattern::Adaptive { depth, .. } => {
            let side = tile * (1 << depth.min(16)) + 1;
            // The lattice of optional colours, and the split squares' set.
            return side * side * (rgb + 4) * 2;
        }
        Pattern::HalfPixel => (2 * tile + 1) * (2 * tile + 1),
        // One ray a pixel, one more per sphere reaching into it (at most 64) and the remainder's: the list
        // of parts, and their colours as they are summed.
        Pattern::Coverage => {
            let part = std::mem::size_of::<crate::render::CoveragePart>() as u64 + 8;
            return tile * tile * 66 * part + (1 << 20);
        }
        _ => {
            let side = tile + 2 * u64::from(filter.map_or(0, |f| f.apron()));
            side * side * pattern.rays_per_pixel() as u64
        }
    };
    samples * rgb + (1 << 20)
}

/// Refuses a PPM or HDR file larger than its disk's free space (their sizes are known before writing;
/// PNG's and EXR's depend on how well the image compresses).
fn check_disk(job: &Job, free: Option<u64>) -> Result<(), StillError> {
    if !matches!(job.format, Format::Ppm | Format::Hdr) {
        return Ok(());
    }
    let size = u64::from(job.window.width())
        * u64::from(job.window.height())
        * pixel_bytes(job.format, job.write.bit_depth) as u64;
    match free {
        Some(free) if size > free => Err(refuse(format!(
            "{}: the image takes {} and its disk has {} free",
            job.output.display(),
            bytes(size),
            bytes(free)
        ))),
        _ => Ok(()),
    }
}

fn refuse(why: String) -> StillError {
    StillError::Refused(why)
}

/// `n` bytes in the largest unit that keeps a number ≥ 1 (GiB, MiB, KiB).
pub(crate) fn bytes(n: u64) -> String {
    match n {
        n if n >= 1 << 30 => format!("{:.1} GiB", n as f64 / f64::from(1u32 << 30)),
        n if n >= 1 << 20 => format!("{:.1} MiB", n as f64 / f64::from(1u32 << 20)),
        n if n >= 1 << 10 => format!("{:.1} KiB", n as f64 / 1024.0),
        n => format!("{n} bytes"),
    }
}

/// `MemAvailable` from /proc/meminfo (Linux), in bytes.
fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Free bytes for an unprivileged user on the file system of `path`'s directory.
#[cfg(target_os = "linux")]
fn free_space(path: &Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let name = std::ffi::CString::new(dir.as_os_str().as_bytes()).ok()?;
    // SAFETY: `name` is a NUL-terminated path; statvfs fills the zeroed struct or fails.
    unsafe {
        let mut stat: libc::statvfs = std::mem::zeroed();
        (libc::statvfs(name.as_ptr(), &mut stat) == 0).then(|| stat.f_bavail as u64 * stat.f_frsize as u64)
    }
}

#[cfg(not(target_os = "linux"))]
fn free_space(_: &Path) -> Option<u64> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::WriteOptions;

    fn scene(width: u32, height: u32) -> Scene {
        let mut desc =
            crate::io::toml::parse(Path::new("t.toml"), "[[spheres]]\ncenter = [0, 0, -5]\nradius = 1\n")
                .expect("scene parses");
        (desc.camera.width, desc.camera.height) = (width, height);
        Scene::compile(&desc).expect("scene compiles")
    }

    /// Memory for the bands beyond what is available is refused, with the width that would fit; so is a
    /// PPM larger than the free disk space; both pass with room to spare.
    #[test]
    fn memory_and_disk_beyond_what_there_is_are_refused() {
        let dir = std::env::temp_dir();
        let scene = scene(4000, 3000);
        let job = Job::whole(&scene, &dir.join("bareray-check.ppm"), WriteOptions::default()).unwrap();
        let need = estimate(&scene, &job, 2).total;
        assert!(need > 4000 * 16 * 36, "{need}");
        let err = check_with(&scene, &job, 2, Some(need / 2), None).unwrap_err().to_string();
        assert!(err.contains("needs about") && err.contains("pixels wide would fit"), "{err}");
        let widest: u64 = err.split("at most ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
        assert!(widest < 4000 / 2 && widest > 4000 / 4, "{err}");
        let file = 4000 * 3000 * 3;
        let err = check_with(&scene, &job, 2, Some(need * 2), Some(file - 1)).unwrap_err().to_string();
        assert!(err.contains("the image takes 34.3 MiB"), "{err}");
        assert!(check_with(&scene, &job, 2, Some(need * 2), Some(file + 1)).is_ok());
        // PNG's size is not known before it is written: no disk check.
        let png = Job::whole(&scene, &dir.join("bareray-check.png"), WriteOptions::default()).unwrap();
        assert!(check_with(&scene, &png, 2, Some(need * 2), Some(1)).is_ok());
    }
}
