//! Scene files of a folder, for the tests that render every scene.

use std::path::{Path, PathBuf};

/// The scene files (TOML, NFF, xyzr) directly in `dir`, sorted.
pub fn scene_files(dir: &Path) -> Vec<PathBuf> {
    let mut all: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml" || e == "nff" || e == "xyzr"))
        .collect();
    all.sort();
    all
}
