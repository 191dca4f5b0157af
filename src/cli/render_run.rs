//! Runs `bareray render`: reads the scene, applies the command line, checks and renders it.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};

use super::render::{RenderArgs, DEMO_SCENE};
use super::render_report::{progress_bar, report, scene_warnings, Timings};
use bareray::compile::{load, Accel, CompileOptions, Scene};
use bareray::io::toml;
use bareray::math::Rgb;
use bareray::output::{BitDepth, Format, WriteOptions};
use bareray::render::{Window, TILE};
use bareray::scene::desc::PostFilter;
use bareray::scene::SceneDesc;
use bareray::settings::{Overrides, PatternName, SettingsError};
use bareray::still::{self, Job};

/// Runs `bareray render`: on several MPI ranks when started by an MPI launcher (the `mpi` feature).
pub(super) fn run(args: RenderArgs) -> Result<()> {
    #[cfg(feature = "mpi")]
    if let Some(ranks) = still::mpi::Ranks::start() {
        return run_ranks(args, ranks);
    }
    let mut time = Timings::default();
    let (scene, pool, job) = prepare(&args, &mut time, true)?;
    still::check(&scene, &job, pool.current_num_threads())?;
    let _counting = args.stats.then(bareray::accel::Probe::counting);
    let progress = progress_bar(args.quiet);
    let clock = Instant::now();
    still::catch_interrupts();
    let traced = still::render(&scene, &pool, &progress, &job);
    if let Err(still::StillError::Interrupted(_)) = &traced {
        progress.0.abandon();
    }
    let traced = traced?;
    progress.0.finish_and_clear();
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
    let _counting = args.stats.then(bareray::accel::Probe::counting);
    let progress = progress_bar(args.quiet || !root);
    let clock = Instant::now();
    let traced = ranks.render(&scene, &pool, &progress, &job);
    progress.0.finish_and_clear();
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
    let pool = bareray::render::thread_pool(threads)?;
    let clock = Instant::now();
    let memory = args.memory.unwrap_or_else(bareray::compile::memory::available);
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
    let to_stdout = bareray::output::is_stdout(&output);
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
    overrides(args).apply(desc).map_err(settings_error)?;
    if loaded.accel == Accel::Particles {
        if let Some(why) = load::particles_unsupported(desc) {
            return Err(super::usage(format!("--accel pkd: {why}")));
        }
    }
    let window = args.window(desc.camera.width, desc.camera.height)?;
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
        aov: args.aov.as_ref().map(|which| (which.0.clone(), bareray::aov::aov_path(&output))),
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

/// The scene on standard input, in the format --format names.
fn read_stdin_scene(args: &RenderArgs) -> Result<SceneDesc> {
    let Some(format) = args.format.as_deref().and_then(bareray::io::SceneFormat::from_name) else {
        return Err(super::usage(
            "a scene read from standard input (`-`) needs --format toml, nff, xyzr or f32r, or a particle \
             format: xyz, pdb, pqr, gro or lammpstrj",
        ));
    };
    let mut source = Vec::new();
    std::io::Read::read_to_end(&mut std::io::stdin(), &mut source)
        .context("<stdin>: cannot read the scene")?;
    let name = Path::new("<stdin>");
    let read = bareray::io::parse_with(format, name, source, &args.particles.options())?;
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
                    PatternName::of(scene.render.pattern).long,
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

fn stem(path: &Path) -> String {
    path.file_stem().map_or_else(|| "out".to_owned(), |s| s.to_string_lossy().into_owned())
}

/// Reads a scene file, choosing the reader by extension, on `pool`'s threads (the sphere lists are read in
/// parallel).
pub(super) fn load_scene(path: &Path, pool: &rayon::ThreadPool) -> Result<SceneDesc> {
    super::particle_args::load_scene_with(path, pool, &bareray::io::LoadOptions::default())
}

/// The scene changes the command line asks for.
fn overrides(args: &RenderArgs) -> Overrides {
    Overrides {
        camera: args.camera.overrides(),
        ambient: args.ambient.as_ref().map(|a| a.0.clone()),
        spp: args.spp,
        pattern: args.aa,
        filter: args.filter,
        shade: args.shade,
        postfilter: args.postfilter.as_deref().map(|p| match p {
            "lecture" | "lecture-3x3" => PostFilter::Lecture3x3,
            _ => PostFilter::None,
        }),
        max_depth: args.depth,
        transfer: args.transfer.map(Into::into),
        primary_only: false,
    }
}

/// An override the scene cannot take, as an argument error naming its flag.
pub(super) fn settings_error(e: SettingsError) -> anyhow::Error {
    match e {
        SettingsError::Spp(m) => super::usage(format!("--spp: {m}")),
        e @ SettingsError::Ambient { .. } => super::usage(format!("--{e}")),
    }
}
