//! Two f64 lanes in one NEON register (aarch64). A mask is a register of whole-lane bit
//! patterns (all ones where the condition holds), as the NEON comparisons make them.
//! `f64::max`, `f64::min`, `floor` and `ceil` of one f64 compile to `fmaxnm`, `fminnm`,
//! `frintm` and `frintp` on aarch64; the lanes use the same instructions on two.

use super::{simd_arithmetic, F64Lane, Lane, LaneMask, MANTISSA_BITS, ONE_BITS, TWO_52};
use std::arch::aarch64::*;

/// Two f64 lanes. A value exists only where NEON is present, which `crate::simd` detects
/// (the SAFETY notes below rest on that).
#[derive(Clone, Copy)]
pub(crate) struct F64x2(float64x2_t);

/// The lanes a comparison of two [`F64x2`] holds in: all bits set in those lanes.
#[derive(Clone, Copy)]
pub(crate) struct Mask2(uint64x2_t);

simd_arithmetic!(F64x2 {
    Add add vaddq_f64;
    Sub sub vsubq_f64;
    Mul mul vmulq_f64;
    Div div vdivq_f64;
});
simd_arithmetic!(Mask2 {
    BitAnd bitand vandq_u64;
    BitOr bitor vorrq_u64;
    BitXor bitxor veorq_u64;
});

impl std::ops::Neg for F64x2 {
    type Output = F64x2;
    #[inline(always)]
    fn neg(self) -> F64x2 {
        // SAFETY (this and every block below): NEON is present wherever an F64x2 exists
        F64x2(unsafe { vnegq_f64(self.0) })
    }
}

impl std::ops::Not for Mask2 {
    type Output = Mask2;
    #[inline(always)]
    fn not(self) -> Mask2 {
        Mask2(unsafe { veorq_u64(self.0, vdupq_n_u64(u64::MAX)) })
    }
}

impl LaneMask for Mask2 {
    #[inline(always)]
    fn splat(b: bool) -> Self {
        Mask2(unsafe { vdupq_n_u64(if b { u64::MAX } else { 0 }) })
    }
    #[inline(always)]
    fn any(self) -> bool {
        unsafe { vmaxvq_u32(vreinterpretq_u32_u64(self.0)) != 0 }
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        unsafe { (vgetq_lane_u64::<0>(self.0) & 1) as u32 | ((vgetq_lane_u64::<1>(self.0) & 1) as u32) << 1 }
    }
}

impl Lane for F64x2 {
    type Scalar = f64;
    type Mask = Mask2;
    const WIDTH: usize = 2;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        F64x2(unsafe { vdupq_n_f64(x) })
    }
    #[inline(always)]
    fn load(x: &[f64]) -> Self {
        let x = &x[..2];
        // SAFETY: two f64 are readable at `x` (the slice above)
        F64x2(unsafe { vld1q_f64(x.as_ptr()) })
    }
    #[inline(always)]
    fn store(self, out: &mut [f64]) {
        let out = &mut out[..2];
        // SAFETY: two f64 are writable at `out` (the slice above)
        unsafe { vst1q_f64(out.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn abs(self) -> Self {
        F64x2(unsafe { vabsq_f64(self.0) })
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        F64x2(unsafe { vsqrtq_f64(self.0) })
    }
    #[inline(always)]
    fn floor(self) -> Self {
        F64x2(unsafe { vrndmq_f64(self.0) })
    }
    #[inline(always)]
    fn ceil(self) -> Self {
        F64x2(unsafe { vrndpq_f64(self.0) })
    }
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        F64x2(unsafe { vmaxnmq_f64(self.0, other.0) })
    }
    #[inline(always)]
    fn min(self, other: Self) -> Self {
        F64x2(unsafe { vminnmq_f64(self.0, other.0) })
    }
    #[inline(always)]
    fn lt(self, other: Self) -> Mask2 {
        Mask2(unsafe { vcltq_f64(self.0, other.0) })
    }
    #[inline(always)]
    fn le(self, other: Self) -> Mask2 {
        Mask2(unsafe { vcleq_f64(self.0, other.0) })
    }
    #[inline(always)]
    fn gt(self, other: Self) -> Mask2 {
        Mask2(unsafe { vcgtq_f64(self.0, other.0) })
    }
    #[inline(always)]
    fn ge(self, other: Self) -> Mask2 {
        Mask2(unsafe { vcgeq_f64(self.0, other.0) })
    }
    #[inline(always)]
    fn eq(self, other: Self) -> Mask2 {
        Mask2(unsafe { vceqq_f64(self.0, other.0) })
    }
    #[inline(always)]
    fn ne(self, other: Self) -> Mask2 {
        !self.eq(other)
    }
    #[inline(always)]
    fn select(m: Mask2, a: Self, b: Self) -> Self {
        F64x2(unsafe { vbslq_f64(m.0, a.0, b.0) })
    }
}

impl F64Lane for F64x2 {
    #[inline(always)]
    fn sign_negative(self) -> Mask2 {
        // the bits as a 64-bit integer: negative
        Mask2(unsafe { vcltzq_s64(vreinterpretq_s64_f64(self.0)) })
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        // the sign bit from `sign`, the rest from `self`
        F64x2(unsafe { vbslq_f64(vdupq_n_u64(1 << 63), sign.0, self.0) })
    }
    #[inline(always)]
    fn pow2i(self) -> Self {
        // `f64::pow2i`'s integer trick
        unsafe {
            let biased = vaddq_f64(self.0, vdupq_n_f64(1023.0 + TWO_52));
            F64x2(vreinterpretq_f64_u64(vshlq_n_u64::<52>(vreinterpretq_u64_f64(biased))))
        }
    }
    #[inline(always)]
    fn exponent_field_and_significand(self) -> (Self, Self) {
        // `f64`'s bit operations, lane by lane
        unsafe {
            let bits = vreinterpretq_u64_f64(self.0);
            let field = vandq_u64(vshrq_n_u64::<52>(bits), vdupq_n_u64(0x7ff));
            let field =
                vsubq_f64(vreinterpretq_f64_u64(vorrq_u64(vdupq_n_u64(TWO_52.to_bits()), field)), vdupq_n_f64(TWO_52));
            let significand = vorrq_u64(vandq_u64(bits, vdupq_n_u64(MANTISSA_BITS)), vdupq_n_u64(ONE_BITS));
            (F64x2(field), F64x2(vreinterpretq_f64_u64(significand)))
        }
    }
}
