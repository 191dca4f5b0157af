//! The command line: one file per subcommand; `main.rs` only calls [`main`].

mod accuracy;
mod bench;
mod bench_compare;
mod bench_isa;
mod bench_isa_level;
mod bench_isa_print;
mod bench_isa_runs;
mod bench_kinds;
mod bench_print;
mod camera_args;
mod converge;
mod convert;
mod diff;
mod gen;
mod merge;
mod particle_args;
mod render;
mod render_report;
mod render_run;
mod sampling_values;
mod values;

use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

/// bareray — a data-oriented SIMD packet ray tracer with a bit-identical scalar path.
///
/// Renders Whitted-shaded scenes (spheres, planes, transformed shapes, polygons; shadows, mirrors, glass)
/// to PNG, EXR or PPM. Scenes are read by extension: `.toml` (bareray's format), `.nff` (SPD's Neutral
/// File Format) or `.xyzr` (one sphere `x y z r` per line).
#[derive(Parser, Debug)]
#[command(
    name = "bareray",
    version,
    about,
    long_about,
    propagate_version = true,
    after_help = "Exit codes: 0 success; 2 argument or usage errors (a bad flag or value, a wrong \
                  extension), nothing done; 1 errors reading the scene, rendering or writing files."
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene to an image file.
    Render(render::RenderArgs),
    /// Measure: trace a scene repeatedly at each packet width and thread count and print a table (or JSON).
    Bench(bench::BenchArgs),
    /// Compare the f32 renderer's hits with an f64 twin of the scene, ray by ray (primary, and with
    /// --secondary shadow and mirror rays), and report disagreements and t errors.
    Accuracy(accuracy::AccuracyArgs),
    /// Run time against error: each sampling method at increasing sample counts against a reference (CSV,
    /// SVG plot).
    Converge(converge::ConvergeArgs),
    /// Generate a scene file: the benchmark sphere field (.xyzr or binary .f32r) or SPD's sphereflake
    /// (.nff).
    Gen(gen::GenArgs),
    /// Convert a sphere list between .xyzr (text) and .f32r (binary), the output's extension naming the
    /// format.
    Convert(convert::ConvertArgs),
    /// Compare two images (PNG, EXR, PPM): size, RMSE, PSNR, max difference, differing pixels; exit 0 when
    /// identical, 1 when different, 2 on error.
    Diff(diff::DiffArgs),
    /// Paste regions rendered apart (`render --region`) into one image, checking they tile it exactly.
    Merge(merge::MergeArgs),
}

/// An argument error found after clap parsed the command line (a value clap cannot check alone, such as
/// an output extension that does not match what the command writes): exit code 2, as clap's own.
#[derive(Debug)]
pub(crate) struct UsageError(pub String);

impl std::fmt::Display for UsageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for UsageError {}

/// A [`UsageError`] as an `anyhow` error.
pub(super) fn usage(message: impl Into<String>) -> anyhow::Error {
    UsageError(message.into()).into()
}

/// Parses the command line, runs the subcommand, and turns errors into a message and an exit code: 2 for
/// argument errors (clap's and [`UsageError`]), 1 for the rest. The CPU check ([`crate::cpu`]: exit code 1
/// and nothing done when the CPU lacks an instruction set the binary was compiled for) has run before, as
/// an ELF constructor, on Linux; elsewhere it runs here first, before clap.
pub(crate) fn main() -> ExitCode {
    #[cfg(not(all(target_os = "linux", any(target_arch = "x86", target_arch = "x86_64"))))]
    if let Err(message) = crate::cpu::check() {
        eprintln!("{message}");
        return ExitCode::FAILURE;
    }
    let cli = parse_args();
    let result = match cli.command {
        Command::Render(args) => render_run::run(args),
        Command::Gen(args) => gen::run(args),
        Command::Convert(args) => convert::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Accuracy(args) => accuracy::run(args),
        Command::Converge(args) => converge::run(args),
        Command::Merge(args) => merge::run(args),
        Command::Diff(args) => return diff::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => ExitCode::from(report(&e)),
    }
}

/// Prints a command's error and gives its exit code: 2 for argument errors (clap's and [`UsageError`]), 130
/// for an interrupted render (the shell's code for SIGINT), 1 for the rest; 0, silently, for a reader that
/// stopped early (`bareray bench ... | head`).
pub(super) fn report(e: &anyhow::Error) -> u8 {
    if e.downcast_ref::<std::io::Error>().is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe) {
        return 0;
    }
    match e.downcast_ref::<UsageError>() {
        Some(_) => eprintln!("error: {e:#}\n\nFor more information, try '--help'."),
        None => eprintln!("error: {e:#}"),
    }
    exit_code(e)
}

/// The exit code of an error that [`report`] prints: 2 for argument errors, 130 for an interrupt, 1 for
/// the rest.
pub(super) fn exit_code(e: &anyhow::Error) -> u8 {
    if e.downcast_ref::<UsageError>().is_some() {
        2
    } else if matches!(
        e.downcast_ref::<bareray::still::StillError>(),
        Some(bareray::still::StillError::Interrupted(_))
    ) {
        130
    } else {
        1
    }
}

/// [`Cli::parse`], with the instruction sets the build was compiled for in `--version` (`-V` stays short).
fn parse_args() -> Cli {
    let required = crate::cpu::required_features();
    let isa = match required.is_empty() {
        true => "the target's baseline".to_string(),
        false => required.join(" "),
    };
    let version = format!("{}\ncompiled for: {isa}", env!("CARGO_PKG_VERSION"));
    let matches = Cli::command()
        .long_version(&*Box::leak(version.into_boxed_str()))
        .try_get_matches()
        .unwrap_or_else(|e| exit_once(e));
    Cli::from_arg_matches(&matches).unwrap_or_else(|e| exit_once(e))
}

/// Exits on a command-line error (or `--help`, `--version`), printing it on one rank only when a launcher
/// started several: every rank parses the same command line.
///
/// The other ranks leave rank 0 time to print and exit first. A launcher aborts the job when the first
/// rank exits with an error; were that another rank, rank 0 could be killed before its message is out.
/// Rank 0 meets the same error at once, so the wait ends when the launcher kills the waiting ranks; only
/// a rank whose command line rank 0 accepted waits it out, and then prints its error itself.
fn exit_once(e: clap::Error) -> ! {
    #[cfg(feature = "mpi")]
    if bareray::still::mpi::launched_rank().is_some_and(|rank| rank != 0) {
        if e.exit_code() == 0 {
            std::process::exit(0);
        }
        std::thread::sleep(std::time::Duration::from_secs(5));
    }
    e.exit()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn command_line_definition_is_consistent() {
        Cli::command().debug_assert();
    }
}
