//! One pixel under the coverage pattern: the spheres found in it, its grid of points and their depths, and
//! the parts its value is the weighted sum of ([`resolve`]).

use super::silhouette::{dot, Ball, View, V};
use super::{CoveragePart, MAX_SPHERES, POINTS, SIDE};

/// A sphere found in a pixel.
#[derive(Clone, Copy, Debug)]
pub(super) struct Found {
    pub(super) item: u32,
    pub(super) ball: Ball,
    /// The covered area (exact for ellipses; estimated from the grid for spheres crossing the eye's plane).
    pub(super) area: f64,
    pub(super) centroid: [f64; 2],
    /// The grid points inside the silhouette, once computed.
    pub(super) mask: Option<u64>,
    /// The silhouette's bounding box in pixel space (unbounded without an ellipse): grid points outside
    /// it are outside the silhouette.
    pub(super) lo: [f64; 2],
    pub(super) hi: [f64; 2],
}

/// The grid of one pixel: its points and their directions.
pub(super) struct Grid {
    pub(super) points: [[f64; 2]; POINTS],
    pub(super) dirs: [V; POINTS],
}

impl Grid {
    fn new(view: &View, x: f64, y: f64) -> Grid {
        let points = std::array::from_fn(|i| {
            let (col, row) = ((i % SIDE) as f64, (i / SIDE) as f64);
            [x + (col + 0.5) / SIDE as f64, y + (row + 0.5) / SIDE as f64]
        });
        Grid { dirs: points.map(|p| view.dir(p)), points }
    }
}

/// A pixel's working state, reused from pixel to pixel: the spheres found, the grid and its depth buffer.
pub(super) struct Pixel {
    lo: [f64; 2],
    pub(super) found: Vec<Found>,
    grid: Grid,
    /// Whether `grid` is this pixel's.
    grid_ready: bool,
    /// Per grid point, the nearest depth found so far and whose it is (`u8::MAX`: no one's).
    pub(super) zbuf: [(f64, u8); POINTS],
    /// Whether `zbuf` holds every sphere found (kept from the second sphere on; cleared then).
    pub(super) zbuf_live: bool,
}

impl Pixel {
    pub(super) fn new() -> Pixel {
        Pixel {
            lo: [0.0; 2],
            found: Vec::new(),
            grid: Grid { points: [[0.0; 2]; POINTS], dirs: [[0.0; 3]; POINTS] },
            grid_ready: false,
            zbuf: [(f64::INFINITY, u8::MAX); POINTS],
            zbuf_live: false,
        }
    }

    pub(super) fn start(&mut self, lo: [f64; 2]) {
        self.lo = lo;
        self.found.clear();
        self.grid_ready = false;
        self.zbuf_live = false;
    }

    pub(super) fn grid(&mut self, view: &View) -> &Grid {
        if !self.grid_ready {
            self.grid = Grid::new(view, self.lo[0], self.lo[1]);
            self.grid_ready = true;
        }
        &self.grid
    }

    /// Enters sphere `j` into the per-point depth buffer (nearer wins; a tie keeps the one found first).
    pub(super) fn enter(&mut self, view: &View, j: usize) {
        let Found { ball, lo, hi, .. } = self.found[j];
        self.grid(view);
        // The grid's columns and rows whose points may lie in the box (point k of a row at k + ½ of 1/SIDE).
        let range = |lo: f64, hi: f64, origin: f64| {
            let at = |v: f64| (v - origin) * SIDE as f64 - 0.5;
            let first = at(lo).ceil().max(0.0).min(SIDE as f64) as usize;
            let end = (at(hi).floor() + 1.0).max(0.0).min(SIDE as f64) as usize;
            first..end.max(first)
        };
        let (cols, rows) = (range(lo[0], hi[0], self.lo[0]), range(lo[1], hi[1], self.lo[1]));
        let mut mask = 0u64;
        for row in rows {
            for i in cols.clone().map(|col| row * SIDE + col) {
                if let Some(d) = ball.depth(self.grid.dirs[i]) {
                    mask |= 1 << i;
                    if d < self.zbuf[i].0 {
                        self.zbuf[i] = (d, j as u8);
                    }
                }
            }
        }
        self.found[j].mask = Some(mask);
    }
}

/// The parts of a pixel from the spheres its walk found.
pub(super) fn resolve(px: &mut Pixel, view: &View, centre: [f64; 2], out: &mut Vec<CoveragePart>) {
    let n = px.found.len();
    let to32 = |p: [f64; 2]| (p[0] as f32, p[1] as f32);
    let first = out.len();
    let mut overlap = false;
    if n == 1 {
        let f = px.found[0];
        out.push(CoveragePart { sphere: Some(f.item), weight: f.area, at: to32(f.centroid) });
    } else if n > 1 {
        // Who owns each grid point.
        let mut owned = [0u64; MAX_SPHERES];
        for (i, z) in px.zbuf.iter().enumerate() {
            if z.1 != u8::MAX {
                owned[usize::from(z.1)] |= 1 << i;
            }
        }
        for (j, &owned) in owned.iter().enumerate().take(n) {
            let f = px.found[j];
            let mask = f.mask.expect("every sphere found is in the depth buffer");
            overlap |= owned != mask;
            // The nearest sphere along the ray through `p`, by depth (ties to the one found first).
            let nearest = |p: [f64; 2]| {
                let t = view.dir(p);
                let own = f.ball.depth(t).unwrap_or(f64::INFINITY);
                (0..n).all(|m| {
                    m == j || px.found[m].ball.depth(t).is_none_or(|d| d > own || (d == own && m > j))
                })
            };
            let (weight, at) = if mask == 0 {
                // Too thin for the grid: all or nothing, by its centroid.
                if nearest(f.centroid) {
                    (f.area, f.centroid)
                } else {
                    (0.0, f.centroid)
                }
            } else {
                let share = f64::from(owned.count_ones()) / f64::from(mask.count_ones());
                let at = if owned == mask || nearest(f.centroid) {
                    f.centroid
                } else {
                    closest(&px.grid.points, owned, f.centroid).unwrap_or(f.centroid)
                };
                (f.area * share, at)
            };
            if weight > 0.0 {
                out.push(CoveragePart { sphere: Some(f.item), weight, at: to32(at) });
            }
        }
    }
    let total: f64 = out[first..].iter().map(|p| p.weight).sum();
    if total > 1.0 {
        for p in &mut out[first..] {
            p.weight /= total;
        }
        return;
    }
    let rest = 1.0 - total;
    if rest <= 1e-12 {
        return;
    }
    // The remainder's centroid: exact when the silhouettes do not overlap (the pixel's moment less theirs).
    let target = if overlap {
        let covered = (0..n).fold(0u64, |m, j| m | px.found[j].mask.unwrap_or(0));
        let grid = px.grid(view);
        let free: Vec<usize> = (0..POINTS).filter(|&k| covered >> k & 1 == 0).collect();
        match free.len() {
            0 => centre,
            f => {
                let s = free
                    .iter()
                    .fold([0.0, 0.0], |s, &k| [s[0] + grid.points[k][0], s[1] + grid.points[k][1]]);
                [s[0] / f as f64, s[1] / f as f64]
            }
        }
    } else {
        let m = px.found.iter().fold([centre[0], centre[1]], |m, f| {
            [m[0] - f.area * f.centroid[0], m[1] - f.area * f.centroid[1]]
        });
        let r = 1.0 - px.found.iter().map(|f| f.area).sum::<f64>();
        let p = [m[0] / r, m[1] / r];
        if r > 0.0 && p.iter().all(|v| v.is_finite()) {
            p
        } else {
            centre
        }
    };
    let target = [target[0].clamp(px.lo[0], px.lo[0] + 1.0), target[1].clamp(px.lo[1], px.lo[1] + 1.0)];
    let at = remainder_point(px, view, target);
    out.push(CoveragePart { sphere: None, weight: rest, at: (at[0] as f32, at[1] as f32) });
}

/// Of the grid points in `mask`, the one nearest `p` (the first in grid order among equals).
fn closest(points: &[[f64; 2]; POINTS], mask: u64, p: [f64; 2]) -> Option<[f64; 2]> {
    let d = |q: [f64; 2]| (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2);
    (0..POINTS).filter(|&k| mask >> k & 1 == 1).map(|k| points[k]).min_by(|a, b| d(*a).total_cmp(&d(*b)))
}

/// The point the remainder's ray goes through: `target` (rounded to f32, as the ray will be) when it lies
/// outside every silhouette by [`CLEARANCE`](super::CLEARANCE), else the grid point nearest it that does
/// among those no silhouette holds, else the nearest of those, else `target` (every grid point is covered:
/// the remainder is what the grid cannot see).
fn remainder_point(px: &mut Pixel, view: &View, target: [f64; 2]) -> [f64; 2] {
    let rounded = |p: [f64; 2]| [f64::from(p[0] as f32), f64::from(p[1] as f32)];
    let clear = |px: &Pixel, p: [f64; 2]| {
        let t = view.dir(p);
        let len = dot(t, t).sqrt();
        px.found.iter().all(|f| f.ball.clear_of(t, len))
    };
    let target = rounded(target);
    if clear(px, target) {
        return target;
    }
    let covered = px.found.iter().fold(0u64, |m, f| m | f.mask.unwrap_or(0));
    let points = px.grid(view).points.map(rounded);
    let d = |q: [f64; 2]| (q[0] - target[0]).powi(2) + (q[1] - target[1]).powi(2);
    let mut free: Vec<usize> = (0..POINTS).filter(|&k| covered >> k & 1 == 0).collect();
    free.sort_unstable_by(|&a, &b| d(points[a]).total_cmp(&d(points[b])).then(a.cmp(&b)));
    free.iter().find(|&&k| clear(px, points[k])).or(free.first()).map_or(target, |&k| points[k])
}
