//! Which search structure a sphere field gets when the choice is left to bareray (`--accel auto`), and the
//! check before loading that refuses a field too large for either: both from the memory each structure
//! needs per sphere and the memory this process may use.

use std::fmt;

/// Peak bytes per sphere of reading a sphere list and building its BVH: the description's f64 spheres, the
/// SoA arrays, their reordered copy and the nodes, with a margin over the measured peaks (PERF.md, "Scale").
pub(crate) const BVH_BYTES_PER_SPHERE: u64 = 110;

/// Bytes per sphere of a mapped `.f32r` field in the particle tree: the 16-byte record (its page becomes
/// this process's own when the build reorders it) and the 4-byte key.
pub(crate) const PARTICLE_BYTES_PER_SPHERE: u64 = 20;

/// Bytes every render needs beside the spheres (image, threads' stacks, the program), so a field is not
/// planned to the last byte.
pub(crate) const RESERVE_BYTES: u64 = 256 << 20;

/// What `--accel auto` picks for a sphere field, and why.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum FieldChoice {
    /// The BVH fits.
    Bvh,
    /// The particle tree: asked for, or the BVH would not fit.
    Particles {
        /// True when chosen because the BVH would not fit.
        for_memory: bool,
    },
}

/// A sphere field larger than the memory allows, even in the particle tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TooLarge {
    /// The field's spheres.
    pub(crate) spheres: u64,
    /// The memory available, in bytes.
    pub(crate) available: u64,
    /// The largest field that fits.
    pub(crate) largest: u64,
}

impl fmt::Display for TooLarge {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} spheres need about {:.1} GB in the particle tree ({PARTICLE_BYTES_PER_SPHERE} bytes each, at \
             most 2^30 spheres), and {:.1} GB of memory is available: at most {} spheres fit",
            self.spheres,
            (self.spheres * PARTICLE_BYTES_PER_SPHERE + RESERVE_BYTES) as f64 / 1e9,
            self.available as f64 / 1e9,
            self.largest
        )
    }
}

impl std::error::Error for TooLarge {}

/// The structure for `spheres` spheres with `available` bytes of memory: the BVH when `particles` is not
/// asked for and the BVH fits, else the particle tree when it fits, else [`TooLarge`].
pub(crate) fn choose(spheres: u64, particles: bool, available: u64) -> Result<FieldChoice, TooLarge> {
    let fits =
        |per_sphere: u64| spheres.saturating_mul(per_sphere).saturating_add(RESERVE_BYTES) <= available;
    if !particles && fits(BVH_BYTES_PER_SPHERE) {
        return Ok(FieldChoice::Bvh);
    }
    if fits(PARTICLE_BYTES_PER_SPHERE) && spheres <= crate::accel::pkd::MAX_PARTICLES as u64 {
        return Ok(FieldChoice::Particles { for_memory: !particles });
    }
    let largest = (available.saturating_sub(RESERVE_BYTES) / PARTICLE_BYTES_PER_SPHERE)
        .min(crate::accel::pkd::MAX_PARTICLES as u64);
    Err(TooLarge { spheres, available, largest })
}

/// The memory this process may use: the kernel's `MemAvailable`, lowered to the cgroup's limit less its
/// usage where one is set (a container). `u64::MAX` where neither can be read.
pub fn available() -> u64 {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok().and_then(|text| {
        let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
        let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some(kb * 1024)
    });
    let read = |path: &str| std::fs::read_to_string(path).ok().and_then(|s| s.trim().parse::<u64>().ok());
    let cgroup = read("/sys/fs/cgroup/memory.max")
        .map(|max| max.saturating_sub(read("/sys/fs/cgroup/memory.current").unwrap_or(0)));
    [meminfo, cgroup].into_iter().flatten().min().unwrap_or(u64::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn picks_the_bvh_while_it_fits_then_the_tree_then_refuses() {
        let gb = 1u64 << 30;
        assert_eq!(choose(1_000_000, false, gb), Ok(FieldChoice::Bvh));
        assert_eq!(choose(1_000_000, true, gb), Ok(FieldChoice::Particles { for_memory: false }));
        assert_eq!(choose(20_000_000, false, gb), Ok(FieldChoice::Particles { for_memory: true }));
        let e = choose(100_000_000, false, gb).unwrap_err();
        assert_eq!(e.largest, (gb - RESERVE_BYTES) / PARTICLE_BYTES_PER_SPHERE);
        assert!(choose(e.largest, false, gb).is_ok() && choose(e.largest + 1, false, gb).is_err());
        assert!(e.to_string().contains(&format!("at most {} spheres fit", e.largest)), "{e}");
    }
}
