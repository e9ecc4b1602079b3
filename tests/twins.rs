//! The Rust twins of the WGSL kernel's parts that the `cpu` engine does not run itself: the
//! per-design reduction at the end of `simulate` (`kernel::reduce`, same lanes and order as
//! the workgroup) against the `cpu` engine's own aggregation (`outcome::summarise`) of the
//! same particles, in both precisions, both physics modes, lunar and earth.

use sawtooth::engine::cpu::{engine_lanes, kernel_design, kernel_physics, run_design, run_particles};
use sawtooth::engine::kernel::{follow_particle, init_particle, particle_steps, reduce, KOutcome};
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
            let (mut parts, iterations) = run_particles::<T>(&prep, &ctx, engine_lanes(), None);
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
            let run = run_design::<T>(&prep, &ctx, engine_lanes(), None);
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

/// Physical mode's GPU path, `simulate_particles` (one thread follows one particle to rest)
/// and `reduce_designs` (iterations = the most steps any particle took, at least 1), in its
/// Rust twins, leaves every particle and the iteration count exactly as the cpu engine's
/// bounce-by-bounce loop does.
fn check_particle_major<T: Real + PartialEq + std::fmt::Debug>(s: &Scenario, seed: u64) {
    let mut s = s.clone();
    s.sim.particles = 150;
    let ctx = Context::new(&s);
    for design in random_valid_designs(&s, 12, seed) {
        let prep = prepare(&s, &design).unwrap();
        let (d, ph) = (kernel_design::<T>(&prep), kernel_physics::<T>(&ctx));
        let (bounce_major, iterations) = run_particles::<T>(&prep, &ctx, engine_lanes(), None);
        let mut most = 1;
        for (i, l) in prep.launches.iter().enumerate() {
            let mut p = init_particle(&d, &ph, [T::c(l[0]), T::c(l[1])], i as u32);
            let steps = follow_particle(&d, &ph, &mut p, i as u32, ctx.max_bounces);
            assert_eq!(steps, particle_steps(&p).min(ctx.max_bounces), "particle {i}");
            most = most.max(steps);
            let q = &bounce_major[i];
            assert_eq!((p.state, p.bounces, p.tooth), (q.state, q.bounces, q.tooth), "particle {i}");
            assert_eq!((p.pos, p.vel, p.hop, p.first), (q.pos, q.vel, q.hop, q.first), "particle {i}");
        }
        assert_eq!(most, iterations);
    }
}

#[test]
fn particle_major_twin_matches_the_bounce_loop_physical() {
    for (i, s) in [Scenario::lunar(), Scenario::earth()].iter().enumerate() {
        check_particle_major::<f32>(s, 71 + i as u64);
        check_particle_major::<f64>(s, 81 + i as u64);
    }
}
