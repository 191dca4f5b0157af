//! Stills in bands from the command line: regions merge back into the full image byte for byte, interrupted
//! renders resume to the same bytes, and what cannot work is refused before any tracing (the streamed files'
//! bytes are tested through the library in `library/stills.rs`).

use crate::common;

use std::path::Path;

use common::{bareray, stderr};

/// Regions cut across tiles and packet blocks, rendered apart (through the command line, with --region and
/// --crop) and merged, are the full render's file byte for byte, for 8- and 16-bit PNG, EXR and PPM, on a
/// scene with the lecture's 3×3 postfilter (whose neighbours cross the cuts), one with a Mitchell filter,
/// a sphere field under the coverage pattern (whose per-tile sphere lists start elsewhere in a region), and
/// ambient occlusion under stratified sampling (whose directions must not depend on where tiles start).
#[test]
fn regions_merge_into_the_full_image_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for (scene, extra) in [
        ("scenes/lecture.toml", &[][..]),
        ("scenes/whitted.toml", &["--filter", "mitchell"][..]),
        ("scenes/field.toml", &["--aa", "coverage"][..]),
        ("scenes/whitted.toml", &["--shade", "ao:4", "--aa", "stratified:4"][..]),
    ] {
        let scene = root.join(scene);
        for (ext, depth) in [("png", "8"), ("png", "16"), ("exr", "8"), ("ppm", "8")] {
            let render = |out: &str, region: &[&str]| {
                let mut args =
                    vec!["render", scene.to_str().unwrap(), "-o", out, "--width", "97", "--height", "61"];
                args.extend(["--bit-depth", depth, "-q"]);
                args.extend(extra);
                args.extend(region);
                let run = bareray(&args);
                assert!(run.status.success(), "{args:?}: {}", stderr(&run));
            };
            let full = p(&format!("full.{ext}"));
            render(&full, &[]);
            // Three regions and a crop (rows ⌈0.5·61⌉ = 31 to 61): a left and a right part of the top half,
            // split at a column inside a tile, and the bottom half.
            let parts = [p(&format!("a.{ext}")), p(&format!("b.{ext}")), p(&format!("c.{ext}"))];
            render(&parts[0], &["--region", "0,0,37,31"]);
            render(&parts[1], &["--region", "37,0,97,31"]);
            render(&parts[2], &["--crop", "0,1,0.5,1"]);
            let merged = p(&format!("merged.{ext}"));
            let run = bareray(&["merge", &parts[2], &parts[0], &parts[1], "-o", &merged, "-q"]);
            assert!(run.status.success(), "{}", stderr(&run));
            assert!(
                std::fs::read(&full).unwrap() == std::fs::read(&merged).unwrap(),
                "{}: {ext} at {depth} bits: merged regions differ from the full render",
                scene.display()
            );
            // A part is a file of the region's size that other tools read.
            if ext != "exr" {
                let part = image::open(&parts[0]).unwrap();
                assert_eq!((part.width(), part.height()), (37, 31));
            }
        }
    }
}

/// `merge` refuses parts that leave a gap, overlap, mix formats or renders, or are not bareray's, with the
/// part named, exit 1 and no output file.
#[test]
fn merge_refuses_gaps_overlaps_and_foreign_parts() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/balls3.nff");
    let render = |out: &str, more: &[&str]| {
        let mut args = vec!["render", scene.to_str().unwrap(), "-o", out, "-q"];
        args.extend(more);
        let run = bareray(&args);
        assert!(run.status.success(), "{args:?}: {}", stderr(&run));
    };
    let size = ["--width", "40", "--height", "30"];
    render(&p("top.png"), &[&size[..], &["--region", "0,0,40,15"]].concat());
    render(&p("bottom.png"), &[&size[..], &["--region", "0,15,40,30"]].concat());
    render(&p("bottom.ppm"), &[&size[..], &["--region", "0,15,40,30"]].concat());
    render(&p("lower.png"), &[&size[..], &["--region", "0,10,40,30"]].concat());
    render(&p("bottom-wide.png"), &["--width", "80", "--height", "60", "--region", "0,15,40,30"]);
    render(&p("bottom-linear.png"), &[&size[..], &["--region", "0,15,40,30", "--transfer", "srgb"]].concat());
    image::RgbImage::new(40, 15).save(p("foreign.png")).unwrap();
    let cases: [(&[&str], &str); 6] = [
        (&["top.png"], "cover 600 of the 40x30 image's 1200 pixels"),
        (&["top.png", "lower.png"], "overlap"),
        (&["top.png", "bottom.ppm"], "bottom.ppm: is PPM, the output is PNG"),
        (&["top.png", "bottom-wide.png"], "not from the same render"),
        (&["top.png", "bottom-linear.png"], "not from the same render"),
        (&["foreign.png", "bottom.png"], "foreign.png: no Transfer text chunk"),
    ];
    for (parts, message) in cases {
        let mut args = vec!["merge".to_owned()];
        args.extend(parts.iter().map(|n| p(n)));
        args.extend(["-o".to_owned(), p("out.png")]);
        let run = bareray(&args.iter().map(String::as_str).collect::<Vec<_>>());
        assert_eq!(run.status.code(), Some(1), "{parts:?}");
        assert!(stderr(&run).contains(message), "{parts:?}: {}", stderr(&run));
        assert!(!dir.path().join("out.png").exists(), "{parts:?} left an output");
    }
}

/// A size past bareray's side limit, an unwritable path and a region outside the image are refused before
/// any tracing, with a message, exit 1 (2 for the argument error), and nothing written.
#[test]
fn impossible_sizes_and_bad_targets_are_refused_before_tracing() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let huge = dir.path().join("huge.toml");
    let whitted =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/whitted.toml")).unwrap();
    let mut huge_scene: toml::Table = whitted.parse().unwrap();
    let camera = huge_scene["camera"].as_table_mut().unwrap();
    camera.insert("width".into(), toml::Value::Integer(9_000_000));
    camera.insert("height".into(), toml::Value::Integer(4));
    std::fs::write(&huge, toml::to_string(&huge_scene).unwrap()).unwrap();
    let run = bareray(&["render", huge.to_str().unwrap(), "-o", &p("huge.png"), "-q"]);
    assert_eq!(run.status.code(), Some(1));
    assert!(stderr(&run).contains("up to 8388608 pixels a side"), "{}", stderr(&run));
    assert!(!dir.path().join("huge.png").exists());

    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/balls3.nff");
    let scene = scene.to_str().unwrap();
    let run = bareray(&["render", scene, "-o", &p("no/such/dir/a.png"), "-q"]);
    assert_eq!(run.status.code(), Some(1));
    assert!(stderr(&run).contains("does not exist"), "{}", stderr(&run));
    let run = bareray(&[
        "render",
        scene,
        "-o",
        &p("a.png"),
        "--width",
        "40",
        "--height",
        "30",
        "--region",
        "0,0,41,10",
    ]);
    assert_eq!(run.status.code(), Some(2));
    assert!(stderr(&run).contains("reaches outside the 40x30 image"), "{}", stderr(&run));
    let run = bareray(&["render", scene, "-o", &p("a.hdr"), "--region", "0,0,10,10"]);
    assert_eq!(run.status.code(), Some(2));
    assert!(!dir.path().join("a.png").exists() && !dir.path().join("a.hdr").exists());
}

/// A `--resume` render stopped by SIGINT exits 130, leaves no image and keeps its finished rows; the same
/// command again traces the rest and writes the bytes of an uninterrupted render, and removes the side
/// file. A side file of other settings is not used.
#[cfg(unix)]
#[test]
fn an_interrupted_render_resumes_to_the_same_bytes() {
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/balls3.nff");
    let args = |out: &str, width: &str| -> Vec<String> {
        let s = scene.to_str().unwrap();
        [
            "render",
            s,
            "-o",
            out,
            "--width",
            width,
            "--height",
            "768",
            "--spp",
            "16",
            "--band-rows",
            "16",
            "--resume",
            "-q",
        ]
        .map(str::to_owned)
        .to_vec()
    };
    let side = dir.path().join(".r.png.resume");
    let interrupt = |width: &str| {
        let started = std::time::SystemTime::now();
        let child = Command::new(env!("CARGO_BIN_EXE_bareray"))
            .args(args(&p("r.png"), width))
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Wait for this run's first record beyond the side file's 24-byte header, then interrupt.
        let written = |m: std::fs::Metadata| m.len() > 24 && m.modified().unwrap() > started;
        while !std::fs::metadata(&side).is_ok_and(written) {
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
        let out = child.wait_with_output().unwrap();
        assert_eq!(out.status.code(), Some(130), "{}", stderr(&out));
        assert!(stderr(&out).contains("interrupted; the finished rows are kept in"), "{}", stderr(&out));
        assert!(!dir.path().join("r.png").exists() && side.exists());
    };
    // A side file of another width, then the real one.
    interrupt("600");
    interrupt("1024");
    let kept = std::fs::metadata(&side).unwrap().len();
    let args = args(&p("r.png"), "1024");
    let run = bareray(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(!side.exists(), "the side file stays after the render");
    let mut plain = args.clone();
    plain[3] = p("plain.png");
    plain.retain(|a| a != "--resume");
    assert!(bareray(&plain.iter().map(String::as_str).collect::<Vec<_>>()).status.success());
    assert!(kept > 24);
    assert!(
        std::fs::read(p("r.png")).unwrap() == std::fs::read(p("plain.png")).unwrap(),
        "resumed image differs"
    );
}

/// `render -` reads the scene from standard input in the format --format names (and asks for it), `-o -`
/// writes PPM to standard output, the summary then going to standard error: the bytes of the file render.
#[test]
fn scenes_from_standard_input_and_ppm_to_standard_output() {
    use std::io::Write;
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/balls3.nff");
    let file = dir.path().join("f.ppm");
    let size = ["--width", "64", "--height", "48"];
    let run = bareray(
        &[&["render", scene.to_str().unwrap(), "-o", file.to_str().unwrap(), "-q"][..], &size].concat(),
    );
    assert!(run.status.success());
    let mut child = Command::new(env!("CARGO_BIN_EXE_bareray"))
        .args([&["render", "-", "--format", "nff", "-o", "-"][..], &size].concat())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(&std::fs::read(&scene).unwrap()).unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(out.stdout == std::fs::read(&file).unwrap(), "standard output differs from the file");
    assert!(stderr(&out).starts_with("<stdout>: 64x48"), "{}", stderr(&out));
    let run = bareray(&["render", "-", "-o", "-"]);
    assert_eq!(run.status.code(), Some(2));
    assert!(stderr(&run).contains("needs --format toml, nff, xyzr or f32r"), "{}", stderr(&run));
    let run = bareray(&["render", scene.to_str().unwrap(), "-o", "-", "--resume"]);
    assert_eq!(run.status.code(), Some(2));
}

/// TIFF holds the PNG's values (8 and 16 bits), JPEG stays close to them (PSNR above 30 dB on the
/// whitted scene), and a JPEG wider than its 16-bit size field is refused before tracing.
#[test]
fn tiff_and_jpeg_hold_the_pngs_values() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/whitted.toml");
    let render = |out: &str, more: &[&str]| {
        let mut args =
            vec!["render", scene.to_str().unwrap(), "-o", out, "--width", "80", "--height", "60", "-q"];
        args.extend(more);
        bareray(&args)
    };
    for (out, more) in [("a.png", &[][..]), ("b.tif", &[][..]), ("c.png", &["--bit-depth", "16"][..])] {
        assert!(render(&p(out), more).status.success());
    }
    assert!(render(&p("d.tiff"), &["--bit-depth", "16"]).status.success());
    assert!(render(&p("e.jpg"), &[]).status.success());
    let png = image::open(p("a.png")).unwrap();
    assert_eq!(image::open(p("b.tif")).unwrap().to_rgb8(), png.to_rgb8());
    assert_eq!(image::open(p("d.tiff")).unwrap().to_rgb16(), image::open(p("c.png")).unwrap().to_rgb16());
    let jpeg = image::open(p("e.jpg")).unwrap().to_rgb8();
    let squares: f64 = jpeg
        .as_raw()
        .iter()
        .zip(png.to_rgb8().as_raw())
        .map(|(&a, &b)| (f64::from(a) - f64::from(b)).powi(2))
        .sum();
    let psnr = 20.0 * (255.0 / (squares / jpeg.as_raw().len() as f64).sqrt()).log10();
    assert!(psnr > 30.0, "JPEG PSNR {psnr:.1} dB");
    let run =
        bareray(&["render", scene.to_str().unwrap(), "-o", &p("f.jpg"), "--width", "65536", "--height", "4"]);
    assert_eq!(run.status.code(), Some(1));
    assert!(stderr(&run).contains("at most 65535 pixels a side"), "{}", stderr(&run));
    assert!(!dir.path().join("f.jpg").exists());
}

/// `--postfilter lecture` (or `lecture-3x3`) renders what the scene key `postfilter = "lecture-3x3"` renders,
/// and `--postfilter none` takes a scene's postfilter away (what the scene without the key renders).
#[test]
fn postfilter_flag_is_the_scene_key() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let whitted = std::fs::read_to_string(root.join("scenes/whitted.toml")).unwrap();
    let mut keyed: toml::Table = whitted.parse().unwrap();
    keyed["render"].as_table_mut().unwrap().insert("postfilter".into(), "lecture-3x3".into());
    std::fs::write(p("keyed.toml"), toml::to_string(&keyed).unwrap()).unwrap();
    let run = |scene: &str, out: &str, more: &[&str]| {
        let args =
            [&["render", scene, "-o", out, "--width", "48", "--height", "36", "-q"][..], more].concat();
        assert!(bareray(&args).status.success(), "{args:?}");
        // Pixels, not bytes: the PNG names its scene file, which differs.
        image::open(out).unwrap().into_rgb8().into_raw()
    };
    let whitted = root.join("scenes/whitted.toml");
    let flag = run(whitted.to_str().unwrap(), &p("flag.png"), &["--postfilter", "lecture"]);
    let key = run(&p("keyed.toml"), &p("key.png"), &[]);
    let plain = run(whitted.to_str().unwrap(), &p("plain.png"), &[]);
    assert!(flag == key, "--postfilter lecture differs from the scene key");
    let spelled = run(whitted.to_str().unwrap(), &p("spelled.png"), &["--postfilter", "lecture-3x3"]);
    assert!(spelled == key, "--postfilter lecture-3x3, the key's spelling, differs from the scene key");
    assert!(flag != plain, "--postfilter lecture changed nothing");
    let none = run(&p("keyed.toml"), &p("none.png"), &["--postfilter", "none"]);
    assert!(none == plain, "--postfilter none left the scene's postfilter on");
}
