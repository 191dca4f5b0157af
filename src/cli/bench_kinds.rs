//! `bench --isa`'s per-ray-kind table, from the builds' JSON lines. The table of one build and the
//! `by_kind` field of its JSON lines are [`bareray::bench::write_kind_table`] and [`bareray::bench::ByKind`].

use std::io::Write;

use anyhow::Result;

use super::values::LanesArg;

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
