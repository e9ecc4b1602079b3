// Counter-based random numbers keyed by (seed, particle, bounce, draw): pcg4d
// (Jarzynski & Olano, JCGT 2020). Twin of src/model/rng.rs; both must give identical bits.

#import shared/klog.wgsl

fn pcg4d(v_in: vec4<u32>) -> vec4<u32> {
    var v = v_in * 1664525u + 1013904223u;
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    v = v ^ (v >> vec4<u32>(16u));
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    return v;
}

// Uniform in [0, 1) with 24 random bits (exact in f32).
fn uniform01(seed: u32, particle: u32, bounce: u32, draw: u32) -> f32 {
    let h = pcg4d(pcg4d(vec4<u32>(particle, bounce, draw, seed)));
    return f32(h.x >> 8u) * (1.0 / 16777216.0);
}

// Standard normal deviate from two keyed uniforms (Box-Muller), as src/model/rng.rs `normal`.
fn normal01(seed: u32, particle: u32, bounce: u32, draw: u32) -> f32 {
    let u1 = 1.0 - uniform01(seed, particle, bounce, draw);
    let u2 = uniform01(seed, particle, bounce, draw + 1u);
    return sqrt(-2.0 * kln(u1)) * ksin_cos(2.0 * PI * u2).y;
}
