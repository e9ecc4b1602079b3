//! NSGA-II on standard benchmarks (Deb et al. 2002) and constraint handling (Deb 2000):
//! front quality by hypervolume, determinism and exact checkpoint/resume.
//! Run with `cargo test --release --test suite nsga2:: -- --nocapture` to see the measured figures.

use sawtooth::optim::nsga2::{self, pareto_front};
use sawtooth::optim::test_problems::{Bnh, Zdt1, Zdt2};
use sawtooth::optim::{
    constrained_dominates, hypervolume_2d, load_checkpoint, save_checkpoint, BatchProblem, Config, Evaluation, Mode,
    Nsga2, State, Termination,
};

const SEED: u64 = 20_240_611;

fn config(max_generations: u64) -> Config {
    Config { pop: 100, seed: SEED, max_generations, ..Config::default() }
}

fn run_to_end(solver: &Nsga2, problem: &mut impl BatchProblem) -> (State, Termination) {
    solver.run(problem, |_, _| {})
}

fn front_hv(state: &State, reference: [f64; 2]) -> f64 {
    let pts: Vec<[f64; 2]> = pareto_front(state).iter().map(|i| [i.eval.objectives[0], i.eval.objectives[1]]).collect();
    hypervolume_2d(&pts, reference)
}

/// Runs `problem` for `generations` and returns HV as a fraction of the true front's.
fn hv_ratio(problem: &mut impl BatchProblem, generations: u64, reference: [f64; 2], truth: f64) -> f64 {
    let solver = Nsga2::new(config(generations));
    let (state, why) = run_to_end(&solver, problem);
    assert_eq!(why, Termination::MaxGenerations);
    assert_eq!(state.generation, generations);
    assert_eq!(state.evaluations, 100 * (generations + 1));
    front_hv(&state, reference) / truth
}

#[test]
fn zdt1_reaches_95_percent_hypervolume() {
    let r = [1.1, 1.1];
    let ratio = hv_ratio(&mut Zdt1::default(), 250, r, Zdt1::true_hypervolume(r));
    eprintln!("ZDT1: HV {:.2} % of the true front", 100.0 * ratio);
    assert!(ratio >= 0.95, "ZDT1 HV ratio {ratio}");
}

#[test]
fn zdt2_reaches_95_percent_hypervolume() {
    let r = [1.1, 1.1];
    let ratio = hv_ratio(&mut Zdt2::default(), 250, r, Zdt2::true_hypervolume(r));
    eprintln!("ZDT2: HV {:.2} % of the true front", 100.0 * ratio);
    assert!(ratio >= 0.95, "ZDT2 HV ratio {ratio}");
}

#[test]
fn bnh_front_is_feasible_and_reaches_95_percent_hypervolume() {
    let r = [140.0, 50.0];
    let solver = Nsga2::new(config(100));
    let (state, _) = run_to_end(&solver, &mut Bnh);
    let front = pareto_front(&state);
    assert!(front.len() > 50, "front of {} points", front.len());
    for ind in &front {
        assert_eq!(ind.eval.violation, 0.0, "infeasible front point {:?}", ind.x);
        assert_eq!(Bnh::violation(&ind.x), 0.0);
    }
    let ratio = front_hv(&state, r) / Bnh::true_hypervolume(r);
    eprintln!("BNH: HV {:.2} % of the true front, {} points", 100.0 * ratio, front.len());
    assert!(ratio >= 0.95, "BNH HV ratio {ratio}");
}

fn xs(state: &State) -> Vec<Vec<u64>> {
    state.population.iter().map(|i| i.x.iter().map(|v| v.to_bits()).collect()).collect()
}

fn objectives(state: &State) -> Vec<Vec<u64>> {
    state.population.iter().map(|i| i.eval.objectives.iter().map(|v| v.to_bits()).collect()).collect()
}

#[test]
fn same_seed_gives_identical_populations() {
    let solver = Nsga2::new(config(40));
    let (a, _) = run_to_end(&solver, &mut Zdt1::default());
    let (b, _) = run_to_end(&solver, &mut Zdt1::default());
    assert_eq!(xs(&a), xs(&b));
    let other = Nsga2::new(Config { seed: SEED + 1, ..config(40) });
    let (c, _) = run_to_end(&other, &mut Zdt1::default());
    assert_ne!(xs(&a), xs(&c), "a different seed should give a different run");
}

/// 60 generations straight vs 25 + checkpoint to disk + load + 35: bit-identical.
fn check_resume(solver: &Nsga2, problem: &mut impl BatchProblem, file: &str) {
    let mut straight = solver.init(problem);
    for _ in 0..60 {
        solver.step(&mut straight, problem);
    }

    let mut first = solver.init(problem);
    for _ in 0..25 {
        solver.step(&mut first, problem);
    }
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(file);
    save_checkpoint(&path, &first).unwrap();
    let mut resumed = load_checkpoint(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    // The loaded state re-serialises to the same text (NaN-safe, unlike PartialEq).
    assert_eq!(serde_json::to_string(&resumed).unwrap(), serde_json::to_string(&first).unwrap());
    drop(first);
    assert_eq!(resumed.generation, 25);
    for _ in 0..35 {
        solver.step(&mut resumed, problem);
    }

    assert_eq!(xs(&resumed), xs(&straight));
    assert_eq!(objectives(&resumed), objectives(&straight));
    let bits = |s: &State| s.spread_history.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&resumed), bits(&straight));
    assert_eq!(resumed.rng, straight.rng);
    assert_eq!(resumed.evaluations, straight.evaluations);
}

#[test]
fn checkpoint_resume_is_bit_identical() {
    check_resume(&Nsga2::new(config(60)), &mut Zdt1::default(), "nsga2_resume_zdt1.json");
    // Constrained, and the MATLAB-like survival with its spread bookkeeping.
    let matlab = Nsga2::new(Config {
        mode: Mode::MatlabLike { pareto_fraction: 0.35, tol: 1e-4, stall_generations: 20 },
        ..config(60)
    });
    check_resume(&matlab, &mut Bnh, "nsga2_resume_bnh.json");
}

/// MATLAB's stall test weights the newest spread changes most, so it fires when the spread
/// happens to hold still for a few generations: a chance event whose waiting time depends on
/// tol. Measured over seeds 0..16 with stall 20: tol 3e-4 (a weighted recent relative change
/// below ~0.6 %) stopped 14 runs between generations 145 and 1802, all with HV >= 96.8 %, and
/// 2 ran to 2000; tol 4e-4 already stopped some runs near generation 40 (HV ~65 %); tol 1e-4
/// never stopped within 2000 generations (Deb's spread changes 5-10 % a generation). So the
/// test runs 8 seeds and asserts on all of them rather than on one lucky seed.
#[test]
fn matlab_like_mode_stops_on_stalled_spread() {
    use rayon::prelude::*;
    let r = [1.1, 1.1];
    let truth = Zdt1::true_hypervolume(r);
    let max_generations = 2000;
    let runs: Vec<(u64, Termination, u64, f64)> = (0..8u64)
        .into_par_iter()
        .map(|seed| {
            let solver = Nsga2::new(Config {
                seed,
                mode: Mode::MatlabLike { pareto_fraction: 0.35, tol: 3e-4, stall_generations: 20 },
                ..config(max_generations)
            });
            let (state, why) = run_to_end(&solver, &mut Zdt1::default());
            (seed, why, state.generation, front_hv(&state, r) / truth)
        })
        .collect();
    for (seed, why, generation, ratio) in &runs {
        eprintln!("ZDT1 MatlabLike seed {seed}: {why:?} at generation {generation}, HV {:.2} %", 100.0 * ratio);
        assert!(*ratio >= 0.90, "seed {seed}: HV ratio {ratio}");
        if *why == Termination::SpreadStalled {
            assert!(*generation < max_generations);
        }
    }
    let stalled = runs.iter().filter(|r| r.1 == Termination::SpreadStalled).count();
    assert!(stalled >= 6, "only {stalled} of 8 runs stopped on a stalled spread");
}

fn ev(objectives: &[f64], violation: f64) -> Evaluation {
    Evaluation { objectives: objectives.to_vec(), violation }
}

#[test]
fn feasible_beats_infeasible_regardless_of_objectives() {
    let feasible = ev(&[1e9, 1e9], 0.0);
    let infeasible = ev(&[-1e9, -1e9], 1e-12);
    assert!(constrained_dominates(&feasible, &infeasible));
    assert!(!constrained_dominates(&infeasible, &feasible));
}

#[test]
fn lower_violation_wins_between_infeasible() {
    let small = ev(&[10.0, 10.0], 0.5);
    let large = ev(&[0.0, 0.0], 2.0);
    assert!(constrained_dominates(&small, &large));
    assert!(!constrained_dominates(&large, &small));
    let tie = ev(&[0.0, 0.0], 0.5);
    assert!(!constrained_dominates(&small, &tie) && !constrained_dominates(&tie, &small));
}

#[test]
fn feasible_pair_uses_pareto_dominance() {
    assert!(constrained_dominates(&ev(&[1.0, 1.0], 0.0), &ev(&[1.0, 2.0], 0.0)));
    assert!(!constrained_dominates(&ev(&[0.0, 3.0], 0.0), &ev(&[1.0, 2.0], 0.0)));
    assert!(!constrained_dominates(&ev(&[1.0, 2.0], 0.0), &ev(&[1.0, 2.0], 0.0)));
}

#[test]
fn infeasible_only_population_reports_least_violating_members() {
    // Every candidate violates a constraint; the front falls back to the least violating.
    struct AlwaysInfeasible;
    impl BatchProblem for AlwaysInfeasible {
        fn dim(&self) -> usize {
            2
        }
        fn n_objectives(&self) -> usize {
            2
        }
        fn bounds(&self) -> (Vec<f64>, Vec<f64>) {
            (vec![0.0, 0.0], vec![1.0, 1.0])
        }
        fn evaluate_batch(&mut self, xs: &[Vec<f64>], _generation: u64) -> Vec<Evaluation> {
            xs.iter().map(|x| ev(&[x[0], 1.0 - x[0]], 1.0 + x[1])).collect()
        }
    }
    let solver = Nsga2::new(config(20));
    let mut problem = AlwaysInfeasible;
    let mut state = solver.init(&mut problem);
    for _ in 0..20 {
        let stats = solver.step(&mut state, &mut problem);
        assert_eq!(stats.feasible_fraction, 0.0);
        assert!(stats.spread.is_nan());
    }
    let least = state.population.iter().map(|i| i.eval.violation).fold(f64::INFINITY, f64::min);
    let front = nsga2::pareto_front(&state);
    assert!(!front.is_empty());
    assert!(front.iter().all(|i| i.eval.violation == least));
    // Selection pressure drives x2 (the violation) towards its lower bound.
    assert!(least < 1.01, "least violation {least}");
}

/// Issue 14: the permutation (pymoo-like) mating selection is a full NSGA-II too — it reaches
/// the same front quality on ZDT1/BNH and resumes bit for bit from a checkpoint.
#[test]
fn permutation_selection_reaches_the_fronts_and_resumes_exactly() {
    let perm = |generations| Config { selection: nsga2::Selection::Permutation, ..config(generations) };
    let r = [1.1, 1.1];
    let (state, _) = run_to_end(&Nsga2::new(perm(250)), &mut Zdt1::default());
    let ratio = front_hv(&state, r) / Zdt1::true_hypervolume(r);
    eprintln!("ZDT1, permutation selection: HV {:.2} % of the true front", 100.0 * ratio);
    assert!(ratio >= 0.95, "ZDT1 HV ratio {ratio}");
    let (deb, _) = run_to_end(&Nsga2::new(config(40)), &mut Zdt1::default());
    let (per, _) = run_to_end(&Nsga2::new(perm(40)), &mut Zdt1::default());
    assert_ne!(xs(&deb), xs(&per), "the selection setting must change the run");
    check_resume(&Nsga2::new(perm(60)), &mut Bnh, "nsga2_resume_bnh_permutation.json");
}
