//! The loop of every rank but 0 while rendering: bands traced as rank 0 sends them, and sent back.

use ::mpi::point_to_point::MatchedReceiveVec;
use ::mpi::traits::*;

use crate::accel::Work;
use crate::compile::Scene;
use crate::render::Bands;
use crate::shade::RayCounts;
use crate::still::Job;

use super::message::pack;
use super::trace::trace;
use super::{Ranks, BAND, FAILED, POLL, STOP, WORK};

impl Ranks {
    /// Another rank's part: traces the bands rank 0 sends until told to stop, and sends them back (or the
    /// error that stopped it; it then waits for rank 0 to end the job). Gives what it traced.
    pub(super) fn work(
        &self,
        scene: &Scene,
        pool: &rayon::ThreadPool,
        job: &Job,
        bands: &Bands,
    ) -> (RayCounts, Work) {
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
}
