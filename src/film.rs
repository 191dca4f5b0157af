//! The film: a linear-light RGB image, row 0 at the top.

use crate::math::Rgb;

/// A linear RGB image in f32.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Row-major pixels, row 0 at the top.
    pub pixels: Vec<Rgb>,
}

impl Image {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        Self { width, height, pixels: black_pixels(width as usize * height as usize) }
    }
    /// Pixel (x, y).
    pub(crate) fn get(&self, x: u32, y: u32) -> Rgb {
        self.pixels[y as usize * self.width as usize + x as usize]
    }
    /// Sets pixel (x, y).
    pub(crate) fn set(&mut self, x: u32, y: u32, c: Rgb) {
        self.pixels[y as usize * self.width as usize + x as usize] = c;
    }

    /// The pixels' channels, `r, g, b` per pixel in row order (what an array of shape (height, width, 3)
    /// holds): the pixel buffer itself, taken over without a copy.
    ///
    /// ```
    /// let image = bareray::film::Image::new(2, 1);
    /// assert_eq!(image.into_rgb_values(), [0.0; 6]);
    /// ```
    pub fn into_rgb_values(self) -> Vec<f32> {
        const _: () =
            assert!(size_of::<Rgb>() == 3 * size_of::<f32>() && align_of::<Rgb>() == align_of::<f32>());
        let mut pixels = std::mem::ManuallyDrop::new(self.pixels);
        let (block, len, capacity) = (pixels.as_mut_ptr(), pixels.len(), pixels.capacity());
        // SAFETY: `Rgb` is `#[repr(C)]` with three `f32` fields, of three `f32`s' size and an `f32`'s
        // alignment (asserted above): no padding, so the block of `capacity` pixels is the block of
        // `3 · capacity` floats, of the same size and alignment, from the same (global) allocator, and its
        // first `3 · len` floats are the initialised pixels' channels in order. With `capacity` 0 the pointer
        // is a dangling one aligned for `Rgb`, so for `f32`, and nothing is freed. `pixels` is not dropped.
        unsafe { Vec::from_raw_parts(block.cast::<f32>(), 3 * len, 3 * capacity) }
    }
}

/// `n` black pixels from the allocator's zeroed memory. `vec![Rgb::default(); n]` would write every pixel
/// (Rgb is not a type `Vec` knows to be all zero bits): the whole image's page faults and stores on one
/// thread before the render (docs/perf-log/2026-11.md, "Where the time around the render went").
/// Zeroed pages come lazily, on the threads that write the tiles.
fn black_pixels(n: usize) -> Vec<Rgb> {
    if n == 0 {
        return Vec::new();
    }
    let layout = std::alloc::Layout::array::<Rgb>(n).expect("image size fits in memory");
    // SAFETY: the layout's size is non-zero; an Rgb of zero bytes is three +0.0 f32, a valid value; the
    // vector takes the block with the layout (n Rgb, global allocator) it was allocated with.
    unsafe {
        let block = std::alloc::alloc_zeroed(layout).cast::<Rgb>();
        if block.is_null() {
            std::alloc::handle_alloc_error(layout);
        }
        Vec::from_raw_parts(block, n, n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The channels come out in pixel order, and a buffer with spare capacity (freed as floats) and an empty
    /// one are handed over too.
    #[test]
    fn rgb_values_are_the_pixels_channels_in_order() {
        let mut pixels = Vec::with_capacity(5);
        pixels.extend([Rgb::new(1.0, 2.0, 3.0), Rgb::new(4.0, 5.0, 6.0)]);
        let capacity = pixels.capacity();
        let mut values = Image { width: 2, height: 1, pixels }.into_rgb_values();
        assert_eq!(values, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert_eq!(values.capacity(), 3 * capacity);
        values.push(7.0);
        assert_eq!(values[6], 7.0);
        assert!(Image::new(0, 3).into_rgb_values().is_empty());
        let image = Image::new(3, 2);
        assert_eq!(image.clone().into_rgb_values().len(), 18);
        assert!(image.into_rgb_values().iter().all(|&v| v == 0.0));
    }
}
