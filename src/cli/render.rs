//! `bareray render`.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use super::camera_args::CameraArgs;
use super::particle_args::ParticleArgs;
use super::values::{AccelArg, BvhPresetArg, LanesArg, TransferArg};
use crate::aov::{self, AovList};
use crate::compile::{load, Accel, CompileOptions, Scene};
use crate::io::toml;
use crate::math::Rgb;
use crate::output::{BitDepth, Format, WriteOptions};
use crate::render::{Traced, Window, TILE};
use crate::scene::desc::{Pattern, PostFilter};
use crate::scene::SceneDesc;
use crate::still::{self, Job};

/// The demo scene rendered when no scene file is given.
pub const DEMO_SCENE: &str = include_str!("../../scenes/whitted.toml");

/// Arguments of `bareray render`.
#[derive(Args, Debug)]
#[command(
    after_help = "Examples:\n  bareray render                       # the built-in demo scene -> demo.png\n  \
bareray render scenes/transforms.toml -o out.exr --spp 16\n  \
bareray render scenes/balls3.nff -o balls3.ppm --width 1024\n  \
bareray render scenes/field.toml --width 1920 --threads 2\n\n\
Exit codes: 0 success; 2 argument errors (nothing rendered); 1 scene, render or write errors."
)]
pub struct RenderArgs {
    /// Scene file: .toml (bareray's format), .nff (SPD's Neutral File Format), .xyzr (`x y z r` per
    /// line), .f32r (binary x y z r records), or a particle file: .xyz/.extxyz, .pdb/.ent, .pqr, .gro,
    /// .dump/.lammpstrj, each maybe compressed (.gz, .bz2); `-` reads the scene from standard input (name
    /// its format with --format). Without it, the built-in demo scene (scenes/whitted.toml) is rendered.
    pub scene: Option<PathBuf>,
    /// The format of a scene read from standard input (`render -`): toml, nff, xyzr, f32r, or a particle
    /// format: xyz, pdb, pqr, gro, lammpstrj (compressed input is recognised by its first bytes).
    #[arg(long, value_parser = ["toml", "nff", "xyzr", "f32r", "xyz", "extxyz", "pdb", "ent", "pqr", "gro", "dump", "lammpstrj"])]
    pub format: Option<String>,
    /// Output image; the extension picks the format: .png (8-bit), .exr (linear float RGB), .ppm or .pnm
    /// (binary 8-bit PPM, P6), .hdr (Radiance), .tif/.tiff (uncompressed RGB), .jpg/.jpeg (quality 92);
    /// `-` writes PPM to standard output (the summary then goes
    /// to standard error). Default: the scene's name with .png, in the current directory.
    #[arg(short, long, value_parser = parse_output)]
    pub output: Option<PathBuf>,
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub particles: ParticleArgs,
    /// Samples per pixel on a regular n×n grid (1, 4, 9, 16, ...); overrides the scene.
    #[arg(long, value_parser = parse_spp, conflicts_with = "aa")]
    pub spp: Option<u32>,
    /// Sampling method and samples per pixel N, overriding the scene: `grid:N` (regular √N×√N grid of
    /// stratum centres), `stratified:N` (one jittered sample per stratum of a √N×√N grid), `r2:N` (N points
    /// of the R2 low-discrepancy sequence, rotated per pixel), `sobol:N` (N points of the Sobol' sequence,
    /// Owen-scrambled per pixel; a (0, 2)-net at powers of two), `lecture` (the 9-point half-pixel grid shared
    /// with the neighbours), `adaptive[:THRESHOLD,DEPTH]` (Whitted: pixel corners shared, squares split where
    /// their corners differ by more than THRESHOLD in a channel, down to DEPTH levels; default 0.1,2),
    /// `coverage` (prefiltering: each sphere's exact covered area of the pixel, one ray per covered part and
    /// one for the rest). Jitter and rotation are seeded by the pixel, so every width and thread count
    /// gives the same image.
    #[arg(long, value_parser = super::values::parse_aa)]
    pub aa: Option<Pattern>,
    /// Shading, overriding the scene: `whitted` (lights, shadows, mirrors, refraction) or
    /// `ao[:SAMPLES[,DISTANCE]]`, ambient occlusion: at each camera ray's hit SAMPLES (1 to 4096, default
    /// 16) cosine-weighted occlusion rays of length DISTANCE (scene units; default a quarter of the
    /// diagonal of the box around the bounded primitives); the pixel is the surface colour times the share
    /// of them that nothing blocks. Every antialiasing sample gets its own set.
    #[arg(long, value_name = "MODE", value_parser = super::values::parse_shade)]
    pub shade: Option<crate::scene::desc::Shade>,
    /// Reconstruction filter over the samples, overriding the scene: `box`, `tent`, `gaussian` or `mitchell`,
    /// optionally with a radius in pixels (`tent:1.5`; defaults 0.5, 1, 1.5, 2). Each sample counts in every
    /// pixel whose centre is within the radius; without a filter a pixel averages its own samples.
    #[arg(long, value_parser = super::values::parse_filter)]
    pub filter: Option<crate::scene::desc::Filter>,
    /// Postfilter over the finished image, overriding the scene: `lecture` or `lecture-3x3` (the lecture's 3×3 kernel, ½ at
    /// the centre and 1/16 at each neighbour, renormalised at the border) or `none`.
    #[arg(long, value_parser = ["none", "lecture", "lecture-3x3"])]
    pub postfilter: Option<String>,
    /// Bits per channel of a PNG or TIFF: 8 or 16 (16 keeps the shading's gradients without banding).
    #[arg(long, default_value_t = 8, value_parser = parse_bit_depth)]
    pub bit_depth: u8,
    /// Reflection/refraction depth limit; overrides the scene.
    #[arg(long)]
    pub depth: Option<u32>,
    /// How values become 8-bit PNG/PPM pixels: `srgb` encodes them as linear light with the sRGB curve
    /// (TOML scenes' default), `linear` writes them as they are, clamped, ×255 (NFF's and xyzr's default,
    /// as SPD, POV-Ray and Tachyon write NFF colours). Overrides the scene; PNG records it. EXR holds
    /// linear floats either way.
    #[arg(long, value_enum)]
    pub transfer: Option<TransferArg>,
    /// Ambient coefficients of the scene's materials, overriding the scene: one value for every material,
    /// or a comma list with one value per material: an NFF's `f` lines in file order, a TOML's `default`
    /// material and then its named ones alphabetically. NFF has no ambient term and its materials get 0.1, as SPD's own NFF reader gives them; SPD's
    /// POV-Ray output carries the generator's values (balls: `--ambient 0.2,0`, the floor and the spheres).
    #[arg(long, value_name = "A[,A...]", value_parser = super::values::parse_ambient)]
    pub ambient: Option<super::values::AmbientList>,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// Also write raw primary-ray results (one sample per pixel at pixel centres) as float EXR channels
    /// to OUT's name with `.aov.exr`: a comma list of depth (channel Z), normal (N.X, N.Y, N.Z), id.
    #[arg(long, value_parser = aov::parse_list)]
    pub aov: Option<AovList>,
    /// Render only the pixels X0..X1, Y0..Y1 of the full image (X1, Y1 exclusive), with the full image's
    /// camera: regions rendered apart and pasted together (`bareray merge`) are the full image's bits. The
    /// file records where it belongs (PNG `Region` text, EXR data window, PPM header comment).
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = parse_region, conflicts_with = "crop")]
    pub region: Option<[u32; 4]>,
    /// Render a region given as fractions of the image, as pbrt's --cropwindow: columns from ⌈X0·width⌉ to
    /// ⌈X1·width⌉, rows from ⌈Y0·height⌉ to ⌈Y1·height⌉.
    #[arg(long, value_name = "X0,X1,Y0,Y1", value_parser = parse_crop)]
    pub crop: Option<[f64; 4]>,
    /// Keep the finished rows in a side file beside the output (`.NAME.resume`) as the render goes, and
    /// use one an interrupted run of the same command left: only the rest is traced, and the image is the
    /// bytes of an uninterrupted render. Ctrl-C stops such a render at the next band, keeping the side file.
    #[arg(long)]
    pub resume: bool,
    /// Rows per band: the image is traced and written band by band, so memory holds a few bands of this
    /// many rows (rounded up to whole 16-row tiles). Default: about 32 MiB of pixels per band.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub band_rows: Option<u32>,
    /// Print a scene summary, rays by kind and the time split (parse, build, render and write).
    #[arg(long)]
    pub stats: bool,
    /// Rays per packet: 1 (single-ray SIMD: one ray against a BVH node's children, and a leaf's spheres, at
    /// once), 4, 8 or 16 (the default: fastest on every scene in scenes/ but the refraction-heavy whitted.toml,
    /// docs/perf-log/2026-11.md); or `scalar`: one ray against one box and one primitive at a time, over
    /// binary BVHs. The image is identical at every width and on the scalar path.
    #[arg(long, default_value = "16", value_parser = parse_lanes)]
    pub lanes: LanesArg,
    /// The BVH builder: bareray's binned SAH (the default), or an obvhs PLOC preset (PERF.md, "Tree builder").
    #[arg(long, value_enum, default_value_t = BvhPresetArg::Sah)]
    pub bvh_preset: BvhPresetArg,
    /// How the spheres are searched: `auto` (a BVH, or the particle tree when the BVH would not fit in
    /// memory), `bvh`, `brute` or `pkd` (the particle tree: 5 bytes per sphere beside the spheres; an .f32r
    /// file is mapped, not read). The image is the same bits whichever is used.
    #[arg(long, value_enum, default_value_t = AccelArg::Auto)]
    pub accel: AccelArg,
    /// The memory a render may plan for, in bytes with an optional K, M, G or T suffix (powers of 1024).
    /// Default: what the system has available (MemAvailable, or a container's limit). Decides what `auto`
    /// picks; a field that fits neither structure is refused before it is loaded.
    #[arg(long, value_name = "BYTES", value_parser = super::values::parse_bytes)]
    pub memory: Option<u64>,
    /// No progress bar and no summary line.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Wall-clock seconds of each stage.
#[derive(Default)]
struct Timings {
    parse: f64,
    build: f64,
    /// Tracing, and the writing that overlaps it.
    render: f64,
}

/// Runs `bareray render`: on several MPI ranks when started by an MPI launcher (the `mpi` feature).
pub fn run(args: RenderArgs) -> Result<()> {
    #[cfg(feature = "mpi")]
    if let Some(ranks) = still::mpi::Ranks::start() {
        return run_ranks(args, ranks);
    }
    let mut time = Timings::default();
    let (scene, pool, job) = prepare(&args, &mut time, true)?;
    still::check(&scene, &job, pool.current_num_threads())?;
    let _counting = args.stats.then(crate::accel::Probe::counting);
    let progress = progress_bar(args.quiet);
    let clock = Instant::now();
    still::catch_interrupts();
    let traced = still::render(&scene, &pool, &progress, &job);
    if let Err(still::StillError::Interrupted(_)) = &traced {
        progress.abandon();
    }
    let traced = traced?;
    progress.finish_and_clear();
    time.render = clock.elapsed().as_secs_f64();
    report(&args, &scene, &job, &traced, &time);
    Ok(())
}

/// `run` on one rank of an MPI job (`still::mpi`): every rank prepares, rank 0 checks, all agree to go on
/// or stop; rank 0 alone writes and prints.
#[cfg(feature = "mpi")]
fn run_ranks(args: RenderArgs, ranks: still::mpi::Ranks) -> Result<()> {
    let root = ranks.is_root();
    let mut time = Timings::default();
    let ready = if args.resume {
        // The side file is written by one process; a distributed render would need every rank's rows in it.
        Err(super::usage("--resume renders in one process, not under an MPI launcher"))
    } else {
        prepare(&args, &mut time, root)
    };
    let ready = ready.and_then(|(scene, pool, job)| {
        if root {
            still::check(&scene, &job, pool.current_num_threads())?;
        }
        Ok((scene, pool, job))
    });
    let (scene, pool, job) = match ranks.agree(ready, |e| super::exit_code(e).into()) {
        Ok(setup) => setup,
        // Printed before MPI is finalised: the other ranks exit once it is, and the launcher may then end
        // this one.
        Err(e) => ranks.exit(super::report(&e).into()),
    };
    let _counting = args.stats.then(crate::accel::Probe::counting);
    let progress = progress_bar(args.quiet || !root);
    let clock = Instant::now();
    let traced = ranks.render(&scene, &pool, &progress, &job);
    progress.finish_and_clear();
    time.render = clock.elapsed().as_secs_f64();
    if let Some(traced) = traced {
        report(&args, &scene, &job, &traced, &time);
    }
    Ok(())
}

/// Reads the scene, applies the command line and compiles it: the scene, the render's threads and the job.
/// Scene warnings are printed when `warn`.
fn prepare(args: &RenderArgs, time: &mut Timings, warn: bool) -> Result<(Scene, rayon::ThreadPool, Job)> {
    let threads = args.threads.map(|t| t as usize);
    // Reading and the build run on the render's threads too: `--threads 1` means one core throughout.
    let pool = crate::render::thread_pool(threads)?;
    let clock = Instant::now();
    let memory = args.memory.unwrap_or_else(crate::compile::memory::available);
    let in_memory = |desc| load::loaded_desc(desc, args.accel.into(), memory);
    let (mut loaded, name) = match &args.scene {
        Some(path) if path == Path::new("-") => {
            (in_memory(pool.install(|| read_stdin_scene(args))?), "stdin".to_owned())
        }
        Some(path) => {
            let loaded =
                pool.install(|| load::load(path, args.accel.into(), memory, &args.particles.options()))?;
            if warn {
                super::particle_args::print_warnings(path, &loaded.warnings);
            }
            (loaded, stem(path))
        }
        None => (in_memory(toml::parse(Path::new("<built-in demo>"), DEMO_SCENE)?), "demo".to_owned()),
    };
    let desc = &mut loaded.desc;
    let output = args.output.clone().unwrap_or_else(|| PathBuf::from(format!("{name}.png")));
    let to_stdout = crate::output::is_stdout(&output);
    if to_stdout && (args.aov.is_some() || args.resume) {
        return Err(super::usage("-o - (standard output) takes neither --aov nor --resume: they need files"));
    }
    // Fail on an output that cannot be written now, not after the render.
    let format = Format::from_path(&output)?;
    if args.bit_depth == 16 && !matches!(format, Format::Png | Format::Tiff) {
        return Err(super::usage(format!(
            "--bit-depth 16: {} is not a PNG or TIFF (16 bits are for those)",
            output.display()
        )));
    }
    apply_overrides(desc, args)?;
    if loaded.accel == Accel::Particles {
        if let Some(why) = load::particles_unsupported(desc) {
            return Err(super::usage(format!("--accel pkd: {why}")));
        }
    }
    let window = region(args, desc.camera.width, desc.camera.height)?;
    // A mapped field's spheres are not in the description: its size, bounds and modification time stand
    // for them.
    let field = loaded.mapped.as_ref().map(|m| {
        let modified = args.scene.as_ref().and_then(|p| std::fs::metadata(p).ok()?.modified().ok());
        format!("{m:?} {modified:?}")
    });
    let settings = args.resume.then(|| settings_hash(args, desc, field.as_deref(), window, &output));
    if window != Window::whole(desc.camera.width, desc.camera.height)
        && !matches!(format, Format::Png | Format::Exr | Format::Ppm)
    {
        return Err(super::usage(format!(
            "--region and --crop write PNG, EXR or PPM, which record where the region belongs; not {}",
            format.name()
        )));
    }
    let scene_name = args.scene.as_deref().unwrap_or(Path::new("<built-in demo>"));
    if warn {
        for warning in scene_warnings(desc).into_iter().filter(|_| loaded.mapped.is_none()) {
            eprintln!("warning: {}: {warning}", scene_name.display());
        }
    }
    time.parse = clock.elapsed().as_secs_f64();

    // Build: the scene compiled for rendering, the BVH included (`scene.build.seconds` is the BVH's part).
    let clock = Instant::now();
    let options = CompileOptions {
        preset: args.bvh_preset.into(),
        scalar: args.lanes.is_scalar(),
        ..CompileOptions::default()
    };
    let scene = pool.install(|| Scene::compile_loaded(loaded, options)).context("camera")?;
    time.build = clock.elapsed().as_secs_f64();

    let job = Job {
        write: write_options(args, &scene, scene_name),
        window,
        lanes: args.lanes.k(),
        aov: args.aov.as_ref().map(|which| (which.0.clone(), aov::aov_path(&output))),
        resume: settings,
        ..Job::whole(&scene, &output, WriteOptions::default())?
    };
    let job = match args.band_rows {
        // A budget that gives exactly the rows asked for (band_rows rounds down to whole tiles).
        Some(rows) => {
            let rows = rows.div_ceil(TILE) * TILE;
            let band_budget = rows as usize * job.window.width() as usize * size_of::<Rgb>();
            Job { band_budget, min_bands: 1, ..job }
        }
        None => job,
    };
    Ok((scene, pool, job))
}

/// The summary line, or the statistics with `--stats`; nothing with `--quiet`.
fn report(args: &RenderArgs, scene: &Scene, job: &Job, traced: &Traced, time: &Timings) {
    let to_stdout = crate::output::is_stdout(&job.output);
    if args.stats {
        // With the image on standard output, the report goes to standard error.
        let mut out: Box<dyn std::io::Write> =
            if to_stdout { Box::new(std::io::stderr()) } else { Box::new(std::io::stdout()) };
        print_stats(&mut out, scene, job, traced, time);
    } else if !args.quiet {
        let line = summary(&job.output, job, traced, time);
        // With the image on standard output, the summary goes beside it, to standard error.
        if to_stdout {
            eprintln!("{line}");
        } else {
            println!("{line}");
        }
    }
}

/// The scene on standard input, in the format --format names.
fn read_stdin_scene(args: &RenderArgs) -> Result<SceneDesc> {
    let Some(format) = args.format.as_deref().and_then(crate::io::SceneFormat::from_name) else {
        return Err(super::usage(
            "a scene read from standard input (`-`) needs --format toml, nff, xyzr or f32r, or a particle \
             format: xyz, pdb, pqr, gro or lammpstrj",
        ));
    };
    let mut source = Vec::new();
    std::io::Read::read_to_end(&mut std::io::stdin(), &mut source)
        .context("<stdin>: cannot read the scene")?;
    let name = Path::new("<stdin>");
    let read = crate::io::parse_with(format, name, source, &args.particles.options())?;
    super::particle_args::print_warnings(name, &read.warnings);
    Ok(read.desc)
}

/// What decides the output's bytes, hashed: the version, the scene after the command line's overrides
/// (every field, in Rust's exact float notation), the settings the file records and the part rendered.
fn settings_hash(
    args: &RenderArgs,
    desc: &SceneDesc,
    field: Option<&str>,
    window: Window,
    output: &Path,
) -> u64 {
    struct Fnv(u64);
    impl std::fmt::Write for Fnv {
        fn write_str(&mut self, s: &str) -> std::fmt::Result {
            self.0 = s.bytes().fold(self.0, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3));
            Ok(())
        }
    }
    let mut hash = Fnv(0xcbf2_9ce4_8422_2325);
    let _ = std::fmt::Write::write_fmt(
        &mut hash,
        format_args!(
            "bareray {} {:?} {:?} {:?} {} {:?} {:?} {:?} {:?}",
            env!("CARGO_PKG_VERSION"),
            desc,
            field,
            window,
            args.bit_depth,
            args.scene,
            output.extension(),
            args.aov,
            args.bvh_preset,
        ),
    );
    hash.0
}

/// The file's transfer, bit depth and text: the renderer, the scene file, and the size and sampling.
fn write_options(args: &RenderArgs, scene: &Scene, scene_name: &Path) -> WriteOptions {
    WriteOptions {
        transfer: scene.render.transfer,
        bit_depth: if args.bit_depth == 16 { BitDepth::Sixteen } else { BitDepth::Eight },
        text: vec![
            ("Software".to_owned(), format!("bareray {}", env!("CARGO_PKG_VERSION"))),
            ("Source".to_owned(), scene_name.display().to_string()),
            (
                "Comment".to_owned(),
                format!(
                    "{}x{}, {}, depth {}{}",
                    scene.camera.width,
                    scene.camera.height,
                    pattern_name(scene.render.pattern),
                    scene.render.max_depth,
                    args.ambient.as_ref().map_or_else(String::new, |a| {
                        let list: Vec<String> = a.0.iter().map(f32::to_string).collect();
                        format!(", ambient {}", list.join(","))
                    })
                ),
            ),
        ],
    }
}

/// The pixels to render: `--region`, `--crop` (pbrt's rounding: ⌈fraction × size⌉ at both ends), or
/// the whole `width × height` image. A region outside the image or empty is an argument error.
fn region(args: &RenderArgs, width: u32, height: u32) -> Result<Window> {
    let window = match (args.region, args.crop) {
        (Some([x0, y0, x1, y1]), _) => Window { x0, y0, x1, y1 },
        (None, Some([x0, x1, y0, y1])) => {
            let at = |f: f64, size: u32| (f * f64::from(size)).ceil() as u32;
            Window { x0: at(x0, width), y0: at(y0, height), x1: at(x1, width), y1: at(y1, height) }
        }
        (None, None) => return Ok(Window::whole(width, height)),
    };
    let Window { x0, y0, x1, y1 } = window;
    if x0 >= x1 || y0 >= y1 || x1 > width || y1 > height {
        return Err(super::usage(format!(
            "the region {x0},{y0},{x1},{y1} is empty or reaches outside the {width}x{height} image"
        )));
    }
    Ok(window)
}

/// The render's tiles as the bar's length and position.
impl crate::render::Progress for ProgressBar {
    fn start(&self, total: u64) {
        self.set_length(total);
    }
    fn tile_done(&self, _: u64, _: u64) {
        self.inc(1);
    }
}

fn progress_bar(quiet: bool) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(0);
    let style =
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {pos}/{len} tiles, eta {eta}")
            .expect("valid template");
    bar.set_style(style);
    bar
}

fn summary(output: &Path, job: &Job, r: &Traced, time: &Timings) -> String {
    let c = r.counts;
    let output = if crate::output::is_stdout(output) { Path::new("<stdout>") } else { output };
    format!(
        "{}: {}x{} in {:.3} s (parse {:.3} s, build {:.3} s); {} rays ({} primary, {} shadow, {} reflection, \
         {} refraction, {} ao), {:.2} Mrays/s",
        output.display(),
        job.window.width(),
        job.window.height(),
        time.render,
        time.parse,
        time.build,
        c.total(),
        c.primary,
        c.shadow,
        c.reflection,
        c.refraction,
        c.ao,
        c.total() as f64 / r.seconds / 1e6
    )
}

fn print_stats(out: &mut dyn std::io::Write, scene: &Scene, job: &Job, r: &Traced, time: &Timings) {
    let g = &scene.geometry;
    let features = crate::compile::features::Features::of(scene);
    let n = features.counts;
    let _ = writeln!(
        out,
        "scene: {} ({}, {}, {}, {}, {}{}), {}, {}{}",
        plural(g.len(), "primitive"),
        plural(n.spheres, "sphere"),
        plural(n.ellipsoids, "ellipsoid"),
        plural(n.planes, "plane"),
        plural(n.polygons, "polygon"),
        plural(n.cones, "cone"),
        g.kinds.counted().iter().map(|c| format!(", {c}")).collect::<String>(),
        plural(scene.lights.len(), "light"),
        plural(scene.materials.len(), "material"),
        match g.sphere_colors() {
            0 => String::new(),
            c => format!(", {} (3 bytes each)", plural(c, "sphere colour")),
        }
    );
    let w = job.window;
    let region = if w == Window::whole(scene.camera.width, scene.camera.height) {
        String::new()
    } else {
        format!(
            " (region {},{},{},{} of {}x{})",
            w.x0, w.y0, w.x1, w.y1, scene.camera.width, scene.camera.height
        )
    };
    let _ = writeln!(
        out,
        "image: {}x{}{region}, {}, {} shading, {} transfer, in bands of {} rows",
        w.width(),
        w.height(),
        pattern_name(scene.render.pattern),
        super::values::shade_name(scene.render.shade),
        scene.render.transfer.name(),
        job.band_rows()
    );
    let _ = writeln!(out, "features: {features}");
    let search = |bvh: &Option<crate::bvh::Bvh>| if bvh.is_some() { "BVH" } else { "brute force" };
    let spheres = match (&scene.accel_note, g.particles.is_empty()) {
        (_, true) => {
            format!("{} ({:.1} bytes/sphere with the nodes)", search(&g.sphere_bvh), scene.bytes_per_sphere())
        }
        (why, false) => format!(
            "the particle tree{} ({:.1} bytes/sphere with the keys{}{})",
            if g.particles.is_mapped() { " over the mapped file" } else { "" },
            scene.bytes_per_sphere(),
            if why.is_some() { "; chosen by auto: " } else { "" },
            why.as_deref().unwrap_or_default()
        ),
    };
    let _ = writeln!(
        out,
        "accel: spheres by {spheres}, polygons by {}, ellipsoids by {}, cones by {}{}",
        search(&g.polygon_bvh),
        search(&g.shape_bvh),
        search(&g.cone_bvh),
        (crate::kinds::NAMES.iter().zip(g.kinds.trees()).zip(g.kinds.counts()))
            .filter(|(_, n)| *n > 0)
            .map(|((name, tree), _)| format!(", {name} by {}", if tree { "BVH" } else { "brute force" }))
            .collect::<String>(),
    );
    let c = r.counts;
    let _ = writeln!(
        out,
        "rays: {} total: {} primary, {} shadow, {} reflection, {} refraction, {} ao",
        c.total(),
        c.primary,
        c.shadow,
        c.reflection,
        c.refraction,
        c.ao
    );
    let _ = writeln!(
        out,
        "intersection tests: {} packet-primitive, {} packet-box, at {} rays per packet",
        r.work.prim_tests, r.work.box_tests, job.lanes
    );
    let _ = writeln!(
        out,
        "time: parse {:.3} s, build {:.3} s (scene and BVH), render and write {:.3} s (tracing {:.3} s)",
        time.parse, time.build, time.render, r.seconds
    );
    let _ = writeln!(out, "throughput: {:.2} Mrays/s", c.total() as f64 / r.seconds / 1e6);
}

/// `n thing` or `n things`.
fn plural(n: usize, thing: &str) -> String {
    if n == 1 {
        format!("1 {thing}")
    } else {
        format!("{n} {thing}s")
    }
}

/// The sampling pattern as the summary prints it.
fn pattern_name(pattern: Pattern) -> String {
    match pattern {
        Pattern::Grid(n) => {
            let spp = n * n;
            format!("{spp} sample{} per pixel ({n}×{n} grid)", if spp == 1 { "" } else { "s" })
        }
        Pattern::Stratified(n) => {
            let spp = n * n;
            format!("{spp} sample{} per pixel ({n}×{n} jittered grid)", if spp == 1 { "" } else { "s" })
        }
        Pattern::R2(count) => {
            format!(
                "{count} sample{} per pixel (R2 sequence, rotated per pixel)",
                if count == 1 { "" } else { "s" }
            )
        }
        Pattern::Sobol(count) => {
            format!(
                "{count} sample{} per pixel (Sobol' sequence, Owen-scrambled per pixel)",
                if count == 1 { "" } else { "s" }
            )
        }
        Pattern::HalfPixel => {
            "half-pixel pattern (9 samples per pixel shared with the neighbours)".to_owned()
        }
        Pattern::Adaptive { threshold, depth } => {
            format!("adaptive: corners shared, squares split where they differ by > {threshold}, to depth {depth}")
        }
        Pattern::Coverage => "coverage: spheres' covered areas per pixel, one ray per part".to_owned(),
    }
}

/// What a scene lacks that makes its image surely not what was meant: no primitives at all, or no lights
/// while some material has a diffuse or specular term (which only lights light).
pub fn scene_warnings(desc: &SceneDesc) -> Vec<&'static str> {
    let mut warnings = Vec::new();
    if desc.spheres.is_empty()
        && desc.shapes.is_empty()
        && desc.polygons.is_empty()
        && desc.cones.is_empty()
        && desc.kinds.is_empty()
    {
        warnings.push("no objects");
    }
    if desc.lights.is_empty() && desc.materials.iter().any(|m| m.diffuse > 0.0 || m.specular > 0.0) {
        warnings.push("no lights");
    }
    warnings
}

/// Parses `--output`: the extension must name an image format.
fn parse_output(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    Format::from_extension(&path).map_err(|_| {
        "unknown image format (use .png, .exr, .ppm or .pnm, .hdr, or - for PPM to standard output)"
            .to_owned()
    })?;
    Ok(path)
}

/// Parses `--region X0,Y0,X1,Y1`: four pixel coordinates.
fn parse_region(s: &str) -> Result<[u32; 4], String> {
    let v: Option<Vec<u32>> = s.split(',').map(|p| p.trim().parse().ok()).collect();
    match v.as_deref() {
        Some(&[x0, y0, x1, y1]) if x0 < x1 && y0 < y1 => Ok([x0, y0, x1, y1]),
        _ => {
            Err(format!("expected X0,Y0,X1,Y1 with X0 < X1 and Y0 < Y1 (pixels, ends exclusive), got `{s}`"))
        }
    }
}

/// Parses `--crop X0,X1,Y0,Y1`: four fractions in [0, 1].
fn parse_crop(s: &str) -> Result<[f64; 4], String> {
    let v: Option<Vec<f64>> = s.split(',').map(|p| p.trim().parse().ok()).collect();
    match v.as_deref() {
        Some(&[x0, x1, y0, y1])
            if [x0, x1, y0, y1].iter().all(|f| (0.0..=1.0).contains(f)) && x0 < x1 && y0 < y1 =>
        {
            Ok([x0, x1, y0, y1])
        }
        _ => Err(format!("expected X0,X1,Y0,Y1, fractions in [0, 1] with X0 < X1 and Y0 < Y1, got `{s}`")),
    }
}

/// Parses `--spp`: a square number.
pub(super) fn parse_spp(s: &str) -> Result<u32, String> {
    let spp = s
        .trim()
        .parse::<u32>()
        .map_err(|_| format!("expected a square number (1, 4, 9, 16, ...), got `{s}`"))?;
    toml::grid_side(spp)?;
    Ok(spp)
}

/// Parses `--bit-depth`: 8 or 16.
fn parse_bit_depth(s: &str) -> Result<u8, String> {
    match s.trim() {
        "8" => Ok(8),
        "16" => Ok(16),
        _ => Err(format!("PNG takes 8 or 16 bits per channel, got `{s}`")),
    }
}

/// Parses a thread count, 1 to 1024.
pub fn parse_threads(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(t) if (1..=1024).contains(&t) => Ok(t),
        _ => Err("thread counts run from 1 to 1024".to_owned()),
    }
}

pub use super::values::parse_lanes;

fn stem(path: &Path) -> String {
    path.file_stem().map_or_else(|| "out".to_owned(), |s| s.to_string_lossy().into_owned())
}

/// Reads a scene file, choosing the reader by extension, on `pool`'s threads (the sphere lists are read in
/// parallel).
pub fn load_scene(path: &Path, pool: &rayon::ThreadPool) -> Result<SceneDesc> {
    super::particle_args::load_scene_with(path, pool, &crate::io::LoadOptions::default())
}

fn apply_overrides(desc: &mut SceneDesc, args: &RenderArgs) -> Result<()> {
    args.camera.apply(desc);
    if let Some(ambient) = &args.ambient {
        set_ambient(desc, &ambient.0)?;
    }
    if let Some(spp) = args.spp {
        desc.render.pattern = Pattern::Grid(toml::grid_side(spp).expect("--spp was checked"));
    }
    if let Some(pattern) = args.aa {
        desc.render.pattern = pattern;
    }
    if let Some(filter) = args.filter {
        desc.render.filter = Some(filter);
    }
    if let Some(shade) = args.shade {
        desc.render.shade = shade;
    }
    match args.postfilter.as_deref() {
        Some("lecture") => desc.render.postfilter = PostFilter::Lecture3x3,
        Some(_) => desc.render.postfilter = PostFilter::None,
        None => {}
    }
    if let Some(d) = args.depth {
        desc.render.max_depth = d;
    }
    if let Some(t) = args.transfer {
        desc.render.transfer = t.into();
    }
    Ok(())
}

/// `--ambient`: one value for every material, or one per material in definition order.
fn set_ambient(desc: &mut SceneDesc, ambient: &[f32]) -> Result<()> {
    let materials = &mut desc.materials;
    match ambient {
        [a] => materials.iter_mut().for_each(|m| m.ambient = *a),
        list if list.len() == materials.len() => {
            materials.iter_mut().zip(list).for_each(|(m, a)| m.ambient = *a);
        }
        list => {
            return Err(super::usage(format!(
                "--ambient gave {} values; the scene defines {} material{} (one value sets them all)",
                list.len(),
                materials.len(),
                if materials.len() == 1 { "" } else { "s" }
            )))
        }
    }
    Ok(())
}
