//! The float type the kernels are written against.
//!
//! The `cpu` engine runs the same arithmetic in `f64` (physics) or `f32` (the precision the
//! WGSL kernels have), so the kernel code is generic over this small trait, as parry does
//! with its `Real` alias.

use crate::lane::Lane;
use num_traits::{Float, FloatConst};

pub trait Real: Float + FloatConst + Default + Into<f64> + Send + Sync + std::fmt::Debug + 'static {
    /// Convert a constant (always exactly representable or rounded once).
    fn c(x: f64) -> Self;
    fn f64(self) -> f64;
    /// sin and cos as the kernels compute them (see `ktrig`).
    fn ksin_cos(self) -> (Self, Self);
    /// atan2 as the kernels compute it (see `ktrig`).
    fn katan2(self, x: Self) -> Self;
    /// e^x - 1 as the kernels compute it.
    fn kexp_m1(self) -> Self;
    /// ln x as the kernels compute it.
    fn kln(self) -> Self;
    /// ln(1 + x) as the kernels compute it.
    fn kln_1p(self) -> Self;
    /// The number as a lane of one (`crate::lane`), for code written once over lanes that
    /// the scalar kernel runs too (the restitution law); it is the number itself.
    type One: Lane<Scalar = Self>;
    fn to_one(self) -> Self::One;
    fn from_one(x: Self::One) -> Self;
}

impl Real for f32 {
    type One = f32;
    #[inline(always)]
    fn to_one(self) -> f32 {
        self
    }
    #[inline(always)]
    fn from_one(x: f32) -> Self {
        x
    }
    #[inline(always)]
    fn c(x: f64) -> Self {
        x as f32
    }
    #[inline(always)]
    fn f64(self) -> f64 {
        self as f64
    }
    #[inline(always)]
    fn ksin_cos(self) -> (Self, Self) {
        ktrig::sin_cos(self)
    }
    #[inline(always)]
    fn katan2(self, x: Self) -> Self {
        ktrig::atan2(self, x)
    }
    #[inline(always)]
    fn kexp_m1(self) -> Self {
        self.exp_m1()
    }
    #[inline(always)]
    fn kln(self) -> Self {
        klog::ln(self)
    }
    #[inline(always)]
    fn kln_1p(self) -> Self {
        klog::ln_1p(self)
    }
}

impl Real for f64 {
    type One = f64;
    #[inline(always)]
    fn to_one(self) -> f64 {
        self
    }
    #[inline(always)]
    fn from_one(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn c(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn f64(self) -> f64 {
        self
    }
    // the project's own functions, which the SIMD lanes run too (`crate::lane_math`):
    // the same bits on both paths and on every libm
    #[inline(always)]
    fn ksin_cos(self) -> (Self, Self) {
        crate::lane_math::sin_cos(self)
    }
    #[inline(always)]
    fn katan2(self, x: Self) -> Self {
        crate::lane_math::atan2(self, x)
    }
    #[inline(always)]
    fn kexp_m1(self) -> Self {
        crate::lane_math::exp_m1(self)
    }
    #[inline(always)]
    fn kln(self) -> Self {
        crate::lane_math::ln(self)
    }
    #[inline(always)]
    fn kln_1p(self) -> Self {
        crate::lane_math::ln_1p(self)
    }
}

/// f32 trigonometry of the kernels, written out so the GPU and the CPU twin run the same
/// arithmetic: Vulkan only promises sin/cos to 2^-11 absolute and atan2 to 4096 ulp, which
/// moved first impacts by up to 19 µm. The textbook forms (reduction by π/2 in two pieces,
/// odd and even polynomials on |r| <= π/4; atan on [0, tan(π/8)] after (t-1)/(t+1) above
/// it) with the project's own near-minimax coefficients for f32
/// (`python3 scripts/fit_polynomials.py sin 2 f32`, `cos 2 f32`, `atan 3 f32`; about 1-3 ulp
/// on the kernels' arguments, docs/math.md). Twin: shaders/shared/trig.wgsl.
#[allow(clippy::approx_constant)] // π/2's pieces and tan(π/8), as f32
pub mod ktrig {
    const PIO2_HI: f32 = 1.570_796_3;
    const PIO2_LO: f32 = -4.371_139e-8;

    #[inline(always)]
    pub fn sin_cos(x: f32) -> (f32, f32) {
        let k = (x * std::f32::consts::FRAC_2_PI).round();
        let r = (x - k * PIO2_HI) - k * PIO2_LO;
        let z = r * r;
        let s = r + r * z * (-1.666_665_5e-1 + z * (8.332_178e-3 + z * -1.951_723_8e-4));
        let c = 1.0 - 0.5 * z + z * z * (4.166_664_6e-2 + z * (-1.388_736_7e-3 + z * 2.443_837_5e-5));
        match (k as i32).rem_euclid(4) {
            0 => (s, c),
            1 => (c, -s),
            2 => (-s, -c),
            _ => (-c, s),
        }
    }

    #[inline(always)]
    fn atan_unit(t: f32) -> f32 {
        // t in [0, 1]
        let (u, off) = if t > 0.414_213_57 { ((t - 1.0) / (t + 1.0), std::f32::consts::FRAC_PI_4) } else { (t, 0.0) };
        let z = u * u;
        off + ((((8.059_838_4e-2 * z - 1.387_971_6e-1) * z + 1.997_791_5e-1) * z - 3.333_295_6e-1) * z * u + u)
    }

    #[inline(always)]
    pub fn atan2(y: f32, x: f32) -> f32 {
        let (ax, ay) = (x.abs(), y.abs());
        if ax == 0.0 && ay == 0.0 {
            return 0.0;
        }
        let mut a = if ay <= ax { atan_unit(ay / ax) } else { std::f32::consts::FRAC_PI_2 - atan_unit(ax / ay) };
        if x < 0.0 {
            a = std::f32::consts::PI - a;
        }
        if y < 0.0 {
            -a
        } else {
            a
        }
    }

    #[cfg(test)]
    mod tests {
        #[test]
        fn close_to_libm_on_the_kernels_range() {
            let mut worst: f64 = 0.0;
            for i in 0..20_000 {
                let x = -7.0f32 + 14.0 * i as f32 / 20_000.0;
                let (s, c) = super::sin_cos(x);
                worst = worst.max((s as f64 - (x as f64).sin()).abs()).max((c as f64 - (x as f64).cos()).abs());
                let (yy, xx) = ((x * 1.3).sin(), (x * 0.7).cos());
                let a = super::atan2(yy, xx) as f64;
                worst = worst.max((a - (yy as f64).atan2(xx as f64)).abs());
            }
            assert!(worst < 1e-6, "{worst}");
        }
    }
}

/// The f32 kernels' natural logarithm, written out: Vulkan promises `log` only to 2^-21
/// absolute on [0.5, 2], which near 1 is no relative accuracy at all (a Box-Muller radius
/// sqrt(-2 ln u) may come out NaN, a short Stokes flight time far off), so the kernels do not
/// rely on the builtin (the H200's own was accurate enough on the conformance cases;
/// docs/math.md). ln x = e ln 2 + 2 atanh(s) with x = m 2^e,
/// m in [√½, √2), s = (m − 1)/(m + 1), |s| ≤ 0.1716: the atanh series to s⁹ is within 2e-9
/// relative, so the error is the rounding of s and of the sum, a few ulp, relative also near 1.
/// ln 2 in two pieces (the high one has 16 significant bits, so e·ln2_hi is exact).
/// Twin: shaders/shared/klog.wgsl (`kln`) and flight.wgsl (`log1p_`).
pub mod klog {
    const LN2_HI: f32 = 0.693_145_75;
    const LN2_LO: f32 = 1.428_606_8e-6;

    /// ln x for x > 0; x ≤ 0 (the kernels pass none) gives −f32::MAX, +∞ itself.
    #[inline(always)]
    pub fn ln(x: f32) -> f32 {
        // `!(x > 0)` also catches NaN
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !(x > 0.0) {
            return -f32::MAX;
        }
        if x > f32::MAX {
            return x;
        }
        let (mut x, mut e) = (x, 0i32);
        if x < f32::MIN_POSITIVE {
            // subnormal: scale by 2^23 into the normal range first
            x *= 8_388_608.0;
            e = -23;
        }
        let bits = x.to_bits();
        e += ((bits >> 23) & 0xff) as i32 - 127;
        let mut m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
        if m > std::f32::consts::SQRT_2 {
            m *= 0.5;
            e += 1;
        }
        let s = (m - 1.0) / (m + 1.0);
        let z = s * s;
        let p = 2.0 * s + 2.0 * s * z * (0.333_333_34 + z * (0.2 + z * (0.142_857_15 + z * 0.111_111_11)));
        let ef = e as f32;
        ef * LN2_HI + (ef * LN2_LO + p)
    }

    /// ln(1 + x) for x > −1: a series near 0, else `ln(1 + x)` with the rounding of 1 + x
    /// repaired (ln u · x / (u − 1), u = 1 + x; Goldberg's form).
    #[inline(always)]
    pub fn ln_1p(x: f32) -> f32 {
        if x.abs() < 0.01 {
            return x * (1.0 - x * (0.5 - x * (1.0 / 3.0 - x * (0.25 - x * 0.2))));
        }
        let u = 1.0 + x;
        if u > 16_777_216.0 {
            return ln(u);
        }
        ln(u) * (x / (u - 1.0))
    }

    #[cfg(test)]
    mod tests {
        fn ulps(a: f32, exact: f64) -> f64 {
            let e = exact as f32;
            let ulp = (f32::from_bits(e.abs().to_bits() + 1) - e.abs()) as f64;
            (a as f64 - exact).abs() / ulp
        }

        #[test]
        fn ln_is_within_a_few_ulp_everywhere_and_relative_near_one() {
            let mut worst: f64 = 0.0;
            // a sweep over 2^-140 .. 2^120 (subnormals included) ...
            for i in 0..200_000 {
                let x = 2f64.powf(-140.0 + 260.0 * i as f64 / 200_000.0) as f32;
                if x == 1.0 {
                    continue;
                }
                worst = worst.max(ulps(super::ln(x), (x as f64).ln()));
            }
            // ... and the arguments Vulkan's builtin gets wrong: 1 ± a few ulp to 1 ± 0.1
            for i in 1..200_000 {
                for x in [1.0 + i as f32 * 5e-7, 1.0 - i as f32 * 2.5e-7] {
                    if x != 1.0 {
                        worst = worst.max(ulps(super::ln(x), (x as f64).ln()));
                    }
                }
            }
            assert!(worst <= 4.0, "worst {worst} ulp");
            assert_eq!(super::ln(1.0), 0.0);
            assert_eq!(super::ln(f32::INFINITY), f32::INFINITY);
            assert_eq!(super::ln(0.0), -f32::MAX);
            assert_eq!(super::ln(-1.0), -f32::MAX);
        }

        #[test]
        fn ln_1p_is_relative_over_the_kernels_range() {
            let mut worst: f64 = 0.0;
            for i in 1..400_000 {
                let x = -0.99 + 1.0e4 * (i as f64 / 400_000.0).powi(4);
                let x = x as f32;
                worst = worst.max(ulps(super::ln_1p(x), (x as f64).ln_1p()));
            }
            assert!(worst <= 4.0, "worst {worst} ulp");
        }
    }
}
