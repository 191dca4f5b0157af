//! The f64 twin's own sphere BVH: a binary tree built by median split over the spheres' boxes, walked
//! nearest-first with an explicit stack and an f64 slab test. Independent of the renderer's BVH on
//! purpose, so that a bug there cannot hide in the reference.
//!
//! It returns exactly what brute force over the same spheres returns (t and id, bit for bit): every sphere is
//! tested by the same kernel call, hits are combined by the total order (smaller t, then lower id), and the
//! boxes are padded far beyond the slab test's rounding (below), so no box that holds a hit is ever skipped.

use crate::geometry::{intersect_sphere, Ray};
use crate::math::V3;

use super::hit64::Hit64;

/// Most spheres in a leaf.
const LEAF: usize = 4;

/// Relative padding of every box: `PAD` times (the box's largest extent plus its largest coordinate
/// magnitude). The slab test's rounding is a few f64 units (1.1e-16) of those magnitudes, and the f64 sphere
/// kernel accepts points at most a few units outside the exact sphere; 1e-9 is ten million times both.
const PAD: f64 = 1e-9;

/// A node: an inner node's children are `a` and `b`; a leaf (`count > 0`) holds spheres `a..a + count` of
/// the tree's sphere order.
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: [f64; 3],
    hi: [f64; 3],
    a: u32,
    b: u32,
    count: u32,
}

/// A binary BVH over spheres, with the spheres stored in leaf order.
#[derive(Clone, Debug)]
pub(crate) struct Bvh64 {
    nodes: Vec<Node>,
    /// Sphere centres in leaf order.
    centre: Vec<V3<f64>>,
    /// Radii in leaf order.
    radius: Vec<f64>,
    /// Ids (indices into the list the tree was built from) in leaf order.
    id: Vec<u32>,
}

fn axis(v: V3<f64>, k: usize) -> f64 {
    [v.x, v.y, v.z][k]
}

impl Bvh64 {
    /// Builds the tree over `spheres` (centre, radius), whose ids are their indices. All values must be
    /// finite (the caller falls back to brute force otherwise).
    pub(crate) fn build(spheres: &[(V3<f64>, f64)]) -> Self {
        let mut order: Vec<u32> = (0..spheres.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * spheres.len() / LEAF + 1);
        if !spheres.is_empty() {
            build_range(spheres, &mut order, 0, &mut nodes);
        }
        Self {
            nodes,
            centre: order.iter().map(|&i| spheres[i as usize].0).collect(),
            radius: order.iter().map(|&i| spheres[i as usize].1).collect(),
            id: order,
        }
    }

    /// Merges into `best` the closest hit in `[0, t_max)` of `ray` with every sphere but `skip`, by the total
    /// order (smaller t, then lower id).
    pub(crate) fn closest(&self, ray: &Ray<f64>, skip: u32, t_max: f64, best: &mut Hit64) {
        if self.nodes.is_empty() {
            return;
        }
        let slab = Slab::new(ray);
        let Some(entry) = slab.entry(&self.nodes[0], t_max) else { return };
        // A median-split tree over at most 2^32 spheres is at most 31 levels deep: the stack never holds more
        // than one pending child per level.
        let mut stack = [(0u32, 0.0f64); 64];
        stack[0] = (0, entry);
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let (at, entry) = stack[top];
            // `>`: a box entered exactly at the best t may still hold a tie with a lower id.
            if entry > best.t {
                continue;
            }
            let node = &self.nodes[at as usize];
            if node.count > 0 {
                for j in node.a as usize..(node.a + node.count) as usize {
                    let id = self.id[j];
                    if id == skip {
                        continue;
                    }
                    let (hit, t) = intersect_sphere(self.centre[j], self.radius[j], ray, t_max);
                    if hit {
                        best.update(id, t);
                    }
                }
                continue;
            }
            let ea = slab.entry(&self.nodes[node.a as usize], t_max);
            let eb = slab.entry(&self.nodes[node.b as usize], t_max);
            // Push the farther child first, so the nearer one is popped next.
            let (first, second) = match (ea, eb) {
                (Some(x), Some(y)) if y < x => ((node.a, ea), (node.b, eb)),
                _ => ((node.b, eb), (node.a, ea)),
            };
            for (child, e) in [first, second] {
                if let Some(e) = e {
                    stack[top] = (child, e);
                    top += 1;
                }
            }
        }
    }
}

/// Builds the subtree over `order[lo..]` (the slice given), appending its nodes; returns its root's index.
fn build_range(spheres: &[(V3<f64>, f64)], order: &mut [u32], first: usize, nodes: &mut Vec<Node>) -> u32 {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    let (mut clo, mut chi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for &i in order.iter() {
        let (c, r) = spheres[i as usize];
        for k in 0..3 {
            let x = axis(c, k);
            lo[k] = lo[k].min(x - r);
            hi[k] = hi[k].max(x + r);
            clo[k] = clo[k].min(x);
            chi[k] = chi[k].max(x);
        }
    }
    let extent = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    let magnitude = (0..3).map(|k| lo[k].abs().max(hi[k].abs())).fold(0.0, f64::max);
    let pad = PAD * (extent + magnitude);
    for k in 0..3 {
        lo[k] -= pad;
        hi[k] += pad;
    }
    let at = nodes.len() as u32;
    nodes.push(Node { lo, hi, a: first as u32, b: 0, count: order.len() as u32 });
    if order.len() <= LEAF {
        return at;
    }
    // Median split of the centres along their widest axis: balanced whatever the distribution, duplicates
    // included, so the depth is log2(n / LEAF).
    let k = (0..3).max_by(|&a, &b| (chi[a] - clo[a]).total_cmp(&(chi[b] - clo[b]))).unwrap_or(0);
    let mid = order.len() / 2;
    order.select_nth_unstable_by(mid, |&a, &b| {
        axis(spheres[a as usize].0, k).total_cmp(&axis(spheres[b as usize].0, k))
    });
    let (left, right) = order.split_at_mut(mid);
    let a = build_range(spheres, left, first, nodes);
    let b = build_range(spheres, right, first + mid, nodes);
    nodes[at as usize] = Node { lo, hi, a, b, count: 0 };
    at
}

/// A ray prepared for slab tests.
struct Slab {
    origin: [f64; 3],
    dir: [f64; 3],
    inv: [f64; 3],
}

impl Slab {
    fn new(ray: &Ray<f64>) -> Self {
        let dir = [ray.dir.x, ray.dir.y, ray.dir.z];
        Self { origin: [ray.origin.x, ray.origin.y, ray.origin.z], dir, inv: dir.map(|d| 1.0 / d) }
    }

    /// Where the ray enters the box (clamped to 0) if it meets it within `[0, t_max]`.
    #[inline]
    fn entry(&self, node: &Node, t_max: f64) -> Option<f64> {
        let (mut near, mut far) = (0.0f64, t_max);
        for k in 0..3 {
            let o = self.origin[k];
            if self.dir[k] == 0.0 {
                // Parallel to the slab: inside it or never.
                if o < node.lo[k] || o > node.hi[k] {
                    return None;
                }
                continue;
            }
            let (a, b) = ((node.lo[k] - o) * self.inv[k], (node.hi[k] - o) * self.inv[k]);
            let (a, b) = if a <= b { (a, b) } else { (b, a) };
            near = near.max(a);
            far = far.min(b);
        }
        // f64::max and min ignore a NaN operand, so a NaN ray enters every box: conservative, and the kernel
        // then misses.
        (near <= far).then_some(near)
    }
}
