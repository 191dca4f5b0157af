//! One band traced on any rank, with the test hook's faults and a panic turned into the band's error.

use std::sync::atomic::{AtomicBool, Ordering};

use crate::accel::Work;
use crate::compile::Scene;
use crate::math::Rgb;
use crate::render::{trace_band_lanes, Bands};
use crate::shade::RayCounts;
use crate::still::Job;

use super::FAIL_BAND;

/// Set while this rank traces a band: a panic then unwinds to [`trace`], which turns it into the band's
/// error (the path every other failure takes), instead of aborting the job from the panic hook: Open MPI's
/// `mpirun` was seen to hang with the ranks left as zombies when a rank other than 0 called `MPI_Abort`.
pub(super) static TRACING: AtomicBool = AtomicBool::new(false);

/// Band `i` traced, or its error: the test hook's, or a panic while tracing.
pub(super) fn trace(
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
pub(super) struct FailBand {
    band: u32,
    panic: bool,
}

impl FailBand {
    /// `k` or `panic:k`.
    pub(super) fn parse(text: &str) -> Option<Self> {
        let text = text.trim();
        let (panic, band) = text.strip_prefix("panic:").map_or((false, text), |k| (true, k));
        Some(Self { band: band.parse().ok()?, panic })
    }
}
