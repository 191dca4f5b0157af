//! Stills in bands through the library: the streamed files are the bytes of the whole-image path, and a
//! source that ends early keeps the old file (the command line's stills are tested in `tests/stills.rs`).

use super::common;

use std::path::{Path, PathBuf};

use bareray::compile::Scene;
use bareray::output::{write_image_with, write_rows, BitDepth, Format, Frame, WriteOptions};
use bareray::render::{render_lanes, thread_pool, Window};
use bareray::scene::desc::{Ao, Filter, FilterKind, Pattern, Shade, Transfer};
use bareray::still::{self, Job};
use common::scene_files;

/// `path`'s scene at `width × height` (odd sizes: partial tiles and blocks at the edges).
fn scene_at(path: &Path, width: u32, height: u32, change: impl Fn(&mut bareray::scene::SceneDesc)) -> Scene {
    let mut desc = bareray::io::load(path).expect("scene loads");
    (desc.camera.width, desc.camera.height) = (width, height);
    change(&mut desc);
    Scene::compile(&desc).expect("scene compiles")
}

fn scenes() -> Vec<PathBuf> {
    scene_files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes"))
}

/// Every format, with the text a render writes.
fn variants() -> Vec<(&'static str, WriteOptions)> {
    let text =
        vec![("Software".to_owned(), "bareray test".to_owned()), ("Comment".to_owned(), "× 1".to_owned())];
    let with = |transfer, bit_depth| WriteOptions { transfer, bit_depth, text: text.clone() };
    vec![
        ("a.png", with(Transfer::Srgb, BitDepth::Eight)),
        ("b.png", with(Transfer::Linear, BitDepth::Sixteen)),
        ("c.exr", with(Transfer::Srgb, BitDepth::Eight)),
        ("d.ppm", with(Transfer::Linear, BitDepth::Eight)),
        ("e.hdr", with(Transfer::Srgb, BitDepth::Eight)),
    ]
}

/// Bands of 16 rows (the smallest), so every image here streams through several bands.
fn job(scene: &Scene, path: &Path, write: WriteOptions, window: Window) -> Job {
    Job { window, band_budget: 1, lanes: 8, ..Job::whole(scene, path, write).unwrap() }
}

/// The streamed file of every scene in scenes/ — and of the whitted scene under a reconstruction filter,
/// adaptive sampling, the lecture's half-pixel pattern and ambient occlusion — is byte for byte the file the whole-image path
/// writes (render into one image, then encode), in every format.
#[test]
fn streamed_files_are_the_whole_image_paths_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let pool = thread_pool(Some(2)).unwrap();
    let whitted = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/whitted.toml");
    let mut cases: Vec<(String, Scene)> =
        scenes().iter().map(|p| (p.display().to_string(), scene_at(p, 75, 53, |_| {}))).collect();
    let filter = Filter { kind: FilterKind::Mitchell, radius: 2.0 };
    cases.push(("whitted, mitchell".into(), scene_at(&whitted, 61, 47, |d| d.render.filter = Some(filter))));
    let adaptive = Pattern::Adaptive { threshold: 0.05, depth: 2 };
    cases.push(("whitted, adaptive".into(), scene_at(&whitted, 61, 47, |d| d.render.pattern = adaptive)));
    let postfilter = bareray::scene::desc::PostFilter::Lecture3x3;
    cases.push((
        "whitted, postfilter".into(),
        scene_at(&whitted, 61, 47, |d| d.render.postfilter = postfilter),
    ));
    cases.push((
        "whitted, lecture".into(),
        scene_at(&whitted, 61, 47, |d| d.render.pattern = Pattern::HalfPixel),
    ));
    let ao = Shade::Ao(Ao { samples: 4, distance: None });
    cases.push(("whitted, ao".into(), scene_at(&whitted, 61, 47, |d| d.render.shade = ao)));
    let stratified =
        |d: &mut bareray::scene::SceneDesc| (d.render.shade, d.render.pattern) = (ao, Pattern::Stratified(2));
    cases.push(("whitted, ao, stratified".into(), scene_at(&whitted, 61, 47, stratified)));
    for (name, scene) in &cases {
        let image = render_lanes(scene, 8, &pool, &()).image;
        for (file, options) in variants() {
            let (whole, streamed) = (dir.path().join(format!("whole-{file}")), dir.path().join(file));
            write_image_with(&image, &whole, &options).unwrap();
            let window = Window::whole(scene.camera.width, scene.camera.height);
            still::render(scene, &pool, &(), &job(scene, &streamed, options, window)).unwrap();
            assert!(
                std::fs::read(&whole).unwrap() == std::fs::read(&streamed).unwrap(),
                "{name}: {file} differs from the whole-image path"
            );
        }
    }
}

/// A source that ends before the image does fails the write and leaves an existing file as it was, with
/// no temporary file beside it.
#[test]
fn a_short_source_keeps_the_old_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("kept.png");
    std::fs::write(&path, b"old").unwrap();
    for format in [Format::Png, Format::Exr, Format::Ppm] {
        let path = path.with_extension(match format {
            Format::Png => "png",
            Format::Exr => "exr",
            _ => "ppm",
        });
        std::fs::write(&path, b"old").unwrap();
        let frame = Frame::whole(4, 3);
        let row = vec![0u8; 4 * bareray::output::pixel_bytes(format, BitDepth::Eight)];
        let err = write_rows(
            &path,
            format,
            &WriteOptions::default(),
            frame,
            &mut vec![row.clone(), row].into_iter(),
        )
        .unwrap_err();
        assert!(err.to_string().contains("ended after 2 of 3 rows"), "{format:?}: {err}");
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
    }
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names.len(), 3, "temporary files left: {names:?}");
}
