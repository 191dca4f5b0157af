//! A binary BVH over the spheres, built by obvhs (PLOC) and flattened into bareray's own node layout: each
//! node holds the boxes of both its children in SoA form (one 64-byte cache line), so a traversal step loads
//! one line, tests both children at once and visits the nearer one first.
//!
//! obvhs sorts primitives into leaf order (`primitive_indices`); compile reorders the SoA sphere arrays once
//! into that order, so leaves index the arrays directly.
//!
//! Traversal is generic over the lane type: a packet of K rays walks the tree together (a node is entered
//! when any live lane's slab test passes; each stack entry keeps its lanes' entry distances, `inf` for lanes
//! that missed it), and K = 1 is the single-ray traversal. Culling is conservative: boxes are padded by a
//! bound on the sphere kernel's rounding error, and the slab test widens its exit distance by 2γ₃ (Ize 2013).
//! Together with the (t, id) order of [`HitPacket::update`] this makes every lane's result equal, bit for bit,
//! to brute force over the same spheres, whatever order the nodes are visited in.

use std::time::Instant;

use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::BvhBuildParams;

use super::brute::{spheres_intersect_k, spheres_occluded_k};
use super::Spheres;
use crate::geometry::{HitPacket, Ray};
use crate::math::{Mask, V3};
use crate::simd::Lanes;

/// One node: the boxes of its two children and where each child's content is.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Node {
    /// Lower corner per axis (x, y, z), per child (0, 1).
    pub lo: [[f32; 2]; 3],
    /// Upper corner per axis, per child.
    pub hi: [[f32; 2]; 3],
    /// Inner child: index of its node; leaf child: index of its first sphere.
    pub child: [u32; 2],
    /// Number of spheres of a leaf child; 0 for an inner child.
    pub count: [u16; 2],
    /// The axis along which child 0 lies before child 1 (by centroid): rays going toward −axis visit child 1
    /// first.
    pub axis: u32,
}

/// A child slot's box and content, while flattening.
#[derive(Clone, Copy)]
struct ChildRef {
    lo: [f32; 3],
    hi: [f32; 3],
    child: u32,
    count: u16,
}

/// A slot no ray can enter: a box at +inf, whose slab distances are +inf or −inf, never a finite entry. (An
/// inverted box, lo = +inf and hi = −inf, would give every slab (−inf, +inf) and be entered by every ray.)
const EMPTY: ChildRef = ChildRef { lo: [f32::INFINITY; 3], hi: [f32::INFINITY; 3], child: 0, count: 0 };

impl Node {
    fn new(c0: ChildRef, c1: ChildRef) -> Node {
        let centre = |c: &ChildRef, a: usize| c.lo[a] + c.hi[a];
        let axis = (0..3)
            .max_by(|&a, &b| {
                let (da, db) =
                    ((centre(&c1, a) - centre(&c0, a)).abs(), (centre(&c1, b) - centre(&c0, b)).abs());
                da.partial_cmp(&db).unwrap_or(std::cmp::Ordering::Equal)
            })
            .unwrap_or(0);
        let (a, b) = if centre(&c1, axis) < centre(&c0, axis) { (c1, c0) } else { (c0, c1) };
        Node {
            lo: std::array::from_fn(|k| [a.lo[k], b.lo[k]]),
            hi: std::array::from_fn(|k| [a.hi[k], b.hi[k]]),
            child: [a.child, b.child],
            count: [a.count, b.count],
            axis: axis as u32,
        }
    }
}

/// The BVH: `nodes[0]` holds the root as a child (its other slot empty), so traversal has one entry point
/// whether the root is a leaf or not.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    /// Flattened nodes, depth-first, the first child right after its parent.
    pub nodes: Vec<Node>,
}

/// What building cost.
#[derive(Clone, Copy, Debug, Default)]
pub struct BuildStats {
    /// Seconds in obvhs plus flattening and reordering.
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

/// Builds the BVH and reorders `spheres` into its leaf order. Returns the BVH, the file index of each
/// reordered sphere, and build statistics.
pub fn build(spheres: &mut Spheres, pad: f32, params: BvhBuildParams) -> (Bvh, Vec<u32>, BuildStats) {
    let start = Instant::now();
    let boxes: Vec<Aabb> = (0..spheres.len())
        .map(|i| {
            let c = Vec3A::new(spheres.cx[i], spheres.cy[i], spheres.cz[i]);
            let r = Vec3A::splat(spheres.r[i] + pad);
            Aabb { min: c - r, max: c + r }
        })
        .collect();
    let bvh2 = build_bvh2(&boxes, params, &mut Default::default());
    let order = bvh2.primitive_indices.clone();
    *spheres = spheres.permuted(&order);
    let mut nodes = vec![Node::new(EMPTY, EMPTY)];
    let root = flatten(&bvh2.nodes, 0, &mut nodes);
    nodes[0] = Node::new(root, EMPTY);
    let stats =
        BuildStats { seconds: start.elapsed().as_secs_f64(), node_bytes: nodes.len() * size_of::<Node>() };
    (Bvh { nodes }, order, stats)
}

/// Appends the subtree of obvhs node `i` and returns the reference to it.
fn flatten(src: &[Bvh2Node], i: usize, out: &mut Vec<Node>) -> ChildRef {
    let n = &src[i];
    let (lo, hi) = (n.aabb.min.to_array(), n.aabb.max.to_array());
    if n.prim_count > 0 {
        return ChildRef { lo, hi, child: n.first_index, count: n.prim_count as u16 };
    }
    let me = out.len();
    out.push(Node::new(EMPTY, EMPTY));
    let c0 = flatten(src, n.first_index as usize, out);
    let c1 = flatten(src, n.first_index as usize + 1, out);
    out[me] = Node::new(c0, c1);
    ChildRef { lo, hi, child: me as u32, count: 0 }
}

/// Deep enough for any tree obvhs builds over 2^32 primitives with its leaf collapsing; checked on push.
const STACK: usize = 128;

/// A ray packet prepared for slab tests.
struct SlabRays<F: Lanes> {
    origin: V3<F>,
    inv_dir: V3<F>,
    /// Visit child 1 first along each axis (from the first live lane's direction).
    flip: [bool; 3],
}

impl<F: Lanes> SlabRays<F> {
    fn new(ray: &Ray<F>, live: F::Mask) -> Self {
        // A zero component becomes ±1e-30 so no slab product is 0·inf = NaN.
        let tiny = F::splat_f32(1e-30);
        let inv = |d: F| {
            let away = F::select(d.lt(F::splat_f32(0.0)), -tiny, tiny);
            F::splat_f32(1.0) / F::select(d.abs().lt(tiny), away, d)
        };
        let first = F::move_mask(live).trailing_zeros() as usize;
        let lane = first.min(F::K - 1);
        Self {
            origin: ray.origin,
            inv_dir: V3::new(inv(ray.dir.x), inv(ray.dir.y), inv(ray.dir.z)),
            flip: [ray.dir.x.lane(lane) < 0.0, ray.dir.y.lane(lane) < 0.0, ray.dir.z.lane(lane) < 0.0],
        }
    }

    /// Entry distance of each lane into child `c` of `n`, `inf` where the lane misses it or enters beyond
    /// `limit`.
    #[inline(always)]
    fn enter(&self, n: &Node, c: usize, limit: F) -> F {
        let slab = |lo: f32, hi: f32, o: F, inv: F| {
            let t0 = (F::splat_f32(lo) - o) * inv;
            let t1 = (F::splat_f32(hi) - o) * inv;
            (t0.fast_min(t1), t0.fast_max(t1))
        };
        let (nx, fx) = slab(n.lo[0][c], n.hi[0][c], self.origin.x, self.inv_dir.x);
        let (ny, fy) = slab(n.lo[1][c], n.hi[1][c], self.origin.y, self.inv_dir.y);
        let (nz, fz) = slab(n.lo[2][c], n.hi[2][c], self.origin.z, self.inv_dir.z);
        let near = nx.fast_max(F::splat_f32(0.0)).fast_max(ny).fast_max(nz);
        let far = fx.fast_min(fy).fast_min(fz) * F::splat_f32(1.0 + 4.0 * f32::EPSILON);
        let inside = near.le(far) & near.le(limit);
        F::select(inside, near, F::splat_f32(f32::INFINITY))
    }
}

/// A pending subtree: its reference and each lane's entry distance.
#[derive(Clone, Copy)]
struct Entry<F: Lanes> {
    child: u32,
    count: u16,
    near: F,
}

/// A fixed-capacity traversal stack on the call stack (a heap vector per packet costs more than a small
/// BVH's whole traversal).
struct Stack<F: Lanes> {
    items: [std::mem::MaybeUninit<Entry<F>>; STACK],
    len: usize,
}

impl<F: Lanes> Stack<F> {
    #[inline(always)]
    fn new() -> Self {
        Self { items: [const { std::mem::MaybeUninit::uninit() }; STACK], len: 0 }
    }
    #[inline(always)]
    fn push(&mut self, e: Entry<F>) {
        assert!(self.len < STACK, "BVH deeper than the traversal stack");
        self.items[self.len].write(e);
        self.len += 1;
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<Entry<F>> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: entries below `len` were written by `push` and are plain `Copy` data.
        Some(unsafe { self.items[self.len].assume_init() })
    }
}

impl Bvh {
    /// Pushes the two children of `n` that some lane enters, the nearer last so it is popped first.
    #[inline(always)]
    fn push_children<F: Lanes>(&self, n: &Node, rays: &SlabRays<F>, limit: F, stack: &mut Stack<F>) {
        let first = usize::from(rays.flip[n.axis as usize]);
        for c in [1 - first, first] {
            let near = rays.enter(n, c, limit);
            if near.lt(F::splat_f32(f32::INFINITY)).any() {
                stack.push(Entry { child: n.child[c], count: n.count[c], near });
            }
        }
    }

    /// Closest hits of the spheres for the live lanes, merged into `best`.
    pub fn intersect_k<F: Lanes>(
        &self,
        s: &Spheres,
        ray: &Ray<F>,
        t_max: F,
        live: F::Mask,
        skip: F::Ids,
        best: &mut HitPacket<F>,
    ) {
        let rays = SlabRays::new(ray, live);
        let mut stack = Stack::<F>::new();
        let limit =
            |best: &HitPacket<F>| F::select(live, best.t.min_of(t_max), F::splat_f32(f32::NEG_INFINITY));
        self.push_children(&self.nodes[0], &rays, limit(best), &mut stack);
        // Counted locally and reported once per packet: a shared counter per node costs measurably.
        let (mut nodes, mut tests) = (1, 0);
        while let Some(e) = stack.pop() {
            // Lanes that entered this subtree no farther than their best hit so far.
            let lanes = e.near.le(best.t) & live;
            if !lanes.any() {
                continue;
            }
            if e.count > 0 {
                let first = e.child as usize;
                tests += usize::from(e.count);
                spheres_intersect_k(s, first..first + usize::from(e.count), ray, t_max, lanes, skip, best);
            } else {
                nodes += 1;
                let lim = F::select(lanes, best.t.min_of(t_max), F::splat_f32(f32::NEG_INFINITY));
                self.push_children(&self.nodes[e.child as usize], &rays, lim, &mut stack);
            }
        }
        super::count_work(tests, 2 * nodes);
    }

    /// Lanes of `live` blocked by a sphere within their `t_max`; stops as soon as every live lane is.
    pub fn occluded_k<F: Lanes>(
        &self,
        s: &Spheres,
        ray: &Ray<F>,
        t_max: F,
        live: F::Mask,
        skip: F::Ids,
    ) -> F::Mask {
        let rays = SlabRays::new(ray, live);
        let mut stack = Stack::<F>::new();
        let mut blocked = F::mask_from_bits(0);
        let limit = F::select(live, t_max, F::splat_f32(f32::NEG_INFINITY));
        self.push_children(&self.nodes[0], &rays, limit, &mut stack);
        let (mut nodes, mut tests) = (1, 0);
        while let Some(e) = stack.pop() {
            let lanes = e.near.lt(F::splat_f32(f32::INFINITY)) & live & !blocked;
            if !lanes.any() {
                continue;
            }
            if e.count > 0 {
                let first = e.child as usize;
                tests += usize::from(e.count);
                blocked = blocked
                    | spheres_occluded_k(s, first..first + usize::from(e.count), ray, t_max, lanes, skip);
                if (blocked | !live).all() {
                    break;
                }
            } else {
                nodes += 1;
                let lim = F::select(lanes, t_max, F::splat_f32(f32::NEG_INFINITY));
                self.push_children(&self.nodes[e.child as usize], &rays, lim, &mut stack);
            }
        }
        super::count_work(tests, 2 * nodes);
        blocked
    }
}
