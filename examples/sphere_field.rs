//! Builds a scene in code, with no scene file: a field of coloured spheres on a mirror-ish floor sphere,
//! a camera, one point light, and renders it.
//!
//! Run: `cargo run --release --example sphere_field -- field.png [COUNT]` (COUNT spheres, 400 by default).

use std::path::PathBuf;

use bareray::compile::Scene;
use bareray::kinds::sphere::SphereDesc;
use bareray::math::{Rgb, SplitMix64};
use bareray::scene::desc::{Aim, CameraDesc, Field, LightDesc, Material, Pattern, RenderDesc, SceneDesc};
use bareray::{output, render};
use glam::DVec3;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let Some(out_path) = args.next().map(PathBuf::from) else {
        eprintln!("usage: sphere_field OUTPUT [COUNT]");
        std::process::exit(2);
    };
    let count: usize = args.next().map_or(Ok(400), |n| n.parse())?;

    // Material 0 is the floor, 1.. are the balls' colours; spheres refer to materials by index.
    let mut materials =
        vec![Material { color: Rgb::all(0.5), reflect: 0.4, specular: 0.3, ..Material::default() }];
    let palette = [(0.9, 0.2, 0.2), (0.2, 0.7, 0.3), (0.2, 0.4, 0.9), (0.9, 0.8, 0.2), (0.8, 0.8, 0.8)];
    materials.extend(palette.iter().map(|&(r, g, b)| Material {
        color: Rgb::new(r, g, b),
        specular: 0.5,
        shininess: 60.0,
        ..Material::default()
    }));

    // A huge sphere as the floor under y = 0, and the balls resting on it, placed by a seeded generator
    // so every run builds the same scene.
    let floor = 1e4;
    let mut spheres = vec![SphereDesc { center: DVec3::new(0.0, -floor, 0.0), radius: floor, material: 0 }];
    let mut rng = SplitMix64::new(7);
    for _ in 0..count {
        let radius = 0.15 + 0.25 * rng.unit();
        let (x, z) = (20.0 * rng.unit() - 10.0, 20.0 * rng.unit() - 10.0);
        let material = 1 + (rng.next_u64() % palette.len() as u64) as u32;
        spheres.push(SphereDesc { center: DVec3::new(x, radius, z), radius, material });
    }

    let desc = SceneDesc {
        camera: CameraDesc {
            eye: DVec3::new(0.0, 6.0, -16.0),
            aim: Aim::LookAt(DVec3::new(0.0, 0.0, 0.0)),
            field: Field::HorizontalAngle(50.0),
            width: 800,
            height: 500,
            ..CameraDesc::default()
        },
        render: RenderDesc {
            pattern: Pattern::Grid(2), // 2×2 samples per pixel
            background: Rgb::new(0.5, 0.7, 1.0),
            ambient: Rgb::all(0.3),
            ..RenderDesc::default()
        },
        materials,
        lights: vec![LightDesc {
            position: DVec3::new(-10.0, 20.0, -10.0),
            color: Rgb::all(1.0),
            falloff: Default::default(),
        }],
        spheres,
        ..SceneDesc::default()
    };

    let pool = render::thread_pool(None)?;
    let scene = pool.install(|| Scene::compile(&desc))?;
    let rendered = render::render_lanes(&scene, 8, &pool, &());
    output::write_image(&rendered.image, &out_path, scene.render.transfer)?;
    println!(
        "{}: {} spheres, {} rays in {:.3} s",
        out_path.display(),
        desc.spheres.len(),
        rendered.counts.total(),
        rendered.seconds
    );
    Ok(())
}
