//! [`Rgb8`]: a colour in three bytes, the form of the per-sphere colour store
//! ([`crate::kinds::sphere::Spheres::color`]).

use super::Rgb;

/// A colour as three 8-bit codes, `round(255·c)` of channels `c` in [0, 1], read back as `code / 255`.
///
/// Three bytes a sphere, not twelve: a field of 10⁹ spheres keeps its colours in 3 GB. The codes are of the
/// value as given, not sRGB-encoded: the scenes with per-sphere colours (particle files, arrays) are
/// written with `transfer = "linear"`, whose 8-bit output has this very step, and the element and type
/// tables' `#RRGGBB` colours (`elements::rgb`, `code as f32 / 255`) come back bit for bit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Rgb8(pub [u8; 3]);

impl Rgb8 {
    /// The nearest codes to `c`, each channel clamped to [0, 1] first (NaN to 0).
    pub fn quantize(c: Rgb) -> Rgb8 {
        let code = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
        Rgb8([code(c.x), code(c.y), code(c.z)])
    }

    /// The colour the codes stand for, `code / 255` per channel.
    ///
    /// ```
    /// use bareray::math::{Rgb, Rgb8};
    ///
    /// let c = Rgb8::quantize(Rgb::new(1.0, 0.5, 0.0));
    /// assert_eq!(c, Rgb8([255, 128, 0]));
    /// assert_eq!(c.to_rgb(), Rgb::new(1.0, 128.0 / 255.0, 0.0));
    /// ```
    #[inline]
    pub fn to_rgb(self) -> Rgb {
        let [r, g, b] = self.0.map(|v| f32::from(v) / 255.0);
        Rgb::new(r, g, b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every code survives a round trip, and `code / 255` is what the tables' hex colours give.
    #[test]
    fn codes_round_trip_and_clamp() {
        for v in 0..=255u8 {
            let c = Rgb8([v, 255 - v, v / 2]);
            assert_eq!(Rgb8::quantize(c.to_rgb()), c);
            assert_eq!(c.to_rgb().x, v as f32 / 255.0);
        }
        assert_eq!(Rgb8::quantize(Rgb::new(-1.0, 2.0, f32::NAN)), Rgb8([0, 255, 0]));
    }
}
