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
/// by the cell of their direction ([`direction_cell`]): origins, directions and the lane each came from,
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
            for i in set_bits(bits) {
                let v = [x.as_ref()[i], y.as_ref()[i], z.as_ref()[i]];
                let key = group[i] + u16::from(direction_cell(v));
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

/// Cells of [`direction_cell`]: an 8×8 grid.
const CELLS: usize = 64;

/// A unit direction's cell in an 8×8 grid over its octahedral map (the sphere folded onto the square
/// `|u| + |v| ≤ 1`, the lower half unfolded into the corners), numbered in Z-order so that neighbouring cells
/// mostly come together.
fn direction_cell(d: [f32; 3]) -> u8 {
    let l1 = d[0].abs() + d[1].abs() + d[2].abs();
    let (mut u, mut v) = (d[0] / l1, d[1] / l1);
    if d[2] < 0.0 {
        (u, v) = ((1.0 - v.abs()) * u.signum(), (1.0 - u.abs()) * v.signum());
    }
    let q = |x: f32| (((x + 1.0) * 4.0) as u32).min(7);
    let spread = |x: u32| (x & 1) | (x & 2) << 1 | (x & 4) << 2;
    (spread(q(u)) | spread(q(v)) << 1) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every direction gets a cell below 64; opposite directions and the six axes get six different cells.
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
        let mut seen = [false; CELLS];
        for _ in 0..100_000 {
            let d = V3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5).normalize().to_f32();
            seen[usize::from(direction_cell([d.x, d.y, d.z]))] = true;
        }
        assert!(seen.iter().filter(|&&s| s).count() >= 56, "cells hit: {:?}", seen);
    }
}
