//! What `bareray bench` prints: the table's header and rows, or one JSON object per row.

use std::io::Write;

use anyhow::Result;
use serde::Serialize;

use super::bench_compare::Old;
use super::values::LanesArg;
use bareray::bench::{ByKind, Host, Measured, Profile};

/// A line for the table's header when this CPU has a wider SIMD instruction set than the kernels were
/// compiled for (a default x86-64-v3 build on an AVX-512 machine): the numbers are not this CPU's best.
fn unused_isa_note() -> Option<&'static str> {
    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    {
        let cpu = crate::cpu::detect::Cpu::read();
        if !cfg!(target_feature = "avx512f") && cpu.has("avx512f") {
            return Some(
                "note: this CPU has AVX-512, which this build leaves unused; `cargo build-native` builds \
                 for it (PERF.md's numbers are native builds)",
            );
        }
        if !cfg!(target_feature = "avx2") && cpu.has("avx2") {
            return Some(
                "note: this CPU has AVX2, which this build leaves unused; `cargo build --release` builds \
                 for it, `cargo build-native` for all this CPU has",
            );
        }
    }
    None
}

/// One line of `--json`. Keys read by bench-peers/run_ab.sh: lanes, threads, seconds, mrays_per_s, checksum.
#[derive(Serialize)]
struct Record<'a> {
    tracer: &'static str,
    scene: String,
    primary_only: bool,
    lanes: LanesArg,
    threads: usize,
    rays: u64,
    /// Median seconds.
    seconds: f64,
    min_s: f64,
    max_s: f64,
    /// From the median.
    mrays_per_s: f64,
    checksum: String,
    reps: u32,
    /// Samples per pixel (null for the half-pixel pattern, about 4 rays per pixel).
    spp: Option<u32>,
    pattern: String,
    max_depth: u32,
    spheres: usize,
    build_s: f64,
    width: u32,
    height: u32,
    frustum_culling: bool,
    bvh_preset: String,
    #[serde(flatten)]
    host: &'a Host,
    /// The render split by ray kind (absent for primary-only runs and with `--by-kind false`).
    #[serde(skip_serializing_if = "Option::is_none")]
    by_kind: Option<ByKind>,
    #[serde(skip_serializing_if = "Option::is_none")]
    compare: Option<CompareField>,
}

/// `compare` of a `--json` line under `--compare`.
#[derive(Serialize)]
struct CompareField {
    file: String,
    /// Null when OLD.json has no row with these lanes and threads.
    old_mrays_per_s: Option<f64>,
    /// New over old Mrays/s.
    ratio: Option<f64>,
}

/// What every row of a run shares: the scene, the settings and the host.
pub(super) struct RunInfo<'a> {
    pub(super) scene: String,
    pub(super) primary_only: bool,
    pub(super) reps: u32,
    /// Samples per pixel (null for patterns without a fixed count).
    pub(super) spp: Option<u32>,
    pub(super) pattern: String,
    pub(super) max_depth: u32,
    pub(super) spheres: usize,
    pub(super) build_s: f64,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) frustum_culling: bool,
    pub(super) bvh_preset: String,
    pub(super) host: &'a Host,
    pub(super) old: Option<&'a Old>,
}

/// The table's header: the scene and settings (`what`), the host, and the column names.
pub(super) fn print_header(out: &mut impl Write, run: &RunInfo, what: &str, base: LanesArg) -> Result<()> {
    let host = run.host;
    writeln!(out, "{what}")?;
    writeln!(
        out,
        "host: {}, {} cores; kernels for {} (16 lanes = {}); {} build; bareray {}",
        host.cpu, host.cores, host.isa, host.lanes16, host.profile, host.version
    )?;
    if let Some(note) = unused_isa_note() {
        writeln!(out, "{note}")?;
    }
    writeln!(out, "{} timed runs per row after one warm-up; Mrays/s from the median", run.reps)?;
    writeln!(
        out,
        " lanes threads        rays      min s   median s      max s    Mrays/s {:>10}  checksum",
        if base.is_scalar() { "vs scalar" } else { "vs 1 lane" }
    )?;
    Ok(())
}

/// One row as a `--json` line.
pub(super) fn print_json(
    out: &mut impl Write,
    run: &RunInfo,
    (lanes, threads): (LanesArg, usize),
    row: &Measured,
    kinds: Option<&Profile>,
) -> Result<()> {
    let mrays = row.mrays_per_s();
    let old_mrays = run.old.and_then(|o| o.mrays(lanes, threads));
    let record = Record {
        tracer: "bareray",
        scene: run.scene.clone(),
        primary_only: run.primary_only,
        lanes,
        threads,
        rays: row.rays,
        seconds: row.seconds,
        min_s: row.min_s,
        max_s: row.max_s,
        mrays_per_s: mrays,
        checksum: format!("{:016x}", row.checksum),
        reps: run.reps,
        spp: run.spp,
        pattern: run.pattern.clone(),
        max_depth: run.max_depth,
        spheres: run.spheres,
        build_s: run.build_s,
        width: run.width,
        height: run.height,
        frustum_culling: run.frustum_culling,
        bvh_preset: run.bvh_preset.clone(),
        host: run.host,
        by_kind: kinds.map(ByKind::of),
        compare: run.old.map(|o| CompareField {
            file: o.path.display().to_string(),
            old_mrays_per_s: old_mrays.map(|(m, _)| m),
            ratio: old_mrays.map(|(m, _)| mrays / m),
        }),
    };
    writeln!(out, "{}", serde_json::to_string(&record)?)?;
    Ok(())
}

/// One row of the table.
pub(super) fn print_row(
    out: &mut impl Write,
    lanes: LanesArg,
    threads: usize,
    row: &Measured,
    base: Option<f64>,
) -> Result<()> {
    let mrays = row.mrays_per_s();
    let ratio = base.map_or("-".to_owned(), |s| format!("{:.2}x", mrays / s));
    writeln!(
        out,
        "{:>6} {:7} {:11} {:10.4} {:10.4} {:10.4} {:10.2} {:>10}  {:016x}",
        lanes, threads, row.rays, row.min_s, row.seconds, row.max_s, mrays, ratio, row.checksum
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The note appears exactly when the CPU has AVX-512 (or AVX2) and the build does not use it.
    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    #[test]
    fn unused_isa_note_names_what_the_cpu_has_beyond_the_build() {
        let cpu = crate::cpu::detect::Cpu::read();
        let note = unused_isa_note();
        let avx512_unused = cpu.has("avx512f") && !cfg!(target_feature = "avx512f");
        let avx2_unused = cpu.has("avx2") && !cfg!(target_feature = "avx2");
        assert_eq!(note.is_some(), avx512_unused || avx2_unused, "{note:?}");
        assert_eq!(note.is_some_and(|n| n.contains("AVX-512")), avx512_unused, "{note:?}");
        assert!(note.is_none_or(|n| n.contains("`cargo build-native`")));
    }
}
