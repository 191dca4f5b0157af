//! One still rendered across the ranks of an MPI job, `mpirun -n N bareray render ...` (the `mpi` feature;
//! docs/mpi.md). Every rank reads and compiles the scene; rank 0 alone checks the job and writes the files.
//! Rank 0 hands out bands of rows ([`Bands`]) a few at a time to each other rank, so a faster rank takes
//! more of them, and traces bands itself on a thread of its own while its main thread answers; the bands
//! that come back are put in order and go through the [`RowStage`](crate::render::RowStage) (the
//! postfilter, if any) into [`write_bands`], so the files are the same bytes one process writes.
//!
//! Memory stays bounded: bands are handed out at most [`AHEAD`] per rank past the first band not yet
//! written, and a band takes at most the job's band budget divided by twice the number of ranks, so the
//! bands waiting on rank 0 take at most twice the budget, whatever the image's height. Each other rank holds
//! the band it traces and the one it sends.
//!
//! Errors: before any tracing the ranks [`agree`](Ranks::agree): each reports whether its setup (parse,
//! compile, and on rank 0 the checks of [`super::check`]) worked; on a failure rank 0 prints one error
//! (its own first) and every rank exits with the same non-zero code, no file written. A failure while
//! rendering (a rank's error, a write error on rank 0) makes rank 0 abandon the files, as [`write_bands`]
//! does (temporary files removed, an existing file kept), print one `error: rank R: ...` line and abort
//! the job with exit code 1. A panic while tracing a band is caught and becomes that band's error; a panic
//! anywhere else aborts the job at once (a rank that died otherwise would leave the others waiting
//! forever), rank 0 removing its temporary files first.
//!
//! Test hook: with `BAREARAY_MPI_FAIL_BAND=k` in the environment, the rank that traces band `k` (counted
//! from 0 at the top) fails with an error instead, and with `panic:k` it panics; the tests inject faults
//! with it.

use std::collections::BTreeMap;
use std::fmt::Display;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::{Duration, Instant};

use ::mpi::collective::SystemOperation;
use ::mpi::environment::Universe;
use ::mpi::point_to_point::MatchedReceiveVec;
use ::mpi::topology::{Rank, SimpleCommunicator};
use ::mpi::traits::*;
use ::mpi::Threading;

use super::{write_bands, Job, StillError, Stop};
use crate::accel::Work;
use crate::compile::Scene;
use crate::math::Rgb;
use crate::render::{band_rows, trace_band_lanes, Bands, Progress, Traced};
use crate::shade::RayCounts;

/// Rank → 0: its setup's outcome, empty when ready, else the exit code and the error's text.
const READY: i32 = 1;
/// 0 → rank: go (empty) or stop (the exit code).
const VERDICT: i32 = 2;
/// 0 → rank: trace the band `[index]`.
const WORK: i32 = 3;
/// 0 → rank: no more bands.
const STOP: i32 = 4;
/// Rank → 0: a traced band, `[index as f32 bits, r, g, b, r, g, b, ...]` (the index travels in the
/// message: MPI guarantees tags only up to 32767).
const BAND: i32 = 5;
/// Rank → 0: the text of the error that stopped it.
const FAILED: i32 = 6;

/// Bands each other rank holds at a time: the one it traces and the next, so it never waits for work.
const IN_FLIGHT: u32 = 2;
/// Bands handed out past the first one not yet written, per rank.
pub(crate) const AHEAD: u32 = 4;
/// Bands per rank the image is cut into at least, so that ranks of unequal speed finish together.
const BANDS_PER_RANK: u32 = 8;
/// How long a rank with nothing to do sleeps between looks for a message: MPI's blocking calls spin.
const POLL: Duration = Duration::from_millis(1);

/// The test hook's variable (module documentation).
const FAIL_BAND: &str = "BAREARAY_MPI_FAIL_BAND";

/// The variables that hold the number of ranks a launcher started, most specific first: Open MPI's
/// `mpirun` sets `OMPI_COMM_WORLD_SIZE`; MPICH's and Intel MPI's Hydra and `srun --mpi=pmi2` set
/// `PMI_SIZE`; Slurm's `srun` sets `SLURM_STEP_NUM_TASKS` for the tasks of a job step (and not in a batch
/// script itself, where `SLURM_NTASKS` is set without any other rank having been started).
pub(crate) const SIZE_VARIABLES: [&str; 3] = ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "SLURM_STEP_NUM_TASKS"];

/// The variables that hold this process's rank, in the order of [`SIZE_VARIABLES`].
const RANK_VARIABLES: [&str; 3] = ["OMPI_COMM_WORLD_RANK", "PMI_RANK", "SLURM_PROCID"];

/// This process's rank when a launcher started it as one of several ([`launched`]), read from the
/// launcher's variables before MPI is initialised: for errors found while parsing the command line, which
/// only rank 0 prints.
pub fn launched_rank() -> Option<u32> {
    let var = |name: &str| std::env::var(name).ok();
    let (i, _) = SIZE_VARIABLES.iter().enumerate().find(|(_, name)| var(name).is_some())?;
    launched_in(var).then(|| var(RANK_VARIABLES[i])?.trim().parse().ok()).flatten()
}

/// Whether a launcher started this process as one of several ranks: the first of [`SIZE_VARIABLES`]
/// that is set holds a number above 1.
pub(crate) fn launched() -> bool {
    launched_in(|name| std::env::var(name).ok())
}

/// [`launched`] in the environment `var` gives.
pub fn launched_in(var: impl Fn(&str) -> Option<String>) -> bool {
    SIZE_VARIABLES
        .iter()
        .find_map(|name| var(name))
        .and_then(|size| size.trim().parse::<u32>().ok())
        .is_some_and(|size| size > 1)
}

/// This process as a rank of an MPI job: MPI is initialised while it lives and finalised when it is
/// dropped.
pub struct Ranks {
    world: SimpleCommunicator,
    /// The test hook's band.
    fail_band: Option<FailBand>,
    _universe: Universe,
}

impl Ranks {
    /// MPI initialised, when [`launched`] says a launcher started this process; `None` otherwise. From
    /// then on a panic on this rank aborts the whole job.
    pub fn start() -> Option<Self> {
        if !launched() {
            return None;
        }
        // Funneled: rank 0 traces on a thread of its own, only the main thread calls MPI.
        let (universe, _) =
            ::mpi::initialize_with_threading(Threading::Funneled).expect("MPI is initialised once");
        let report = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            report(info);
            if TRACING.load(Ordering::SeqCst) {
                return; // `trace` catches it and reports it as the band's error.
            }
            crate::output::remove_temporaries();
            // SAFETY: MPI is initialised and stays so until the process ends; MPI_Abort does not return.
            unsafe {
                ::mpi::ffi::MPI_Abort(::mpi::ffi::RSMPI_COMM_WORLD, 101);
            }
        }));
        let fail_band = std::env::var(FAIL_BAND).ok().and_then(|k| FailBand::parse(&k));
        Some(Self { world: universe.world(), fail_band, _universe: universe })
    }

    /// This rank's number, 0 to [`Ranks::size`] − 1.
    pub(crate) fn rank(&self) -> i32 {
        self.world.rank()
    }

    /// How many ranks.
    pub(crate) fn size(&self) -> i32 {
        self.world.size()
    }

    /// Whether this is rank 0, the one that writes and prints.
    pub fn is_root(&self) -> bool {
        self.rank() == 0
    }

    /// Whether every rank is ready to render, every rank calling it with its setup's outcome `ready`
    /// (`code` gives an error's exit code). When all are ready, `ready` comes back. Otherwise every rank is
    /// told to stop: rank 0 gets its own error back, to print before it calls [`Ranks::exit`] (the other
    /// ranks end as soon as MPI is finalised, and a launcher may end rank 0 then); when only another rank
    /// failed, rank 0 prints `error: rank R: ...` for the first of them and exits with its code; the other
    /// ranks exit silently with rank 0's code.
    pub fn agree<T, E: Display>(&self, ready: Result<T, E>, code: impl Fn(&E) -> i32) -> Result<T, E> {
        let code = |e: &E| code(e).clamp(1, 255) as u8;
        let root = self.world.process_at_rank(0);
        if !self.is_root() {
            let report = match &ready {
                Ok(_) => Vec::new(),
                Err(e) => std::iter::once(code(e)).chain(format!("{e:#}").into_bytes()).collect(),
            };
            root.send_with_tag(&report[..], READY);
            let (verdict, _) = root.receive_vec_with_tag::<u8>(VERDICT);
            return match verdict.first() {
                None => ready,
                Some(&stop) => self.exit(stop.into()),
            };
        }
        let mut first = None;
        for rank in 1..self.size() {
            let (report, _) = self.world.process_at_rank(rank).receive_vec_with_tag::<u8>(READY);
            if let (None, Some((&code, text))) = (&first, report.split_first()) {
                first = Some((rank, code, String::from_utf8_lossy(text).into_owned()));
            }
        }
        let stop = ready.as_ref().err().map(code).or(first.as_ref().map(|f| f.1));
        let verdict: Vec<u8> = stop.into_iter().collect();
        for rank in 1..self.size() {
            self.world.process_at_rank(rank).send_with_tag(&verdict[..], VERDICT);
        }
        match (ready, first) {
            (Ok(_), Some((rank, code, message))) => {
                eprintln!("error: rank {rank}: {message}");
                self.exit(code.into())
            }
            (ready, _) => ready,
        }
    }

    /// Renders `job` with every rank (each calls it once, after [`Ranks::agree`]); rank 0 writes the files.
    /// Gives rank 0 what all ranks traced (rays and tests summed; the seconds are rank 0's, spent tracing
    /// and waiting for bands, not writing), the other ranks `None`. `progress` hears of every tile on rank
    /// 0. A failure on any rank ends the job (module documentation): this returns only on success.
    pub fn render(
        &self,
        scene: &Scene,
        pool: &rayon::ThreadPool,
        progress: &dyn Progress,
        job: &Job,
    ) -> Option<Traced> {
        let bands = self.bands(scene, job);
        let (counts, work, seconds) = if self.is_root() {
            match write_bands(scene, pool, job, |emit| {
                self.coordinate(scene, pool, progress, job, &bands, emit)
            }) {
                Ok(traced) => (traced.counts, traced.work, traced.seconds),
                Err(e) => {
                    match e {
                        e @ StillError::Rank { .. } => eprintln!("error: {e}"),
                        e => eprintln!("error: rank 0: {e}"),
                    }
                    self.world.abort(1)
                }
            }
        } else {
            let (counts, work) = self.work(scene, pool, job, &bands);
            (counts, work, 0.0)
        };
        let mine = [
            counts.primary,
            counts.shadow,
            counts.reflection,
            counts.refraction,
            counts.ao,
            work.prim_tests,
            work.box_tests,
            work.prim_lanes,
            work.box_lanes,
        ];
        let root = self.world.process_at_rank(0);
        if !self.is_root() {
            root.reduce_into(&mine[..], SystemOperation::sum());
            return None;
        }
        let mut all = [0u64; 9];
        root.reduce_into_root(&mine[..], &mut all[..], SystemOperation::sum());
        let [primary, shadow, reflection, refraction, ao, prim_tests, box_tests, prim_lanes, box_lanes] = all;
        Some(Traced {
            counts: RayCounts { primary, shadow, reflection, refraction, ao },
            work: Work { prim_tests, box_tests, prim_lanes, box_lanes },
            seconds,
        })
    }

    /// The job's window in bands small enough that [`AHEAD`] per rank of them take at most twice the
    /// job's band budget, and at least [`BANDS_PER_RANK`] per rank where the image is tall enough.
    fn bands(&self, scene: &Scene, job: &Job) -> Bands {
        let size = self.size() as u32;
        let traced = Bands::new(scene, job.window, job.band_rows()).traced;
        let rows = band_rows(traced.width(), job.band_budget / (2 * size as usize))
            .min(traced.height().div_ceil(BANDS_PER_RANK * size));
        Bands::new(scene, job.window, rows)
    }

    /// Rank 0's part, [`write_bands`]'s producer: hands out bands, traces bands on a thread of its own,
    /// receives the others' and gives them all to the stage in order, and the finished rows to `emit`.
    /// Gives what this rank traced, and the seconds spent outside `emit`.
    fn coordinate(
        &self,
        scene: &Scene,
        pool: &rayon::ThreadPool,
        progress: &dyn Progress,
        job: &Job,
        bands: &Bands,
        emit: &mut dyn FnMut(&[Rgb]) -> Result<(), Stop>,
    ) -> Result<Traced, Option<StillError>> {
        let start = Instant::now();
        let (count, tiles) = (bands.count(), bands.tiles());
        progress.start(tiles);
        let done = AtomicU64::new(0);
        let tile_done = &|| progress.tile_done(done.fetch_add(1, Ordering::Relaxed) + 1, tiles);
        let fail_band = self.fail_band;
        std::thread::scope(|s| {
            // Returning drops `to_tracer`, which ends the tracer after its band; the scope then joins it.
            let (to_tracer, for_tracer) = mpsc::channel::<u32>();
            let (from_tracer, traced) = mpsc::channel();
            s.spawn(move || {
                for i in for_tracer {
                    let result = trace(scene, pool, job, bands, i, fail_band, tile_done);
                    if from_tracer.send((i, result)).is_err() {
                        break;
                    }
                }
            });
            let size = self.size() as usize;
            // Bands handed out and not back, by rank; this rank's are its tracer's.
            let mut in_flight = vec![0; size];
            let mut stopped = vec![false; size];
            let (mut next, mut fed) = (0, 0);
            let limit = |fed: u32| count.min(fed + AHEAD * size as u32);
            let mut waiting = BTreeMap::new();
            let mut stage = bands.stage();
            let mut mine = Traced::default();
            let mut outside = 0.0;
            loop {
                // The other ranks first: they have nothing else to do.
                for rank in 1..size {
                    let process = self.world.process_at_rank(rank as Rank);
                    while in_flight[rank] < IN_FLIGHT && next < limit(fed) {
                        process.send_with_tag(&[next][..], WORK);
                        next += 1;
                        in_flight[rank] += 1;
                    }
                    if !stopped[rank] && in_flight[rank] == 0 && next == count {
                        process.send_with_tag(&[0u32; 0][..], STOP);
                        stopped[rank] = true;
                    }
                }
                if in_flight[0] == 0 && next < limit(fed) {
                    to_tracer.send(next).expect("the tracer runs until its channel closes");
                    next += 1;
                    in_flight[0] = 1;
                }
                if fed == count {
                    break;
                }
                let message = self.world.any_process().immediate_matched_probe();
                let received = message.is_some();
                if let Some((message, status)) = message {
                    let from = status.source_rank();
                    match status.tag() {
                        BAND => {
                            let (band, _) = (message, status).matched_receive_vec::<f32>();
                            let (i, pixels) = unpack(&band, bands);
                            in_flight[from as usize] -= 1;
                            (0..bands.tiles_of(i)).for_each(|_| tile_done());
                            waiting.insert(i, pixels);
                        }
                        FAILED => {
                            let (text, _) = (message, status).matched_receive_vec::<u8>();
                            let message = String::from_utf8_lossy(&text).into_owned();
                            return Err(Some(StillError::Rank { rank: from, message }));
                        }
                        tag => unreachable!("rank {from} sent a message tagged {tag} while rendering"),
                    }
                }
                // This rank's own band, if done; when nothing came from the others, wait for it a little.
                let own = match received {
                    true => traced.try_recv().ok(),
                    false => match traced.recv_timeout(POLL) {
                        Ok(own) => Some(own),
                        Err(RecvTimeoutError::Timeout) => None,
                        Err(RecvTimeoutError::Disconnected) => unreachable!("the tracer ended early"),
                    },
                };
                match own {
                    Some((i, Ok((pixels, counts, work)))) => {
                        mine.counts += counts;
                        mine.work += work;
                        in_flight[0] = 0;
                        waiting.insert(i, pixels);
                    }
                    Some((_, Err(message))) => return Err(Some(StillError::Rank { rank: 0, message })),
                    None => {}
                }
                while let Some(pixels) = waiting.remove(&fed) {
                    fed += 1;
                    if let Some(rows) = stage.push(pixels) {
                        let clock = Instant::now();
                        emit(&rows).map_err(|Stop| None)?;
                        outside += clock.elapsed().as_secs_f64();
                    }
                }
            }
            mine.seconds = start.elapsed().as_secs_f64() - outside;
            Ok(mine)
        })
    }

    /// Another rank's part: traces the bands rank 0 sends until told to stop, and sends them back (or the
    /// error that stopped it; it then waits for rank 0 to end the job). Gives what it traced.
    fn work(&self, scene: &Scene, pool: &rayon::ThreadPool, job: &Job, bands: &Bands) -> (RayCounts, Work) {
        let root = self.world.process_at_rank(0);
        let (mut counts, mut work) = (RayCounts::default(), Work::default());
        let mut failed = false;
        loop {
            let (message, status) = loop {
                match root.immediate_matched_probe() {
                    Some(message) => break message,
                    None => std::thread::sleep(POLL),
                }
            };
            match status.tag() {
                WORK => {
                    let (band, _) = (message, status).matched_receive_vec::<u32>();
                    if failed {
                        continue;
                    }
                    match trace(scene, pool, job, bands, band[0], self.fail_band, &|| {}) {
                        Ok((pixels, c, w)) => {
                            counts += c;
                            work += w;
                            root.send_with_tag(&pack(band[0], &pixels)[..], BAND);
                        }
                        Err(message) => {
                            root.send_with_tag(message.as_bytes(), FAILED);
                            failed = true;
                        }
                    }
                }
                STOP => {
                    let _ = (message, status).matched_receive_vec::<u32>();
                    break;
                }
                tag => unreachable!("rank 0 sent a message tagged {tag} while rendering"),
            }
        }
        if failed {
            self.exit(1);
        }
        (counts, work)
    }

    /// Finalises MPI and ends the process with exit code `code`.
    pub fn exit(&self, code: i32) -> ! {
        // SAFETY: MPI is initialised; the process ends right after, so nothing calls MPI again.
        unsafe {
            ::mpi::ffi::MPI_Finalize();
        }
        std::process::exit(code)
    }
}

/// Set while this rank traces a band: a panic then unwinds to [`trace`], which turns it into the band's
/// error (the path every other failure takes), instead of aborting the job from the panic hook: Open MPI's
/// `mpirun` was seen to hang with the ranks left as zombies when a rank other than 0 called `MPI_Abort`.
static TRACING: AtomicBool = AtomicBool::new(false);

/// Band `i` traced, or its error: the test hook's, or a panic while tracing.
fn trace(
    scene: &Scene,
    pool: &rayon::ThreadPool,
    job: &Job,
    bands: &Bands,
    i: u32,
    fail_band: Option<FailBand>,
    tile_done: &(dyn Fn() + Sync),
) -> Result<(Vec<Rgb>, RayCounts, Work), String> {
    TRACING.store(true, Ordering::SeqCst);
    let traced = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        match fail_band {
            Some(FailBand { band, panic: false }) if band == i => {
                return Err(format!("band {i}: failed on purpose ({FAIL_BAND} is set)"))
            }
            Some(FailBand { band, panic: true }) if band == i => {
                panic!("on purpose ({FAIL_BAND})")
            }
            _ => {}
        }
        Ok(trace_band_lanes(scene, job.lanes, pool, bands, i, tile_done))
    }));
    TRACING.store(false, Ordering::SeqCst);
    traced.unwrap_or_else(|payload| {
        let what = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("a panic");
        Err(format!("band {i}: panicked: {what}"))
    })
}

/// The test hook's fault: band `band` fails with an error, or panics.
#[derive(Clone, Copy, Debug)]
struct FailBand {
    band: u32,
    panic: bool,
}

impl FailBand {
    /// `k` or `panic:k`.
    fn parse(text: &str) -> Option<Self> {
        let text = text.trim();
        let (panic, band) = text.strip_prefix("panic:").map_or((false, text), |k| (true, k));
        Some(Self { band: band.parse().ok()?, panic })
    }
}

/// Band `i`'s pixels as a [`BAND`] message.
fn pack(i: u32, pixels: &[Rgb]) -> Vec<f32> {
    let mut message = Vec::with_capacity(1 + 3 * pixels.len());
    message.push(f32::from_bits(i));
    message.extend(pixels.iter().flat_map(|p| [p.x, p.y, p.z]));
    message
}

/// A [`BAND`] message's band and pixels.
fn unpack(message: &[f32], bands: &Bands) -> (u32, Vec<Rgb>) {
    let (&i, values) = message.split_first().expect("a band message holds its band's index");
    let i = i.to_bits();
    let rows = bands.rows_of(i);
    let pixels = bands.traced.width() as usize * (rows.end - rows.start) as usize;
    assert!(i < bands.count() && values.len() == 3 * pixels, "band {i}: {} values", values.len());
    (i, values.chunks_exact(3).map(|c| Rgb::new(c[0], c[1], c[2])).collect())
}
