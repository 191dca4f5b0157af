//! Large packets through the particle tree: up to [`MAX_PACKETS`] packets of K camera rays that share an
//! origin, each with its pyramid, walk the tree once together, as they walk the BVH
//! ([`crate::bvh::Bvh::intersect_large`]). The walk looks at the members' frusta, never at their
//! lanes:
//!
//! - a range's box (its ancestors' split planes widened, as in the packet walk) is first tested against the
//!   tile's frustum, then against every member's frustum at once (one member per lane of a 16-wide test); a
//!   range inherits the members that may reach its parent;
//! - a member whose every live lane has a hit nearer than a box's distance from the shared origin is done
//!   with that box;
//! - each visited sphere (a node's, or a leaf's) is tested against the members' frusta at once, then by the
//!   K-lane kernel of each member that may meet it: the kernel and (t, id) merge of the packet walk, so every
//!   lane gets the bits [`Particles::intersect_k`] gives it.
//!
//! The range on the origin's side of a split plane is walked first.

use wide::f32x16;

use super::walk::Query;
use super::{place, with_records, Particles, Record, Records, LEAF};
use crate::accel::{add_work, counting, Work};
use crate::bvh::{farthest, members, Frustum, MemberSides, Stack, MAX_PACKETS};
use crate::geometry::{DeparturePacket, HitPacket, Pyramid, RayPacket};
use crate::math::{Mask, Real, Vec3f};
use crate::simd::{set_bits, IdLanes, Lanes};

/// A range waiting on the stack: positions `lo..hi`, its box, the members (bit p for member p) that may
/// reach it, and a lower bound on its distance from the shared origin.
#[derive(Clone, Copy)]
struct Pending {
    lo: u32,
    hi: u32,
    min: [f32; 3],
    max: [f32; 3],
    members: u16,
    near: f32,
}

/// A lower bound on the distance from `origin` to the box `min..max`, shrunk past its own rounding (the
/// BVH's large walk's bound).
#[inline(always)]
fn box_distance(min: [f32; 3], max: [f32; 3], origin: [f32; 3]) -> f32 {
    let mut d2 = 0.0f32;
    for a in 0..3 {
        let gap = (min[a] - origin[a]).max(origin[a] - max[a]).max(0.0);
        d2 = gap.mul_add(gap, d2);
    }
    d2.sqrt() * (1.0 - 16.0 * f32::EPSILON)
}

/// One large packet's walk over records `R`.
struct Walk<'a, F: Lanes, R> {
    tree: &'a Particles,
    recs: &'a [R],
    packets: &'a [RayPacket<F>],
    /// Each member's query, made when it first meets a sphere.
    made: [Option<Query<'a, F, R>>; MAX_PACKETS],
    live: [F::Mask; MAX_PACKETS],
    sides: MemberSides,
    tile: Frustum,
    origin: [f32; 3],
    base: u32,
    /// Per member, the farthest best hit of its live lanes (inf while one has none): it looks no farther.
    far: f32x16,
}

impl<'a, F: Lanes, R: Record> Walk<'a, F, R> {
    /// The pending range `lo..hi` with box `min..max`, if some of `members` may reach it.
    #[inline(always)]
    fn pending(&self, lo: u32, hi: u32, min: [f32; 3], max: [f32; 3], members: u32) -> Option<Pending> {
        if lo >= hi || !self.tile.may_enter(min, max) {
            return None;
        }
        let near = box_distance(min, max, self.origin);
        let planes = [0, 1, 2].map(|a| (min[a], max[a]));
        let reach = self.sides.reaching_corners(planes, self.far, near) & members;
        (reach != 0).then_some(Pending { lo, hi, min, max, members: reach as u16, near })
    }

    /// The sphere at position `i` (centre `c`, radius `r` in rendering space) for each of `members` whose
    /// frustum may meet it, merged into their best hits. Returns the member–sphere tests made and the live
    /// rays they served.
    #[inline(always)]
    fn test(
        &mut self,
        i: usize,
        c: Vec3f,
        r: f32,
        members: u32,
        best: &mut [HitPacket<F>],
    ) -> (usize, usize) {
        let reach = self.sides.reaching_ball(c, r + self.tree.pad) & members;
        let mut far = None;
        for p in set_bits(reach) {
            let (tree, recs, packets, base) = (self.tree, self.recs, self.packets, self.base);
            let q = self.made[p]
                .get_or_insert_with(|| Query::new(tree, recs, &packets[p], &DeparturePacket::camera(), base));
            if let Some((hit, t)) = q.placed_sphere(i, c, r, self.live[p]) {
                if hit.any() {
                    let id = F::Ids::splat(base + i as u32);
                    best[p].update(hit, t, id, F::Ids::splat(tree.key(i)));
                    let f = far.get_or_insert_with(|| self.far.to_array());
                    f[p] = farthest(F::select(self.live[p], best[p].t, F::splat_f32(f32::NEG_INFINITY)));
                }
            }
        }
        if let Some(f) = far {
            self.far = f32x16::from(f);
        }
        (reach.count_ones() as usize, self.rays_of(reach))
    }

    /// The live rays of `members`.
    fn rays_of(&self, members: u32) -> usize {
        set_bits(members).map(|p| F::move_mask(self.live[p]).count_ones() as usize).sum()
    }

    fn run(&mut self, alive: u32, best: &mut [HitPacket<F>]) {
        let mut stack = Stack::<Pending>::new();
        let [min, max] = self.tree.bounds;
        // Live rays a split serves, summed only when counting (a loop over the members per split).
        let counting = counting();
        let (mut spheres, mut boxes, mut sphere_lanes) = (0, 1, 0);
        let mut box_lanes = if counting { self.rays_of(alive) } else { 0 };
        if let Some(root) = self.pending(0, self.recs.len() as u32, min, max, alive) {
            stack.push(root);
        }
        while let Some(e) = stack.pop() {
            let members = u32::from(e.members) & !f32x16::move_mask(self.far.lt(f32x16::splat(e.near)));
            if members == 0 {
                continue;
            }
            let (lo, hi) = (e.lo as usize, e.hi as usize);
            if hi - lo <= LEAF {
                for i in lo..hi {
                    let (c, r) = place(&self.recs[i], self.tree.origin);
                    let (tests, lanes) = self.test(i, c, r, members, best);
                    spheres += tests;
                    sphere_lanes += lanes;
                }
                continue;
            }
            let mid = lo + (hi - lo) / 2;
            let (c, r) = place(&self.recs[mid], self.tree.origin);
            let (tests, lanes) = self.test(mid, c, r, members, best);
            spheres += tests;
            sphere_lanes += lanes;
            let axis = self.tree.axis(mid);
            let plane = [c.x, c.y, c.z][axis];
            let reach = self.tree.split_reach();
            let (mut below_max, mut above_min) = (e.max, e.min);
            below_max[axis] = below_max[axis].min(plane + reach);
            above_min[axis] = above_min[axis].max(plane - reach);
            boxes += 2;
            if counting {
                box_lanes += 2 * self.rays_of(members);
            }
            let below = self.pending(e.lo, mid as u32, e.min, below_max, members);
            let above = self.pending(mid as u32 + 1, e.hi, above_min, e.max, members);
            let (near, far) = if self.origin[axis] < plane { (below, above) } else { (above, below) };
            for p in [far, near].into_iter().flatten() {
                stack.push(p);
            }
        }
        if counting {
            add_work(Work::lanes(spheres, sphere_lanes, boxes, box_lanes));
        }
    }
}

impl Particles {
    /// Closest hits of the tree's spheres (ids from `base`) for a tile of camera packets that share an origin,
    /// each with its pyramid (`packets[p]`, merged into `best[p]`), walking the tree once for all of them;
    /// `pyramid` encloses every active ray of the tile. The directions must be unit length (camera rays are).
    /// Each lane gets the bits [`Particles::intersect_k`] gives it.
    pub(crate) fn intersect_large<F: Lanes>(
        &self,
        packets: &[RayPacket<F>],
        pyramid: &Pyramid,
        base: u32,
        best: &mut [HitPacket<F>],
    ) {
        let (live, alive) = members(packets, best.len());
        if alive == 0 || self.is_empty() {
            return;
        }
        let extent = self.extent();
        with_records!(&self.records, |recs| Walk {
            tree: self,
            recs,
            packets,
            made: std::array::from_fn(|_| None),
            live,
            sides: MemberSides::new(packets, pyramid.apex, extent),
            tile: Frustum::new(pyramid, extent),
            origin: pyramid.apex,
            base,
            far: f32x16::splat(f32::INFINITY),
        }
        .run(alive, best))
    }
}
