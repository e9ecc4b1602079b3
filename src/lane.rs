//! The lane type: one number, or a vector of numbers on which code runs lane by lane.
//!
//! Code written once over [`Lane`] — the flight search of `engine::lanes`, the restitution
//! law of `model::collision`, the elementary functions of `crate::lane_math` — runs on one
//! `f64` or `f32` (the scalar kernel) and on the SIMD instantiations below, chosen at run
//! time by `crate::simd`:
//!
//! | type | lanes | instructions | module |
//! |---|---|---|---|
//! | `f64`, `f32` | 1 | the type's own | here |
//! | [`avx2::F64x4`] | 4 × f64 | AVX2 (x86-64-v3) | `lane/avx2.rs` |
//! | [`avx512::F64x8`] | 8 × f64 | AVX-512F | `lane/avx512.rs` |
//! | [`neon::F64x2`] | 2 × f64 | NEON (aarch64) | `lane/neon.rs` |
//!
//! Every operation is the IEEE operation of the scalar type in every lane, nothing more:
//! no fused multiply-add (Rust never contracts `a * b + c`, and no instantiation calls an
//! FMA instruction), ordered comparisons false where either side is NaN (`ne` true there,
//! as `!=`), and [`Lane::max`] and [`Lane::min`] with `f64::max`'s and `f64::min`'s
//! answers, signed zeros included. A branch of scalar code becomes a [`Lane::select`] of
//! both sides, so each lane gives the scalar code's bits.
//!
//! The SIMD types hold registers of an instruction set the CPU may lack: a value of one may
//! only be made inside a function compiled with that instruction set
//! (`#[target_feature]`) and called where `crate::simd` detected it. The types are
//! crate-private, and `engine::lanes` is the one place that instantiates code with them.

use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Neg, Not, Sub};

#[cfg(target_arch = "x86_64")]
pub(crate) mod avx2;
#[cfg(target_arch = "x86_64")]
pub(crate) mod avx512;
#[cfg(target_arch = "aarch64")]
pub(crate) mod neon;

/// A number or a vector of numbers: the IEEE operations of [`Lane::Scalar`] in every lane,
/// and comparisons that give a mask of lanes.
pub trait Lane:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> + Neg<Output = Self>
{
    /// The float of one lane.
    type Scalar: Copy + Into<f64>;
    /// Which lanes a comparison holds in (`bool` for one number).
    type Mask: LaneMask;
    /// How many lanes.
    const WIDTH: usize;
    /// `x` (rounded to the lane's float) in every lane.
    fn splat(x: f64) -> Self;
    /// The first [`Lane::WIDTH`] numbers of `x`, one a lane.
    fn load(x: &[Self::Scalar]) -> Self;
    /// The lanes into the first [`Lane::WIDTH`] places of `out`.
    fn store(self, out: &mut [Self::Scalar]);
    /// `|self|` (the sign bit cleared).
    fn abs(self) -> Self;
    /// The correctly rounded square root.
    fn sqrt(self) -> Self;
    /// Rounded down to a whole number.
    fn floor(self) -> Self;
    /// Rounded up to a whole number.
    fn ceil(self) -> Self;
    /// `f64::max`: the other operand where one is NaN.
    fn max(self, other: Self) -> Self;
    /// `f64::min`: the other operand where one is NaN.
    fn min(self, other: Self) -> Self;
    /// `self < other`, false where either is NaN.
    fn lt(self, other: Self) -> Self::Mask;
    /// `self <= other`, false where either is NaN.
    fn le(self, other: Self) -> Self::Mask;
    /// `self > other`, false where either is NaN.
    fn gt(self, other: Self) -> Self::Mask;
    /// `self >= other`, false where either is NaN.
    fn ge(self, other: Self) -> Self::Mask;
    /// `self == other`, false where either is NaN.
    fn eq(self, other: Self) -> Self::Mask;
    /// `self != other`, true where either is NaN.
    fn ne(self, other: Self) -> Self::Mask;
    /// `if m { a } else { b }` in every lane.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
}

/// Which lanes a condition holds in.
pub trait LaneMask:
    Copy + BitAnd<Output = Self> + BitOr<Output = Self> + BitXor<Output = Self> + Not<Output = Self>
{
    /// `b` in every lane.
    fn splat(b: bool) -> Self;
    /// Whether it holds in any lane (a branch that no lane takes is skipped).
    fn any(self) -> bool;
    /// Bit `l` set where it holds in lane `l`.
    fn bits(self) -> u32;
}

/// An f64 lane's bits, for the elementary functions of `crate::lane_math`.
pub trait F64Lane: Lane<Scalar = f64> {
    /// Whether the sign bit is set (true for -0.0).
    fn sign_negative(self) -> Self::Mask;
    /// `self` with the sign of `sign`.
    fn copysign(self, sign: Self) -> Self;
    /// 2^k for a whole number k in [-1022, 1024] (infinity at 1024); anything outside gives
    /// an unspecified number.
    fn pow2i(self) -> Self;
    /// The biased exponent field (0 to 2047, as a number) and the significand with the
    /// exponent field set to 1023 (in [1, 2)), read from the bits.
    fn exponent_field_and_significand(self) -> (Self, Self);
}

impl LaneMask for bool {
    #[inline(always)]
    fn splat(b: bool) -> Self {
        b
    }
    #[inline(always)]
    fn any(self) -> bool {
        self
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        self as u32
    }
}

/// One `f64` or `f32` as a lane: its own operations (a select is a branch).
macro_rules! one_lane {
    ($t:ty) => {
        impl Lane for $t {
            type Scalar = $t;
            type Mask = bool;
            const WIDTH: usize = 1;
            #[inline(always)]
            fn splat(x: f64) -> Self {
                x as $t
            }
            #[inline(always)]
            fn load(x: &[$t]) -> Self {
                x[0]
            }
            #[inline(always)]
            fn store(self, out: &mut [$t]) {
                out[0] = self;
            }
            #[inline(always)]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            #[inline(always)]
            fn floor(self) -> Self {
                <$t>::floor(self)
            }
            #[inline(always)]
            fn ceil(self) -> Self {
                <$t>::ceil(self)
            }
            #[inline(always)]
            fn max(self, other: Self) -> Self {
                <$t>::max(self, other)
            }
            #[inline(always)]
            fn min(self, other: Self) -> Self {
                <$t>::min(self, other)
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
            fn gt(self, other: Self) -> bool {
                self > other
            }
            #[inline(always)]
            fn ge(self, other: Self) -> bool {
                self >= other
            }
            #[inline(always)]
            fn eq(self, other: Self) -> bool {
                self == other
            }
            #[inline(always)]
            fn ne(self, other: Self) -> bool {
                self != other
            }
            #[inline(always)]
            fn select(m: bool, a: Self, b: Self) -> Self {
                if m {
                    a
                } else {
                    b
                }
            }
        }
    };
}
one_lane!(f64);
one_lane!(f32);

/// The 52 stored significand bits of an f64.
pub const MANTISSA_BITS: u64 = 0x000f_ffff_ffff_ffff;
/// 1.0's bits: the exponent field 1023.
pub const ONE_BITS: u64 = 0x3ff0_0000_0000_0000;
/// 2^52: adding it to a whole number below 2^52 leaves the number in the low mantissa bits.
pub const TWO_52: f64 = 4_503_599_627_370_496.0;

impl F64Lane for f64 {
    #[inline(always)]
    fn sign_negative(self) -> bool {
        self.is_sign_negative()
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        f64::copysign(self, sign)
    }
    #[inline(always)]
    fn pow2i(self) -> Self {
        // k + 1023 as the low bits of a number in [2^52, 2^53), shifted into the exponent
        f64::from_bits((self + (1023.0 + TWO_52)).to_bits() << 52)
    }
    #[inline(always)]
    fn exponent_field_and_significand(self) -> (Self, Self) {
        let bits = self.to_bits();
        // the field as the low bits of a number in [2^52, 2^53), minus 2^52
        let field = f64::from_bits(TWO_52.to_bits() | ((bits >> 52) & 0x7ff)) - TWO_52;
        (field, f64::from_bits((bits & MANTISSA_BITS) | ONE_BITS))
    }
}

/// The arithmetic operators of a SIMD lane type `$v` (a newtype of its register), each
/// one intrinsic.
macro_rules! simd_arithmetic {
    ($v:ident { $($op:ident $method:ident $intrinsic:path;)* }) => {$(
        impl std::ops::$op for $v {
            type Output = $v;
            #[inline(always)]
            fn $method(self, other: $v) -> $v {
                // SAFETY: the instruction set is present wherever a value exists (the type's note)
                $v(unsafe { $intrinsic(self.0, other.0) })
            }
        }
    )*};
}
#[allow(unused_imports)] // used by the instruction sets of this target only
pub(crate) use simd_arithmetic;
