//! One tile's pixels under each sampling pattern: the shared-offset and per-pixel passes, the reconstruction
//! filters (with an apron of neighbouring pixels traced again), the lecture's half-pixel grid, Whitted's
//! adaptive subdivision and the coverage pattern (`coverage.rs`). Every pixel's value depends only on its own samples (and, under a filter, its
//! neighbours'), never on where the tile starts, so any cut of the image into tiles gives the same bits.

use crate::camera::Camera;
use crate::compile::Scene;
use crate::geometry::RayPacket;
use crate::math::Rgb;
use crate::sample::{grid_offsets, sequence, HALF_PIXEL_WEIGHTS};
use crate::scene::desc::{Filter, Pattern};
use crate::shade::Tracer;
use crate::simd::Lanes;

use super::{for_each_camera_hit, lane_rgb, LargePacket, Offsets, Tile};

/// The pixels of one tile, row by row.
pub(super) fn trace_tile<F: Lanes>(scene: &Scene, tracer: &mut Tracer<F>, tile: Tile) -> Vec<Rgb> {
    let camera = &scene.camera_f64;
    let pattern = scene.render.pattern;
    match pattern {
        Pattern::HalfPixel => return half_pixel_tile(scene, tracer, tile),
        Pattern::Adaptive { threshold, depth } => {
            return adaptive_tile(camera, tracer, tile, threshold, depth)
        }
        Pattern::Coverage => return super::coverage::coverage_tile(scene, tracer, tile),
        Pattern::Grid(_) | Pattern::Stratified(_) | Pattern::R2(_) | Pattern::Sobol(_) => {}
    }
    if let Some(filter) = scene.render.filter {
        return filtered_tile(scene, tracer, tile, filter);
    }
    let mut sum = vec![Rgb::default(); (tile.w * tile.h) as usize];
    let mut large = LargePacket::default();
    let mut pass = |offsets: &Offsets| {
        for_each_camera_hit(scene, tile, offsets, &mut large, |rays, hit, block| {
            let c = tracer.primary_from(rays, hit);
            for (i, x, y) in block.pixels() {
                let p = (y * tile.w + x) as usize;
                sum[p] = sum[p] + lane_rgb(&c, i);
            }
        });
    };
    let grid = grid_of(pattern);
    let count = pattern.rays_per_pixel() as u32;
    for k in 0..count {
        match pattern {
            // The regular grid's offset is the same in every pixel: splatted, not computed per lane.
            Pattern::Grid(_) => pass(&Offsets::Shared(grid[k as usize].0, grid[k as usize].1)),
            _ => pass(&Offsets::PerPixel(&|x, y| sample_offset(pattern, &grid, k, x, y))),
        }
    }
    let scale = 1.0 / count as f32;
    sum.into_iter().map(|s| s * scale).collect()
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

/// Whitted's adaptive supersampling over one tile ([`Pattern::Adaptive`]). Points live on a lattice of
/// `2^depth` steps per pixel; the pixel corners are traced first (those on the tile's edges again by the
/// neighbouring tile: the same bits), then level by level every square whose corners differ by more than
/// `threshold` in a channel gets its edge midpoints and centre traced (each point once, shared by the
/// squares that meet there, in lattice order) and is split. Every decision depends only on colours, which are
/// the same bits at every width, so the image is too.
fn adaptive_tile<F: Lanes>(
    camera: &Camera<f64>,
    tracer: &mut Tracer<F>,
    tile: Tile,
    threshold: f32,
    depth: u32,
) -> Vec<Rgb> {
    let unit = 1u32 << depth;
    let mut colour = Lattice::new(tile.w * unit + 1, tile.h * unit + 1);
    // Lattice points relative to the tile's corner, in 1/unit pixel steps; traced K at a time.
    let mut trace = |points: Vec<(u32, u32)>, colour: &mut Lattice| {
        let step = 1.0 / unit as f32;
        for chunk in points.chunks(F::K) {
            let at = |i: usize, pick: fn((u32, u32)) -> u32, origin: u32| {
                let p = chunk[i.min(chunk.len() - 1)];
                origin as f32 + pick(p) as f32 * step
            };
            let sx = F::from_fn(|i| at(i, |p| p.0, tile.x0));
            let sy = F::from_fn(|i| at(i, |p| p.1, tile.y0));
            let ray = camera.rays(sx, sy);
            let rays =
                RayPacket::new(ray.origin, ray.dir, F::splat_f32(f32::INFINITY), F::lanes_below(chunk.len()));
            let c = tracer.primary(&rays);
            for (i, &p) in chunk.iter().enumerate() {
                colour.set(p, lane_rgb(&c, i));
            }
        }
    };
    let corners = (0..=tile.h).flat_map(|y| (0..=tile.w).map(move |x| (x * unit, y * unit))).collect();
    trace(corners, &mut colour);
    // Squares as (left, top, size) in lattice steps; `split` holds those divided, for the final averages.
    let mut squares: Vec<(u32, u32, u32)> =
        (0..tile.h).flat_map(|y| (0..tile.w).map(move |x| (x * unit, y * unit, unit))).collect();
    let mut split = std::collections::BTreeSet::new();
    let differ = |a: Rgb, b: Rgb| (a.x - b.x).abs().max((a.y - b.y).abs()).max((a.z - b.z).abs()) > threshold;
    for _ in 0..depth {
        let corners_of = |&(x, y, s): &(u32, u32, u32)| [(x, y), (x + s, y), (x, y + s), (x + s, y + s)];
        let busy: Vec<(u32, u32, u32)> = squares
            .iter()
            .filter(|sq| {
                let c = corners_of(sq).map(|p| colour.get(p));
                (0..4).any(|i| (i + 1..4).any(|j| differ(c[i], c[j])))
            })
            .copied()
            .collect();
        let mut new = std::collections::BTreeSet::new();
        for &(x, y, s) in &busy {
            let h = s / 2;
            for p in [(x + h, y), (x, y + h), (x + h, y + h), (x + s, y + h), (x + h, y + s)] {
                if !colour.has(p) {
                    new.insert(p);
                }
            }
        }
        trace(new.into_iter().collect(), &mut colour);
        squares = busy
            .iter()
            .flat_map(|&(x, y, s)| {
                split.insert((x, y, s));
                let h = s / 2;
                [(x, y, h), (x + h, y, h), (x, y + h, h), (x + h, y + h, h)]
            })
            .collect();
        if squares.is_empty() {
            break;
        }
    }
    // A square's value: its quarters' mean when split, else its corners' mean.
    fn value(
        sq: (u32, u32, u32),
        colour: &Lattice,
        split: &std::collections::BTreeSet<(u32, u32, u32)>,
    ) -> Rgb {
        let (x, y, s) = sq;
        let quarter = |sum: Rgb| sum * 0.25;
        if split.contains(&sq) {
            let h = s / 2;
            let q =
                [(x, y, h), (x + h, y, h), (x, y + h, h), (x + h, y + h, h)].map(|q| value(q, colour, split));
            quarter(q[0] + q[1] + q[2] + q[3])
        } else {
            let c = [(x, y), (x + s, y), (x, y + s), (x + s, y + s)].map(|p| colour.get(p));
            quarter(c[0] + c[1] + c[2] + c[3])
        }
    }
    (0..tile.h)
        .flat_map(|y| (0..tile.w).map(move |x| (x, y)))
        .map(|(x, y)| value((x * unit, y * unit, unit), &colour, &split))
        .collect()
}

/// The colours of an adaptive tile's lattice points, traced or not yet.
struct Lattice {
    width: u32,
    colour: Vec<Option<Rgb>>,
}

impl Lattice {
    fn new(width: u32, height: u32) -> Self {
        Lattice { width, colour: vec![None; (width * height) as usize] }
    }
    fn index(&self, (x, y): (u32, u32)) -> usize {
        (y * self.width + x) as usize
    }
    fn has(&self, p: (u32, u32)) -> bool {
        self.colour[self.index(p)].is_some()
    }
    fn get(&self, p: (u32, u32)) -> Rgb {
        self.colour[self.index(p)].expect("a square's corners are traced before it is judged")
    }
    fn set(&mut self, p: (u32, u32), c: Rgb) {
        let i = self.index(p);
        self.colour[i] = Some(c);
    }
}
