//! `bareray bench`'s per-ray-kind report: the table after the main one, and the `by_kind` field of each
//! JSON line. The figures come from [`bareray::bench::profile`].

use std::io::Write;

use anyhow::Result;
use serde::Serialize;

use super::values::LanesArg;
use bareray::bench::{KindProfile, Profile};

/// One measured setting with its split.
pub(super) struct Split {
    pub(super) lanes: LanesArg,
    pub(super) threads: usize,
    /// The median seconds of the setting's clean runs.
    pub(super) seconds: f64,
    pub(super) profile: Profile,
}

/// The `by_kind` field of a JSON line.
#[derive(Serialize)]
pub(super) struct ByKind {
    kinds: Vec<KindRecord>,
    /// Share of the median run's thread time outside every kind's queries (shading, sampling, film,
    /// waiting).
    rest_share: f64,
    /// Ticks one probe reads, taken off each query's time.
    probe_ticks: u64,
}

#[derive(Serialize)]
struct KindRecord {
    kind: &'static str,
    rays: u64,
    queries: u64,
    /// This kind's query time in the timed run over the row's median seconds × threads.
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

/// The JSON form of `profile` for a row whose median is `seconds`.
pub(super) fn record(profile: &Profile, seconds: f64) -> ByKind {
    let kinds = profile
        .kinds
        .iter()
        .map(|k| KindRecord {
            kind: k.kind.name(),
            rays: k.rays,
            queries: k.queries,
            share: profile.share(k, seconds),
            mrays_per_s: profile.mrays_per_s(k),
            box_tests: k.work.box_tests,
            prim_tests: k.work.prim_tests,
            box_lanes: k.work.box_lanes,
            prim_lanes: k.work.prim_lanes,
            rays_per_box_test: k.rays_per_box_test(),
            rays_per_prim_test: k.rays_per_prim_test(),
        })
        .collect();
    ByKind { kinds, rest_share: profile.rest_share(seconds), probe_ticks: profile.probe_ticks }
}

/// The per-kind table: kind by kind, each setting in the order measured, with its Mrays/s against the
/// `base` width's at `base_threads` threads.
pub(super) fn print_table(
    out: &mut impl Write,
    rows: &[Split],
    base: LanesArg,
    base_threads: usize,
) -> Result<()> {
    writeln!(
        out,
        "\nby ray kind (four more runs per row: one counting tests, three timing each query; share: the kind's \
         query time over the\nmedian's thread time; Mrays/s: the kind's rays over its query time per thread; \
         rays/box, rays/prim: live rays per test)"
    )?;
    writeln!(
        out,
        " kind        lanes threads        rays  share    Mrays/s {:>9}  boxes/ray prims/ray  rays/box rays/prim",
        if base.is_scalar() { "vs scalar" } else { "vs 1 lane" }
    )?;
    let kinds = bareray::accel::RayKind::ALL;
    for kind in kinds {
        let of = |r: &Split| r.profile.kinds.iter().find(|k| k.kind == kind).copied();
        let base_mrays = rows
            .iter()
            .find(|r| r.lanes == base && r.threads == base_threads)
            .and_then(|r| of(r).map(|k| r.profile.mrays_per_s(&k)));
        for r in rows {
            if let Some(k) = of(r) {
                print_kind(out, r, &k, base_mrays)?;
            }
        }
    }
    for r in rows {
        writeln!(
            out,
            " {:<10} {:>6} {:7} {:>11} {:>5.1}%",
            "rest",
            r.lanes,
            r.threads,
            "-",
            100.0 * r.profile.rest_share(r.seconds)
        )?;
    }
    writeln!(out, "each query's time has the probe's own {} ticks taken off", rows[0].profile.probe_ticks)?;
    Ok(())
}

fn print_kind(out: &mut impl Write, r: &Split, k: &KindProfile, base_mrays: Option<f64>) -> Result<()> {
    let mrays = r.profile.mrays_per_s(k);
    let opt = |v: Option<f64>, p: usize| v.map_or("-".to_owned(), |v| format!("{v:.p$}"));
    writeln!(
        out,
        " {:<10} {:>6} {:7} {:11} {:>5.1}% {:10.2} {:>9}  {:>9} {:>9} {:>9} {:>9}",
        k.kind.name(),
        r.lanes,
        r.threads,
        k.rays,
        100.0 * r.profile.share(k, r.seconds),
        mrays,
        base_mrays.map_or("-".to_owned(), |b| format!("{:.2}x", mrays / b)),
        opt(k.box_tests_per_ray(), 1),
        opt(k.prim_tests_per_ray(), 1),
        opt(k.rays_per_box_test(), 2),
        opt(k.rays_per_prim_test(), 2),
    )?;
    Ok(())
}

/// `bench --isa`'s per-kind table: for each kind, each row of each build (`(build, lanes, threads, its
/// first round's JSON line)`, in print order), its Mrays/s against the `base` build's at the same lanes
/// and threads. Nothing when the rows have no `by_kind` field.
pub(super) fn print_builds(
    out: &mut impl Write,
    rows: &[(&str, LanesArg, usize, &serde_json::Value)],
    base: &str,
) -> Result<()> {
    let kind_of = |v: &serde_json::Value, kind: &str| {
        v["by_kind"]["kinds"].as_array()?.iter().find(|k| k["kind"] == kind).cloned()
    };
    if rows.iter().all(|r| r.3["by_kind"].is_null()) {
        return Ok(());
    }
    writeln!(
        out,
        "\nby ray kind (each build's first round; docs/cli.md, \"Reading the per-ray-kind report\")"
    )?;
    writeln!(
        out,
        " kind        isa  lanes threads        rays  share    Mrays/s {:>8}  rays/box rays/prim",
        format!("vs {base}")
    )?;
    for kind in bareray::accel::RayKind::ALL.map(bareray::accel::RayKind::name) {
        for &(build, lanes, threads, v) in rows {
            let Some(k) = kind_of(v, kind) else { continue };
            let base_mrays = rows
                .iter()
                .find(|r| r.0 == base && r.1 == lanes && r.2 == threads)
                .and_then(|r| kind_of(r.3, kind))
                .and_then(|b| b["mrays_per_s"].as_f64());
            let mrays = k["mrays_per_s"].as_f64().unwrap_or(f64::NAN);
            let opt = |key: &str| k[key].as_f64().map_or("-".to_owned(), |v| format!("{v:.2}"));
            writeln!(
                out,
                " {kind:<10} {build:<4} {lanes:>6} {threads:7} {:11} {:>5.1}% {mrays:10.2} {:>8}  {:>8} {:>9}",
                k["rays"].as_u64().unwrap_or(0),
                100.0 * k["share"].as_f64().unwrap_or(f64::NAN),
                base_mrays.map_or("-".to_owned(), |b| format!("{:.2}x", mrays / b)),
                opt("rays_per_box_test"),
                opt("rays_per_prim_test"),
            )?;
        }
    }
    Ok(())
}
