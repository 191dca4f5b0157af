//! The coverage pattern ([`Pattern::Coverage`](crate::scene::desc::Pattern::Coverage)): the lecture's
//! prefiltering. A pixel's value is the box filter's integral over the pixel square, and for primary
//! visibility of spheres that integral is computed from the geometry instead of estimated from samples:
//!
//! 1. **Which spheres reach into the pixel.** Once per tile, the spheres' BVH is walked nearest first
//!    ([`NearFirst`], keyed by each sphere's nearest distance `|C| − r` from the eye) over the spheres that
//!    meet the tile's pyramid (the four planes through the eye and the tile's edges); each pixel then takes,
//!    in that order, those whose silhouette's bounding box reaches it. A pixel's spheres and their order do
//!    not depend on the tile it is traced in.
//! 2. **How much of the pixel each covers.** The perspective image of a sphere wholly in front of the eye's
//!    plane (`C·Z > r`) is an ellipse: the directions `t` toward it satisfy `(t·C)² ≥ |t|²(|C|² − r²)`, a
//!    quadratic form in the window coordinates (u, v), and pixel space is an affine image of the window. Its
//!    exact area and centroid inside the pixel square come from [`Ellipse::clip`], in f64, for the sphere as
//!    the renderer stores it (f32 centre and radius).
//! 3. **Who is in front.** Where more than one sphere reaches into the pixel, an 8×8 grid of points in the
//!    pixel decides: each point belongs to the sphere whose surface is nearest along its ray (depths in f64),
//!    and a sphere's exact area is scaled by the share of its points it keeps (a sphere too thin to hold a
//!    point keeps its area when the nearest sphere at its centroid is itself, else none; a sphere that
//!    keeps none of its points is dropped before its area is computed).
//! 4. **Colours.** Each sphere left with a weight is shaded by one ray through its covered part's centroid
//!    (through its visible point nearest the centroid when a nearer sphere hides the centroid), and the
//!    uncovered remainder by one ray through the remainder's centroid, or, where that falls inside a
//!    silhouette, the grid point nearest it clear of every silhouette. The rays are ordinary camera rays
//!    traced by the [`Tracer`], secondary rays and all, and the pixel is the weighted sum of their colours.
//!
//! **Exact** (to f64 rounding in the weights, f32 in the colours): the weights, when the silhouettes of the
//! spheres reaching into the pixel do not overlap inside it — each sphere's weight is its exact covered area
//! and the remainder's weight the exact uncovered area — and with them the pixel, wherever each part has one
//! colour (flat shading, no other primitive in front of it). A pixel covered by one sphere is one ray at its
//! centre; a pixel no sphere reaches is one ray at its centre.
//!
//! **Approximate**:
//! - *Overlapping silhouettes* inside a pixel: the hidden share of each sphere is counted on the 8×8 points,
//!   not integrated (weights then sum to at most 1, renormalised when the estimates exceed it). Spheres
//!   that pass through each other are ordered per point by depth, so their intersection curve is resolved
//!   at the points' spacing only.
//! - *Shading across a part*: each part takes the colour of the ray through its centroid. That is the exact
//!   mean for colour varying linearly across the part (its centroid's value), not for highlights, shadow
//!   edges, reflections or refractions inside it: secondary rays come from that one primary ray.
//! - *Other primitives* (planes, polygons, transformed shapes, cones) are not prefiltered: they are seen
//!   only through the parts' rays. One in front of a sphere's part replaces that part's colour as a whole,
//!   and the remainder (background, floor, polygons) is one ray, like one sample per pixel.
//! - *Spheres that cross the eye's plane* (a ground sphere under the eye: its image is bounded by a
//!   hyperbola or parabola) take the share of the 8×8 points inside their silhouette as their area (exactly
//!   0 or 1 when the pixel is wholly outside or inside). A sphere holding the eye covers every pixel.
//! - Walk cut-offs: the walk ends when a sphere covering the whole pixel is nearer everywhere in it than the
//!   next sphere can be (exact), or when every grid point is covered, the areas found sum to at least 1 and
//!   the next sphere lies beyond the farthest grid point's depth; and after 64 spheres.

use crate::accel::NearFirst;
use crate::bvh::Frustum;
use crate::camera::Camera;
use crate::compile::Scene;
use crate::geometry::{Ellipse, RayPacket, Spheres};
use crate::math::Rgb;
use crate::shade::Tracer;
use crate::simd::Lanes;

use super::{lane_rgb, Tile};

/// Points per side of the grid that resolves overlaps and finds the remainder's point.
const SIDE: usize = 8;
/// Points in the grid, one bit each in a `u64` mask.
const POINTS: usize = SIDE * SIDE;
/// The most spheres kept for one pixel.
const MAX_SPHERES: usize = 64;
/// How far outside every silhouette (radians) the remainder's ray is aimed when it can be: far beyond the
/// rounding of an f32 camera ray (about 1e-7) and of the sphere kernel near a rim.
const CLEARANCE: f64 = 2e-6;

/// One ray of a pixel under the coverage pattern.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct CoveragePart {
    /// The sphere whose part of the pixel the ray shades (storage order, as the BVH keeps the spheres), or
    /// `None` for the part no sphere covers.
    pub(crate) sphere: Option<u32>,
    /// The part's share of the pixel: 0 to 1, the shares of a pixel summing to 1.
    pub(crate) weight: f64,
    /// Where the ray goes through, in pixel-space coordinates (column j's centre at j + ½).
    pub(crate) at: (f32, f32),
}

/// A vector of the camera's frame coordinates: x along the image's columns, y up, z forward.
type V = [f64; 3];

fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The camera as coverage needs it: the frame, and pixel space ↔ window.
struct View {
    /// The eye in rendering space (the origin but in a far scene, `crate::compile::RenderingFrame`).
    eye: V,
    right: V,
    up: V,
    forward: V,
    /// Window `u = sx·au + bu`, `v = sy·av + bv` (directions `(u, v, 1)` in the frame).
    au: f64,
    bu: f64,
    av: f64,
    bv: f64,
}

impl View {
    fn new(camera: &Camera<f64>) -> View {
        let v = |p: crate::math::V3<f64>| [p.x, p.y, p.z];
        View {
            eye: v(camera.eye),
            right: v(camera.right),
            up: v(camera.up),
            forward: v(camera.forward),
            au: camera.u_scale * camera.half_w,
            bu: camera.u_offset * camera.half_w,
            av: camera.v_scale * camera.half_h,
            bv: camera.v_offset * camera.half_h,
        }
    }

    /// The direction (in the frame, not unit) toward pixel-space point `p`.
    fn dir(&self, p: [f64; 2]) -> V {
        [p[0] * self.au + self.bu, p[1] * self.av + self.bv, 1.0]
    }

    /// A rendering-space point as a vector from the eye, in f64.
    fn eye_to(&self, p: [f32; 3]) -> V {
        [0, 1, 2].map(|a| f64::from(p[a]) - self.eye[a])
    }

    /// A rendering-space vector in the frame.
    fn to_frame(&self, c: V) -> V {
        [dot(c, self.right), dot(c, self.up), dot(c, self.forward)]
    }
}

/// The largest coordinate magnitude of `spheres`' boxes (a tree's `extent`, for spheres kept without one).
fn spheres_extent(spheres: &Spheres) -> f32 {
    (0..spheres.len())
        .map(|i| {
            let (c, r) = (spheres.center(i), spheres.r[i]);
            c.x.abs().max(c.y.abs()).max(c.z.abs()) + r
        })
        .fold(0.0, f32::max)
}

/// A sphere in the camera's frame (from the eye), in f64 from its stored f32 values.
#[derive(Clone, Copy, Debug)]
struct Ball {
    c: V,
    r: f64,
    /// `|C|² − r²`, as `(|C| − r)(|C| + r)`: positive when the eye is outside.
    k: f64,
    /// `|C|`.
    dist: f64,
    /// `|C|·cos(α + CLEARANCE)` (sin α = r/|C|): a direction `t` with `t·C ≤ |t|·rim` passes outside the
    /// silhouette by at least [`CLEARANCE`]; −∞ for a sphere holding the eye.
    rim: f64,
}

impl Ball {
    fn new(c: V, r: f64) -> Ball {
        let dist = dot(c, c).sqrt();
        let k = (dist - r) * (dist + r);
        let (sin, cos) = CLEARANCE.sin_cos();
        let rim = if k > 0.0 { k.sqrt() * cos - r * sin } else { f64::NEG_INFINITY };
        Ball { c, r, k, dist, rim }
    }

    /// Whether `t` (of length `len`) passes outside the silhouette by at least [`CLEARANCE`].
    fn clear_of(&self, t: V, len: f64) -> bool {
        dot(t, self.c) <= len * self.rim
    }

    /// The distance (along the unit direction) to the surface the eye sees along `t`: the entry point, or
    /// the exit point from inside; `None` where the ray misses.
    fn depth(&self, t: V) -> Option<f64> {
        let (b, tt) = (dot(t, self.c), dot(t, t));
        let disc = b * b - tt * self.k;
        if self.k > 0.0 {
            (b > 0.0 && disc >= 0.0).then(|| self.k / (b + disc.sqrt()) * tt.sqrt())
        } else {
            Some((b + disc.max(0.0).sqrt()) / tt.sqrt())
        }
    }

    /// The silhouette in pixel space when the sphere lies wholly in front of the eye's plane.
    fn ellipse(&self, view: &View) -> Option<Ellipse> {
        let [cu, cv, cz] = self.c;
        if !(self.k > 0.0 && cz > self.r) || view.au == 0.0 || view.av == 0.0 {
            return None;
        }
        // In the window (u, v): centre cz·c/(cz² − r²), semi-axes r√k/(cz² − r²) along c = (cu, cv) and
        // r/√(cz² − r²) across it.
        let g = (cz - self.r) * (cz + self.r);
        let m = [cz * cu / g, cz * cv / g];
        let (along, across) = (self.r * self.k.sqrt() / g, self.r / g.sqrt());
        let len = cu.hypot(cv);
        let (ex, ey) = if len > 0.0 { (cu / len, cv / len) } else { (1.0, 0.0) };
        // Rows of the map onto the unit disc, composed with window = (au·sx + bu, av·sy + bv).
        let to_unit =
            [[ex / along * view.au, ey / along * view.av], [-ey / across * view.au, ex / across * view.av]];
        let centre = [(m[0] - view.bu) / view.au, (m[1] - view.bv) / view.av];
        Some(Ellipse { centre, to_unit })
    }
}

/// A sphere found in a pixel.
#[derive(Clone, Copy, Debug)]
struct Found {
    item: u32,
    ball: Ball,
    /// The covered area (exact for ellipses; estimated from the grid for spheres crossing the eye's plane).
    area: f64,
    centroid: [f64; 2],
    /// The grid points inside the silhouette, once computed.
    mask: Option<u64>,
    /// The silhouette's bounding box in pixel space (unbounded without an ellipse): grid points outside
    /// it are outside the silhouette.
    lo: [f64; 2],
    hi: [f64; 2],
}

/// The grid of one pixel: its points and their directions.
struct Grid {
    points: [[f64; 2]; POINTS],
    dirs: [V; POINTS],
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

/// A sphere that meets a tile's pyramid, prepared for the tile's pixels.
#[derive(Clone, Copy, Debug)]
struct Near {
    item: u32,
    /// `|C| − r` (0 from inside): no point of the sphere is nearer the eye.
    key: f64,
    ball: Ball,
    ellipse: Option<Ellipse>,
    /// The silhouette's bounding box in pixel space; unbounded for spheres without an ellipse.
    lo: [f64; 2],
    hi: [f64; 2],
}

/// A pixel's working state, reused from pixel to pixel: the spheres found, the grid and its depth buffer.
struct Pixel {
    lo: [f64; 2],
    found: Vec<Found>,
    grid: Grid,
    /// Whether `grid` is this pixel's.
    grid_ready: bool,
    /// Per grid point, the nearest depth found so far and whose it is (`u8::MAX`: no one's).
    zbuf: [(f64, u8); POINTS],
    /// Whether `zbuf` holds every sphere found (kept from the second sphere on; cleared then).
    zbuf_live: bool,
}

impl Pixel {
    fn new() -> Pixel {
        Pixel {
            lo: [0.0; 2],
            found: Vec::new(),
            grid: Grid { points: [[0.0; 2]; POINTS], dirs: [[0.0; 3]; POINTS] },
            grid_ready: false,
            zbuf: [(f64::INFINITY, u8::MAX); POINTS],
            zbuf_live: false,
        }
    }

    fn start(&mut self, lo: [f64; 2]) {
        self.lo = lo;
        self.found.clear();
        self.grid_ready = false;
        self.zbuf_live = false;
    }

    fn grid(&mut self, view: &View) -> &Grid {
        if !self.grid_ready {
            self.grid = Grid::new(view, self.lo[0], self.lo[1]);
            self.grid_ready = true;
        }
        &self.grid
    }

    /// Enters sphere `j` into the per-point depth buffer (nearer wins; a tie keeps the one found first).
    fn enter(&mut self, view: &View, j: usize) {
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

/// The scene's spheres and camera, ready for per-pixel coverage: the spheres of one tile at a time.
pub(super) struct Coverage<'a> {
    scene: &'a Scene,
    view: View,
    walk: NearFirst,
    /// The spheres that meet the current tile's pyramid, nearest first (by `key`, then storage index).
    near: Vec<Near>,
    /// The current tile.
    tile: Tile,
    /// Per pixel of the tile (row-major), the indices into `near` of the spheres whose silhouette's box
    /// reaches it, in `near`'s order: pixel p's are `bins[starts[p]..starts[p + 1]]`.
    bins: Vec<u32>,
    starts: Vec<u32>,
    px: Pixel,
}

impl<'a> Coverage<'a> {
    pub(super) fn new(scene: &'a Scene) -> Self {
        let view = View::new(&scene.camera_f64);
        let tile = Tile { x0: 0, y0: 0, w: 0, h: 0 };
        let (bins, starts) = (Vec::new(), Vec::new());
        Coverage {
            scene,
            view,
            walk: NearFirst::new(),
            near: Vec::new(),
            tile,
            bins,
            starts,
            px: Pixel::new(),
        }
    }

    /// Finds the spheres that meet the pyramid of `tile` (the planes through the eye and the tile's edges):
    /// every sphere that reaches into one of its pixels, whichever tile the pixel is seen from.
    pub(super) fn tile(&mut self, tile: Tile) {
        self.tile = tile;
        let Coverage { scene, view, walk, near, .. } = self;
        near.clear();
        if view.au == 0.0 || view.av == 0.0 {
            return;
        }
        let spheres = &scene.geometry.spheres;
        let bvh = scene.geometry.sphere_bvh.as_ref();
        // The packet walks' frustum of the tile's pixel squares: it keeps every box and sphere an exact
        // direction through the tile may reach. A view too wide for one (beyond about 177°) culls nothing.
        let frustum = scene
            .camera_f64
            .window_pyramid(
                [tile.x0, tile.x0 + tile.w].map(|x| x as f32),
                [tile.y0, tile.y0 + tile.h].map(|y| y as f32),
            )
            .map(|p| Frustum::new(&p, bvh.map_or_else(|| spheres_extent(spheres), |b| b.extent)));
        let box_key = |lo: [f32; 3], hi: [f32; 3]| {
            if frustum.as_ref().is_some_and(|f| !f.may_enter(lo, hi)) {
                return None;
            }
            let (lo, hi) = (view.eye_to(lo), view.eye_to(hi));
            let gap = |a: usize| lo[a].max(0.0).max(-hi[a]);
            Some((gap(0).powi(2) + gap(1).powi(2) + gap(2).powi(2)).sqrt())
        };
        let view = &*view;
        let ball = |i: usize| {
            let c = view.eye_to([spheres.cx[i], spheres.cy[i], spheres.cz[i]]);
            Ball::new(view.to_frame(c), f64::from(spheres.r[i]))
        };
        let item_key = |i: usize| {
            let meets = frustum.as_ref().is_none_or(|f| f.may_meet(spheres.center(i), spheres.r[i]));
            meets.then(|| (ball(i).dist - f64::from(spheres.r[i])).max(0.0))
        };
        let visit = |i: usize, key: f64| {
            let ball = ball(i);
            let ellipse = ball.ellipse(view);
            let (lo, hi) = match &ellipse {
                Some(e) => {
                    let h = e.half_extent();
                    ([e.centre[0] - h[0], e.centre[1] - h[1]], [e.centre[0] + h[0], e.centre[1] + h[1]])
                }
                None => ([f64::NEG_INFINITY; 2], [f64::INFINITY; 2]),
            };
            near.push(Near { item: i as u32, key, ball, ellipse, lo, hi });
            f64::INFINITY
        };
        walk.walk(scene.geometry.sphere_bvh.as_ref(), spheres.len(), box_key, item_key, visit);
        self.bin();
    }

    /// Sorts the tile's spheres into its pixels by their silhouettes' boxes (a pixel is reached when the
    /// box overlaps its square), keeping their order.
    fn bin(&mut self) {
        let t = self.tile;
        // The tile's columns (or rows) a box [lo, hi] overlaps, as a range relative to `origin`.
        let span = |lo: f64, hi: f64, origin: u32, len: u32| {
            let first = (lo - f64::from(origin)).floor().max(0.0).min(f64::from(len)) as u32;
            let end = (hi - f64::from(origin)).ceil().max(0.0).min(f64::from(len)) as u32;
            first..end.max(first)
        };
        let spans: Vec<_> = self
            .near
            .iter()
            .map(|n| (span(n.lo[0], n.hi[0], t.x0, t.w), span(n.lo[1], n.hi[1], t.y0, t.h)))
            .collect();
        let pixels = (t.w * t.h) as usize;
        self.starts.clear();
        self.starts.resize(pixels + 1, 0);
        for (xs, ys) in &spans {
            for y in ys.clone() {
                for x in xs.clone() {
                    self.starts[(y * t.w + x) as usize + 1] += 1;
                }
            }
        }
        for p in 0..pixels {
            self.starts[p + 1] += self.starts[p];
        }
        self.bins.clear();
        self.bins.resize(self.starts[pixels] as usize, 0);
        let mut fill: Vec<u32> = self.starts[..pixels].to_vec();
        for (i, (xs, ys)) in spans.iter().enumerate() {
            for y in ys.clone() {
                for x in xs.clone() {
                    let p = (y * t.w + x) as usize;
                    self.bins[fill[p] as usize] = i as u32;
                    fill[p] += 1;
                }
            }
        }
    }

    /// The rays of pixel (x, y), which lies in the tile last given to [`Coverage::tile`], appended to `out`.
    pub(super) fn pixel(&mut self, x: u32, y: u32, out: &mut Vec<CoveragePart>) {
        let Coverage { view, near, tile, bins, starts, px, .. } = self;
        let view = &*view;
        let (lo, hi) = ([f64::from(x), f64::from(y)], [f64::from(x) + 1.0, f64::from(y) + 1.0]);
        let centre = [lo[0] + 0.5, lo[1] + 0.5];
        if view.au == 0.0 || view.av == 0.0 {
            // A window edge sweep one pixel wide or high: every column (or row) looks the same way.
            out.push(CoveragePart { sphere: None, weight: 1.0, at: (centre[0] as f32, centre[1] as f32) });
            return;
        }
        px.start(lo);
        let corners = [lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]].map(|p| view.dir(p));
        let mut cut = f64::INFINITY;
        let p = ((y - tile.y0) * tile.w + (x - tile.x0)) as usize;
        let mine =
            bins.get(starts.get(p).map_or(0, |&s| s as usize)..starts.get(p + 1).map_or(0, |&s| s as usize));
        for &i in mine.unwrap_or(&[]) {
            let n = &near[i as usize];
            if n.key >= cut {
                break;
            }
            if n.hi[0] <= lo[0] || n.lo[0] >= hi[0] || n.hi[1] <= lo[1] || n.lo[1] >= hi[1] {
                continue;
            }
            let ball = n.ball;
            let holds = corners.map(|t| ball.depth(t));
            let whole = holds.iter().all(Option::is_some);
            // From the second sphere on, the depth grid comes first: a sphere behind others at every grid
            // point inside it gets no weight, so it is dropped before its area is computed.
            let first = px.found.is_empty();
            let mut owns = false;
            if !first {
                let (lo, hi) = (n.lo, n.hi);
                px.found.push(Found { item: n.item, ball, area: 0.0, centroid: centre, mask: None, lo, hi });
                let j = px.found.len() - 1;
                if !px.zbuf_live {
                    px.zbuf_live = true;
                    px.zbuf = [(f64::INFINITY, u8::MAX); POINTS];
                    for k in 0..j {
                        px.enter(view, k);
                    }
                }
                px.enter(view, j);
                owns = px.zbuf.iter().any(|z| usize::from(z.1) == j);
                if !owns && px.found[j].mask != Some(0) {
                    px.found.pop();
                    continue;
                }
            }
            let (area, centroid) = match (whole, &n.ellipse) {
                (true, _) => (1.0, centre),
                (false, Some(e)) => {
                    let part = e.clip(lo, hi);
                    (part.area, part.centroid)
                }
                (false, None) => {
                    // Crossing the eye's plane: the share of the grid inside.
                    let grid = px.grid(view);
                    let inside: Vec<usize> =
                        (0..POINTS).filter(|&k| ball.depth(grid.dirs[k]).is_some()).collect();
                    let count = inside.len() as f64;
                    let sum = inside
                        .iter()
                        .fold([0.0, 0.0], |s, &k| [s[0] + grid.points[k][0], s[1] + grid.points[k][1]]);
                    let centroid = if count > 0.0 { [sum[0] / count, sum[1] / count] } else { centre };
                    (count / POINTS as f64, centroid)
                }
            };
            if first {
                if area <= 0.0 {
                    continue;
                }
                let (lo, hi) = (n.lo, n.hi);
                px.found.push(Found { item: n.item, ball, area, centroid, mask: None, lo, hi });
            } else if area <= 0.0 && !owns {
                px.found.pop();
                continue;
            } else {
                let f = px.found.last_mut().expect("pushed above");
                (f.area, f.centroid) = (area.max(0.0), centroid);
            }
            if whole {
                // Nearer than anything whose nearest point lies beyond the farthest of its corners (the
                // depth grows with the angle from the centre's direction, largest at a corner).
                let far = match ball.k > 0.0 {
                    true => holds.iter().flatten().fold(0.0f64, |m, &d| m.max(d)),
                    false => ball.dist + ball.r,
                };
                cut = cut.min(far);
            }
            if px.zbuf_live {
                let area_sum: f64 = px.found.iter().map(|f| f.area).sum();
                if area_sum >= 1.0 && px.zbuf.iter().all(|z| z.1 != u8::MAX) {
                    cut = cut.min(px.zbuf.iter().fold(0.0f64, |m, z| m.max(z.0)));
                }
            }
            if px.found.len() >= MAX_SPHERES {
                break;
            }
        }
        resolve(px, view, centre, out);
    }
}

/// The parts of a pixel from the spheres its walk found.
fn resolve(px: &mut Pixel, view: &View, centre: [f64; 2], out: &mut Vec<CoveragePart>) {
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
/// outside every silhouette by [`CLEARANCE`], else the grid point nearest it that does among those no
/// silhouette holds, else the nearest of those, else `target` (every grid point is covered: the remainder is
/// what the grid cannot see).
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

/// The parts of pixel (x, y) of `scene` under the coverage pattern: the rays its value is the weighted sum
/// of, whatever the scene's own pattern (for the tests, which check the parts' weights).
#[cfg(test)]
pub(crate) fn coverage_parts(scene: &Scene, x: u32, y: u32) -> Vec<CoveragePart> {
    let mut out = Vec::new();
    let mut coverage = Coverage::new(scene);
    coverage.tile(Tile { x0: x, y0: y, w: 1, h: 1 });
    coverage.pixel(x, y, &mut out);
    out
}

/// The pixels of one tile under the coverage pattern: each pixel's parts found, then all the tile's rays
/// traced K at a time in pixel order, and each pixel summed over its parts in their order. A pixel's parts
/// depend only on the pixel, and each ray's colour is the same bits at every width, so the image is too.
pub(super) fn coverage_tile<F: Lanes>(scene: &Scene, tracer: &mut Tracer<F>, tile: Tile) -> Vec<Rgb> {
    let mut coverage = Coverage::new(scene);
    coverage.tile(tile);
    let mut parts = Vec::new();
    let mut owner = Vec::new();
    for y in tile.y0..tile.y0 + tile.h {
        for x in tile.x0..tile.x0 + tile.w {
            let before = parts.len();
            coverage.pixel(x, y, &mut parts);
            let p = ((y - tile.y0) * tile.w + (x - tile.x0)) as usize;
            owner.extend(std::iter::repeat_n(p, parts.len() - before));
        }
    }
    let camera = &scene.camera_f64;
    let mut out = vec![Rgb::default(); (tile.w * tile.h) as usize];
    for (chunk, owners) in parts.chunks(F::K).zip(owner.chunks(F::K)) {
        let at = |i: usize| chunk[i.min(chunk.len() - 1)].at;
        let ray = camera.rays(F::from_fn(|i| at(i).0), F::from_fn(|i| at(i).1));
        let rays =
            RayPacket::new(ray.origin, ray.dir, F::splat_f32(f32::INFINITY), F::lanes_below(chunk.len()));
        let c = tracer.primary(&rays);
        for (i, (part, &p)) in chunk.iter().zip(owners).enumerate() {
            out[p] = out[p] + lane_rgb(&c, i) * part.weight as f32;
        }
    }
    out
}
