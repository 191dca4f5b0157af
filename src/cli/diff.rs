//! `bareray diff`: compares two images (the comparison is [`bareray::imagediff`]); argument parsing and
//! printing only.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{anyhow, Result};
use clap::Args;
use image::ImageFormat;

use bareray::imagediff::{diff_files, Diff};
use bareray::output::write_atomic;

/// Arguments of `bareray diff`.
#[derive(Args, Debug)]
#[command(after_help = "Values are compared as stored: each channel value is converted to f32 — EXR floats \
as they are (linear light), 8-bit PNG/PPM values as v/255 in [0, 1] (16-bit: v/65535) — with no sRGB \
decoding, so a PNG and an EXR of one render differ. RGB is compared, and alpha when either image has it \
(missing alpha counts as 1). RMSE is over every compared value; PSNR is 20 log10(1 / RMSE) dB (peak 1.0), \
\"inf\" when the images are identical.\n\n\
Exit status: 0 identical, 1 different, 2 error (unreadable file, different sizes).\n\n\
Examples:\n  bareray diff before.png after.png\n  bareray diff a.exr b.exr --heatmap d.png")]
pub(super) struct DiffArgs {
    /// First image (.png, .exr or .ppm; the decoder is chosen by the file's contents).
    pub(super) a: PathBuf,
    /// Second image; any of the formats, in any mix with the first.
    pub(super) b: PathBuf,
    /// Also write a grey PNG of each pixel's largest channel difference, scaled so the largest difference
    /// is white and any difference at least grey level 1 (black: equal pixels).
    #[arg(long, value_name = "OUT.png")]
    pub(super) heatmap: Option<PathBuf>,
}

/// Runs `bareray diff`: exit code 0 when the images are identical, 1 when they differ, 2 on an error.
pub(super) fn run(args: DiffArgs) -> ExitCode {
    match compare(&args) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

/// Compares, prints, writes the heatmap; whether the images are identical.
fn compare(args: &DiffArgs) -> Result<bool> {
    if let Some(path) = &args.heatmap {
        let png = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"));
        if !png {
            return Err(anyhow!("{}: --heatmap writes a PNG; name it .png", path.display()));
        }
    }
    let d = diff_files(&args.a, &args.b)?;
    if let Some(path) = &args.heatmap {
        let map = d.heatmap();
        write_atomic(path, |tmp| Ok(map.save_with_format(tmp, ImageFormat::Png)?))
            .map_err(|e| anyhow!("{}: cannot write the heatmap: {e}", path.display()))?;
    }
    print(&mut std::io::stdout().lock(), args, &d)?;
    Ok(d.identical())
}

fn print(out: &mut impl Write, args: &DiffArgs, d: &Diff) -> std::io::Result<()> {
    let psnr = d.psnr();
    let pixels = u64::from(d.width) * u64::from(d.height);
    writeln!(out, "{} vs {}", args.a.display(), args.b.display())?;
    writeln!(out, "size: {}x{}, {} channels compared", d.width, d.height, d.channels)?;
    writeln!(out, "rmse: {:.6e}", d.rmse)?;
    writeln!(out, "psnr: {}", if psnr.is_infinite() { "inf".to_owned() } else { format!("{psnr:.2} dB") })?;
    writeln!(out, "max abs difference: {}", d.max_abs)?;
    writeln!(
        out,
        "differing pixels: {} of {pixels} ({:.4}%)",
        d.differing_pixels,
        100.0 * d.differing_pixels as f64 / pixels.max(1) as f64
    )?;
    if let Some(path) = &args.heatmap {
        writeln!(out, "heatmap: {} (white = {})", path.display(), d.max_abs)?;
    }
    writeln!(out, "{}", if d.identical() { "identical" } else { "different" })
}
