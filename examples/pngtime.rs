use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::ImageEncoder;
use std::time::Instant;
fn main() {
    let img = image::open("/tmp/balls4-1024.png").unwrap().to_rgb8();
    for (name, f) in [
        ("adaptive", FilterType::Adaptive),
        ("sub", FilterType::Sub),
        ("up", FilterType::Up),
        ("paeth", FilterType::Paeth),
        ("avg", FilterType::Avg),
    ] {
        let mut best = f64::MAX;
        let mut len = 0;
        for _ in 0..15 {
            let mut out = Vec::with_capacity(4 << 20);
            let t = Instant::now();
            PngEncoder::new_with_quality(&mut out, CompressionType::Fast, f)
                .write_image(&img, img.width(), img.height(), image::ExtendedColorType::Rgb8)
                .unwrap();
            best = best.min(t.elapsed().as_secs_f64());
            len = out.len();
        }
        println!("{name}: {:.2} ms, {} bytes", best * 1e3, len);
    }
}
