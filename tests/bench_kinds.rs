//! `bareray bench`'s report per ray kind from the command line (its measurement is tested in
//! `library/bench_kinds.rs`).

use std::path::Path;

use crate::common::{bareray, stderr};

/// The command line: the table's "by ray kind" section and the JSON's `by_kind` field, whose kinds' rays
/// sum to the row's; `--by-kind false` and primary-only runs have neither.
#[test]
fn bench_reports_the_split_in_table_and_json() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/whitted.toml");
    let small = [scene.to_str().unwrap(), "--width", "32", "--height", "24", "--reps", "1", "--threads", "1"];
    let run = bareray(&[&["bench"], &small[..], &["--lanes", "scalar,8", "--json"]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    for line in String::from_utf8(run.stdout).unwrap().lines() {
        let row: serde_json::Value = serde_json::from_str(line).unwrap();
        let kinds = row["by_kind"]["kinds"].as_array().unwrap_or_else(|| panic!("{row}"));
        let names: Vec<&str> = kinds.iter().map(|k| k["kind"].as_str().unwrap()).collect();
        assert_eq!(names, ["camera", "shadow", "reflection", "refraction"], "{row}");
        let rays: u64 = kinds.iter().map(|k| k["rays"].as_u64().unwrap()).sum();
        assert_eq!(Some(rays), row["rays"].as_u64(), "{row}");
        for k in kinds {
            assert!(k["mrays_per_s"].as_f64().unwrap() > 0.0, "{k}");
            assert!(k["rays_per_prim_test"].as_f64().unwrap() >= 1.0, "{k}");
        }
    }
    let run = bareray(&[&["bench"], &small[..], &["--lanes", "1,16"]].concat());
    let table = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success() && table.contains("\nby ray kind"), "{table}");
    for kind in ["camera", "shadow", "reflection", "refraction", "rest"] {
        assert_eq!(table.lines().filter(|l| l.trim_start().starts_with(kind)).count(), 2, "{kind}: {table}");
    }
    for extra in [&["--by-kind", "false"][..], &["--primary-only"][..]] {
        let run = bareray(&[&["bench"], &small[..], &["--lanes", "1", "--json"], extra].concat());
        let text = String::from_utf8_lossy(&run.stdout);
        assert!(run.status.success() && !text.contains("by_kind"), "{extra:?}: {text}");
    }
}
