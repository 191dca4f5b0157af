//! Time of the PNG encoder's row filters on an image (fast compression, as bareray writes): the measurement
//! behind `output.rs` writing PNGs with the Paeth filter. Prints each filter's best time of 15 encodes and
//! the encoded size.
//!
//! Run: `cargo run --release --example pngtime -- IMAGE` (any format the `image` crate reads: PNG, EXR, PPM).

use std::time::Instant;

use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::ImageEncoder;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let Some(path) = std::env::args_os().nth(1) else {
        eprintln!("usage: pngtime IMAGE");
        std::process::exit(2);
    };
    let img = image::open(&path)?.to_rgb8();
    for (name, filter) in [
        ("adaptive", FilterType::Adaptive),
        ("sub", FilterType::Sub),
        ("up", FilterType::Up),
        ("paeth", FilterType::Paeth),
        ("avg", FilterType::Avg),
    ] {
        let (mut best, mut len) = (f64::MAX, 0);
        for _ in 0..15 {
            let mut out = Vec::with_capacity(4 << 20);
            let t = Instant::now();
            PngEncoder::new_with_quality(&mut out, CompressionType::Fast, filter).write_image(
                &img,
                img.width(),
                img.height(),
                image::ExtendedColorType::Rgb8,
            )?;
            best = best.min(t.elapsed().as_secs_f64());
            len = out.len();
        }
        println!("{name}: {:.2} ms, {len} bytes", best * 1e3);
    }
    Ok(())
}
