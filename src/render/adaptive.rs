//! Adaptive supersampling (`--aa adaptive:T,D`, [`Pattern::Adaptive`]) over a band of tiles. Points live on
//! a lattice of `2^D` steps per pixel. The band's pixel corners are traced first, once each, as camera
//! blocks (each tile its own corners: its top and left edges and its inside; the band's right and bottom
//! edges by the tiles along them). Then each tile, level by level, splits the squares [`Rule`] picks (corners
//! on different primitives or far apart in depth, down to D levels; colours more than T apart in a
//! channel, down to D − 1): their edge midpoints and centres are traced, each point once in the band (a
//! point on the edge between two tiles by the tile refined first, which hands it to the other: tiles are
//! refined in two passes, each of tiles that share no edge), in the Z-order of their squares and packed K
//! at a time, each packet with the pyramid of its points and up to [`crate::bvh::MAX_PACKETS`] packets
//! walking the tree as one large packet, as camera blocks do. A square's value is its quarters' mean where
//! it was split, else its corners' mean.
//!
//! Every decision depends only on the colours, ids and depths of lattice points, which are the same bits
//! at every width and thread count and whichever tile traces them, so the image is too, and so is the ray
//! count.
//!
//! [`Pattern::Adaptive`]: crate::scene::desc::Pattern::Adaptive

use std::cell::RefCell;
use std::ops::Range;

use rayon::prelude::*;

use crate::accel::{take_work, traced, RayKind, Work};
use crate::compile::Scene;
use crate::geometry::RayPacket;
use crate::math::Rgb;
use crate::shade::{RayCounts, Tracer};
use crate::simd::{IdLanes, Lanes};

use super::{for_each_camera_hit, lane_rgb, tile_rows, tiles, LargePacket, Offsets, Tile, TileCounter, TILE};

/// A traced lattice point: its colour, and the scene-file id of the primitive its camera ray meets first
/// ([`crate::geometry::NO_PRIM`] on a miss).
#[derive(Clone, Copy, Debug, Default)]
struct Point {
    colour: Rgb,
    key: u32,
    t: f32,
}

/// How much farther one corner's hit may be than another's before the square splits: a surface seen at a
/// grazing angle (a plane towards its horizon), where a texture's detail shrinks below the lattice's step
/// and corners of one colour can hide the other.
const DEPTH_RATIO: f32 = 1.03;

/// The split rule: a square splits where its corners see different primitives or lie at depths more than
/// [`DEPTH_RATIO`] apart (down to `depth` levels), or where their colours differ by more than `threshold`
/// in a channel (down to `depth - 1` levels, at least 1: colour differences inside a primitive, shading,
/// shadows and reflections, are smooth or small enough at a quarter pixel; silhouettes are not).
#[derive(Clone, Copy, Debug)]
struct Rule {
    threshold: f32,
    depth: u32,
}

impl Rule {
    /// Whether the square with corners `c` splits at `level`. The cheap tests come first: ids, then depths,
    /// then colours (the answer is their `or`, whatever the order).
    fn splits(&self, c: [&Point; 4], level: u32) -> bool {
        if c[1].key != c[0].key || c[2].key != c[0].key || c[3].key != c[0].key {
            return true;
        }
        // Colours and depths are never NaN, so plain comparisons give `f32::max`'s and `f32::min`'s values.
        let max = |a: f32, b: f32| if a > b { a } else { b };
        let min = |a: f32, b: f32| if a < b { a } else { b };
        let range =
            |v: [f32; 4]| max(max(v[0], v[1]), max(v[2], v[3])) - min(min(v[0], v[1]), min(v[2], v[3]));
        let t = c.map(|p| p.t);
        let (near, far) = (min(min(t[0], t[1]), min(t[2], t[3])), max(max(t[0], t[1]), max(t[2], t[3])));
        // All four missing (t = inf) is no reason to split.
        if far.is_finite() && far > near * DEPTH_RATIO {
            return true;
        }
        level < (self.depth - 1).max(1) && {
            let spread = max(
                max(range(c.map(|p| p.colour.x)), range(c.map(|p| p.colour.y))),
                range(c.map(|p| p.colour.z)),
            );
            spread > self.threshold
        }
    }
}

/// Traces rows `rows` of columns `columns` of the image under adaptive supersampling (`threshold`, `depth`):
/// the pixels row-major, and the rays and tests it took. The corners in one pass over the band's tiles,
/// then the refinement in two passes, each tile a job on `pool`: first the tiles whose row and column add
/// up to an even number, no two of which share an edge, then the others, which take the points their four
/// neighbours traced on their shared edges.
pub(super) fn adaptive_rows<F: Lanes>(
    scene: &Scene,
    pool: &rayon::ThreadPool,
    (columns, rows): (Range<u32>, Range<u32>),
    counter: &TileCounter,
    (threshold, depth): (f32, u32),
) -> (Vec<Rgb>, RayCounts, Work) {
    let (width, height) = (columns.end - columns.start, rows.end - rows.start);
    let local = tiles(width, height);
    let (corners, mut counts, mut work) =
        band_corners::<F>(scene, pool, &local, (columns.start, rows.start), (width, height));
    let mut band_pixels = vec![Rgb::default(); width as usize * height as usize];
    let per_row = width.div_ceil(TILE) as usize;
    let band = Band {
        scene,
        origin: (columns.start, rows.start),
        width,
        per_row,
        corners: &corners,
        rule: Rule { threshold, depth },
        counter,
    };
    let mut passes: [Vec<TileJob>; 2] = [Vec::new(), Vec::new()];
    for (k, (&tile, part)) in local.iter().zip(tile_rows(&mut band_pixels, width, &local)).enumerate() {
        passes[(k / per_row + k % per_row) % 2].push(TileJob { index: k, tile, part });
    }
    let [first, second] = passes;
    let mut edges: Vec<Option<Edges>> = vec![None; local.len()];
    let traced: Vec<_> = pool.install(|| {
        first.into_par_iter().with_max_len(1).map(|job| band.refine::<F>(job, &[], true)).collect()
    });
    for (index, own, c, w) in traced {
        edges[index] = own;
        counts += c;
        work += w;
    }
    let traced: Vec<_> = pool.install(|| {
        second.into_par_iter().with_max_len(1).map(|job| band.refine::<F>(job, &edges, false)).collect()
    });
    for (_, _, c, w) in traced {
        counts += c;
        work += w;
    }
    (band_pixels, counts, work)
}

/// The pixel corners of a band of `size` whose corner is `origin` in the image, `(width + 1) × (height + 1)`
/// row-major, each traced once: every tile of `local` traces its inside and its top and left edges, and the
/// band's right and bottom edges where it lies on them, as camera blocks, one job per tile on `pool`.
fn band_corners<F: Lanes>(
    scene: &Scene,
    pool: &rayon::ThreadPool,
    local: &[Tile],
    origin: (u32, u32),
    (width, height): (u32, u32),
) -> (Vec<Point>, RayCounts, Work) {
    let own = |t: &Tile| Tile {
        w: t.w + u32::from(t.x0 + t.w == width),
        h: t.h + u32::from(t.y0 + t.h == height),
        ..*t
    };
    let traced: Vec<(Vec<Point>, RayCounts, Work)> = pool.install(|| {
        local
            .par_iter()
            .with_max_len(1)
            .map(|tile| {
                take_work();
                let mut tracer = Tracer::<F>::new(scene);
                let at = Tile { x0: tile.x0 + origin.0, y0: tile.y0 + origin.1, ..own(tile) };
                let points = trace_corners(scene, &mut tracer, at);
                (points, tracer.counts, take_work())
            })
            .collect()
    });
    let corner_width = width as usize + 1;
    let mut corners = vec![Point::default(); corner_width * (height as usize + 1)];
    let (mut counts, mut work) = (RayCounts::default(), Work::default());
    for (tile, (points, c, w)) in local.iter().zip(traced) {
        for (y, row) in points.chunks_exact(own(tile).w as usize).enumerate() {
            let at = (tile.y0 as usize + y) * corner_width + tile.x0 as usize;
            corners[at..at + row.len()].copy_from_slice(row);
        }
        counts += c;
        work += w;
    }
    (corners, counts, work)
}

/// One tile of a band: its index in the band's row-major tiles, its place (band coordinates), and its
/// pixels' rows in the band's buffer.
struct TileJob<'b> {
    index: usize,
    tile: Tile,
    part: Vec<&'b mut [Rgb]>,
}

/// The lattice points a tile traced or took on its four edges, each edge in lattice steps left to right or
/// top to bottom.
#[derive(Clone, Default)]
struct Edges {
    top: Vec<Option<Point>>,
    bottom: Vec<Option<Point>>,
    left: Vec<Option<Point>>,
    right: Vec<Option<Point>>,
}

/// What every tile of a band shares: the scene, the band's corner in the image, its width and tiles per
/// row, its traced corners, the split rule and the progress counter.
struct Band<'a> {
    scene: &'a Scene,
    origin: (u32, u32),
    width: u32,
    per_row: usize,
    corners: &'a [Point],
    rule: Rule,
    counter: &'a TileCounter<'a>,
}

impl Band<'_> {
    /// Refines one tile, first taking the points its neighbours traced on their shared edges (`edges`, by
    /// tile index; none traced yet where empty); returns its index, the points on its own edges when
    /// `export`, and the rays and tests it took.
    fn refine<F: Lanes>(
        &self,
        TileJob { index, tile, mut part }: TileJob,
        edges: &[Option<Edges>],
        export: bool,
    ) -> (usize, Option<Edges>, RayCounts, Work) {
        take_work();
        let mut tracer = Tracer::<F>::new(self.scene);
        let unit = 1u32 << self.rule.depth;
        let (w, h) = (tile.w * unit, tile.h * unit);
        let corner_width = self.width as usize + 1;
        let corner =
            |x: u32, y: u32| self.corners[(tile.y0 + y) as usize * corner_width + (tile.x0 + x) as usize];
        let (row, column) = (index / self.per_row, index % self.per_row);
        // The traced edges of the tile at (row, column), if it is in the band and has been refined.
        let neighbour = |row: Option<usize>, column: Option<usize>| {
            let (row, column) = (row?, column.filter(|&c| c < self.per_row)?);
            edges.get(row * self.per_row + column)?.as_ref()
        };
        let preload = |lattice: &mut Lattice| {
            let load = |lattice: &mut Lattice, line: &[Option<Point>], at: &dyn Fn(u32) -> (u32, u32)| {
                for (i, p) in line.iter().enumerate() {
                    lattice.load(at(i as u32), *p);
                }
            };
            if let Some(e) = neighbour(Some(row), column.checked_sub(1)) {
                load(lattice, &e.right, &|y| (0, y));
            }
            if let Some(e) = neighbour(Some(row), Some(column + 1)) {
                load(lattice, &e.left, &|y| (w, y));
            }
            if let Some(e) = neighbour(row.checked_sub(1), Some(column)) {
                load(lattice, &e.bottom, &|x| (x, 0));
            }
            if let Some(e) = neighbour(Some(row + 1), Some(column)) {
                load(lattice, &e.top, &|x| (x, h));
            }
        };
        let mut own = None;
        let keep = |lattice: &Lattice| {
            if export {
                let line =
                    |n: u32, at: &dyn Fn(u32) -> (u32, u32)| (0..=n).map(|i| lattice.known(at(i))).collect();
                own = Some(Edges {
                    top: line(w, &|x| (x, 0)),
                    bottom: line(w, &|x| (x, h)),
                    left: line(h, &|y| (0, y)),
                    right: line(h, &|y| (w, y)),
                });
            }
        };
        let at = Tile { x0: tile.x0 + self.origin.0, y0: tile.y0 + self.origin.1, ..tile };
        let pixels = refine_tile(self.scene, &mut tracer, at, corner, self.rule, preload, keep);
        for (row, traced) in part.iter_mut().zip(pixels.chunks_exact(tile.w as usize)) {
            row.copy_from_slice(traced);
        }
        self.counter.tile_done();
        (index, own, tracer.counts, take_work())
    }
}

/// The points of `tile`'s pixel corners `(x0 + i, y0 + j)`, row-major, traced as camera blocks.
fn trace_corners<F: Lanes>(scene: &Scene, tracer: &mut Tracer<F>, tile: Tile) -> Vec<Point> {
    let mut points = vec![Point::default(); (tile.w * tile.h) as usize];
    let mut large = LargePacket::default();
    for_each_camera_hit(scene, tile, &Offsets::Shared(0.0, 0.0), &mut large, |rays, hit, block| {
        let c = tracer.primary_from(rays, hit);
        let (keys, ts) = (IdLanes::to_array(hit.key), hit.t.to_array());
        for (i, x, y) in block.pixels() {
            let (key, t) = (keys.as_ref()[i], ts.as_ref()[i]);
            points[(y * tile.w + x) as usize] = Point { colour: lane_rgb(&c, i), key, t };
        }
    });
    points
}

thread_local! {
    /// Each thread's lattice, reused from tile to tile.
    static LATTICE: RefCell<Lattice> = RefCell::new(Lattice::default());
}

/// One tile's pixels: its corners from `corner(i, j)` (`0..=w`, `0..=h`), refined by `rule` down to
/// `depth` levels.
fn refine_tile<F: Lanes>(
    scene: &Scene,
    tracer: &mut Tracer<F>,
    tile: Tile,
    corner: impl Fn(u32, u32) -> Point,
    rule: Rule,
    preload: impl FnOnce(&mut Lattice),
    export: impl FnOnce(&Lattice),
) -> Vec<Rgb> {
    let depth = rule.depth;
    LATTICE.with_borrow_mut(|lattice| {
        let unit = 1u32 << depth;
        lattice.reset(tile.w * unit + 1, tile.h * unit + 1);
        for y in 0..=tile.h {
            for x in 0..=tile.w {
                lattice.set((x * unit, y * unit), corner(x, y));
            }
        }
        preload(lattice);
        // Squares by their top-left lattice point, their size the level's, in Z-order (Morton order): each
        // level's squares are their parents' quarters in the same order, so the points they add, taken square
        // by square, come in nearly Z-order too, and K neighbours make a packet with no sort.
        let mut squares: Vec<(u32, u32)> =
            (0..tile.h).flat_map(|y| (0..tile.w).map(move |x| (x * unit, y * unit))).collect();
        squares.sort_unstable_by_key(|&(x, y)| z_order(x, y));
        let mut packets = Packets::default();
        let mut points = Vec::new();
        for level in 0..depth {
            let s = unit >> level;
            let h = s / 2;
            squares.retain(|&(x, y)| {
                rule.splits([(x, y), (x + s, y), (x, y + s), (x + s, y + s)].map(|p| lattice.get(p)), level)
            });
            if squares.is_empty() {
                break;
            }
            points.clear();
            for &(x, y) in &squares {
                lattice.mark_split((x, y), level);
                for p in [(x + h, y), (x, y + h), (x + h, y + h), (x + s, y + h), (x + h, y + s)] {
                    if lattice.claim(p) {
                        points.push(p);
                    }
                }
            }
            if scene.camera_f64.start != 0.0 {
                packets.trace::<true>(scene, tracer, tile, unit, &points, lattice);
            } else {
                packets.trace::<false>(scene, tracer, tile, unit, &points, lattice);
            }
            squares =
                squares.iter().flat_map(|&(x, y)| [(x, y), (x + h, y), (x, y + h), (x + h, y + h)]).collect();
        }
        export(lattice);
        (0..tile.h)
            .flat_map(|y| (0..tile.w).map(move |x| (x * unit, y * unit)))
            .map(|p| lattice.value(p, unit, 0))
            .collect()
    })
}

/// The position of `(x, y)` along the Z-order (Morton) curve: the bits of x and y interleaved.
fn z_order(x: u32, y: u32) -> u64 {
    let spread = |v: u32| {
        let mut v = u64::from(v);
        v = (v | (v << 16)) & 0x0000_ffff_0000_ffff;
        v = (v | (v << 8)) & 0x00ff_00ff_00ff_00ff;
        v = (v | (v << 4)) & 0x0f0f_0f0f_0f0f_0f0f;
        v = (v | (v << 2)) & 0x3333_3333_3333_3333;
        (v | (v << 1)) & 0x5555_5555_5555_5555
    };
    spread(x) | (spread(y) << 1)
}

/// Reusable buffers for one large packet of lattice points.
struct Packets<F: Lanes> {
    rays: Vec<RayPacket<F>>,
    hits: Vec<crate::geometry::HitPacket<F>>,
}

impl<F: Lanes> Default for Packets<F> {
    fn default() -> Self {
        Self { rays: Vec::new(), hits: Vec::new() }
    }
}

impl<F: Lanes> Packets<F> {
    /// Traces `points` (lattice points of `tile`, `unit` steps a pixel) in the order given, K at a time, each
    /// packet with the pyramid of its points and [`crate::bvh::MAX_PACKETS`] packets as one large packet, and
    /// stores their colours and ids in `lattice`. A point's position is `x0 + p·2^-depth`, the same bits from
    /// whichever tile shares it.
    /// `FAR` says whether the camera's rays start away from the eye
    /// ([`Camera::rays_in`](crate::camera::Camera::rays_in)).
    fn trace<const FAR: bool>(
        &mut self,
        scene: &Scene,
        tracer: &mut Tracer<F>,
        tile: Tile,
        unit: u32,
        points: &[(u32, u32)],
        lattice: &mut Lattice,
    ) {
        let camera = &scene.camera_f64;
        let pyramids = scene.geometry.culls_by_pyramid() && F::K > 1;
        let step = 1.0 / unit as f32;
        // A coordinate's range over a chunk's points, from its extreme points: `x0 + p·step` rounds
        // monotonically in p, so these are the extremes of the lanes' values.
        let range = |chunk: &[(u32, u32)], coordinate: fn(&(u32, u32)) -> u32, x0: u32| {
            let (lo, hi) =
                chunk.iter().map(coordinate).fold((u32::MAX, 0), |(lo, hi), c| (lo.min(c), hi.max(c)));
            [x0 as f32 + lo as f32 * step, x0 as f32 + hi as f32 * step]
        };
        for group in points.chunks(F::K * crate::bvh::MAX_PACKETS) {
            self.rays.clear();
            let (mut xs, mut ys) = ([f32::INFINITY, f32::NEG_INFINITY], [f32::INFINITY, f32::NEG_INFINITY]);
            for chunk in group.chunks(F::K) {
                // Lanes past the chunk's end repeat its last point (inactive, and inside its pyramid).
                let at = |i: usize| chunk[i.min(chunk.len() - 1)];
                let sx = F::from_fn(|i| tile.x0 as f32 + at(i).0 as f32 * step);
                let sy = F::from_fn(|i| tile.y0 as f32 + at(i).1 as f32 * step);
                let ray = camera.rays_in::<F, FAR>(sx, sy);
                let (rx, ry) = (range(chunk, |p| p.0, tile.x0), range(chunk, |p| p.1, tile.y0));
                (xs, ys) = ([xs[0].min(rx[0]), xs[1].max(rx[1])], [ys[0].min(ry[0]), ys[1].max(ry[1])]);
                let pyramid = pyramids.then(|| camera.pyramid(rx, ry)).flatten();
                let active = F::lanes_below(chunk.len());
                self.rays.push(RayPacket {
                    pyramid,
                    ..RayPacket::new(ray.origin, ray.dir, F::splat_f32(f32::INFINITY), active)
                });
            }
            let pyramid = pyramids.then(|| camera.pyramid(xs, ys)).flatten();
            self.hits.resize(self.rays.len(), crate::geometry::HitPacket::miss());
            let (rays, hits) = (&self.rays, &mut self.hits);
            traced(RayKind::Camera, || scene.geometry.intersect_tile(rays, pyramid.as_ref(), hits));
            for ((rays, hit), chunk) in self.rays.iter().zip(&self.hits).zip(group.chunks(F::K)) {
                let c = tracer.primary_from(rays, *hit);
                let (keys, ts) = (IdLanes::to_array(hit.key), hit.t.to_array());
                for (i, &p) in chunk.iter().enumerate() {
                    let (key, t) = (keys.as_ref()[i], ts.as_ref()[i]);
                    lattice.set(p, Point { colour: lane_rgb(&c, i), key, t });
                }
            }
        }
    }
}

/// One tile's lattice: each point's colour and id once traced, whether it is traced or queued, and for each
/// square's top-left point the number of levels at which the squares anchored there were split.
#[derive(Default)]
struct Lattice {
    width: u32,
    points: Vec<Point>,
    claimed: Vec<bool>,
    split: Vec<u8>,
}

impl Lattice {
    /// An empty `width × height` lattice (buffers kept from the previous tile).
    fn reset(&mut self, width: u32, height: u32) {
        let n = (width * height) as usize;
        self.width = width;
        self.points.resize(n, Point::default());
        self.claimed.clear();
        self.claimed.resize(n, false);
        self.split.clear();
        self.split.resize(n, 0);
    }
    fn index(&self, (x, y): (u32, u32)) -> usize {
        (y * self.width + x) as usize
    }
    fn get(&self, p: (u32, u32)) -> &Point {
        &self.points[self.index(p)]
    }
    fn set(&mut self, p: (u32, u32), point: Point) {
        let i = self.index(p);
        self.points[i] = point;
        self.claimed[i] = true;
    }
    /// Sets `p` when a neighbour traced it.
    fn load(&mut self, p: (u32, u32), point: Option<Point>) {
        if let Some(point) = point {
            self.set(p, point);
        }
    }
    /// The point at `p` once traced.
    fn known(&self, p: (u32, u32)) -> Option<Point> {
        let i = self.index(p);
        self.claimed[i].then(|| self.points[i])
    }
    /// Marks `p` to be traced; false when it is traced or marked already.
    fn claim(&mut self, p: (u32, u32)) -> bool {
        let i = self.index(p);
        !std::mem::replace(&mut self.claimed[i], true)
    }
    /// Records that the square at `p` of `level` is split.
    fn mark_split(&mut self, p: (u32, u32), level: u32) {
        let i = self.index(p);
        self.split[i] = level as u8 + 1;
    }
    /// The value of the square at `p` of `level` (size `unit >> level`): its quarters' mean when split,
    /// else its corners' mean.
    fn value(&self, (x, y): (u32, u32), unit: u32, level: u32) -> Rgb {
        let s = unit >> level;
        let parts = if u32::from(self.split[self.index((x, y))]) > level {
            let h = s / 2;
            [(x, y), (x + h, y), (x, y + h), (x + h, y + h)].map(|q| self.value(q, unit, level + 1))
        } else {
            [(x, y), (x + s, y), (x, y + s), (x + s, y + s)].map(|p| self.get(p).colour)
        };
        (parts[0] + parts[1] + parts[2] + parts[3]) * 0.25
    }
}
