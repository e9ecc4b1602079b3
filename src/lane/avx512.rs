//! Eight f64 lanes in one AVX-512 register (AVX-512F only, on top of x86-64-v3). A mask is
//! the AVX-512 mask register of the comparisons: one bit a lane.

use super::{simd_arithmetic, F64Lane, Lane, LaneMask, MANTISSA_BITS, ONE_BITS, TWO_52};
use std::arch::x86_64::*;

/// Eight f64 lanes. A value exists only inside functions compiled for AVX-512F and called
/// where `crate::simd` detected it (the SAFETY notes below rest on that); the methods inline
/// into those functions.
#[derive(Clone, Copy)]
pub(crate) struct F64x8(__m512d);

/// The lanes a comparison of two [`F64x8`] holds in: bit `l` for lane `l`.
#[derive(Clone, Copy)]
pub(crate) struct Mask8(__mmask8);

simd_arithmetic!(F64x8 {
    Add add _mm512_add_pd;
    Sub sub _mm512_sub_pd;
    Mul mul _mm512_mul_pd;
    Div div _mm512_div_pd;
});

impl std::ops::BitAnd for Mask8 {
    type Output = Mask8;
    #[inline(always)]
    fn bitand(self, other: Mask8) -> Mask8 {
        Mask8(self.0 & other.0)
    }
}
impl std::ops::BitOr for Mask8 {
    type Output = Mask8;
    #[inline(always)]
    fn bitor(self, other: Mask8) -> Mask8 {
        Mask8(self.0 | other.0)
    }
}
impl std::ops::BitXor for Mask8 {
    type Output = Mask8;
    #[inline(always)]
    fn bitxor(self, other: Mask8) -> Mask8 {
        Mask8(self.0 ^ other.0)
    }
}

impl std::ops::Neg for F64x8 {
    type Output = F64x8;
    #[inline(always)]
    fn neg(self) -> F64x8 {
        // SAFETY (this and every block below): AVX-512F is present wherever an F64x8 exists
        F64x8(unsafe {
            _mm512_castsi512_pd(_mm512_xor_si512(_mm512_castpd_si512(self.0), _mm512_set1_epi64(i64::MIN)))
        })
    }
}

impl std::ops::Not for Mask8 {
    type Output = Mask8;
    #[inline(always)]
    fn not(self) -> Mask8 {
        Mask8(!self.0)
    }
}

impl LaneMask for Mask8 {
    #[inline(always)]
    fn splat(b: bool) -> Self {
        Mask8(if b { 0xff } else { 0 })
    }
    #[inline(always)]
    fn any(self) -> bool {
        self.0 != 0
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        self.0 as u32
    }
}

/// `a OP b` in every lane as a mask, OP one of the `_CMP_*` predicates.
macro_rules! compare {
    ($a:expr, $b:expr, $op:ident) => {
        Mask8(unsafe { _mm512_cmp_pd_mask::<$op>($a.0, $b.0) })
    };
}

impl Lane for F64x8 {
    type Scalar = f64;
    type Mask = Mask8;
    const WIDTH: usize = 8;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        F64x8(unsafe { _mm512_set1_pd(x) })
    }
    #[inline(always)]
    fn load(x: &[f64]) -> Self {
        let x = &x[..8];
        // SAFETY: eight f64 are readable at `x` (the slice above)
        F64x8(unsafe { _mm512_loadu_pd(x.as_ptr()) })
    }
    #[inline(always)]
    fn store(self, out: &mut [f64]) {
        let out = &mut out[..8];
        // SAFETY: eight f64 are writable at `out` (the slice above)
        unsafe { _mm512_storeu_pd(out.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn abs(self) -> Self {
        F64x8(unsafe { _mm512_abs_pd(self.0) })
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        F64x8(unsafe { _mm512_sqrt_pd(self.0) })
    }
    #[inline(always)]
    fn floor(self) -> Self {
        F64x8(unsafe { _mm512_roundscale_pd::<{ _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC }>(self.0) })
    }
    #[inline(always)]
    fn ceil(self) -> Self {
        F64x8(unsafe { _mm512_roundscale_pd::<{ _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC }>(self.0) })
    }
    /// As the compiler lowers `a.max(b)` for one f64 (`lane::avx2::F64x4::max`):
    /// `maxpd(b, a)`, and `b` where `a` is NaN.
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        unsafe {
            let m = _mm512_max_pd(other.0, self.0);
            F64x8(_mm512_mask_blend_pd(_mm512_cmp_pd_mask::<_CMP_UNORD_Q>(self.0, self.0), m, other.0))
        }
    }
    /// As [`F64x8::max`], with `minpd(b, a)`.
    #[inline(always)]
    fn min(self, other: Self) -> Self {
        unsafe {
            let m = _mm512_min_pd(other.0, self.0);
            F64x8(_mm512_mask_blend_pd(_mm512_cmp_pd_mask::<_CMP_UNORD_Q>(self.0, self.0), m, other.0))
        }
    }
    #[inline(always)]
    fn lt(self, other: Self) -> Mask8 {
        compare!(self, other, _CMP_LT_OQ)
    }
    #[inline(always)]
    fn le(self, other: Self) -> Mask8 {
        compare!(self, other, _CMP_LE_OQ)
    }
    #[inline(always)]
    fn gt(self, other: Self) -> Mask8 {
        compare!(self, other, _CMP_GT_OQ)
    }
    #[inline(always)]
    fn ge(self, other: Self) -> Mask8 {
        compare!(self, other, _CMP_GE_OQ)
    }
    #[inline(always)]
    fn eq(self, other: Self) -> Mask8 {
        compare!(self, other, _CMP_EQ_OQ)
    }
    #[inline(always)]
    fn ne(self, other: Self) -> Mask8 {
        compare!(self, other, _CMP_NEQ_UQ)
    }
    #[inline(always)]
    fn select(m: Mask8, a: Self, b: Self) -> Self {
        F64x8(unsafe { _mm512_mask_blend_pd(m.0, b.0, a.0) })
    }
}

impl F64Lane for F64x8 {
    #[inline(always)]
    fn sign_negative(self) -> Mask8 {
        // the bits as a 64-bit integer: negative (`movepi64_mask` would need AVX-512DQ)
        Mask8(unsafe { _mm512_cmplt_epi64_mask(_mm512_castpd_si512(self.0), _mm512_setzero_si512()) })
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        unsafe {
            let bit = _mm512_set1_epi64(i64::MIN);
            let (a, s) = (_mm512_castpd_si512(self.0), _mm512_castpd_si512(sign.0));
            F64x8(_mm512_castsi512_pd(_mm512_or_si512(_mm512_andnot_si512(bit, a), _mm512_and_si512(s, bit))))
        }
    }
    #[inline(always)]
    fn pow2i(self) -> Self {
        // `f64::pow2i`'s integer trick
        unsafe {
            let biased = _mm512_add_pd(self.0, _mm512_set1_pd(1023.0 + TWO_52));
            F64x8(_mm512_castsi512_pd(_mm512_slli_epi64::<52>(_mm512_castpd_si512(biased))))
        }
    }
    #[inline(always)]
    fn exponent_field_and_significand(self) -> (Self, Self) {
        // `f64`'s bit operations, lane by lane
        unsafe {
            let bits = _mm512_castpd_si512(self.0);
            let two_52 = _mm512_set1_pd(TWO_52);
            let field = _mm512_and_si512(_mm512_srli_epi64::<52>(bits), _mm512_set1_epi64(0x7ff));
            let field = _mm512_sub_pd(_mm512_castsi512_pd(_mm512_or_si512(_mm512_castpd_si512(two_52), field)), two_52);
            let significand = _mm512_or_si512(
                _mm512_and_si512(bits, _mm512_set1_epi64(MANTISSA_BITS as i64)),
                _mm512_set1_epi64(ONE_BITS as i64),
            );
            (F64x8(field), F64x8(_mm512_castsi512_pd(significand)))
        }
    }
}
