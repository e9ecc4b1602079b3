//! The `listing` engine: a port of listing D.1's bounce loop and D.2's intersection search.
//! Every segment of every tooth is scanned, a sign change of (trajectory - segment) is
//! bracketed on the clamped x-interval and refined by 40-step bisection. It works in mm and
//! mm/s like the listing, so its tolerances (1e-6 mm clamp, 1e-3 mm minimum hop, 1e-5
//! bisection tolerance, 1e-3 mm drag-asymptote margin) mean what they meant there.
//! It is the speed baseline and the reference for compatibility mode.

use super::cpu::kernel_design;
use super::kernel::{randomise_launch, KParticle, KPhysics, SURFACE_BASE, SURFACE_CATCH, SURFACE_NONE, SURFACE_RAMP};
use super::{Context, FlightRecord, ParticleEngine, Run};
use crate::model::outcome::{ParticleEnd, ParticleState};
use crate::model::{PhysicsMode, Prepared};

#[derive(Clone, Copy, Debug, Default)]
pub struct ListingEngine;

type P = [f64; 2];

/// MATLAB's sign: -1, 0 or 1.
fn sign(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

struct Traj {
    x0: f64,
    y0: f64,
    delta: f64,
    vx: f64,
    g: f64,
    k: f64,
}

impl Traj {
    /// D.2 get_diff: trajectory minus segment line at x (Eq. 4.52 / 4.55).
    fn diff(&self, x: f64, a: P, m_s: f64) -> f64 {
        let y_traj = if self.k < 1e-6 {
            let kk = self.g / (2.0 * self.vx * self.vx);
            self.y0 + (x - self.x0) * self.delta.tan() - kk * (x - self.x0).powi(2)
        } else {
            let term1 = self.delta.tan() + self.g / (self.k * self.vx);
            let term2 = self.g / (self.k * self.k);
            let val_log = 1.0 - self.k * (x - self.x0) / self.vx;
            if val_log < 1e-9 {
                -1e10
            } else {
                self.y0 + term1 * (x - self.x0) + term2 * val_log.ln()
            }
        };
        y_traj - (m_s * (x - a[0]) + a[1])
    }

    /// D.2 bisection_solver.
    fn bisect(&self, mut lo: f64, mut hi: f64, a: P, m_s: f64) -> f64 {
        let tol = 1e-5;
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            let f_lo = self.diff(lo, a, m_s);
            let f_mid = self.diff(mid, a, m_s);
            if f_mid.abs() < tol || (hi - lo) < tol {
                return mid;
            }
            if sign(f_mid) == sign(f_lo) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// D.2 intersection_points for one particle over a list of segments: the hit closest in x.
    fn closest_hit(&self, segs: impl Iterator<Item = (P, P)>) -> Option<P> {
        let mut best: Option<P> = None;
        for (a, b) in segs {
            let m_s = (b[1] - a[1]) / (b[0] - a[0]);
            let mut x_start = a[0].min(b[0]);
            let mut x_end = a[0].max(b[0]);
            if self.vx > 0.0 {
                x_start = x_start.max(self.x0 + 1e-6);
            } else {
                x_end = x_end.min(self.x0 - 1e-6);
            }
            if x_start >= x_end || self.vx.abs() < 1e-6 {
                continue;
            }
            if self.k > 1e-6 {
                let asym = self.x0 + self.vx / self.k;
                if self.vx > 0.0 {
                    if x_start > asym - 1e-3 {
                        continue;
                    }
                    x_end = x_end.min(asym - 1e-3);
                } else {
                    if x_end < asym + 1e-3 {
                        continue;
                    }
                    x_start = x_start.max(asym + 1e-3);
                }
            }
            let ds = self.diff(x_start, a, m_s);
            let de = self.diff(x_end, a, m_s);
            if ds.is_nan() || de.is_nan() || sign(ds) == sign(de) {
                continue;
            }
            let x = self.bisect(x_start, x_end, a, m_s);
            let ahead = (self.vx >= 0.0 && x > self.x0) || (self.vx < 0.0 && x < self.x0);
            if ahead && (x - self.x0).abs() > 1e-3 {
                let closer = best.is_none_or(|p| (x - self.x0).abs() < (p[0] - self.x0).abs());
                if closer {
                    best = Some([x, m_s * (x - a[0]) + a[1]]);
                }
            }
        }
        best
    }
}

struct State {
    pos: P,
    v: f64,
    delta: f64,
    surface: u32,
    lost: bool,
    resting: bool,
    bounces: u32,
    hop: f64,
    first: Option<P>,
}

impl ParticleEngine for ListingEngine {
    fn name(&self) -> &'static str {
        "listing"
    }

    fn run(&self, prep: &Prepared, ctx: &Context, mut trace: Option<&mut Vec<FlightRecord>>) -> Run {
        let mm = 1e3;
        let pr = &prep.profile;
        let n = pr.teeth as usize;
        let pt = |j: usize, off: P| -> P {
            [(pr.pitch[0] * j as f64 + off[0]) * mm, (pr.pitch[1] * j as f64 + off[1]) * mm]
        };
        let p1: Vec<P> = (0..n).map(|j| pt(j, [0.0, 0.0])).collect();
        let p2: Vec<P> = (0..n).map(|j| pt(j, pr.p2)).collect();
        let p4: Vec<P> = (0..n).map(|j| pt(j, pr.p4)).collect();
        let base_end = [prep.base_length * pr.alpha.cos() * mm, prep.base_length * pr.alpha.sin() * mm];
        let [nb, nr, nc] = pr.normals();
        let g_mm = ctx.g * mm;
        let k = ctx.k_drag;
        let kd = kernel_design::<f64>(prep); // normals for the shared randomisation
        let kph = KPhysics {
            g: ctx.g,
            k_drag: k,
            restitution: ctx.restitution,
            randomise: ctx.randomise,
            band: ctx.band,
            seed: ctx.seed_word,
            rest_threshold: ctx.rest_threshold,
            min_hop: 0.0,
            min_hop_horizontal: true,
            per_particle_rest: ctx.mode == PhysicsMode::Physical,
            // effects are refused for this engine (engine::make_engine_for)
            scatter_sigma: 0.0,
            launch_speed_spread: 0.0,
            launch_angle_sigma: 0.0,
            size_sigma_ln: 0.0,
            size_uniform: false,
            sled_delay: 0.0,
            sled_speed: 0.0,
            sled_along_launch: false,
            scatter_uniform: false,
            qd_k0: 0.0,
            qd_re_per_speed: 0.0,
            qd_step: 0.0,
            surface_loss: 0.0,
            surface_decay: 1.0,
        };
        let mut st: Vec<State> = prep
            .launches
            .iter()
            .map(|l| State {
                pos: [l[0] * mm, l[1] * mm],
                v: prep.design.v0 * mm,
                delta: prep.launch_angle,
                surface: SURFACE_NONE,
                lost: false,
                resting: false,
                bounces: 0,
                hop: f64::NAN,
                first: None,
            })
            .collect();
        let rest_mm = ctx.rest_threshold * mm;
        let mut iterations = 0;
        for bounce in 0..ctx.max_bounces {
            let (mut active, mut hop_sum, mut hop_n) = (0usize, 0.0, 0usize);
            for (i, s) in st.iter_mut().enumerate() {
                if s.lost || s.resting {
                    continue;
                }
                // D.3 randomisation (shared with the cpu kernel so both draw the same numbers)
                let mut kp = KParticle {
                    vel: [s.v * s.delta.cos(), s.v * s.delta.sin()],
                    surface: s.surface,
                    ..Default::default()
                };
                randomise_launch(&kd, &kph, &mut kp, i as u32, bounce);
                s.v = kp.vel[0].hypot(kp.vel[1]);
                s.delta = kp.vel[1].atan2(kp.vel[0]);
                if s.delta < 0.0 {
                    s.delta += 2.0 * std::f64::consts::PI;
                }
                let vx = s.v * s.delta.cos();
                let tr = Traj { x0: s.pos[0], y0: s.pos[1], delta: s.delta, vx, g: g_mm, k };
                // D.1 lines 221-233: ramp, catch (tooth 1's skipped on the first flight), base.
                let ramp = tr.closest_hit((0..n).map(|j| (p1[j], p2[j])));
                let c0 = if bounce == 0 { 1 } else { 0 };
                let catch = tr.closest_hit((c0..n).map(|j| (p2[j], p4[j])));
                let base = tr.closest_hit(std::iter::once((p1[0], base_end)));
                // D.1 lines 236-266: first along the flight direction.
                let mut pick: Option<(P, u32)> = None;
                for (h, surf) in [(ramp, SURFACE_RAMP), (catch, SURFACE_CATCH), (base, SURFACE_BASE)] {
                    if let Some(h) = h {
                        let better = match pick {
                            None => true,
                            Some((b, _)) => {
                                if vx > 0.0 {
                                    h[0] < b[0]
                                } else {
                                    h[0] > b[0]
                                }
                            }
                        };
                        if better {
                            pick = Some((h, surf));
                        }
                    }
                }
                let from = s.pos;
                let launch_vel = [s.v * s.delta.cos() / mm, s.v * s.delta.sin() / mm];
                let Some((hit, surf)) = pick else {
                    s.lost = true;
                    if let Some(t) = trace.as_deref_mut() {
                        t.push(FlightRecord {
                            particle: i as u32,
                            bounce,
                            from: [from[0] / mm, from[1] / mm],
                            vel: launch_vel,
                            t: 0.0,
                            state: ParticleState::Lost,
                        });
                    }
                    continue;
                };
                // D.1 lines 279-296: impact velocity from the flight time.
                let dx = hit[0] - s.pos[0];
                let (t, v_in) = if k < 1e-6 {
                    let t = dx / vx;
                    (t, [vx, s.v * s.delta.sin() - g_mm * t])
                } else {
                    let t = -(1.0 - dx * k / vx).ln() / k;
                    let e = (-k * t).exp();
                    (t, [vx * e, -g_mm / k + (s.v * s.delta.sin() + g_mm / k) * e])
                };
                let n_vec = match surf {
                    SURFACE_RAMP => nr,
                    SURFACE_CATCH => nc,
                    _ => nb,
                };
                // The restitution law works in SI (v_limit is m/s; erratum 6's unit trap).
                let v_out = ctx.restitution.bounce([v_in[0] / mm, v_in[1] / mm], n_vec);
                let v_out = [v_out[0] * mm, v_out[1] * mm];
                s.v = v_out[0].hypot(v_out[1]);
                s.delta = v_out[1].atan2(v_out[0]);
                if s.delta < 0.0 {
                    s.delta += 2.0 * std::f64::consts::PI;
                }
                s.hop = dx.abs();
                s.pos = hit;
                s.surface = surf;
                s.bounces += 1;
                if s.first.is_none() {
                    s.first = Some([hit[0] / mm, hit[1] / mm]);
                }
                if kph.per_particle_rest && s.hop < rest_mm {
                    s.resting = true;
                }
                hop_sum += s.hop;
                hop_n += 1;
                if !s.resting {
                    active += 1;
                }
                if let Some(tr) = trace.as_deref_mut() {
                    let state = if s.resting { ParticleState::Resting } else { ParticleState::Flying };
                    tr.push(FlightRecord {
                        particle: i as u32,
                        bounce,
                        from: [from[0] / mm, from[1] / mm],
                        vel: launch_vel,
                        t,
                        state,
                    });
                }
            }
            iterations = bounce + 1;
            if kph.per_particle_rest {
                if active == 0 {
                    break;
                }
            } else if hop_n == 0 || hop_sum / (hop_n as f64) < rest_mm {
                break; // D.1 lines 328-336
            }
        }
        let particles = st
            .iter()
            .map(|s| {
                let state = if s.lost {
                    ParticleState::Lost
                } else if s.resting || (s.bounces > 0 && s.hop < rest_mm) {
                    ParticleState::Resting
                } else {
                    ParticleState::Flying
                };
                ParticleEnd {
                    state,
                    end: if s.lost { [f64::NAN; 2] } else { [s.pos[0] / mm, s.pos[1] / mm] },
                    first_impact: s.first,
                    bounces: s.bounces,
                }
            })
            .collect();
        Run { particles, iterations }
    }
}
