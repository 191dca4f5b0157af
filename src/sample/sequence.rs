//! Per-pixel sample positions that are not the same in every pixel: jittered strata, a rotated R2
//! low-discrepancy set and an Owen-scrambled Sobol' net. Each pixel's positions depend only on its coordinates and the sample index (a hash
//! seeds them), so tiles, threads and packet widths cannot change an image.

use crate::math::SplitMix64;

/// The random bits of pixel `(x, y)`'s sample `k`, stream `s` (0 and 1 for the two coordinates, more for
/// other uses): one splitmix64 step over the packed arguments, so neighbouring pixels and indices get
/// unrelated values.
pub(crate) fn pixel_hash(x: u32, y: u32, k: u32, s: u32) -> u64 {
    let packed = (u64::from(x) << 32 | u64::from(y)) ^ (u64::from(k) << 20 | u64::from(s)).rotate_left(45);
    SplitMix64::new(packed).next_u64()
}

/// A uniform number in [0, 1) with 24 random bits (exact in f32) from `pixel_hash`.
pub(crate) fn pixel_unit(x: u32, y: u32, k: u32, s: u32) -> f32 {
    (pixel_hash(x, y, k, s) >> 40) as f32 * (1.0 / 16_777_216.0)
}

/// Sample `k` of pixel `(x, y)` on an n×n jittered grid: a uniform position inside the k-th stratum (row by
/// row), in [0, 1)².
pub(crate) fn stratified(n: u32, x: u32, y: u32, k: u32) -> (f32, f32) {
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
pub(crate) fn r2(x: u32, y: u32, k: u32) -> (f32, f32) {
    let shift = |s: u32| f64::from(pixel_unit(x, y, 0, s));
    let step = |u: f64, a: f64| ((u + f64::from(k) * a).fract() as f32).min(ONE_BELOW);
    (step(shift(0), R2_STEP.0), step(shift(1), R2_STEP.1))
}

/// Bits of a sample coordinate that the scramble randomises and [`sobol`] keeps: 24, all an f32 holds in
/// [0, 1). The bits below would not reach the f32; Owen scrambling them would only make them uniform noise.
const SOBOL_BITS: u32 = 24;

/// Point `k` of the first two dimensions of the Sobol' sequence, unscrambled, as 32-bit binary fractions
/// (value · 2³²): the van der Corput radical inverse in base 2 (`k`'s bits mirrored about the binary point)
/// and the second Sobol' dimension, whose generator matrix is Pascal's triangle mod 2 (bit `r` of column
/// `i`, counted from the top, is `C(i, r)` mod 2; by Lucas's theorem it is odd exactly when the bits of `r`
/// are a subset of those of `i`). Together they are a (0, 2)-sequence in base 2: each aligned block of 2^m
/// points, the first one included, is a (0, m, 2)-net.
pub(crate) fn sobol_point(k: u32) -> (u32, u32) {
    let (mut second, mut bits) = (0u32, k);
    while bits != 0 {
        second ^= SOBOL_PASCAL[bits.trailing_zeros() as usize];
        bits &= bits - 1;
    }
    (k.reverse_bits(), second)
}

/// The columns of the second Sobol' dimension's generator matrix (see [`sobol_point`]), column `i` as a
/// 32-bit fraction: bit `31 − r` set when `r & i == r`.
const SOBOL_PASCAL: [u32; 32] = {
    let mut columns = [0u32; 32];
    let mut i = 0;
    while i < 32 {
        let mut r = 0;
        while r < 32 {
            if r & i == r {
                columns[i] |= 1 << (31 - r);
            }
            r += 1;
        }
        i += 1;
    }
    columns
};

/// Owen's nested uniform scramble of the 32-bit fraction `v` under `seed`, on its top 24 bits
/// (the rest are returned as 0). Every node of the binary tree of dyadic intervals gets its own random
/// flip: bit `d` (from the top) of the result is bit `d` of `v` XOR the flip of the node `v`'s top `d` bits
/// name. Points sharing an interval of width 2^−d stay in one (possibly swapped) interval of that width, so
/// a net stays a net; each point on its own becomes uniform on [0, 1). The flips depend on `v`'s own bits,
/// not on earlier flips.
///
/// The tree is cut into subtrees six levels deep (levels 0–5, 6–11, 12–17, 18–23): the 63 nodes of one
/// subtree take their flips from the bits of one splitmix64 step over the seed XOR the subtree root's heap
/// index (`2^top + prefix`, distinct for every root), node `2^r + q` (relative depth `r`, the next `r` bits
/// `q`) from bit `2^r + q`. So every node's flip is its own random bit, at four hashes a coordinate.
pub(crate) fn owen_scramble(v: u32, seed: u64) -> u32 {
    const _: () = assert!(SOBOL_BITS == 4 * 6, "four subtrees of six levels");
    let mut flips = 0u32;
    for top in [0, 6, 12, 18] {
        // The root's prefix (`top` bits; none for the first subtree) and the subtree's six bits of `v`.
        let root = (1u64 << top) | u64::from(v) >> (32 - top);
        let chunk = v >> (26 - top) & 63;
        let bits = SplitMix64::new(seed ^ root).next_u64();
        let mut local = 0u32;
        for r in 0..6 {
            let node = (1 << r) | chunk >> (6 - r);
            local |= ((bits >> node) as u32 & 1) << (5 - r);
        }
        flips |= local << (26 - top);
    }
    (v ^ flips) & !(u32::MAX >> SOBOL_BITS)
}

/// Sample `k` of pixel `(x, y)` from the Owen-scrambled Sobol' sequence ([`sobol_point`] then
/// [`owen_scramble`]), in [0, 1)². Each coordinate has its own scramble seeded by the pixel (two
/// [`pixel_hash`] streams), so pixels get independent, decorrelated point sets. The first 2^m samples of
/// every pixel form a (0, m, 2)-net in base 2: each of the 2^m elementary intervals of area 2^−m (for every
/// split `2^−i × 2^−(m−i)`) holds exactly one. Other counts are a prefix of the next power of two's net and
/// keep low discrepancy without that guarantee.
pub(crate) fn sobol(x: u32, y: u32, k: u32) -> (f32, f32) {
    let (a, b) = sobol_point(k);
    let unit = |v: u32| (v >> (32 - SOBOL_BITS)) as f32 * (1.0 / (1u32 << SOBOL_BITS) as f32);
    let (seed_u, seed_v) = (pixel_hash(x, y, 0, SOBOL_STREAM), pixel_hash(x, y, 0, SOBOL_STREAM + 1));
    (unit(owen_scramble(a, seed_u)), unit(owen_scramble(b, seed_v)))
}

/// The [`pixel_hash`] streams of the Sobol' scrambles' seeds (this and the next): apart from the streams
/// the jitter and the R2 rotation use (0 and 1).
const SOBOL_STREAM: u32 = 2;

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

    /// The unscrambled points against values worked by hand: van der Corput 0, ½, ¼, ¾, ⅛, …, and the second
    /// dimension from the columns ½, ¾, ⅝ (0.1, 0.11, 0.101 in binary) XORed by k's bits.
    #[test]
    fn sobol_points_are_the_first_two_dimensions() {
        let unit = |v: u32| f64::from(v) / 4_294_967_296.0;
        let first: Vec<(f64, f64)> = (0..8).map(sobol_point).map(|(a, b)| (unit(a), unit(b))).collect();
        let vdc = [0.0, 0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875];
        let second = [0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875];
        assert_eq!(first, vdc.into_iter().zip(second).collect::<Vec<_>>());
        assert_eq!(SOBOL_PASCAL[0], 1 << 31);
        for i in 1..32 {
            assert_eq!(SOBOL_PASCAL[i], SOBOL_PASCAL[i - 1] ^ (SOBOL_PASCAL[i - 1] >> 1), "column {i}");
        }
    }

    /// Whether points `p` form a (0, m, 2)-net in base 2 with `p.len() == 2^m`: for each split i + j = m,
    /// every 2^−i × 2^−j box holds exactly one point.
    fn is_net(p: &[(f32, f32)]) -> bool {
        let m = p.len().trailing_zeros();
        assert_eq!(p.len(), 1 << m);
        (0..=m).all(|i| {
            let mut cells = vec![0u32; p.len()];
            for &(u, v) in p {
                let (a, b) = ((u * (1u32 << i) as f32) as usize, (v * (1u32 << (m - i)) as f32) as usize);
                cells[a << (m - i) | b] += 1;
            }
            cells.iter().all(|&c| c == 1)
        })
    }

    /// The first 2^m samples of a pixel, m = 0..=8, form a (0, m, 2)-net, in pixels near and far from the
    /// origin; the same counts of the R2 and jittered patterns (which have no such property) are not all nets,
    /// so the check can fail.
    #[test]
    fn sobol_prefixes_are_nets() {
        for (x, y) in [(0, 0), (1, 0), (0, 1), (37, 411), (1919, 1079), (65_535, 3), (u32::MAX, u32::MAX)] {
            let points: Vec<(f32, f32)> = (0..256).map(|k| sobol(x, y, k)).collect();
            assert!(points.iter().all(|&(u, v)| (0.0..1.0).contains(&u) && (0.0..1.0).contains(&v)));
            for m in 0..=8 {
                assert!(is_net(&points[..1 << m]), "pixel ({x}, {y}), 2^{m} points");
            }
            // Every aligned block of 16, not only the first, is a net: a (0, 2)-sequence.
            assert!(points.chunks(16).all(is_net), "pixel ({x}, {y}): blocks of 16");
        }
        let r2: Vec<(f32, f32)> = (0..64).map(|k| r2(5, 6, k)).collect();
        assert!(!is_net(&r2));
        let jitter: Vec<(f32, f32)> = (0..16).map(|k| stratified(4, 5, 6, k)).collect();
        assert!(!is_net(&jitter));
    }

    /// The scramble is a different random permutation in every pixel and for each coordinate: the first
    /// point of 4096 pixels is spread uniformly (each of 16 bins of either coordinate within a few standard
    /// deviations of 256), neighbouring pixels' first points are uncorrelated, and no two pixels share their
    /// point sets.
    #[test]
    fn sobol_scrambles_differ_between_pixels() {
        let first: Vec<(f32, f32)> = (0..4096).map(|i| sobol(i % 64, i / 64, 0)).collect();
        for coord in [0, 1] {
            let mut bins = [0u32; 16];
            for p in &first {
                bins[([p.0, p.1][coord] * 16.0) as usize] += 1;
            }
            assert!(bins.iter().all(|&b| (196..=316).contains(&b)), "coordinate {coord}: {bins:?}");
        }
        let corr = |a: &[f64], b: &[f64]| {
            let n = a.len() as f64;
            let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
            let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
            let var = |v: &[f64], m: f64| v.iter().map(|x| (x - m) * (x - m)).sum::<f64>();
            cov / (var(a, ma) * var(b, mb)).sqrt()
        };
        let u: Vec<f64> = first.iter().map(|p| f64::from(p.0)).collect();
        let v: Vec<f64> = first.iter().map(|p| f64::from(p.1)).collect();
        // Left neighbours within a row, and the two coordinates of one pixel: |r| < 4/√4096.
        let (left, right): (Vec<f64>, Vec<f64>) =
            (0..4096).filter(|i| i % 64 != 63).map(|i| (u[i], u[i + 1])).unzip();
        assert!(corr(&left, &right).abs() < 0.0625, "{}", corr(&left, &right));
        assert!(corr(&u, &v).abs() < 0.0625, "{}", corr(&u, &v));
        let mut sets: Vec<Vec<u32>> = (0..256)
            .map(|i| {
                (0..4).flat_map(|k| <[f32; 2]>::from(sobol(i % 16, i / 16, k))).map(f32::to_bits).collect()
            })
            .collect();
        sets.sort();
        sets.dedup();
        assert_eq!(sets.len(), 256);
        assert_eq!(sobol(7, 11, 5), sobol(7, 11, 5));
    }

    /// Owen's scramble flips each level by its node: points in one dyadic interval stay together, the
    /// mapping is a bijection on the kept bits, and over many seeds each level flips about half the time.
    #[test]
    fn owen_scramble_is_a_nested_permutation() {
        let seed = 0x1234_5678_9abc_def0;
        let top = |v: u32, d: u32| v.checked_shr(32 - d).unwrap_or(0);
        let mut images: Vec<u32> = (0..4096u32).map(|i| owen_scramble(i << 20, seed)).collect();
        for d in 0..=12 {
            for i in 0..4096u32 {
                for j in [i ^ 1, i ^ 0x40, i ^ 0x800] {
                    if top(i << 20, d) == top(j << 20, d) {
                        let (a, b) = (owen_scramble(i << 20, seed), owen_scramble(j << 20, seed));
                        assert_eq!(top(a, d), top(b, d), "level {d}: {i} and {j} split");
                    }
                }
            }
        }
        images.iter_mut().for_each(|v| *v >>= 20);
        images.sort();
        assert_eq!(images, (0..4096).collect::<Vec<_>>());
        // Each level flips about half the time, and a node's flip is independent of its sibling's (the
        // sibling of 0's node at level d is the node of 2^−d) and of its parent's.
        let flip = |v: u32, d: u32, s: u64| owen_scramble(v, s * 0x9E37) >> (31 - d) & 1;
        for d in 0..SOBOL_BITS {
            let flips = (0..2000u64).filter(|&s| flip(0, d, s) == 1).count();
            assert!((900..=1100).contains(&flips), "level {d}: {flips} of 2000");
            if d > 0 {
                let sibling = (0..2000u64).filter(|&s| flip(0, d, s) == flip(1 << (32 - d), d, s)).count();
                let parent = (0..2000u64).filter(|&s| flip(0, d, s) == flip(0, d - 1, s)).count();
                assert!((900..=1100).contains(&sibling), "level {d}: siblings agree {sibling} of 2000");
                assert!((900..=1100).contains(&parent), "level {d}: parent agrees {parent} of 2000");
            }
        }
    }

    #[test]
    fn pixel_units_are_uniform_enough() {
        let n = 100_000;
        let mean = (0..n).map(|i| f64::from(pixel_unit(i % 317, i / 317, 2, 1))).sum::<f64>() / f64::from(n);
        assert!((mean - 0.5).abs() < 0.005, "{mean}");
    }
}
