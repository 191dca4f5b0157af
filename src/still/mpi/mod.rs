//! One still rendered across the ranks of an MPI job, `mpirun -n N bareray render ...` (the `mpi` feature;
//! docs/mpi.md). Every rank reads and compiles the scene; rank 0 alone checks the job and writes the files.
//! Rank 0 hands out bands of rows (`render::Bands`) a few at a time to each other rank, so a faster rank
//! takes more of them, and traces bands itself on a thread of its own while its main thread answers; the
//! bands that come back are put in order and go through the band stage (`render::RowStage`, the postfilter if
//! any) into `still::write_bands`, so the files are the same bytes one process writes.
//!
//! Memory stays bounded: bands are handed out at most `AHEAD` per rank past the first band not yet
//! written, and a band takes at most the job's band budget divided by twice the number of ranks, so the
//! bands waiting on rank 0 take at most twice the budget, whatever the image's height. Each other rank holds
//! the band it traces and the one it sends.
//!
//! Errors: before any tracing the ranks [`agree`](Ranks::agree): each reports whether its setup (parse,
//! compile, and on rank 0 the checks of [`super::check()`]) worked; on a failure rank 0 prints one error
//! (its own first) and every rank exits with the same non-zero code, no file written. A failure while
//! rendering (a rank's error, a write error on rank 0) makes rank 0 abandon the files, as `write_bands`
//! does (temporary files removed, an existing file kept), print one `error: rank R: ...` line and abort
//! the job with exit code 1. A panic while tracing a band is caught and becomes that band's error; a panic
//! anywhere else aborts the job at once (a rank that died otherwise would leave the others waiting
//! forever), rank 0 removing its temporary files first.
//!
//! Test hook: with `BAREARAY_MPI_FAIL_BAND=k` in the environment, the rank that traces band `k` (counted
//! from 0 at the top) fails with an error instead, and with `panic:k` it panics; the tests inject faults
//! with it.

use std::sync::atomic::Ordering;
use std::time::Duration;

use ::mpi::environment::Universe;
use ::mpi::topology::SimpleCommunicator;
use ::mpi::traits::*;
use ::mpi::Threading;

mod agree;
mod coordinator;
mod message;
mod render;
mod trace;
mod worker;

use trace::{FailBand, TRACING};

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
const AHEAD: u32 = 4;
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
const SIZE_VARIABLES: [&str; 3] = ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "SLURM_STEP_NUM_TASKS"];

/// The variables that hold this process's rank, in the order of [`SIZE_VARIABLES`].
const RANK_VARIABLES: [&str; 3] = ["OMPI_COMM_WORLD_RANK", "PMI_RANK", "SLURM_PROCID"];

/// This process's rank when a launcher started it as one of several ([`launched_in`]), read from the
/// launcher's variables before MPI is initialised: for errors found while parsing the command line, which
/// only rank 0 prints.
pub fn launched_rank() -> Option<u32> {
    let var = |name: &str| std::env::var(name).ok();
    let (i, _) = SIZE_VARIABLES.iter().enumerate().find(|(_, name)| var(name).is_some())?;
    launched_in(var).then(|| var(RANK_VARIABLES[i])?.trim().parse().ok()).flatten()
}

/// [`launched_in`] in this process's environment.
fn launched() -> bool {
    launched_in(|name| std::env::var(name).ok())
}

/// Whether a launcher started this process as one of several ranks, in the environment `var` gives: the
/// first launcher variable for the number of ranks that is set (Open MPI's, Hydra's or Slurm's, most
/// specific first) holds a number above 1.
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
    /// MPI initialised, when [`launched_in`] says a launcher started this process; `None` otherwise. From
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

    /// Finalises MPI and ends the process with exit code `code`.
    pub fn exit(&self, code: i32) -> ! {
        // SAFETY: MPI is initialised; the process ends right after, so nothing calls MPI again.
        unsafe {
            ::mpi::ffi::MPI_Finalize();
        }
        std::process::exit(code)
    }
}
