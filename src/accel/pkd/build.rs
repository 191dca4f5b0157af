//! Building the particle tree in place: each range longer than [`LEAF`] is split at its middle position by a
//! selection (not a sort) on the widest axis of its box, the two halves built in parallel. Every level
//! moves each sphere at most a few times, so the build is O(n log n) with no memory beyond the keys.

use glam::DVec3;

use super::Record;
use crate::math::Rgb8;

/// Ranges of at most this many spheres are leaves, tested one after another without further boxes: fewer
/// box tests per sphere than single-sphere nodes, at a few more sphere tests.
pub(crate) const LEAF: usize = 8;

/// Ranges at least this long build their halves on two rayon tasks.
const PARALLEL: usize = 1 << 15;

/// Builds the tree over `recs`, reordering `key` (file indices below [`super::MAX_PARTICLES`]), `material`
/// and `color` (each empty, or one per record) alike, and writing each node's split axis into the top bits
/// of its key.
pub(super) fn build<R: Record>(recs: &mut [R], key: &mut [u32], material: &mut [u32], color: &mut [Rgb8]) {
    let n = recs.len();
    if n == 0 {
        return;
    }
    let (lo, hi) = centre_box(recs);
    node(Slices { recs, key, material, color }, lo, hi);
}

/// The arrays of one range, reordered together.
struct Slices<'a, R> {
    recs: &'a mut [R],
    key: &'a mut [u32],
    /// Empty when the spheres share one material.
    material: &'a mut [u32],
    /// Empty when the spheres have no colours of their own.
    color: &'a mut [Rgb8],
}

impl<'a, R: Record> Slices<'a, R> {
    #[inline(always)]
    fn swap(&mut self, a: usize, b: usize) {
        self.recs.swap(a, b);
        self.key.swap(a, b);
        if !self.material.is_empty() {
            self.material.swap(a, b);
        }
        if !self.color.is_empty() {
            self.color.swap(a, b);
        }
    }

    /// The order the tree keeps on `axis`: the centre's coordinate, then the file index.
    #[inline(always)]
    fn order(&self, i: usize, axis: usize) -> (f64, u32) {
        (self.recs[i].value(axis), self.key[i] & super::INDEX_MASK)
    }

    /// The ranges before and after position `mid` (the node itself in neither).
    fn split_at(self, mid: usize) -> (Slices<'a, R>, Slices<'a, R>) {
        let (recs_lo, recs_hi) = self.recs.split_at_mut(mid);
        let (key_lo, key_hi) = self.key.split_at_mut(mid);
        let (mat_lo, mat_hi) = split_optional(self.material, mid);
        let (color_lo, color_hi) = split_optional(self.color, mid);
        (
            Slices { recs: recs_lo, key: key_lo, material: mat_lo, color: color_lo },
            Slices { recs: &mut recs_hi[1..], key: &mut key_hi[1..], material: mat_hi, color: color_hi },
        )
    }
}

/// An optional per-record array (empty, or one per record) cut before and after position `mid`.
fn split_optional<T>(v: &mut [T], mid: usize) -> (&mut [T], &mut [T]) {
    if v.is_empty() {
        return (&mut [], &mut []);
    }
    let (a, b) = v.split_at_mut(mid);
    (a, &mut b[1..])
}

/// The box of the centres of `recs` (radii aside), in world space.
fn centre_box<R: Record>(recs: &[R]) -> (DVec3, DVec3) {
    use rayon::prelude::*;
    let empty = || (DVec3::INFINITY, DVec3::NEG_INFINITY);
    recs.par_iter()
        .with_min_len(1 << 16)
        .fold(empty, |(lo, hi), r| {
            let c = DVec3::new(r.value(0), r.value(1), r.value(2));
            (lo.min(c), hi.max(c))
        })
        .reduce(empty, |a, b| (a.0.min(b.0), a.1.max(b.1)))
}

/// Builds the subtree over `s`, whose centres lie in `[lo, hi]`.
fn node<R: Record>(mut s: Slices<'_, R>, lo: DVec3, hi: DVec3) {
    let n = s.recs.len();
    if n <= LEAF {
        return;
    }
    let axis = (hi - lo).max_position();
    let mid = n / 2;
    select(&mut s, mid, axis);
    // The halves' selections never see this key (they exclude `mid`), nor compare the axis bits.
    s.key[mid] |= (axis as u32) << super::INDEX_BITS;
    let plane = s.recs[mid].value(axis);
    let (mut below_hi, mut above_lo) = (hi, lo);
    below_hi[axis] = plane;
    above_lo[axis] = plane;
    let (below, above) = s.split_at(mid);
    if n >= PARALLEL {
        rayon::join(|| node(below, lo, below_hi), || node(above, above_lo, hi));
    } else {
        node(below, lo, below_hi);
        node(above, above_lo, hi);
    }
}

/// Reorders `s` so that position `nth` holds the element of that rank in the (coordinate on `axis`, file
/// index) order, the ones before it below and the ones after above: quickselect with Hoare's partition (few
/// swaps) and a median-of-three pivot from a fixed pseudo-random sequence. File indices are distinct, so no
/// two elements tie and no input — duplicated centres, sorted collinear runs — degrades it.
fn select<R: Record>(s: &mut Slices<'_, R>, nth: usize, axis: usize) {
    let (mut lo, mut hi) = (0, s.recs.len());
    let mut state = 0x9e37_79b9_7f4a_7c15u64 ^ (hi as u64);
    let mut next = |n: usize| {
        state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        ((state >> 33) as usize) % n
    };
    while hi - lo > 1 {
        let pick = [lo + next(hi - lo), lo + next(hi - lo), lo + next(hi - lo)];
        let [a, b, c] = pick.map(|i| (s.order(i, axis), i));
        let pivot = if (a.0 < b.0) == (b.0 < c.0) {
            b.1
        } else if (b.0 < a.0) == (a.0 < c.0) {
            a.1
        } else {
            c.1
        };
        s.swap(pivot, lo);
        let p = s.order(lo, axis);
        // Invariant: lo + 1..i below the pivot, j + 1..hi above; they meet with i = j + 1 (no ties).
        let (mut i, mut j) = (lo + 1, hi - 1);
        loop {
            while i <= j && s.order(i, axis) < p {
                i += 1;
            }
            while i <= j && s.order(j, axis) > p {
                j -= 1;
            }
            if i >= j {
                break;
            }
            s.swap(i, j);
            i += 1;
            j -= 1;
        }
        s.swap(lo, j);
        match nth.cmp(&j) {
            std::cmp::Ordering::Equal => return,
            std::cmp::Ordering::Less => hi = j,
            std::cmp::Ordering::Greater => lo = j + 1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::SplitMix64;

    /// Checks the tree's order over `recs`/`key` (see the module documentation of `pkd`): every node's
    /// lower range at or below it on its axis, its upper range at or above, in (coordinate, index) order.
    fn check<R: Record>(recs: &[R], key: &[u32], range: std::ops::Range<usize>) {
        let n = range.len();
        if n <= LEAF {
            return;
        }
        let mid = range.start + n / 2;
        let axis = (key[mid] >> crate::accel::pkd::INDEX_BITS) as usize;
        let at = |i: usize| (recs[i].value(axis), key[i] & crate::accel::pkd::INDEX_MASK);
        assert!((range.start..mid).all(|i| at(i) < at(mid)), "lower range of {mid}");
        assert!((mid + 1..range.end).all(|i| at(i) > at(mid)), "upper range of {mid}");
        check(recs, key, range.start..mid);
        check(recs, key, mid + 1..range.end);
    }

    /// Random fields, duplicated centres and collinear sorted runs all build into a valid tree that keeps
    /// every record with its key, material and colour.
    #[test]
    fn builds_a_valid_tree_that_keeps_records_together() {
        let mut rng = SplitMix64::new(9);
        for (case, n) in [0usize, 1, 7, 8, 9, 17, 100, 1000, 40_000].into_iter().enumerate() {
            let recs: Vec<[f32; 4]> = (0..n)
                .map(|i| match case % 3 {
                    0 => [rng.unit() as f32, rng.unit() as f32, rng.unit() as f32, 0.01],
                    1 => [(i % 5) as f32, 0.5, 0.5, 0.1],
                    _ => [i as f32, 2.0 * i as f32, 0.0, 0.3],
                })
                .collect();
            let mut tree = recs.clone();
            let mut key: Vec<u32> = (0..n as u32).collect();
            let mut material: Vec<u32> = (0..n as u32).map(|i| i * 3).collect();
            let colour = |k: u32| Rgb8([k as u8, (k >> 8) as u8, (k >> 16) as u8]);
            let mut color: Vec<Rgb8> = (0..n as u32).map(colour).collect();
            build(&mut tree, &mut key, &mut material, &mut color);
            check(&tree, &key, 0..n);
            for i in 0..n {
                let k = key[i] & crate::accel::pkd::INDEX_MASK;
                assert_eq!(tree[i], recs[k as usize], "record {i} kept its key");
                assert_eq!(material[i], k * 3, "record {i} kept its material");
                assert_eq!(color[i], colour(k), "record {i} kept its colour");
            }
        }
    }
}
