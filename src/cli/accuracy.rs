//! `bareray accuracy`: argument parsing and printing; the comparison is [`bareray::accuracy`].

use std::io::Write;
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use super::camera_args::CameraArgs;
use super::render_run::load_scene;
use super::values::LanesArg;
use super::values::{parse_lanes, parse_threads};
use bareray::accuracy::{run as compare_scene, Options};
use bareray::settings::Overrides;

/// Arguments of `bareray accuracy`.
#[derive(Args, Debug)]
#[command(after_help = "Examples:\n  bareray accuracy scenes/whitted.toml --secondary\n  \
bareray accuracy scenes/field1k.xyzr --width 1920 --height 1080 --json")]
pub(super) struct AccuracyArgs {
    /// Scene file (.toml, .nff or .xyzr).
    pub(super) scene: PathBuf,
    /// Packet width of the f32 pass: 1 (single-ray SIMD), 4, 8 or 16, or `scalar` (one ray against one box
    /// and one primitive at a time, over binary BVHs); the results are the same bits on every path.
    #[arg(long, default_value = "16", value_parser = parse_lanes)]
    pub(super) lanes: LanesArg,
    /// Also compare secondary rays: one shadow ray per light and the mirror ray of every pixel whose two
    /// primary hits agree.
    #[arg(long)]
    pub(super) secondary: bool,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub(super) json: bool,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = parse_threads)]
    pub(super) threads: Option<usize>,
    #[command(flatten)]
    pub(super) camera: CameraArgs,
}

/// Runs `bareray accuracy`.
pub(super) fn run(args: AccuracyArgs) -> Result<()> {
    // The comparison makes its own pool of `--threads`; reading takes as many.
    let mut desc = load_scene(&args.scene, &bareray::render::thread_pool(args.threads)?)?;
    let overrides = Overrides { camera: args.camera.overrides(), ..Overrides::default() };
    overrides.apply(&mut desc).map_err(super::render_run::settings_error)?;
    let opts = Options {
        lanes: args.lanes.k(),
        scalar: args.lanes.is_scalar(),
        secondary: args.secondary,
        threads: args.threads,
        ..Options::default()
    };
    let report = compare_scene(&args.scene.display().to_string(), &desc, &opts)?;
    let mut out = std::io::stdout().lock();
    if args.json {
        writeln!(out, "{}", report.to_json())?;
    } else {
        write!(out, "{}", report.table())?;
    }
    Ok(())
}
