//! The Rust twins of the WGSL kernel's parts that the `cpu` engine does not run itself: the
//! per-design reduction at the end of `simulate` (`kernel::reduce`, same lanes and order as
//! the workgroup) against the `cpu` engine's own aggregation (`outcome::summarise`) of the
//! same particles, in both precisions, both physics modes, lunar and earth.

use sawtooth::engine::cpu::{kernel_design, kernel_physics, run_design, run_particles};
use sawtooth::engine::kernel::{reduce, KOutcome};
use sawtooth::engine::Context;
use sawtooth::model::outcome::{from_counts, summarise, SimOutcome};
use sawtooth::model::prepare::prepare;
use sawtooth::model::real::Real;
use sawtooth::model::sampling::random_valid_designs;
use sawtooth::model::Scenario;

/// The outcome `reduce` gives for `n` random designs, beside the engine's.
fn both<T: Real>(s: &Scenario, n: usize, seed: u64) -> Vec<(SimOutcome, SimOutcome)> {
    let ctx = Context::new(s);
    random_valid_designs(s, n, seed)
        .iter()
        .map(|design| {
            let prep = prepare(s, design).unwrap();
            let (d, ph) = (kernel_design::<T>(&prep), kernel_physics::<T>(&ctx));
            let (mut parts, iterations) = run_particles::<T>(&prep, &ctx, None);
            let mut hist = vec![0u32; prep.profile.teeth as usize];
            let k: KOutcome<T> = reduce(&d, &ph, &mut parts, iterations, &mut hist);
            let twin = from_counts(
                &hist,
                parts.len(),
                k.lost as usize,
                k.flying as usize,
                k.distance_sum.f64(),
                k.advance_teeth as f64 * prep.profile.pitch_len,
                prep.fill.area,
                k.iterations,
                k.bounce_sum as u64,
            );
            let run = run_design::<T>(&prep, &ctx, None);
            let engine = summarise(&prep.profile, prep.fill.area, &run.particles, run.iterations);
            (twin, engine)
        })
        .collect()
}

fn check<T: Real>(s: &Scenario, seed: u64) {
    let mut s = s.clone();
    s.sim.particles = 150; // more than one lane's worth per lane (WG = 64)
    for (twin, engine) in both::<T>(&s, 12, seed) {
        // counts: exactly
        assert_eq!(twin.distribution, engine.distribution);
        assert_eq!(twin.lost_fraction, engine.lost_fraction);
        assert_eq!(twin.unsettled_fraction, engine.unsettled_fraction);
        assert_eq!(twin.bounces, engine.bounces);
        assert_eq!(twin.mean_bounces, engine.mean_bounces);
        assert_eq!(twin.advance_m, engine.advance_m);
        // distances: the kernel's precision and lane order against f64 in particle order
        let tol = if std::mem::size_of::<T>() == 4 { 1e-5 } else { 1e-12 };
        assert!(
            (twin.d_avg_m - engine.d_avg_m).abs() <= tol * engine.d_avg_m.abs().max(1e-3),
            "d_avg {} vs {}",
            twin.d_avg_m,
            engine.d_avg_m
        );
    }
}

#[test]
fn reduction_twin_matches_the_cpu_engine_physical() {
    for (i, s) in [Scenario::lunar(), Scenario::earth()].iter().enumerate() {
        check::<f32>(s, 31 + i as u64);
        check::<f64>(s, 41 + i as u64);
    }
}

#[test]
fn reduction_twin_matches_the_cpu_engine_listing() {
    for (i, s) in [Scenario::lunar().into_listing_compat(), Scenario::earth().into_listing_compat()].iter().enumerate()
    {
        check::<f32>(s, 51 + i as u64);
        check::<f64>(s, 61 + i as u64);
    }
}
