//! The engine's elementary functions — `exp_m1`, `sin_cos`, `atan2`, `ln`, `ln_1p` —
//! written once, over the lane type of `crate::lane`: one `f64` (the scalar kernel) or a
//! vector of them (the SIMD lanes of `engine::lanes`). Each lane does the same IEEE
//! operations in the same order as the scalar code (no fused multiply-add, selects instead
//! of branches), so the lanes give the scalar kernel's bits by construction, on every CPU,
//! whatever the system's libm.
//!
//! The method (docs/math.md has the derivation and the measured error):
//! - `exp_m1`: x = k ln2 + r with |r| <= ln2/2 (Cody-Waite: ln2 in a 42-bit head and a
//!   tail, so k·head is exact), expm1(r) = r + r²/2 + r³ P(r), then
//!   expm1(x) = 2^k expm1(r) + (2^k - 1).
//! - `sin_cos`: x = k π/2 + r with |r| <= π/4 (π/2 in three pieces, the first two of 33
//!   bits, so k·piece is exact for |k| < 2^20), sin r = r + r³ S(r²),
//!   cos r = 1 - r²/2 + r⁴ C(r²), and the quadrant k mod 4 picks and signs them.
//! - `ln`: x = 2^e m from the bits, m in [√2/2, √2), s = (m - 1)/(m + 1),
//!   ln m = 2 atanh s = f - s (f - s² Q(s²)) with f = m - 1; `ln_1p`: ln(1 + x) rounded,
//!   times x / ((1 + x) - 1), which cancels the rounding of 1 + x.
//! - `atan2`: the octant by |y| against |x|, u = min/max or, above tan(π/8),
//!   (min - max)/(min + max) (one division either way), atan u = u + u³ A(u²), then
//!   π/4, π/2 ± a, π - a and the sign of y as the octant says.
//!
//! P, S, C, A and Q are near-minimax polynomials (weighted least squares by Lawson's
//! iteration on a Chebyshev grid, in 50-digit arithmetic) that `scripts/fit_polynomials.py`
//! computes; the coefficients below are its output rounded to f64. Measured against mpmath
//! (`scripts/lane_math_error.py`, 125 000 arguments each): at most 1.30 ulp (sin), 1.42
//! (cos), 1.57 (expm1), 1.42 (atan2), 1.11 (ln) and 2.24 (ln_1p); docs/math.md has the
//! arguments and the commands.

use crate::lane::{F64Lane, Lane};

/// 1.5 · 2^52: `(y + ROUNDER) - ROUNDER` is y rounded to the nearest whole number, ties to
/// even, for |y| < 2^51 — two additions, the same in every lane and without SSE4.1.
const ROUNDER: f64 = 6_755_399_441_055_744.0;

/// `y` rounded to a whole number, ties to even (|y| < 2^51).
#[inline(always)]
fn round_whole<T: F64Lane>(y: T) -> T {
    (y + T::splat(ROUNDER)) - T::splat(ROUNDER)
}

/// c[0] + c[1] z + ... + c[n-1] z^(n-1) by Horner's rule, from the highest coefficient.
#[inline(always)]
fn poly<T: Lane, const N: usize>(z: T, c: &[f64; N]) -> T {
    let mut p = T::splat(c[N - 1]);
    for &ci in c[..N - 1].iter().rev() {
        p = p * z + T::splat(ci);
    }
    p
}

// ---- exp_m1 ----

const INV_LN2: f64 = f64::from_bits(0x3ff7_1547_652b_82fe); // 1/ln 2
/// ln 2 cut to 42 significant bits: k · LN2_HI is exact for |k| < 2^11.
const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fefa_3800);
/// ln 2 - LN2_HI, rounded.
const LN2_LO: f64 = f64::from_bits(0x3d2e_f357_93c7_6730);
/// P(r) ≈ (expm1 r - r - r²/2) / r³ on |r| <= ln2/2, weighted by r² (its share of the
/// relative error); fit error 2^-61.7.
const EXPM1_P: [f64; 10] = [
    f64::from_bits(0x3fc5_5555_5555_5559),
    f64::from_bits(0x3fa5_5555_5555_5558),
    f64::from_bits(0x3f81_1111_1110_f6bc),
    f64::from_bits(0x3f56_c16c_16c1_4f4c),
    f64::from_bits(0x3f2a_01a0_1afe_0970),
    f64::from_bits(0x3efa_01a0_1ade_179b),
    f64::from_bits(0x3ec7_1ddf_85df_553a),
    f64::from_bits(0x3e92_7e4c_af61_4384),
    f64::from_bits(0x3e5a_f5ea_e7ec_4b97),
    f64::from_bits(0x3e21_f8de_7b55_5b01),
];

/// e^x - 1, accurate for small x (Cody-Waite reduction by ln 2 and a polynomial; see the
/// module's notes). Exact at ±0 (keeping the sign); -1 below -40, +inf above 709.78; NaN
/// for NaN.
#[inline(always)]
pub fn exp_m1<T: F64Lane>(x: T) -> T {
    // clamped so that k stays in the range of `pow2i`; expm1(-40) already rounds to -1 and
    // expm1(710) overflows
    let xc = T::select(T::splat(710.0).lt(x), T::splat(710.0), x);
    let xc = T::select(xc.lt(T::splat(-40.0)), T::splat(-40.0), xc);
    let k = round_whole(xc * T::splat(INV_LN2));
    let r = (xc - k * T::splat(LN2_HI)) - k * T::splat(LN2_LO);
    let z = r * r;
    let e = r + (T::splat(0.5) * z + z * r * poly(r, &EXPM1_P));
    let one = T::splat(1.0);
    // 2^k (e + 1) - 1: split so that neither the rounding of 2^k - 1 nor an overflowing
    // 2^k spoils it (above k = 56 the -1 is below half an ulp)
    let two_k = k.pow2i();
    let small_k = two_k * e + (two_k - one);
    let large_k = (e + one) * (k - one).pow2i() * T::splat(2.0);
    let y = T::select(T::splat(56.0).lt(k), large_k, small_k);
    T::select(x.eq(T::splat(0.0)), x, y)
}

// ---- sin_cos ----

const FRAC_2_PI: f64 = f64::from_bits(0x3fe4_5f30_6dc9_c883); // 2/π
/// π/2 in three pieces: the first two of 33 significant bits (k · piece exact for
/// |k| < 2^20), the third the rest rounded.
const PIO2_1: f64 = f64::from_bits(0x3ff9_21fb_5440_0000);
const PIO2_2: f64 = f64::from_bits(0x3dd0_b461_1a60_0000);
const PIO2_3: f64 = f64::from_bits(0x3ba3_198a_2e03_7073);
/// The largest |x| `sin_cos` reduces exactly enough (k < 2^19 quadrants); beyond it NaN.
pub const SIN_COS_MAX: f64 = 524_288.0;
/// S(z) ≈ (sin r - r) / r³, z = r², on |r| <= π/4, weighted by r²; fit error 2^-58.0.
const SIN_S: [f64; 6] = [
    f64::from_bits(0xbfc5_5555_5555_5549),
    f64::from_bits(0x3f81_1111_1110_f87b),
    f64::from_bits(0xbf2a_01a0_19c1_1b25),
    f64::from_bits(0x3ec7_1de3_577c_a0a7),
    f64::from_bits(0xbe5a_e5e6_6486_b8f2),
    f64::from_bits(0x3de5_d930_4aff_f5c0),
];
/// C(z) ≈ (cos r - 1 + r²/2) / r⁴, z = r², on |r| <= π/4, weighted by r⁴; fit error 2^-64.2.
const COS_C: [f64; 6] = [
    f64::from_bits(0x3fa5_5555_5555_554c),
    f64::from_bits(0xbf56_c16c_16c1_517e),
    f64::from_bits(0x3efa_01a0_19cb_1bd5),
    f64::from_bits(0xbe92_7e4f_809f_0aeb),
    f64::from_bits(0x3e21_ee9e_be95_d244),
    f64::from_bits(0xbda8_fae9_c9d1_e00e),
];

/// (sin x, cos x) (reduction by π/2 in three pieces and two polynomials; see the module's
/// notes). sin keeps the sign of ±0; NaN for NaN, infinities and |x| > [`SIN_COS_MAX`].
#[inline(always)]
pub fn sin_cos<T: F64Lane>(x: T) -> (T, T) {
    let k = round_whole(x * T::splat(FRAC_2_PI));
    let r = ((x - k * T::splat(PIO2_1)) - k * T::splat(PIO2_2)) - k * T::splat(PIO2_3);
    let z = r * r;
    let s = r + r * z * poly(z, &SIN_S);
    // 1 - z/2 rounds; (1 - w) - z/2 is that rounding's error, exactly, added back with the
    // tail
    let (one, hz) = (T::splat(1.0), T::splat(0.5) * z);
    let w = one - hz;
    let c = w + (((one - w) - hz) + z * z * poly(z, &COS_C));
    // the quadrant k mod 4 as q = k - 4 round(k/4) in {-2, -1, 0, 1, 2}
    let q = k - T::splat(4.0) * round_whole(k * T::splat(0.25));
    let (q_odd, q_even_two) = (q.eq(T::splat(1.0)) | q.eq(T::splat(-1.0)), q.abs().eq(T::splat(2.0)));
    let (sin, cos) = (T::select(q_odd, c, s), T::select(q_odd, s, c));
    let sin_negated = q_even_two | q.eq(T::splat(-1.0));
    let cos_negated = q_even_two | q.eq(T::splat(1.0));
    let inside = x.abs().le(T::splat(SIN_COS_MAX));
    let nan = T::splat(f64::NAN);
    // sin(±0) = ±0 (the polynomial's r + r z S gives +0 for -0)
    let sin = T::select(x.eq(T::splat(0.0)), x, sin);
    (
        T::select(inside, T::select(sin_negated, -sin, sin), nan),
        T::select(inside, T::select(cos_negated, -cos, cos), nan),
    )
}

// ---- atan2 ----

const TAN_FRAC_PI_8: f64 = f64::from_bits(0x3fda_8279_99fc_ef32); // tan(π/8) = √2 - 1
const FRAC_PI_4: f64 = std::f64::consts::FRAC_PI_4;
const FRAC_PI_2: f64 = std::f64::consts::FRAC_PI_2;
const PI: f64 = std::f64::consts::PI;
/// π/4, π/2 and π minus their f64 roundings above.
const FRAC_PI_4_LO: f64 = f64::from_bits(0x3c81_a626_3314_5c07);
const FRAC_PI_2_LO: f64 = f64::from_bits(0x3c91_a626_3314_5c07);
const PI_LO: f64 = f64::from_bits(0x3ca1_a626_3314_5c07);
/// A(z) ≈ (atan u - u) / u³, z = u², on |u| <= tan(π/8), weighted by u²; fit error 2^-59.5.
const ATAN_A: [f64; 11] = [
    f64::from_bits(0xbfd5_5555_5555_553d),
    f64::from_bits(0x3fc9_9999_9999_58e0),
    f64::from_bits(0xbfc2_4924_922b_0d20),
    f64::from_bits(0x3fbc_71c7_0e78_0fd4),
    f64::from_bits(0xbfb7_45cf_9071_c4c9),
    f64::from_bits(0x3fb3_b111_c198_189b),
    f64::from_bits(0xbfb1_0ebd_a207_ec37),
    f64::from_bits(0x3fad_f113_28ed_7c4c),
    f64::from_bits(0xbfa9_cdb2_f7e2_9225),
    f64::from_bits(0x3fa3_7eab_6ef2_1deb),
    f64::from_bits(0xbf92_5979_06d4_9db5),
];

/// The angle of the point (x, y) from the positive x axis, in [-π, π] (an octant reduction
/// and one polynomial; see the module's notes). IEEE's special values: ±0 or ±π on the
/// axes by the signs of the zeros, the diagonals' angles when both are infinite, NaN for NaN.
#[inline(always)]
pub fn atan2<T: F64Lane>(y: T, x: T) -> T {
    let (zero, one, inf) = (T::splat(0.0), T::splat(1.0), T::splat(f64::INFINITY));
    let (ax, ay) = (x.abs(), y.abs());
    // both infinite: the angle of (±1, ±1)
    let both_inf = ax.eq(inf) & ay.eq(inf);
    let (ax, ay) = (T::select(both_inf, one, ax), T::select(both_inf, one, ay));
    let steep = ax.lt(ay);
    let (n, d) = (T::select(steep, ax, ay), T::select(steep, ay, ax));
    // above tan(π/8), atan(n/d) = π/4 + atan((n - d)/(n + d)): one division either way
    let upper = (T::splat(TAN_FRAC_PI_8) * d).lt(n);
    let (num, den) = (T::select(upper, n - d, n), T::select(upper, n + d, d));
    let u = T::select(num.eq(zero), zero, num / den); // 0/0 at the origin
    let z = u * u;
    let mut a = u + u * z * poly(z, &ATAN_A);
    a = T::select(upper, T::splat(FRAC_PI_4) + (a + T::splat(FRAC_PI_4_LO)), a);
    // the octant's base angle plus or minus a, in one rounding: π/2 - a above the diagonal
    // and π/2 + a left of it, π - a left of the y axis otherwise (x = -0 counts as left,
    // as IEEE has it)
    let left = x.sign_negative();
    let minus = (steep & !left) | (!steep & left);
    let a_signed = T::select(minus, -a, a);
    let (base, base_lo) = (
        T::select(steep, T::splat(FRAC_PI_2), T::splat(PI)),
        T::select(steep, T::splat(FRAC_PI_2_LO), T::splat(PI_LO)),
    );
    a = T::select(steep | left, base + (base_lo + a_signed), a);
    // a NaN among x and y: NaN (the 0/0 guard above would give 0 for atan2(0, NaN))
    T::select(x.eq(x) & y.eq(y), a.copysign(y), x + y)
}

// ---- ln, ln_1p ----

/// 2^54: subnormals are scaled by it before their exponent is read.
const TWO_54: f64 = 18_014_398_509_481_984.0;
/// Q(z) ≈ (2 atanh s - 2s) / s³, z = s², on |s| <= (√2 - 1)/(√2 + 1), weighted by s²; fit
/// error 2^-58.5.
const LN_Q: [f64; 7] = [
    f64::from_bits(0x3fe5_5555_5555_5592),
    f64::from_bits(0x3fd9_9999_9997_fd4b),
    f64::from_bits(0x3fd2_4924_941f_7c85),
    f64::from_bits(0x3fcc_71c5_2037_a6f0),
    f64::from_bits(0x3fc7_4664_0358_5c48),
    f64::from_bits(0x3fc3_9a19_6de1_985e),
    f64::from_bits(0x3fc2_f06e_281c_9782),
];

/// The natural logarithm: x = 2^e m with m in [√2/2, √2) read from the bits (subnormals
/// scaled by 2^54 first), f = m - 1, s = f/(2 + f), and
/// ln(1 + f) = 2 atanh s = f - s (f - s² Q(s²)) (since 2s = f - s f); then e ln 2 added
/// in LN2_HI and LN2_LO. -inf at ±0, NaN below 0 and for NaN, +inf at +inf.
#[inline(always)]
pub fn ln<T: F64Lane>(x: T) -> T {
    let (zero, one) = (T::splat(0.0), T::splat(1.0));
    let subnormal = x.lt(T::splat(f64::MIN_POSITIVE));
    let (field, m) = T::select(subnormal, x * T::splat(TWO_54), x).exponent_field_and_significand();
    let e = field - T::splat(1023.0) - T::select(subnormal, T::splat(54.0), zero);
    // m in [√2/2, √2): f = m - 1 is exact either way
    let upper = T::splat(std::f64::consts::SQRT_2).lt(m);
    let (m, e) = (T::select(upper, T::splat(0.5) * m, m), T::select(upper, e + one, e));
    let f = m - one;
    let s = f / (T::splat(2.0) + f);
    let z = s * s;
    let y = e * T::splat(LN2_HI) + (e * T::splat(LN2_LO) + (f - s * (f - z * poly(z, &LN_Q))));
    let inf = T::splat(f64::INFINITY);
    let special = T::select(x.eq(zero), -inf, T::select(x.eq(inf), inf, T::splat(f64::NAN)));
    T::select(zero.lt(x) & x.lt(inf), y, special)
}

/// ln(1 + x), accurate for small x: with u = 1 + x rounded, ln(u) · x/(u - 1), which
/// cancels u's rounding (x itself where u rounds to 1). NaN below -1, -inf at -1.
#[inline(always)]
pub fn ln_1p<T: F64Lane>(x: T) -> T {
    let (one, inf) = (T::splat(1.0), T::splat(f64::INFINITY));
    let u = one + x;
    let d = u - one;
    let y = T::select(d.eq(T::splat(0.0)), x, ln(u) * (x / d));
    T::select(u.eq(inf), u, y)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// How many units in the last place `got` lies from `want` (both finite).
    fn ulps(got: f64, want: f64) -> f64 {
        if got == want {
            return 0.0;
        }
        let ulp = f64::from_bits((want.abs().max(f64::MIN_POSITIVE).to_bits() & 0x7ff0_0000_0000_0000) - (52 << 52));
        (got - want).abs() / ulp
    }

    /// Arguments spread over `lo..hi` (a fixed low-discrepancy walk), and magnitudes from
    /// 1e-300 up to `hi` with both signs.
    fn arguments(lo: f64, hi: f64, n: usize) -> Vec<f64> {
        let golden = 0.618_033_988_749_894_9;
        let mut xs: Vec<f64> = (0..n).map(|i| lo + (hi - lo) * ((i as f64 * golden) % 1.0)).collect();
        let top = hi.abs().max(lo.abs()).log10();
        xs.extend((0..n / 4).map(|i| {
            let x = 10f64.powf(-300.0 + (top + 300.0) * (i as f64 * golden % 1.0));
            if i % 2 == 0 {
                x
            } else {
                -x
            }
        }));
        xs
    }

    /// Within 3 ulp of this system's libm (itself within 1 ulp; ours measured within 1.6
    /// against mpmath, docs/math.md) over the kernels' ranges and tiny magnitudes.
    #[test]
    fn close_to_libm_over_the_kernels_ranges() {
        let mut worst = [0.0f64; 4];
        for x in arguments(-10.0, 10.0, 400_000) {
            let (s, c) = sin_cos(x);
            worst[0] = worst[0].max(ulps(s, x.sin()));
            worst[1] = worst[1].max(ulps(c, x.cos()));
        }
        for x in arguments(-745.0, 709.0, 400_000) {
            worst[2] = worst[2].max(ulps(exp_m1(x), x.exp_m1()));
        }
        let ys = arguments(-1e3, 1e3, 200_000);
        for (i, &y) in ys.iter().enumerate() {
            let x = ys[(i * 7919 + 13) % ys.len()];
            worst[3] = worst[3].max(ulps(atan2(y, x), y.atan2(x)));
        }
        assert!(worst.iter().all(|&w| w <= 3.0), "worst ulps from libm: sin, cos, expm1, atan2 = {worst:?}");
        let mut worst_ln = [0.0f64; 2];
        for x in arguments(0.0, 10.0, 400_000).into_iter().map(f64::abs).chain([5e-324, 1e-310, 1e300, f64::MAX]) {
            worst_ln[0] = worst_ln[0].max(ulps(ln(x), x.ln()));
        }
        for x in arguments(-0.999_999, 1e3, 400_000).into_iter().filter(|&x| x > -1.0) {
            worst_ln[1] = worst_ln[1].max(ulps(ln_1p(x), x.ln_1p()));
        }
        assert!(worst_ln.iter().all(|&w| w <= 3.0), "worst ulps from libm: ln, ln_1p = {worst_ln:?}");
    }

    /// The edges: signed zeros, infinities, NaN, overflow and the reduction's domain.
    #[test]
    fn special_values_follow_ieee() {
        let bits = |x: f64| x.to_bits();
        assert_eq!(bits(exp_m1(0.0)), bits(0.0));
        assert_eq!(bits(exp_m1(-0.0)), bits(-0.0));
        assert_eq!(exp_m1(f64::NEG_INFINITY), -1.0);
        assert_eq!(exp_m1(-50.0), -1.0);
        assert_eq!(exp_m1(f64::INFINITY), f64::INFINITY);
        assert_eq!(exp_m1(709.8), f64::INFINITY);
        let big = exp_m1(709.78);
        assert!(big.is_finite() && ulps(big, 709.78f64.exp_m1()) <= 2.0, "{big}");
        assert_eq!(exp_m1(1e-300), 1e-300);
        assert!(exp_m1(f64::NAN).is_nan());

        assert_eq!((bits(sin_cos(0.0).0), sin_cos(0.0).1), (bits(0.0), 1.0));
        assert_eq!((bits(sin_cos(-0.0).0), sin_cos(-0.0).1), (bits(-0.0), 1.0));
        for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, SIN_COS_MAX * 1.5, -1e300] {
            let (s, c) = sin_cos(x);
            assert!(s.is_nan() && c.is_nan(), "{x}");
        }
        let (s, c) = sin_cos(SIN_COS_MAX);
        assert!(ulps(s, SIN_COS_MAX.sin()) <= 2.0 && ulps(c, SIN_COS_MAX.cos()) <= 2.0);

        let pi = std::f64::consts::PI;
        for (y, x, want) in [
            (0.0, 0.0, 0.0),
            (-0.0, 0.0, -0.0),
            (0.0, -0.0, pi),
            (-0.0, -0.0, -pi),
            (0.0, -1.0, pi),
            (-0.0, -1.0, -pi),
            (1.0, 0.0, pi / 2.0),
            (-1.0, -0.0, -pi / 2.0),
            (f64::INFINITY, f64::INFINITY, pi / 4.0),
            (f64::INFINITY, f64::NEG_INFINITY, 3.0 * pi / 4.0),
            (f64::NEG_INFINITY, f64::NEG_INFINITY, -3.0 * pi / 4.0),
            (1.0, f64::INFINITY, 0.0),
            (1.0, f64::NEG_INFINITY, pi),
            (f64::NEG_INFINITY, 1.0, -pi / 2.0),
            (1.0, 1.0, pi / 4.0),
        ] {
            assert_eq!(bits(atan2(y, x)), bits(want), "atan2({y}, {x})");
        }
        for (y, x) in [(f64::NAN, 1.0), (1.0, f64::NAN), (f64::NAN, 0.0), (0.0, f64::NAN)] {
            assert!(atan2(y, x).is_nan(), "atan2({y}, {x})");
        }
    }

    /// Writes sample arguments and results, as bit patterns, for `scripts/lane_math_error.py`
    /// to hold against mpmath (run by hand: docs/math.md has the command). The arguments:
    /// the kernels' ranges, uniformly, and magnitudes spread over the exponents.
    #[test]
    #[ignore = "writes a file for the mpmath measurement; run by hand"]
    fn write_samples_for_mpmath() {
        use std::fmt::Write;
        let path = std::env::var("LANE_MATH_SAMPLES").unwrap_or_else(|_| "target/lane_math_samples.csv".into());
        let n: usize = std::env::var("LANE_MATH_N").map_or(100_000, |v| v.parse().expect("LANE_MATH_N is a count"));
        let mut out = String::from("function,x,y,result\n");
        for x in arguments(-10.0, 10.0, n) {
            let (s, c) = sin_cos(x);
            writeln!(
                out,
                "sin,{:016x},0,{:016x}\ncos,{:016x},0,{:016x}",
                x.to_bits(),
                s.to_bits(),
                x.to_bits(),
                c.to_bits()
            )
            .unwrap();
        }
        for x in arguments(-40.0, 709.0, n) {
            writeln!(out, "expm1,{:016x},0,{:016x}", x.to_bits(), exp_m1(x).to_bits()).unwrap();
        }
        for x in arguments(0.0, 10.0, n).into_iter().map(f64::abs) {
            writeln!(out, "ln,{:016x},0,{:016x}", x.to_bits(), ln(x).to_bits()).unwrap();
        }
        for x in arguments(-0.999_999, 1e3, n).into_iter().filter(|&x| x > -1.0) {
            writeln!(out, "ln_1p,{:016x},0,{:016x}", x.to_bits(), ln_1p(x).to_bits()).unwrap();
        }
        let ys = arguments(-1e3, 1e3, n);
        for (i, &y) in ys.iter().enumerate() {
            let x = ys[(i * 7919 + 13) % ys.len()];
            writeln!(out, "atan2,{:016x},{:016x},{:016x}", x.to_bits(), y.to_bits(), atan2(y, x).to_bits()).unwrap();
        }
        std::fs::write(&path, out).unwrap();
        eprintln!("wrote {path}");
    }

    /// ln and ln_1p at their edges.
    #[test]
    fn logarithms_special_values_follow_ieee() {
        let bits = |x: f64| x.to_bits();
        assert_eq!(ln(1.0), 0.0);
        assert_eq!(ln(0.0), f64::NEG_INFINITY);
        assert_eq!(ln(-0.0), f64::NEG_INFINITY);
        assert_eq!(ln(f64::INFINITY), f64::INFINITY);
        assert!(ln(-1.0).is_nan() && ln(f64::NAN).is_nan() && ln(f64::NEG_INFINITY).is_nan());
        assert_eq!(ln(5e-324), 5e-324f64.ln());
        assert_eq!(bits(ln_1p(0.0)), bits(0.0));
        assert_eq!(bits(ln_1p(-0.0)), bits(-0.0));
        assert_eq!(ln_1p(1e-300), 1e-300);
        assert_eq!(ln_1p(-1.0), f64::NEG_INFINITY);
        assert_eq!(ln_1p(f64::INFINITY), f64::INFINITY);
        assert!(ln_1p(-2.0).is_nan() && ln_1p(f64::NAN).is_nan());
    }

    /// `Lane::pow2i` over its whole range.
    #[test]
    fn pow2i_is_two_to_the_k() {
        for k in -1022..=1023 {
            assert_eq!((k as f64).pow2i(), 2f64.powi(k), "{k}");
        }
        assert_eq!(1024.0.pow2i(), f64::INFINITY);
    }
}
