//! `bareray bench --isa v2,v3,v4`: the same bench run by builds of this source for several x86-64 levels,
//! one process each, and their rows printed in one table. `wide` and `Real::mul_add` pick their code when
//! they are compiled, so the levels are separate binaries (`cargo build-v2` and so on, into
//! `target/isa/<level>/`), not one binary choosing at run time. Each build runs `bareray bench ... --json
//! --reps 1` with this command's other arguments, once per round, the builds taking turns; the checksums of
//! every (lanes, threads) row must agree between builds, since every build traces the same bits.

use std::ffi::OsString;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use super::bench_isa_level::{Build, Level, ISA_DIR_VAR};
use super::bench_isa_print::{print_json, print_table};
use super::bench_isa_runs::{add_round, by_kind_args, child_args, find, run_build, Measured};

/// Runs `bench --isa`: `levels` in the given order, `rounds` rounds, the builds found in `dir` (else next to
/// the running binary), each given `args` (what followed `bench` on the command line) for its own run.
pub(super) fn run(
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
