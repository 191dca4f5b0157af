//! The binary tree from obvhs: its PLOC build, reinsertion and leaf collapse, in the order of obvhs's
//! `build_bvh2` helper, with the builder's largest buffer written in parallel before the build.
//!
//! obvhs sizes the tree's node array (2n − 1 nodes of 48 bytes: 96 MB for a million spheres) with a serial
//! `resize` on the calling thread. Its first touch is page faults, and under a hypervisor a fresh page costs
//! far more than the write: that `resize` showed in a 1e6-sphere bench's profile as the kernel's
//! `clear_page`, all of it on one core while the other waited (docs/perf-log/2026-11.md, "The 1e6
//! build: page faults on one core"). Handing obvhs an array already of that length, first touched by all
//! threads, leaves its `resize` nothing to do.

use obvhs::aabb::Aabb;
use obvhs::bvh2::leaf_collapser::collapse;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::bvh2::Bvh2;
use obvhs::ploc::PlocBuilder;
use obvhs::BvhBuildParams;
use rayon::prelude::*;

/// obvhs's binary BVH over `boxes` with `params`: the tree its `build_bvh2` builds, node for node.
pub(super) fn build_binary(boxes: &[Aabb], params: BvhBuildParams) -> Bvh2 {
    let n = boxes.len();
    let mut bvh = Bvh2 {
        nodes: (0..(2 * n).saturating_sub(1)).into_par_iter().map(|_| Bvh2Node::default()).collect(),
        ..Bvh2::default()
    };
    let indices = (0..n as u32).into_par_iter().collect();
    PlocBuilder::with_capacity(n).build_with_bvh(
        &mut bvh,
        params.ploc_search_distance,
        boxes,
        indices,
        params.sort_precision,
        params.search_depth_threshold,
    );
    let mut reinsertion = ReinsertionOptimizer::default();
    reinsertion.run(&mut bvh, params.reinsertion_batch_ratio, None);
    collapse(&mut bvh, params.max_prims_per_leaf.clamp(1, 255), params.collapse_traversal_cost);
    let after_collapse =
        params.reinsertion_batch_ratio * params.post_collapse_reinsertion_batch_ratio_multiplier;
    reinsertion.run(&mut bvh, after_collapse, None);
    bvh
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::SplitMix64;
    use glam::Vec3A;

    /// The same tree as obvhs's own helper, for every preset bareray offers, on clustered boxes of several
    /// sizes (coincident ones included).
    #[test]
    fn builds_the_tree_obvhs_builds() {
        let mut rng = SplitMix64::new(7);
        let mut next = move || rng.unit() as f32;
        let boxes: Vec<Aabb> = (0..3000)
            .map(|i| {
                let c = if i % 7 == 0 { Vec3A::ONE } else { Vec3A::new(next(), next(), next()) * 10.0 };
                let r = 0.01 + next() * 0.5;
                Aabb { min: c - r, max: c + r }
            })
            .collect();
        let presets = [
            BvhBuildParams::fastest_build(),
            BvhBuildParams::very_fast_build(),
            BvhBuildParams::fast_build(),
            BvhBuildParams::medium_build(),
            BvhBuildParams::slow_build(),
        ];
        for (k, params) in presets.into_iter().enumerate() {
            for n in [1, 2, 3, 100, boxes.len()] {
                let ours = build_binary(&boxes[..n], params);
                let theirs = obvhs::bvh2::builder::build_bvh2(&boxes[..n], params, &mut Default::default());
                let fields = |b: &Bvh2| -> Vec<_> {
                    let node = |v: &Bvh2Node| {
                        (v.aabb.min.to_array(), v.aabb.max.to_array(), v.prim_count, v.first_index)
                    };
                    b.nodes.iter().map(node).collect()
                };
                assert_eq!(fields(&ours), fields(&theirs), "preset {k}, {n} boxes");
                assert_eq!(ours.primitive_indices, theirs.primitive_indices, "preset {k}, {n} boxes");
            }
        }
    }
}
