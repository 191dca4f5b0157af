//! Whole renders checked against closed-form answers, and the image's independence of the thread count.

use super::common;

use bareray::compile::Scene;
use bareray::film::Image;
use bareray::render::{render_lanes, thread_pool};
use common::{compile, parse_toml, render, scene_files};

fn render_toml(src: &str, threads: usize) -> Image {
    render(&compile(&parse_toml(src)), threads)
}

/// pbrt's inside-out test: the camera sits inside a diffuse sphere of radius R with a point light of intensity
/// I at its centre. Every camera ray hits the inside (the exit root, normal flipped), every shading point faces
/// the light head-on at distance R, so every pixel is kd·C·I/R² exactly. The shadow ray heads into the sphere
/// and must not hit the sphere it leaves (only its far side, beyond the light).
#[test]
fn inside_out_sphere_with_a_central_light_is_uniform() {
    let src = r#"
        [camera]
        eye = [0.3, -0.2, 0.1]
        look_at = [1.0, 0.5, 2.0]
        hfov = 100
        width = 48
        height = 32
        [render]
        ambient = [0, 0, 0]
        [materials.wall]
        color = [0.5, 0.25, 1.0]
        diffuse = 0.7
        [[lights]]
        position = [0, 0, 0]
        intensity = 8.0
        falloff = "inverse-square"
        [[spheres]]
        center = [0, 0, 0]
        radius = 2.0
        material = "wall"
    "#;
    let img = render_toml(src, 2);
    let expect = [0.7 * 0.5 * 2.0, 0.7 * 0.25 * 2.0, 0.7 * 1.0 * 2.0];
    for p in &img.pixels {
        for (got, want) in [p.x, p.y, p.z].iter().zip(expect) {
            assert!((got - want).abs() < 2e-6 * want, "pixel {p:?}, want {expect:?}");
        }
    }
}

/// A white Lambertian unit sphere lit by a light at the eye with no falloff: each pixel is n·v, the cosine
/// between the surface normal and the direction back to the eye. The expected image is computed here in f64
/// from the camera formula and the textbook quadratic, independently of the renderer's kernels.
#[test]
fn lambert_sphere_lit_from_the_eye_matches_the_closed_form() {
    let (w, h) = (64u32, 48u32);
    let src = format!(
        r#"
        [camera]
        eye = [0, 0, -4]
        look_at = [0, 0, 0]
        hfov = 40
        width = {w}
        height = {h}
        [render]
        ambient = [0, 0, 0]
        background = [0.25, 0.5, 0.75]
        [materials.white]
        color = [1, 1, 1]
        diffuse = 1.0
        [[lights]]
        position = [0, 0, -4]
        [[spheres]]
        center = [0, 0, 0]
        radius = 1.0
        material = "white"
    "#
    );
    let img = render_toml(&src, 1);
    let th = (20.0f64).to_radians().tan();
    let mut checked_hits = 0;
    for j in 0..h {
        for i in 0..w {
            // Camera looks down +z with up +y: right = f × up = −x.
            let px = (2.0 * (f64::from(i) + 0.5) / f64::from(w) - 1.0) * th;
            let py = (1.0 - 2.0 * (f64::from(j) + 0.5) / f64::from(h)) * th * f64::from(h) / f64::from(w);
            let d = glam::DVec3::new(-px, py, 1.0).normalize();
            let o = glam::DVec3::new(0.0, 0.0, -4.0);
            let b = o.dot(d);
            let disc = b * b - (o.dot(o) - 1.0);
            let got = img.get(i, j);
            if disc < -1e-4 {
                assert_eq!([got.x, got.y, got.z], [0.25, 0.5, 0.75], "background at ({i},{j})");
            } else if disc > 1e-4 {
                let t = -b - disc.sqrt();
                let n = o + d * t;
                let cos = n.dot(-d);
                assert!((f64::from(got.x) - cos).abs() < 1e-5, "({i},{j}): {} vs {cos}", got.x);
                checked_hits += 1;
            }
        }
    }
    assert!(checked_hits > 500, "the sphere covers a good part of the image: {checked_hits}");
}

#[test]
fn images_are_identical_at_one_and_two_threads() {
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/whitted.toml")).unwrap();
    let src = src.replace("width = 800", "width = 160").replace("height = 600", "height = 120");
    let one = render_toml(&src, 1);
    let two = render_toml(&src, 2);
    assert!(one.pixels.iter().zip(&two.pixels).all(|(a, b)| a.x.to_bits() == b.x.to_bits()
        && a.y.to_bits() == b.y.to_bits()
        && a.z.to_bits() == b.z.to_bits()));
}

/// The half-pixel pattern and the regular grid estimate the same pixel integral: on a smooth image they agree
/// closely, and both differ from one sample per pixel only at edges.
#[test]
fn half_pixel_pattern_agrees_with_a_fine_grid() {
    let base = r#"
        [camera]
        eye = [0, 0, -4]
        look_at = [0, 0, 0]
        hfov = 40
        width = 32
        height = 32
        [materials.white]
        color = [1, 1, 1]
        [[lights]]
        position = [-3, 3, -4]
        [[spheres]]
        center = [0, 0, 0]
        radius = 1.0
        material = "white"
        [render]
    "#;
    let fine = render_toml(&format!("{base}samples = 64\n"), 2);
    let half = render_toml(&format!("{base}pattern = \"half-pixel\"\n"), 2);
    let one = render_toml(base, 2);
    let err = |img: &Image| -> f32 {
        img.pixels.iter().zip(&fine.pixels).map(|(a, b)| (a.x - b.x).abs()).sum::<f32>()
            / fine.pixels.len() as f32
    };
    assert!(err(&half) < 0.5 * err(&one), "half-pixel {} vs one sample {}", err(&half), err(&one));
}

/// Every scene in scenes/ and scenes/stress/ renders to the same pixels, bit for bit, on the scalar path
/// (binary BVHs, one box and one primitive at a time) and at 1, 4, 8 and 16 lanes, on 1 and 2 threads: the
/// packet paths, single-ray SIMD and the scalar path are one computation. The ray counts agree too
/// (secondary packets with few live lanes are handed to the K = 1 tracer, whose counts must not be lost).
/// The scene is compiled once with the scalar trees; the scalar walk is switched off after the reference.
/// Compiled again with its spheres in the particle tree (`--accel pkd`), every scene but the coverage one
/// renders the same bits and counts.
#[test]
fn every_scene_is_identical_at_every_width_and_thread_count() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut scenes = scene_files(&root);
    scenes.extend(scene_files(&root.join("stress")));
    scenes.sort();
    let (mut checked, mut scalar_trees, mut particle_trees) = (0, 0, 0);
    for path in &scenes {
        let mut desc = bareray::io::load(path).unwrap();
        desc.camera.width = 96;
        desc.camera.height = 64;
        let options = bareray::compile::CompileOptions { scalar: true, ..Default::default() };
        let mut scene = Scene::compile_with_options(&desc, options).unwrap();
        scalar_trees += scene.geometry.bvhs().filter(|b| b.scalar.is_some() && b.scalar_walk).count();
        // The scalar path: K = 1 on the binary trees.
        let reference = render_lanes(&scene, 1, &thread_pool(Some(2)).unwrap(), &());
        assert!(scene.geometry.set_scalar_walk(false));
        for (lanes, threads) in [(1, 1), (1, 2), (4, 1), (4, 2), (8, 1), (8, 2), (16, 1), (16, 2)] {
            let rendered = render_lanes(&scene, lanes, &thread_pool(Some(threads)).unwrap(), &());
            assert_eq!(
                rendered.counts, reference.counts,
                "{path:?} counts at lanes {lanes}, threads {threads}"
            );
            let img = &rendered.image;
            let same = img.pixels.iter().zip(&reference.image.pixels).all(|(a, b)| {
                a.x.to_bits() == b.x.to_bits()
                    && a.y.to_bits() == b.y.to_bits()
                    && a.z.to_bits() == b.z.to_bits()
            });
            assert!(same, "{path:?} differs at lanes {lanes}, threads {threads}");
        }
        // The spheres in the particle tree instead of the BVH: the same bits (coverage prefilters spheres
        // from the BVH's arrays and does not take the tree).
        if desc.render.pattern != bareray::scene::desc::Pattern::Coverage {
            let options = bareray::compile::CompileOptions {
                accel: bareray::compile::Accel::Particles,
                ..Default::default()
            };
            let scene = Scene::compile_with_options(&desc, options).unwrap();
            assert_eq!(scene.geometry.particles.len(), desc.spheres.len());
            for (lanes, threads) in [(1, 1), (4, 2), (8, 1), (16, 2)] {
                let rendered = render_lanes(&scene, lanes, &thread_pool(Some(threads)).unwrap(), &());
                assert_eq!(rendered.counts, reference.counts, "{path:?} particle tree counts, lanes {lanes}");
                let same = rendered
                    .image
                    .pixels
                    .iter()
                    .zip(&reference.image.pixels)
                    .all(|(a, b)| [a.x, a.y, a.z].map(f32::to_bits) == [b.x, b.y, b.z].map(f32::to_bits));
                assert!(same, "{path:?} differs in the particle tree at lanes {lanes}, threads {threads}");
            }
            particle_trees += 1;
        }
        checked += 1;
    }
    assert!(checked >= 18, "toml, nff and xyzr scenes, and the stress scenes: {checked}");
    assert!(particle_trees >= 16, "only {particle_trees} scenes rendered with the particle tree");
    assert!(scalar_trees >= 10, "the scalar path walked only {scalar_trees} BVHs");
}

/// The per-pixel patterns (jittered strata, rotated R2, scrambled Sobol') give the same bits at every width
/// and thread count:
/// each pixel's positions come from its coordinates, not from the tile, thread or lane that traces it. They
/// also differ from the regular grid (the jitter is real) and converge toward the same image: with 16
/// samples each, both lie closer to a 64-sample stratified render than one centred sample does.
#[test]
fn per_pixel_patterns_are_deterministic_and_converge() {
    use bareray::scene::desc::Pattern;
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/whitted.toml")).unwrap();
    let mut desc = parse_toml(&src);
    desc.camera.width = 80;
    desc.camera.height = 60;
    let image = |pattern: Pattern, lanes: usize, threads: usize| {
        let mut d = desc.clone();
        d.render.pattern = pattern;
        let scene = Scene::compile(&d).unwrap();
        render_lanes(&scene, lanes, &thread_pool(Some(threads)).unwrap(), &()).image
    };
    let bits =
        |img: &Image| img.pixels.iter().flat_map(|p| [p.x, p.y, p.z]).map(f32::to_bits).collect::<Vec<_>>();
    for pattern in [Pattern::Stratified(2), Pattern::R2(3), Pattern::Sobol(4)] {
        let reference = bits(&image(pattern, 1, 1));
        for (lanes, threads) in [(1, 2), (4, 1), (4, 2), (8, 1), (16, 2)] {
            assert!(
                bits(&image(pattern, lanes, threads)) == reference,
                "{pattern:?} at {lanes} lanes, {threads} threads"
            );
        }
    }
    assert!(bits(&image(Pattern::Stratified(2), 8, 2)) != bits(&image(Pattern::Grid(2), 8, 2)));
    assert!(bits(&image(Pattern::Sobol(4), 8, 2)) != bits(&image(Pattern::Grid(2), 8, 2)));
    let fine = image(Pattern::Stratified(8), 16, 2);
    let err = |img: &Image| {
        img.pixels
            .iter()
            .zip(&fine.pixels)
            .map(|(a, b)| f64::from((a.x - b.x).abs() + (a.y - b.y).abs()))
            .sum::<f64>()
    };
    let one = err(&image(Pattern::Grid(1), 8, 2));
    for pattern in [Pattern::Stratified(4), Pattern::R2(16), Pattern::Sobol(16), Pattern::Grid(4)] {
        let e = err(&image(pattern, 8, 2));
        assert!(e < 0.5 * one, "{pattern:?}: {e} against one sample's {one}");
    }
}

/// Reconstruction filters: every filter gives the same bits at every width and thread count (each tile
/// traces its apron's samples again and sums in one order); a box of radius 0.5 is exactly the unfiltered
/// image (each sample counts in its own pixel only, summed in the same order); and on a scene of one colour
/// every filter, negative lobes included, gives that colour back.
#[test]
fn filters_are_deterministic_and_normalised() {
    use bareray::scene::desc::{Filter, FilterKind, Pattern};
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/whitted.toml")).unwrap();
    let mut desc = parse_toml(&src);
    desc.camera.width = 70;
    desc.camera.height = 50;
    let image = |desc: &bareray::scene::SceneDesc, lanes: usize, threads: usize| {
        let scene = Scene::compile(desc).unwrap();
        render_lanes(&scene, lanes, &thread_pool(Some(threads)).unwrap(), &()).image
    };
    let bits =
        |img: &Image| img.pixels.iter().flat_map(|p| [p.x, p.y, p.z]).map(f32::to_bits).collect::<Vec<_>>();
    let kinds = [FilterKind::Box, FilterKind::Tent, FilterKind::Gaussian, FilterKind::Mitchell];
    for (kind, pattern) in
        kinds.into_iter().zip([Pattern::Grid(2), Pattern::Stratified(2), Pattern::R2(3), Pattern::Grid(1)])
    {
        let mut d = desc.clone();
        d.render.pattern = pattern;
        d.render.filter = Some(Filter { kind, radius: Filter::default_radius(kind) + 0.3 });
        let reference = bits(&image(&d, 1, 1));
        for (lanes, threads) in [(4, 2), (8, 1), (16, 2)] {
            assert!(
                bits(&image(&d, lanes, threads)) == reference,
                "{kind:?} at {lanes} lanes, {threads} threads"
            );
        }
        d.render.filter = None;
        assert!(bits(&image(&d, 8, 2)) != reference, "{kind:?} changes the image");
    }
    for pattern in [Pattern::Grid(2), Pattern::Stratified(3)] {
        let mut d = desc.clone();
        d.render.pattern = pattern;
        let plain = bits(&image(&d, 8, 2));
        d.render.filter = Some(Filter { kind: FilterKind::Box, radius: 0.5 });
        assert!(bits(&image(&d, 8, 2)) == plain, "{pattern:?}: box 0.5 is the unfiltered image");
    }
    // Nothing in view: every sample is the background colour.
    let mut empty = desc.clone();
    empty.spheres.clear();
    empty.kinds.ellipsoids.clear();
    empty.kinds.planes.clear();
    empty.render.background = bareray::math::V3::new(0.25, 0.5, 0.75);
    for kind in kinds {
        empty.render.filter = Some(Filter { kind, radius: 2.0 });
        for p in &image(&empty, 8, 2).pixels {
            assert!(
                (p.x - 0.25).abs() < 1e-6 && (p.y - 0.5).abs() < 1e-6 && (p.z - 0.75).abs() < 1e-6,
                "{kind:?}: {p:?}"
            );
        }
    }
}

/// Adaptive supersampling gives the same bits and ray counts on the scalar path, at 1, 4, 8 and 16 lanes on
/// 1 and 2 threads, and with the spheres in the particle tree, on every scene in scenes/ and scenes/stress/:
/// every split depends only on the colours, primitive ids and depths of lattice points, which each ray
/// gets with the bits of its one-lane trace whatever packet it travels in.
#[test]
fn adaptive_sampling_is_identical_at_every_width_and_thread_count() {
    use bareray::compile::{Accel, CompileOptions};
    use bareray::scene::desc::Pattern;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut scenes = scene_files(&root);
    scenes.extend(scene_files(&root.join("stress")));
    let bits =
        |img: &Image| img.pixels.iter().flat_map(|p| [p.x, p.y, p.z]).map(f32::to_bits).collect::<Vec<_>>();
    for path in &scenes {
        let mut desc = bareray::io::load(path).unwrap();
        (desc.camera.width, desc.camera.height) = (56, 40);
        desc.render.pattern = Pattern::Adaptive { threshold: 0.05, depth: 3 };
        let mut scene =
            Scene::compile_with_options(&desc, CompileOptions { scalar: true, ..Default::default() })
                .unwrap();
        let reference = render_lanes(&scene, 1, &thread_pool(Some(2)).unwrap(), &());
        assert!(reference.counts.primary >= 57 * 41, "{path:?}: every pixel corner");
        assert!(scene.geometry.set_scalar_walk(false));
        let particles = Scene::compile_with_options(
            &desc,
            CompileOptions { accel: Accel::Particles, ..Default::default() },
        )
        .unwrap();
        let runs = [(1, 1), (4, 2), (8, 1), (16, 1), (16, 2)].map(|w| (&scene, w, "BVH"));
        for (scene, (lanes, threads), accel) in
            runs.into_iter().chain([(&particles, (16, 2), "particle tree")])
        {
            let r = render_lanes(scene, lanes, &thread_pool(Some(threads)).unwrap(), &());
            assert_eq!(
                r.counts, reference.counts,
                "{path:?} counts at lanes {lanes}, threads {threads}, {accel}"
            );
            assert!(
                bits(&r.image) == bits(&reference.image),
                "{path:?} differs at lanes {lanes}, threads {threads}, {accel}"
            );
        }
    }
}

/// Adaptive supersampling on whitted.toml: with nothing in view it traces each pixel corner once (tiles share
/// their edges); it spends more rays where the image has edges, far fewer than splitting every pixel, and
/// comes closer to a 64-sample reference than one sample per pixel does.
#[test]
fn adaptive_sampling_traces_corners_once_and_splits_at_edges() {
    use bareray::scene::desc::Pattern;
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/whitted.toml")).unwrap();
    let mut desc = parse_toml(&src);
    desc.camera.width = 72;
    desc.camera.height = 48;
    let run = |desc: &bareray::scene::SceneDesc, pattern: Pattern| {
        let mut d = desc.clone();
        d.render.pattern = pattern;
        let scene = Scene::compile(&d).unwrap();
        render_lanes(&scene, 8, &thread_pool(Some(2)).unwrap(), &())
    };
    let adaptive = Pattern::Adaptive { threshold: 0.1, depth: 2 };
    let mut empty = desc.clone();
    empty.spheres.clear();
    empty.kinds.ellipsoids.clear();
    empty.kinds.planes.clear();
    let corners = 73 * 49;
    assert_eq!(run(&empty, adaptive).counts.primary, corners, "nothing in view: each corner once");
    // Splitting every pixel to depth 2 would trace the whole lattice of quarter-pixel points.
    let full = (4 * 72 + 1) * (4 * 48 + 1);
    let rendered = run(&desc, adaptive);
    let primary = rendered.counts.primary;
    assert!(
        primary > corners && primary < full / 2,
        "{primary} rays: corners {corners}, full lattice {full}"
    );
    let fine = run(&desc, Pattern::Stratified(8)).image;
    let err = |img: &Image| {
        img.pixels
            .iter()
            .zip(&fine.pixels)
            .map(|(a, b)| f64::from((a.x - b.x).abs() + (a.y - b.y).abs()))
            .sum::<f64>()
    };
    let one = err(&run(&desc, Pattern::Grid(1)).image);
    let ours = err(&rendered.image);
    assert!(ours < 0.7 * one, "adaptive {ours} against one sample's {one}");
}

/// The coverage pattern gives the same bits and ray counts at every width and thread count on every scene
/// in scenes/ and scenes/stress/ (spheres with polygons, planes, shapes and cones; ground spheres crossing
/// the eye's plane; reflections and refractions): a pixel's parts depend only on the pixel, and each part's
/// ray is traced with the bits of its one-lane trace.
#[test]
fn coverage_is_identical_at_every_width_and_thread_count() {
    use bareray::scene::desc::Pattern;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut scenes = scene_files(&root);
    scenes.extend(scene_files(&root.join("stress")));
    scenes.sort();
    let bits =
        |img: &Image| img.pixels.iter().flat_map(|p| [p.x, p.y, p.z]).map(f32::to_bits).collect::<Vec<_>>();
    for path in &scenes {
        let mut desc = bareray::io::load(path).unwrap();
        (desc.camera.width, desc.camera.height) = (72, 40);
        desc.render.pattern = Pattern::Coverage;
        let scene = Scene::compile(&desc).unwrap();
        let reference = render_lanes(&scene, 1, &thread_pool(Some(1)).unwrap(), &());
        let pixels = 72 * 40;
        assert!(reference.counts.primary >= pixels, "{path:?}: at least one ray a pixel");
        for (lanes, threads) in [(1, 2), (4, 1), (8, 2), (16, 1), (16, 2)] {
            let r = render_lanes(&scene, lanes, &thread_pool(Some(threads)).unwrap(), &());
            assert_eq!(r.counts, reference.counts, "{path:?} counts at lanes {lanes}, threads {threads}");
            assert!(
                bits(&r.image) == bits(&reference.image),
                "{path:?} differs at lanes {lanes}, threads {threads}"
            );
        }
    }
}

/// The per-pixel patterns on a scene with a sphere BVH, where camera packets carry their block's pyramid
/// for frustum culling: the pyramid must enclose every lane's jittered position, not only the first and
/// last lane's, or nodes a lane needs are culled and the image depends on the packet width.
#[test]
fn per_pixel_patterns_are_identical_at_every_width_with_frustum_culling() {
    use bareray::scene::desc::Pattern;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/field.toml");
    let mut desc = bareray::io::load(&path).unwrap();
    (desc.camera.width, desc.camera.height) = (128, 72);
    let bits =
        |img: &Image| img.pixels.iter().flat_map(|p| [p.x, p.y, p.z]).map(f32::to_bits).collect::<Vec<_>>();
    for pattern in [Pattern::Stratified(3), Pattern::R2(5), Pattern::Sobol(6)] {
        desc.render.pattern = pattern;
        let scene = Scene::compile(&desc).unwrap();
        assert!(scene.geometry.culls_by_pyramid());
        let pool = thread_pool(Some(2)).unwrap();
        let reference = bits(&render_lanes(&scene, 1, &pool, &()).image);
        for lanes in [4, 8, 16] {
            let image = render_lanes(&scene, lanes, &pool, &()).image;
            assert!(bits(&image) == reference, "{pattern:?} at {lanes} lanes");
        }
    }
}
