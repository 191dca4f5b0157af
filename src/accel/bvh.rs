//! A binary BVH over the spheres, built by obvhs (PLOC) and flattened into bareray's own node layout: each
//! node holds the boxes of both its children in SoA form (one 64-byte cache line), so a traversal step loads
//! one line, tests both children at once and can order them front to back.
//!
//! obvhs sorts primitives into leaf order (`primitive_indices`); compile reorders the SoA sphere arrays once
//! into that order, so leaves index the arrays directly. Boxes are padded outward by a few ulps so that every
//! hit the sphere kernel reports lies inside its box: traversal then finds exactly the brute-force result.

use std::time::Instant;

use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::BvhBuildParams;

use super::Spheres;

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
    pub count: [u32; 2],
}

impl Node {
    /// A child slot that no ray can enter (an inverted box).
    const EMPTY_BOX: ([f32; 3], [f32; 3]) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);

    fn set_child(&mut self, slot: usize, (lo, hi): ([f32; 3], [f32; 3]), child: u32, count: u32) {
        for axis in 0..3 {
            self.lo[axis][slot] = lo[axis];
            self.hi[axis][slot] = hi[axis];
        }
        self.child[slot] = child;
        self.count[slot] = count;
    }
}

/// The BVH: `nodes[0]` holds the root as its child 0 (child 1 is empty), so traversal has one entry point
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

/// Padded box of sphere `i`: outward by 2^-20 of the coordinates' magnitude, far more than the few ulps of
/// rounding in the kernel's hit decision, far less than any sphere.
fn sphere_box(s: &Spheres, i: usize) -> Aabb {
    let c = Vec3A::new(s.cx[i], s.cy[i], s.cz[i]);
    let r = s.r[i];
    let pad = Vec3A::splat(r) + (c.abs() + Vec3A::splat(r)) * (1.0 / 1_048_576.0);
    Aabb { min: c - pad, max: c + pad }
}

/// Builds the BVH and reorders `spheres` into its leaf order. Returns the BVH, the file index of each
/// reordered sphere, and build statistics.
pub fn build(spheres: &mut Spheres, params: BvhBuildParams) -> (Bvh, Vec<u32>, BuildStats) {
    let start = Instant::now();
    let boxes: Vec<Aabb> = (0..spheres.len()).map(|i| sphere_box(spheres, i)).collect();
    let bvh2 = build_bvh2(&boxes, params, &mut Default::default());
    let order = bvh2.primitive_indices.clone();
    *spheres = spheres.permuted(&order);
    let mut bvh =
        Bvh { nodes: vec![Node { lo: [[0.0; 2]; 3], hi: [[0.0; 2]; 3], child: [0; 2], count: [0; 2] }] };
    let (root_box, root_child, root_count) = flatten(&bvh2.nodes, 0, &mut bvh.nodes);
    bvh.nodes[0].set_child(0, root_box, root_child, root_count);
    bvh.nodes[0].set_child(1, Node::EMPTY_BOX, 0, 0);
    let stats = BuildStats {
        seconds: start.elapsed().as_secs_f64(),
        node_bytes: bvh.nodes.len() * std::mem::size_of::<Node>(),
    };
    (bvh, order, stats)
}

/// Appends the subtree of obvhs node `i` and returns its box and its (child, count) reference.
fn flatten(
    src: &[obvhs::bvh2::node::Bvh2Node],
    i: usize,
    out: &mut Vec<Node>,
) -> (([f32; 3], [f32; 3]), u32, u32) {
    let n = &src[i];
    let bounds = (n.aabb.min.to_array(), n.aabb.max.to_array());
    if n.prim_count > 0 {
        return (bounds, n.first_index, n.prim_count);
    }
    let me = out.len();
    out.push(Node { lo: [[0.0; 2]; 3], hi: [[0.0; 2]; 3], child: [0; 2], count: [0; 2] });
    for slot in 0..2 {
        let (b, child, count) = flatten(src, n.first_index as usize + slot, out);
        out[me].set_child(slot, b, child, count);
    }
    (bounds, me as u32, 0)
}
