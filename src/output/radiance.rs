//! Radiance HDR: the header (`#?RADIANCE`, `FORMAT=32-bit_rle_rgbe`, the resolution line `-Y h +X w`: rows
//! top to bottom), then each pixel as RGBE — three 8-bit mantissas and a shared exponent — in flat
//! (uncompressed) scanlines, which every reader takes. Negative and NaN values are written as 0.

use std::io::Write;

use super::{BoxError, Frame, Rows};
use crate::math::Rgb;

/// Writes an HDR file of `frame` from `rows` (4 bytes, RGBE, per pixel).
pub(super) fn write(out: &mut impl Write, frame: Frame, mut rows: Rows) -> Result<(), BoxError> {
    write!(out, "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {} +X {}\n", frame.height, frame.width)?;
    for _ in 0..frame.height {
        out.write_all(rows.next_row()?)?;
    }
    rows.finish()
}

/// One pixel as RGBE: m = f·2^e with f in [0.5, 1) for the largest value m; the mantissas are v·256/2^e,
/// rounded (the largest clamped to 255).
pub(super) fn rgbe(p: &Rgb) -> [u8; 4] {
    let clean = |v: f32| if v.is_nan() || v < 0.0 { 0.0 } else { v.min(f32::MAX) };
    let (r, g, b) = (clean(p.x), clean(p.y), clean(p.z));
    let m = r.max(g).max(b);
    if m < 1e-32 {
        return [0; 4];
    }
    let e = m.log2().floor() as i32 + 1;
    let scale = 256.0 / 2f32.powi(e);
    let q = |v: f32| (v * scale + 0.5).min(255.0) as u8;
    [q(r), q(g), q(b), (e + 128).clamp(0, 255) as u8]
}
