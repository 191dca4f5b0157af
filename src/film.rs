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
    /// holds), copied in parallel into zeroed memory.
    ///
    /// ```
    /// let image = bareray::film::Image::new(2, 1);
    /// assert_eq!(image.rgb_values(), [0.0; 6]);
    /// ```
    pub fn rgb_values(&self) -> Vec<f32> {
        use rayon::prelude::*;
        const PIXELS: usize = 1 << 14;
        let mut values = vec![0.0f32; 3 * self.pixels.len()];
        values.par_chunks_mut(3 * PIXELS).zip(self.pixels.par_chunks(PIXELS)).for_each(|(out, pixels)| {
            for (o, p) in out.chunks_exact_mut(3).zip(pixels) {
                o.copy_from_slice(&[p.x, p.y, p.z]);
            }
        });
        values
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
