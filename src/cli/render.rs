//! `bareray render`.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use crate::output::{write_image, Format};
use crate::render::render;
use crate::scene::desc::Pattern;
use crate::scene::{toml, Scene, SceneDesc};

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
    /// Image width in pixels. Given alone, the height follows the scene's aspect ratio.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub width: Option<u32>,
    /// Image height in pixels. Given alone, the width follows the scene's aspect ratio.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub height: Option<u32>,
    /// Samples per pixel on a regular n×n grid (1, 4, 9, 16, ...); overrides the scene.
    #[arg(long)]
    pub spp: Option<u32>,
    /// Reflection/refraction depth limit; overrides the scene.
    #[arg(long)]
    pub depth: Option<u32>,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// No progress bar and no summary line.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Runs `bareray render`.
pub fn run(args: RenderArgs) -> Result<()> {
    let t_parse = Instant::now();
    let (mut desc, name) = match &args.scene {
        Some(path) => (load_scene(path)?, stem(path)),
        None => (toml::parse(Path::new("<built-in demo>"), DEMO_SCENE)?, "demo".to_owned()),
    };
    let output = args.output.clone().unwrap_or_else(|| PathBuf::from(format!("{name}.png")));
    // Fail on a bad output name now, not after the render.
    Format::from_path(&output)?;
    apply_overrides(&mut desc, &args)?;
    let scene = Scene::compile(&desc).context("camera")?;
    let parse_s = t_parse.elapsed().as_secs_f64();

    let progress = if !args.quiet && std::io::stderr().is_terminal() {
        let bar = ProgressBar::new(0);
        bar.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {wide_bar} {pos}/{len} tiles, eta {eta}",
            )
            .expect("valid template"),
        );
        bar
    } else {
        ProgressBar::hidden()
    };
    let rendered = render(&scene, args.threads.map(|t| t as usize), &progress)?;
    progress.finish_and_clear();
    let t_write = Instant::now();
    write_image(&rendered.image, &output)?;
    let write_s = t_write.elapsed().as_secs_f64();
    if !args.quiet {
        let c = rendered.counts;
        println!(
            "{}: {}x{} in {:.3} s (parse {:.3} s, write {:.3} s); {} rays ({} primary, {} shadow, {} reflection, {} refraction), {:.2} Mrays/s",
            output.display(),
            scene.camera.width,
            scene.camera.height,
            rendered.seconds,
            parse_s,
            write_s,
            c.total(),
            c.primary,
            c.shadow,
            c.reflection,
            c.refraction,
            c.total() as f64 / rendered.seconds / 1e6
        );
    }
    Ok(())
}

fn stem(path: &Path) -> String {
    path.file_stem().map_or_else(|| "out".to_owned(), |s| s.to_string_lossy().into_owned())
}

/// Reads a scene file, choosing the reader by extension.
pub fn load_scene(path: &Path) -> Result<SceneDesc> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("toml") => Ok(toml::load(path)?),
        Some("nff") => Ok(crate::scene::nff::load(path)?),
        Some("xyzr") => Ok(crate::scene::xyzr::load(path)?),
        _ => bail!("{}: unknown scene format (expected a .toml, .nff or .xyzr file)", path.display()),
    }
}

fn apply_overrides(desc: &mut SceneDesc, args: &RenderArgs) -> Result<()> {
    let cam = &mut desc.camera;
    let aspect = f64::from(cam.width) / f64::from(cam.height);
    match (args.width, args.height) {
        (Some(w), Some(h)) => (cam.width, cam.height) = (w, h),
        (Some(w), None) => (cam.width, cam.height) = (w, ((f64::from(w) / aspect).round() as u32).max(1)),
        (None, Some(h)) => (cam.width, cam.height) = (((f64::from(h) * aspect).round() as u32).max(1), h),
        (None, None) => {}
    }
    if let Some(spp) = args.spp {
        let n = toml::grid_side(spp).map_err(|m| anyhow::anyhow!("--spp: {m}"))?;
        desc.render.pattern = Pattern::Grid(n);
    }
    if let Some(d) = args.depth {
        desc.render.max_depth = d;
    }
    Ok(())
}
