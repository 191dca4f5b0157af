//! `bareray converge`: run time against error for the sampling methods; the study itself is
//! [`bareray::converge`].

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, Context, Result};
use clap::Args;
use indicatif::ProgressBar;

use super::camera_args::CameraArgs;
use super::render_run::load_scene;
use super::sampling_values::FilterChoice;
use super::values::LanesArg;
use super::values::{parse_lanes, parse_threads};
use bareray::compile::{CompileOptions, Scene};
use bareray::converge::{csv, curves, ladder, plot, study, Reference, METHODS};
use bareray::film::Image;
use bareray::math::Rgb;
use bareray::output::{write_atomic_with, write_image};
use bareray::scene::desc::{Pattern, Transfer};
use bareray::settings::Overrides;

/// Arguments of `bareray converge`.
#[derive(Args, Debug)]
#[command(
    after_help = "Renders a reference (32×32 stratified samples per pixel unless --reference-spp says \
otherwise; cached next to the CSV, reused while the scene file and settings are unchanged), then each method \
at 1, 4, 16, … samples per pixel (R2 and Sobol at 1, 2, 4, …) up to --max-spp, and reports wall time, rays traced, and \
the error against the reference: RMSE over the image, RMSE over edge pixels (where the primitive seen at \
the pixel centre changes between neighbours), PSNR. Values are linear film values clamped to [0, 1].\n\n\
Examples:\n  bareray converge scenes/whitted.toml --width 320 --height 240 --csv w.csv --plot w.svg\n  \
bareray converge scenes/balls3.nff --methods grid,r2 --max-spp 16\n  \
bareray converge scenes/field.toml --methods stratified,sobol --filters none,gaussian,mitchell --csv f.csv"
)]
pub(super) struct ConvergeArgs {
    /// Scene file (.toml, .nff or .xyzr).
    pub(super) scene: PathBuf,
    /// Methods to compare, comma-separated: grid, stratified, r2, sobol, adaptive, lecture, coverage.
    #[arg(long, value_delimiter = ',', default_values_t = METHODS.map(String::from), value_parser = parse_method)]
    pub(super) methods: Vec<String>,
    /// Largest samples per pixel of a method's runs.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub(super) max_spp: u32,
    /// Reconstruction filters to compare, comma-separated: `none` (each pixel averages its own samples) or
    /// `KIND[:RADIUS]` as `render --filter` takes it (box, tent, gaussian, mitchell). Each (method, filter)
    /// pair is a series of its own (CSV: a `filter` column after `method`; plot: `method, filter`), measured
    /// against a reference rendered with the same filter. Adaptive, lecture and coverage ignore filters and
    /// run under `none` only. Default: the scene's own filter, one series per method.
    #[arg(long, value_delimiter = ',', value_parser = super::sampling_values::parse_filter_choice, conflicts_with = "precision")]
    pub(super) filters: Option<Vec<FilterChoice>>,
    /// Samples per pixel of the reference, a square number (stratified √N×√N).
    #[arg(long, default_value_t = 1024, value_parser = super::values::parse_spp)]
    pub(super) reference_spp: u32,
    /// Write the runs as CSV (`method,spp,seconds,rays,rmse,rmse_edges,psnr`); the reference is cached
    /// beside it.
    #[arg(long)]
    pub(super) csv: Option<PathBuf>,
    /// Write the log-log plot of RMSE against time as SVG.
    #[arg(long)]
    pub(super) plot: Option<PathBuf>,
    /// Compare precision paths instead of sampling methods: primary hits at pixel centres by f32 packets,
    /// f32 single-ray SIMD, the f32 scalar path and the f64 twin, each timed, the f32 ones measured against
    /// the f64 one.
    #[arg(long)]
    pub(super) precision: bool,
    /// Shading of the reference and of every run, overriding the scene: `whitted` or
    /// `ao[:SAMPLES[,DISTANCE]]` (as `render --shade`). Each camera sample gets its own SAMPLES occlusion
    /// rays, so a run at N samples per pixel traces N×SAMPLES of them per pixel, and the reference
    /// reference-spp×SAMPLES: the ambient occlusion's noise falls with the samples per pixel too.
    #[arg(long, value_name = "MODE", value_parser = super::sampling_values::parse_shade)]
    pub(super) shade: Option<bareray::scene::desc::Shade>,
    /// Rays per packet: 1 (single-ray SIMD), 4, 8 or 16; or `scalar` (one ray against one box and one
    /// primitive at a time, over binary BVHs). With --precision, the packet path's width (the scalar path
    /// is always one of the paths compared).
    #[arg(long, default_value = "16", value_parser = parse_lanes)]
    pub(super) lanes: LanesArg,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = parse_threads)]
    pub(super) threads: Option<usize>,
    #[command(flatten)]
    pub(super) camera: CameraArgs,
}

/// Runs `bareray converge`.
pub(super) fn run(args: ConvergeArgs) -> Result<()> {
    let methods = args
        .methods
        .iter()
        .map(|m| Ok((m.clone(), ladder(m, args.max_spp).map_err(|e| anyhow!("--methods: {e}"))?)))
        .collect::<Result<Vec<_>>>()?;
    for out in [&args.csv, &args.plot].into_iter().flatten() {
        bareray::output::check_writable(out)?;
    }
    let source = std::fs::read(&args.scene).with_context(|| format!("{}", args.scene.display()))?;
    let pool = bareray::render::thread_pool(args.threads)?;
    let mut desc = load_scene(&args.scene, &pool)?;
    let overrides = Overrides { camera: args.camera.overrides(), shade: args.shade, ..Overrides::default() };
    overrides.apply(&mut desc).map_err(super::render_run::settings_error)?;
    // The scalar path needs each BVH's binary tree; --precision compares it with the others.
    let options =
        CompileOptions { scalar: args.lanes.is_scalar() || args.precision, ..CompileOptions::default() };
    let mut scene = pool.install(|| Scene::compile_with_options(&desc, options)).context("camera")?;
    if args.precision {
        return run_precision(&args, &desc, &mut scene, &pool);
    }
    let lanes = args.lanes.k();
    let side = bareray::io::toml::grid_side(args.reference_spp).map_err(|e| anyhow!(e))?;
    // One pass with the scene's own filter, or one per filter of --filters, each with its own reference.
    let passes: Vec<Option<FilterChoice>> = match &args.filters {
        None => vec![None],
        Some(list) => list.iter().copied().map(Some).collect(),
    };
    if args.filters.as_ref().is_some_and(|list| list.iter().any(|c| c.0.is_some())) {
        let unfiltered = passes.contains(&Some(FilterChoice(None)));
        for (name, _) in methods.iter().filter(|(_, p)| !p.iter().all(|p| p.takes_filter())) {
            let under =
                if unfiltered { "runs under `none` only" } else { "does not run (no `none` in --filters)" };
            eprintln!("{name} ignores reconstruction filters: it {under}");
        }
    }
    let mut runs = Vec::new();
    for pass in passes {
        if let Some(choice) = pass {
            desc.render.filter = choice.0;
            scene.render.filter = choice.0;
        }
        let label = pass.map(FilterChoice::name);
        let key = reference_key(&source, &desc, args.reference_spp);
        let file = match &label {
            None => "reference.exr".to_owned(),
            Some(name) => format!("reference.{}.exr", name.replace(':', "-")),
        };
        let cached = args.csv.as_ref().map(|csv| csv.with_extension(&file));
        let filtered = label.as_ref().map_or(String::new(), |name| format!(", filter {name}"));
        let reference = match cached.as_deref().and_then(|path| read_cached(path, &key, &scene)) {
            Some(image) => {
                eprintln!(
                    "reference{filtered}: {} (cached)",
                    cached.as_deref().map_or(String::new(), |p| p.display().to_string())
                );
                Reference::from_image(&scene, image, lanes, &pool)
            }
            None => {
                let spp = args.reference_spp;
                eprintln!("reference{filtered}: {spp} samples per pixel (stratified {side}×{side}) ...");
                let reference = Reference::render(&mut scene, Pattern::Stratified(side), lanes, &pool);
                if let Some(path) = cached.as_deref() {
                    write_image(&reference.image, path, Transfer::Linear)?;
                    std::fs::write(path.with_extension("key"), &key)?;
                }
                reference
            }
        };
        // Under a filter, only the methods it applies to: the others would repeat their unfiltered runs
        // against a filtered reference.
        let here: Vec<(String, Vec<Pattern>)> = methods
            .iter()
            .filter(|(_, p)| pass.is_none_or(|c| c.0.is_none() || p.iter().all(|p| p.takes_filter())))
            .cloned()
            .collect();
        let bar = super::render_report::TileBar(ProgressBar::new(0));
        let mut part = study(&mut scene, &here, &reference, lanes, &pool, &bar);
        bar.0.finish_and_clear();
        part.iter_mut().for_each(|r| r.filter.clone_from(&label));
        runs.extend(part);
    }
    let mut out = std::io::stdout().lock();
    let width = runs.iter().map(|r| r.series().chars().count()).max().unwrap_or(0).max(11);
    writeln!(
        out,
        "{:<width$} {:>7} {:>9} {:>12} {:>10} {:>10} {:>7}",
        "method", "spp", "seconds", "rays", "rmse", "rmse_edges", "psnr"
    )?;
    for r in &runs {
        let e = &r.errors;
        writeln!(
            out,
            "{:<width$} {:>7.2} {:>9.4} {:>12} {:>10.3e} {:>10.3e} {:>7.2}",
            r.series(),
            r.spp,
            r.seconds,
            r.rays,
            e.rmse,
            e.rmse_edges,
            e.psnr
        )?;
    }
    if let Some(path) = &args.csv {
        write_atomic_with(path, |w| w.write_all(csv(&runs).as_bytes()))
            .with_context(|| format!("{}", path.display()))?;
    }
    if let Some(path) = &args.plot {
        let shading = bareray::settings::shade_name(desc.render.shade);
        let title = format!("{}, {shading}: error against time", args.scene.display());
        let svg = plot::svg(&title, "RMSE against the reference", &curves(&runs));
        write_atomic_with(path, |w| w.write_all(svg.as_bytes()))
            .with_context(|| format!("{}", path.display()))?;
    }
    Ok(())
}

/// `converge --precision`: the primary-hit paths, a table, and the CSV and plot when asked.
fn run_precision(
    args: &ConvergeArgs,
    desc: &bareray::scene::SceneDesc,
    scene: &mut Scene,
    pool: &rayon::ThreadPool,
) -> Result<()> {
    let runs =
        bareray::converge::precision::primary_paths(desc, scene, args.lanes.k(), pool).context("camera")?;
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "{:<22} {:>9} {:>10} {:>10} {:>10} {:>10}",
        "path", "seconds", "disagree", "t_err_p50", "t_err_p99", "t_err_max"
    )?;
    let mut csv = String::from("path,seconds,disagree,t_err_p50,t_err_p99,t_err_max\n");
    for r in &runs {
        let [p50, p99, max] = r.t_err;
        writeln!(
            out,
            "{:<22} {:>9.4} {:>10.3e} {:>10.3e} {:>10.3e} {:>10.3e}",
            r.path, r.seconds, r.disagree, p50, p99, max
        )?;
        csv +=
            &format!("{},{:.6},{:.6e},{:.6e},{:.6e},{:.6e}\n", r.path, r.seconds, r.disagree, p50, p99, max);
    }
    if let Some(path) = &args.csv {
        write_atomic_with(path, |w| w.write_all(csv.as_bytes()))
            .with_context(|| format!("{}", path.display()))?;
    }
    if let Some(path) = &args.plot {
        // The f64 twin is the reference: its error is 0, which a log axis cannot show.
        let curves: Vec<plot::Curve> = runs
            .iter()
            .filter(|r| r.t_err[1] > 0.0)
            .enumerate()
            .map(|(colour, r)| plot::Curve {
                name: r.path.clone(),
                points: vec![(r.seconds, r.t_err[1])],
                colour,
                dash: 0,
            })
            .collect();
        let title =
            format!("{}: primary hits, precision against time (f64 twin: reference)", args.scene.display());
        let svg = plot::svg(&title, "relative t error p99 against f64", &curves);
        write_atomic_with(path, |w| w.write_all(svg.as_bytes()))
            .with_context(|| format!("{}", path.display()))?;
    }
    Ok(())
}

/// Parses one of `--methods`: a name in [`METHODS`].
fn parse_method(s: &str) -> Result<String, String> {
    match METHODS.contains(&s) {
        true => Ok(s.to_owned()),
        false => Err(format!("unknown method `{s}`: {}", METHODS.join(", "))),
    }
}

/// What the cached reference depends on: the scene file's bytes, the description after the command line's
/// camera changes (its debug form), the reference's sample count and the version.
fn reference_key(source: &[u8], desc: &bareray::scene::SceneDesc, spp: u32) -> String {
    let text = format!("{:?}|{spp}|{}", desc, env!("CARGO_PKG_VERSION"));
    let hash = bareray::render::fnv1a(source.iter().copied().chain(text.bytes()));
    format!("bareray converge reference {hash:016x}\n")
}

/// The cached reference at `path`, if its key file matches `key` and it has the scene's size.
fn read_cached(path: &Path, key: &str, scene: &Scene) -> Option<Image> {
    if std::fs::read_to_string(path.with_extension("key")).ok()? != key {
        return None;
    }
    let img = bareray::imagediff::load(path).ok()?.to_rgb32f();
    if (img.width(), img.height()) != (scene.camera.width, scene.camera.height) {
        return None;
    }
    let pixels = img.pixels().map(|p| Rgb::new(p[0], p[1], p[2])).collect();
    Some(Image { width: img.width(), height: img.height(), pixels })
}
