//! What `bareray bench --isa` prints: the builds' rows as one table, or as JSON lines.

use std::io::Write;

use anyhow::Result;

use super::bench_isa_level::{Build, Level};
use super::bench_isa_runs::Measured;
use bareray::bench::min_median_max;

/// The rows in print order: each (lanes, threads) of the first build's order, each build in `--isa`'s
/// order: (build, row) indices.
fn order(all: &[Measured]) -> impl Iterator<Item = (usize, usize)> + '_ {
    (0..all[0].rows.len()).flat_map(move |r| (0..all.len()).map(move |b| (b, r)))
}

/// The builds' rows as `bench --json` lines, each with the seconds over rounds and `isa_level`,
/// `software_fma` and `binary` added.
pub(super) fn print_json(
    out: &mut impl Write,
    builds: &[Build],
    all: &[Measured],
    rounds: u32,
) -> Result<()> {
    for (b, r) in order(all) {
        let (row, value) = &all[b].rows[r];
        let (min, median, max) = min_median_max(&all[b].seconds[r]);
        let mut value = value.clone();
        if let Some(obj) = value.as_object_mut() {
            obj.insert("seconds".into(), median.into());
            obj.insert("min_s".into(), min.into());
            obj.insert("max_s".into(), max.into());
            obj.insert("mrays_per_s".into(), (row.rays as f64 / median / 1e6).into());
            obj.insert("reps".into(), rounds.into());
            obj.insert("isa_level".into(), builds[b].level.name().into());
            obj.insert("software_fma".into(), (!row.isa.contains("fma")).into());
            obj.insert("binary".into(), builds[b].path.display().to_string().into());
        }
        writeln!(out, "{value}")?;
    }
    Ok(())
}

/// The builds' rows as one table, each row's speed relative to the v3 build's (the default build's) row of
/// the same lanes and threads, or to the first build's when v3 is not measured.
pub(super) fn print_table(
    out: &mut impl Write,
    builds: &[Build],
    all: &[Measured],
    rounds: u32,
    notes: &[String],
) -> Result<()> {
    let first = &all[0].rows[0].1;
    let s = |key: &str| first[key].as_str().unwrap_or("?").to_owned();
    let n = |key: &str| first[key].as_u64().unwrap_or(0);
    let what = if first["primary_only"].as_bool() == Some(true) {
        "primary rays only".to_owned()
    } else {
        format!("full render, {}, depth {}", s("pattern"), n("max_depth"))
    };
    let names: Vec<&str> = builds.iter().map(|b| b.level.name()).collect();
    writeln!(out, "{}: {} spheres, {}x{}; {what}", s("scene"), n("spheres"), n("width"), n("height"))?;
    writeln!(
        out,
        "host: {}, {} cores; {} builds of bareray {}",
        s("cpu"),
        n("cores"),
        s("profile"),
        s("version")
    )?;
    writeln!(
        out,
        "builds x86-64-{}: {rounds} rounds, each build once per round (its own process, `bench --reps 1` after \
         one warm-up) in turn, the order rotating by round; min, median and max seconds over rounds, Mrays/s \
         from the median",
        names.join(", ")
    )?;
    for note in notes {
        writeln!(out, "{note}")?;
    }
    let base = builds.iter().position(|b| b.level == Level::V3).unwrap_or(0);
    writeln!(
        out,
        "isa  kernels      lanes threads        rays      min s   median s      max s    Mrays/s {:>10}  checksum",
        format!("vs {}", builds[base].level.name())
    )?;
    let mrays =
        |b: usize, r: usize| all[b].rows[r].0.rays as f64 / min_median_max(&all[b].seconds[r]).1 / 1e6;
    for (b, r) in order(all) {
        let row = &all[b].rows[r].0;
        let (min, median, max) = min_median_max(&all[b].seconds[r]);
        writeln!(
            out,
            "{:<4} {:<12} {:>5} {:7} {:11} {min:10.4} {median:10.4} {max:10.4} {:10.2} {:>9.2}x  {}{}",
            builds[b].level.name(),
            row.isa,
            row.lanes,
            row.threads,
            row.rays,
            mrays(b, r),
            mrays(b, r) / mrays(base, r),
            row.checksum,
            if row.isa.contains("fma") { "" } else { "  software FMA" }
        )?;
    }
    writeln!(out, "checksums: equal in every build for every row")?;
    let split: Vec<_> = order(all)
        .map(|(b, r)| {
            (builds[b].level.name(), all[b].rows[r].0.lanes, all[b].rows[r].0.threads, &all[b].rows[r].1)
        })
        .collect();
    super::bench_kinds::print_builds(out, &split, builds[base].level.name())
}
