//! What a DEM case needs beyond the scenario: grain count and size, slab depth, rolling
//! friction, the overlap that sets the softened modulus, when to stop. Read from a config's
//! `[dem]` table (`crate::io::config::DemTable`); each value's rule is checked here and a
//! broken rule names the key.

use serde::{Deserialize, Serialize};

use crate::io::config::{DemRestitution, DemTable};
use crate::model::effects::EffectKind;
use crate::model::{PhysicsMode, Scenario};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DemSettings {
    /// Grains in the case.
    pub particles: u32,
    /// Grain diameter, m; `None`: the diameter at which `particles` grains hold the model's
    /// fill mass (fill area × depth × bulk density).
    pub grain_diameter_m: Option<f64>,
    /// Periodic depth of the slab in grain diameters (a few: grains can pass each other, and
    /// the cost stays that of a quasi-2D case).
    pub depth_grains: f64,
    /// Rolling friction coefficient (LIGGGHTS `rolling_friction cdt`). The model has none;
    /// 0.1 is a usual value for angular grains modelled as spheres (assumption, docs/dem.md).
    pub rolling_friction: f64,
    /// Largest Hertz overlap at the design impact speed, as a fraction of the grain radius;
    /// the Young's modulus is softened down to the value that reaches it (docs/dem.md).
    pub max_overlap_fraction: f64,
    /// Simulated time after the stroke at which the run stops even if grains still move, s.
    pub max_time_s: f64,
    /// RMS grain speed below which the grains count as at rest, m/s.
    pub rest_speed_m_s: f64,
    /// Teeth of the mesh; `None`: the model's reach on a long conveyor plus a margin.
    pub teeth: Option<u32>,
    /// Where the constant normal COR comes from (`[dem] restitution`).
    #[serde(default)]
    pub restitution: DemRestitution,
}

impl Default for DemSettings {
    fn default() -> Self {
        DemSettings {
            // converged on both lunar picks and the rig (docs/dem.md, "Converged numerics"):
            // from 600, twice the grains moved A+C +0.2 % and front-1 +1.3 %, half the overlap
            // moved A+C -3.5 % and front-1 -2.4 % (inside two seed spreads); the rig 300 -> 600
            // -0.2 %; 150 grains were 5 % short on the picks
            particles: 600,
            grain_diameter_m: None,
            depth_grains: 4.0,
            rolling_friction: 0.1,
            // converged on the lunar pick A+C (docs/dem.md, "Converged numerics"): half of it
            // moved d_avg by +1.7 %, twice the grains by -3.0 % (inside two seed spreads)
            max_overlap_fraction: 0.025,
            max_time_s: 6.0,
            rest_speed_m_s: 0.005,
            teeth: None,
            restitution: DemRestitution::KElastic,
        }
    }
}

impl DemSettings {
    /// Defaults, then the `[dem]` table's keys.
    pub fn from_table(t: Option<&DemTable>) -> Self {
        let mut s = DemSettings::default();
        if let Some(t) = t {
            if let Some(v) = t.particles {
                s.particles = v;
            }
            s.grain_diameter_m = t.grain_diameter_m.or(s.grain_diameter_m);
            if let Some(v) = t.depth_grains {
                s.depth_grains = v;
            }
            if let Some(v) = t.rolling_friction {
                s.rolling_friction = v;
            }
            if let Some(v) = t.max_overlap_fraction {
                s.max_overlap_fraction = v;
            }
            if let Some(v) = t.max_time_s {
                s.max_time_s = v;
            }
            if let Some(v) = t.rest_speed_m_s {
                s.rest_speed_m_s = v;
            }
            s.teeth = t.teeth.or(s.teeth);
            s.restitution = t.restitution.unwrap_or(s.restitution);
        }
        s
    }

    /// Every value inside its rule; the message names the `[dem]` key.
    pub fn validate(&self) -> Result<(), String> {
        let within = |key: &str, v: f64, lo: f64, hi: f64| {
            if v.is_finite() && v >= lo && v <= hi {
                Ok(())
            } else {
                Err(format!("[dem] {key} must lie in [{lo}, {hi}], got {v}"))
            }
        };
        crate::schema::DEM_PARTICLES.check_u32("[dem] particles (--particles)", self.particles)?;
        if let Some(d) = self.grain_diameter_m {
            within("grain_diameter_m", d, 1e-6, 0.05)?;
        }
        within("depth_grains", self.depth_grains, 1.0, 100.0)?;
        within("rolling_friction", self.rolling_friction, 0.0, 5.0)?;
        within("max_overlap_fraction", self.max_overlap_fraction, 1e-4, 0.3)?;
        within("max_time_s", self.max_time_s, 0.01, 1000.0)?;
        within("rest_speed_m_s", self.rest_speed_m_s, 1e-6, 1.0)?;
        if let Some(t) = self.teeth {
            crate::schema::DEM_TEETH.check_u32("[dem] teeth", t)?;
        }
        Ok(())
    }
}

/// Refuse, by name, a scenario a DEM case cannot represent: the listing's compatibility mode
/// (its geometry forces α = 35° and a 10-point catch arc, erratum 4/20: no real conveyor),
/// and effects that are the model's stand-ins for what DEM computes itself (impact scatter,
/// launch spread, the fill-surface loss) or that the case does not carry yet (quadratic drag).
/// The sled's return and the polydisperse size law (as size classes, `super::sizes`) are
/// carried.
pub fn check_representable(s: &Scenario) -> Result<(), String> {
    if s.mode == PhysicsMode::Listing {
        return Err("the listing compatibility mode (--compat listing / mode = \"listing\") has no physical geometry to mesh (erratum 4: it forces alpha 35 deg); use the physical mode".into());
    }
    for kind in s.effects.active_kinds() {
        let why = match kind {
            EffectKind::SledMotion | EffectKind::Polydisperse => continue,
            EffectKind::ImpactScatter => "the DEM's grain-grain and grain-wall contacts scatter impacts themselves",
            EffectKind::LaunchSpread => "in the DEM grains leave the fill when the contacts let them, not by a law",
            EffectKind::QuadraticDrag => "the DEM case carries the linear Stokes drag (fix viscous) only",
            EffectKind::FillSurfaceLoss => {
                "the DEM's grains leave the fill through their own contacts (the effect was fitted to that)"
            }
        };
        return Err(format!("effect `{}` is not carried into a DEM case: {why}", kind.name()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_broken_rule_names_its_key() {
        let mut s = DemSettings { depth_grains: 0.5, ..Default::default() };
        assert!(s.validate().unwrap_err().contains("[dem] depth_grains"));
        s.depth_grains = 4.0;
        s.grain_diameter_m = Some(f64::NAN);
        assert!(s.validate().unwrap_err().contains("[dem] grain_diameter_m"));
        s.grain_diameter_m = None;
        s.particles = 0;
        assert!(s.validate().unwrap_err().contains("--particles"));
    }

    #[test]
    fn the_listing_mode_and_model_only_effects_are_refused_by_name() {
        let mut s = Scenario::lunar();
        assert!(check_representable(&s).is_ok());
        s.effects.set_from_cli("impact-scatter=5").unwrap();
        assert!(check_representable(&s).unwrap_err().contains("impact-scatter"));
        let s = Scenario::lunar().into_listing_compat();
        assert!(check_representable(&s).unwrap_err().contains("listing"));
    }
}
