//! `bareray bench`: the same scene traced repeatedly at each packet width and thread count. The measuring
//! is [`bareray::bench`]'s; [`super::bench_print`] prints it and [`super::bench_compare`] sets it beside an
//! earlier run.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{anyhow, Result};
use clap::Args;

use super::bench_compare::{Compared, Old, Setting};
use super::bench_print::{print_header, print_json, print_row, RunInfo};
use super::camera_args::CameraArgs;
use super::values::{parse_lanes, parse_threads, AccelArg, BvhPresetArg, LanesArg};
use bareray::bench::{cores, default_threads, measure_setting, write_kind_table, Host, KindRow, Trace};
use bareray::compile::{Accel, CompileOptions, Scene};
use bareray::render::thread_pool;
use bareray::scene::desc::{Pattern, Shade};
use bareray::settings::{shade_name, Overrides, PatternName};

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
pub(super) struct BenchArgs {
    /// Scene file (.toml, .nff or .xyzr).
    pub(super) scene: PathBuf,
    /// Packet widths to measure, a comma list of `scalar` (one ray against one box and one primitive at a
    /// time, over binary BVHs), 1 (single-ray SIMD), 4, 8, 16. Each row is relative to the first thread
    /// count's `scalar` row when it is measured, else to its 1-lane row. `scalar` keeps each BVH's binary
    /// tree, which the reported build time and bytes per sphere then include.
    #[arg(long, value_delimiter = ',', default_values = ["1", "4", "8", "16"], value_parser = parse_lanes)]
    pub(super) lanes: Vec<LanesArg>,
    /// Thread counts to measure, a comma list, each from 1 to 1024 [default: 1 and all cores (1 alone on a
    /// 1-core machine)].
    #[arg(long, value_delimiter = ',', value_parser = parse_threads)]
    pub(super) threads: Option<Vec<usize>>,
    /// Trace camera rays to the closest hit only (one per pixel centre): no shading, no secondary rays.
    #[arg(long)]
    pub(super) primary_only: bool,
    /// Samples per pixel (a square number: an n×n grid); overrides the scene, as `render --spp` does.
    #[arg(long, value_parser = super::values::parse_spp, conflicts_with_all = ["primary_only", "aa"])]
    pub(super) spp: Option<u32>,
    /// Sampling method and samples per pixel, as `render --aa` takes it; overrides the scene.
    #[arg(long, value_parser = super::sampling_values::parse_aa, conflicts_with = "primary_only")]
    pub(super) aa: Option<Pattern>,
    /// Shading, as `render --shade` takes it (`whitted` or `ao[:SAMPLES[,DISTANCE]]`); overrides the scene.
    #[arg(long, value_name = "MODE", value_parser = super::sampling_values::parse_shade, conflicts_with = "primary_only")]
    pub(super) shade: Option<bareray::scene::desc::Shade>,
    /// Reflection/refraction depth limit; overrides the scene, as `render --depth` does.
    #[arg(long, conflicts_with = "primary_only")]
    pub(super) depth: Option<u32>,
    /// How spheres are searched: `auto` (a BVH from 4 spheres on), `bvh`, or `brute` (every ray tests every
    /// sphere: the setting for comparing kernels).
    #[arg(long, value_enum, default_value_t = AccelArg::Auto)]
    pub(super) accel: AccelArg,
    /// The BVH builder: bareray's Morton order over binned SAH (the default) or binned SAH alone, or an obvhs
    /// PLOC preset (PERF.md, "Tree builder").
    #[arg(long, value_enum, default_value_t = BvhPresetArg::Morton)]
    pub(super) bvh_preset: BvhPresetArg,
    /// Test each BVH node's children, and each leaf's spheres, against a shared-origin packet's frustum
    /// before its lanes, and walk camera tiles as large packets (default: on, measured faster on large
    /// fields; docs/perf-log/2026-11.md). `false` to measure without.
    #[arg(long, value_name = "BOOL", default_value_t = true, action = clap::ArgAction::Set)]
    pub(super) frustum_culling: bool,
    /// BVH subtrees that a packet enters with at most this many live lanes are walked one ray at a time
    /// (default: the measured switch, 2; 0 never switches). Here to measure the switch again.
    #[arg(long, value_name = "LANES", value_parser = clap::value_parser!(u32).range(0..=16))]
    pub(super) single_ray_lanes: Option<u32>,
    /// Split each full render by ray kind (camera, shadow, reflection, refraction, ambient occlusion):
    /// rays, share of the time, Mrays/s, tests per ray and live rays per test, from two more runs per row
    /// (one counting, one timing each geometry query); docs/cli.md, "Reading the per-ray-kind report".
    /// `false` to skip them. Primary-only runs have one kind and never split.
    #[arg(long, value_name = "BOOL", default_value_t = true, action = clap::ArgAction::Set)]
    pub(super) by_kind: bool,
    /// Timed repetitions per setting (min, median and max are reported), after one untimed warm-up.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub(super) reps: u32,
    /// One JSON object per line instead of a table.
    #[arg(long)]
    pub(super) json: bool,
    /// A previous `--json` output (one object per line): print each row's old and new Mrays/s and their
    /// ratio, rows matched by (lanes, threads). With --json the objects get a `compare` field instead.
    /// In JSON, `lanes` is a packet width's number or the string `"scalar"`.
    #[arg(long, value_name = "OLD.json")]
    pub(super) compare: Option<PathBuf>,
    /// Run builds of this source for these x86-64 levels (a comma list of v2, v3, v4) side by side with
    /// this command's other settings and print one table: `target/isa/<level>/release/bareray`, built by
    /// `bench-peers/build_isa.sh` (docs/cli.md, "Per-ISA builds"). --reps is then the number of rounds, each
    /// build running once per round in turn. A level this CPU lacks is skipped with a note; checksums that
    /// differ between builds are an error.
    #[arg(long, value_name = "LEVELS", value_delimiter = ',', value_parser = super::bench_isa_level::parse_level,
          conflicts_with = "compare")]
    pub(super) isa: Option<Vec<super::bench_isa_level::Level>>,
    /// The directory holding the per-ISA builds, as `DIR/<level>/release/bareray` [default: `isa/` in a
    /// directory above this binary, such as target/isa/; or $BARERAY_ISA_DIR].
    #[arg(long, value_name = "DIR", requires = "isa")]
    pub(super) isa_dir: Option<PathBuf>,
    #[command(flatten)]
    pub(super) camera: CameraArgs,
    #[command(flatten)]
    pub(super) particles: super::particle_args::ParticleArgs,
}

/// Runs `bareray bench`.
pub(super) fn run(args: BenchArgs) -> Result<()> {
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
    let threads = args.threads.clone().unwrap_or_else(|| default_threads(cores()));
    // Read the old results first: a bad file fails before minutes of measuring.
    let old = args.compare.as_deref().map(Old::read).transpose()?;
    let host = Host::detect();
    let (mut scene, info, what) = prepare(&args, &threads, &host, old.as_ref())?;
    if let Some(old) = &old {
        let now = Setting {
            scene: info.scene.clone(),
            primary_only: args.primary_only,
            width: info.width,
            height: info.height,
            pattern: info.pattern.clone(),
            max_depth: info.max_depth,
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
        print_header(&mut out, &info, &what, base)?;
    }
    let compared = measure_rows(&args, &mut scene, &info, (&threads, base), &mut out)?;
    if let Some(old) = &old {
        super::bench_compare::print(&mut out, old, compared, args.json)?;
    }
    Ok(())
}

/// Reads the scene, applies the command line and compiles it: the scene, what every row shares, and the
/// table header's first line.
fn prepare<'a>(
    args: &BenchArgs,
    threads: &[usize],
    host: &'a Host,
    old: Option<&'a Old>,
) -> Result<(Scene, RunInfo<'a>, String)> {
    // Reading and the build run on as many threads as the largest setting measured, not on every core: a
    // 1-thread bench reads and builds on one thread, as a 1-thread peer run does.
    let build_pool = thread_pool(threads.iter().copied().max())?;
    let clock = Instant::now();
    let accel = Accel::from(args.accel);
    // Read as `render` reads: an `.f32r` field bound for the particle tree is mapped, not read.
    let available = bareray::compile::memory::available();
    let load_options = args.particles.options();
    let mut loaded =
        build_pool.install(|| bareray::compile::load::load(&args.scene, accel, available, &load_options))?;
    super::particle_args::print_warnings(&args.scene, &loaded.warnings);
    overrides(args).apply(&mut loaded.desc).map_err(super::render_run::settings_error)?;
    let render = loaded.desc.render;
    let name = PatternName::of(render.pattern);
    let (spp, pattern) = match args.primary_only {
        true => (Some(1), "pixel centre".to_owned()),
        false => (name.samples, name.short),
    };
    // The shading mode is part of what was measured: runs compared with --compare must agree on it.
    let pattern = match render.shade {
        Shade::Whitted => pattern,
        shade => format!("{pattern}, {} shading", shade_name(shade)),
    };
    let parse_s = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    let options = CompileOptions {
        accel,
        preset: args.bvh_preset.into(),
        frustum_culling: args.frustum_culling,
        single_ray_lanes: args.single_ray_lanes.unwrap_or(CompileOptions::default().single_ray_lanes),
        scalar: args.lanes.contains(&LanesArg::Scalar),
    };
    let scene = build_pool.install(|| Scene::compile_loaded(loaded, options))?;
    drop(build_pool);
    let compile_s = clock.elapsed().as_secs_f64();
    let info = RunInfo {
        scene: args.scene.display().to_string(),
        primary_only: args.primary_only,
        reps: args.reps,
        spp,
        pattern,
        max_depth: render.max_depth,
        spheres: scene.geometry.spheres.len(),
        build_s: scene.build.seconds,
        width: scene.camera.width,
        height: scene.camera.height,
        frustum_culling: args.frustum_culling,
        bvh_preset: super::values::name(args.bvh_preset),
        host,
        old,
    };
    let what = match (args.primary_only, render.shade) {
        (true, _) => "primary rays only".to_owned(),
        (false, Shade::Whitted) => {
            format!("full Whitted render, {}, depth {}", info.pattern, info.max_depth)
        }
        (false, Shade::Ao(_)) => format!("full render, {}", info.pattern),
    };
    let what = format!(
        "{}: {} primitives ({} spheres), {}x{}; parse {parse_s:.3} s, compile {compile_s:.3} s (BVH build \
         {:.3} s, {:.1} bytes/sphere); {what}",
        info.scene,
        scene.geometry.len(),
        info.spheres,
        info.width,
        info.height,
        info.build_s,
        scene.bytes_per_sphere(),
    );
    Ok((scene, info, what))
}

/// Measures and prints each setting, threads by lanes, then the split by ray kind; the rows for
/// `--compare`.
fn measure_rows(
    args: &BenchArgs,
    scene: &mut Scene,
    info: &RunInfo,
    (threads, base): (&[usize], LanesArg),
    out: &mut impl Write,
) -> Result<Vec<Compared>> {
    let mut base_mrays: Option<f64> = None;
    let mut compared = Vec::new();
    let trace = if args.primary_only { Trace::PrimaryOnly } else { Trace::Render };
    let split = args.by_kind && !args.primary_only;
    let mut split_rows = Vec::new();
    for &t in threads {
        // One thread pool for every repetition, as the peer harnesses reuse theirs.
        let pool = thread_pool(Some(t))?;
        for &lanes in &args.lanes {
            // The scalar row walks the binary trees, every other row the wide nodes.
            let setting =
                measure_setting(scene, trace, (lanes.k(), lanes.is_scalar()), &pool, args.reps, split)
                    .map_err(|e| anyhow!("lanes {lanes}, {t} threads: {e}"))?;
            let row = &setting.measured;
            let mrays = row.mrays_per_s();
            if lanes == base && t == threads[0] {
                base_mrays = Some(mrays);
            }
            compared.push((lanes, t, mrays, info.old.and_then(|o| o.mrays(lanes, t))));
            if args.json {
                print_json(out, info, (lanes, t), row, setting.kinds.as_ref())?;
            } else {
                print_row(out, lanes, t, row, base_mrays)?;
            }
            if let Some(profile) = setting.kinds {
                split_rows.push(KindRow { lanes: lanes.to_string(), threads: t, profile });
            }
        }
    }
    if !args.json && !split_rows.is_empty() {
        let vs = if base.is_scalar() { "scalar" } else { "1 lane" };
        write_kind_table(out, &split_rows, (&base.to_string(), threads[0]), vs)?;
    }
    Ok(compared)
}

/// The scene changes the command line asks for.
fn overrides(args: &BenchArgs) -> Overrides {
    Overrides {
        camera: args.camera.overrides(),
        spp: args.spp,
        pattern: args.aa,
        shade: args.shade,
        max_depth: args.depth,
        primary_only: args.primary_only,
        ..Overrides::default()
    }
}
