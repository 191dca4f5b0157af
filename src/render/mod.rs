//! The render loop: the image is cut into tiles, tiles are traced in parallel (rayon), and inside a tile
//! camera rays go out in packets of K over pixel blocks (2×2 for K = 4, 4×2 for 8, 4×4 for 16, one pixel
//! for K = 1), one sample offset at a time. Each pixel's samples are summed in the same fixed order at every
//! width and thread count, so the image is the same bits whatever K and the number of threads.

use std::time::Instant;

use crate::accel::{traced, RayKind, Work};
use crate::camera::Camera;
use crate::compile::Scene;
use crate::film::Image;
use crate::geometry::{HitPacket, Pyramid, RayPacket};
use crate::math::{Rgb, V3};
use crate::sample::lecture_3x3;
use crate::scene::desc::PostFilter;
use crate::shade::RayCounts;
use crate::simd::Lanes;

/// Evaluates `$call` with the type name `$F` bound to the lane type of the run-time packet width `$lanes`
/// (1: `f32`, single rays, on the scalar walk when the scene is compiled for it; 4, 8, 16: `wide`'s `f32x4`, `f32x8`, `f32x16`); panics on another
/// width. The one place a width chosen at run time becomes a type parameter.
macro_rules! with_lanes {
    ($lanes:expr, $F:ident => $call:expr) => {
        match $lanes {
            1 => {
                type $F = f32;
                $call
            }
            4 => {
                type $F = wide::f32x4;
                $call
            }
            8 => {
                type $F = wide::f32x8;
                $call
            }
            16 => {
                type $F = wide::f32x16;
                $call
            }
            k => panic!("unsupported packet width {k}: choose one of {:?}", $crate::render::LANE_CHOICES),
        }
    };
}

mod adaptive;
mod bands;
mod coverage;
mod order;
mod primary;
mod tile;
mod tile_rows;

use bands::trace_band;
pub(crate) use bands::{band_rows, render_window_lanes};
#[cfg(feature = "mpi")]
pub(crate) use bands::{trace_band_lanes, Bands};
pub use bands::{Traced, Window};
pub(crate) use coverage::CoveragePart;
// Named by the tests (tests/library/) alone.
#[cfg(test)]
pub(crate) use coverage::coverage_parts;

use order::{column_key, rows_together, tile_group};
#[cfg(test)]
use order::{rows_for, ROWS_TOGETHER};
pub use primary::fnv1a;
pub(crate) use primary::trace_primary_window_lanes;
pub(crate) use primary::PrimaryHits;
pub(crate) use primary::{primary_hits_lanes, trace_primary_lanes};
use tile::trace_tile;

/// Tile edge in pixels: small enough to balance two threads on small images, large enough to amortise.
pub const TILE: u32 = 16;

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
    pub(crate) work: Work,
    /// Rays per packet.
    pub lanes: usize,
    /// Wall-clock seconds spent tracing and filtering.
    pub seconds: f64,
}

/// A rectangle of the image.
#[derive(Clone, Copy, Debug)]
pub struct Tile {
    /// Left column.
    pub(crate) x0: u32,
    /// Top row.
    pub(crate) y0: u32,
    /// Width.
    pub(crate) w: u32,
    /// Height.
    pub(crate) h: u32,
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

/// A run's tiles as reported to its [`Progress`].
struct TileCounter<'a> {
    progress: &'a dyn Progress,
    done: std::sync::atomic::AtomicU64,
    total: u64,
}

impl<'a> TileCounter<'a> {
    /// Starts the report: `total` tiles to come.
    fn new(progress: &'a dyn Progress, total: u64) -> Self {
        progress.start(total);
        Self { progress, done: std::sync::atomic::AtomicU64::new(0), total }
    }
    fn tile_done(&self) {
        self.progress.tile_done(self.done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1, self.total);
    }
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
/// Every width and thread count gives the same image, bit for bit; 1 traces single rays (single-ray SIMD,
/// or the scalar path for a scene compiled with [`crate::compile::CompileOptions::scalar`]). Panics
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
    with_lanes!(lanes, F => render::<F>(scene, pool, progress))
}

/// Renders `scene` with packets of `F::K` rays on the threads of `pool`, reporting each finished tile to
/// `progress`: [`render_lanes`] with the width as a type (`f32`, or `wide`'s `f32x4`, `f32x8`, `f32x16`).
pub fn render<F: Lanes>(scene: &Scene, pool: &rayon::ThreadPool, progress: &dyn Progress) -> Rendered {
    let start = Instant::now();
    let (width, height) = (scene.camera.width, scene.camera.height);
    let counter = TileCounter::new(progress, tiles(width, height).len() as u64);
    let mut pixels = Vec::new();
    let (counts, work) = trace_band::<F>(scene, pool, 0..width, 0..height, &counter, &mut pixels);
    let mut image = Image { width, height, pixels };
    if scene.render.postfilter == PostFilter::Lecture3x3 {
        image = lecture_3x3(&image);
    }
    Rendered { image, counts, work, lanes: F::K, seconds: start.elapsed().as_secs_f64() }
}

/// Pixel-block shape of a packet: (columns, rows).
pub(crate) fn block<F: Lanes>() -> (u32, u32) {
    match F::K {
        1 => (1, 1),
        4 => (2, 2),
        8 => (4, 2),
        16 => (4, 4),
        k => (k as u32, 1),
    }
}

/// The pixels of one packet: a block of `w × h` pixels at column `x`, row `y` of its tile; lane `i` is the
/// pixel `(i mod bw, i div bw)` of the block, `bw × bh` = `block` (`w`, `h` are smaller at a tile's edge).
#[derive(Clone, Copy, Debug)]
pub struct Block {
    /// Left column in the tile.
    pub(crate) x: u32,
    /// Top row in the tile.
    pub(crate) y: u32,
    /// Columns covered.
    pub(crate) w: u32,
    /// Rows covered.
    pub(crate) h: u32,
    /// Columns of a whole block (lanes per row).
    pub(crate) bw: u32,
}

impl Block {
    /// `(lane, column, row)` in the tile for each pixel of the block.
    pub(crate) fn pixels(self) -> impl Iterator<Item = (usize, u32, u32)> {
        (0..self.h)
            .flat_map(move |r| (0..self.w).map(move |c| ((r * self.bw + c) as usize, self.x + c, self.y + r)))
    }
}

/// Calls `visit` for each packet of pixel-space sample positions covering `tile`, each position offset by
/// `(dx, dy)` from its pixel's corner: the camera rays and the block of pixels they sample. With `pyramids`
/// (the scene culls by them, [`crate::accel::Geometry::culls_by_pyramid`]) each packet carries its block's
/// `Camera::pyramid`.
pub fn for_each_packet<F: Lanes>(
    camera: &Camera<f64>,
    tile: Tile,
    (dx, dy): (f32, f32),
    pyramids: bool,
    visit: impl FnMut(&RayPacket<F>, Block),
) {
    for_each_packet_at(camera, tile, &Offsets::Shared(dx, dy), pyramids, visit);
}

/// `tile` cut into the pieces one large packet covers ([`crate::bvh::MAX_PACKETS`] packets of
/// `block``::<F>()` pixels: 16×16 pixels at K = 16, 16×8 at K = 8, 8×8 at K = 4), row by row, in image
/// coordinates.
pub(crate) fn large_packets<F: Lanes>(tile: Tile) -> impl Iterator<Item = Tile> {
    let (bw, bh) = block::<F>();
    let (w, h) = (bw * 4, bh * crate::bvh::MAX_PACKETS as u32 / 4);
    (0..tile.h).step_by(h as usize).flat_map(move |y0| {
        (0..tile.w).step_by(w as usize).map(move |x0| Tile {
            x0: tile.x0 + x0,
            y0: tile.y0 + y0,
            w: w.min(tile.w - x0),
            h: h.min(tile.h - y0),
        })
    })
}

/// The [`Camera::pyramid`] of every camera ray through `tile`'s pixels, each offset by `(dx, dy)` from its
/// pixel's corner (the sums [`for_each_packet`] computes for its edge lanes).
pub(crate) fn tile_pyramid(camera: &Camera<f64>, tile: Tile, (dx, dy): (f32, f32)) -> Option<Pyramid> {
    let edge = |first: u32, count: u32, d: f32| [first as f32 + d, (first + count - 1) as f32 + d];
    camera.pyramid(edge(tile.x0, tile.w, dx), edge(tile.y0, tile.h, dy))
}

/// Reusable buffers for [`for_each_camera_hit`]: one large packet's rays, blocks and hits.
pub(crate) struct LargePacket<F: Lanes> {
    packets: Vec<RayPacket<F>>,
    blocks: Vec<Block>,
    hits: Vec<HitPacket<F>>,
}

impl<F: Lanes> Default for LargePacket<F> {
    fn default() -> Self {
        let n = crate::bvh::MAX_PACKETS;
        Self { packets: Vec::with_capacity(n), blocks: Vec::with_capacity(n), hits: Vec::with_capacity(n) }
    }
}

/// [`for_each_packet_at`] with each packet's closest camera hits: the packets of each piece of `tile` that
/// [`large_packets`] cuts are traced together ([`crate::accel::Geometry::intersect_tile`], with the piece's
/// pyramid), then `visit` gets each packet, its hits and its block (in `tile`'s coordinates). Offsets must
/// lie in the pixel (`[0, 1]`), as every sampling pattern's do.
pub(crate) fn for_each_camera_hit<F: Lanes>(
    scene: &Scene,
    tile: Tile,
    offsets: &Offsets,
    large: &mut LargePacket<F>,
    mut visit: impl FnMut(&RayPacket<F>, HitPacket<F>, Block),
) {
    let camera = &scene.camera_f64;
    let pyramids = scene.geometry.culls_by_pyramid();
    for piece in large_packets::<F>(tile) {
        large.packets.clear();
        large.blocks.clear();
        for_each_packet_at(camera, piece, offsets, pyramids, |rays, b| {
            large.packets.push(*rays);
            large.blocks.push(Block { x: b.x + piece.x0 - tile.x0, y: b.y + piece.y0 - tile.y0, ..b });
        });
        let pyramid = match offsets {
            _ if !pyramids => None,
            Offsets::Shared(dx, dy) => tile_pyramid(camera, piece, (*dx, *dy)),
            Offsets::PerPixel(_) => {
                let edge = |first: u32, count: u32| [first as f32, (first + count) as f32];
                camera.pyramid(edge(piece.x0, piece.w), edge(piece.y0, piece.h))
            }
        };
        large.hits.resize(large.packets.len(), HitPacket::miss());
        let (packets, hits) = (&large.packets, &mut large.hits);
        traced(RayKind::Camera, || scene.geometry.intersect_tile(packets, pyramid.as_ref(), hits));
        for ((rays, hit), b) in large.packets.iter().zip(&large.hits).zip(&large.blocks) {
            visit(rays, *hit, *b);
        }
    }
}

/// Where a pass of samples lies in each pixel, from the pixel's corner.
pub(crate) enum Offsets<'a> {
    /// The same offset in every pixel.
    Shared(f32, f32),
    /// Each pixel's own offset, given its image column and row.
    PerPixel(&'a (dyn Fn(u32, u32) -> (f32, f32) + Sync)),
}

/// [`for_each_packet`] with an offset per pixel: lane i's position is `(column + lane column) + dx_i`, the sums
/// a one-lane packet of that pixel computes, so every width gives the same rays.
pub(crate) fn for_each_packet_at<F: Lanes>(
    camera: &Camera<f64>,
    tile: Tile,
    offsets: &Offsets,
    pyramids: bool,
    visit: impl FnMut(&RayPacket<F>, Block),
) {
    if camera.start != 0.0 {
        packets_at::<F, true>(camera, tile, offsets, pyramids, visit);
    } else {
        packets_at::<F, false>(camera, tile, offsets, pyramids, visit);
    }
}

/// [`for_each_packet_at`] for a camera whose rays start at the eye (`FAR` false) or at its start points.
fn packets_at<F: Lanes, const FAR: bool>(
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
                    // Each lane's offset once (a scrambled or hashed position costs several hashes).
                    let mut lanes = [(0.0, 0.0); 16];
                    debug_assert!(F::K <= lanes.len());
                    for (i, o) in lanes.iter_mut().enumerate().take(F::K) {
                        *o = at(x0 + i as u32 % bw, y0 + i as u32 / bw);
                    }
                    (F::from_fn(|i| lanes[i].0), F::from_fn(|i| lanes[i].1))
                }
            };
            let sx = (F::splat_f32(x0 as f32) + lane_x) + dx;
            let sy = (F::splat_f32(y0 as f32) + lane_y) + dy;
            let ray = camera.rays_in::<F, FAR>(sx, sy);
            let active = if b.w == bw && b.h == bh {
                F::mask_from_bits(u32::MAX)
            } else {
                F::mask_from_fn(|i| (i as u32 % bw) < b.w && (i as u32 / bw) < b.h)
            };
            // The block's extreme sample positions, taken from the lanes themselves: the first and last
            // lanes for a shared offset, every lane for per-pixel offsets (a jittered lane 0 need not be the
            // leftmost of its block).
            let (last_column, last_row) = ((bw - 1) as usize, ((bh - 1) * bw) as usize);
            let range = |v: F, first: usize, last: usize| match offsets {
                Offsets::Shared(..) => [v.lane(first), v.lane(last)],
                Offsets::PerPixel(_) => (0..F::K)
                    .map(|i| v.lane(i))
                    .fold([f32::INFINITY, f32::NEG_INFINITY], |[lo, hi], c| [lo.min(c), hi.max(c)]),
            };
            let pyramid = (pyramids && F::K > 1)
                .then(|| camera.pyramid(range(sx, 0, last_column), range(sy, 0, last_row)))
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
/// place: returning each tile's pixels and merging them after the trace measured slower on a sphereflake
/// (the merge, and the first touch of a buffer per tile; docs/perf-log/2026-11.md, "Page faults:
/// huge pages, and tiles written in place").
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
