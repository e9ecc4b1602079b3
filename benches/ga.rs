//! The GA's own cost per generation at pop 1000 (issue 4 §5): NSGA-II on a problem whose
//! evaluation is nearly free (8 variables, 2 objectives, like the sawtooth problem), so what
//! is timed is selection, variation, sorting and crowding.

use criterion::{criterion_group, criterion_main, Criterion};
use sawtooth::optim::nsga2::{BatchProblem, Config, Evaluation, Nsga2};

struct Cheap;

impl BatchProblem for Cheap {
    fn dim(&self) -> usize {
        8
    }
    fn n_objectives(&self) -> usize {
        2
    }
    fn bounds(&self) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0; 8], vec![1.0; 8])
    }
    fn evaluate_batch(&mut self, xs: &[Vec<f64>], _generation: u64) -> Vec<Evaluation> {
        xs.iter()
            .map(|x| {
                let g = 1.0 + x[1..].iter().sum::<f64>();
                Evaluation { objectives: vec![x[0], g * (1.0 - (x[0] / g).sqrt())], violation: (x[2] - x[3]).max(0.0) }
            })
            .collect()
    }
}

fn ga_overhead(c: &mut Criterion) {
    let ga = Nsga2 { config: Config { pop: 1000, seed: 1, max_generations: u64::MAX, ..Config::default() } };
    let mut p = Cheap;
    let mut state = ga.init(&mut p);
    for _ in 0..20 {
        ga.step(&mut state, &mut p); // a converged-ish population, as late in a run
    }
    let mut g = c.benchmark_group("nsga2");
    g.sample_size(20);
    g.bench_function("generation_pop1000", |b| b.iter(|| ga.step(&mut state, &mut p)));
    g.finish();
}

criterion_group!(benches, ga_overhead);
criterion_main!(benches);
