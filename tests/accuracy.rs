//! `bareray accuracy` from the command line (the twin's own tests are in `library/accuracy.rs`).

use std::process::Command;

/// `bareray accuracy --json` prints one JSON object with the documented keys, numbers where numbers belong;
/// a bad scene is an error naming the file and line, exit code 1, no panic.
#[test]
fn json_output_has_every_key() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/whitted.toml");
    let run = Command::new(env!("CARGO_BIN_EXE_bareray"))
        .args(["accuracy", scene, "--secondary", "--json", "--width", "80", "--lanes", "4", "--threads", "2"])
        .output()
        .expect("bareray runs");
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let text = String::from_utf8(run.stdout).expect("utf-8");
    assert_eq!(text.lines().count(), 1, "one line: {text}");
    let v: serde_json::Value = serde_json::from_str(&text).expect("valid JSON");
    for key in [
        "rays",
        "hit_miss_disagree",
        "id_disagree",
        "unexplained_disagree",
        "t_rel_err_p50",
        "t_rel_err_p99",
        "t_rel_err_max",
        "self_hits",
        "shadow_rays",
        "shadow_seen_from_eye",
        "shadow_disagree",
        "shadow_unexplained",
        "reflection_rays",
        "reflection_unexplained",
        "reflection_t_rel_err_p50",
        "reflection_t_rel_err_p99",
        "reflection_t_rel_err_max",
        "refraction_rays",
        "refraction_hits_agree",
        "refraction_tir_disagree",
        "refraction_unexplained",
        "refraction_self_hits",
        "refraction_t_rel_err_p99",
        "width",
        "height",
        "lanes",
        "k_graze",
        "k_tie",
    ] {
        assert!(v[key].is_number(), "{key}: {:?} in {text}", v[key]);
    }
    assert_eq!(v["width"], 80);
    assert_eq!(v["height"], 60);
    assert_eq!(v["lanes"], 4);
    assert_eq!(v["rays"], 80 * 60);
    assert!(v["scene"].as_str().is_some_and(|s| s.ends_with("whitted.toml")));
    assert!(v["examples"].is_array());

    // The scalar path: `"lanes":"scalar"`, and the same comparison as packets of 4 (the same bits).
    let balls = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/balls3.nff");
    let json = |lanes: &str| -> serde_json::Value {
        let run = Command::new(env!("CARGO_BIN_EXE_bareray"))
            .args([
                "accuracy",
                balls,
                "--secondary",
                "--json",
                "--width",
                "48",
                "--lanes",
                lanes,
                "--threads",
                "2",
            ])
            .output()
            .expect("bareray runs");
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
        serde_json::from_slice(&run.stdout).expect("valid JSON")
    };
    let (scalar, packets) = (json("scalar"), json("4"));
    assert_eq!(scalar["lanes"], "scalar");
    for key in ["rays", "id_disagree", "t_rel_err_max", "shadow_disagree", "reflection_t_rel_err_max"] {
        assert_eq!(scalar[key], packets[key], "{key}");
    }

    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "[camera]\neye = [0, 0]\n").unwrap();
    let run = Command::new(env!("CARGO_BIN_EXE_bareray"))
        .args(["accuracy", bad.to_str().unwrap()])
        .output()
        .expect("bareray runs");
    let err = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(err.contains("bad.toml:2"), "names file and line: {err}");
    assert!(!err.contains("panicked"), "{err}");
}
