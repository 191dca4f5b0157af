//! bareray's own tree builder: top-down binned surface-area-heuristic (SAH) splits of the items' boxes, in
//! obvhs's binary layout (which the collapse turns into the wide nodes).
//!
//! It needs little memory besides what it returns: one 32-byte reference per item (box and index), partitioned
//! in place, and the binary nodes, one per leaf or split rather than one per item. obvhs's PLOC needs about
//! 224 bytes an item at its peak, and under a hypervisor a fresh page costs more than its use, so the memory is
//! also the build's time (docs/perf-log/2026-11-own-builder.md).
//!
//! The top of the tree is split on the calling thread (binning large ranges in parallel) down to ranges of
//! about 1/[`TASKS`] of the items; those subtrees are then built in parallel, each into a vector of its own, and
//! appended. Every split leaves both sides non-empty, and past [`MAX_SAH_DEPTH`] levels ranges are halved at
//! their median, so the tree's depth stays within the walks' stacks whatever the boxes.

use glam::{Vec3A, Vec4};
use obvhs::aabb::Aabb;
use obvhs::bvh2::node::Bvh2Node;
use rayon::prelude::*;

use super::median::unset;

/// Bins per axis.
const BINS: usize = 16;

/// A range whose centres spread at least this many times as far along one axis as along either other is
/// binned along that axis alone: a third of the binning's work per item, and the split it misses on the
/// other axes seldom pays (PERF.md, "Register", SAH split candidates).
const DOMINANT_SPREAD: f32 = 1.5;

/// The most items a leaf holds (as in obvhs's presets other than `fastest`, whose leaves hold one).
pub(super) const MAX_LEAF: usize = 8;

/// Ranges of at least this many items are binned in parallel.
const PARALLEL_BINNING: usize = 1 << 15;

/// The top of the tree is split until ranges hold at most 1/`TASKS` of the items (or [`MIN_TASK`]).
const TASKS: usize = 64;

/// Ranges this small are never split on the calling thread.
const MIN_TASK: usize = 4096;

/// Binary levels past which ranges are halved at their median instead of by the SAH: with at most about
/// log2(items) levels below, every collapsed tree fits the walks' stacks.
pub(super) const MAX_SAH_DEPTH: u32 = 40;

/// An item's box with its index in the box's spare `w` lane.
#[derive(Clone, Copy)]
pub(super) struct Ref {
    pub(super) lo: Vec4,
    pub(super) hi: Vec4,
}

impl Ref {
    pub(super) fn new(b: Aabb, item: u32) -> Self {
        Ref { lo: b.min.extend(f32::from_bits(item)), hi: b.max.extend(0.0) }
    }
    pub(super) fn item(&self) -> u32 {
        self.lo.w.to_bits()
    }
    fn bounds(&self) -> Aabb {
        Aabb { min: Vec3A::from_vec4(self.lo), max: Vec3A::from_vec4(self.hi) }
    }
    /// Twice the box's centre (only compared and binned, so never halved).
    pub(super) fn centre2(&self) -> Vec3A {
        Vec3A::from_vec4(self.lo + self.hi)
    }
}

/// The box around a range's boxes and the box around their (doubled) centres.
#[derive(Clone, Copy)]
pub(super) struct Extent {
    pub(super) boxes: Aabb,
    pub(super) centres: Aabb,
}

impl Extent {
    const EMPTY: Extent = Extent { boxes: Aabb::INVALID, centres: Aabb::INVALID };

    /// Adds `r`. A NaN centre (a box infinite both ways on an axis) is left out of the centre box: the SSE
    /// min and max would let it replace the centres before it. It bins into the last bin all the same.
    fn add(&mut self, r: &Ref) {
        self.boxes = self.boxes.union(&r.bounds());
        let centre = r.centre2();
        if !centre.is_nan() {
            self.centres.extend(centre);
        }
    }
    fn union(self, o: Extent) -> Extent {
        Extent { boxes: self.boxes.union(&o.boxes), centres: self.centres.union(&o.centres) }
    }
    /// The extent of `refs`, on this thread.
    fn fold(refs: &[Ref]) -> Extent {
        refs.iter().fold(Extent::EMPTY, |mut e, r| (e.add(r), e).1)
    }
    /// The extent of `refs`, in parallel when they are many.
    pub(super) fn of(refs: &[Ref]) -> Extent {
        summarise(refs, Extent::fold, Extent::EMPTY, Extent::union)
    }
}

/// `serial` of `refs`: at once for a short range, else of chunks in parallel, combined by `merge` (which
/// must not depend on how the range is cut: unions and counts).
fn summarise<T: Send + Sync + Copy>(
    refs: &[Ref],
    serial: impl Fn(&[Ref]) -> T + Sync + Send,
    empty: T,
    merge: impl Fn(T, T) -> T + Sync + Send,
) -> T {
    match refs.len() < PARALLEL_BINNING {
        true => serial(refs),
        false => refs.par_chunks(PARALLEL_BINNING / 4).map(serial).reduce(|| empty, merge),
    }
}

/// Bins along each axis: the box around the items whose centres fall in each, and their number.
#[derive(Clone, Copy)]
struct Bins {
    bounds: [[Aabb; BINS]; 3],
    counts: [[u32; BINS]; 3],
}

const EMPTY_BINS: Bins = Bins { bounds: [[Aabb::INVALID; BINS]; 3], counts: [[0; BINS]; 3] };

impl Bins {
    /// Adds `o`'s items (unions and counts, so the order of merging does not matter).
    fn merge(mut self, o: Bins) -> Bins {
        for (x, y) in self.bounds.iter_mut().flatten().zip(o.bounds.iter().flatten()) {
            *x = x.union(y);
        }
        for (x, y) in self.counts.iter_mut().flatten().zip(o.counts.iter().flatten()) {
            *x += y;
        }
        self
    }
}

/// Which bin a centre falls in, along each axis, over a range's centre box.
struct Binner {
    min: Vec3A,
    scale: Vec3A,
}

/// Per axis, `cells` over the spread of `centres` (slightly fewer, so that the largest centre stays below
/// `cells` in most cases; where it rounds to `cells` the users clamp it), or 0 on an axis without spread.
pub(super) fn cells_per_unit(centres: &Aabb, cells: f32) -> Vec3A {
    let spread = centres.max - centres.min;
    Vec3A::select(spread.cmpgt(Vec3A::ZERO), (cells * 0.9999) / spread, Vec3A::ZERO)
}

impl Binner {
    fn new(centres: &Aabb) -> Self {
        // The largest centre rounds to BINS in `index`, whose clamp puts it in the last bin.
        Binner { min: centres.min, scale: cells_per_unit(centres, BINS as f32) }
    }
    /// The bin: the position over the centre box, rounded to the nearest integer by adding 2^23 (whose ulp is
    /// 1), so the float's low bits hold it, without a float-to-integer conversion (which checks each lane).
    /// The first bin is half as wide as the others and the last one and a half times: any monotone binning
    /// serves, as long as the partition uses the same one. A NaN centre (an overflowed corner) lands in the
    /// last bin.
    fn index(&self, r: &Ref) -> [usize; 3] {
        const TWO_23: f32 = 8_388_608.0;
        let at = (r.centre2() - self.min) * self.scale + TWO_23;
        at.to_array().map(|x| (x.to_bits().wrapping_sub(TWO_23.to_bits()) as usize).min(BINS - 1))
    }
    /// [`Binner::index`] along axis `A`: the same operations on that coordinate alone. The axis is a constant
    /// so that the loops over a range (the dominant axis's binning, the partition) read that coordinate
    /// directly: with the axis a variable they stored the centre and loaded one lane back for every item
    /// (PERF.md, "Register", the SAH builder's partition).
    fn index_on<const A: usize>(&self, r: &Ref) -> usize {
        const TWO_23: f32 = 8_388_608.0;
        let at = ((r.lo[A] + r.hi[A]) - self.min[A]) * self.scale[A] + TWO_23;
        (at.to_bits().wrapping_sub(TWO_23.to_bits()) as usize).min(BINS - 1)
    }
    /// The bins of `refs` along every axis, or along `only` (the other axes' bins then stay empty).
    fn bins(&self, refs: &[Ref], only: Option<usize>) -> Bins {
        let serial = |refs: &[Ref]| {
            let mut bins = EMPTY_BINS;
            let mut add = |axis: usize, at: usize, b: &Aabb| {
                let bound = &mut bins.bounds[axis][at];
                *bound = bound.union(b);
                bins.counts[axis][at] += 1;
            };
            match only {
                None => refs.iter().for_each(|r| {
                    let b = r.bounds();
                    self.index(r).into_iter().enumerate().for_each(|(axis, at)| add(axis, at, &b))
                }),
                Some(0) => refs.iter().for_each(|r| add(0, self.index_on::<0>(r), &r.bounds())),
                Some(1) => refs.iter().for_each(|r| add(1, self.index_on::<1>(r), &r.bounds())),
                Some(_) => refs.iter().for_each(|r| add(2, self.index_on::<2>(r), &r.bounds())),
            }
            bins
        };
        summarise(refs, serial, EMPTY_BINS, Bins::merge)
    }
}

/// The axis along which `centres` spread at least [`DOMINANT_SPREAD`] times as far as along either other.
fn dominant_axis(centres: &Aabb) -> Option<usize> {
    let (spread, axis) = ((centres.max - centres.min).to_array(), centres.largest_axis());
    let others = (0..3).filter(|&a| a != axis).map(|a| spread[a]).fold(0.0f32, f32::max);
    (spread[axis] >= DOMINANT_SPREAD * others).then_some(axis)
}

/// The cheapest split between bins: items whose centre's bin along `axis` is below `bin` go left. `cost` is
/// the sum over both sides of surface area times items.
struct Split {
    axis: usize,
    bin: usize,
    cost: f32,
}

fn best_split(bins: &Bins) -> Option<Split> {
    let mut best: Option<Split> = None;
    for (axis, (bounds, counts)) in bins.bounds.iter().zip(&bins.counts).enumerate() {
        // The occupied bins in order. A split anywhere in the empty bins between two of them leaves the same
        // items on each side at the same cost, so only the highest such bin is a candidate: the one a sweep
        // over every bin from the top, keeping only cheaper splits, would keep. Small ranges occupy few bins.
        let (mut occupied, mut m) = ([0u8; BINS], 0);
        for (s, &count) in counts.iter().enumerate() {
            occupied[m] = s as u8;
            m += (count > 0) as usize;
        }
        // left[j]: area × count of the occupied bins before the j-th.
        let (mut left, mut acc, mut count) = ([0.0; BINS], Aabb::INVALID, 0);
        for j in 1..m {
            let bin = usize::from(occupied[j - 1]);
            (acc, count) = (acc.union(&bounds[bin]), count + counts[bin]);
            left[j] = acc.half_area() * count as f32;
        }
        let (mut acc, mut count) = (Aabb::INVALID, 0);
        for j in (1..m).rev() {
            let bin = usize::from(occupied[j]);
            (acc, count) = (acc.union(&bounds[bin]), count + counts[bin]);
            let cost = left[j] + acc.half_area() * count as f32;
            if best.as_ref().is_none_or(|b| cost < b.cost) {
                best = Some(Split { axis, bin, cost });
            }
        }
    }
    best
}

/// Splits `refs` in place into a left and a right part, returning the left part's length and both parts'
/// extents; `None` when they make a leaf: one item, or at most [`MAX_LEAF`] items that cost less tested
/// together than split (a binary node costing `node_cost` item tests), that have no binned split (all centres
/// equal), or that lie past [`MAX_SAH_DEPTH`].
pub(super) fn split(
    refs: &mut [Ref],
    extent: &Extent,
    depth: u32,
    node_cost: f32,
) -> Option<(usize, Extent, Extent)> {
    let n = refs.len();
    if n <= 1 {
        return None;
    }
    let binner = Binner::new(&extent.centres);
    let bins = || binner.bins(refs, dominant_axis(&extent.centres));
    let split = (depth < MAX_SAH_DEPTH).then(|| best_split(&bins())).flatten();
    let Some(Split { axis, bin, cost }) = split else {
        return (n > MAX_LEAF).then(|| median(refs, extent));
    };
    let area = extent.boxes.half_area();
    // Compared multiplied through by the area, so a range of flat boxes (area 0) compares too.
    if n <= MAX_LEAF && n as f32 * area <= node_cost * area + cost {
        return None;
    }
    // The partition bins as `bins` did, so it leaves the split's counts on each side, neither empty.
    let parts = match axis {
        0 => partition(refs, |r| binner.index_on::<0>(r) < bin),
        1 => partition(refs, |r| binner.index_on::<1>(r) < bin),
        _ => partition(refs, |r| binner.index_on::<2>(r) < bin),
    };
    debug_assert!(0 < parts.0 && parts.0 < n, "a split left a side empty");
    Some(parts)
}

/// Splits `refs` in place: those `left` accepts first. Returns their number and both parts' extents.
///
/// Branch-free (Lomuto's scheme with the swap always made): which side an item goes to is a coin toss for the
/// branch predictor, and a mispredicted branch per item costs more than the swap. The parts' extents are
/// folded afterwards (in registers; a large part in parallel): added in the loop, to the side picked by index,
/// each item waited for the previous one's store (PERF.md, "Register", the SAH builder's partition).
fn partition(refs: &mut [Ref], left: impl Fn(&Ref) -> bool) -> (usize, Extent, Extent) {
    let mut store = 0;
    for i in 0..refs.len() {
        let goes_left = left(&refs[i]);
        // refs[store..i] all go right: swapping refs[i] to `store` keeps that, whichever side it goes. `swap`
        // moves whole 32-byte references; two half-width stores followed by the next item's full-width load
        // of refs[store] can defeat store-to-load forwarding (`perf annotate` of a partition written that way
        // shows its hottest instruction there).
        refs.swap(i, store);
        store += goes_left as usize;
    }
    let (l, r) = refs.split_at(store);
    (store, Extent::of(l), Extent::of(r))
}

/// Halves `refs` at the median centre along the axis of widest centre spread.
pub(super) fn median(refs: &mut [Ref], extent: &Extent) -> (usize, Extent, Extent) {
    let axis = extent.centres.largest_axis();
    let mid = refs.len() / 2;
    refs.select_nth_unstable_by(mid, |a, b| a.centre2()[axis].total_cmp(&b.centre2()[axis]));
    let (l, r) = refs.split_at(mid);
    (mid, Extent::of(l), Extent::of(r))
}

/// A range of items whose subtree is still to build: the node slot it goes in, its first item, its items'
/// extent and its depth.
#[derive(Clone, Copy)]
struct Pending {
    slot: usize,
    first: usize,
    len: usize,
    extent: Extent,
    depth: u32,
}

/// Builds the subtree of `root`, whose items `refs` holds, into `nodes`, as `split` splits ranges.
fn grow(refs: &mut [Ref], root: Pending, nodes: &mut Vec<Bvh2Node>, split: &SplitRange) {
    let mut stack = vec![root];
    while let Some(p) = stack.pop() {
        let range = p.first - root.first..p.first - root.first + p.len;
        let split = split(&mut refs[range], &p.extent, p.depth);
        stack.extend(place(p, split, nodes).into_iter().flatten().rev());
    }
}

/// Writes `p`'s node: a leaf, or for `split` an inner node whose two children's slots it appends to `nodes`.
/// Returns the children's ranges.
fn place(
    p: Pending,
    split: Option<(usize, Extent, Extent)>,
    nodes: &mut Vec<Bvh2Node>,
) -> Option<[Pending; 2]> {
    let Some((mid, l, r)) = split else {
        nodes[p.slot] = Bvh2Node::new(p.extent.boxes, p.len as u32, p.first as u32);
        return None;
    };
    let at = nodes.len();
    nodes.extend([unset(); 2]);
    nodes[p.slot] = Bvh2Node::new(p.extent.boxes, 0, at as u32);
    let depth = p.depth + 1;
    Some([
        Pending { slot: at, first: p.first, len: mid, extent: l, depth },
        Pending { slot: at + 1, first: p.first + mid, len: p.len - mid, extent: r, depth },
    ])
}

/// Disjoint slices of `refs` for `ranges`, which are in item order and do not overlap.
fn slices<'a>(refs: &'a mut [Ref], ranges: &[Pending]) -> Vec<&'a mut [Ref]> {
    let (mut rest, mut at, mut out) = (refs, 0, Vec::with_capacity(ranges.len()));
    for p in ranges {
        let (_, tail) = std::mem::take(&mut rest).split_at_mut(p.first - at);
        let (mine, tail) = tail.split_at_mut(p.len);
        (rest, at) = (tail, p.first + p.len);
        out.push(mine);
    }
    out
}

/// The binary tree over the boxes `item_box` gives for items `0..n`, in obvhs's layout: its nodes (the root
/// first; an inner node's children adjacent at `first_index`) and the item order its leaves index. `n` ≥ 1;
/// a binary node costs `node_cost` item tests ([`super::Builder::Sah`]).
pub(super) fn build_sah(
    n: usize,
    item_box: impl Fn(usize) -> Aabb + Sync,
    node_cost: f32,
) -> (Vec<Bvh2Node>, Vec<u32>) {
    let (refs, extent) = references(n, item_box);
    build_with(refs, extent, &|refs: &mut [Ref], extent: &Extent, depth: u32| {
        split(refs, extent, depth, node_cost)
    })
}

/// One reference per item `0..n` and their extent. `n` ≥ 1.
pub(super) fn references(n: usize, item_box: impl Fn(usize) -> Aabb + Sync) -> (Vec<Ref>, Extent) {
    assert!(n > 0, "a tree over no items");
    // Item indices and node links are u32, and a tree has fewer than 2n nodes.
    assert!(n < 1 << 31, "{n} items: more than a tree's u32 links reach");
    let refs: Vec<Ref> = (0..n).into_par_iter().map(|i| Ref::new(item_box(i), i as u32)).collect();
    let extent = Extent::of(&refs);
    (refs, extent)
}

/// How a builder splits a range of references in place: [`split`]'s contract (the left part's length and
/// both parts' extents, `None` for a leaf of at most [`MAX_LEAF`] items, both parts non-empty), given the
/// range's extent and depth.
pub(super) type SplitRange<'a> =
    dyn Fn(&mut [Ref], &Extent, u32) -> Option<(usize, Extent, Extent)> + Sync + 'a;

/// The binary tree `split` makes of `refs` (whose extent is `extent`), top down: the top levels on this
/// thread, range by range in parallel, then subtrees of at most 1/[`TASKS`] of the items each on a thread of
/// its own. The tree does not depend on the thread count.
pub(super) fn build_with(
    mut refs: Vec<Ref>,
    extent: Extent,
    split: &SplitRange,
) -> (Vec<Bvh2Node>, Vec<u32>) {
    let n = refs.len();
    let root = Pending { slot: 0, first: 0, len: n, extent, depth: 0 };
    let mut nodes = vec![unset()];
    // The top, level by level, each level's ranges split in parallel; ranges of at most `task` items are
    // left for the subtrees.
    let task = (n / TASKS).max(MIN_TASK);
    let (mut level, mut tasks) = (vec![root], Vec::new());
    while !level.is_empty() {
        let (small, large): (Vec<Pending>, Vec<Pending>) = level.into_iter().partition(|p| p.len <= task);
        tasks.extend(small);
        let splits: Vec<_> = (large.par_iter().zip(slices(&mut refs, &large)))
            .map(|(p, refs)| split(refs, &p.extent, p.depth))
            .collect();
        level =
            (large.into_iter().zip(splits)).flat_map(|(p, s)| place(p, s, &mut nodes)).flatten().collect();
    }
    tasks.sort_unstable_by_key(|p| p.first);
    let subtrees: Vec<Vec<Bvh2Node>> = (tasks.par_iter().zip(slices(&mut refs, &tasks)))
        .map(|(t, refs)| {
            let mut nodes = vec![unset()];
            grow(refs, Pending { slot: 0, ..*t }, &mut nodes, split);
            nodes
        })
        .collect();
    // Each subtree's root goes in its slot, the rest after the nodes so far in task order, its links moved
    // with it: written in parallel, each node once into its place.
    let top = nodes.len();
    let starts: Vec<usize> =
        (subtrees.iter()).scan(0, |at, s| Some(std::mem::replace(at, *at + s.len() - 1))).collect();
    let shift = |p: usize| (top - 1 + starts[p]) as u32;
    let total = subtrees.iter().map(|s| s.len() - 1).sum::<usize>();
    nodes.par_extend((0..total).into_par_iter().map(|k| {
        // The last subtree starting at or before k holds it (one with no nodes past its root holds none).
        let p = starts.partition_point(|&start| start <= k) - 1;
        moved(subtrees[p][1 + k - starts[p]], shift(p))
    }));
    for (p, t) in tasks.iter().enumerate() {
        nodes[t.slot] = moved(subtrees[p][0], shift(p));
    }
    (nodes, refs.par_iter().map(Ref::item).collect())
}

/// Node `v` of a subtree whose nodes after its root move `shift` places up: an inner node's link moves too.
fn moved(mut v: Bvh2Node, shift: u32) -> Bvh2Node {
    if v.prim_count == 0 {
        v.first_index += shift;
    }
    v
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::math::SplitMix64;

    /// Cubes of half-size `r` around `centres`.
    fn cubes(centres: impl IntoIterator<Item = (Vec3A, f32)>) -> Vec<Aabb> {
        centres.into_iter().map(|(c, r)| Aabb { min: c - r, max: c + r }).collect()
    }

    /// Box sets that stress the builder: uniform, clustered with a pile of copies, all one box, sizes and
    /// positions spread over many orders of magnitude (a chain for a pure SAH split), flat boxes.
    pub(in crate::bvh) fn box_sets() -> Vec<(&'static str, Vec<Aabb>)> {
        let mut rng = SplitMix64::new(11);
        let mut next = move || rng.unit() as f32;
        let mut point = move || Vec3A::new(next(), next(), next());
        let uniform = cubes((0..20_000).map(|_| (point() * 100.0, 0.05)));
        let clustered = cubes((0..9000).map(|i| match i % 3 {
            0 => (Vec3A::splat(5.0), 0.5),
            _ => (point() * 10.0, 0.01 + point().x),
        }));
        let pile = cubes((0..5000).map(|_| (Vec3A::ONE, 0.25)));
        let spread = cubes((0..800).map(|i| (Vec3A::X * 1.1f32.powi(i), 1e-3 * 1.1f32.powi(i))));
        let flat: Vec<Aabb> = (0..2000).map(|i| Aabb::from_point(Vec3A::new(i as f32, 0.0, 0.0))).collect();
        // Two boxes far from 6000 others: the first split leaves them a subtree that is one leaf.
        let far = |i: usize| (i >= 6000).then(|| Vec3A::splat(1e6 + i as f32));
        let outliers = cubes((0..6002).map(|i| (far(i).unwrap_or_else(&mut point), 0.05)));
        let few = |n: usize| cubes((0..n).map(|i| (Vec3A::Y * i as f32, 0.5)));
        vec![
            ("uniform", uniform),
            ("clustered", clustered),
            ("pile", pile),
            ("spread", spread),
            ("flat", flat),
            ("outliers", outliers),
            ("one", few(1)),
            ("two", few(2)),
            ("nine", few(9)),
        ]
    }

    /// Checks the subtree at `i`: boxes enclose what they hold, leaves hold 1 to MAX_LEAF items; collects the
    /// leaves' ranges and returns the subtree's depth.
    fn check(
        nodes: &[Bvh2Node],
        i: usize,
        boxes: &[Aabb],
        order: &[u32],
        ranges: &mut Vec<(u32, u32)>,
    ) -> usize {
        let v = &nodes[i];
        let encloses = |b: &Aabb| v.aabb.min.cmple(b.min).all() && v.aabb.max.cmpge(b.max).all();
        if v.prim_count > 0 {
            assert!(v.prim_count as usize <= MAX_LEAF, "leaf of {}", v.prim_count);
            let items = &order[v.first_index as usize..][..v.prim_count as usize];
            assert!(items.iter().all(|&k| encloses(&boxes[k as usize])), "a leaf's box misses an item");
            ranges.push((v.first_index, v.prim_count));
            return 1;
        }
        let first = v.first_index as usize;
        assert!(first > i && first + 1 < nodes.len(), "node {i} links to {first}");
        assert!(encloses(&nodes[first].aabb) && encloses(&nodes[first + 1].aabb), "node {i} misses a child");
        1 + check(nodes, first, boxes, order, ranges).max(check(nodes, first + 1, boxes, order, ranges))
    }

    /// Checks a whole tree over `boxes`: its order a permutation, every item in one leaf under boxes that
    /// enclose it, leaves neither overlapping nor leaving gaps, depth at most `bound`, fewer than 2n nodes.
    pub(in crate::bvh) fn check_tree(
        name: &str,
        nodes: &[Bvh2Node],
        order: &[u32],
        boxes: &[Aabb],
        bound: usize,
    ) {
        let mut sorted = order.to_vec();
        sorted.sort_unstable();
        assert!(sorted.iter().copied().eq(0..boxes.len() as u32), "{name}: the order is no permutation");
        let mut ranges = Vec::new();
        let depth = check(nodes, 0, boxes, order, &mut ranges);
        ranges.sort_unstable();
        let mut at = 0;
        for (first, count) in ranges {
            assert_eq!(first, at, "{name}: leaves overlap or leave a gap");
            at += count;
        }
        assert_eq!(at as usize, boxes.len(), "{name}");
        assert!(depth <= bound, "{name}: depth {depth} over {bound}");
        assert!(nodes.len() < 2 * boxes.len(), "{name}: {} nodes", nodes.len());
    }

    #[test]
    fn every_item_is_in_one_leaf_under_boxes_that_enclose_it() {
        for (name, boxes) in box_sets() {
            let (nodes, order) = build_sah(boxes.len(), |i| boxes[i], 6.0);
            // Past MAX_SAH_DEPTH ranges are halved, so at most log2 more levels follow.
            check_tree(
                name,
                &nodes,
                &order,
                &boxes,
                MAX_SAH_DEPTH as usize + boxes.len().ilog2() as usize + 2,
            );
        }
    }

    /// The split a sweep over every bin chooses (the first cheapest from the top, axis by axis).
    fn best_split_over_every_bin(bins: &Bins) -> Option<(usize, usize, f32)> {
        let mut best: Option<(usize, usize, f32)> = None;
        for axis in 0..3 {
            let (bounds, counts) = (&bins.bounds[axis], &bins.counts[axis]);
            let (mut left, mut acc, mut count) = ([None; BINS], Aabb::INVALID, 0);
            for s in 1..BINS {
                (acc, count) = (acc.union(&bounds[s - 1]), count + counts[s - 1]);
                left[s] = (count > 0).then(|| acc.half_area() * count as f32);
            }
            let (mut acc, mut count) = (Aabb::INVALID, 0);
            for s in (1..BINS).rev() {
                (acc, count) = (acc.union(&bounds[s]), count + counts[s]);
                let Some(left) = left[s].filter(|_| count > 0) else { continue };
                let cost = left + acc.half_area() * count as f32;
                if best.is_none_or(|b| cost < b.2) {
                    best = Some((axis, s, cost));
                }
            }
        }
        best
    }

    /// Only the occupied bins are candidates, and the split chosen among them is the one a sweep over every
    /// bin chooses: same axis, bin (the partition's boundary) and cost bits, over ranges of every size.
    #[test]
    fn the_occupied_bins_give_the_full_sweeps_split() {
        for (name, boxes) in box_sets() {
            let mut rng = SplitMix64::new(5);
            for _ in 0..200 {
                let len = 1 + (rng.unit() * 40.0) as usize % boxes.len().max(1);
                let start = (rng.unit() * (boxes.len() - len.min(boxes.len())) as f64) as usize;
                let refs: Vec<Ref> =
                    boxes[start..][..len].iter().enumerate().map(|(i, b)| Ref::new(*b, i as u32)).collect();
                let bins = Binner::new(&Extent::of(&refs).centres).bins(&refs, None);
                let fast = best_split(&bins).map(|s| (s.axis, s.bin, s.cost.to_bits()));
                let full = best_split_over_every_bin(&bins).map(|(a, b, c)| (a, b, c.to_bits()));
                assert_eq!(fast, full, "{name}: {len} items from {start}");
            }
        }
    }

    /// Binning along one axis fills that axis's bins exactly as binning along all three does, and no other.
    #[test]
    fn one_axis_bins_as_all_three_do() {
        for (name, boxes) in box_sets() {
            let refs: Vec<Ref> = boxes.iter().enumerate().map(|(i, b)| Ref::new(*b, i as u32)).collect();
            let binner = Binner::new(&Extent::of(&refs).centres);
            let all = binner.bins(&refs, None);
            for axis in 0..3 {
                let one = binner.bins(&refs, Some(axis));
                let row = |b: &Bins, a: usize| {
                    let corners = b.bounds[a].map(|x| (x.min.to_array(), x.max.to_array()));
                    (corners, b.counts[a])
                };
                assert!(row(&one, axis) == row(&all, axis), "{name}: axis {axis} binned differently");
                let others = (0..3).filter(|&a| a != axis);
                assert!(others.map(|a| one.counts[a]).all(|c| c == [0; BINS]), "{name}: other axes binned");
            }
        }
    }

    /// A dominant axis is one whose spread is at least DOMINANT_SPREAD times either other's.
    #[test]
    fn a_dominant_axis_spreads_well_beyond_the_others() {
        let spread =
            |x: f32, y: f32, z: f32| dominant_axis(&Aabb { min: Vec3A::ZERO, max: Vec3A::new(x, y, z) });
        assert_eq!(spread(2.0, 1.0, 1.0), Some(0));
        assert_eq!(spread(1.0, 0.5, 1.5), Some(2));
        assert_eq!(spread(0.0, 3.0, 2.0), Some(1), "exactly DOMINANT_SPREAD times");
        assert_eq!(spread(1.0, 1.0, 0.5), None, "two axes alike");
        assert_eq!(spread(1.4, 1.0, 1.0), None);
        assert_eq!(spread(5.0, 0.0, 0.0), Some(0), "flat");
    }

    /// The partition puts exactly the accepted items first, keeps every item, and returns each side's extent
    /// as computed afresh.
    #[test]
    fn the_partition_keeps_the_items_and_their_extents() {
        let (_, boxes) = box_sets().into_iter().find(|(name, _)| *name == "clustered").unwrap();
        let mut refs: Vec<Ref> = boxes.iter().enumerate().map(|(i, b)| Ref::new(*b, i as u32)).collect();
        let left = |r: &Ref| r.item() % 3 == 1 || r.centre2().y < 6.0;
        let (mid, l, r) = partition(&mut refs, left);
        assert!(refs[..mid].iter().all(left) && !refs[mid..].iter().any(left), "a side holds a stray item");
        let mut items: Vec<u32> = refs.iter().map(Ref::item).collect();
        items.sort_unstable();
        assert!(items.into_iter().eq(0..boxes.len() as u32), "items lost or repeated");
        let same = |a: &Extent, b: &Extent| {
            (a.boxes.min, a.boxes.max, a.centres.min, a.centres.max)
                == (b.boxes.min, b.boxes.max, b.centres.min, b.centres.max)
        };
        assert!(same(&l, &Extent::of(&refs[..mid])) && same(&r, &Extent::of(&refs[mid..])));
        assert!(0 < mid && mid < refs.len(), "the test's split is one-sided: {mid}");
    }

    /// At the depth cap a range is halved at its median, whatever the SAH would choose; below it the SAH
    /// splits the spread set unevenly.
    #[test]
    fn past_the_depth_cap_ranges_are_halved() {
        let (_, boxes) = box_sets().into_iter().find(|(name, _)| *name == "spread").unwrap();
        let mut refs: Vec<Ref> = boxes.iter().enumerate().map(|(i, b)| Ref::new(*b, i as u32)).collect();
        let extent = Extent::of(&refs);
        let (mid, ..) = split(&mut refs, &extent, 0, 6.0).expect("a split");
        assert!(
            mid.abs_diff(boxes.len() / 2) > boxes.len() / 4,
            "the SAH split the spread set evenly: {mid}"
        );
        let (mid, l, r) = split(&mut refs, &extent, MAX_SAH_DEPTH, 6.0).expect("a split");
        assert_eq!(mid, boxes.len() / 2);
        let right_of = |e: &Extent| e.centres.min.x;
        assert!(l.centres.max.x <= right_of(&r), "the halves overlap");
        assert!(
            refs[..mid].iter().all(|r| r.centre2().x <= l.centres.max.x),
            "a left item is outside its extent"
        );
    }

    /// `n` boxes, every third infinite both ways (centre NaN), the others points along x.
    pub(in crate::bvh) fn overflowed_boxes(n: usize) -> Vec<Aabb> {
        let whole = Aabb { min: Vec3A::NEG_INFINITY, max: Vec3A::INFINITY };
        (0..n).map(|i| if i % 3 == 0 { whole } else { Aabb::from_point(Vec3A::X * i as f32) }).collect()
    }

    /// A tree's nodes as comparable fields (corners, count, link), with its order.
    pub(in crate::bvh) type Fields = (Vec<([f32; 3], [f32; 3], u32, u32)>, Vec<u32>);

    /// [`Fields`] of a tree.
    pub(in crate::bvh) fn fields((nodes, order): (Vec<Bvh2Node>, Vec<u32>)) -> Fields {
        let node = |v: &Bvh2Node| (v.aabb.min.to_array(), v.aabb.max.to_array(), v.prim_count, v.first_index);
        (nodes.iter().map(node).collect(), order)
    }

    /// Boxes infinite both ways (centres NaN) still build, each item in one leaf: a split with an empty side
    /// would repeat forever, and a NaN cost must not make one the best.
    #[test]
    fn boxes_with_overflowed_corners_build() {
        let boxes = overflowed_boxes(300);
        let (nodes, mut order) = build_sah(boxes.len(), |i| boxes[i], 6.0);
        order.sort_unstable();
        assert!(order.iter().copied().eq(0..300), "the order is no permutation");
        let held: u32 = nodes.iter().map(|v| v.prim_count).sum();
        assert_eq!(held, 300);
    }

    /// Binning in parallel and building subtrees on several threads give the one-thread tree, node for node:
    /// over enough boxes for the parallel binning, some of them infinite both ways (NaN centres).
    #[test]
    fn the_tree_does_not_depend_on_the_threads() {
        let mut rng = SplitMix64::new(3);
        let mut next = move || rng.unit() as f32;
        let whole = Aabb { min: Vec3A::NEG_INFINITY, max: Vec3A::INFINITY };
        let boxes: Vec<Aabb> = (0..3 * PARALLEL_BINNING)
            .map(|i| match i % 1000 {
                0 => whole,
                _ => cubes([(Vec3A::new(next(), next(), next()) * 100.0, 0.05)])[0],
            })
            .collect();
        let on = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            fields(pool.install(|| build_sah(boxes.len(), |i| boxes[i], 6.0)))
        };
        assert!(on(1) == on(4), "the tree differs between 1 and 4 threads");
    }
}
