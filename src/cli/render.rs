//! `bareray render`.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use super::camera_args::CameraArgs;
use crate::aov::{self, AovList};
use crate::geometry::ShapeKind;
use crate::output::{write_image, Format};
use crate::render::{render_lanes, Rendered, LANE_CHOICES};
use crate::scene::desc::Pattern;
use crate::scene::{toml, Accel, BvhPreset, Scene, SceneDesc};

/// The demo scene rendered when no scene file is given.
pub const DEMO_SCENE: &str = include_str!("../../scenes/whitted.toml");

/// Arguments of `bareray render`.
#[derive(Args, Debug)]
#[command(
    after_help = "Examples:\n  bareray render                       # the built-in demo scene -> demo.png\n  \
bareray render scenes/ellipsoids.toml -o out.exr --spp 16\n  \
bareray render scenes/field.toml --width 1920 --threads 2"
)]
pub struct RenderArgs {
    /// Scene file (.toml). Without it, the built-in demo scene (scenes/whitted.toml) is rendered.
    pub scene: Option<PathBuf>,
    /// Output image; the extension picks the format: .png (8-bit sRGB), .exr (linear float), .ppm.
    /// Default: the scene's name with .png, in the current directory.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    #[command(flatten)]
    pub camera: CameraArgs,
    /// Samples per pixel on a regular n×n grid (1, 4, 9, 16, ...); overrides the scene.
    #[arg(long)]
    pub spp: Option<u32>,
    /// Reflection/refraction depth limit; overrides the scene.
    #[arg(long)]
    pub depth: Option<u32>,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// Also write raw primary-ray results (one sample per pixel at pixel centres) as float EXR channels
    /// to OUT's name with `.aov.exr`: a comma list of depth (channel Z), normal (N.X, N.Y, N.Z), id.
    #[arg(long, value_parser = aov::parse_list)]
    pub aov: Option<AovList>,
    /// Print a scene summary, rays by kind and the time split.
    #[arg(long)]
    pub stats: bool,
    /// Rays per packet: 1 (the scalar reference path), 4, 8 or 16 (the default: fastest on every scene in
    /// scenes/ but the refraction-heavy whitted.toml, PERF.md). The image is identical at every width.
    #[arg(long, default_value_t = 16, value_parser = parse_lanes)]
    pub lanes: usize,
    /// obvhs build preset for the BVH over the spheres (`very-fast` builds quickest; PERF.md compares them).
    #[arg(long, value_enum, default_value_t = BvhPreset::Fast)]
    pub bvh_preset: BvhPreset,
    /// No progress bar and no summary line.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Wall-clock seconds of each stage.
#[derive(Default)]
struct Timings {
    parse: f64,
    build: f64,
    render: f64,
    aov: f64,
    write: f64,
}

/// Runs `bareray render`.
pub fn run(args: RenderArgs) -> Result<()> {
    let mut time = Timings::default();
    let clock = Instant::now();
    let (mut desc, name) = match &args.scene {
        Some(path) => (load_scene(path)?, stem(path)),
        None => (toml::parse(Path::new("<built-in demo>"), DEMO_SCENE)?, "demo".to_owned()),
    };
    let output = args.output.clone().unwrap_or_else(|| PathBuf::from(format!("{name}.png")));
    // Fail on a bad output name now, not after the render.
    Format::from_path(&output)?;
    apply_overrides(&mut desc, &args)?;
    time.parse = clock.elapsed().as_secs_f64();

    let threads = args.threads.map(|t| t as usize);
    let clock = Instant::now();
    // The build runs on the render's threads too: `--threads 1` means one core throughout.
    let pool = crate::render::thread_pool(threads)?;
    let scene =
        pool.install(|| Scene::compile_owned(desc, Accel::Auto, args.bvh_preset)).context("camera")?;
    time.build = clock.elapsed().as_secs_f64();

    crate::accel::set_counting(args.stats);
    let progress = progress_bar(args.quiet);
    let rendered = render_lanes(&scene, args.lanes, &pool, &progress);
    progress.finish_and_clear();
    time.render = rendered.seconds;

    let aovs = match &args.aov {
        None => None,
        Some(which) => {
            let clock = Instant::now();
            let img = aov::render_aovs(&scene, args.lanes, &pool);
            time.aov = clock.elapsed().as_secs_f64();
            Some((img, which))
        }
    };
    let clock = Instant::now();
    pool.install(|| write_image(&rendered.image, &output))?;
    if let Some((img, which)) = aovs {
        let path = aov::aov_path(&output);
        aov::write_exr(&img, &which.0, scene.geometry.len(), &path)
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    }
    time.write = clock.elapsed().as_secs_f64();

    if args.stats {
        print_stats(&scene, &rendered, &time);
    } else if !args.quiet {
        print_summary(&output, &scene, &rendered, &time);
    }
    Ok(())
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

fn print_summary(output: &Path, scene: &Scene, r: &Rendered, time: &Timings) {
    let c = r.counts;
    println!(
        "{}: {}x{} in {:.3} s (parse {:.3} s, write {:.3} s); {} rays ({} primary, {} shadow, {} reflection, \
         {} refraction), {:.2} Mrays/s",
        output.display(),
        scene.camera.width,
        scene.camera.height,
        r.seconds,
        time.parse,
        time.write,
        c.total(),
        c.primary,
        c.shadow,
        c.reflection,
        c.refraction,
        c.total() as f64 / r.seconds / 1e6
    );
}

fn print_stats(scene: &Scene, r: &Rendered, time: &Timings) {
    let g = &scene.geometry;
    let count = |kind| g.shapes.iter().filter(|s| s.kind == kind).count();
    println!(
        "scene: {} primitives ({} spheres, {} ellipsoids, {} planes, {} polygons), {} lights, {} materials",
        g.len(),
        g.spheres.len(),
        count(ShapeKind::Sphere),
        count(ShapeKind::Plane),
        g.polygons.len(),
        scene.lights.len(),
        scene.materials.len()
    );
    println!("image: {}x{}, {:?}", scene.camera.width, scene.camera.height, scene.render.pattern);
    println!("features: {}", crate::scene::features::Features::of(scene));
    println!(
        "accel: {}, build {:.3} s, {:.1} bytes/sphere (spheres + BVH nodes)",
        if g.bvh.is_some() { "BVH" } else { "brute force" },
        scene.build.seconds,
        scene.bytes_per_sphere()
    );
    let c = r.counts;
    println!(
        "rays: {} total: {} primary, {} shadow, {} reflection, {} refraction",
        c.total(),
        c.primary,
        c.shadow,
        c.reflection,
        c.refraction
    );
    println!(
        "intersection tests: {} packet-primitive, {} packet-box, at {} rays per packet",
        r.work.prim_tests, r.work.box_tests, r.lanes
    );
    println!(
        "time: parse {:.3} s, build {:.3} s, render {:.3} s, aov {:.3} s, write {:.3} s",
        time.parse, time.build, time.render, time.aov, time.write
    );
    println!("throughput: {:.2} Mrays/s", c.total() as f64 / r.seconds / 1e6);
}

/// Parses a packet width.
pub fn parse_lanes(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(k) if LANE_CHOICES.contains(&k) => Ok(k),
        _ => Err(format!("lanes must be one of 1, 4, 8, 16, got `{s}`")),
    }
}

fn stem(path: &Path) -> String {
    path.file_stem().map_or_else(|| "out".to_owned(), |s| s.to_string_lossy().into_owned())
}

/// Reads a scene file, choosing the reader by extension.
pub fn load_scene(path: &Path) -> Result<SceneDesc> {
    Ok(crate::scene::load(path)?)
}

fn apply_overrides(desc: &mut SceneDesc, args: &RenderArgs) -> Result<()> {
    args.camera.apply(desc)?;
    if let Some(spp) = args.spp {
        let n = toml::grid_side(spp).map_err(|m| anyhow::anyhow!("--spp: {m}"))?;
        desc.render.pattern = Pattern::Grid(n);
    }
    if let Some(d) = args.depth {
        desc.render.max_depth = d;
    }
    Ok(())
}
