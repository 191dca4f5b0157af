//! `bareray bench --isa v2,v3,v4`: the same bench run by builds of this source for several x86-64 levels,
//! one process each, and their rows printed in one table. `wide` and `Real::mul_add` pick their code when
//! they are compiled, so the levels are separate binaries (`cargo build-v2` and so on, into
//! `target/isa/<level>/`), not one binary choosing at run time. Each build runs `bareray bench ... --json
//! --reps 1` with this command's other arguments, once per round, the builds taking turns; the checksums of
//! every (lanes, threads) row must agree between builds, since every build traces the same bits.

use std::ffi::OsString;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use anyhow::{anyhow, bail, Context, Result};
use serde::Deserialize;
use serde_json::Value;

use super::values::LanesArg;

/// The variable naming the directory that holds the per-ISA builds (`<level>/release/bareray` in it), as
/// `--isa-dir` does; the flag wins.
pub const ISA_DIR_VAR: &str = "BARERAY_ISA_DIR";

/// An x86-64 micro-architecture level a build is compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    /// x86-64-v2: SSE4.2, no FMA (`mul_add` is the C library's `fmaf`, one lane at a time).
    V2,
    /// x86-64-v3: AVX2 and FMA (the default build).
    V3,
    /// x86-64-v4: AVX-512.
    V4,
}

impl Level {
    /// The short name, as `--isa` takes it and the build's directory is called: `v2`, `v3`, `v4`.
    pub fn name(self) -> &'static str {
        match self {
            Level::V2 => "v2",
            Level::V3 => "v3",
            Level::V4 => "v4",
        }
    }

    /// The features a CPU needs to run a build for this level.
    fn features(self) -> Vec<&'static str> {
        use crate::cpu::{X86_64_V2, X86_64_V3, X86_64_V4};
        let levels: &[&[&str]] = match self {
            Level::V2 => &[X86_64_V2],
            Level::V3 => &[X86_64_V2, X86_64_V3],
            Level::V4 => &[X86_64_V2, X86_64_V3, X86_64_V4],
        };
        levels.concat()
    }

    /// Whether `isa`, what a build's `bench` reports its kernels compiled for, is this level's.
    fn kernels_match(self, isa: &str) -> bool {
        match self {
            Level::V2 => !isa.contains("avx"),
            Level::V3 => isa.starts_with("avx2"),
            Level::V4 => isa.starts_with("avx512"),
        }
    }
}

/// Parses one `--isa` level: `v2`, `v3`, `v4`, or the same with `x86-64-` in front.
pub fn parse_level(s: &str) -> Result<Level, String> {
    let t = s.trim().to_ascii_lowercase();
    match t.strip_prefix("x86-64-").unwrap_or(&t) {
        "v2" => Ok(Level::V2),
        "v3" => Ok(Level::V3),
        "v4" => Ok(Level::V4),
        _ => Err(format!(
            "levels are v2 (SSE4.2), v3 (AVX2 and FMA) and v4 (AVX-512), as a comma list; got `{s}`"
        )),
    }
}

/// A build to run: its level and binary.
struct Build {
    level: Level,
    path: PathBuf,
}

/// The fields of a build's `bench --json` line that the comparison reads (the line is kept whole for
/// `--json`).
#[derive(Deserialize)]
struct ChildRow {
    lanes: LanesArg,
    threads: usize,
    rays: u64,
    seconds: f64,
    checksum: String,
    isa: String,
}

/// One build's rows over the rounds: the first round's lines, and every round's seconds per row.
struct Measured {
    rows: Vec<(ChildRow, Value)>,
    seconds: Vec<Vec<f64>>,
}

/// The binary name of a build inside its level's directory, below `<level>/`.
fn binary_below(level: Level) -> PathBuf {
    Path::new(level.name()).join("release").join(format!("bareray{}", std::env::consts::EXE_SUFFIX))
}

/// Where a level's build is looked for: `DIR/<level>/release/bareray` with a directory given
/// (`--isa-dir` or [`ISA_DIR_VAR`]); else `isa/<level>/release/bareray` in each directory above the running
/// binary (`target/release/bareray` and `target/isa/v3/release/bareray` both find `target/isa/`), then
/// `target/isa/<level>/release/bareray` under the working directory.
fn candidates(level: Level, dir: Option<&Path>, exe: Option<&Path>) -> Vec<PathBuf> {
    if let Some(dir) = dir {
        return vec![dir.join(binary_below(level))];
    }
    let mut paths: Vec<PathBuf> = exe
        .and_then(Path::parent)
        .into_iter()
        .flat_map(Path::ancestors)
        .map(|a| a.join("isa").join(binary_below(level)))
        .collect();
    paths.push(Path::new("target/isa").join(binary_below(level)));
    paths
}

/// The first of [`candidates`] that is a file, or an error naming where it looked and the command that
/// builds it.
fn find(level: Level, dir: Option<&Path>, exe: Option<&Path>) -> Result<PathBuf, String> {
    let paths = candidates(level, dir, exe);
    if let Some(found) = paths.iter().find(|p| p.is_file()) {
        return Ok(found.clone());
    }
    let looked = match (dir, exe.and_then(Path::parent)) {
        (Some(_), _) | (None, None) => format!("{}", paths[0].display()),
        (None, Some(exe_dir)) => format!(
            "isa/{} in the directories above {}, and {}",
            binary_below(level).display(),
            exe_dir.display(),
            paths[paths.len() - 1].display()
        ),
    };
    Err(format!(
        "no x86-64-{0} build of bareray (looked for {looked}): build it at the repository root with \
         `cargo build-{0}` (all three levels: `bench-peers/build_isa.sh`), or name the directory holding \
         {0}/release/bareray with --isa-dir or {ISA_DIR_VAR}",
        level.name()
    ))
}

/// The arguments for a build's run: `args` (what followed `bench`) without `--isa`, `--isa-dir`, `--json`,
/// `--reps` and `--by-kind` (as `--flag value` or `--flag=value`), after `--json --reps 1`. The split by ray
/// kind is added per round ([`by_kind_args`]).
fn child_args(args: &[OsString]) -> Vec<OsString> {
    const WITH_VALUE: [&str; 4] = ["--isa", "--isa-dir", "--reps", "--by-kind"];
    let mut out: Vec<OsString> = ["--json", "--reps", "1"].map(OsString::from).into();
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        match arg.to_str() {
            Some("--") => {
                out.push(arg.clone());
                out.extend(it.by_ref().cloned());
            }
            Some("--json") => {}
            Some(a) if WITH_VALUE.contains(&a) => {
                it.next();
            }
            Some(a) if WITH_VALUE.iter().any(|f| a.strip_prefix(f).is_some_and(|r| r.starts_with('='))) => {}
            _ => out.push(arg.clone()),
        }
    }
    out
}

/// `--by-kind` for a build's run in `round`: the first round splits its rows by ray kind (unless the
/// command said `--by-kind false`), the later ones only time them.
fn by_kind_args(round: usize, split: bool) -> [OsString; 2] {
    ["--by-kind", if round == 0 && split { "true" } else { "false" }].map(OsString::from)
}

/// Runs one build's bench and parses its lines.
fn run_build(build: &Build, args: &[OsString]) -> Result<Vec<(ChildRow, Value)>> {
    let name = build.level.name();
    let out = Command::new(&build.path)
        .arg("bench")
        .args(args)
        .stdin(Stdio::null())
        .output()
        .with_context(|| format!("cannot run the {name} build, {}", build.path.display()))?;
    let err = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        bail!("the {name} build, {}, failed ({}):\n{}", build.path.display(), out.status, err.trim_end());
    }
    for line in err.lines() {
        eprintln!("[{name}] {line}");
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let rows = text
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|line| {
            let value: Value = serde_json::from_str(line)?;
            Ok((ChildRow::deserialize(&value)?, value))
        })
        .collect::<Result<Vec<_>, serde_json::Error>>()
        .map_err(|e| {
            anyhow!("the {name} build, {}, printed a line that is not bench JSON: {e}", build.path.display())
        })?;
    if rows.is_empty() {
        bail!("the {name} build, {}, printed no rows", build.path.display());
    }
    Ok(rows)
}

/// Adds a round's rows of build `i` to `all`, checking that they have the settings, rays and checksums of
/// its earlier rounds and of every other build's rows.
fn add_round(
    all: &mut [Option<Measured>],
    builds: &[Build],
    i: usize,
    rows: Vec<(ChildRow, Value)>,
) -> Result<()> {
    let label = |k: usize| format!("{} ({})", builds[k].level.name(), builds[k].path.display());
    let key = |r: &ChildRow| (r.lanes, r.threads);
    for (j, other) in all.iter().enumerate() {
        let Some(other) = other else { continue };
        if rows.len() != other.rows.len()
            || rows.iter().zip(&other.rows).any(|((a, _), (b, _))| key(a) != key(b))
        {
            bail!(
                "{} and {} measured different rows; are they builds of the same source?",
                label(i),
                label(j)
            );
        }
        for ((a, _), (b, _)) in rows.iter().zip(&other.rows) {
            if a.checksum != b.checksum || a.rays != b.rays {
                let what = if i == j { "between rounds of one build" } else { "between builds" };
                bail!(
                    "checksums differ {what} at lanes {}, threads {}: {} gave {} ({} rays), {} gave {} ({} rays); \
                     every build should trace the same bits",
                    a.lanes,
                    a.threads,
                    label(j),
                    b.checksum,
                    b.rays,
                    label(i),
                    a.checksum,
                    a.rays
                );
            }
        }
    }
    match &mut all[i] {
        Some(m) => m.seconds.iter_mut().zip(&rows).for_each(|(s, (r, _))| s.push(r.seconds)),
        slot => {
            let seconds = rows.iter().map(|(r, _)| vec![r.seconds]).collect();
            *slot = Some(Measured { rows, seconds });
        }
    }
    Ok(())
}

/// Runs `bench --isa`: `levels` in the given order, `rounds` rounds, the builds found in `dir` (else next to
/// the running binary), each given `args` (what followed `bench` on the command line) for its own run.
pub fn run(
    levels: &[Level],
    dir: Option<&Path>,
    rounds: u32,
    json: bool,
    by_kind: bool,
    args: &[OsString],
) -> Result<()> {
    if !cfg!(target_arch = "x86_64") {
        bail!("--isa runs x86-64 builds, and this is not an x86-64 machine");
    }
    for (i, level) in levels.iter().enumerate() {
        if levels[..i].contains(level) {
            return Err(super::usage(format!("--isa: {} is listed twice", level.name())));
        }
    }
    let env_dir = std::env::var_os(ISA_DIR_VAR).filter(|d| !d.is_empty()).map(PathBuf::from);
    let dir = dir.or(env_dir.as_deref());
    let exe = std::env::current_exe().ok();
    let (mut builds, mut notes, mut missing) = (Vec::new(), Vec::new(), Vec::new());
    for &level in levels {
        let lacks = crate::cpu::lacking(&level.features());
        if !lacks.is_empty() {
            notes.push(format!("note: x86-64-{} skipped: CPU lacks {}", level.name(), lacks.join(", ")));
            continue;
        }
        match find(level, dir, exe.as_deref()) {
            Ok(path) => builds.push(Build { level, path }),
            Err(message) => missing.push(message),
        }
    }
    if !missing.is_empty() {
        bail!("{}", missing.join("\nerror: "));
    }
    if builds.is_empty() {
        bail!(
            "no build to run: {}",
            notes.iter().map(|n| n.trim_start_matches("note: ")).collect::<Vec<_>>().join("; ")
        );
    }
    let child = child_args(args);
    let mut all: Vec<Option<Measured>> = builds.iter().map(|_| None).collect();
    let progress = std::io::stderr().is_terminal();
    for round in 0..rounds as usize {
        for turn in 0..builds.len() {
            let i = (turn + round) % builds.len();
            if progress {
                eprint!("\rround {}/{rounds}: {}  ", round + 1, builds[i].level.name());
            }
            let rows = run_build(&builds[i], &[&child[..], &by_kind_args(round, by_kind)[..]].concat())?;
            add_round(&mut all, &builds, i, rows)?;
        }
    }
    if progress {
        eprint!("\r{:40}\r", "");
    }
    let all: Vec<Measured> = all.into_iter().map(|m| m.expect("every build ran at least once")).collect();
    for (b, m) in builds.iter().zip(&all) {
        if !b.level.kernels_match(&m.rows[0].0.isa) {
            notes.push(format!(
                "warning: the {} build, {}, reports kernels for {}: not an x86-64-{} build (RUSTFLAGS replaces \
                 the flags of `cargo build-{}`)",
                b.level.name(),
                b.path.display(),
                m.rows[0].0.isa,
                b.level.name(),
                b.level.name()
            ));
        }
    }
    let mut out = std::io::stdout().lock();
    if json {
        for note in &notes {
            eprintln!("{note}");
        }
        print_json(&mut out, &builds, &all, rounds)
    } else {
        print_table(&mut out, &builds, &all, rounds, &notes)
    }
}

/// Minimum, median and maximum of a row's seconds over rounds.
fn spread(seconds: &[f64]) -> (f64, f64, f64) {
    let mut s = seconds.to_vec();
    s.sort_by(f64::total_cmp);
    (s[0], s[s.len() / 2], s[s.len() - 1])
}

/// The rows in print order: each (lanes, threads) of the first build's order, each build in `--isa`'s
/// order: (build, row) indices.
fn order(all: &[Measured]) -> impl Iterator<Item = (usize, usize)> + '_ {
    (0..all[0].rows.len()).flat_map(move |r| (0..all.len()).map(move |b| (b, r)))
}

/// The builds' rows as `bench --json` lines, each with the seconds over rounds and `isa_level`,
/// `software_fma` and `binary` added.
fn print_json(out: &mut impl Write, builds: &[Build], all: &[Measured], rounds: u32) -> Result<()> {
    for (b, r) in order(all) {
        let (row, value) = &all[b].rows[r];
        let (min, median, max) = spread(&all[b].seconds[r]);
        let mut value = value.clone();
        if let Some(obj) = value.as_object_mut() {
            obj.insert("seconds".into(), median.into());
            obj.insert("min_s".into(), min.into());
            obj.insert("max_s".into(), max.into());
            obj.insert("mrays_per_s".into(), (row.rays as f64 / median / 1e6).into());
            obj.insert("reps".into(), rounds.into());
            obj.insert("isa_level".into(), builds[b].level.name().into());
            obj.insert("software_fma".into(), (!row.isa.contains("fma")).into());
            obj.insert("binary".into(), builds[b].path.display().to_string().into());
        }
        writeln!(out, "{value}")?;
    }
    Ok(())
}

/// The builds' rows as one table, each row's speed relative to the v3 build's (the default build's) row of
/// the same lanes and threads, or to the first build's when v3 is not measured.
fn print_table(
    out: &mut impl Write,
    builds: &[Build],
    all: &[Measured],
    rounds: u32,
    notes: &[String],
) -> Result<()> {
    let first = &all[0].rows[0].1;
    let s = |key: &str| first[key].as_str().unwrap_or("?").to_owned();
    let n = |key: &str| first[key].as_u64().unwrap_or(0);
    let what = if first["primary_only"].as_bool() == Some(true) {
        "primary rays only".to_owned()
    } else {
        format!("full render, {}, depth {}", s("pattern"), n("max_depth"))
    };
    let names: Vec<&str> = builds.iter().map(|b| b.level.name()).collect();
    writeln!(out, "{}: {} spheres, {}x{}; {what}", s("scene"), n("spheres"), n("width"), n("height"))?;
    writeln!(
        out,
        "host: {}, {} cores; {} builds of bareray {}",
        s("cpu"),
        n("cores"),
        s("profile"),
        s("version")
    )?;
    writeln!(
        out,
        "builds x86-64-{}: {rounds} rounds, each build once per round (its own process, `bench --reps 1` after \
         one warm-up) in turn, the order rotating by round; min, median and max seconds over rounds, Mrays/s \
         from the median",
        names.join(", ")
    )?;
    for note in notes {
        writeln!(out, "{note}")?;
    }
    let base = builds.iter().position(|b| b.level == Level::V3).unwrap_or(0);
    writeln!(
        out,
        "isa  kernels      lanes threads        rays      min s   median s      max s    Mrays/s {:>10}  checksum",
        format!("vs {}", builds[base].level.name())
    )?;
    let mrays = |b: usize, r: usize| all[b].rows[r].0.rays as f64 / spread(&all[b].seconds[r]).1 / 1e6;
    for (b, r) in order(all) {
        let row = &all[b].rows[r].0;
        let (min, median, max) = spread(&all[b].seconds[r]);
        writeln!(
            out,
            "{:<4} {:<12} {:>5} {:7} {:11} {min:10.4} {median:10.4} {max:10.4} {:10.2} {:>9.2}x  {}{}",
            builds[b].level.name(),
            row.isa,
            row.lanes,
            row.threads,
            row.rays,
            mrays(b, r),
            mrays(b, r) / mrays(base, r),
            row.checksum,
            if row.isa.contains("fma") { "" } else { "  software FMA" }
        )?;
    }
    writeln!(out, "checksums: equal in every build for every row")?;
    let split: Vec<_> = order(all)
        .map(|(b, r)| {
            (builds[b].level.name(), all[b].rows[r].0.lanes, all[b].rows[r].0.threads, &all[b].rows[r].1)
        })
        .collect();
    super::bench_kinds::print_builds(out, &split, builds[base].level.name())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn os(args: &[&str]) -> Vec<OsString> {
        args.iter().map(OsString::from).collect()
    }

    #[test]
    fn levels_parse_and_bad_ones_are_named() {
        assert_eq!(parse_level("v2"), Ok(Level::V2));
        assert_eq!(parse_level(" V3 "), Ok(Level::V3));
        assert_eq!(parse_level("x86-64-v4"), Ok(Level::V4));
        for bad in ["v5", "", "avx2", "x86-64"] {
            assert!(parse_level(bad).unwrap_err().contains(&format!("`{bad}`")), "{bad}");
        }
    }

    #[test]
    fn level_features_grow_with_the_level() {
        let (v2, v3, v4) = (Level::V2.features(), Level::V3.features(), Level::V4.features());
        assert!(v2.contains(&"sse4.2") && !v2.contains(&"fma"));
        assert!(v3.contains(&"fma") && v3.contains(&"avx2") && !v3.contains(&"avx512f"));
        assert!(v4.contains(&"avx512vl") && v2.iter().chain(&v3).all(|f| v4.contains(f)));
    }

    #[test]
    fn kernels_match_their_level() {
        assert!(Level::V2.kernels_match("sse2") && !Level::V2.kernels_match("avx2+fma"));
        assert!(Level::V3.kernels_match("avx2+fma") && !Level::V3.kernels_match("avx512f+fma"));
        assert!(Level::V4.kernels_match("avx512f+fma") && !Level::V4.kernels_match("avx2+fma"));
    }

    #[test]
    fn child_args_drop_isa_json_reps_and_by_kind() {
        let args = os(&[
            "s.toml",
            "--isa",
            "v2,v3",
            "--lanes",
            "1,8",
            "--isa-dir=/x",
            "--json",
            "--reps",
            "3",
            "--isa=v4",
            "--reps=2",
            "--by-kind",
            "false",
            "--threads",
            "1",
            "--by-kind=true",
        ]);
        assert_eq!(
            child_args(&args),
            os(&["--json", "--reps", "1", "s.toml", "--lanes", "1,8", "--threads", "1"])
        );
        // After `--` everything is a positional argument and passes as it is.
        assert_eq!(child_args(&os(&["--", "--json"])), os(&["--json", "--reps", "1", "--", "--json"]));
        // The first round splits by kind unless told not to; the later ones never do.
        assert_eq!(by_kind_args(0, true), os(&["--by-kind", "true"]).as_slice());
        assert_eq!(by_kind_args(0, false), os(&["--by-kind", "false"]).as_slice());
        assert_eq!(by_kind_args(3, true), os(&["--by-kind", "false"]).as_slice());
    }

    #[test]
    fn builds_are_looked_for_above_the_binary_then_in_the_override() {
        let exe = Path::new("/r/target/release/bareray");
        let found = candidates(Level::V4, None, Some(exe));
        assert_eq!(found[0], Path::new("/r/target/release/isa").join(binary_below(Level::V4)));
        assert!(found.contains(&Path::new("/r/target/isa").join(binary_below(Level::V4))));
        assert_eq!(found.last().unwrap(), &Path::new("target/isa").join(binary_below(Level::V4)));
        let dir = Path::new("/builds");
        assert_eq!(candidates(Level::V2, Some(dir), Some(exe)), [dir.join("v2/release/bareray")]);
    }

    #[test]
    fn a_missing_build_names_its_build_command() {
        let dir = tempfile::tempdir().unwrap();
        let err = find(Level::V4, Some(dir.path()), None).unwrap_err();
        assert!(err.contains("`cargo build-v4`") && err.contains("bench-peers/build_isa.sh"), "{err}");
        assert!(err.contains(&dir.path().join("v4/release/bareray").display().to_string()), "{err}");
    }

    #[test]
    fn spread_is_min_median_max() {
        assert_eq!(spread(&[3.0, 1.0, 2.0]), (1.0, 2.0, 3.0));
        assert_eq!(spread(&[5.0]), (5.0, 5.0, 5.0));
    }
}
