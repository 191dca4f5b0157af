//! A binary tree in obvhs's layout (from bareray's builders or obvhs) collapsed into `WIDTH`-wide nodes: each
//! node takes its two children, then opens the inner child of largest surface area until it has `WIDTH`; the
//! top levels are flattened in parallel.

use obvhs::bvh2::node::Bvh2Node;
use rayon::prelude::*;

use super::node::{ChildRef, RayNode, EMPTY};
use super::slab::STACK;
use super::wide_node::WIDE_N;

/// bareray's nodes (4-wide [`Node`](super::node::Node) or 8-wide [`WideNode`](super::wide_node::WideNode))
/// from a binary tree in obvhs's layout, in depth-first order, and the stack entries a walk of them may need
/// ([`stack_need`]; `usize::MAX` for a tree deeper than [`MAX_COLLAPSE_LEVELS`], whose nodes are then
/// incomplete). The top [`PARALLEL_LEVELS`] levels flatten their subtrees in parallel; the layout is the
/// serial one ([`flatten`]) node for node.
pub(super) fn collapse<T: RayNode>(src: &[Bvh2Node]) -> (Vec<T>, usize) {
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
pub(super) const MAX_COLLAPSE_LEVELS: usize = STACK;

/// The most entries a walk holds on its stack at once in the subtree of a node with `slots` children whose
/// inner children's subtrees need `below` at most: the walk pushes up to `slots` entries, then goes on into
/// one of them with the others still pending.
pub(super) fn stack_need(slots: usize, below: usize) -> usize {
    slots.saturating_sub(1).saturating_add(below.max(1))
}

/// Levels of collapsed nodes above the subtrees flattened as parallel jobs (at most 4³ = 64 jobs for 4-wide
/// nodes, 8³ for 8-wide). Done on one thread, the collapse was a serial part of a 1e6 build on 2 threads
/// (docs/perf-log/2026-11.md, "Kept": the collapse runs in parallel).
pub(super) const PARALLEL_LEVELS: u32 = 3;

/// [`flatten`] of obvhs inner node `root`: the whole collapsed tree and its stack need. The top `levels`
/// levels are written first; the subtrees below them are jobs flattened in parallel, each straight into its
/// range of the output, which is allocated once at its final length (each job's nodes counted first). So
/// every node is written once, and no second copy of the tree is held: flattened into vectors of their own
/// and appended level by level, the nodes were copied once per level into fresh memory, and each fresh
/// page's first touch is costly under a hypervisor (docs/perf-log/2026-11-zen3.md, "balls6's load and
/// build").
pub(super) fn flatten_parallel<T: RayNode>(src: &[Bvh2Node], root: usize, levels: u32) -> (Vec<T>, usize) {
    let mut jobs = Vec::new();
    let tops = find_jobs(src, root, levels, T::WIDTH, &mut jobs);
    let level = PARALLEL_LEVELS as usize;
    let sizes: Vec<usize> = jobs.par_iter().map(|&j| count(src, j, T::WIDTH, level)).collect();
    let total = tops + sizes.iter().sum::<usize>();
    let mut out: Vec<T> = Vec::with_capacity(total);
    let slots = &mut out.spare_capacity_mut()[..total];
    let mut tops = Tops { slots, at: 0, sizes: sizes.iter(), bases: Vec::with_capacity(jobs.len()) };
    tops.write(src, root, levels);
    let Tops { slots, at, bases, .. } = tops;
    assert_eq!(at, total, "the top nodes and the jobs' nodes fill the output");
    // The jobs' ranges, in increasing order, cut from the slots between the top nodes.
    let (mut rest, mut cut, mut ranges) = (slots, 0, Vec::with_capacity(jobs.len()));
    for ((&base, &size), &job) in bases.iter().zip(&sizes).zip(&jobs) {
        let (_, tail) = std::mem::take(&mut rest).split_at_mut(base - cut);
        let (mine, tail) = tail.split_at_mut(size);
        (rest, cut) = (tail, base + size);
        ranges.push((InPlace { slots: mine, base, len: 0 }, job));
    }
    let needs: Vec<usize> = ranges
        .into_par_iter()
        .map(|(mut range, job)| {
            let (_, need) = flatten(src, job, &mut range, level);
            assert_eq!(range.len, range.slots.len(), "a job writes the nodes it was counted");
            need
        })
        .collect();
    // SAFETY: every one of the first `total` slots was written: the top nodes at the places `Tops::write`
    // gave them, each job's nodes over its whole range (asserted), and the places and ranges together are
    // the `total` slots (asserted), each handed out once.
    unsafe { out.set_len(total) };
    (out, need(src, root, levels, T::WIDTH, &mut needs.iter()))
}

/// Lists in depth-first order the inner nodes `levels` levels below obvhs inner node `i` (or `i` itself at
/// 0) that the collapse's top nodes refer to; returns the number of top nodes above them.
fn find_jobs(src: &[Bvh2Node], i: usize, levels: u32, width: usize, jobs: &mut Vec<usize>) -> usize {
    if levels == 0 {
        jobs.push(i);
        return 0;
    }
    1 + inner_children(src, i, width).1.map(|j| find_jobs(src, j, levels - 1, width, jobs)).sum::<usize>()
}

/// The stack need of the tree from obvhs inner node `i`, `levels` levels above the jobs, given the jobs'
/// needs in depth-first order: [`stack_need`] as [`flatten`] combines it.
fn need(src: &[Bvh2Node], i: usize, levels: u32, width: usize, jobs: &mut std::slice::Iter<usize>) -> usize {
    if levels == 0 {
        return *jobs.next().expect("a need for every job");
    }
    let (len, inner) = inner_children(src, i, width);
    stack_need(len, inner.map(|j| need(src, j, levels - 1, width, jobs)).max().unwrap_or(0))
}

/// The nodes [`flatten`] writes for obvhs inner node `i` at `level` of the collapsed tree.
fn count(src: &[Bvh2Node], i: usize, width: usize, level: usize) -> usize {
    if level > MAX_COLLAPSE_LEVELS {
        return 0;
    }
    1 + inner_children(src, i, width).1.map(|j| count(src, j, width, level + 1)).sum::<usize>()
}

/// The number of children of the node for obvhs inner node `i` ([`open_children`]) and its inner ones.
fn inner_children(src: &[Bvh2Node], i: usize, width: usize) -> (usize, impl Iterator<Item = usize> + '_) {
    let (open, len) = open_children(src, i, width);
    (len, open.into_iter().take(len).filter(|&j| src[j].prim_count == 0))
}

/// Where the collapse writes nodes: a vector, or a job's range of the output.
pub(super) trait Sink<T> {
    /// The place the next node goes: its index in the whole tree.
    fn next(&self) -> usize;
    /// Writes `node` at [`Sink::next`].
    fn push(&mut self, node: T);
    /// Writes `node` over the one at `place`, written before.
    fn set(&mut self, place: usize, node: T);
}

impl<T> Sink<T> for Vec<T> {
    fn next(&self) -> usize {
        self.len()
    }
    fn push(&mut self, node: T) {
        Vec::push(self, node);
    }
    fn set(&mut self, place: usize, node: T) {
        self[place] = node;
    }
}

/// A job's range of the output: the slots from place `base` on, `len` of them written.
struct InPlace<'a, T> {
    slots: &'a mut [std::mem::MaybeUninit<T>],
    base: usize,
    len: usize,
}

impl<T> Sink<T> for InPlace<'_, T> {
    fn next(&self) -> usize {
        self.base + self.len
    }
    fn push(&mut self, node: T) {
        self.slots[self.len].write(node);
        self.len += 1;
    }
    fn set(&mut self, place: usize, node: T) {
        assert!(place - self.base < self.len, "a node is set after it was pushed");
        self.slots[place - self.base].write(node);
    }
}

/// The output's top levels being written: its slots, the next free place, the jobs' node counts in
/// depth-first order, and the place each job was given.
struct Tops<'a, 'b, T> {
    slots: &'a mut [std::mem::MaybeUninit<T>],
    at: usize,
    sizes: std::slice::Iter<'b, usize>,
    bases: Vec<usize>,
}

impl<T: RayNode> Tops<'_, '_, T> {
    /// Writes the top node for obvhs inner node `i` at the next place, `levels` levels above the jobs, and
    /// the top nodes below it, giving each job its place in depth-first order: the serial layout. Returns
    /// the node's place.
    fn write(&mut self, src: &[Bvh2Node], i: usize, levels: u32) -> u32 {
        let me = self.at;
        if levels == 0 {
            self.bases.push(me);
            self.at += self.sizes.next().expect("a size for every job");
            return me as u32;
        }
        let (open, len) = open_children(src, i, T::WIDTH);
        self.at += 1;
        let mut children = [EMPTY; MAX_WIDTH];
        for (slot, &j) in children.iter_mut().zip(&open[..len]) {
            *slot = match src[j].prim_count {
                0 => reference(&src[j], self.write(src, j, levels - 1), 0),
                _ => leaf_ref(&src[j]),
            };
        }
        self.slots[me].write(T::new(&children[..len]));
        me as u32
    }
}

/// The reference to obvhs node `i` from its parent, whose node is at `level` of the collapsed tree: a leaf as
/// it is, an inner node flattened first; with the stack need of what it refers to (0 for a leaf).
pub(super) fn child_ref<T: RayNode>(
    src: &[Bvh2Node],
    i: usize,
    out: &mut impl Sink<T>,
    level: usize,
) -> (ChildRef, usize) {
    let n = &src[i];
    if n.prim_count > 0 {
        return (leaf_ref(n), 0);
    }
    let (child, need) = flatten(src, i, out, level + 1);
    (reference(n, child, 0), need)
}

/// The reference to obvhs leaf `n`: its items as they are.
fn leaf_ref(n: &Bvh2Node) -> ChildRef {
    reference(n, n.first_index, u8::try_from(n.prim_count).expect("obvhs leaf of more than 255 spheres"))
}

/// The reference to obvhs node `n` with its box, as node `child` (inner) or `count` items from `child`.
fn reference(n: &Bvh2Node, child: u32, count: u8) -> ChildRef {
    ChildRef { lo: n.aabb.min.to_array(), hi: n.aabb.max.to_array(), child, count }
}

/// The widest node: the bound of [`RayNode::WIDTH`].
pub(super) const MAX_WIDTH: usize = WIDE_N;

/// The obvhs nodes that become the children of the `width`-wide node for obvhs inner node `i` (the first
/// `len` of the array): its two children, then repeatedly the inner one of largest surface area (the
/// likeliest to be entered) replaced by its two children, until there are `width`.
pub(super) fn open_children(src: &[Bvh2Node], i: usize, width: usize) -> ([usize; MAX_WIDTH], usize) {
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
pub(super) fn flatten<T: RayNode>(
    src: &[Bvh2Node],
    i: usize,
    out: &mut impl Sink<T>,
    level: usize,
) -> (u32, usize) {
    if level > MAX_COLLAPSE_LEVELS {
        return (0, usize::MAX);
    }
    let (open, len) = open_children(src, i, T::WIDTH);
    let me = out.next();
    out.push(T::new(&[]));
    let (mut children, mut below) = ([EMPTY; MAX_WIDTH], 0);
    for k in 0..len {
        let need;
        (children[k], need) = child_ref(src, open[k], out, level);
        below = below.max(need);
    }
    out.set(me, T::new(&children[..len]));
    (me as u32, stack_need(len, below))
}

#[cfg(test)]
mod tests {
    use super::super::binary;
    use super::super::node::Node;
    use super::super::wide_node::WideNode;
    use super::*;
    use glam::Vec3A;
    use obvhs::aabb::Aabb;
    use obvhs::BvhBuildParams;

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
