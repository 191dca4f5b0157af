//! The slab test both walks run, the ray preparation it needs, and the fixed-capacity traversal stack.

use crate::geometry::Ray;
use crate::math::V3;
use crate::simd::Lanes;

/// Exit distances are widened by this factor so rounding never culls a box a ray enters. The fused slab
/// distance `fma(lo, 1/d, −o·(1/d))` (see [`slab_entry`]) is `(lo − o − o·δ)·(1/d)` rounded, |δ| ≤ u = ε/2:
/// the box plane moved by at most u·|o| and then relative errors (the rounded `1/d` and the final rounding),
/// at most γ₂ on every distance. Where |o| ≤ 2·reach the move is at most 2u·reach, inside the boxes'
/// [`padding`](super::padding); where |o| > 2·reach every box plane is more than |o|/2 away, so the move is
/// at most a further relative 2u. Entry and exit each err by at most γ₂ + 2u(1 + γ₂) < 4.01u; widening the
/// exit by 6ε = 12u (rounded up, and itself rounded) covers both sides.
pub(crate) const WIDEN: f32 = 1.0 + 6.0 * f32::EPSILON;

/// `1/d` with a zero component replaced by ±1e-30 first, so no slab product is 0·inf = NaN.
#[inline(always)]
pub(super) fn inverse<F: Lanes>(d: F) -> F {
    let tiny = F::splat_f32(1e-30);
    let away = F::select(d.lt(F::splat_f32(0.0)), -tiny, tiny);
    F::splat_f32(1.0) / F::select(d.abs().lt(tiny), away, d)
}

/// A ray (or a packet of them) prepared for slab tests: `1/d` and `−o·(1/d)`, so each box plane costs one
/// fused multiply-add.
#[derive(Clone, Copy)]
pub(crate) struct SlabRay<F> {
    pub(crate) inv_dir: V3<F>,
    pub(crate) neg_o_inv: V3<F>,
}

impl<F: Lanes> SlabRay<F> {
    #[inline(always)]
    pub(crate) fn new(ray: &Ray<F>) -> Self {
        let (origin, dir) = (&ray.origin, &ray.dir);
        let inv_dir = V3::new(inverse(dir.x), inverse(dir.y), inverse(dir.z));
        let neg = |o: F, inv: F| -(o * inv);
        Self {
            inv_dir,
            neg_o_inv: V3::new(neg(origin.x, inv_dir.x), neg(origin.y, inv_dir.y), neg(origin.z, inv_dir.z)),
        }
    }
}

/// The slab test both traversals run, in either layout: lanes = rays (one box, corners splatted; packet
/// traversal) or lanes = boxes (one ray splatted; single-ray traversal). Returns each lane's entry distance,
/// `inf` where it misses the box or enters beyond `limit`. Conservative by [`WIDEN`] and
/// [`padding`](super::padding).
#[inline(always)]
pub(crate) fn slab_entry<F: Lanes>(lo: [F; 3], hi: [F; 3], ray: &SlabRay<F>, limit: F) -> F {
    let slab = |lo: F, hi: F, inv: F, neg_o_inv: F| {
        let (t0, t1) = (lo.mul_add(inv, neg_o_inv), hi.mul_add(inv, neg_o_inv));
        (t0.fast_min(t1), t0.fast_max(t1))
    };
    let (i, n) = (&ray.inv_dir, &ray.neg_o_inv);
    let (nx, fx) = slab(lo[0], hi[0], i.x, n.x);
    let (ny, fy) = slab(lo[1], hi[1], i.y, n.y);
    let (nz, fz) = slab(lo[2], hi[2], i.z, n.z);
    entry_within([nx, ny, nz], [fx, fy, fz], limit)
}

/// [`slab_entry`] for rays whose direction signs are known: `near[a]` and `far[a]` are the planes a ray
/// meets first and last on axis a (lower and upper where `1/d` is positive). Fused rounding is monotone, so
/// where `1/d > 0` the lower plane's distance is never above the upper's: the min and max of [`slab_entry`]
/// pick exactly these, and both functions return the same bits — this one in 6 fewer operations.
#[inline(always)]
pub(super) fn slab_entry_ordered<F: Lanes>(near: [F; 3], far: [F; 3], ray: &SlabRay<F>, limit: F) -> F {
    let (i, n) = (&ray.inv_dir, &ray.neg_o_inv);
    let t = |p: F, inv: F, neg_o_inv: F| p.mul_add(inv, neg_o_inv);
    let (nx, ny, nz) = (t(near[0], i.x, n.x), t(near[1], i.y, n.y), t(near[2], i.z, n.z));
    let (fx, fy, fz) = (t(far[0], i.x, n.x), t(far[1], i.y, n.y), t(far[2], i.z, n.z));
    entry_within([nx, ny, nz], [fx, fy, fz], limit)
}

/// The entry distance from each axis's near and far plane distances: entering before the (widened) exit and
/// before the limit, else `inf`. Balanced trees keep the dependency chains short; entering before the exit
/// and before the limit is one comparison against the smaller of the two.
#[inline(always)]
pub(super) fn entry_within<F: Lanes>(near: [F; 3], far: [F; 3], limit: F) -> F {
    let entry = near[0].fast_max(near[1]).fast_max(near[2].fast_max(F::splat_f32(0.0)));
    let exit = (far[0].fast_min(far[1]).fast_min(far[2]) * F::splat_f32(WIDEN)).fast_min(limit);
    F::select(entry.le(exit), entry, F::splat_f32(f32::INFINITY))
}

/// Per axis, the side (0 lower, 1 upper) of the plane a ray with this `1/d` meets first: 1 where `1/d` is
/// negative. `inverse` never returns ±0, so the sign is the direction's.
#[inline(always)]
pub(super) fn near_side(inv: f32) -> usize {
    usize::from(inv < 0.0)
}

/// Deep enough for the trees the builders make (a 4-wide node pushes up to 3 entries per level; bareray's trees
/// are at most about 40 + 2 log2 n binary levels deep); the build checks each tree's need against it, and push
/// checks again.
pub(super) const STACK: usize = 256;

/// A fixed-capacity traversal stack on the call stack (a heap vector per packet costs more than a small
/// BVH's whole traversal).
pub(crate) struct Stack<E: Copy> {
    items: [std::mem::MaybeUninit<E>; STACK],
    len: usize,
}

impl<E: Copy> Stack<E> {
    #[inline(always)]
    pub(crate) fn new() -> Self {
        Self { items: [const { std::mem::MaybeUninit::uninit() }; STACK], len: 0 }
    }
    #[inline(always)]
    pub(crate) fn push(&mut self, e: E) {
        assert!(self.len < STACK, "BVH deeper than the traversal stack");
        self.items[self.len].write(e);
        self.len += 1;
    }
    /// Pushes `e` when `keep`, without a branch on `keep`: the entry is written either way and the length
    /// moves by `keep`, so a child entered by an unpredictable set of lanes costs no misprediction.
    #[inline(always)]
    pub(super) fn push_if(&mut self, e: E, keep: bool) {
        assert!(self.len < STACK, "BVH deeper than the traversal stack");
        self.items[self.len].write(e);
        self.len += usize::from(keep);
    }
    #[inline(always)]
    pub(crate) fn pop(&mut self) -> Option<E> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: entries below `len` were written by `push` and are plain `Copy` data.
        Some(unsafe { self.items[self.len].assume_init() })
    }
}
