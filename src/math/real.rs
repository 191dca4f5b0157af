//! The number type the geometric kernels are generic over.
//!
//! `f32` is the renderer, `f64` the accuracy oracle, and (later) SIMD lane types give the packet kernels.
//! Every comparison yields a [`Mask`] and every choice goes through [`Real::select`], so a scalar instance and
//! a lane instance evaluate the same IEEE operations in the same order: that is what makes packet results
//! bit-identical to the `f32` instance.

use std::fmt::Debug;
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

/// A boolean per lane: `bool` for scalars.
pub trait Mask: Copy + Debug + BitAnd<Output = Self> + BitOr<Output = Self> + Not<Output = Self> {
    /// True when any lane is set.
    fn any(self) -> bool;
    /// True when every lane is set.
    fn all(self) -> bool;
}

impl Mask for bool {
    #[inline(always)]
    fn any(self) -> bool {
        self
    }
    #[inline(always)]
    fn all(self) -> bool {
        self
    }
}

/// IEEE floating point, one value or one value per lane.
pub trait Real:
    Copy
    + Debug
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// The comparison result type.
    type Mask: Mask;
    /// Unit roundoff of the lane's float format (half an ulp of 1): 2⁻²⁴ for f32 lanes, 2⁻⁵³ for f64.
    const UNIT_ROUNDOFF: f64;
    /// `v` in every lane (rounded to nearest when narrowing).
    fn splat(v: f64) -> Self;
    /// Correctly rounded square root (NaN for negative input).
    fn sqrt(self) -> Self;
    /// `self < other`; false when either is NaN.
    fn lt(self, other: Self) -> Self::Mask;
    /// `self <= other`; false when either is NaN.
    fn le(self, other: Self) -> Self::Mask;
    /// `a` where `mask` is set, else `b`.
    fn select(mask: Self::Mask, a: Self, b: Self) -> Self;
    /// The smaller of the two by the hardware instruction (`minps`): which operand a NaN gives is not
    /// specified, so use it only where a NaN operand cannot change a result (BVH slab tests, whose NaN rays
    /// miss every primitive anyway).
    fn fast_min(self, other: Self) -> Self;
    /// The larger of the two by the hardware instruction; NaN behaviour as [`Real::fast_min`].
    fn fast_max(self, other: Self) -> Self;
    /// `|self|`, exactly (sign bit cleared).
    fn abs(self) -> Self;
    /// `self · m + a` rounded once (fused multiply-add) in every instance, so a kernel that uses it gives
    /// the same bits at every width.
    fn mul_add(self, m: Self, a: Self) -> Self;

    /// `self > other`.
    #[inline(always)]
    fn gt(self, other: Self) -> Self::Mask {
        other.lt(self)
    }
    /// `self >= other`.
    #[inline(always)]
    fn ge(self, other: Self) -> Self::Mask {
        other.le(self)
    }
    /// The smaller of the two, `other` when either is NaN (the SIMD `min` rule, spelled out for scalars).
    #[inline(always)]
    fn min_of(self, other: Self) -> Self {
        Self::select(self.lt(other), self, other)
    }
    /// The larger of the two, `other` when either is NaN.
    #[inline(always)]
    fn max_of(self, other: Self) -> Self {
        Self::select(other.lt(self), self, other)
    }
}

macro_rules! impl_real_scalar {
    ($t:ty) => {
        impl Real for $t {
            type Mask = bool;
            const UNIT_ROUNDOFF: f64 = <$t>::EPSILON as f64 * 0.5;
            #[inline(always)]
            fn splat(v: f64) -> Self {
                v as $t
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            #[inline(always)]
            fn lt(self, other: Self) -> bool {
                self < other
            }
            #[inline(always)]
            fn le(self, other: Self) -> bool {
                self <= other
            }
            #[inline(always)]
            fn select(mask: bool, a: Self, b: Self) -> Self {
                if mask {
                    a
                } else {
                    b
                }
            }
            #[inline(always)]
            fn fast_min(self, other: Self) -> Self {
                <$t>::min(self, other)
            }
            #[inline(always)]
            fn fast_max(self, other: Self) -> Self {
                <$t>::max(self, other)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            #[inline(always)]
            fn mul_add(self, m: Self, a: Self) -> Self {
                <$t>::mul_add(self, m, a)
            }
        }
    };
}

impl_real_scalar!(f32);
impl_real_scalar!(f64);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn min_max_follow_the_simd_nan_rule() {
        assert_eq!(1.0f32.min_of(2.0), 1.0);
        assert_eq!(2.0f32.max_of(1.0), 2.0);
        assert_eq!(f32::NAN.min_of(3.0), 3.0);
        assert!(3.0f32.min_of(f32::NAN).is_nan());
        assert_eq!(f64::NAN.max_of(-1.0), -1.0);
    }
}
