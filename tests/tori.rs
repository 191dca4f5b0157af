//! Tori from the command line: the same bits at every width and thread count, and scene errors with the
//! file and line (the kernel and its twin are tested in `library/tori.rs`).

use std::process::Command;

fn bareray() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bareray"))
}

#[test]
fn bad_tori_name_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("major_radius = 1.0\nminor_radius = 1.0\n", "below major_radius"),
        ("major_radius = 1.0\nminor_radius = -0.5\n", "minor_radius"),
        ("major_radius = 0.0\nminor_radius = 0.5\n", "major_radius must be positive"),
        ("axis = [0, 0, 0]\nmajor_radius = 1.0\nminor_radius = 0.5\n", "axis"),
        (
            "major_radius = 1.0\nminor_radius = 0.5\ntransform = [{ scale = [1, 2, 1] }]\n",
            "rotate, translate and scale uniformly",
        ),
        ("major_radius = 1.0\nminor_radius = 0.5\nmaterial = \"none\"\n", "unknown material"),
        ("major_radius = 1.0\nminor_radius = 0.5\nwobble = 1\n", "unknown field"),
    ];
    for (body, want) in cases {
        let path = dir.path().join("t.toml");
        std::fs::write(
            &path,
            format!("[[lights]]\nposition = [0, 5, 0]\n\n[[tori]]\ncenter = [0, 0, 5]\n{body}"),
        )
        .unwrap();
        let out = bareray()
            .args(["render", path.to_str().unwrap(), "-o"])
            .arg(dir.path().join("o.png"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{body}: {err}");
        assert!(err.contains("t.toml:") && err.contains(want), "{body}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(!dir.path().join("o.png").exists());
    }
}

#[test]
fn tori_render_the_same_bits_at_every_width_and_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/stress/tori.toml");
    let mut images = Vec::new();
    for (lanes, threads) in [("1", "1"), ("4", "2"), ("8", "1"), ("16", "2"), ("scalar", "1")] {
        let out = dir.path().join(format!("l{lanes}-t{threads}.ppm"));
        let run = bareray()
            .args(["render", scene, "--lanes", lanes, "--threads", threads, "-o"])
            .arg(&out)
            .output()
            .unwrap();
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
        images.push((lanes, std::fs::read(&out).unwrap()));
    }
    let (_, first) = &images[0];
    for (lanes, img) in &images {
        assert!(img == first, "lanes {lanes} differ from lanes 1");
    }
    // The image shows tori: some pixels differ from the background's.
    assert!(first.len() > 128 * 96 * 3);
}
