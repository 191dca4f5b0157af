//! `bareray bench`: the same scene traced repeatedly at each packet width and thread count.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use clap::Args;
use indicatif::ProgressBar;

use super::camera_args::CameraArgs;
use super::render::{load_scene, parse_lanes, parse_threads};
use crate::render::{fnv1a, render_lanes, thread_pool, trace_primary_lanes, PrimaryHits};
use crate::scene::{Accel, BvhPreset, Scene};

/// Arguments of `bareray bench`.
#[derive(Args, Debug)]
#[command(after_help = "Examples:\n  bareray gen field --count 1000000 -o f.xyzr\n  \
bareray bench f.xyzr --primary-only --eye 0,0,-4 --look 0,0,0 --up 0,1,0 --hfov 45 --width 1920 --height 1080\n  \
bareray bench scenes/whitted.toml --lanes 1,16 --threads 1,2 --json")]
pub struct BenchArgs {
    /// Scene file (.toml, .nff or .xyzr).
    pub scene: PathBuf,
    /// Packet widths to measure, a comma list of 1, 4, 8, 16 (1 is the scalar reference path).
    #[arg(long, value_delimiter = ',', default_values_t = vec![1, 4, 8, 16], value_parser = parse_lanes)]
    pub lanes: Vec<usize>,
    /// Thread counts to measure, a comma list (each from 1 to 1024).
    #[arg(long, value_delimiter = ',', default_values_t = vec![1, 2], value_parser = parse_threads)]
    pub threads: Vec<usize>,
    /// Trace camera rays to the closest hit only (one per pixel centre): no shading, no secondary rays.
    #[arg(long)]
    pub primary_only: bool,
    /// How spheres are searched: `auto` (a BVH from 4 spheres on), `bvh`, or `brute` (every ray tests every
    /// sphere: the setting for comparing kernels).
    #[arg(long, value_enum, default_value_t = AccelArg::Auto)]
    pub accel: AccelArg,
    /// obvhs build preset for the BVH (`very-fast` builds quickest and traces uniform fields fastest).
    #[arg(long, value_enum, default_value_t = BvhPreset::Fast)]
    pub bvh_preset: BvhPreset,
    /// Test each BVH node's children, and each leaf's spheres, against a shared-origin packet's frustum
    /// before its lanes (default: on, measured faster on large fields; PERF.md). `false` to measure without.
    #[arg(long, value_name = "BOOL", default_value_t = true, action = clap::ArgAction::Set)]
    pub frustum_culling: bool,
    /// BVH subtrees that a packet enters with at most this many live lanes are walked one ray at a time
    /// (default: the measured switch, 2; 0 never switches). Here to measure the switch again.
    #[arg(long, value_name = "LANES", value_parser = clap::value_parser!(u32).range(0..=16))]
    pub single_ray_lanes: Option<u32>,
    /// Timed repetitions per setting (the median is reported), after one untimed warm-up.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub reps: u32,
    /// One JSON object per line instead of a table.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub camera: CameraArgs,
}

/// `--accel`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum AccelArg {
    /// BVH from 4 spheres on.
    Auto,
    /// Always a BVH.
    Bvh,
    /// Always brute force.
    Brute,
}

/// One measured setting.
struct Row {
    lanes: usize,
    threads: usize,
    rays: u64,
    seconds: f64,
    checksum: u64,
}

/// Runs `bareray bench`.
pub fn run(args: BenchArgs) -> Result<()> {
    let clock = Instant::now();
    let mut desc = load_scene(&args.scene)?;
    args.camera.apply(&mut desc);
    if args.primary_only {
        // Primary hits need no lights and no bounces; without them the build skips the single-ray tree.
        desc.lights.clear();
        desc.render.max_depth = 0;
    }
    let parse_s = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    let accel = match args.accel {
        AccelArg::Auto => Accel::Auto,
        AccelArg::Bvh => Accel::Bvh,
        AccelArg::Brute => Accel::Brute,
    };
    // The build runs on as many threads as the largest setting measured, not on every core: a 1-thread
    // bench builds on one thread, as a 1-thread peer run does.
    let build_threads = args.threads.iter().copied().max();
    let mut scene = crate::render::thread_pool(build_threads)?
        .install(|| Scene::compile_owned(desc, accel, args.bvh_preset))?;
    if let Some(bvh) = &mut scene.geometry.bvh {
        bvh.frustum_culling = args.frustum_culling;
        if let Some(lanes) = args.single_ray_lanes {
            bvh.single_ray_lanes = lanes;
        }
    }
    let compile_s = clock.elapsed().as_secs_f64();
    let g = &scene.geometry;
    let mut out = std::io::stdout().lock();
    if !args.json {
        writeln!(
            out,
            "{}: {} primitives ({} spheres), {}x{}; parse {parse_s:.3} s, compile {compile_s:.3} s (BVH build {:.3} s, \
             {:.1} bytes/sphere); {}",
            args.scene.display(),
            g.len(),
            g.spheres.len(),
            scene.camera.width,
            scene.camera.height,
            scene.build.seconds,
            scene.bytes_per_sphere(),
            if args.primary_only { "primary rays only" } else { "full Whitted render" }
        )?;
        writeln!(out, "lanes threads        rays   median s    Mrays/s  vs 1 lane  checksum")?;
    }
    let mut scalar: Option<f64> = None;
    for &threads in &args.threads {
        for &lanes in &args.lanes {
            let row = measure(&scene, &args, lanes, threads)?;
            let mrays = row.rays as f64 / row.seconds / 1e6;
            if lanes == 1 && threads == args.threads[0] {
                scalar = Some(mrays);
            }
            if args.json {
                writeln!(
                    out,
                    "{{\"tracer\":\"bareray\",\"scene\":{:?},\"primary_only\":{},\"lanes\":{},\"threads\":{},\"rays\":{},\
                     \"seconds\":{:.6},\"mrays_per_s\":{:.3},\"checksum\":\"{:016x}\",\"reps\":{},\"spheres\":{},\
                     \"build_s\":{:.6},\"width\":{},\"height\":{},\"frustum_culling\":{},\"bvh_preset\":\"{:?}\"}}",
                    args.scene.display().to_string(),
                    args.primary_only,
                    row.lanes,
                    row.threads,
                    row.rays,
                    row.seconds,
                    mrays,
                    row.checksum,
                    args.reps,
                    g.spheres.len(),
                    scene.build.seconds,
                    scene.camera.width,
                    scene.camera.height,
                    args.frustum_culling,
                    args.bvh_preset
                )?;
            } else {
                let ratio = scalar.map_or("-".to_owned(), |s| format!("{:.2}x", mrays / s));
                writeln!(
                    out,
                    "{:5} {:7} {:11} {:10.4} {:10.2} {:>10}  {:016x}",
                    row.lanes, row.threads, row.rays, row.seconds, mrays, ratio, row.checksum
                )?;
            }
        }
    }
    Ok(())
}

/// The median of `reps` timed runs after one warm-up.
fn measure(scene: &Scene, args: &BenchArgs, lanes: usize, threads: usize) -> Result<Row> {
    let mut times = Vec::with_capacity(args.reps as usize);
    let (mut rays, mut checksum) = (0, 0);
    // One thread pool for every repetition, and for primary rays one frame, as the peer harnesses do.
    let pool = thread_pool(Some(threads))?;
    let mut frame = args.primary_only.then(|| PrimaryHits::new(scene.camera.width, scene.camera.height));
    for rep in 0..=args.reps {
        let seconds = if let Some(hits) = &mut frame {
            trace_primary_lanes(scene, lanes, &pool, hits);
            rays = hits.t.len() as u64;
            checksum = hits.checksum(scene);
            hits.seconds
        } else {
            let r = render_lanes(scene, lanes, &pool, &ProgressBar::hidden());
            rays = r.counts.total();
            checksum = image_checksum(&r.image);
            r.seconds
        };
        if rep > 0 {
            times.push(seconds);
        }
    }
    times.sort_by(f64::total_cmp);
    Ok(Row { lanes, threads, rays, seconds: times[times.len() / 2], checksum })
}

/// FNV-1a 64 over the image's f32 bits, row-major.
fn image_checksum(img: &crate::film::Image) -> u64 {
    fnv1a(img.pixels.iter().flat_map(|p| [p.x, p.y, p.z]).flat_map(|v| v.to_bits().to_le_bytes()))
}
