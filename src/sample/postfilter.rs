//! Postfiltering: a convolution over the finished image.

use crate::film::Image;
use crate::math::Rgb;

/// The lecture's 3×3 kernel, ½ at the centre and 1/16 at each neighbour. At the image border the missing
/// neighbours' weights are dropped and the rest renormalised, so a flat image stays flat.
pub fn lecture_3x3(img: &Image) -> Image {
    let (w, h) = (img.width as i64, img.height as i64);
    let mut out = Image::new(img.width, img.height);
    for y in 0..h {
        for x in 0..w {
            let mut sum = Rgb::default();
            let mut weight = 0.0f32;
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (nx, ny) = (x + dx, y + dy);
                    if nx < 0 || ny < 0 || nx >= w || ny >= h {
                        continue;
                    }
                    let k = if dx == 0 && dy == 0 { 0.5 } else { 1.0 / 16.0 };
                    sum = sum + img.get(nx as u32, ny as u32) * k;
                    weight += k;
                }
            }
            out.set(x as u32, y as u32, sum * (1.0 / weight));
        }
    }
    out
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
