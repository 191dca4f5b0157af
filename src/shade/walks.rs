//! Which walk finds the closest hits of a scattered secondary packet: the packet walk, or each live lane
//! alone over the single-ray tree. Both give the same bits, so only the time depends on the choice.
//!
//! Mirror rays that leave several small spheres go apart at once. On a deep tree (SPD balls L6, 598k
//! spheres) the packet walk then visits each level with few lanes per box and its reflection rays run at
//! 0.8x their single-ray speed; on a shallow one (balls L4, 7k) the packet walk still wins
//! (docs/perf-log/2026-11-xeon167.md, "Scattered secondary packets: the walk chosen by timing"). Neither
//! the tree's size nor the packet's spread decides it alone, so each thread times both walks on
//! interleaved packets for a while and takes the faster one for the packets that follow, and does so again
//! every [`PERIOD`] packets.

use std::cell::Cell;

use crate::accel::ticks;
use crate::simd::{set_bits, IdLanes, Lanes};

/// Scattered packets timed on each walk in each round: the round's first `2 · TRIALS` packets, the walks
/// interleaved in Thue–Morse order (packet `i` walks lane by lane when `i` has an odd number of set bits),
/// which no regular pattern of the packets (a first bounce, then a second) lines up with.
const TRIALS: u32 = 64;
/// Scattered packets per round: the trials, then the faster walk for the rest (a power of two, so that
/// the count may wrap).
const PERIOD: u32 = 2048;

/// One thread's choice and the round's timings, for one scene.
#[derive(Clone, Copy, Debug, Default)]
struct Choice {
    /// The scene's address: a scene at another address starts afresh (one compiled where a dropped one was
    /// keeps its choice until the next round's trials: only the time depends on it).
    scene: usize,
    /// Scattered packets walked so far.
    seen: u32,
    /// Ticks of the round's timed packets, packet walk then lanes alone.
    ticks: [u64; 2],
    /// Live rays of the round's timed packets, likewise.
    rays: [u64; 2],
    /// Whether the lanes walk alone outside the trials.
    by_lanes: bool,
}

thread_local! {
    static CHOICE: Cell<Choice> =
        const { Cell::new(Choice { scene: 0, seen: 0, ticks: [0; 2], rays: [0; 2], by_lanes: false }) };
}

/// Whether the live lanes of a secondary packet leave more than two different primitives: the packets
/// whose walk is chosen by timing. Rays leaving one or two primitives (a large sphere, the floor) stay
/// together long enough for the packet walk.
pub(super) fn scattered<F: Lanes>(prim: F::Ids, live: F::Mask) -> bool {
    let ids = prim.to_array();
    let ids = ids.as_ref();
    let mut seen = [0u32; 2];
    let mut distinct = 0;
    for i in set_bits(F::move_mask(live)) {
        if seen[..distinct].contains(&ids[i]) {
            continue;
        }
        if distinct == seen.len() {
            return true;
        }
        seen[distinct] = ids[i];
        distinct += 1;
    }
    false
}

impl Choice {
    /// The walk for the next scattered packet, and whether it is a trial (to be timed and
    /// [`Choice::record`]ed).
    fn next(&mut self) -> (bool, bool) {
        let phase = self.seen % PERIOD;
        self.seen = self.seen.wrapping_add(1);
        match phase < 2 * TRIALS {
            true => (phase.count_ones() % 2 == 1, true),
            false => (self.by_lanes, false),
        }
    }

    /// A trial's time: `ticks` for `rays` live rays walked `by_lanes` or not. The round's last trial
    /// settles the choice: the lower ticks per ray.
    fn record(&mut self, by_lanes: bool, ticks: u64, rays: u32) {
        let w = usize::from(by_lanes);
        (self.ticks[w], self.rays[w]) = (self.ticks[w].saturating_add(ticks), self.rays[w] + u64::from(rays));
        if self.seen.wrapping_sub(1) % PERIOD == 2 * TRIALS - 1 {
            // Ticks per ray, lanes alone against the packet walk, compared without a division.
            let per_ray = |w: usize, other: usize| u128::from(self.ticks[w]) * u128::from(self.rays[other]);
            self.by_lanes = per_ray(1, 0) < per_ray(0, 1);
            (self.ticks, self.rays) = ([0; 2], [0; 2]);
        }
    }
}

/// Runs `walk(by_lanes)` for a scattered packet of `rays` live rays in `scene` (any address that tells
/// scenes apart), choosing `by_lanes` as described in the module's documentation.
pub(super) fn walk_scattered<R>(scene: usize, rays: u32, walk: impl FnOnce(bool) -> R) -> R {
    let mut c = CHOICE.get();
    if c.scene != scene {
        c = Choice { scene, ..Choice::default() };
    }
    let (by_lanes, trial) = c.next();
    let result = match trial {
        false => walk(by_lanes),
        true => {
            let start = ticks();
            let result = walk(by_lanes);
            // A thread moved to a core whose counter is behind reads an earlier time: no time, not 2⁶⁴.
            c.record(by_lanes, ticks().saturating_sub(start), rays);
            result
        }
    };
    CHOICE.set(c);
    result
}

#[cfg(test)]
mod tests {
    use super::*;
    use wide::f32x8;

    #[test]
    fn scattered_counts_the_live_lanes_departure_primitives() {
        let ids = |v: [u32; 8]| <f32x8 as Lanes>::Ids::from_fn(|i| v[i]);
        let all = <f32x8 as Lanes>::mask_from_bits(0xff);
        assert!(!scattered::<f32x8>(ids([3; 8]), all));
        assert!(!scattered::<f32x8>(ids([3, 4, 3, 4, 3, 4, 3, 4]), all));
        assert!(scattered::<f32x8>(ids([3, 4, 5, 4, 3, 4, 3, 4]), all));
        // A third primitive in a dead lane does not count.
        assert!(!scattered::<f32x8>(ids([3, 4, 5, 4, 3, 4, 3, 4]), <f32x8 as Lanes>::mask_from_bits(0xfb)));
    }

    /// Drives a choice through `rounds` rounds, lanes alone costing `lanes_cost` ticks a ray in round `r`
    /// and the packet walk 100; returns the walk of every packet.
    fn drive(rounds: usize, lanes_cost: impl Fn(usize) -> u64) -> Vec<bool> {
        let mut c = Choice::default();
        let mut asked = Vec::new();
        for packet in 0..rounds * PERIOD as usize {
            let (by_lanes, trial) = c.next();
            if trial {
                let cost = if by_lanes { lanes_cost(packet / PERIOD as usize) } else { 100 };
                c.record(by_lanes, 8 * cost, 8);
            }
            asked.push(by_lanes);
        }
        asked
    }

    #[test]
    fn each_round_times_both_walks_interleaved_then_keeps_the_faster() {
        // Lanes alone slower in the first round, faster in the second, slower again in the third.
        let asked = drive(3, |round| if round == 1 { 60 } else { 140 });
        let (period, trials) = (PERIOD as usize, 2 * TRIALS as usize);
        for (round, lanes_won) in [(0, false), (1, true), (2, false)] {
            let at = round * period;
            let tried = &asked[at..at + trials];
            assert!(tried.iter().enumerate().all(|(i, &l)| l == (i.count_ones() % 2 == 1)), "round {round}");
            assert_eq!(tried.iter().filter(|&&l| l).count(), TRIALS as usize, "round {round}");
            assert!(asked[at + trials..at + period].iter().all(|&l| l == lanes_won), "round {round}");
        }
    }

    #[test]
    fn the_trials_sums_saturate() {
        // A huge reading cannot wrap a walk's sum around to a small one: one trial of lanes alone took
        // u64::MAX ticks, the others 1, which a wrapping sum would make 62.
        let mut c = Choice::default();
        let mut first = true;
        for _ in 0..2 * TRIALS {
            let (by_lanes, _) = c.next();
            let ticks = match (by_lanes, first) {
                (false, _) => 100,
                (true, true) => u64::MAX,
                (true, false) => 1,
            };
            first &= !by_lanes;
            c.record(by_lanes, ticks, 8);
        }
        assert!(!c.by_lanes, "lanes alone took over u64::MAX ticks in all");
    }
}
