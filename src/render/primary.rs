//! Primary visibility only: the closest hit of one camera ray per pixel centre, for `bench`, the AOVs and
//! the checksums shared with the peer harnesses.

use std::time::Instant;

use rayon::prelude::*;

use crate::compile::Scene;
use crate::simd::Lanes;

use super::tile_rows::{self, TileRows};
use super::{
    column_key, for_each_camera_hit, rows_together, tiles, LargePacket, Offsets, Tile, Window, TILE,
};

/// Closest hits of one camera ray through every pixel centre: no shading, no secondary rays.
#[derive(Clone, Debug)]
pub(crate) struct PrimaryHits {
    /// Columns.
    pub(crate) width: u32,
    /// Rows.
    pub(crate) height: u32,
    /// Hit distance per pixel, row-major, `inf` on a miss.
    pub(crate) t: Vec<f32>,
    /// Primitive id per pixel in storage order ([`crate::accel::Geometry::file_id`] maps it to the scene
    /// file's numbering), [`crate::geometry::NO_PRIM`] on a miss.
    pub(crate) prim: Vec<u32>,
    /// Wall-clock seconds of the tracing.
    pub(crate) seconds: f64,
}

impl PrimaryHits {
    /// FNV-1a 64 over the per-pixel scene-file ids as little-endian i32 (−1 on a miss), row-major: the
    /// checksum bench-peers/ computes for Embree, so equal results give equal checksums across tracers.
    pub(crate) fn checksum(&self, scene: &Scene) -> u64 {
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
pub fn fnv1a(bytes: impl IntoIterator<Item = u8>) -> u64 {
    bytes.into_iter().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3))
}

impl PrimaryHits {
    /// A frame of misses, to be filled by [`trace_primary`].
    pub(crate) fn new(width: u32, height: u32) -> Self {
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

/// One camera ray per pixel centre, in packets of `lanes` (1, 4, 8 or 16), into a new frame on the threads
/// of `pool` ([`trace_primary`]).
pub(crate) fn primary_hits_lanes(scene: &Scene, lanes: usize, pool: &rayon::ThreadPool) -> PrimaryHits {
    let mut hits = PrimaryHits::new(scene.camera.width, scene.camera.height);
    trace_primary_lanes(scene, lanes, pool, &mut hits);
    hits
}

/// [`trace_primary`] at a packet width chosen at run time.
pub(crate) fn trace_primary_lanes(
    scene: &Scene,
    lanes: usize,
    pool: &rayon::ThreadPool,
    hits: &mut PrimaryHits,
) {
    with_lanes!(lanes, F => trace_primary::<F>(scene, pool, hits))
}

/// Traces one camera ray per pixel centre in packets of `F::K` on `pool` and writes the closest hits into
/// `hits` (sized to the camera), every pixel; `hits.seconds` is the wall-clock time of the tracing. Taking
/// the frame and the pool from the caller lets repeated frames (`bench`) reuse both, as a peer harness
/// reuses its frame buffers and threads.
pub(crate) fn trace_primary<F: Lanes>(scene: &Scene, pool: &rayon::ThreadPool, hits: &mut PrimaryHits) {
    let (width, height) = (scene.camera.width, scene.camera.height);
    assert_eq!((hits.width, hits.height), (width, height), "frame size differs from the camera's");
    trace_primary_window::<F>(scene, pool, Window::whole(width, height), hits);
}

/// [`trace_primary`] over `window` of the image: `hits` is the window's size, its pixel (0, 0) the
/// window's corner.
pub(crate) fn trace_primary_window<F: Lanes>(
    scene: &Scene,
    pool: &rayon::ThreadPool,
    window: Window,
    hits: &mut PrimaryHits,
) {
    let rows = rows_together(window.height(), pool.current_num_threads());
    trace_primary_rows::<F>(scene, pool, window, rows, hits);
}

/// [`trace_primary_window`] in bands of `rows` rows of tiles, each band's tiles column by column.
fn trace_primary_rows<F: Lanes>(
    scene: &Scene,
    pool: &rayon::ThreadPool,
    window: Window,
    rows: u32,
    hits: &mut PrimaryHits,
) {
    let start = Instant::now();
    let (width, height) = (window.width(), window.height());
    assert_eq!((hits.width, hits.height), (width, height), "frame size differs from the window's");
    // One band of rows of tiles per task, each tile's hits gathered in a buffer and written to the frame in
    // place (`TileRows`): no serial merge. Each band's tiles column by column (`column_key`).
    let band = width as usize * (TILE * rows) as usize;
    pool.install(|| {
        // One job per band, as for tiles in `render`.
        let bands =
            hits.t.par_chunks_mut(band).zip(hits.prim.par_chunks_mut(band)).enumerate().with_max_len(1);
        bands.for_each(|(band, (t, prim))| {
            let y0 = band as u32 * TILE * rows;
            let mut large = LargePacket::default();
            let mut local = tiles(width, (TILE * rows).min(height - y0));
            local.sort_by_key(|tile| column_key(tile, rows));
            let mut buffer = TileRows::default();
            for local in local {
                let tile = Tile { x0: window.x0 + local.x0, y0: window.y0 + y0 + local.y0, ..local };
                for_each_camera_hit::<F>(scene, tile, &Offsets::Shared(0.5, 0.5), &mut large, |_, hit, b| {
                    let (ts, ids) = (hit.t.to_array(), crate::simd::IdLanes::to_array(hit.prim));
                    buffer.put(&b, ts.as_ref(), ids.as_ref());
                });
                let at = local.y0 as usize * width as usize + local.x0 as usize;
                let size = (local.w as usize, local.h as usize);
                buffer.write(size, width as usize, &mut t[at..], &mut prim[at..]);
            }
            tile_rows::fence();
        });
    });
    hits.seconds = start.elapsed().as_secs_f64();
}

/// [`trace_primary_window`] into a new frame, at a packet width chosen at run time (1, 4, 8 or 16).
pub(crate) fn trace_primary_window_lanes(
    scene: &Scene,
    lanes: usize,
    pool: &rayon::ThreadPool,
    window: Window,
) -> PrimaryHits {
    let mut hits = PrimaryHits::new(window.width(), window.height());
    with_lanes!(lanes, F => trace_primary_window::<F>(scene, pool, window, &mut hits));
    hits
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{rows_for, thread_pool, ROWS_TOGETHER};

    /// Camera-ray bands of four, two and one rows of tiles (1, 2 and 5 threads on 300 rows, the last row of
    /// tiles partial), and the rows this machine takes, over the whole image and over a window at an odd
    /// offset: every pixel the same bits, and a window's pixels those of the whole image.
    #[test]
    fn every_band_height_and_window_gives_the_same_hits() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/field.toml");
        let mut desc = crate::io::load(&path).unwrap();
        (desc.camera.width, desc.camera.height) = (150, 300);
        let scene = Scene::compile(&desc).unwrap();
        assert_eq!([1, 2, 5].map(|t| rows_for(300, t, ROWS_TOGETHER)), [4, 2, 1]);
        let bits = |h: &PrimaryHits| (h.t.iter().map(|t| t.to_bits()).collect::<Vec<_>>(), h.prim.clone());
        let whole = bits(&primary_hits_lanes(&scene, 16, &thread_pool(Some(1)).unwrap()));
        assert!(whole.1.iter().filter(|&&p| p != u32::MAX).count() > 1000, "too few hits to compare");
        let window = Window { x0: 7, y0: 21, x1: 150, y1: 293 };
        for threads in [1, 2, 5] {
            let pool = thread_pool(Some(threads)).unwrap();
            for lanes in [1, 16] {
                assert_eq!(
                    bits(&primary_hits_lanes(&scene, lanes, &pool)),
                    whole,
                    "{threads} threads, K = {lanes}"
                );
            }
            let mut grouped = PrimaryHits::new(150, 300);
            let rows = rows_for(300, threads, ROWS_TOGETHER);
            trace_primary_rows::<wide::f32x16>(&scene, &pool, Window::whole(150, 300), rows, &mut grouped);
            assert_eq!(bits(&grouped), whole, "{threads} threads in bands of {rows} rows of tiles");
            let part = bits(&trace_primary_window_lanes(&scene, 16, &pool, window));
            for (row, y) in (window.y0..window.y1).enumerate() {
                let (w, at) = (window.width() as usize, (y * 150 + window.x0) as usize);
                assert_eq!(part.0[row * w..(row + 1) * w], whole.0[at..at + w], "row {y}, {threads} threads");
                assert_eq!(part.1[row * w..(row + 1) * w], whole.1[at..at + w], "row {y}, {threads} threads");
            }
        }
    }
}
