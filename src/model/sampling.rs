//! Seeded random designs: valid designs inside the optimisation bounds (tests, GA start) and
//! a neighbourhood of a design (benchmarks).

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

use super::design::{Design, LOWER_BOUND_CLI, UPPER_BOUND_CLI};
use super::prepare::prepare;
use super::scenario::Scenario;

/// A design inside the listing's bounds that satisfies the chain l_b <= r <= l_a <= l_c by
/// construction (each drawn below the previous), not yet checked otherwise.
pub fn draw_in_bounds(rng: &mut impl Rng) -> Design {
    let (lo, hi) = (LOWER_BOUND_CLI, UPPER_BOUND_CLI);
    let l_c = rng.random_range(lo[0]..hi[0]);
    let l_a = rng.random_range(lo[1]..l_c.min(hi[1]).max(lo[1] + 1e-9));
    let r = rng.random_range(lo[3]..l_a.min(hi[3]).max(lo[3] + 1e-9));
    let l_b = rng.random_range(lo[2]..r.min(hi[2]).max(lo[2] + 1e-9));
    let omega = rng.random_range(lo[4]..hi[4]);
    let delta = rng.random_range(lo[5]..hi[5]);
    let v0 = rng.random_range(lo[6]..hi[6]);
    let a = rng.random_range(lo[7]..hi[7]);
    Design::from_cli_units([l_c, l_a, l_b, r, omega, delta, v0, a])
}

/// `n` designs inside the bounds that the scenario can simulate (rejection sampling).
pub fn random_valid_designs(scenario: &Scenario, n: usize, seed: u64) -> Vec<Design> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(n);
    let mut tries = 0usize;
    while out.len() < n {
        tries += 1;
        assert!(tries < 1_000_000, "could not find {n} valid designs");
        let d = draw_in_bounds(&mut rng);
        if prepare(scenario, &d).is_ok() {
            out.push(d);
        }
    }
    out
}

/// `n` valid designs with every variable scaled by a factor in [1 - spread, 1 + spread].
pub fn neighbourhood(scenario: &Scenario, centre: &Design, n: usize, spread: f64, seed: u64) -> Vec<Design> {
    let mut rng = StdRng::seed_from_u64(seed);
    let c = centre.to_cli_units();
    let mut out = Vec::with_capacity(n);
    let mut tries = 0usize;
    while out.len() < n {
        tries += 1;
        assert!(tries < 1_000_000, "could not find {n} valid neighbours");
        let mut v = c;
        for x in v.iter_mut() {
            *x *= rng.random_range(1.0 - spread..=1.0 + spread);
        }
        let d = Design::from_cli_units(v);
        if prepare(scenario, &d).is_ok() {
            out.push(d);
        }
    }
    out
}
