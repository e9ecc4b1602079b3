//! Criterion bench: one batch of 64 designs around lunar solution C (±5 %), 100 particles,
//! up to 100 bounces, each engine on the same batch. Throughput is in particle-bounces.
//! And the preparation every engine pays (validity, fill, launch points), one design at a
//! time, over a GA generation's random valid designs.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use sawtooth::engine::gpu::{AdapterChoice, GpuEngine};
use sawtooth::engine::{particle_engine, BatchEvaluator, EngineKind};
use sawtooth::model::sampling::{neighbourhood, random_valid_designs};
use sawtooth::model::{prepare, Design, Scenario};

fn engines(c: &mut Criterion) {
    for (label, scenario, centre) in [
        ("lunar", Scenario::lunar(), Design::lunar_solution_c()),
        ("lunar-listing-mode", Scenario::lunar().into_listing_compat(), Design::lunar_solution_c()),
        ("earth", Scenario::earth(), Design::earth_solution_c()),
    ] {
        let designs = neighbourhood(&scenario, &centre, 64, 0.05, 1);
        let mut group = c.benchmark_group(format!("batch64/{label}"));
        group.sample_size(10);
        let mut engines: Vec<Box<dyn BatchEvaluator>> =
            vec![Box::new(particle_engine(EngineKind::Listing)), Box::new(particle_engine(EngineKind::Cpu))];
        match GpuEngine::new(AdapterChoice::Any) {
            Ok(g) => {
                eprintln!("gpu: {}", g.describe());
                engines.push(Box::new(g));
            }
            Err(e) => eprintln!("no GPU adapter, gpu not benchmarked: {e}"),
        }
        for engine in &engines {
            let bounces: f64 =
                engine.evaluate(&scenario, &designs).iter().flatten().map(|e| e.sim.mean_bounces * 100.0).sum();
            group.throughput(Throughput::Elements(bounces as u64));
            group.bench_function(engine.backend(), |b| b.iter(|| engine.evaluate(&scenario, &designs)));
        }
        group.finish();
    }
}

fn preparation(c: &mut Criterion) {
    let mut group = c.benchmark_group("prepare");
    for (label, scenario) in [("lunar", Scenario::lunar()), ("earth", Scenario::earth())] {
        let designs = random_valid_designs(&scenario, 200, 1);
        group.throughput(Throughput::Elements(designs.len() as u64));
        group.bench_function(format!("{label}/200-random-designs"), |b| {
            b.iter(|| designs.iter().map(|d| prepare(&scenario, d).is_ok() as usize).sum::<usize>())
        });
    }
    group.finish();
}

criterion_group!(benches, engines, preparation);
criterion_main!(benches);
