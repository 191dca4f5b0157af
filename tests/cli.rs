//! The `bareray` binary end to end: every scene in scenes/ renders to every format; bad input gives a clear
//! error, no panic, and never touches an existing output file; argument errors exit with 2, scene, render
//! and file errors with 1.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{bareray, scene_files, stderr};

fn scenes() -> Vec<PathBuf> {
    scene_files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes"))
}

#[test]
fn every_scene_renders_to_png_exr_and_ppm() {
    let dir = tempfile::tempdir().unwrap();
    let scenes = scenes();
    assert!(scenes.len() >= 4, "scenes/ holds the demo scenes: {scenes:?}");
    for scene in &scenes {
        for ext in ["png", "exr", "ppm"] {
            let out = dir.path().join(format!("{}.{ext}", scene.file_stem().unwrap().to_string_lossy()));
            let run =
                bareray(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--width", "40"]);
            assert!(run.status.success(), "{scene:?} -> {ext}: {}", stderr(&run));
            let img = image::open(&out).unwrap_or_else(|e| panic!("{out:?} does not decode: {e}"));
            assert_eq!(img.width(), 40);
            assert!(img.height() >= 20);
        }
    }
    // Nothing but the outputs is left behind (no temporary files).
    let files = std::fs::read_dir(dir.path()).unwrap().count();
    assert_eq!(files, scenes.len() * 3);
}

#[test]
fn exr_holds_linear_values_and_png_their_srgb_encoding() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("a.exr");
    let png = dir.path().join("a.png");
    for out in [&exr, &png] {
        let run = bareray(&["render", "-o", out.to_str().unwrap(), "--width", "32", "--spp", "1", "-q"]);
        assert!(run.status.success(), "{}", stderr(&run));
        assert!(run.stdout.is_empty(), "--quiet prints nothing");
    }
    let lin = image::open(&exr).unwrap().into_rgb32f();
    let srgb = image::open(&png).unwrap().into_rgb8();
    let mut compared = 0;
    for (l, s) in lin.pixels().zip(srgb.pixels()) {
        for c in 0..3 {
            if l[c] <= 1.0 {
                assert_eq!(bareray::output::srgb8(l[c]), s[c]);
                compared += 1;
            }
        }
    }
    assert!(compared > 1000);
}

/// The PNG's `Transfer` text chunk.
fn png_transfer(path: &Path) -> String {
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let reader = png::Decoder::new(file).read_info().unwrap();
    let text = &reader.info().uncompressed_latin1_text;
    let chunk = text.iter().find(|t| t.keyword == "Transfer").expect("a Transfer tEXt chunk");
    chunk.text.clone()
}

/// NFF and xyzr scenes write their values as they are (classic tracers' way with NFF colours), TOML scenes
/// encode them with the sRGB curve; `[render] transfer` and `--transfer` choose; PNG records the choice.
#[test]
fn nff_and_xyzr_write_values_as_they_are_toml_encodes_srgb_and_transfer_overrides() {
    use bareray::output::{linear8, srgb8};
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    // A flat background colour, and a lit sphere that leaves the corners to it.
    let (r, g, b) = (0.2f32, 0.4f32, 0.6f32);
    let nff = "b 0.2 0.4 0.6\nv\nfrom 0 -5 0\nat 0 0 0\nup 0 0 1\nangle 30\nhither 0.01\nresolution 24 24\n\
               l 2 -4 3\nf 0.9 0.5 0.3 0.8 0 1 0 1\ns 0 0 0 0.5\n";
    std::fs::write(p("s.nff"), nff).unwrap();
    std::fs::write(p("lin.toml"), "[render]\nbackground = [0.2, 0.4, 0.6]\ntransfer = \"linear\"\n").unwrap();
    std::fs::write(p("s.toml"), "[render]\nbackground = [0.2, 0.4, 0.6]\n").unwrap();
    std::fs::write(p("s.xyzr"), "0 0 0 1\n2 0 0 0.5\n").unwrap();
    let linear = [linear8(r), linear8(g), linear8(b)];
    let srgb = [srgb8(r), srgb8(g), srgb8(b)];
    assert_eq!(linear, [51, 102, 153], "round(255·c)");
    assert_ne!(linear, srgb);
    let cases: [(&str, &[&str], &str, [u8; 3]); 7] = [
        ("s.nff", &[], "linear", linear),
        ("s.nff", &["--transfer", "srgb"], "srgb", srgb),
        ("s.nff", &["--transfer", "linear"], "linear", linear),
        ("s.toml", &[], "srgb", srgb),
        ("s.toml", &["--transfer", "linear"], "linear", linear),
        ("lin.toml", &[], "linear", linear),
        ("lin.toml", &["--transfer", "srgb"], "srgb", srgb),
    ];
    for (scene, extra, name, corner) in cases {
        for ext in ["png", "ppm"] {
            let out = p(&format!("out.{ext}"));
            let mut args = vec!["render", scene, "-o", &out, "--width", "24", "-q"];
            args.extend_from_slice(extra);
            let run = Command::new(env!("CARGO_BIN_EXE_bareray"))
                .args(&args)
                .current_dir(dir.path())
                .output()
                .unwrap();
            assert!(run.status.success(), "{args:?}: {}", stderr(&run));
            let img = image::open(&out).unwrap().into_rgb8();
            assert_eq!(img.get_pixel(0, 0).0, corner, "{args:?}");
            if ext == "png" {
                assert_eq!(png_transfer(Path::new(&out)), name, "{args:?}");
            }
        }
    }
    // Every pixel, shaded ones included, is the linear encoding of the EXR's value, on NFF and xyzr.
    for scene in ["s.nff", "s.xyzr"] {
        for out in [p("v.exr"), p("v.png")] {
            let run = bareray(&["render", &p(scene), "-o", &out, "--width", "24", "-q"]);
            assert!(run.status.success(), "{scene}: {}", stderr(&run));
        }
        assert_eq!(png_transfer(Path::new(&p("v.png"))), "linear", "{scene}");
        let lin = image::open(p("v.exr")).unwrap().into_rgb32f();
        let png = image::open(p("v.png")).unwrap().into_rgb8();
        let expected: Vec<u8> = lin.as_raw().iter().map(|&v| linear8(v)).collect();
        assert_eq!(png.as_raw(), &expected, "{scene}");
        assert!(png.as_raw().iter().collect::<std::collections::BTreeSet<_>>().len() > 8, "{scene}: shaded");
    }
}

#[test]
fn demo_scene_renders_without_arguments() {
    let dir = tempfile::tempdir().unwrap();
    let run = Command::new(env!("CARGO_BIN_EXE_bareray"))
        .args(["render", "--width", "64"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", stderr(&run));
    let summary = String::from_utf8_lossy(&run.stdout);
    assert!(summary.contains("demo.png: 64x48") && summary.contains("Mrays/s"), "{summary}");
    assert_eq!(image::open(dir.path().join("demo.png")).unwrap().height(), 48);
}

#[test]
fn bad_scene_fails_cleanly_and_keeps_the_old_output() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("bad.toml");
    std::fs::write(&scene, "[camera]\nwidth = 64\n\n[[spheres]]\ncentre = [0, 0, 0]\nradius = 1\n").unwrap();
    let out = dir.path().join("keep.png");
    std::fs::write(&out, b"precious").unwrap();
    let run = bareray(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(run.status.code(), Some(1));
    let err = stderr(&run);
    assert!(err.contains("bad.toml:5:1: unknown field `centre`"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(std::fs::read(&out).unwrap(), b"precious");
}

#[test]
fn bad_arguments_fail_before_rendering() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("out.png")).unwrap();
    std::fs::create_dir(dir.path().join("sub.toml")).unwrap();
    let whitted = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/whitted.toml");
    let whitted = whitted.to_str().unwrap();
    // (arguments, exit code, the message)
    let cases: [(&[&str], i32, &str); 16] = [
        (&["render", "nope.toml"], 1, "nope.toml: cannot read scene"),
        (&["render", "scene.obj"], 1, "unknown scene format"),
        (&["render", "sub.toml"], 1, "sub.toml: is a directory"),
        (&["render", "."], 1, ".: is a directory"),
        (&["render", "-o", "no/such/dir/out.png"], 1, "directory no/such/dir does not exist"),
        (&["render", "-o", "out.png"], 1, "out.png: is a directory"),
        (&["render", "-o", "out.gif"], 2, "unknown image format"),
        (&["render", "--spp", "5"], 2, "square number"),
        (&["render", "--hfov", "180"], 2, "(0, 180)"),
        (&["render", "--threads", "0"], 2, "--threads"),
        (&["bench", whitted, "--threads", "0"], 2, "--threads"),
        (&["bench", whitted, "--threads", "1,2000"], 2, "--threads"),
        (&["accuracy", whitted, "--threads", "0"], 2, "--threads"),
        (&["gen", "field", "--count", "10", "-o", "f.nff"], 2, "f.nff: this command writes .xyzr"),
        (&["gen", "flake", "--level", "2", "-o", "f.toml"], 2, "f.toml: this command writes .nff"),
        (&["gen", "field", "--count", "0", "-o", "f.xyzr"], 2, "--count"),
    ];
    for (args, code, needle) in cases {
        let run =
            Command::new(env!("CARGO_BIN_EXE_bareray")).args(args).current_dir(dir.path()).output().unwrap();
        let err = stderr(&run);
        assert_eq!(run.status.code(), Some(code), "{args:?}: {err}");
        assert!(err.contains(needle) && !err.contains("panicked"), "{args:?}: {err}");
        // One message, said once: no error chain repeating the OS's words.
        assert_eq!(err.matches("error:").count(), 1, "{args:?}: {err}");
        assert!(err.matches("os error").count() <= 1, "{args:?}: {err}");
        assert!(run.stdout.is_empty(), "nothing rendered or measured: {args:?}");
    }
    let mut left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    left.sort();
    assert_eq!(left, ["out.png", "sub.toml"], "no output written, no temporary file left");
}

/// `.ppm` (and `.pnm`) is binary 8-bit PPM: `P6`, width and height, 255, then 3 bytes per pixel.
#[test]
fn ppm_is_binary_p6() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["a.ppm", "a.pnm"] {
        let out = dir.path().join(name);
        let run = bareray(&["render", "-o", out.to_str().unwrap(), "--width", "20", "--height", "15", "-q"]);
        assert!(run.status.success(), "{}", stderr(&run));
        let bytes = std::fs::read(&out).unwrap();
        let header = b"P6\n20 15\n255\n";
        assert_eq!(&bytes[..header.len()], header, "{name}");
        assert_eq!(bytes.len(), header.len() + 3 * 20 * 15, "{name}");
    }
}

/// A scene with no objects, or without lights for materials that need them, renders but says so.
#[test]
fn empty_and_unlit_scenes_warn() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("empty.toml", "[camera]\nwidth = 16\nheight = 12\n", &["no objects", "no lights"][..]),
        (
            "dark.toml",
            "[camera]\nwidth = 16\nheight = 12\n[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\n",
            &["no lights"],
        ),
        (
            "glow.toml",
            "[camera]\nwidth = 16\nheight = 12\n[materials.default]\ndiffuse = 0\nambient = 1\n\
             [[spheres]]\ncenter = [0, 0, 0]\nradius = 1\n",
            &[],
        ),
    ];
    for (name, text, warnings) in cases {
        let scene = dir.path().join(name);
        std::fs::write(&scene, text).unwrap();
        let out = dir.path().join("out.png");
        let run = bareray(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"]);
        assert_eq!(run.status.code(), Some(0), "{name}: {}", stderr(&run));
        let err = stderr(&run);
        for w in warnings {
            assert!(err.contains(&format!("warning: {}: {w}", scene.display())), "{name}: {err}");
        }
        assert_eq!(err.lines().count(), warnings.len(), "{name}: {err}");
        assert!(out.exists());
    }
    // The demo scene has both.
    let run = bareray(&["render", "-o", dir.path().join("d.png").to_str().unwrap(), "--width", "16", "-q"]);
    assert!(run.status.success() && run.stderr.is_empty(), "{}", stderr(&run));
}

#[test]
fn help_explains_the_commands() {
    let run = bareray(&["--help"]);
    assert!(run.status.success());
    let text = String::from_utf8_lossy(&run.stdout);
    for needle in ["render", ".toml", ".nff", ".xyzr", "Exit codes", "2 argument", "1 errors"] {
        assert!(text.contains(needle), "--help lacks {needle:?}: {text}");
    }
    let run = bareray(&["render", "--help"]);
    let text = String::from_utf8_lossy(&run.stdout);
    for needle in [
        "--output",
        "--width",
        "--height",
        "--spp",
        "--threads",
        ".exr",
        ".ppm",
        ".toml",
        ".nff",
        ".xyzr",
        "pixel_size",
        "Exit codes",
    ] {
        assert!(text.contains(needle), "render --help lacks {needle}");
    }
    // Every scene the examples name exists.
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let named: Vec<&str> = text
        .split_whitespace()
        .filter(|w| w.starts_with("scenes/") && [".toml", ".nff", ".xyzr"].iter().any(|e| w.ends_with(e)))
        .collect();
    assert!(named.len() >= 3, "{named:?}");
    for scene in named {
        assert!(root.join(scene).is_file(), "render --help names {scene}, which does not exist");
    }
}

/// `--aov` writes float EXR channels Z, N.X, N.Y, N.Z and id; camera flags override the scene's camera.
#[test]
fn aov_channels_hold_depth_normal_and_id() {
    use exr::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("one.toml");
    // The camera in the file looks away; the flags turn it toward the sphere.
    std::fs::write(
        &scene,
        "[camera]\neye = [9, 9, 9]\nlook_at = [20, 9, 9]\n[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\n",
    )
    .unwrap();
    let out = dir.path().join("one.png");
    let args = ["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--aov", "depth,normal,id"];
    let flags = [
        "--eye", "0,0,-4", "--look", "0,0,0", "--up", "0,1,0", "--hfov", "45", "--width", "31", "--height",
        "21",
    ];
    let run = bareray(&[&args[..], &flags[..]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let img = read_all_flat_layers_from_file(dir.path().join("one.aov.exr")).unwrap();
    let layer = &img.layer_data[0];
    assert_eq!(layer.size, Vec2(31, 21));
    let channel = |name: &str| -> Vec<f32> {
        let c = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == name)
            .unwrap_or_else(|| panic!("{name}"));
        c.sample_data.values_as_f32().collect()
    };
    let (z, id, nz) = (channel("Z"), channel("id"), channel("N.Z"));
    channel("N.X");
    channel("N.Y");
    let centre = 10 * 31 + 15;
    // The centre ray runs straight down +z from z = −4 and meets the unit sphere at z = −1.
    assert_eq!(z[centre], 3.0);
    assert_eq!(id[centre], 0.0);
    assert_eq!(nz[centre], -1.0);
    assert_eq!(z[0], f32::INFINITY);
    assert_eq!(id[0], -1.0);
}

#[test]
fn stats_report_scene_rays_and_times() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.png");
    let run = bareray(&["render", "-o", out.to_str().unwrap(), "--width", "40", "--stats", "--spp", "1"]);
    assert!(run.status.success(), "{}", stderr(&run));
    let text = String::from_utf8_lossy(&run.stdout);
    // Human names and counts: no Debug names, singular for one.
    assert!(!text.contains("Grid(") && !text.contains("1 planes"), "{text}");
    // One build time.
    assert_eq!(text.matches("build").count(), 1, "{text}");
    for needle in [
        "3 primitives (2 spheres, 1 plane), 2 lights",
        "1 sample per pixel (1×1 grid), whitted shading, srgb transfer",
        "skips: bvh, polygons, ellipsoids, cones, tori",
        "brute force",
        "primary",
        "shadow",
        "parse",
        "build",
        "Mrays/s",
    ] {
        assert!(text.contains(needle), "--stats lacks {needle:?}: {text}");
    }
}

/// An output in a directory that cannot be written to is refused before rendering (skipped where the test
/// can write there anyway, as root can).
#[cfg(unix)]
#[test]
fn unwritable_output_directory_is_refused_before_rendering() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let locked = dir.path().join("locked");
    std::fs::create_dir(&locked).unwrap();
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
    if std::fs::write(locked.join("probe"), b"").is_ok() {
        eprintln!("skipped: this user can write into a read-only directory");
        return;
    }
    let out = locked.join("out.png");
    let run = bareray(&["render", "-o", out.to_str().unwrap(), "--width", "16"]);
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(err.contains("cannot write in") && err.matches("error:").count() == 1, "{err}");
    assert!(run.stdout.is_empty(), "refused before rendering");
    assert_eq!(std::fs::read_dir(&locked).unwrap().count(), 0);
}

/// Runs `bareray bench ... --json` and parses every stdout line as JSON.
fn bench_json(args: &[&str]) -> Vec<serde_json::Value> {
    let run = bareray(&[&["bench"], args, &["--json"]].concat());
    assert!(run.status.success(), "{args:?}: {}", stderr(&run));
    String::from_utf8(run.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("not JSON ({e}): {l}")))
        .collect()
}

/// `bench --json`: one valid JSON object per line even when the scene's name holds a quote and a backslash;
/// min ≤ median ≤ max seconds; the host fields; `--spp` and `--depth` reach the scene; `--compare` matches
/// rows by (lanes, threads) and marks the rest.
#[test]
fn bench_json_is_valid_and_compare_matches_rows() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("wh\"it\\ed.toml");
    std::fs::copy(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/whitted.toml"), &scene).unwrap();
    let name = scene.to_str().unwrap();
    let small = ["--width", "16", "--height", "12", "--reps", "3", "--threads", "1"];
    let rows = bench_json(&[&[name, "--lanes", "1,16", "--spp", "4", "--depth", "1"], &small[..]].concat());
    assert_eq!(rows.len(), 2);
    for (row, lanes) in rows.iter().zip([1, 16]) {
        assert_eq!(row["scene"], name);
        assert_eq!((row["lanes"].as_u64(), row["threads"].as_u64()), (Some(lanes), Some(1)));
        let (min, med, max) = (
            row["min_s"].as_f64().unwrap(),
            row["seconds"].as_f64().unwrap(),
            row["max_s"].as_f64().unwrap(),
        );
        assert!(0.0 < min && min <= med && med <= max, "{row}");
        assert!(row["mrays_per_s"].as_f64().unwrap() > 0.0);
        assert_eq!(row["checksum"].as_str().unwrap().len(), 16);
        assert_eq!((row["spp"].as_u64(), row["max_depth"].as_u64()), (Some(4), Some(1)));
        assert!(!row["cpu"].as_str().unwrap().is_empty() && !row["isa"].as_str().unwrap().is_empty());
        assert!(row["lanes16"].as_str().unwrap().contains("register") || row["isa"] == "none");
        assert!(row["cores"].as_u64().unwrap() >= 1);
        assert!(["release", "debug"].contains(&row["profile"].as_str().unwrap()));
        assert_eq!(row["version"], env!("CARGO_PKG_VERSION"));
    }
    // Fewer bounces, fewer rays; the same image size and samples.
    let deeper = bench_json(&[&[name, "--lanes", "1", "--spp", "4", "--depth", "5"], &small[..]].concat());
    assert!(deeper[0]["rays"].as_u64() > rows[0]["rays"].as_u64(), "{} {}", deeper[0], rows[0]);

    let old = dir.path().join("old.json");
    let text: String = rows.iter().map(|r| format!("{r}\n")).collect();
    std::fs::write(&old, text).unwrap();
    let args = [&[name, "--lanes", "1,4", "--spp", "4", "--depth", "1"], &small[..]].concat();
    let run = bareray(&[&["bench"], &args[..], &["--compare", old.to_str().unwrap()]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let table = String::from_utf8_lossy(&run.stdout);
    let line = |lanes: &str| {
        table
            .lines()
            .skip_while(|l| !l.starts_with("compared with"))
            .find(|l| l.trim_start().starts_with(lanes))
    };
    assert!(line("1 ").unwrap().ends_with('x'), "{table}");
    assert!(line("4 ").unwrap().ends_with("no old row"), "{table}");
    assert!(table.contains("old rows not measured now: lanes 16 threads 1"), "{table}");
    let compared = bench_json(&[&args[..], &["--compare", old.to_str().unwrap()]].concat());
    assert!(compared[0]["compare"]["ratio"].as_f64().unwrap() > 0.0);
    assert!(compared[1]["compare"]["old_mrays_per_s"].is_null());
}

/// `bench --lanes scalar,...`: the scalar row (binary BVHs, one box and one primitive at a time) has the
/// checksum of every packet width, for primary hits and for a shaded render (shadow rays, reflections);
/// JSON writes its lanes as `"scalar"`, `--compare` matches it, and the table compares every row with it.
#[test]
fn bench_scalar_row_has_the_same_checksum() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/balls3.nff");
    let scene = scene.to_str().unwrap();
    let small = ["--width", "32", "--height", "24", "--reps", "1", "--threads", "1"];
    for mode in [&["--primary-only"][..], &["--depth", "2"][..]] {
        let rows = bench_json(&[&[scene, "--lanes", "scalar,1,4,16"], mode, &small[..]].concat());
        let lanes: Vec<_> = rows.iter().map(|r| r["lanes"].clone()).collect();
        assert_eq!(lanes, [serde_json::json!("scalar"), 1.into(), 4.into(), 16.into()], "{mode:?}");
        for row in &rows {
            assert_eq!(row["checksum"], rows[0]["checksum"], "{mode:?}: {row}");
            assert_eq!(row["rays"], rows[0]["rays"], "{mode:?}: {row}");
        }
    }
    let old = dir.path().join("old.json");
    let args = [&[scene, "--lanes", "scalar,4", "--primary-only"], &small[..]].concat();
    let text: String = bench_json(&args).iter().map(|r| format!("{r}\n")).collect();
    std::fs::write(&old, text).unwrap();
    let args = [&[scene, "--lanes", "scalar,8", "--primary-only"], &small[..]].concat();
    let compared = bench_json(&[&args[..], &["--compare", old.to_str().unwrap()]].concat());
    assert!(compared[0]["compare"]["ratio"].as_f64().unwrap() > 0.0, "{}", compared[0]);
    assert!(compared[1]["compare"]["old_mrays_per_s"].is_null(), "{}", compared[1]);
    let run = bareray(&[&["bench"], &args[..], &["--compare", old.to_str().unwrap()]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let table = String::from_utf8_lossy(&run.stdout);
    assert!(table.contains("vs scalar"), "{table}");
    let row = table.lines().find(|l| l.trim_start().starts_with("scalar ")).unwrap();
    assert!(row.contains(" 1.00x "), "{table}");
    assert!(table.contains("old rows not measured now: lanes 4 threads 1"), "{table}");
}

#[test]
fn bench_compare_errors_name_the_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let old = dir.path().join("old.json");
    std::fs::write(&old, "{\"lanes\":1,\"threads\":1,\"mrays_per_s\":2.5}\nnot json\n").unwrap();
    let missing = dir.path().join("missing.json");
    for (file, needle) in
        [(&old, format!("{}:2:", old.display())), (&missing, format!("{}: cannot read", missing.display()))]
    {
        let run = bareray(&["bench", "scenes/whitted.toml", "--compare", file.to_str().unwrap()]);
        assert_eq!(run.status.code(), Some(1));
        let err = stderr(&run);
        assert!(err.contains(&needle) && !err.contains("panicked"), "{err}");
    }
}

#[test]
fn bench_threads_default_to_one_and_all_cores() {
    let cores = std::thread::available_parallelism().unwrap().get() as u64;
    let rows =
        bench_json(&["scenes/whitted.toml", "--lanes", "1", "--reps", "1", "--width", "8", "--height", "6"]);
    let threads: Vec<u64> = rows.iter().map(|r| r["threads"].as_u64().unwrap()).collect();
    assert_eq!(threads, if cores == 1 { vec![1] } else { vec![1, cores] });
}

/// `diff`: PNG, PPM and EXR of the same values are identical (exit 0); one changed pixel is one differing
/// pixel (exit 1) and the heatmap's only non-black pixel; different sizes and unreadable files exit 2.
#[test]
fn diff_reports_identical_different_and_errors() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let a = image::RgbImage::from_fn(8, 6, |x, y| image::Rgb([x as u8 * 30, y as u8 * 40, 200]));
    a.save(p("a.png")).unwrap();
    a.save(p("a.ppm")).unwrap();
    image::DynamicImage::ImageRgb8(a.clone()).into_rgb32f().save(p("a.exr")).unwrap();
    for other in ["a.ppm", "a.exr"] {
        let run = bareray(&["diff", &p("a.png"), &p(other)]);
        let text = String::from_utf8_lossy(&run.stdout);
        assert_eq!(run.status.code(), Some(0), "{other}: {text}{}", stderr(&run));
        assert!(
            text.contains("size: 8x6") && text.contains("psnr: inf") && text.contains("identical"),
            "{text}"
        );
    }

    let mut b = a.clone();
    b.put_pixel(3, 2, image::Rgb([90, 80, 201]));
    b.save(p("b.png")).unwrap();
    let run = bareray(&["diff", &p("a.ppm"), &p("b.png"), "--heatmap", &p("heat.png")]);
    let text = String::from_utf8_lossy(&run.stdout);
    assert_eq!(run.status.code(), Some(1), "{text}{}", stderr(&run));
    assert!(text.contains("differing pixels: 1 of 48") && text.contains("dB"), "{text}");
    // 201/255 − 200/255 in f32.
    assert!(text.contains("max abs difference: 0.00392"), "{text}");
    let heat = image::open(p("heat.png")).unwrap().into_luma8();
    let lit: Vec<_> =
        heat.enumerate_pixels().filter(|(_, _, v)| v[0] > 0).map(|(x, y, v)| (x, y, v[0])).collect();
    assert_eq!(lit, vec![(3, 2, 255)]);

    image::RgbImage::new(4, 4).save(p("small.png")).unwrap();
    let run = bareray(&["diff", &p("a.png"), &p("small.png")]);
    assert_eq!(run.status.code(), Some(2));
    let err = stderr(&run);
    assert!(
        err.contains("different sizes") && err.contains("a.png is 8x6") && err.contains("small.png is 4x4"),
        "{err}"
    );
    std::fs::write(p("junk.png"), b"not an image").unwrap();
    for bad in ["missing.png", "junk.png"] {
        let run = bareray(&["diff", &p(bad), &p("a.png")]);
        assert_eq!(run.status.code(), Some(2), "{bad}");
        let err = stderr(&run);
        assert!(
            err.contains(&format!("{}: cannot read image", p(bad))) && !err.contains("panicked"),
            "{err}"
        );
    }
    // Only the inputs and the heatmap: no temporary file left beside it.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 7);
}

/// A CPU that lacks an instruction set the binary was compiled for (forced with BARERAY_ASSUME_CPU_LACKS):
/// exit 1 and one message naming the missing features and the fix, before anything else happens (no
/// argument parsing, no output file). On builds with no x86 features to check the variable changes nothing.
#[test]
fn a_cpu_lacking_a_compiled_for_feature_stops_with_a_message() {
    let version = compiled_for();
    let required: Vec<&str> = version.iter().map(String::as_str).collect();
    // avx512f and fma where the build uses them (the kernels' instruction sets), else its first feature.
    let mut lacks: Vec<&str> = required.iter().copied().filter(|f| ["avx512f", "fma"].contains(f)).collect();
    if lacks.is_empty() {
        lacks.extend(required.first());
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.png");
    let run = Command::new(env!("CARGO_BIN_EXE_bareray"))
        .args(["render", "-o", out.to_str().unwrap(), "--width", "16", "--no-such-flag"])
        .env(ASSUME_LACKS_VAR, if lacks.is_empty() { "avx512f,fma".into() } else { lacks.join(",") })
        .output()
        .unwrap();
    if lacks.is_empty() {
        // Nothing compiled for beyond the baseline: the check has nothing to find (and clap rejects the flag).
        assert_eq!(run.status.code(), Some(2), "{}", stderr(&run));
        return;
    }
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(run.stdout.is_empty());
    assert!(!out.exists(), "nothing rendered");
    assert_eq!(err.matches("error:").count(), 1, "one message, before clap sees the bad flag: {err}");
    let missing = err.lines().find_map(|l| l.trim().strip_prefix("missing:")).expect(&err);
    assert_eq!(missing.split_whitespace().collect::<Vec<_>>(), lacks, "{err}");
    let listed = err.lines().find_map(|l| l.trim().strip_prefix("required:")).expect(&err);
    assert_eq!(listed.split_whitespace().collect::<Vec<_>>(), required, "{err}");
    assert!(err.contains("`cargo build --release`") && err.contains("x86-64-v3"), "{err}");
    assert!(err.contains("`cargo build-native`") && err.contains("-C target-cpu=x86-64-v2"), "{err}");
}

/// Without the variable the check passes on the machine that built the binary: it renders as usual.
#[test]
fn the_cpu_that_built_the_binary_passes_the_check() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.png");
    let run = Command::new(env!("CARGO_BIN_EXE_bareray"))
        .args(["render", "-o", out.to_str().unwrap(), "--width", "16", "-q"])
        .env_remove(ASSUME_LACKS_VAR)
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(run.stderr.is_empty(), "{}", stderr(&run));
    assert!(out.exists());
    // The test crate is compiled with the binary's flags: what it was compiled for, `--version` names.
    let required = compiled_for();
    for (feature, on) in [("avx2", cfg!(target_feature = "avx2")), ("fma", cfg!(target_feature = "fma"))] {
        assert_eq!(required.iter().any(|f| f == feature), on, "{feature}: {required:?}");
    }
}

/// The variable that makes the binary's CPU check treat the features it names as missing.
const ASSUME_LACKS_VAR: &str = "BARERAY_ASSUME_CPU_LACKS";

/// The instruction sets `bareray --version` says the binary was compiled for (none for the baseline).
fn compiled_for() -> Vec<String> {
    let run = bareray(&["--version"]);
    let version = String::from_utf8_lossy(&run.stdout);
    let line = version.lines().find_map(|l| l.strip_prefix("compiled for: ")).expect(&version);
    match line {
        "the target's baseline" => Vec::new(),
        features => features.split_whitespace().map(str::to_owned).collect(),
    }
}

/// `converge` measures every method against a reference and writes the CSV (the issue's columns, one line
/// per run, errors falling as samples grow, coverage's single run below one sample's on the edges) and an
/// SVG plot; a second run reuses the cached reference, and
/// an unknown method is an argument error before anything renders.
#[test]
fn converge_writes_csv_and_plot_and_reuses_its_reference() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, svg) = (dir.path().join("w.csv"), dir.path().join("w.svg"));
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/whitted.toml");
    let args = |extra: &[&str]| {
        let mut a = vec!["converge", scene.to_str().unwrap(), "--width", "48", "--height", "36"];
        a.extend_from_slice(&["--max-spp", "16", "--reference-spp", "64", "--csv", csv.to_str().unwrap()]);
        a.extend_from_slice(extra);
        a.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    let run = |extra: &[&str]| {
        let a = args(extra);
        bareray(&a.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let first = run(&["--plot", svg.to_str().unwrap()]);
    assert!(first.status.success(), "{}", stderr(&first));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("method,spp,seconds,rays,rmse,rmse_edges,psnr"));
    let rows: Vec<Vec<String>> = lines.map(|l| l.split(',').map(String::from).collect()).collect();
    // grid and stratified at 1, 4, 16; r2 and sobol at 1, 2, 4, 8, 16; adaptive at 6 thresholds; lecture and
    // coverage once.
    assert_eq!(rows.len(), 3 + 3 + 5 + 5 + 6 + 1 + 1, "{text}");
    let rmse = |method: &str, spp: f64| -> f64 {
        let at = |r: &&Vec<String>| r[0] == method && r[1].parse::<f64>().unwrap() == spp;
        rows.iter().find(at).map(|r| r[4].parse().unwrap()).unwrap()
    };
    let adaptive: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r[0] == "adaptive")
        .map(|r| (r[1].parse().unwrap(), r[4].parse().unwrap()))
        .collect();
    assert!(adaptive[5].0 > adaptive[0].0 && adaptive[5].1 < adaptive[0].1, "adaptive: {adaptive:?}");
    for method in ["grid", "stratified", "r2", "sobol"] {
        assert!(rmse(method, 16.0) < 0.6 * rmse(method, 1.0), "{method}: {text}");
    }
    // Coverage has one setting, about one ray a pixel: on the edges it beats one sample per pixel.
    let coverage = rows.iter().find(|r| r[0] == "coverage").unwrap();
    let edges = |r: &Vec<String>| r[5].parse::<f64>().unwrap();
    let one = rows.iter().find(|r| r[0] == "grid" && r[1].parse::<f64>().unwrap() == 1.0).unwrap();
    assert!(edges(coverage) < edges(one), "{text}");
    let plot = std::fs::read_to_string(&svg).unwrap();
    assert!(plot.starts_with("<svg") && plot.matches("<polyline").count() == 7);
    assert!(stderr(&first).contains("stratified 8×8"), "{}", stderr(&first));
    let second = run(&[]);
    assert!(second.status.success() && stderr(&second).contains("(cached)"), "{}", stderr(&second));
    let bad = run(&["--methods", "grid,halton"]);
    assert_eq!(bad.status.code(), Some(2), "{}", stderr(&bad));
    assert!(stderr(&bad).contains("unknown method `halton`"));
}

/// `converge --filters`: each (method, filter) pair is a series (CSV `filter` column, plot legend
/// `method, filter`) measured against a reference with the same filter, cached per filter; adaptive ignores
/// filters and runs under `none` only; a bad filter is an argument error.
#[test]
fn converge_compares_filters() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, svg) = (dir.path().join("f.csv"), dir.path().join("f.svg"));
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/whitted.toml");
    let run = |filters: &str| {
        bareray(&[
            "converge",
            scene.to_str().unwrap(),
            "--width",
            "40",
            "--height",
            "30",
            "--methods",
            "sobol,adaptive",
            "--filters",
            filters,
            "--max-spp",
            "4",
            "--reference-spp",
            "64",
            "--csv",
            csv.to_str().unwrap(),
            "--plot",
            svg.to_str().unwrap(),
        ])
    };
    let first = run("none,gaussian");
    assert!(first.status.success(), "{}", stderr(&first));
    assert!(stderr(&first).contains("adaptive ignores reconstruction filters"), "{}", stderr(&first));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("method,filter,spp,seconds,rays,rmse,rmse_edges,psnr"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let series = |m: &str, f: &str| rows.iter().filter(|r| r[0] == m && r[1] == f).count();
    // sobol at 1, 2, 4 under each filter; adaptive's 6 thresholds under `none` only.
    assert_eq!((series("sobol", "none"), series("sobol", "gaussian:1.5")), (3, 3), "{text}");
    assert_eq!((series("adaptive", "none"), series("adaptive", "gaussian:1.5")), (6, 0), "{text}");
    // Rising counts lower the error under each filter (a filter's spp counts its apron's rays too).
    for filter in ["none", "gaussian:1.5"] {
        let rmse: Vec<f64> = rows
            .iter()
            .filter(|r| r[0] == "sobol" && r[1] == filter)
            .map(|r| r[5].parse().unwrap())
            .collect();
        assert!(rmse[2] < rmse[0], "{filter}: {text}");
    }
    let plot = std::fs::read_to_string(&svg).unwrap();
    assert_eq!(plot.matches("<polyline").count(), 3, "{plot}");
    assert!(plot.contains(">sobol, gaussian:1.5<") && plot.contains(">adaptive, none<"), "{plot}");
    for name in ["f.reference.none.exr", "f.reference.gaussian-1.5.exr"] {
        assert!(dir.path().join(name).exists(), "{name}");
    }
    let again = run("gaussian");
    assert!(again.status.success() && stderr(&again).contains("filter gaussian:1.5: "), "{}", stderr(&again));
    assert!(
        stderr(&again).contains("(cached)") && stderr(&again).contains("does not run"),
        "{}",
        stderr(&again)
    );
    let bad = run("none,sinc");
    assert_eq!(bad.status.code(), Some(2), "{}", stderr(&bad));
    assert!(stderr(&bad).contains("unknown filter `sinc`"), "{}", stderr(&bad));
}

/// `--aa sobol:N` renders with the scrambled Sobol' points and names them in the summary; `sobol:0` is an
/// argument error that says what N may be.
#[test]
fn render_takes_sobol_samples() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.png");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/whitted.toml");
    let render = |aa: &str| {
        bareray(&[
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--width",
            "32",
            "--stats",
            "--aa",
            aa,
        ])
    };
    let run = render("sobol:16");
    assert!(run.status.success(), "{}", stderr(&run));
    let text = String::from_utf8_lossy(&run.stdout);
    assert!(text.contains("16 samples per pixel (Sobol' sequence, Owen-scrambled per pixel)"), "{text}");
    let bad = render("sobol:0");
    assert_eq!(bad.status.code(), Some(2), "{}", stderr(&bad));
    assert!(stderr(&bad).contains("samples per pixel run from 1 to 65536, got `0`"), "{}", stderr(&bad));
}

/// `converge --precision`: the f32 packet, single-ray SIMD and scalar paths give the same hits (so the same
/// error against the f64 twin), small but measured; the f64 twin is the reference (error 0); CSV has one
/// line per path.
#[test]
fn converge_precision_compares_the_four_paths() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("p.csv");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/field1k.xyzr");
    let run = bareray(&[
        "converge",
        scene.to_str().unwrap(),
        "--precision",
        "--width",
        "96",
        "--height",
        "54",
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let text = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<Vec<&str>> = text.lines().skip(1).map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 4, "{text}");
    assert!(
        rows[0][0].starts_with("f32 packets")
            && rows[1][0].starts_with("f32 single-ray SIMD")
            && rows[2][0] == "f32 scalar"
            && rows[3][0] == "f64 twin",
        "{text}"
    );
    assert_eq!(rows[0][2..], rows[1][2..], "packets and single-ray SIMD: the same hits");
    assert_eq!(rows[0][2..], rows[2][2..], "packets and scalar: the same hits");
    let p99: f64 = rows[0][4].parse().unwrap();
    assert!(p99 > 0.0 && p99 < 2e-6, "{text}");
    assert!(rows[3][2..].iter().all(|v| v.parse::<f64>().unwrap() == 0.0));
}

/// Formats beyond 8 bits: `--bit-depth 16` writes a 16-bit PNG whose values are the 8-bit PNG's to within
/// rounding (256 codes per 8-bit step), `.hdr` writes Radiance RGBE that decodes to the EXR's linear values
/// within RGBE's precision (a 1/256 mantissa step), a PNG records the renderer, scene and sampling in text
/// chunks, and `--bit-depth 16` for a PPM is an argument error that writes nothing.
#[test]
fn sixteen_bit_png_and_radiance_hdr_match_the_other_formats() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/transforms.toml");
    let out = |name: &str| dir.path().join(name);
    let render = |path: &Path, extra: &[&str]| {
        let mut args =
            vec!["render", scene.to_str().unwrap(), "-o", path.to_str().unwrap(), "--width", "64", "-q"];
        args.extend_from_slice(extra);
        bareray(&args)
    };
    for (name, extra) in
        [("a.png", &[][..]), ("b.png", &["--bit-depth", "16"][..]), ("c.exr", &[][..]), ("d.hdr", &[][..])]
    {
        let run = render(&out(name), extra);
        assert!(run.status.success(), "{name}: {}", stderr(&run));
    }
    let png8 = image::open(out("a.png")).unwrap();
    let png16 = image::open(out("b.png")).unwrap();
    assert!(matches!(png16, image::DynamicImage::ImageRgb16(_)), "{:?}", png16.color());
    let (p8, p16) = (png8.to_rgb8(), png16.to_rgb16());
    let close = p8
        .as_raw()
        .iter()
        .zip(p16.as_raw())
        .all(|(&a, &b)| (f64::from(b) / 257.0 - f64::from(a)).abs() <= 0.5 + 1e-9);
    assert!(close, "16-bit values round to the 8-bit ones");
    assert!(p16.as_raw().iter().any(|&v| v % 257 != 0), "16 bits carry more than the 8-bit codes");
    let exr = image::open(out("c.exr")).unwrap().to_rgb32f();
    let hdr = image::open(out("d.hdr")).unwrap().to_rgb32f();
    assert_eq!(exr.dimensions(), hdr.dimensions());
    // RGBE shares one exponent per pixel: each channel is within half a step of 1/256 of the pixel's
    // largest channel's power of two (a whole step where the largest is clamped to 255).
    for (e, h) in exr.as_raw().chunks(3).zip(hdr.as_raw().chunks(3)) {
        let largest = e.iter().fold(0.0f32, |m, v| m.max(v.abs()));
        let step = 2f32.powi(largest.log2().floor() as i32 + 1) / 256.0;
        for (a, b) in e.iter().zip(h) {
            assert!((a - b).abs() <= step + 1e-6, "exr {e:?} hdr {h:?}");
        }
    }
    let text = std::fs::read(out("a.png")).unwrap();
    let has = |needle: &str| text.windows(needle.len()).any(|w| w == needle.as_bytes());
    assert!(has("Software") && has("bareray ") && has("Source") && has("transforms.toml") && has("Comment"));
    let bad = render(&out("e.ppm"), &["--bit-depth", "16"]);
    assert_eq!(bad.status.code(), Some(2), "{}", stderr(&bad));
    assert!(!out("e.ppm").exists());
}

/// `--ambient`: with no lights a pixel is ambient × colour, so the floor and the sphere of a two-fill NFF
/// show the coefficient each got: one value sets every material, a list one per `f` line in file order;
/// a list of the wrong length is an argument error that writes nothing; the PNG records the values.
#[test]
fn ambient_sets_the_materials_coefficients_in_file_order() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("two.nff");
    std::fs::write(
        &scene,
        "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nhither 0.01\nresolution 9 9\nb 0 0 0\n\
         f 1 1 1 1 0 0 0 1\np 4\n-10 -10 -1\n10 -10 -1\n10 10 -1\n-10 10 -1\n\
         f 1 1 1 1 0 0 0 1\ns 0 0 0 0.8\n",
    )
    .unwrap();
    let render = |ambient: Option<&str>, out: &Path| {
        let mut args = vec!["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"];
        if let Some(a) = ambient {
            args.extend(["--ambient", a]);
        }
        bareray(&args)
    };
    // (corner: the floor, centre: the sphere), 8-bit linear values.
    let floor_and_sphere = |out: &Path| {
        let img = image::open(out).unwrap().into_rgb8();
        (img.get_pixel(0, 0)[0], img.get_pixel(4, 4)[0])
    };
    let out = dir.path().join("a.png");
    for (ambient, expect) in
        [(None, (26, 26)), (Some("0.5,0"), (128, 0)), (Some("0,1"), (0, 255)), (Some("0.25"), (64, 64))]
    {
        let run = render(ambient, &out);
        assert!(run.status.success(), "{ambient:?}: {}", stderr(&run));
        assert_eq!(floor_and_sphere(&out), expect, "--ambient {ambient:?}");
    }
    let text = std::fs::read(&out).unwrap();
    assert!(text.windows(12).any(|w| w == b"ambient 0.25"), "the PNG records --ambient");
    let missing = dir.path().join("b.png");
    let run = render(Some("0.2,0,1"), &missing);
    assert_eq!(run.status.code(), Some(2));
    assert!(
        stderr(&run).contains("--ambient gave 3 values; the scene defines 2 materials"),
        "{}",
        stderr(&run)
    );
    assert!(!missing.exists());
    let run = render(Some("1.5"), &missing);
    assert_eq!(run.status.code(), Some(2), "{}", stderr(&run));
    assert!(!missing.exists());
}

/// EXR attribute text is UTF-8, as OpenEXR's tools and bindings read it: the comment's `×` is the two
/// bytes C3 97, not Latin-1's single D7 (which Python's OpenEXR module refuses to decode).
#[test]
fn exr_attribute_text_is_utf8() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.exr");
    let run = bareray(&["render", "-o", out.to_str().unwrap(), "--width", "16", "--spp", "1", "-q"]);
    assert!(run.status.success(), "{}", stderr(&run));
    let bytes = std::fs::read(&out).unwrap();
    let has = |needle: &[u8]| bytes.windows(needle.len()).any(|w| w == needle);
    assert!(has("(1×1 grid)".as_bytes()), "the comment in UTF-8");
    assert!(!has(b"(1\xd71 grid)"), "not in Latin-1");
}

/// A floor under a sphere seen from above: every pixel hits something, so every camera ray traces its
/// occlusion rays.
const FLOOR_UNDER_A_BALL: &str = r#"
[camera]
eye = [0.0, 4.0, -3.0]
look_at = [0.0, 0.0, 0.0]
hfov = 40
[materials.floor]
color = [0.9, 0.8, 0.7]
[[planes]]
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
material = "floor"
[[spheres]]
center = [0.0, 0.8, 0.0]
radius = 0.8
"#;

/// `converge --shade ao:N`: the reference and every run shade with ambient occlusion, the rays column counts
/// N occlusion rays per camera ray, and the error falls as samples per pixel grow (each camera sample brings
/// its own occlusion rays) and as N grows at one sample per pixel.
#[test]
fn converge_covers_ambient_occlusion() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("ball.toml");
    std::fs::write(&scene, FLOOR_UNDER_A_BALL).unwrap();
    let study = |shade: &str| -> Vec<(f64, u64, f64)> {
        let csv = dir.path().join(format!("{shade}.csv").replace(':', "-"));
        let run = bareray(&[
            "converge",
            scene.to_str().unwrap(),
            "--shade",
            shade,
            "--methods",
            "stratified,r2",
            "--width",
            "32",
            "--height",
            "24",
            "--max-spp",
            "16",
            "--reference-spp",
            "256",
            "--csv",
            csv.to_str().unwrap(),
        ]);
        assert!(run.status.success(), "{}", stderr(&run));
        let text = std::fs::read_to_string(&csv).unwrap();
        let rows: Vec<(f64, u64, f64)> = text
            .lines()
            .skip(1)
            .filter(|l| l.starts_with("stratified"))
            .map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                (f[1].parse().unwrap(), f[3].parse().unwrap(), f[4].parse().unwrap())
            })
            .collect();
        assert_eq!(rows.len(), 3, "{text}");
        rows
    };
    let one = study("ao:1");
    let eight = study("ao:8");
    for (per_ray, rows) in [(1, &one), (8, &eight)] {
        for &(spp, rays, _) in rows {
            assert_eq!(rays, (spp as u64) * 32 * 24 * (1 + per_ray), "ao:{per_ray} at {spp} spp");
        }
        assert!(rows[2].2 < 0.5 * rows[0].2, "ao:{per_ray}: {rows:?}");
    }
    assert!(
        eight[0].2 < 0.6 * one[0].2,
        "8 occlusion rays against 1 at one sample per pixel: {eight:?} {one:?}"
    );
}

/// A bad `--shade` is an argument error (exit 2) that names the flag and lists the valid forms, and nothing
/// is written; a bad `shade` key in a scene file names its line and column.
#[test]
fn bad_shade_values_are_refused_before_rendering() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o.png");
    for bad in ["ao:0", "ao:abc", "ao:4,-1", "ao:4,0", "phong", "whitted:2"] {
        let run = bareray(&["render", "-o", out.to_str().unwrap(), "--width", "20", "--shade", bad]);
        assert_eq!(run.status.code(), Some(2), "{bad}: {}", stderr(&run));
        let e = stderr(&run);
        assert!(
            e.contains("--shade") && e.contains("whitted, ao, ao:SAMPLES or ao:SAMPLES,DISTANCE"),
            "{bad}: {e}"
        );
        assert!(!out.exists(), "{bad}: an image was written");
    }
    let scene = dir.path().join("bad.toml");
    std::fs::write(&scene, format!("{FLOOR_UNDER_A_BALL}\n[render]\nshade = \"ao:2,-3\"\n")).unwrap();
    let run = bareray(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    assert!(stderr(&run).contains("bad.toml:17:9") && stderr(&run).contains("DISTANCE"), "{}", stderr(&run));
    assert!(!out.exists());
}

/// `--stats` names the shading with its resolved distance and counts the occlusion rays in the total: one
/// sample per pixel, every pixel a hit, 3 occlusion rays each.
#[test]
fn stats_count_ambient_occlusion_rays() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("ball.toml");
    std::fs::write(&scene, FLOOR_UNDER_A_BALL).unwrap();
    let out = dir.path().join("ao.png");
    let args =
        ["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--width", "40", "--height", "30"];
    let run = bareray(&[&args[..], &["--stats", "--shade", "ao:3,0.5"]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let text = String::from_utf8_lossy(&run.stdout);
    assert!(text.contains("ao:3,0.5 shading") && text.contains("ambient occlusion rays;"), "{text}");
    assert!(
        text.contains("rays: 4800 total: 1200 primary, 0 shadow, 0 reflection, 0 refraction, 3600 ao"),
        "{text}"
    );
    // The default distance is a quarter of the sphere's box diagonal (1.6·√3).
    let run = bareray(&[&args[..], &["--stats", "--shade", "ao"]].concat());
    let text = String::from_utf8_lossy(&run.stdout);
    let shown =
        text.split("ao:16,").nth(1).and_then(|t| t.split(' ').next()).unwrap_or_else(|| panic!("{text}"));
    let distance = 0.25 * 1.6 * 3f64.sqrt();
    assert!((shown.parse::<f64>().unwrap() - distance).abs() < 1e-12, "{distance}: {text}");
}

/// `--accel pkd` maps an `.f32r` field and renders the BVH's image byte for byte; `auto` takes the tree
/// when `--memory` leaves too little for the BVH and says why in `--stats`; a field too large for either is
/// refused before loading, with the largest count that fits, exit 1 and the old output kept.
#[test]
fn the_particle_tree_renders_the_bvhs_image_and_memory_decides_auto() {
    let dir = tempfile::tempdir().unwrap();
    let field = dir.path().join("f.f32r");
    let field_s = field.to_str().unwrap();
    assert!(bareray(&["gen", "field", "--count", "20000", "-o", field_s]).status.success());
    let render = |accel: &str, extra: &[&str]| {
        let out = dir.path().join(format!("{accel}.png"));
        let mut args =
            vec!["render", field_s, "--width", "200", "--height", "120", "--stats", "--accel", accel];
        args.extend_from_slice(&["-o", out.to_str().unwrap()]);
        args.extend_from_slice(extra);
        let run = bareray(&args);
        (run, out)
    };
    let (bvh, bvh_png) = render("bvh", &[]);
    assert!(bvh.status.success(), "{}", stderr(&bvh));
    let (pkd, pkd_png) = render("pkd", &[]);
    assert!(pkd.status.success(), "{}", stderr(&pkd));
    let stats = String::from_utf8_lossy(&pkd.stdout);
    assert!(stats.contains("spheres by the particle tree over the mapped file"), "{stats}");
    assert_eq!(std::fs::read(&bvh_png).unwrap(), std::fs::read(&pkd_png).unwrap());
    // 20 000 spheres: the tree needs 0.4 MB and the BVH 1.8 MB beside the 256 MB reserve.
    let (auto, auto_png) = render("auto", &["--memory", "257M"]);
    assert!(auto.status.success(), "{}", stderr(&auto));
    let stats = String::from_utf8_lossy(&auto.stdout);
    assert!(stats.contains("chosen by auto: the particle tree, as the BVH would need"), "{stats}");
    assert_eq!(std::fs::read(&bvh_png).unwrap(), std::fs::read(&auto_png).unwrap());
    let (auto, _) = render("auto", &["--memory", "1G"]);
    assert!(String::from_utf8_lossy(&auto.stdout).contains("spheres by BVH"));
    // Too large for either: refused before loading, the old image kept.
    let keep = dir.path().join("keep.png");
    std::fs::copy(&bvh_png, &keep).unwrap();
    let keep_s = keep.to_str().unwrap();
    let refused = bareray(&["render", field_s, "--memory", "262244K", "-o", keep_s]);
    assert_eq!(refused.status.code(), Some(1));
    let err = stderr(&refused);
    // 100 KiB above the reserve: 102400 / 20 bytes.
    assert!(err.contains(field_s) && err.contains("at most 5120 spheres fit"), "{err}");
    assert_eq!(std::fs::read(&bvh_png).unwrap(), std::fs::read(&keep).unwrap());
    let planned = bareray(&["render", field_s, "--accel", "bvh", "--memory", "1K", "-o", keep_s]);
    assert!(planned.status.success(), "--accel bvh plans no memory: {}", stderr(&planned));
}

/// Hostile `.f32r` files are refused by the mapped reader as by the plain one: exit 1, the file and the
/// byte offset named, no panic.
#[test]
fn hostile_f32r_files_are_refused_by_the_mapped_reader() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("good.f32r");
    assert!(bareray(&["gen", "field", "--count", "100", "-o", good.to_str().unwrap()]).status.success());
    let bytes = std::fs::read(&good).unwrap();
    let mut nan = bytes.clone();
    nan[16 + 16 * 7 + 4..16 + 16 * 7 + 8].copy_from_slice(&f32::NAN.to_le_bytes());
    let mut lying = bytes.clone();
    lying[12..16].copy_from_slice(&1000u32.to_le_bytes());
    let cases: [(&str, Vec<u8>, &str); 6] = [
        ("text", b"0 0 0 1\n1 1 1 1\n2 2 2 1\n".to_vec(), "not an .f32r sphere list"),
        ("truncated", bytes[..16 + 16 * 50 + 5].to_vec(), "ends inside record 50 (byte 816)"),
        ("lying", lying, "the header's count is 1000"),
        ("nan", nan, "record 7 (byte 128): y is not finite"),
        ("header", bytes[..10].to_vec(), "ends inside the 16-byte header"),
        ("empty", Vec::new(), "ends inside the 16-byte header, after 0 bytes"),
    ];
    for (name, content, want) in cases {
        let path = dir.path().join(format!("{name}.f32r"));
        std::fs::write(&path, content).unwrap();
        let out = dir.path().join("out.png");
        let run = bareray(&["render", path.to_str().unwrap(), "--accel", "pkd", "-o", out.to_str().unwrap()]);
        assert_eq!(run.status.code(), Some(1), "{name}");
        let err = stderr(&run);
        assert!(err.contains(path.to_str().unwrap()) && err.contains(want), "{name}: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
    }
}

/// `convert` streams `.xyzr` text into `.f32r` (the same bytes `gen` writes for the same field), and a bad
/// line is named with its number, exit 1 and no output file.
#[test]
fn convert_streams_text_into_binary() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    assert!(bareray(&["gen", "field", "--count", "3000", "-o", &p("g.f32r")]).status.success());
    assert!(bareray(&["gen", "field", "--count", "3000", "-o", &p("g.xyzr")]).status.success());
    let run = bareray(&["convert", &p("g.xyzr"), "-o", &p("c.f32r")]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert_eq!(std::fs::read(p("g.f32r")).unwrap(), std::fs::read(p("c.f32r")).unwrap());
    std::fs::write(p("bad.xyzr"), "# two good, one bad\n0 0 0 1\n1 1 1 0.5\n\n2 2 x 1\n").unwrap();
    let run = bareray(&["convert", &p("bad.xyzr"), "-o", &p("bad.f32r")]);
    assert_eq!(run.status.code(), Some(1));
    assert!(stderr(&run).contains("bad.xyzr:5"), "{}", stderr(&run));
    assert!(!Path::new(&p("bad.f32r")).exists());
}

/// `bench --isa`: a level that is not v2, v3 or v4, a level listed twice, and `--isa-dir` without `--isa`
/// are argument errors (exit 2) that name the problem, before anything runs.
#[test]
fn bench_isa_bad_levels_are_argument_errors() {
    let cases: [(&[&str], &str); 4] = [
        (&["--isa", "v5"], "`v5`"),
        (&["--isa", "v3,avx2"], "levels are v2 (SSE4.2), v3 (AVX2 and FMA) and v4 (AVX-512)"),
        (&["--isa", "v3,x86-64-v3"], "v3 is listed twice"),
        (&["--isa-dir", "."], "--isa"),
    ];
    for (extra, needle) in cases {
        let run = bareray(&[&["bench", "scenes/whitted.toml"], extra].concat());
        let err = stderr(&run);
        assert_eq!(run.status.code(), Some(2), "{extra:?}: {err}");
        assert!(err.contains(needle) && !err.contains("panicked"), "{extra:?}: {err}");
        assert!(run.stdout.is_empty(), "{extra:?}");
    }
}

/// `bench --isa`: a build that is not there is an error (exit 1) naming where it was looked for and the
/// command that builds it.
#[test]
fn bench_isa_missing_build_names_the_build_command() {
    let dir = tempfile::tempdir().unwrap();
    let run =
        bareray(&["bench", "scenes/whitted.toml", "--isa", "v3", "--isa-dir", dir.path().to_str().unwrap()]);
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(err.contains("no x86-64-v3 build") && err.contains("`cargo build-v3`"), "{err}");
    assert!(err.contains(&dir.path().join("v3/release/bareray").display().to_string()), "{err}");
    assert!(err.contains("bench-peers/build_isa.sh") && !err.contains("panicked"), "{err}");
    assert!(run.stdout.is_empty());
}

/// A directory of per-ISA builds (`<level>/release/bareray`) in which each level is this test binary.
#[cfg(all(unix, target_arch = "x86_64"))]
fn isa_dir_of_this_binary(levels: &[&str]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for level in levels {
        let release = dir.path().join(level).join("release");
        std::fs::create_dir_all(&release).unwrap();
        std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_bareray"), release.join("bareray")).unwrap();
    }
    dir
}

/// `bench --isa v2,v3,v4` end to end, with this binary standing in for the v2 and v3 builds: one row per
/// (isa, lanes, threads) with the checksum of a plain bench at the same settings (the other arguments reach
/// the builds), a level the CPU lacks skipped with a note, a build whose kernels are not its level's
/// flagged, each build's split by ray kind, and the JSON lines carrying the level, the rounds and the split.
#[cfg(all(unix, target_arch = "x86_64"))]
#[test]
fn bench_isa_runs_the_builds_side_by_side() {
    let dir = isa_dir_of_this_binary(&["v2", "v3"]);
    let settings =
        ["scenes/whitted.toml", "--lanes", "1,8", "--threads", "1", "--width", "16", "--height", "12"];
    let plain = bench_json(&[&settings[..], &["--reps", "1"]].concat());
    let isa = ["--isa", "v2,v3,v4", "--isa-dir", dir.path().to_str().unwrap(), "--reps", "2"];
    let run = Command::new(env!("CARGO_BIN_EXE_bareray"))
        .args([&["bench"], &settings[..], &isa[..]].concat())
        .env("BARERAY_ASSUME_CPU_LACKS", "avx512bw")
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", stderr(&run));
    let table = String::from_utf8_lossy(&run.stdout);
    // The variable makes every CPU lack avx512bw; one without AVX-512 lacks the rest of v4's too.
    let note = table.lines().find(|l| l.starts_with("note: x86-64-v4 skipped: CPU lacks "));
    assert!(note.is_some_and(|l| l.contains("avx512bw")), "{table}");
    assert!(table.contains("2 rounds") && table.contains("vs v3"), "{table}");
    assert!(table.contains("checksums: equal in every build for every row"), "{table}");
    if cfg!(target_feature = "fma") {
        // This binary is not a v2 build: the table says so.
        assert!(
            table.contains("warning: the v2 build") && table.contains("not an x86-64-v2 build"),
            "{table}"
        );
    }
    let rows: Vec<&str> = table.lines().filter(|l| l.starts_with("v2 ") || l.starts_with("v3 ")).collect();
    assert_eq!(rows.len(), 4, "{table}");
    for (row, (level, lanes)) in rows.iter().zip([("v2", 1), ("v3", 1), ("v2", 8), ("v3", 8)]) {
        let fields: Vec<&str> = row.split_whitespace().collect();
        assert_eq!((fields[0], fields[2], fields[3]), (level, &*lanes.to_string(), "1"), "{table}");
        let plain_row = plain.iter().find(|r| r["lanes"] == lanes).unwrap();
        assert!(row.contains(plain_row["checksum"].as_str().unwrap()), "{row} vs {plain_row}");
    }
    // The first round's split by ray kind, per build: whitted.toml traces all but AO rays.
    let split = table.split_once("\nby ray kind").map_or("", |(_, s)| s);
    for kind in ["camera", "shadow", "reflection", "refraction"] {
        let lines = split.lines().filter(|l| l.trim_start().starts_with(&format!("{kind} "))).count();
        assert_eq!(lines, 4, "{kind}: {table}");
    }
    // With --json: one line per (isa, lanes, threads), the level and the rounds in it; the note on stderr.
    let run = Command::new(env!("CARGO_BIN_EXE_bareray"))
        .args([&["bench"], &settings[..], &isa[..], &["--json"]].concat())
        .env("BARERAY_ASSUME_CPU_LACKS", "avx512bw")
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", stderr(&run));
    let err = stderr(&run);
    let note = err.lines().find(|l| l.contains("x86-64-v4 skipped: CPU lacks "));
    assert!(note.is_some_and(|l| l.contains("avx512bw")), "{err}");
    let lines: Vec<serde_json::Value> =
        String::from_utf8_lossy(&run.stdout).lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    let levels: Vec<_> = lines.iter().map(|l| l["isa_level"].as_str().unwrap().to_owned()).collect();
    assert_eq!(levels, ["v2", "v3", "v2", "v3"]);
    for line in &lines {
        assert_eq!(line["reps"], 2, "{line}");
        assert_eq!(line["width"], 16, "{line}");
        let plain_row = plain.iter().find(|r| r["lanes"] == line["lanes"]).unwrap();
        assert_eq!(line["checksum"], plain_row["checksum"], "{line}");
        assert!(line["min_s"].as_f64() <= line["seconds"].as_f64(), "{line}");
        assert_eq!(line["software_fma"], !cfg!(target_feature = "fma"), "{line}");
        assert_eq!(line["by_kind"]["kinds"][0]["kind"], "camera", "{line}");
    }
}

/// `bench --isa`: builds whose checksums differ are an error (exit 1) naming both builds and both
/// checksums. The v2 "build" is a script printing a row with another checksum.
#[cfg(all(unix, target_arch = "x86_64"))]
#[test]
fn bench_isa_checksum_mismatch_is_an_error() {
    use std::os::unix::fs::PermissionsExt;
    let dir = isa_dir_of_this_binary(&["v3"]);
    let fake = dir.path().join("v2/release/bareray");
    std::fs::create_dir_all(fake.parent().unwrap()).unwrap();
    let line =
        r#"{"lanes":1,"threads":1,"rays":192,"seconds":0.001,"checksum":"00000000deadbeef","isa":"sse2"}"#;
    std::fs::write(&fake, format!("#!/bin/sh\necho '{line}'\n")).unwrap();
    std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
    let run = bareray(&[
        "bench",
        "scenes/whitted.toml",
        "--lanes",
        "1",
        "--threads",
        "1",
        "--width",
        "16",
        "--height",
        "12",
        "--reps",
        "1",
        "--isa",
        "v2,v3",
        "--isa-dir",
        dir.path().to_str().unwrap(),
    ]);
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(err.contains("checksums differ between builds at lanes 1, threads 1"), "{err}");
    assert!(err.contains(&format!("v2 ({}) gave 00000000deadbeef", fake.display())), "{err}");
    assert!(err.contains(&format!("v3 ({}", dir.path().join("v3/release/bareray").display())), "{err}");
    assert!(!err.contains("panicked") && run.stdout.is_empty(), "{err}");
}
