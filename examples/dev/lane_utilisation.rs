//! How busy the SIMD lanes of the GPU's physical-mode kernel (`simulate_particles`: one
//! thread follows one particle to rest) can be: a group of lanes runs until its longest
//! particle rests, so with steps s_i per particle the useful share of a group of w lanes is
//! sum(s_i) / (w max s_i). Steps come from the `cpu` engine (the kernel's twin) on a
//! pop-1000 generation of random valid designs, as `bench --designs 1000 --sample random`.
//!
//! cargo run --release --example lane_utilisation

use sawtooth::engine::{cpu, Context};
use sawtooth::model::sampling::random_valid_designs;
use sawtooth::model::{prepare, EnvPreset, ParticleState, Scenario};

fn main() {
    for env in [EnvPreset::Lunar, EnvPreset::Earth] {
        let scenario = Scenario::preset(env);
        let ctx = Context::new(&scenario);
        let mut steps: Vec<u64> = Vec::new();
        for d in random_valid_designs(&scenario, 1000, 1) {
            let prep = prepare(&scenario, &d).expect("random_valid_designs gives valid designs");
            let run = cpu::run_design::<f64>(&prep, &ctx, cpu::engine_lanes(), None);
            // kernel.rs `particle_steps`: one per impact, plus the flight that lost it
            steps.extend(run.particles.iter().map(|p| p.bounces as u64 + u64::from(p.state == ParticleState::Lost)));
        }
        let total: u64 = steps.iter().sum();
        let mean = total as f64 / steps.len() as f64;
        let shares: Vec<String> = [8usize, 32, 64]
            .iter()
            .map(|&lanes| {
                let busy: u64 = steps.chunks(lanes).map(|c| c.iter().max().unwrap() * lanes as u64).sum();
                format!("{:.3} at {lanes} lanes", total as f64 / busy as f64)
            })
            .collect();
        println!("{env:?}: {} particles, {mean:.2} steps each; lane utilisation {}", steps.len(), shares.join(", "));
    }
}
