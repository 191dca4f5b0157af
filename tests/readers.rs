//! The readers and generators from the command line: `gen`, `convert` and reader errors as the binary
//! reports them (the readers themselves are tested in `library/readers.rs`).

use std::path::Path;

use bareray::io::generate::{flake_nff, FieldParams};

use crate::common::{bareray, stderr};

const VIEW: &str = "v\nfrom 0 0 -5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 0.01\nresolution 64 64\n";

#[test]
fn cli_generates_and_renders_fields_and_flakes() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_string_lossy().into_owned();
    let out = bareray(&["gen", "field", "--count", "1000", "-o", &path("f.xyzr")]);
    assert!(out.status.success(), "{}", stderr(&out));
    let mut want = Vec::new();
    FieldParams { count: 1000, ..Default::default() }.write_xyzr(&mut want).unwrap();
    assert_eq!(std::fs::read(path("f.xyzr")).unwrap(), want);
    let out = bareray(&["gen", "flake", "--level", "2", "-o", &path("b.nff")]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(std::fs::read_to_string(path("b.nff")).unwrap(), flake_nff(2).unwrap());
    for (scene, png) in [("f.xyzr", "f.png"), ("b.nff", "b.png")] {
        let out = bareray(&["render", &path(scene), "--width", "32", "-q", "-o", &path(png)]);
        assert!(out.status.success(), "{scene}: {}", stderr(&out));
        assert!(std::fs::metadata(path(png)).unwrap().len() > 0);
    }
}

#[test]
fn cli_reports_reader_errors_with_file_and_line_and_rejects_bad_generator_arguments() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("cone.nff");
    std::fs::write(&scene, format!("{VIEW}c\n0 0 0 1\n0 0 0 1\n")).unwrap();
    let out =
        bareray(&["render", &scene.to_string_lossy(), "-o", &dir.path().join("x.png").to_string_lossy()]);
    let err = stderr(&out);
    assert!(
        !out.status.success() && err.contains("cone.nff:8: cone base and apex are the same point"),
        "{err}"
    );
    let target = dir.path().join("never.xyzr").to_string_lossy().into_owned();
    for args in [
        &["gen", "field", "--count", "0", "-o", &target][..],
        &["gen", "field", "--count", "9", "--box", "0,0,0,1,1", "-o", &target],
        &["gen", "field", "--count", "9", "--rmin", "-1", "-o", &target],
        &["gen", "flake", "--level", "99", "-o", &target],
    ] {
        let out = bareray(args);
        assert!(!out.status.success(), "{args:?} must fail");
        assert!(stderr(&out).starts_with("error: "), "{args:?}");
    }
    assert!(!Path::new(&target).exists(), "failed runs leave no file");
}

/// `gen field -o f.f32r` writes the generator's binary file, `convert` turns the text list into the same
/// bytes and back into a list of the same values, and `render` and `bench` read it; a broken file or a
/// wrong input is an error naming the file.
#[test]
fn cli_writes_converts_and_reads_f32r_fields() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_string_lossy().into_owned();
    let ok = |args: &[&str]| {
        let out = bareray(args);
        assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    };
    ok(&["gen", "field", "--count", "3000", "--seed", "5", "-o", &path("f.f32r")]);
    ok(&["gen", "field", "--count", "3000", "--seed", "5", "-o", &path("f.xyzr")]);
    let mut want = Vec::new();
    FieldParams { count: 3000, seed: 5, ..Default::default() }.write_f32r(&mut want).unwrap();
    assert_eq!(std::fs::read(path("f.f32r")).unwrap(), want);
    ok(&["convert", &path("f.xyzr"), "-o", &path("c.f32r"), "--threads", "1"]);
    assert_eq!(std::fs::read(path("c.f32r")).unwrap(), want);
    ok(&["convert", &path("f.f32r"), "-o", &path("back.xyzr")]);
    // The text holds the binary file's values: both read as the same f32 spheres.
    let values = |name: &str| -> Vec<[f32; 4]> {
        let scene = bareray::io::load(Path::new(&path(name))).unwrap();
        scene
            .spheres
            .iter()
            .map(|s| [s.center.x, s.center.y, s.center.z, s.radius].map(|v| v as f32))
            .collect()
    };
    assert_eq!(values("back.xyzr"), values("f.f32r"));
    ok(&["render", &path("f.f32r"), "--width", "32", "-q", "-o", &path("f.png"), "--threads", "1"]);
    let out = bareray(&[
        "bench",
        &path("f.f32r"),
        "--primary-only",
        "--width",
        "32",
        "--height",
        "32",
        "--reps",
        "1",
        "--threads",
        "1",
    ]);
    assert!(
        out.status.success() && String::from_utf8_lossy(&out.stdout).contains("3000 spheres"),
        "{}",
        stderr(&out)
    );

    std::fs::write(path("short.f32r"), &want[..want.len() - 1]).unwrap();
    std::fs::write(path("text.f32r"), std::fs::read(path("f.xyzr")).unwrap()).unwrap();
    for (file, message) in [
        ("short.f32r", "short.f32r: the file ends inside record 2999 (byte 48000)"),
        ("text.f32r", "text.f32r: not an .f32r sphere list"),
    ] {
        for (cmd, output) in [("render", "never.png"), ("convert", "never.xyzr")] {
            let out = bareray(&[cmd, &path(file), "-o", &path(output)]);
            assert_eq!(out.status.code(), Some(1), "{cmd} {file}: {}", stderr(&out));
            assert!(stderr(&out).contains(message), "{cmd} {file}: {}", stderr(&out));
        }
    }
    for args in [
        &["convert", &path("f.xyzr"), "-o", &path("never.nff")][..],
        &["convert", &path("b.nff"), "-o", &path("never.f32r")],
        &["gen", "field", "--count", "5e9", "-o", &path("never.f32r")],
    ] {
        let out = bareray(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
    }
    for never in ["never.png", "never.xyzr", "never.f32r", "never.nff"] {
        assert!(!dir.path().join(never).exists(), "{never}");
    }
}
