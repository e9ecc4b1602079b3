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

/// Draws before giving up when not one design has been valid: a scenario that no design
/// can be simulated in (a fill that cannot seat its particles) fails every draw, and each
/// failed preparation may have drawn millions of Halton points first.
const FIRST_VALID_WITHIN: usize = 64;

/// Draws per wanted design before giving up once some were valid: the valid fraction of the
/// bounds is far above 1/200 for either preset (of 3000 draws, seed 1: 588 lunar, 1780 on
/// Earth, the same in the listing's mode), and 64 draws without one valid design happen by
/// chance with probability 0.8^64 < 1e-6.
const DRAWS_PER_DESIGN: usize = 200;

/// Rejection sampling of `n` designs from `draw`, bounded so that a scenario no design
/// fits ends in an error naming the commonest reason draws were refused, instead of a loop
/// or a panic.
fn sample(scenario: &Scenario, n: usize, what: &str, mut draw: impl FnMut() -> Design) -> Result<Vec<Design>, String> {
    let mut out = Vec::with_capacity(n.min(1 << 20));
    // refusals by their rule (the message up to its first ':'), with one example each
    let mut refusals: std::collections::BTreeMap<String, (usize, String)> = Default::default();
    let mut tries = 0usize;
    while out.len() < n {
        if (out.is_empty() && tries >= FIRST_VALID_WITHIN) || tries >= 1000 + DRAWS_PER_DESIGN.saturating_mul(n) {
            let (count, example) =
                refusals.values().max_by_key(|(count, _)| *count).cloned().unwrap_or((0, String::new()));
            return Err(format!(
                "found {} of {n} {what} the scenario can simulate in {tries} draws; {count} were refused by: {example}",
                out.len()
            ));
        }
        tries += 1;
        let d = draw();
        match prepare(scenario, &d) {
            Ok(_) => out.push(d),
            Err(e) => {
                let e = e.to_string();
                let rule = e.split(':').next().unwrap_or_default().to_string();
                let entry = refusals.entry(rule).or_insert((0, e));
                entry.0 += 1;
            }
        }
    }
    Ok(out)
}

/// `n` designs inside the bounds that the scenario can simulate (rejection sampling), or why
/// the scenario seats none.
pub fn sample_valid_designs(scenario: &Scenario, n: usize, seed: u64) -> Result<Vec<Design>, String> {
    let mut rng = StdRng::seed_from_u64(seed);
    sample(scenario, n, "designs", || draw_in_bounds(&mut rng))
}

/// [`sample_valid_designs`] for tests and benchmarks, whose scenarios seat designs by
/// construction: a refusal there is a bug, so it panics with the reason.
pub fn random_valid_designs(scenario: &Scenario, n: usize, seed: u64) -> Vec<Design> {
    sample_valid_designs(scenario, n, seed).unwrap_or_else(|e| panic!("{e}"))
}

/// `n` valid designs with every variable scaled by a factor in [1 - spread, 1 + spread], or
/// why the scenario seats none of them.
pub fn sample_neighbourhood(
    scenario: &Scenario,
    centre: &Design,
    n: usize,
    spread: f64,
    seed: u64,
) -> Result<Vec<Design>, String> {
    let mut rng = StdRng::seed_from_u64(seed);
    let c = centre.to_cli_units();
    sample(scenario, n, "neighbours", || {
        let mut v = c;
        for x in v.iter_mut() {
            *x *= rng.random_range(1.0 - spread..=1.0 + spread);
        }
        Design::from_cli_units(v)
    })
}

/// [`sample_neighbourhood`] for benchmarks around a known-good centre: panics with the reason.
pub fn neighbourhood(scenario: &Scenario, centre: &Design, n: usize, spread: f64, seed: u64) -> Vec<Design> {
    sample_neighbourhood(scenario, centre, n, spread, seed).unwrap_or_else(|e| panic!("{e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scenario_no_design_fits_is_an_error_naming_the_refusal_not_a_panic() {
        // the listing draws 2000 Halton points (D.5 line 31-32): 5000 particles seat in no
        // fill (on Earth most draws pass the spill check, so the fill is the commonest refusal)
        let mut s = Scenario::earth().into_listing_compat();
        s.sim.particles = 5000;
        let e = sample_valid_designs(&s, 3, 1).unwrap_err();
        assert!(e.starts_with("found 0 of 3 designs"), "{e}");
        assert!(e.contains("fill area too small"), "{e}");
        let e = sample_neighbourhood(&s, &Design::earth_solution_c(), 3, 0.05, 1).unwrap_err();
        assert!(e.contains("neighbours") && e.contains("fill area too small"), "{e}");
    }

    #[test]
    fn the_sampled_designs_are_valid_and_repeat_with_the_seed() {
        let s = Scenario::lunar();
        let a = sample_valid_designs(&s, 20, 7).unwrap();
        assert_eq!(a.len(), 20);
        assert!(a.iter().all(|d| prepare(&s, d).is_ok()));
        assert_eq!(a, random_valid_designs(&s, 20, 7));
    }
}
