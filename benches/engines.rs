//! Criterion bench: one batch of 64 designs around lunar solution C (±5 %), 100 particles,
//! up to 100 bounces, each engine on the same batch. Throughput is in particle-bounces.
//! And the preparation every engine pays (validity, fill, launch points), one design at a
//! time, over a GA generation's random valid designs. And libm's `sincos`, `atan2` and
//! `expm1` against the kernel's own (`sawtooth::lane_math`), one value at a time, on
//! arguments like the kernel's.

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

fn libm(c: &mut Criterion) {
    use sawtooth::lane_math::{atan2, exp_m1, sin_cos};
    let n = 4096;
    // launch angles, velocity components, and -k t of drag flights
    let angles: Vec<f64> = (0..n).map(|i| 7.0 * (i as f64 + 0.5) / n as f64).collect();
    let ys: Vec<f64> = (0..n).map(|i| 3.0 * ((i * 7919) % n) as f64 / n as f64 - 1.5).collect();
    let xs: Vec<f64> = (0..n).map(|i| 3.0 * ((i * 104_729) % n) as f64 / n as f64 - 1.5).collect();
    let kts: Vec<f64> = (0..n).map(|i| -40.0 * (i as f64 + 0.5) / n as f64).collect();
    let mut group = c.benchmark_group("libm");
    group.throughput(Throughput::Elements(n as u64));
    group.bench_function("sincos/libm", |b| b.iter(|| angles.iter().map(|a| a.sin_cos()).collect::<Vec<_>>()));
    group.bench_function("sincos/own", |b| b.iter(|| angles.iter().map(|&a| sin_cos(a)).collect::<Vec<_>>()));
    group.bench_function("atan2/libm", |b| b.iter(|| ys.iter().zip(&xs).map(|(y, x)| y.atan2(*x)).collect::<Vec<_>>()));
    group
        .bench_function("atan2/own", |b| b.iter(|| ys.iter().zip(&xs).map(|(&y, &x)| atan2(y, x)).collect::<Vec<_>>()));
    group.bench_function("expm1/libm", |b| b.iter(|| kts.iter().map(|x| x.exp_m1()).collect::<Vec<_>>()));
    group.bench_function("expm1/own", |b| b.iter(|| kts.iter().map(|&x| exp_m1(x)).collect::<Vec<_>>()));
    group.finish();
}

criterion_group!(benches, engines, preparation, libm);
criterion_main!(benches);
