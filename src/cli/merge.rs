//! `bareray merge`: pastes regions rendered apart into one image ([`bareray::still::merge`]).

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use bareray::still::merge::merge;

/// Arguments of `bareray merge`.
#[derive(Args, Debug)]
#[command(
    after_help = "The parts are files `bareray render --region` (or --crop) wrote, all PNG, all EXR or \
all PPM, from one render (same size and settings); together they must cover the image exactly once. The \
merged file is byte for byte the file the whole render writes.\n\n\
Example (four quarters of a 2048x2048 image, e.g. as four jobs of a job array):\n  \
bareray render balls.nff --width 2048 --region 0,0,1024,1024 -o q1.png\n  ...\n  \
bareray merge q1.png q2.png q3.png q4.png -o balls.png"
)]
pub(super) struct MergeArgs {
    /// The parts, in any order.
    #[arg(required = true)]
    pub(super) parts: Vec<PathBuf>,
    /// The merged image; its extension must name the parts' format.
    #[arg(short, long)]
    pub(super) output: PathBuf,
    /// No summary line.
    #[arg(short, long)]
    pub(super) quiet: bool,
}

/// Runs `bareray merge`.
pub(super) fn run(args: MergeArgs) -> Result<()> {
    let full = merge(&args.parts, &args.output)?;
    if !args.quiet {
        println!(
            "{}: {}x{} from {} part{}",
            args.output.display(),
            full.width,
            full.height,
            args.parts.len(),
            if args.parts.len() == 1 { "" } else { "s" }
        );
    }
    Ok(())
}
