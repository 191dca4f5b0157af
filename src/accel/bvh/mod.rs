//! A 4-wide BVH over the spheres, built by obvhs (PLOC) as a binary tree and collapsed into bareray's own
//! node layout: each node holds the boxes of up to [`N`] children in SoA form (two 64-byte cache lines), so
//! one node visit tests all its children — K rays against each child in the packet traversal
//! ([`packet`]), one ray against all children at once in the single-ray traversal ([`single`]).
//!
//! obvhs sorts primitives into leaf order (`primitive_indices`); compile reorders the SoA sphere arrays once
//! into that order, so leaves index the arrays directly.
//!
//! Culling is conservative: boxes are padded by a bound on the sphere kernel's rounding error, and every slab
//! test widens its exit distance by 6ε, which covers the fused slab distances' rounding ([`WIDEN`]). With the
//! (t, id) order of [`crate::geometry::HitPacket::update`] this makes every lane's result equal, bit for bit,
//! to brute force over the same spheres, whatever order the nodes are visited in and whichever traversal
//! runs.

mod binary;
mod node8;
mod packet;
mod piles;
mod single;

pub use node8::{WideNode, WIDE_N};

use std::time::Instant;

use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::BvhBuildParams;
use rayon::prelude::*;

use super::brute::SphereQuery;
use crate::geometry::{HitPacket, Ray, Spheres};
use crate::math::V3;
use crate::simd::Lanes;

/// Subtrees that a packet enters with at most this many live lanes are walked one ray at a time (measured:
/// docs/perf-log/2026-11.md, "Single-ray switch").
pub const SINGLE_RAY_MAX_LANES: u32 = 2;

/// Children per node (Embree's N).
pub const N: usize = 4;

/// One node: the boxes of its children and where each child's content is. Occupied slots come first.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Node {
    /// `bounds[0]` the lower corner, `bounds[1]` the upper, per axis (x, y, z), per child: indexed by side
    /// so a ray picks its near and far planes by the signs of its direction.
    pub bounds: [[[f32; N]; 3]; 2],
    /// Inner child: index of its node; leaf child: index of its first sphere.
    pub child: [u32; N],
    /// Number of spheres of a leaf child (M ≤ obvhs's leaf size, at most 255); 0 for an inner child.
    pub count: [u8; N],
    /// Front-to-back order of the occupied slots for rays in each octant (index: bit a set when the
    /// direction's axis-a component is negative), 2 bits per slot, nearest in the low bits.
    pub order: [u8; 8],
    /// Occupied slots (2 to N, 1 only for a root that is a leaf).
    pub slots: u8,
    /// Bit c set where slot c is a leaf (`count[c]` not 0).
    pub leaves: u8,
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

/// The SoA slots of a `W`-wide node over `children`: boxes (`[side][axis][slot]`), references and sphere
/// counts, with [`EMPTY`] past the last child.
type Slots<const W: usize> = ([[[f32; W]; 3]; 2], [u32; W], [u8; W]);

fn slots<const W: usize>(children: &[ChildRef]) -> Slots<W> {
    assert!(children.len() <= W);
    let c = |i: usize| children.get(i).copied().unwrap_or(EMPTY);
    let bounds = [
        std::array::from_fn(|a| std::array::from_fn(|i| c(i).lo[a])),
        std::array::from_fn(|a| std::array::from_fn(|i| c(i).hi[a])),
    ];
    (bounds, std::array::from_fn(|i| c(i).child), std::array::from_fn(|i| c(i).count))
}

/// Moves the inner children's node indices (count 0) of the first `slots` up by `base`: a subtree flattened
/// on its own, placed at `base` in the whole array.
fn shift_inner(child: &mut [u32], count: &[u8], slots: u8, base: u32) {
    for c in 0..usize::from(slots) {
        if count[c] == 0 {
            child[c] += base;
        }
    }
}

/// Bit c set where `count[c]` is not 0: the leaf slots (empty slots have count 0 and are never entered).
/// Kept in each node: the single-ray occlusion walk asks for it at every visit, and computing it there was
/// 1.5% of balls4's instructions (docs/perf-log/2026-11.md).
fn leaf_bits(count: &[u8]) -> u8 {
    count.iter().enumerate().fold(0, |bits, (c, &n)| bits | u8::from(n != 0) << c)
}

impl Node {
    fn new(children: &[ChildRef]) -> Node {
        let (bounds, child, count) = slots::<N>(children);
        let order = std::array::from_fn(|octant| front_to_back(children, octant));
        Node { bounds, child, count, order, slots: children.len() as u8, leaves: leaf_bits(&count) }
    }

    /// Lower corners per axis, per child.
    #[inline(always)]
    pub fn lo(&self) -> &[[f32; N]; 3] {
        &self.bounds[0]
    }
    /// Upper corners per axis, per child.
    #[inline(always)]
    pub fn hi(&self) -> &[[f32; N]; 3] {
        &self.bounds[1]
    }

    /// The occupied slots farthest first for rays in `octant` (the order to push them in), from
    /// [`Node::order`].
    #[inline(always)]
    pub fn slots_far_to_near(&self, octant: usize) -> impl Iterator<Item = usize> {
        let order = self.order[octant];
        (0..usize::from(self.slots)).rev().map(move |k| usize::from(order >> (2 * k) & 3))
    }
}

/// The [`RayNode`] methods that only read or shift the SoA slots (`bounds`, `child`, `count`, `slots`), alike
/// for every node width; `$lanes` holds one child per lane.
macro_rules! slot_access {
    ($lanes:ty) => {
        #[inline(always)]
        fn planes(&self, side: usize, axis: usize) -> $lanes {
            <$lanes>::from(self.bounds[side][axis])
        }
        #[inline(always)]
        fn child(&self, c: usize) -> (u32, u8) {
            (self.child[c], self.count[c])
        }
        #[inline(always)]
        fn leaves(&self) -> u32 {
            u32::from(self.leaves)
        }
        fn shifted(mut self, base: u32) -> Self {
            shift_inner(&mut self.child, &self.count, self.slots, base);
            self
        }
    };
}
use slot_access;

/// A node as the collapse builds it and the single-ray walk reads it: up to `WIDTH` children, one per lane of
/// `Lanes` in the walk's slab test. Implemented by the 4-wide packet [`Node`] and the 8-wide [`WideNode`].
trait RayNode: Copy + Send + Sync {
    /// Children per node.
    const WIDTH: usize;
    /// One lane per child.
    type Lanes: Lanes;
    /// A node over `children` (at most `WIDTH`).
    fn new(children: &[ChildRef]) -> Self;
    /// The `side` (0 lower, 1 upper) planes on `axis` of every child.
    fn planes(&self, side: usize, axis: usize) -> Self::Lanes;
    /// Child `c`'s reference and sphere count (0 for an inner node).
    fn child(&self, c: usize) -> (u32, u8);
    /// Bit c set for each leaf child.
    fn leaves(&self) -> u32;
    /// The node with its inner children's indices moved up by `base`.
    fn shifted(self, base: u32) -> Self;
}

impl RayNode for Node {
    const WIDTH: usize = N;
    type Lanes = wide::f32x4;

    fn new(children: &[ChildRef]) -> Self {
        Node::new(children)
    }
    slot_access!(wide::f32x4);
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
    /// Subtrees entered by at most this many live lanes of a packet are walked one ray at a time
    /// ([`SINGLE_RAY_MAX_LANES`] by default; 0 never switches).
    pub single_ray_lanes: u32,
    /// Test each node's children and each leaf's spheres against a shared-origin packet as a whole (its
    /// frustum, [`packet`]) before their lanes. On by default (docs/perf-log/2026-11.md, "Frustum culling").
    pub frustum_culling: bool,
    /// The largest coordinate magnitude of any box: bounds the frustum test's rounding.
    pub extent: f32,
    /// The padding the spheres' boxes were built with ([`padding`]): the frustum's sphere test pads by it too.
    pub pad: f32,
    /// The same tree in 8-wide nodes for rays walked alone from the root ([`node8`]), when the scene traces
    /// secondary rays.
    pub wide: Option<Vec<WideNode>>,
}

impl Bvh {
    /// Closest hits of the spheres for the live lanes, merged into `best`: one ray at a time for K = 1,
    /// else the packet traversal, which switches to single rays in sparse subtrees.
    pub fn intersect_k<F: Lanes>(&self, q: &SphereQuery<F>, live: F::Mask, best: &mut HitPacket<F>) {
        if F::K == 1 {
            let slab = SlabRay::new(&q.ray);
            return match &self.wide {
                Some(wide) => self.intersect_lanes(wide, 0, q, &slab, live, best),
                None => self.intersect_lanes(&self.nodes, 0, q, &slab, live, best),
            };
        }
        self.intersect_packet(q, live, best)
    }

    /// Lanes of `live` blocked by a sphere within their `t_max`, like [`Bvh::intersect_k`]. `blocker` is set
    /// to a sphere that blocked a lane.
    pub fn occluded_k<F: Lanes>(&self, q: &SphereQuery<F>, live: F::Mask, blocker: &mut u32) -> F::Mask {
        if F::K == 1 {
            let slab = SlabRay::new(&q.ray);
            return match &self.wide {
                Some(wide) => self.occluded_lanes(wide, 0, q, &slab, live, blocker),
                None => self.occluded_lanes(&self.nodes, 0, q, &slab, live, blocker),
            };
        }
        self.occluded_packet(q, live, blocker)
    }
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
/// (the largest coordinate magnitude of any sphere, eye or light); the fused slab test may move a box plane
/// by up to one more ulp of it ([`WIDEN`]). 64 ulps is ample and far below any sphere the scene can resolve.
pub fn padding(reach: f32) -> f32 {
    reach * (64.0 * f32::EPSILON)
}

/// Builds the BVH and reorders `spheres` into its leaf order (their `key` keeps each one's file index), with
/// the 8-wide single-ray tree too when `single_ray_tree` (scenes that trace secondary rays). Returns the BVH
/// and build statistics.
pub fn build(
    spheres: &mut Spheres,
    pad: f32,
    params: BvhBuildParams,
    single_ray_tree: bool,
) -> (Bvh, BuildStats) {
    let start = Instant::now();
    let boxes: Vec<Aabb> = (0..spheres.len())
        .into_par_iter()
        .map(|i| {
            let c = Vec3A::new(spheres.cx[i], spheres.cy[i], spheres.cz[i]);
            let r = Vec3A::splat(spheres.r[i] + pad);
            Aabb { min: c - r, max: c + r }
        })
        .collect();
    let over_piles = piles::has_piles(&boxes);
    let binary = match over_piles {
        true => piles::build_over_piles(&boxes, params),
        false => {
            let bvh2 = binary::build_binary(&boxes, params);
            (bvh2.nodes, bvh2.primitive_indices)
        }
    };
    let trees = |(tree, order): &(Vec<Bvh2Node>, Vec<u32>)| {
        rayon::join(
            || spheres.permuted(order),
            || rayon::join(|| collapse::<Node>(tree), || single_ray_tree.then(|| collapse::<WideNode>(tree))),
        )
    };
    let fits = |(_, need): &(Vec<Node>, usize), wide: &Option<(Vec<WideNode>, usize)>| {
        *need <= STACK && wide.as_ref().is_none_or(|(_, need)| *need <= STACK)
    };
    let (mut permuted, (mut packet_tree, mut wide)) = trees(&binary);
    // Coincident spheres can make obvhs's tree a chain as long as their number: too deep for the traversal
    // stacks (and for the collapse's recursion, which gives up past MAX_COLLAPSE_LEVELS). A pile the sample
    // missed is then built over one box per distinct sphere (unless that was the first build); anything still
    // too deep gets the balanced tree.
    let fallbacks: [&dyn Fn() -> _; 2] = [&|| piles::build_over_piles(&boxes, params), &|| balanced(&boxes)];
    for fallback in fallbacks.into_iter().skip(usize::from(over_piles)) {
        if fits(&packet_tree, &wide) {
            break;
        }
        (permuted, (packet_tree, wide)) = trees(&fallback());
    }
    assert!(
        fits(&packet_tree, &wide),
        "a balanced tree of {} spheres fits the traversal stacks",
        boxes.len()
    );
    let (nodes, wide) = (packet_tree.0, wide.map(|(w, _)| w));
    *spheres = permuted;
    let wide_bytes = wide.as_ref().map_or(0, |w: &Vec<WideNode>| w.len() * size_of::<WideNode>());
    let node_bytes = nodes.len() * size_of::<Node>() + wide_bytes;
    let stats = BuildStats { seconds: start.elapsed().as_secs_f64(), node_bytes };
    let extent = extent(&nodes[0]);
    let single_ray_lanes = SINGLE_RAY_MAX_LANES;
    (Bvh { nodes, single_ray_lanes, frustum_culling: true, extent, pad, wide }, stats)
}

/// The largest coordinate magnitude of the root's occupied child boxes.
fn extent(root: &Node) -> f32 {
    let slots = usize::from(root.slots);
    root.bounds.iter().flatten().flat_map(|axis| axis[..slots].iter()).fold(0.0f32, |m, v| m.max(v.abs()))
}

/// bareray's nodes (4-wide [`Node`] or 8-wide [`WideNode`]) from obvhs's binary tree, in depth-first order,
/// and the stack entries a walk of them may need ([`stack_need`]; `usize::MAX` for a tree deeper than
/// [`MAX_COLLAPSE_LEVELS`], whose nodes are then incomplete). The top [`PARALLEL_LEVELS`] levels flatten their
/// subtrees in parallel; the layout is the serial one ([`flatten`]) node for node.
fn collapse<T: RayNode>(src: &[Bvh2Node]) -> (Vec<T>, usize) {
    if src[0].prim_count > 0 {
        let mut nodes = Vec::with_capacity(1);
        let (leaf, _) = child_ref::<T>(src, 0, &mut nodes, 0);
        nodes.push(T::new(&[leaf]));
        return (nodes, 1);
    }
    flatten_parallel(src, 0, PARALLEL_LEVELS)
}

/// Levels of the collapsed tree past which the collapse gives up (its recursion would risk the thread's
/// stack): far more than any tree whose walks fit [`STACK`] entries, each level holding at least one.
const MAX_COLLAPSE_LEVELS: usize = STACK;

/// The most entries a walk holds on its stack at once in the subtree of a node with `slots` children whose
/// inner children's subtrees need `below` at most: the walk pushes up to `slots` entries, then goes on into
/// one of them with the others still pending.
fn stack_need(slots: usize, below: usize) -> usize {
    slots.saturating_sub(1).saturating_add(below.max(1))
}

/// Spheres per leaf of [`balanced`].
const BALANCED_LEAF: usize = 4;

/// A binary tree over `boxes` in obvhs's layout (nodes, and the primitive order its leaves index), split at
/// the median centre along the widest spread of centres: about log2(n / 4) levels whatever the boxes, for
/// scenes whose obvhs tree is too deep.
fn balanced(boxes: &[Aabb]) -> (Vec<Bvh2Node>, Vec<u32>) {
    let (mut nodes, mut order) = tree_for(boxes.len());
    balanced_into(boxes, 0..boxes.len() as u32, &mut nodes, &mut order, 0);
    (nodes, order)
}

/// [`balanced`] over the boxes `items`, written as the subtree at `nodes[at]`: its nodes appended to
/// `nodes`, its leaves' primitives to `order`. Built without recursion.
fn balanced_into(
    boxes: &[Aabb],
    items: impl IntoIterator<Item = u32>,
    nodes: &mut Vec<Bvh2Node>,
    order: &mut Vec<u32>,
    at: usize,
) {
    let base = order.len();
    order.extend(items);
    let mut pending = vec![(at, base, order.len())];
    while let Some((at, lo, hi)) = pending.pop() {
        let part = &mut order[lo..hi];
        let bounds = part.iter().fold(Aabb::empty(), |b, &i| b.union(&boxes[i as usize]));
        if part.len() <= BALANCED_LEAF {
            nodes[at] = Bvh2Node::new(bounds, part.len() as u32, lo as u32);
            continue;
        }
        let mut centres = Aabb::empty();
        part.iter().for_each(|&i| _ = centres.extend(boxes[i as usize].center()));
        let axis = centres.largest_axis();
        let key = |i: &u32| boxes[*i as usize].center_axis(axis);
        let mid = part.len() / 2;
        part.select_nth_unstable_by(mid, |a, b| key(a).total_cmp(&key(b)));
        let first = nodes.len();
        nodes.extend([unset(); 2]);
        nodes[at] = Bvh2Node::new(bounds, 0, first as u32);
        pending.extend([(first, lo, lo + mid), (first + 1, lo + mid, hi)]);
    }
}

/// A node slot reserved for a node written later (the root, or an inner node's two children).
fn unset() -> Bvh2Node {
    Bvh2Node::new(Aabb::empty(), 0, 0)
}

/// An obvhs-layout tree to be built over `n` boxes: the root's slot, and room for the leaves' order.
fn tree_for(n: usize) -> (Vec<Bvh2Node>, Vec<u32>) {
    (vec![unset()], Vec::with_capacity(n))
}

/// Levels of 4-wide nodes whose subtrees are flattened as parallel jobs (up to 4 + 16 + 64 of them). Done on
/// one thread, the collapse was ~70 ms of a 1e6 build that takes ~0.5 s on 2 threads (docs/perf-log/2026-11.md).
const PARALLEL_LEVELS: u32 = 3;

/// [`flatten`] of obvhs inner node `i` into a vector of its own (the subtree's root first, indices local to
/// it), its inner children's subtrees flattened in parallel for `levels` more levels; with the subtree's
/// stack need.
fn flatten_parallel<T: RayNode>(src: &[Bvh2Node], i: usize, levels: u32) -> (Vec<T>, usize) {
    let mut out = Vec::new();
    if levels == 0 {
        // This node is at level PARALLEL_LEVELS: the root, at 0, was called with PARALLEL_LEVELS levels left.
        let (_, need) = flatten(src, i, &mut out, PARALLEL_LEVELS as usize);
        return (out, need);
    }
    let (open, len) = open_children(src, i, T::WIDTH);
    let subtrees: Vec<Option<(Vec<T>, usize)>> = open[..len]
        .par_iter()
        .map(|&j| (src[j].prim_count == 0).then(|| flatten_parallel(src, j, levels - 1)))
        .collect();
    out.reserve_exact(1 + subtrees.iter().flatten().map(|(nodes, _)| nodes.len()).sum::<usize>());
    out.push(T::new(&[]));
    let (mut children, mut below) = ([EMPTY; MAX_WIDTH], 0);
    for (k, subtree) in subtrees.into_iter().enumerate() {
        children[k] = match subtree {
            None => child_ref(src, open[k], &mut out, 0).0,
            Some((nodes, need)) => {
                below = below.max(need);
                let base = out.len() as u32;
                out.extend(nodes.into_iter().map(|node| node.shifted(base)));
                let aabb = &src[open[k]].aabb;
                ChildRef { lo: aabb.min.to_array(), hi: aabb.max.to_array(), child: base, count: 0 }
            }
        };
    }
    out[0] = T::new(&children[..len]);
    (out, stack_need(len, below))
}

/// The reference to obvhs node `i` from its parent, whose node is at `level` of the collapsed tree: a leaf as
/// it is, an inner node flattened first; with the stack need of what it refers to (0 for a leaf).
fn child_ref<T: RayNode>(src: &[Bvh2Node], i: usize, out: &mut Vec<T>, level: usize) -> (ChildRef, usize) {
    let n = &src[i];
    let (lo, hi) = (n.aabb.min.to_array(), n.aabb.max.to_array());
    if n.prim_count > 0 {
        let count = u8::try_from(n.prim_count).expect("obvhs leaf of more than 255 spheres");
        return (ChildRef { lo, hi, child: n.first_index, count }, 0);
    }
    let (child, need) = flatten(src, i, out, level + 1);
    (ChildRef { lo, hi, child, count: 0 }, need)
}

/// The widest node: the bound of [`RayNode::WIDTH`].
const MAX_WIDTH: usize = WIDE_N;

/// The obvhs nodes that become the children of the `width`-wide node for obvhs inner node `i` (the first
/// `len` of the array): its two children, then repeatedly the inner one of largest surface area (the
/// likeliest to be entered) replaced by its two children, until there are `width`.
fn open_children(src: &[Bvh2Node], i: usize, width: usize) -> ([usize; MAX_WIDTH], usize) {
    let first = src[i].first_index as usize;
    let (mut open, mut len) = ([0; MAX_WIDTH], 2);
    (open[0], open[1]) = (first, first + 1);
    while len < width {
        let area = |j: usize| src[j].aabb.half_area();
        let inner = (0..len).filter(|&k| src[open[k]].prim_count == 0);
        let Some(at) = inner.max_by(|&a, &b| area(open[a]).total_cmp(&area(open[b]))) else { break };
        let grand = src[open[at]].first_index as usize;
        (open[at], open[len]) = (grand, grand + 1);
        len += 1;
    }
    (open, len)
}

/// Appends the subtree of obvhs inner node `i` at `level` of the collapsed tree and returns its node index
/// and stack need ([`open_children`] gives the node's children). Past [`MAX_COLLAPSE_LEVELS`] it appends
/// nothing and returns a need of `usize::MAX`.
fn flatten<T: RayNode>(src: &[Bvh2Node], i: usize, out: &mut Vec<T>, level: usize) -> (u32, usize) {
    if level > MAX_COLLAPSE_LEVELS {
        return (0, usize::MAX);
    }
    let (open, len) = open_children(src, i, T::WIDTH);
    let me = out.len();
    out.push(T::new(&[]));
    let (mut children, mut below) = ([EMPTY; MAX_WIDTH], 0);
    for k in 0..len {
        let need;
        (children[k], need) = child_ref(src, open[k], out, level);
        below = below.max(need);
    }
    out[me] = T::new(&children[..len]);
    (me as u32, stack_need(len, below))
}

/// Exit distances are widened by this factor so rounding never culls a box a ray enters. The fused slab
/// distance `fma(lo, 1/d, −o·(1/d))` (see [`slab_entry`]) is `(lo − o − o·δ)·(1/d)` rounded, |δ| ≤ u = ε/2:
/// the box plane moved by at most u·|o| and then relative errors (the rounded `1/d` and the final rounding),
/// at most γ₂ on every distance. Where |o| ≤ 2·reach the move is at most 2u·reach, inside the boxes'
/// [`padding`]; where |o| > 2·reach every box plane is more than |o|/2 away, so the move is at most a further
/// relative 2u. Entry and exit each err by at most γ₂ + 2u(1 + γ₂) < 4.01u; widening the exit by 6ε = 12u
/// (rounded up, and itself rounded) covers both sides.
const WIDEN: f32 = 1.0 + 6.0 * f32::EPSILON;

/// `1/d` with a zero component replaced by ±1e-30 first, so no slab product is 0·inf = NaN.
#[inline(always)]
fn inverse<F: Lanes>(d: F) -> F {
    let tiny = F::splat_f32(1e-30);
    let away = F::select(d.lt(F::splat_f32(0.0)), -tiny, tiny);
    F::splat_f32(1.0) / F::select(d.abs().lt(tiny), away, d)
}

/// A ray (or a packet of them) prepared for slab tests: `1/d` and `−o·(1/d)`, so each box plane costs one
/// fused multiply-add.
#[derive(Clone, Copy)]
struct SlabRay<F> {
    inv_dir: V3<F>,
    neg_o_inv: V3<F>,
}

impl<F: Lanes> SlabRay<F> {
    #[inline(always)]
    fn new(ray: &Ray<F>) -> Self {
        let (origin, dir) = (&ray.origin, &ray.dir);
        let inv_dir = V3::new(inverse(dir.x), inverse(dir.y), inverse(dir.z));
        let neg = |o: F, inv: F| -(o * inv);
        Self {
            inv_dir,
            neg_o_inv: V3::new(neg(origin.x, inv_dir.x), neg(origin.y, inv_dir.y), neg(origin.z, inv_dir.z)),
        }
    }
}

/// The slab test both traversals run, in either layout: lanes = rays (one box, corners splatted; packet
/// traversal) or lanes = boxes (one ray splatted; single-ray traversal). Returns each lane's entry distance,
/// `inf` where it misses the box or enters beyond `limit`. Conservative by [`WIDEN`] and [`padding`].
#[inline(always)]
fn slab_entry<F: Lanes>(lo: [F; 3], hi: [F; 3], ray: &SlabRay<F>, limit: F) -> F {
    let slab = |lo: F, hi: F, inv: F, neg_o_inv: F| {
        let (t0, t1) = (lo.mul_add(inv, neg_o_inv), hi.mul_add(inv, neg_o_inv));
        (t0.fast_min(t1), t0.fast_max(t1))
    };
    let (i, n) = (&ray.inv_dir, &ray.neg_o_inv);
    let (nx, fx) = slab(lo[0], hi[0], i.x, n.x);
    let (ny, fy) = slab(lo[1], hi[1], i.y, n.y);
    let (nz, fz) = slab(lo[2], hi[2], i.z, n.z);
    entry_within([nx, ny, nz], [fx, fy, fz], limit)
}

/// [`slab_entry`] for rays whose direction signs are known: `near[a]` and `far[a]` are the planes a ray
/// meets first and last on axis a (lower and upper where `1/d` is positive). Fused rounding is monotone, so
/// where `1/d > 0` the lower plane's distance is never above the upper's: the min and max of [`slab_entry`]
/// pick exactly these, and both functions return the same bits — this one in 6 fewer operations.
#[inline(always)]
fn slab_entry_ordered<F: Lanes>(near: [F; 3], far: [F; 3], ray: &SlabRay<F>, limit: F) -> F {
    let (i, n) = (&ray.inv_dir, &ray.neg_o_inv);
    let t = |p: F, inv: F, neg_o_inv: F| p.mul_add(inv, neg_o_inv);
    let (nx, ny, nz) = (t(near[0], i.x, n.x), t(near[1], i.y, n.y), t(near[2], i.z, n.z));
    let (fx, fy, fz) = (t(far[0], i.x, n.x), t(far[1], i.y, n.y), t(far[2], i.z, n.z));
    entry_within([nx, ny, nz], [fx, fy, fz], limit)
}

/// The entry distance from each axis's near and far plane distances: entering before the (widened) exit and
/// before the limit, else `inf`. Balanced trees keep the dependency chains short; entering before the exit
/// and before the limit is one comparison against the smaller of the two.
#[inline(always)]
fn entry_within<F: Lanes>(near: [F; 3], far: [F; 3], limit: F) -> F {
    let entry = near[0].fast_max(near[1]).fast_max(near[2].fast_max(F::splat_f32(0.0)));
    let exit = (far[0].fast_min(far[1]).fast_min(far[2]) * F::splat_f32(WIDEN)).fast_min(limit);
    F::select(entry.le(exit), entry, F::splat_f32(f32::INFINITY))
}

/// Per axis, the side (0 lower, 1 upper) of the plane a ray with this `1/d` meets first: 1 where `1/d` is
/// negative. `inverse` never returns ±0, so the sign is the direction's.
#[inline(always)]
fn near_side(inv: f32) -> usize {
    usize::from(inv < 0.0)
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
    /// Pushes `e` when `keep`, without a branch on `keep`: the entry is written either way and the length
    /// moves by `keep`, so a child entered by an unpredictable set of lanes costs no misprediction.
    #[inline(always)]
    fn push_if(&mut self, e: E, keep: bool) {
        assert!(self.len < STACK, "BVH deeper than the traversal stack");
        self.items[self.len].write(e);
        self.len += usize::from(keep);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// obvhs's binary tree over `n` small cubes spread by a fixed LCG, with leaves of at most `leaf`
    /// boxes: many levels for large `n`, inner nodes with leaf and inner children mixed for small ones.
    fn tree(n: usize, leaf: u32) -> Vec<Bvh2Node> {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let boxes: Vec<Aabb> = (0..n)
            .map(|_| {
                let c = Vec3A::new(next(), next(), next()) * 10.0;
                Aabb { min: c - 0.01, max: c + 0.01 }
            })
            .collect();
        let params = BvhBuildParams { max_prims_per_leaf: leaf, ..BvhBuildParams::fast_build() };
        binary::build_binary(&boxes, params).nodes
    }

    /// Levels of 4-wide nodes from `nodes[i]` down.
    fn depth(nodes: &[Node], i: usize) -> u32 {
        let n = &nodes[i];
        let inner = (0..usize::from(n.slots)).filter(|&c| n.count[c] == 0);
        1 + inner.map(|c| depth(nodes, n.child[c] as usize)).max().unwrap_or(0)
    }

    /// The parallel collapse of `src` into `T` nodes, checked against the serial one.
    fn collapse_both_ways<T: RayNode + PartialEq>(src: &[Bvh2Node]) -> Vec<T> {
        let (parallel, _) = collapse::<T>(src);
        if src[0].prim_count > 0 {
            assert_eq!(parallel.len(), 1, "boxes in one leaf make one node");
            return parallel;
        }
        let mut serial = Vec::new();
        flatten(src, 0, &mut serial, 0);
        assert!(parallel == serial, "{} boxes: the parallel collapse differs from the serial one", src.len());
        serial
    }

    #[test]
    fn parallel_collapse_is_the_serial_layout() {
        for (n, leaf) in [(1, 8), (5, 8), (2, 1), (3, 1), (5, 1), (9, 1), (40, 1), (1000, 2), (30_000, 8)] {
            let src = tree(n, leaf);
            let serial = collapse_both_ways::<Node>(&src);
            collapse_both_ways::<WideNode>(&src);
            if n >= 1000 {
                // Deeper than the parallel levels, so every level of jobs ran.
                assert!(depth(&serial, 0) > PARALLEL_LEVELS + 1, "{n} boxes: depth {}", depth(&serial, 0));
            }
        }
    }
}
