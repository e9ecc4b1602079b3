//! The flight search of [`first_hit`](super::kernel::first_hit) for [`LANES`] particles at
//! once, in f64, every hop an impact: vacuum parabolas (the lunar batches) and Stokes
//! flights (Earth's), in one piece ([`first_hits`]) or in the pieces of a flight with sled
//! motion or quadratic drag ([`first_hits_piecewise`], `first_hit_in` with a time limit and a
//! drift). The branches of the scalar search become masks and selects on AVX-512 lanes,
//! and every lane does the scalar search's IEEE operations in the scalar search's order, so
//! each lane's hit is the scalar hit to the bit (`tests` below, and
//! `examples/dev/engine_digest.rs`). A lane whose particle has finished its teeth (or its
//! Halley steps) idles while the others go on. Beside it, on the same lanes: the launch
//! randomisation ([`randomise_launches`]), the restitution law ([`bounce_velocities`]) and
//! the counter-based generator's hash ([`uniforms`]). `exp_m1`, `sin_cos`, `atan2`, `ln`
//! and `ln_1p` are the project's own (`crate::lane_math`), one generic code that the scalar
//! kernel runs on one `f64` and these lanes on eight (`avx512::F64x8`). Only on CPUs with AVX-512F ([`available`]) and where
//! `SAWTOOTH_CPU_LEVEL` does not cap it (`crate::x86_64_v3::level_cap`); elsewhere the cpu
//! engine runs the scalar kernel.
//! Why intrinsics: written as loops over eight-element arrays the compiler left the search
//! scalar, 45 % slower than the one-particle search (BENCHMARKS.md).

use super::kernel::{
    end_of_piece, first_hit, first_hit_in, next_piece, Hit, KDesign, KParticle, KPhysics, SURFACE_BASE, SURFACE_CATCH,
    SURFACE_NONE, SURFACE_RAMP,
};
use crate::model::collision::Restitution;
use crate::model::flight::Flight;

/// Particles searched together: eight f64 lanes, one AVX-512 register.
pub const LANES: usize = 8;

/// Whether [`first_hits`] gives the scalar search's hits for these physics: a flight in one
/// piece (no sled motion, no quadratic drag) and no minimum hop (the listing mode's 1e-3 mm
/// rule skips roots the lanes would take). Vacuum (the Moon) and Stokes drag (Earth) both.
pub fn applies(ph: &KPhysics<f64>) -> bool {
    ph.sled_speed == 0.0 && ph.qd_step == 0.0 && ph.min_hop == 0.0
}

/// Whether [`first_hits_piecewise`] gives the scalar search's hits for these physics:
/// flights in pieces (sled motion, quadratic drag) and no minimum hop.
pub fn applies_piecewise(ph: &KPhysics<f64>) -> bool {
    (ph.sled_speed > 0.0 || ph.qd_step > 0.0) && ph.min_hop == 0.0
}

/// The lanes' flights for [`avx512::first_hits`], one row per quantity and one column per
/// lane (filled in place: the lunar batches' search is short enough for a copy to show):
/// where each starts (the particle's position, surface and tooth frame), its launch velocity
/// and drag rate, and for a piece how long the search looks and the drift.
struct LaneFlights([[f64; LANES]; 10]);

impl LaneFlights {
    const POS: usize = 0;
    const VEL: usize = 2;
    const SURFACE: usize = 4;
    const TOOTH: usize = 5;
    const K: usize = 6;
    const LIMIT: usize = 7;
    const DRIFT: usize = 8;

    fn new() -> Self {
        LaneFlights([[0.0; LANES]; 10])
    }

    /// Which of `n` flights (1 to [`LANES`]) lane `l` takes: its own, or the first again
    /// beyond `n` (a lane whose hit the caller drops).
    #[inline(always)]
    fn source(l: usize, n: usize) -> usize {
        if l < n {
            l
        } else {
            0
        }
    }

    /// Lane `l` flies particle `p` with drag rate `k` (a flight in one piece).
    #[inline(always)]
    fn set(&mut self, l: usize, p: &KParticle<f64>, k: f64) {
        let a = &mut self.0;
        (a[Self::POS][l], a[Self::POS + 1][l]) = (p.pos[0], p.pos[1]);
        (a[Self::VEL][l], a[Self::VEL + 1][l]) = (p.vel[0], p.vel[1]);
        (a[Self::SURFACE][l], a[Self::TOOTH][l], a[Self::K][l]) = (p.surface as f64, p.tooth as f64, k);
    }

    /// Lane `l` flies a piece of particle `p`'s flight: drag rate `k`, `drift`, length `limit`.
    #[inline(always)]
    fn set_piece(&mut self, l: usize, p: &KParticle<f64>, k: f64, drift: [f64; 2], limit: f64) {
        self.set(l, p, k);
        let a = &mut self.0;
        (a[Self::DRIFT][l], a[Self::DRIFT + 1][l], a[Self::LIMIT][l]) = (drift[0], drift[1], limit);
    }
}

/// The lanes' search of [`LANES`] flights (a caller with fewer repeats the first and drops
/// its lanes' hits); `pieces`: some may have a time limit or a drift.
fn search(d: &KDesign<f64>, ph: &KPhysics<f64>, lanes: &LaneFlights, pieces: bool, bounce: u32) -> [Hit<f64>; LANES] {
    assert!(available());
    #[cfg(target_arch = "x86_64")]
    // SAFETY: the CPU has AVX-512F (asserted above).
    return unsafe {
        match (ph.k_drag > 0.0, pieces) {
            (true, false) => avx512::first_hits::<true, false>(d, ph, lanes, bounce),
            (false, false) => avx512::first_hits::<false, false>(d, ph, lanes, bounce),
            (true, true) => avx512::first_hits::<true, true>(d, ph, lanes, bounce),
            (false, true) => avx512::first_hits::<false, true>(d, ph, lanes, bounce),
        }
    };
    #[allow(unreachable_code)]
    {
        unreachable!("available() is false off x86-64")
    }
}

/// Whether this CPU runs [`first_hits`] (AVX-512F, not capped by `SAWTOOTH_CPU_LEVEL`; the
/// caller searches one particle at a time otherwise).
pub fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    return crate::x86_64_v3::level_cap() >= crate::x86_64_v3::Level::Avx512
        && std::arch::is_x86_feature_detected!("avx512f");
    #[allow(unreachable_code)]
    false
}

/// The first impact of each of the particles `parts[idx[l]]` (as `kernel::first_hit` finds
/// it), for physics where [`applies`] holds, on a CPU where [`available`] holds. `idx` has
/// 1 to [`LANES`] entries; lanes beyond it repeat the first particle and are dropped.
#[inline]
pub fn first_hits(
    d: &KDesign<f64>,
    ph: &KPhysics<f64>,
    parts: &[KParticle<f64>],
    idx: &[u32],
    bounce: u32,
) -> [Hit<f64>; LANES] {
    assert!(applies(ph) && available() && !idx.is_empty() && idx.len() <= LANES);
    // every grain has drag when the air has (Stokes k_drag > 0, scaled per grain when
    // polydisperse), none in vacuum
    let drag = ph.k_drag > 0.0;
    let mut flights = LaneFlights::new();
    for l in 0..LANES {
        let p = &parts[idx[LaneFlights::source(l, idx.len())] as usize];
        flights.set(l, p, if drag { p.k_drag } else { 0.0 });
    }
    let mut hits = search(d, ph, &flights, false, bounce);
    // a grain whose own k_drag rounds to 0 (polydisperse, an extreme draw) flies in vacuum:
    // the scalar search, which picks the flight's form per grain, takes it (in vacuum every
    // grain's k_drag is 0 times its factor, and the vacuum search never reads it)
    if drag {
        for (h, &i) in hits.iter_mut().zip(idx) {
            let p = &parts[i as usize];
            if p.k_drag.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                *h = scalar_hit(d, ph, p, bounce);
            }
        }
    }
    hits
}

/// A flight's first impact (time from the flight's start), the flight of the piece it lies
/// in, and that piece's start: what `kernel::first_hit_piecewise` returns.
pub type PieceHit = (Hit<f64>, Flight<f64>, f64);

/// `kernel::first_hit_piecewise` of the particles `parts[i]`, i in `idx` (any number), on a
/// CPU where [`available`] holds and for physics where [`applies_piecewise`] does: for each,
/// the hit (time from the flight's start), the piece's flight it lies in and that piece's
/// start, to the scalar search's bits. Eight particles fly at a time, each from piece to
/// piece with the scalar `next_piece` and `end_of_piece`, each piece's search on the lanes
/// (a drifting piece, the sled returning, searches every tooth of its reach over the whole
/// piece, as the scalar search does; a grain without drag in air goes to the scalar
/// search). A particle whose flight ends leaves its lane to the next.
pub fn first_hits_piecewise(
    d: &KDesign<f64>,
    ph: &KPhysics<f64>,
    parts: &[KParticle<f64>],
    idx: &[u32],
    bounce: u32,
) -> Vec<PieceHit> {
    assert!(applies_piecewise(ph) && available());
    let drag = ph.k_drag > 0.0;
    /// A particle in flight: its place in `idx`, its state at its piece's start and when
    /// that piece starts.
    struct Slot {
        n: usize,
        q: KParticle<f64>,
        elapsed: f64,
    }
    let mut out: Vec<Option<PieceHit>> = vec![None; idx.len()];
    let mut waiting = 0..idx.len();
    let mut slots: Vec<Slot> = Vec::with_capacity(LANES);
    // each round's pieces and the slots searched on the lanes (kept across rounds: no
    // allocation per round)
    let mut pieces: Vec<(Flight<f64>, f64, f64)> = Vec::with_capacity(LANES);
    let mut on_lanes: Vec<usize> = Vec::with_capacity(LANES);
    // a grain without drag in air goes to the scalar search
    let lane_search = |fl: &Flight<f64>| !drag || fl.k > 0.0;
    loop {
        while slots.len() < LANES {
            let Some(n) = waiting.next() else { break };
            slots.push(Slot { n, q: parts[idx[n] as usize], elapsed: 0.0 });
        }
        if slots.is_empty() {
            break;
        }
        pieces.clear();
        pieces.extend(slots.iter().map(|s| next_piece(d, ph, &s.q)));
        on_lanes.clear();
        on_lanes.extend((0..slots.len()).filter(|&i| lane_search(&pieces[i].0)));
        let mut hits = [Hit::default(); LANES];
        if !on_lanes.is_empty() {
            let mut flights = LaneFlights::new();
            for l in 0..LANES {
                let i = on_lanes[LaneFlights::source(l, on_lanes.len())];
                let (fl, _, limit) = &pieces[i];
                flights.set_piece(l, &slots[i].q, if drag { fl.k } else { 0.0 }, fl.drift, *limit);
            }
            let found = search(d, ph, &flights, true, bounce);
            for (l, &i) in on_lanes.iter().enumerate() {
                hits[i] = found[l];
            }
        }
        for ((slot, piece), hit) in slots.iter().zip(&pieces).zip(&mut hits) {
            if !lane_search(&piece.0) {
                *hit = first_hit_in(d, ph, &slot.q, &piece.0, bounce, piece.2);
            }
        }
        for i in (0..slots.len()).rev() {
            let (fl, phase_end, limit) = pieces[i];
            let slot = &mut slots[i];
            let start = slot.elapsed;
            if let Some(hit) = end_of_piece(d, &mut slot.q, &fl, (phase_end, limit), hits[i], &mut slot.elapsed) {
                out[slot.n] = Some((hit, fl, start));
                slots.swap_remove(i);
            }
        }
    }
    out.into_iter().map(|o| o.expect("every flight ends")).collect()
}

/// The scalar search for the rare grain the lanes leave to it, kept out of line.
#[inline(never)]
fn scalar_hit(d: &KDesign<f64>, ph: &KPhysics<f64>, p: &KParticle<f64>, bounce: u32) -> Hit<f64> {
    first_hit(d, ph, p, bounce)
}

/// `Restitution::bounce` of [`LANES`] impact velocities `v` on surfaces with normals `n`,
/// on a CPU where [`available`] holds: the same bits as the scalar law in every lane.
pub fn bounce_velocities(r: &Restitution<f64>, v: &[[f64; LANES]; 2], n: &[[f64; LANES]; 2]) -> [[f64; LANES]; 2] {
    assert!(available());
    if r.dem {
        // the DEM law's table look-up has no lane form: the scalar law, lane by lane
        let mut out = [[0.0; LANES]; 2];
        for l in 0..LANES {
            [out[0][l], out[1][l]] = r.bounce([v[0][l], v[1][l]], [n[0][l], n[1][l]]);
        }
        return out;
    }
    #[cfg(target_arch = "x86_64")]
    // SAFETY: the CPU has AVX-512F (asserted above).
    return unsafe { avx512::bounce(r, v, n) };
    #[allow(unreachable_code)]
    {
        unreachable!("available() is false off x86-64")
    }
}

/// Whether [`randomise_launches`] gives `kernel::randomise_launch_drawn`'s launches for
/// these physics when the launch factors are drawn: yes unless the launch-spread effect draws
/// more per first launch (then one particle at a time).
pub fn randomises(ph: &KPhysics<f64>) -> bool {
    ph.launch_speed_spread == 0.0 && ph.launch_angle_sigma == 0.0
}

/// `kernel::randomise_launch_drawn` of the particles `parts[idx[l]]` (1 to [`LANES`]) whose
/// launch factors are drawn, with their draws `angle[l]`, `speed[l]` (`DRAW_ANGLE`,
/// `DRAW_SPEED`), on a CPU where [`available`] holds and for physics where [`randomises`]
/// does: the same velocities to the bit.
pub fn randomise_launches(
    d: &KDesign<f64>,
    ph: &KPhysics<f64>,
    parts: &mut [KParticle<f64>],
    idx: &[u32],
    angle: &[f64],
    speed: &[f64],
) {
    assert!(available() && randomises(ph) && !idx.is_empty() && idx.len() <= LANES);
    assert!(angle.len() >= idx.len() && speed.len() >= idx.len());
    #[cfg(target_arch = "x86_64")]
    // SAFETY: the CPU has AVX-512F (asserted above).
    unsafe {
        avx512::randomise(d, ph, parts, idx, angle, speed)
    };
    #[cfg(not(target_arch = "x86_64"))]
    unreachable!("available() is false off x86-64");
}

/// `rng::uniform01(seed_word, particle, bounce, draw)` for each of `particles` (1 to 16),
/// on a CPU where [`available`] holds: the counter-based generator's integer hash on
/// sixteen lanes, the same numbers.
pub fn uniforms(seed_word: u32, particles: &[u32], bounce: u32, draw: u32) -> [f64; 16] {
    assert!(available() && !particles.is_empty() && particles.len() <= 16);
    let mut ids = [particles[0]; 16];
    ids[..particles.len()].copy_from_slice(particles);
    #[cfg(target_arch = "x86_64")]
    // SAFETY: the CPU has AVX-512F (asserted above).
    let h = unsafe { avx512::uniform_bits(seed_word, &ids, bounce, draw) };
    #[cfg(not(target_arch = "x86_64"))]
    let h: [u32; 16] = unreachable!("available() is false off x86-64");
    h.map(crate::model::rng::unit_from_hash)
}

#[cfg(target_arch = "x86_64")]
mod avx512 {
    use super::*;
    use crate::lane_math::{self, Lane};
    use std::arch::x86_64::*;
    use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

    type V = __m512d;
    type M = __mmask8;

    // One helper per scalar operation, each the IEEE operation of the scalar code in every
    // lane (the target feature lets them inline into `first_hits`).
    macro_rules! lane_ops {
        ($($name:ident -> $out:ty = $body:expr;)*) => {$(
            #[target_feature(enable = "avx512f")]
            #[inline]
            fn $name(a: V, b: V) -> $out {
                $body(a, b)
            }
        )*};
    }
    lane_ops! {
        add -> V = _mm512_add_pd;
        sub -> V = _mm512_sub_pd;
        mul -> V = _mm512_mul_pd;
        div -> V = _mm512_div_pd;
        // ordered comparisons: false where either is NaN, as in scalar code
        lt -> M = _mm512_cmp_pd_mask::<_CMP_LT_OQ>;
        le -> M = _mm512_cmp_pd_mask::<_CMP_LE_OQ>;
        gt -> M = _mm512_cmp_pd_mask::<_CMP_GT_OQ>;
        ge -> M = _mm512_cmp_pd_mask::<_CMP_GE_OQ>;
        eq -> M = _mm512_cmp_pd_mask::<_CMP_EQ_OQ>;
        // `!=`: true where either is NaN, as in scalar code
        ne -> M = _mm512_cmp_pd_mask::<_CMP_NEQ_UQ>;
    }
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn sp(x: f64) -> V {
        _mm512_set1_pd(x)
    }
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn neg(a: V) -> V {
        _mm512_castsi512_pd(_mm512_xor_si512(_mm512_castpd_si512(a), _mm512_set1_epi64(i64::MIN)))
    }
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn abs(a: V) -> V {
        _mm512_abs_pd(a)
    }
    /// `f64::max`: the other operand where one is NaN.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn max(a: V, b: V) -> V {
        let m = _mm512_max_pd(a, b);
        _mm512_mask_blend_pd(_mm512_cmp_pd_mask::<_CMP_UNORD_Q>(b, b), m, a)
    }
    /// `f64::min`: the other operand where one is NaN.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn min(a: V, b: V) -> V {
        let m = _mm512_min_pd(a, b);
        _mm512_mask_blend_pd(_mm512_cmp_pd_mask::<_CMP_UNORD_Q>(b, b), m, a)
    }
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn floor(a: V) -> V {
        _mm512_roundscale_pd::<{ _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC }>(a)
    }
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn ceil(a: V) -> V {
        _mm512_roundscale_pd::<{ _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC }>(a)
    }
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn sqrt(a: V) -> V {
        _mm512_sqrt_pd(a)
    }
    /// `if m { a } else { b }` in every lane.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn sel(m: M, a: V, b: V) -> V {
        _mm512_mask_blend_pd(m, b, a)
    }
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn load(a: &[f64; LANES]) -> V {
        // SAFETY: eight f64 are readable at `a`.
        unsafe { _mm512_loadu_pd(a.as_ptr()) }
    }
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn store(v: V) -> [f64; LANES] {
        let mut a = [0.0; LANES];
        // SAFETY: eight f64 are writable at `a`.
        unsafe { _mm512_storeu_pd(a.as_mut_ptr(), v) };
        a
    }

    /// Eight f64 lanes as a [`Lane`] for `crate::lane_math`'s functions. Its operations are
    /// AVX-512F instructions: a value exists only inside this module's functions, which all
    /// run where [`super::available`] holds (the SAFETY notes below rest on that), and they
    /// inline into those functions' `target_feature` code.
    #[derive(Clone, Copy)]
    pub struct F64x8(pub V);
    /// The lanes a comparison of two [`F64x8`] holds in.
    #[derive(Clone, Copy)]
    pub struct Mask8(pub M);

    macro_rules! binary {
        ($($op:ident $method:ident $intrinsic:ident;)*) => {$(
            impl $op for F64x8 {
                type Output = F64x8;
                #[inline(always)]
                fn $method(self, other: F64x8) -> F64x8 {
                    // SAFETY: AVX-512F is present wherever an F64x8 exists (see the type)
                    F64x8(unsafe { $intrinsic(self.0, other.0) })
                }
            }
        )*};
    }
    binary! {
        Add add _mm512_add_pd;
        Sub sub _mm512_sub_pd;
        Mul mul _mm512_mul_pd;
        Div div _mm512_div_pd;
    }
    impl Neg for F64x8 {
        type Output = F64x8;
        #[inline(always)]
        fn neg(self) -> F64x8 {
            // SAFETY: AVX-512F is present wherever an F64x8 exists (see the type)
            F64x8(unsafe { neg(self.0) })
        }
    }
    impl BitAnd for Mask8 {
        type Output = Mask8;
        #[inline(always)]
        fn bitand(self, other: Mask8) -> Mask8 {
            Mask8(self.0 & other.0)
        }
    }
    impl BitOr for Mask8 {
        type Output = Mask8;
        #[inline(always)]
        fn bitor(self, other: Mask8) -> Mask8 {
            Mask8(self.0 | other.0)
        }
    }
    impl Not for Mask8 {
        type Output = Mask8;
        #[inline(always)]
        fn not(self) -> Mask8 {
            Mask8(!self.0)
        }
    }
    // SAFETY (every block below): AVX-512F is present wherever an F64x8 exists (see the type)
    impl Lane for F64x8 {
        type Mask = Mask8;
        #[inline(always)]
        fn splat(x: f64) -> Self {
            F64x8(unsafe { sp(x) })
        }
        #[inline(always)]
        fn abs(self) -> Self {
            F64x8(unsafe { abs(self.0) })
        }
        #[inline(always)]
        fn lt(self, other: Self) -> Mask8 {
            Mask8(unsafe { lt(self.0, other.0) })
        }
        #[inline(always)]
        fn le(self, other: Self) -> Mask8 {
            Mask8(unsafe { le(self.0, other.0) })
        }
        #[inline(always)]
        fn eq(self, other: Self) -> Mask8 {
            Mask8(unsafe { eq(self.0, other.0) })
        }
        #[inline(always)]
        fn select(m: Mask8, a: Self, b: Self) -> Self {
            F64x8(unsafe { sel(m.0, a.0, b.0) })
        }
        #[inline(always)]
        fn sign_negative(self) -> Mask8 {
            // the sign bit as a 64-bit integer's: negative
            Mask8(unsafe { sign_mask(self.0) })
        }
        #[inline(always)]
        fn copysign(self, sign: Self) -> Self {
            F64x8(unsafe { copysign(self.0, sign.0) })
        }
        #[inline(always)]
        fn pow2i(self) -> Self {
            F64x8(unsafe { pow2i(self.0) })
        }
        #[inline(always)]
        fn exponent_field_and_significand(self) -> (Self, Self) {
            let (field, significand) = unsafe { exponent_field_and_significand(self.0) };
            (F64x8(field), F64x8(significand))
        }
    }
    /// [`Lane::exponent_field_and_significand`]: the lanes of f64's, the same bit operations.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn exponent_field_and_significand(x: V) -> (V, V) {
        let bits = _mm512_castpd_si512(x);
        let two_52 = _mm512_set1_pd(4_503_599_627_370_496.0);
        let field = _mm512_and_si512(_mm512_srli_epi64::<52>(bits), _mm512_set1_epi64(0x7ff));
        let field = _mm512_sub_pd(_mm512_castsi512_pd(_mm512_or_si512(_mm512_castpd_si512(two_52), field)), two_52);
        let significand = _mm512_or_si512(
            _mm512_and_si512(bits, _mm512_set1_epi64(lane_math::MANTISSA_BITS as i64)),
            _mm512_set1_epi64(lane_math::ONE_BITS as i64),
        );
        (field, _mm512_castsi512_pd(significand))
    }
    /// Lanes whose sign bit is set (AVX-512F has no `movepi64_mask`, which is AVX-512DQ).
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn sign_mask(a: V) -> M {
        _mm512_cmplt_epi64_mask(_mm512_castpd_si512(a), _mm512_setzero_si512())
    }
    /// `|a|` with the sign of `sign`.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn copysign(a: V, sign: V) -> V {
        let bit = _mm512_set1_epi64(i64::MIN);
        let (a, sign) = (_mm512_castpd_si512(a), _mm512_castpd_si512(sign));
        _mm512_castsi512_pd(_mm512_or_si512(_mm512_andnot_si512(bit, a), _mm512_and_si512(sign, bit)))
    }
    /// [`Lane::pow2i`]: the lanes of `f64::pow2i`, the same integer trick.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn pow2i(k: V) -> V {
        let biased = _mm512_add_pd(k, _mm512_set1_pd(1023.0 + 4_503_599_627_370_496.0));
        _mm512_castsi512_pd(_mm512_slli_epi64::<52>(_mm512_castpd_si512(biased)))
    }

    /// Up to two crossing times per lane: how many (as f64), the first and the second.
    #[derive(Clone, Copy)]
    struct Roots {
        n: V,
        r0: V,
        r1: V,
    }

    /// `push_root` in the lanes of `mask`.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn push(r: &mut Roots, mask: M, t: V, t_min: V, t_max: V) {
        let ok = mask & gt(t, sp(0.0)) & ge(t, t_min) & le(t, t_max);
        let first = eq(r.n, sp(0.0));
        r.r0 = sel(ok & first, t, r.r0);
        r.r1 = sel(ok & !first, t, r.r1);
        r.n = _mm512_mask_add_pd(r.n, ok, r.n, sp(1.0));
    }

    /// A flight's start, launch velocity and drag in every lane.
    #[derive(Clone, Copy)]
    struct Fl {
        px: V,
        py: V,
        vx: V,
        vy: V,
        /// 0.5 g, as the scalar position multiplies it.
        half_g: V,
        /// Stokes k_drag (1/s; 0 in vacuum) and the terminal velocity -g/k of a drag flight.
        k: V,
        vinf: V,
        /// The sled-motion drift added to the position (zero but where a piece drifts) and
        /// the lanes whose piece drifts (`Flight::drift` not zero).
        wx: V,
        wy: V,
        drifting: M,
    }

    /// `relax`, (1 - e^{-kt})/k (flight.rs), in the lanes of `mask`.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn relax(f: &Fl, mask: M, t: V) -> V {
        div(neg(exp_m1(f, mask, mul(neg(f.k), t))), f.k)
    }

    /// `Real::kexp_m1` (`lane_math::exp_m1`) in every lane; the flight and the mask say
    /// where it is needed, and the other lanes' results are dropped.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn exp_m1(_f: &Fl, _mask: M, x: V) -> V {
        lane_math::exp_m1(F64x8(x)).0
    }

    /// `Flight::pos`, needed in the lanes of `mask` (a drag flight's exponential is taken
    /// there only).
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn pos_at<const DRAG: bool>(f: &Fl, mask: M, t: V) -> (V, V) {
        let (x, y) = if DRAG {
            // Eq. 4.53-4.54
            let e = relax(f, mask, t);
            (add(f.px, mul(f.vx, e)), add(add(f.py, mul(f.vinf, t)), mul(sub(f.vy, f.vinf), e)))
        } else {
            (add(f.px, mul(f.vx, t)), sub(add(f.py, mul(f.vy, t)), mul(mul(f.half_g, t), t)))
        };
        if f.drifting == 0 {
            return (x, y);
        }
        // the drift adds to the position where there is one (`Flight::pos`)
        (sel(f.drifting, add(x, mul(f.wx, t)), x), sel(f.drifting, add(y, mul(f.wy, t)), y))
    }

    /// `Flight::time_at_x`, needed in the lanes of `mask`.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn time_at_x<const DRAG: bool>(f: &Fl, _mask: M, x: V) -> V {
        let dx = sub(x, f.px);
        let t = div(dx, f.vx);
        let never = eq(f.vx, sp(0.0)) | lt(t, sp(0.0));
        let behind = sel(eq(dx, sp(0.0)), sp(0.0), sp(f64::INFINITY));
        if DRAG {
            // beyond the drag asymptote x0 + vx/k when q <= 0
            let q = sub(sp(1.0), div(mul(f.k, dx), f.vx));
            let beyond = le(q, sp(0.0));
            let t = div(neg(lane_math::ln(F64x8(q)).0), f.k);
            return sel(never, behind, sel(beyond, sp(f64::INFINITY), t));
        }
        sel(never, behind, t)
    }

    /// `Flight::y_at_x`, needed in the lanes of `mask`: whether it gets there, and the height.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn y_at_x<const DRAG: bool>(f: &Fl, _mask: M, x: V) -> (M, V) {
        let e = div(sub(x, f.px), f.vx);
        let reaches = ne(f.vx, sp(0.0)) & !lt(e, sp(0.0));
        if DRAG {
            // Eq. 4.55
            let q = sub(sp(1.0), mul(f.k, e));
            let reaches = reaches & !le(q, sp(0.0));
            let t = div(neg(lane_math::ln(F64x8(q)).0), f.k);
            return (reaches, add(add(f.py, mul(f.vinf, t)), mul(sub(f.vy, f.vinf), e)));
        }
        (reaches, sub(add(f.py, mul(f.vy, e)), mul(mul(f.half_g, e), e)))
    }

    /// `Flight::line_crossings` of vacuum flights against the line through `a` with normal
    /// `n`, in the lanes of `mask` (no roots elsewhere). `c2_g` is -0.5 g.
    #[allow(clippy::too_many_arguments)]
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn line_crossings(
        mask: M,
        f: &Fl,
        c2_g: f64,
        (ax, ay): (V, V),
        (nx, ny): (V, V),
        departing: M,
        t_min: V,
        t_max: V,
    ) -> Roots {
        let zero = sp(0.0);
        let c0 = sel(departing, zero, add(mul(nx, sub(f.px, ax)), mul(ny, sub(f.py, ay))));
        let nv = add(mul(nx, f.vx), mul(ny, f.vy));
        let nw = add(mul(nx, f.wx), mul(ny, f.wy)); // drift adds to the linear term
        let c1 = add(nv, nw);
        let c2 = mul(sp(c2_g), ny);
        let mut r = Roots { n: zero, r0: zero, r1: zero };
        // (a branch taken by no lane is skipped: a mask is the same for the whole group)
        // departing: f(t) = t (c1 + c2 t)
        let dep = mask & departing & ne(c2, zero);
        if dep != 0 {
            push(&mut r, dep, div(neg(c1), c2), t_min, t_max);
        }
        // quadratic_roots: the linear case, then both roots of the stable form
        let solve = mask & !departing;
        if solve == 0 {
            return r;
        }
        let linear = solve & eq(c2, zero) & ne(c1, zero);
        if linear != 0 {
            push(&mut r, linear, div(neg(c0), c1), t_min, t_max);
        }
        let disc = sub(mul(c1, c1), mul(mul(sp(4.0), c2), c0));
        let sq = sqrt(disc);
        let q = sel(ge(c1, zero), mul(sp(-0.5), add(c1, sq)), mul(sp(-0.5), sub(c1, sq)));
        let quad = solve & ne(c2, zero) & !lt(disc, zero) & !eq(q, zero);
        let (x, y) = (div(q, c2), div(c0, q));
        let swap = lt(y, x);
        push(&mut r, quad, sel(swap, y, x), t_min, t_max);
        push(&mut r, quad, sel(swap, x, y), t_min, t_max);
        r
    }

    /// `stokes_f` (flight.rs), f(t) = c0 + a t + b E(t), in the lanes of `mask`.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn stokes_f(f: &Fl, mask: M, (c0, ca, cb): (V, V, V), t: V) -> V {
        add(add(c0, mul(ca, t)), mul(cb, relax(f, mask, t)))
    }

    /// `stokes_horizon` (flight.rs): a time by which f has its final sign.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn stokes_horizon((c0, a, b): (V, V, V), k: V) -> V {
        let zero = sp(0.0);
        let falling = max(div(add(c0, div(max(b, zero), k)), neg(a)), zero);
        let rising = max(div(sub(neg(c0), div(min(b, zero), k)), a), zero);
        sel(lt(a, zero), falling, sel(gt(a, zero), rising, div(sp(40.0), k)))
    }

    /// `final_sign_at_horizon` (flight.rs): f at the horizon with the sign the bound gives it.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn final_sign_at_horizon(f: V, a: V) -> V {
        let zero = sp(0.0);
        sel(lt(a, zero), min(f, zero), sel(gt(a, zero), max(f, sp(f64::MIN_POSITIVE)), f))
    }

    /// The first root `quadratic_roots` (flight.rs) keeps in (0, ∞) ∩ [t_min, t_max], and
    /// the lanes that have one.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn first_quadratic_root(c2: V, c1: V, c0: V, t_min: V, t_max: V) -> (M, V) {
        let zero = sp(0.0);
        let kept = |t: V| gt(t, zero) & ge(t, t_min) & le(t, t_max);
        let linear = eq(c2, zero);
        let t_lin = div(neg(c0), c1);
        let lin_ok = linear & ne(c1, zero) & kept(t_lin);
        let disc = sub(mul(c1, c1), mul(mul(sp(4.0), c2), c0));
        let sq = sqrt(disc);
        let q = sel(ge(c1, zero), mul(sp(-0.5), add(c1, sq)), mul(sp(-0.5), sub(c1, sq)));
        let quad = !linear & !lt(disc, zero) & !eq(q, zero);
        let (x, y) = (div(q, c2), div(c0, q));
        let swap = lt(y, x);
        let (small, large) = (sel(swap, y, x), sel(swap, x, y));
        let (ok_small, ok_large) = (quad & kept(small), quad & kept(large));
        (lin_ok | ok_small | ok_large, sel(lin_ok, t_lin, sel(ok_small, small, large)))
    }

    /// `bracketed_newton` (flight.rs) in the lanes of `mask`: each lane takes the scalar
    /// function's steps and stops where it returns; the group runs as many steps as its
    /// slowest lane.
    #[allow(clippy::too_many_arguments)]
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn bracketed_newton(f: &Fl, mask: M, (c0, ca, cb): (V, V, V), mut lo: V, mut hi: V, f_lo: V, f_hi: V) -> V {
        let (zero, one, k) = (sp(0.0), sp(1.0), f.k);
        let lo_positive = gt(f_lo, zero);
        let (has, root) = first_quadratic_root(mul(mul(sp(-0.5), k), cb), add(ca, cb), c0, lo, hi);
        let mut t = sel(has, root, lo);
        let regula =
            sel(ne(f_hi, f_lo), sub(lo, div(mul(f_lo, sub(hi, lo)), sub(f_hi, f_lo))), mul(sp(0.5), add(lo, hi)));
        t = sel(gt(t, lo) & lt(t, hi), t, regula);
        t = sel(gt(t, lo) & lt(t, hi), t, mul(sp(0.5), add(lo, hi)));
        let (mut active, mut result) = (mask, t);
        for _ in 0..48 {
            if active == 0 {
                break;
            }
            // f and its derivatives share e^{-kt}: one expm1 per step
            let m = exp_m1(f, active, mul(neg(k), t));
            let ft = sub(add(c0, mul(ca, t)), div(mul(cb, m), k));
            let d = add(ca, mul(cb, add(one, m)));
            let on_root = active & eq(ft, zero);
            result = sel(on_root, t, result);
            active &= !on_root;
            let same_side = !(gt(ft, zero) ^ lo_positive);
            lo = sel(active & same_side, t, lo);
            hi = sel(active & !same_side, t, hi);
            let d2 = mul(mul(neg(k), cb), add(one, m));
            let den = sub(mul(mul(sp(2.0), d), d), mul(ft, d2));
            let halley = sel(ne(den, zero), sub(t, div(mul(mul(sp(2.0), ft), d), den)), sub(lo, one));
            let tol = mul(sp(f64::EPSILON * 4.0), max(abs(t), sp(f64::MIN_POSITIVE)));
            let inside = gt(halley, lo) & lt(halley, hi);
            let step = abs(sub(halley, t));
            let c = abs(add(div(mul(d2, d2), mul(mul(sp(4.0), d), d)), div(mul(k, d2), mul(sp(6.0), d))));
            let short = le(step, mul(sp(1e-3), abs(t))) & le(mul(mul(mul(c, step), step), step), tol);
            let halley_final = active & inside & (le(step, tol) | short);
            let next = mul(sp(0.5), add(lo, hi));
            let bisection_final = active & !inside & le(abs(sub(next, t)), tol);
            result = sel(halley_final, halley, sel(bisection_final, next, result));
            active &= !(halley_final | bisection_final);
            t = sel(inside, halley, next);
        }
        sel(active, t, result)
    }

    /// `Flight::line_crossings` of Stokes flights (the second half of the scalar function:
    /// at most two roots, each bracketed on a monotone interval), in the lanes of `mask`.
    #[allow(clippy::too_many_arguments)]
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn stokes_crossings(
        mask: M,
        f: &Fl,
        (ax, ay): (V, V),
        (nx, ny): (V, V),
        departing: M,
        t_min: V,
        t_max: V,
    ) -> Roots {
        let (zero, inf) = (sp(0.0), sp(f64::INFINITY));
        let c0 = sel(departing, zero, add(mul(nx, sub(f.px, ax)), mul(ny, sub(f.py, ay))));
        let nv = add(mul(nx, f.vx), mul(ny, f.vy));
        let nw = add(mul(nx, f.wx), mul(ny, f.wy)); // drift adds to the linear term
        let mut r = Roots { n: zero, r0: zero, r1: zero };
        let vinf_n = mul(f.vinf, ny);
        let (ca, cb) = (add(vinf_n, nw), sub(nv, vinf_n));
        let coef = (c0, ca, cb);
        // the extremum t* = ln(1 + x)/k, where x = n·v/(-a) > 0
        let x = sel(ne(ca, zero), div(add(nv, nw), neg(ca)), zero);
        let has_star = mask & gt(x, zero) & lt(abs(x), inf);
        let t_star = div(lane_math::ln_1p(F64x8(x)).0, f.k);
        let horizon = stokes_horizon(coef, f.k);
        let t_end = min(t_max, horizon);
        let active = mask & !gt(t_min, t_end);
        if active == 0 {
            return r;
        }
        let mut lo = max(t_min, zero);
        let from_zero = eq(lo, zero);
        let mut f_lo = sel(from_zero, c0, stokes_f(f, active & !from_zero, coef, lo));
        for (present, hi) in [(has_star, t_star), (!0, t_end)] {
            let go = active & present & !le(hi, lo);
            if go == 0 {
                continue;
            }
            let hi = min(hi, t_end);
            let f_hi = stokes_f(f, go, coef, hi);
            let f_hi = sel(eq(hi, horizon), final_sign_at_horizon(f_hi, ca), f_hi);
            let starts_on_line = eq(lo, zero) & (departing | eq(f_lo, zero));
            // lift-off below rounding: the flight is back on its surface at t*
            let lift_off = go & departing & gt(lo, zero) & le(f_lo, zero) & eq(r.n, zero);
            push(&mut r, lift_off, lo, t_min, t_max);
            let bracket = go & !lift_off & !starts_on_line & (gt(f_lo, zero) ^ gt(f_hi, zero));
            if bracket != 0 {
                let t = bracketed_newton(f, bracket, coef, lo, hi, f_lo, f_hi);
                push(&mut r, bracket, t, t_min, t_max);
            }
            lo = sel(go, hi, lo);
            f_lo = sel(go, f_hi, f_lo);
        }
        r
    }

    /// `contact` (kernel.rs) in every lane.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn contact(pitch_len: f64, f: &Fl, (vx, vy): (V, V), (ax, ay): (V, V), (bx, by): (V, V), (nx, ny): (V, V)) -> M {
        let (dx, dy) = (sub(f.px, ax), sub(f.py, ay));
        let c0 = add(mul(dx, nx), mul(dy, ny));
        let tol = mul(sp(64.0 * f64::EPSILON), max(max(sp(pitch_len), abs(f.px)), abs(f.py)));
        let away = ge(add(mul(vx, nx), mul(vy, ny)), sp(0.0));
        let near = !(gt(abs(c0), tol) | away);
        if near == 0 {
            return 0; // the usual case: no lane lies on the line
        }
        let (ex, ey) = (sub(bx, ax), sub(by, ay));
        let s = div(add(mul(dx, ex), mul(dy, ey)), add(mul(ex, ex), mul(ey, ey)));
        near & ge(s, sp(0.0)) & le(s, sp(1.0))
    }

    /// [`super::bounce_velocities`]: Eq. 4.47-4.49 with Eq. 4.9 and 4.14 as
    /// `Restitution::bounce` evaluates them, operation for operation.
    #[target_feature(enable = "avx512f")]
    pub fn bounce(r: &Restitution<f64>, v: &[[f64; LANES]; 2], n: &[[f64; LANES]; 2]) -> [[f64; LANES]; 2] {
        let (vx, vy, nx, ny) = (load(&v[0]), load(&v[1]), load(&n[0]), load(&n[1]));
        let (zero, one) = (sp(0.0), sp(1.0));
        let vn_s = add(mul(vx, nx), mul(vy, ny));
        let (vnx, vny) = (mul(vn_s, nx), mul(vn_s, ny));
        let (vtx, vty) = (sub(vx, vnx), sub(vy, vny));
        let vn_abs = abs(vn_s);
        let vt_abs = sqrt(add(mul(vtx, vtx), mul(vty, vty)));
        let k_elastic = sp(r.k_elastic);
        let k_norm = if r.plastic {
            let plastic = gt(vn_abs, sp(r.v_limit));
            sel(plastic, mul(k_elastic, sqrt(sqrt(div(sp(r.v_limit), vn_abs)))), k_elastic)
        } else {
            k_elastic
        };
        let slip = div(mul(mul(sp(r.tangential_factor * r.mu_friction), add(k_norm, one)), vn_abs), vt_abs);
        let mut k_tang = sel(gt(vt_abs, zero), sub(one, slip), zero);
        if r.clamp_tangential {
            k_tang = min(max(k_tang, zero), one);
        }
        [store(sub(mul(k_tang, vtx), mul(k_norm, vnx))), store(sub(mul(k_tang, vty), mul(k_norm, vny)))]
    }

    /// One round of `rng::pcg4d` with each of the four words a vector of sixteen keys.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn pcg4d(v: [__m512i; 4]) -> [__m512i; 4] {
        let (m, c) = (_mm512_set1_epi32(1_664_525), _mm512_set1_epi32(1_013_904_223));
        let [mut v0, mut v1, mut v2, mut v3] = v;
        v0 = _mm512_add_epi32(_mm512_mullo_epi32(v0, m), c);
        v1 = _mm512_add_epi32(_mm512_mullo_epi32(v1, m), c);
        v2 = _mm512_add_epi32(_mm512_mullo_epi32(v2, m), c);
        v3 = _mm512_add_epi32(_mm512_mullo_epi32(v3, m), c);
        for round in 0..2 {
            v0 = _mm512_add_epi32(v0, _mm512_mullo_epi32(v1, v3));
            v1 = _mm512_add_epi32(v1, _mm512_mullo_epi32(v2, v0));
            v2 = _mm512_add_epi32(v2, _mm512_mullo_epi32(v0, v1));
            v3 = _mm512_add_epi32(v3, _mm512_mullo_epi32(v1, v2));
            if round == 0 {
                v0 = _mm512_xor_si512(v0, _mm512_srli_epi32::<16>(v0));
                v1 = _mm512_xor_si512(v1, _mm512_srli_epi32::<16>(v1));
                v2 = _mm512_xor_si512(v2, _mm512_srli_epi32::<16>(v2));
                v3 = _mm512_xor_si512(v3, _mm512_srli_epi32::<16>(v3));
            }
        }
        [v0, v1, v2, v3]
    }

    /// The first word of `pcg4d(pcg4d([particle, bounce, draw, seed_word]))` for sixteen
    /// particles, as `rng::uniform01` hashes its key.
    #[target_feature(enable = "avx512f")]
    pub fn uniform_bits(seed_word: u32, particles: &[u32; 16], bounce: u32, draw: u32) -> [u32; 16] {
        // SAFETY: sixteen u32 are readable at `particles`.
        let ids = unsafe { _mm512_loadu_si512(particles.as_ptr().cast()) };
        let key = [
            ids,
            _mm512_set1_epi32(bounce as i32),
            _mm512_set1_epi32(draw as i32),
            _mm512_set1_epi32(seed_word as i32),
        ];
        let h = pcg4d(pcg4d(key));
        let mut out = [0u32; 16];
        // SAFETY: sixteen u32 are writable at `out`.
        unsafe { _mm512_storeu_si512(out.as_mut_ptr().cast(), h[0]) };
        out
    }

    /// `Real::ksin_cos` (`lane_math::sin_cos`) in every lane.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn sin_cos(x: V) -> (V, V) {
        let (s, c) = lane_math::sin_cos(F64x8(x));
        (s.0, c.0)
    }

    /// `lane_math`'s `exp_m1`, sin and cos, `atan2(y, x)`, `ln` and `ln_1p` of eight lanes
    /// (for the tests).
    #[cfg(test)]
    #[target_feature(enable = "avx512f")]
    pub fn math_on_lanes(x: [f64; LANES], y: [f64; LANES]) -> [[f64; LANES]; 6] {
        let (x, y) = (F64x8(load(&x)), F64x8(load(&y)));
        let (s, c) = lane_math::sin_cos(x);
        [lane_math::exp_m1(x), s, c, lane_math::atan2(y, x), lane_math::ln(x), lane_math::ln_1p(x)].map(|v| store(v.0))
    }

    /// [`super::randomise_launches`]: `kernel::randomise_launch_drawn` with the launch factors
    /// applied and no launch spread, operation for operation.
    #[allow(clippy::needless_range_loop)] // lane l of five arrays at once
    #[target_feature(enable = "avx512f")]
    pub fn randomise(
        d: &KDesign<f64>,
        ph: &KPhysics<f64>,
        parts: &mut [KParticle<f64>],
        idx: &[u32],
        angle: &[f64],
        speed: &[f64],
    ) {
        let mut a = [[0.0; LANES]; 5];
        for l in 0..LANES {
            let j = if l < idx.len() { l } else { 0 };
            let p = &parts[idx[j] as usize];
            (a[0][l], a[1][l], a[2][l]) = (p.vel[0], p.vel[1], p.surface as f64);
            (a[3][l], a[4][l]) = (angle[j], speed[j]);
        }
        let (vx, vy, surface) = (load(&a[0]), load(&a[1]), load(&a[2]));
        let (one_less_band, two_band) = (sp(1.0 - ph.band), sp(2.0 * ph.band));
        let fa = add(one_less_band, mul(two_band, load(&a[3])));
        let fs = add(one_less_band, mul(two_band, load(&a[4])));
        let speed = mul(sqrt(add(mul(vx, vx), mul(vy, vy))), fs);
        // one atan2 and one sincos for both kinds of launch, as the scalar function
        let first = eq(surface, sp(SURFACE_NONE as f64));
        let (ramp, catch) = (eq(surface, sp(SURFACE_RAMP as f64)), eq(surface, sp(SURFACE_CATCH as f64)));
        let normal = |i: usize| sel(ramp, sp(d.n_ramp[i]), sel(catch, sp(d.n_catch[i]), sp(d.n_base[i])));
        let (nx, ny) = (normal(0), normal(1));
        let (tx, ty) = (ny, neg(nx));
        let y = sel(first, vy, add(mul(vx, nx), mul(vy, ny)));
        let x = sel(first, vx, add(mul(vx, tx), mul(vy, ty)));
        let ang = lane_math::atan2(F64x8(y), F64x8(x)).0;
        // the first launch's angle kept in [0, 2π), a rebound's inside (0, π)
        let global = mul(sel(lt(ang, sp(0.0)), add(ang, sp(2.0 * std::f64::consts::PI)), ang), fa);
        let eps = 1e-6;
        let rebound = min(max(mul(ang, fa), sp(eps)), sp(std::f64::consts::PI - eps));
        let (s, c) = sin_cos(sel(first, global, rebound));
        let out_x = sel(first, mul(speed, c), mul(speed, add(mul(c, tx), mul(s, nx))));
        let out_y = sel(first, mul(speed, s), mul(speed, add(mul(c, ty), mul(s, ny))));
        let (out_x, out_y) = (store(out_x), store(out_y));
        for (l, &i) in idx.iter().enumerate() {
            parts[i as usize].vel = [out_x[l], out_y[l]];
        }
    }

    /// A position's index (`to_index`): clamped to ±1e9, kept as a whole f64.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn to_index(x: V) -> V {
        min(max(x, sp(-1e9)), sp(1e9))
    }

    /// `Flight::line_crossings` in the lanes of `mask`, for vacuum or Stokes flights.
    #[allow(clippy::too_many_arguments)]
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn crossings<const DRAG: bool>(
        mask: M,
        f: &Fl,
        c2_g: f64,
        a: (V, V),
        n: (V, V),
        departing: M,
        t_min: V,
        t_max: V,
    ) -> Roots {
        if DRAG {
            stokes_crossings(mask, f, a, n, departing, t_min, t_max)
        } else {
            line_crossings(mask, f, c2_g, a, n, departing, t_min, t_max)
        }
    }

    /// [`super::first_hits`] on eight AVX-512 lanes: `kernel::first_hit_in` step by step;
    /// whole numbers (teeth, codes) ride as f64. `DRAG`: every lane's grain has Stokes drag
    /// (k_drag > 0), else none has. `PIECES`: the lanes' flights are pieces, with a time limit
    /// and perhaps a drift; else flights in one piece, whose code is the search's without
    /// either (the lunar batches ran 7 % slower through the pieces' selects).
    #[target_feature(enable = "avx512f")]
    pub(super) fn first_hits<const DRAG: bool, const PIECES: bool>(
        d: &KDesign<f64>,
        ph: &KPhysics<f64>,
        lanes: &LaneFlights,
        bounce: u32,
    ) -> [Hit<f64>; LANES] {
        let a = &lanes.0;
        let k = if DRAG { load(&a[LaneFlights::K]) } else { sp(0.0) };
        let (zero, inf) = (sp(0.0), sp(f64::INFINITY));
        // how long each lane's search looks (`first_hit_in`'s t_limit: a piece's length,
        // infinite for a flight in one piece), and each lane's drift
        let limit = if PIECES { load(&a[LaneFlights::LIMIT]) } else { inf };
        let (wx, wy) =
            if PIECES { (load(&a[LaneFlights::DRIFT]), load(&a[LaneFlights::DRIFT + 1])) } else { (zero, zero) };
        let drifting = if PIECES { ne(wx, zero) | ne(wy, zero) } else { 0 };
        let (px, py) = (load(&a[LaneFlights::POS]), load(&a[LaneFlights::POS + 1]));
        let (vx, vy) = (load(&a[LaneFlights::VEL]), load(&a[LaneFlights::VEL + 1]));
        // the terminal velocity as `Flight` computes it, -g / k
        let vinf = if DRAG { div(neg(sp(ph.g)), k) } else { sp(0.0) };
        let f = Fl { px, py, vx, vy, half_g: sp(0.5 * ph.g), k, vinf, wx, wy, drifting };
        let (surface, kf) = (load(&a[LaneFlights::SURFACE]), load(&a[LaneFlights::TOOTH]));
        let c2_g = -0.5 * ph.g;
        // `rel_vel` of the scalar search: the velocity plus the drift
        let rel_vel = (add(f.vx, wx), add(f.vy, wy));

        // The base line through every p1; its crossing bounds the flight.
        let n_base = (sp(d.n_base[0]), sp(d.n_base[1]));
        let departing_base = eq(surface, sp(SURFACE_BASE as f64));
        let mut roots = crossings::<DRAG>(!0, &f, c2_g, (zero, zero), n_base, departing_base, zero, limit);
        let s0 = mul(neg(kf), sp(d.pitch_len));
        let s1 = add(s0, sp(d.base_length));
        let (tb0, tb1) = (sp(d.t_base[0]), sp(d.t_base[1]));
        let ends = ((mul(s0, tb0), mul(s0, tb1)), (mul(s1, tb0), mul(s1, tb1)));
        let over = !departing_base & contact(d.pitch_len, &f, rel_vel, ends.0, ends.1, n_base);
        roots.n = sel(over, sp(1.0), roots.n);
        roots.r0 = sel(over, zero, roots.r0);
        // every hop counts, so the first root is the base crossing
        let has = ge(roots.n, sp(1.0));
        let t = roots.r0;
        let (qx, qy) = pos_at::<DRAG>(&f, has, t);
        let s = add(mul(qx, tb0), mul(qy, tb1));
        let mut found = has & ge(s, s0) & le(s, add(sp(d.base_length), s0));
        let horizon = if PIECES { min(sel(has, t, inf), limit) } else { sel(has, t, inf) };
        let teeth_last = sp((d.teeth - 1) as f64);
        let j = min(max(add(to_index(floor(div(s, sp(d.pitch_len)))), kf), zero), teeth_last);
        let mut best_t = sel(found, t, inf);
        let (mut best_x, mut best_y) = (sel(found, qx, zero), sel(found, qy, zero));
        let mut best_tooth = sel(found, j, zero);
        let mut best_surface = sel(found, sp(SURFACE_BASE as f64), zero);

        // The teeth whose x-extent overlaps the flight's x-range before the horizon.
        let finite = lt(abs(horizon), inf);
        let x_end = sel(finite, pos_at::<DRAG>(&f, finite, horizon).0, sel(ge(f.vx, zero), inf, sp(f64::NEG_INFINITY)));
        // with drift x(t) need not be monotone: |x(t) - x0| <= (|vx| + |wx|) t bounds the
        // range instead
        let (x_end, x_start) = if drifting != 0 {
            let reach = mul(add(abs(f.vx), abs(wx)), horizon);
            (sel(drifting, add(f.px, reach), x_end), sel(drifting, sub(f.px, reach), f.px))
        } else {
            (x_end, f.px)
        };
        let forward = ge(x_end, x_start);
        let (xmin, xmax) = (sel(forward, x_start, x_end), sel(forward, x_end, x_start));
        let lo = add(to_index(ceil(div(sub(xmin, sp(d.ext_max)), sp(d.pitch[0])))), kf);
        let hi = add(to_index(floor(div(sub(xmax, sp(d.ext_min)), sp(d.pitch[0])))), kf);
        let j_lo = min(max(lo, zero), teeth_last);
        let j_hi = min(max(hi, zero), teeth_last);
        let none = gt(lo, teeth_last) | lt(hi, zero);
        let count = sel(none, zero, max(add(sub(j_hi, j_lo), sp(1.0)), zero));
        let x_far = sel(found, best_x, x_end);
        let steps = store(count).iter().fold(0.0f64, |m, &c| m.max(c)) as usize;
        let top_rel = sp(d.p2[1].max(d.p4[1]).max(0.0));
        let margin = sp(64.0 * f64::EPSILON * d.pitch_len);
        for step in 0..steps {
            // flies_over: a lane whose flight stays above this tooth's peak skips it
            let stepf = sp(step as f64);
            let j = add(j_lo, stepf);
            let dj = sub(j, kf);
            let base = mul(dj, sp(d.pitch[0]));
            let ahead = ge(x_far, f.px);
            let (lo, hi) = (sel(ahead, f.px, x_far), sel(ahead, x_far, f.px));
            let xa = max(add(base, sp(d.ext_min)), lo);
            let xb = min(add(base, sp(d.ext_max)), hi);
            let top = add(mul(dj, sp(d.pitch[1])), top_rel);
            let in_range = lt(stepf, count);
            let reached = in_range & !gt(xa, xb);
            let (sa, ya) = y_at_x::<DRAG>(&f, reached, xa);
            let (sb, yb) = y_at_x::<DRAG>(&f, reached, xb);
            // (a drifting lane's x(t) is not monotone: it searches every tooth of its range)
            let flies_over = (gt(xa, xb) | (sa & sb & gt(ya, top) & gt(yb, top))) & !drifting;
            let live = in_range & !flies_over;
            if live == 0 {
                continue;
            }
            for surface_kind in [SURFACE_RAMP, SURFACE_CATCH] {
                let first_catch = surface_kind == SURFACE_CATCH && bounce == 0;
                let on = if first_catch { live & !eq(j, zero) } else { live };
                if on == 0 {
                    continue;
                }
                let (from, to, normal) =
                    if surface_kind == SURFACE_RAMP { ([0.0, 0.0], d.p2, d.n_ramp) } else { (d.p2, d.p4, d.n_catch) };
                let (ox, oy) = (mul(dj, sp(d.pitch[0])), mul(dj, sp(d.pitch[1])));
                let (ax, ay) = (add(ox, sp(from[0])), add(oy, sp(from[1])));
                let (bx, by) = (add(ox, sp(to[0])), add(oy, sp(to[1])));
                let n = (sp(normal[0]), sp(normal[1]));
                let departing = eq(surface, sp(surface_kind as f64)) & eq(dj, zero);
                let t_max = sel(found, best_t, horizon);
                let (xa, xb) = (sub(min(ax, bx), margin), add(max(ax, bx), margin));
                let backward = lt(f.vx, zero);
                let x_in = sel(backward, min(xb, f.px), max(xa, f.px));
                let x_out = sel(backward, xa, xb);
                let moving = gt(f.vx, zero) | lt(f.vx, zero);
                let inside = ge(f.px, xa) & le(f.px, xb);
                let t_lo = sel(moving, time_at_x::<DRAG>(&f, on & moving, x_in), sel(inside, zero, inf));
                // a drifting lane searches the whole time (`first_hit_in`: no x-window)
                let t_lo = if drifting != 0 { sel(drifting, zero, t_lo) } else { t_lo };
                let search_lo = on & !gt(t_lo, t_max);
                let t_hi = sel(moving, time_at_x::<DRAG>(&f, search_lo & moving, x_out), inf);
                let t_hi = if drifting != 0 { sel(drifting, inf, t_hi) } else { t_hi };
                let search = search_lo;
                let mut roots = crossings::<DRAG>(search, &f, c2_g, (ax, ay), n, departing, t_lo, min(t_max, t_hi));
                let over = on & !departing & contact(d.pitch_len, &f, rel_vel, (ax, ay), (bx, by), n);
                roots.n = sel(over, sp(1.0), roots.n);
                roots.r0 = sel(over, zero, roots.r0);
                // the first root on the segment itself (0 <= s <= 1) is this segment's hit
                let (ex, ey) = (sub(bx, ax), sub(by, ay));
                let ee = add(mul(ex, ex), mul(ey, ey));
                let has0 = on & ge(roots.n, sp(1.0));
                let q0 = pos_at::<DRAG>(&f, has0, roots.r0);
                let s0 = div(add(mul(sub(q0.0, ax), ex), mul(sub(q0.1, ay), ey)), ee);
                let ok0 = has0 & !(lt(s0, zero) | gt(s0, sp(1.0)));
                let second = on & ge(roots.n, sp(2.0)) & !ok0;
                let (q1, ok1) = if second != 0 {
                    let q1 = pos_at::<DRAG>(&f, second, roots.r1);
                    let s1 = div(add(mul(sub(q1.0, ax), ex), mul(sub(q1.1, ay), ey)), ee);
                    (q1, second & !(lt(s1, zero) | gt(s1, sp(1.0))))
                } else {
                    (q0, 0)
                };
                let t = sel(ok0, roots.r0, roots.r1);
                let better = (ok0 | ok1) & lt(t, best_t);
                found |= better;
                best_t = sel(better, t, best_t);
                best_x = sel(better, sel(ok0, q0.0, q1.0), best_x);
                best_y = sel(better, sel(ok0, q0.1, q1.1), best_y);
                best_tooth = sel(better, j, best_tooth);
                best_surface = sel(better, sp(surface_kind as f64), best_surface);
            }
        }
        let (t, x, y, tooth, surface) =
            (store(best_t), store(best_x), store(best_y), store(best_tooth), store(best_surface));
        std::array::from_fn(|l| Hit {
            found: found & (1 << l) != 0,
            t: t[l],
            pos: [x[l], y[l]],
            tooth: tooth[l] as i32,
            surface: surface[l] as u32,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::cpu::{kernel_design, kernel_physics};
    use crate::engine::kernel::{first_hit, fly_particle, init_particle, randomise_launch, STATE_FLYING};
    use crate::engine::Context;
    use crate::model::effects::{
        Effects, FillSurfaceLoss, ImpactScatter, LaunchSpread, Polydisperse, SizeForm, TiltForm,
    };
    use crate::model::sampling::random_valid_designs;
    use crate::model::scenario::LaunchPoints;
    use crate::model::{prepare, Scenario};

    type HitBits = (bool, u64, [u64; 2], i32, u32);

    fn bits(h: &Hit<f64>) -> HitBits {
        (h.found, h.t.to_bits(), [h.pos[0].to_bits(), h.pos[1].to_bits()], h.tooth, h.surface)
    }

    /// The scenarios the lane tests run: `base` at slopes from 0 to 40°, plain and with the
    /// effects that change launches, bounces and (polydisperse) each grain's drag, on Halton
    /// and random launch points.
    fn cases(base: Scenario, particles: u32) -> Vec<Scenario> {
        let mut cases = Vec::new();
        for alpha in [0.0, 20.0, 35.0, 40.0] {
            let mut s = base.clone();
            s.sim.particles = particles;
            s.environment.alpha_deg = alpha;
            cases.push(s.clone());
            s.effects.impact_scatter = Some(ImpactScatter { sigma_deg: 6.0, form: TiltForm::default() });
            s.effects.launch_spread = Some(LaunchSpread { speed_spread: 0.3, angle_sigma_deg: 8.0 });
            s.effects.polydisperse = Some(Polydisperse { sigma_ln: 0.4, form: SizeForm::default() });
            s.sim.launch_points = LaunchPoints::Random;
            cases.push(s.clone());
            if alpha == 20.0 {
                // the fill-surface loss alone: slower first launches that the lanes'
                // randomisation still takes (no launch spread)
                s.effects = Effects::default();
                s.effects.fill_surface_loss = Some(FillSurfaceLoss { speed_loss: 0.4, decay_depth_m: 2e-3 });
                cases.push(s);
            }
        }
        cases
    }

    /// Every lane finds the hit the scalar search finds, to the bit, at every bounce of
    /// every particle: random valid lunar designs (vacuum flights) in [`cases`], in groups of
    /// every size from one to eight.
    #[test]
    fn each_lane_finds_the_scalar_hit_to_the_bit() {
        let Some((compared, on_teeth)) = compare_lane_hits(&cases(Scenario::lunar(), 120)) else {
            return;
        };
        assert!(compared > 20_000 && on_teeth > compared / 3, "{compared} flights compared, {on_teeth} on teeth");
    }

    /// The same for Earth's designs: flights with Stokes drag, whose root search (Halley
    /// steps, one `expm1` each) the lanes run to the scalar search's bits.
    #[test]
    fn each_lane_finds_the_scalar_hit_to_the_bit_with_drag() {
        let Some((compared, on_teeth)) = compare_lane_hits(&cases(Scenario::earth(), 120)) else {
            return;
        };
        assert!(compared > 10_000 && on_teeth > compared / 3, "{compared} flights compared, {on_teeth} on teeth");
    }

    /// Heavily damped grains (lunar gravity with k_drag 8 1/s and polydisperse sizes of sd 0.5
    /// in ln d: a grain's k up to ~160 1/s) fall for long after e^{-kt} has underflowed; their
    /// crossings just before the horizon are the scalar search's on the lanes too.
    #[test]
    fn each_lane_finds_the_scalar_hit_for_heavily_damped_grains() {
        let mut damped = Vec::new();
        for alpha in [0.0, 20.0, 35.0] {
            let mut s = Scenario::lunar();
            s.sim.particles = 120;
            s.environment.alpha_deg = alpha;
            s.environment.k_drag = Some(8.0);
            s.effects.polydisperse = Some(Polydisperse { sigma_ln: 0.5, form: SizeForm::default() });
            damped.push(s);
        }
        let Some((compared, _)) = compare_lane_hits(&damped) else {
            return;
        };
        assert!(compared > 5_000, "{compared} flights compared");
    }

    /// Flights in pieces: a sled that returns while grains fly (down the slope or along the
    /// launch, at once or after a delay; lunar and Earth) and quadratic drag (alone, with
    /// polydisperse sizes, and with a returning sled). Every particle's hit, the piece it lies
    /// in and that piece's start are the scalar `first_hit_piecewise`'s to the bit, in lane
    /// groups of every size, and the flights compared include ones that end after their first
    /// piece and ones that end in a drifting piece.
    #[test]
    fn each_lane_finds_the_scalar_piecewise_hit_to_the_bit() {
        use crate::engine::kernel::first_hit_piecewise;
        use crate::model::effects::{MotionDirection, QuadraticDrag, SledMotion};
        if !available() {
            eprintln!("skipped: this CPU lacks AVX-512F, so the engine does not use the lanes");
            return;
        }
        let sled = |delay_s, return_speed_m_s, direction| SledMotion { delay_s, return_speed_m_s, direction };
        let drag = QuadraticDrag { diameter_m: 300e-6, density_kg_m3: 2500.0 };
        let mut cases = Vec::new();
        for (c, base) in [Scenario::lunar(), Scenario::earth()].into_iter().enumerate() {
            for (m, motion) in [
                sled(0.0, 0.3, MotionDirection::Slope),
                sled(0.05, 0.5, MotionDirection::Slope),
                sled(0.02, 0.06, MotionDirection::Launch),
            ]
            .into_iter()
            .enumerate()
            {
                let mut s = base.clone();
                s.sim.particles = 100;
                s.environment.alpha_deg = [0.0, 20.0, 35.0][(c + m) % 3];
                s.effects.sled_motion = Some(motion);
                cases.push(s);
            }
        }
        for alpha in [0.0, 30.0] {
            let mut s = Scenario::earth();
            s.sim.particles = 100;
            s.environment.alpha_deg = alpha;
            s.effects.quadratic_drag = Some(drag);
            cases.push(s.clone());
            s.effects.polydisperse = Some(Polydisperse { sigma_ln: 0.4, form: SizeForm::default() });
            cases.push(s.clone());
            s.effects.polydisperse = None;
            s.effects.sled_motion = Some(sled(0.0, 0.25, MotionDirection::Slope));
            cases.push(s);
        }
        let (mut compared, mut drifting, mut pieces) = (0usize, 0usize, 0usize);
        each_bounce(&cases, 3, 70, |c, d, ph, parts, flying, bounce| {
            assert!(applies_piecewise(ph) && !applies(ph), "case {c} flies in pieces");
            // all at once, then in groups of 1, 2, ..., 7 particles
            let mut lane_hits = first_hits_piecewise(d, ph, parts, flying, bounce);
            let mut size = 1 + (bounce as usize % (LANES - 1));
            let mut rest = flying;
            while !rest.is_empty() {
                let (group, tail) = rest.split_at(size.min(rest.len()));
                lane_hits.extend(first_hits_piecewise(d, ph, parts, group, bounce));
                rest = tail;
                size = size % (LANES - 1) + 1;
            }
            for (n, (h, fl, start)) in lane_hits.iter().enumerate() {
                let i = flying[n % flying.len()];
                let (sh, sfl, sstart) = first_hit_piecewise(d, ph, &parts[i as usize], bounce);
                let flight_bits = |f: &Flight<f64>| [f.p0, f.v0, f.drift, [f.k, f.g]].map(|v| v.map(f64::to_bits));
                assert_eq!(
                    (bits(h), flight_bits(fl), start.to_bits()),
                    (bits(&sh), flight_bits(&sfl), sstart.to_bits()),
                    "case {c}, bounce {bounce}, particle {i}"
                );
                compared += 1;
                pieces += usize::from(*start > 0.0);
                drifting += usize::from(fl.drift != [0.0; 2]);
            }
        });
        assert!(
            compared > 20_000 && drifting > compared / 50 && pieces > compared / 20,
            "{compared} flights compared, {drifting} ending in a drifting piece, {pieces} after their first piece"
        );
    }

    /// Every bounce of the particles of `designs` random valid designs per case of `cases`
    /// (design seeds from `seed`), as the scalar kernel's loop flies them: `visit` gets the
    /// case's index, the design, the physics, the particles with this bounce's launches
    /// randomised, the flying ones and the bounce, before they fly.
    fn each_bounce(
        cases: &[Scenario],
        designs: usize,
        seed: u64,
        mut visit: impl FnMut(usize, &KDesign<f64>, &KPhysics<f64>, &[KParticle<f64>], &[u32], u32),
    ) {
        for (c, s) in cases.iter().enumerate() {
            let ctx = Context::new(s);
            let ph = kernel_physics::<f64>(&ctx);
            for design in random_valid_designs(s, designs, seed + c as u64) {
                let prep = prepare(s, &design).unwrap();
                let d = kernel_design::<f64>(&prep);
                let mut parts: Vec<KParticle<f64>> =
                    prep.launches.iter().enumerate().map(|(i, l)| init_particle(&d, &ph, *l, i as u32)).collect();
                for bounce in 0..ctx.max_bounces {
                    for (i, p) in parts.iter_mut().enumerate().filter(|(_, p)| p.state == STATE_FLYING) {
                        randomise_launch(&d, &ph, p, i as u32, bounce);
                    }
                    let flying: Vec<u32> =
                        (0..parts.len() as u32).filter(|&i| parts[i as usize].state == STATE_FLYING).collect();
                    if flying.is_empty() {
                        break;
                    }
                    visit(c, &d, &ph, &parts, &flying, bounce);
                    for &i in &flying {
                        fly_particle(&d, &ph, &mut parts[i as usize], i, bounce);
                    }
                }
            }
        }
    }

    /// Lane hits against scalar hits over `cases`: how many flights were compared, and how
    /// many of them end on a tooth (not the base line or lost); None on a CPU without the lanes.
    fn compare_lane_hits(cases: &[Scenario]) -> Option<(usize, usize)> {
        if !available() {
            eprintln!("skipped: this CPU lacks AVX-512F, so the engine does not use the lanes");
            return None;
        }
        let (mut compared, mut on_teeth) = (0usize, 0usize);
        each_bounce(cases, 5, 7, |c, d, ph, parts, flying, bounce| {
            assert!(applies(ph), "case {c} is a one-piece flight of the text's physics");
            // groups of 1, 2, ..., 8 particles, then again
            let mut rest = flying;
            let mut size = 1 + (bounce as usize % LANES);
            while !rest.is_empty() {
                let (group, tail) = rest.split_at(size.min(rest.len()));
                let hits = first_hits(d, ph, parts, group, bounce);
                for (h, &i) in hits.iter().zip(group) {
                    let scalar = first_hit(d, ph, &parts[i as usize], bounce);
                    assert_eq!(bits(h), bits(&scalar), "case {c}, bounce {bounce}, particle {i}");
                    compared += 1;
                    on_teeth += usize::from(scalar.found && scalar.surface != SURFACE_BASE);
                }
                rest = tail;
                size = size % LANES + 1;
            }
        });
        Some((compared, on_teeth))
    }

    /// The launch randomisation on lanes gives `randomise_launch_drawn`'s velocities to the
    /// bit, for first launches and rebounds off every surface: the particles of random valid
    /// lunar and Earth designs at every bounce, with the same draws.
    #[test]
    fn lane_launches_are_the_scalar_launches_to_the_bit() {
        use crate::engine::kernel::randomise_launch_drawn;
        use crate::model::rng::{uniform01, DRAW_ANGLE, DRAW_SPEED};
        if !available() {
            eprintln!("skipped: this CPU lacks AVX-512F, so the engine does not use the lanes");
            return;
        }
        let mut compared = [0usize; 4]; // by the surface left: none (first launch), base, ramp, catch
        for base in [Scenario::lunar(), Scenario::earth()] {
            for (c, s) in cases(base, 80).iter().filter(|s| s.effects.launch_spread.is_none()).enumerate() {
                let ctx = Context::new(s);
                let ph = kernel_physics::<f64>(&ctx);
                assert!(randomises(&ph));
                for design in random_valid_designs(s, 3, 50 + c as u64) {
                    let prep = prepare(s, &design).unwrap();
                    let d = kernel_design::<f64>(&prep);
                    let mut parts: Vec<KParticle<f64>> =
                        prep.launches.iter().enumerate().map(|(i, l)| init_particle(&d, &ph, *l, i as u32)).collect();
                    for bounce in 0..ctx.max_bounces {
                        let flying: Vec<u32> =
                            (0..parts.len() as u32).filter(|&i| parts[i as usize].state == STATE_FLYING).collect();
                        if flying.is_empty() {
                            break;
                        }
                        let mut lanes = parts.clone();
                        for group in flying.chunks(LANES) {
                            let draw = |k| group.iter().map(|&i| uniform01(ph.seed, i, bounce, k)).collect::<Vec<_>>();
                            randomise_launches(&d, &ph, &mut lanes, group, &draw(DRAW_ANGLE), &draw(DRAW_SPEED));
                        }
                        for &i in &flying {
                            let p = &mut parts[i as usize];
                            compared[p.surface as usize] += 1;
                            randomise_launch_drawn(&d, &ph, p, i, bounce, None);
                            let b = |v: [f64; 2]| [v[0].to_bits(), v[1].to_bits()];
                            assert_eq!(b(lanes[i as usize].vel), b(p.vel), "case {c}, bounce {bounce}, particle {i}");
                            fly_particle(&d, &ph, p, i, bounce);
                        }
                    }
                }
            }
        }
        assert!(compared.iter().all(|&n| n > 500), "launches compared by surface left: {compared:?}");
    }

    /// The restitution law on lanes gives the scalar law's bits, over impacts of every
    /// speed (both sides of the plastic limit) and angle, in both modes' laws.
    #[test]
    fn lane_bounces_are_the_scalar_bounces_to_the_bit() {
        use crate::model::scenario::{Material, PhysicsMode};
        use rand::{Rng, SeedableRng};
        if !available() {
            eprintln!("skipped: this CPU lacks AVX-512F, so the engine does not use the lanes");
            return;
        }
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for mode in [PhysicsMode::Physical, PhysicsMode::Listing] {
            let r = Restitution::new(mode, &crate::model::Collision::thesis(0.8, 0.3), &Material::lunar_regolith());
            for _ in 0..2000 {
                let (mut v, mut n) = ([[0.0; LANES]; 2], [[0.0; LANES]; 2]);
                for l in 0..LANES {
                    let speed = 10f64.powf(rng.random_range(-4.0..1.0));
                    let (a, b): (f64, f64) = (rng.random_range(0.0..6.3), rng.random_range(0.0..6.3));
                    (v[0][l], v[1][l]) = (speed * a.cos(), speed * a.sin());
                    (n[0][l], n[1][l]) = (b.cos(), b.sin());
                }
                // a grazing, a head-on and a resting impact among them
                (v[0][0], v[1][0], n[0][0], n[1][0]) = (1.0, 0.0, 0.0, 1.0);
                (v[0][1], v[1][1], n[0][1], n[1][1]) = (0.0, -1.0, 0.0, 1.0);
                (v[0][2], v[1][2]) = (0.0, 0.0);
                let out = bounce_velocities(&r, &v, &n);
                for l in 0..LANES {
                    let s = r.bounce([v[0][l], v[1][l]], [n[0][l], n[1][l]]);
                    assert_eq!(
                        [out[0][l].to_bits(), out[1][l].to_bits()],
                        [s[0].to_bits(), s[1].to_bits()],
                        "{mode:?}"
                    );
                }
            }
        }
    }

    /// `lane_math`'s functions on eight lanes give the scalar functions' bits, by
    /// construction (one generic code); held here over a million arguments and the special
    /// values, in case a lane operation of [`avx512::F64x8`] ever differs from f64's.
    #[test]
    fn lane_math_on_eight_lanes_is_the_scalar_math_to_the_bit() {
        use crate::lane_math::{atan2, exp_m1, ln, ln_1p, sin_cos};
        if !available() {
            eprintln!("skipped: this CPU lacks AVX-512F, so the engine does not use the lanes");
            return;
        }
        let mut xs: Vec<f64> =
            (0..1_000_000).map(|i| -12.0 + 24.0 * ((i as f64 * 0.618_033_988_749_895) % 1.0)).collect();
        xs.extend(
            (0..200_000).map(|i| (if i % 2 == 0 { 1.0 } else { -1.0 }) * 10f64.powf(-310.0 + 620.0 * i as f64 / 2e5)),
        );
        xs.extend([0.0, -0.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 709.78, 709.79, -40.0, 524_288.0, 524_289.0]);
        xs.extend([f64::MIN_POSITIVE, 5e-324, -5e-324, 1.0, -1.0, std::f64::consts::FRAC_PI_2, std::f64::consts::PI]);
        let b = |x: f64| x.to_bits();
        for (c, chunk) in xs.chunks(8).enumerate() {
            let mut a = [chunk[0]; 8];
            a[..chunk.len()].copy_from_slice(chunk);
            // the y of atan2: another argument of the list, with its special values
            let ys: [f64; 8] = std::array::from_fn(|l| xs[(c * 8 + l) * 7919 % xs.len()]);
            // SAFETY: the CPU has AVX-512F (checked above)
            let [e, s, co, at, lg, lg1p] = unsafe { avx512::math_on_lanes(a, ys) };
            for l in 0..8 {
                let x = a[l];
                let (ws, wc) = sin_cos(x);
                assert_eq!(b(e[l]), b(exp_m1(x)), "exp_m1({x:e})");
                assert_eq!((b(s[l]), b(co[l])), (b(ws), b(wc)), "sin_cos({x:e})");
                assert_eq!(b(at[l]), b(atan2(ys[l], x)), "atan2({:e}, {x:e})", ys[l]);
                assert_eq!(b(lg[l]), b(ln(x)), "ln({x:e})");
                assert_eq!(b(lg1p[l]), b(ln_1p(x)), "ln_1p({x:e})");
            }
        }
    }

    /// The generator on sixteen lanes draws `uniform01`'s numbers.
    #[test]
    fn lane_uniforms_are_uniform01() {
        use crate::model::rng::{seed_word, uniform01};
        if !available() {
            eprintln!("skipped: this CPU lacks AVX-512F, so the engine does not use the lanes");
            return;
        }
        for seed in [0u64, 1, 0xdead_beef_1234] {
            let s = seed_word(seed);
            for first in [0u32, 5, 1000, u32::MAX - 20] {
                let ids: Vec<u32> = (0..16).map(|k| first.wrapping_add(3 * k)).collect();
                for (bounce, draw) in [(0, 0), (7, 1), (99, 6)] {
                    for n in [1, 9, 16] {
                        let u = uniforms(s, &ids[..n], bounce, draw);
                        for (k, id) in ids[..n].iter().enumerate() {
                            assert_eq!(u[k].to_bits(), uniform01(s, *id, bounce, draw).to_bits());
                        }
                    }
                }
            }
        }
    }

    /// The cpu engine with its lanes leaves every particle as the scalar kernel's bounce
    /// loop does (randomise every launch, fly, land, one particle at a time): lunar designs
    /// with and without launch randomisation, Earth's (drag), with and without the effects,
    /// and with flights in pieces (a returning sled; quadratic drag on Earth).
    #[test]
    fn the_engine_on_lanes_leaves_every_particle_as_the_scalar_loop() {
        use crate::model::effects::{QuadraticDrag, SledMotion};
        if !available() {
            eprintln!("skipped: this CPU lacks AVX-512F, so the engine does not use the lanes");
            return;
        }
        let mut cases = Vec::new();
        for (base, randomise) in [(Scenario::lunar(), true), (Scenario::lunar(), false), (Scenario::earth(), true)] {
            let mut s = base;
            s.sim.particles = 150;
            s.sim.randomise = randomise;
            cases.push(s.clone());
            s.effects.impact_scatter = Some(ImpactScatter { sigma_deg: 4.0, form: TiltForm::default() });
            s.effects.launch_spread = Some(LaunchSpread { speed_spread: 0.2, angle_sigma_deg: 5.0 });
            s.effects.polydisperse = Some(Polydisperse { sigma_ln: 0.3, form: SizeForm::default() });
            cases.push(s.clone());
            // flights in pieces: the sled returning while grains fly, and (in air) quadratic drag
            s.effects.sled_motion =
                Some(SledMotion { delay_s: 0.02, return_speed_m_s: 0.3, direction: Default::default() });
            cases.push(s.clone());
            if s.environment.k_drag.is_some() {
                s.effects.quadratic_drag = Some(QuadraticDrag { diameter_m: 300e-6, density_kg_m3: 2500.0 });
                cases.push(s);
            }
        }
        for (c, s) in cases.iter().enumerate() {
            let ctx = Context::new(s);
            let ph = kernel_physics::<f64>(&ctx);
            for design in random_valid_designs(s, 4, 30 + c as u64) {
                let prep = prepare(s, &design).unwrap();
                let d = kernel_design::<f64>(&prep);
                let (engine, _) = crate::engine::cpu::run_particles::<f64>(&prep, &ctx, None);
                for (i, l) in prep.launches.iter().enumerate() {
                    let mut p = init_particle(&d, &ph, *l, i as u32);
                    for bounce in 0..ctx.max_bounces {
                        if p.state != STATE_FLYING {
                            break;
                        }
                        randomise_launch(&d, &ph, &mut p, i as u32, bounce);
                        fly_particle(&d, &ph, &mut p, i as u32, bounce);
                    }
                    let e = &engine[i];
                    let b = |v: [f64; 2]| [v[0].to_bits(), v[1].to_bits()];
                    assert_eq!(
                        (e.state, e.tooth, b(e.pos), b(e.vel), e.bounces, b(e.first)),
                        (p.state, p.tooth, b(p.pos), b(p.vel), p.bounces, b(p.first)),
                        "case {c}, particle {i}"
                    );
                }
            }
        }
    }

    /// What the vector search does not cover it says so: a flight in pieces (sled motion,
    /// quadratic drag), the listing's minimum hop. Vacuum and Stokes flights it covers.
    #[test]
    fn the_vector_search_is_only_for_one_piece_flights_of_the_texts_physics() {
        use crate::model::effects::{QuadraticDrag, SledMotion};
        let physics = |s: &Scenario| kernel_physics::<f64>(&Context::new(s));
        assert!(applies(&physics(&Scenario::lunar())));
        assert!(applies(&physics(&Scenario::earth())));
        assert!(!applies(&physics(&Scenario::lunar().into_listing_compat())));
        assert!(!applies(&physics(&Scenario::earth().into_listing_compat())));
        let mut s = Scenario::earth();
        s.effects.quadratic_drag = Some(QuadraticDrag { diameter_m: 1e-4, density_kg_m3: 3100.0 });
        assert!(!applies(&physics(&s)));
        let mut s = Scenario::lunar();
        s.effects.sled_motion =
            Some(SledMotion { delay_s: 0.01, return_speed_m_s: 0.5, direction: Default::default() });
        assert!(!applies(&physics(&s)));
        // flights in pieces go to the piecewise search, unless the listing's minimum hop applies
        assert!(applies_piecewise(&physics(&s)));
        assert!(!applies_piecewise(&physics(&s.clone().into_listing_compat())));
        assert!(!applies_piecewise(&physics(&Scenario::earth())));
    }
}
