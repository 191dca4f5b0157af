//! Lane types: [`Real`] for wide's `f32x4`, `f32x8` and `f32x16`, and the [`Lanes`] trait packets are written
//! against. `f32` is the K = 1 instance, so single rays and every packet width are one generic
//! code path instantiated at different types. (At K = 1 the arithmetic is plain `f32`; the BVH walk is
//! single-ray SIMD — one ray against a wide node's children, and a leaf's spheres, at once — unless the scene
//! is compiled for the scalar path, which walks binary trees one box and one primitive at a time.)
//!
//! # Why the lane instances are bit-identical to `f32`
//!
//! Checked in wide 1.7.1's source (`f32x{4,8,16}_.rs`, with safe_arch underneath), for x86-64 with SSE4.1,
//! AVX and AVX-512F enabled (`target-cpu=native` on an AVX-512 machine; the default x86-64-v3 build takes
//! the same operations' AVX forms, f32x16 as two f32x8):
//!
//! - `+ − × ÷` are `addps/subps/mulps/divps` (and the `v…256/512` forms); `sqrt` is `sqrtps`. All are IEEE
//!   correctly rounded, exactly like the scalar `addss/…/sqrtss` the `f32` instance compiles to. Nothing here
//!   calls `recip` or `recip_sqrt` (approximate `rcpps`/`rsqrtps`), and LLVM does not fuse separate
//!   `fmul`/`fadd` without fast-math flags, so `a*b + c` rounds twice at every width.
//! - Fused multiply-add is used only where asked for, through [`Real::mul_add`]: `vfmadd…ps` in the lane
//!   types and `f32::mul_add` (`vfmadd…ss`, or libm's correctly rounded `fmaf` without the FMA feature) in
//!   the scalar one — one rounding in both. (Users: the sphere kernel's perpendicular distance, the cone
//!   kernel, the BVH slab test and the frustum tests.)
//! - Negation XORs the sign bit, as scalar negation does.
//! - `simd_lt`/`simd_le` use the *ordered* predicates (`cmpltps`, `_CMP_LT_OQ`, `_CMP_LE_OQ`): a NaN operand
//!   gives false, like scalar `<`/`<=`. The results are all-ones/all-zeros lanes (AVX-512 compares into a
//!   k-register and wide expands it back to a vector), so `&`, `|`, `!` on masks are plain bit operations.
//! - `select` blends on each lane's sign bit (`blendvps`, or `movepi32_mask` + masked blend on AVX-512). That
//!   agrees with a scalar `if` only for true masks, which is why `LaneMask` keeps its vector private: every
//!   mask comes from a comparison, a logical operation on masks, or [`Lanes::mask_from_bits`].
//!
//! What would break bit-exactness and is therefore not used by the kernels:
//!
//! - wide's `min`/`max` add NaN fix-ups and `fast_min`/`fast_max` return the *second* operand when either is
//!   NaN (`minps` semantics) — neither matches Rust's scalar `f32::min`/`max`, which ignore a NaN operand.
//!   [`Real::min_of`]/[`Real::max_of`] are defined through `lt` + `select`, which every instance evaluates
//!   identically.
//! - `recip`, `recip_sqrt` (≈12-bit approximations), wide's own `mul_add`/`mul_sub` (unfused without the
//!   FMA feature; [`Real::mul_add`] guards that), `reduce_add`
//!   (tree order, not left to right), and the polynomial `exp`/`ln`/`sin_cos`/`powf` (not correctly rounded,
//!   and different from libm).
//! - NaN *payloads*: IEEE and LLVM leave which NaN an operation returns unspecified (x86 returns the first
//!   operand's, and LLVM may commute `a + b`). Lanes that are NaN are NaN at every width, but their bits may
//!   differ; no kernel returns a NaN `t` on a hit lane, because the hit test `t ≥ 0` rejects NaN.

mod lanes;
mod splat;

use std::fmt::Debug;
use std::ops::Add;

use crate::math::{Real, V3};

/// u32 values, one per lane: primitive ids travelling with a packet's `t` values.
pub trait IdLanes: Copy + Debug + PartialEq + Send + Sync + 'static + Add<Output = Self> {
    /// `[u32; K]`.
    type Array: AsRef<[u32]>;
    /// The lanes as an array.
    fn to_array(self) -> Self::Array;
    /// `v` in every lane.
    fn splat(v: u32) -> Self;
    /// Lane `i` is `f(i)`.
    fn from_fn(f: impl FnMut(usize) -> u32) -> Self;
    /// The value in lane `i` (panics when `i` is out of range).
    fn lane(self, i: usize) -> u32;
}

/// What packet code needs from a lane type beyond [`Real`]: its width, loads, lane access, masks as bits, and
/// id lanes selected by float masks. Implemented for `f32` (K = 1, single rays), `f32x4`, `f32x8`
/// and `f32x16`.
pub trait Lanes: Real {
    /// The number of lanes.
    const K: usize;
    /// `[f32; K]`.
    type Array: Copy + Debug + AsRef<[f32]> + AsMut<[f32]>;
    /// One u32 id per lane.
    type Ids: IdLanes;

    /// `v` in every lane, without the detour through f64 that [`Real::splat`] takes.
    fn splat_f32(v: f32) -> Self;
    /// Lane `i` is `f(i)`.
    fn from_fn(f: impl FnMut(usize) -> f32) -> Self;
    /// `src[at..at + K]` (panics when the slice is too short).
    fn load(src: &[f32], at: usize) -> Self;
    /// Like [`Lanes::load`], with `fill` in the lanes past the end of `src` (for the tail of an array).
    fn load_partial(src: &[f32], at: usize, fill: f32) -> Self;
    /// The lanes as an array.
    fn to_array(self) -> Self::Array;

    /// Bit `i` set when lane `i` of the mask is set (`movmskps`); bits K and above are zero.
    fn move_mask(m: Self::Mask) -> u32;
    /// Lane `i` set when bit `i` of `bits` is set; bits K and above are ignored.
    fn mask_from_bits(bits: u32) -> Self::Mask;
    /// Lane `i` of `if_true` where the mask is set, else of `if_false`.
    fn select_ids(m: Self::Mask, if_true: Self::Ids, if_false: Self::Ids) -> Self::Ids;
    /// `a == b` per lane, as a float mask.
    fn ids_eq(a: Self::Ids, b: Self::Ids) -> Self::Mask;
    /// `a < b` per lane (unsigned), as a float mask.
    fn ids_lt(a: Self::Ids, b: Self::Ids) -> Self::Mask;
    /// [`Real::select`] for a value stored back where `if_false` was loaded from, blended as integer lanes.
    /// LLVM turns a float blend stored over its own source into a masked store (`vmaskmovps`), which AMD
    /// Zen 1–3 run as microcode; the integer blend is stored as a plain vector. The same bits either way.
    fn select_stored(m: Self::Mask, if_true: Self, if_false: Self) -> Self;

    /// The value in lane `i` (panics when `i ≥ K`).
    #[inline(always)]
    fn lane(self, i: usize) -> f32 {
        self.to_array().as_ref()[i]
    }
    /// Lanes from exactly K values (panics on any other length).
    #[inline(always)]
    fn from_lanes(values: &[f32]) -> Self {
        assert_eq!(values.len(), Self::K, "expected one value per lane");
        Self::load(values, 0)
    }
    /// Lane `i` set when `f(i)`.
    #[inline(always)]
    fn mask_from_fn(mut f: impl FnMut(usize) -> bool) -> Self::Mask {
        Self::mask_from_bits((0..Self::K).fold(0, |bits, i| bits | (u32::from(f(i)) << i)))
    }
    /// Lane `i` set when `flags[i]`; `flags` has exactly K entries.
    #[inline(always)]
    fn mask_from_bools(flags: &[bool]) -> Self::Mask {
        assert_eq!(flags.len(), Self::K, "expected one flag per lane");
        Self::mask_from_fn(|i| flags[i])
    }
    /// Whether lane `i` of the mask is set.
    #[inline(always)]
    fn mask_lane(m: Self::Mask, i: usize) -> bool {
        assert!(i < Self::K, "lane {i} of {}", Self::K);
        (Self::move_mask(m) >> i) & 1 == 1
    }
    /// Lanes `0..n` set (all of them when `n ≥ K`): the valid lanes of an array's tail.
    #[inline(always)]
    fn lanes_below(n: usize) -> Self::Mask {
        let bits = if n >= 32 { u32::MAX } else { (1u32 << n) - 1 };
        Self::mask_from_bits(bits)
    }
    /// Lane `i` holds `i`: added to a base id, the ids of K consecutive primitives.
    #[inline(always)]
    fn lane_ids() -> Self::Ids {
        Self::Ids::from_fn(|i| i as u32)
    }
    /// `(xs[at..], ys[at..], zs[at..])` as a vector of lanes, padded with `fill` past the end.
    #[inline(always)]
    fn load_v3(xs: &[f32], ys: &[f32], zs: &[f32], at: usize, fill: f32) -> V3<Self> {
        V3::new(
            Self::load_partial(xs, at, fill),
            Self::load_partial(ys, at, fill),
            Self::load_partial(zs, at, fill),
        )
    }
    /// One scalar vector in every lane.
    #[inline(always)]
    fn splat_v3(v: V3<f32>) -> V3<Self> {
        v.map(Self::splat_f32)
    }
}

/// The indices of the set bits of `bits`, lowest first: a loop over the lanes of a mask that branches once
/// per set lane, not once per lane on whether it is set.
#[inline(always)]
pub(crate) fn set_bits(mut bits: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        let j = bits.trailing_zeros() as usize;
        bits &= bits.wrapping_sub(1);
        (j < 32).then_some(j)
    })
}

/// Asks the memory system to bring every cache line of `v[i]` close to the core: one line for a number, each
/// of a node's lines. A hint: no effect on any result, nothing when `i` is out of range or the target has no
/// prefetch instruction.
#[inline(always)]
#[cfg_attr(not(target_arch = "x86_64"), allow(unused_variables))]
pub(crate) fn prefetch<T>(v: &[T], i: usize) {
    #[cfg(target_arch = "x86_64")]
    if let Some(x) = v.get(i) {
        let p = std::ptr::from_ref(x).cast::<i8>();
        for line in (0..size_of::<T>()).step_by(64) {
            // SAFETY: a prefetch reads nothing architecturally and cannot fault; `p + line` lies within `v[i]`.
            unsafe { std::arch::x86_64::_mm_prefetch(p.add(line), std::arch::x86_64::_MM_HINT_T0) }
        }
    }
}
