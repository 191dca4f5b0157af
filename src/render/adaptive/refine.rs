//! The refinement of a band's tiles: each tile's squares split level by level in Z-order, with the points
//! on edges shared between tiles handed from the tile refined first to its neighbours.

use std::cell::RefCell;

use crate::accel::{take_work, Work};
use crate::compile::Scene;
use crate::math::Rgb;
use crate::render::{Tile, TileCounter};
use crate::shade::{RayCounts, Tracer};
use crate::simd::Lanes;

use super::lattice::Lattice;
use super::packets::Packets;
use super::{Point, Rule};

/// One tile of a band: its index in the band's row-major tiles, its place (band coordinates), and its
/// pixels' rows in the band's buffer.
pub(super) struct TileJob<'b> {
    pub(super) index: usize,
    pub(super) tile: Tile,
    pub(super) part: Vec<&'b mut [Rgb]>,
}

/// The lattice points a tile traced or took on its four edges, each edge in lattice steps left to right or
/// top to bottom.
#[derive(Clone, Default)]
pub(super) struct Edges {
    top: Vec<Option<Point>>,
    bottom: Vec<Option<Point>>,
    left: Vec<Option<Point>>,
    right: Vec<Option<Point>>,
}

/// What every tile of a band shares: the scene, the band's corner in the image, its width and tiles per
/// row, its traced corners, the split rule and the progress counter.
pub(super) struct Band<'a> {
    pub(super) scene: &'a Scene,
    pub(super) origin: (u32, u32),
    pub(super) width: u32,
    pub(super) per_row: usize,
    pub(super) corners: &'a [Point],
    pub(super) rule: Rule,
    pub(super) counter: &'a TileCounter<'a>,
}

impl Band<'_> {
    /// Refines one tile, first taking the points its neighbours traced on their shared edges (`edges`, by
    /// tile index; none traced yet where empty); returns its index, the points on its own edges when
    /// `export`, and the rays and tests it took.
    pub(super) fn refine<F: Lanes>(
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
