//! Generated-input tests of `bareray merge`'s inputs: two regions of one render (PNG, PPM, EXR) are written
//! by the binary, then one of them is mutated (bytes flipped, mostly in the header; truncated; a 4-byte
//! window set to an extreme integer in either byte order; bytes inserted or a range repeated; the region's
//! numbers in a PPM header rewritten) and [`merge`] runs on the pair. Every input must give the merged image
//! (a PNG, PPM or EXR of the full size that decodes) or an error naming a part or the tiling, with the
//! output file as it was and nothing else left in the directory; none may panic or hang.
//!
//! Each input is a function of (format, seed, index) alone: `BARERAY_FUZZ_SEED=S BARERAY_FUZZ_START=I
//! BARERAY_FUZZ_INPUTS=1` reproduces one. The default test, which `cargo test` and CI run, takes
//! [`CI_RUN`] inputs per format; the ignored test is the full run, 1 000 000 per format:
//! `cargo test --release --test suite fuzz_merge:: -- --ignored --nocapture`. Each prints its count and outcome.

use crate::common;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use bareray::math::SplitMix64;
use bareray::still::merge::{merge, MergeError};
use common::{bareray, stderr, watchdog};

/// Inputs per format in the ignored full run.
const FULL_RUN: u64 = 1_000_000;
/// Inputs per format in the default run.
const CI_RUN: u64 = 5_000;
/// How often a long run reports progress.
const PROGRESS: u64 = 100_000;
const DEFAULT_SEED: u64 = 0xB4E4_F022_3E26_0001;
/// An input that takes longer than this is a hang.
const HANG: Duration = Duration::from_secs(30);
/// The merged image's size; the parts are its top and bottom halves.
const SIZE: (u32, u32) = (24, 16);

/// Renders the two halves of a small image as `ext` files into `dir`.
fn parts(dir: &Path, ext: &str) -> [Vec<u8>; 2] {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/whitted.toml");
    let (w, h) = SIZE;
    [format!("0,0,{w},{}", h / 2), format!("0,{},{w},{h}", h / 2)].map(|region| {
        let out = dir.join(format!("seed.{ext}"));
        let run = bareray(&[
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--width",
            &w.to_string(),
            "--height",
            &h.to_string(),
            "--spp",
            "1",
            "--region",
            &region,
            "-q",
        ]);
        assert!(run.status.success(), "{}", stderr(&run));
        let bytes = std::fs::read(&out).unwrap();
        std::fs::remove_file(&out).unwrap();
        bytes
    })
}

/// A uniform index below `n` (n > 0).
fn below(rng: &mut SplitMix64, n: usize) -> usize {
    (rng.unit() * n as f64) as usize % n.max(1)
}

/// One mutation of `part`; positions lean towards the header, where the reader decides most.
fn mutate(rng: &mut SplitMix64, part: &mut Vec<u8>) {
    if part.is_empty() {
        part.push(below(rng, 256) as u8);
        return;
    }
    let len = part.len();
    let at = |rng: &mut SplitMix64| if rng.unit() < 0.7 { below(rng, len.min(160)) } else { below(rng, len) };
    match below(rng, 6) {
        0 => {
            for _ in 0..1 + below(rng, 8) {
                let i = at(rng);
                part[i] ^= 1 << below(rng, 8);
            }
        }
        1 => part.truncate(below(rng, len)),
        2 => {
            let value = [0u32, 1, 0x7fff_ffff, 0xffff_ffff, 0x8000_0000, 65_536][below(rng, 6)];
            let bytes = if rng.unit() < 0.5 { value.to_be_bytes() } else { value.to_le_bytes() };
            let i = at(rng).min(len.saturating_sub(4));
            part[i..(i + 4).min(len)].copy_from_slice(&bytes[..4.min(len - i)]);
        }
        3 => {
            let i = at(rng);
            let extra: Vec<u8> = (0..1 + below(rng, 16)).map(|_| below(rng, 256) as u8).collect();
            part.splice(i..i, extra);
        }
        4 => {
            let i = at(rng);
            let j = (i + 1 + below(rng, 64)).min(len);
            let copy = part[i..j].to_vec();
            part.splice(j..j, copy);
        }
        _ => {
            // A number in a text header (PPM's region comment, sizes) becomes another.
            let digits: Vec<usize> = (0..len.min(160)).filter(|&i| part[i].is_ascii_digit()).collect();
            if digits.is_empty() {
                part[at(rng)] ^= 0x10;
            } else {
                let i = digits[below(rng, digits.len())];
                let new = ["0", "9", "99999999999", "4294967296", "-1", ""][below(rng, 6)];
                part.splice(i..i + 1, new.bytes());
            }
        }
    }
}

/// The pair of parts for input `index`: one of them mutated once or twice.
fn input(seeds: &[Vec<u8>; 2], seed: u64, index: u64) -> [Vec<u8>; 2] {
    let mut rng = SplitMix64::new(seed ^ index.wrapping_mul(0x9E37_79B9_7F4A_7C15));
    let mut pair = seeds.clone();
    let which = below(&mut rng, 2);
    for _ in 0..1 + below(&mut rng, 2) {
        mutate(&mut rng, &mut pair[which]);
    }
    pair
}

/// What is wrong with one outcome, if anything.
fn check(dir: &Path, paths: &[PathBuf; 2], out: &Path, result: Result<(), MergeError>) -> Option<String> {
    let mut left: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    let names = |list: &[&Path]| {
        let mut v: Vec<String> =
            list.iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    };
    if left != names(&[&paths[0], &paths[1], out]) {
        return Some(format!("the directory holds {left:?}"));
    }
    match result {
        Ok(()) => match image::open(out) {
            Ok(img) if (img.width(), img.height()) == SIZE => None,
            Ok(img) => Some(format!("merged to {}x{}", img.width(), img.height())),
            Err(e) => Some(format!("merged into a file that does not decode: {e}")),
        },
        Err(e) => {
            let text = e.to_string();
            let named = paths.iter().any(|p| text.starts_with(&format!("{}: ", p.display())));
            if std::fs::read(out).unwrap() != b"precious" {
                Some(format!("an error ({text}) changed the output file"))
            } else if !named && !matches!(e, MergeError::Tiling(_)) {
                Some(format!("an error names neither a part nor the tiling: {text}"))
            } else {
                None
            }
        }
    }
}

/// Runs `default_count` inputs (or `BARERAY_FUZZ_INPUTS`) for parts of format `ext`.
fn fuzz(ext: &str, default_count: u64) {
    let env =
        |key: &str| std::env::var(key).ok().map(|v| v.parse::<u64>().unwrap_or_else(|_| panic!("{key}")));
    let count = env("BARERAY_FUZZ_INPUTS").unwrap_or(default_count);
    let seed = env("BARERAY_FUZZ_SEED").unwrap_or(DEFAULT_SEED);
    let start = env("BARERAY_FUZZ_START").unwrap_or(0);
    let dir = tempfile::tempdir().unwrap();
    let seeds = parts(dir.path(), ext);
    let paths = [dir.path().join(format!("top.{ext}")), dir.path().join(format!("bottom.{ext}"))];
    let out = dir.path().join(format!("merged.{ext}"));

    let current = Arc::new(AtomicU64::new(start));
    let watchdog = {
        let ext = ext.to_owned();
        watchdog::watch(current.clone(), HANG, move |now| {
            eprintln!("fuzz: merge {ext}: input {now} (seed {seed:#x}) has not finished in {HANG:?}: hang");
        })
    };
    let began = Instant::now();
    let (mut merged, mut errors, mut failures) = (0u64, 0u64, Vec::new());
    for index in start..start + count {
        current.store(index, Ordering::Relaxed);
        for (path, bytes) in paths.iter().zip(input(&seeds, seed, index)) {
            std::fs::write(path, bytes).unwrap();
        }
        std::fs::write(&out, b"precious").unwrap();
        let outcome = catch_unwind(AssertUnwindSafe(|| merge(&paths[..], &out).map(|_| ())));
        let failure = match outcome {
            Err(panic) => Some(format!(
                "panic: {}",
                panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default()
            )),
            Ok(result) => {
                if result.is_ok() {
                    merged += 1;
                } else {
                    errors += 1;
                }
                check(dir.path(), &paths, &out, result)
            }
        };
        if let Some(why) = failure {
            let report = format!("input {index} (seed {seed:#x}): {why}");
            eprintln!("fuzz: merge {ext}: {report}");
            failures.push(report);
        }
        let done = index - start + 1;
        if done % PROGRESS == 0 && done < count {
            println!("fuzz: merge {ext}: {done} of {count} inputs, {} failures", failures.len());
        }
    }
    current.store(watchdog::DONE, Ordering::Relaxed);
    watchdog.join().expect("watchdog");
    println!(
        "fuzz: merge {ext}: {count} inputs, {merged} merged, {errors} errors, {} panics or bad outcomes \
         ({:.1} s; seed {seed:#x}, from index {start})",
        failures.len(),
        began.elapsed().as_secs_f64()
    );
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}

#[test]
fn merge_survives_generated_png_parts() {
    fuzz("png", CI_RUN);
}

#[test]
fn merge_survives_generated_ppm_parts() {
    fuzz("ppm", CI_RUN);
}

#[test]
fn merge_survives_generated_exr_parts() {
    fuzz("exr", CI_RUN);
}

#[test]
#[ignore = "the full run: 1e6 inputs per format, minutes in release mode"]
fn merge_survives_a_million_png_ppm_and_exr_inputs() {
    for ext in ["png", "ppm", "exr"] {
        fuzz(ext, FULL_RUN);
    }
}
