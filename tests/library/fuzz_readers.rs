//! Generated-input tests of the scene readers (TOML, NFF, xyzr): mutations of the real scenes in `scenes/`
//! (and a generated sphereflake) are parsed, and every one must give a scene or an error naming the file and
//! a line; none may panic or hang. The binary f32r reader gets mutations of binary fields, checked against
//! an independent decoding of the format (its tests at the end of the file).
//!
//! Each input is a function of (reader, seed, index) alone, so a failure is reproduced by its seed and
//! index: `BARERAY_FUZZ_SEED=S BARERAY_FUZZ_START=I BARERAY_FUZZ_INPUTS=1`. A failing input is also written
//! to the system's temporary directory.
//!
//! The default tests, which `cargo test` and so CI run, take 20 000 inputs per reader ([`CI_RUN`]); the
//! ignored tests are the full run, 1 000 000 per reader ([`FULL_RUN`]):
//! `cargo test --release --lib fuzz_readers:: -- --ignored --nocapture`. `BARERAY_FUZZ_INPUTS` replaces the
//! count of either. Each test prints the count it ran and what came of it (`fuzz: toml: 1000000 inputs, …`,
//! seen with `--nocapture`), and a run of [`PROGRESS`] inputs or more prints how far it got every
//! [`PROGRESS`] inputs.
//!
//! What an error must say: `name:N` (and optionally `:column`) with 1 ≤ N ≤ (number of '\n') + 1; the
//! last value is the line after a final newline, where an error about the end of the file lands (TOML
//! reports the end-of-file offset there). Only errors about the file as a whole carry no line (`name: …`):
//! an NFF file without a view, an xyzr file without spheres; there is no line to point at.
//!
//! A stack overflow aborts the process and cannot be caught in it: the test binary then fails, and the
//! deterministic inputs reproduce it (bisect with `BARERAY_FUZZ_START` / `BARERAY_FUZZ_INPUTS`). A hang is
//! caught by a watchdog thread, which writes the input and exits the process with failure.

use super::common;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use bareray::compile::Scene;
use bareray::io::generate::flake_nff;
use bareray::io::{nff, toml, xyzr, SceneError};
use bareray::math::SplitMix64;
use bareray::scene::SceneDesc;
use common::watchdog;

/// Inputs per reader of the ignored full run.
const FULL_RUN: u64 = 1_000_000;
/// Inputs per reader of the default run, unless `BARERAY_FUZZ_INPUTS` says otherwise: a few seconds per
/// reader in the test profile on a shared 2-core machine.
const CI_RUN: u64 = 20_000;
/// A run prints a progress line every this many inputs.
const PROGRESS: u64 = 100_000;
/// The default seed; every run with it sees the same inputs.
const DEFAULT_SEED: u64 = 0xB4E4_F022_5EED_0001;
/// A parse that makes no progress for this long is a hang. The slowest input of the full run (a 39 MB
/// TOML file of repeated nesting lines, a located error) took 13–25 s on a loaded 2-core host.
const HANG: Duration = Duration::from_secs(120);
/// Seed files larger than this are cut to their head plus a random window of lines, which keeps inputs
/// (and so parse times) small while every construct of the file still turns up in some window.
const WINDOW_BYTES: usize = 4096;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Reader {
    Toml,
    Nff,
    Xyzr,
}

impl Reader {
    fn name(self) -> &'static str {
        match self {
            Reader::Toml => "toml",
            Reader::Nff => "nff",
            Reader::Xyzr => "xyzr",
        }
    }

    fn parse(self, path: &Path, source: &str) -> Result<SceneDesc, SceneError> {
        match self {
            Reader::Toml => toml::parse(path, source),
            Reader::Nff => nff::parse(path, source),
            Reader::Xyzr => xyzr::parse(path, source),
        }
    }

    /// Messages of the errors about the whole file, which have no line.
    fn whole_file_errors(self) -> &'static [&'static str] {
        match self {
            Reader::Toml => &[],
            Reader::Nff => &["no view (`v`)"],
            Reader::Xyzr => &["no spheres"],
        }
    }

    /// Bytes that mean something to the reader, favoured by the byte mutators.
    fn syntax(self) -> &'static [u8] {
        match self {
            Reader::Toml => b"[]{}=,.\"'#\n\r\t -+_:eE0123456789abcdxyz\\",
            Reader::Nff => b"#\n\r\t -+.eE0123456789vblfspcpp",
            Reader::Xyzr => b"#\n\r\t -+.eE0123456789",
        }
    }
}

/// The seed scenes of a reader: its files under `scenes/` and `scenes/stress/`, and for NFF a sphereflake.
fn seeds(reader: Reader) -> Vec<Vec<u8>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut files: Vec<PathBuf> = [root.clone(), root.join("stress")]
        .iter()
        .flat_map(|dir| std::fs::read_dir(dir).expect("scenes/ is readable"))
        .map(|entry| entry.expect("scenes/ is listable").path())
        .filter(|p| p.extension().is_some_and(|e| e == reader.name()))
        .collect();
    files.sort();
    let mut seeds: Vec<Vec<u8>> = files.iter().map(|p| std::fs::read(p).expect("seed is readable")).collect();
    if reader == Reader::Nff {
        seeds.push(flake_nff(2).expect("sphereflake level 2").into_bytes());
    }
    assert!(!seeds.is_empty(), "no {} seed scenes in {}", reader.name(), root.display());
    seeds
}

/// Random choices from a [`SplitMix64`].
struct Rng(SplitMix64);

impl Rng {
    /// A number in `0..n` (`n` > 0).
    fn below(&mut self, n: usize) -> usize {
        ((self.0.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * n as f64) as usize
    }
    fn chance(&mut self, p: f64) -> bool {
        self.0.unit() < p
    }
    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// Numbers that readers must reject or survive: out of f32 or f64 range, below f32's smallest, not finite,
/// signed zero, absurdly long, empty, malformed, and integers past u32.
fn odd_number(rng: &mut Rng) -> String {
    const ODD: &[&str] = &[
        "1e39",
        "-1e39",
        "1e308",
        "1.8e308",
        "-1e400",
        "1e400",
        "1e-45",
        "1e-400",
        "-1e-320",
        "nan",
        "NaN",
        "-nan",
        "inf",
        "-inf",
        "+inf",
        "infinity",
        "-0",
        "-0.0",
        "0",
        "",
        "1e",
        "1e+",
        ".",
        "-",
        "--1",
        "0x10",
        "1_000",
        "1__0",
        "4294967295",
        "4294967296",
        "18446744073709551616",
        "-1",
        "65537",
        "1.",
        ".5",
        "3.4028236e38",
        "-3.4028235e38",
        "+1",
        "1e-7",
        "\"1\"",
        "true",
    ];
    match rng.below(8) {
        0 => "9".repeat(1 + rng.below(2000)),
        1 => format!("0.{}1", "0".repeat(rng.below(1000))),
        2 => format!("1{}", "0".repeat(rng.below(400))),
        _ => rng.pick(ODD).to_string(),
    }
}

/// Whether `w` looks like a number (starts like one).
fn numberish(w: &[u8]) -> bool {
    w.first().is_some_and(|c| c.is_ascii_digit() || b"-+.".contains(c))
}

/// Byte ranges of the whitespace-separated tokens of `s`, split around TOML's `[]{},=` too.
fn tokens(s: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, &c) in s.iter().enumerate() {
        let sep = c.is_ascii_whitespace() || b"[]{},=".contains(&c);
        match (start, sep) {
            (None, false) => start = Some(i),
            (Some(b), true) => {
                out.push((b, i));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(b) = start {
        out.push((b, s.len()));
    }
    out
}

/// Byte ranges of the lines of `s`, each with its '\n'.
fn lines(s: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut b = 0;
    for (i, &c) in s.iter().enumerate() {
        if c == b'\n' {
            out.push((b, i + 1));
            b = i + 1;
        }
    }
    if b < s.len() {
        out.push((b, s.len()));
    }
    out
}

/// Deeply nested TOML: arrays, inline tables, dotted keys or table headers, `depth` deep, closed or not.
fn toml_nesting(rng: &mut Rng) -> String {
    // Mostly around the toml crate's limit; seldom very deep, as such inputs take milliseconds each.
    const DEPTHS: &[usize] = &[8, 79, 80, 81, 127, 128, 129, 255, 256, 1000, 5000];
    let depth = if rng.chance(0.05) { *rng.pick(&[20_000, 100_000]) } else { *rng.pick(DEPTHS) };
    let closed = rng.chance(0.5);
    match rng.below(6) {
        0 => format!(
            "\nx = {}1{}\n",
            "[".repeat(depth),
            if closed { "]".repeat(depth) } else { String::new() }
        ),
        1 => format!(
            "\nx = {}1{}\n",
            "{a=".repeat(depth),
            if closed { "}".repeat(depth) } else { String::new() }
        ),
        2 => format!("\n{} = 1\n", vec!["a"; depth].join(".")),
        3 => format!("\n[{}]\n", vec!["a"; depth].join(".")),
        4 => format!("\n[[{}]]\n", vec!["a"; depth].join(".")),
        _ => format!("\nx = {}\n", "[{a=".repeat(depth)),
    }
}

/// NFF lines with too few or too many fields, huge counts, odd views.
fn nff_line(rng: &mut Rng) -> String {
    const LINES: &[&str] = &[
        "p 1000000000",
        "p 4294967296",
        "p 1048576",
        "p 1048577",
        "pp 1048576",
        "p 3",
        "p 3\n0 0 0\n1 0 0",
        "p 2\n0 0 0\n1 0 0",
        "p 3\n0 0 0\n0 0 0\n0 0 0",
        "p 4\n0 0 0\n1 0 0\n1 1 0\n0 1 1",
        "pp 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 0",
        "s 1 2",
        "s 1 2 3",
        "s 1 2 3 4 5",
        "s 0 0 0 0",
        "s 0 0 0 -1",
        "s 1e38 1e38 1e38 1e38",
        "c 0 0 0 1 0 0 1",
        "c 0 0 0 0 0 0 1 0",
        "c 0 0 0 1 0 0 0 1",
        "l",
        "l 1 2",
        "l 1 2 3 4",
        "l 1 2 3 -1 0 0",
        "b",
        "b 1 1",
        "b -1 0 0",
        "f 1 1 1",
        "f 1 1 1 0 0 0 1 0",
        "f 1 1 1 0.5 0.5 10 0.5 -1",
        "f 1 1 1 -0.5 0 0 0 1",
        "v",
        "v\nfrom 0 0 0\nat 0 0 0\nup 0 1 0",
        "from 0 0 1",
        "angle 0",
        "angle 180",
        "angle 360",
        "angle -45",
        "resolution 0 0",
        "resolution 65536 65536",
        "resolution 65537 1",
        "resolution 1",
        "hither",
        "up 0 0 0",
        "x",
        "#",
        "",
    ];
    rng.pick(LINES).to_string()
}

/// xyzr lines with too few or too many fields, or odd values.
fn xyzr_line(rng: &mut Rng) -> String {
    let n = *rng.pick(&[0usize, 1, 2, 3, 3, 4, 5, 5, 6, 40]);
    let mut line: Vec<String> = (0..n)
        .map(|_| if rng.chance(0.3) { odd_number(rng) } else { format!("{}", rng.0.unit() * 4.0 - 1.0) })
        .collect();
    if rng.chance(0.2) {
        line.insert(0, "#".into());
    }
    line.join(if rng.chance(0.5) { " " } else { "\t" })
}

/// One mutation of `s`.
fn mutate(reader: Reader, rng: &mut Rng, s: &mut Vec<u8>) {
    let len = s.len();
    match rng.below(14) {
        // Truncate anywhere, including inside a UTF-8 sequence.
        0 => s.truncate(rng.below(len + 1)),
        1 if len > 0 => {
            let i = rng.below(len);
            s[i] ^= 1 << rng.below(8);
        }
        2 if len > 0 => {
            let i = rng.below(len);
            s[i] = if rng.chance(0.5) { *rng.pick(reader.syntax()) } else { rng.below(256) as u8 };
        }
        3 => {
            let c = if rng.chance(0.7) { *rng.pick(reader.syntax()) } else { rng.below(256) as u8 };
            let n = if rng.chance(0.9) { 1 } else { 1 + rng.below(64) };
            let i = rng.below(len + 1);
            s.splice(i..i, std::iter::repeat_n(c, n));
        }
        4 if len > 0 => {
            let i = rng.below(len);
            let n = (1 + rng.below(16)).min(len - i);
            s.drain(i..i + n);
        }
        // Whole lines: duplicate, delete, swap.
        5..=7 => {
            let ls = lines(s);
            if ls.is_empty() {
                return;
            }
            let (a0, a1) = *rng.pick(&ls);
            match rng.below(3) {
                0 => {
                    let line = s[a0..a1].to_vec();
                    let times = if rng.chance(0.9) { 1 } else { 1 + rng.below(100) };
                    for _ in 0..times {
                        s.splice(a1..a1, line.iter().copied());
                    }
                }
                1 => {
                    s.drain(a0..a1);
                }
                _ => {
                    let (b0, b1) = *rng.pick(&ls);
                    swap_ranges(s, (a0, a1), (b0, b1));
                }
            }
        }
        8 => {
            let ts = tokens(s);
            if ts.len() >= 2 {
                let (a, b) = (*rng.pick(&ts), *rng.pick(&ts));
                swap_ranges(s, a, b);
            }
        }
        // A number (or any token) becomes an odd one.
        9..=11 => {
            let ts = tokens(s);
            let nums: Vec<_> = ts.iter().copied().filter(|&(a, b)| numberish(&s[a..b])).collect();
            let pool = if nums.is_empty() || rng.chance(0.1) { &ts } else { &nums };
            if pool.is_empty() {
                return;
            }
            let (a, b) = *rng.pick(pool);
            s.splice(a..b, odd_number(rng).into_bytes());
        }
        // Reader-specific constructs, at a line start (also what the byte edits of an empty input do).
        _ => {
            let text = match reader {
                Reader::Toml => {
                    if rng.chance(0.5) {
                        toml_nesting(rng)
                    } else {
                        format!("\n{}\n", rng.pick(TOML_LINES))
                    }
                }
                Reader::Nff => format!("\n{}\n", nff_line(rng)),
                Reader::Xyzr => format!("\n{}\n", xyzr_line(rng)),
            };
            let ls = lines(s);
            let at = if ls.is_empty() { 0 } else { rng.pick(&ls).0 };
            s.splice(at..at, text.into_bytes());
        }
    }
}

/// TOML lines: tables and keys the scene format knows, with odd or wrongly typed values.
const TOML_LINES: &[&str] = &[
    "[camera]",
    "[[camera]]",
    "[render]",
    "[[spheres]]",
    "[[planes]]",
    "[[cones]]",
    "[[ellipsoids]]",
    "[[lights]]",
    "[materials.x]",
    "[materials]",
    "[materials.default]",
    "[spheres]",
    "camera = 1",
    "eye = [0, 0]",
    "eye = [0, 0, 0, 0]",
    "eye = []",
    "eye = [1e400, 0, 0]",
    "look_at = [0, 0, 0]",
    "direction = [0, 0, 0]",
    "up = [0, 0, 0]",
    "hfov = 0",
    "hfov = 180",
    "hfov = nan",
    "pixel_size = 0",
    "width = 0",
    "width = 4294967296",
    "height = -1",
    "samples = 0",
    "samples = 4294967295",
    "samples = 10",
    "pattern = \"half-pixel\"",
    "max_depth = 4294967295",
    "center = [0, 0, 0]",
    "radius = 1e39",
    "radius = -0.0",
    "radius = inf",
    "radii = [1, 1]",
    "radii = [1, 0, 1]",
    "radii = [1e-300, 1, 1]",
    "radii = [nan, 1, 1]",
    "material = \"nope\"",
    "material = 1",
    "point = [0, 0, 0]",
    "normal = [0, 0, 0]",
    "normal = [nan, 0, 1]",
    "base = [0, 0, 0]",
    "apex = [0, 0, 0]",
    "base_radius = 0",
    "apex_radius = -1",
    "position = [0, 0, 0]",
    "intensity = -1",
    "color = [1, 1, -1]",
    "color = [nan, 0, 0]",
    "ior = 0",
    "transmit = inf",
    "transform = []",
    "transform = [{ scale = 0 }]",
    "transform = [{ scale = [1, 1] }]",
    "transform = [{ scale = 1e308 }]",
    "transform = [{ rotate = { axis = [0, 0, 0], degrees = 90 } }]",
    "transform = [{ rotate = { axis = [1e308, 1e308, 1e308], degrees = 1e308 } }]",
    "transform = [{ translate = [1e308, 0, 0] }, { scale = 1e308 }]",
    "transform = [{ bend = 1 }]",
    "transform = [{ translate = [0, 0, 0], scale = 2 }]",
    "x = \"\\u{110000}\"",
    "x = '''",
    "x = \"\"\"",
    "x = 1979-05-27T07:32:00Z",
    "a.b.c = 1",
    "\"\" = 1",
    "= 1",
    "[",
    "]",
    "[[",
    "]]",
    "x = [1, [2, {a = 3}]]",
];

fn swap_ranges(s: &mut Vec<u8>, a: (usize, usize), b: (usize, usize)) {
    let (x, y) = if a.0 <= b.0 { (a, b) } else { (b, a) };
    if x.1 > y.0 {
        return; // Overlapping ranges: leave the input as it is.
    }
    let mut out = Vec::with_capacity(s.len());
    out.extend_from_slice(&s[..x.0]);
    out.extend_from_slice(&s[y.0..y.1]);
    out.extend_from_slice(&s[x.1..y.0]);
    out.extend_from_slice(&s[x.0..x.1]);
    out.extend_from_slice(&s[y.1..]);
    *s = out;
}

/// Input `index` of `reader` for `seed`: a seed scene (or a window of a large one), mutated one to eight
/// times; bytes, then made valid UTF-8 (readers take text; invalid UTF-8 in a file is tested apart).
fn input(reader: Reader, seeds: &[Vec<u8>], seed: u64, index: u64) -> String {
    let salt = match reader {
        Reader::Toml => 1,
        Reader::Nff => 2,
        Reader::Xyzr => 3,
    };
    let mut rng = Rng(SplitMix64::new(seed ^ index.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (salt << 56)));
    let base = rng.pick(seeds);
    let mut s = if base.len() > WINDOW_BYTES { window(&mut rng, base) } else { base.clone() };
    for _ in 0..1 + rng.below(8) {
        mutate(reader, &mut rng, &mut s);
    }
    String::from_utf8_lossy(&s).into_owned()
}

/// The first lines of `base` (where a view or a camera is) and a random run of lines after them.
fn window(rng: &mut Rng, base: &[u8]) -> Vec<u8> {
    let ls = lines(base);
    let head = 12.min(ls.len());
    let start = head + rng.below(ls.len() - head + 1);
    let end = (start + 1 + rng.below(60)).min(ls.len());
    let mut s = base[..ls.get(head).map_or(base.len(), |l| l.0)].to_vec();
    if start < end {
        s.extend_from_slice(&base[ls[start].0..ls[end - 1].1]);
    }
    s
}

/// What is wrong with the error `e` for `source` named `name`, if anything.
fn check_error(reader: Reader, name: &str, source: &str, e: &SceneError) -> Option<String> {
    let text = e.to_string();
    let Some(rest) = text.strip_prefix(name).and_then(|r| r.strip_prefix(':')) else {
        return Some(format!("error does not start with `{name}:`: {text}"));
    };
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    if digits.is_empty() {
        let whole =
            rest.starts_with(' ') && reader.whole_file_errors().iter().any(|m| e.message.starts_with(m));
        return (!whole).then(|| format!("error names no line: {text}"));
    }
    let last = source.bytes().filter(|&b| b == b'\n').count() + 1;
    match digits.parse::<usize>() {
        Ok(n) if (1..=last).contains(&n) && n == e.line => None,
        _ => Some(format!("line {digits} is not within 1..={last} (or disagrees with {}): {text}", e.line)),
    }
}

#[derive(Default)]
struct Tally {
    parsed: u64,
    errors: u64,
    compiled: u64,
    failures: Vec<String>,
    slowest: (Duration, u64),
}

/// Runs `count` inputs of `reader` from `start`, and fails the test on any panic, hang or bad error.
fn fuzz(reader: Reader, default_count: u64) {
    let env =
        |key: &str| std::env::var(key).ok().map(|v| v.parse::<u64>().unwrap_or_else(|_| panic!("{key}")));
    let count = env("BARERAY_FUZZ_INPUTS").unwrap_or(default_count);
    let seed = env("BARERAY_FUZZ_SEED").unwrap_or(DEFAULT_SEED);
    let start = env("BARERAY_FUZZ_START").unwrap_or(0);
    let seeds = Arc::new(seeds(reader));
    let name = format!("fuzz-input.{}", reader.name());
    let path = PathBuf::from(&name);

    // The index being parsed, u64::MAX when done; the watchdog compares it over time.
    let current = Arc::new(AtomicU64::new(start));
    let watchdog = {
        let seeds = seeds.clone();
        watchdog::watch(current.clone(), HANG, move |now| {
            let file = save(reader.name(), seed, now, input(reader, &seeds, seed, now).as_bytes());
            eprintln!(
                "fuzz: {}: input {now} (seed {seed:#x}) has not finished in {HANG:?}: hang; input in {}",
                reader.name(),
                file.display()
            );
        })
    };

    let began = Instant::now();
    let mut t = Tally::default();
    for index in start..start + count {
        current.store(index, Ordering::Relaxed);
        let source = input(reader, &seeds, seed, index);
        let t0 = Instant::now();
        let outcome = catch_unwind(AssertUnwindSafe(|| {
            let result = reader.parse(&path, &source);
            // Compiling a parsed scene must not panic either (a camera error is an Err, fine); every 16th
            // keeps the run short, as the BVH build dominates otherwise.
            let compiled = matches!(&result, Ok(desc) if index % 16 == 0 && Scene::compile(desc).is_ok());
            (result, compiled)
        }));
        let took = t0.elapsed();
        if took > t.slowest.0 {
            t.slowest = (took, index);
        }
        let failure = match outcome {
            Err(panic) => {
                let what = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                Some(format!("panic: {what}"))
            }
            Ok((Ok(_), compiled)) => {
                t.parsed += 1;
                t.compiled += u64::from(compiled);
                None
            }
            Ok((Err(e), _)) => {
                t.errors += 1;
                check_error(reader, &name, &source, &e)
            }
        };
        if let Some(why) = failure {
            let file = save(reader.name(), seed, index, source.as_bytes());
            let report = format!("input {index} (seed {seed:#x}, saved as {}): {why}", file.display());
            eprintln!("fuzz: {}: {report}", reader.name());
            t.failures.push(report);
        }
        let done = index - start + 1;
        if done % PROGRESS == 0 && done < count {
            println!(
                "fuzz: {}: {done} of {count} inputs, {} panics or bad errors, {:.1} s",
                reader.name(),
                t.failures.len(),
                began.elapsed().as_secs_f64()
            );
        }
    }
    current.store(watchdog::DONE, Ordering::Relaxed);
    watchdog.join().expect("watchdog");
    t.finish(reader.name(), count, began, seed, start);
}

impl Tally {
    /// Prints the run's counts and fails the test on any failure.
    fn finish(&self, name: &str, count: u64, began: Instant, seed: u64, start: u64) {
        println!(
            "fuzz: {name}: {count} inputs, {} parsed, {} errors, {} panics or bad errors ({} compiled; {:.1} s; \
             slowest input {} took {:.1} ms; seed {seed:#x}, from index {start})",
            self.parsed,
            self.errors,
            self.failures.len(),
            self.compiled,
            began.elapsed().as_secs_f64(),
            self.slowest.1,
            self.slowest.0.as_secs_f64() * 1e3,
        );
        assert!(self.failures.is_empty(), "{} failures:\n{}", self.failures.len(), self.failures.join("\n"));
    }
}

/// Writes a failing input where it can be read back for reproduction (`extension` names its format).
fn save(extension: &str, seed: u64, index: u64, input: &[u8]) -> PathBuf {
    let file = std::env::temp_dir().join(format!("bareray-fuzz-{seed:x}-{index}.{extension}"));
    std::fs::write(&file, input).expect("temporary directory is writable");
    file
}

#[test]
fn toml_reader_survives_generated_inputs() {
    fuzz(Reader::Toml, CI_RUN);
}

#[test]
fn nff_reader_survives_generated_inputs() {
    fuzz(Reader::Nff, CI_RUN);
}

#[test]
fn xyzr_reader_survives_generated_inputs() {
    fuzz(Reader::Xyzr, CI_RUN);
}

#[test]
#[ignore = "the full run: 1e6 inputs per reader, minutes in release mode"]
fn toml_reader_survives_a_million_inputs() {
    fuzz(Reader::Toml, FULL_RUN);
}

#[test]
#[ignore = "the full run: 1e6 inputs per reader, minutes in release mode"]
fn nff_reader_survives_a_million_inputs() {
    fuzz(Reader::Nff, FULL_RUN);
}

#[test]
#[ignore = "the full run: 1e6 inputs per reader, minutes in release mode"]
fn xyzr_reader_survives_a_million_inputs() {
    fuzz(Reader::Xyzr, FULL_RUN);
}

/// Nesting far past the toml crate's limit is an error naming the line, not a stack overflow: the crate
/// stops at its recursion limit, for every construct that nests.
#[test]
fn deep_toml_nesting_is_a_located_error() {
    for depth in [1_000, 100_000, 1_000_000] {
        for nest in [
            format!("x = {}", "[".repeat(depth)),
            format!("x = {}1{}", "[".repeat(depth), "]".repeat(depth)),
            format!("x = {}", "{a=".repeat(depth)),
            format!("x = {}", "[{a=".repeat(depth)),
            format!("{} = 1", vec!["a"; depth].join(".")),
            format!("[{}]", vec!["a"; depth].join(".")),
        ] {
            let source = format!("[camera]\nwidth = 64\n{nest}\n");
            let e = toml::parse(Path::new("deep.toml"), &source).expect_err("nesting is rejected");
            assert!(e.to_string().starts_with("deep.toml:3:"), "depth {depth}: {e}");
        }
    }
}

/// Invalid UTF-8 in a scene file (what the text inputs above cannot hold) is an error naming the file and
/// the line and column of the bad bytes, from each reader's file path.
#[test]
fn invalid_utf8_files_are_errors_naming_file_and_line() {
    let dir = tempfile::tempdir().expect("temporary directory");
    for (ext, text) in [("toml", "[camera]\n"), ("nff", "v\n"), ("xyzr", "0 0 0 1\n")] {
        let path = dir.path().join(format!("bad.{ext}"));
        let mut bytes = text.as_bytes().to_vec();
        bytes.extend_from_slice(b"# \xE2\x82\n");
        std::fs::write(&path, &bytes).expect("write");
        let e = bareray::io::load(&path).expect_err("invalid UTF-8 is rejected");
        assert!(e.to_string().starts_with(&format!("{}:2:3: ", path.display())), "{e}");
    }
}

// ---------------------------------------------------------------------------------------------------- f32r

/// The `.f32r` reader takes bytes, not text, so it has inputs of its own: generated fields of 1 to 300
/// spheres, mutated one to eight times by byte edits (as above) and by edits of the format's parts (header
/// words, whole records, single values). An independent decoding of the format says what every input must
/// give: the exact values, or an error naming the file and (for a record) the first bad record and its byte.
mod f32r_inputs {
    use super::*;
    use bareray::io::f32r;
    use bareray::io::generate::FieldParams;

    /// Floats a record may hold that the reader must reject or pass through exactly.
    const ODD: &[f32] = &[
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        0.0,
        -0.0,
        -1.0,
        1e-45,
        -1e-45,
        f32::MIN_POSITIVE,
        f32::MAX,
        f32::MIN,
        1e30,
        -1e30,
    ];

    fn seeds() -> Vec<Vec<u8>> {
        [(1, 1), (3, 2), (50, 3), (300, 4)]
            .iter()
            .map(|&(count, seed)| {
                let mut out = Vec::new();
                FieldParams { count, seed, ..Default::default() }.write_f32r(&mut out).expect("field");
                out
            })
            .collect()
    }

    /// One edit of `s`.
    fn mutate(rng: &mut Rng, s: &mut Vec<u8>) {
        let len = s.len();
        let records = len.saturating_sub(16) / 16;
        match rng.below(10) {
            0 => s.truncate(rng.below(len + 1)),
            1 if len > 0 => {
                let i = rng.below(len);
                s[i] ^= 1 << rng.below(8);
            }
            2 if len > 0 => {
                let i = rng.below(len);
                s[i] = rng.below(256) as u8;
            }
            3 => {
                let i = rng.below(len + 1);
                let most = if rng.chance(0.5) { 4 } else { 40 };
                let n = 1 + rng.below(most);
                let bytes: Vec<u8> = (0..n).map(|_| rng.below(256) as u8).collect();
                s.splice(i..i, bytes);
            }
            4 if len > 0 => {
                let i = rng.below(len);
                let n = (1 + rng.below(20)).min(len - i);
                s.drain(i..i + n);
            }
            // The version or the count: off by a little, zero, huge.
            5 if len >= 16 => {
                let at = *rng.pick(&[8usize, 12, 12, 12]);
                let old = u32::from_le_bytes(s[at..at + 4].try_into().expect("4 bytes"));
                let new = *rng.pick(&[
                    0,
                    1,
                    2,
                    old.wrapping_add(1),
                    old.wrapping_sub(1),
                    old.wrapping_mul(2),
                    u32::MAX,
                ]);
                s[at..at + 4].copy_from_slice(&new.to_le_bytes());
            }
            // Whole records: duplicate, delete, swap.
            6 | 7 if records > 0 => {
                let a = 16 + 16 * rng.below(records);
                let b = 16 + 16 * rng.below(records);
                match rng.below(3) {
                    0 => {
                        let r = s[a..a + 16].to_vec();
                        s.splice(a..a, r);
                    }
                    1 => {
                        s.drain(a..a + 16);
                    }
                    _ => swap_ranges(s, (a, a + 16), (b, b + 16)),
                }
            }
            // One value becomes an odd float.
            _ if records > 0 => {
                let at = 16 + 16 * rng.below(records) + 4 * rng.below(4);
                s[at..at + 4].copy_from_slice(&rng.pick(ODD).to_le_bytes());
            }
            _ => {}
        }
    }

    /// Input `index` for `seed`.
    fn input(seeds: &[Vec<u8>], seed: u64, index: u64) -> Vec<u8> {
        let mut rng = Rng(SplitMix64::new(seed ^ index.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (4 << 56)));
        let mut s = rng.pick(seeds).clone();
        for _ in 0..1 + rng.below(8) {
            mutate(&mut rng, &mut s);
        }
        s
    }

    /// What the format says `bytes` hold: the records, or what the error must contain.
    fn expected(bytes: &[u8]) -> Result<Vec<[f32; 4]>, String> {
        if bytes.len() < 16 || bytes[..8] != f32r::MAGIC {
            let magic_ok = bytes.iter().zip(f32r::MAGIC).all(|(a, b)| *a == b);
            return Err(if magic_ok {
                "ends inside the 16-byte header".into()
            } else {
                "not an .f32r".into()
            });
        }
        let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
        if word(8) != 1 {
            return Err(format!("version {} is not", word(8)));
        }
        let count = word(12) as usize;
        if count == 0 {
            return Err("no spheres".into());
        }
        let body = bytes.len() - 16;
        if body < 16 * count {
            return Err(format!("ends inside record {} (byte {})", body / 16, 16 + body / 16 * 16));
        }
        if body > 16 * count {
            return Err(format!("{} bytes follow", body - 16 * count));
        }
        let mut out = Vec::with_capacity(count);
        for (i, r) in bytes[16..].chunks_exact(16).enumerate() {
            let v: [f32; 4] =
                std::array::from_fn(|k| f32::from_le_bytes(r[4 * k..4 * k + 4].try_into().unwrap()));
            if v.iter().any(|x| !x.is_finite()) || v[3] <= 0.0 {
                return Err(format!("record {i} (byte {}): ", 16 + 16 * i));
            }
            out.push(v);
        }
        Ok(out)
    }

    /// What is wrong with the reader's answer for `bytes`, if anything.
    fn check(name: &str, bytes: &[u8], got: &Result<SceneDesc, SceneError>) -> Option<String> {
        match (expected(bytes), got) {
            (Ok(want), Ok(desc)) => {
                let values: Vec<[u32; 4]> = desc
                    .spheres
                    .iter()
                    .map(|s| [s.center.x, s.center.y, s.center.z, s.radius].map(|v| (v as f32).to_bits()))
                    .collect();
                let want: Vec<[u32; 4]> = want.iter().map(|v| v.map(f32::to_bits)).collect();
                (values != want).then(|| "accepted with other values than the file's".to_owned())
            }
            (Ok(_), Err(e)) => Some(format!("a valid file was rejected: {e}")),
            (Err(why), Ok(_)) => Some(format!("accepted, but the file is wrong: {why}")),
            (Err(why), Err(e)) => {
                let text = e.to_string();
                let ok = text.starts_with(&format!("{name}: ")) && e.line == 0 && text.contains(&why);
                (!ok).then(|| format!("error `{text}` should name the file and say `{why}`"))
            }
        }
    }

    /// Runs `default_count` inputs (or as the environment says, as for the text readers).
    pub fn fuzz(default_count: u64) {
        let env =
            |key: &str| std::env::var(key).ok().map(|v| v.parse::<u64>().unwrap_or_else(|_| panic!("{key}")));
        let count = env("BARERAY_FUZZ_INPUTS").unwrap_or(default_count);
        let seed = env("BARERAY_FUZZ_SEED").unwrap_or(DEFAULT_SEED);
        let start = env("BARERAY_FUZZ_START").unwrap_or(0);
        let seeds = seeds();
        let name = "fuzz-input.f32r";
        let began = Instant::now();
        let mut t = Tally::default();
        for index in start..start + count {
            let bytes = input(&seeds, seed, index);
            let t0 = Instant::now();
            let outcome = catch_unwind(AssertUnwindSafe(|| {
                let result = f32r::parse(Path::new(name), &bytes);
                let compiled = matches!(&result, Ok(desc) if index % 16 == 0 && Scene::compile(desc).is_ok());
                (result, compiled)
            }));
            let took = t0.elapsed();
            if took > t.slowest.0 {
                t.slowest = (took, index);
            }
            let failure = match &outcome {
                Err(_) => Some("panic".to_owned()),
                Ok((result, compiled)) => {
                    t.parsed += u64::from(result.is_ok());
                    t.errors += u64::from(result.is_err());
                    t.compiled += u64::from(*compiled);
                    check(name, &bytes, result)
                }
            };
            if let Some(why) = failure {
                let file = super::save("f32r", seed, index, &bytes);
                let report = format!("input {index} (seed {seed:#x}, saved as {}): {why}", file.display());
                eprintln!("fuzz: f32r: {report}");
                t.failures.push(report);
            }
        }
        t.finish("f32r", count, began, seed, start);
        assert!(count < 1000 || (t.parsed > count / 100 && t.errors > count / 100), "inputs too uniform");
    }
}

#[test]
fn f32r_reader_survives_generated_inputs() {
    f32r_inputs::fuzz(CI_RUN);
}

#[test]
#[ignore = "the full run: 1e6 inputs, minutes in release mode"]
fn f32r_reader_survives_a_million_inputs() {
    f32r_inputs::fuzz(FULL_RUN);
}
