//! Four f64 lanes in one AVX register (x86-64-v3: AVX2 and the rest of
//! `crate::simd::X86_64_V3_FEATURES`). A mask is a register of whole-lane bit patterns (all
//! ones where the condition holds), as the AVX comparisons make them.

use super::{simd_arithmetic, F64Lane, Lane, LaneMask, MANTISSA_BITS, ONE_BITS, TWO_52};
use std::arch::x86_64::*;

/// Four f64 lanes. A value exists only inside functions compiled for x86-64-v3 and called
/// where `crate::simd` detected it (the SAFETY notes below rest on that); the methods inline
/// into those functions.
#[derive(Clone, Copy)]
pub(crate) struct F64x4(__m256d);

/// The lanes a comparison of two [`F64x4`] holds in: all bits set in those lanes.
#[derive(Clone, Copy)]
pub(crate) struct Mask4(__m256d);

simd_arithmetic!(F64x4 {
    Add add _mm256_add_pd;
    Sub sub _mm256_sub_pd;
    Mul mul _mm256_mul_pd;
    Div div _mm256_div_pd;
});
simd_arithmetic!(Mask4 {
    BitAnd bitand _mm256_and_pd;
    BitOr bitor _mm256_or_pd;
    BitXor bitxor _mm256_xor_pd;
});

/// The sign bit of every lane.
const SIGN: f64 = -0.0;

impl std::ops::Neg for F64x4 {
    type Output = F64x4;
    #[inline(always)]
    fn neg(self) -> F64x4 {
        // SAFETY (this and every block below): AVX2 is present wherever an F64x4 exists
        F64x4(unsafe { _mm256_xor_pd(self.0, _mm256_set1_pd(SIGN)) })
    }
}

impl std::ops::Not for Mask4 {
    type Output = Mask4;
    #[inline(always)]
    fn not(self) -> Mask4 {
        Mask4(unsafe { _mm256_xor_pd(self.0, _mm256_castsi256_pd(_mm256_set1_epi64x(-1))) })
    }
}

impl LaneMask for Mask4 {
    #[inline(always)]
    fn splat(b: bool) -> Self {
        Mask4(unsafe { _mm256_castsi256_pd(_mm256_set1_epi64x(-i64::from(b))) })
    }
    #[inline(always)]
    fn any(self) -> bool {
        unsafe { _mm256_movemask_pd(self.0) != 0 }
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        unsafe { _mm256_movemask_pd(self.0) as u32 }
    }
}

/// `a OP b` in every lane as a mask, OP one of the `_CMP_*` predicates.
macro_rules! compare {
    ($a:expr, $b:expr, $op:ident) => {
        Mask4(unsafe { _mm256_cmp_pd::<$op>($a.0, $b.0) })
    };
}

impl Lane for F64x4 {
    type Scalar = f64;
    type Mask = Mask4;
    const WIDTH: usize = 4;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        F64x4(unsafe { _mm256_set1_pd(x) })
    }
    #[inline(always)]
    fn load(x: &[f64]) -> Self {
        let x = &x[..4];
        // SAFETY: four f64 are readable at `x` (the slice above)
        F64x4(unsafe { _mm256_loadu_pd(x.as_ptr()) })
    }
    #[inline(always)]
    fn store(self, out: &mut [f64]) {
        let out = &mut out[..4];
        // SAFETY: four f64 are writable at `out` (the slice above)
        unsafe { _mm256_storeu_pd(out.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn abs(self) -> Self {
        F64x4(unsafe { _mm256_andnot_pd(_mm256_set1_pd(SIGN), self.0) })
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        F64x4(unsafe { _mm256_sqrt_pd(self.0) })
    }
    #[inline(always)]
    fn floor(self) -> Self {
        F64x4(unsafe { _mm256_round_pd::<{ _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC }>(self.0) })
    }
    #[inline(always)]
    fn ceil(self) -> Self {
        F64x4(unsafe { _mm256_round_pd::<{ _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC }>(self.0) })
    }
    /// As the compiler lowers `a.max(b)` for one f64: `maxpd(b, a)` ((b > a) ? b : a, so `a`
    /// of two zeros and `a` where `b` is NaN), and `b` where `a` is NaN.
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        unsafe {
            let m = _mm256_max_pd(other.0, self.0);
            F64x4(_mm256_blendv_pd(m, other.0, _mm256_cmp_pd::<_CMP_UNORD_Q>(self.0, self.0)))
        }
    }
    /// As [`F64x4::max`], with `minpd(b, a)`.
    #[inline(always)]
    fn min(self, other: Self) -> Self {
        unsafe {
            let m = _mm256_min_pd(other.0, self.0);
            F64x4(_mm256_blendv_pd(m, other.0, _mm256_cmp_pd::<_CMP_UNORD_Q>(self.0, self.0)))
        }
    }
    #[inline(always)]
    fn lt(self, other: Self) -> Mask4 {
        compare!(self, other, _CMP_LT_OQ)
    }
    #[inline(always)]
    fn le(self, other: Self) -> Mask4 {
        compare!(self, other, _CMP_LE_OQ)
    }
    #[inline(always)]
    fn gt(self, other: Self) -> Mask4 {
        compare!(self, other, _CMP_GT_OQ)
    }
    #[inline(always)]
    fn ge(self, other: Self) -> Mask4 {
        compare!(self, other, _CMP_GE_OQ)
    }
    #[inline(always)]
    fn eq(self, other: Self) -> Mask4 {
        compare!(self, other, _CMP_EQ_OQ)
    }
    #[inline(always)]
    fn ne(self, other: Self) -> Mask4 {
        compare!(self, other, _CMP_NEQ_UQ)
    }
    #[inline(always)]
    fn select(m: Mask4, a: Self, b: Self) -> Self {
        F64x4(unsafe { _mm256_blendv_pd(b.0, a.0, m.0) })
    }
}

impl F64Lane for F64x4 {
    #[inline(always)]
    fn sign_negative(self) -> Mask4 {
        // the bits as a 64-bit integer: negative
        Mask4(unsafe { _mm256_castsi256_pd(_mm256_cmpgt_epi64(_mm256_setzero_si256(), _mm256_castpd_si256(self.0))) })
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        unsafe {
            let bit = _mm256_set1_pd(SIGN);
            F64x4(_mm256_or_pd(_mm256_andnot_pd(bit, self.0), _mm256_and_pd(sign.0, bit)))
        }
    }
    #[inline(always)]
    fn pow2i(self) -> Self {
        // `f64::pow2i`'s integer trick
        unsafe {
            let biased = _mm256_add_pd(self.0, _mm256_set1_pd(1023.0 + TWO_52));
            F64x4(_mm256_castsi256_pd(_mm256_slli_epi64::<52>(_mm256_castpd_si256(biased))))
        }
    }
    #[inline(always)]
    fn exponent_field_and_significand(self) -> (Self, Self) {
        // `f64`'s bit operations, lane by lane
        unsafe {
            let bits = _mm256_castpd_si256(self.0);
            let two_52 = _mm256_set1_pd(TWO_52);
            let field = _mm256_and_si256(_mm256_srli_epi64::<52>(bits), _mm256_set1_epi64x(0x7ff));
            let field = _mm256_sub_pd(_mm256_castsi256_pd(_mm256_or_si256(_mm256_castpd_si256(two_52), field)), two_52);
            let significand = _mm256_or_si256(
                _mm256_and_si256(bits, _mm256_set1_epi64x(MANTISSA_BITS as i64)),
                _mm256_set1_epi64x(ONE_BITS as i64),
            );
            (F64x4(field), F64x4(_mm256_castsi256_pd(significand)))
        }
    }
}
