//! `bareray convert`: a sphere list from one format into the other, `.xyzr` text and `.f32r` binary.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;

use super::gen::check_extension;
use super::render_run::load_scene;
use super::usage;
use super::values::parse_threads;
use bareray::io::{f32r, xyzr, SceneFormat};
use bareray::kinds::sphere::SphereDesc;
use bareray::output::{write_atomic, write_atomic_with};

/// Arguments of `bareray convert`.
#[derive(Args, Debug)]
#[command(after_help = "Examples:\n  bareray convert field1m.xyzr -o field1m.f32r\n  \
                        bareray convert field1m.f32r -o field1m.xyzr")]
pub(super) struct ConvertArgs {
    /// The sphere list read: .xyzr or .f32r.
    pub(super) input: PathBuf,
    /// Output file; its extension picks the format written: .xyzr or .f32r. Written atomically. Values
    /// written to .f32r are rounded to the nearest f32.
    #[arg(short, long)]
    pub(super) output: PathBuf,
    /// Worker threads for reading (default: all cores).
    #[arg(long, value_parser = parse_threads)]
    pub(super) threads: Option<usize>,
}

/// Runs `bareray convert`.
pub(super) fn run(args: ConvertArgs) -> Result<()> {
    let start = Instant::now();
    let binary = check_extension(&args.output, &["xyzr", "f32r"])? == "f32r";
    if !matches!(SceneFormat::from_extension(&args.input), Some(SceneFormat::Xyzr | SceneFormat::F32r)) {
        return Err(usage(format!("{}: convert reads sphere lists, .xyzr or .f32r", args.input.display())));
    }
    if binary && SceneFormat::from_extension(&args.input) == Some(SceneFormat::Xyzr) {
        // Text to binary streams, in memory independent of the list's size.
        let mut count = 0;
        let mut failure = None;
        let written = write_atomic(&args.output, |tmp| {
            let mut w = std::io::BufWriter::with_capacity(1 << 20, std::fs::File::create(tmp)?);
            match f32r::from_xyzr(&args.input, &mut w) {
                Ok(n) => count = n,
                Err(f32r::StreamError::Write(e)) => return Err(e.into()),
                Err(f32r::StreamError::Scene(e)) => {
                    failure = Some(e);
                    return Err("bad input".into());
                }
            }
            w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
            Ok(())
        });
        if let Some(e) = failure {
            return Err(e.into());
        }
        written.map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", args.output.display()))?;
        println!("{}: {count} spheres in {:.3} s", args.output.display(), start.elapsed().as_secs_f64());
        return Ok(());
    }
    let desc = load_scene(&args.input, &bareray::render::thread_pool(args.threads)?)?;
    let spheres = &desc.spheres;
    let values = if binary { singles(&args.input, spheres)? } else { Vec::new() };
    let comment = format!("bareray convert: {} spheres from {}", spheres.len(), args.input.display());
    write_atomic_with(&args.output, |w| match binary {
        true => f32r::write(w, values.len() as u64, values.iter().copied()),
        false => xyzr::write(w, &comment, spheres),
    })
    .with_context(|| format!("{}: cannot write", args.output.display()))?;
    println!(
        "{}: {} spheres in {:.3} s",
        args.output.display(),
        spheres.len(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// The spheres rounded to the nearest f32 (which gives back the very values of a `gen field` list: its
/// text is the shortest that reads back to each f32); a radius that rounds to 0 is an error, as the file
/// would be rejected when read.
fn singles(input: &std::path::Path, spheres: &[SphereDesc]) -> Result<Vec<[f32; 4]>> {
    if u32::try_from(spheres.len()).is_err() {
        anyhow::bail!(
            "{}: {} spheres; an .f32r file holds at most {}",
            input.display(),
            spheres.len(),
            u32::MAX
        );
    }
    let single = |s: &SphereDesc| [s.center.x, s.center.y, s.center.z, s.radius].map(|x| x as f32);
    if let Some(i) = spheres.iter().position(|s| single(s)[3] <= 0.0) {
        anyhow::bail!(
            "{}: sphere {} has radius {}, which is 0 as an f32",
            input.display(),
            i + 1,
            spheres[i].radius
        );
    }
    Ok(spheres.iter().map(single).collect())
}
