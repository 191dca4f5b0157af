//! Renders a scene file to an image: the library's read → compile → render → write, with a progress line.
//!
//! Run: `cargo run --release --example render_file -- scenes/whitted.toml whitted.png [WIDTH HEIGHT]`
//! (scene: `.toml`, `.nff` or `.xyzr`; image: `.png`, `.exr` or `.ppm`; the size defaults to the scene's).

use std::io::Write;
use std::path::PathBuf;

use bareray::{compile::Scene, io, output, render};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if !(args.len() == 2 || args.len() == 4) {
        eprintln!("usage: render_file SCENE OUTPUT [WIDTH HEIGHT]");
        std::process::exit(2);
    }
    let (scene_path, out_path) = (PathBuf::from(&args[0]), PathBuf::from(&args[1]));

    let mut desc = io::load(&scene_path)?;
    if let [_, _, width, height] = &args[..] {
        (desc.camera.width, desc.camera.height) = (width.parse()?, height.parse()?);
    }
    // Check the output name before the render, not after it.
    output::Format::from_path(&out_path)?;

    let pool = render::thread_pool(None)?;
    let scene = pool.install(|| Scene::compile(&desc))?;
    // Called from the render's threads as tiles finish: a mark per 10% done.
    let progress = |done: u64, total: u64| {
        if done * 10 / total.max(1) != done.saturating_sub(1) * 10 / total.max(1) || done == 0 {
            eprint!("{}% ", done * 100 / total.max(1));
            let _ = std::io::stderr().flush();
        }
    };
    let rendered = render::render_lanes(&scene, 8, &pool, &progress);
    eprintln!();
    pool.install(|| output::write_image(&rendered.image, &out_path, scene.render.transfer))?;

    let c = rendered.counts;
    println!(
        "{}: {}x{} in {:.3} s, {} rays ({} primary, {} shadow, {} reflection, {} refraction)",
        out_path.display(),
        scene.camera.width,
        scene.camera.height,
        rendered.seconds,
        c.total(),
        c.primary,
        c.shadow,
        c.reflection,
        c.refraction
    );
    Ok(())
}
