//! The single-ray tree: the same binary tree collapsed into 8-wide nodes, so one `f32x8` slab test covers a
//! node's children (one AVX2 register) and a ray walks about half as many levels as in the 4-wide tree.
//! Built beside the 4-wide packet tree only for scenes that trace secondary rays (shadow, mirror or
//! transmitted, ambient occlusion), whose lanes the K = 1 tracer walks one ray at a time, as do the lanes of
//! a packet in a subtree it enters with few of them ([`super::wide_starts`]).

use wide::f32x8;

use super::node::{leaf_bits, slot_access, slots, ChildRef, RayNode};

/// Children per node of the single-ray tree (its N).
pub(crate) const WIDE_N: usize = 8;

/// One node of the single-ray tree: the boxes of up to [`WIDE_N`] children and where each one's content is.
/// Occupied slots come first; empty ones hold a box at +inf, which no ray enters.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct WideNode {
    /// `bounds[0]` the lower corner, `bounds[1]` the upper, per axis, per child.
    pub(crate) bounds: [[[f32; WIDE_N]; 3]; 2],
    /// Inner child: index of its node; leaf child: index of its first sphere.
    pub(crate) child: [u32; WIDE_N],
    /// Number of spheres of a leaf child; 0 for an inner child.
    pub(crate) count: [u8; WIDE_N],
    /// Occupied slots.
    pub(crate) slots: u8,
    /// Bit c set where slot c is a leaf.
    pub(crate) leaves: u8,
}

const _: () = assert!(size_of::<WideNode>() == 256, "a wide node is four cache lines");

impl RayNode for WideNode {
    const WIDTH: usize = WIDE_N;
    type Lanes = f32x8;

    fn new(children: &[ChildRef]) -> Self {
        let (bounds, child, count) = slots::<WIDE_N>(children);
        WideNode { bounds, child, count, slots: children.len() as u8, leaves: leaf_bits(&count) }
    }

    slot_access!(f32x8);
}
