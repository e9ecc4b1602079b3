//! Optional physical effects the thesis's model leaves out (issue 5), each off by default and
//! with at most two parameters. The `cpu` and `gpu` kernels apply them; the `listing` port of
//! the thesis's algorithm refuses a scenario that switches one on (`engine::make_engine_for`).

use serde::{Deserialize, Serialize};

/// The surface normal is tilted by a random angle at each impact (rough printed surfaces,
/// non-spherical grains): tilt ~ N(0, sigma).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImpactScatter {
    pub sigma_deg: f64,
}

/// Grains leave at different times of the acceleration phase: a grain that leaves early is
/// slower, speed factor 1 - speed_spread·u with u ~ U(0, 1); its direction is jittered by
/// N(0, angle_sigma). Applied to the first launch, before the ±band randomisation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LaunchSpread {
    pub speed_spread: f64,
    pub angle_sigma_deg: f64,
}

/// Particle diameters log-normal around the reference size whose drag k_drag describes:
/// d/d_ref = exp(sigma_ln z), z ~ N(0, 1); Stokes b/m ∝ 1/d² (Eq. 4.16, 4.20), so each
/// grain's k_drag is k_drag (d_ref/d)². Only matters with drag.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Polydisperse {
    pub sigma_ln: f64,
}

/// The sled keeps moving after the launch (the thesis assumes it stops): it rests for
/// `delay_s`, then returns down the slope at `return_speed_m_s` until it has travelled back
/// the stroke v0²/(2a) (the POC profile vs the delayed profile of Tests 1 and 2). Impacts are
/// computed against the moving profile, restitution on the velocity relative to it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SledMotion {
    pub delay_s: f64,
    pub return_speed_m_s: f64,
}

/// Non-linear air drag with the Schiller-Naumann coefficient (Eq. 4.15, 4.17, 4.18) instead
/// of the fitted linear k_drag: per unit mass the drag over speed is
/// k(v) = 18 μ / (ρ_p d²) · (1 + 0.15 Re^0.687), Re = ρ_air |v| d / μ, for a sphere of
/// diameter `diameter_m` and density `density_kg_m3` in sea-level air (4.1.3). Integrated as
/// Stokes flights whose k is refreshed every `QUADRATIC_DRAG_STEP_S`. Only where the
/// environment has air (drag on).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct QuadraticDrag {
    pub diameter_m: f64,
    pub density_kg_m3: f64,
}

/// Sea-level air (4.1.3): density, kg/m³, and dynamic viscosity, Pa s.
pub const AIR_DENSITY: f64 = 1.225;
pub const AIR_VISCOSITY: f64 = 1.81e-5;
/// Length of the piecewise-Stokes steps of the quadratic-drag integration, s.
pub const QUADRATIC_DRAG_STEP_S: f64 = 0.02;

impl QuadraticDrag {
    /// Stokes part 18 μ / (ρ_p d²), 1/s, and Re per unit speed ρ_air d / μ, s/m.
    pub fn coefficients(&self) -> (f64, f64) {
        (18.0 * AIR_VISCOSITY / (self.density_kg_m3 * self.diameter_m.powi(2)), AIR_DENSITY * self.diameter_m / AIR_VISCOSITY)
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Effects {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quadratic_drag: Option<QuadraticDrag>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sled_motion: Option<SledMotion>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub impact_scatter: Option<ImpactScatter>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub launch_spread: Option<LaunchSpread>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub polydisperse: Option<Polydisperse>,
}

/// Names as the CLI spells them.
pub const EFFECT_NAMES: [&str; 5] = ["impact-scatter", "launch-spread", "polydisperse", "sled-motion", "quadratic-drag"];

impl Effects {
    pub fn is_default(&self) -> bool {
        *self == Effects::default()
    }

    pub fn any(&self) -> bool {
        self.impact_scatter.is_some() || self.launch_spread.is_some() || self.polydisperse.is_some() || self.sled_motion.is_some() || self.quadratic_drag.is_some()
    }

    /// Names of the effects switched on.
    pub fn active(&self) -> Vec<&'static str> {
        let mut v = Vec::new();
        if self.impact_scatter.is_some() {
            v.push("impact-scatter");
        }
        if self.launch_spread.is_some() {
            v.push("launch-spread");
        }
        if self.polydisperse.is_some() {
            v.push("polydisperse");
        }
        if self.sled_motion.is_some() {
            v.push("sled-motion");
        }
        if self.quadratic_drag.is_some() {
            v.push("quadratic-drag");
        }
        v
    }

    /// Parse `NAME=p1[,p2]` (CLI): impact-scatter=SIGMA_DEG, launch-spread=SPEED,ANGLE_DEG,
    /// polydisperse=SIGMA_LN, sled-motion=DELAY_S,RETURN_SPEED_M_S,
    /// quadratic-drag=DIAMETER_M,DENSITY_KG_M3.
    pub fn set_from_cli(&mut self, spec: &str) -> Result<(), String> {
        let (name, params) = spec.split_once('=').ok_or_else(|| format!("--effect `{spec}`: expected NAME=PARAMS, e.g. impact-scatter=5"))?;
        let values: Vec<f64> = params
            .split(',')
            .map(|p| p.trim().parse::<f64>().map_err(|_| format!("--effect {name}: `{p}` is not a number")))
            .collect::<Result<_, _>>()?;
        let want = |n: usize| {
            if values.len() == n {
                Ok(())
            } else {
                Err(format!("--effect {name} takes {n} value(s), got {}", values.len()))
            }
        };
        match name {
            "impact-scatter" => {
                want(1)?;
                self.impact_scatter = Some(ImpactScatter { sigma_deg: values[0] });
            }
            "launch-spread" => {
                want(2)?;
                self.launch_spread = Some(LaunchSpread { speed_spread: values[0], angle_sigma_deg: values[1] });
            }
            "polydisperse" => {
                want(1)?;
                self.polydisperse = Some(Polydisperse { sigma_ln: values[0] });
            }
            "sled-motion" => {
                want(2)?;
                self.sled_motion = Some(SledMotion { delay_s: values[0], return_speed_m_s: values[1] });
            }
            "quadratic-drag" => {
                want(2)?;
                self.quadratic_drag = Some(QuadraticDrag { diameter_m: values[0], density_kg_m3: values[1] });
            }
            other => return Err(format!("--effect: unknown effect `{other}` (known: {})", EFFECT_NAMES.join(", "))),
        }
        self.validate()
    }

    pub fn validate(&self) -> Result<(), String> {
        let check = |name: &str, v: f64, lo: f64, hi: f64| {
            if v.is_finite() && v >= lo && v <= hi {
                Ok(())
            } else {
                Err(format!("`effects.{name}` must lie in [{lo}, {hi}], got {v}"))
            }
        };
        if let Some(e) = self.impact_scatter {
            check("impact_scatter.sigma_deg", e.sigma_deg, 0.0, 45.0)?;
        }
        if let Some(e) = self.launch_spread {
            check("launch_spread.speed_spread", e.speed_spread, 0.0, 0.95)?;
            check("launch_spread.angle_sigma_deg", e.angle_sigma_deg, 0.0, 45.0)?;
        }
        if let Some(e) = self.polydisperse {
            check("polydisperse.sigma_ln", e.sigma_ln, 0.0, 1.5)?;
        }
        if let Some(e) = self.sled_motion {
            check("sled_motion.delay_s", e.delay_s, 0.0, 100.0)?;
            check("sled_motion.return_speed_m_s", e.return_speed_m_s, 1e-6, 10.0)?;
        }
        if let Some(e) = self.quadratic_drag {
            check("quadratic_drag.diameter_m", e.diameter_m, 1e-6, 0.01)?;
            check("quadratic_drag.density_kg_m3", e.density_kg_m3, 100.0, 20_000.0)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cli_specs_parse_and_reject() {
        let mut e = Effects::default();
        e.set_from_cli("impact-scatter=5").unwrap();
        e.set_from_cli("launch-spread=0.3,4").unwrap();
        e.set_from_cli("polydisperse=0.4").unwrap();
        assert_eq!(e.active(), vec!["impact-scatter", "launch-spread", "polydisperse"]);
        assert!(e.set_from_cli("rotation=1").unwrap_err().contains("unknown effect"));
        assert!(e.set_from_cli("launch-spread=0.3").unwrap_err().contains("takes 2"));
        assert!(e.set_from_cli("impact-scatter=90").unwrap_err().contains("sigma_deg"));
    }
}
