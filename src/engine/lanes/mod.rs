//! The flight search of [`first_hit`](super::kernel::first_hit) for several particles at
//! once, in f64, every hop an impact: vacuum parabolas (the lunar batches) and Stokes
//! flights (Earth's), in one piece ([`Lanes::first_hits`]) or in the pieces of a flight with
//! sled motion or quadratic drag ([`Lanes::first_hits_piecewise`], `first_hit_in` with a time
//! limit and a drift). Beside it, on the same lanes: the launch randomisation
//! ([`Lanes::randomise_launches`]), the restitution law ([`Lanes::bounce_velocities`],
//! `Restitution::bounce_on`, the one law the scalar kernel runs too) and the counter-based
//! generator's hash ([`Lanes::uniforms`]).
//!
//! The search is written once (`search.rs`), over the lane type of `crate::lane`: the
//! branches of the scalar search become masks and selects, and every lane does the scalar
//! search's IEEE operations in the scalar search's order, so each lane's hit is the scalar
//! hit to the bit (`tests.rs`, and `examples/dev/engine_digest.rs`). A lane whose particle
//! has finished its teeth (or its Halley steps) idles while the others go on. It is
//! instantiated for one f64 ([`Lanes::ONE`], which every CPU runs: the tests hold it to the
//! scalar kernel too), four AVX2 lanes, eight AVX-512 lanes and two NEON lanes; the cpu
//! engine takes the widest this CPU has, or the one `SAWTOOTH_SIMD` names
//! ([`Lanes::of`], `crate::simd`), and the scalar kernel on the `scalar` path.

use super::kernel::{end_of_piece, first_hit, first_hit_in, next_piece, Hit, KDesign, KParticle, KPhysics};
use crate::lane::Lane;
use crate::model::collision::Restitution;
use crate::model::flight::Flight;
use crate::simd::Simd;

mod search;
#[cfg(test)]
mod tests;

/// The most particles one search takes (AVX-512's eight f64); the arrays the lanes fill and
/// return have this length, of which an instantiation uses its [`Lanes::width`].
pub const MAX_LANES: usize = 8;

/// Whether [`Lanes::first_hits`] gives the scalar search's hits for these physics: a flight
/// in one piece (no sled motion, no quadratic drag) and no minimum hop (the listing mode's
/// 1e-3 mm rule skips roots the lanes would take). Vacuum (the Moon) and Stokes drag (Earth)
/// both.
pub fn applies(ph: &KPhysics<f64>) -> bool {
    ph.sled_speed == 0.0 && ph.qd_step == 0.0 && ph.min_hop == 0.0
}

/// Whether [`Lanes::first_hits_piecewise`] gives the scalar search's hits for these physics:
/// flights in pieces (sled motion, quadratic drag) and no minimum hop.
pub fn applies_piecewise(ph: &KPhysics<f64>) -> bool {
    (ph.sled_speed > 0.0 || ph.qd_step > 0.0) && ph.min_hop == 0.0
}

/// Whether [`Lanes::randomise_launches`] gives `kernel::randomise_launch_drawn`'s launches
/// for these physics when the launch factors are drawn: yes unless the launch-spread effect
/// draws more per first launch (then one particle at a time).
pub fn randomises(ph: &KPhysics<f64>) -> bool {
    ph.launch_speed_spread == 0.0 && ph.launch_angle_sigma == 0.0
}

/// The lanes' flights, one row per quantity and one column per lane (filled in place: the
/// lunar batches' search is short enough for a copy to show): where each starts (the
/// particle's position, surface and tooth frame), its launch velocity and drag rate, and
/// for a piece how long the search looks and the drift.
struct LaneFlights([[f64; MAX_LANES]; 10]);

impl LaneFlights {
    const POS: usize = 0;
    const VEL: usize = 2;
    const SURFACE: usize = 4;
    const TOOTH: usize = 5;
    const K: usize = 6;
    const LIMIT: usize = 7;
    const DRIFT: usize = 8;

    fn new() -> Self {
        LaneFlights([[0.0; MAX_LANES]; 10])
    }

    /// Which of `n` particles (1 to the lanes' width) lane `l` takes: its own, or the first
    /// again beyond `n` (a lane whose result the caller drops).
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

/// A flight's first impact (time from the flight's start), the flight of the piece it lies
/// in, and that piece's start: what `kernel::first_hit_piecewise` returns.
pub type PieceHit = (Hit<f64>, Flight<f64>, f64);

/// Which instantiation: the lane type and the instruction set it runs on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Isa {
    One,
    #[cfg(target_arch = "x86_64")]
    Avx2,
    #[cfg(target_arch = "x86_64")]
    Avx512,
    #[cfg(target_arch = "aarch64")]
    Neon,
}

/// An instantiation of the lane search on this CPU. Made only where the CPU has its
/// instruction set ([`Lanes::of`]), which is what makes its methods safe to call.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lanes(Isa);

/// `$call` (a function of `search.rs`, with its generic lane type left out) on the lanes
/// of `$lanes`: the instantiation for one f64 directly, the SIMD ones through their
/// `#[target_feature]` entry points below.
macro_rules! on_lanes {
    ($lanes:expr, $f:ident($($arg:expr),*)) => {
        match $lanes.0 {
            Isa::One => one::$f($($arg),*),
            // SAFETY: a `Lanes` of this instruction set exists only where the CPU has it
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { avx2::$f($($arg),*) },
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => unsafe { avx512::$f($($arg),*) },
            #[cfg(target_arch = "aarch64")]
            Isa::Neon => unsafe { neon::$f($($arg),*) },
        }
    };
}

/// The entry points of one instantiation: `search.rs`'s functions for the lane type `$lane`,
/// compiled with the instruction set's features (`$feature`, none for one f64), so the lane
/// operations inline into them as single instructions.
macro_rules! instantiation {
    ($(#[$cfg:meta])* mod $name:ident for $lane:ty $(, #[$feature:meta])?) => {
        $(#[$cfg])*
        mod $name {
            use super::*;
            type L = $lane;

            $(#[$feature])?
            pub(super) fn search(
                d: &KDesign<f64>,
                ph: &KPhysics<f64>,
                flights: &LaneFlights,
                pieces: bool,
                bounce: u32,
            ) -> [Hit<f64>; MAX_LANES] {
                match (ph.k_drag > 0.0, pieces) {
                    (true, false) => search::first_hits::<L, true, false>(d, ph, flights, bounce),
                    (false, false) => search::first_hits::<L, false, false>(d, ph, flights, bounce),
                    (true, true) => search::first_hits::<L, true, true>(d, ph, flights, bounce),
                    (false, true) => search::first_hits::<L, false, true>(d, ph, flights, bounce),
                }
            }

            $(#[$feature])?
            pub(super) fn bounce(
                r: &Restitution<f64>,
                v: &[[f64; MAX_LANES]; 2],
                n: &[[f64; MAX_LANES]; 2],
            ) -> [[f64; MAX_LANES]; 2] {
                search::bounce::<L>(r, v, n)
            }

            $(#[$feature])?
            pub(super) fn randomise(
                d: &KDesign<f64>,
                ph: &KPhysics<f64>,
                parts: &mut [KParticle<f64>],
                idx: &[u32],
                draws: [&[f64]; 2],
            ) {
                search::randomise::<L>(d, ph, parts, idx, draws)
            }

            $(#[$feature])?
            pub(super) fn uniform_bits(seed_word: u32, ids: &[u32; 16], bounce: u32, draw: u32) -> [u32; 16] {
                search::uniform_bits(seed_word, ids, bounce, draw)
            }

            #[cfg(test)]
            $(#[$feature])?
            pub(super) fn operations(x: &[f64; MAX_LANES], y: &[f64; MAX_LANES]) -> Vec<[f64; MAX_LANES]> {
                tests::operations::<L>(x, y)
            }
        }
    };
}

instantiation!(mod one for f64);
instantiation!(
    #[cfg(target_arch = "x86_64")]
    mod avx2 for crate::lane::avx2::F64x4,
    #[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,movbe,popcnt,sse3,ssse3,sse4.1,sse4.2")]
);
instantiation!(
    #[cfg(target_arch = "x86_64")]
    mod avx512 for crate::lane::avx512::F64x8,
    #[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,movbe,popcnt,sse3,ssse3,sse4.1,sse4.2,avx512f")]
);
instantiation!(
    #[cfg(target_arch = "aarch64")]
    mod neon for crate::lane::neon::F64x2,
    #[target_feature(enable = "neon")]
);

impl Lanes {
    /// The search on one f64 a lane: every CPU runs it, and the tests hold it to the scalar
    /// kernel as they hold the SIMD instantiations (the cpu engine's `scalar` path runs the
    /// scalar kernel itself).
    pub const ONE: Lanes = Lanes(Isa::One);

    /// The lanes of a SIMD path where this CPU has it; None for the scalar path (the cpu
    /// engine then searches one particle at a time with the scalar kernel) and for a path
    /// this CPU lacks.
    pub fn of(simd: Simd) -> Option<Lanes> {
        if !simd.supported() {
            return None;
        }
        match simd {
            Simd::Scalar => None,
            #[cfg(target_arch = "x86_64")]
            Simd::Avx2 => Some(Lanes(Isa::Avx2)),
            #[cfg(target_arch = "x86_64")]
            Simd::Avx512 => Some(Lanes(Isa::Avx512)),
            #[cfg(target_arch = "aarch64")]
            Simd::Neon => Some(Lanes(Isa::Neon)),
            #[allow(unreachable_patterns)] // the other architecture's paths
            _ => None,
        }
    }

    /// Every instantiation this CPU runs: [`Lanes::ONE`] and those of [`Lanes::of`].
    pub fn on_this_cpu() -> Vec<Lanes> {
        std::iter::once(Lanes::ONE).chain(Simd::ALL.into_iter().filter_map(Lanes::of)).collect()
    }

    /// Particles per search.
    pub fn width(self) -> usize {
        match self.0 {
            Isa::One => <f64 as Lane>::WIDTH,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => 4,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => 8,
            #[cfg(target_arch = "aarch64")]
            Isa::Neon => 2,
        }
    }

    /// The instantiation's name, for test messages.
    pub fn name(self) -> &'static str {
        match self.0 {
            Isa::One => "one f64",
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => "avx2",
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => "avx512",
            #[cfg(target_arch = "aarch64")]
            Isa::Neon => "neon",
        }
    }

    /// The lanes' search of [`Lanes::width`] flights (a caller with fewer repeats the first
    /// and drops its lanes' hits); `pieces`: some may have a time limit or a drift.
    fn search(
        self,
        d: &KDesign<f64>,
        ph: &KPhysics<f64>,
        flights: &LaneFlights,
        pieces: bool,
        bounce: u32,
    ) -> [Hit<f64>; MAX_LANES] {
        on_lanes!(self, search(d, ph, flights, pieces, bounce))
    }

    /// The first impact of each of the particles `parts[idx[l]]` (as `kernel::first_hit`
    /// finds it), for physics where [`applies`] holds. `idx` has 1 to [`Lanes::width`]
    /// entries; the hits beyond it are to be dropped.
    #[inline]
    pub fn first_hits(
        self,
        d: &KDesign<f64>,
        ph: &KPhysics<f64>,
        parts: &[KParticle<f64>],
        idx: &[u32],
        bounce: u32,
    ) -> [Hit<f64>; MAX_LANES] {
        assert!(applies(ph) && !idx.is_empty() && idx.len() <= self.width());
        // every grain has drag when the air has (Stokes k_drag > 0, scaled per grain when
        // polydisperse), none in vacuum
        let drag = ph.k_drag > 0.0;
        let mut flights = LaneFlights::new();
        for l in 0..self.width() {
            let p = &parts[idx[LaneFlights::source(l, idx.len())] as usize];
            flights.set(l, p, if drag { p.k_drag } else { 0.0 });
        }
        let mut hits = self.search(d, ph, &flights, false, bounce);
        // a grain whose own k_drag rounds to 0 (polydisperse, an extreme draw) flies in
        // vacuum: the scalar search, which picks the flight's form per grain, takes it (in
        // vacuum every grain's k_drag is 0 times its factor, and the vacuum search never
        // reads it)
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

    /// `kernel::first_hit_piecewise` of the particles `parts[i]`, i in `idx` (any number),
    /// for physics where [`applies_piecewise`] holds: for each, the hit (time from the
    /// flight's start), the piece's flight it lies in and that piece's start, to the scalar
    /// search's bits. [`Lanes::width`] particles fly at a time, each from piece to piece with
    /// the scalar `next_piece` and `end_of_piece`, each piece's search on the lanes (a
    /// drifting piece, the sled returning, searches every tooth of its reach over the whole
    /// piece, as the scalar search does; a grain without drag in air goes to the scalar
    /// search). A particle whose flight ends leaves its lane to the next.
    pub fn first_hits_piecewise(
        self,
        d: &KDesign<f64>,
        ph: &KPhysics<f64>,
        parts: &[KParticle<f64>],
        idx: &[u32],
        bounce: u32,
    ) -> Vec<PieceHit> {
        assert!(applies_piecewise(ph));
        let width = self.width();
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
        let mut slots: Vec<Slot> = Vec::with_capacity(width);
        // each round's pieces and the slots searched on the lanes (kept across rounds: no
        // allocation per round)
        let mut pieces: Vec<(Flight<f64>, f64, f64)> = Vec::with_capacity(width);
        let mut on_lanes: Vec<usize> = Vec::with_capacity(width);
        // a grain without drag in air goes to the scalar search
        let lane_search = |fl: &Flight<f64>| !drag || fl.k > 0.0;
        loop {
            while slots.len() < width {
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
            let mut hits = [Hit::default(); MAX_LANES];
            if !on_lanes.is_empty() {
                let mut flights = LaneFlights::new();
                for l in 0..width {
                    let i = on_lanes[LaneFlights::source(l, on_lanes.len())];
                    let (fl, _, limit) = &pieces[i];
                    flights.set_piece(l, &slots[i].q, if drag { fl.k } else { 0.0 }, fl.drift, *limit);
                }
                let found = self.search(d, ph, &flights, true, bounce);
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

    /// `Restitution::bounce` of [`Lanes::width`] impact velocities `v` on surfaces with
    /// normals `n` (the law's one code, `Restitution::bounce_on`, on these lanes): the same
    /// bits as the scalar law in every lane, by the thesis's law or the DEM's.
    pub fn bounce_velocities(
        self,
        r: &Restitution<f64>,
        v: &[[f64; MAX_LANES]; 2],
        n: &[[f64; MAX_LANES]; 2],
    ) -> [[f64; MAX_LANES]; 2] {
        on_lanes!(self, bounce(r, v, n))
    }

    /// `kernel::randomise_launch_drawn` of the particles `parts[idx[l]]` (1 to
    /// [`Lanes::width`]) whose launch factors are drawn, with their draws `angle[l]`,
    /// `speed[l]` (`DRAW_ANGLE`, `DRAW_SPEED`), for physics where [`randomises`] holds: the
    /// same velocities to the bit.
    pub fn randomise_launches(
        self,
        d: &KDesign<f64>,
        ph: &KPhysics<f64>,
        parts: &mut [KParticle<f64>],
        idx: &[u32],
        angle: &[f64],
        speed: &[f64],
    ) {
        assert!(randomises(ph) && !idx.is_empty() && idx.len() <= self.width());
        assert!(angle.len() >= idx.len() && speed.len() >= idx.len());
        on_lanes!(self, randomise(d, ph, parts, idx, [angle, speed]))
    }

    /// `rng::uniform01(seed_word, particle, bounce, draw)` for each of `particles` (1 to
    /// 16), the counter-based generator's integer hash compiled for these lanes'
    /// instruction set (the compiler vectorises it): the same numbers.
    pub fn uniforms(self, seed_word: u32, particles: &[u32], bounce: u32, draw: u32) -> [f64; 16] {
        assert!(!particles.is_empty() && particles.len() <= 16);
        let mut ids = [particles[0]; 16];
        ids[..particles.len()].copy_from_slice(particles);
        let h = on_lanes!(self, uniform_bits(seed_word, &ids, bounce, draw));
        h.map(crate::model::rng::unit_from_hash)
    }

    /// `tests::operations` on these lanes.
    #[cfg(test)]
    fn operations(self, x: &[f64; MAX_LANES], y: &[f64; MAX_LANES]) -> Vec<[f64; MAX_LANES]> {
        on_lanes!(self, operations(x, y))
    }
}

/// The scalar search for the rare grain the lanes leave to it, kept out of line.
#[inline(never)]
fn scalar_hit(d: &KDesign<f64>, ph: &KPhysics<f64>, p: &KParticle<f64>, bounce: u32) -> Hit<f64> {
    first_hit(d, ph, p, bounce)
}
