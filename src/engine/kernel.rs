//! The particle kernel of the `cpu` engine, the CPU twin of the WGSL kernel
//! (shaders/particles.wgsl): flat `Copy` data, no allocation, and for each WGSL function a
//! Rust function of the same name and arguments (the design and physics records first):
//!
//! | WGSL (particles.wgsl)             | Rust                                              |
//! |-----------------------------------|---------------------------------------------------|
//! | `offset`, `normal_of`, `to_index` | same names here                                   |
//! | `randomise_launch`, `hop_ok`      | same names here                                   |
//! | `contact`, `teeth_span`           | same names here                                   |
//! | `above_at_ends`, `vacuum_run`     | same names here                                   |
//! | `run_line` (`RunLine`)            | same names here                                   |
//! | `next_tooth_to_search`            | same name here (its passes call `flies_over` or   |
//! |                                   | `clears_run`; the WGSL computes either's inputs   |
//! |                                   | in one place and runs one test)                   |
//! | `first_hit`, `step_particle`      | same names here (plus the cpu-only effects)       |
//! | `fly_particle`                    | same name here                                    |
//! | `end_tooth`                       | [`end_tooth`]                                     |
//! | `bounce_velocity`                 | `Restitution::bounce` (src/model/collision.rs)    |
//! | `simulate`: bounce loop           | `run_particles` (src/engine/cpu.rs)               |
//! | `simulate_particles`              | [`follow_particle`] for each particle             |
//! | `particle_steps`                  | [`particle_steps`]                                |
//! | `reduce_designs`                  | max of [`particle_steps`], then [`reduce`]        |
//! | `reduce_design` (one design)      | [`reduce`]                                        |
//! | `pitch(d)`                        | the field `d.pitch`                               |
//!
//! `init_particle` runs on the host for both engines. The shared files have their own twins:
//! shared/flight.wgsl in src/model/flight.rs, shared/rng.wgsl in src/model/rng.rs,
//! shared/trig.wgsl in src/model/real.rs (`ktrig`), shared/types.wgsl in
//! src/engine/gpu/layout.rs, and the integer codes come from src/kernel_codes.rs.
//!
//! Precision strategy: a particle's position is kept relative to the p1 of the tooth it last
//! touched (`tooth`), and segments are built as `(j - tooth) * pitch + offset`, so every
//! coordinate the arithmetic sees is within a few pitches of zero. That keeps f32 at about
//! 1e-8 m even on the 100th tooth.

use crate::model::collision::Restitution;
use crate::model::flight::Flight;
use crate::model::real::Real;
use crate::model::rng::{
    normal01, uniform01, DRAW_ANGLE, DRAW_LAUNCH_ANGLE, DRAW_LAUNCH_SPEED, DRAW_SCATTER, DRAW_SIZE, DRAW_SPEED,
    PER_PARTICLE,
};

use crate::kernel_codes::{DRAW_SCATTER_AGAIN, RUN_CLEARANCE_PITCHES, TILT_DRAWS};
/// The state, surface and randomisation codes, declared once for both sides (build.rs
/// generates their WGSL twins from src/kernel_codes.rs).
pub use crate::kernel_codes::{
    RANDOMISE_EVERY_LAUNCH, RANDOMISE_FIRST_LAUNCH, RANDOMISE_OFF, STATE_FLYING, STATE_LOST, STATE_RESTING,
    SURFACE_BASE, SURFACE_CATCH, SURFACE_NONE, SURFACE_RAMP,
};

/// One design's profile as the kernel sees it (offsets relative to a tooth's p1, global
/// orientation).
#[derive(Clone, Copy, Debug)]
pub struct KDesign<T> {
    pub pitch: [T; 2],
    pub p2: [T; 2],
    pub p4: [T; 2],
    pub n_base: [T; 2],
    pub n_ramp: [T; 2],
    pub n_catch: [T; 2],
    /// Unit vector along the base, uphill.
    pub t_base: [T; 2],
    pub pitch_len: T,
    /// Base extent along the conveyor from tooth 0's p1.
    pub base_length: T,
    /// Smallest and largest x offset of a tooth's points from its p1.
    pub ext_min: T,
    pub ext_max: T,
    pub teeth: i32,
    pub launch_angle: T,
    /// sin and cos of the launch angle, computed once per design (every particle starts
    /// along it).
    pub launch_sin_cos: (T, T),
    pub v0: T,
    /// Stroke v0²/(2a), m: how far the sled returns (sled-motion effect).
    pub stroke: T,
    /// A point of the fill's free surface line (p_fill, Figure 4.6) and the sine and cosine of
    /// its angle: a launch point's depth below the surface (`Fill::depth`) for the
    /// fill-surface-loss effect. Used by `init_particle` only (on the host for both engines),
    /// so the GPU's design record does not carry them.
    pub fill_point: [T; 2],
    pub fill_sin_cos: (T, T),
}

/// Scenario-wide constants.
///
/// The GPU splits this record in two (keep in sync with shaders/shared/types.wgsl and
/// src/engine/gpu/layout.rs): what a calibration varies per candidate (`restitution`, the
/// effect parameters scatter_sigma, launch_speed_spread, launch_angle_sigma) travels in each
/// design's record `GpuDesign`, the rest in the dispatch-wide `GpuPhysics`; `k_drag` and
/// `size_sigma_ln` reach the kernel only through each particle's `k_drag` (`init_particle`,
/// run on the host). The cpu-only fields (size_uniform, sled_*, qd_*) have no GPU twin.
#[derive(Clone, Copy, Debug)]
pub struct KPhysics<T> {
    pub g: T,
    /// Stokes k_drag, 1/s; 0 = vacuum.
    pub k_drag: T,
    pub restitution: Restitution<T>,
    pub randomise: u32,
    pub band: T,
    pub seed: u32,
    pub rest_threshold: T,
    /// Smallest hop that counts as a new impact, m.
    pub min_hop: T,
    /// Measure `min_hop` horizontally, as listing D.2 line 60 does (|x_sol - x0| > 1e-3 mm).
    pub min_hop_horizontal: bool,
    /// Rest per particle (text) instead of the listing's mean-hop stop for all.
    pub per_particle_rest: bool,
    /// Effects (issue 5; 0 = off; in the `cpu` and `gpu` kernels): impact tilt σ (rad),
    /// launch speed spread (fraction), launch angle σ (rad), log-normal size σ.
    pub scatter_sigma: T,
    pub launch_speed_spread: T,
    pub launch_angle_sigma: T,
    pub size_sigma_ln: T,
    /// Sizes uniform (not log-normal) in number (`SizeForm::Uniform`; cpu only).
    pub size_uniform: bool,
    /// Sled motion after the launch (cpu only; speed 0 = off): rest for `sled_delay` s, then
    /// return at `sled_speed` m/s over the design's stroke.
    pub sled_delay: T,
    pub sled_speed: T,
    /// The sled returns along the launch direction, not the slope (`MotionDirection`; cpu
    /// only).
    pub sled_along_launch: bool,
    /// Impact tilt uniform with sd `scatter_sigma` (`TiltForm::Uniform`; cpu only).
    pub scatter_uniform: bool,
    /// Quadratic drag (cpu only; step 0 = off): Stokes part 18μ/(ρ_p d²) (1/s), Reynolds
    /// number per unit speed (s/m), refresh step (s).
    pub qd_k0: T,
    pub qd_re_per_speed: T,
    pub qd_step: T,
    /// Fill-surface loss (0 = off): the speed lost at the free surface (fraction) and its
    /// decay depth (m). Applied in `init_particle`, on the host for both engines: it reaches
    /// the WGSL kernel as each particle's launch velocity, as the polydisperse size law
    /// reaches it as each particle's k_drag.
    pub surface_loss: T,
    pub surface_decay: T,
}

#[derive(Clone, Copy, Debug, Default)]
pub struct KParticle<T> {
    /// Tooth whose p1 is the origin of `pos`.
    pub tooth: i32,
    pub pos: [T; 2],
    /// Launch velocity of the next flight (after a bounce: the rebound velocity).
    pub vel: [T; 2],
    /// Surface the particle sits on (last impact).
    pub surface: u32,
    pub state: u32,
    pub bounces: u32,
    /// Horizontal length of the last hop, m.
    pub hop: T,
    /// First impact point, global.
    pub first: [T; 2],
    /// This grain's Stokes k_drag, 1/s (differs between grains only when polydisperse).
    pub k_drag: T,
    /// Time since the launch, s (kept for the sled-motion effect).
    pub clock: T,
}

/// The first surface a flight meets.
#[derive(Clone, Copy, Debug, Default)]
pub struct Hit<T> {
    pub found: bool,
    pub t: T,
    /// Impact point relative to the particle's current tooth frame.
    pub pos: [T; 2],
    pub tooth: i32,
    pub surface: u32,
}

#[inline(always)]
fn dot<T: Real>(a: [T; 2], b: [T; 2]) -> T {
    a[0] * b[0] + a[1] * b[1]
}

#[inline(always)]
pub fn offset<T: Real>(d: &KDesign<T>, dj: i32, p: [T; 2]) -> [T; 2] {
    let f = T::c(dj as f64);
    [f * d.pitch[0] + p[0], f * d.pitch[1] + p[1]]
}

pub fn normal_of<T: Real>(d: &KDesign<T>, surface: u32) -> [T; 2] {
    match surface {
        SURFACE_RAMP => d.n_ramp,
        SURFACE_CATCH => d.n_catch,
        _ => d.n_base,
    }
}

/// A particle at its launch point (global = tooth 0 frame), moving at v0 along the launch
/// angle (listing lines 45, 206-210).
pub fn init_particle<T: Real>(d: &KDesign<T>, ph: &KPhysics<T>, launch: [T; 2], index: u32) -> KParticle<T> {
    // polydisperse: k ∝ 1/d² (Eq. 4.16, 4.20), d drawn from the mass-weighted size law so
    // that every simulated grain stands for an equal mass (`effects::Polydisperse`)
    let k_drag = if ph.size_sigma_ln > T::zero() && ph.size_uniform {
        let half = T::c(3f64.sqrt()) * ph.size_sigma_ln;
        let (a4, b4) = ((T::c(-4.0) * half).exp(), (T::c(4.0) * half).exp());
        let u = T::c(uniform01(ph.seed, index, PER_PARTICLE, DRAW_SIZE));
        // k_ref / d² with d = (a⁴ + u (b⁴ − a⁴))^{1/4}
        ph.k_drag / (a4 + u * (b4 - a4)).sqrt()
    } else if ph.size_sigma_ln > T::zero() {
        ph.k_drag * (T::c(-2.0) * ph.size_sigma_ln * T::c(normal01(ph.seed, index, PER_PARTICLE, DRAW_SIZE))).exp()
    } else {
        ph.k_drag
    };
    // fill-surface loss (DEM evidence, `effects::FillSurfaceLoss`): the launch speed falls
    // off towards the free surface, depth = distance from its line (`Fill::depth`)
    let speed = if ph.surface_loss > T::zero() {
        let (s, c) = d.fill_sin_cos;
        let depth = ((launch[0] - d.fill_point[0]) * s - (launch[1] - d.fill_point[1]) * c).abs();
        d.v0 * (T::one() - ph.surface_loss * (-depth / ph.surface_decay).exp())
    } else {
        d.v0
    };
    KParticle {
        k_drag,
        tooth: 0,
        pos: launch,
        vel: {
            let (s, c) = d.launch_sin_cos;
            [speed * c, speed * s]
        },
        surface: SURFACE_NONE,
        state: STATE_FLYING,
        ..Default::default()
    }
}

/// Randomise the launch angle and speed with factors in [1 - band, 1 + band] (Eq. 4.38).
/// First launch: the global angle is multiplied, as 4.2.4 and D.3 do. Rebounds (text mode
/// only, erratum 5): the angle measured from the departed surface's tangent is multiplied
/// and kept inside (0, π), so a randomised rebound never points into that surface
/// (erratum 24).
#[inline(always)]
pub fn randomise_launch<T: Real>(d: &KDesign<T>, ph: &KPhysics<T>, p: &mut KParticle<T>, index: u32, bounce: u32) {
    randomise_launch_drawn(d, ph, p, index, bounce, None);
}

/// [`randomise_launch`] with its two factors' uniform draws (`DRAW_ANGLE`, `DRAW_SPEED`)
/// given when the caller has them already (the cpu engine draws a whole bounce's on SIMD
/// lanes, `lanes::uniforms`, the same numbers).
#[inline(always)]
pub fn randomise_launch_drawn<T: Real>(
    d: &KDesign<T>,
    ph: &KPhysics<T>,
    p: &mut KParticle<T>,
    index: u32,
    bounce: u32,
    draws: Option<[f64; 2]>,
) {
    let apply = match ph.randomise {
        RANDOMISE_FIRST_LAUNCH => bounce == 0,
        RANDOMISE_EVERY_LAUNCH => true,
        _ => false,
    };
    let spread = p.surface == SURFACE_NONE && (ph.launch_speed_spread > T::zero() || ph.launch_angle_sigma > T::zero());
    if !apply && !spread {
        return;
    }
    let two = T::c(2.0);
    let (fa, fs) = if apply {
        (
            T::one() - ph.band
                + two * ph.band * T::c(draws.map_or_else(|| uniform01(ph.seed, index, bounce, DRAW_ANGLE), |u| u[0])),
            T::one() - ph.band
                + two * ph.band * T::c(draws.map_or_else(|| uniform01(ph.seed, index, bounce, DRAW_SPEED), |u| u[1])),
        )
    } else {
        (T::one(), T::one())
    };
    let mut speed = (p.vel[0] * p.vel[0] + p.vel[1] * p.vel[1]).sqrt() * fs;
    // One atan2 and one sincos serve both kinds of launch, the branches only choosing what
    // goes in and comes out: a SIMD machine (lavapipe, a GPU warp) whose lanes disagree runs
    // both sides of a branch, and each side held an atan2 and a sincos.
    let first = p.surface == SURFACE_NONE;
    let n = normal_of(d, p.surface);
    let t = [n[1], -n[0]];
    // the first launch's angle is global, a rebound's from the departed surface's tangent
    let (y, x) = if first { (p.vel[1], p.vel[0]) } else { (dot(p.vel, n), dot(p.vel, t)) };
    let mut ang = y.katan2(x);
    if first {
        if ang < T::zero() {
            ang = ang + two * T::PI(); // listing keeps angles in [0, 2π)
        }
        if spread {
            // launch-spread effect: earlier (slower) departures and a jittered direction
            speed = speed
                * (T::one() - ph.launch_speed_spread * T::c(uniform01(ph.seed, index, bounce, DRAW_LAUNCH_SPEED)));
            ang = ang + ph.launch_angle_sigma * T::c(normal01(ph.seed, index, bounce, DRAW_LAUNCH_ANGLE));
        }
        ang = ang * fa;
    } else {
        let eps = T::c(1e-6);
        ang = (ang * fa).max(eps).min(T::PI() - eps);
    }
    let (s, c) = ang.ksin_cos();
    p.vel = if first { [speed * c, speed * s] } else { [speed * (c * t[0] + s * n[0]), speed * (c * t[1] + s * n[1])] };
}

#[inline(always)]
fn hop_ok<T: Real>(ph: &KPhysics<T>, from: [T; 2], to: [T; 2]) -> bool {
    if ph.min_hop == T::zero() {
        return true;
    }
    let dx = to[0] - from[0];
    if ph.min_hop_horizontal {
        dx.abs() > ph.min_hop
    } else {
        let dy = to[1] - from[1];
        dx * dx + dy * dy > ph.min_hop * ph.min_hop
    }
}

/// A particle lying on a surface's line (to rounding), inside its extent and moving into it,
/// touches it at once (t = 0). This happens in corners, e.g. a rebound off the catch chord
/// at p4 aimed into the base: rounding can leave the point a hair below the base line, and
/// the flight would then find no later crossing. Points merely behind a line (a point on
/// ramp j is behind tooth j's own chord) are not in contact.
#[inline(always)]
fn contact<T: Real>(d: &KDesign<T>, pos: [T; 2], vel: [T; 2], a: [T; 2], b: [T; 2], n: [T; 2]) -> bool {
    let c0 = dot([pos[0] - a[0], pos[1] - a[1]], n);
    let tol = T::c(64.0) * T::epsilon() * d.pitch_len.max(pos[0].abs()).max(pos[1].abs());
    if c0.abs() > tol || dot(vel, n) >= T::zero() {
        return false;
    }
    let e = [b[0] - a[0], b[1] - a[1]];
    let s = dot([pos[0] - a[0], pos[1] - a[1]], e) / dot(e, e);
    s >= T::zero() && s <= T::one()
}

/// Earliest impact of the particle's next flight among the base line, and the ramps and
/// catch chords of the teeth the flight can reach (4.2.4-4.2.5; the first tooth's catch is
/// ignored on the first flight). The base-line crossing bounds the flight: every tooth
/// segment lies above the base, so nothing after it can be hit.
#[inline(always)]
pub fn first_hit<T: Real>(d: &KDesign<T>, ph: &KPhysics<T>, p: &KParticle<T>, bounce: u32) -> Hit<T> {
    let fl = Flight { p0: p.pos, v0: p.vel, g: ph.g, k: p.k_drag, drift: [T::zero(); 2] };
    first_hit_in(d, ph, p, &fl, bounce, T::infinity())
}

/// `first_hit` for a given flight (possibly drifting: sled motion), looking no further than
/// `t_limit`. With drift the flight's x(t) is no longer the air-frame one, so the x-window
/// and concavity culls are skipped (they are exact only without drift).
#[inline(always)]
pub fn first_hit_in<T: Real>(
    d: &KDesign<T>,
    ph: &KPhysics<T>,
    p: &KParticle<T>,
    fl: &Flight<T>,
    bounce: u32,
    t_limit: T,
) -> Hit<T> {
    let fl = *fl;
    let drifting = fl.drift != [T::zero(); 2];
    let rel_vel = [fl.v0[0] + fl.drift[0], fl.v0[1] + fl.drift[1]];
    let mut best = Hit { found: false, t: T::infinity(), ..Default::default() };
    let k = p.tooth;
    let kf = T::c(k as f64);

    // Base: one line through every p1 (frame origin lies on it).
    let mut horizon = T::infinity();
    let departing_base = p.surface == SURFACE_BASE;
    let mut roots = fl.line_crossings([T::zero(), T::zero()], d.n_base, departing_base, T::zero(), t_limit);
    if !departing_base && hop_ok(ph, p.pos, p.pos) {
        let s0 = -kf * d.pitch_len;
        let a = [s0 * d.t_base[0], s0 * d.t_base[1]];
        let b = [(s0 + d.base_length) * d.t_base[0], (s0 + d.base_length) * d.t_base[1]];
        if contact(d, p.pos, rel_vel, a, b, d.n_base) {
            roots = [Some(T::zero()), None];
        }
    }
    for t in roots.into_iter().flatten() {
        let q = fl.pos(t);
        if !hop_ok(ph, p.pos, q) {
            continue;
        }
        horizon = t;
        let s = dot(q, d.t_base); // along the base from this frame's p1
        let s_global_lo = -kf * d.pitch_len;
        if s >= s_global_lo && s <= d.base_length + s_global_lo {
            let j = (to_index((s / d.pitch_len).floor()) + k).clamp(0, d.teeth - 1);
            best = Hit { found: true, t, pos: q, tooth: j, surface: SURFACE_BASE };
        }
        break;
    }

    // Teeth whose x-extent overlaps the flight's x-range before the horizon (with drift x(t)
    // need not be monotone: then every tooth up to the time limit is considered).
    let horizon = horizon.min(t_limit);
    let x_end = if horizon.is_finite() {
        fl.pos(horizon)[0]
    } else if p.vel[0] >= T::zero() {
        T::infinity()
    } else {
        T::neg_infinity()
    };
    // with drift: |x(t) - x0| <= (|vx| + |wx|) t bounds the range instead of monotonicity
    let reach = (fl.v0[0].abs() + fl.drift[0].abs()) * horizon;
    let (x_end, x_start) = if drifting { (p.pos[0] + reach, p.pos[0] - reach) } else { (x_end, p.pos[0]) };
    let (xmin, xmax) = if x_end >= x_start { (x_start, x_end) } else { (x_end, x_start) };
    let lo = ((xmin - d.ext_max) / d.pitch[0]).ceil().max(T::c(-1e9)).min(T::c(1e9));
    let hi = ((xmax - d.ext_min) / d.pitch[0]).floor().max(T::c(-1e9)).min(T::c(1e9));
    let j_lo = (lo.to_i64().unwrap_or(0) + k as i64).clamp(0, d.teeth as i64 - 1) as i32;
    let j_hi = (hi.to_i64().unwrap_or(0) + k as i64).clamp(0, d.teeth as i64 - 1) as i32;
    if (lo.to_i64().unwrap_or(0) + k as i64) > d.teeth as i64 - 1 || (hi.to_i64().unwrap_or(0) + k as i64) < 0 {
        return best;
    }
    let x_far = if best.found { best.pos[0] } else { x_end };
    // As the WGSL: first pass the teeth the flight clears, then search one it may hit (on a
    // SIMD machine a `continue` would make every lane pay for each tooth any lane scans).
    let mut j = j_lo;
    loop {
        if !drifting {
            j = next_tooth_to_search(d, &fl, j, j_hi, k, p.pos[0], x_far);
        }
        if j > j_hi {
            break;
        }
        let dj = j - k;
        for surface in [SURFACE_RAMP, SURFACE_CATCH] {
            if surface == SURFACE_CATCH && bounce == 0 && j == 0 {
                continue;
            }
            let (a, b, n) = if surface == SURFACE_RAMP {
                (offset(d, dj, [T::zero(), T::zero()]), offset(d, dj, d.p2), d.n_ramp)
            } else {
                (offset(d, dj, d.p2), offset(d, dj, d.p4), d.n_catch)
            };
            let departing = p.surface == surface && dj == 0;
            let t_max = if best.found { best.t } else { horizon };
            // Only while the flight is within the segment's x-extent can it hit the segment
            // (x(t) is monotone): search that time window only.
            let margin = T::c(64.0) * T::epsilon() * d.pitch_len;
            let (xa, xb) = (a[0].min(b[0]) - margin, a[0].max(b[0]) + margin);
            let (t_lo, t_hi) = if drifting {
                (T::zero(), T::infinity())
            } else if fl.v0[0] > T::zero() || fl.v0[0] < T::zero() {
                // the window's ends in the direction of flight, then one time_at_x for each
                // (as the WGSL does: lanes flying both ways would run both pairs)
                let (x_in, x_out) = if fl.v0[0] < T::zero() { (xb.min(p.pos[0]), xa) } else { (xa.max(p.pos[0]), xb) };
                (fl.time_at_x(x_in), fl.time_at_x(x_out))
            } else if p.pos[0] >= xa && p.pos[0] <= xb {
                (T::zero(), T::infinity())
            } else {
                (T::infinity(), T::infinity())
            };
            let mut roots =
                if t_lo > t_max { [None, None] } else { fl.line_crossings(a, n, departing, t_lo, t_max.min(t_hi)) };
            if !departing && hop_ok(ph, p.pos, p.pos) && contact(d, p.pos, rel_vel, a, b, n) {
                roots = [Some(T::zero()), None];
            }
            let e = [b[0] - a[0], b[1] - a[1]];
            let ee = dot(e, e);
            // the first root on the segment (the WGSL tests both side by side)
            let on_segment = |t: T| {
                let q = fl.pos(t);
                let s = dot([q[0] - a[0], q[1] - a[1]], e) / ee;
                (s >= T::zero() && s <= T::one() && hop_ok(ph, p.pos, q)).then_some((t, q))
            };
            if let Some((t, q)) = roots[0].and_then(on_segment).or_else(|| roots[1].and_then(on_segment)) {
                if t < best.t {
                    best = Hit { found: true, t, pos: q, tooth: j, surface };
                }
            }
        }
        j += 1;
    }
    best
}

/// The x-interval from tooth `dj_first`'s left end to tooth `dj_last`'s right end, clipped to
/// [lo, hi] (empty, `.0 > .1`, when they do not meet).
#[inline(always)]
fn teeth_span<T: Real>(d: &KDesign<T>, dj_first: i32, dj_last: i32, lo: T, hi: T) -> (T, T) {
    let xa = (T::c(dj_first as f64) * d.pitch[0] + d.ext_min).max(lo);
    let xb = (T::c(dj_last as f64) * d.pitch[0] + d.ext_max).min(hi);
    (xa, xb)
}

/// Whether the flight is higher than `need_a` at x = `xa` and than `need_b` at x = `xb` (true
/// when xa > xb: it is not there at all). The trajectory is concave in x, so above a line at
/// both ends of an interval is above it over the whole interval.
#[inline(always)]
fn above_at_ends<T: Real>(fl: &Flight<T>, xa: T, xb: T, need_a: T, need_b: T) -> bool {
    if xa > xb {
        return true;
    }
    match (fl.y_at_x(xa), fl.y_at_x(xb)) {
        (Some(ya), Some(yb)) => ya > need_a && yb > need_b,
        _ => false,
    }
}

/// True when the flight stays above tooth `dj`'s peak over the tooth's x-extent (clipped to
/// the part of the flight before `x_far`): no point of a tooth is higher than its peak.
#[inline(always)]
fn flies_over<T: Real>(d: &KDesign<T>, fl: &Flight<T>, dj: i32, x0: T, x_far: T) -> bool {
    let (lo, hi) = if x_far >= x0 { (x0, x_far) } else { (x_far, x0) };
    let (xa, xb) = teeth_span(d, dj, dj, lo, hi);
    let top = T::c(dj as f64) * d.pitch[1] + d.p2[1].max(d.p4[1]).max(T::zero());
    above_at_ends(fl, xa, xb, top, top)
}

/// True when the flight is higher, by [`RUN_CLEARANCE_PITCHES`], than a line at least as high
/// as each peak of teeth `dj_first..=dj_last` over that tooth's extent (clipped as in
/// [`flies_over`]): then `flies_over` is true of each of them.
#[inline(always)]
fn clears_run<T: Real>(d: &KDesign<T>, fl: &Flight<T>, dj_first: i32, dj_last: i32, x0: T, x_far: T) -> bool {
    let (lo, hi) = if x_far >= x0 { (x0, x_far) } else { (x_far, x0) };
    let (xa, xb) = teeth_span(d, dj_first, dj_last, lo, hi);
    let line = run_line(d);
    let need = |x: T| line.peak + line.slope * (x - line.x_ref) + line.clearance;
    above_at_ends(fl, xa, xb, need(xa), need(xb))
}

/// The line of [`clears_run`], at least as high as each tooth's peak over that tooth's
/// extent: it rises with the teeth (`slope`) and has tooth 0's peak height at the left end of
/// its extent (`x_ref`; uphill, the right end downhill); the run test asks for `clearance`
/// above it. WGSL twin: `RunLine`, `run_line`.
struct RunLine<T> {
    peak: T,
    slope: T,
    x_ref: T,
    clearance: T,
}

#[inline(always)]
fn run_line<T: Real>(d: &KDesign<T>) -> RunLine<T> {
    let slope = d.pitch[1] / d.pitch[0];
    let x_ref = if slope < T::zero() { d.ext_max } else { d.ext_min };
    RunLine {
        peak: d.p2[1].max(d.p4[1]).max(T::zero()),
        slope,
        x_ref,
        clearance: T::c(RUN_CLEARANCE_PITCHES) * d.pitch_len,
    }
}

/// How many teeth from `j` on a vacuum flight clears by [`clears_run`]'s test, worked out
/// instead of searched for: the parabola minus [`clears_run`]'s line is a quadratic in time,
/// so the flight is above the line between its two roots, and every tooth from `j` to the last
/// one ending before the later root (in x) is cleared when tooth `j` starts after the earlier
/// one. 1 (the doubling's first run) when tooth `j` does not start inside, 0 when the interval
/// ends within tooth `j` (then it is tested alone). Rounding may make the count one too many:
/// `next_tooth_to_search` still tests the run, and halves it when the test fails. `line` is
/// the design's [`run_line`], `[lo, hi]` the flight's x-range as the scan clips it.
// `!(a > b)` as in the WGSL twin: a NaN takes the cautious branch; the arguments are the
// WGSL twin's
#[allow(clippy::neg_cmp_op_on_partial_ord, clippy::too_many_arguments)]
#[inline(always)]
fn vacuum_run<T: Real>(
    d: &KDesign<T>,
    fl: &Flight<T>,
    line: &RunLine<T>,
    j: i32,
    j_hi: i32,
    k: i32,
    lo: T,
    hi: T,
) -> i32 {
    // y(t) - line(x(t)) = -g/2 t^2 + b t + c
    let vx = fl.v0[0];
    let b = fl.v0[1] - line.slope * vx;
    let c = fl.p0[1] - line.peak - line.slope * (fl.p0[0] - line.x_ref) - line.clearance;
    let disc = b * b + T::c(2.0) * fl.g * c;
    if !(disc > T::zero()) || !(fl.g > T::zero()) || vx == T::zero() {
        return 1;
    }
    let sq = disc.sqrt();
    let x1 = fl.p0[0] + vx * ((b - sq) / fl.g);
    let x2 = fl.p0[0] + vx * ((b + sq) / fl.g);
    let (xl, xr) = (x1.min(x2), x1.max(x2));
    let xa = (T::c((j - k) as f64) * d.pitch[0] + d.ext_min).max(lo);
    if !(xa > xl) {
        return 1;
    }
    if xr >= hi {
        return (j_hi - j + 1).max(0);
    }
    let last = to_index(((xr - d.ext_max) / d.pitch[0]).floor()) + k;
    (last.min(j_hi) - j + 1).max(0)
}

/// The first tooth from `j_from` on that the flight does not fly over (`j_hi + 1` when none),
/// in few passes where it clears many teeth: after a tooth it clears, a run of the next teeth
/// is passed at once when the flight is above the line over the run's peaks by
/// [`RUN_CLEARANCE_PITCHES`] (far more than rounding, so [`flies_over`] would say the same of
/// each tooth); the run doubles while that holds and halves when not, down to one tooth tested
/// by `flies_over` itself. A vacuum flight's run is worked out instead ([`vacuum_run`]),
/// and after it passes the next tooth is tested alone. The WGSL twin makes the same passes
/// (on a SIMD machine the scan lasts as long as its slowest lane's, and one tooth at a time
/// that was a quarter of the lunar kernel on lavapipe).
#[inline(always)]
fn next_tooth_to_search<T: Real>(
    d: &KDesign<T>,
    fl: &Flight<T>,
    j_from: i32,
    j_hi: i32,
    k: i32,
    x0: T,
    x_far: T,
) -> i32 {
    let mut j = j_from;
    let mut run = 0;
    while j <= j_hi {
        let last = if run == 0 { j } else { (j + run - 1).min(j_hi) };
        let passed =
            if run == 0 { flies_over(d, fl, j - k, x0, x_far) } else { clears_run(d, fl, j - k, last - k, x0, x_far) };
        if passed {
            j = last + 1;
            run = if fl.drag() {
                (2 * run).max(1)
            } else if run == 0 {
                let (lo, hi) = if x_far >= x0 { (x0, x_far) } else { (x_far, x0) };
                vacuum_run(d, fl, &run_line(d), j, j_hi, k, lo, hi)
            } else {
                0
            };
        } else if run == 0 {
            break;
        } else {
            run /= 2;
        }
    }
    j
}

/// What one flight did, for trajectory output.
#[derive(Clone, Copy, Debug, Default)]
pub struct Flown<T> {
    pub from_tooth: i32,
    pub from: [T; 2],
    /// Launch velocity after randomisation.
    pub vel: [T; 2],
    pub t: T,
}

/// The sled's velocity seen as a drift of the particles in the sled frame at time `clock`
/// since the launch, and the time that motion phase ends (sled-motion effect): at rest until
/// the delay, then returning down the slope (so particles drift up it) until it has
/// travelled back the stroke, then at rest for good.
#[inline(always)]
fn sled_phase<T: Real>(d: &KDesign<T>, ph: &KPhysics<T>, clock: T) -> ([T; 2], T) {
    let back_end = ph.sled_delay + d.stroke / ph.sled_speed;
    if clock < ph.sled_delay {
        ([T::zero(); 2], ph.sled_delay)
    } else if clock < back_end {
        let dir = if ph.sled_along_launch {
            let (s, c) = d.launch_sin_cos;
            [c, s]
        } else {
            d.t_base
        };
        ([ph.sled_speed * dir[0], ph.sled_speed * dir[1]], back_end)
    } else {
        ([T::zero(); 2], T::infinity())
    }
}

/// Longest flight the piecewise integration follows, s; longer ones count as lost.
pub const MAX_FLIGHT_S: f64 = 60.0;

/// Drag rate for the quadratic-drag effect at air speed `speed`: the Schiller-Naumann force
/// per unit mass and speed, 18μ/(ρ_p d²)(1 + 0.15 Re^0.687) (Eq. 4.18).
#[inline(always)]
fn schiller_naumann_k<T: Real>(ph: &KPhysics<T>, speed: T) -> T {
    crate::model::effects::schiller_naumann_rate(ph.qd_k0, ph.qd_re_per_speed, speed)
}

/// The next piece of a flight split into pieces, for the particle `q` as it is at the
/// piece's start: pieces end where the sled's motion changes (each piece a drifting flight
/// in the sled frame) and, with quadratic drag, every `qd_step` (each piece a Stokes flight
/// with k from the speed at its midpoint). Returns the piece's flight, the clock at its end
/// and its length (infinite for the last piece).
#[inline(always)]
pub fn next_piece<T: Real>(d: &KDesign<T>, ph: &KPhysics<T>, q: &KParticle<T>) -> (Flight<T>, T, T) {
    let (drift, mut phase_end) =
        if ph.sled_speed > T::zero() { sled_phase(d, ph, q.clock) } else { ([T::zero(); 2], T::infinity()) };
    let mut k = q.k_drag;
    if ph.qd_step > T::zero() {
        // midpoint rule for the drag rate: predict the speed half a piece ahead with the
        // rate at the start, fly the piece with the rate there (second order in the step)
        phase_end = phase_end.min(q.clock + ph.qd_step);
        let k0 = schiller_naumann_k(ph, (q.vel[0] * q.vel[0] + q.vel[1] * q.vel[1]).sqrt());
        let probe = Flight { p0: q.pos, v0: q.vel, g: ph.g, k: k0, drift };
        let vh = probe.vel(T::c(0.5) * (phase_end - q.clock));
        k = schiller_naumann_k(ph, (vh[0] * vh[0] + vh[1] * vh[1]).sqrt());
    }
    let fl = Flight { p0: q.pos, v0: q.vel, g: ph.g, k, drift };
    (fl, phase_end, phase_end - q.clock)
}

/// After the search of one piece (`next_piece`'s `fl`, ending at clock `phase_end` after
/// `limit`) found `hit`: the flight's first impact (time counted from the start of the whole
/// flight, `elapsed` being the piece's start) when the flight ends in this piece; otherwise
/// None, with `q` moved to the piece's end and `elapsed` to the next piece's start.
#[inline(always)]
pub fn end_of_piece<T: Real>(
    d: &KDesign<T>,
    q: &mut KParticle<T>,
    fl: &Flight<T>,
    (phase_end, limit): (T, T),
    mut hit: Hit<T>,
    elapsed: &mut T,
) -> Option<Hit<T>> {
    if hit.found || !limit.is_finite() {
        hit.t = hit.t + *elapsed;
        return Some(hit);
    }
    // no impact in this phase: continue from where the particle is when it ends
    q.pos = fl.pos(limit);
    q.vel = fl.vel(limit);
    // Below the base line (through this frame's p1) without a hit: the flight crossed the
    // line beyond the conveyor's ends and falls away (lost, as in `first_hit`). The time
    // cap keeps a pathological flight from looping (no flight lasts a minute on the rig).
    if dot(q.pos, d.n_base) < T::zero() || *elapsed + limit > T::c(MAX_FLIGHT_S) {
        hit.t = hit.t + *elapsed;
        return Some(hit);
    }
    q.surface = SURFACE_NONE; // airborne: no surface is being left any more
    q.clock = phase_end;
    *elapsed = *elapsed + limit;
    None
}

/// The first impact of a flight split into pieces ([`next_piece`]). Returns the hit (time
/// counted from the start of the whole flight) and the flight of the piece it lies in, with
/// that piece's start time. The cpu engine's lanes fly eight particles' pieces at once
/// (`lanes::first_hits_piecewise`) with the same two steps around each piece's search.
pub fn first_hit_piecewise<T: Real>(
    d: &KDesign<T>,
    ph: &KPhysics<T>,
    p: &KParticle<T>,
    bounce: u32,
) -> (Hit<T>, Flight<T>, T) {
    let mut q = *p;
    let mut elapsed = T::zero();
    loop {
        let (fl, phase_end, limit) = next_piece(d, ph, &q);
        let hit = first_hit_in(d, ph, &q, &fl, bounce, limit);
        let start = elapsed;
        if let Some(hit) = end_of_piece(d, &mut q, &fl, (phase_end, limit), hit, &mut elapsed) {
            return (hit, fl, start);
        }
    }
}

/// One flight and bounce of one particle (one iteration of the bounce loop, 4.2.4).
#[inline(always)]
pub fn step_particle<T: Real>(
    d: &KDesign<T>,
    ph: &KPhysics<T>,
    p: &mut KParticle<T>,
    index: u32,
    bounce: u32,
) -> Flown<T> {
    randomise_launch(d, ph, p, index, bounce);
    fly_particle(d, ph, p, index, bounce)
}

/// [`step_particle`] after the launch randomisation: the flight from the launch velocity to
/// the next impact, and the bounce there. The cpu engine's bounce loop randomises a whole
/// bounce's launches first and then flies them (`run_particles`): the same operations per
/// particle, so the same bits, and the libm calls of the randomisation run back to back
/// instead of between two branchy flight searches (lunar batches −7 to −8 %, BENCHMARKS.md).
#[inline(always)]
pub fn fly_particle<T: Real>(
    d: &KDesign<T>,
    ph: &KPhysics<T>,
    p: &mut KParticle<T>,
    index: u32,
    bounce: u32,
) -> Flown<T> {
    let (hit, fl, piece_start) = if ph.sled_speed > T::zero() || ph.qd_step > T::zero() {
        first_hit_piecewise(d, ph, p, bounce)
    } else {
        let fl = Flight { p0: p.pos, v0: p.vel, g: ph.g, k: p.k_drag, drift: [T::zero(); 2] };
        (first_hit(d, ph, p, bounce), fl, T::zero())
    };
    land(d, ph, p, index, bounce, hit, &fl, piece_start)
}

/// The second half of [`fly_particle`]: the bounce at the flight's first impact `hit` (or
/// the particle's loss when there is none). `fl` is the flight (piece) the hit lies in and
/// `piece_start` the time that piece began. The cpu engine's vector search
/// (`lanes::first_hits`) finds eight particles' hits at once and lands each with this.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn land<T: Real>(
    d: &KDesign<T>,
    ph: &KPhysics<T>,
    p: &mut KParticle<T>,
    index: u32,
    bounce: u32,
    hit: Hit<T>,
    fl: &Flight<T>,
    piece_start: T,
) -> Flown<T> {
    let flown = Flown { from_tooth: p.tooth, from: p.pos, vel: p.vel, t: T::zero() };
    if !hit.found {
        p.state = STATE_LOST;
        return flown;
    }
    // restitution acts on the velocity relative to the (possibly moving) surface
    let v_air = fl.vel(hit.t - piece_start);
    let v_in = [v_air[0] + fl.drift[0], v_air[1] + fl.drift[1]];
    let n_true = normal_of(d, hit.surface);
    let mut v_rel_out = ph.restitution.bounce(v_in, n_true);
    if ph.scatter_sigma > T::zero() {
        // impact-scatter effect: the local normal is tilted by a drawn angle. The grain must
        // meet the tilted facet (arrive against it) and leave the true surface; a tilt it
        // cannot meet is drawn again, the shadow rule of rough-wall collision models (a grain
        // cannot strike a roughness facet's lee side: Sommerfeld & Huber 1999), up to
        // TILT_DRAWS times, then the untilted bounce. Without the second test a grazing
        // grain's rebound points into the surface, the next flight touches it at t = 0
        // (`contact`) and the grain stops dead. Keeping the untilted bounce instead of a
        // redraw biases the rough surface towards the smooth one, most at grazing impacts: it
        // could not fit an independent simulator's 15° scatter (25.8 %² left at the true σ,
        // 1.0 with the redraw; docs/diagnosis-report.md).
        for k in 0..TILT_DRAWS {
            let draw = if k == 0 { DRAW_SCATTER } else { DRAW_SCATTER_AGAIN + 2 * (k - 1) };
            let z = if ph.scatter_uniform {
                // uniform on [-√3, √3]: unit variance, like the normal draw
                T::c(3f64.sqrt() * (2.0 * uniform01(ph.seed, index, bounce, draw) - 1.0))
            } else {
                T::c(normal01(ph.seed, index, bounce, draw))
            };
            let (s, c) = (ph.scatter_sigma * z).ksin_cos();
            let tilted = [c * n_true[0] - s * n_true[1], s * n_true[0] + c * n_true[1]];
            if dot(v_in, tilted) < T::zero() {
                let out = ph.restitution.bounce(v_in, tilted);
                if dot(out, n_true) > T::zero() {
                    v_rel_out = out;
                    break;
                }
            }
        }
    }
    let v_out = [v_rel_out[0] - fl.drift[0], v_rel_out[1] - fl.drift[1]];
    settle(d, ph, p, &hit, v_out);
    Flown { t: hit.t, ..flown }
}

/// The end of [`land`]: the particle moves to its impact `hit` (found) and leaves it with
/// `v_out`; it rests when the hop was below the threshold (text mode).
#[inline(always)]
pub fn settle<T: Real>(d: &KDesign<T>, ph: &KPhysics<T>, p: &mut KParticle<T>, hit: &Hit<T>, v_out: [T; 2]) {
    p.hop = (hit.pos[0] - p.pos[0]).abs(); // Eq. 4.50, per particle
    p.clock = p.clock + hit.t;
    let back = offset(d, hit.tooth - p.tooth, [T::zero(), T::zero()]);
    p.pos = [hit.pos[0] - back[0], hit.pos[1] - back[1]];
    p.tooth = hit.tooth;
    p.vel = v_out;
    p.surface = hit.surface;
    p.bounces += 1;
    if p.bounces == 1 {
        p.first = offset(d, p.tooth, p.pos);
    }
    if ph.per_particle_rest && p.hop < ph.rest_threshold {
        p.state = STATE_RESTING;
    }
}

/// Threads per workgroup of the WGSL kernel (`WG` in particles.wgsl): the reduction's lanes.
pub const WG: usize = 64;

/// A position's index as i32, clamped to ±1e9 first. WGSL twin: `to_index`.
#[inline(always)]
pub fn to_index<T: Real>(x: T) -> i32 {
    x.max(T::c(-1e9)).min(T::c(1e9)).to_i64().unwrap_or(0) as i32
}

/// Eq. 4.56: the 1-based tooth (clamped to the conveyor) of a final position. WGSL twin:
/// `end_tooth`.
#[inline(always)]
pub fn end_tooth<T: Real>(d: &KDesign<T>, p: &KParticle<T>) -> i32 {
    let j = p.tooth + to_index(((p.pos[0] - d.p2[0]) / d.pitch[0]).floor()) + 1;
    j.clamp(1, d.teeth)
}

/// What the kernel reduces one design to: the twin of WGSL `Outcome` (less its padding).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct KOutcome<T> {
    pub iterations: u32,
    pub lost: u32,
    pub flying: u32,
    pub bounce_sum: u32,
    /// Sum over binned particles of (tooth - 1).
    pub advance_teeth: u32,
    /// Sum of credited distances, m (listing semantics).
    pub distance_sum: T,
}

/// Physical mode: follow one particle to rest (or loss, or `max_bounces` steps), as one
/// thread of WGSL `simulate_particles` does; returns the steps taken. `max_bounces` is the
/// WGSL uniform's `ph.max_bounces` (the kernel's physics record does not carry it). The
/// same particle as `run_particles` leaves it: the random draws are keyed by (particle,
/// bounce), not by the order particles are stepped in.
pub fn follow_particle<T: Real>(
    d: &KDesign<T>,
    ph: &KPhysics<T>,
    p: &mut KParticle<T>,
    index: u32,
    max_bounces: u32,
) -> u32 {
    let mut steps = 0;
    for bounce in 0..max_bounces {
        if p.state != STATE_FLYING {
            break;
        }
        step_particle(d, ph, p, index, bounce);
        steps = bounce + 1;
    }
    steps
}

/// Steps a particle took in [`follow_particle`], from what it left: one per impact, plus the
/// flight that lost it (WGSL `particle_steps`; `reduce_designs` takes the largest, at least 1,
/// as the iterations of the design's bounce loop).
pub fn particle_steps<T: Real>(p: &KParticle<T>) -> u32 {
    p.bounces + u32::from(p.state == STATE_LOST)
}

/// The reduction of one design, WGSL `reduce_design` (one thread per design, at the end of
/// `simulate` and in `reduce_designs`), with the same loops: lane `l` of [`WG`] takes
/// particles l, l + WG, ... and sums its own distances, then the lanes' sums are added in
/// lane order. Particles still flying with a hop below the rest threshold
/// are marked resting (listing mode: the loop stopped on the mean hop), as the kernel
/// writes them back. `histogram` (one bin per tooth) is added to.
pub fn reduce<T: Real>(
    d: &KDesign<T>,
    ph: &KPhysics<T>,
    particles: &mut [KParticle<T>],
    iterations: u32,
    histogram: &mut [u32],
) -> KOutcome<T> {
    let mut out = KOutcome { iterations, distance_sum: T::zero(), ..Default::default() };
    let mut lane_sums = [T::zero(); WG];
    for (lid, lane_sum) in lane_sums.iter_mut().enumerate() {
        let mut dist = T::zero();
        for p in particles.iter_mut().skip(lid).step_by(WG) {
            out.bounce_sum = out.bounce_sum.wrapping_add(p.bounces);
            if p.state == STATE_LOST {
                out.lost += 1;
                continue;
            }
            if p.state == STATE_FLYING && p.bounces > 0 && p.hop < ph.rest_threshold {
                p.state = STATE_RESTING;
            }
            if p.state == STATE_FLYING {
                out.flying += 1;
            }
            let j = end_tooth(d, p);
            histogram[(j - 1) as usize] += 1;
            out.advance_teeth = out.advance_teeth.wrapping_add((j - 1) as u32);
            if j > 1 {
                dist = dist + (d.pitch[0] * T::c((j - 1) as f64) + d.p4[0]); // listing D.1 l.347-351
            }
        }
        *lane_sum = dist;
    }
    for s in lane_sums {
        out.distance_sum = out.distance_sum + s;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::cpu::kernel_design;
    use crate::engine::Context;
    use crate::model::rng::uniform01;
    use crate::model::sampling::random_valid_designs;
    use crate::model::{prepare, Scenario};

    /// The tooth a one-at-a-time scan with `flies_over` stops at.
    fn one_by_one<T: Real>(d: &KDesign<T>, fl: &Flight<T>, j_from: i32, j_hi: i32, k: i32, x0: T, x_far: T) -> i32 {
        let mut j = j_from;
        while j <= j_hi && flies_over(d, fl, j - k, x0, x_far) {
            j += 1;
        }
        j
    }

    /// Flights from every launch point of random valid designs (slopes 0-40°, Moon and Earth
    /// with its drag), in random directions and at random speeds, each scanned from every
    /// tooth it can reach: the runs stop where `flies_over` one tooth at a time stops, in f64
    /// and in f32. Returns how many scans were compared, how many runs of four teeth
    /// `clears_run` passed within them (so that the runs are taken, not only tried), and how
    /// many runs of two teeth or more `vacuum_run` worked out on the Moon that `clears_run`
    /// passed and failed.
    fn compare_scans<T: Real>() -> (usize, usize, [usize; 2]) {
        let (mut compared, mut in_runs, mut worked_out) = (0, 0, [0; 2]);
        for (c, base) in [Scenario::lunar(), Scenario::earth()].into_iter().enumerate() {
            for (a, alpha) in [0.0, 20.0, 40.0].into_iter().enumerate() {
                let mut s = base.clone();
                s.environment.alpha_deg = alpha;
                s.sim.particles = 20;
                let ctx = Context::new(&s);
                let (g, k_drag) = (T::c(ctx.g), T::c(ctx.k_drag));
                for (n, design) in random_valid_designs(&s, 6, 11 + (3 * c + a) as u64).into_iter().enumerate() {
                    let prep = prepare(&s, &design).unwrap();
                    let d = kernel_design::<T>(&prep);
                    for (i, launch) in prep.launches.iter().enumerate() {
                        let key = (100 * n + i) as u32;
                        let angle = std::f64::consts::PI * (0.05 + 0.9 * uniform01(7, key, c as u32, 0));
                        let speed = 0.2 + 4.0 * uniform01(7, key, c as u32, 1);
                        let v0 = [T::c(speed * angle.cos()), T::c(speed * angle.sin())];
                        let fl =
                            Flight { p0: [T::c(launch[0]), T::c(launch[1])], v0, g, k: k_drag, drift: [T::zero(); 2] };
                        // x_far: somewhere along the flight, or its horizon far away
                        let t_far = T::c(2.0 * speed / ctx.g * uniform01(7, key, c as u32, 2));
                        let x_far = if i % 5 == 0 { T::c(1e3) } else { fl.pos(t_far)[0] };
                        let (x0, k) = (fl.p0[0], 0);
                        for j_from in -2..d.teeth.min(60) {
                            let j_hi = d.teeth - 1;
                            let expected = one_by_one(&d, &fl, j_from, j_hi, k, x0, x_far);
                            let found = next_tooth_to_search(&d, &fl, j_from, j_hi, k, x0, x_far);
                            assert_eq!(
                                found, expected,
                                "case {c}, slope {alpha}, design {n}, launch {i}, from {j_from}"
                            );
                            compared += 1;
                            // runs of four the scan could pass at once from here
                            let runs = (j_from..expected - 3).filter(|&j| clears_run(&d, &fl, j, j + 3, x0, x_far));
                            in_runs += runs.count();
                            // a vacuum flight's worked-out run from here, as the scan takes it
                            // after a tooth it flew over, passes the run test
                            if !fl.drag() && j_from >= 0 && j_from <= j_hi {
                                let (lo, hi) = if x_far >= x0 { (x0, x_far) } else { (x_far, x0) };
                                let m = vacuum_run(&d, &fl, &run_line(&d), j_from, j_hi, k, lo, hi);
                                if m >= 2 {
                                    let passed = clears_run(&d, &fl, j_from, (j_from + m - 1).min(j_hi), x0, x_far);
                                    worked_out[usize::from(!passed)] += 1;
                                }
                            }
                        }
                    }
                }
            }
        }
        (compared, in_runs, worked_out)
    }

    /// Impact scatter's shadow rule: a grain grazing the ramp at 5° meets a 15° scatter's
    /// first drawn tilt only about half the time (the other tilts face away from it, or send
    /// its rebound into the ramp); the tilts it cannot meet are drawn again, so nearly every
    /// impact is tilted, never into the true surface.
    #[test]
    fn a_tilt_the_grain_cannot_meet_is_drawn_again() {
        let s = Scenario::earth();
        let design = random_valid_designs(&s, 1, 3)[0];
        let prep = prepare(&s, &design).unwrap();
        let d = kernel_design::<f64>(&prep);
        let mut ph = crate::engine::cpu::kernel_physics::<f64>(&Context::new(&s));
        let n = normal_of(&d, SURFACE_RAMP);
        let (tangent, grazing) = ([n[1], -n[0]], 5f64.to_radians());
        let v_in =
            [grazing.cos() * tangent[0] - grazing.sin() * n[0], grazing.cos() * tangent[1] - grazing.sin() * n[1]];
        // a straight flight (no gravity, no drag) that strikes the ramp with v_in at t = 0.01
        let fl = Flight { p0: [0.0, 0.0], v0: v_in, g: 0.0, k: 0.0, drift: [0.0; 2] };
        let hit = Hit { found: true, t: 0.01, pos: [0.01 * v_in[0], 0.01 * v_in[1]], tooth: 0, surface: SURFACE_RAMP };
        let rebound = |ph: &KPhysics<f64>, index: u32| {
            let mut p = init_particle(&d, ph, [0.0, 0.0], index);
            p.vel = v_in;
            land(&d, ph, &mut p, index, 0, hit, &fl, 0.0);
            p.vel
        };
        let smooth = rebound(&ph, 0);
        ph.scatter_sigma = 15f64.to_radians();
        let (mut untilted, mut first_met, mut steeper, n_grains) = (0, 0, 0, 4000u32);
        for index in 0..n_grains {
            let out = rebound(&ph, index);
            assert!(dot(out, n) > 0.0, "grain {index}'s rebound {out:?} points into the ramp");
            untilted += usize::from(out == smooth);
            steeper += usize::from(dot(out, n) * dot(smooth, tangent) > dot(smooth, n) * dot(out, tangent));
            // whether the first draw alone was a tilt the grain could meet
            let z = normal01(ph.seed, index, 0, DRAW_SCATTER);
            let (sn, cs) = (ph.scatter_sigma * z).sin_cos();
            let tilted = [cs * n[0] - sn * n[1], sn * n[0] + cs * n[1]];
            first_met += usize::from(dot(v_in, tilted) < 0.0 && dot(ph.restitution.bounce(v_in, tilted), n) > 0.0);
        }
        let n_grains = n_grains as usize;
        assert!((n_grains / 4..3 * n_grains / 4).contains(&first_met), "the first tilt met {first_met} times");
        assert!(untilted * 100 < n_grains, "{untilted} of {n_grains} impacts kept the smooth bounce");
        // both ways, mostly steeper: the tilts that would flatten a grazing rebound further are
        // the ones it cannot meet
        assert!(steeper > n_grains / 2 && steeper < 19 * n_grains / 20, "{steeper} of {n_grains} left steeper");
    }

    #[test]
    fn the_run_scan_stops_where_the_one_by_one_scan_stops() {
        for (compared, runs, [passed, failed]) in [compare_scans::<f64>(), compare_scans::<f32>()] {
            assert!(compared > 40_000 && runs > compared, "{compared} scans, {runs} runs of four passed");
            // the worked-out runs are taken, and rarely cost a halving
            assert!(passed > 1_000 && failed * 100 < passed, "vacuum runs: {passed} passed, {failed} failed");
        }
    }
}
