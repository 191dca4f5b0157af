//! Large packets: up to [`MAX_PACKETS`] packets of K rays that share an origin (a tile of camera rays), each
//! with its pyramid, walk the tree together. The walk is over the members' frusta, never their lanes:
//!
//! - the tile's [`Frustum`] rules out the children no ray of the tile can enter (one 4-wide pass);
//! - each member's frustum, tested for all members at once (one member per lane of a 16-wide test), says
//!   which members may reach a child; a child inherits its parent's members, so a subtree never looks at a
//!   member that missed an ancestor;
//! - a member whose every live lane has a hit nearer than a box's distance from the shared origin is done
//!   with that box (a lower bound on the distance, shrunk past its rounding).
//!
//! Leaves test each sphere against the members' frusta at once, then run each member's K-lane sphere
//! kernel on the spheres its frustum may meet — the kernel and the (t, id) merge of the K-ray walk, so every
//! lane gets the bits [`Bvh::intersect_k`] gives it (culling is conservative, and merging is independent
//! of the order of visits).

use wide::{f32x16, f32x4};

use super::node::Node;
use super::packet::{Frustum, Side};
use super::slab::Stack;
use super::work::{add_work, counting, Work};
use super::{Bvh, LeafQuery};
use crate::geometry::{HitPacket, Pyramid, RayPacket};
use crate::math::{Mask, Real, Vec3f};
use crate::simd::{set_bits, Lanes};

/// The most packets a large packet holds: a 16×16-pixel tile of 4×4-ray packets.
pub(crate) const MAX_PACKETS: usize = 16;

/// A child waiting on the stack: its node (`count` 0) or its leaf's `count` items from `child`, which the
/// members of `members` (bit p for member p) may reach, no nearer than `near` to the shared origin.
#[derive(Clone, Copy)]
struct Pending {
    child: u32,
    count: u8,
    members: u16,
    near: f32,
}

/// Every member's four frustum sides, one member per lane: which members may reach a box or a ball.
/// Members without a pyramid always may. Shared with the particle tree's large-packet walk.
pub(crate) struct MemberSides {
    /// Per side, the normals' components.
    normal: [[f32x16; 3]; 4],
    /// Per side, the normals' components where positive, else 0: with `below`, a box's corner farthest
    /// along a normal without a select (`n·corner = n⁺·hi + n⁻·lo` per axis, one term an exact zero).
    above: [[f32x16; 3]; 4],
    /// Per side, the normals' components where negative, else 0.
    below: [[f32x16; 3]; 4],
    /// Per side, `|n|` rounded up, for balls.
    norm: [f32x16; 4],
    /// Per side, the offsets (with [`Side::all`]'s slack); `-inf` for members without a pyramid.
    offset: [f32x16; 4],
}

impl MemberSides {
    /// The sides of `packets`' pyramids, which share the apex `apex`, by [`Side::all`]'s arithmetic (its
    /// slack) in 16 lanes.
    pub(crate) fn new<F: Lanes>(packets: &[RayPacket<F>], apex: [f32; 3], extent: f32) -> Self {
        // One pass over the members, transposing their normals into lanes. Added to the offsets: 0 for a
        // member's own planes; −inf (nothing is outside) for a member without a pyramid; NaN (no comparison
        // holds, so nothing is outside) for one whose apex is not the tile's.
        let mut lanes = [[[0.0f32; MAX_PACKETS]; 3]; 4];
        let mut without = [f32::NEG_INFINITY; MAX_PACKETS];
        for (p, m) in packets.iter().enumerate().filter_map(|(p, rays)| Some((p, rays.pyramid?))) {
            for (side, n) in lanes.iter_mut().zip(&m.normals) {
                for (axis, c) in side.iter_mut().zip(n) {
                    axis[p] = *c;
                }
            }
            without[p] = if m.apex == apex { 0.0 } else { f32::NAN };
        }
        let without = f32x16::from(without);
        let normal = lanes.map(|side| side.map(f32x16::from));
        let o = apex.map(f32x16::splat);
        let reach = f32x16::splat(Side::reach(apex, extent));
        let slack = f32x16::splat(Side::SLACK);
        let offset = normal.map(|n| {
            let dot = n[2].mul_add(o[2], n[1].mul_add(o[1], n[0] * o[0]));
            let l1 = n[0].abs() + n[1].abs() + n[2].abs();
            (dot - slack * l1 * reach) + without
        });
        let norm = normal.map(|n| {
            (n[2].mul_add(n[2], n[1].mul_add(n[1], n[0] * n[0]))).sqrt() * f32x16::splat(Side::NORM_UP)
        });
        let zero = f32x16::splat(0.0);
        let above = normal.map(|n| n.map(|c| c.fast_max(zero)));
        let below = normal.map(|n| n.map(|c| c.fast_min(zero)));
        Self { normal, above, below, norm, offset }
    }

    /// Bit p set where member p's frustum may reach child `c` of `n`, no nearer than `near` to the apex,
    /// before its farthest best hit (`far`, per member): the box's corner farthest along each side's
    /// normal (per lane) is not below the side, as in [`Frustum`]'s box test.
    #[inline(always)]
    fn reaching_box(&self, n: &Node, c: usize, far: f32x16, near: f32) -> u32 {
        let corner = |a: usize| (n.lo()[a][c], n.hi()[a][c]);
        self.reaching_corners([corner(0), corner(1), corner(2)], far, near)
    }

    /// [`MemberSides::reaching_box`] for the box whose `(low, high)` planes on each axis are `planes`.
    #[inline(always)]
    pub(crate) fn reaching_corners(&self, planes: [(f32, f32); 3], far: f32x16, near: f32) -> u32 {
        let zero = f32x16::splat(0.0);
        let (lo, hi) = (planes.map(|p| f32x16::splat(p.0)), planes.map(|p| f32x16::splat(p.1)));
        // Members whose best hits are all nearer than the box are done with it.
        let mut outside = far.lt(f32x16::splat(near));
        for ((above, below), offset) in self.above.iter().zip(&self.below).zip(&self.offset) {
            // Each axis adds its corner's product and an exact zero (the box is finite), in the order of
            // the select form `corner·n`, so the sum is that form's to the bit.
            let mut s = -*offset;
            for a in 0..3 {
                s = hi[a].mul_add(above[a], lo[a].mul_add(below[a], s));
            }
            // The sides' masks are merged as vectors and turned into bits once.
            outside = outside | s.lt(zero);
        }
        !f32x16::move_mask(outside)
    }

    /// Bit p set where member p's frustum may meet the ball of radius `r` around `centre`, as in
    /// [`Frustum`]'s sphere test.
    #[inline(always)]
    pub(crate) fn reaching_ball(&self, centre: Vec3f, r: f32) -> u32 {
        let (zero, r) = (f32x16::splat(0.0), f32x16::splat(r));
        let (x, y, z) = (f32x16::splat(centre.x), f32x16::splat(centre.y), f32x16::splat(centre.z));
        let mut outside = f32x16::mask_from_bits(0);
        for ((normal, norm), offset) in self.normal.iter().zip(&self.norm).zip(&self.offset) {
            let s =
                normal[2].mul_add(z, normal[1].mul_add(y, normal[0].mul_add(x, norm.mul_add(r, -*offset))));
            outside = outside | s.lt(zero);
        }
        !f32x16::move_mask(outside)
    }
}

/// Member `p`'s query, made on first use.
#[inline(always)]
fn made<'m, Q>(made: &'m mut [Option<Q>; MAX_PACKETS], query: &impl Fn(usize) -> Q, p: usize) -> &'m Q {
    made[p].get_or_insert_with(|| query(p))
}

/// A lower bound on the distance from `origin` to each child box of `n`, shrunk past its own rounding: no
/// ray from `origin` with a unit direction (within an ulp) enters a child at a smaller t.
#[inline(always)]
fn box_distance(n: &Node, origin: [f32; 3]) -> [f32; 4] {
    let zero = f32x4::splat(0.0);
    let mut d2 = zero;
    for (a, &o) in origin.iter().enumerate() {
        let o = f32x4::splat(o);
        let gap = (f32x4::from(n.lo()[a]) - o).fast_max(o - f32x4::from(n.hi()[a])).fast_max(zero);
        d2 = gap.mul_add(gap, d2);
    }
    (d2.sqrt() * f32x4::splat(1.0 - 16.0 * f32::EPSILON)).to_array()
}

impl Bvh {
    /// Closest hits of the leaf items for a tile of packets that share an origin, each with its pyramid
    /// (`packets[p]`, merged into `best[p]`), walking the tree once for all of them; `pyramid` encloses every
    /// active ray of the tile. The directions must be unit length (camera rays are): the walk culls boxes
    /// by their distance from the origin against the rays' t. `query(p)` makes packet p's leaf query,
    /// called only for packets that reach a leaf's box. Each lane gets the bits [`Bvh::intersect_k`] gives
    /// it with that query.
    pub(crate) fn intersect_large<F: Lanes, Q: LeafQuery<F>>(
        &self,
        packets: &[RayPacket<F>],
        query: impl Fn(usize) -> Q,
        pyramid: &Pyramid,
        best: &mut [HitPacket<F>],
    ) {
        let (live, alive) = members(packets, best.len());
        if alive == 0 {
            return;
        }
        let lead = &packets[alive.trailing_zeros() as usize];
        let first = F::move_mask(lead.active).trailing_zeros() as usize;
        let negative = |d: F| usize::from(d.lane(first) < 0.0);
        // Outside the walk's state, which is then built in place: a state holding the queries (about 1.6 KB
        // each at K = 16) would copy them all whenever it moves. `from_fn` writes only the `None`s' tags,
        // where an array expression compiles to copying a whole constant for each.
        let mut made: [Option<Q>; MAX_PACKETS] = std::array::from_fn(|_| None);
        let mut walk = Walk {
            bvh: self,
            query,
            made: &mut made,
            live,
            sides: MemberSides::new(packets, pyramid.apex, self.extent),
            tile: Frustum::new(pyramid, self.extent),
            octant: negative(lead.ray.dir.x) | negative(lead.ray.dir.y) << 1 | negative(lead.ray.dir.z) << 2,
            origin: pyramid.apex,
            prefetch: self.nodes.len() > PREFETCH_MIN_NODES,
        };
        walk.run(alive, best);
    }
}

/// The largest of `t`'s lanes, none of them NaN (hit distances, inf or −inf), from an array with room for
/// the widest lane type (K ≤ 16): four 4-lane maxima (no NaN rule to keep), then the last four lanes.
#[inline(always)]
pub(crate) fn farthest<F: Lanes>(t: F) -> f32 {
    let mut a = [f32::NEG_INFINITY; 16];
    a[..F::K].copy_from_slice(t.to_array().as_ref());
    debug_assert!(!a.iter().any(|v| v.is_nan()), "a NaN hit distance");
    let quarter = |k: usize| f32x4::from([a[4 * k], a[4 * k + 1], a[4 * k + 2], a[4 * k + 3]]);
    let m = quarter(0).fast_max(quarter(1)).fast_max(quarter(2).fast_max(quarter(3))).to_array();
    let larger = |x: f32, y: f32| if y > x { y } else { x };
    larger(larger(m[0], m[1]), larger(m[2], m[3]))
}

/// The members of a large packet of `packets` (with `hits` hit packets to fill): each member's live lanes
/// (none past the last packet) and bit p for each member with a live lane. Panics on more than
/// [`MAX_PACKETS`] packets or a hit count that differs; the directions must be unit length (checked in
/// debug builds).
pub(crate) fn members<F: Lanes>(packets: &[RayPacket<F>], hits: usize) -> ([F::Mask; MAX_PACKETS], u32) {
    let count = packets.len();
    assert!(count <= MAX_PACKETS && count == hits, "{count} packets for a large packet");
    debug_assert!(packets.iter().all(unit_directions), "large packets need unit directions");
    let live: [F::Mask; MAX_PACKETS] =
        std::array::from_fn(|p| packets.get(p).map_or(F::mask_from_bits(0), |rays| rays.active));
    let alive = live.iter().enumerate().fold(0u32, |bits, (p, m)| bits | u32::from(m.any()) << p);
    (live, alive)
}

/// Whether every active lane's direction is unit length to within its rounding (the distance cull's
/// premise).
fn unit_directions<F: Lanes>(rays: &RayPacket<F>) -> bool {
    (0..F::K).filter(|&i| F::mask_lane(rays.active, i)).all(|i| {
        let d = [rays.ray.dir.x.lane(i), rays.ray.dir.y.lane(i), rays.ray.dir.z.lane(i)].map(f64::from);
        ((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) - 1.0).abs() <= 8.0 * f64::from(f32::EPSILON)
    })
}

/// One large packet's walk.
struct Walk<'a, F: Lanes, Q, M> {
    bvh: &'a Bvh,
    /// Makes a member's leaf query.
    query: M,
    /// The queries made so far.
    made: &'a mut [Option<Q>; MAX_PACKETS],
    live: [F::Mask; MAX_PACKETS],
    sides: MemberSides,
    tile: Frustum,
    octant: usize,
    origin: [f32; 3],
    /// Ask for each pushed child's node, or its leaf's items, as it is pushed ([`PREFETCH_MIN_NODES`]).
    prefetch: bool,
}

/// Trees of more nodes than this (1 MiB of nodes, a Zen 4 core's whole L2) have the large walk prefetch
/// each child it pushes, so that its cache misses overlap the tests of the children popped before it.
/// Trees that stay in cache would only pay for the prefetch instructions: 2% slower on the 1e3 field
/// (PERF.md, Register).
const PREFETCH_MIN_NODES: usize = 8192;

impl<F: Lanes, Q: LeafQuery<F>, M: Fn(usize) -> Q> Walk<'_, F, Q, M> {
    fn run(&mut self, alive: u32, best: &mut [HitPacket<F>]) {
        // Per member, the farthest best hit of its live lanes (inf while one has none): it looks no farther.
        let mut far = f32x16::splat(f32::INFINITY);
        let mut stack = Stack::<Pending>::new();
        // Live rays a box test serves, summed only when counting (a loop over the members per node).
        let counting = counting();
        let (mut boxes, mut prims, mut box_lanes, mut prim_lanes) = (0, 0, 0, 0);
        let tested = self.push_children(0, alive, far, &mut stack);
        boxes += tested;
        if counting {
            box_lanes += tested * self.rays_of(alive);
        }
        while let Some(e) = stack.pop() {
            // Members that found nearer hits since the push are done with this box.
            let members = u32::from(e.members) & !f32x16::move_mask(far.lt(f32x16::splat(e.near)));
            if members == 0 {
                continue;
            }
            let (child, count) = (e.child, e.count);
            if count == 0 {
                let tested = self.push_children(child, members, far, &mut stack);
                boxes += tested;
                if counting {
                    box_lanes += tested * self.rays_of(members);
                }
                continue;
            }
            let first = child as usize;
            let (tests, lanes) =
                self.intersect_leaf(first..first + usize::from(count), members, best, &mut far, counting);
            prims += tests;
            prim_lanes += lanes;
        }
        if counting {
            add_work(Work::lanes(prims, prim_lanes, boxes, box_lanes));
        }
    }

    /// The live rays of `members`.
    fn rays_of(&self, members: u32) -> usize {
        set_bits(members).map(|p| F::move_mask(self.live[p]).count_ones() as usize).sum()
    }

    /// Each of `members`' closest hits among `items`, each member testing the items its frustum may meet;
    /// updates the members' `far`. Returns the member–item tests made and, when `counting`, the live rays
    /// they served.
    #[inline(always)]
    fn intersect_leaf(
        &mut self,
        items: std::ops::Range<usize>,
        members: u32,
        best: &mut [HitPacket<F>],
        far: &mut f32x16,
        counting: bool,
    ) -> (usize, usize) {
        let (mut tests, mut lanes) = (0, 0);
        let mut updated = far.to_array();
        // Leaves hold at most 8 spheres under every builder bareray uses; longer ones go 16 at a time.
        for start in items.clone().step_by(16) {
            let chunk = start..(start + 16).min(items.end);
            let mut reach = [0u32; 16];
            let mut any = 0;
            let q = made(self.made, &self.query, members.trailing_zeros() as usize);
            for i in chunk.clone() {
                let ball = q.ball(i);
                let m =
                    ball.map_or(members, |(c, r)| self.sides.reaching_ball(c, r + self.bvh.pad) & members);
                reach[i - start] = m;
                any |= m;
            }
            for p in set_bits(any) {
                // Bit k for the chunk's item start + k that member p may meet.
                let bits = reach.iter().enumerate().fold(0u32, |b, (k, m)| b | (m >> p & 1) << k);
                let mine = set_bits(bits).map(|k| start + k);
                let mine_count = bits.count_ones() as usize;
                tests += mine_count;
                if counting {
                    lanes += mine_count * F::move_mask(self.live[p]).count_ones() as usize;
                }
                made(self.made, &self.query, p).intersect(mine, self.live[p], &mut best[p]);
                updated[p] = farthest(F::select(self.live[p], best[p].t, F::splat_f32(f32::NEG_INFINITY)));
            }
        }
        *far = f32x16::from(updated);
        (tests, lanes)
    }

    /// Pushes the children of node `at` that some of `members` may reach before its best hits, farthest
    /// first, each with the members that may. Returns the box tests made.
    #[inline(always)]
    fn push_children(&mut self, at: u32, members: u32, far: f32x16, stack: &mut Stack<Pending>) -> usize {
        let bvh = self.bvh;
        let n = &bvh.nodes[at as usize];
        let maybe = self.tile.maybe_entered(n);
        let near = box_distance(n, self.origin);
        let mut tests = 0;
        for c in n.slots_far_to_near(self.octant).filter(|&c| maybe >> c & 1 == 1) {
            tests += 1;
            let reach = self.sides.reaching_box(n, c, far, near[c]) & members;
            if self.prefetch && reach != 0 {
                let (child, count) = (n.child[c] as usize, usize::from(n.count[c]));
                if count == 0 {
                    crate::simd::prefetch(&bvh.nodes, child);
                } else {
                    made(self.made, &self.query, reach.trailing_zeros() as usize).prefetch(child, count);
                }
            }
            stack.push_if(
                Pending { child: n.child[c], count: n.count[c], members: reach as u16, near: near[c] },
                reach != 0,
            );
        }
        tests
    }
}
