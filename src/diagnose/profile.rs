//! Profile starts for the candidates' fits: each candidate's strength held at a few values
//! across its search box while the shared parameters are polished from the baseline's
//! optimum, so that the candidate's fit can start in the basin where the effect is on.
//!
//! Why: the baseline, fitted without the effect, has bent the shared parameters to mimic it,
//! and switching the effect on at those parameters makes the fit worse, not better. A
//! differential evolution seeded at the baseline's shared parameters (`effect_starts`) then
//! has to cross a narrow valley (k_drag is set to a few per cent of its box) in all
//! dimensions at once, and on a small budget it does not:
//! - a launch spread of 0.3 and 6° (k_drag 11.7 → 5.3 s⁻¹ and μ 0.63 → 0.2 between the
//!   baseline and the truth): after 10 generations the candidate was still the baseline;
//! - an impact scatter of 18° on three runs of the practice rig's fast condition (k_elastic
//!   0.34 at the baseline, 0.7 true): 30 generations left 7.3 %² where the truth scores 1.8.
//!
//! With the strength held, the shared parameters are a smooth three-parameter
//! least-squares problem that the Levenberg–Marquardt polish solves from the baseline's
//! point in a few steps; the candidate's own polish then starts from the best of these, the
//! evolution's best and the baseline's point.
//!
//! The sled-motion candidate has its own screen ([`super::motion_screen`]) and is left out.

use crate::calibrate::{Model, Search, Simulator, Solver, Space, Target};
use crate::model::effects::EffectKind;

/// Where the strength (the candidate's first free parameter) is held, as shares of its
/// search box.
pub const PROFILE_AT: [f64; 2] = [1.0 / 3.0, 2.0 / 3.0];
/// Levenberg–Marquardt iterations per held strength at most (it stops sooner once a step
/// gains less than the solver's minimum).
const PROFILE_POLISH: usize = 6;

/// Per candidate space, the profile starts in that space's parameter order (empty for the
/// sled-motion candidate and for a space without free effect parameters), with the
/// simulations of the condition set each candidate's took.
pub fn profile_starts(
    solver: &Solver,
    sim: &Simulator,
    spaces: &[Space],
    targets: &[Target],
    base_names: &[&'static str],
    base_x: &[f64],
) -> anyhow::Result<Vec<(Vec<Vec<f64>>, u64)>> {
    // (candidate, held value, pinned space, its start)
    let mut held: Vec<(usize, &'static str, f64, Space, Vec<f64>)> = Vec::new();
    for (c, space) in spaces.iter().enumerate() {
        if space.effects.contains(&EffectKind::SledMotion) {
            continue;
        }
        let Some(&(k, i)) = space.free.first() else { continue };
        let name = space.effects[k].param_names()[i];
        let (lo, hi) = space.effects[k].search_bounds()[i];
        for share in PROFILE_AT {
            let value = lo + share * (hi - lo);
            let pinned = space.pin(name, value).expect("the first free parameter is free");
            let Some(start) = start_in(&pinned, base_names, base_x) else { continue };
            held.push((c, name, value, pinned, start));
        }
    }
    let mut starts: Vec<(Vec<Vec<f64>>, u64)> = vec![(Vec::new(), 0); spaces.len()];
    if held.is_empty() {
        return Ok(starts);
    }
    let models: Vec<Model> = held
        .iter()
        .map(|(_, _, _, space, start)| Model {
            space,
            targets,
            starts: vec![start.clone()],
            search: Search::FromStarts,
        })
        .collect();
    // at the screen's particle count: the profile only has to find the basin, and the
    // candidate's polish at the full budget starts from it (at the full count the profile
    // cost more than every candidate's evolution together: 349 simulations of the conditions
    // at 12 000 particles, a diagnosis 55 → 100 CPU s)
    let polish = Solver { polish_iterations: PROFILE_POLISH, particles: solver.screen_particles, ..*solver };
    let fits = polish.polish(sim, &models, &mut |_| {})?;
    for ((c, name, value, pinned, _), fit) in held.iter().zip(fits) {
        let fitted = pinned.names();
        let x: Vec<f64> = spaces[*c]
            .names()
            .iter()
            .map(|n| match fitted.iter().position(|m| m == n) {
                Some(p) => fit.x[p],
                None if n == name => *value,
                None => unreachable!("only the held parameter leaves the pinned space"),
            })
            .collect();
        starts[*c].0.push(x);
        starts[*c].1 += fit.evaluations;
    }
    Ok(starts)
}

/// The start of a pinned space: the baseline's shared parameters, the effect's other free
/// parameters at their neutral values (the middle of their box where the effect has none:
/// quadratic drag's density).
fn start_in(space: &Space, base_names: &[&'static str], base_x: &[f64]) -> Option<Vec<f64>> {
    let bounds = space.bounds();
    space
        .names()
        .iter()
        .enumerate()
        .map(|(j, n)| {
            if let Some(p) = base_names.iter().position(|m| m == n) {
                return Some(base_x[p]);
            }
            let (k, i) = *space.free.get(j.checked_sub(space.shared.len())?)?;
            let (lo, hi) = bounds[j];
            Some(space.effects[k].neutral().map_or(0.5 * (lo + hi), |v| v[i].clamp(lo, hi)))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::condition::test3;
    use crate::calibrate::shared_params;

    #[test]
    fn a_held_start_keeps_the_baselines_shared_values_and_the_effects_neutral_others() {
        let conds = vec![test3()];
        let shared = shared_params(&conds);
        let names: Vec<&'static str> = shared.iter().map(|p| p.name()).collect();
        let base = [0.8, 0.15, 5.0];
        // launch spread held in its speed spread: the angle starts at its neutral 0
        let space = Space::new(shared.clone(), &[EffectKind::LaunchSpread], &conds);
        let held = space.pin("speed_spread", 0.3).unwrap();
        assert_eq!(held.names(), ["k_elastic", "mu_fric", "k_drag", "angle_sigma_deg"]);
        assert_eq!(start_in(&held, &names, &base), Some(vec![0.8, 0.15, 5.0, 0.0]));
        // quadratic drag has no neutral setting and drops k_drag: the density starts mid-box
        let space = Space::new(shared, &[EffectKind::QuadraticDrag], &conds);
        let held = space.pin("diameter_m", 300e-6).unwrap();
        let (lo, hi) = EffectKind::QuadraticDrag.search_bounds()[1];
        assert_eq!(start_in(&held, &names, &base), Some(vec![0.8, 0.15, 0.5 * (lo + hi)]));
    }
}
