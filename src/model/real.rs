//! The float type the kernels are written against.
//!
//! The `cpu` engine runs the same arithmetic in `f64` (physics) or `f32` (the precision the
//! WGSL kernels have), so the kernel code is generic over this small trait, as parry does
//! with its `Real` alias.

use num_traits::{Float, FloatConst};

pub trait Real: Float + FloatConst + Default + Send + Sync + std::fmt::Debug + 'static {
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
}

impl Real for f32 {
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
        self.ln()
    }
    #[inline(always)]
    fn kln_1p(self) -> Self {
        self.ln_1p()
    }
}

impl Real for f64 {
    #[inline(always)]
    fn c(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn f64(self) -> f64 {
        self
    }
    // the project's own functions, which the AVX-512 lanes run too (`crate::lane_math`):
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
