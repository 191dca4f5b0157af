//! Probes of the walks: how many box and primitive tests they make, with how many live rays each, and
//! (for `bench`'s per-ray-kind report) which kind of ray each query serves and the time spent in it.
//!
//! Both are off unless a [`Probe`] guard asks for them: a plain render pays one relaxed atomic load per query
//! and per walk. Counting adds thread-local sums per walk (one add per node slowed the 1e3 field by a large
//! share, so the walks count locally and report once: docs/perf-log/2026-11.md, "cost of `--stats` work
//! counters"); timing reads the time-stamp counter before and after each query, which is why its pass is
//! separate from the passes that are timed as a whole.

use std::cell::{Cell, RefCell};
use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

/// The kind of ray a query serves, as `traced` tags it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum RayKind {
    /// Rays from the eye through the image.
    Camera,
    /// Occlusion rays toward point lights.
    Shadow,
    /// Mirror rays.
    Reflection,
    /// Transmitted rays.
    Refraction,
    /// Ambient occlusion rays.
    Ao,
}

impl RayKind {
    /// Every kind, in report order.
    pub const ALL: [RayKind; 5] =
        [RayKind::Camera, RayKind::Shadow, RayKind::Reflection, RayKind::Refraction, RayKind::Ao];

    /// The kind's name in reports: `camera`, `shadow`, `reflection`, `refraction`, `ao`.
    pub fn name(self) -> &'static str {
        match self {
            RayKind::Camera => "camera",
            RayKind::Shadow => "shadow",
            RayKind::Reflection => "reflection",
            RayKind::Refraction => "refraction",
            RayKind::Ao => "ao",
        }
    }
}

/// The slots of the per-kind sums: one per [`RayKind`], then one for work done outside any `traced` query
/// (none in the renderer: a test checks it).
pub(crate) const KIND_SLOTS: usize = 6;
/// The slot of work done outside any `traced` query.
pub(crate) const UNTAGGED: usize = 5;

/// Intersection tests done, each on a whole packet (K lanes at once; K = 1 counts single rays), and the
/// live rays they served.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Work {
    /// Packet–primitive tests: spheres in visited BVH leaves (or all spheres without a BVH), triangles and
    /// the other kinds' items.
    pub prim_tests: u64,
    /// Packet–box slab tests in BVH traversal (one per visited node and occupied child, fewer where frustum
    /// culling rules children out; for single rays each node's 4-wide test counts as N).
    pub box_tests: u64,
    /// Live rays summed over the primitive tests: `prim_lanes / prim_tests` is the mean number of rays a
    /// test served (K when every lane of every packet is live, 1 for single rays).
    pub(crate) prim_lanes: u64,
    /// Live rays summed over the box tests. A large packet's box test serves every member that tests the
    /// box, so its mean may exceed K.
    pub(crate) box_lanes: u64,
}

impl Work {
    /// Work of single rays: one live ray per test.
    pub(crate) fn single(prim_tests: usize, box_tests: usize) -> Work {
        Work::lanes(prim_tests, prim_tests, box_tests, box_tests)
    }

    /// Work with its live rays counted.
    pub(crate) fn lanes(prim_tests: usize, prim_lanes: usize, box_tests: usize, box_lanes: usize) -> Work {
        Work {
            prim_tests: prim_tests as u64,
            box_tests: box_tests as u64,
            prim_lanes: prim_lanes as u64,
            box_lanes: box_lanes as u64,
        }
    }
}

impl std::ops::AddAssign for Work {
    fn add_assign(&mut self, o: Work) {
        self.prim_tests += o.prim_tests;
        self.box_tests += o.box_tests;
        self.prim_lanes += o.prim_lanes;
        self.box_lanes += o.box_lanes;
    }
}

/// One kind's sums on one thread: its work, its queries and the time-stamp counter ticks spent in them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct KindWork {
    /// Tests made for this kind (counting on).
    pub(crate) work: Work,
    /// `traced` queries made for this kind (counting or timing on).
    pub(crate) queries: u64,
    /// Time-stamp counter ticks inside them (timing on), [`ticks`]' unit.
    pub(crate) ticks: u64,
}

impl std::ops::AddAssign for KindWork {
    fn add_assign(&mut self, o: KindWork) {
        self.work += o.work;
        self.queries += o.queries;
        self.ticks += o.ticks;
    }
}

/// [`PROBES`]' unit for one counting guard, and for one timing guard.
const COUNTING: u32 = 1;
const TIMING: u32 = 1 << 16;

/// The live [`Probe`] guards: counting ones in the low 16 bits, timing ones above.
static PROBES: AtomicU32 = AtomicU32::new(0);

thread_local! {
    /// Work on this thread since the last [`take_work`].
    static WORK: Cell<Work> = const { Cell::new(Work { prim_tests: 0, box_tests: 0, prim_lanes: 0, box_lanes: 0 }) };
    /// Per kind, since the last [`take_kind_work`].
    static KINDS: RefCell<[KindWork; KIND_SLOTS]> = RefCell::new([KindWork::default(); KIND_SLOTS]);
    /// The slot of the query running on this thread.
    static KIND: Cell<usize> = const { Cell::new(UNTAGGED) };
}

/// A probe switched on for the whole process while this guard lives: the work counters
/// ([`Probe::counting`]) or the per-kind query timing (`Probe::timing`). Guards nest and overlap (a probe
/// is on while any of its guards lives), so tests on parallel threads cannot switch each other's off.
#[must_use = "the probe is off again when the guard drops"]
#[derive(Debug)]
pub struct Probe(u32);

impl Probe {
    /// Counts the walks' tests (`take_work`, `take_kind_work`).
    pub fn counting() -> Probe {
        PROBES.fetch_add(COUNTING, Relaxed);
        Probe(COUNTING)
    }

    /// Times each `traced` query by [`ticks`] ([`take_kind_work`]).
    pub(crate) fn timing() -> Probe {
        PROBES.fetch_add(TIMING, Relaxed);
        Probe(TIMING)
    }
}

impl Drop for Probe {
    fn drop(&mut self) {
        PROBES.fetch_sub(self.0, Relaxed);
    }
}

/// Whether the work counters are on: a walk that counts something costly to count (live rays over a large
/// packet's members) asks once.
#[inline(always)]
pub(crate) fn counting() -> bool {
    PROBES.load(Relaxed) & (TIMING - 1) != 0
}

/// Returns and resets this thread's work counters.
pub(crate) fn take_work() -> Work {
    WORK.with(|w| w.replace(Work::default()))
}

/// Returns and resets this thread's per-kind sums, indexed by `RayKind as usize` (and [`UNTAGGED`]).
pub(crate) fn take_kind_work() -> [KindWork; KIND_SLOTS] {
    KINDS.with_borrow_mut(|k| std::mem::replace(k, [KindWork::default(); KIND_SLOTS]))
}

/// Adds `work()` to this thread's work counters, and to the running query's kind, when counting is on;
/// `work` is not evaluated otherwise.
#[inline(always)]
pub(crate) fn count_work(work: impl FnOnce() -> Work) {
    if counting() {
        add_work(work());
    }
}

/// Adds `work` to this thread's work counters and to the running query's kind: for a walk that has read
/// [`counting`] already.
#[cold]
#[inline(never)]
pub(crate) fn add_work(work: Work) {
    WORK.with(|w| {
        let mut v = w.get();
        v += work;
        w.set(v);
    });
    let slot = KIND.with(Cell::get);
    KINDS.with_borrow_mut(|k| k[slot].work += work);
}

/// Runs `query`, a geometry query for rays of `kind`: with the probes on, its work counts toward `kind`
/// and, with timing on, its time.
#[inline(always)]
pub(crate) fn traced<R>(kind: RayKind, query: impl FnOnce() -> R) -> R {
    if PROBES.load(Relaxed) == 0 {
        return query();
    }
    probed(kind, query)
}

#[inline(never)]
fn probed<R>(kind: RayKind, query: impl FnOnce() -> R) -> R {
    let slot = kind as usize;
    let outer = KIND.replace(slot);
    let timing = PROBES.load(Relaxed) >= TIMING;
    let start = if timing { ticks() } else { 0 };
    let result = query();
    let spent = if timing { ticks().wrapping_sub(start) } else { 0 };
    KIND.set(outer);
    KINDS.with_borrow_mut(|k| {
        k[slot].queries += 1;
        k[slot].ticks += spent;
    });
    result
}

/// A monotonic tick count: the time-stamp counter on x86-64 (constant-rate on the CPUs the default build
/// runs on), nanoseconds since the first call elsewhere. Callers convert ticks to seconds by timing a span
/// both ways.
pub(crate) fn ticks() -> u64 {
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: RDTSC exists on every x86-64 CPU and has no memory effects.
        unsafe { core::arch::x86_64::_rdtsc() }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        static START: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();
        START.get_or_init(std::time::Instant::now).elapsed().as_nanos() as u64
    }
}

/// The ticks a `traced` query of nothing reads with timing on: the probe's own share of each timed query,
/// which the per-kind times subtract: the median of `samples` tries.
pub(crate) fn probe_overhead(samples: usize) -> u64 {
    let _timing = Probe::timing();
    let mut spent: Vec<u64> = (0..samples.max(1))
        .map(|_| {
            probed(RayKind::Camera, || ());
            let k = take_kind_work()[RayKind::Camera as usize];
            k.ticks
        })
        .collect();
    spent.sort_unstable();
    spent[spent.len() / 2]
}
