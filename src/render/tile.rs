//! One tile's pixels under each sampling pattern: the shared-offset and per-pixel passes, the reconstruction
//! filters (with an apron of neighbouring pixels traced again), the lecture's half-pixel grid and the
//! coverage pattern (`coverage/`); adaptive subdivision traces whole bands (`adaptive/`). Every pixel's value
//! depends only on its own samples (and, under a filter, its neighbours'), never on where the tile starts, so
//! any cut of the image into tiles gives the same bits.

use crate::compile::Scene;
use crate::math::Rgb;
use crate::sample::{grid_offsets, sequence, HALF_PIXEL_WEIGHTS};
use crate::scene::desc::{Filter, Pattern};
use crate::shade::Tracer;
use crate::simd::Lanes;

use super::{for_each_camera_hit, lane_rgb, LargePacket, Offsets, Tile};

/// Traces one tile into `rows`, its rows of the band (each `tile.w` pixels): every pixel is written.
pub(super) fn trace_tile<F: Lanes>(
    scene: &Scene,
    tracer: &mut Tracer<F>,
    tile: Tile,
    rows: &mut [&mut [Rgb]],
) {
    debug_assert!(
        rows.len() == tile.h as usize && rows.iter().all(|r| r.len() == tile.w as usize),
        "{tile:?}"
    );
    let pattern = scene.render.pattern;
    let pixels = match pattern {
        Pattern::HalfPixel => half_pixel_tile(scene, tracer, tile),
        Pattern::Adaptive { .. } => unreachable!("adaptive sampling traces whole bands (adaptive/)"),
        Pattern::Coverage => super::coverage::coverage_tile(scene, tracer, tile),
        Pattern::Grid(_) | Pattern::Stratified(_) | Pattern::R2(_) | Pattern::Sobol(_) => {
            match scene.render.filter {
                Some(filter) => filtered_tile(scene, tracer, tile, filter),
                None => return sampled_tile(scene, tracer, tile, rows),
            }
        }
    };
    debug_assert_eq!(pixels.len(), rows.len() * tile.w as usize, "{tile:?}");
    for (row, traced) in rows.iter_mut().zip(pixels.chunks_exact(tile.w as usize)) {
        row.copy_from_slice(traced);
    }
}

/// The pixels of one tile under a sampling pattern without a reconstruction filter (the mean of each
/// pixel's samples), summed in place in `rows`, its rows.
fn sampled_tile<F: Lanes>(scene: &Scene, tracer: &mut Tracer<F>, tile: Tile, rows: &mut [&mut [Rgb]]) {
    let pattern = scene.render.pattern;
    let count = pattern.rays_per_pixel() as u32;
    // One pass writes each pixel once: `0 + c` (so a −0 channel is +0, as the sum from zero gives) and no
    // scaling by one, the same bits without clearing the rows first or reading them twice more.
    let single = count == 1;
    if !single {
        rows.iter_mut().for_each(|row| row.fill(Rgb::default()));
    }
    let mut large = LargePacket::default();
    let mut pass = |offsets: &Offsets| {
        for_each_camera_hit(scene, tile, offsets, &mut large, |rays, hit, block| {
            let c = tracer.primary_from(rays, hit);
            // The lanes read from arrays taken once: `lane` on the packet stored it again for every pixel.
            let (r, g, b) = (c.x.to_array(), c.y.to_array(), c.z.to_array());
            let (r, g, b) = (r.as_ref(), g.as_ref(), b.as_ref());
            for (i, x, y) in block.pixels() {
                let p = &mut rows[y as usize][x as usize];
                let sum = if single { Rgb::default() } else { *p };
                *p = sum + Rgb::new(r[i], g[i], b[i]);
            }
        });
    };
    let grid = grid_of(pattern);
    for k in 0..count {
        match pattern {
            // The regular grid's offset is the same in every pixel: splatted, not computed per lane.
            Pattern::Grid(_) => pass(&Offsets::Shared(grid[k as usize].0, grid[k as usize].1)),
            _ => pass(&Offsets::PerPixel(&|x, y| sample_offset(pattern, &grid, k, x, y))),
        }
    }
    if !single {
        let scale = 1.0 / count as f32;
        rows.iter_mut().flat_map(|row| row.iter_mut()).for_each(|p| *p = *p * scale);
    }
}

/// The regular grid's offsets for [`sample_offset`] (empty for the other patterns).
fn grid_of(pattern: Pattern) -> Vec<(f32, f32)> {
    match pattern {
        Pattern::Grid(n) => grid_offsets(n),
        _ => Vec::new(),
    }
}

/// Sample `k`'s position in pixel `(x, y)` (image column and row) under a per-pixel or shared pattern, as
/// [`trace_tile`] traces it (`grid` from [`grid_of`]). Not for the half-pixel, adaptive and coverage
/// patterns.
fn sample_offset(pattern: Pattern, grid: &[(f32, f32)], k: u32, x: u32, y: u32) -> (f32, f32) {
    match pattern {
        Pattern::Grid(_) => grid[k as usize],
        Pattern::Stratified(n) => sequence::stratified(n, x, y, k),
        Pattern::R2(_) => sequence::r2(x, y, k),
        Pattern::Sobol(_) => sequence::sobol(x, y, k),
        Pattern::HalfPixel | Pattern::Adaptive { .. } | Pattern::Coverage => {
            unreachable!("the half-pixel, adaptive and coverage patterns have their own reconstruction")
        }
    }
}

/// The pixels of one tile under a reconstruction filter: the samples of the tile and of an apron of
/// neighbouring pixels (those whose samples reach the tile's pixels, [`Filter::apron`]) are traced, each
/// pixel's colour is the filter-weighted sum of the samples within its radius over the sum of their weights.
/// Neighbouring tiles trace their shared aprons again (at radius 1.5, 16×16 tiles trace 18×18 pixels: 1.27x
/// the rays), which keeps every tile independent: each sample's colour is the same bits whichever tile,
/// thread or packet width traces it, and the sums run in one fixed order, so the image is too.
fn filtered_tile<F: Lanes>(scene: &Scene, tracer: &mut Tracer<F>, tile: Tile, filter: Filter) -> Vec<Rgb> {
    let (width, height) = (scene.camera.width, scene.camera.height);
    let a = filter.apron();
    let (x0, y0) = (tile.x0.saturating_sub(a), tile.y0.saturating_sub(a));
    let ext = Tile {
        x0,
        y0,
        w: (tile.x0 + tile.w + a).min(width) - x0,
        h: (tile.y0 + tile.h + a).min(height) - y0,
    };
    let pattern = scene.render.pattern;
    let grid = grid_of(pattern);
    let count = pattern.rays_per_pixel() as u32;
    let area = (ext.w * ext.h) as usize;
    let mut samples = vec![Rgb::default(); area * count as usize];
    let mut large = LargePacket::default();
    for k in 0..count {
        let at = |x: u32, y: u32| sample_offset(pattern, &grid, k, x, y);
        let plane = &mut samples[k as usize * area..][..area];
        for_each_camera_hit(scene, ext, &Offsets::PerPixel(&at), &mut large, |rays, hit, block| {
            let c = tracer.primary_from(rays, hit);
            for (i, x, y) in block.pixels() {
                plane[(y * ext.w + x) as usize] = lane_rgb(&c, i);
            }
        });
    }
    let mut out = Vec::with_capacity((tile.w * tile.h) as usize);
    for y in tile.y0..tile.y0 + tile.h {
        for x in tile.x0..tile.x0 + tile.w {
            let (cx, cy) = (x as f32 + 0.5, y as f32 + 0.5);
            let (mut sum, mut weight) = (Rgb::default(), 0.0f32);
            for ny in y.saturating_sub(a).max(ext.y0)..(y + a + 1).min(ext.y0 + ext.h) {
                for nx in x.saturating_sub(a).max(ext.x0)..(x + a + 1).min(ext.x0 + ext.w) {
                    let p = ((ny - ext.y0) * ext.w + (nx - ext.x0)) as usize;
                    for k in 0..count {
                        let (ox, oy) = sample_offset(pattern, &grid, k, nx, ny);
                        let w = filter.weight(nx as f32 + ox - cx, ny as f32 + oy - cy);
                        sum = sum + samples[k as usize * area + p] * w;
                        weight += w;
                    }
                }
            }
            out.push(if weight != 0.0 { sum * (1.0 / weight) } else { Rgb::default() });
        }
    }
    out
}

/// The 9-sample half-pixel grid: a (2w+1)×(2h+1) lattice at half-pixel spacing over the tile, each interior
/// sample shared by up to four pixels, combined with the trapezoid weights. The lattice is four grids of
/// whole-pixel spacing, offset by 0 or ½ in each direction, each traced as camera blocks with one shared
/// offset (large packets where the scene has them); a point's position `(x0 + m) + ½` is the `x0 + i·½` of
/// the lattice exactly, so the rays are the lattice's.
fn half_pixel_tile<F: Lanes>(scene: &Scene, tracer: &mut Tracer<F>, tile: Tile) -> Vec<Rgb> {
    let (lw, lh) = (2 * tile.w + 1, 2 * tile.h + 1);
    let mut lattice = vec![Rgb::default(); (lw * lh) as usize];
    let mut large = LargePacket::default();
    for (px, py) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        // Even lattice columns sit on pixel corners (w + 1 of them), odd ones on pixel centres (w).
        let grid = Tile { w: tile.w + 1 - px, h: tile.h + 1 - py, ..tile };
        let offset = Offsets::Shared(px as f32 * 0.5, py as f32 * 0.5);
        for_each_camera_hit(scene, grid, &offset, &mut large, |rays, hit, block| {
            let c = tracer.primary_from(rays, hit);
            for (i, x, y) in block.pixels() {
                lattice[((2 * y + py) * lw + 2 * x + px) as usize] = lane_rgb(&c, i);
            }
        });
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
