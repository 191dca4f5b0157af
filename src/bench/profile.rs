//! A render split by ray kind: rays, queries, tests with their live rays, and the time spent in each
//! kind's geometry queries.

use std::time::Instant;

use crate::accel::{
    probe_overhead, take_kind_work, ticks, KindWork, Probe, RayKind, Work, KIND_SLOTS, UNTAGGED,
};
use crate::compile::Scene;
use crate::render::render_lanes;
use crate::shade::RayCounts;

use super::image_checksum;

/// The timed runs of [`profile`]; each kind's time is their median.
const TIMED_RUNS: usize = 3;

/// One ray kind's part of a render.
#[derive(Clone, Copy, Debug)]
pub(crate) struct KindProfile {
    /// The kind.
    pub(crate) kind: RayKind,
    /// Rays of this kind the render traced (the render's own count).
    pub(crate) rays: u64,
    /// Geometry queries made for them: packets, or single rays where packets went lane by lane.
    pub(crate) queries: u64,
    /// Their box and primitive tests and the live rays those served (the counting run).
    pub(crate) work: Work,
    /// Thread-seconds inside their queries in the timed runs (the median of them), the probe's own ticks
    /// taken off.
    pub(crate) seconds: f64,
    /// The share of the fastest timed run's thread time spent in these queries ([`Profile::share`]).
    pub(crate) share: f64,
}

impl KindProfile {
    /// Mean live rays per box test: K when every lane of every packet is live, 1 for single rays; a large
    /// packet's test serves all its members. `None` without box tests.
    pub(crate) fn rays_per_box_test(&self) -> Option<f64> {
        ratio(self.work.box_lanes, self.work.box_tests)
    }

    /// Mean live rays per primitive test, as [`KindProfile::rays_per_box_test`].
    pub(crate) fn rays_per_prim_test(&self) -> Option<f64> {
        ratio(self.work.prim_lanes, self.work.prim_tests)
    }

    /// Box tests per ray of this kind.
    pub(crate) fn box_tests_per_ray(&self) -> Option<f64> {
        ratio(self.work.box_tests, self.rays)
    }

    /// Primitive tests per ray of this kind.
    pub(crate) fn prim_tests_per_ray(&self) -> Option<f64> {
        ratio(self.work.prim_tests, self.rays)
    }
}

fn ratio(a: u64, b: u64) -> Option<f64> {
    (b > 0).then(|| a as f64 / b as f64)
}

/// A render split by ray kind ([`profile`]).
#[derive(Clone, Debug)]
pub struct Profile {
    /// Every kind the render traced, in [`RayKind::ALL`]'s order.
    pub(crate) kinds: Vec<KindProfile>,
    /// Threads of the pool.
    pub(crate) threads: usize,
    /// Work done outside any tagged query: none in the renderer, which the tests check with it.
    #[cfg_attr(not(test), allow(dead_code))]
    pub(crate) untagged: Work,
    /// All the counting run's work, as the render itself summed it tile by tile.
    pub total: Work,
    /// Ticks one timed query of nothing reads: what each kind's time had taken off per query.
    pub(crate) probe_ticks: u64,
    /// The image checksums of the counting run and of the timed runs (the first that differs from the
    /// others' if one does): the probes change no bits.
    pub(crate) checksums: [u64; 2],
}

impl Profile {
    /// The share of a render's thread time that `kind` spends in its queries, both times from one run: the
    /// fastest timed run, its wall time × threads with every query's probe ticks taken off, and the kind's
    /// query time in it, its probe ticks taken off. Taken from one run, the shares hold on a host whose speed
    /// jumps between levels from one run to the next, where a share over another run's time did not
    /// (docs/perf-log/2026-11-zen3.md, "Per-kind shares from one run").
    pub(crate) fn share(&self, kind: &KindProfile) -> f64 {
        kind.share
    }

    /// The share of the same run's thread time outside every query: shading, sampling, the film, and threads
    /// waiting.
    pub(crate) fn rest_share(&self) -> f64 {
        1.0 - self.kinds.iter().map(|k| self.share(k)).sum::<f64>()
    }

    /// The kind's millions of rays per second on all the pool's threads: its rays over its time per thread.
    pub(crate) fn mrays_per_s(&self, kind: &KindProfile) -> f64 {
        kind.rays as f64 * self.threads as f64 / kind.seconds / 1e6
    }
}

/// Renders `scene` at `lanes` rays per packet on `pool` (a scalar run walks the binary trees, as in
/// `super::measure`) once counting work per ray kind and `TIMED_RUNS` (3) times timing each kind's
/// geometry queries by the time-stamp counter.
pub fn profile(scene: &Scene, lanes: usize, pool: &rayon::ThreadPool) -> Profile {
    let take_all = || -> [KindWork; KIND_SLOTS] {
        let mut sum = [KindWork::default(); KIND_SLOTS];
        for per_thread in pool.broadcast(|_| take_kind_work()) {
            for (s, k) in sum.iter_mut().zip(per_thread) {
                *s += k;
            }
        }
        sum
    };
    take_all();
    let counting = Probe::counting();
    let counted_run = render_lanes(scene, lanes, pool, &());
    drop(counting);
    let counted = take_all();
    let probe_ticks = probe_overhead(10_001);
    // Timed runs, each kind's time the median of them: one run on a shared host is too noisy to split. Each
    // holds the kinds' work, seconds per tick, the image checksum and the run's wall seconds.
    let runs: Vec<([KindWork; KIND_SLOTS], f64, u64, f64)> = (0..TIMED_RUNS)
        .map(|_| {
            take_all();
            let timing = Probe::timing();
            let (clock, start) = (Instant::now(), ticks());
            let run = render_lanes(scene, lanes, pool, &());
            let (wall, spent) = (clock.elapsed().as_secs_f64(), ticks().wrapping_sub(start));
            drop(timing);
            (take_all(), wall / spent.max(1) as f64, image_checksum(&run.image), wall)
        })
        .collect();
    let timed_checksum = runs.iter().map(|r| r.2).find(|&c| c != runs[0].2).unwrap_or(runs[0].2);
    let seconds_in = |(k, per_tick, ..): &([KindWork; KIND_SLOTS], f64, u64, f64), slot: usize| {
        k[slot].ticks.saturating_sub(k[slot].queries * probe_ticks) as f64 * per_tick
    };
    let median_seconds = |slot: usize| {
        let mut s: Vec<f64> = runs.iter().map(|run| seconds_in(run, slot)).collect();
        s.sort_by(f64::total_cmp);
        s[s.len() / 2]
    };
    let threads = pool.current_num_threads();
    let fastest = runs.iter().min_by(|a, b| a.3.total_cmp(&b.3)).expect("timed runs");
    // The probes' ticks as each kind's time had them taken off (never more than its time), so that the kinds'
    // times never sum past the run's.
    let probes: u64 = fastest.0.iter().map(|k| k.ticks.min(k.queries * probe_ticks)).sum();
    let thread_seconds = (fastest.3 * threads as f64 - probes as f64 * fastest.1).max(f64::MIN_POSITIVE);
    let kinds = RayKind::ALL
        .iter()
        .map(|&kind| {
            let c = counted[kind as usize];
            KindProfile {
                kind,
                rays: rays_of(&counted_run.counts, kind),
                queries: c.queries,
                work: c.work,
                seconds: median_seconds(kind as usize),
                share: seconds_in(fastest, kind as usize) / thread_seconds,
            }
        })
        .filter(|k| k.rays > 0 || k.queries > 0)
        .collect();
    Profile {
        kinds,
        threads,
        untagged: counted[UNTAGGED].work,
        total: counted_run.work,
        probe_ticks,
        checksums: [image_checksum(&counted_run.image), timed_checksum],
    }
}

/// The render's count of rays of `kind`.
fn rays_of(counts: &RayCounts, kind: RayKind) -> u64 {
    match kind {
        RayKind::Camera => counts.primary,
        RayKind::Shadow => counts.shadow,
        RayKind::Reflection => counts.reflection,
        RayKind::Refraction => counts.refraction,
        RayKind::Ao => counts.ao,
    }
}
