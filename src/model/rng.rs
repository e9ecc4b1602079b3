//! Counter-based random numbers keyed by (seed, particle, bounce, draw).
//!
//! Every random number a particle draws is a pure function of its key, so the CPU engines
//! and the WGSL kernels draw identical numbers in any order or thread layout. The mixer is
//! the `pcg4d` hash (Jarzynski & Olano, "Hash Functions for GPU Rendering", JCGT 2020):
//! 32-bit multiplies, adds, xors and shifts only, which WGSL has (it has no 64-bit integers).
//! Twin of `shaders/shared/rng.wgsl`: same function names and arguments; `pcg4d` and
//! `uniform01` give identical bits on both sides, `normal01` agrees to rounding.

/// One round of pcg4d on a 4-vector of u32.
#[inline(always)]
pub fn pcg4d(v: [u32; 4]) -> [u32; 4] {
    pcg4d_keys::<1>(v.map(|x| [x])).map(|[x]| x)
}

/// One round of pcg4d on `N` 4-vectors at once, stored component by component (`v[c][k]` is
/// component c of key k): the hash written once, for one key ([`pcg4d`]) and for the cpu
/// engine's sixteen-lane draws, where each step is one loop over the keys that the compiler
/// turns into vector instructions of the caller's instruction set. Integer arithmetic, so
/// every `N` gives the same words.
#[inline(always)]
pub fn pcg4d_keys<const N: usize>(mut v: [[u32; N]; 4]) -> [[u32; N]; 4] {
    for c in v.iter_mut() {
        for x in c.iter_mut() {
            *x = x.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        }
    }
    mix::<N>(&mut v);
    for c in v.iter_mut() {
        for x in c.iter_mut() {
            *x ^= *x >> 16;
        }
    }
    mix::<N>(&mut v);
    v
}

/// pcg4d's cross-component step: each component plus the product of two others.
#[inline(always)]
fn mix<const N: usize>(v: &mut [[u32; N]; 4]) {
    for (to, a, b) in [(0, 1, 3), (1, 2, 0), (2, 0, 1), (3, 1, 2)] {
        let (x, y) = (v[a], v[b]);
        for ((t, x), y) in v[to].iter_mut().zip(x).zip(y) {
            *t = t.wrapping_add(x.wrapping_mul(y));
        }
    }
}

/// Fold a 64-bit seed into the 32-bit key word (both halves matter).
#[inline(always)]
pub fn seed_word(seed: u64) -> u32 {
    let lo = seed as u32;
    let hi = (seed >> 32) as u32;
    lo ^ hi.wrapping_mul(0x9E37_79B9).rotate_left(16)
}

/// Uniform number in [0, 1) with 24 random bits: exactly representable in f32 and f64,
/// so both precisions see the same value. WGSL twin: `uniform01` (same bits, as f32).
#[inline(always)]
pub fn uniform01(seed_word: u32, particle: u32, bounce: u32, draw: u32) -> f64 {
    // Two rounds: one round of pcg4d leaves visible structure for small consecutive keys.
    let h = pcg4d(pcg4d([particle, bounce, draw, seed_word]));
    unit_from_hash(h[0])
}

/// The uniform number of a hash word: its top 24 bits as a fraction of 2^24 (exact in f32
/// and f64). Shared by [`uniform01`] and the cpu engine's sixteen-lane draws.
#[inline(always)]
pub fn unit_from_hash(word: u32) -> f64 {
    (word >> 8) as f64 * (1.0 / 16_777_216.0)
}

/// The draw ids (which draw of a particle's launch or bounce a number is), declared once for
/// the Rust and WGSL sides in src/kernel_codes.rs (build.rs generates the WGSL twins).
pub use crate::kernel_codes::{
    DRAW_ANGLE, DRAW_LAUNCH_ANGLE, DRAW_LAUNCH_POINT, DRAW_LAUNCH_SPEED, DRAW_SCATTER, DRAW_SIZE, DRAW_SPEED,
    PER_PARTICLE,
};

/// Standard normal deviate from two keyed uniforms (Box-Muller). WGSL twin: `normal01`, which
/// is this in f32 with the kernel's `ksin_cos` for the cosine and `kln` for the logarithm (so
/// equal to rounding, not bits).
pub fn normal01(seed_word: u32, particle: u32, bounce: u32, draw: u32) -> f64 {
    let u1 = 1.0 - uniform01(seed_word, particle, bounce, draw); // (0, 1]
    let u2 = uniform01(seed_word, particle, bounce, draw + 1);
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_is_in_unit_interval_and_roughly_flat() {
        let s = seed_word(42);
        let mut bins = [0u32; 10];
        let n = 100_000u32;
        for i in 0..n {
            let u = uniform01(s, i, i % 7, i % 2);
            assert!((0.0..1.0).contains(&u));
            bins[(u * 10.0) as usize] += 1;
        }
        for b in bins {
            // 10 000 expected per bin; 5 sigma is 300
            assert!((9_500..10_500).contains(&b), "bins {bins:?}");
        }
    }

    #[test]
    fn keys_change_the_value() {
        let s = seed_word(1);
        let a = uniform01(s, 3, 4, 0);
        assert_ne!(a, uniform01(s, 3, 4, 1));
        assert_ne!(a, uniform01(s, 3, 5, 0));
        assert_ne!(a, uniform01(s, 4, 4, 0));
        assert_ne!(a, uniform01(seed_word(2), 3, 4, 0));
        assert_eq!(a, uniform01(s, 3, 4, 0));
    }

    #[test]
    fn normal_deviates_have_unit_variance() {
        let s = seed_word(9);
        let n = 50_000u32;
        let z: Vec<f64> = (0..n).map(|i| normal01(s, i, 0, DRAW_SCATTER)).collect();
        let m = z.iter().sum::<f64>() / n as f64;
        let v = z.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n as f64;
        assert!(m.abs() < 0.02 && (v - 1.0).abs() < 0.03, "{m} {v}");
    }

    #[test]
    fn pcg4d_gives_the_published_hash() {
        // the words of the paper's definition (LCG step, cross mix, xor-shift 16, cross mix),
        // computed apart from this code
        assert_eq!(pcg4d([0, 1, 2, 3]), [0x37a6_3737, 0x8642_5e4b, 0x4eef_b3bc, 0x76a7_b083]);
        assert_eq!(pcg4d(pcg4d([7, 0, 3, 0xdead_beef])), [0x6a9b_7d51, 0xcda2_172d, 0x0307_7e00, 0x3eab_6fe5]);
    }

    #[test]
    fn the_hash_of_many_keys_side_by_side_is_each_keys_hash() {
        let keys: [[u32; 4]; 5] = std::array::from_fn(|k| [k as u32 * 977, 3 + k as u32, 5, 0x1234_5678 ^ k as u32]);
        let side_by_side = pcg4d_keys::<5>(std::array::from_fn(|c| keys.map(|key| key[c])));
        for (k, key) in keys.iter().enumerate() {
            assert_eq!(pcg4d(*key), std::array::from_fn(|c| side_by_side[c][k]), "key {k}");
        }
    }

    #[test]
    fn high_seed_bits_matter() {
        assert_ne!(seed_word(5), seed_word(5 | (1 << 40)));
    }
}
