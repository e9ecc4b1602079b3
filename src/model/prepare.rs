//! Everything about a design that does not depend on the particle engine: validity,
//! profile, fill area, launch points and launch velocity (4.2.1-4.2.3).

use super::design::Design;
use super::fill::{build_fill, launch_points, listing_spill_check, Fill};
use super::geometry::{check_design, Profile, V2};
use super::scenario::{PhysicsMode, Scenario};
use super::validity::Invalid;

/// The conveyor angle the particle simulation uses: the listing forces 35° (D.1 line 47,
/// erratum 4); the physical mode uses the configured angle.
pub const LISTING_SIMULATION_ALPHA_DEG: f64 = 35.0;

#[derive(Clone, Debug)]
pub struct Prepared {
    pub design: Design,
    pub profile: Profile,
    pub fill: Fill,
    /// Launch points, global coordinates (tooth 0's p1 at the origin).
    pub launches: Vec<V2>,
    /// Global launch angle α + offset + δ, radians (listing lines 35, 167).
    pub launch_angle: f64,
    /// Extent of the base line along the conveyor from tooth 0's p1, m: to the last tooth's
    /// p1 in the listing (erratum 20), to its p4 in the text.
    pub base_length: f64,
}

pub fn simulation_alpha_deg(s: &Scenario) -> f64 {
    match s.mode {
        PhysicsMode::Physical => s.environment.alpha_deg,
        PhysicsMode::Listing => LISTING_SIMULATION_ALPHA_DEG,
    }
}

pub fn prepare(s: &Scenario, d: &Design) -> Result<Prepared, Invalid> {
    let local = check_design(d)?;
    let alpha_deg = simulation_alpha_deg(s);
    let offset_deg = s.sim.launch_offset_deg + d.delta_deg;
    if s.mode == PhysicsMode::Listing {
        // D.6 lines 61-69 use the configured α (the override of erratum 4 lives inside D.1).
        let g = s.performance.spill_check_g.unwrap_or(s.environment.g);
        listing_spill_check(s.environment.alpha_deg, s.material.aor_deg, g, offset_deg, d)?;
    }
    let profile = Profile::new(d, local, alpha_deg, s.sim.teeth);
    let launch_angle = (alpha_deg + offset_deg).to_radians();
    let fill = build_fill(&profile, s.environment.g, d, launch_angle, s.material.aor_deg, s.mode)?;
    let launches = launch_points(&fill, s.sim.particles as usize, s.mode, s.sim.launch_points, s.sim.seed)?;
    let last = (s.sim.teeth - 1) as f64 * d.l_c;
    let base_length = match s.mode {
        PhysicsMode::Listing => last,
        PhysicsMode::Physical => last + local.p4[0],
    };
    Ok(Prepared { design: *d, profile, fill, launches, launch_angle, base_length })
}
