//! The `cpu` engine: the fast reference. Drives the kernel of `kernel.rs` over a design's
//! particles, bounce by bounce, in f64 (physics) or f32 (the GPU's precision).

use super::kernel::*;
use super::{Context, FlightRecord, ParticleEngine, Run};
use crate::model::geometry::Profile;
use crate::model::outcome::{ParticleEnd, ParticleState};
use crate::model::real::Real;
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
        v0: T::c(prep.design.v0),
        stroke: T::c(prep.design.v0 * prep.design.v0 / (2.0 * prep.design.a)),
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
    }
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
/// (its reduction's twin is `kernel::reduce`).
pub fn run_particles<T: Real>(
    prep: &Prepared,
    ctx: &Context,
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
    let mut iterations = 0;
    for bounce in 0..ctx.max_bounces {
        let (mut flying, mut hop_sum, mut hop_n) = (0usize, 0.0f64, 0usize);
        for (i, p) in parts.iter_mut().enumerate() {
            if p.state != STATE_FLYING {
                continue;
            }
            let flown = step_particle(&d, &ph, p, i as u32, bounce);
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
pub fn run_design<T: Real>(prep: &Prepared, ctx: &Context, trace: Option<&mut Vec<FlightRecord>>) -> Run {
    let d = kernel_design::<T>(prep);
    let (parts, iterations) = run_particles::<T>(prep, ctx, trace);
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

impl ParticleEngine for CpuEngine {
    fn name(&self) -> &'static str {
        match self.precision {
            Precision::F64 => "cpu",
            Precision::F32 => "cpu-f32",
        }
    }
    fn run(&self, prep: &Prepared, ctx: &Context, trace: Option<&mut Vec<FlightRecord>>) -> Run {
        match self.precision {
            Precision::F64 => run_design::<f64>(prep, ctx, trace),
            Precision::F32 => run_design::<f32>(prep, ctx, trace),
        }
    }
}
