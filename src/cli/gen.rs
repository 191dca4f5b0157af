//! `bareray gen`: write generated scenes (the benchmark field, SPD's sphereflake, the random-scene
//! campaign's scenes) to files.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Args, Subcommand};

use super::usage;
use bareray::io::generate::{flake_count, write_flake_nff, FieldParams, MAX_FLAKE_LEVEL};
use bareray::output::write_atomic_with;

/// Arguments of `bareray gen`.
#[derive(Args, Debug)]
pub(super) struct GenArgs {
    #[command(subcommand)]
    what: GenCommand,
}

#[derive(Subcommand, Debug)]
enum GenCommand {
    /// The benchmark contract's random sphere field (splitmix64), as .xyzr text or binary .f32r.
    #[command(after_help = "Examples:\n  bareray gen field --count 1000000 -o field1m.xyzr\n  \
                            bareray gen field --count 1e7 -o field10m.f32r")]
    Field(FieldArgs),
    /// SPD's sphereflake (`balls`) at a size factor, as NFF.
    #[command(after_help = "Example:\n  bareray gen flake --level 4 -o balls4.nff   # 7381 spheres")]
    Flake(FlakeArgs),
    /// One scene of the random-scene campaign (tests/library/random_scenes.rs) by its seed, as TOML.
    #[command(after_help = "Example:\n  bareray gen random --seed 42 -o random-42.toml")]
    Random(RandomArgs),
}

/// Arguments of `bareray gen random`.
#[derive(Args, Debug)]
pub(super) struct RandomArgs {
    /// The scene's seed.
    #[arg(long)]
    pub(super) seed: u64,
    /// Image width (the campaign renders 48×32).
    #[arg(long, default_value_t = 48)]
    pub(super) width: u32,
    /// Image height.
    #[arg(long, default_value_t = 32)]
    pub(super) height: u32,
    /// Output file; must end in .toml. Written atomically.
    #[arg(short, long)]
    pub(super) output: PathBuf,
}

/// Arguments of `bareray gen field`.
#[derive(Args, Debug)]
pub(super) struct FieldArgs {
    /// Number of spheres (at least 1): an integer, or a power-of-ten form such as `1e6`.
    #[arg(long, value_parser = parse_count)]
    pub(super) count: u64,
    /// splitmix64 seed.
    #[arg(long, default_value_t = 1)]
    pub(super) seed: u64,
    /// The box the centres fill: x0,y0,z0,x1,y1,z1.
    #[arg(long = "box", value_name = "x0,y0,z0,x1,y1,z1", allow_hyphen_values = true, value_parser = parse_box)]
    pub(super) bounds: Option<([f64; 3], [f64; 3])>,
    /// Smallest radius [default: 0.1·s, s = (x1 − x0)/cbrt(count)].
    #[arg(long, allow_negative_numbers = true)]
    pub(super) rmin: Option<f64>,
    /// Largest radius [default: 0.25·s].
    #[arg(long, allow_negative_numbers = true)]
    pub(super) rmax: Option<f64>,
    /// Output file; its extension picks the format written: .xyzr (text) or .f32r (binary). Written
    /// atomically.
    #[arg(short, long)]
    pub(super) output: PathBuf,
}

/// Arguments of `bareray gen flake`.
#[derive(Args, Debug)]
pub(super) struct FlakeArgs {
    /// Size factor: (9^(L+1) − 1)/8 spheres (2: 91, 3: 820, 4: 7381, 5: 66430, 6: 597871).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=MAX_FLAKE_LEVEL as i64))]
    pub(super) level: u32,
    /// Output file; must end in .nff (the format written). Written atomically.
    #[arg(short, long)]
    pub(super) output: PathBuf,
}

/// Runs `bareray gen`.
pub(super) fn run(args: GenArgs) -> Result<()> {
    match args.what {
        GenCommand::Field(a) => field(a),
        GenCommand::Flake(a) => flake(a),
        GenCommand::Random(a) => random(a),
    }
}

fn random(a: RandomArgs) -> Result<()> {
    check_extension(&a.output, &["toml"])?;
    if a.width == 0 || a.height == 0 {
        return Err(usage("--width and --height must be at least 1"));
    }
    let text = bareray::io::random_scene::random_scene_toml(a.seed, a.width, a.height);
    write_atomic_with(&a.output, |w| std::io::Write::write_all(w, text.as_bytes()))
        .with_context(|| format!("{}: cannot write", a.output.display()))?;
    eprintln!("{}: random scene {}", a.output.display(), a.seed);
    Ok(())
}

fn field(a: FieldArgs) -> Result<()> {
    let start = Instant::now();
    let mut params =
        FieldParams { count: a.count, seed: a.seed, rmin: a.rmin, rmax: a.rmax, ..Default::default() };
    if let Some((lo, hi)) = a.bounds {
        (params.lo, params.hi) = (lo, hi);
    }
    // Check first so that bad arguments say so instead of failing a half-written file.
    let binary = check_extension(&a.output, &["xyzr", "f32r"])? == "f32r";
    params.radii().map_err(|e| usage(e.to_string()))?;
    if binary && u32::try_from(a.count).is_err() {
        return Err(usage(format!("--count: an .f32r file holds at most {} spheres", u32::MAX)));
    }
    write_atomic_with(&a.output, |w| if binary { params.write_f32r(w) } else { params.write_xyzr(w) })
        .with_context(|| format!("{}: cannot write", a.output.display()))?;
    report(a.count, &a.output, start);
    Ok(())
}

fn flake(a: FlakeArgs) -> Result<()> {
    let start = Instant::now();
    check_extension(&a.output, &["nff"])?;
    write_atomic_with(&a.output, |w| write_flake_nff(a.level, w))
        .with_context(|| format!("{}: cannot write", a.output.display()))?;
    report(flake_count(a.level), &a.output, start);
    Ok(())
}

/// The output must carry the extension of a format written (one of `expected`, which is returned): a scene
/// named `.toml` but holding NFF would fail to load, or load as the wrong format, later. Case-insensitive,
/// as the readers choose.
pub(super) fn check_extension(path: &Path, expected: &[&'static str]) -> Result<&'static str> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if let Some(&found) = expected.iter().find(|&&e| ext.as_deref() == Some(e)) {
        return Ok(found);
    }
    let names = expected.iter().map(|e| format!(".{e}")).collect::<Vec<_>>().join(" or ");
    Err(usage(format!(
        "{}: this command writes {names}; name the output with that extension",
        path.display()
    )))
}

/// A whole count written as digits or as `<mantissa>e<exponent>` (`1e6`, `2.5e5`).
fn parse_count(s: &str) -> Result<u64, String> {
    if let Ok(n) = s.parse::<u64>() {
        return Ok(n);
    }
    let bad = || format!("'{s}' is not a whole number of spheres (e.g. 1000000 or 1e6)");
    let (m, e) = s.split_once(['e', 'E']).ok_or_else(bad)?;
    let (m, e): (f64, u32) = (m.parse().map_err(|_| bad())?, e.parse().map_err(|_| bad())?);
    let n = m * 10f64.powi(e as i32);
    if !(0.0..=u64::MAX as f64).contains(&n) || n.fract() != 0.0 || !m.is_finite() {
        return Err(bad());
    }
    Ok(n as u64)
}

fn report(count: u64, path: &Path, start: Instant) {
    println!("{}: {count} spheres in {:.3} s", path.display(), start.elapsed().as_secs_f64());
}

/// `x0,y0,z0,x1,y1,z1` as two corners.
fn parse_box(text: &str) -> Result<([f64; 3], [f64; 3]), String> {
    let v: Vec<f64> = text
        .split(',')
        .map(|w| w.trim().parse::<f64>().map_err(|_| format!("`{w}` is not a number")))
        .collect::<Result<_, _>>()?;
    if v.len() != 6 {
        return Err(format!("six numbers x0,y0,z0,x1,y1,z1 expected, got {}", v.len()));
    }
    Ok(([v[0], v[1], v[2]], [v[3], v[4], v[5]]))
}

#[cfg(test)]
mod tests {
    use super::{check_extension, parse_count};
    use std::path::Path;

    #[test]
    fn output_extension_must_be_the_format_written() {
        assert_eq!(check_extension(Path::new("a/f.xyzr"), &["xyzr", "f32r"]).unwrap(), "xyzr");
        assert_eq!(check_extension(Path::new("a/f.F32R"), &["xyzr", "f32r"]).unwrap(), "f32r");
        assert_eq!(check_extension(Path::new("F.NFF"), &["nff"]).unwrap(), "nff");
        for bad in ["f.nff", "f.toml", "f", "f.xyzr.tmp"] {
            let e = check_extension(Path::new(bad), &["xyzr", "f32r"]).unwrap_err();
            assert!(e.downcast_ref::<super::super::UsageError>().is_some(), "{bad}");
            assert!(e.to_string().contains("writes .xyzr or .f32r;"), "{e}");
        }
    }

    #[test]
    fn counts_in_digits_and_powers_of_ten() {
        assert_eq!(parse_count("1000"), Ok(1000));
        assert_eq!(parse_count("1e6"), Ok(1_000_000));
        assert_eq!(parse_count("2.5E5"), Ok(250_000));
        for bad in ["1.5", "1e-3", "2.5e0", "e6", "1e", "1e99", "-1e3", "ten"] {
            assert!(parse_count(bad).is_err(), "{bad}");
        }
    }
}
