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
//!    exact area and centroid inside the pixel square come from
//!    [`Ellipse::clip`](crate::geometry::Ellipse::clip), in f64, for the sphere as the renderer stores it (f32
//!    centre and radius).
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
//!
//! Files: `silhouette.rs` (the camera's frame in f64, a sphere's depth and silhouette), `pixel.rs` (one
//! pixel's spheres, grid, depths and parts); here the tile's walk and binning and the tile's rays.

use crate::accel::NearFirst;
use crate::bvh::Frustum;
use crate::compile::Scene;
use crate::geometry::{Ellipse, RayPacket};
use crate::math::Rgb;
use crate::shade::Tracer;
use crate::simd::Lanes;

use super::{lane_rgb, Tile};

mod pixel;
mod silhouette;

use pixel::{resolve, Found, Pixel};
use silhouette::{spheres_extent, Ball, View};

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
