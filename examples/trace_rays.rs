//! Traces rays of your own against a compiled scene, without rendering: one ray at a time
//! (`Geometry::intersect`) and eight at a time (`Geometry::intersect_k` on a `RayPacket<f32x8>`), prints the
//! hits and checks that both agree, lane by lane and bit for bit.
//!
//! Run: `cargo run --release --example trace_rays -- scenes/whitted.toml [RAYS]` (RAYS camera rays spread
//! over the image, 24 by default, then the same number straight down from above the eye).

use std::path::Path;

use bareray::compile::Scene;
use bareray::geometry::{Departure, DeparturePacket, Hit, Ray, RayPacket};
use bareray::io;
use bareray::math::V3;
use glam::DVec3;
use wide::f32x8;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let Some(scene_path) = args.next() else {
        eprintln!("usage: trace_rays SCENE [RAYS]");
        std::process::exit(2);
    };
    let n: usize = args.next().map_or(Ok(24), |n| n.parse())?;
    let desc = io::load(Path::new(&scene_path))?;
    let scene = Scene::compile(&desc)?;

    // The compiled scene lives in rendering space: the camera's eye is its origin. Camera rays come from the
    // camera; other rays start at world points mapped by `to_rendering`.
    let (width, height) = (scene.camera.width as f32, scene.camera.height as f32);
    let mut rays: Vec<Ray<f32>> = (0..n)
        .map(|i| {
            let u = (i as f32 + 0.5) / n as f32;
            scene.camera_f64.ray_f32(u * width, (0.25 + 0.5 * u) * height)
        })
        .collect();
    let above = desc.camera.eye + DVec3::new(0.0, 100.0, 0.0);
    rays.extend((0..n).map(|i| {
        let x = (i as f64 / n.max(2) as f64 - 0.5) * 8.0;
        Ray::new(scene.to_rendering(above + DVec3::new(x, 0.0, 0.0)), V3::new(0.0, -1.0, 0.0))
    }));

    // One ray at a time (K = 1).
    let scalar: Vec<Hit> =
        rays.iter().map(|ray| scene.geometry.intersect(ray, Departure::CAMERA, f32::INFINITY)).collect();

    // Eight at a time: a packet per chunk; lanes past the end of the last chunk are inactive.
    let mut packed = Vec::with_capacity(rays.len());
    for chunk in rays.chunks(8) {
        let packet = RayPacket::<f32x8>::from_rays(chunk, f32::INFINITY);
        let hits = scene.geometry.intersect_k(&packet, &DeparturePacket::camera());
        packed.extend((0..chunk.len()).map(|i| hits.lane(i)));
    }

    let mut disagree = 0;
    for (i, ((ray, one), eight)) in rays.iter().zip(&scalar).zip(&packed).enumerate() {
        let what = if one.is_hit() {
            let world = scene.origin + DVec3::from(ray.at(one.t).to_f64());
            format!(
                "primitive {:>3} at t = {:<10.4} world ({:.3}, {:.3}, {:.3})",
                scene.geometry.file_id(one.prim),
                one.t,
                world.x,
                world.y,
                world.z
            )
        } else {
            "miss".to_owned()
        };
        let same = one.t.to_bits() == eight.t.to_bits() && one.prim == eight.prim;
        disagree += usize::from(!same);
        println!("ray {i:>3}: {what}{}", if same { "" } else { "  <- the packet differs" });
    }
    println!("{} rays: scalar and 8-wide packets agree on {}", rays.len(), rays.len() - disagree);
    if disagree > 0 {
        std::process::exit(1);
    }
    Ok(())
}
