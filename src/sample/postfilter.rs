//! Postfiltering: a convolution over the finished image.

use crate::film::Image;
use crate::math::Rgb;

/// The lecture's 3×3 kernel, ½ at the centre and 1/16 at each neighbour. At the image border the missing
/// neighbours' weights are dropped and the rest renormalised, so a flat image stays flat.
pub(crate) fn lecture_3x3(img: &Image) -> Image {
    let (w, h) = (img.width as i64, img.height as i64);
    let mut out = Image::new(img.width, img.height);
    for y in 0..h {
        for x in 0..w {
            let inside = |nx: i64, ny: i64| {
                (nx >= 0 && ny >= 0 && nx < w && ny < h).then(|| img.get(nx as u32, ny as u32))
            };
            out.set(x as u32, y as u32, lecture_3x3_pixel(x, y, inside));
        }
    }
    out
}

/// One pixel of [`lecture_3x3`]: `at(x, y)` gives a pixel's value, `None` outside the image. Every caller
/// (the whole image, rows streamed band by band) sums the same terms in this order, so gets the same bits.
pub(crate) fn lecture_3x3_pixel(x: i64, y: i64, at: impl Fn(i64, i64) -> Option<Rgb>) -> Rgb {
    let mut sum = Rgb::default();
    let mut weight = 0.0f32;
    for dy in -1..=1 {
        for dx in -1..=1 {
            let Some(value) = at(x + dx, y + dy) else { continue };
            let k = if dx == 0 && dy == 0 { 0.5 } else { 1.0 / 16.0 };
            sum = sum + value * k;
            weight += k;
        }
    }
    sum * (1.0 / weight)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spreads_an_impulse_by_the_kernel_and_keeps_flat_images_flat() {
        let mut img = Image::new(5, 5);
        img.set(2, 2, Rgb::all(16.0));
        let out = lecture_3x3(&img);
        assert_eq!(out.get(2, 2), Rgb::all(8.0));
        assert_eq!(out.get(1, 1), Rgb::all(1.0));
        assert_eq!(out.get(3, 2), Rgb::all(1.0));
        assert_eq!(out.get(0, 0), Rgb::all(0.0));
        let mut flat = Image::new(3, 2);
        flat.pixels.fill(Rgb::all(0.25));
        assert!(lecture_3x3(&flat).pixels.iter().all(|p| (p.x - 0.25).abs() < 1e-7));
    }
}
