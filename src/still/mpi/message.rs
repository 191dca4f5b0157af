//! The traced band's message, [`BAND`](super::BAND): its index and its pixels as `f32`s.

use crate::math::Rgb;
use crate::render::Bands;

/// Band `i`'s pixels as a [`BAND`] message.
///
/// [`BAND`]: super::BAND
pub(super) fn pack(i: u32, pixels: &[Rgb]) -> Vec<f32> {
    let mut message = Vec::with_capacity(1 + 3 * pixels.len());
    message.push(f32::from_bits(i));
    message.extend(pixels.iter().flat_map(|p| [p.x, p.y, p.z]));
    message
}

/// A [`BAND`] message's band and pixels.
///
/// [`BAND`]: super::BAND
pub(super) fn unpack(message: &[f32], bands: &Bands) -> (u32, Vec<Rgb>) {
    let (&i, values) = message.split_first().expect("a band message holds its band's index");
    let i = i.to_bits();
    let rows = bands.rows_of(i);
    let pixels = bands.traced.width() as usize * (rows.end - rows.start) as usize;
    assert!(i < bands.count() && values.len() == 3 * pixels, "band {i}: {} values", values.len());
    (i, values.chunks_exact(3).map(|c| Rgb::new(c[0], c[1], c[2])).collect())
}
