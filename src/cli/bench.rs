//! `bareray bench`: the same scene traced repeatedly at each packet width and thread count.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{anyhow, Context, Result};
use clap::Args;
use serde::{Deserialize, Serialize};

use super::camera_args::CameraArgs;
use super::render::{parse_lanes, parse_threads};
use super::values::{AccelArg, BvhPresetArg, LanesArg};
use crate::bench::{measure, profile, Measured, Trace};
use crate::compile::{Accel, CompileOptions, Scene};
use crate::io::toml;
use crate::render::thread_pool;
use crate::scene::desc::Pattern;

/// Arguments of `bareray bench`.
#[derive(Args, Debug)]
#[command(after_help = "Every row reports the minimum, median and maximum seconds of its timed runs, and \
Mrays/s from the median. The table's header and every JSON object name the CPU model, the instruction set \
the kernels were compiled for (and what 16 lanes are in it), the core count, the build profile and the \
version; the header notes when this CPU has AVX-512 that the build leaves unused (the default x86-64-v3 \
build; `cargo build-native` builds for this CPU).\n\n\
Examples:\n  bareray gen field --count 1000000 -o f.xyzr\n  \
bareray bench f.xyzr --primary-only --eye 0,0,-4 --look 0,0,0 --up 0,1,0 --hfov 45 --width 1920 --height 1080\n  \
bareray bench scenes/whitted.toml --lanes scalar,1,16 --threads 1,2 --json > old.json\n  \
bareray bench scenes/whitted.toml --lanes scalar,1,16 --threads 1,2 --compare old.json\n  \
bench-peers/build_isa.sh && target/isa/v3/release/bareray bench scenes/whitted.toml --isa v2,v3,v4 --reps 3")]
pub struct BenchArgs {
    /// Scene file (.toml, .nff or .xyzr).
    pub scene: PathBuf,
    /// Packet widths to measure, a comma list of `scalar` (one ray against one box and one primitive at a
    /// time, over binary BVHs), 1 (single-ray SIMD), 4, 8, 16. Each row is relative to the first thread
    /// count's `scalar` row when it is measured, else to its 1-lane row. `scalar` keeps each BVH's binary
    /// tree, which the reported build time and bytes per sphere then include.
    #[arg(long, value_delimiter = ',', default_values = ["1", "4", "8", "16"], value_parser = parse_lanes)]
    pub lanes: Vec<LanesArg>,
    /// Thread counts to measure, a comma list, each from 1 to 1024 [default: 1 and all cores (1 alone on a
    /// 1-core machine)].
    #[arg(long, value_delimiter = ',', value_parser = parse_threads)]
    pub threads: Option<Vec<usize>>,
    /// Trace camera rays to the closest hit only (one per pixel centre): no shading, no secondary rays.
    #[arg(long)]
    pub primary_only: bool,
    /// Samples per pixel (a square number: an n×n grid); overrides the scene, as `render --spp` does.
    #[arg(long, value_parser = super::render::parse_spp, conflicts_with_all = ["primary_only", "aa"])]
    pub spp: Option<u32>,
    /// Sampling method and samples per pixel, as `render --aa` takes it; overrides the scene.
    #[arg(long, value_parser = super::values::parse_aa, conflicts_with = "primary_only")]
    pub aa: Option<Pattern>,
    /// Shading, as `render --shade` takes it (`whitted` or `ao[:SAMPLES[,DISTANCE]]`); overrides the scene.
    #[arg(long, value_name = "MODE", value_parser = super::values::parse_shade, conflicts_with = "primary_only")]
    pub shade: Option<crate::scene::desc::Shade>,
    /// Reflection/refraction depth limit; overrides the scene, as `render --depth` does.
    #[arg(long, conflicts_with = "primary_only")]
    pub depth: Option<u32>,
    /// How spheres are searched: `auto` (a BVH from 4 spheres on), `bvh`, or `brute` (every ray tests every
    /// sphere: the setting for comparing kernels).
    #[arg(long, value_enum, default_value_t = AccelArg::Auto)]
    pub accel: AccelArg,
    /// The BVH builder: bareray's binned SAH (the default), or an obvhs PLOC preset (PERF.md, "Tree builder").
    #[arg(long, value_enum, default_value_t = BvhPresetArg::Sah)]
    pub bvh_preset: BvhPresetArg,
    /// Test each BVH node's children, and each leaf's spheres, against a shared-origin packet's frustum
    /// before its lanes, and walk camera tiles as large packets (default: on, measured faster on large
    /// fields; docs/perf-log/2026-11.md). `false` to measure without.
    #[arg(long, value_name = "BOOL", default_value_t = true, action = clap::ArgAction::Set)]
    pub frustum_culling: bool,
    /// BVH subtrees that a packet enters with at most this many live lanes are walked one ray at a time
    /// (default: the measured switch, 2; 0 never switches). Here to measure the switch again.
    #[arg(long, value_name = "LANES", value_parser = clap::value_parser!(u32).range(0..=16))]
    pub single_ray_lanes: Option<u32>,
    /// Split each full render by ray kind (camera, shadow, reflection, refraction, ambient occlusion):
    /// rays, share of the time, Mrays/s, tests per ray and live rays per test, from two more runs per row
    /// (one counting, one timing each geometry query); docs/cli.md, "Reading the per-ray-kind report".
    /// `false` to skip them. Primary-only runs have one kind and never split.
    #[arg(long, value_name = "BOOL", default_value_t = true, action = clap::ArgAction::Set)]
    pub by_kind: bool,
    /// Timed repetitions per setting (min, median and max are reported), after one untimed warm-up.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub reps: u32,
    /// One JSON object per line instead of a table.
    #[arg(long)]
    pub json: bool,
    /// A previous `--json` output (one object per line): print each row's old and new Mrays/s and their
    /// ratio, rows matched by (lanes, threads). With --json the objects get a `compare` field instead.
    /// In JSON, `lanes` is a packet width's number or the string `"scalar"`.
    #[arg(long, value_name = "OLD.json")]
    pub compare: Option<PathBuf>,
    /// Run builds of this source for these x86-64 levels (a comma list of v2, v3, v4) side by side with
    /// this command's other settings and print one table: `target/isa/<level>/release/bareray`, built by
    /// `bench-peers/build_isa.sh` (docs/cli.md, "Per-ISA builds"). --reps is then the number of rounds, each
    /// build running once per round in turn. A level this CPU lacks is skipped with a note; checksums that
    /// differ between builds are an error.
    #[arg(long, value_name = "LEVELS", value_delimiter = ',', value_parser = super::bench_isa::parse_level,
          conflicts_with = "compare")]
    pub isa: Option<Vec<super::bench_isa::Level>>,
    /// The directory holding the per-ISA builds, as `DIR/<level>/release/bareray` [default: `isa/` in a
    /// directory above this binary, such as target/isa/; or $BARERAY_ISA_DIR].
    #[arg(long, value_name = "DIR", requires = "isa")]
    pub isa_dir: Option<PathBuf>,
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub particles: super::particle_args::ParticleArgs,
}

/// What the numbers were measured on and built with: in the table's header and in every JSON object.
#[derive(Serialize, Debug, Clone)]
struct Host {
    /// `model name` of /proc/cpuinfo, or "unknown".
    cpu: String,
    /// The SIMD instruction set the kernels were compiled for (`target_feature`s of this build).
    isa: &'static str,
    /// What one 16-lane packet is in that instruction set.
    lanes16: &'static str,
    /// `std::thread::available_parallelism`: the cores this process may run on.
    cores: usize,
    /// "release" or "debug" (debug assertions on).
    profile: &'static str,
    /// bareray's version.
    version: &'static str,
}

impl Host {
    fn detect() -> Self {
        let cpu = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|text| {
                text.lines()
                    .find(|l| l.starts_with("model name"))
                    .and_then(|l| l.split_once(':'))
                    .map(|(_, v)| v.trim().to_owned())
            })
            .filter(|v| !v.is_empty())
            .unwrap_or_else(|| "unknown".to_owned());
        let (isa, lanes16) = isa();
        Host {
            cpu,
            isa,
            lanes16,
            cores: cores(),
            profile: if cfg!(debug_assertions) { "debug" } else { "release" },
            version: env!("CARGO_PKG_VERSION"),
        }
    }
}

/// The widest SIMD instruction set this build's kernels use (wide's f32x16 follows the target features),
/// and what 16 lanes are in it.
fn isa() -> (&'static str, &'static str) {
    let fma = cfg!(target_feature = "fma");
    if cfg!(target_feature = "avx512f") {
        (if fma { "avx512f+fma" } else { "avx512f" }, "one 512-bit AVX-512 register")
    } else if cfg!(target_feature = "avx2") {
        (if fma { "avx2+fma" } else { "avx2" }, "two 256-bit AVX2 registers")
    } else if cfg!(target_feature = "avx") {
        ("avx", "two 256-bit AVX registers")
    } else if cfg!(target_feature = "sse2") {
        ("sse2", "four 128-bit SSE registers")
    } else if cfg!(target_feature = "neon") {
        ("neon", "four 128-bit NEON registers")
    } else {
        ("none", "16 scalar values (no SIMD)")
    }
}

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

/// The cores this process may run on (1 when unknown).
fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
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
    by_kind: Option<super::bench_kinds::ByKind>,
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

/// The fields of an old `--json` line that `--compare` reads (the others are ignored).
#[derive(Deserialize)]
struct OldRow {
    lanes: LanesArg,
    threads: usize,
    mrays_per_s: f64,
    scene: Option<String>,
    primary_only: Option<bool>,
    width: Option<u32>,
    height: Option<u32>,
    pattern: Option<String>,
    max_depth: Option<u32>,
}

/// The rows of an old `--json` output by (lanes, threads): Mrays/s of each (several when runs were
/// appended to one file), and the first row, for its settings.
struct Old {
    path: PathBuf,
    rows: BTreeMap<(LanesArg, usize), Vec<f64>>,
    first: OldRow,
}

impl Old {
    fn read(path: &Path) -> Result<Old> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("{}: cannot read the --compare file", path.display()))?;
        let mut rows: BTreeMap<(LanesArg, usize), Vec<f64>> = BTreeMap::new();
        let mut first = None;
        for (i, line) in text.lines().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            let row: OldRow = serde_json::from_str(line)
                .map_err(|e| anyhow!("{}:{}: not a bench --json line: {e}", path.display(), i + 1))?;
            rows.entry((row.lanes, row.threads)).or_default().push(row.mrays_per_s);
            first.get_or_insert(row);
        }
        let first = first.ok_or_else(|| anyhow!("{}: holds no bench --json lines", path.display()))?;
        Ok(Old { path: path.to_owned(), rows, first })
    }

    /// The old Mrays/s of a setting (the median when the file holds several) and how many rows it had.
    fn mrays(&self, lanes: LanesArg, threads: usize) -> Option<(f64, usize)> {
        let mut v = self.rows.get(&(lanes, threads))?.clone();
        v.sort_by(f64::total_cmp);
        Some((v[v.len() / 2], v.len()))
    }

    /// Settings in which the old run differs from this one, for a note (keys missing in the old file
    /// are not compared).
    fn differences(&self, now: &Setting) -> Vec<String> {
        fn differs<T: PartialEq + std::fmt::Debug>(d: &mut Vec<String>, key: &str, old: &Option<T>, now: &T) {
            if let Some(old) = old.as_ref().filter(|&o| o != now) {
                d.push(format!("{key} {old:?} (now {now:?})"));
            }
        }
        let f = &self.first;
        let mut d = Vec::new();
        differs(&mut d, "scene", &f.scene, &now.scene);
        differs(&mut d, "primary_only", &f.primary_only, &now.primary_only);
        differs(&mut d, "width", &f.width, &now.width);
        differs(&mut d, "height", &f.height, &now.height);
        differs(&mut d, "pattern", &f.pattern, &now.pattern);
        differs(&mut d, "max_depth", &f.max_depth, &now.max_depth);
        d
    }
}

/// What a bench run measures, besides lanes and threads: compared with `--compare`'s file.
struct Setting {
    scene: String,
    primary_only: bool,
    width: u32,
    height: u32,
    pattern: String,
    max_depth: u32,
}

/// Runs `bareray bench`.
pub fn run(args: BenchArgs) -> Result<()> {
    if let Some(levels) = &args.isa {
        // The builds get this command's own arguments, those after `bench`, less --isa's.
        let raw: Vec<_> = std::env::args_os().skip_while(|a| a != "bench").skip(1).collect();
        return super::bench_isa::run(
            levels,
            args.isa_dir.as_deref(),
            args.reps,
            args.json,
            args.by_kind,
            &raw,
        );
    }
    let threads = match &args.threads {
        Some(t) => t.clone(),
        None => default_threads(cores()),
    };
    // Read the old results first: a bad file fails before minutes of measuring.
    let old = args.compare.as_deref().map(Old::read).transpose()?;
    let host = Host::detect();
    // Reading and the build run on as many threads as the largest setting measured, not on every core: a
    // 1-thread bench reads and builds on one thread, as a 1-thread peer run does.
    let build_pool = thread_pool(threads.iter().copied().max())?;
    let clock = Instant::now();
    let accel = Accel::from(args.accel);
    // Read as `render` reads: an `.f32r` field bound for the particle tree is mapped, not read.
    let available = crate::compile::memory::available();
    let load_options = args.particles.options();
    let mut loaded =
        build_pool.install(|| crate::compile::load::load(&args.scene, accel, available, &load_options))?;
    super::particle_args::print_warnings(&args.scene, &loaded.warnings);
    let desc = &mut loaded.desc;
    args.camera.apply(desc);
    if let Some(pattern) = args.aa {
        desc.render.pattern = pattern;
    }
    if let Some(shade) = args.shade {
        desc.render.shade = shade;
    }
    if let Some(spp) = args.spp {
        let n = toml::grid_side(spp).map_err(|m| anyhow!("--spp: {m}"))?;
        desc.render.pattern = Pattern::Grid(n);
    }
    if let Some(d) = args.depth {
        desc.render.max_depth = d;
    }
    if args.primary_only {
        // Primary hits need no lights and no bounces; without them the build skips the single-ray tree.
        desc.lights.clear();
        desc.render.max_depth = 0;
    }
    let (spp, pattern) = match (args.primary_only, desc.render.pattern) {
        (true, _) => (Some(1), "pixel centre".to_owned()),
        (false, Pattern::Grid(n)) => (Some(n * n), format!("grid {n}x{n}")),
        (false, Pattern::Stratified(n)) => (Some(n * n), format!("stratified {n}x{n}")),
        (false, Pattern::R2(count)) => (Some(count), format!("r2 {count}")),
        (false, Pattern::Sobol(count)) => (Some(count), format!("sobol {count}")),
        (false, Pattern::HalfPixel) => (None, "half-pixel".to_owned()),
        (false, Pattern::Adaptive { threshold, depth }) => {
            (None, format!("adaptive {threshold} to depth {depth}"))
        }
        (false, Pattern::Coverage) => (None, "coverage".to_owned()),
    };
    let max_depth = desc.render.max_depth;
    let desc_shade = desc.render.shade;
    // The shading mode is part of what was measured: runs compared with --compare must agree on it.
    let pattern = match desc_shade {
        crate::scene::desc::Shade::Whitted => pattern,
        shade => format!("{pattern}, {} shading", super::values::shade_name(shade)),
    };
    let parse_s = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    let defaults = CompileOptions::default();
    let options = CompileOptions {
        accel,
        preset: args.bvh_preset.into(),
        frustum_culling: args.frustum_culling,
        single_ray_lanes: args.single_ray_lanes.unwrap_or(defaults.single_ray_lanes),
        scalar: args.lanes.contains(&LanesArg::Scalar),
    };
    let mut scene = build_pool.install(|| Scene::compile_loaded(loaded, options))?;
    drop(build_pool);
    let compile_s = clock.elapsed().as_secs_f64();
    let (primitives, spheres) = (scene.geometry.len(), scene.geometry.spheres.len());
    let scene_name = args.scene.display().to_string();
    let (width, height) = (scene.camera.width, scene.camera.height);
    if let Some(old) = &old {
        let now = Setting {
            scene: scene_name.clone(),
            primary_only: args.primary_only,
            width,
            height,
            pattern: pattern.clone(),
            max_depth,
        };
        let d = old.differences(&now);
        if !d.is_empty() {
            eprintln!("note: {} was measured with other settings: {}", old.path.display(), d.join(", "));
        }
    }
    let mut out = std::io::stdout().lock();
    // The row every other is compared with: scalar when it is measured, else one lane.
    let base = if args.lanes.contains(&LanesArg::Scalar) { LanesArg::Scalar } else { LanesArg::Packet(1) };
    if !args.json {
        writeln!(
            out,
            "{scene_name}: {} primitives ({} spheres), {width}x{height}; parse {parse_s:.3} s, compile \
             {compile_s:.3} s (BVH build {:.3} s, {:.1} bytes/sphere); {}",
            primitives,
            spheres,
            scene.build.seconds,
            scene.bytes_per_sphere(),
            if args.primary_only {
                "primary rays only".to_owned()
            } else {
                match desc_shade {
                    crate::scene::desc::Shade::Whitted => {
                        format!("full Whitted render, {pattern}, depth {max_depth}")
                    }
                    crate::scene::desc::Shade::Ao(_) => format!("full render, {pattern}"),
                }
            }
        )?;
        writeln!(
            out,
            "host: {}, {} cores; kernels for {} (16 lanes = {}); {} build; bareray {}",
            host.cpu, host.cores, host.isa, host.lanes16, host.profile, host.version
        )?;
        if let Some(note) = unused_isa_note() {
            writeln!(out, "{note}")?;
        }
        writeln!(out, "{} timed runs per row after one warm-up; Mrays/s from the median", args.reps)?;
        writeln!(
            out,
            " lanes threads        rays      min s   median s      max s    Mrays/s {:>10}  checksum",
            if base.is_scalar() { "vs scalar" } else { "vs 1 lane" }
        )?;
    }
    let mut base_mrays: Option<f64> = None;
    let mut compared = Vec::new();
    let trace = if args.primary_only { Trace::PrimaryOnly } else { Trace::Render };
    let split = args.by_kind && !args.primary_only;
    let mut split_rows = Vec::new();
    for &t in &threads {
        // One thread pool for every repetition, as the peer harnesses reuse theirs.
        let pool = thread_pool(Some(t))?;
        for &lanes in &args.lanes {
            // The scalar row walks the binary trees, every other row the wide nodes.
            scene.geometry.set_scalar_walk(lanes.is_scalar());
            let row = measure(&scene, trace, lanes.k(), &pool, args.reps)
                .map_err(|e| anyhow!("lanes {lanes}, {t} threads: {e}"))?;
            let kinds = split.then(|| profile(&scene, lanes.k(), &pool));
            if let Some(changed) =
                kinds.as_ref().and_then(|p| p.checksums.iter().find(|&&c| c != row.checksum))
            {
                anyhow::bail!(
                    "lanes {lanes}, {t} threads: a probed run's checksum {changed:016x} differs from the timed \
                     runs' {:016x}",
                    row.checksum
                );
            }
            let mrays = row.mrays_per_s();
            if lanes == base && t == threads[0] {
                base_mrays = Some(mrays);
            }
            let old_mrays = old.as_ref().and_then(|o| o.mrays(lanes, t));
            compared.push((lanes, t, mrays, old_mrays));
            if args.json {
                let record = Record {
                    tracer: "bareray",
                    scene: scene_name.clone(),
                    primary_only: args.primary_only,
                    lanes,
                    threads: t,
                    rays: row.rays,
                    seconds: row.seconds,
                    min_s: row.min_s,
                    max_s: row.max_s,
                    mrays_per_s: mrays,
                    checksum: format!("{:016x}", row.checksum),
                    reps: args.reps,
                    spp,
                    pattern: pattern.clone(),
                    max_depth,
                    spheres,
                    build_s: scene.build.seconds,
                    width,
                    height,
                    frustum_culling: args.frustum_culling,
                    bvh_preset: super::values::name(args.bvh_preset),
                    host: &host,
                    by_kind: kinds.as_ref().map(|p| super::bench_kinds::record(p, row.seconds)),
                    compare: old.as_ref().map(|o| CompareField {
                        file: o.path.display().to_string(),
                        old_mrays_per_s: old_mrays.map(|(m, _)| m),
                        ratio: old_mrays.map(|(m, _)| mrays / m),
                    }),
                };
                writeln!(out, "{}", serde_json::to_string(&record)?)?;
            } else {
                print_row(&mut out, lanes, t, &row, base_mrays)?;
            }
            if let Some(p) = kinds {
                split_rows.push(super::bench_kinds::Split {
                    lanes,
                    threads: t,
                    seconds: row.seconds,
                    profile: p,
                });
            }
        }
    }
    if !args.json && !split_rows.is_empty() {
        super::bench_kinds::print_table(&mut out, &split_rows, base, threads[0])?;
    }
    if let Some(old) = &old {
        let unmatched: Vec<String> = old
            .rows
            .keys()
            .filter(|&&(l, t)| !compared.iter().any(|&(cl, ct, ..)| (cl, ct) == (l, t)))
            .map(|(l, t)| format!("lanes {l} threads {t}"))
            .collect();
        if args.json {
            if !unmatched.is_empty() {
                eprintln!("note: rows of {} not measured now: {}", old.path.display(), unmatched.join(", "));
            }
        } else {
            writeln!(
                out,
                "\ncompared with {} (Mrays/s; old: the median when it holds several runs):",
                old.path.display()
            )?;
            writeln!(out, " lanes threads        old        new   new/old")?;
            for (lanes, t, new, old_mrays) in compared {
                match old_mrays {
                    Some((m, n)) => writeln!(
                        out,
                        "{lanes:>6} {t:7} {m:10.2} {new:10.2} {:>8.3}x{}",
                        new / m,
                        if n > 1 { format!("  (old: median of {n})") } else { String::new() }
                    )?,
                    None => writeln!(out, "{lanes:>6} {t:7} {:>10} {new:10.2} {:>9}  no old row", "-", "-")?,
                }
            }
            if !unmatched.is_empty() {
                writeln!(out, "old rows not measured now: {}", unmatched.join(", "))?;
            }
        }
    }
    Ok(())
}

/// The default `--threads`: 1 and every core, or 1 alone on a 1-core machine.
fn default_threads(cores: usize) -> Vec<usize> {
    if cores > 1 {
        vec![1, cores]
    } else {
        vec![1]
    }
}

/// One row of the table.
fn print_row(
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

    #[test]
    fn default_threads_are_one_and_all_cores() {
        assert_eq!(default_threads(1), vec![1]);
        assert_eq!(default_threads(2), vec![1, 2]);
        assert_eq!(default_threads(64), vec![1, 64]);
    }

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

    #[test]
    fn isa_names_what_sixteen_lanes_are() {
        let (isa, lanes16) = isa();
        assert!(!isa.is_empty() && !lanes16.is_empty());
        if cfg!(target_feature = "avx512f") {
            assert!(lanes16.starts_with("one"));
        }
    }
}
