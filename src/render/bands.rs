//! The image, or a window of it, traced band by band: a band is a run of whole tile rows across the window,
//! its tiles traced in parallel into one buffer; finished bands leave in order, top to bottom, so a caller
//! can encode them and let them go while the next is traced. Memory then grows with the band, not the
//! image. The lecture's postfilter, which reads the rows above and below, runs on the band stream: it
//! holds back a band's last row until the row under it arrives, and a window traces one more row and
//! column of apron wherever the image goes on. Every pixel is the same bits as in the whole-image render.

use std::ops::Range;
use std::time::Instant;

use rayon::prelude::*;

use crate::accel::{take_work, Work};
use crate::compile::Scene;
use crate::math::Rgb;
use crate::sample::lecture_3x3_pixel;
use crate::scene::desc::{Pattern, PostFilter};
use crate::shade::{RayCounts, Tracer};
use crate::simd::Lanes;

use super::{column_key, tile_group, tile_rows, tiles, trace_tile, Progress, Tile, TileCounter, TILE};

/// A rectangle of the image in pixels: columns `x0..x1`, rows `y0..y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Window {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

impl Window {
    /// The whole of a `width × height` image.
    pub fn whole(width: u32, height: u32) -> Self {
        Self { x0: 0, y0: 0, x1: width, y1: height }
    }
    /// Columns.
    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }
    /// Rows.
    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }
    /// The window grown by `apron` pixels on every side, clipped to a `width × height` image.
    pub(crate) fn grown(&self, apron: u32, width: u32, height: u32) -> Self {
        Self {
            x0: self.x0.saturating_sub(apron),
            y0: self.y0.saturating_sub(apron),
            x1: (self.x1 + apron).min(width),
            y1: (self.y1 + apron).min(height),
        }
    }
}

/// What a banded render traced, and how long it took.
#[derive(Clone, Copy, Debug, Default)]
pub struct Traced {
    /// Rays traced by kind.
    pub counts: RayCounts,
    /// Intersection tests done.
    pub work: Work,
    /// Wall-clock seconds spent tracing and filtering (not in `emit`).
    pub seconds: f64,
}

/// Traces rows `rows` of columns `columns` of the image, before any postfilter: the pixels row-major, and
/// the rays and tests it took. Tiles of TILE × TILE from the band's corner, one job each, on `pool`.
pub(super) fn trace_band<F: Lanes>(
    scene: &Scene,
    pool: &rayon::ThreadPool,
    columns: Range<u32>,
    rows: Range<u32>,
    counter: &TileCounter,
    band: &mut Vec<Rgb>,
) -> (RayCounts, Work) {
    if let Pattern::Adaptive { threshold, depth } = scene.render.pattern {
        let (pixels, counts, work) =
            super::adaptive::adaptive_rows::<F>(scene, pool, (columns, rows), counter, (threshold, depth));
        *band = pixels;
        return (counts, work);
    }
    let (width, height) = (columns.end - columns.start, rows.end - rows.start);
    let local = tiles(width, height);
    // Every pixel is written by its tile: what the buffer held before is overwritten.
    band.resize(width as usize * height as usize, Rgb::default());
    let mut jobs: Vec<_> = local.iter().copied().zip(tile_rows(band, width, &local)).collect();
    // Rows of tiles column by column (or one by one: `tile_group`); each thread takes its share of jobs in
    // that order.
    let group = tile_group();
    jobs.sort_by_key(|(tile, _)| column_key(tile, group));
    let traced: Vec<(RayCounts, Work)> = pool.install(|| {
        // One job per tile (with_max_len): rayon otherwise runs whole quarters of the band as single
        // jobs, which a thread slowed by the host cannot hand over (docs/perf-log/2026-11.md).
        jobs.into_par_iter()
            .with_max_len(1)
            .map(|(tile, mut part)| {
                take_work();
                let mut tracer = Tracer::<F>::new(scene);
                let at = Tile { x0: tile.x0 + columns.start, y0: tile.y0 + rows.start, ..tile };
                trace_tile(scene, &mut tracer, at, &mut part);
                counter.tile_done();
                (tracer.counts, take_work())
            })
            .collect()
    });
    let (mut counts, mut work) = (RayCounts::default(), Work::default());
    for (c, w) in traced {
        counts += c;
        work += w;
    }
    (counts, work)
}

/// Rows per band for an image `width` pixels wide when a band may take about `budget` bytes of linear
/// RGB: whole tile rows, at least one.
pub(crate) fn band_rows(width: u32, budget: usize) -> u32 {
    let row = width.max(1) as usize * std::mem::size_of::<Rgb>();
    let tile_rows = (budget / row / TILE as usize).clamp(1, u32::MAX as usize / TILE as usize) as u32;
    tile_rows * TILE
}

/// A window of the image cut into bands: the rows traced (the window, and an apron of one pixel wherever
/// the image goes on when the lecture's postfilter reads the neighbours), in bands of whole tile rows from
/// the traced window's top. Band `i` can be traced anywhere (another thread, another process) and the
/// results finished in order by a [`RowStage`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Bands {
    /// The pixels wanted.
    pub(crate) window: Window,
    /// The pixels traced: `window` and its apron.
    pub(crate) traced: Window,
    /// Rows per band (the last may have fewer).
    pub(crate) rows: u32,
    postfilter: bool,
}

impl Bands {
    /// `window` of the scene's image in bands of about `rows` rows (rounded up to whole tile rows). Panics
    /// on an empty window or one reaching outside the image.
    pub(crate) fn new(scene: &Scene, window: Window, rows: u32) -> Self {
        let (width, height) = (scene.camera.width, scene.camera.height);
        assert!(window.x1 <= width && window.y1 <= height && window.x0 < window.x1 && window.y0 < window.y1);
        let postfilter = scene.render.postfilter == PostFilter::Lecture3x3;
        let traced = window.grown(u32::from(postfilter), width, height);
        Self { window, traced, rows: rows.div_ceil(TILE).max(1) * TILE, postfilter }
    }
    /// How many bands.
    pub(crate) fn count(&self) -> u32 {
        self.traced.height().div_ceil(self.rows)
    }
    /// The image rows band `i` traces.
    pub(crate) fn rows_of(&self, i: u32) -> Range<u32> {
        let y = self.traced.y0 + i * self.rows;
        y..(y + self.rows).min(self.traced.y1)
    }
    /// Tiles traced in all.
    pub(crate) fn tiles(&self) -> u64 {
        u64::from(self.traced.width().div_ceil(TILE)) * u64::from(self.traced.height().div_ceil(TILE))
    }
    /// Tiles band `i` traces.
    #[cfg(feature = "mpi")]
    pub(crate) fn tiles_of(&self, i: u32) -> u64 {
        let rows = self.rows_of(i);
        u64::from(self.traced.width().div_ceil(TILE)) * u64::from((rows.end - rows.start).div_ceil(TILE))
    }
    /// The stage that turns the bands, given in order, into the window's finished rows.
    pub(crate) fn stage(&self) -> RowStage {
        RowStage::new(self.window, self.traced, self.postfilter)
    }
}

/// Band `i` of `bands` traced in packets of `lanes` on `pool`: its pixels (the traced window's width,
/// row-major, before any postfilter) and what tracing them took; `tile_done` is called after each tile.
#[cfg(feature = "mpi")]
pub(crate) fn trace_band_lanes(
    scene: &Scene,
    lanes: usize,
    pool: &rayon::ThreadPool,
    bands: &Bands,
    i: u32,
    tile_done: &(dyn Fn() + Sync),
) -> (Vec<Rgb>, RayCounts, Work) {
    let each = EachTile(tile_done);
    let counter = TileCounter::new(&each, bands.tiles());
    let (columns, rows) = (bands.traced.x0..bands.traced.x1, bands.rows_of(i));
    let mut band = Vec::new();
    let (counts, work) =
        with_lanes!(lanes, F => trace_band::<F>(scene, pool, columns, rows, &counter, &mut band));
    (band, counts, work)
}

/// A [`Progress`] that only counts: a call per finished tile.
#[cfg(feature = "mpi")]
struct EachTile<'a>(&'a (dyn Fn() + Sync));

#[cfg(feature = "mpi")]
impl Progress for EachTile<'_> {
    fn start(&self, _: u64) {}
    fn tile_done(&self, _: u64, _: u64) {
        (self.0)();
    }
}

/// [`render_window`] at a packet width chosen at run time (1, 4, 8 or 16; panics on another).
pub(crate) fn render_window_lanes<E>(
    scene: &Scene,
    lanes: usize,
    pool: &rayon::ThreadPool,
    progress: &dyn Progress,
    window: Window,
    band: u32,
    emit: &mut dyn FnMut(&[Rgb]) -> Result<(), E>,
) -> Result<Traced, E> {
    with_lanes!(lanes, F => render_window::<F, E>(scene, pool, progress, window, band, emit))
}

/// Renders `window` of the scene's image band by band (about `band` rows each, whole tile rows), handing
/// its finished rows to `emit` in order, top to bottom, each call one or more whole rows of the window's
/// width; stops at the first error `emit` returns. The pixels are those of [`super::render`]'s image, bit
/// for bit, at every band height, window, width and thread count.
pub(crate) fn render_window<F: Lanes, E>(
    scene: &Scene,
    pool: &rayon::ThreadPool,
    progress: &dyn Progress,
    window: Window,
    band: u32,
    emit: &mut dyn FnMut(&[Rgb]) -> Result<(), E>,
) -> Result<Traced, E> {
    let start = Instant::now();
    let mut outside = 0.0;
    let bands = Bands::new(scene, window, band);
    let counter = TileCounter::new(progress, bands.tiles());
    let mut stage = bands.stage();
    let mut total = Traced::default();
    // One band's pixels, reused from band to band: a fresh band's pages would each fault on first touch.
    let mut band = Vec::new();
    for i in 0..bands.count() {
        let columns = bands.traced.x0..bands.traced.x1;
        let (counts, work) = trace_band::<F>(scene, pool, columns, bands.rows_of(i), &counter, &mut band);
        total.counts += counts;
        total.work += work;
        if let Some(out) = stage.push(std::mem::take(&mut band)) {
            let clock = Instant::now();
            emit(&out)?;
            outside += clock.elapsed().as_secs_f64();
            band = out;
        }
    }
    total.seconds = start.elapsed().as_secs_f64() - outside;
    Ok(total)
}

/// Traced rows to finished rows: as they are, or through the lecture's 3×3 postfilter, which needs each
/// row's neighbours above and below and so holds back the last row it has until the next arrives.
pub(crate) struct RowStage {
    window: Window,
    traced: Window,
    postfilter: bool,
    /// Traced rows `first..first + held.len() / width` not yet let go.
    held: Vec<Rgb>,
    first: u32,
    /// The next window row to finish.
    next: u32,
}

impl RowStage {
    fn new(window: Window, traced: Window, postfilter: bool) -> Self {
        Self { window, traced, postfilter, held: Vec::new(), first: traced.y0, next: window.y0 }
    }

    /// Takes the next traced rows (in order, the traced window's width each); gives the window rows now
    /// finished, if any.
    pub(crate) fn push(&mut self, rows: Vec<Rgb>) -> Option<Vec<Rgb>> {
        if !self.postfilter {
            return Some(rows);
        }
        let tw = self.traced.width() as usize;
        self.held.extend_from_slice(&rows);
        let end = self.first + (self.held.len() / tw) as u32;
        // A row is finished once the row below it is here, or when it is the last.
        let ready = if end == self.traced.y1 { self.window.y1 } else { (end - 1).min(self.window.y1) };
        if ready <= self.next {
            return None;
        }
        let (held, first, traced) = (&self.held, self.first, self.traced);
        let at = |x: i64, y: i64| {
            let inside = x >= i64::from(traced.x0)
                && x < i64::from(traced.x1)
                && y >= i64::from(traced.y0)
                && y < i64::from(end);
            inside.then(|| held[(y - i64::from(first)) as usize * tw + (x - i64::from(traced.x0)) as usize])
        };
        let mut out = Vec::with_capacity((ready - self.next) as usize * self.window.width() as usize);
        for y in self.next..ready {
            out.extend((self.window.x0..self.window.x1).map(|x| lecture_3x3_pixel(x.into(), y.into(), at)));
        }
        self.next = ready;
        // Keep the last finished row's successor's upper neighbour, and everything after it.
        let keep_from = ready.saturating_sub(1).max(self.first);
        self.held.drain(..(keep_from - self.first) as usize * tw);
        self.first = keep_from;
        Some(out)
    }
}
