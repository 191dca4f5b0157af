//! Measuring renders, as `bareray bench` reports them: repeated timed runs of one setting (`measure`) and
//! the split of a render by ray kind ([`profile()`]).
//!
//! Times come from runs with every probe off. The per-kind figures come from two extra runs: one with the
//! work counters on (tests and live rays per kind), one that reads the time-stamp counter around each
//! geometry query (time per kind, the probe's own ticks taken off); the timed run's shares are then
//! applied to the median of the clean runs.

mod host;
mod profile;
mod report;

pub use host::{cores, default_threads, Host};
#[cfg(test)]
pub(crate) use profile::KindProfile;
pub use profile::{profile, Profile};
pub use report::{write_kind_table, ByKind, KindRow};

use crate::compile::Scene;
use crate::film::Image;
use crate::render::{fnv1a, render_lanes, trace_primary_lanes, PrimaryHits};

/// What `measure` found for one setting.
#[derive(Clone, Debug)]
pub struct Measured {
    /// Rays traced per run.
    pub rays: u64,
    /// Median seconds of the timed runs.
    pub seconds: f64,
    /// Fastest run.
    pub min_s: f64,
    /// Slowest run.
    pub max_s: f64,
    /// FNV-1a 64 of the image (or of the primary hits' depths and ids).
    pub checksum: u64,
}

impl Measured {
    /// Millions of rays per second, from the median.
    pub fn mrays_per_s(&self) -> f64 {
        self.rays as f64 / self.seconds / 1e6
    }
}

/// What `measure` traces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Trace {
    /// The whole render: camera rays and everything their shading traces.
    Render,
    /// One camera ray per pixel centre to its closest hit, nothing else.
    PrimaryOnly,
}

/// Minimum, median and maximum of `reps` timed runs of `scene` at `lanes` rays per packet on `pool`,
/// after one untimed warm-up. The checksum is taken from the warm-up and from the last run, which must
/// agree (every path is deterministic; an error says which run differed); the runs between skip it, since
/// hashing a frame costs about as long as tracing a small field. The scalar path is `lanes` 1 on a scene
/// whose geometry walks its binary trees ([`crate::accel::Geometry::set_scalar_walk`]).
pub(crate) fn measure(
    scene: &Scene,
    trace: Trace,
    lanes: usize,
    pool: &rayon::ThreadPool,
    reps: u32,
) -> Result<Measured, String> {
    let mut times = Vec::with_capacity(reps as usize);
    let (mut rays, mut checksum) = (0, None);
    // One frame for every repetition of the primary rays, as the peer harnesses reuse theirs.
    let mut frame =
        (trace == Trace::PrimaryOnly).then(|| PrimaryHits::new(scene.camera.width, scene.camera.height));
    for rep in 0..=reps.max(1) {
        let hashed = rep == 0 || rep == reps.max(1);
        let (seconds, sum) = if let Some(hits) = &mut frame {
            trace_primary_lanes(scene, lanes, pool, hits);
            rays = hits.t.len() as u64;
            (hits.seconds, hashed.then(|| hits.checksum(scene)))
        } else {
            let r = render_lanes(scene, lanes, pool, &());
            rays = r.counts.total();
            (r.seconds, hashed.then(|| image_checksum(&r.image)))
        };
        match (checksum, sum) {
            (Some(first), Some(last)) if first != last => {
                return Err(format!(
                    "the last run's checksum {last:016x} differs from the warm-up's {first:016x}"
                ))
            }
            (None, sum) => checksum = sum,
            _ => {}
        }
        if rep > 0 {
            times.push(seconds);
        }
    }
    let checksum = checksum.expect("the warm-up run is hashed");
    let (min_s, seconds, max_s) = min_median_max(&times);
    Ok(Measured { rays, seconds, min_s, max_s, checksum })
}

/// The smallest, the median (the upper one of an even count) and the largest of `values`, which must not be
/// empty.
pub fn min_median_max(values: &[f64]) -> (f64, f64, f64) {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    (v[0], v[v.len() / 2], v[v.len() - 1])
}

/// What [`measure_setting`] found: the timed runs and, when asked, the render split by ray kind.
#[derive(Clone, Debug)]
pub struct Setting {
    /// The timed runs.
    pub measured: Measured,
    /// The split by ray kind ([`profile()`]), whose runs gave the timed runs' checksum.
    pub kinds: Option<Profile>,
}

/// `measure`s `scene` at `lanes` rays per packet, on the scalar path when `scalar` (the geometry then
/// walks its binary trees, which the scene must have been compiled with), and with `split` also
/// [`profile()`]s it, checking that the probed runs traced the timed runs' bits.
pub fn measure_setting(
    scene: &mut Scene,
    trace: Trace,
    (lanes, scalar): (usize, bool),
    pool: &rayon::ThreadPool,
    reps: u32,
    split: bool,
) -> Result<Setting, String> {
    scene.geometry.set_scalar_walk(scalar);
    let measured = measure(scene, trace, lanes, pool, reps)?;
    let kinds = split.then(|| profile(scene, lanes, pool));
    if let Some(changed) = kinds.as_ref().and_then(|p| p.checksums.iter().find(|&&c| c != measured.checksum))
    {
        return Err(format!(
            "a probed run's checksum {changed:016x} differs from the timed runs' {:016x}",
            measured.checksum
        ));
    }
    Ok(Setting { measured, kinds })
}

/// FNV-1a 64 over the image's f32 bits, row-major.
pub(crate) fn image_checksum(img: &Image) -> u64 {
    fnv1a(img.pixels.iter().flat_map(|p| [p.x, p.y, p.z]).flat_map(|v| v.to_bits().to_le_bytes()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn min_median_max_of_odd_and_single_counts() {
        assert_eq!(min_median_max(&[3.0, 1.0, 2.0]), (1.0, 2.0, 3.0));
        assert_eq!(min_median_max(&[5.0]), (5.0, 5.0, 5.0));
        assert_eq!(min_median_max(&[4.0, 1.0]), (1.0, 4.0, 4.0));
    }
}
