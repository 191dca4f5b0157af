//! Stills of any size: the image (or a region of it) is rendered band by band and each finished band is
//! encoded and let go while the next is traced, so memory is the scene plus a few bands whatever the
//! image's height ([`render`]); before that, [`check()`] refuses what cannot work — a size past a format's or
//! bareray's limits, a render whose bands would not fit in memory, a file that would not fit on its disk —
//! with the reason and what would fit. Regions written separately are pasted back together by [`merge`].

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{sync_channel, SyncSender};
use std::sync::Mutex;

use thiserror::Error;

use crate::aov::{self, Aov};
use crate::compile::Scene;
use crate::math::Rgb;
use crate::output::{self, Format, Frame, OutputError, WriteOptions};
use crate::render::{render_window_lanes, Progress, Traced, Window};

mod check;
mod describe;
pub mod merge;
#[cfg(feature = "mpi")]
pub mod mpi;
pub(crate) mod resume;

pub use check::{check, Estimate, Limit};
pub use describe::describe;
use resume::Resume;

/// Bytes of linear RGB a band may hold by default: at 32768 columns, 80 rows.
pub(crate) const BAND_BUDGET: usize = 32 << 20;

/// The fewest bands an image is cut into by default, however small: one band is traced while the one before
/// is encoded, so memory holds about two bands' pixels, not the whole image (measured peaks:
/// docs/perf-log/2026-11-scale.md, "Peak memory in KiB, and bands"); and the render ends by waiting for the
/// last band's encoding, a sixteenth of the image's rather than a quarter's (PERF.md, Register: "Sixteen
/// bands").
pub(crate) const MIN_BANDS: u32 = 16;

/// One still to render: where it goes, how it is written, which part of the image.
#[derive(Clone, Debug)]
pub struct Job {
    /// The image file.
    pub output: PathBuf,
    /// Its format (by its extension, [`Format::from_extension`]).
    pub format: Format,
    /// Transfer, bit depth, text chunks.
    pub write: WriteOptions,
    /// The part of the image to render (the whole image unless a region is asked for).
    pub window: Window,
    /// Rays per packet: 1, 4, 8 or 16.
    pub lanes: usize,
    /// AOVs to write beside the image, and their file.
    pub aov: Option<(Vec<Aov>, PathBuf)>,
    /// Bytes of linear RGB per band (`BAND_BUDGET` unless set).
    pub band_budget: usize,
    /// The fewest bands the window is cut into where the budget would allow bigger ones (`MIN_BANDS`
    /// unless set; 1 lets the budget alone decide).
    pub min_bands: u32,
    /// Resumable (`resume`): the hash of everything that decides the files' bytes (scene, settings,
    /// window, format), which a side file must match to be used. `None`: no side file.
    pub resume: Option<u64>,
}

impl Job {
    /// The whole image of `scene` into `output`, in the format its extension names.
    pub fn whole(scene: &Scene, output: &Path, write: WriteOptions) -> Result<Self, OutputError> {
        Ok(Self {
            output: output.to_owned(),
            format: Format::from_extension(output)?,
            write,
            window: Window::whole(scene.camera.width, scene.camera.height),
            lanes: 16,
            aov: None,
            band_budget: BAND_BUDGET,
            min_bands: MIN_BANDS,
            resume: None,
        })
    }

    /// Where the file's pixels sit in the full image.
    pub(crate) fn frame(&self, scene: &Scene) -> Frame {
        let w = self.window;
        Frame {
            width: w.width(),
            height: w.height(),
            x0: w.x0,
            y0: w.y0,
            full_width: scene.camera.width,
            full_height: scene.camera.height,
        }
    }

    /// Rows per band: what the budget holds, but no more than a [`Job::min_bands`]th of the window's height,
    /// in whole tiles.
    pub fn band_rows(&self) -> u32 {
        let tile = crate::render::TILE;
        let rows = crate::render::band_rows(self.window.width(), self.band_budget);
        rows.min(self.window.height().div_ceil(self.min_bands.max(1)).div_ceil(tile) * tile)
    }
}

/// Why a still was not rendered or written.
#[derive(Debug, Error)]
pub enum StillError {
    /// Refused before tracing: the reason and what would fit.
    #[error("{0}")]
    Refused(String),
    /// The image or AOV file could not be written (nothing is left at its path).
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The render was interrupted ([`interrupt`]); nothing was written at the output's path.
    #[error("interrupted{}", match .0 { Some(p) => format!("; the finished rows are kept in {}: run the same command again to go on", p.display()), None => String::new() })]
    Interrupted(Option<PathBuf>),
    /// The resume side file could not be read or written.
    #[error("{path}: {cause}")]
    Resume {
        /// The side file.
        path: PathBuf,
        /// What went wrong.
        cause: output::BoxError,
    },
    /// A rank of a distributed render ([`mpi`]) failed: which, and its error.
    #[cfg(feature = "mpi")]
    #[error("rank {rank}: {message}")]
    Rank {
        /// The failing rank.
        rank: i32,
        /// Its error.
        message: String,
    },
}

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Asks running stills to stop at the next band: they end with [`StillError::Interrupted`], leave no
/// output file, and keep their side file when resumable. Safe to call from a signal handler.
pub fn interrupt() {
    INTERRUPTED.store(true, Ordering::Relaxed);
}

/// Makes SIGINT and SIGTERM [`interrupt`] stills (Unix): a second signal ends the process at once.
#[cfg(unix)]
pub fn catch_interrupts() {
    extern "C" fn on_signal(signal: libc::c_int) {
        if INTERRUPTED.swap(true, Ordering::Relaxed) {
            // SAFETY: _exit is async-signal-safe.
            unsafe { libc::_exit(128 + signal) };
        }
    }
    // SAFETY: the handler only touches an atomic and calls _exit, both async-signal-safe.
    unsafe {
        libc::signal(libc::SIGINT, on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t);
        libc::signal(libc::SIGTERM, on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t);
    }
}

/// Signals stay as they are where there is no Unix signal API.
#[cfg(not(unix))]
pub(crate) fn catch_interrupts() {}

/// Renders `job` on `pool`, reporting tiles to `progress`: bands of rows go through the postfilter, are
/// turned into the format's bytes, and are handed to a writer thread (one more for the AOVs) through a
/// channel that holds one band, so tracing, encoding and writing overlap and at most a few bands are alive.
/// Each file is written atomically: on any failure neither is left half-written and an existing file of
/// the same name is kept. The bytes are those `output::write_image_with` writes for the whole image that
/// [`crate::render::render`] makes (cropped to the region for a region).
pub fn render(
    scene: &Scene,
    pool: &rayon::ThreadPool,
    progress: &dyn Progress,
    job: &Job,
) -> Result<Traced, StillError> {
    write_bands_resuming(scene, pool, job, |emit, first| {
        if first == job.window.y1 {
            // Every row came from the side file.
            return Ok(Traced::default());
        }
        let window = Window { y0: first, ..job.window };
        render_window_lanes(scene, job.lanes, pool, progress, window, job.band_rows(), emit)
            .map_err(|Stop| None)
    })
}

/// A writer has failed: the producer of rows should stop (the writer's error is what gets reported).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stop;

/// Writes `job`'s files from the rows `produce` makes: it is called with `emit`, which takes the window's
/// finished rows in order (one or more whole rows a call), turns them into the format's bytes (and makes
/// the AOVs of the same rows), and queues them for the writer threads; `emit` returns [`Stop`] once a
/// writer has failed. `produce` ends with its result, or with `Err(None)` when told to stop, or
/// `Err(Some(e))` when it failed itself — then the files are abandoned (their temporary files removed,
/// existing files kept) and `e` is returned. [`render`] produces the rows by tracing bands here; a
/// distributed render receives them from elsewhere. `job.resume` is not used here (see [`render`]).
#[cfg(feature = "mpi")]
pub(crate) fn write_bands<T>(
    scene: &Scene,
    pool: &rayon::ThreadPool,
    job: &Job,
    produce: impl FnOnce(&mut dyn FnMut(&[Rgb]) -> Result<(), Stop>) -> Result<T, Option<StillError>>,
) -> Result<T, StillError> {
    let job = Job { resume: None, ..job.clone() };
    write_bands_resuming(scene, pool, &job, |emit, _| produce(emit))
}

/// `write_bands` (built with the `mpi` feature), resumable when `job.resume` is set: the side file's rows (if
/// its hash matches) are replayed into the writers first, `produce` is told the first window row still to
/// make, and every chunk of rows is recorded before it is written; the side file goes once the files are in
/// place.
fn write_bands_resuming<T>(
    scene: &Scene,
    pool: &rayon::ThreadPool,
    job: &Job,
    produce: impl FnOnce(&mut dyn FnMut(&[Rgb]) -> Result<(), Stop>, u32) -> Result<T, Option<StillError>>,
) -> Result<T, StillError> {
    let frame = job.frame(scene);
    let (format, window) = (job.format, job.window);
    // The first writer to fail is the cause; the other then fails for want of rows.
    let failure = Mutex::new(None);
    let mut interrupted = false;
    let (produced, resume) = std::thread::scope(|s| {
        let (image_tx, image_rx) = sync_channel::<Vec<u8>>(1);
        let failed = &failure;
        s.spawn(move || {
            let written =
                output::write_rows(&job.output, format, &job.write, frame, &mut image_rx.into_iter());
            keep_first(failed, written);
        });
        let aov_tx = job.aov.as_ref().map(|(which, path)| {
            let (tx, rx) = sync_channel::<Vec<u8>>(1);
            let channels = aov::channels(which, scene.geometry.len());
            s.spawn(move || {
                let written = output::write_channels(path, frame, &channels, &[], &mut rx.into_iter());
                keep_first(failed, written);
            });
            (which, tx)
        });
        let mut resume = match job.resume.map(|hash| open_resume(job, hash, &image_tx, &aov_tx)) {
            None => None,
            Some(Ok(side)) => Some(side),
            // Dropping the senders ends the writers' rows: they fail and remove their temporary files.
            Some(Err(e)) => return (Err(Some(e)), None),
        };
        let first = window.y0 + resume.as_ref().map_or(0, |r| r.rows);
        let mut y = first;
        let mut record_failure = None;
        let mut emit = |rows: &[Rgb]| -> Result<(), Stop> {
            if INTERRUPTED.load(Ordering::Relaxed) {
                interrupted = true;
                return Err(Stop);
            }
            let n = (rows.len() / window.width() as usize) as u32;
            let samples = pool.install(|| output::to_samples(rows, window.width(), format, &job.write));
            let aov = aov_tx.as_ref().map(|(which, _)| {
                let band = Window { y0: y, y1: y + n, ..window };
                aov::samples(scene, job.lanes, pool, band, which)
            });
            if let Some(side) = &mut resume {
                if let Err(cause) = side.record(n, &samples, aov.as_deref().unwrap_or(&[])) {
                    record_failure = Some(StillError::Resume { path: side.path().to_owned(), cause });
                    return Err(Stop);
                }
            }
            send(&image_tx, samples)?;
            if let (Some((_, tx)), Some(aov)) = (&aov_tx, aov) {
                send(tx, aov)?;
            }
            y += n;
            Ok(())
        };
        let produced = produce(&mut emit, first);
        // Dropping the senders ends the writers' rows: complete files, or (when the rows stopped short)
        // failed writes that remove their temporary files.
        drop((image_tx, aov_tx));
        (record_failure.map_or(produced, |e| Err(Some(e))), resume)
    });
    // The scope has joined the writers.
    if interrupted {
        return Err(StillError::Interrupted(resume.map(|r| r.path().to_owned())));
    }
    match (produced, failure.into_inner().expect("no writer panics holding the lock")) {
        (Err(Some(e)), _) => Err(e),
        (_, Some(e)) => Err(e.into()),
        (Ok(done), None) => {
            if let Some(side) = resume {
                // The output is complete; a side file that cannot be removed is only clutter.
                let _ = side.finish();
            }
            Ok(done)
        }
        (Err(None), None) => unreachable!("rows stop only when a writer failed or on an interrupt"),
    }
}

/// Opens `job`'s side file for `hash`, replaying its finished rows into the writers.
fn open_resume(
    job: &Job,
    hash: u64,
    image: &SyncSender<Vec<u8>>,
    aov: &Option<(&Vec<Aov>, SyncSender<Vec<u8>>)>,
) -> Result<Resume, StillError> {
    let replay = |rows: Vec<u8>, aov_rows: Vec<u8>| -> Result<(), output::BoxError> {
        send(image, rows).map_err(|_| "the image writer stopped")?;
        if let Some((_, tx)) = aov {
            send(tx, aov_rows).map_err(|_| "the AOV writer stopped")?;
        }
        Ok(())
    };
    Resume::open(&job.output, hash, replay)
        .map_err(|cause| StillError::Resume { path: resume::side_path(&job.output), cause })
}

fn keep_first(slot: &Mutex<Option<OutputError>>, result: Result<(), OutputError>) {
    if let Err(e) = result {
        slot.lock().expect("no writer panics holding the lock").get_or_insert(e);
    }
}

fn send(to: &SyncSender<Vec<u8>>, rows: Vec<u8>) -> Result<(), Stop> {
    to.send(rows).map_err(|_| Stop)
}
