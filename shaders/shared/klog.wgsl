// f32 natural logarithm written out: Vulkan promises `log` only to 2^-21 ABSOLUTE on [0.5, 2],
// which near 1 is no relative accuracy at all: a Box-Muller radius sqrt(-2 log u) may come out
// NaN and the Stokes flight time -log(1 - k x / vx) / k far off where u or 1 - k x / vx is close
// to 1 (the H200's own log was accurate enough on the conformance cases; docs/math.md).
// ln x = e ln 2 + 2 atanh(s) with x = m 2^e, m in [sqrt(1/2), sqrt(2)), s = (m - 1)/(m + 1),
// |s| <= 0.1716: the atanh series to s^9 is within 2e-9 relative, so the error is the rounding
// of s and of the sum, a few ulp, relative also near 1. ln 2 in two pieces (the high one has
// 16 significant bits, so e ln2_hi is exact). For x > 0; x <= 0 (the kernels pass none) gives
// -3.4028235e38, +inf itself.
// Twin: src/model/real.rs `klog`.

const LN2_HI: f32 = 0.69314575;
const LN2_LO: f32 = 1.4286068e-6;

fn kln(x_in: f32) -> f32 {
    if (!(x_in > 0.0)) { return -3.4028235e38; }
    if (x_in > 3.4028235e38) { return x_in; }
    var x = x_in;
    var e = 0;
    // subnormal (where the device keeps them): scale by 2^23 into the normal range first
    if (x < 1.1754944e-38) {
        x = x * 8388608.0;
        e = -23;
    }
    let bits = bitcast<u32>(x);
    e += i32((bits >> 23u) & 0xffu) - 127;
    var m = bitcast<f32>((bits & 0x007fffffu) | 0x3f800000u);
    if (m > 1.4142135) {
        m = m * 0.5;
        e += 1;
    }
    let s = (m - 1.0) / (m + 1.0);
    let z = s * s;
    let p = 2.0 * s + 2.0 * s * z * (0.33333334 + z * (0.2 + z * (0.14285715 + z * 0.11111111)));
    let ef = f32(e);
    return ef * LN2_HI + (ef * LN2_LO + p);
}
