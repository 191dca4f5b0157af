//! Ambient occlusion with fewer samples than K, or with hits close together: every sample of every found
//! lane of a camera packet, regrouped by direction, then traced K at a time. The rays come from
//! neighbouring hit points; sorted by the primitive they leave, then by the cell of their direction, each
//! packet holds rays running nearly parallel from nearby origins, which walk the tree together, where one
//! sample of each of K pixels (random directions) split at once; a packet whose rays all leave one sphere
//! starts its walk at that sphere's leaf. Each ray is the one [`super::ao`]'s lattice gives its pixel and
//! sample, and each ray's answer is exact, so the counts are the same bits in any grouping (PERF.md,
//! Register).

use crate::accel::{traced, RayKind};
use crate::geometry::{DeparturePacket, HitPacket, RayPacket};
use crate::math::V3;
use crate::scene::desc::Ao;
use crate::simd::{set_bits, IdLanes, Lanes};

use super::ao::{around, local_directions, rotation};
use super::{Surface, Tracer};

impl<F: Lanes> Tracer<'_, F> {
    /// How many of each found lane's `ao.samples` occlusion rays nothing blocks: all of the packet's rays
    /// regrouped by direction ([`AoStream`]).
    pub(super) fn open_by_direction(
        &mut self,
        rays: &RayPacket<F>,
        hit: &HitPacket<F>,
        s: &Surface<F>,
        found: F::Mask,
        ao: Ao,
        distance: F,
    ) -> F {
        let bits = F::move_mask(found);
        let mut shift = [(0.0, 0.0); 16];
        for i in set_bits(bits) {
            shift[i] = rotation(rays.ray.dir.x.lane(i), rays.ray.dir.y.lane(i), rays.ray.dir.z.lane(i));
        }
        let mut stream = std::mem::take(&mut self.ao_stream);
        let prims = std::array::from_fn(|i| if i < F::K { hit.prim.lane(i) } else { 0 });
        stream.fill::<F>(s, bits, &prims, &shift, ao);
        self.counts.ao += stream.len as u64;
        let inside = F::move_mask(s.inside);
        let mut open = [0u32; 16];
        let load = |v: &[f32], at: usize| F::load(v, at);
        for at in (0..stream.len).step_by(F::K) {
            let [ox, oy, oz] = &stream.origin;
            let [dx, dy, dz] = &stream.dir;
            let origin = V3::new(load(ox, at), load(oy, at), load(oz, at));
            let dir = V3::new(load(dx, at), load(dy, at), load(dz, at));
            let live = F::lanes_below(stream.len - at);
            let probe = RayPacket::new(origin, dir, distance, live);
            let lanes = &stream.lane[at..at + F::K];
            let inward = lanes.iter().enumerate().fold(0u32, |b, (j, &i)| b | (inside >> i & 1) << j);
            let from = DeparturePacket {
                prim: F::Ids::from_fn(|j| hit.prim.lane(usize::from(lanes[j]))),
                inward: F::mask_from_bits(inward),
            };
            let (geometry, hint) = (&self.scene.geometry, &mut self.ao_hint);
            let blocked = traced(RayKind::Ao, || geometry.occluded_hinted_k(&probe, &from, hint));
            for j in set_bits(F::move_mask(live & !blocked)) {
                open[usize::from(lanes[j])] += 1;
            }
        }
        self.ao_stream = stream;
        F::from_fn(|i| open[i] as f32)
    }
}

/// A packet's ambient occlusion rays in structure-of-arrays form, ordered by the primitive they leave, then
/// by the cell of their direction ([`direction_cells`]): origins, directions and the lane each came from,
/// padded to whole packets (the padding's lanes are never live). Kept by the tracer and reused from packet to
/// packet.
#[derive(Default)]
pub(crate) struct AoStream {
    origin: [Vec<f32>; 3],
    dir: [Vec<f32>; 3],
    lane: Vec<u8>,
    /// Rays before the padding.
    len: usize,
    /// Each ray before sorting: its key, its lane and its direction.
    unsorted: Vec<(u16, u8, [f32; 3])>,
    /// Rays per key, then (after the prefix sums) where the next ray of each key goes.
    count: Vec<u32>,
}

impl AoStream {
    /// Every sample of every lane of `bits` (their directions computed as by-pixel packets compute them,
    /// sample by sample in lanes), sorted by a counting sort by the primitive they leave (`prims`, per lane),
    /// then by cell: packets then leave one primitive wherever a primitive's rays fill them (K or more
    /// samples over the lanes that leave it).
    fn fill<F: Lanes>(
        &mut self,
        s: &Surface<F>,
        bits: u32,
        prims: &[u32; 16],
        shift: &[(f64, f64); 16],
        ao: Ao,
    ) {
        self.unsorted.clear();
        let (group, groups) = groups(bits, prims);
        let count = &mut self.count;
        count.clear();
        count.resize(groups * CELLS, 0);
        for k in 0..ao.samples {
            let local = local_directions::<F>(set_bits(bits).map(|i| (i, shift[i], k)), ao.samples);
            let d = around(s.normal, local);
            let (x, y, z) = (d.x.to_array(), d.y.to_array(), d.z.to_array());
            let cells = direction_cells([x.as_ref(), y.as_ref(), z.as_ref()]);
            for i in set_bits(bits) {
                let v = [x.as_ref()[i], y.as_ref()[i], z.as_ref()[i]];
                let key = group[i] + u16::from(cells[i]);
                count[usize::from(key)] += 1;
                self.unsorted.push((key, i as u8, v));
            }
        }
        let mut sum = 0;
        for c in count.iter_mut() {
            (*c, sum) = (sum, sum + *c);
        }
        let next = count;
        self.len = self.unsorted.len();
        let padded = self.len.div_ceil(F::K) * F::K;
        let lanes = |v: &F| {
            let a = v.to_array();
            std::array::from_fn::<f32, 16, _>(|i| a.as_ref().get(i).copied().unwrap_or(0.0))
        };
        let point = [lanes(&s.point.x), lanes(&s.point.y), lanes(&s.point.z)];
        for v in self.origin.iter_mut().chain(self.dir.iter_mut()) {
            v.clear();
            v.resize(padded, 0.0);
        }
        self.lane.clear();
        self.lane.resize(padded, self.unsorted.first().map_or(0, |r| r.1));
        for &(key, i, v) in &self.unsorted {
            let at = next[usize::from(key)] as usize;
            next[usize::from(key)] += 1;
            for a in 0..3 {
                self.origin[a][at] = point[a][usize::from(i)];
                self.dir[a][at] = v[a];
            }
            self.lane[at] = i;
        }
    }
}

/// Each lane of `bits` numbered by the primitive it leaves (`prims`), in the order the lanes first name them,
/// times [`CELLS`]: the first part of its rays' sort keys; and the number of primitives.
fn groups(bits: u32, prims: &[u32; 16]) -> ([u16; 16], usize) {
    let (mut group, mut distinct, mut groups) = ([0u16; 16], [0u32; 16], 0);
    for i in set_bits(bits) {
        let g = distinct[..groups].iter().position(|&p| p == prims[i]).unwrap_or_else(|| {
            distinct[groups] = prims[i];
            groups += 1;
            groups - 1
        });
        group[i] = (g * CELLS) as u16;
    }
    (group, groups)
}

/// Cells of [`direction_cells`]: an 8×8 grid.
const CELLS: usize = 64;

/// Each lane's unit direction's cell in an 8×8 grid over its octahedral map (the sphere folded onto the
/// square `|u| + |v| ≤ 1`, the lower half unfolded into the corners), numbered in Z-order so that
/// neighbouring cells mostly come together; below [`CELLS`] for any input, NaN included. Lane arithmetic
/// over all K lanes at once (the compiler vectorises the loops): a cell is only a sort key, so it need not
/// match any other computation's bits.
fn direction_cells(d: [&[f32]; 3]) -> [u8; 16] {
    let ([x, y, z], k) = (d, d[0].len().min(16));
    let (mut u, mut v) = ([0.0f32; 16], [0.0f32; 16]);
    for i in 0..k {
        let l1 = x[i].abs() + y[i].abs() + z[i].abs();
        let (a, b) = (x[i] / l1, y[i] / l1);
        let lower = z[i] < 0.0;
        u[i] = if lower { (1.0 - b.abs()).copysign(a) } else { a };
        v[i] = if lower { (1.0 - a.abs()).copysign(b) } else { b };
    }
    let mut cells = [0u8; 16];
    for ((cell, &u), &v) in cells.iter_mut().zip(&u).zip(&v).take(k) {
        *cell = (spread(eighth(u)) | spread(eighth(v)) << 1) as u8;
    }
    cells
}

/// `⌊(x + 1)·4⌋` for x in [−1, 1], clamped to 0..=7 (up to rounding at the eighths' edges), without a
/// float-to-integer conversion: `x/2 + 3/2`, clamped below 2, lies in [1, 2), whose three leading mantissa
/// bits are that eighth. Any input gives a value below 8.
#[inline(always)]
fn eighth(x: f32) -> u32 {
    let t = (x * 0.5 + 1.5).clamp(1.0, 1.999_999_9);
    t.to_bits() >> 20 & 7
}

/// The three bits of `q` spread to bits 0, 2 and 4 (Z-order's interleaving).
#[inline(always)]
fn spread(q: u32) -> u32 {
    (q & 1) | (q & 2) << 1 | (q & 4) << 2
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One direction's cell.
    fn direction_cell(d: [f32; 3]) -> u8 {
        direction_cells([&d[0..1], &d[1..2], &d[2..3]])[0]
    }

    /// The octahedral map's cell by the textbook steps in f64: `⌊(u + 1)·4⌋` clamped to 7, Z-order.
    fn reference_cell(d: [f64; 3], near_edge: &mut bool) -> u8 {
        let l1 = d[0].abs() + d[1].abs() + d[2].abs();
        let (mut u, mut v) = (d[0] / l1, d[1] / l1);
        if d[2] < 0.0 {
            (u, v) = ((1.0 - v.abs()) * u.signum(), (1.0 - u.abs()) * v.signum());
        }
        let mut q = |x: f64| {
            let e = (x + 1.0) * 4.0;
            *near_edge |= (e - e.round()).abs() < 1e-4;
            (e.floor() as u32).min(7)
        };
        (spread(q(u)) | spread(q(v)) << 1) as u8
    }

    /// Every direction gets a cell below 64; opposite directions and the six axes get six different cells;
    /// away from the cells' edges the lanes give the textbook map's cell.
    #[test]
    fn cells_cover_the_sphere() {
        let axes = [
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ];
        let cells: std::collections::BTreeSet<u8> = axes.iter().map(|&d| direction_cell(d)).collect();
        assert_eq!(cells.len(), 6, "{cells:?}");
        let mut rng = crate::math::SplitMix64::new(3);
        let (mut seen, mut compared) = ([false; CELLS], 0);
        for _ in 0..100_000 {
            let d = V3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5).normalize().to_f32();
            let cell = direction_cell([d.x, d.y, d.z]);
            seen[usize::from(cell)] = true;
            let mut near_edge = false;
            let reference = reference_cell([d.x, d.y, d.z].map(f64::from), &mut near_edge);
            if !near_edge {
                assert_eq!(cell, reference, "{d:?}");
                compared += 1;
            }
        }
        assert!(compared > 99_000, "{compared}");
        assert!(seen.iter().filter(|&&s| s).count() >= 56, "cells hit: {:?}", seen);
    }

    /// Sixteen lanes at once give each lane's own cell, and NaN, zero and infinite directions a cell below 64
    /// without a panic (a range check on odd input; the map itself is checked above).
    #[test]
    fn lanes_are_independent_and_any_input_has_a_cell() {
        let odd = [f32::NAN, 0.0, -0.0, f32::INFINITY, f32::NEG_INFINITY, 1e-40, -1.0, 1.0];
        let mut rng = crate::math::SplitMix64::new(4);
        for _ in 0..1000 {
            let mut pick = || match rng.next_u64() % 3 {
                0 => odd[(rng.next_u64() % 8) as usize],
                _ => rng.unit() as f32 * 2.0 - 1.0,
            };
            let d: [[f32; 16]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| pick()));
            let cells = direction_cells([&d[0], &d[1], &d[2]]);
            for i in 0..16 {
                assert!(usize::from(cells[i]) < CELLS);
                assert_eq!(cells[i], direction_cell([d[0][i], d[1][i], d[2][i]]));
            }
        }
    }
}
