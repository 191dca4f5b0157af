//! `bareray bench --isa`'s builds: where each is found, the arguments it gets, its run, and the rounds'
//! rows checked against each other.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use anyhow::{anyhow, bail, Context, Result};
use serde::Deserialize;
use serde_json::Value;

use super::bench_isa_level::{Build, Level, ISA_DIR_VAR};
use super::values::LanesArg;

/// The fields of a build's `bench --json` line that the comparison reads (the line is kept whole for
/// `--json`).
#[derive(Deserialize)]
pub(super) struct ChildRow {
    pub(super) lanes: LanesArg,
    pub(super) threads: usize,
    pub(super) rays: u64,
    pub(super) seconds: f64,
    pub(super) checksum: String,
    pub(super) isa: String,
}

/// One build's rows over the rounds: the first round's lines, and every round's seconds per row.
pub(super) struct Measured {
    pub(super) rows: Vec<(ChildRow, Value)>,
    pub(super) seconds: Vec<Vec<f64>>,
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
pub(super) fn find(level: Level, dir: Option<&Path>, exe: Option<&Path>) -> Result<PathBuf, String> {
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
pub(super) fn child_args(args: &[OsString]) -> Vec<OsString> {
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
pub(super) fn by_kind_args(round: usize, split: bool) -> [OsString; 2] {
    ["--by-kind", if round == 0 && split { "true" } else { "false" }].map(OsString::from)
}

/// Runs one build's bench and parses its lines.
pub(super) fn run_build(build: &Build, args: &[OsString]) -> Result<Vec<(ChildRow, Value)>> {
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
pub(super) fn add_round(
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

#[cfg(test)]
mod tests {
    use super::*;

    fn os(args: &[&str]) -> Vec<OsString> {
        args.iter().map(OsString::from).collect()
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
}
