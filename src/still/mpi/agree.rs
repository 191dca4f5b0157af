//! The ranks' agreement before any tracing: every rank reports its setup's outcome to rank 0, which tells
//! them all to go on or to stop.

use std::fmt::Display;

use ::mpi::traits::*;

use super::{Ranks, READY, VERDICT};

impl Ranks {
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
}
