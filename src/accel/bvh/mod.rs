//! A 4-wide BVH over the spheres, built by obvhs (PLOC) as a binary tree and collapsed into bareray's own
//! node layout: each node holds the boxes of up to [`N`] children in SoA form (two 64-byte cache lines), so
//! one node visit tests all its children — K rays against each child in the packet traversal
//! ([`packet`]), one ray against all children at once in the single-ray traversal ([`single`]).
//!
//! obvhs sorts primitives into leaf order (`primitive_indices`); compile reorders the SoA sphere arrays once
//! into that order, so leaves index the arrays directly.
//!
//! Culling is conservative: boxes are padded by a bound on the sphere kernel's rounding error, and every slab
//! test widens its exit distance by 2γ₃ (Ize 2013). With the (t, id) order of
//! [`crate::geometry::HitPacket::update`] this makes every lane's result equal, bit for bit, to brute force
//! over the same spheres, whatever order the nodes are visited in and whichever traversal runs.

mod packet;
mod single;

use std::time::Instant;

use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::BvhBuildParams;

use super::Spheres;
use crate::math::V3;
use crate::simd::Lanes;

pub use single::SINGLE_RAY_MAX_LANES;

/// Children per node (Embree's N).
pub const N: usize = 4;

/// One node: the boxes of its children and where each child's content is. Occupied slots come first.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Node {
    /// Lower corner per axis (x, y, z), per child.
    pub lo: [[f32; N]; 3],
    /// Upper corner per axis, per child.
    pub hi: [[f32; N]; 3],
    /// Inner child: index of its node; leaf child: index of its first sphere.
    pub child: [u32; N],
    /// Number of spheres of a leaf child (M ≤ obvhs's leaf size, at most 255); 0 for an inner child.
    pub count: [u8; N],
    /// Front-to-back order of the occupied slots for rays in each octant (index: bit a set when the
    /// direction's axis-a component is negative), 2 bits per slot, nearest in the low bits.
    pub order: [u8; 8],
    /// Occupied slots (2 to N, 1 only for a root that is a leaf).
    pub slots: u8,
}

const _: () = assert!(size_of::<Node>() == 128, "a node is two cache lines");

/// A child slot's box and content, while flattening.
#[derive(Clone, Copy)]
struct ChildRef {
    lo: [f32; 3],
    hi: [f32; 3],
    child: u32,
    count: u8,
}

/// A slot no ray can enter: a box at +inf, whose slab distances are +inf or −inf, never a finite entry. (An
/// inverted box, lo = +inf and hi = −inf, would give every slab (−inf, +inf) and be entered by every ray.)
const EMPTY: ChildRef = ChildRef { lo: [f32::INFINITY; 3], hi: [f32::INFINITY; 3], child: 0, count: 0 };

impl Node {
    fn new(children: &[ChildRef]) -> Node {
        assert!(children.len() <= N);
        let c = |i: usize| children.get(i).copied().unwrap_or(EMPTY);
        Node {
            lo: std::array::from_fn(|a| std::array::from_fn(|i| c(i).lo[a])),
            hi: std::array::from_fn(|a| std::array::from_fn(|i| c(i).hi[a])),
            child: std::array::from_fn(|i| c(i).child),
            count: std::array::from_fn(|i| c(i).count),
            order: std::array::from_fn(|octant| front_to_back(children, octant)),
            slots: children.len() as u8,
        }
    }

    /// The occupied slots farthest first for rays in `octant` (the order to push them in), from
    /// [`Node::order`].
    #[inline(always)]
    pub fn slots_far_to_near(&self, octant: usize) -> impl Iterator<Item = usize> {
        let order = self.order[octant];
        (0..usize::from(self.slots)).rev().map(move |k| usize::from(order >> (2 * k) & 3))
    }
}

/// The children sorted by the projection of their box centres on the octant's diagonal direction: the
/// order a ray in that octant meets well-separated boxes. Packed 2 bits per slot, nearest first.
fn front_to_back(children: &[ChildRef], octant: usize) -> u8 {
    let sign = |a: usize| if octant >> a & 1 == 1 { -1.0 } else { 1.0 };
    let key = |c: &ChildRef| (0..3).map(|a| sign(a) * (c.lo[a] + c.hi[a])).sum::<f32>();
    // Farthest first by the negated key is nearest first by the key (negation is exact).
    let mut order = [(0.0, 0); N];
    for (slot, c) in children.iter().enumerate() {
        order[slot] = (-key(c), slot);
    }
    far_to_near(&mut order[..children.len()]);
    order[..children.len()].iter().enumerate().fold(0, |bits, (k, &(_, slot))| bits | (slot as u8) << (2 * k))
}

/// The BVH: `nodes[0]` is the root.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    /// Flattened nodes, depth-first.
    pub nodes: Vec<Node>,
    /// Test each node against shared-origin packets as a whole first ([`packet`]'s interval test). Off by
    /// default: measured slower on every field (PERF.md, "Whole-packet culling").
    pub interval_culling: bool,
}

/// What building cost.
#[derive(Clone, Copy, Debug, Default)]
pub struct BuildStats {
    /// Seconds in obvhs plus collapsing and reordering.
    pub seconds: f64,
    /// Bytes of the node array.
    pub node_bytes: usize,
}

/// The padding that keeps culling conservative: the sphere kernel may accept a ray passing up to a few ulps
/// of the ray's distance outside the sphere, and that distance is at most about the scene's extent `reach`
/// (the largest coordinate magnitude of any sphere, eye or light). 64 ulps of it is ample and far below any
/// sphere the scene can resolve.
pub fn padding(reach: f32) -> f32 {
    reach * (64.0 * f32::EPSILON)
}

/// Builds the BVH and reorders `spheres` into its leaf order (their `key` keeps each one's file index).
/// Returns the BVH and build statistics.
pub fn build(spheres: &mut Spheres, pad: f32, params: BvhBuildParams) -> (Bvh, BuildStats) {
    let start = Instant::now();
    let boxes: Vec<Aabb> = (0..spheres.len())
        .map(|i| {
            let c = Vec3A::new(spheres.cx[i], spheres.cy[i], spheres.cz[i]);
            let r = Vec3A::splat(spheres.r[i] + pad);
            Aabb { min: c - r, max: c + r }
        })
        .collect();
    let bvh2 = build_bvh2(&boxes, params, &mut Default::default());
    *spheres = spheres.permuted(&bvh2.primitive_indices);
    let mut nodes = Vec::with_capacity(bvh2.nodes.len() / 2 + 1);
    if bvh2.nodes[0].prim_count > 0 {
        let leaf = child_ref(&bvh2.nodes, 0, &mut nodes);
        nodes.push(Node::new(&[leaf]));
    } else {
        flatten(&bvh2.nodes, 0, &mut nodes);
    }
    let stats =
        BuildStats { seconds: start.elapsed().as_secs_f64(), node_bytes: nodes.len() * size_of::<Node>() };
    (Bvh { nodes, interval_culling: false }, stats)
}

/// The reference to obvhs node `i` from its parent: a leaf as it is, an inner node flattened first.
fn child_ref(src: &[Bvh2Node], i: usize, out: &mut Vec<Node>) -> ChildRef {
    let n = &src[i];
    let (lo, hi) = (n.aabb.min.to_array(), n.aabb.max.to_array());
    if n.prim_count > 0 {
        let count = u8::try_from(n.prim_count).expect("obvhs leaf of more than 255 spheres");
        return ChildRef { lo, hi, child: n.first_index, count };
    }
    ChildRef { lo, hi, child: flatten(src, i, out), count: 0 }
}

/// Appends the subtree of obvhs inner node `i` and returns its node index. The node takes the binary node's
/// two children and keeps opening the inner child of largest surface area (the likeliest to be entered)
/// into its two children until it has N.
fn flatten(src: &[Bvh2Node], i: usize, out: &mut Vec<Node>) -> u32 {
    let first = src[i].first_index as usize;
    let (mut open, mut len) = ([first, first + 1, 0, 0], 2);
    while len < N {
        let area = |j: usize| src[j].aabb.half_area();
        let inner = (0..len).filter(|&k| src[open[k]].prim_count == 0);
        let Some(at) = inner.max_by(|&a, &b| area(open[a]).total_cmp(&area(open[b]))) else { break };
        let grand = src[open[at]].first_index as usize;
        (open[at], open[len]) = (grand, grand + 1);
        len += 1;
    }
    let me = out.len();
    out.push(Node::new(&[]));
    let mut children = [EMPTY; N];
    for k in 0..len {
        children[k] = child_ref(src, open[k], out);
    }
    out[me] = Node::new(&children[..len]);
    me as u32
}

/// Exit distances are widened by this factor (2γ₃ rounded up) so rounding never culls a box a ray enters.
const WIDEN: f32 = 1.0 + 4.0 * f32::EPSILON;

/// `1/d` with a zero component replaced by ±1e-30 first, so no slab product is 0·inf = NaN.
#[inline(always)]
fn inverse<F: Lanes>(d: F) -> F {
    let tiny = F::splat_f32(1e-30);
    let away = F::select(d.lt(F::splat_f32(0.0)), -tiny, tiny);
    F::splat_f32(1.0) / F::select(d.abs().lt(tiny), away, d)
}

/// The slab test both traversals run, in either layout: lanes = rays (one box, corners splatted; packet
/// traversal) or lanes = boxes (one ray, origin and `1/d` splatted; single-ray traversal). Returns each
/// lane's entry distance, `inf` where it misses the box or enters beyond `limit`.
#[inline(always)]
fn slab_entry<F: Lanes>(lo: [F; 3], hi: [F; 3], origin: &V3<F>, inv_dir: &V3<F>, limit: F) -> F {
    let slab = |lo: F, hi: F, o: F, inv: F| {
        let (t0, t1) = ((lo - o) * inv, (hi - o) * inv);
        (t0.fast_min(t1), t0.fast_max(t1))
    };
    let (nx, fx) = slab(lo[0], hi[0], origin.x, inv_dir.x);
    let (ny, fy) = slab(lo[1], hi[1], origin.y, inv_dir.y);
    let (nz, fz) = slab(lo[2], hi[2], origin.z, inv_dir.z);
    // Balanced trees keep the dependency chain short; entering before the exit and before the limit is one
    // comparison against the smaller of the two.
    let near = nx.fast_max(ny).fast_max(nz.fast_max(F::splat_f32(0.0)));
    let far = (fx.fast_min(fy).fast_min(fz) * F::splat_f32(WIDEN)).fast_min(limit);
    F::select(near.le(far), near, F::splat_f32(f32::INFINITY))
}

/// Deep enough for any tree obvhs builds over 2^32 primitives with its leaf collapsing (a 4-wide node pushes
/// up to 3 entries per level); checked on push.
const STACK: usize = 256;

/// A fixed-capacity traversal stack on the call stack (a heap vector per packet costs more than a small
/// BVH's whole traversal).
struct Stack<E: Copy> {
    items: [std::mem::MaybeUninit<E>; STACK],
    len: usize,
}

impl<E: Copy> Stack<E> {
    #[inline(always)]
    fn new() -> Self {
        Self { items: [const { std::mem::MaybeUninit::uninit() }; STACK], len: 0 }
    }
    #[inline(always)]
    fn push(&mut self, e: E) {
        assert!(self.len < STACK, "BVH deeper than the traversal stack");
        self.items[self.len].write(e);
        self.len += 1;
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<E> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: entries below `len` were written by `push` and are plain `Copy` data.
        Some(unsafe { self.items[self.len].assume_init() })
    }
}

/// Sorts up to N (key, slot) pairs so that the largest key comes first: pushed in this order, the nearest
/// child is popped first.
#[inline(always)]
fn far_to_near(order: &mut [(f32, usize)]) {
    for i in 1..order.len() {
        let mut j = i;
        while j > 0 && order[j - 1].0 < order[j].0 {
            order.swap(j - 1, j);
            j -= 1;
        }
    }
}
