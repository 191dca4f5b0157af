//! Linear values to 8-bit codes: the sRGB curve (by table, bit for bit the formula) and the linear transfer.

use image::RgbImage;

use crate::film::Image;
use crate::math::Rgb;
use crate::scene::desc::Transfer;

/// Linear to sRGB-encoded 8-bit, clamped: the definition, one `powf` per value. [`srgb8`] gives the same
/// bits from a table.
pub(crate) fn srgb8_formula(linear: f32) -> u8 {
    let c = if linear.is_nan() { 0.0 } else { linear.clamp(0.0, 1.0) };
    let s = if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

/// Linear to sRGB-encoded 8-bit, clamped: the sRGB formula (`srgb8_formula`) by table, bit for bit (checked
/// over every f32 in [0, 1] by a test). The table took a large share off an image's write time
/// (docs/perf-log/2026-11.md, "Exact table-driven sRGB encoding").
pub fn srgb8(linear: f32) -> u8 {
    SrgbTable::get().encode(linear)
}

/// Buckets of equal width over [0, 1]: the curve's steepest slope is 12.92·255 ≈ 3295 codes per unit, so
/// a bucket 1/4096 wide holds at most one code boundary (checked when the table is built).
const SRGB_BUCKETS: usize = 4096;

/// [`srgb8_formula`], which never decreases, per bucket: `first[b]` is its code at the bucket's start and
/// `next[b]` the smallest f32 it maps to the code above (+inf past 255), so a value in bucket b encodes to
/// `first[b]`, plus one from `next[b]` on.
struct SrgbTable {
    first: [u8; SRGB_BUCKETS],
    next: [f32; SRGB_BUCKETS],
}

impl SrgbTable {
    /// The table, built on first use (about 12 000 `powf`, well under a millisecond).
    fn get() -> &'static Self {
        static TABLE: std::sync::OnceLock<SrgbTable> = std::sync::OnceLock::new();
        TABLE.get_or_init(Self::new)
    }

    fn new() -> Self {
        // threshold[k]: the smallest f32 in [0, 1] encoded as k or above, by bisection over the bit
        // patterns of [0, 1], which order like the values.
        let mut threshold = [f32::INFINITY; 257];
        threshold[0] = 0.0;
        for (k, t) in threshold.iter_mut().enumerate().take(256).skip(1) {
            let (mut lo, mut hi) = (0u32, 1.0f32.to_bits());
            while hi - lo > 1 {
                let mid = lo + (hi - lo) / 2;
                if usize::from(srgb8_formula(f32::from_bits(mid))) >= k {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            *t = f32::from_bits(hi);
        }
        let start = |b: usize| b as f32 / SRGB_BUCKETS as f32;
        let first: [u8; SRGB_BUCKETS] = std::array::from_fn(|b| srgb8_formula(start(b)));
        let next = std::array::from_fn(|b| {
            let code = usize::from(first[b]);
            let after_next = threshold.get(code + 2).copied().unwrap_or(f32::INFINITY);
            assert!(after_next >= start(b + 1), "two sRGB code boundaries in bucket {b}");
            threshold[code + 1]
        });
        Self { first, next }
    }

    /// [`SrgbTable::encode`] of 8 values into `out`: the clamp and the bucket in SIMD (the scalar rounding:
    /// NaN to 0, then max and min, then an exact product and truncation), the look-ups per value. Measured
    /// against the scalar encode: docs/perf-log/2026-11.md, "Kept" (sRGB conversion 8 values at
    /// a time).
    #[inline(always)]
    fn encode8(&self, values: [f32; 8], out: &mut [u8]) {
        use wide::{f32x8, i32x8};
        let v = f32x8::from(values);
        let (zero, one) = (f32x8::splat(0.0), f32x8::splat(1.0));
        let c = v.is_nan().select(zero, v.fast_max(zero).fast_min(one));
        let bucket = (c * f32x8::splat(SRGB_BUCKETS as f32))
            .fast_trunc_int()
            .min(i32x8::splat(SRGB_BUCKETS as i32 - 1));
        let (c, bucket) = (c.to_array(), bucket.to_array());
        for ((o, c), b) in out.iter_mut().zip(c).zip(bucket) {
            // The mask keeps the index in range for the compiler (the bucket already is).
            let b = b as usize & (SRGB_BUCKETS - 1);
            *o = self.first[b] + u8::from(c >= self.next[b]);
        }
    }

    #[inline(always)]
    fn encode(&self, linear: f32) -> u8 {
        let c = if linear.is_nan() { 0.0 } else { linear.clamp(0.0, 1.0) };
        // c·4096 is exact (a power of two), so c lies in bucket b's [b, b + 1)/4096 (1.0 in the last).
        let b = ((c * SRGB_BUCKETS as f32) as usize).min(SRGB_BUCKETS - 1);
        self.first[b] + u8::from(c >= self.next[b])
    }
}

/// One row of pixels as 8-bit R, G, B (3 bytes per pixel in `out`) under `transfer`: [`srgb8`] by table or
/// [`linear8`], 8 pixels (24 values) per step (a fixed-size step the compiler turns into vector code).
pub(super) fn encode8_row(row: &[Rgb], transfer: Transfer, out: &mut [u8]) {
    let table = (transfer == Transfer::Srgb).then(SrgbTable::get);
    let (pixels, rest) = row.split_at(row.len() - row.len() % 8);
    for (o, p) in out.chunks_exact_mut(24).zip(pixels.chunks_exact(8)) {
        let mut values = [0.0f32; 24];
        for (v, q) in values.chunks_exact_mut(3).zip(p) {
            v.copy_from_slice(&[q.x, q.y, q.z]);
        }
        match table {
            Some(table) => {
                for (o, v) in o.chunks_exact_mut(8).zip(values.chunks_exact(8)) {
                    table.encode8(v.try_into().expect("8 values"), o);
                }
            }
            None => linear8_step(&values, o.try_into().expect("24 bytes")),
        }
    }
    let encode = |v: f32| table.map_or_else(|| linear8(v), |t| t.encode(v));
    for (o, p) in out[3 * pixels.len()..].chunks_exact_mut(3).zip(rest) {
        o.copy_from_slice(&[encode(p.x), encode(p.y), encode(p.z)]);
    }
}

/// [`linear8`] of 24 values, eight to a vector: the same operations in the same order (NaN to 0, the
/// clamp, the product, the sum and the truncation), so the same bytes.
#[inline(always)]
fn linear8_step(values: &[f32; 24], out: &mut [u8; 24]) {
    use wide::f32x8;
    for (o, v) in out.chunks_exact_mut(8).zip(values.chunks_exact(8)) {
        let v = f32x8::from(<[f32; 8]>::try_from(v).expect("8 values"));
        // NaN set to 0 first: not every target's maximum drops a NaN operand.
        let v = v.is_nan().bitselect(f32x8::ZERO, v);
        let c = v.fast_max(f32x8::ZERO).fast_min(f32x8::ONE);
        let codes = (c * f32x8::splat(255.0) + f32x8::splat(0.5)).trunc_int().to_array();
        for (o, code) in o.iter_mut().zip(codes) {
            *o = code as u8;
        }
    }
}

/// Linear transfer to 8-bit: clamped to [0, 1] (NaN to 0), times 255, rounded to nearest, as classic
/// tracers write their values.
#[inline(always)]
pub fn linear8(value: f32) -> u8 {
    let c = if value.is_nan() { 0.0 } else { value.clamp(0.0, 1.0) };
    (c * 255.0 + 0.5) as u8
}

/// 8-bit copy of the image under `transfer`: [`srgb8`] or [`linear8`] per value, a row per task.
pub fn to_rgb8(img: &Image, transfer: Transfer) -> RgbImage {
    use rayon::prelude::*;
    let width = (img.width as usize).max(1);
    let mut raw = vec![0u8; img.pixels.len() * 3];
    raw.par_chunks_mut(3 * width)
        .zip(img.pixels.par_chunks(width))
        .for_each(|(out, row)| encode8_row(row, transfer, out));
    RgbImage::from_raw(img.width, img.height, raw).expect("buffer size matches the image")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_transfer_clamps_scales_and_rounds() {
        assert_eq!(
            [linear8(0.0), linear8(1.0), linear8(2.0), linear8(-1.0), linear8(f32::NAN)],
            [0, 255, 255, 0, 0]
        );
        assert_eq!([linear8(0.5), linear8(0.498), linear8(0.753)], [128, 127, 192]);
        let mut img = Image::new(11, 2);
        for (k, p) in img.pixels.iter_mut().enumerate() {
            *p = crate::math::V3::new(k as f32 / 21.0, 0.25, 1.5);
        }
        let out = to_rgb8(&img, Transfer::Linear);
        for (k, p) in img.pixels.iter().enumerate() {
            assert_eq!(&out.as_raw()[3 * k..3 * k + 3], &[linear8(p.x), 64, 255], "pixel {k}");
        }
    }

    #[test]
    fn srgb_curve_endpoints_and_midpoint() {
        assert_eq!(srgb8(0.0), 0);
        assert_eq!(srgb8(1.0), 255);
        assert_eq!(srgb8(2.0), 255);
        assert_eq!(srgb8(-1.0), 0);
        assert_eq!(srgb8(f32::NAN), 0);
        // sRGB 0.5 is linear 0.21404.
        assert_eq!(srgb8(0.2141), 128);
    }

    /// The image conversion (8 pixels at a time, then the row's rest) gives each value's scalar code under
    /// either transfer, NaN, signed zeros, out-of-range and subnormal values included.
    #[test]
    fn image_conversion_is_the_scalar_encode() {
        // Edge values, and the table's code boundaries and the floats just below them.
        let next = &SrgbTable::get().next;
        let boundaries = (1..64).map(|k| next[k * 64]).filter(|t| t.is_finite());
        let special: Vec<f32> =
            [f32::NAN, -f32::NAN, f32::from_bits(0x7fc0_1234), f32::from_bits(0xff80_0001), -0.0, 0.0]
                .into_iter()
                .chain([-1.0, 2.0, f32::INFINITY, f32::NEG_INFINITY, 1e-40, 1.0])
                .chain(boundaries.flat_map(|t| [t, f32::from_bits(t.to_bits() - 1)]))
                // The linear codes' boundaries, (k - 1/2)/255, and their neighbours.
                .chain((1..256).flat_map(|k| {
                    let t = (k as f32 - 0.5) / 255.0;
                    [f32::from_bits(t.to_bits() - 1), t, f32::from_bits(t.to_bits() + 1)]
                }))
                .collect();
        let mut state = 7u32;
        let mut random = move || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1u32 << 24) as f32 * 1.2 - 0.1
        };
        // 13 columns: one step of 8 pixels and a rest of 5; the special values, then as many random ones.
        let mut img = Image::new(13, 9);
        let n = special.len();
        for (k, p) in img.pixels.iter_mut().enumerate() {
            let mut v = |j: usize| special.get((3 * k + j) % (2 * n)).copied().unwrap_or_else(&mut random);
            *p = crate::math::V3::new(v(0), v(1), v(2));
        }
        for (transfer, code) in [(Transfer::Srgb, srgb8 as fn(f32) -> u8), (Transfer::Linear, linear8)] {
            let out = to_rgb8(&img, transfer);
            for (k, p) in img.pixels.iter().enumerate() {
                assert_eq!(
                    &out.as_raw()[3 * k..3 * k + 3],
                    &[code(p.x), code(p.y), code(p.z)],
                    "{transfer:?} pixel {k}: {p:?}"
                );
            }
        }
    }

    /// The table is the formula, bit for bit, on every f32 from 0 to 1 (and clamps like it outside).
    #[test]
    fn srgb_table_matches_the_formula_on_every_f32_in_range() {
        use rayon::prelude::*;
        let one = 1.0f32.to_bits();
        let bad = (0..=one / 65536)
            .into_par_iter()
            .map(|hi| {
                (hi * 65536..=(hi * 65536 + 65535).min(one))
                    .map(f32::from_bits)
                    .filter(|&c| srgb8(c) != srgb8_formula(c))
                    .count()
            })
            .sum::<usize>();
        assert_eq!(bad, 0, "values the table encodes differently");
        for c in [-0.0, -1e-30, f32::NEG_INFINITY, 1.5, f32::INFINITY, f32::NAN, f32::MIN_POSITIVE / 2.0] {
            assert_eq!(srgb8(c), srgb8_formula(c), "{c}");
        }
    }
}
