//! The light buffer (Haines and Greenberg, "The Light Buffer", 1986): around each point light, a cube of
//! direction cells, each listing the spheres that a ray from the light in one of the cell's directions could
//! meet, nearest the light first. A shadow ray toward the light lies on such a ray, so it tests only its
//! cell's spheres, and only those nearer the light than its own origin, instead of walking the sphere tree.
//! Cells cover only windows of the cube's faces, around the directions that hold spheres, so the offsets stay
//! small enough to be cached.
//!
//! The answer is the tree's: the lists are conservative (each sphere's box is padded as the tree's are, grown
//! further by a bound on how far the f32 shadow ray strays from the exact segment between its origin and the
//! light, and each cell range widened past the rounding of the cell lookup), and each listed sphere is tested
//! by the kernel the tree's leaves use. So every sphere that kernel finds blocking a ray is in its cell's
//! list; `tests/library/light_buffers.rs` compares the two lane by lane at every width.

use super::{count_work, SphereQuery, Work};
use crate::bvh::LeafQuery;
use crate::kinds::sphere::Spheres;
use crate::math::{Mask, Vec3f, V3};
use crate::simd::{set_bits, Lanes};
use glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

/// Cells per sphere over a light's windows: fewer make long lists, more make the offsets fall out of the cache
/// (PERF.md, "Register", light buffers).
const CELLS_PER_SPHERE: f64 = 0.5;

/// A light gets no buffer when its lists would hold more than this many entries a sphere (beyond one a
/// cell): spheres that cover many cells (the large ones of a sphereflake seen from close by) make the
/// lists long and the memory large, and the tree serves such a light better.
const MAX_ENTRIES_PER_SPHERE: usize = 8;

/// At most this many cells along a window's side.
const MAX_SIDE: f64 = 4096.0;

/// A cell range is widened by this much in face coordinates (which run from −1 to 1): the lookup's f32
/// division is off by a few ulps of 1.
const FACE_SLACK: f64 = 1e-4;

/// Boxes grow by this fraction of the farthest box corner's distance from the light: a shadow ray's f32
/// direction strays from the exact segment by a few ulps of the segment's length.
const STRAY: f64 = 1e-5;

/// One face of the cube around the light, in the coordinates `(u, v) = (b / |a|, c / |a|)` of a direction
/// `(a, b, c)` (the face's axis first): the window of cells `u0 ≤ u`, `v0 ≤ v` that holds spheres.
#[derive(Clone, Copy, Debug, Default)]
struct Face {
    u0: f32,
    v0: f32,
    /// Cells per unit of `u` and `v`.
    inv: f32,
    columns: u32,
    rows: u32,
    /// The index of the window's first cell.
    base: u32,
}

/// One point light's buffer.
#[derive(Clone, Debug)]
pub(crate) struct LightBuffer {
    /// The light, in rendering space (f32, as shading aims at it).
    light: Vec3f,
    /// The six faces: +x, −x, +y, −y, +z, −z.
    faces: [Face; 6],
    /// `start[c]..start[c + 1]` are cell `c`'s entries; a window's cells row by row.
    start: Vec<u32>,
    /// Each cell's spheres (storage indices), nearest the light first.
    sphere: Vec<u32>,
    /// A lower bound on each entry's distance from the light.
    near: Vec<f32>,
}

/// The face axes: the face's own axis, then the axes of its column and its row.
const AXES: [[usize; 3]; 3] = [[0, 1, 2], [1, 2, 0], [2, 0, 1]];

impl LightBuffer {
    /// The buffer of the light at `light` over `spheres`, whose boxes are padded by `pad` as the tree's are;
    /// `None` when its lists would pass [`MAX_ENTRIES_PER_SPHERE`].
    pub(crate) fn new(light: Vec3f, spheres: &Spheres, pad: f32) -> Option<Self> {
        let at = DVec3::new(light.x as f64, light.y as f64, light.z as f64);
        let pad = pad as f64;
        let raw = |i: usize| {
            let c = DVec3::new(spheres.cx[i] as f64, spheres.cy[i] as f64, spheres.cz[i] as f64) - at;
            let r = DVec3::splat(spheres.r[i] as f64 + pad);
            (c - r, c + r)
        };
        let n = spheres.len();
        let span = (0..n)
            .into_par_iter()
            .map(|i| {
                let (lo, hi) = raw(i);
                lo.abs().max(hi.abs()).length()
            })
            .reduce(|| 0.0, f64::max);
        let grow = DVec3::splat(span * STRAY + pad);
        let grown = |i: usize| {
            let (lo, hi) = raw(i);
            (lo - grow, hi + grow)
        };
        let faces = windows(n, grown);
        let cells = faces.iter().map(|f| (f.columns * f.rows) as usize).sum::<usize>();
        // A light whose lists would be long gets no buffer: known from every 16th sphere before the work.
        let sample: usize = (0..n)
            .step_by(16)
            .map(|i| {
                let (lo, hi) = grown(i);
                let mut count = 0;
                for_cells(lo, hi, &faces, |_| count += 1);
                count
            })
            .sum();
        if sample * 16 > MAX_ENTRIES_PER_SPHERE * n + cells {
            return None;
        }
        let (start, sphere, near) = lists(n, &faces, cells, grown)?;
        Some(Self { light, faces, start, sphere, near })
    }

    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        (self.start.len() + self.sphere.len() + self.near.len()) * size_of::<u32>()
    }

    /// The cell of the direction from the light to `point`, or `None` outside every window.
    #[inline(always)]
    fn cell(&self, point: Vec3f) -> Option<usize> {
        let w = [point.x - self.light.x, point.y - self.light.y, point.z - self.light.z];
        let (ax, ay, az) = (w[0].abs(), w[1].abs(), w[2].abs());
        let axis = if ax >= ay && ax >= az {
            0
        } else if ay >= az {
            1
        } else {
            2
        };
        let [a, b, c] = AXES[axis].map(|k| w[k]);
        self.face_cell(2 * axis + usize::from(a < 0.0), b / a.abs(), c / a.abs())
    }

    /// [`LightBuffer::cell`] for each lane of `bits` of `points`, the divisions done for all lanes at once
    /// (the same operations on each lane's values, so the same cells).
    #[inline(always)]
    fn cells<F: Lanes>(&self, points: &V3<F>, bits: u32) -> [Option<usize>; 16] {
        let light = F::splat_v3(self.light);
        let w = V3::new(points.x - light.x, points.y - light.y, points.z - light.z);
        let (ax, ay, az) = (w.x.abs(), w.y.abs(), w.z.abs());
        let x_axis = ax.ge(ay) & ax.ge(az);
        let y_axis = !x_axis & ay.ge(az);
        let pick = |x: F, y: F, z: F| F::select(x_axis, x, F::select(y_axis, y, z));
        // The face's axis, then the axes of its column and its row ([`AXES`]).
        let (a, b, c) = (pick(w.x, w.y, w.z), pick(w.y, w.z, w.x), pick(w.z, w.x, w.y));
        let (u, v) = (b / a.abs(), c / a.abs());
        let mut out = [None; 16];
        for i in set_bits(bits) {
            let axis = match (F::mask_lane(x_axis, i), F::mask_lane(y_axis, i)) {
                (true, _) => 0,
                (false, true) => 1,
                _ => 2,
            };
            out[i] = self.face_cell(2 * axis + usize::from(a.lane(i) < 0.0), u.lane(i), v.lane(i));
        }
        out
    }

    /// The cell at face coordinates `(u, v)` of face `face`, or `None` outside its window.
    #[inline(always)]
    fn face_cell(&self, face: usize, u: f32, v: f32) -> Option<usize> {
        let f = &self.faces[face];
        // Negative and NaN (a point at the light) give 0 here, and are caught by the comparisons.
        let (column, row) = (((u - f.u0) * f.inv) as u32, ((v - f.v0) * f.inv) as u32);
        let inside = u >= f.u0 && v >= f.v0 && column < f.columns && row < f.rows;
        inside.then(|| (f.base + row * f.columns + column) as usize)
    }

    /// Cell `c`'s spheres, nearest the light first, with a lower bound on each one's distance from the light
    /// (empty outside every window). A ray reaching `reach` from the light may meet the prefix whose bounds
    /// are at most [`limit`]`(reach)`; the callers find that prefix's end as they test ([`LightBuffer::reachable`],
    /// or a chunk of bounds at a time), instead of a binary search whose compares and loads form one chain of
    /// dependent steps.
    #[inline(always)]
    fn listed(&self, c: Option<usize>) -> (&[u32], &[f32]) {
        let Some(c) = c else { return (&[], &[]) };
        let (first, end) = (self.start[c] as usize, self.start[c + 1] as usize);
        (&self.sphere[first..end], &self.near[first..end])
    }

    /// The spheres of cell `c` a ray reaching `reach` from the light may meet, one at a time (nearest the
    /// light first), stopping at the first bound past the reach.
    #[inline(always)]
    fn reachable(&self, c: Option<usize>, reach: f32) -> impl Iterator<Item = u32> + '_ {
        let (ids, near) = self.listed(c);
        let reach = limit(reach);
        ids.iter().zip(near).take_while(move |&(_, &n)| n <= reach).map(|(&s, _)| s)
    }

    /// The lanes of `live` blocked by a sphere: the query's rays must start at their hit points and end at
    /// this buffer's light (`t_max` the distance to it). `scalar` tests one sphere at a time (the scalar
    /// path); `blocker` is set to a sphere that blocked a lane.
    #[inline(always)]
    pub(crate) fn occluded<F: Lanes>(
        &self,
        q: &SphereQuery<'_, F>,
        live: F::Mask,
        scalar: bool,
        blocker: &mut u32,
    ) -> F::Mask {
        let bits = F::move_mask(live);
        if F::K == 1 {
            let cell = || self.cell(q.ray().origin.map(|v| v.lane(0)));
            return match bits != 0 && self.occluded_lane(q, 0, cell(), scalar, blocker) {
                true => live,
                false => F::mask_from_bits(0),
            };
        }
        let origin = q.ray().origin;
        let t_max = q.t_max();
        debug_assert!(F::K <= 16);
        let cells = self.cells(&origin, bits);
        let mut blocked = 0u32;
        let mut left = bits;
        while left != 0 {
            let c = cells[left.trailing_zeros() as usize];
            let group = set_bits(left).filter(|&i| cells[i] == c).fold(0u32, |m, i| m | 1 << i);
            left &= !group;
            if group.count_ones() <= crate::bvh::SINGLE_RAY_MAX_LANES {
                for i in set_bits(group) {
                    if self.occluded_lane(q, i, c, scalar, blocker) {
                        blocked |= 1 << i;
                    }
                }
                continue;
            }
            let reach = set_bits(group).map(|i| t_max.lane(i)).fold(0.0, f32::max);
            blocked |= self.occluded_group(q, c, reach, F::mask_from_bits(group), blocker);
        }
        F::mask_from_bits(blocked)
    }

    /// Whether lane `i`, in cell `c`, is blocked, tested alone: the cell's spheres across the lanes (one at a
    /// time for the scalar path).
    #[inline(always)]
    fn occluded_lane<F: Lanes>(
        &self,
        q: &SphereQuery<'_, F>,
        i: usize,
        c: Option<usize>,
        scalar: bool,
        blocker: &mut u32,
    ) -> bool {
        let one = q.lane(i);
        count_work(|| {
            let n = self.reachable(c, one.t_max()).count();
            Work::lanes(n, n, 0, 0)
        });
        match scalar {
            true => self
                .reachable(c, one.t_max())
                .any(|s| one.occluded(s as usize..s as usize + 1, true, blocker)),
            false => {
                let (ids, near) = self.listed(c);
                one.occluded_listed(ids, near, limit(one.t_max()), blocker)
            }
        }
    }

    /// The lanes of `group` blocked by one of cell `c`'s spheres that a ray reaching `reach` may meet, tested
    /// together.
    #[inline(always)]
    fn occluded_group<F: Lanes>(
        &self,
        q: &SphereQuery<'_, F>,
        c: Option<usize>,
        reach: f32,
        group: F::Mask,
        blocker: &mut u32,
    ) -> u32 {
        let lanes = F::move_mask(group).count_ones() as usize;
        count_work(|| {
            let n = self.reachable(c, reach).count();
            Work::lanes(n, n * lanes, 0, 0)
        });
        let mut blocked = F::mask_from_bits(0);
        for s in self.reachable(c, reach) {
            blocked = blocked | q.occluded(s as usize..s as usize + 1, group & !blocked, blocker);
            if (blocked | !group).all() {
                break;
            }
        }
        F::move_mask(blocked)
    }
}

/// The cells' lists over the `n` boxes `grown(i)` (relative to the light): each cell's start, its spheres
/// nearest the light first (ties by index), and a lower bound on each entry's distance from the light; `None`
/// past [`MAX_ENTRIES_PER_SPHERE`].
fn lists(
    n: usize,
    faces: &[Face; 6],
    cells: usize,
    grown: impl Fn(usize) -> (DVec3, DVec3) + Sync,
) -> Option<(Vec<u32>, Vec<u32>, Vec<f32>)> {
    // A lower bound on each sphere's distance from the light, rounded down so the f32 bound never exceeds
    // the exact distance.
    let near_of = |lo: DVec3, hi: DVec3| {
        let gap = lo.max(-hi).max(DVec3::ZERO).length();
        match gap as f32 {
            g if g as f64 > gap => g.next_down(),
            g => g,
        }
    };
    // Three parallel passes over the spheres' cell rectangles: count, place (in any order), then sort
    // each cell's entries nearest the light first (ties by index), which fixes the lists whatever the
    // threads did.
    let counts: Vec<AtomicU32> = (0..=cells).map(|_| AtomicU32::new(0)).collect();
    (0..n).into_par_iter().for_each(|i| {
        let (lo, hi) = grown(i);
        for_cells(lo, hi, faces, |c| {
            counts[c + 1].fetch_add(1, Ordering::Relaxed);
        });
    });
    let mut start: Vec<u32> = counts.into_iter().map(AtomicU32::into_inner).collect();
    for c in 0..cells {
        start[c + 1] += start[c];
    }
    let total = start[cells] as usize;
    if total > MAX_ENTRIES_PER_SPHERE * n + cells {
        return None;
    }
    let fill: Vec<AtomicU32> = start[..cells].iter().map(|&s| AtomicU32::new(s)).collect();
    let placed: Vec<AtomicU64> = (0..total).map(|_| AtomicU64::new(0)).collect();
    (0..n).into_par_iter().for_each(|i| {
        let (lo, hi) = grown(i);
        // Distances are not negative, so their bits order as they do; the index breaks ties.
        let key = u64::from(near_of(lo, hi).to_bits()) << 32 | i as u64;
        for_cells(lo, hi, faces, |c| {
            placed[fill[c].fetch_add(1, Ordering::Relaxed) as usize].store(key, Ordering::Relaxed);
        });
    });
    let mut keys: Vec<u64> = placed.into_iter().map(AtomicU64::into_inner).collect();
    let mut lists = Vec::with_capacity(cells);
    let mut rest = keys.as_mut_slice();
    for c in 0..cells {
        let (list, tail) = rest.split_at_mut((start[c + 1] - start[c]) as usize);
        lists.push(list);
        rest = tail;
    }
    lists.into_par_iter().with_min_len(256).for_each(|list| list.sort_unstable());
    let sphere = keys.iter().map(|&k| k as u32).collect();
    let near = keys.iter().map(|&k| f32::from_bits((k >> 32) as u32)).collect();
    Some((start, sphere, near))
}

/// The farthest distance from the light a shadow ray of length `t_max` reaches, with room for its rounding.
#[inline(always)]
fn limit(t_max: f32) -> f32 {
    t_max * (1.0 + STRAY as f32)
}

/// The range of `x / a` over `x` in `x_lo..x_hi` and `a` in `a_lo..a_hi` with `a > 0` (`a_hi > 0`), widened
/// by [`FACE_SLACK`] and cut to the face; `None` when that lies off the face.
fn span(x_lo: f64, x_hi: f64, a_lo: f64, a_hi: f64) -> Option<(f64, f64)> {
    let least = match (x_lo >= 0.0, a_lo > 0.0) {
        (true, _) => x_lo / a_hi,
        (false, true) => x_lo / a_lo,
        (false, false) => f64::NEG_INFINITY,
    };
    let most = match (x_hi <= 0.0, a_lo > 0.0) {
        (true, _) => x_hi / a_hi,
        (false, true) => x_hi / a_lo,
        (false, false) => f64::INFINITY,
    };
    let edge = 1.0 + FACE_SLACK;
    let (least, most) = ((least - FACE_SLACK).max(-edge), (most + FACE_SLACK).min(edge));
    (least <= most).then_some((least, most))
}

/// The face coordinates `((u_lo, u_hi), (v_lo, v_hi))` of the directions from the light (the origin) that
/// may meet the box `lo..hi` through face `face`, or `None`.
fn face_spans(lo: &[f64; 3], hi: &[f64; 3], face: usize) -> Option<((f64, f64), (f64, f64))> {
    let [a, b, c] = AXES[face / 2];
    // The box's coordinates along the face's axis, seen from its side.
    let (a_lo, a_hi) = match face % 2 {
        0 => (lo[a], hi[a]),
        _ => (-hi[a], -lo[a]),
    };
    if a_hi <= 0.0 {
        return None;
    }
    Some((span(lo[b], hi[b], a_lo, a_hi)?, span(lo[c], hi[c], a_lo, a_hi)?))
}

/// The faces' windows around the `n` boxes `bounds(i)`, with about [`CELLS_PER_SPHERE`] cells a box in
/// all, square cells of one size on every face.
fn windows(n: usize, bounds: impl Fn(usize) -> (DVec3, DVec3) + Sync) -> [Face; 6] {
    type Window = [(f64, f64, f64, f64); 6];
    let none: Window = [(f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY); 6];
    let join = |a: Window, b: Window| -> Window {
        std::array::from_fn(|f| {
            (a[f].0.min(b[f].0), a[f].1.max(b[f].1), a[f].2.min(b[f].2), a[f].3.max(b[f].3))
        })
    };
    let bounds = (0..n)
        .into_par_iter()
        .map(|i| {
            let (lo, hi) = bounds(i);
            let (lo, hi) = (lo.to_array(), hi.to_array());
            let mut w = none;
            for (face, w) in w.iter_mut().enumerate() {
                if let Some(((u_lo, u_hi), (v_lo, v_hi))) = face_spans(&lo, &hi, face) {
                    *w = (u_lo, u_hi, v_lo, v_hi);
                }
            }
            w
        })
        .reduce(|| none, join);
    let area: f64 = bounds.iter().filter(|w| w.0 <= w.1).map(|w| (w.1 - w.0) * (w.3 - w.2)).sum();
    let target = (n as f64 * CELLS_PER_SPHERE).max(1.0);
    let inv = (target / area.max(f64::MIN_POSITIVE)).sqrt();
    let mut base = 0;
    bounds.map(|w| {
        if w.0 > w.1 {
            return Face { base, ..Face::default() };
        }
        let side = |extent: f64| ((extent * inv).ceil().clamp(1.0, MAX_SIDE)) as u32;
        let (columns, rows) = (side(w.1 - w.0), side(w.3 - w.2));
        // The cell size the sides allow, rounded to f32 once: the lookup and `for_cells` use the same value.
        let inv = (columns as f64 / (w.1 - w.0)).min(rows as f64 / (w.3 - w.2)) as f32;
        let face = Face { u0: w.0 as f32, v0: w.2 as f32, inv, columns, rows, base };
        base += columns * rows;
        face
    })
}

/// Calls `f` with every cell a ray from the light (the origin) may meet the box `lo..hi` in.
fn for_cells(lo: DVec3, hi: DVec3, faces: &[Face; 6], mut f: impl FnMut(usize)) {
    let (lo, hi) = (lo.to_array(), hi.to_array());
    for (face, w) in faces.iter().enumerate() {
        if w.columns == 0 {
            continue;
        }
        let Some(((u_lo, u_hi), (v_lo, v_hi))) = face_spans(&lo, &hi, face) else { continue };
        let cell =
            |x: f64, x0: f32, n: u32| (((x - x0 as f64) * w.inv as f64).floor().max(0.0) as u32).min(n - 1);
        let (c0, c1) = (cell(u_lo, w.u0, w.columns), cell(u_hi, w.u0, w.columns));
        let (r0, r1) = (cell(v_lo, w.v0, w.rows), cell(v_hi, w.v0, w.rows));
        for row in r0..=r1 {
            for column in c0..=c1 {
                f((w.base + row * w.columns + column) as usize);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::SplitMix64;
    use wide::{f32x16, f32x4, f32x8};

    /// A packet's cells ([`LightBuffer::cells`], the divisions in lanes) are the single-ray lookup's, lane
    /// by lane: for points anywhere around a light (inside and outside its windows), on the cube's edges and
    /// diagonals where faces meet, on the axes, and at the light itself.
    #[test]
    fn packet_cells_are_the_single_ray_cells() {
        let mut rng = SplitMix64::new(11);
        let mut unit = move || rng.unit() as f32 * 2.0 - 1.0;
        let mut spheres = Spheres::default();
        for _ in 0..400 {
            spheres.push(V3::new(unit() * 3.0, unit() * 3.0, unit()), 0.05 + 0.1 * unit().abs(), 0);
        }
        let light = V3::new(0.25, -0.5, 4.0);
        let buffer = LightBuffer::new(light, &spheres, 1e-4).expect("a buffer");
        let mut points: Vec<Vec3f> =
            (0..4000).map(|_| V3::new(unit() * 6.0, unit() * 6.0, unit() * 6.0)).collect();
        for k in 0..64 {
            let d = [unit(), unit(), unit()];
            let s = if k % 2 == 0 { 1.0 } else { -1.0 };
            // Ties between axes (edges, diagonals), points on an axis, and the light itself.
            points.push(light + V3::new(d[0], d[0] * s, d[1]));
            points.push(light + V3::new(d[0], d[0], d[0] * s));
            points.push(light + V3::new(0.0, 0.0, d[2]));
            points.push(light + V3::new(d[2], 0.0, 0.0));
        }
        points.push(light);
        assert!(
            points.iter().any(|&p| buffer.cell(p).is_some())
                && points.iter().any(|&p| buffer.cell(p).is_none())
        );
        same_cells::<f32x4>(&buffer, &points);
        same_cells::<f32x8>(&buffer, &points);
        same_cells::<f32x16>(&buffer, &points);
    }

    fn same_cells<F: Lanes>(buffer: &LightBuffer, points: &[Vec3f]) {
        for (n, chunk) in points.chunks(F::K).enumerate() {
            let at = |i: usize| chunk[i.min(chunk.len() - 1)];
            let lanes = V3::new(F::from_fn(|i| at(i).x), F::from_fn(|i| at(i).y), F::from_fn(|i| at(i).z));
            // Every other packet leaves its odd lanes out.
            let bits = ((1u32 << chunk.len()) - 1) & if n % 2 == 0 { u32::MAX } else { 0x5555_5555 };
            let cells = buffer.cells(&lanes, bits);
            for (i, &cell) in cells.iter().enumerate().take(F::K) {
                let want = if bits >> i & 1 == 1 { buffer.cell(at(i)) } else { None };
                assert_eq!(cell, want, "K = {}, point {:?}", F::K, at(i));
            }
        }
    }
}
