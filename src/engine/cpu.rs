//! The `cpu` engine: the fast reference. Drives the kernel of `kernel.rs` over a design's
//! particles, bounce by bounce, in f64 (physics) or f32 (the GPU's precision).

use std::any::Any;

use super::kernel::*;
use super::lanes::{self, Lanes, MAX_LANES};
use super::{Context, FlightRecord, ParticleEngine, Run};
use crate::model::flight::Flight;
use crate::model::geometry::Profile;
use crate::model::outcome::{ParticleEnd, ParticleState};
use crate::model::real::Real;
use crate::model::rng::{DRAW_ANGLE, DRAW_SPEED};
use crate::model::{PhysicsMode, Prepared};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Precision {
    #[default]
    F64,
    F32,
}

#[derive(Clone, Copy, Debug, Default)]
pub struct CpuEngine {
    pub precision: Precision,
}

/// The flat per-design data of the kernel (the geometry part of the GPU's design record,
/// `GpuDesign`, whose physics part comes from `kernel_physics`).
pub fn kernel_design<T: Real>(prep: &Prepared) -> KDesign<T> {
    let p: &Profile = &prep.profile;
    let [nb, nr, nc] = p.normals();
    let v = |a: [f64; 2]| [T::c(a[0]), T::c(a[1])];
    let xs = [0.0, p.p2[0], p.p4[0]];
    KDesign {
        pitch: v(p.pitch),
        p2: v(p.p2),
        p4: v(p.p4),
        n_base: v(nb),
        n_ramp: v(nr),
        n_catch: v(nc),
        t_base: v([p.alpha.cos(), p.alpha.sin()]),
        pitch_len: T::c(p.pitch_len),
        base_length: T::c(prep.base_length),
        ext_min: T::c(xs.iter().cloned().fold(f64::INFINITY, f64::min)),
        ext_max: T::c(xs.iter().cloned().fold(f64::NEG_INFINITY, f64::max)),
        teeth: p.teeth as i32,
        launch_angle: T::c(prep.launch_angle),
        launch_sin_cos: T::c(prep.launch_angle).ksin_cos(),
        v0: T::c(prep.design.v0),
        stroke: T::c(prep.design.v0 * prep.design.v0 / (2.0 * prep.design.a)),
        fill_point: v(prep.fill.p_fill),
        fill_sin_cos: {
            // as `Fill::depth` computes it (host side, once per design)
            let (s, c) = prep.fill.surface_angle.sin_cos();
            (T::c(s), T::c(c))
        },
    }
}

/// Smallest hop that counts as an impact: the listing discards hits within 1e-3 mm of the
/// launch x (D.2 line 60). The text's model needs no such guard (the departure root is
/// removed analytically), so a grain in a corner meets the next wall at once and rests.
pub const LISTING_MIN_HOP_X: f64 = 1e-6;
pub const PHYSICAL_MIN_HOP: f64 = 0.0;

pub fn kernel_physics<T: Real>(ctx: &Context) -> KPhysics<T> {
    let listing = ctx.mode == PhysicsMode::Listing;
    KPhysics {
        g: T::c(ctx.g),
        k_drag: T::c(ctx.k_drag),
        restitution: ctx.restitution.cast(),
        randomise: ctx.randomise,
        band: T::c(ctx.band),
        seed: ctx.seed_word,
        rest_threshold: T::c(ctx.rest_threshold),
        min_hop: T::c(if listing { LISTING_MIN_HOP_X } else { PHYSICAL_MIN_HOP }),
        min_hop_horizontal: listing,
        per_particle_rest: !listing,
        scatter_sigma: T::c(ctx.effects.impact_scatter.map_or(0.0, |e| e.sigma_deg.to_radians())),
        launch_speed_spread: T::c(ctx.effects.launch_spread.map_or(0.0, |e| e.speed_spread)),
        launch_angle_sigma: T::c(ctx.effects.launch_spread.map_or(0.0, |e| e.angle_sigma_deg.to_radians())),
        size_sigma_ln: T::c(ctx.effects.polydisperse.map_or(0.0, |e| e.sigma_ln)),
        size_uniform: ctx.effects.polydisperse.is_some_and(|e| e.form == crate::model::effects::SizeForm::Uniform),
        sled_delay: T::c(ctx.effects.sled_motion.map_or(0.0, |e| e.delay_s)),
        sled_speed: T::c(ctx.effects.sled_motion.map_or(0.0, |e| e.return_speed_m_s)),
        sled_along_launch: ctx
            .effects
            .sled_motion
            .is_some_and(|e| e.direction == crate::model::effects::MotionDirection::Launch),
        scatter_uniform: ctx.effects.impact_scatter.is_some_and(|e| e.form == crate::model::effects::TiltForm::Uniform),
        // quadratic drag needs air: it replaces the linear drag where there is some
        qd_k0: T::c(ctx.effects.quadratic_drag.filter(|_| ctx.k_drag > 0.0).map_or(0.0, |e| e.coefficients().0)),
        qd_re_per_speed: T::c(ctx.effects.quadratic_drag.map_or(0.0, |e| e.coefficients().1)),
        qd_step: T::c(if ctx.effects.quadratic_drag.is_some() && ctx.k_drag > 0.0 {
            crate::model::effects::QUADRATIC_DRAG_STEP_S
        } else {
            0.0
        }),
        surface_loss: T::c(ctx.effects.fill_surface_loss.map_or(0.0, |e| e.speed_loss)),
        surface_decay: T::c(ctx.effects.fill_surface_loss.map_or(1.0, |e| e.decay_depth_m)),
    }
}

/// A hit the lanes found (in f64) as the kernel's precision `T` holds it (`T` is f64
/// wherever the lanes run, so this copies).
fn hit_from_lanes<T: Real>(h: &Hit<f64>) -> Hit<T> {
    Hit { found: h.found, t: T::c(h.t), pos: [T::c(h.pos[0]), T::c(h.pos[1])], tooth: h.tooth, surface: h.surface }
}

fn state_of(code: u32) -> ParticleState {
    match code {
        STATE_RESTING => ParticleState::Resting,
        STATE_LOST => ParticleState::Lost,
        _ => ParticleState::Flying,
    }
}

/// The bounce loop (4.2.4) over one design, generic over precision: every particle as the
/// kernel leaves it, and the iterations run. The twin of the bounce loop of WGSL `simulate`
/// (its reduction's twin is `kernel::reduce`). `lanes`: the SIMD lanes that search flights
/// of the text's physics in f64 several at a time and draw the launch factors sixteen at a
/// time (`lanes::Lanes::of` the engine's path; None: one particle at a time), to the same
/// bits.
#[inline(always)]
pub fn run_particles<T: Real>(
    prep: &Prepared,
    ctx: &Context,
    lanes: Option<Lanes>,
    mut trace: Option<&mut Vec<FlightRecord>>,
) -> (Vec<KParticle<T>>, u32) {
    let d = kernel_design::<T>(prep);
    let ph = kernel_physics::<T>(ctx);
    let mut parts: Vec<KParticle<T>> = prep
        .launches
        .iter()
        .enumerate()
        .map(|(i, l)| init_particle(&d, &ph, [T::c(l[0]), T::c(l[1])], i as u32))
        .collect();
    // flights of the text's physics in f64 (the lunar and Earth batches) are searched
    // several at a time on the SIMD lanes, to the same bits
    let any_d: &dyn Any = &d;
    let any_ph: &dyn Any = &ph;
    let on_lanes = match (lanes, any_d.downcast_ref::<KDesign<f64>>(), any_ph.downcast_ref::<KPhysics<f64>>()) {
        (Some(lanes), Some(d64), Some(ph64)) => Some((lanes, d64, ph64)),
        _ => None,
    };
    let vector = on_lanes.filter(|(_, _, ph64)| lanes::applies(ph64));
    // flights in pieces (sled motion, quadratic drag) likewise, piece by piece
    let piecewise = on_lanes.filter(|(_, _, ph64)| lanes::applies_piecewise(ph64));
    // and the launch factors' draws of every engine run are made sixteen at a time
    let draw_lanes = lanes;
    // the indices of the particles still flying, for the lanes
    let mut to_fly: Vec<u32> = Vec::with_capacity(parts.len());
    let mut iterations = 0;
    for bounce in 0..ctx.max_bounces {
        let (mut flying, mut hop_sum, mut hop_n) = (0usize, 0.0f64, 0usize);
        if draw_lanes.is_some() {
            to_fly.clear();
            to_fly.extend((0..parts.len() as u32).filter(|&i| parts[i as usize].state == STATE_FLYING));
        }
        // every launch of this bounce first, then every flight (`fly_particle` says why)
        let factors_drawn = match ph.randomise {
            RANDOMISE_EVERY_LAUNCH => true,
            RANDOMISE_FIRST_LAUNCH => bounce == 0,
            _ => false,
        };
        if let (Some(draws), true) = (draw_lanes, factors_drawn) {
            // the launch factors' draws sixteen particles at a time, and in f64 the launches
            // on the lanes too (unless the launch spread draws more)
            let launch_lanes = vector.filter(|(_, _, ph64)| lanes::randomises(ph64));
            for group in to_fly.chunks(16) {
                let angle = draws.uniforms(ph.seed, group, bounce, DRAW_ANGLE);
                let speed = draws.uniforms(ph.seed, group, bounce, DRAW_SPEED);
                if let Some((lanes, d64, ph64)) = launch_lanes {
                    let any_parts: &mut dyn Any = &mut parts;
                    let parts64 = any_parts.downcast_mut::<Vec<KParticle<f64>>>().expect("T is f64 here");
                    for (h, part) in group.chunks(lanes.width()).enumerate() {
                        let from = h * lanes.width();
                        lanes.randomise_launches(d64, ph64, parts64, part, &angle[from..], &speed[from..]);
                    }
                    continue;
                }
                for (l, &i) in group.iter().enumerate() {
                    randomise_launch_drawn(&d, &ph, &mut parts[i as usize], i, bounce, Some([angle[l], speed[l]]));
                }
            }
        } else {
            for (i, p) in parts.iter_mut().enumerate() {
                if p.state == STATE_FLYING {
                    randomise_launch(&d, &ph, p, i as u32, bounce);
                }
            }
        }
        let mut record = |i: usize, p: &KParticle<T>, flown: Flown<T>| {
            if let Some(tr) = trace.as_deref_mut() {
                let origin = [T::c(flown.from_tooth as f64) * d.pitch[0], T::c(flown.from_tooth as f64) * d.pitch[1]];
                tr.push(FlightRecord {
                    particle: i as u32,
                    bounce,
                    from: [(origin[0] + flown.from[0]).f64(), (origin[1] + flown.from[1]).f64()],
                    vel: [flown.vel[0].f64(), flown.vel[1].f64()],
                    t: flown.t.f64(),
                    state: state_of(p.state),
                });
            }
            if p.state != STATE_LOST {
                hop_sum += p.hop.f64();
                hop_n += 1;
            }
            if p.state == STATE_FLYING {
                flying += 1;
            }
        };
        if let Some((lanes, d64, ph64)) = vector {
            for group in to_fly.chunks(lanes.width()) {
                let any_parts: &dyn Any = &parts;
                let parts64 = any_parts.downcast_ref::<Vec<KParticle<f64>>>().expect("T is f64 here");
                let hits = lanes.first_hits(d64, ph64, parts64, group, bounce);
                // the restitution law on the lanes too, unless impact scatter draws a tilt
                // per grain (then `land`, one grain at a time)
                let bounced = (ph64.scatter_sigma == 0.0).then(|| {
                    let (mut v_in, mut normal) = ([[0.0; MAX_LANES]; 2], [[0.0; MAX_LANES]; 2]);
                    for (l, (h, &i)) in hits.iter().zip(group).enumerate() {
                        // as `land`: the flight's velocity at the impact, plus a zero drift
                        let p = &parts64[i as usize];
                        let fl = Flight { p0: p.pos, v0: p.vel, g: ph64.g, k: p.k_drag, drift: [0.0; 2] };
                        let v = fl.vel(h.t);
                        let n = normal_of(d64, h.surface);
                        (v_in[0][l], v_in[1][l]) = (v[0] + 0.0, v[1] + 0.0);
                        (normal[0][l], normal[1][l]) = (n[0], n[1]);
                    }
                    lanes.bounce_velocities(&ph64.restitution, &v_in, &normal)
                });
                for (l, (h, &i)) in hits.iter().zip(group).enumerate() {
                    let p = &mut parts[i as usize];
                    let hit = hit_from_lanes(h);
                    let flown = if let (Some(out), true) = (&bounced, hit.found) {
                        // as `land`, with the rebound from the lanes (less the zero drift)
                        let flown = Flown { from_tooth: p.tooth, from: p.pos, vel: p.vel, t: hit.t };
                        settle(&d, &ph, p, &hit, [T::c(out[0][l] - 0.0), T::c(out[1][l] - 0.0)]);
                        flown
                    } else {
                        let fl = Flight { p0: p.pos, v0: p.vel, g: ph.g, k: p.k_drag, drift: [T::zero(); 2] };
                        land(&d, &ph, p, i, bounce, hit, &fl, T::zero())
                    };
                    record(i as usize, p, flown);
                }
            }
        } else if let Some((lanes, d64, ph64)) = piecewise {
            // as `fly_particle`: each flight's pieces searched (on the lanes), then the landing
            let any_parts: &dyn Any = &parts;
            let parts64 = any_parts.downcast_ref::<Vec<KParticle<f64>>>().expect("T is f64 here");
            let flights = lanes.first_hits_piecewise(d64, ph64, parts64, &to_fly, bounce);
            for ((h, fl, start), &i) in flights.into_iter().zip(&to_fly) {
                let p = &mut parts[i as usize];
                let hit = hit_from_lanes(&h);
                let fl = Flight {
                    p0: [T::c(fl.p0[0]), T::c(fl.p0[1])],
                    v0: [T::c(fl.v0[0]), T::c(fl.v0[1])],
                    g: T::c(fl.g),
                    k: T::c(fl.k),
                    drift: [T::c(fl.drift[0]), T::c(fl.drift[1])],
                };
                let flown = land(&d, &ph, p, i, bounce, hit, &fl, T::c(start));
                record(i as usize, p, flown);
            }
        } else {
            for (i, p) in parts.iter_mut().enumerate() {
                if p.state == STATE_FLYING {
                    let flown = fly_particle(&d, &ph, p, i as u32, bounce);
                    record(i, p, flown);
                }
            }
        }
        iterations = bounce + 1;
        if ph.per_particle_rest {
            if flying == 0 {
                break;
            }
        } else if hop_n == 0 || hop_sum / (hop_n as f64) < ctx.rest_threshold {
            // Listing D.1 lines 328-336: all particles gone, or mean hop below l_limit (Eq. 4.50).
            break;
        }
    }
    (parts, iterations)
}

/// [`run_particles`] with each particle's end state, in f64.
#[inline(always)]
pub fn run_design<T: Real>(
    prep: &Prepared,
    ctx: &Context,
    lanes: Option<Lanes>,
    trace: Option<&mut Vec<FlightRecord>>,
) -> Run {
    let d = kernel_design::<T>(prep);
    let (parts, iterations) = run_particles::<T>(prep, ctx, lanes, trace);
    let particles = parts
        .iter()
        .map(|p| {
            let mut state = state_of(p.state);
            if state == ParticleState::Flying && p.bounces > 0 && p.hop.f64() < ctx.rest_threshold {
                state = ParticleState::Resting; // listing mode: hopping below l_limit when the loop stopped
            }
            let end = if state == ParticleState::Lost {
                [f64::NAN, f64::NAN]
            } else {
                let o = [T::c(p.tooth as f64) * d.pitch[0], T::c(p.tooth as f64) * d.pitch[1]];
                [(o[0] + p.pos[0]).f64(), (o[1] + p.pos[1]).f64()]
            };
            ParticleEnd {
                state,
                end,
                first_impact: if p.bounces > 0 { Some([p.first[0].f64(), p.first[1].f64()]) } else { None },
                bounces: p.bounces,
            }
        })
        .collect();
    Run { particles, iterations }
}

/// The lanes the engine's path takes ([`Lanes::of`] the path `crate::simd` chose; None on
/// the scalar path).
pub fn engine_lanes() -> Option<Lanes> {
    Lanes::of(crate::simd::selected())
}

impl ParticleEngine for CpuEngine {
    fn name(&self) -> &'static str {
        match self.precision {
            Precision::F64 => "cpu",
            Precision::F32 => "cpu-f32",
        }
    }
    fn run(&self, prep: &Prepared, ctx: &Context, trace: Option<&mut Vec<FlightRecord>>) -> Run {
        // the path this CPU takes, or the one SAWTOOTH_SIMD names (`crate::simd`)
        let lanes = engine_lanes();
        #[cfg(target_arch = "x86_64")]
        if crate::simd::selected().x86_64_v3() {
            // SAFETY: the CPU has every feature the function is compiled for (the path is one
            // this CPU has).
            return match self.precision {
                Precision::F64 => unsafe { x86_64_v3::run_design::<f64>(prep, ctx, lanes, trace) },
                Precision::F32 => unsafe { x86_64_v3::run_design::<f32>(prep, ctx, lanes, trace) },
            };
        }
        match self.precision {
            Precision::F64 => run_design::<f64>(prep, ctx, lanes, trace),
            Precision::F32 => run_design::<f32>(prep, ctx, lanes, trace),
        }
    }
}

/// The bounce loop compiled a second time for x86-64-v3 (see [`crate::simd`]): every kernel
/// function is inlined into [`x86_64_v3::run_design`], so all of it gets the features; the
/// results are the same to the bit (tested below).
#[cfg(target_arch = "x86_64")]
mod x86_64_v3 {
    use super::*;

    #[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,movbe,popcnt,sse3,ssse3,sse4.1,sse4.2")]
    pub fn run_design<T: Real>(
        prep: &Prepared,
        ctx: &Context,
        lanes: Option<Lanes>,
        trace: Option<&mut Vec<FlightRecord>>,
    ) -> Run {
        super::run_design::<T>(prep, ctx, lanes, trace)
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use crate::model::effects::{ImpactScatter, LaunchSpread, Polydisperse, SizeForm, TiltForm};
    use crate::model::sampling::random_valid_designs;
    use crate::model::{prepare, Scenario};

    /// A particle's end as bits: state, end point, first impact, bounces.
    type EndBits = (ParticleState, [u64; 2], Option<[u64; 2]>, u32);

    fn bits(run: &Run) -> Vec<EndBits> {
        let b = |v: [f64; 2]| [v[0].to_bits(), v[1].to_bits()];
        run.particles.iter().map(|p| (p.state, b(p.end), p.first_impact.map(b), p.bounces)).collect()
    }

    /// The x86-64-v3 compilation of the bounce loop leaves every particle as the baseline
    /// compilation does, to the bit: both environments and modes, with the effects of both
    /// engines on, in f64 and f32.
    #[test]
    fn the_x86_64_v3_build_gives_the_baseline_bits() {
        if !crate::simd::Simd::Avx2.supported() {
            eprintln!("skipped: this CPU lacks x86-64-v3, so only the baseline build runs here");
            return;
        }
        // the scalar kernel's flight search, and the lanes' where the CPU has them
        let lanes = Lanes::of(crate::simd::Simd::Avx2);
        let with_effects = |mut s: Scenario| {
            s.effects.impact_scatter = Some(ImpactScatter { sigma_deg: 3.0, form: TiltForm::default() });
            s.effects.launch_spread = Some(LaunchSpread { speed_spread: 0.2, angle_sigma_deg: 5.0 });
            s.effects.polydisperse = Some(Polydisperse { sigma_ln: 0.4, form: SizeForm::default() });
            s
        };
        let mut listing_mode = Scenario::lunar();
        listing_mode.mode = PhysicsMode::Listing;
        let scenarios = [
            Scenario::lunar(),
            Scenario::earth(),
            listing_mode,
            with_effects(Scenario::lunar()),
            with_effects(Scenario::earth()),
        ];
        let mut flights = 0;
        for (i, mut s) in scenarios.into_iter().enumerate() {
            s.sim.particles = 200;
            let ctx = Context::new(&s);
            for d in random_valid_designs(&s, 6, 40 + i as u64) {
                let prep = prepare(&s, &d).unwrap();
                // SAFETY: the CPU has x86-64-v3 (checked above).
                let (v3, v3_f32) = unsafe {
                    (
                        x86_64_v3::run_design::<f64>(&prep, &ctx, None, None),
                        x86_64_v3::run_design::<f32>(&prep, &ctx, lanes, None),
                    )
                };
                let (base, base_f32) =
                    (run_design::<f64>(&prep, &ctx, None, None), run_design::<f32>(&prep, &ctx, None, None));
                assert_eq!(bits(&v3), bits(&base), "scenario {i}, design {d:?}");
                assert_eq!(bits(&v3_f32), bits(&base_f32), "f32: scenario {i}, design {d:?}");
                assert_eq!((v3.iterations, v3_f32.iterations), (base.iterations, base_f32.iterations));
                flights += base.particles.iter().map(|p| p.bounces as usize).sum::<usize>();
            }
        }
        assert!(flights > 10_000, "the batches flew {flights} flights");
    }
}
