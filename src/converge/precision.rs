//! Precision against time for primary hits: the f32 packet path, f32 single-ray SIMD (K = 1), the f32 scalar
//! path (binary BVHs, one box and one primitive at a time; when the scene was compiled with
//! [`crate::compile::CompileOptions::scalar`]) and the f64 twin (`crate::accuracy::Twin`), each timed over one camera ray per pixel centre, the f32 paths measured
//! against the f64 one: the fraction of pixels whose hit names another primitive (or hits where the other
//! misses), and the relative t error over the pixels that agree.

use std::time::Instant;

use rayon::prelude::*;

use crate::accuracy::{Hit64, Twin};
use crate::compile::Scene;
use crate::geometry::{Departure, NO_PRIM};
use crate::render::primary_hits_lanes;
use crate::scene::SceneDesc;

/// One path's time and error.
#[derive(Clone, Debug, PartialEq)]
pub struct PathRun {
    /// `f32 packets (K = 16)`, `f32 single-ray SIMD (K = 1)`, `f32 scalar` or `f64 twin`.
    pub path: String,
    /// Wall-clock seconds for every pixel's primary hit.
    pub seconds: f64,
    /// Fraction of pixels whose hit differs from the f64 path's (another primitive, or hit against miss).
    pub disagree: f64,
    /// Relative t error `|t − t64| / t64` over the agreeing hits: median, 99th percentile, largest.
    pub t_err: [f64; 3],
}

/// Times the paths on `desc` (compiled as `scene`) at `lanes` for the packet path; the scalar path only where
/// the scene has its binary trees, and its scalar walk is on afterwards exactly then (as compiling leaves it).
pub fn primary_paths(
    desc: &SceneDesc,
    scene: &mut Scene,
    lanes: usize,
    pool: &rayon::ThreadPool,
) -> Result<Vec<PathRun>, crate::camera::CameraError> {
    let twin = Twin::new(desc)?;
    let (w, h) = (scene.camera.width, scene.camera.height);
    let clock = Instant::now();
    let exact: Vec<Hit64> = pool.install(|| {
        (0..w * h)
            .into_par_iter()
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let ray = twin.camera_ray(f64::from(x) + 0.5, f64::from(y) + 0.5);
                twin.intersect(&ray, Departure::CAMERA, f64::INFINITY)
            })
            .collect()
    });
    let f64_seconds = clock.elapsed().as_secs_f64();
    let mut runs = Vec::new();
    // The scalar walk is on only for the scalar path, which runs where the scene has the binary trees.
    let scalar = scene.geometry.set_scalar_walk(true);
    let paths = [
        (lanes, false, format!("f32 packets (K = {lanes})")),
        (1, false, "f32 single-ray SIMD (K = 1)".to_owned()),
        (1, true, "f32 scalar".to_owned()),
    ];
    for (k, walk, name) in paths.into_iter().filter(|&(_, walk, _)| !walk || scalar) {
        scene.geometry.set_scalar_walk(walk);
        let hits = primary_hits_lanes(scene, k, pool);
        let (mut disagree, mut errs) = (0usize, Vec::new());
        for ((&t, &prim), e) in hits.t.iter().zip(&hits.prim).zip(&exact) {
            let id = if prim == NO_PRIM { NO_PRIM } else { scene.geometry.file_id(prim) };
            if id != e.prim {
                disagree += 1;
            } else if e.is_hit() {
                errs.push((f64::from(t) - e.t).abs() / e.t);
            }
        }
        runs.push(PathRun {
            path: name,
            seconds: hits.seconds,
            disagree: disagree as f64 / exact.len().max(1) as f64,
            t_err: percentiles(errs),
        });
    }
    scene.geometry.set_scalar_walk(scalar);
    runs.push(PathRun { path: "f64 twin".to_owned(), seconds: f64_seconds, disagree: 0.0, t_err: [0.0; 3] });
    Ok(runs)
}

/// Nearest-rank median, 99th percentile and maximum of `v` (zeros when empty).
fn percentiles(mut v: Vec<f64>) -> [f64; 3] {
    if v.is_empty() {
        return [0.0; 3];
    }
    v.sort_by(f64::total_cmp);
    let rank = |p: f64| v[((p * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
    [rank(0.5), rank(0.99), v[v.len() - 1]]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_are_nearest_rank() {
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(percentiles(v), [50.0, 99.0, 100.0]);
        assert_eq!(percentiles(vec![]), [0.0; 3]);
    }
}
