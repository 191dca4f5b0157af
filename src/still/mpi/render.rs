//! One still rendered by every rank: the image cut into bands, rank 0 coordinating and writing, the others
//! working, and the rays and tests of all ranks summed on rank 0.

use ::mpi::collective::SystemOperation;
use ::mpi::traits::*;

use crate::accel::Work;
use crate::compile::Scene;
use crate::render::{band_rows, Bands, Progress, Traced};
use crate::shade::RayCounts;
use crate::still::{write_bands, Job, StillError};

use super::{Ranks, BANDS_PER_RANK};

impl Ranks {
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
    ///
    /// [`AHEAD`]: super::AHEAD
    fn bands(&self, scene: &Scene, job: &Job) -> Bands {
        let size = self.size() as u32;
        let traced = Bands::new(scene, job.window, job.band_rows()).traced;
        let rows = band_rows(traced.width(), job.band_budget / (2 * size as usize))
            .min(traced.height().div_ceil(BANDS_PER_RANK * size));
        Bands::new(scene, job.window, rows)
    }
}
