//! The band's pixel corners, the lattice's coarsest points: traced once each as camera blocks, one job per
//! tile, before any refinement.

use rayon::prelude::*;

use crate::accel::{take_work, Work};
use crate::compile::Scene;
use crate::render::{for_each_camera_hit, lane_rgb, LargePacket, Offsets, Tile};
use crate::shade::{RayCounts, Tracer};
use crate::simd::{IdLanes, Lanes};

use super::Point;

/// The pixel corners of a band of `width` × `height` pixels whose corner is `origin` in the image, `(width + 1) × (height + 1)`
/// row-major, each traced once: every tile of `local` traces its inside and its top and left edges, and the
/// band's right and bottom edges where it lies on them, as camera blocks, one job per tile on `pool`.
pub(super) fn band_corners<F: Lanes>(
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
