//! What `render --stats` says of the scene and the image before its figures: the primitives, the image and
//! its settings, the features the render path uses, the rendering space of a far scene, and how each kind
//! is searched.

use std::fmt::Write;

use super::Job;
use crate::bvh::Bvh;
use crate::compile::features::Features;
use crate::compile::Scene;
use crate::render::Window;
use crate::settings::{shade_name, PatternName};

/// The scene, image, features, far-scene (where the scene has its own frame) and accel lines of
/// `render --stats` for `scene` rendered as `job` asks, each ending in a newline.
pub fn describe(scene: &Scene, job: &Job) -> String {
    let g = &scene.geometry;
    let features = Features::of(scene);
    let n = features.counts;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "scene: {} ({}{}), {}, {}{}",
        plural(g.len(), "primitive"),
        plural(n.spheres, "sphere"),
        g.kinds.counted().iter().map(|c| format!(", {c}")).collect::<String>(),
        plural(scene.lights.len(), "light"),
        plural(scene.materials.len(), "material"),
        match g.sphere_colors() {
            0 => String::new(),
            c => format!(", {} (3 bytes each)", plural(c, "sphere colour")),
        }
    );
    let w = job.window;
    let region = if w == Window::whole(scene.camera.width, scene.camera.height) {
        String::new()
    } else {
        format!(
            " (region {},{},{},{} of {}x{})",
            w.x0, w.y0, w.x1, w.y1, scene.camera.width, scene.camera.height
        )
    };
    let _ = writeln!(
        out,
        "image: {}x{}{region}, {}, {} shading, {} transfer, in bands of {} rows",
        w.width(),
        w.height(),
        PatternName::of(scene.render.pattern).long,
        shade_name(scene.render.shade),
        scene.render.transfer.name(),
        job.band_rows()
    );
    let _ = writeln!(out, "features: {features}");
    if scene.camera_f64.start != 0.0 {
        let o = scene.origin;
        let _ = writeln!(
            out,
            "far scene: rendering space centred on the geometry at ({}, {}, {}), camera rays start {} from the eye",
            o.x, o.y, o.z, scene.camera_f64.start
        );
    }
    let search = |bvh: &Option<Bvh>| if bvh.is_some() { "BVH" } else { "brute force" };
    let spheres = match (&scene.accel_note, g.particles.is_empty()) {
        (_, true) => {
            format!("{} ({:.1} bytes/sphere with the nodes)", search(&g.sphere_bvh), scene.bytes_per_sphere())
        }
        (why, false) => format!(
            "the particle tree{} ({:.1} bytes/sphere with the keys{}{})",
            if g.particles.is_mapped() { " over the mapped file" } else { "" },
            scene.bytes_per_sphere(),
            if why.is_some() { "; chosen by auto: " } else { "" },
            why.as_deref().unwrap_or_default()
        ),
    };
    let _ = writeln!(
        out,
        "accel: spheres by {spheres}{}",
        (crate::kinds::NAMES.iter().zip(g.kinds.trees()).zip(g.kinds.counts()))
            .filter(|(_, n)| *n > 0)
            .map(|((name, tree), _)| format!(", {name} by {}", if tree { "BVH" } else { "brute force" }))
            .collect::<String>(),
    );
    out
}

/// `n thing` or `n things`.
fn plural(n: usize, thing: &str) -> String {
    if n == 1 {
        format!("1 {thing}")
    } else {
        format!("{n} {thing}s")
    }
}
