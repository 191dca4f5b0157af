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

use std::ops::Range;

use rayon::prelude::*;

use crate::accel::Work;
use crate::compile::Scene;
use crate::math::Rgb;
use crate::shade::RayCounts;
use crate::simd::Lanes;

use super::{tile_rows, tiles, TileCounter, TILE};

mod corners;
mod lattice;
mod packets;
mod refine;

use corners::band_corners;
use refine::{Band, Edges, TileJob};

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
