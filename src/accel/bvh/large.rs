//! Large packets: up to [`MAX_PACKETS`] packets of K rays that share an origin (a tile of camera rays) walk
//! the tree together. Per node the tile pays once what the K-ray walk pays per packet:
//!
//! - the tile's [`Frustum`] rules out the children no ray of the tile can enter (one 4-wide pass);
//! - a child whose box lies farther from the shared origin than every ray's best hit so far is skipped;
//! - a child is entered with the index of the first packet that enters it (Wald et al.'s "first active
//!   ray", here a first active packet): packets before it missed the child, so its subtree never tests them.
//!
//! Only leaves test each packet from the first active one on, by its own slab test and frustum, with the same
//! K-lane sphere kernel as the K-ray walk, so every lane gets the bits [`Bvh::intersect_k`] gives it
//! (leaf items are merged in (t, id) order, whatever the order of visits).

use wide::{f32x16, f32x4};

use super::super::count_work;
use super::node::Node;
use super::packet::{Frustum, SlabRays};
use super::slab::Stack;
use super::{Bvh, LeafQuery};
use crate::geometry::{HitPacket, Pyramid};
use crate::math::{Mask, Real};
use crate::simd::{set_bits, Lanes};

/// The most packets a large packet holds: a 16×16-pixel tile of 4×4-ray packets.
pub const MAX_PACKETS: usize = 16;

/// A child waiting on the stack: slot `slot` of node `parent`, first entered by packet `first`, no nearer
/// than `near` to the shared origin.
#[derive(Clone, Copy)]
struct Pending {
    parent: u32,
    slot: u8,
    first: u8,
    near: f32,
}

/// One packet of the tile and what its walk keeps.
struct Member<'q, F: Lanes, Q> {
    q: &'q Q,
    live: F::Mask,
    rays: SlabRays<F>,
}

impl<F: Lanes, Q: LeafQuery<F>> Member<'_, F, Q> {
    /// Each live lane's entry distance limit: its best hit so far (or its end), `-inf` for dead lanes.
    #[inline(always)]
    fn limit(&self, best: &HitPacket<F>) -> F {
        F::select(self.live, best.t.min_of(self.q.t_max()), F::splat_f32(f32::NEG_INFINITY))
    }

    /// The lanes that enter child `c` of `n` before their best hit.
    #[inline(always)]
    fn entering(&self, n: &Node, c: usize, best: &HitPacket<F>) -> F::Mask {
        self.rays.enter(n, c, self.limit(best)).lt(F::splat_f32(f32::INFINITY))
    }
}

/// The largest best-hit distance among the live lanes (`-inf` with none): no lane looks beyond it.
#[inline(always)]
fn reach<F: Lanes>(live: F::Mask, best: &HitPacket<F>) -> f32 {
    let t = F::select(live, best.t, F::splat_f32(f32::NEG_INFINITY)).to_array();
    t.as_ref().iter().copied().fold(f32::NEG_INFINITY, f32::max)
}

/// Every member's frustum at once, one member per lane: the test that tells which members may reach a box,
/// before any member's K-lane slab test. Members without a frustum always may.
struct MemberSides {
    /// Per side, the normals' components.
    normal: [[f32x16; 3]; 4],
    /// Per side, the offsets ([`Frustum`]'s, with its slack); `-inf` for members without a frustum.
    offset: [f32x16; 4],
    /// Bit p set for each member with a live lane.
    alive: u32,
}

impl MemberSides {
    fn new<F: Lanes, Q>(members: &[Member<F, Q>]) -> Self {
        let lane = |f: &dyn Fn(&Frustum) -> f32, none: f32| {
            f32x16::from(std::array::from_fn::<f32, MAX_PACKETS, _>(|p| {
                members.get(p).and_then(|m| m.rays.frustum.as_ref()).map_or(none, f)
            }))
        };
        Self {
            normal: std::array::from_fn(|s| std::array::from_fn(|a| lane(&|f| f.sides[s].normal[a], 0.0))),
            offset: std::array::from_fn(|s| lane(&|f| f.sides[s].offset, f32::NEG_INFINITY)),
            alive: members.iter().enumerate().fold(0, |bits, (p, m)| bits | u32::from(m.live.any()) << p),
        }
    }

    /// Bit p set where member p's frustum may reach child `c` of `n`: the box's corner farthest along each
    /// side's normal (per lane) is not below the side. The same corner and sums as [`Frustum`]'s box test.
    #[inline(always)]
    fn reaching(&self, n: &Node, c: usize) -> u32 {
        let zero = f32x16::splat(0.0);
        let corner = |a: usize, normal: f32x16| {
            let (lo, hi) = (f32x16::splat(n.lo()[a][c]), f32x16::splat(n.hi()[a][c]));
            Real::select(zero.le(normal), hi, lo)
        };
        let mut outside = 0;
        for (normal, offset) in self.normal.iter().zip(&self.offset) {
            let w = |a: usize| corner(a, normal[a]);
            let s = w(2).mul_add(normal[2], w(1).mul_add(normal[1], w(0).mul_add(normal[0], -*offset)));
            outside |= f32x16::move_mask(s.lt(zero));
        }
        !outside & self.alive
    }
}

/// A lower bound on the distance from `origin` to each child box of `n`, shrunk past its own rounding: no
/// ray from `origin` with a unit direction (within an ulp) enters a child at a smaller t.
#[inline(always)]
fn box_distance(n: &Node, origin: [f32; 3]) -> [f32; 4] {
    let zero = f32x4::splat(0.0);
    let mut d2 = zero;
    for (a, &o) in origin.iter().enumerate() {
        let o = f32x4::splat(o);
        let below = f32x4::from(n.lo()[a]) - o;
        let above = o - f32x4::from(n.hi()[a]);
        let gap = below.fast_max(above).fast_max(zero);
        d2 = gap.mul_add(gap, d2);
    }
    (d2.sqrt() * f32x4::splat(1.0 - 16.0 * f32::EPSILON)).to_array()
}

impl Bvh {
    /// Closest hits of the leaf items for a tile of packets that share an origin (`qs[p]` with its lanes
    /// `live[p]`, merged into `best[p]`), walking the tree once for all of them; `pyramid` encloses every
    /// live ray of the tile. Each lane gets the bits [`Bvh::intersect_k`] gives it.
    pub fn intersect_large<F: Lanes, Q: LeafQuery<F>>(
        &self,
        qs: &[Q],
        live: &[F::Mask],
        pyramid: &Pyramid,
        best: &mut [HitPacket<F>],
    ) {
        assert!(qs.len() <= MAX_PACKETS && qs.len() == live.len() && qs.len() == best.len());
        let extent = self.frustum_culling.then_some(self.extent);
        let Some(lead) = live.iter().position(|m| m.any()) else { return };
        let member = |p: usize| {
            let (q, live) = (&qs[p.min(qs.len() - 1)], live.get(p).copied().unwrap_or(F::mask_from_bits(0)));
            Member { q, live, rays: SlabRays::new(q, live, extent) }
        };
        let members: [Member<F, Q>; MAX_PACKETS] = std::array::from_fn(member);
        let tile = Frustum::new(pyramid, self.extent);
        let octant = members[lead].rays.octant;
        let members = &members[..qs.len()];
        let sides = MemberSides::new(members);
        let mut walk = Walk { bvh: self, members, sides, tile, octant, origin: pyramid.apex, boxes: 0 };
        walk.run(lead, best);
    }
}

/// One large packet's walk.
struct Walk<'a, 'q, F: Lanes, Q> {
    bvh: &'a Bvh,
    members: &'a [Member<'q, F, Q>],
    sides: MemberSides,
    tile: Frustum,
    octant: usize,
    origin: [f32; 3],
    boxes: usize,
}

impl<F: Lanes, Q: LeafQuery<F>> Walk<'_, '_, F, Q> {
    fn run(&mut self, lead: usize, best: &mut [HitPacket<F>]) {
        let mut far: [f32; MAX_PACKETS] = [f32::INFINITY; MAX_PACKETS];
        let mut tile_far = f32::INFINITY;
        let mut stack = Stack::<Pending>::new();
        let mut prims = 0;
        self.push_children(0, lead, tile_far, best, &mut stack);
        while let Some(e) = stack.pop() {
            if e.near > tile_far {
                continue;
            }
            let n = &self.bvh.nodes[e.parent as usize];
            let (slot, first) = (usize::from(e.slot), usize::from(e.first));
            let (child, count) = (n.child[slot], n.count[slot]);
            if count == 0 {
                self.push_children(child, first, tile_far, best, &mut stack);
                continue;
            }
            let items = child as usize..child as usize + usize::from(count);
            for p in set_bits(self.sides.reaching(n, slot) >> first << first) {
                let m = &self.members[p];
                self.boxes += 1;
                let lanes = m.entering(n, slot, &best[p]) & m.live;
                if !lanes.any() {
                    continue;
                }
                prims += items.len();
                self.intersect_leaf(m, items.clone(), lanes, &mut best[p]);
                far[p] = reach(m.live, &best[p]);
            }
            tile_far = far[..self.members.len()].iter().copied().fold(f32::NEG_INFINITY, f32::max);
        }
        count_work(prims, self.boxes);
    }

    /// Member `m`'s closest hits among `items` for `lanes`, its frustum ruling out single items first.
    #[inline(always)]
    fn intersect_leaf(
        &self,
        m: &Member<F, Q>,
        items: std::ops::Range<usize>,
        lanes: F::Mask,
        best: &mut HitPacket<F>,
    ) {
        let pad = self.bvh.pad;
        match &m.rays.frustum {
            Some(f) => {
                let items = items.filter(|&i| m.q.ball(i).is_none_or(|(c, r)| f.may_meet(c, r + pad)));
                m.q.intersect(items, lanes, best)
            }
            None => m.q.intersect(items, lanes, best),
        }
    }

    /// Pushes the children of node `at` that some member from `first` on enters before its best hit, farthest
    /// first, each with the first member that enters it.
    #[inline(always)]
    fn push_children(
        &mut self,
        at: u32,
        first: usize,
        tile_far: f32,
        best: &[HitPacket<F>],
        stack: &mut Stack<Pending>,
    ) {
        let n = &self.bvh.nodes[at as usize];
        let maybe = self.tile.maybe_entered(n);
        let near = box_distance(n, self.origin);
        for c in n.slots_far_to_near(self.octant).filter(|&c| maybe >> c & 1 == 1 && near[c] <= tile_far) {
            let entered = set_bits(self.sides.reaching(n, c) >> first << first).find(|&p| {
                self.boxes += 1;
                self.members[p].entering(n, c, &best[p]).any()
            });
            if let Some(p) = entered {
                stack.push(Pending { parent: at, slot: c as u8, first: p as u8, near: near[c] });
            }
        }
    }
}
