//! Per-pixel sample positions that are not the same in every pixel: jittered strata and a rotated R2
//! low-discrepancy set. Each pixel's positions depend only on its coordinates and the sample index (a hash
//! seeds them), so tiles, threads and packet widths cannot change an image.

use crate::math::SplitMix64;

/// The random bits of pixel `(x, y)`'s sample `k`, stream `s` (0 and 1 for the two coordinates, more for
/// other uses): one splitmix64 step over the packed arguments, so neighbouring pixels and indices get
/// unrelated values.
pub fn pixel_hash(x: u32, y: u32, k: u32, s: u32) -> u64 {
    let packed = (u64::from(x) << 32 | u64::from(y)) ^ (u64::from(k) << 20 | u64::from(s)).rotate_left(45);
    SplitMix64::new(packed).next_u64()
}

/// A uniform number in [0, 1) with 24 random bits (exact in f32) from `pixel_hash`.
pub fn pixel_unit(x: u32, y: u32, k: u32, s: u32) -> f32 {
    (pixel_hash(x, y, k, s) >> 40) as f32 * (1.0 / 16_777_216.0)
}

/// Sample `k` of pixel `(x, y)` on an n×n jittered grid: a uniform position inside the k-th stratum (row by
/// row), in [0, 1)².
pub fn stratified(n: u32, x: u32, y: u32, k: u32) -> (f32, f32) {
    let (a, b) = (k % n, k / n);
    let step = 1.0 / n as f32;
    let jitter = |s: u32, cell: u32| ((cell as f32 + pixel_unit(x, y, k, s)) * step).min(ONE_BELOW);
    (jitter(0, a), jitter(1, b))
}

/// The largest f32 below 1: a position rounded up to 1 is clamped to it, so every sample stays in its pixel.
const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

/// The R2 sequence's steps (Roberts 2018): `1/g` and `1/g²` with `g` the plastic number, the real root of
/// `g³ = g + 1`, whose multiples mod 1 fill the square with low discrepancy for any count.
const R2_STEP: (f64, f64) = (0.754_877_666_246_692_8, 0.569_840_290_998_053_3);

/// Sample `k` of pixel `(x, y)` from the R2 sequence, shifted by a per-pixel random rotation
/// (Cranley–Patterson) so that pixels do not repeat one pattern: `frac(u + k·α)`, in [0, 1)².
pub fn r2(x: u32, y: u32, k: u32) -> (f32, f32) {
    let shift = |s: u32| f64::from(pixel_unit(x, y, 0, s));
    let step = |u: f64, a: f64| ((u + f64::from(k) * a).fract() as f32).min(ONE_BELOW);
    (step(shift(0), R2_STEP.0), step(shift(1), R2_STEP.1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn r2_steps_come_from_the_plastic_number() {
        let g = 1.324_717_957_244_746_f64;
        assert!((g * g * g - g - 1.0).abs() < 1e-14);
        assert!((R2_STEP.0 - 1.0 / g).abs() < 1e-15 && (R2_STEP.1 - 1.0 / (g * g)).abs() < 1e-15);
    }

    /// Every jittered sample lies in its own stratum, and the jitter is not the stratum centre.
    #[test]
    fn stratified_samples_stay_in_their_strata() {
        for n in [1, 2, 3, 8] {
            for (x, y) in [(0, 0), (5, 9), (1919, 1079)] {
                for k in 0..n * n {
                    let (u, v) = stratified(n, x, y, k);
                    let (a, b) = ((k % n) as f32 / n as f32, (k / n) as f32 / n as f32);
                    let step = 1.0 / n as f32;
                    assert!(u >= a && u < a + step && v >= b && v < b + step, "n {n} k {k}: {u} {v}");
                }
            }
        }
        let centres = (0..64).filter(|&k| {
            stratified(8, 3, 4, k) == ((k % 8) as f32 / 8.0 + 1.0 / 16.0, (k / 8) as f32 / 8.0 + 1.0 / 16.0)
        });
        assert_eq!(centres.count(), 0);
    }

    /// R2 points of one pixel spread over the square: every cell of a 4×4 grid gets one of 16 points within
    /// one, and different pixels get different rotations.
    #[test]
    fn r2_points_cover_the_pixel_and_differ_between_pixels() {
        let mut cells = [0u32; 16];
        for k in 0..64 {
            let (u, v) = r2(7, 11, k);
            assert!((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v));
            cells[(u * 4.0) as usize + 4 * (v * 4.0) as usize] += 1;
        }
        assert!(cells.iter().all(|&c| (2..=6).contains(&c)), "{cells:?}");
        assert_ne!(r2(7, 11, 0), r2(8, 11, 0));
        assert_eq!(r2(7, 11, 3), r2(7, 11, 3));
    }

    #[test]
    fn pixel_units_are_uniform_enough() {
        let n = 100_000;
        let mean = (0..n).map(|i| f64::from(pixel_unit(i % 317, i / 317, 2, 1))).sum::<f64>() / f64::from(n);
        assert!((mean - 0.5).abs() < 0.005, "{mean}");
    }
}
