//! Packet traversal: K rays walk the tree together. A child is entered when any live lane's slab test passes;
//! each stack entry keeps its lanes' entry distances (`inf` for lanes that missed it), so a popped subtree
//! is skipped for every lane that has already hit something nearer. Children are pushed in the node's
//! precomputed order for the octant of the packet's first live lane, so the nearest is popped first.
//!
//! Packets whose live lanes share one origin (camera rays) first test each node's children against the whole
//! packet at once ([`Frustum`]: four planes, one 4-wide pass) and run the K-lane slab test only on the
//! children it cannot rule out ([`Bvh::frustum_culling`]). On the contract fields most children a packet
//! visits are missed by all its lanes, and this rules out nearly all of those (counts: docs/perf-log/
//! 2026-11.md, "Where the time went (before)" and "Frustum culling"). In leaves the same planes
//! rule out single spheres before their K-lane test. The planes come with the packet when its maker knows
//! them (the camera's blocks, [`crate::camera::Camera::pyramid`]), else they are fitted to the lanes.

use wide::f32x4;

use super::node::{Node, N};
use super::slab::{slab_entry, slab_entry_ordered, SlabRay, Stack};
use super::work::{add_work, counting, Work};
use super::{Bvh, LeafQuery};
use crate::geometry::{HitPacket, Pyramid, Ray};
use crate::math::{Mask, Real, V3};
use crate::simd::{set_bits, Lanes};

/// A ray packet prepared for slab tests.
pub(super) struct SlabRays<F: Lanes> {
    slab: SlabRay<F>,
    /// The octant of the first live lane's direction, which orders the children.
    pub(super) octant: usize,
    /// Per axis, the side of the near plane ([`near_side`](super::slab::near_side)), when every live lane's
    /// is the same.
    near: Option<[usize; 3]>,
    /// The whole-packet pyramid, when asked for and the live lanes share an origin.
    pub(super) frustum: Option<Frustum>,
}

impl<F: Lanes> SlabRays<F> {
    /// `extent` bounds the boxes' coordinates when frustum culling is wanted; the query's own pyramid is
    /// used when it carries one, else one is fitted to the live lanes.
    #[inline(always)]
    pub(super) fn new<Q: LeafQuery<F>>(q: &Q, live: F::Mask, extent: Option<f32>) -> Self {
        let ray = q.ray();
        let slab = SlabRay::new(ray);
        let first = (F::move_mask(live).trailing_zeros() as usize).min(F::K - 1);
        let negative = |d: F| usize::from(d.lane(first) < 0.0);
        let octant = negative(ray.dir.x) | negative(ray.dir.y) << 1 | negative(ray.dir.z) << 2;
        let near = Self::shared_near_side(&slab.inv_dir, live);
        let frustum = extent.and_then(|extent| {
            let pyramid = q.pyramid().or_else(|| fit_pyramid(&ray.origin, &ray.dir, live))?;
            debug_assert!(encloses(&pyramid, ray, live), "{pyramid:?} misses a live ray");
            Some(Frustum::new(&pyramid, extent))
        });
        Self { slab, octant, near, frustum }
    }

    /// The near sides of the live lanes, if they agree on every axis.
    fn shared_near_side(inv: &V3<F>, live: F::Mask) -> Option<[usize; 3]> {
        let bits = F::move_mask(live);
        let side = |v: F| match F::move_mask(v.lt(F::splat_f32(0.0)) & live) {
            0 => Some(0),
            negative if negative == bits => Some(1),
            _ => None,
        };
        Some([side(inv.x)?, side(inv.y)?, side(inv.z)?])
    }

    /// Entry distance of each lane into child `c` of `n`, `inf` where the lane misses it or enters beyond
    /// `limit`.
    #[inline(always)]
    pub(super) fn enter(&self, n: &Node, c: usize, limit: F) -> F {
        let corner = |v: &[[f32; N]; 3]| [0, 1, 2].map(|a| F::splat_f32(v[a][c]));
        match self.near {
            Some(near) => {
                let plane = |side: [usize; 3]| [0, 1, 2].map(|a| F::splat_f32(n.bounds[side[a]][a][c]));
                slab_entry_ordered(plane(near), plane(near.map(|s| 1 - s)), &self.slab, limit)
            }
            None => slab_entry(corner(n.lo()), corner(n.hi()), &self.slab, limit),
        }
    }
}

/// One side of a [`Frustum`]: a plane through the shared origin that every live ray lies on the positive side
/// of, with the box corner that is farthest along its normal picked per axis.
#[derive(Clone, Copy)]
pub(super) struct Side {
    pub(super) normal: [f32; 3],
    /// Per axis, the box side (0 lower, 1 upper) farthest along the normal.
    far_side: [usize; 3],
    /// `normal · origin − tolerance`: a box whose farthest corner is below this is outside.
    pub(super) offset: f32,
}

impl Side {
    /// The four sides of `p` and the plane normal to its axis, with slack for the box and sphere tests' own
    /// rounding: the box test sums 3 products and the offset, all within |n|₁·reach, so 16ε of that is ample.
    pub(super) fn all(p: &Pyramid, extent: f32) -> [Side; 5] {
        let o = glam::Vec3::from(p.apex);
        let reach = Self::reach(p.apex, extent);
        let [a, b, c, d] = p.normals;
        [a, b, c, d, p.axis].map(|n| {
            let n = glam::Vec3::from(n);
            Side {
                normal: n.to_array(),
                far_side: n.to_array().map(|x| usize::from(x >= 0.0)),
                offset: n.dot(o) - Self::SLACK * n.abs().element_sum() * reach,
            }
        })
    }

    /// The offsets' slack per unit of `|n|₁·reach`.
    pub(super) const SLACK: f32 = 16.0 * f32::EPSILON;

    /// `|n|` is rounded up by this factor for the sphere test.
    pub(super) const NORM_UP: f32 = 1.0 + 4.0 * f32::EPSILON;

    /// The largest coordinate magnitude the tests meet: the boxes' `extent` or the apex's.
    pub(super) fn reach(apex: [f32; 3], extent: f32) -> f32 {
        extent.max(glam::Vec3::from(apex).abs().max_element())
    }

    /// `|n|` rounded up, for the sphere test.
    pub(super) fn norm(&self) -> f32 {
        glam::Vec3::from(self.normal).length() * Self::NORM_UP
    }
}

/// The packet as a pyramid: its live lanes share an origin, and four planes through it enclose every live
/// direction; a fifth, normal to the pyramid's axis, has them all in front. A box wholly outside one plane
/// is missed by every lane, so the node's K-lane slab tests run only on the children the pyramid may reach.
/// The planes are widened by margins that cover the rounding of their construction and of the box test, so
/// the test never rules out a box an exact ray enters.
#[derive(Clone, Copy)]
pub(crate) struct Frustum {
    pub(super) sides: [Side; 5],
    /// The four sides again, one per lane, for the sphere test: normal components, `|n|` rounded up, and
    /// the offsets. (A sphere behind the apex is in a box the fifth plane ruled out.)
    nx: f32x4,
    ny: f32x4,
    nz: f32x4,
    norm: f32x4,
    offset: f32x4,
}

impl Frustum {
    /// The box and sphere tests of `p` ([`Side::all`]).
    #[inline(always)]
    pub(crate) fn new(p: &Pyramid, extent: f32) -> Self {
        let sides = Side::all(p, extent);
        let [a, b, c, d, _] = &sides;
        let lanes = |f: &dyn Fn(&Side) -> f32| f32x4::from([a, b, c, d].map(f));
        Self {
            nx: lanes(&|s| s.normal[0]),
            ny: lanes(&|s| s.normal[1]),
            nz: lanes(&|s| s.normal[2]),
            norm: lanes(&Side::norm),
            offset: lanes(&|s| s.offset),
            sides,
        }
    }

    /// Whether some lane may meet the ball of radius `r` around `c` (a sphere of the leaf, `r` padded as
    /// its box was): false when the ball lies wholly outside a side. The ball is inside its padded box and
    /// its centre within `reach`, so the slack in the offsets covers this test's rounding as it does the
    /// box test's (the extra term `r·|n|` adds one rounding of a value below |n|₁·reach).
    #[inline(always)]
    pub(crate) fn may_meet(&self, c: V3<f32>, r: f32) -> bool {
        let s = self.nz.mul_add(
            f32x4::splat(c.z),
            self.ny
                .mul_add(f32x4::splat(c.y), self.nx.mul_add(f32x4::splat(c.x), self.norm * r - self.offset)),
        );
        f32x4::move_mask(Real::lt(s, f32x4::splat(0.0))) == 0
    }

    /// Whether some lane may enter the box `[lo, hi]`: false when it lies wholly outside a side (the one-box
    /// form of [`Frustum::maybe_entered`], for the particle tree's implicit boxes).
    #[inline(always)]
    pub(crate) fn may_enter(&self, lo: [f32; 3], hi: [f32; 3]) -> bool {
        self.sides.iter().all(|side| {
            let corner = |a: usize| if side.far_side[a] == 1 { hi[a] } else { lo[a] };
            let n = side.normal;
            // Unfused: the sides' slack covers the rounding of three products and three sums alike.
            corner(0) * n[0] + corner(1) * n[1] + corner(2) * n[2] - side.offset >= 0.0
        })
    }

    /// Bit `c` set for each child of `n` that some lane may enter.
    #[inline(always)]
    pub(super) fn maybe_entered(&self, n: &Node) -> u32 {
        let mut outside = 0;
        for side in &self.sides {
            // `& 1` lets the compiler drop the bounds check (far_side is 0 or 1).
            let plane = |a: usize| f32x4::from(n.bounds[side.far_side[a] & 1][a]);
            let w = |a: usize| f32x4::splat(side.normal[a]);
            let s = plane(2)
                .mul_add(w(2), plane(1).mul_add(w(1), plane(0).mul_add(w(0), f32x4::splat(-side.offset))));
            outside |= f32x4::move_mask(Real::lt(s, f32x4::splat(0.0)));
        }
        !outside
    }
}

/// A [`Pyramid`] around the live lanes of a packet, if they share an origin and lie within about 83° of a
/// common axis.
fn fit_pyramid<F: Lanes>(origin: &V3<F>, dir: &V3<F>, live: F::Mask) -> Option<Pyramid> {
    let bits = F::move_mask(live);
    if F::K == 1 || bits == 0 {
        return None;
    }
    let (first, last) = (bits.trailing_zeros() as usize, 31 - bits.leading_zeros() as usize);
    let o = [origin.x.lane(first), origin.y.lane(first), origin.z.lane(first)];
    let same = |v: F, o: f32| v.le(F::splat_f32(o)) & v.ge(F::splat_f32(o));
    if !(same(origin.x, o[0]) & same(origin.y, o[1]) & same(origin.z, o[2]) | !live).all() {
        return None;
    }
    // Axis: between the first and last live directions (opposite corners of a camera tile); u and v
    // complete an orthonormal basis. Any axis gives valid planes; a central one gives tight ones.
    let lane = |i: usize| glam::Vec3::new(dir.x.lane(i), dir.y.lane(i), dir.z.lane(i));
    let c = (lane(first) + lane(last)).try_normalize()?;
    let (u, v) = c.any_orthonormal_pair();
    let along =
        |b: glam::Vec3| dir.x * F::splat_f32(b.x) + dir.y * F::splat_f32(b.y) + dir.z * F::splat_f32(b.z);
    let (du, dv, dc) = (along(u), along(v), along(c));
    if !(dc.gt(F::splat_f32(0.0)) | !live).all() {
        return None;
    }
    let inv = F::splat_f32(1.0) / dc;
    let (ru, rv) = (du * inv, dv * inv);
    // The ratios are finite (dc > 0 on live lanes), so plain comparisons fold them.
    let fold = |r: F, fill: f32, pick: fn(f32, f32) -> f32| {
        F::select(live, r, F::splat_f32(fill)).to_array().as_ref().iter().copied().fold(fill, pick)
    };
    let lo = |r: F| fold(r, f32::INFINITY, |a, b| if b < a { b } else { a });
    let hi = |r: F| fold(r, f32::NEG_INFINITY, |a, b| if b > a { b } else { a });
    let (u0, u1, v0, v1) = (lo(ru), hi(ru), lo(rv), hi(rv));
    let r_max = u0.abs().max(u1.abs()).max(v0.abs()).max(v1.abs());
    // Wider than about 83° off the axis (or NaN): no frustum.
    if r_max.is_nan() || r_max > 8.0 {
        return None;
    }
    // |d|₁/dc ≤ √3·|d|/dc = √3·√(1 + ru² + rv²) for the (nearly) orthonormal basis; call it kappa. The
    // ratios err by at most about 4u·kappa·(1 + |r|), the rounded normals by 2u(1 + |r|) per unit of
    // |d|₁/dc: 64ε·kappa·(1 + r_max) covers both with room.
    let kappa = 2.0 * (1.0 + 1.5 * r_max);
    let margin = 64.0 * f32::EPSILON * kappa * (1.0 + r_max);
    let normals =
        [u - (u0 - margin) * c, (u1 + margin) * c - u, v - (v0 - margin) * c, (v1 + margin) * c - v];
    // Every live dc is above |d|/√129 (r_max ≤ 8), far above its rounding: c is a valid axis.
    Some(Pyramid { apex: o, normals: normals.map(|n| n.to_array()), axis: c.to_array() })
}

/// Whether every live lane starts at the apex and lies on the inner side of every plane, evaluated in f64
/// (exact products, so only a direction within 1e-16 of a plane could be misjudged).
fn encloses<F: Lanes>(p: &Pyramid, ray: &Ray<F>, live: F::Mask) -> bool {
    (0..F::K).filter(|&i| F::mask_lane(live, i)).all(|i| {
        let o = [ray.origin.x.lane(i), ray.origin.y.lane(i), ray.origin.z.lane(i)];
        let d = [ray.dir.x.lane(i), ray.dir.y.lane(i), ray.dir.z.lane(i)];
        let dot = |n: &[f32; 3]| (0..3).map(|a| f64::from(n[a]) * f64::from(d[a])).sum::<f64>();
        o == p.apex && p.normals.iter().all(|n| dot(n) >= 0.0) && dot(&p.axis) > 0.0
    })
}

/// A pending subtree: its reference and each lane's entry distance.
#[derive(Clone, Copy)]
struct Entry<F: Lanes> {
    child: u32,
    count: u8,
    near: F,
}

impl<F: Lanes> Entry<F> {
    /// The root node, entered by every lane (its box is not tested: its children's are).
    fn root() -> Self {
        Self { child: 0, count: 0, near: F::splat_f32(f32::NEG_INFINITY) }
    }
}

impl Bvh {
    /// Pushes the children of `n` (but the slots of `skip_slots`) that some lane enters within its `limit`, farthest
    /// first, so the nearest is popped next. Adds the box tests to `tests`.
    #[inline(always)]
    fn push_children<F: Lanes>(
        &self,
        n: &Node,
        rays: &SlabRays<F>,
        limit: F,
        stack: &mut Stack<Entry<F>>,
        tests: &mut usize,
        skip_slots: u32,
    ) {
        let maybe = match &rays.frustum {
            Some(frustum) => frustum.maybe_entered(n),
            None => u32::MAX,
        } & !skip_slots;
        for c in n.slots_far_to_near(rays.octant).filter(|c| maybe >> c & 1 == 1) {
            *tests += 1;
            let near = rays.enter(n, c, limit);
            let entered = near.lt(F::splat_f32(f32::INFINITY)).any();
            stack.push_if(Entry { child: n.child[c], count: n.count[c], near }, entered);
        }
    }

    /// Closest hits of the leaf items for the live lanes, merged into `best`, by packet traversal; subtrees
    /// entered by at most [`Bvh::single_ray_lanes`] live lanes are walked one ray at a time.
    pub(super) fn intersect_packet<F: Lanes, Q: LeafQuery<F>>(
        &self,
        q: &Q,
        live: F::Mask,
        best: &mut HitPacket<F>,
    ) {
        let rays = SlabRays::new(q, live, self.frustum_culling.then_some(self.extent));
        let mut stack = Stack::<Entry<F>>::new();
        let limit = |lanes: F::Mask, best: &HitPacket<F>| {
            F::select(lanes, best.t.min_of(q.t_max()), F::splat_f32(f32::NEG_INFINITY))
        };
        // Counted locally and reported once per packet: a shared counter per node costs measurably.
        // Live rays are summed only when counting (a mask count per node and leaf otherwise spent).
        let counting = counting();
        let (mut boxes, mut prims, mut box_lanes, mut prim_lanes) = (0, 0, 0, 0);
        stack.push(Entry::root());
        while let Some(e) = stack.pop() {
            // Lanes that entered this subtree no farther than their best hit so far.
            let lanes = e.near.le(best.t) & live;
            if !lanes.any() {
                continue;
            }
            if e.count > 0 {
                let first = e.child as usize;
                let items = first..first + usize::from(e.count);
                prims += usize::from(e.count);
                if counting {
                    prim_lanes += usize::from(e.count) * F::move_mask(lanes).count_ones() as usize;
                }
                match &rays.frustum {
                    Some(f) => q.intersect(
                        items.filter(|&i| q.ball(i).is_none_or(|(c, r)| f.may_meet(c, r + self.pad))),
                        lanes,
                        best,
                    ),
                    None => q.intersect(items, lanes, best),
                }
            } else if F::move_mask(lanes).count_ones() <= self.single_ray_lanes {
                self.intersect_subtree(e.child, q, &rays.slab, lanes, best);
            } else {
                let n = &self.nodes[e.child as usize];
                let before = boxes;
                self.push_children(n, &rays, limit(lanes, best), &mut stack, &mut boxes, 0);
                if counting {
                    box_lanes += (boxes - before) * F::move_mask(lanes).count_ones() as usize;
                }
            }
        }
        if counting {
            add_work(Work::lanes(prims, prim_lanes, boxes, box_lanes));
        }
    }

    /// Lanes of `live` blocked by a leaf item within their `t_max`, by packet traversal (subtrees entered by at
    /// most [`Bvh::single_ray_lanes`] unblocked lanes one ray at a time); stops as soon as every live lane is.
    /// A packet whose live lanes all leave one item of the tree starts at the node holding that item's leaf and
    /// climbs ([`Bvh::up`]); any other from the root.
    pub(super) fn occluded_packet<F: Lanes, Q: LeafQuery<F>>(
        &self,
        q: &Q,
        live: F::Mask,
        blocker: &mut u32,
    ) -> F::Mask {
        let rays = SlabRays::new(q, live, self.frustum_culling.then_some(self.extent));
        let mut stack = Stack::<Entry<F>>::new();
        let mut blocked = F::mask_from_bits(0);
        let limit = |lanes: F::Mask| F::select(lanes, q.t_max(), F::splat_f32(f32::NEG_INFINITY));
        // Live rays are summed only when counting (a mask count per node and leaf otherwise spent).
        let counting = counting();
        let (mut boxes, mut prims, mut box_lanes, mut prim_lanes) = (0, 0, 0, 0);
        // Where every live lane leaves the same item of the tree (an ambient-occlusion packet of one hit), the
        // walk starts at the node holding that item's leaf and then climbs to the root, walking each
        // ancestor's other children (the ancestors' own boxes untested): every node a walk from the root would
        // visit, each once, so the same answer; the blockers near the item come sooner.
        let up = self.up.as_ref().map(|(packet, _)| packet);
        let start = up.and_then(|up| Some(up.leaf_of(shared_departure(q, live)?)?.0));
        // The node whose subtree has been walked, once the stack is empty.
        let mut done = start.unwrap_or(0);
        stack.push(Entry { child: done as u32, ..Entry::root() });
        loop {
            while let Some(e) = stack.pop() {
                let lanes = e.near.lt(F::splat_f32(f32::INFINITY)) & live & !blocked;
                if !lanes.any() {
                    continue;
                }
                if e.count > 0 {
                    let first = e.child as usize;
                    prims += usize::from(e.count);
                    if counting {
                        prim_lanes += usize::from(e.count) * F::move_mask(lanes).count_ones() as usize;
                    }
                    blocked = blocked | q.occluded(first..first + usize::from(e.count), lanes, blocker);
                } else if F::move_mask(lanes).count_ones() <= self.single_ray_lanes {
                    blocked = blocked | self.occluded_subtree(e.child, q, &rays.slab, lanes, blocker);
                } else {
                    let n = &self.nodes[e.child as usize];
                    let before = boxes;
                    self.push_children(n, &rays, limit(lanes), &mut stack, &mut boxes, 0);
                    if counting {
                        box_lanes += (boxes - before) * F::move_mask(lanes).count_ones() as usize;
                    }
                    continue;
                }
                if (blocked | !live).all() {
                    break;
                }
            }
            let (Some(up), false) = (up, (blocked | !live).all() || done == 0) else { break };
            let (parent, slot) = up.parent_of(done);
            let lanes = live & !blocked;
            let before = boxes;
            self.push_children(&self.nodes[parent], &rays, limit(lanes), &mut stack, &mut boxes, 1 << slot);
            if counting {
                box_lanes += (boxes - before) * F::move_mask(lanes).count_ones() as usize;
            }
            done = parent;
        }
        if counting {
            add_work(Work::lanes(prims, prim_lanes, boxes, box_lanes));
        }
        blocked
    }
}

/// The item every live lane's ray leaves, if they all leave the same item of the tree.
#[inline(always)]
fn shared_departure<F: Lanes, Q: LeafQuery<F>>(q: &Q, live: F::Mask) -> Option<usize> {
    let mut lanes = set_bits(F::move_mask(live));
    let first = q.departure(lanes.next()?)?;
    lanes.all(|i| q.departure(i) == Some(first)).then_some(first)
}
