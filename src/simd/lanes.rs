//! The [`Real`], [`Mask`] and [`Lanes`] instances: `f32` by hand (K = 1), the wide types by one macro.

use std::fmt;
use std::ops::{BitAnd, BitOr, Not};

use wide::{f32x16, f32x4, f32x8, u32x16, u32x4, u32x8};

use super::{IdLanes, Lanes};
use crate::math::{Mask, Real};

/// A per-lane boolean for a wide float type: each lane all ones (true) or all zeros (false).
///
/// The vector is private so that only comparisons, mask logic and [`Lanes::mask_from_bits`] make masks:
/// wide's `select` reads the sign bit alone, which matches a scalar `if` only for such all-or-nothing lanes.
/// There is no `PartialEq`: an all-ones lane is a NaN as a float; compare [`Lanes::move_mask`] instead.
/// `Debug` prints the bitmask with lane 0 as the rightmost digit.
#[derive(Clone, Copy)]
#[repr(transparent)]
pub struct LaneMask<V>(V);

impl<V: BitAnd<Output = V>> BitAnd for LaneMask<V> {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        Self(self.0 & o.0)
    }
}

impl<V: BitOr<Output = V>> BitOr for LaneMask<V> {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        Self(self.0 | o.0)
    }
}

impl<V: Not<Output = V>> Not for LaneMask<V> {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        Self(!self.0)
    }
}

impl IdLanes for u32 {
    type Array = [u32; 1];
    #[inline(always)]
    fn to_array(self) -> [u32; 1] {
        [self]
    }
    #[inline(always)]
    fn splat(v: u32) -> Self {
        v
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> u32) -> Self {
        f(0)
    }
    #[inline(always)]
    fn lane(self, i: usize) -> u32 {
        assert_eq!(i, 0, "a scalar has one lane");
        self
    }
}

impl Lanes for f32 {
    const K: usize = 1;
    type Array = [f32; 1];
    type Ids = u32;

    #[inline(always)]
    fn splat_f32(v: f32) -> Self {
        v
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f32) -> Self {
        f(0)
    }
    #[inline(always)]
    fn load(src: &[f32], at: usize) -> Self {
        src[at]
    }
    #[inline(always)]
    fn load_partial(src: &[f32], at: usize, fill: f32) -> Self {
        src.get(at).copied().unwrap_or(fill)
    }
    #[inline(always)]
    fn to_array(self) -> [f32; 1] {
        [self]
    }
    #[inline(always)]
    fn move_mask(m: bool) -> u32 {
        u32::from(m)
    }
    #[inline(always)]
    fn mask_from_bits(bits: u32) -> bool {
        bits & 1 == 1
    }
    #[inline(always)]
    fn select_ids(m: bool, if_true: u32, if_false: u32) -> u32 {
        if m {
            if_true
        } else {
            if_false
        }
    }
    #[inline(always)]
    fn select_stored(m: bool, if_true: f32, if_false: f32) -> f32 {
        <f32 as Real>::select(m, if_true, if_false)
    }
    #[inline(always)]
    fn ids_eq(a: u32, b: u32) -> bool {
        a == b
    }
    #[inline(always)]
    fn ids_lt(a: u32, b: u32) -> bool {
        a < b
    }
}

/// Implements everything for one width: float type, its u32 lanes, and K.
macro_rules! impl_lanes {
    ($f:ident, $u:ident, $k:literal) => {
        impl fmt::Debug for LaneMask<$f> {
            fn fmt(&self, out: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(out, "LaneMask({:0width$b})", self.0.to_bitmask(), width = $k)
            }
        }

        impl Mask for LaneMask<$f> {
            #[inline(always)]
            fn any(self) -> bool {
                self.0.any()
            }
            #[inline(always)]
            fn all(self) -> bool {
                self.0.all()
            }
        }

        impl Real for $f {
            type Mask = LaneMask<$f>;
            const UNIT_ROUNDOFF: f64 = f32::EPSILON as f64 * 0.5;
            #[inline(always)]
            fn splat(v: f64) -> Self {
                // The same single rounding as the scalar `v as f32`.
                $f::splat(v as f32)
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                $f::sqrt(self)
            }
            #[inline(always)]
            fn lt(self, other: Self) -> Self::Mask {
                LaneMask(self.simd_lt(other))
            }
            #[inline(always)]
            fn le(self, other: Self) -> Self::Mask {
                LaneMask(self.simd_le(other))
            }
            #[inline(always)]
            fn select(mask: Self::Mask, a: Self, b: Self) -> Self {
                mask.0.select(a, b)
            }
            #[inline(always)]
            fn fast_min(self, other: Self) -> Self {
                $f::fast_min(self, other)
            }
            #[inline(always)]
            fn fast_max(self, other: Self) -> Self {
                $f::fast_max(self, other)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                $f::abs(self)
            }
            #[inline(always)]
            fn mul_add(self, m: Self, a: Self) -> Self {
                // wide falls back to an unfused `a·b + c` without the FMA feature; fuse lane by lane then,
                // so the result is still the scalar `f32::mul_add`'s.
                if cfg!(target_feature = "fma") {
                    $f::mul_add(self, m, a)
                } else {
                    let (x, m, a) = (self.to_array(), m.to_array(), a.to_array());
                    $f::new(std::array::from_fn(|i| x[i].mul_add(m[i], a[i])))
                }
            }
        }

        impl IdLanes for $u {
            type Array = [u32; $k];
            #[inline(always)]
            fn to_array(self) -> [u32; $k] {
                $u::to_array(self)
            }
            #[inline(always)]
            fn splat(v: u32) -> Self {
                $u::splat(v)
            }
            #[inline(always)]
            fn from_fn(f: impl FnMut(usize) -> u32) -> Self {
                $u::new(std::array::from_fn(f))
            }
            #[inline(always)]
            fn lane(self, i: usize) -> u32 {
                self.as_array()[i]
            }
        }

        impl Lanes for $f {
            const K: usize = $k;
            type Array = [f32; $k];
            type Ids = $u;

            #[inline(always)]
            fn splat_f32(v: f32) -> Self {
                $f::splat(v)
            }
            #[inline(always)]
            fn from_fn(f: impl FnMut(usize) -> f32) -> Self {
                $f::new(std::array::from_fn(f))
            }
            #[inline(always)]
            fn load(src: &[f32], at: usize) -> Self {
                let lanes: [f32; $k] = src[at..at + $k].try_into().expect("slice of K values");
                $f::new(lanes)
            }
            #[inline(always)]
            fn load_partial(src: &[f32], at: usize, fill: f32) -> Self {
                if src.len() >= at + $k {
                    Self::load(src, at)
                } else {
                    Self::from_fn(|i| src.get(at + i).copied().unwrap_or(fill))
                }
            }
            #[inline(always)]
            fn to_array(self) -> [f32; $k] {
                $f::to_array(self)
            }
            #[inline(always)]
            fn move_mask(m: Self::Mask) -> u32 {
                m.0.to_bitmask()
            }
            #[inline(always)]
            fn mask_from_bits(bits: u32) -> Self::Mask {
                // Lane i tests bit i: all ones where set, all zeros elsewhere, as a comparison would give.
                let bit = $u::new(std::array::from_fn(|i| 1u32 << i));
                let set = ($u::splat(bits) & bit).simd_eq(bit);
                LaneMask($f::from_bits(set))
            }
            #[inline(always)]
            fn select_ids(m: Self::Mask, if_true: $u, if_false: $u) -> $u {
                // Reinterprets the float mask's bits as u32 lanes (wide's `Select<u32xK> for f32xK`).
                m.0.select(if_true, if_false)
            }
            #[inline(always)]
            fn select_stored(m: Self::Mask, if_true: Self, if_false: Self) -> Self {
                let bits: $u = m.0.select(if_true.to_bits(), if_false.to_bits());
                $f::from_bits(bits)
            }
            #[inline(always)]
            fn ids_eq(a: $u, b: $u) -> Self::Mask {
                LaneMask($f::from_bits(a.simd_eq(b)))
            }
            #[inline(always)]
            fn ids_lt(a: $u, b: $u) -> Self::Mask {
                LaneMask($f::from_bits(a.simd_lt(b)))
            }
        }
    };
}

impl_lanes!(f32x4, u32x4, 4);
impl_lanes!(f32x8, u32x8, 8);
impl_lanes!(f32x16, u32x16, 16);

#[cfg(test)]
mod tests {
    use super::*;

    fn masks_round_trip<F: Lanes>() {
        for bits in [0u32, 1, 0b1010, 0xFFFF, 0x8001] {
            let want = bits & ((1u64 << F::K) - 1) as u32;
            let m = F::mask_from_bits(bits);
            assert_eq!(F::move_mask(m), want, "K = {}", F::K);
            assert_eq!(F::move_mask(!m), !want & ((1u64 << F::K) - 1) as u32);
            for i in 0..F::K {
                assert_eq!(F::mask_lane(m, i), want >> i & 1 == 1);
            }
        }
        assert_eq!(F::move_mask(F::lanes_below(3)), (1 << F::K.min(3)) - 1);
        assert!(F::lanes_below(F::K).all());
    }

    #[test]
    fn mask_bits_round_trip_at_every_width() {
        masks_round_trip::<f32>();
        masks_round_trip::<f32x4>();
        masks_round_trip::<f32x8>();
        masks_round_trip::<f32x16>();
    }

    fn comparisons_and_selects<F: Lanes>() {
        let a = F::from_fn(|i| [1.0, f32::NAN, 3.0, -0.0][i % 4]);
        let b = F::splat_f32(0.0);
        let lt = b.lt(a);
        let le = b.le(a);
        for i in 0..F::K {
            let (x, y) = (a.lane(i), b.lane(i));
            assert_eq!(F::mask_lane(lt, i), y < x, "lane {i}");
            assert_eq!(F::mask_lane(le, i), y <= x, "lane {i}");
        }
        let ids = F::select_ids(lt, F::lane_ids(), F::Ids::splat(99));
        let (two, big) = (F::Ids::splat(2), F::Ids::splat(u32::MAX));
        for i in 0..F::K {
            assert_eq!(F::mask_lane(F::ids_eq(F::lane_ids(), two), i), i == 2);
            assert_eq!(F::mask_lane(F::ids_lt(F::lane_ids(), two), i), i < 2);
            assert!(F::mask_lane(F::ids_lt(F::lane_ids(), big), i), "unsigned compare");
        }
        for i in 0..F::K {
            let want = if b.lane(i) < a.lane(i) { i as u32 } else { 99 };
            assert_eq!(ids.lane(i), want);
        }
        // The integer-lane blend gives `select`'s bits, NaN and −0 included, with the mask either way round.
        for m in [lt, !lt] {
            let (stored, plain) = (F::select_stored(m, a, b), F::select(m, a, b));
            for i in 0..F::K {
                assert_eq!(stored.lane(i).to_bits(), plain.lane(i).to_bits(), "lane {i}");
            }
        }
    }

    #[test]
    fn nan_compares_false_and_ids_follow_float_masks() {
        comparisons_and_selects::<f32>();
        comparisons_and_selects::<f32x4>();
        comparisons_and_selects::<f32x8>();
        comparisons_and_selects::<f32x16>();
    }

    fn loads<F: Lanes>() {
        let src: Vec<f32> = (0..21).map(|i| i as f32).collect();
        assert_eq!(F::load(&src, 2).lane(0), 2.0);
        let tail = F::load_partial(&src, 20, -1.0);
        for i in 0..F::K {
            assert_eq!(tail.lane(i), if i == 0 { 20.0 } else { -1.0 });
        }
        let all = F::from_lanes(&src[5..5 + F::K]);
        assert_eq!(all.to_array().as_ref(), &src[5..5 + F::K]);
    }

    #[test]
    fn loads_pad_the_tail() {
        loads::<f32>();
        loads::<f32x4>();
        loads::<f32x8>();
        loads::<f32x16>();
    }
}
