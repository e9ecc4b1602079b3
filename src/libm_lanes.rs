//! libm's functions on AVX-512 lanes, to the bit of the libm they were ported from: glibc
//! 2.36's `expm1`, `sincos` and `atan2` as glibc runs them on CPUs with FMA (`__expm1_fma`,
//! `__sincos_fma`, `__ieee754_atan2_fma`: fdlibm's `s_expm1.c` and the IBM Accurate
//! Mathematical Library's `s_sin.c`/`s_sincos.c`/`e_atan2.c` compiled with -mfma, so GCC
//! contracted some multiply-adds). Each port repeats the compiled code's operations in its
//! order, read from the disassembly, its branches as masks and the table lookups as gathers;
//! lanes outside the ported range call libm. The cpu engine's lanes (`engine::lanes`) and
//! the fill arc (`model::fill`) take a port only where [`expm1_ported`], [`sincos_ported`]
//! or [`atan2_ported`] finds it equal to this process's libm on probes over every branch,
//! and call libm one value at a time otherwise: the results never depend on the port being
//! right for another libm. Tests compare each port with libm over millions of arguments.

/// Whether the lane `expm1` gives this process's libm `expm1` on 4 124 probes over each of
/// its branches; checked once.
pub fn expm1_ported() -> bool {
    static PORTED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *PORTED.get_or_init(|| {
        // ±10^-20 to ±10^3 in 4096 steps, and the edges of fdlibm's ranges
        let mut probes: Vec<f64> = (0..4096)
            .map(|i| (if i % 5 == 0 { 1.0 } else { -1.0 }) * 10f64.powf(-20.0 + 23.0 * i as f64 / 4095.0))
            .collect();
        for w in [0x3c90_0000u64, 0x3fd6_2e42, 0x3fd6_2e43, 0x3ff0_a2b1, 0x3ff0_a2b2, 0x4043_6879, 0x4043_687a] {
            let x = f64::from_bits(w << 32);
            probes.extend([x, -x, f64::from_bits(x.to_bits() - 1), -f64::from_bits(x.to_bits() - 1)]);
        }
        agrees(
            &probes,
            |x| {
                let y = x.exp_m1();
                (y, y)
            },
            |a| {
                let y = lanes_expm1(a);
                (y, y)
            },
        )
    })
}

/// Whether the lane `sincos` gives this process's `f64::sin_cos` (libm's `sincos`, as the
/// kernel's `ksin_cos` calls it) on probes over each of its branches and table rows;
/// checked once.
pub fn sincos_ported() -> bool {
    static PORTED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *PORTED.get_or_init(|| {
        // -8 to 8 in 4096 steps (every table row and reduction quadrant the kernel meets),
        // magnitudes 10^-12 to 10^7, and the branch edges
        let mut probes: Vec<f64> = (0..4096).map(|i| -8.0 + 16.0 * i as f64 / 4095.0).collect();
        probes.extend(
            (0..1024).map(|i| (if i % 2 == 0 { 1.0 } else { -1.0 }) * 10f64.powf(-12.0 + 19.0 * i as f64 / 1023.0)),
        );
        for w in [0x3e40_0000u64, 0x3e50_0000, 0x3feb_6000, 0x4003_68fd] {
            let x = f64::from_bits(w << 32);
            probes.extend([x, -x, f64::from_bits(x.to_bits() - 1), -f64::from_bits(x.to_bits() - 1)]);
        }
        probes.push(f64::from_bits(0x3ffa_d1fb_5444_2d18)); // where libm's sincos and sin differ
        agrees(&probes, |x| std::hint::black_box(x).sin_cos(), lanes_sincos)
    })
}

/// Whether the lane `atan2` gives this process's libm `atan2` on probes over every quadrant,
/// both of its branches (the polynomial below |y/x| = 1/16 and the table) and their edges;
/// checked once.
pub fn atan2_ported() -> bool {
    static PORTED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *PORTED.get_or_init(|| {
        // points on circles of radii 10^-6 to 10 at 512 angles, and ratios at the branch
        // edges (1/16, the table's rows, 1) in every quadrant
        let mut probes: Vec<(f64, f64)> = Vec::new();
        for r in [1e-6, 1e-3, 0.37, 1.0, 10.0] {
            probes.extend((0..512).map(|i| {
                let a = -std::f64::consts::PI + 2.0 * std::f64::consts::PI * (i as f64 + 0.5) / 512.0;
                (r * a.sin(), r * a.cos())
            }));
        }
        for u in [1.0f64 / 16.0, 17.0 / 256.0, 0.5, 1.0, 2.0, 16.0] {
            for (sy, sx) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                probes.extend([(sy * u, sx), (sy * f64::from_bits(u.to_bits() + 1), sx), (sy, sx * u)]);
            }
        }
        probes.extend([(0.0, 1.0), (-0.0, -1.0), (1.0, 0.0), (0.0, 0.0)]);
        let ys: Vec<f64> = probes.iter().map(|p| p.0).collect();
        let xs: Vec<f64> = probes.iter().map(|p| p.1).collect();
        available()
            && atan2_on_lanes(&ys, &xs).iter().zip(&probes).all(|(r, (y, x))| r.to_bits() == y.atan2(*x).to_bits())
    })
}

/// The lane `atan2` of `ys[i]`, `xs[i]` (eight at a time), on a CPU where [`available`]
/// holds.
fn atan2_on_lanes(ys: &[f64], xs: &[f64]) -> Vec<f64> {
    assert!(available() && ys.len() == xs.len());
    let mut out = Vec::with_capacity(ys.len());
    #[cfg(target_arch = "x86_64")]
    // SAFETY: the CPU has AVX-512F and FMA (asserted above).
    unsafe {
        avx512::atan2_slice(ys, xs, &mut out)
    };
    out
}

/// `y.atan2(x)` of every pair `ys[i]`, `xs[i]`, in order: eight at a time where the port is
/// this libm's `atan2` ([`atan2_ported`]), else one at a time. The same bits either way.
pub fn atan2_all(ys: &[f64], xs: &[f64]) -> Vec<f64> {
    assert_eq!(ys.len(), xs.len(), "as many y as x");
    if !atan2_ported() {
        return ys.iter().zip(xs).map(|(y, x)| y.atan2(*x)).collect();
    }
    atan2_on_lanes(ys, xs)
}

/// `x.exp_m1()` of every argument, in order: eight at a time where the port is this libm's
/// `expm1` ([`expm1_ported`]), else one at a time. The same bits either way.
pub fn exp_m1_all(xs: &[f64]) -> Vec<f64> {
    if !expm1_ported() {
        return xs.iter().map(|x| x.exp_m1()).collect();
    }
    let mut out = Vec::with_capacity(xs.len());
    #[cfg(target_arch = "x86_64")]
    // SAFETY: the port is taken only where the CPU has AVX-512F and FMA.
    unsafe {
        avx512::expm1_slice(xs, &mut out)
    };
    out
}

/// `(x.sin(), x.cos())` of every angle, in order: eight at a time on the lanes where the
/// port is this libm's `sincos` ([`sincos_ported`]), else one at a time. The same bits as
/// `f64::sin_cos` (libm's `sincos`) either way.
pub fn sin_cos_all(angles: &[f64]) -> Vec<(f64, f64)> {
    if !sincos_ported() {
        return angles.iter().map(|x| x.sin_cos()).collect();
    }
    let mut out = Vec::with_capacity(angles.len());
    #[cfg(target_arch = "x86_64")]
    // SAFETY: the port is taken only where the CPU has AVX-512F and FMA.
    unsafe {
        avx512::sincos_slice(angles, &mut out)
    };
    out
}

/// Whether `lanes(x)` (eight at a time) equals `scalar(x)` to the bit on every probe; false
/// on a CPU without AVX-512F and FMA.
fn agrees(
    probes: &[f64],
    scalar: impl Fn(f64) -> (f64, f64),
    lanes: impl Fn([f64; 8]) -> ([f64; 8], [f64; 8]),
) -> bool {
    if !available() {
        return false;
    }
    probes.chunks(8).all(|chunk| {
        let mut a = [chunk[0]; 8];
        a[..chunk.len()].copy_from_slice(chunk);
        let (s, c) = lanes(a);
        a.iter().enumerate().all(|(l, &x)| {
            let (ws, wc) = scalar(x);
            ws.to_bits() == s[l].to_bits() && wc.to_bits() == c[l].to_bits()
        })
    })
}

/// Whether this CPU runs the ports (AVX-512F and FMA).
fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    return std::arch::is_x86_feature_detected!("avx512f") && std::arch::is_x86_feature_detected!("fma");
    #[allow(unreachable_code)]
    false
}

/// The lane `expm1` of eight arguments, on a CPU where [`available`] holds.
fn lanes_expm1(x: [f64; 8]) -> [f64; 8] {
    assert!(available());
    #[cfg(target_arch = "x86_64")]
    // SAFETY: the CPU has AVX-512F and FMA (asserted above).
    return unsafe { avx512::expm1_array(x) };
    #[allow(unreachable_code)]
    {
        unreachable!("available() is false off x86-64")
    }
}

/// The lane `sincos` of eight arguments, on a CPU where [`available`] holds.
fn lanes_sincos(x: [f64; 8]) -> ([f64; 8], [f64; 8]) {
    assert!(available());
    #[cfg(target_arch = "x86_64")]
    // SAFETY: the CPU has AVX-512F and FMA (asserted above).
    return unsafe { avx512::sincos_array(x) };
    #[allow(unreachable_code)]
    {
        unreachable!("available() is false off x86-64")
    }
}

#[cfg(target_arch = "x86_64")]
mod atan2;

#[cfg(target_arch = "x86_64")]
pub mod avx512 {
    use std::arch::x86_64::*;

    pub use super::atan2::atan2_lanes as atan2;

    // sincos: the constants and table (addresses: their place in Debian 12's libm.so.6,
    // where they were read and checked against glibc 2.36's source); do_sin, do_cos and
    // reduce_sincos repeat the instructions of __sin_fma/__cos_fma (0x702c0/0x70ad0), whose
    // inlined copies in __sincos_fma give the same results on every test argument.

    // POLYNOMIAL / TAYLOR_SIN coefficients (usncs.h)
    const S1: f64 = f64::from_bits(0xbfc5555555555555); // -0x1.5555555555555p-3   @0xbc760
    const S2: f64 = f64::from_bits(0x3f81111111110ece); //  0x1.1111111110ECEp-7   @0x948d8
    const S3: f64 = f64::from_bits(0xbf2a01a019db08b8); // -0x1.A01A019DB08B8p-13  @0xbc758
    const S4: f64 = f64::from_bits(0x3ec71de27b9a7ed9); //  0x1.71DE27B9A7ED9p-19  @0x948c8
    const S5: f64 = f64::from_bits(0xbe5addffc2fcdf59); // -0x1.ADDFFC2FCDF59p-26  @0x948c0
    const BIG: f64 = f64::from_bits(0x42c8000000000000); //  0x1.8p45               @0x948e8
    const HP0: f64 = f64::from_bits(0x3ff921fb54442d18); //  0x1.921FB54442D18p0    @0x8d088
    const HP1: f64 = f64::from_bits(0x3c91a62633145c07); //  0x1.1A62633145C07p-54  @0x8d0f8
    const MP1: f64 = f64::from_bits(0x3ff921fb58000000); //  0x1.921FB58000000p0    @0x94910
    const MP2: f64 = f64::from_bits(0xbe4dde973c000000); // -0x1.DDE973C000000p-27  @0x94918
    const PP3: f64 = f64::from_bits(0xbc8cb3b398000000); // -0x1.CB3B398000000p-55  @0x94920
    const PP4: f64 = f64::from_bits(0xbacd747f23e32ed7); // -0x1.d747f23e32ed7p-83  @0x94928
    const HPINV: f64 = f64::from_bits(0x3fe45f306dc9c883); // 0x1.45F306DC9C883p-1  @0x909f8
    const TOINT: f64 = f64::from_bits(0x4338000000000000); // 0x1.8p52              @0x91050

    // do_sin / do_cos polynomial (s_sin.c)
    const SN3: f64 = f64::from_bits(0xbfc5555555555515); // -1.66666666666664880952546298448555E-01 @0xbc768
    const SN5: f64 = f64::from_bits(0x3f811110e829872f); //  8.33333214285722277379541354343671E-03 @0x948f0
    const CS2: f64 = f64::from_bits(0x3fe0000000000000); //  4.99999999999999999999950396842453E-01 (=0.5) @0x84a80
    const CS4: f64 = f64::from_bits(0xbfa5555555555535); // -4.16666666666664434524222570944589E-02 @0xbc770
    const CS6: f64 = f64::from_bits(0x3f56c16bedd9e239); //  1.38888874007937613028114285595617E-03 @0x94900

    /// do_sin: `if (fabs (x) < 0.126) return TAYLOR_SIN (...)`   @0x948b8
    const TAYLOR_LIMIT: f64 = 0.126;

    // Branch limits on the high 32 bits of |x| (k = u.i[HIGH_HALF] & 0x7fffffff).
    const K_COS_TINY: i64 = 0x3e400000; // sincos: k < 0x3e400000 (|x| < 2^-27) -> x, 1.0
    const K_SMALL: i64 = 0x3feb6000; //    k < 0x3feb6000  (|x| < 0.855469)
    const K_MID: i64 = 0x400368fd; //      k < 0x400368fd  (|x| < 2.426265)
    const K_REDUCE: i64 = 0x419921FB; //   k < 0x419921FB  (|x| < 105414350)

    /// `__sincostab` (sysdeps/ieee754/dbl-64/sincostab.c), 110 groups of
    /// {sn, ssn, cs, ccs}.  Read from libm.so.6 at 0xa9d40 and checked equal to
    /// the glibc-2.36 source.
    static SINCOSTAB: [f64; 440] = [
        f64::from_bits(0x0000000000000000),
        f64::from_bits(0x0000000000000000),
        f64::from_bits(0x3ff0000000000000),
        f64::from_bits(0x0000000000000000),
        f64::from_bits(0x3f7fffeaaaaeeeef),
        f64::from_bits(0xbc1e45e2ec67b77c),
        f64::from_bits(0x3fefffc000155552),
        f64::from_bits(0x3c8f4a01a0196dae),
        f64::from_bits(0x3f8fffaaaaeeeed5),
        f64::from_bits(0xbc02ab639a9f0777),
        f64::from_bits(0x3fefff000155549f),
        f64::from_bits(0x3c828a28a03a5ef3),
        f64::from_bits(0x3f97ff7001033255),
        f64::from_bits(0x3bfefe2b51527336),
        f64::from_bits(0x3feffdc006bff7e6),
        f64::from_bits(0x3c8ae6dae86977bd),
        f64::from_bits(0x3f9ffeaaaeeee86f),
        f64::from_bits(0xbc3cd406fb224ae2),
        f64::from_bits(0x3feffc00155527d3),
        f64::from_bits(0xbc83b54492d89b5b),
        f64::from_bits(0x3fa3feb2b12d45d5),
        f64::from_bits(0x3c34ec54203d1c11),
        f64::from_bits(0x3feff9c03414a7ba),
        f64::from_bits(0x3c6991f4be6c59bf),
        f64::from_bits(0x3fa7fdc01032fba9),
        f64::from_bits(0xbc4599bdf46e997a),
        f64::from_bits(0x3feff7006bfdf99f),
        f64::from_bits(0xbc78b3b560648d5f),
        f64::from_bits(0x3fabfc6d78586dac),
        f64::from_bits(0x3c18e4fd03dbf236),
        f64::from_bits(0x3feff3c0c8103a31),
        f64::from_bits(0x3c74856dbddc0e66),
        f64::from_bits(0x3faffaaaeeed4edb),
        f64::from_bits(0xbc42d16d32684b69),
        f64::from_bits(0x3feff0015549f4d3),
        f64::from_bits(0x3c8328387b99426f),
        f64::from_bits(0x3fb1fc343d808bef),
        f64::from_bits(0xbc5f3d32e6f3be4f),
        f64::from_bits(0x3fefebc222a8ef9f),
        f64::from_bits(0x3c57934934f54c77),
        f64::from_bits(0x3fb3facb12d1755b),
        f64::from_bits(0xbc5921915299468c),
        f64::from_bits(0x3fefe7034129ef6f),
        f64::from_bits(0xbc6cbf4337c96f97),
        f64::from_bits(0x3fb5f911fd10b737),
        f64::from_bits(0xbc50184f02be9102),
        f64::from_bits(0x3fefe1c4c3c873eb),
        f64::from_bits(0xbc35a9c9057c4a02),
        f64::from_bits(0x3fb7f701032550e4),
        f64::from_bits(0x3c3afc2d1800501a),
        f64::from_bits(0x3fefdc06bf7e6b9b),
        f64::from_bits(0x3c831902b535f8db),
        f64::from_bits(0x3fb9f4902d55d1f9),
        f64::from_bits(0x3c52696d7eac1dc1),
        f64::from_bits(0x3fefd5c94b43e000),
        f64::from_bits(0xbc62e768cb4f92f9),
        f64::from_bits(0x3fbbf1b78568391d),
        f64::from_bits(0x3c5e91841dea4cc8),
        f64::from_bits(0x3fefcf0c800e99b1),
        f64::from_bits(0x3c6ea3d786d186ac),
        f64::from_bits(0x3fbdee6f16c1cce6),
        f64::from_bits(0xbc450f8e2fb71673),
        f64::from_bits(0x3fefc7d078d1bc88),
        f64::from_bits(0x3c8075d2447db685),
        f64::from_bits(0x3fbfeaaeee86ee36),
        f64::from_bits(0xbc4afcb2bcc6f03b),
        f64::from_bits(0x3fefc015527d5bd3),
        f64::from_bits(0x3c8b68f35094efb8),
        f64::from_bits(0x3fc0f3378ddd71d1),
        f64::from_bits(0x3c6d8468724f0f9e),
        f64::from_bits(0x3fefb7db2bfe0695),
        f64::from_bits(0x3c821dadf4f65ab1),
        f64::from_bits(0x3fc1f0d3d7afceaf),
        f64::from_bits(0xbc66ef95099769a5),
        f64::from_bits(0x3fefaf22263c4bd3),
        f64::from_bits(0xbc552ace133a2769),
        f64::from_bits(0x3fc2ee285e4ab88f),
        f64::from_bits(0xbc6e4d0f05dee058),
        f64::from_bits(0x3fefa5ea641c36f2),
        f64::from_bits(0x3c404da6ed17cc7c),
        f64::from_bits(0x3fc3eb312c5d66cb),
        f64::from_bits(0x3c647d666b66cb91),
        f64::from_bits(0x3fef9c340a7cc428),
        f64::from_bits(0x3c8c5b6b063b7462),
        f64::from_bits(0x3fc4e7ea4dc5f27b),
        f64::from_bits(0x3c5949db2ac072fc),
        f64::from_bits(0x3fef91ff40374d01),
        f64::from_bits(0xbc67d03f4d3a9e4c),
        f64::from_bits(0x3fc5e44fcfa126f3),
        f64::from_bits(0xbc66f443063f89b6),
        f64::from_bits(0x3fef874c2e1eecf6),
        f64::from_bits(0xbc8c6514e1332b16),
        f64::from_bits(0x3fc6e05dc05a4d4c),
        f64::from_bits(0xbbd32c5c8b81c940),
        f64::from_bits(0x3fef7c1afeffde24),
        f64::from_bits(0xbc78f55bc47540b1),
        f64::from_bits(0x3fc7dc102fbaf2b5),
        f64::from_bits(0x3c45ab50e23c97c3),
        f64::from_bits(0x3fef706bdf9ece1c),
        f64::from_bits(0xbc8698c80c36dcb4),
        f64::from_bits(0x3fc8d7632efaa944),
        f64::from_bits(0xbc620fa262cbb953),
        f64::from_bits(0x3fef643efeb82acd),
        f64::from_bits(0x3c76b00ac1fe28ac),
        f64::from_bits(0x3fc9d252d0cec312),
        f64::from_bits(0x3c59c43d80b1137d),
        f64::from_bits(0x3fef57948cff6797),
        f64::from_bits(0x3c6e3a0d3e03b1d5),
        f64::from_bits(0x3fcaccdb297a0765),
        f64::from_bits(0xbc59883b57d6cdeb),
        f64::from_bits(0x3fef4a6cbd1e3a79),
        f64::from_bits(0x3c813df0edaebb57),
        f64::from_bits(0x3fcbc6f84edc6199),
        f64::from_bits(0x3c69c1a56a7b0cab),
        f64::from_bits(0x3fef3cc7c3b3d16e),
        f64::from_bits(0xbc621a3ad28a3494),
        f64::from_bits(0x3fccc0a6588289a3),
        f64::from_bits(0xbc6868d09bc87c6b),
        f64::from_bits(0x3fef2ea5d753ffed),
        f64::from_bits(0x3c8cc4215f56d583),
        f64::from_bits(0x3fcdb9e15fb5a5d0),
        f64::from_bits(0xbc632e20d6cc6fc2),
        f64::from_bits(0x3fef20073086649f),
        f64::from_bits(0x3c7b940416c1984b),
        f64::from_bits(0x3fceb2a57f8ae5a3),
        f64::from_bits(0xbc60be06af572ceb),
        f64::from_bits(0x3fef10ec09c5873b),
        f64::from_bits(0x3c8d9072762c1283),
        f64::from_bits(0x3fcfaaeed4f31577),
        f64::from_bits(0xbc615d88508e32b8),
        f64::from_bits(0x3fef01549f7deea1),
        f64::from_bits(0x3c8d3c1e99e5cafd),
        f64::from_bits(0x3fd0515cbf65155c),
        f64::from_bits(0xbc79b8c29dfd8ec8),
        f64::from_bits(0x3feef141300d2f26),
        f64::from_bits(0xbc82aa1b08ded372),
        f64::from_bits(0x3fd0cd00cef36436),
        f64::from_bits(0xbc79fb0a0c93e2b5),
        f64::from_bits(0x3feee0b1fbc0f11c),
        f64::from_bits(0xbc4bfd2380bbc3b1),
        f64::from_bits(0x3fd14861aa94ddeb),
        f64::from_bits(0xbc6be881b5b615a4),
        f64::from_bits(0x3feecfa744d5efa1),
        f64::from_bits(0xbc556d0a4af541d0),
        f64::from_bits(0x3fd1c37d64c6b876),
        f64::from_bits(0x3c746076fe0dcff5),
        f64::from_bits(0x3feebe214f76efa8),
        f64::from_bits(0xbc802f9f12ba543e),
        f64::from_bits(0x3fd23e52111aaf36),
        f64::from_bits(0xbc74f080334eff18),
        f64::from_bits(0x3feeac2061bbaf4f),
        f64::from_bits(0x3c62c1d53e94658d),
        f64::from_bits(0x3fd2b8ddc43eb49f),
        f64::from_bits(0x3c61553899f2d807),
        f64::from_bits(0x3fee99a4c3a7cd83),
        f64::from_bits(0xbc82264b1bc53ce8),
        f64::from_bits(0x3fd3331e94049f87),
        f64::from_bits(0x3c7e0cb6b40c302c),
        f64::from_bits(0x3fee86aebf29a9ed),
        f64::from_bits(0x3c89397afdbb58a7),
        f64::from_bits(0x3fd3ad129769d3d8),
        f64::from_bits(0x3c003d5504878398),
        f64::from_bits(0x3fee733ea0193d40),
        f64::from_bits(0xbc86428b3546ce13),
        f64::from_bits(0x3fd426b7e69ee697),
        f64::from_bits(0xbc7f09c75705c59f),
        f64::from_bits(0x3fee5f54b436e9d0),
        f64::from_bits(0x3c87eb0fd02fc8bc),
        f64::from_bits(0x3fd4a00c9b0f3d20),
        f64::from_bits(0x3c7823ba6bb08ead),
        f64::from_bits(0x3fee4af14b2a449c),
        f64::from_bits(0xbc868ca02e8a6833),
        f64::from_bits(0x3fd5190ecf68a77a),
        f64::from_bits(0x3c7b357155eef0f3),
        f64::from_bits(0x3fee3614b680d6a5),
        f64::from_bits(0xbc727793aa015237),
        f64::from_bits(0x3fd591bc9fa2f597),
        f64::from_bits(0x3c67c74bac3fe0cb),
        f64::from_bits(0x3fee20bf49acd6c1),
        f64::from_bits(0xbc5660aec7ef636c),
        f64::from_bits(0x3fd60a1429078775),
        f64::from_bits(0x3c5b1fd80ba89133),
        f64::from_bits(0x3fee0af15a03dbce),
        f64::from_bits(0x3c5fe8e702771ae6),
        f64::from_bits(0x3fd682138a38d7f7),
        f64::from_bits(0xbc7d889202444aad),
        f64::from_bits(0x3fedf4ab3ebd875e),
        f64::from_bits(0xbc8e2d8a7e6736c4),
        f64::from_bits(0x3fd6f9b8e33a0255),
        f64::from_bits(0x3c742bc14ee9da0d),
        f64::from_bits(0x3feddded50f228d6),
        f64::from_bits(0xbc6e80c8d42ba2bf),
        f64::from_bits(0x3fd7710255764214),
        f64::from_bits(0xbc66ead7314bb6ce),
        f64::from_bits(0x3fedc6b7eb995912),
        f64::from_bits(0x3c54b364776dcd35),
        f64::from_bits(0x3fd7e7ee03c86d4e),
        f64::from_bits(0xbc7b63bcdabf5af2),
        f64::from_bits(0x3fedaf0b6b888e83),
        f64::from_bits(0x3c8a249e2b5e5cea),
        f64::from_bits(0x3fd85e7a12826949),
        f64::from_bits(0x3c78a40e9b5face0),
        f64::from_bits(0x3fed96e82f71a9dc),
        f64::from_bits(0x3c8ff61bd5d2039d),
        f64::from_bits(0x3fd8d4a4a774992f),
        f64::from_bits(0x3c744a02ea766326),
        f64::from_bits(0x3fed7e4e97e17b4a),
        f64::from_bits(0xbc63b770352bed94),
        f64::from_bits(0x3fd94a6be9f546c5),
        f64::from_bits(0xbc769ce13e683f58),
        f64::from_bits(0x3fed653f073e4040),
        f64::from_bits(0xbc876236434bec37),
        f64::from_bits(0x3fd9bfce02e80510),
        f64::from_bits(0x3c709e39a320b0a4),
        f64::from_bits(0x3fed4bb9e1c619e0),
        f64::from_bits(0x3c8f34bb77858f61),
        f64::from_bits(0x3fda34c91cc50cca),
        f64::from_bits(0xbc5a310e3b50cecd),
        f64::from_bits(0x3fed31bf8d8d7c06),
        f64::from_bits(0x3c7e60dd3089cbdd),
        f64::from_bits(0x3fdaa95b63a09277),
        f64::from_bits(0xbc66293eb13c0381),
        f64::from_bits(0x3fed1750727d94f0),
        f64::from_bits(0x3c80d52b1ec1a48e),
        f64::from_bits(0x3fdb1d8305321617),
        f64::from_bits(0xbc7ae242cb99f519),
        f64::from_bits(0x3fecfc6cfa52ad9f),
        f64::from_bits(0x3c88b5b5508f2a0d),
        f64::from_bits(0x3fdb913e30dbac43),
        f64::from_bits(0xbc7e38ad2f6c3ff1),
        f64::from_bits(0x3fece115909a82e5),
        f64::from_bits(0x3c81f139bb31109a),
        f64::from_bits(0x3fdc048b17b140a3),
        f64::from_bits(0x3c619fe6757e9fa7),
        f64::from_bits(0x3fecc54aa2b2972e),
        f64::from_bits(0x3c64ee162ba83a98),
        f64::from_bits(0x3fdc7767ec7fd19e),
        f64::from_bits(0xbc5eb14d1a3d5826),
        f64::from_bits(0x3feca90c9fc67d0b),
        f64::from_bits(0xbc646a81485e3462),
        f64::from_bits(0x3fdce9d2e3d4a51f),
        f64::from_bits(0xbc62fc8a12dae298),
        f64::from_bits(0x3fec8c5bf8ce1a84),
        f64::from_bits(0x3c7ab3d1a1590123),
        f64::from_bits(0x3fdd5bca34047661),
        f64::from_bits(0x3c728a44a75fc29c),
        f64::from_bits(0x3fec6f39208be53b),
        f64::from_bits(0xbc8741dbfbaadb42),
        f64::from_bits(0x3fddcd4c15329c9a),
        f64::from_bits(0x3c70d4c6e171fd9a),
        f64::from_bits(0x3fec51a48b8b175e),
        f64::from_bits(0xbc61bbb43b9aa880),
        f64::from_bits(0x3fde3e56c1582a69),
        f64::from_bits(0xbc50a4821099f88f),
        f64::from_bits(0x3fec339eb01ddd81),
        f64::from_bits(0xbc8caaf5ee82c5c0),
        f64::from_bits(0x3fdeaee8744b05f0),
        f64::from_bits(0xbc5789b43c9b027d),
        f64::from_bits(0x3fec1528065b7d50),
        f64::from_bits(0xbc8892111312e828),
        f64::from_bits(0x3fdf1eff6bc4f97b),
        f64::from_bits(0x3c717212f8a7525c),
        f64::from_bits(0x3febf641081e7536),
        f64::from_bits(0x3c8b7bd71628a9a1),
        f64::from_bits(0x3fdf8e99e76abc97),
        f64::from_bits(0x3c59d950af2d00a3),
        f64::from_bits(0x3febd6ea310294f5),
        f64::from_bits(0x3c731bbcc88c109d),
        f64::from_bits(0x3fdffdb628d2f57a),
        f64::from_bits(0x3c6f4a992e905b6a),
        f64::from_bits(0x3febb723fe630f32),
        f64::from_bits(0x3c772bd2452d0a39),
        f64::from_bits(0x3fe0362939c69955),
        f64::from_bits(0xbc82d8cd78397b01),
        f64::from_bits(0x3feb96eeef58840e),
        f64::from_bits(0x3c545a3cc78fade0),
        f64::from_bits(0x3fe06d3686946e5b),
        f64::from_bits(0x3c83f5ae4538ff1b),
        f64::from_bits(0x3feb764b84b704c2),
        f64::from_bits(0xbc8f5848c21b389b),
        f64::from_bits(0x3fe0a4021e9e1001),
        f64::from_bits(0xbc86f643a13914f6),
        f64::from_bits(0x3feb553a410c104e),
        f64::from_bits(0x3c58ff7947027a16),
        f64::from_bits(0x3fe0da8b26b5672e),
        f64::from_bits(0xbc8a58def0bee909),
        f64::from_bits(0x3feb33bba89c8948),
        f64::from_bits(0x3c8ea6a51d1f6ca9),
        f64::from_bits(0x3fe110d0c4b69c3b),
        f64::from_bits(0x3c8d918998809981),
        f64::from_bits(0x3feb11d04162a4c6),
        f64::from_bits(0x3c71dd561efbc0c2),
        f64::from_bits(0x3fe146d21f8b7f82),
        f64::from_bits(0x3c7bf9535e2739a8),
        f64::from_bits(0x3feaef78930bd275),
        f64::from_bits(0xbc7f836279746f94),
        f64::from_bits(0x3fe17c8e5f2eedb0),
        f64::from_bits(0x3c635e57102e2488),
        f64::from_bits(0x3feaccb526f69de5),
        f64::from_bits(0x3c88fb6a8dd6b6cc),
        f64::from_bits(0x3fe1b204acb02fdd),
        f64::from_bits(0xbc5f190c70cbb5ff),
        f64::from_bits(0x3feaa98688308913),
        f64::from_bits(0xbc0b83d607cd5070),
        f64::from_bits(0x3fe1e7343236574c),
        f64::from_bits(0x3c722a3fa4f41d5a),
        f64::from_bits(0x3fea85ed4373e02d),
        f64::from_bits(0x3c69be06385ec792),
        f64::from_bits(0x3fe21c1c1b0394cf),
        f64::from_bits(0x3c5e5b324b23aa31),
        f64::from_bits(0x3fea61e9e72586af),
        f64::from_bits(0x3c858330e2fd453f),
        f64::from_bits(0x3fe250bb93788bbb),
        f64::from_bits(0x3c7ea3d02457bcce),
        f64::from_bits(0x3fea3d7d0352bdcf),
        f64::from_bits(0xbc868dbaeca19669),
        f64::from_bits(0x3fe28511c917a067),
        f64::from_bits(0xbc801df1d9a16b70),
        f64::from_bits(0x3fea18a729aee445),
        f64::from_bits(0x3c395e25736c0358),
        f64::from_bits(0x3fe2b91dea88421e),
        f64::from_bits(0xbc8fa371db216ab0),
        f64::from_bits(0x3fe9f368ed912f85),
        f64::from_bits(0xbc81d200c5791606),
        f64::from_bits(0x3fe2ecdf279a3082),
        f64::from_bits(0x3c8d3557e0e7e37e),
        f64::from_bits(0x3fe9cdc2e3f25e5c),
        f64::from_bits(0x3c83f99112993f62),
        f64::from_bits(0x3fe32054b148bc4f),
        f64::from_bits(0x3c8f6b42095a135b),
        f64::from_bits(0x3fe9a7b5a36a6514),
        f64::from_bits(0x3c8722cfcc9fa7a9),
        f64::from_bits(0x3fe3537db9be0367),
        f64::from_bits(0x3c6b327e7af040f0),
        f64::from_bits(0x3fe98141c42e1310),
        f64::from_bits(0x3c8d1ff80488f08d),
        f64::from_bits(0x3fe386597456282b),
        f64::from_bits(0xbc710fada93b07a8),
        f64::from_bits(0x3fe95a67e00cb1fd),
        f64::from_bits(0xbc80befda21f862d),
        f64::from_bits(0x3fe3b8e715a2840a),
        f64::from_bits(0xbc797653a7d2f07b),
        f64::from_bits(0x3fe93328926d9e92),
        f64::from_bits(0xbc8bb77003600cda),
        f64::from_bits(0x3fe3eb25d36cd53a),
        f64::from_bits(0xbc5be570e1570fc0),
        f64::from_bits(0x3fe90b84784ddaf7),
        f64::from_bits(0xbc70feb10ab93b87),
        f64::from_bits(0x3fe41d14e4ba6790),
        f64::from_bits(0x3c84608fd287ecf5),
        f64::from_bits(0x3fe8e37c303d9ad1),
        f64::from_bits(0xbc6463a4b53d4bf8),
        f64::from_bits(0x3fe44eb381cf386b),
        f64::from_bits(0xbc83ed6c1e6a5505),
        f64::from_bits(0x3fe8bb105a5dc900),
        f64::from_bits(0x3c8863e03e9474c1),
        f64::from_bits(0x3fe48000e431159f),
        f64::from_bits(0xbc8b194a7463ed10),
        f64::from_bits(0x3fe89241985d871f),
        f64::from_bits(0x3c8c48d9c413ed84),
        f64::from_bits(0x3fe4b0fc46aab761),
        f64::from_bits(0x3c20da05738cc59a),
        f64::from_bits(0x3fe869108d77a6c6),
        f64::from_bits(0x3c7338ffe2bfe9dd),
        f64::from_bits(0x3fe4e1a4e54ed51b),
        f64::from_bits(0xbc8a492f89b7c76a),
        f64::from_bits(0x3fe83f7dde701ca0),
        f64::from_bits(0xbc4152cf609bc6e8),
        f64::from_bits(0x3fe511f9fd7b351c),
        f64::from_bits(0xbc85c0e861c48831),
        f64::from_bits(0x3fe8158a31916d5d),
        f64::from_bits(0xbc6de8b90b8228de),
        f64::from_bits(0x3fe541facddbb724),
        f64::from_bits(0x3c7232c28520d391),
        f64::from_bits(0x3fe7eb362eaa1488),
        f64::from_bits(0x3c5a1d65a4a5959f),
        f64::from_bits(0x3fe571a6966d59b3),
        f64::from_bits(0x3c5c843b4d0fb198),
        f64::from_bits(0x3fe7c0827f09e54f),
        f64::from_bits(0xbc6c73d6d72aee68),
        f64::from_bits(0x3fe5a0fc98813a12),
        f64::from_bits(0xbc8d82e2b7d4227b),
        f64::from_bits(0x3fe7956fcd7f6543),
        f64::from_bits(0xbc8ab276e9d45ae4),
        f64::from_bits(0x3fe5cffc16bf8f0d),
        f64::from_bits(0x3c896cb370eb578a),
        f64::from_bits(0x3fe769fec655211f),
        f64::from_bits(0xbc6827d5cf8c68c5),
        f64::from_bits(0x3fe5fea4552a9e57),
        f64::from_bits(0x3c80b6cef7ee20b7),
        f64::from_bits(0x3fe73e30174efba1),
        f64::from_bits(0xbc65d3ae3d94ad5f),
        f64::from_bits(0x3fe62cf49921ac79),
        f64::from_bits(0xbc8edd9855b6241a),
        f64::from_bits(0x3fe712046fa77678),
        f64::from_bits(0x3c8425b0a5029c81),
        f64::from_bits(0x3fe65aec2963e755),
        f64::from_bits(0x3c8126f96b71053c),
        f64::from_bits(0x3fe6e57c800cf55e),
        f64::from_bits(0x3c860286dedbd0a6),
        f64::from_bits(0x3fe6888a4e134b2f),
        f64::from_bits(0xbc86b7d37644d5e6),
        f64::from_bits(0x3fe6b898fa9efb5d),
        f64::from_bits(0x3c715ac786ccf4b2),
        f64::from_bits(0x3fe6b5ce50b7821a),
        f64::from_bits(0xbc65d5158f702e0f),
        f64::from_bits(0x3fe68b5a92eb6253),
        f64::from_bits(0xbc89a91ad985f89c),
        f64::from_bits(0x3fe6e2b77c40bde1),
        f64::from_bits(0xbc70e729857fad53),
        f64::from_bits(0x3fe65dc1fdeb8cba),
        f64::from_bits(0xbc597c1b47337c77),
        f64::from_bits(0x3fe70f451d0a8c40),
        f64::from_bits(0x3c697ede3885770d),
        f64::from_bits(0x3fe62fcff20191c7),
        f64::from_bits(0x3c6d9143895756ef),
        f64::from_bits(0x3fe73b7680dea578),
        f64::from_bits(0xbc72248306dc12a2),
        f64::from_bits(0x3fe6018526f563df),
        f64::from_bits(0x3c846ca5e0e432d0),
        f64::from_bits(0x3fe7674af6f7b524),
        f64::from_bits(0x3c7e9d3f94ac84a8),
        f64::from_bits(0x3fe5d2e255f1f17a),
        f64::from_bits(0x3c80314104c8892b),
        f64::from_bits(0x3fe792c1d0041d52),
        f64::from_bits(0xbc8abf05eeb354eb),
        f64::from_bits(0x3fe5a3e839824077),
        f64::from_bits(0x3c8428aa2759be62),
        f64::from_bits(0x3fe7bdda5e28b3c2),
        f64::from_bits(0x3c4ad1197ccd0393),
        f64::from_bits(0x3fe574978d8e83f2),
        f64::from_bits(0x3c8f4714af282d23),
        f64::from_bits(0x3fe7e893f5037959),
        f64::from_bits(0x3c80eefbaa650c4c),
        f64::from_bits(0x3fe544f10f592ca5),
        f64::from_bits(0xbc8e7ae8e6c7a62f),
        f64::from_bits(0x3fe812ede9ae4ba4),
        f64::from_bits(0xbc87830adf402dda),
        f64::from_bits(0x3fe514f57d7bf3da),
        f64::from_bits(0x3c747a108073c259),
    ];

    // ---------------------------------------------------------------------------
    // Small vector helpers.  fma(a,b,c) = a*b+c, fnma(a,b,c) = -(a*b)+c,
    // fms(a,b,c) = a*b-c, each with a single rounding.
    // ---------------------------------------------------------------------------

    #[inline(always)]
    pub(super) unsafe fn splat(v: f64) -> __m512d {
        _mm512_set1_pd(v)
    }
    #[inline(always)]
    unsafe fn add(a: __m512d, b: __m512d) -> __m512d {
        _mm512_add_pd(a, b)
    }
    #[inline(always)]
    unsafe fn sub(a: __m512d, b: __m512d) -> __m512d {
        _mm512_sub_pd(a, b)
    }
    #[inline(always)]
    unsafe fn mul(a: __m512d, b: __m512d) -> __m512d {
        _mm512_mul_pd(a, b)
    }
    #[inline(always)]
    unsafe fn fma(a: __m512d, b: __m512d, c: __m512d) -> __m512d {
        _mm512_fmadd_pd(a, b, c)
    }
    #[inline(always)]
    unsafe fn fnma(a: __m512d, b: __m512d, c: __m512d) -> __m512d {
        _mm512_fnmadd_pd(a, b, c)
    }
    #[inline(always)]
    unsafe fn fms(a: __m512d, b: __m512d, c: __m512d) -> __m512d {
        _mm512_fmsub_pd(a, b, c)
    }
    #[inline(always)]
    unsafe fn sign_mask() -> __m512i {
        _mm512_set1_epi64(i64::MIN)
    }
    /// fabs
    #[inline(always)]
    pub(super) unsafe fn vabs(a: __m512d) -> __m512d {
        _mm512_castsi512_pd(_mm512_andnot_si512(sign_mask(), _mm512_castpd_si512(a)))
    }
    /// -a (xor with the sign bit, as glibc's `vxorpd` with -0.0)
    #[inline(always)]
    unsafe fn vneg(a: __m512d) -> __m512d {
        _mm512_castsi512_pd(_mm512_xor_si512(sign_mask(), _mm512_castpd_si512(a)))
    }
    /// copysign (mag, sgn)
    #[inline(always)]
    pub(super) unsafe fn vcopysign(mag: __m512d, sgn: __m512d) -> __m512d {
        let m = sign_mask();
        _mm512_castsi512_pd(_mm512_or_si512(
            _mm512_andnot_si512(m, _mm512_castpd_si512(mag)),
            _mm512_and_si512(m, _mm512_castpd_si512(sgn)),
        ))
    }
    /// Lane-wise `m ? b : a`.
    #[inline(always)]
    unsafe fn select(m: __mmask8, b: __m512d, a: __m512d) -> __m512d {
        _mm512_mask_blend_pd(m, a, b)
    }

    /// One row {sn, ssn, cs, ccs} of `__sincostab` per lane.
    #[derive(Clone, Copy)]
    struct TabRow {
        sn: __m512d,
        ssn: __m512d,
        cs: __m512d,
        ccs: __m512d,
    }

    /// `u.x = big + fabs (x)` as computed at the top of do_sin / do_cos; the
    /// table row is then k = u.i[LOW_HALF] << 2.
    #[inline(always)]
    unsafe fn table_u(x: __m512d) -> __m512d {
        add(vabs(x), splat(BIG))
    }

    /// k = u.i[LOW_HALF] << 2, clamped to the table so lanes that do not use the
    /// result (other branches, NaN, huge x) never read out of bounds.
    #[inline(always)]
    unsafe fn table_index(u: __m512d) -> __m512i {
        let low = _mm512_and_si512(_mm512_castpd_si512(u), _mm512_set1_epi64(0xffff_ffff));
        _mm512_min_epu64(_mm512_slli_epi64::<2>(low), _mm512_set1_epi64(436))
    }

    /// SINCOS_TABLE_LOOKUP (u, sn, ssn, cs, ccs) with four gathers.
    #[inline(always)]
    unsafe fn table_lookup(k: __m512i) -> TabRow {
        let base = SINCOSTAB.as_ptr();
        // sn = x[k], ssn = x[k+1], cs = x[k+2], ccs = x[k+3]  (scale 8 = sizeof(double))
        TabRow {
            sn: _mm512_i64gather_pd::<8>(k, base),
            ssn: _mm512_i64gather_pd::<8>(k, base.add(1)),
            cs: _mm512_i64gather_pd::<8>(k, base.add(2)),
            ccs: _mm512_i64gather_pd::<8>(k, base.add(3)),
        }
    }

    /// do_sin (x, dx), including its TAYLOR_SIN branch for |x| < 0.126.
    /// Instruction order from __sin_fma 0x70950.. (Taylor) and 0x704f3.. (table).
    #[inline(always)]
    unsafe fn do_sin(x: __m512d, dx: __m512d, row: TabRow) -> __m512d {
        let ax = vabs(x);

        // --- if (fabs (x) < 0.126) return TAYLOR_SIN (x * x, x, dx);
        //   t = ((POLYNOMIAL (xx) * x - 0.5 * dx) * xx + dx); res = x + t;
        let xx = mul(x, x); // vmulsd
        let p = fma(xx, splat(S5), splat(S4)); // POLYNOMIAL: 4 x vfmadd213sd
        let p = fma(xx, p, splat(S3));
        let p = fma(xx, p, splat(S2));
        let p = fma(xx, p, splat(S1));
        let half_dx = mul(dx, splat(0.5)); // vmulsd 0.5*dx
        let q = fms(p, x, half_dx); // vfmsub132sd: POLYNOMIAL*x - 0.5*dx
        let t = fma(xx, q, dx); // vfmadd132sd: (...)*xx + dx
        let res_taylor = add(t, x); // vaddsd

        // --- general case
        // if (x <= 0) dx = -dx;   (glibc tests !(0 < x))
        let x_le_0 = _mm512_cmp_pd_mask::<_CMP_LE_OQ>(x, _mm512_setzero_pd());
        let dx = select(x_le_0, vneg(dx), dx);
        // u.x = big + fabs (x); x = fabs (x) - (u.x - big);
        let u = add(ax, splat(BIG)); // == table_u (x)
        let xr = sub(ax, sub(u, splat(BIG)));
        // xx = x * x;
        let xx = mul(xr, xr);
        // s = x + (dx + x * xx * (sn3 + xx * sn5));
        let ps = fma(xx, splat(SN5), splat(SN3)); // vfmadd213sd
        let x3 = mul(xr, xx); // vmulsd
        let s = add(xr, fma(x3, ps, dx)); // vfmadd132sd, vaddsd
                                          // c = x * dx + xx * (cs2 + xx * (cs4 + xx * cs6));
        let pc = fma(xx, splat(CS6), splat(CS4)); // vfmadd213sd
        let pc = fma(xx, pc, splat(CS2)); // vfmadd213sd
        let c = fma(xr, dx, mul(xx, pc)); // vmulsd, vfmadd132sd
                                          // SINCOS_TABLE_LOOKUP (u, sn, ssn, cs, ccs);
                                          // (looked up by the caller from table_index (u))
        let TabRow { sn, ssn, cs, ccs } = row;
        // cor = (ssn + s * ccs - sn * c) + cs * s;
        let cor = fma(s, ccs, ssn); // vfmadd213sd: ssn + s*ccs
        let cor = fnma(c, sn, cor); // vfnmadd132sd: - sn*c
        let cor = fma(s, cs, cor); // vfmadd132sd: + cs*s
                                   // return copysign (sn + cor, xold);
        let res_table = vcopysign(add(sn, cor), x);

        let small = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(ax, splat(TAYLOR_LIMIT));
        select(small, res_taylor, res_table)
    }

    /// do_cos (x, dx).  Instruction order from __sin_fma 0x70780.. / __cos_fma 0x70b32..
    #[inline(always)]
    unsafe fn do_cos(x: __m512d, dx: __m512d, row: TabRow) -> __m512d {
        // if (x < 0) dx = -dx;
        let x_lt_0 = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(x, _mm512_setzero_pd());
        let dx = select(x_lt_0, vneg(dx), dx);
        // u.x = big + fabs (x); x = fabs (x) - (u.x - big) + dx;
        let ax = vabs(x);
        let u = add(ax, splat(BIG)); // == table_u (x)
        let xr = add(sub(ax, sub(u, splat(BIG))), dx);
        // xx = x * x;
        let xx = mul(xr, xr);
        // s = x + x * xx * (sn3 + xx * sn5);
        let ps = fma(xx, splat(SN5), splat(SN3)); // vfmadd213sd
        let x3 = mul(xr, xx); // vmulsd
        let s = fma(x3, ps, xr); // vfmadd132sd (the "x +" is fused here)
                                 // c = xx * (cs2 + xx * (cs4 + xx * cs6));
        let pc = fma(xx, splat(CS6), splat(CS4));
        let pc = fma(xx, pc, splat(CS2));
        let c = mul(xx, pc); // vmulsd
                             // SINCOS_TABLE_LOOKUP (u, sn, ssn, cs, ccs);
                             // (looked up by the caller from table_index (u))
        let TabRow { sn, ssn, cs, ccs } = row;
        // cor = (ccs - s * ssn - cs * c) - sn * s;
        let cor = fnma(s, ssn, ccs); // vfnmadd213sd: ccs - s*ssn
        let cor = fnma(c, cs, cor); // vfnmadd132sd: - cs*c
        let cor = fnma(s, sn, cor); // vfnmadd132sd: - sn*s
                                    // return cs + cor;
        add(cs, cor)
    }

    /// reduce_sincos (x, &a, &da) -> n  (n returned as the raw low bits of t;
    /// callers use n & 3).  Instruction order from __sin_fma 0x7046e..
    #[inline(always)]
    unsafe fn reduce_sincos(x: __m512d) -> (__m512d, __m512d, __m512i) {
        // double t = (x * hpinv + toint);
        let t = fma(x, splat(HPINV), splat(TOINT)); // vfmadd132sd
                                                    // double xn = t - toint;
        let xn = sub(t, splat(TOINT));
        // v.x = t;  int4 n = v.i[LOW_HALF] & 3;
        let n = _mm512_castpd_si512(t);
        // double y = (x - xn * mp1) - xn * mp2;
        let y = fnma(xn, splat(MP1), x); // vfnmadd231sd
        let y = fnma(xn, splat(MP2), y); // vfnmadd231sd
                                         // t1 = xn * pp3; t2 = y - t1; db = (y - t2) - t1;
        let t2 = fnma(xn, splat(PP3), y); // vfnmadd132sd
        let db = fnma(xn, splat(PP3), sub(y, t2)); // vsubsd, vfnmadd132sd
                                                   // t1 = xn * pp4; b = t2 - t1; db += (t2 - b) - t1;
        let b = fnma(xn, splat(PP4), t2); // vfnmadd132sd
        let db = add(db, fnma(xn, splat(PP4), sub(t2, b))); // vsubsd, vfnmadd132sd, vaddsd
                                                            // *a = b; *da = db;
        (b, db, n)
    }

    /// `f64::exp_m1` in the lanes of `mask`, to the bit of the libm this was ported from:
    /// glibc's `expm1` as it runs on CPUs with FMA (`__expm1_fma`, fdlibm's `s_expm1.c`
    /// compiled with the multiply-adds contracted), operation for operation, its branches
    /// (the reduction by k·ln2 and the reconstruction for each k) as masks. Lanes outside
    /// its plain range (x > 56 ln2, NaN) call libm. The other lanes keep `x`.
    ///
    /// # Safety
    /// The CPU must have AVX-512F and FMA.
    #[target_feature(enable = "avx512f,fma")]
    #[inline]
    pub unsafe fn expm1(mask: __mmask8, x: __m512d) -> __m512d {
        const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
        const LN2_LO: f64 = f64::from_bits(0x3dea_39ef_3579_3c76);
        const INV_LN2: f64 = f64::from_bits(0x3ff7_1547_652b_82fe);
        const Q: [f64; 5] = [
            f64::from_bits(0xbfa1_1111_1111_10f4),
            f64::from_bits(0x3f5a_01a0_19fe_5585),
            f64::from_bits(0xbf14_ce19_9eaa_dbb7),
            f64::from_bits(0x3ed0_cfca_86e6_5239),
            f64::from_bits(0xbe8a_fdb7_6e09_c32d),
        ];
        if mask == 0 {
            return x;
        }
        let bits = _mm512_castpd_si512(x);
        // the high word of |x|, on which fdlibm branches
        let hx = _mm512_and_si512(_mm512_srli_epi64::<32>(bits), _mm512_set1_epi64(0x7fff_ffff));
        let hx_le = |w: i64| _mm512_cmple_epi64_mask(hx, _mm512_set1_epi64(w));
        let negative = _mm512_cmplt_epi64_mask(bits, _mm512_setzero_si512());
        // |x| >= 56 ln2: -1 below (and at -inf), libm above and at NaN
        let plain = hx_le(0x4043_6879);
        let minus_one = !plain & le(x, splat(-f64::from_bits(0x4043_687a_0000_0000)));
        let tiny = hx_le(0x3c8f_ffff); // |x| < 2^-54: x itself
        let k0 = hx_le(0x3fd6_2e42); // |x| <= ln2/2: no reduction
        let k1 = !k0 & hx_le(0x3ff0_a2b1); // |x| < 1.5 ln2: k = ±1
                                           // the general reduction: k = (int)(x/ln2 ± 0.5), hi = x - k ln2_hi (one rounding)
        let kf_general = _mm512_roundscale_pd::<{ _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC }>(add(
            select(negative, splat(-0.5), splat(0.5)),
            mul(x, splat(INV_LN2)),
        ));
        let kf = select(k0, splat(0.0), select(k1, select(negative, splat(-1.0), splat(1.0)), kf_general));
        let hi = select(
            k1,
            select(negative, add(x, splat(LN2_HI)), sub(x, splat(LN2_HI))),
            _mm512_fnmadd_pd(kf, splat(LN2_HI), x),
        );
        let lo = select(k1, select(negative, splat(-LN2_LO), splat(LN2_LO)), mul(kf, splat(LN2_LO)));
        let xr = select(k0, x, sub(hi, lo));
        let c = sub(sub(hi, xr), lo);
        // x now in the primary range
        let hfx = mul(xr, splat(0.5));
        let hxs = mul(xr, hfx);
        let r1_ = fma(hxs, splat(Q[0]), splat(1.0));
        let r2 = fma(hxs, splat(Q[2]), splat(Q[1]));
        let r3 = fma(hxs, splat(Q[4]), splat(Q[3]));
        let h2 = mul(hxs, hxs);
        let h4 = mul(h2, h2);
        let r1 = fma(h4, r3, fma(h2, r2, r1_));
        let t = _mm512_fnmadd_pd(r1, hfx, splat(3.0));
        let e = mul(div(sub(r1, t), _mm512_fnmadd_pd(xr, t, splat(6.0))), hxs);
        // k = 0
        let y_k0 = sub(xr, _mm512_fmsub_pd(e, xr, hxs));
        // k != 0
        let e = sub(_mm512_fmsub_pd(sub(e, c), xr, c), hxs);
        let y_km1 = fma(splat(0.5), sub(xr, e), splat(-0.5));
        let y_kp1 = select(
            lt(xr, splat(-0.25)),
            mul(sub(e, add(xr, splat(0.5))), splat(-2.0)),
            fma(sub(xr, e), splat(2.0), splat(1.0)),
        );
        let k = _mm512_cvtepi32_epi64(_mm512_cvttpd_epi32(kf));
        let kk = |w: i64| _mm512_set1_epi64(w);
        // 2^k times y, by adding k to y's exponent (the high word, as fdlibm does)
        let scale =
            |y: __m512d| _mm512_castsi512_pd(_mm512_add_epi64(_mm512_castpd_si512(y), _mm512_slli_epi64::<52>(k)));
        let y_far = sub(scale(sub(splat(1.0), sub(e, xr))), splat(1.0)); // k <= -2 or k > 56
        let t_mid = _mm512_castsi512_pd(_mm512_slli_epi64::<32>(_mm512_sub_epi64(
            kk(0x3ff0_0000),
            _mm512_srlv_epi64(kk(0x20_0000), k),
        ))); // 1 - 2^-k, 2 <= k <= 19
        let y_mid = scale(sub(t_mid, sub(e, xr)));
        let t_high = _mm512_castsi512_pd(_mm512_slli_epi64::<52>(_mm512_sub_epi64(kk(0x3ff), k))); // 2^-k
        let y_high = scale(add(sub(xr, add(e, t_high)), splat(1.0))); // 20 <= k <= 56
        let k_is = |w: i64| _mm512_cmpeq_epi64_mask(k, kk(w));
        let far = _mm512_cmplt_epi64_mask(k, kk(-1)) | _mm512_cmpgt_epi64_mask(k, kk(56));
        let high = _mm512_cmpgt_epi64_mask(k, kk(19)) & !far;
        let mut y = select(high, y_high, y_mid);
        y = select(far, y_far, y);
        y = select(k_is(1), y_kp1, y);
        y = select(k_is(-1), y_km1, y);
        y = select(k_is(0), y_k0, y);
        y = select(tiny, x, y);
        y = select(minus_one, splat(-1.0), y);
        let libm = mask & !plain & !minus_one;
        y = select(mask & !libm, y, x);
        each(libm, y, f64::exp_m1)
    }

    /// `f64::sin_cos` (libm's `sincos`, `__sincos_fma`) of eight lanes: glibc's branches on |x|
    /// (tiny, below 0.855469, below 2.426265 through hp0 - |x|, and `reduce_sincos` below
    /// 105414350) as masks; lanes beyond (the `__branred` path, inf, NaN) call libm.
    ///
    /// # Safety
    /// The CPU must have AVX-512F and FMA.
    #[target_feature(enable = "avx512f,fma")]
    #[inline]
    pub unsafe fn sincos(x: __m512d) -> (__m512d, __m512d) {
        // k = u.i[HIGH_HALF] & 0x7fffffff
        let bits = _mm512_castpd_si512(x);
        let k = _mm512_and_si512(_mm512_srli_epi64::<32>(bits), _mm512_set1_epi64(0x7fff_ffff));
        let k_lt = |c: i64| _mm512_cmplt_epi64_mask(k, _mm512_set1_epi64(c));
        let tiny = k_lt(K_COS_TINY); // |x| < 2^-27: sin x = x, cos x = 1
        let small = k_lt(K_SMALL); // |x| < 0.855469
        let mid = k_lt(K_MID) & !small; // 0.855469 <= |x| < 2.426265
        let reduce = k_lt(K_REDUCE) & !k_lt(K_MID); // 2.426265 <= |x| < 105414350
        let fallback = !k_lt(K_REDUCE); // |x| >= 105414350, inf, NaN

        let zero = _mm512_setzero_pd();
        // 0.855469 <= |x| < 2.426265: y = hp0 - fabs (x); a = y + hp1; da = (y - a) + hp1;
        // *sinx = copysign (do_cos (a, da), x); *cosx = do_sin (a, da);
        // (sincos's own form: `sin` alone takes do_cos (hp0 - |x|, hp1), another table row
        // where hp0 - |x| lies on a row's rounding tie)
        let y = sub(splat(HP0), vabs(x));
        let a_mid = add(y, splat(HP1));
        let da_mid = add(sub(y, a_mid), splat(HP1));
        // 2.426265 <= |x| < 105414350: n = reduce_sincos (x, &a, &da);
        let (a_red, da_red, n) = reduce_sincos(x);
        // one do_sin and one do_cos per lane, on the same argument
        let a = select(reduce, a_red, select(mid, a_mid, x));
        let da = select(reduce, da_red, select(mid, da_mid, zero));
        let row = table_lookup(table_index(table_u(a)));
        let vs = do_sin(a, da, row);
        let vc = do_cos(a, da, row);
        // reduced: sin from do_sin/do_cos by n, negated when n & 2; cos by n + 1
        let n_odd = _mm512_test_epi64_mask(n, _mm512_set1_epi64(1));
        let n_bit2 = _mm512_test_epi64_mask(n, _mm512_set1_epi64(2));
        let n1_bit2 = _mm512_test_epi64_mask(_mm512_add_epi64(n, _mm512_set1_epi64(1)), _mm512_set1_epi64(2));
        let sin_red = select(n_odd, vc, vs);
        let sin_red = select(n_bit2, vneg(sin_red), sin_red);
        let cos_red = select(n_odd, vs, vc);
        let cos_red = select(n1_bit2, vneg(cos_red), cos_red);

        let mut s = select(mid, vcopysign(vc, x), vs);
        s = select(reduce, sin_red, s);
        s = select(tiny, x, s);
        let mut c = select(mid, vs, vc);
        c = select(reduce, cos_red, c);
        c = select(tiny, splat(1.0), c);
        if fallback != 0 {
            let (xs, mut ss, mut cc) = (store(x), store(s), store(c));
            let mut m = fallback;
            while m != 0 {
                let l = m.trailing_zeros() as usize;
                (ss[l], cc[l]) = xs[l].sin_cos();
                m &= m - 1;
            }
            s = load(&ss);
            c = load(&cc);
        }
        (s, c)
    }

    /// [`sincos`] of an array.
    ///
    /// # Safety
    /// The CPU must have AVX-512F and FMA.
    #[target_feature(enable = "avx512f,fma")]
    pub(super) unsafe fn sincos_array(x: [f64; 8]) -> ([f64; 8], [f64; 8]) {
        let (s, c) = sincos(load(&x));
        (store(s), store(c))
    }

    /// [`sincos`] of every angle, in order, appended to `out` (the loop compiled with the
    /// ports' features, so that the port inlines into it).
    ///
    /// # Safety
    /// The CPU must have AVX-512F and FMA.
    #[target_feature(enable = "avx512f,fma")]
    pub(super) unsafe fn sincos_slice(x: &[f64], out: &mut Vec<(f64, f64)>) {
        for chunk in x.chunks(8) {
            let mut a = [chunk[0]; 8];
            a[..chunk.len()].copy_from_slice(chunk);
            let (s, c) = sincos(load(&a));
            let (s, c) = (store(s), store(c));
            out.extend((0..chunk.len()).map(|l| (s[l], c[l])));
        }
    }

    /// [`atan2`] of every pair, in order, appended to `out`.
    ///
    /// # Safety
    /// The CPU must have AVX-512F and FMA.
    #[target_feature(enable = "avx512f,fma")]
    pub(super) unsafe fn atan2_slice(ys: &[f64], xs: &[f64], out: &mut Vec<f64>) {
        for (cy, cx) in ys.chunks(8).zip(xs.chunks(8)) {
            let (mut y, mut x) = ([cy[0]; 8], [cx[0]; 8]);
            y[..cy.len()].copy_from_slice(cy);
            x[..cx.len()].copy_from_slice(cx);
            out.extend_from_slice(&store(atan2(load(&y), load(&x)))[..cy.len()]);
        }
    }

    /// [`expm1`] of every argument, in order, appended to `out`.
    ///
    /// # Safety
    /// The CPU must have AVX-512F and FMA.
    #[target_feature(enable = "avx512f,fma")]
    pub(super) unsafe fn expm1_slice(xs: &[f64], out: &mut Vec<f64>) {
        for chunk in xs.chunks(8) {
            let mut a = [chunk[0]; 8];
            a[..chunk.len()].copy_from_slice(chunk);
            out.extend_from_slice(&store(expm1(0xff, load(&a)))[..chunk.len()]);
        }
    }

    /// [`expm1`] of an array.
    ///
    /// # Safety
    /// The CPU must have AVX-512F and FMA.
    #[target_feature(enable = "avx512f,fma")]
    pub(super) unsafe fn expm1_array(x: [f64; 8]) -> [f64; 8] {
        store(expm1(0xff, load(&x)))
    }

    #[inline(always)]
    unsafe fn load(a: &[f64; 8]) -> __m512d {
        _mm512_loadu_pd(a.as_ptr())
    }

    #[inline(always)]
    unsafe fn store(v: __m512d) -> [f64; 8] {
        let mut a = [0.0; 8];
        _mm512_storeu_pd(a.as_mut_ptr(), v);
        a
    }

    #[inline(always)]
    unsafe fn le(a: __m512d, b: __m512d) -> __mmask8 {
        _mm512_cmp_pd_mask::<_CMP_LE_OQ>(a, b)
    }

    #[inline(always)]
    pub(super) unsafe fn lt(a: __m512d, b: __m512d) -> __mmask8 {
        _mm512_cmp_pd_mask::<_CMP_LT_OQ>(a, b)
    }

    #[inline(always)]
    unsafe fn div(a: __m512d, b: __m512d) -> __m512d {
        _mm512_div_pd(a, b)
    }

    /// `f(x)` (a libm function) in the lanes of `mask`, one lane at a time: what the ports
    /// leave to libm, and the functions without a port. The other lanes keep `x`.
    ///
    /// # Safety
    /// The CPU must have AVX-512F (callers with that target feature call it safely).
    #[target_feature(enable = "avx512f")]
    #[inline]
    pub fn each(mask: __mmask8, x: __m512d, f: fn(f64) -> f64) -> __m512d {
        if mask == 0 {
            return x;
        }
        // SAFETY: the target feature is enabled here; eight f64 fit each array
        unsafe {
            let mut a = store(x);
            let mut m = mask;
            while m != 0 {
                let l = m.trailing_zeros() as usize;
                a[l] = f(a[l]);
                m &= m - 1;
            }
            load(&a)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lane `expm1` is libm's to the bit: random arguments over every branch of fdlibm's
    /// algorithm (no reduction, k = ±1, the general reduction for small and large k, the
    /// tiny and the saturated ranges, libm's own lanes), and the edges between them.
    #[test]
    fn lane_expm1_is_libms_to_the_bit() {
        use rand::{Rng, SeedableRng};
        if !expm1_ported() {
            eprintln!("skipped: no AVX-512F and FMA, or this libm's expm1 is not the one ported");
            return;
        }
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut xs: Vec<f64> = Vec::new();
        for _ in 0..400_000 {
            let magnitude = 10f64.powf(rng.random_range(-20.0..3.0));
            xs.push(if rng.random_bool(0.8) { -magnitude } else { magnitude });
        }
        for w in [0x3c90_0000u64, 0x3fd6_2e42, 0x3fd6_2e43, 0x3ff0_a2b1, 0x3ff0_a2b2, 0x4043_6879, 0x4043_687a] {
            for low in [0u64, 1, 0xffff_ffff] {
                let x = f64::from_bits(w << 32 | low);
                xs.extend([x, -x, f64::from_bits(x.to_bits() - 1), -f64::from_bits(x.to_bits() + 1)]);
            }
        }
        xs.extend([0.0, -0.0, 1e-310, -1e-310, f64::INFINITY, f64::NEG_INFINITY, f64::NAN, 710.0, -710.0, -1e300]);
        for chunk in xs.chunks(8) {
            let mut a = [chunk[0]; 8];
            a[..chunk.len()].copy_from_slice(chunk);
            let out = lanes_expm1(a);
            for (l, &x) in chunk.iter().enumerate() {
                let want = x.exp_m1();
                assert!(
                    out[l].to_bits() == want.to_bits() || (out[l].is_nan() && want.is_nan()),
                    "expm1({x:e} = {:#x}): lanes {:e}, libm {want:e}",
                    x.to_bits(),
                    out[l]
                );
            }
        }
    }

    /// The slice functions give libm's values in order for every length, the tail of a
    /// length that is no multiple of eight included, whether or not the ports are taken.
    #[test]
    fn the_slice_functions_are_libm_value_by_value() {
        for n in [0usize, 1, 7, 8, 9, 100] {
            let xs: Vec<f64> = (0..n).map(|i| -3.0 + 0.37 * i as f64).collect();
            let ys: Vec<f64> = (0..n).map(|i| 2.0 - 0.29 * i as f64).collect();
            let sc = sin_cos_all(&xs);
            let at = atan2_all(&ys, &xs);
            let em = exp_m1_all(&xs);
            assert_eq!((sc.len(), at.len(), em.len()), (n, n, n));
            for i in 0..n {
                let (s, c) = xs[i].sin_cos();
                assert_eq!((sc[i].0.to_bits(), sc[i].1.to_bits()), (s.to_bits(), c.to_bits()), "sincos {i}");
                assert_eq!(at[i].to_bits(), ys[i].atan2(xs[i]).to_bits(), "atan2 {i}");
                assert_eq!(em[i].to_bits(), xs[i].exp_m1().to_bits(), "expm1 {i}");
            }
        }
    }

    /// On the libm the ports come from (glibc 2.36 on a CPU with AVX-512F and FMA: this
    /// project's machines) every probe passes, so the engine runs the ports and the tests
    /// below compare them instead of skipping: a port that drifted from its libm fails here.
    #[test]
    fn the_ports_are_taken_on_the_libm_they_come_from() {
        #[cfg(all(target_os = "linux", target_env = "gnu"))]
        {
            extern "C" {
                fn gnu_get_libc_version() -> *const std::ffi::c_char;
            }
            // SAFETY: glibc returns a static NUL-terminated string
            let version = unsafe { std::ffi::CStr::from_ptr(gnu_get_libc_version()) }.to_string_lossy().into_owned();
            if version != "2.36" || !available() {
                eprintln!("skipped: glibc {version}, AVX-512F and FMA {}: not the libm ported", available());
                return;
            }
            assert!(expm1_ported(), "expm1");
            assert!(sincos_ported(), "sincos");
            assert!(atan2_ported(), "atan2");
        }
    }

    /// The lane `atan2` is libm's to the bit: random pairs where the kernel takes them
    /// (velocity components 10^-6 to 10 m/s, any signs) and far beyond, ratios at and next
    /// to the branch edges and the table's rows in every quadrant, angles near the axes and
    /// diagonals, and the special values (zeros, infinities, NaN, subnormals).
    #[test]
    fn lane_atan2_is_libms_to_the_bit() {
        use rand::{Rng, SeedableRng};
        if !atan2_ported() {
            eprintln!("skipped: no AVX-512F and FMA, or this libm's atan2 is not the one ported");
            return;
        }
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(13);
        let signed = |rng: &mut rand_chacha::ChaCha8Rng, m: f64| if rng.random_bool(0.5) { -m } else { m };
        let mut pairs: Vec<(f64, f64)> = Vec::new();
        for _ in 0..400_000 {
            pairs.push((rng.random_range(-10.0..10.0), rng.random_range(-10.0..10.0)));
            let (my, mx) = (10f64.powf(rng.random_range(-6.0..1.0)), 10f64.powf(rng.random_range(-6.0..1.0)));
            pairs.push((signed(&mut rng, my), signed(&mut rng, mx)));
            let (my, mx) = (10f64.powf(rng.random_range(-300.0..300.0)), 10f64.powf(rng.random_range(-300.0..300.0)));
            pairs.push((signed(&mut rng, my), signed(&mut rng, mx)));
        }
        for row in 0..=256 {
            // |y/x| at the polynomial's edge 1/16 and at and between the table's rows
            let u = (row as f64 + 16.0) / 256.0;
            for d in -3i64..=3 {
                let u = f64::from_bits((u.to_bits() as i64 + d) as u64);
                for (sy, sx) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                    let x = rng.random_range(0.5..2.0);
                    pairs.extend([(sy * u * x, sx * x), (sy * x, sx * u * x)]);
                }
            }
        }
        for k in -4..=4 {
            // near the axes and the diagonals
            let a = k as f64 * std::f64::consts::FRAC_PI_4;
            for d in 1..2000 {
                let a = a + d as f64 * 1e-12;
                pairs.extend([(a.sin(), a.cos()), (-a.sin(), a.cos())]);
            }
        }
        let specials =
            [0.0, -0.0, 1.0, -1.0, 1e-310, -1e-310, f64::INFINITY, f64::NEG_INFINITY, f64::NAN, f64::MAX, 1e-300];
        for y in specials {
            pairs.extend(specials.iter().map(|&x| (y, x)));
        }
        let ys: Vec<f64> = pairs.iter().map(|p| p.0).collect();
        let xs: Vec<f64> = pairs.iter().map(|p| p.1).collect();
        for (r, (y, x)) in atan2_on_lanes(&ys, &xs).iter().zip(&pairs) {
            let want = y.atan2(*x);
            assert!(
                r.to_bits() == want.to_bits() || (r.is_nan() && want.is_nan()),
                "atan2({y:e}, {x:e}): lanes {r:e}, libm {want:e}"
            );
        }
    }

    /// The lane `sincos` is libm's `sincos` (as `f64::sin_cos` calls it) to the bit: random
    /// arguments where the kernel takes angles and far beyond, dense runs across each
    /// branch edge and around multiples of π/4 (the reduction's quadrants), the table rows'
    /// rounding ties, and the arguments where libm's `sin` and `sincos` differ.
    #[test]
    fn lane_sincos_is_libms_to_the_bit() {
        use rand::{Rng, SeedableRng};
        if !sincos_ported() {
            eprintln!("skipped: no AVX-512F and FMA, or this libm's sincos is not the one ported");
            return;
        }
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
        let mut xs: Vec<f64> = (0..600_000).map(|_| rng.random_range(-10.0..10.0)).collect();
        for _ in 0..300_000 {
            let magnitude = 10f64.powf(rng.random_range(-12.0..9.0));
            xs.push(if rng.random_bool(0.5) { -magnitude } else { magnitude });
        }
        let around = |xs: &mut Vec<f64>, x: f64| {
            for d in 0..2000u64 {
                xs.extend([f64::from_bits(x.to_bits() + d), f64::from_bits(x.to_bits() - d), -x]);
            }
        };
        for w in [0x3e40_0000u64, 0x3e50_0000, 0x3feb_6000, 0x4003_68fd, 0x4199_21fb] {
            around(&mut xs, f64::from_bits(w << 32));
        }
        for q in 1..=64 {
            around(&mut xs, q as f64 * std::f64::consts::FRAC_PI_4);
        }
        for j in 0..128 {
            // do_sin/do_cos round |x| to a table row at (j + 0.5)/128, also via hp0 - |x|
            let tie = (j as f64 + 0.5) / 128.0;
            xs.extend([tie, -tie, std::f64::consts::FRAC_PI_2 + tie, std::f64::consts::FRAC_PI_2 - tie]);
        }
        xs.extend([0.0, -0.0, 1e-310, -1e-310, f64::INFINITY, f64::NEG_INFINITY, f64::NAN, 1e300, f64::MAX]);
        xs.extend([1.6762650767948966, -1.6762650767948966]);
        for chunk in xs.chunks(8) {
            let mut a = [chunk[0]; 8];
            a[..chunk.len()].copy_from_slice(chunk);
            let (s, c) = lanes_sincos(a);
            for (l, &x) in chunk.iter().enumerate() {
                let (ws, wc) = std::hint::black_box(x).sin_cos();
                let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
                assert!(
                    same(s[l], ws) && same(c[l], wc),
                    "sincos({x:e} = {:#x}): lanes ({:e}, {:e}), libm ({ws:e}, {wc:e})",
                    x.to_bits(),
                    s[l],
                    c[l]
                );
            }
        }
    }
}
