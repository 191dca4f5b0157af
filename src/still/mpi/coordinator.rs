//! Rank 0's loop while rendering: bands handed out to every rank, its own traced on a thread of its own,
//! and all of them put in order for the files.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::Instant;

use ::mpi::point_to_point::MatchedReceiveVec;
use ::mpi::topology::Rank;
use ::mpi::traits::*;

use crate::compile::Scene;
use crate::math::Rgb;
use crate::render::{Bands, Progress, Traced};
use crate::still::{Job, StillError, Stop};

use super::message::unpack;
use super::trace::trace;
use super::{Ranks, AHEAD, BAND, FAILED, IN_FLIGHT, POLL, STOP, WORK};

impl Ranks {
    /// Rank 0's part, [`write_bands`]'s producer: hands out bands, traces bands on a thread of its own,
    /// receives the others' and gives them all to the stage in order, and the finished rows to `emit`.
    /// Gives what this rank traced, and the seconds spent outside `emit`.
    ///
    /// [`write_bands`]: crate::still::write_bands
    pub(super) fn coordinate(
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
}
