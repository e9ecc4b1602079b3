//! Contact parameters of the case, each from a config key, and the time step.
//!
//! - Young's modulus and Poisson's ratio: the material's particle and conveyor solids
//!   (`[material] name`, Table 4.1: basalt 80 GPa, Al 6061-T6 68.9 GPa). A DEM time step
//!   resolves each contact, and a contact of basalt grains lasts about a microsecond, so the
//!   moduli are **softened**: both are scaled by one factor, down to the modulus at which the
//!   Hertz overlap of a grain hitting the wall at the design impact speed reaches
//!   `[dem] max_overlap_fraction` of its radius, and never below 5e6 Pa (LIGGGHTS refuses
//!   smaller moduli in SI units). With the restitution fixed by the COR, a softer contact
//!   changes the contact's duration, not its energy loss.
//! - Restitution: one constant normal COR for grain-grain and grain-wall contacts alike
//!   (LIGGGHTS needs it > 0: clamped to ≥ 0.01): `[collision] k_elastic` (4.1.2) by
//!   default, or with `[dem] restitution = "model"` the thesis law's k_n (Eq. 4.9) at a normal
//!   speed of the design's v0. The model's k_n falls with speed and LIGGGHTS's does not, so
//!   either leaves a residual that `sawtooth dem impact` shows impact by impact.
//! - Sliding friction: `[collision] mu_friction`, the model's μ of Eq. 4.14, as the
//!   Coulomb coefficient.
//! - Rolling friction: `[dem] rolling_friction` (the model has none).
//! - Density: `[material] name`'s particle density.
//!
//! Hertz overlap at impact speed v (effective mass m*, radius R*, modulus E*):
//! δ = (15 m* v² / (16 E* √R*))^(2/5); contact duration t_c ≈ 2.87 (m*² / (R* E*² v))^(1/5);
//! Rayleigh time T_R = π R √(ρ/G) / (0.1631 ν + 0.8766). The step is the smaller of
//! 0.2 T_R and t_c / 30.

use serde::Serialize;

use crate::model::collision::Restitution;
use crate::model::Scenario;

/// The smallest Young's modulus LIGGGHTS 3.8 accepts in SI units (issue 31), Pa.
pub const MIN_YOUNGS_MODULUS_PA: f64 = 5e6;
/// Steps per contact duration the step keeps at least.
const STEPS_PER_CONTACT: f64 = 30.0;
/// Fraction of the Rayleigh time the step keeps at most.
const RAYLEIGH_FRACTION: f64 = 0.2;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Contact {
    /// Softened moduli of the grains and the conveyor, Pa.
    pub grain_youngs_pa: f64,
    pub wall_youngs_pa: f64,
    /// The factor both real moduli were multiplied by (≤ 1).
    pub softening: f64,
    pub grain_poisson: f64,
    pub wall_poisson: f64,
    pub restitution: f64,
    pub sliding_friction: f64,
    pub rolling_friction: f64,
    pub density_kg_m3: f64,
    /// Impact speed the overlap rule is applied at, m/s.
    pub design_speed_m_s: f64,
    /// Peak grain-wall overlap at that speed over the grain radius.
    pub overlap_fraction: f64,
    pub timestep_s: f64,
}

/// The contact model of every pair and of the mesh: Hertz with tangential history (Mindlin
/// with Coulomb's limit) and constant directional torque rolling friction.
pub const CONTACT_MODEL: &str = "model hertz tangential history rolling_friction cdt";

/// The modulus above which LIGGGHTS 3.8 asks for `hard_particles yes` (its global_properties.cpp check).
pub const HARD_PARTICLES_PA: f64 = 1e9;

/// The LIGGGHTS commands that set `c`'s material properties (type 1 the grains, type 2 the
/// wall) and the pair style, and the time step: what a case and a single impact share.
pub fn property_commands(c: &Contact) -> String {
    let pair = |v: f64| format!("{v} {v} {v} {v}");
    // LIGGGHTS refuses a modulus above 1 GPa in SI units unless told the grains are hard; the
    // time step here follows the contact time (Hertz), so a stiff, converged case is legitimate.
    let hard = if c.grain_youngs_pa.max(c.wall_youngs_pa) > HARD_PARTICLES_PA { "hard_particles yes\n" } else { "" };
    format!(
        "{hard}fix m1 all property/global youngsModulus peratomtype {:e} {:e}\n\
         fix m2 all property/global poissonsRatio peratomtype {} {}\n\
         fix m3 all property/global coefficientRestitution peratomtypepair 2 {}\n\
         fix m4 all property/global coefficientFriction peratomtypepair 2 {}\n\
         fix m5 all property/global coefficientRollingFriction peratomtypepair 2 {}\n\
         pair_style gran {CONTACT_MODEL}\npair_coeff * *\ntimestep {:e}\n",
        c.grain_youngs_pa,
        c.wall_youngs_pa,
        c.grain_poisson,
        c.wall_poisson,
        pair(c.restitution),
        pair(c.sliding_friction),
        pair(c.rolling_friction),
        c.timestep_s,
    )
}

/// The model's normal COR k_n for a head-on impact at `speed` (Eq. 4.9 in the physical mode;
/// `[collision] k_elastic` below the limit velocity or under the DEM law).
pub fn model_normal_cor(s: &Scenario, speed: f64) -> f64 {
    let r = Restitution::new(s.mode, &s.collision, &s.material);
    r.bounce([0.0, -speed], [0.0, 1.0])[1] / speed
}

/// Effective modulus of a grain on the wall, Pa.
fn effective_modulus(e1: f64, nu1: f64, e2: f64, nu2: f64) -> f64 {
    1.0 / ((1.0 - nu1 * nu1) / e1 + (1.0 - nu2 * nu2) / e2)
}

/// Peak Hertz overlap of a sphere of mass m and radius r on a flat of modulus e_star at speed v.
pub fn hertz_overlap(m: f64, r: f64, e_star: f64, v: f64) -> f64 {
    (15.0 * m * v * v / (16.0 * e_star * r.sqrt())).powf(0.4)
}

/// The contact parameters for grains of diameter `d` hitting at up to `design_speed`.
pub fn contact(s: &Scenario, d: f64, design_speed: f64, rolling_friction: f64, max_overlap: f64) -> Contact {
    let (p, w) = (&s.material.particle, &s.material.conveyor);
    let r = d / 2.0;
    let m = p.density * std::f64::consts::PI * d.powi(3) / 6.0;
    let e_real = effective_modulus(p.youngs_modulus, p.poisson_ratio, w.youngs_modulus, w.poisson_ratio);
    // δ ∝ E*^(-2/5): the E* that gives the allowed overlap, as a factor on the real moduli
    let e_needed = 15.0 * m * design_speed * design_speed / (16.0 * r.sqrt() * (max_overlap * r).powf(2.5));
    let floor = MIN_YOUNGS_MODULUS_PA / p.youngs_modulus.min(w.youngs_modulus);
    let softening = (e_needed / e_real).clamp(floor, 1.0);
    let (eg, ew) = (p.youngs_modulus * softening, w.youngs_modulus * softening);
    let e_star = e_real * softening;
    let overlap = hertz_overlap(m, r, e_star, design_speed);
    let g = eg / (2.0 * (1.0 + p.poisson_ratio));
    let rayleigh = std::f64::consts::PI * r * (p.density / g).sqrt() / (0.1631 * p.poisson_ratio + 0.8766);
    let t_contact = 2.87 * (m * m / (r * e_star * e_star * design_speed)).powf(0.2);
    Contact {
        grain_youngs_pa: eg,
        wall_youngs_pa: ew,
        softening,
        grain_poisson: p.poisson_ratio,
        wall_poisson: w.poisson_ratio,
        restitution: s.collision.k_elastic.clamp(0.01, 1.0),
        sliding_friction: s.collision.mu_friction,
        rolling_friction,
        density_kg_m3: p.density,
        design_speed_m_s: design_speed,
        overlap_fraction: overlap / r,
        timestep_s: (RAYLEIGH_FRACTION * rayleigh).min(t_contact / STEPS_PER_CONTACT),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_softened_modulus_reaches_the_stated_overlap() {
        let s = Scenario::lunar();
        let c = contact(&s, 300e-6, 1.5, 0.1, 0.1);
        assert!(c.softening < 1.0 && c.grain_youngs_pa >= MIN_YOUNGS_MODULUS_PA, "{c:?}");
        assert!((c.overlap_fraction - 0.1).abs() < 1e-9, "{}", c.overlap_fraction);
        // the moduli keep their ratio
        let ratio = c.grain_youngs_pa / c.wall_youngs_pa;
        assert!((ratio - s.material.particle.youngs_modulus / s.material.conveyor.youngs_modulus).abs() < 1e-12);
        assert!(c.timestep_s > 1e-7 && c.timestep_s < 1e-4, "{}", c.timestep_s);
    }

    #[test]
    fn a_tiny_allowed_overlap_keeps_the_real_modulus_and_a_huge_one_stops_at_the_floor() {
        let s = Scenario::lunar();
        let stiff = contact(&s, 300e-6, 1.5, 0.1, 1e-4);
        assert_eq!(stiff.softening, 1.0);
        let soft = contact(&s, 300e-6, 0.01, 0.1, 0.3);
        assert!((soft.wall_youngs_pa.min(soft.grain_youngs_pa) - MIN_YOUNGS_MODULUS_PA).abs() < 1e-3);
        assert!(soft.overlap_fraction < 0.3);
    }
}
