//! The `cpu` reference and the `listing` port agree particle by particle (issue 2 §3):
//! same inputs and seed, final teeth equal for >= 98 % of particles over random valid
//! designs in both environments.

use sawtooth::engine::{evaluate_detailed, particle_engine, EngineKind};
use sawtooth::model::outcome::end_tooth;
use sawtooth::model::sampling::random_valid_designs;
use sawtooth::model::{ParticleState, Scenario};

/// (agreeing particles, particles) over `n` random designs.
fn agreement(s: &Scenario, n: usize, seed: u64) -> (usize, usize) {
    let cpu = particle_engine(EngineKind::Cpu);
    let listing = particle_engine(EngineKind::Listing);
    let (mut agree, mut total) = (0, 0);
    for d in random_valid_designs(s, n, seed) {
        let a = evaluate_detailed(cpu.as_ref(), s, &d, false).unwrap();
        let b = evaluate_detailed(listing.as_ref(), s, &d, false).unwrap();
        let pr = &a.prepared.profile;
        let tooth =
            |p: &sawtooth::model::ParticleEnd| if p.state == ParticleState::Lost { 0 } else { end_tooth(pr, p.end) };
        for (p, q) in a.particles.iter().zip(&b.particles) {
            total += 1;
            if tooth(p) == tooth(q) {
                agree += 1;
            }
        }
    }
    (agree, total)
}

fn scenario(mut s: Scenario) -> Scenario {
    s.sim.particles = 50;
    s
}

#[test]
fn engines_agree_on_final_teeth_lunar() {
    let (a, n) = agreement(&scenario(Scenario::lunar()), 30, 11);
    eprintln!("lunar physical: {a}/{n} particles agree");
    assert!(a as f64 >= 0.98 * n as f64, "{a}/{n}");
}

#[test]
fn engines_agree_on_final_teeth_earth() {
    let (a, n) = agreement(&scenario(Scenario::earth()), 30, 12);
    eprintln!("earth physical: {a}/{n} particles agree");
    assert!(a as f64 >= 0.98 * n as f64, "{a}/{n}");
}
