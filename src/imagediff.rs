//! Comparing two images value by value: the library side of `bareray diff`.
//!
//! Images are compared as stored: every channel value is converted to f32 — an EXR's floats as they are
//! (linear light), 8-bit PNG and PPM values as `v / 255` in [0, 1], 16-bit ones as `v / 65535` — and
//! nothing else is done to them (no sRGB decoding, no tone mapping). A PNG and an EXR of one render
//! therefore differ: the PNG holds sRGB-encoded values, the EXR linear ones. Grey images compare as RGB;
//! alpha is compared only when one of the images has it (an image without alpha counts as opaque, 1.0).

use std::path::{Path, PathBuf};

use image::{DynamicImage, GrayImage, ImageReader};

/// Why two images could not be compared.
#[derive(Debug, thiserror::Error)]
pub enum DiffError {
    /// A file could not be opened or decoded.
    #[error("{path}: cannot read image: {error}", path = path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The decoder's or file system's error (in the message, so not also a `source`).
        error: image::ImageError,
    },
    /// The images have different sizes.
    #[error("different sizes: {a} is {}x{}, {b} is {}x{}", a_size.0, a_size.1, b_size.0, b_size.1,
            a = a.display(), b = b.display())]
    Size {
        /// The first file.
        a: PathBuf,
        /// Its width and height.
        a_size: (u32, u32),
        /// The second file.
        b: PathBuf,
        /// Its width and height.
        b_size: (u32, u32),
    },
}

/// The difference of two images of one size.
#[derive(Clone, Debug, PartialEq)]
pub struct Diff {
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Channels compared per pixel: 3 (RGB) or 4 (RGBA, when either image has alpha).
    pub channels: u32,
    /// Root mean square of the differences over every compared channel value.
    pub rmse: f64,
    /// The largest absolute difference of one channel value.
    pub max_abs: f32,
    /// Pixels with at least one channel whose values are not equal.
    pub differing_pixels: u64,
    /// Per pixel, row-major from the top: the largest absolute difference of its channels.
    pub(crate) per_pixel: Vec<f32>,
}

/// The absolute difference of two channel values: 0 when they are equal (two NaNs are equal here: the same
/// value stored twice), infinity when only one of them is NaN or both are infinite with opposite signs.
fn value_diff(a: f32, b: f32) -> f32 {
    if a == b || (a.is_nan() && b.is_nan()) {
        0.0
    } else {
        let d = (a - b).abs();
        if d.is_nan() {
            f32::INFINITY
        } else {
            d
        }
    }
}

impl Diff {
    /// Compares two decoded images (see the module documentation for how values are compared).
    ///
    /// Returns `None` when their sizes differ.
    pub(crate) fn new(a: &DynamicImage, b: &DynamicImage) -> Option<Diff> {
        if (a.width(), a.height()) != (b.width(), b.height()) {
            return None;
        }
        let channels = if a.color().has_alpha() || b.color().has_alpha() { 4 } else { 3 };
        let (va, vb) = (a.to_rgba32f(), b.to_rgba32f());
        let mut per_pixel = Vec::with_capacity(va.len() / 4);
        let (mut sum_sq, mut max_abs, mut differing) = (0f64, 0f32, 0u64);
        for (pa, pb) in va.chunks_exact(4).zip(vb.chunks_exact(4)) {
            let mut worst = 0f32;
            for c in 0..channels {
                let d = value_diff(pa[c], pb[c]);
                sum_sq += f64::from(d) * f64::from(d);
                worst = worst.max(d);
            }
            differing += u64::from(worst > 0.0);
            max_abs = max_abs.max(worst);
            per_pixel.push(worst);
        }
        let count = per_pixel.len() * channels;
        let rmse = if count == 0 { 0.0 } else { (sum_sq / count as f64).sqrt() };
        Some(Diff {
            width: a.width(),
            height: a.height(),
            channels: channels as u32,
            rmse,
            max_abs,
            differing_pixels: differing,
            per_pixel,
        })
    }

    /// Whether every compared value is equal.
    pub fn identical(&self) -> bool {
        self.differing_pixels == 0
    }

    /// Peak signal-to-noise ratio in dB for a peak value of 1.0: `20 log10(1 / RMSE)`; infinite when the
    /// images are identical.
    pub fn psnr(&self) -> f64 {
        if self.rmse == 0.0 {
            f64::INFINITY
        } else {
            -20.0 * self.rmse.log10()
        }
    }

    /// A grey image of `Diff::per_pixel`, scaled so that the largest difference is white (255): grey
    /// level `ceil(255 d / max_abs)`, so that any differing pixel is at least 1; black where the pixels are
    /// equal, and everywhere when the images are identical. Infinite differences are white and, when
    /// the largest difference is infinite, so is every other difference.
    pub fn heatmap(&self) -> GrayImage {
        let levels = self.per_pixel.iter().map(|&d| {
            if d == 0.0 {
                0
            } else if !self.max_abs.is_finite() {
                255
            } else {
                (f64::from(d) / f64::from(self.max_abs) * 255.0).ceil().clamp(1.0, 255.0) as u8
            }
        });
        GrayImage::from_raw(self.width, self.height, levels.collect()).expect("one level per pixel")
    }
}

/// Reads an image file, choosing the decoder by its contents (then by its extension).
pub fn load(path: &Path) -> Result<DynamicImage, DiffError> {
    let read = |path: &Path| -> Result<DynamicImage, image::ImageError> {
        ImageReader::open(path)?.with_guessed_format()?.decode()
    };
    read(path).map_err(|error| DiffError::Read { path: path.to_owned(), error })
}

/// Reads and compares two image files.
pub fn diff_files(a: &Path, b: &Path) -> Result<Diff, DiffError> {
    let (ia, ib) = (load(a)?, load(b)?);
    Diff::new(&ia, &ib).ok_or_else(|| DiffError::Size {
        a: a.to_owned(),
        a_size: (ia.width(), ia.height()),
        b: b.to_owned(),
        b_size: (ib.width(), ib.height()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::{Rgb32FImage, RgbImage, RgbaImage};

    #[test]
    fn identical_images_have_no_difference_and_infinite_psnr() {
        let a = DynamicImage::ImageRgb8(RgbImage::from_fn(4, 3, |x, y| image::Rgb([x as u8, y as u8, 7])));
        let d = Diff::new(&a, &a.clone()).unwrap();
        assert!(d.identical());
        assert_eq!((d.rmse, d.max_abs, d.differing_pixels, d.channels), (0.0, 0.0, 0, 3));
        assert_eq!(d.psnr(), f64::INFINITY);
        assert!(d.heatmap().pixels().all(|p| p[0] == 0));
    }

    #[test]
    fn one_changed_value_gives_its_rmse_psnr_and_heatmap() {
        let a = RgbImage::new(2, 2);
        let mut b = a.clone();
        b.put_pixel(1, 0, image::Rgb([0, 51, 0]));
        let d = Diff::new(&DynamicImage::ImageRgb8(a), &DynamicImage::ImageRgb8(b)).unwrap();
        assert_eq!(d.differing_pixels, 1);
        assert_eq!(d.max_abs, 0.2);
        // One value of 12 differs by 0.2: MSE 0.04 / 12.
        assert!((d.rmse - (0.04f64 / 12.0).sqrt()).abs() < 1e-7, "{}", d.rmse);
        assert!((d.psnr() - 10.0 * (12.0f64 / 0.04).log10()).abs() < 1e-4);
        assert_eq!(d.heatmap().into_raw(), vec![0, 255, 0, 0]);
    }

    #[test]
    fn eight_bit_values_compare_as_v_over_255_against_floats() {
        let a = DynamicImage::ImageRgb8(RgbImage::from_pixel(1, 1, image::Rgb([255, 0, 51])));
        let b = DynamicImage::ImageRgb32F(Rgb32FImage::from_pixel(1, 1, image::Rgb([1.0, 0.0, 0.2])));
        assert!(Diff::new(&a, &b).unwrap().identical());
        let c = DynamicImage::ImageRgb32F(Rgb32FImage::from_pixel(1, 1, image::Rgb([1.0, f32::NAN, 2.0])));
        let d = Diff::new(&a, &c).unwrap();
        assert_eq!(d.max_abs, f32::INFINITY);
        assert_eq!(d.heatmap().into_raw(), vec![255]);
    }

    #[test]
    fn alpha_counts_when_one_image_has_it_and_sizes_must_match() {
        let a = DynamicImage::ImageRgb8(RgbImage::new(2, 1));
        let b = DynamicImage::ImageRgba8(RgbaImage::from_pixel(2, 1, image::Rgba([0, 0, 0, 0])));
        let d = Diff::new(&a, &b).unwrap();
        assert_eq!((d.channels, d.differing_pixels, d.max_abs), (4, 2, 1.0));
        assert!(Diff::new(&a, &DynamicImage::ImageRgb8(RgbImage::new(1, 2))).is_none());
    }
}
