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
        Self { width, height, pixels: vec![Rgb::default(); width as usize * height as usize] }
    }
    /// Pixel (x, y).
    pub fn get(&self, x: u32, y: u32) -> Rgb {
        self.pixels[y as usize * self.width as usize + x as usize]
    }
    /// Sets pixel (x, y).
    pub fn set(&mut self, x: u32, y: u32, c: Rgb) {
        self.pixels[y as usize * self.width as usize + x as usize] = c;
    }
}
