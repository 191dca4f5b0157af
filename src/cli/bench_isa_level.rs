//! The x86-64 levels `bareray bench --isa` runs builds for, and a build found for one.

use std::path::PathBuf;

/// The variable naming the directory that holds the per-ISA builds (`<level>/release/bareray` in it), as
/// `--isa-dir` does; the flag wins.
pub(super) const ISA_DIR_VAR: &str = "BARERAY_ISA_DIR";

/// An x86-64 micro-architecture level a build is compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Level {
    /// x86-64-v2: SSE4.2, no FMA (`mul_add` is the C library's `fmaf`, one lane at a time).
    V2,
    /// x86-64-v3: AVX2 and FMA (the default build).
    V3,
    /// x86-64-v4: AVX-512.
    V4,
}

impl Level {
    /// The short name, as `--isa` takes it and the build's directory is called: `v2`, `v3`, `v4`.
    pub(super) fn name(self) -> &'static str {
        match self {
            Level::V2 => "v2",
            Level::V3 => "v3",
            Level::V4 => "v4",
        }
    }

    /// The features a CPU needs to run a build for this level.
    pub(super) fn features(self) -> Vec<&'static str> {
        use crate::cpu::{X86_64_V2, X86_64_V3, X86_64_V4};
        let levels: &[&[&str]] = match self {
            Level::V2 => &[X86_64_V2],
            Level::V3 => &[X86_64_V2, X86_64_V3],
            Level::V4 => &[X86_64_V2, X86_64_V3, X86_64_V4],
        };
        levels.concat()
    }

    /// Whether `isa`, what a build's `bench` reports its kernels compiled for, is this level's.
    pub(super) fn kernels_match(self, isa: &str) -> bool {
        match self {
            Level::V2 => !isa.contains("avx"),
            Level::V3 => isa.starts_with("avx2"),
            Level::V4 => isa.starts_with("avx512"),
        }
    }
}

/// Parses one `--isa` level: `v2`, `v3`, `v4`, or the same with `x86-64-` in front.
pub(super) fn parse_level(s: &str) -> Result<Level, String> {
    let t = s.trim().to_ascii_lowercase();
    match t.strip_prefix("x86-64-").unwrap_or(&t) {
        "v2" => Ok(Level::V2),
        "v3" => Ok(Level::V3),
        "v4" => Ok(Level::V4),
        _ => Err(format!(
            "levels are v2 (SSE4.2), v3 (AVX2 and FMA) and v4 (AVX-512), as a comma list; got `{s}`"
        )),
    }
}

/// A build to run: its level and binary.
pub(super) struct Build {
    pub(super) level: Level,
    pub(super) path: PathBuf,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_parse_and_bad_ones_are_named() {
        assert_eq!(parse_level("v2"), Ok(Level::V2));
        assert_eq!(parse_level(" V3 "), Ok(Level::V3));
        assert_eq!(parse_level("x86-64-v4"), Ok(Level::V4));
        for bad in ["v5", "", "avx2", "x86-64"] {
            assert!(parse_level(bad).unwrap_err().contains(&format!("`{bad}`")), "{bad}");
        }
    }

    #[test]
    fn level_features_grow_with_the_level() {
        let (v2, v3, v4) = (Level::V2.features(), Level::V3.features(), Level::V4.features());
        assert!(v2.contains(&"sse4.2") && !v2.contains(&"fma"));
        assert!(v3.contains(&"fma") && v3.contains(&"avx2") && !v3.contains(&"avx512f"));
        assert!(v4.contains(&"avx512vl") && v2.iter().chain(&v3).all(|f| v4.contains(f)));
    }

    #[test]
    fn kernels_match_their_level() {
        assert!(Level::V2.kernels_match("sse2") && !Level::V2.kernels_match("avx2+fma"));
        assert!(Level::V3.kernels_match("avx2+fma") && !Level::V3.kernels_match("avx512f+fma"));
        assert!(Level::V4.kernels_match("avx512f+fma") && !Level::V4.kernels_match("avx2+fma"));
    }
}
