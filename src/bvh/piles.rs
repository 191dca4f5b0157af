//! Piles of coincident spheres. obvhs's PLOC merges equal boxes about one pair per pass, so a pile of p
//! copies of one sphere costs about p passes over the whole scene (build times: docs/perf-log/2026-11.md,
//! "Kept": piles). A scene with a large pile is built over one box per distinct sphere, and the
//! copies then hang under their box's leaf as a balanced subtree.

use obvhs::aabb::Aabb;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::BvhBuildParams;
use rayon::prelude::*;

use super::median::{balanced_into, tree_for, unset};

/// Spheres sampled to look for piles.
const SAMPLE: usize = 4096;

/// The PLOC work (estimated pile size × spheres) from which the build goes over piles: about a sixth of that
/// of 5000 copies of one sphere (2.5e7), whose build time is in docs/perf-log/2026-11.md
/// ("Kept": piles).
const PILE_WORK: usize = 1 << 22;

/// The bits of a box: equal for copies of one sphere.
fn key(b: &Aabb) -> [u32; 6] {
    let (lo, hi) = (b.min.to_array(), b.max.to_array());
    [lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]].map(f32::to_bits)
}

/// Whether `boxes` hold a pile large enough to slow obvhs down, judged from an even sample (all of them
/// when there are few): the most copies of one box in it, scaled to the whole scene.
pub(super) fn has_piles(boxes: &[Aabb]) -> bool {
    let stride = boxes.len().div_ceil(SAMPLE).max(1);
    let mut sample: Vec<[u32; 6]> = boxes.iter().step_by(stride).map(key).collect();
    sample.sort_unstable();
    let most = sample.chunk_by(|a, b| a == b).map(<[_]>::len).max().unwrap_or(0);
    most >= 2 && (most * stride).saturating_mul(boxes.len()) >= PILE_WORK
}

/// A binary tree over `boxes` in obvhs's layout (nodes, and the order its leaves index): obvhs's over one
/// box per distinct box, then each leaf's copies as a balanced subtree under it.
pub(super) fn build_over_piles(boxes: &[Aabb], params: BvhBuildParams) -> (Vec<Bvh2Node>, Vec<u32>) {
    let mut by_key: Vec<([u32; 6], u32)> =
        boxes.par_iter().enumerate().map(|(i, b)| (key(b), i as u32)).collect();
    by_key.par_sort_unstable();
    // Distinct box g holds the copies members[start[g]..start[g + 1]].
    let mut start: Vec<usize> =
        (0..by_key.len()).filter(|&i| i == 0 || by_key[i].0 != by_key[i - 1].0).collect();
    let distinct: Vec<Aabb> = start.iter().map(|&i| boxes[by_key[i].1 as usize]).collect();
    start.push(by_key.len());
    let members: Vec<u32> = by_key.into_iter().map(|(_, i)| i).collect();
    let copies = |g: u32| members[start[g as usize]..start[g as usize + 1]].iter().copied();
    let bvh2 = super::binary::build_binary(&distinct, params);
    let (mut nodes, mut order) = tree_for(boxes.len());
    // (obvhs node, its slot in `nodes`), walked without recursion.
    let mut pending = vec![(0usize, 0usize)];
    while let Some((i, at)) = pending.pop() {
        let n = &bvh2.nodes[i];
        if n.prim_count == 0 {
            let first = nodes.len();
            nodes.extend([unset(); 2]);
            nodes[at] = Bvh2Node::new(n.aabb, 0, first as u32);
            let child = n.first_index as usize;
            pending.extend([(child, first), (child + 1, first + 1)]);
        } else {
            let leaf = &bvh2.primitive_indices[n.first_index as usize..][..n.prim_count as usize];
            balanced_into(boxes, leaf.iter().flat_map(|&g| copies(g)), &mut nodes, &mut order, at);
        }
    }
    (nodes, order)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;

    fn ball(x: f32, r: f32) -> Aabb {
        Aabb { min: Vec3A::new(x - r, -r, -r), max: Vec3A::new(x + r, r, r) }
    }

    #[test]
    fn piles_are_found_and_every_copy_lands_in_one_leaf_inside_its_box() {
        let spread: Vec<Aabb> = (0..3000).map(|i| ball(i as f32 * 0.01, 0.004)).collect();
        assert!(!has_piles(&spread));
        let mut piled = spread.clone();
        piled.extend(std::iter::repeat_n(ball(7.5, 0.2), 5000));
        assert!(has_piles(&piled));
        let (nodes, order) = build_over_piles(&piled, BvhBuildParams::fast_build());
        let mut seen = vec![0u32; piled.len()];
        let mut pending = vec![0usize];
        while let Some(i) = pending.pop() {
            let n = &nodes[i];
            let first = n.first_index as usize;
            if n.prim_count == 0 {
                pending.extend([first, first + 1]);
                continue;
            }
            assert!(n.prim_count as usize <= super::super::median::BALANCED_LEAF);
            for &p in &order[first..first + n.prim_count as usize] {
                seen[p as usize] += 1;
                let b = &piled[p as usize];
                assert!(
                    n.aabb.min.cmple(b.min).all() && b.max.cmple(n.aabb.max).all(),
                    "sphere {p} outside its leaf"
                );
            }
        }
        assert!(seen.iter().all(|&k| k == 1), "every sphere exactly once");
    }
}
