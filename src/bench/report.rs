//! The split by ray kind as `bareray bench` and the Python module report it: the record of one measured
//! setting ([`ByKind`], the `by_kind` field of a `--json` line) and the table that sets settings side by side,
//! kind by kind ([`write_kind_table`]). docs/cli.md, "Reading the per-ray-kind report", says how to read them.

use std::io::{self, Write};

use serde::Serialize;

use super::profile::{KindProfile, Profile};
use crate::accel::RayKind;

/// A render split by ray kind: what `bench --json` writes in each line's `by_kind` field.
#[derive(Clone, Debug, Serialize)]
pub struct ByKind {
    kinds: Vec<KindRecord>,
    /// Share of the fastest timed run's thread time outside every kind's queries (shading, sampling, film,
    /// waiting).
    rest_share: f64,
    /// Ticks one probe reads, taken off each query's time.
    probe_ticks: u64,
}

/// One kind's part of [`ByKind`].
#[derive(Clone, Debug, Serialize)]
struct KindRecord {
    kind: &'static str,
    rays: u64,
    queries: u64,
    /// This kind's query time in the fastest timed run over that run's seconds × threads.
    share: f64,
    /// The kind's rays over its query time per thread.
    mrays_per_s: f64,
    box_tests: u64,
    prim_tests: u64,
    /// Live rays summed over the box tests, and over the primitive tests.
    box_lanes: u64,
    prim_lanes: u64,
    rays_per_box_test: Option<f64>,
    rays_per_prim_test: Option<f64>,
}

impl ByKind {
    /// The record of `profile`.
    pub fn of(profile: &Profile) -> ByKind {
        let kinds = profile
            .kinds
            .iter()
            .map(|k| KindRecord {
                kind: k.kind.name(),
                rays: k.rays,
                queries: k.queries,
                share: profile.share(k),
                mrays_per_s: profile.mrays_per_s(k),
                box_tests: k.work.box_tests,
                prim_tests: k.work.prim_tests,
                box_lanes: k.work.box_lanes,
                prim_lanes: k.work.prim_lanes,
                rays_per_box_test: k.rays_per_box_test(),
                rays_per_prim_test: k.rays_per_prim_test(),
            })
            .collect();
        ByKind { kinds, rest_share: profile.rest_share(), probe_ticks: profile.probe_ticks }
    }

    /// The record as one JSON object.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("numbers and names serialise")
    }
}

/// One measured setting of [`write_kind_table`]: its packet width as printed (`scalar`, `1`, `8`, …), its
/// threads and its split.
pub struct KindRow {
    /// The packet width as the table prints it.
    pub lanes: String,
    /// Threads.
    pub threads: usize,
    /// The setting's split ([`super::profile()`]).
    pub profile: Profile,
}

/// The per-kind table: kind by kind, each row in the order given, with its Mrays/s against the row whose
/// width and threads are `base` (`vs` names it in the header: "scalar", "1 lane").
pub fn write_kind_table(
    out: &mut impl Write,
    rows: &[KindRow],
    base: (&str, usize),
    vs: &str,
) -> io::Result<()> {
    writeln!(
        out,
        "\nby ray kind (four more runs per row: one counting tests, three timing each query; share: the kind's \
         query time in the\nfastest timing run over that run's thread time; Mrays/s: the kind's rays over its \
         query time per thread;\nrays/box, rays/prim: live rays per test)"
    )?;
    writeln!(
        out,
        " kind        lanes threads        rays  share    Mrays/s {:>9}  boxes/ray prims/ray  rays/box rays/prim",
        format!("vs {vs}")
    )?;
    for kind in RayKind::ALL {
        let of = |r: &KindRow| r.profile.kinds.iter().find(|k| k.kind == kind).copied();
        let base_mrays = rows
            .iter()
            .find(|r| r.lanes == base.0 && r.threads == base.1)
            .and_then(|r| of(r).map(|k| r.profile.mrays_per_s(&k)));
        for r in rows {
            if let Some(k) = of(r) {
                write_kind(out, r, &k, base_mrays)?;
            }
        }
    }
    for r in rows {
        let rest = 100.0 * r.profile.rest_share();
        writeln!(out, " {:<10} {:>6} {:7} {:>11} {:>5.1}%", "rest", r.lanes, r.threads, "-", rest)?;
    }
    if let Some(first) = rows.first() {
        writeln!(out, "each query's time has the probe's own {} ticks taken off", first.profile.probe_ticks)?;
    }
    Ok(())
}

fn write_kind(out: &mut impl Write, r: &KindRow, k: &KindProfile, base_mrays: Option<f64>) -> io::Result<()> {
    let mrays = r.profile.mrays_per_s(k);
    let opt = |v: Option<f64>, p: usize| v.map_or("-".to_owned(), |v| format!("{v:.p$}"));
    writeln!(
        out,
        " {:<10} {:>6} {:7} {:11} {:>5.1}% {:10.2} {:>9}  {:>9} {:>9} {:>9} {:>9}",
        k.kind.name(),
        r.lanes,
        r.threads,
        k.rays,
        100.0 * r.profile.share(k),
        mrays,
        base_mrays.map_or("-".to_owned(), |b| format!("{:.2}x", mrays / b)),
        opt(k.box_tests_per_ray(), 1),
        opt(k.prim_tests_per_ray(), 1),
        opt(k.rays_per_box_test(), 2),
        opt(k.rays_per_prim_test(), 2),
    )
}
