//! The design vector the optimiser varies (thesis 5.2, listing D.5 `x(1..8)`).

use serde::{Deserialize, Serialize};

/// One sawtooth design. Lengths in metres, speeds in m/s, acceleration in m/s²; the two
/// angles are in degrees, as in the CLI and the thesis tables.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Design {
    /// Tooth pitch l_c.
    pub l_c: f64,
    /// Ramp run l_a (local horizontal from p1 to p2).
    pub l_a: f64,
    /// Tooth height l_b (local vertical from p1 to p2).
    pub l_b: f64,
    /// Catch-arc radius r.
    pub r: f64,
    /// Angle ω between catch arc and base at p4, degrees.
    pub omega_deg: f64,
    /// Launch-angle offset δ of the design, degrees (added to α and the launch offset, erratum 10).
    pub delta_deg: f64,
    /// Launch speed v0 at the end of the upstroke.
    pub v0: f64,
    /// Sled acceleration a during the upstroke.
    pub a: f64,
}

/// Names of the eight variables, in order, with the unit the CLI uses.
pub const VARIABLES: [(&str, &str); 8] = [
    ("l_c", "mm"),
    ("l_a", "mm"),
    ("l_b", "mm"),
    ("r", "mm"),
    ("omega_deg", "deg"),
    ("delta_deg", "deg"),
    ("v0", "m/s"),
    ("a", "m/s^2"),
];

/// Optimisation bounds of listing D.5 (erratum 2: Table 5.1 has its rows swapped), in CLI units
/// (mm, mm, mm, mm, deg, deg, m/s, m/s²).
pub const LOWER_BOUND_CLI: [f64; 8] = [5.0, 3.0, 2.0, 2.0, 0.0, 0.0, 0.8, 20.0];
pub const UPPER_BOUND_CLI: [f64; 8] = [50.0, 50.0, 50.0, 50.0, 120.0, 45.0, 2.0, 80.0];

/// Largest values a design may take in CLI units: far beyond the optimisation bounds (a user
/// may explore outside them), but short of values no conveyor has, which would overflow the
/// performance model (a = 1e300 m/s² asks for 4 294 967 295 wires): 1 m teeth, 100 m/s,
/// 10 000 m/s² (about 1000 g).
pub const SENSIBLE_MAX_CLI: [f64; 8] = [1000.0, 1000.0, 1000.0, 1000.0, 180.0, 90.0, 100.0, 10_000.0];

impl Design {
    /// Every variable finite and within [`SENSIBLE_MAX_CLI`]; `field` names a variable the way
    /// the user wrote it (e.g. `--design a` or `design.a_m_s2`). Signs and the angle ranges
    /// the model needs are judged later, with the geometry (`model::validity`).
    pub fn check_sensible(&self, field: impl Fn(usize) -> String) -> Result<(), String> {
        for (i, (v, max)) in self.to_cli_units().iter().zip(SENSIBLE_MAX_CLI).enumerate() {
            let unit = VARIABLES[i].1;
            if !v.is_finite() {
                return Err(format!("{} must be a finite number, got {v}", field(i)));
            }
            if v.abs() > max {
                return Err(format!("{} = {v:e} {unit} is beyond any conveyor (at most {max} {unit})", field(i)));
            }
        }
        Ok(())
    }

    /// From the CLI/Table 5.3 units: mm, mm, mm, mm, deg, deg, m/s, m/s².
    pub fn from_cli_units(v: [f64; 8]) -> Self {
        Design {
            l_c: v[0] * 1e-3,
            l_a: v[1] * 1e-3,
            l_b: v[2] * 1e-3,
            r: v[3] * 1e-3,
            omega_deg: v[4],
            delta_deg: v[5],
            v0: v[6],
            a: v[7],
        }
    }

    /// To the CLI/Table 5.3 units: mm, mm, mm, mm, deg, deg, m/s, m/s².
    pub fn to_cli_units(&self) -> [f64; 8] {
        [self.l_c * 1e3, self.l_a * 1e3, self.l_b * 1e3, self.r * 1e3, self.omega_deg, self.delta_deg, self.v0, self.a]
    }

    /// Parse `l_c,l_a,l_b,r,omega_deg,delta_deg,v0,a` in mm, mm, mm, mm, °, °, m/s, m/s².
    pub fn parse_cli(s: &str) -> Result<Self, String> {
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        if parts.len() != 8 {
            return Err(format!(
                "a design needs 8 comma-separated values l_c,l_a,l_b,r,omega_deg,delta_deg,v0,a \
                 (mm,mm,mm,mm,deg,deg,m/s,m/s^2); got {}",
                parts.len()
            ));
        }
        let mut v = [0.0; 8];
        for (i, p) in parts.iter().enumerate() {
            let (name, unit) = VARIABLES[i];
            v[i] = p.parse::<f64>().map_err(|_| format!("design field `{name}` ({unit}): `{p}` is not a number"))?;
        }
        let d = Self::from_cli_units(v);
        d.check_sensible(|i| format!("design field `{}`", VARIABLES[i].0))?;
        Ok(d)
    }

    /// True when every variable lies inside the optimisation bounds of listing D.5.
    pub fn within_bounds(&self) -> bool {
        self.to_cli_units()
            .iter()
            .zip(LOWER_BOUND_CLI.iter().zip(UPPER_BOUND_CLI.iter()))
            .all(|(x, (lo, hi))| *x >= *lo && *x <= *hi)
    }

    /// Lunar solution C with Table C.6's digits (erratum 22).
    pub fn lunar_solution_c() -> Self {
        Self::from_cli_units([47.346, 46.898, 32.183, 43.687, 1.648f64.to_degrees(), 11.964, 0.840, 32.051])
    }

    /// Terrestrial solution C with Table C.7's digits (Rep_026).
    pub fn earth_solution_c() -> Self {
        Self::from_cli_units([47.376, 45.884, 34.375, 36.916, 1.097f64.to_degrees(), 17.552, 1.299, 58.595])
    }

    /// The validation rig (Table 4.3, Profile 1 of the proof-of-concept tests).
    pub fn validation_rig() -> Self {
        Self::from_cli_units([20.0, 15.0, 5.0, 5.0, 60.0, 0.0, 1.0, 60.0])
    }
}
