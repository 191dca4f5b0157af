//! What a measurement ran on and was built with: the CPU, the instruction set the kernels were compiled
//! for, the cores, the build profile and the version.

use serde::Serialize;

/// What the numbers were measured on and built with.
#[derive(Serialize, Debug, Clone)]
pub struct Host {
    /// `model name` of /proc/cpuinfo, or "unknown".
    pub cpu: String,
    /// The SIMD instruction set the kernels were compiled for (`target_feature`s of this build).
    pub isa: &'static str,
    /// What one 16-lane packet is in that instruction set.
    pub lanes16: &'static str,
    /// `std::thread::available_parallelism`: the cores this process may run on.
    pub cores: usize,
    /// "release" or "debug" (debug assertions on).
    pub profile: &'static str,
    /// bareray's version.
    pub version: &'static str,
}

impl Host {
    /// This machine and this build.
    pub fn detect() -> Self {
        let cpu = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|text| {
                text.lines()
                    .find(|l| l.starts_with("model name"))
                    .and_then(|l| l.split_once(':'))
                    .map(|(_, v)| v.trim().to_owned())
            })
            .filter(|v| !v.is_empty())
            .unwrap_or_else(|| "unknown".to_owned());
        let (isa, lanes16) = isa();
        Host {
            cpu,
            isa,
            lanes16,
            cores: cores(),
            profile: if cfg!(debug_assertions) { "debug" } else { "release" },
            version: env!("CARGO_PKG_VERSION"),
        }
    }
}

/// The widest SIMD instruction set this build's kernels use (wide's f32x16 follows the target features),
/// and what 16 lanes are in it.
fn isa() -> (&'static str, &'static str) {
    let fma = cfg!(target_feature = "fma");
    if cfg!(target_feature = "avx512f") {
        (if fma { "avx512f+fma" } else { "avx512f" }, "one 512-bit AVX-512 register")
    } else if cfg!(target_feature = "avx2") {
        (if fma { "avx2+fma" } else { "avx2" }, "two 256-bit AVX2 registers")
    } else if cfg!(target_feature = "avx") {
        ("avx", "two 256-bit AVX registers")
    } else if cfg!(target_feature = "sse2") {
        ("sse2", "four 128-bit SSE registers")
    } else if cfg!(target_feature = "neon") {
        ("neon", "four 128-bit NEON registers")
    } else {
        ("none", "16 scalar values (no SIMD)")
    }
}

/// The cores this process may run on (1 when unknown).
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// The thread counts measured when none are asked for: 1 and every core, or 1 alone on a 1-core machine.
pub fn default_threads(cores: usize) -> Vec<usize> {
    if cores > 1 {
        vec![1, cores]
    } else {
        vec![1]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_threads_are_one_and_all_cores() {
        assert_eq!(default_threads(1), vec![1]);
        assert_eq!(default_threads(2), vec![1, 2]);
        assert_eq!(default_threads(64), vec![1, 64]);
    }

    #[test]
    fn isa_names_what_sixteen_lanes_are() {
        let (isa, lanes16) = isa();
        assert!(!isa.is_empty() && !lanes16.is_empty());
        if cfg!(target_feature = "avx512f") {
            assert!(lanes16.starts_with("one"));
        }
    }
}
