//! The render loop: the image is cut into tiles, tiles are traced in parallel (rayon), and each pixel's
//! samples are combined in a fixed order, so the image is the same bits at any thread count.

use std::time::Instant;

use indicatif::ProgressBar;
use rayon::prelude::*;

use crate::film::Image;
use crate::math::Rgb;
use crate::sample::{grid_offsets, lecture_3x3, HALF_PIXEL_WEIGHTS};
use crate::scene::desc::{Pattern, PostFilter};
use crate::scene::Scene;
use crate::shade::{RayCounts, Tracer};

/// Tile edge in pixels: small enough to balance two threads on small images, large enough to amortise.
const TILE: u32 = 16;

/// A finished render.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The filtered image.
    pub image: Image,
    /// Rays traced by kind.
    pub counts: RayCounts,
    /// Wall-clock seconds spent tracing and filtering.
    pub seconds: f64,
}

#[derive(Clone, Copy, Debug)]
struct Tile {
    x0: u32,
    y0: u32,
    w: u32,
    h: u32,
}

fn tiles(width: u32, height: u32) -> Vec<Tile> {
    let mut out = Vec::new();
    for y0 in (0..height).step_by(TILE as usize) {
        for x0 in (0..width).step_by(TILE as usize) {
            out.push(Tile { x0, y0, w: TILE.min(width - x0), h: TILE.min(height - y0) });
        }
    }
    out
}

/// A pool of `threads` workers (rayon's default when `None`): each render gets its own pool so that
/// `--threads` holds even when the caller already runs inside rayon.
pub fn thread_pool(threads: Option<usize>) -> Result<rayon::ThreadPool, rayon::ThreadPoolBuildError> {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        builder = builder.num_threads(n);
    }
    builder.build()
}

/// Renders `scene` on `threads` threads (rayon's default when `None`), ticking `progress` once per tile.
pub fn render(
    scene: &Scene,
    threads: Option<usize>,
    progress: &ProgressBar,
) -> Result<Rendered, rayon::ThreadPoolBuildError> {
    let start = Instant::now();
    let (width, height) = (scene.camera.width, scene.camera.height);
    let tiles = tiles(width, height);
    progress.set_length(tiles.len() as u64);
    let pool = thread_pool(threads)?;
    let traced: Vec<(Tile, Vec<Rgb>, RayCounts)> = pool.install(|| {
        tiles
            .par_iter()
            .map(|&tile| {
                let mut tracer = Tracer::new(scene);
                let pixels = trace_tile(scene, &mut tracer, tile);
                progress.inc(1);
                (tile, pixels, tracer.counts)
            })
            .collect()
    });
    let mut image = Image::new(width, height);
    let mut counts = RayCounts::default();
    for (tile, pixels, c) in traced {
        counts += c;
        for (i, p) in pixels.into_iter().enumerate() {
            let i = i as u32;
            image.set(tile.x0 + i % tile.w, tile.y0 + i / tile.w, p);
        }
    }
    if scene.render.postfilter == PostFilter::Lecture3x3 {
        image = lecture_3x3(&image);
    }
    Ok(Rendered { image, counts, seconds: start.elapsed().as_secs_f64() })
}

/// The pixels of one tile, row by row.
fn trace_tile(scene: &Scene, tracer: &mut Tracer, tile: Tile) -> Vec<Rgb> {
    let cam = &scene.camera;
    match scene.render.pattern {
        Pattern::Grid(n) => {
            let offsets = grid_offsets(n);
            let scale = 1.0 / offsets.len() as f32;
            let mut out = Vec::with_capacity((tile.w * tile.h) as usize);
            for y in tile.y0..tile.y0 + tile.h {
                for x in tile.x0..tile.x0 + tile.w {
                    let mut sum = Rgb::default();
                    for &(dx, dy) in &offsets {
                        sum = sum + tracer.primary(&cam.ray(x as f32 + dx, y as f32 + dy));
                    }
                    out.push(sum * scale);
                }
            }
            out
        }
        Pattern::HalfPixel => half_pixel_tile(scene, tracer, tile),
    }
}

/// The 9-sample half-pixel grid: a (2w+1)×(2h+1) lattice at half-pixel spacing over the tile, each interior
/// sample shared by up to four pixels, combined with the trapezoid weights.
fn half_pixel_tile(scene: &Scene, tracer: &mut Tracer, tile: Tile) -> Vec<Rgb> {
    let (lw, lh) = (2 * tile.w + 1, 2 * tile.h + 1);
    let mut lattice = Vec::with_capacity((lw * lh) as usize);
    for b in 0..lh {
        for a in 0..lw {
            let sx = tile.x0 as f32 + a as f32 * 0.5;
            let sy = tile.y0 as f32 + b as f32 * 0.5;
            lattice.push(tracer.primary(&scene.camera.ray(sx, sy)));
        }
    }
    let mut out = Vec::with_capacity((tile.w * tile.h) as usize);
    for y in 0..tile.h {
        for x in 0..tile.w {
            let mut sum = Rgb::default();
            for (dy, row) in HALF_PIXEL_WEIGHTS.iter().enumerate() {
                for (dx, &k) in row.iter().enumerate() {
                    sum = sum + lattice[((2 * y + dy as u32) * lw + 2 * x + dx as u32) as usize] * k;
                }
            }
            out.push(sum);
        }
    }
    out
}
