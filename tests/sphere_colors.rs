//! The per-sphere colour store: colours follow the spheres through the BVH's leaf order and the particle
//! tree's reordering, every packet width, the scalar path and any thread count give the same bits with
//! them, and spheres given as arrays render as the particle file of the same spheres does, on the command
//! line too.

use bareray::api::{self, RenderOptions};
use bareray::compile::{Accel, CompileOptions, Scene};
use bareray::io::particles::arrays::{Floats, SphereArrays};
use bareray::kinds::sphere::SphereDesc;
use bareray::math::{Rgb8, SplitMix64};
use bareray::render::render_lanes;
use bareray::scene::desc::{Ao, CameraOverrides, Material, Shade};
use bareray::scene::SceneDesc;
use glam::DVec3;

use crate::common;

/// `n` random spheres in a cube, and a random 8-bit colour for each (as `f32` channels on the 8-bit grid).
fn field(n: usize, seed: u64) -> (Vec<f64>, Vec<f64>, Vec<f32>) {
    let mut rng = SplitMix64::new(seed);
    let mut unit = || rng.unit();
    let centers: Vec<f64> = (0..3 * n).map(|_| unit() * 8.0 - 4.0).collect();
    let radii: Vec<f64> = (0..n).map(|_| 0.08 + 0.25 * unit()).collect();
    let colors: Vec<f32> = (0..3 * n).map(|_| (unit() * 255.0).floor() as f32 / 255.0).collect();
    (centers, radii, colors)
}

fn arrays<'a>(f: &'a (Vec<f64>, Vec<f64>, Vec<f32>)) -> SphereArrays<'a> {
    SphereArrays { centers: Floats::F64(&f.0), radii: Floats::F64(&f.1), colors: Some(Floats::F32(&f.2)) }
}

/// A small particle scene with per-sphere colours (from `field`), at 96×64.
fn coloured_scene(n: usize, seed: u64) -> SceneDesc {
    let f = field(n, seed);
    let mut desc = arrays(&f).scene(Some(DVec3::new(0.3, 0.4, 1.0))).expect("valid arrays");
    CameraOverrides { width: Some(96), height: Some(64), ..Default::default() }.apply(&mut desc.camera);
    desc
}

/// The same scene in the old form: a material per sphere carrying its colour, no colour store.
fn as_materials(desc: &SceneDesc) -> SceneDesc {
    let base = desc.materials[0];
    let materials: Vec<Material> =
        desc.sphere_colors.iter().map(|c| Material { color: c.to_rgb(), ..base }).collect();
    let spheres =
        desc.spheres.iter().enumerate().map(|(i, s)| SphereDesc { material: i as u32, ..*s }).collect();
    SceneDesc { materials, spheres, sphere_colors: Vec::new(), ..desc.clone() }
}

fn compile(desc: &SceneDesc, accel: Accel, scalar: bool) -> Scene {
    Scene::compile_with_options(desc, CompileOptions { accel, scalar, ..CompileOptions::default() })
        .expect("compile")
}

/// Colours stored per sphere give the image a material per sphere gives, bit for bit, in the BVH (whose
/// leaf order permutes the spheres) and in the particle tree (which reorders them), under Whitted shading
/// and ambient occlusion; and they matter: without them the image differs.
#[test]
fn stored_colours_are_the_material_colours_they_replace() {
    let mut desc = coloured_scene(600, 7);
    for shade in [Shade::Whitted, Shade::Ao(Ao { samples: 4, distance: None })] {
        desc.render.shade = shade;
        let reference = render_lanes(&compile(&as_materials(&desc), Accel::Bvh, false), 8, &pool(2), &());
        for accel in [Accel::Bvh, Accel::Particles] {
            let scene = compile(&desc, accel, false);
            let stored = if accel == Accel::Bvh { scene.geometry.spheres.color.len() } else { 600 };
            assert_eq!(stored, 600, "the BVH's spheres carry the colours");
            let image = render_lanes(&scene, 8, &pool(2), &());
            assert!(image.image.pixels == reference.image.pixels, "{accel:?} {shade:?}: colours moved");
        }
        let plain = SceneDesc { sphere_colors: Vec::new(), ..desc.clone() };
        let grey = render_lanes(&compile(&plain, Accel::Bvh, false), 8, &pool(2), &());
        assert!(grey.image.pixels != reference.image.pixels, "{shade:?}: the colours changed nothing");
    }
}

fn pool(threads: usize) -> rayon::ThreadPool {
    bareray::render::thread_pool(Some(threads)).expect("pool")
}

/// With per-sphere colours, packets of 1, 4, 8 and 16, the scalar path and 1 or 2 threads give the same
/// bits, in the BVH and in the particle tree, with mirrors (secondary rays go lane by lane) and without.
#[test]
fn every_width_path_and_thread_count_gives_the_same_bits_with_colours() {
    let mut desc = coloured_scene(400, 11);
    for reflect in [0.0, 0.4] {
        desc.materials[0].reflect = reflect;
        let reference = render_lanes(&compile(&desc, Accel::Bvh, false), 16, &pool(2), &()).image.pixels;
        for accel in [Accel::Bvh, Accel::Particles] {
            let scene = compile(&desc, accel, false);
            for lanes in [1, 4, 8, 16] {
                for threads in [1, 2] {
                    let image = render_lanes(&scene, lanes, &pool(threads), &()).image.pixels;
                    assert!(
                        image == reference,
                        "{accel:?}, {lanes} lanes, {threads} threads, reflect {reflect}"
                    );
                }
            }
            let scalar = compile(&desc, accel, true);
            let image = render_lanes(&scalar, 1, &pool(2), &()).image.pixels;
            assert!(image == reference, "{accel:?}, scalar path, reflect {reflect}");
        }
    }
}

/// Spheres as arrays give the scene an extended XYZ file of them gives (the same description, field by
/// field), and the library's in-memory render is the image `bareray render` writes for that file, bit for
/// bit (EXR holds the f32 values as they are).
#[test]
fn arrays_render_as_the_command_line_renders_their_file() {
    let f = field(300, 3);
    let from_arrays = arrays(&f).scene(None).expect("valid arrays");
    let mut text = format!("{}\nProperties=species:S:1:pos:R:3:radius:R:1:color:R:3\n", f.1.len());
    for i in 0..f.1.len() {
        let (c, k) = (&f.0[3 * i..3 * i + 3], &f.2[3 * i..3 * i + 3]);
        text += &format!("C {} {} {} {} {} {} {}\n", c[0], c[1], c[2], f.1[i], k[0], k[1], k[2]);
    }
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("field.extxyz");
    std::fs::write(&file, text).expect("write");
    let read = bareray::io::load(&file).expect("read");
    assert!(read == from_arrays, "the file's scene and the arrays' differ");

    let camera = CameraOverrides { width: Some(160), height: Some(90), ..Default::default() };
    let overrides = bareray::settings::Overrides { camera, ..Default::default() };
    let options = RenderOptions { overrides, threads: Some(2), ..Default::default() };
    let picture = api::render_spheres(&arrays(&f), None, &options).expect("render");
    let exr = dir.path().join("field.exr");
    let out = common::bareray(&[
        "render",
        file.to_str().unwrap(),
        "-o",
        exr.to_str().unwrap(),
        "--width",
        "160",
        "--height",
        "90",
        "--quiet",
    ]);
    assert!(out.status.success(), "{}", common::stderr(&out));
    let cli = bareray::imagediff::load(&exr).expect("read the EXR").to_rgb32f();
    let ours: Vec<u32> =
        picture.rendered.image.pixels.iter().flat_map(|p| [p.x, p.y, p.z]).map(f32::to_bits).collect();
    let theirs: Vec<u32> = cli.as_raw().iter().map(|v| v.to_bits()).collect();
    assert_eq!((cli.width(), cli.height()), (160, 90));
    assert!(ours == theirs, "the in-memory render differs from the command line's EXR");

    // One thread gives the same image; zero threads are refused before the arrays are read.
    let one = RenderOptions { threads: Some(1), ..options.clone() };
    let alone = api::render_spheres(&arrays(&f), None, &one).expect("render on one thread");
    assert!(alone.rendered.image.pixels == picture.rendered.image.pixels, "one thread's image differs");
    let none = RenderOptions { threads: Some(0), ..options };
    let refused = api::render_spheres(&arrays(&f), None, &none);
    assert!(matches!(refused, Err(api::Error::Options(ref m)) if m.contains("threads")), "{refused:?}");
}

/// Bad arrays are errors naming the array and the first bad sphere; nothing is rendered.
#[test]
fn bad_arrays_name_the_first_bad_sphere() {
    let centers = [0.0, 0.0, 0.0, 1.0, f64::NAN, 0.0, 2.0, 0.0, f64::INFINITY];
    let radii = [1.0, 1.0, 1.0];
    let a = SphereArrays { centers: Floats::F64(&centers), radii: Floats::F64(&radii), colors: None };
    assert_eq!(
        a.check().unwrap_err().to_string(),
        "centers[1]: (1, NaN, 0) is not finite (or beyond f32's range)"
    );
    let ok = [0.0; 9];
    let a = SphereArrays { centers: Floats::F64(&ok), radii: Floats::F64(&[1.0, 0.0, -1.0]), colors: None };
    assert_eq!(a.check().unwrap_err().index, Some(1));
    let colors = [0.0f32, 0.5, 1.0, 0.25, 1.5, 0.0, -0.1, 0.0, 0.0];
    let a = SphereArrays { radii: Floats::F64(&radii), colors: Some(Floats::F32(&colors)), ..a };
    assert_eq!(a.check().unwrap_err().to_string(), "colors[1]: (0.25, 1.5, 0) has a channel outside [0, 1]");
    let a = SphereArrays { centers: Floats::F64(&ok[..8]), colors: None, ..a };
    assert_eq!(a.check().unwrap_err().to_string(), "centers: 8 values for 3 spheres: expected n×3");
    let huge = [0.0, 0.0, 1e39];
    let a = SphereArrays { centers: Floats::F64(&huge), radii: Floats::F64(&[1.0]), colors: None };
    assert_eq!(a.check().unwrap_err().index, Some(0), "beyond f32's range");
    // Among many spheres (checked in parallel) the first bad one is named, whatever its fault and the
    // faults after it, with one thread or several.
    let n = 300_000;
    let (mut centers, mut radii, mut colors) = (vec![0.5; 3 * n], vec![1.0; n], vec![0.5f32; 3 * n]);
    (centers[3 * 250_000 + 2], radii[200_000], colors[3 * 150_001]) = (f64::NAN, -2.0, 2.0);
    for threads in [1, 2, 3] {
        let a = SphereArrays {
            centers: Floats::F64(&centers),
            radii: Floats::F64(&radii),
            colors: Some(Floats::F32(&colors)),
        };
        let first = |a: SphereArrays| pool(threads).install(|| a.check().unwrap_err().to_string());
        assert_eq!(first(a), "colors[150001]: (2, 0.5, 0.5) has a channel outside [0, 1]");
        assert_eq!(
            first(SphereArrays { colors: None, ..a }),
            "radii[200000]: -2 is not a positive finite radius"
        );
        let ok = vec![1.0; n];
        let a = SphereArrays { radii: Floats::F64(&ok), colors: None, ..a };
        assert!(first(a).starts_with("centers[250000]: (0.5, 0.5, NaN)"));
    }
}

/// A colour list of the wrong length (a description built by hand) is ignored: the spheres keep their
/// material's colour, and nothing panics.
#[test]
fn a_colour_list_of_another_length_is_ignored() {
    let desc = coloured_scene(50, 5);
    let short = SceneDesc { sphere_colors: desc.sphere_colors[..10].to_vec(), ..desc.clone() };
    let none = SceneDesc { sphere_colors: Vec::new(), ..desc.clone() };
    for accel in [Accel::Bvh, Accel::Particles] {
        let a = render_lanes(&compile(&short, accel, false), 8, &pool(2), &()).image.pixels;
        let b = render_lanes(&compile(&none, accel, false), 8, &pool(2), &()).image.pixels;
        assert!(a == b, "{accel:?}");
    }
    assert_eq!(Rgb8::quantize(desc.sphere_colors[3].to_rgb()), desc.sphere_colors[3]);
}
