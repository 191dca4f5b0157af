//! The render loop: the image is cut into tiles, tiles are traced in parallel (rayon), and inside a tile
//! camera rays go out in packets of K over pixel blocks (2×2 for K = 4, 4×2 for 8, 4×4 for 16, one pixel
//! for K = 1), one sample offset at a time. Each pixel's samples are summed in the same fixed order at every
//! width and thread count, so the image is the same bits whatever K and the number of threads.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use rayon::prelude::*;
use wide::{f32x16, f32x4, f32x8};

use crate::accel::{take_work, Work};
use crate::camera::Camera;
use crate::compile::Scene;
use crate::film::Image;
use crate::geometry::RayPacket;
use crate::math::{Rgb, V3};
use crate::sample::{grid_offsets, lecture_3x3, sequence, HALF_PIXEL_WEIGHTS};
use crate::scene::desc::{Filter, Pattern, PostFilter};
use crate::shade::{RayCounts, Tracer};
use crate::simd::Lanes;

/// Tile edge in pixels: small enough to balance two threads on small images, large enough to amortise.
const TILE: u32 = 16;

/// The packet widths a render can run at.
pub const LANE_CHOICES: [usize; 4] = [1, 4, 8, 16];

/// A finished render.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The filtered image.
    pub image: Image,
    /// Rays traced by kind.
    pub counts: RayCounts,
    /// Intersection tests done.
    pub work: Work,
    /// Rays per packet.
    pub lanes: usize,
    /// Wall-clock seconds spent tracing and filtering.
    pub seconds: f64,
}

/// A rectangle of the image.
#[derive(Clone, Copy, Debug)]
pub struct Tile {
    /// Left column.
    pub x0: u32,
    /// Top row.
    pub y0: u32,
    /// Width.
    pub w: u32,
    /// Height.
    pub h: u32,
}

/// The image cut into tiles, row by row.
pub fn tiles(width: u32, height: u32) -> Vec<Tile> {
    let mut out = Vec::new();
    for y0 in (0..height).step_by(TILE as usize) {
        for x0 in (0..width).step_by(TILE as usize) {
            out.push(Tile { x0, y0, w: TILE.min(width - x0), h: TILE.min(height - y0) });
        }
    }
    out
}

/// A pool of `threads` workers (rayon's default when `None`). A run makes one and does all its parallel
/// work there (build, render, output): `--threads` then holds even when the caller already runs inside
/// rayon, and no second pool's threads are started.
pub fn thread_pool(threads: Option<usize>) -> Result<rayon::ThreadPool, rayon::ThreadPoolBuildError> {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        builder = builder.num_threads(n);
    }
    builder.build()
}

/// Where a render reports how far it got: its work is cut into tiles, and it tells how many there are
/// before tracing, then once per finished tile.
///
/// Implemented by `()` (reports go nowhere) and by every `Fn(u64, u64) + Sync` closure, which is called with
/// `(done, total)`: `(0, total)` first, then once per tile with `done` from 1 to `total`. Tiles finish on
/// the render's worker threads, so the calls come from them and concurrent ones may arrive out of order.
///
/// ```
/// use std::path::Path;
/// use std::sync::atomic::{AtomicU64, Ordering};
///
/// use bareray::{compile::Scene, io, render};
///
/// let mut desc = io::load(Path::new("scenes/whitted.toml"))?;
/// (desc.camera.width, desc.camera.height) = (40, 30);
/// let scene = Scene::compile(&desc)?;
/// let pool = render::thread_pool(Some(2))?;
///
/// let finished = AtomicU64::new(0);
/// let count = |done: u64, _total: u64| {
///     finished.fetch_max(done, Ordering::Relaxed);
/// };
/// render::render_lanes(&scene, 8, &pool, &count);
/// assert_eq!(finished.into_inner(), render::tiles(40, 30).len() as u64);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub trait Progress: Sync {
    /// The render has `total` tiles; called once, before any tile is traced.
    fn start(&self, total: u64);
    /// One more tile is finished, `done` of `total` so far (each `done` from 1 to `total` comes once).
    fn tile_done(&self, done: u64, total: u64);
}

impl Progress for () {
    fn start(&self, _: u64) {}
    fn tile_done(&self, _: u64, _: u64) {}
}

impl<F: Fn(u64, u64) + Sync> Progress for F {
    fn start(&self, total: u64) {
        self(0, total);
    }
    fn tile_done(&self, done: u64, total: u64) {
        self(done, total);
    }
}

/// Renders `scene` with packets of `lanes` rays (1, 4, 8 or 16) on the threads of `pool`, reporting each
/// finished tile to `progress` (`&()` for no reports).
///
/// Every width and thread count gives the same image, bit for bit; 1 is the scalar reference path. Panics
/// on a width not in [`LANE_CHOICES`].
///
/// ```
/// use std::path::Path;
///
/// use bareray::{compile::Scene, io, render};
///
/// let mut desc = io::load(Path::new("scenes/whitted.toml"))?;
/// (desc.camera.width, desc.camera.height) = (64, 48);
/// let scene = Scene::compile(&desc)?;
/// let pool = render::thread_pool(Some(2))?;
///
/// let scalar = render::render_lanes(&scene, 1, &pool, &());
/// let packets = render::render_lanes(&scene, 8, &pool, &|done: u64, total: u64| {
///     eprintln!("{done}/{total} tiles");
/// });
/// assert_eq!(scalar.image.pixels, packets.image.pixels);
/// assert!(packets.counts.primary >= 64 * 48);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn render_lanes(
    scene: &Scene,
    lanes: usize,
    pool: &rayon::ThreadPool,
    progress: &dyn Progress,
) -> Rendered {
    match lanes {
        1 => render::<f32>(scene, pool, progress),
        4 => render::<f32x4>(scene, pool, progress),
        8 => render::<f32x8>(scene, pool, progress),
        16 => render::<f32x16>(scene, pool, progress),
        _ => panic!("unsupported packet width {lanes}: choose one of {LANE_CHOICES:?}"),
    }
}

/// Renders `scene` with packets of `F::K` rays on the threads of `pool`, reporting each finished tile to
/// `progress`: [`render_lanes`] with the width as a type (`f32`, or `wide`'s `f32x4`, `f32x8`, `f32x16`).
pub fn render<F: Lanes>(scene: &Scene, pool: &rayon::ThreadPool, progress: &dyn Progress) -> Rendered {
    let start = Instant::now();
    let (width, height) = (scene.camera.width, scene.camera.height);
    let tiles = tiles(width, height);
    let total = tiles.len() as u64;
    progress.start(total);
    let done = AtomicU64::new(0);
    let mut image = Image::new(width, height);
    let rows = tile_rows(&mut image.pixels, width, &tiles);
    let traced: Vec<(RayCounts, Work)> = pool.install(|| {
        // One job per tile (with_max_len): rayon otherwise runs whole quarters of the image as single
        // jobs, which a thread slowed by the host cannot hand over (docs/perf-log/2026-11.md).
        tiles
            .par_iter()
            .zip(rows)
            .with_max_len(1)
            .map(|(&tile, mut rows)| {
                take_work();
                let mut tracer = Tracer::<F>::new(scene);
                let pixels = trace_tile(scene, &mut tracer, tile);
                debug_assert_eq!(pixels.len(), rows.len() * tile.w as usize, "tile {tile:?}");
                for (row, traced) in rows.iter_mut().zip(pixels.chunks_exact(tile.w as usize)) {
                    row.copy_from_slice(traced);
                }
                progress.tile_done(done.fetch_add(1, Ordering::Relaxed) + 1, total);
                (tracer.counts, take_work())
            })
            .collect()
    });
    let mut counts = RayCounts::default();
    let mut work = Work::default();
    for (c, w) in traced {
        counts += c;
        work += w;
    }
    if scene.render.postfilter == PostFilter::Lecture3x3 {
        image = lecture_3x3(&image);
    }
    Rendered { image, counts, work, lanes: F::K, seconds: start.elapsed().as_secs_f64() }
}

/// Pixel-block shape of a packet: (columns, rows).
pub fn block<F: Lanes>() -> (u32, u32) {
    match F::K {
        1 => (1, 1),
        4 => (2, 2),
        8 => (4, 2),
        16 => (4, 4),
        k => (k as u32, 1),
    }
}

/// The pixels of one packet: a block of `w × h` pixels at column `x`, row `y` of its tile; lane `i` is the
/// pixel `(i mod bw, i div bw)` of the block, `bw × bh` = [`block`] (`w`, `h` are smaller at a tile's edge).
#[derive(Clone, Copy, Debug)]
pub struct Block {
    /// Left column in the tile.
    pub x: u32,
    /// Top row in the tile.
    pub y: u32,
    /// Columns covered.
    pub w: u32,
    /// Rows covered.
    pub h: u32,
    /// Columns of a whole block (lanes per row).
    pub bw: u32,
}

impl Block {
    /// `(lane, column, row)` in the tile for each pixel of the block.
    pub fn pixels(self) -> impl Iterator<Item = (usize, u32, u32)> {
        (0..self.h)
            .flat_map(move |r| (0..self.w).map(move |c| ((r * self.bw + c) as usize, self.x + c, self.y + r)))
    }
}

/// Calls `visit` for each packet of pixel-space sample positions covering `tile`, each position offset by
/// `(dx, dy)` from its pixel's corner: the camera rays and the block of pixels they sample. With `pyramids`
/// (the scene culls by them, [`crate::accel::Geometry::culls_by_pyramid`]) each packet carries its block's
/// [`Camera::pyramid`].
pub fn for_each_packet<F: Lanes>(
    camera: &Camera<f64>,
    tile: Tile,
    (dx, dy): (f32, f32),
    pyramids: bool,
    visit: impl FnMut(&RayPacket<F>, Block),
) {
    for_each_packet_at(camera, tile, &Offsets::Shared(dx, dy), pyramids, visit);
}

/// Where a pass of samples lies in each pixel, from the pixel's corner.
pub enum Offsets<'a> {
    /// The same offset in every pixel.
    Shared(f32, f32),
    /// Each pixel's own offset, given its image column and row.
    PerPixel(&'a (dyn Fn(u32, u32) -> (f32, f32) + Sync)),
}

/// [`for_each_packet`] with an offset per pixel: lane i's position is `(column + lane column) + dx_i`, the sums
/// a one-lane packet of that pixel computes, so every width gives the same rays.
pub fn for_each_packet_at<F: Lanes>(
    camera: &Camera<f64>,
    tile: Tile,
    offsets: &Offsets,
    pyramids: bool,
    mut visit: impl FnMut(&RayPacket<F>, Block),
) {
    let (bw, bh) = block::<F>();
    // Lane offsets inside a block, computed once: x = (column + lane column) + dx, the same sums as per lane.
    let lane_x = F::from_fn(|i| (i as u32 % bw) as f32);
    let lane_y = F::from_fn(|i| (i as u32 / bw) as f32);
    for by in (0..tile.h).step_by(bh as usize) {
        for bx in (0..tile.w).step_by(bw as usize) {
            let b = Block { x: bx, y: by, w: bw.min(tile.w - bx), h: bh.min(tile.h - by), bw };
            let (x0, y0) = (tile.x0 + bx, tile.y0 + by);
            let (dx, dy) = match offsets {
                Offsets::Shared(dx, dy) => (F::splat_f32(*dx), F::splat_f32(*dy)),
                Offsets::PerPixel(at) => {
                    let lane = |i: usize| at(x0 + i as u32 % bw, y0 + i as u32 / bw);
                    (F::from_fn(|i| lane(i).0), F::from_fn(|i| lane(i).1))
                }
            };
            let sx = (F::splat_f32(x0 as f32) + lane_x) + dx;
            let sy = (F::splat_f32(y0 as f32) + lane_y) + dy;
            let ray = camera.rays(sx, sy);
            let active = if b.w == bw && b.h == bh {
                F::mask_from_bits(u32::MAX)
            } else {
                F::mask_from_fn(|i| (i as u32 % bw) < b.w && (i as u32 / bw) < b.h)
            };
            // The block's first and last sample positions, taken from the lanes themselves.
            let (last_column, last_row) = ((bw - 1) as usize, ((bh - 1) * bw) as usize);
            let pyramid = (pyramids && F::K > 1)
                .then(|| camera.pyramid([sx.lane(0), sx.lane(last_column)], [sy.lane(0), sy.lane(last_row)]))
                .flatten();
            let rays = RayPacket {
                pyramid,
                ..RayPacket::new(ray.origin, ray.dir, F::splat_f32(f32::INFINITY), active)
            };
            visit(&rays, b);
        }
    }
}

/// The image's pixels as one list of row slices per tile, in the order of `tiles`, which must be
/// [`tiles`]`(width, height)` (row-major bands of TILE rows), so each tile's job writes its own pixels in
/// place: returning each tile's pixels and merging them after the trace measured 1–5% slower on a 1024²
/// sphereflake (the merge, and the first touch of 4096 live tile buffers; docs/perf-log/2026-11.md).
fn tile_rows<'a>(pixels: &'a mut [Rgb], width: u32, tiles: &[Tile]) -> Vec<Vec<&'a mut [Rgb]>> {
    let mut out: Vec<Vec<&mut [Rgb]>> = tiles.iter().map(|t| Vec::with_capacity(t.h as usize)).collect();
    let per_band = width.div_ceil(TILE) as usize;
    for (y, row) in pixels.chunks_mut(width.max(1) as usize).enumerate() {
        let first = y / TILE as usize * per_band;
        let (mut rest, mut x) = (row, 0);
        for (tile, rows) in tiles[first..first + per_band].iter().zip(&mut out[first..first + per_band]) {
            debug_assert_eq!((tile.x0, tile.y0 / TILE), (x, y as u32 / TILE), "tiles out of order");
            x += tile.w;
            let (mine, after) = std::mem::take(&mut rest).split_at_mut(tile.w as usize);
            rows.push(mine);
            rest = after;
        }
        debug_assert!(rest.is_empty(), "the band's tiles do not cover row {y}");
    }
    out
}

/// Lane `i` of a colour packet.
fn lane_rgb<F: Lanes>(c: &V3<F>, i: usize) -> Rgb {
    Rgb::new(c.x.lane(i), c.y.lane(i), c.z.lane(i))
}

/// The pixels of one tile, row by row.
fn trace_tile<F: Lanes>(scene: &Scene, tracer: &mut Tracer<F>, tile: Tile) -> Vec<Rgb> {
    let camera = &scene.camera_f64;
    let pattern = scene.render.pattern;
    match pattern {
        Pattern::HalfPixel => return half_pixel_tile(camera, tracer, tile),
        Pattern::Adaptive { threshold, depth } => {
            return adaptive_tile(camera, tracer, tile, threshold, depth)
        }
        Pattern::Grid(_) | Pattern::Stratified(_) | Pattern::R2(_) => {}
    }
    if let Some(filter) = scene.render.filter {
        return filtered_tile(scene, tracer, tile, filter);
    }
    let pyramids = scene.geometry.culls_by_pyramid();
    let mut sum = vec![Rgb::default(); (tile.w * tile.h) as usize];
    let mut pass = |offsets: &Offsets| {
        for_each_packet_at(camera, tile, offsets, pyramids, |rays, block| {
            let c = tracer.primary(rays);
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
/// [`trace_tile`] traces it (`grid` from [`grid_of`]). Not for the half-pixel and adaptive patterns.
fn sample_offset(pattern: Pattern, grid: &[(f32, f32)], k: u32, x: u32, y: u32) -> (f32, f32) {
    match pattern {
        Pattern::Grid(_) => grid[k as usize],
        Pattern::Stratified(n) => sequence::stratified(n, x, y, k),
        Pattern::R2(_) => sequence::r2(x, y, k),
        Pattern::HalfPixel | Pattern::Adaptive { .. } => {
            unreachable!("the half-pixel and adaptive patterns have their own reconstruction")
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
    let pyramids = scene.geometry.culls_by_pyramid();
    for k in 0..count {
        let at = |x: u32, y: u32| sample_offset(pattern, &grid, k, x, y);
        let plane = &mut samples[k as usize * area..][..area];
        for_each_packet_at(&scene.camera_f64, ext, &Offsets::PerPixel(&at), pyramids, |rays, block| {
            let c = tracer.primary(rays);
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
/// sample shared by up to four pixels, combined with the trapezoid weights. Lattice points go out K at a
/// time along its rows.
fn half_pixel_tile<F: Lanes>(camera: &Camera<f64>, tracer: &mut Tracer<F>, tile: Tile) -> Vec<Rgb> {
    let (lw, lh) = (2 * tile.w + 1, 2 * tile.h + 1);
    let n = (lw * lh) as usize;
    let mut lattice = Vec::with_capacity(n);
    for first in (0..n).step_by(F::K) {
        let point = |i: usize| ((first + i) % lw as usize, (first + i) / lw as usize);
        let sx = F::from_fn(|i| tile.x0 as f32 + point(i).0 as f32 * 0.5);
        let sy = F::from_fn(|i| tile.y0 as f32 + point(i).1 as f32 * 0.5);
        let ray = camera.rays(sx, sy);
        let active = F::lanes_below(n - first);
        let rays = RayPacket::new(ray.origin, ray.dir, F::splat_f32(f32::INFINITY), active);
        let c = tracer.primary(&rays);
        lattice.extend((0..F::K.min(n - first)).map(|i| lane_rgb(&c, i)));
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

/// Closest hits of one camera ray through every pixel centre: no shading, no secondary rays.
#[derive(Clone, Debug)]
pub struct PrimaryHits {
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Hit distance per pixel, row-major, `inf` on a miss.
    pub t: Vec<f32>,
    /// Primitive id per pixel in storage order ([`crate::accel::Geometry::file_id`] maps it to the scene
    /// file's numbering), [`crate::geometry::NO_PRIM`] on a miss.
    pub prim: Vec<u32>,
    /// Wall-clock seconds of the tracing.
    pub seconds: f64,
}

impl PrimaryHits {
    /// FNV-1a 64 over the per-pixel scene-file ids as little-endian i32 (−1 on a miss), row-major: the
    /// checksum bench-peers/ computes for Embree, so equal results give equal checksums across tracers.
    pub fn checksum(&self, scene: &Scene) -> u64 {
        let ids = self.prim.iter().map(|&p| {
            if p == crate::geometry::NO_PRIM {
                -1i32
            } else {
                scene.geometry.file_id(p) as i32
            }
        });
        fnv1a(ids.flat_map(i32::to_le_bytes))
    }
}

/// FNV-1a 64 of a byte stream (offset basis 0xcbf29ce484222325, prime 0x100000001b3).
pub(crate) fn fnv1a(bytes: impl IntoIterator<Item = u8>) -> u64 {
    bytes.into_iter().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3))
}

impl PrimaryHits {
    /// A frame of misses, to be filled by [`trace_primary`].
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            t: vec![f32::INFINITY; n],
            prim: vec![crate::geometry::NO_PRIM; n],
            seconds: 0.0,
        }
    }
}

/// Copies the first `dst.len()` values of `src` into `dst`: a whole 4-pixel row as one fixed-size copy (a
/// `memmove` call per short row cost 2–3% of a small field's frame), a partial one as a slice.
#[inline(always)]
fn copy_row<T: Copy>(dst: &mut [T], src: &[T]) {
    match (<&mut [T; 4]>::try_from(&mut *dst), src.first_chunk::<4>()) {
        (Ok(whole), Some(row)) => *whole = *row,
        _ => dst.copy_from_slice(&src[..dst.len()]),
    }
}

/// One camera ray per pixel centre, in packets of `lanes` (1, 4, 8 or 16), into a new frame on the threads
/// of `pool` ([`trace_primary`]).
pub fn primary_hits_lanes(scene: &Scene, lanes: usize, pool: &rayon::ThreadPool) -> PrimaryHits {
    let mut hits = PrimaryHits::new(scene.camera.width, scene.camera.height);
    trace_primary_lanes(scene, lanes, pool, &mut hits);
    hits
}

/// [`trace_primary`] at a packet width chosen at run time.
pub fn trace_primary_lanes(scene: &Scene, lanes: usize, pool: &rayon::ThreadPool, hits: &mut PrimaryHits) {
    match lanes {
        1 => trace_primary::<f32>(scene, pool, hits),
        4 => trace_primary::<f32x4>(scene, pool, hits),
        8 => trace_primary::<f32x8>(scene, pool, hits),
        16 => trace_primary::<f32x16>(scene, pool, hits),
        _ => panic!("unsupported packet width {lanes}: choose one of {LANE_CHOICES:?}"),
    }
}

/// Traces one camera ray per pixel centre in packets of `F::K` on `pool` and writes the closest hits into
/// `hits` (sized to the camera), every pixel; `hits.seconds` is the wall-clock time of the tracing. Taking
/// the frame and the pool from the caller lets repeated frames (`bench`) reuse both, as a peer harness
/// reuses its frame buffers and threads.
pub fn trace_primary<F: Lanes>(scene: &Scene, pool: &rayon::ThreadPool, hits: &mut PrimaryHits) {
    use crate::geometry::DeparturePacket;
    let start = Instant::now();
    let (width, height) = (scene.camera.width, scene.camera.height);
    assert_eq!((hits.width, hits.height), (width, height), "frame size differs from the camera's");
    // One band of tiles per task, written in place: no per-tile buffers and no serial merge.
    let band = width as usize * TILE as usize;
    let pyramids = scene.geometry.culls_by_pyramid();
    pool.install(|| {
        // One job per band, as for tiles in `render`.
        let bands =
            hits.t.par_chunks_mut(band).zip(hits.prim.par_chunks_mut(band)).enumerate().with_max_len(1);
        bands.for_each(|(band, (t, prim))| {
            let camera = &scene.camera_f64;
            let y0 = band as u32 * TILE;
            for tile in tiles(width, TILE.min(height - y0)) {
                let tile = Tile { y0, ..tile };
                for_each_packet::<F>(camera, tile, (0.5, 0.5), pyramids, |rays, b| {
                    let hit = scene.geometry.intersect_k(rays, &DeparturePacket::camera());
                    let (ts, ids) = (hit.t.to_array(), crate::simd::IdLanes::to_array(hit.prim));
                    // Row by row: each row of the block is a run of pixels in the image row.
                    for r in 0..b.h as usize {
                        let lane = r * b.bw as usize;
                        let at = (b.y as usize + r) * width as usize + (tile.x0 + b.x) as usize;
                        let n = b.w as usize;
                        copy_row(&mut t[at..at + n], &ts.as_ref()[lane..]);
                        copy_row(&mut prim[at..at + n], &ids.as_ref()[lane..]);
                    }
                });
            }
        });
    });
    hits.seconds = start.elapsed().as_secs_f64();
}
