//! `bareray accuracy`: argument parsing and printing; the comparison is [`crate::accuracy`].

use std::io::Write;
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use super::camera_args::CameraArgs;
use super::render::{load_scene, parse_lanes, parse_threads};
use super::values::LanesArg;
use crate::accuracy::{run as compare_scene, Options};

/// Arguments of `bareray accuracy`.
#[derive(Args, Debug)]
#[command(after_help = "Examples:\n  bareray accuracy scenes/whitted.toml --secondary\n  \
bareray accuracy scenes/field1k.xyzr --width 1920 --height 1080 --json")]
pub struct AccuracyArgs {
    /// Scene file (.toml, .nff or .xyzr).
    pub scene: PathBuf,
    /// Packet width of the f32 pass: 1 (single-ray SIMD), 4, 8 or 16, or `scalar` (one ray against one box
    /// and one primitive at a time, over binary BVHs); the results are the same bits on every path.
    #[arg(long, default_value = "16", value_parser = parse_lanes)]
    pub lanes: LanesArg,
    /// Also compare secondary rays: one shadow ray per light and the mirror ray of every pixel whose two
    /// primary hits agree.
    #[arg(long)]
    pub secondary: bool,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = parse_threads)]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub camera: CameraArgs,
}

/// Runs `bareray accuracy`.
pub fn run(args: AccuracyArgs) -> Result<()> {
    // The comparison makes its own pool of `--threads`; reading takes as many.
    let mut desc = load_scene(&args.scene, &crate::render::thread_pool(args.threads)?)?;
    args.camera.apply(&mut desc);
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
