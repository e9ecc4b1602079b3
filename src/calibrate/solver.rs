//! The calibration solver: several models fitted in lockstep, each stage's points of every
//! model simulated as one engine call ([`Simulator::simulate`]).
//!
//! 1. **Screen** at a small particle budget: differential evolution (DE/rand-to-best/1/bin,
//!    F dithered in [0.5, 0.9] per generation, CR 0.9; Storn & Price 1997) in the unit box of
//!    each model's space, the population seeded with uniform points and the model's starts
//!    (e.g. the baseline's optimum with the effect switched off, so a nested model is never
//!    screened worse than the baseline). DE needs no gradient and tolerates the
//!    piecewise-constant objective of a finite-particle simulation.
//! 2. **Polish** at the full budget: the screen's best point and the starts are re-scored
//!    with the full particle count, and a compass search (Kolda, Lewis & Torczon 2003) moves
//!    from the best of them: the 2d points ±step along each axis, move to the best that
//!    improves and double the step (up to 0.2 of the box), else halve it. Each iteration of
//!    every model is one engine call.
//!
//! The objective is the joint SSE of Eq. 4.62 summed over the conditions. Every point of a
//! stage sees the same particle streams (common random numbers), so differences between
//! points are differences of physics, not of noise.

use anyhow::bail;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::batch::{Bins, Simulator};
use super::space::Space;
use crate::fit::Target;

/// One model to fit: its space and extra starting points (parameter units).
pub struct Model<'a> {
    pub space: &'a Space,
    pub starts: Vec<Vec<f64>>,
}

/// How hard the solver works.
#[derive(Clone, Copy, Debug)]
pub struct SolverBudget {
    /// DE population per model (at least 5).
    pub pop: usize,
    /// DE generations after the initial population.
    pub generations: usize,
    /// Particles per simulation while screening.
    pub screen_particles: u32,
    /// Particles per simulation while polishing (the budget the fit is reported at).
    pub particles: u32,
    /// Compass-search iterations.
    pub polish_iterations: usize,
    pub seed: u64,
}

/// One fitted model.
#[derive(Clone, Debug)]
pub struct Fit {
    pub x: Vec<f64>,
    /// Joint SSE at `x` with the full particle count, %².
    pub value: f64,
    /// Simulated bins per condition at `x`.
    pub bins: Vec<Vec<f64>>,
    /// Simulations of the whole condition set this fit used.
    pub evaluations: u64,
}

/// The joint objective: Σ over conditions of the SSE (%²); +inf when not simulable.
pub fn joint_sse(bins: &Bins, targets: &[Target]) -> f64 {
    match bins {
        None => f64::INFINITY,
        Some(b) => b.iter().zip(targets).map(|(b, t)| t.sse(b)).sum(),
    }
}

/// Score every model's unit-box points (`per_model[m]` for model m) in one engine call and
/// hand the values back per model, in order.
fn score_per_model(
    run: &dyn Fn(&[(&Space, Vec<f64>)], u32) -> Vec<f64>,
    models: &[Model],
    per_model: &[Vec<Vec<f64>>],
    particles: u32,
) -> Vec<Vec<f64>> {
    let points: Vec<(&Space, Vec<f64>)> =
        per_model.iter().zip(models).flat_map(|(us, model)| us.iter().map(|u| (model.space, model.space.from_unit(u)))).collect();
    let mut it = run(&points, particles).into_iter();
    per_model.iter().map(|us| us.iter().map(|_| it.next().expect("one value per point")).collect()).collect()
}

/// Polish steps in the unit box: the first and the smallest.
const FIRST_STEP: f64 = 0.05;
const MIN_STEP: f64 = 0.05 / 32.0;
const MAX_STEP: f64 = 0.2;

struct Member {
    pop: Vec<(Vec<f64>, f64)>,
    rng: ChaCha8Rng,
    evaluations: u64,
}

/// Fit every model to `targets` (one per condition). `log` receives progress lines.
pub fn fit_models(
    sim: &Simulator,
    targets: &[Target],
    models: &[Model],
    budget: &SolverBudget,
    log: &mut dyn FnMut(String),
) -> anyhow::Result<Vec<Fit>> {
    if budget.pop < 5 {
        bail!("the calibration's population must be >= 5, got {}", budget.pop);
    }
    let seed = budget.seed;
    let run = |points: &[(&Space, Vec<f64>)], particles: u32| -> Vec<f64> {
        sim.simulate(points, particles, seed).iter().map(|b| joint_sse(b, targets)).collect()
    };

    // 1. screen: DE at the small budget, all models' generations as one call each
    let mut members: Vec<Member> = models
        .iter()
        .enumerate()
        .map(|(m, model)| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed ^ (0xCA11_B000 + m as u64));
            let d = model.space.dim();
            let mut pop: Vec<Vec<f64>> = model.starts.iter().map(|x| model.space.to_unit(x)).take(budget.pop).collect();
            while pop.len() < budget.pop {
                pop.push((0..d).map(|_| rng.random::<f64>()).collect());
            }
            Member { pop: pop.into_iter().map(|u| (u, f64::INFINITY)).collect(), rng, evaluations: 0 }
        })
        .collect();
    let initial: Vec<Vec<Vec<f64>>> = members.iter().map(|mem| mem.pop.iter().map(|(u, _)| u.clone()).collect()).collect();
    for (mem, values) in members.iter_mut().zip(score_per_model(&run, models, &initial, budget.screen_particles)) {
        for (ind, v) in mem.pop.iter_mut().zip(values) {
            ind.1 = v;
        }
        mem.evaluations += mem.pop.len() as u64;
    }
    for g in 0..budget.generations {
        let mut trials: Vec<Vec<Vec<f64>>> = Vec::with_capacity(members.len());
        for mem in members.iter_mut() {
            let n = mem.pop.len();
            let d = mem.pop[0].0.len();
            let best = (0..n).min_by(|a, b| mem.pop[*a].1.total_cmp(&mem.pop[*b].1)).expect("population");
            let f = 0.5 + 0.4 * mem.rng.random::<f64>();
            let mut t = Vec::with_capacity(n);
            for i in 0..n {
                let (r1, r2) = loop {
                    let r1 = mem.rng.random_range(0..n);
                    let r2 = mem.rng.random_range(0..n);
                    if r1 != r2 && r1 != i && r2 != i {
                        break (r1, r2);
                    }
                };
                let jrand = mem.rng.random_range(0..d);
                let xi = &mem.pop[i].0;
                let y: Vec<f64> = (0..d)
                    .map(|j| {
                        if j == jrand || mem.rng.random::<f64>() < 0.9 {
                            let v = xi[j] + f * (mem.pop[best].0[j] - xi[j]) + f * (mem.pop[r1].0[j] - mem.pop[r2].0[j]);
                            // bounce back halfway to the bound it crossed
                            if v < 0.0 {
                                0.5 * xi[j]
                            } else if v > 1.0 {
                                0.5 * (xi[j] + 1.0)
                            } else {
                                v
                            }
                        } else {
                            xi[j]
                        }
                    })
                    .collect();
                t.push(y);
            }
            trials.push(t);
        }
        let values = score_per_model(&run, models, &trials, budget.screen_particles);
        for ((mem, t), values) in members.iter_mut().zip(trials).zip(values) {
            mem.evaluations += t.len() as u64;
            for (i, (u, v)) in t.into_iter().zip(values).enumerate() {
                if v <= mem.pop[i].1 {
                    mem.pop[i] = (u, v);
                }
            }
        }
        if (g + 1) % 10 == 0 || g + 1 == budget.generations {
            let best: Vec<String> =
                members.iter().map(|m| format!("{:.1}", m.pop.iter().map(|p| p.1).fold(f64::INFINITY, f64::min))).collect();
            log(format!("calibrate: screen generation {}/{} (best SSE {} %²)", g + 1, budget.generations, best.join(", ")));
        }
    }

    // 2. polish at the full budget: the screen's best and the starts, then a compass search
    let mut current: Vec<(Vec<f64>, f64)> = Vec::with_capacity(models.len());
    {
        let mut cands: Vec<Vec<Vec<f64>>> = Vec::new();
        for (mem, model) in members.iter().zip(models) {
            let best = mem.pop.iter().min_by(|a, b| a.1.total_cmp(&b.1)).expect("population").0.clone();
            let mut c = vec![best];
            c.extend(model.starts.iter().map(|x| model.space.to_unit(x)));
            cands.push(c);
        }
        let values = score_per_model(&run, models, &cands, budget.particles);
        for ((mem, c), values) in members.iter_mut().zip(cands).zip(values) {
            mem.evaluations += c.len() as u64;
            let mut best: Option<(Vec<f64>, f64)> = None;
            for (u, v) in c.into_iter().zip(values) {
                if best.as_ref().is_none_or(|b| v < b.1) {
                    best = Some((u, v));
                }
            }
            current.push(best.expect("at least the screen's best"));
        }
    }
    let mut steps = vec![FIRST_STEP; models.len()];
    for _ in 0..budget.polish_iterations {
        let mut probes: Vec<Vec<Vec<f64>>> = Vec::with_capacity(models.len());
        for (m, (u, _)) in current.iter().enumerate() {
            let mut p = Vec::new();
            if steps[m] >= MIN_STEP {
                for j in 0..u.len() {
                    for sign in [-1.0, 1.0] {
                        let mut y = u.clone();
                        y[j] = (y[j] + sign * steps[m]).clamp(0.0, 1.0);
                        if y[j] != u[j] {
                            p.push(y);
                        }
                    }
                }
            }
            probes.push(p);
        }
        if probes.iter().all(Vec::is_empty) {
            break;
        }
        let values = score_per_model(&run, models, &probes, budget.particles);
        for (m, (p, values)) in probes.into_iter().zip(values).enumerate() {
            members[m].evaluations += p.len() as u64;
            let mut moved = false;
            for (y, v) in p.into_iter().zip(values) {
                if v < current[m].1 {
                    current[m] = (y, v);
                    moved = true;
                }
            }
            // expand after a success (the screen's best can lie several steps away), contract
            // after a failure
            steps[m] = if moved { (steps[m] * 2.0).min(MAX_STEP) } else { steps[m] * 0.5 };
        }
    }

    // the fits' bins, one more call
    let points: Vec<(&Space, Vec<f64>)> = current.iter().zip(models).map(|((u, _), model)| (model.space, model.space.from_unit(u))).collect();
    let bins = sim.simulate(&points, budget.particles, seed);
    let mut fits = Vec::with_capacity(models.len());
    for (((x, b), (_, v)), mem) in points.into_iter().map(|(_, x)| x).zip(bins).zip(current).zip(&members) {
        let Some(b) = b else {
            bail!("no candidate could be simulated (every evaluation was rejected by the engine)");
        };
        fits.push(Fit { x, value: v, bins: b, evaluations: mem.evaluations + 1 });
    }
    Ok(fits)
}
