//! Building a tree: a binary tree over the item boxes, bareray's binned SAH or Morton order, or obvhs's PLOC (with the
//! fallbacks for piles of equal boxes and for trees too deep to walk), collapsed into the 4-wide packet nodes
//! and, when asked, the 8-wide single-ray nodes; the binary tree itself is kept for the scalar walk when asked.

use std::sync::OnceLock;
use std::time::Instant;

use obvhs::aabb::Aabb;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::BvhBuildParams;
use rayon::prelude::*;

use super::collapse::collapse;
use super::median::balanced;
use super::node::Node;
use super::scalar::{pair_tree, PairNode};
use super::slab::STACK;
use super::upward::Upward;
use super::wide_node::WideNode;
use super::wide_starts::WideStarts;
use super::{binary, morton, piles, sah, BuildStats, Bvh};

/// Which builder makes the binary tree that is collapsed into the wide nodes.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Builder {
    /// bareray's binned SAH (`sah.rs`): the least memory and the quickest build. A binary node costs
    /// `node_cost` tests of the kind's items: ranges of up to 8 items stay one leaf where testing them costs
    /// less than the split.
    Sah {
        /// The cost of a binary node, in item tests.
        node_cost: f32,
    },
    /// Items sorted by the Morton code of their centres, ranges of more than [`morton::SAH_BELOW`] items
    /// split where the code's highest differing bit changes, smaller ones as [`Builder::Sah`] splits them
    /// (`morton.rs`).
    Morton {
        /// The cost of a binary node in the SAH's ranges, in item tests.
        node_cost: f32,
    },
    /// obvhs's PLOC with these settings.
    Obvhs(BvhBuildParams),
}

impl Builder {
    /// The SAH builder for spheres. Measured on the contract fields and balls4: 1 makes leaves of about one
    /// sphere and traces the 1e6 field slower, 4 to 8 trace alike, 12 is slower again
    /// (docs/perf-log/2026-11-own-builder.md, "Node cost and leaves").
    pub(crate) const SAH_SPHERES: Builder = Builder::Sah { node_cost: 6.0 };
    /// The Morton-order builder for spheres, with [`Builder::SAH_SPHERES`]'s node cost below.
    pub(crate) const MORTON_SPHERES: Builder = Builder::Morton { node_cost: 6.0 };
    /// The SAH builder for items dearer to test than spheres (triangles, ellipsoids, cones): cones.toml and
    /// SPD's teapot traced faster with 1 than with 6 (docs/perf-log/2026-11-own-builder.md, "Node cost for
    /// the other kinds").
    pub(crate) const SAH_DEARER_ITEMS: Builder = Builder::Sah { node_cost: 1.0 };

    /// The builder for items dearer to test than spheres: [`Builder::SAH_DEARER_ITEMS`] in place of
    /// bareray's builders (the Morton order's shorter build is measured on sphere fields only), obvhs's
    /// presets as they are.
    pub(crate) fn for_dearer_items(self) -> Builder {
        match self {
            Builder::Sah { .. } | Builder::Morton { .. } => Builder::SAH_DEARER_ITEMS,
            obvhs => obvhs,
        }
    }
}

/// How to build a tree.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BuildOptions {
    /// The padding the item boxes carry ([`super::padding`]), kept for the packet walk's frustum test of single items.
    pub(crate) pad: f32,
    /// The binary tree's builder.
    pub(crate) builder: Builder,
    /// Whether to build the 8-wide single-ray tree too (scenes that trace secondary rays).
    pub(crate) single_ray_tree: bool,
    /// Whether to link the trees' nodes to their parents and the items to their leaves ([`Bvh::up`]) when the
    /// single-ray tree is built: for kinds whose queries name the item a ray leaves (spheres).
    pub(crate) leaf_links: bool,
    /// Whether to keep the binary tree for the scalar walk ([`Bvh::scalar`]) and have single rays walk it
    /// ([`Bvh::scalar_walk`]).
    pub(crate) scalar_tree: bool,
    /// [`Bvh::frustum_culling`].
    pub(crate) frustum_culling: bool,
    /// [`Bvh::single_ray_lanes`].
    pub(crate) single_ray_lanes: u32,
}

/// Builds the tree over `n` items whose padded boxes `item_box` gives, and returns it with `permute(order)`
/// (run in parallel with the collapse): `order[j]` is the item stored at position `j` of the leaf order, in
/// which the owner must store its items, since leaves index them by position. Also the build statistics.
pub(crate) fn build<T: Send>(
    n: usize,
    item_box: impl Fn(usize) -> Aabb + Sync + Send,
    options: BuildOptions,
    permute: impl Fn(&[u32]) -> T + Sync,
) -> (Bvh, T, BuildStats) {
    let BuildOptions {
        pad,
        builder,
        single_ray_tree,
        leaf_links,
        scalar_tree,
        frustum_culling,
        single_ray_lanes,
    } = options;
    let start = Instant::now();
    // The item boxes as one array: obvhs's input, and the fallbacks'. The SAH builder keeps its own copy.
    let boxes = OnceLock::new();
    let boxes = || boxes.get_or_init(|| (0..n).into_par_iter().map(&item_box).collect::<Vec<Aabb>>());
    let (binary, fallbacks): (_, &[Fallback]) = match builder {
        Builder::Sah { node_cost } => (sah::build_sah(n, &item_box, node_cost), &[Fallback::Balanced]),
        Builder::Morton { node_cost } => {
            (morton::build_morton(n, &item_box, node_cost), &[Fallback::Balanced])
        }
        Builder::Obvhs(params) if piles::has_piles(boxes()) => {
            (piles::build_over_piles(boxes(), params), &[Fallback::Balanced])
        }
        Builder::Obvhs(params) => {
            let bvh2 = binary::build_binary(boxes(), params);
            ((bvh2.nodes, bvh2.primitive_indices), &[Fallback::Piles(params), Fallback::Balanced])
        }
    };
    let trees = |(tree, order): &(Vec<Bvh2Node>, Vec<u32>)| {
        let single = || {
            rayon::join(
                || single_ray_tree.then(|| collapse::<WideNode>(tree)),
                || scalar_tree.then(|| pair_tree(tree)),
            )
        };
        rayon::join(|| permute(order), || rayon::join(|| collapse::<Node>(tree), single))
    };
    type Single = (Option<(Vec<WideNode>, usize)>, Option<(Vec<PairNode>, usize)>);
    let fits = |(_, need): &(Vec<Node>, usize), (wide, scalar): &Single| {
        *need <= STACK
            && wide.as_ref().is_none_or(|(_, need)| *need <= STACK)
            && scalar.as_ref().is_none_or(|(_, need)| *need <= STACK)
    };
    let (mut permuted, (mut packet_tree, mut single)) = trees(&binary);
    drop(binary);
    // Coincident items can make obvhs's tree a chain as long as their number: too deep for the traversal
    // stacks (and for the collapse's recursion, which gives up past MAX_COLLAPSE_LEVELS). A pile the sample
    // missed is then built over one box per distinct item; anything still too deep gets the balanced tree.
    for fallback in fallbacks {
        if fits(&packet_tree, &single) {
            break;
        }
        let binary = match *fallback {
            Fallback::Piles(params) => piles::build_over_piles(boxes(), params),
            Fallback::Balanced => balanced(boxes()),
        };
        (permuted, (packet_tree, single)) = trees(&binary);
    }
    assert!(fits(&packet_tree, &single), "a balanced tree of {n} items fits the traversal stacks");
    let (wide, scalar) = single;
    let (nodes, wide, scalar) = (packet_tree.0, wide.map(|(w, _)| w), scalar.map(|(s, _)| s));
    let extent = extent(&nodes[0]);
    let (up, wide_starts) = rayon::join(
        || {
            wide.as_ref()
                .filter(|_| leaf_links)
                .map(|w| rayon::join(|| Upward::of(&nodes, n), || Upward::of(w, n)))
        },
        || wide.as_ref().and_then(|w| WideStarts::of(&nodes, w)),
    );
    let tree = Bvh {
        nodes,
        single_ray_lanes,
        frustum_culling,
        extent,
        pad,
        wide,
        up,
        wide_starts,
        scalar,
        scalar_walk: scalar_tree,
    };
    let stats = BuildStats { seconds: start.elapsed().as_secs_f64(), node_bytes: tree.bytes() };
    (tree, permuted, stats)
}

/// A tree built when the first is too deep for the walks' stacks.
enum Fallback {
    /// obvhs over one box per distinct box ([`piles`]).
    Piles(BvhBuildParams),
    /// [`balanced`].
    Balanced,
}

/// The largest coordinate magnitude of the root's occupied child boxes.
pub(super) fn extent(root: &Node) -> f32 {
    let slots = usize::from(root.slots);
    root.bounds.iter().flatten().flat_map(|axis| axis[..slots].iter()).fold(0.0f32, |m, v| m.max(v.abs()))
}
