//! GPU vs CPU conformance (issue 3 §2). Random valid designs from the optimisation bounds,
//! both environments, drag on and off.
//!
//! - Per particle, GPU against the `cpu` engine in f32 (the same arithmetic): first impact
//!   point within `first_impact_tol_m`, final tooth and state equal for at least
//!   `min_particle_agreement` of the particles.
//! - Per design, GPU against the `cpu` engine in f64 (the physics reference): distribution
//!   L1 distance, d_avg and lost fraction, judged on their mean over designs (single designs
//!   can be chaotic: one grazing impact changes a whole bounce chain).

use serde::Serialize;

use super::cpu::{CpuEngine, Precision};
use super::gpu::GpuEngine;
use super::{Context, ParticleEngine};
use crate::model::design::DesignRow;
use crate::model::outcome::{end_tooth, summarise, ParticleEnd};
use crate::model::sampling::random_valid_designs;
use crate::model::{prepare, ParticleState, Prepared, Scenario};

#[derive(Clone, Debug, Serialize)]
pub struct Tolerances {
    /// First impacts of GPU and CPU-f32 agree to this distance, m (1e-3 mm).
    pub first_impact_tol_m: f64,
    /// Share of first impacts that must meet `first_impact_tol_m`.
    pub min_first_impact_agreement: f64,
    /// Share of particles whose final tooth and state must agree.
    pub min_particle_agreement: f64,
    /// Mean over designs of the L1 distance between the GPU and CPU-f64 distributions.
    pub max_mean_distribution_l1: f64,
    /// Mean over designs of |d_avg(GPU) - d_avg(CPU-f64)|, m.
    pub max_mean_d_avg_diff_m: f64,
    /// Mean over designs of |lost(GPU) - lost(CPU-f64)|.
    pub max_mean_lost_diff: f64,
}

impl Default for Tolerances {
    fn default() -> Self {
        Tolerances {
            first_impact_tol_m: 1e-6,
            min_first_impact_agreement: 0.999,
            min_particle_agreement: 0.98,
            max_mean_distribution_l1: 0.04,
            max_mean_d_avg_diff_m: 0.002,
            max_mean_lost_diff: 0.01,
        }
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct Mismatch {
    pub scenario: String,
    /// The design, in user units with the columns' names (`l_c_mm` … `a_m_s2`).
    pub design: DesignRow,
    pub particle: usize,
    pub what: String,
}

#[derive(Clone, Debug, Serialize)]
pub struct ScenarioReport {
    pub scenario: String,
    pub designs: usize,
    pub particles: usize,
    pub first_impacts_compared: usize,
    pub first_impacts_within_tol: usize,
    pub max_first_impact_diff_m: f64,
    pub tooth_and_state_agree: usize,
    pub mean_distribution_l1: f64,
    pub max_distribution_l1: f64,
    pub mean_d_avg_diff_m: f64,
    pub mean_lost_diff: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub device: String,
    pub tolerances: Tolerances,
    pub scenarios: Vec<ScenarioReport>,
    /// The worst per-particle mismatches (largest first-impact differences first).
    pub worst: Vec<Mismatch>,
    pub failures: Vec<String>,
    pub passed: bool,
}

/// A tangential table of the DEM restitution law (`ContactLaw::Dem`) for the conformance
/// cases: single impacts in LIGGGHTS at the lunar preset's contact (k_elastic 0.872, μ 0.106,
/// rolling friction 0.1), rounded: sliding (1 − 1/ψ) above ψ ≈ 0.7, tangential rebound below.
pub const EXAMPLE_DEM_TANGENTIAL: [f64; crate::model::collision::TANGENTIAL_NODES] =
    [-0.91, -0.91, -0.70, -0.33, 0.0, 0.20, 0.33, 0.50, 0.665, 0.75, 0.833, 0.875];

/// The conformance scenarios of an environment list: each with drag on and off, and with
/// drag off under the DEM's restitution law.
pub fn scenarios(envs: &[Scenario], particles: u32) -> Vec<(String, Scenario)> {
    let mut out = Vec::new();
    for base in envs {
        let name = if base.environment.g < 5.0 { "lunar" } else { "earth" };
        for drag in [false, true] {
            let mut s = base.clone();
            s.sim.particles = particles;
            s.environment.k_drag = if drag { Some(base.environment.k_drag.unwrap_or(5.439)) } else { None };
            out.push((format!("{name}, drag {}", if drag { "on" } else { "off" }), s));
        }
        if base.mode == crate::model::PhysicsMode::Physical {
            let mut s = base.clone();
            s.sim.particles = particles;
            s.environment.k_drag = None;
            s.collision.law = crate::model::ContactLaw::Dem;
            s.collision.tangential_ratio = EXAMPLE_DEM_TANGENTIAL.to_vec();
            out.push((format!("{name}, drag off, DEM law"), s));
        }
    }
    out
}

fn tooth(prep: &Prepared, p: &ParticleEnd) -> u32 {
    if p.state == ParticleState::Lost {
        0
    } else {
        end_tooth(&prep.profile, p.end)
    }
}

/// Each case's designs on the GPU, one `run_prepared` call per case.
pub fn run(
    gpu: &GpuEngine,
    cases: &[(String, Scenario)],
    designs_per_case: usize,
    seed: u64,
    tol: Tolerances,
) -> Report {
    run_cases(gpu, cases, designs_per_case, seed, tol, false)
}

/// As `run`, but every case's designs go to the GPU in ONE `run_jobs` call, each under its own
/// case's context, as `evaluate_groups` sends a calibration's candidates: cases that differ
/// only in per-design physics (restitution, drag, effect parameters) share a dispatch.
pub fn run_merged(
    gpu: &GpuEngine,
    cases: &[(String, Scenario)],
    designs_per_case: usize,
    seed: u64,
    tol: Tolerances,
) -> Report {
    run_cases(gpu, cases, designs_per_case, seed, tol, true)
}

fn run_cases(
    gpu: &GpuEngine,
    cases: &[(String, Scenario)],
    designs_per_case: usize,
    seed: u64,
    tol: Tolerances,
    merged: bool,
) -> Report {
    let cpu32 = CpuEngine { precision: Precision::F32 };
    let cpu64 = CpuEngine { precision: Precision::F64 };
    let mut reports = Vec::new();
    let mut worst: Vec<(f64, Mismatch)> = Vec::new();
    let mut failures = Vec::new();
    let contexts: Vec<Context> = cases.iter().map(|(_, s)| Context::new(s)).collect();
    let prepared: Vec<Vec<Prepared>> = cases
        .iter()
        .enumerate()
        .map(|(ci, (_, s))| {
            let designs = random_valid_designs(s, designs_per_case, seed.wrapping_add(ci as u64));
            designs.iter().map(|d| prepare(s, d).expect("valid by construction")).collect()
        })
        .collect();
    let mut gpu_by_case: Vec<Vec<_>> = if merged {
        let jobs: Vec<(&Context, &Prepared)> =
            contexts.iter().zip(&prepared).flat_map(|(c, ps)| ps.iter().map(move |p| (c, p))).collect();
        let mut all = gpu.run_jobs(&jobs, true).into_iter();
        prepared.iter().map(|ps| all.by_ref().take(ps.len()).collect()).collect()
    } else {
        contexts
            .iter()
            .zip(&prepared)
            .map(|(c, ps)| gpu.run_prepared(c, &ps.iter().collect::<Vec<_>>(), true))
            .collect()
    };
    for (ci, (name, _)) in cases.iter().enumerate() {
        let ctx = &contexts[ci];
        let preps = &prepared[ci];
        let gpu_runs = std::mem::take(&mut gpu_by_case[ci]);
        let mut r = ScenarioReport {
            scenario: name.clone(),
            designs: preps.len(),
            particles: 0,
            first_impacts_compared: 0,
            first_impacts_within_tol: 0,
            max_first_impact_diff_m: 0.0,
            tooth_and_state_agree: 0,
            mean_distribution_l1: 0.0,
            max_distribution_l1: 0.0,
            mean_d_avg_diff_m: 0.0,
            mean_lost_diff: 0.0,
        };
        for (prep, (gsim, gparts)) in preps.iter().zip(gpu_runs) {
            let gparts = gparts.expect("particles requested");
            let c32 = cpu32.run(prep, ctx, None);
            for (i, (g, c)) in gparts.iter().zip(&c32.particles).enumerate() {
                r.particles += 1;
                let same = tooth(prep, g) == tooth(prep, c) && g.state == c.state;
                if same {
                    r.tooth_and_state_agree += 1;
                }
                let mut diff = 0.0;
                match (g.first_impact, c.first_impact) {
                    (Some(a), Some(b)) => {
                        r.first_impacts_compared += 1;
                        diff = (a[0] - b[0]).hypot(a[1] - b[1]);
                        r.max_first_impact_diff_m = r.max_first_impact_diff_m.max(diff);
                        if diff <= tol.first_impact_tol_m {
                            r.first_impacts_within_tol += 1;
                        }
                    }
                    (None, None) => {}
                    _ => {
                        r.first_impacts_compared += 1;
                        diff = f64::INFINITY;
                    }
                }
                if !same || diff > tol.first_impact_tol_m {
                    let what = format!(
                        "first impact diff {:.3e} m; gpu tooth {} {:?}, cpu-f32 tooth {} {:?}",
                        diff,
                        tooth(prep, g),
                        g.state,
                        tooth(prep, c),
                        c.state
                    );
                    worst.push((
                        if diff.is_finite() { diff } else { 1.0 },
                        Mismatch { scenario: name.clone(), design: DesignRow::of(&prep.design), particle: i, what },
                    ));
                }
            }
            let c64 = cpu64.run(prep, ctx, None);
            let csim = summarise(&prep.profile, prep.fill.area, &c64.particles, c64.iterations);
            let l1: f64 = gsim.distribution.iter().zip(&csim.distribution).map(|(a, b)| (a - b).abs()).sum::<f64>()
                + (gsim.lost_fraction - csim.lost_fraction).abs();
            r.mean_distribution_l1 += l1;
            r.max_distribution_l1 = r.max_distribution_l1.max(l1);
            r.mean_d_avg_diff_m += (gsim.d_avg_m - csim.d_avg_m).abs();
            r.mean_lost_diff += (gsim.lost_fraction - csim.lost_fraction).abs();
        }
        let nd = r.designs.max(1) as f64;
        r.mean_distribution_l1 /= nd;
        r.mean_d_avg_diff_m /= nd;
        r.mean_lost_diff /= nd;
        let share = |a: usize, b: usize| if b == 0 { 1.0 } else { a as f64 / b as f64 };
        if share(r.first_impacts_within_tol, r.first_impacts_compared) < tol.min_first_impact_agreement {
            failures.push(format!(
                "{name}: first impacts within {} m: {}/{}",
                tol.first_impact_tol_m, r.first_impacts_within_tol, r.first_impacts_compared
            ));
        }
        if share(r.tooth_and_state_agree, r.particles) < tol.min_particle_agreement {
            failures.push(format!(
                "{name}: final tooth and state agree for {}/{} particles",
                r.tooth_and_state_agree, r.particles
            ));
        }
        if r.mean_distribution_l1 > tol.max_mean_distribution_l1 {
            failures.push(format!("{name}: mean distribution L1 {:.4}", r.mean_distribution_l1));
        }
        if r.mean_d_avg_diff_m > tol.max_mean_d_avg_diff_m {
            failures.push(format!("{name}: mean |d_avg diff| {:.5} m", r.mean_d_avg_diff_m));
        }
        if r.mean_lost_diff > tol.max_mean_lost_diff {
            failures.push(format!("{name}: mean |lost diff| {:.4}", r.mean_lost_diff));
        }
        reports.push(r);
    }
    worst.sort_by(|a, b| b.0.total_cmp(&a.0));
    Report {
        device: gpu.describe(),
        tolerances: tol,
        scenarios: reports,
        worst: worst.into_iter().take(10).map(|w| w.1).collect(),
        passed: failures.is_empty(),
        failures,
    }
}
