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

impl Design {
    /// Every variable within what a sawtooth can be (`schema::DESIGN`, in CLI units: far
    /// beyond the optimisation bounds, as a user may explore outside them, but short of values
    /// no conveyor has: a = 1e300 m/s² would ask the performance model for 4 294 967 295
    /// wires, v0 = 1e-320 m/s launches nothing); `field` names a variable the way the user
    /// wrote it (e.g. `--design a` or `design.a_m_s2`). The chain and the constraints of 5.2
    /// are judged later, with the geometry (`model::validity`).
    pub fn check_sensible(&self, field: impl Fn(usize) -> String) -> Result<(), String> {
        for (i, (v, bound)) in self.to_cli_units().iter().zip(&crate::schema::DESIGN).enumerate() {
            bound.check(&field(i), *v)?;
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

    /// Parse `l_c,l_a,l_b,r,omega_deg,delta_deg,v0,a` in mm, mm, mm, mm, °, °, m/s, m/s²
    /// (the order and units of [`DesignRow`]).
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

/// The eight design variables in user units, named as every file spells them: the columns
/// of every CSV (pareto.csv, evaluations.csv, the sweep and study tables), the keys of a
/// config's `[design]` table and of the JSON reports, and the column names the Python
/// package documents. A table row takes it with `#[serde(flatten)]` (`io::table` writes
/// such rows; `io::table::optional_columns` an optional one), so the eight names, their
/// order and their units are written down once, here.
///
/// Values are [`Design::to_cli_units`]' exactly (mm = m × 1e3), so a file written from a
/// design and read back gives the same bits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DesignRow {
    pub l_c_mm: f64,
    pub l_a_mm: f64,
    pub l_b_mm: f64,
    pub r_mm: f64,
    pub omega_deg: f64,
    pub delta_deg: f64,
    pub v0_m_s: f64,
    pub a_m_s2: f64,
}

impl DesignRow {
    /// The column names, in order (a unit in every name that is not SI).
    pub const COLUMNS: [&'static str; 8] =
        ["l_c_mm", "l_a_mm", "l_b_mm", "r_mm", "omega_deg", "delta_deg", "v0_m_s", "a_m_s2"];

    pub fn of(d: &Design) -> Self {
        Self::from_values(d.to_cli_units())
    }

    /// From the eight values in [`Self::COLUMNS`]' order and units.
    pub fn from_values(v: [f64; 8]) -> Self {
        let [l_c_mm, l_a_mm, l_b_mm, r_mm, omega_deg, delta_deg, v0_m_s, a_m_s2] = v;
        DesignRow { l_c_mm, l_a_mm, l_b_mm, r_mm, omega_deg, delta_deg, v0_m_s, a_m_s2 }
    }

    /// The eight values in [`Self::COLUMNS`]' order and units.
    pub fn values(&self) -> [f64; 8] {
        [self.l_c_mm, self.l_a_mm, self.l_b_mm, self.r_mm, self.omega_deg, self.delta_deg, self.v0_m_s, self.a_m_s2]
    }

    /// The design in SI (angles stay in degrees, as in [`Design`]), unchecked.
    pub fn design(&self) -> Design {
        Design::from_cli_units(self.values())
    }

    /// The design, every value finite and sensible ([`Design::check_sensible`]); an error
    /// names the column as the user wrote it, after `prefix` (`design.` in a config file).
    pub fn checked_design(&self, prefix: &str) -> Result<Design, String> {
        let d = self.design();
        d.check_sensible(|i| format!("{prefix}{}", Self::COLUMNS[i]))?;
        Ok(d)
    }

    /// The `--design` argument that gives this design back: mm and m/s to 3 decimals,
    /// angles and m/s² to 2 (what the optimiser's picks print for the user to copy).
    pub fn cli_argument(&self) -> String {
        let v = self.values();
        format!("{:.3},{:.3},{:.3},{:.3},{:.2},{:.2},{:.3},{:.2}", v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7])
    }

    /// A config file's `[design]` table with every value exact (`{}` is the shortest form
    /// that reads back to the same f64), one key per line.
    pub fn config_table(&self) -> String {
        let mut t = String::from("[design]\n");
        for (name, v) in Self::COLUMNS.iter().zip(self.values()) {
            t.push_str(&format!("{name} = {v}\n"));
        }
        t
    }
}

/// One readable line with the units, for reports, progress lines and figure titles:
/// `l_c 20.000 l_a 15.000 l_b 5.000 r 5.000 mm, omega 60.00 delta 0.00 deg, v0 1.000 m/s, a 60.00 m/s2`.
impl std::fmt::Display for DesignRow {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [l_c, l_a, l_b, r, omega, delta, v0, a] = self.values();
        write!(
            f,
            "l_c {l_c:.3} l_a {l_a:.3} l_b {l_b:.3} r {r:.3} mm, omega {omega:.2} delta {delta:.2} deg, v0 {v0:.3} m/s, a {a:.2} m/s2"
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_design_row_holds_the_cli_units_and_gives_the_same_design_back() {
        let d = Design::lunar_solution_c();
        let row = DesignRow::of(&d);
        assert_eq!(row.values(), d.to_cli_units());
        assert_eq!(row.design(), d);
        assert_eq!(DesignRow::from_values(row.values()), row);
        assert_eq!(row.l_c_mm, 47.346);
        assert_eq!(row.omega_deg, 1.648f64.to_degrees());
    }

    #[test]
    fn a_design_row_names_its_columns_in_order_wherever_it_is_serialized() {
        let v = serde_json::to_value(DesignRow::of(&Design::validation_rig())).unwrap();
        let keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
        let mut sorted = DesignRow::COLUMNS.to_vec();
        sorted.sort_unstable();
        assert_eq!(keys, sorted);
        // every column has a unit in its name, and the CLI's VARIABLES in the same order
        for (c, (name, _)) in DesignRow::COLUMNS.iter().zip(VARIABLES) {
            assert!(c.starts_with(name), "{c} vs {name}");
        }
    }

    #[test]
    fn the_cli_argument_and_the_config_table_read_back() {
        let row = DesignRow::of(&Design::validation_rig());
        assert_eq!(row.cli_argument(), "20.000,15.000,5.000,5.000,60.00,0.00,1.000,60.00");
        assert_eq!(Design::parse_cli(&row.cli_argument()).unwrap(), Design::validation_rig());
        let c = DesignRow::of(&Design::lunar_solution_c());
        let text = c.config_table();
        assert!(text.starts_with("[design]\nl_c_mm = 47.346\n"), "{text}");
        #[derive(Deserialize)]
        struct File {
            design: DesignRow,
        }
        let back: File = toml::from_str(&text).unwrap();
        assert_eq!(back.design, c);
    }

    #[test]
    fn a_design_row_reads_as_one_line_with_its_units() {
        let row = DesignRow::of(&Design::validation_rig());
        assert_eq!(
            row.to_string(),
            "l_c 20.000 l_a 15.000 l_b 5.000 r 5.000 mm, omega 60.00 delta 0.00 deg, v0 1.000 m/s, a 60.00 m/s2"
        );
    }

    #[test]
    fn a_checked_design_names_the_users_field() {
        let mut row = DesignRow::of(&Design::validation_rig());
        assert!(row.checked_design("design.").is_ok());
        row.a_m_s2 = 1e300;
        let e = row.checked_design("design.").unwrap_err();
        assert!(e.starts_with("design.a_m_s2 must lie in [0.01, 10000] m/s^2"), "{e}");
        assert!(e.ends_with("got 1e300"), "{e}");
        row.a_m_s2 = f64::NAN;
        assert!(row.checked_design("[design] ").unwrap_err().starts_with("[design] a_m_s2 must lie in"));
        // issue 45: a launch of 1e-320 m/s launches nothing; delta 0 is Table 5.1's lower bound
        let mut row = DesignRow::of(&Design::validation_rig());
        row.v0_m_s = 1e-320;
        assert!(row.checked_design("").unwrap_err().starts_with("v0_m_s must lie in [0.01, 100] m/s"));
        let mut row = DesignRow::of(&Design::validation_rig());
        row.delta_deg = 0.0;
        assert!(row.checked_design("").is_ok());
    }

    #[test]
    fn unknown_keys_are_refused_in_a_design_table() {
        let e = toml::from_str::<DesignRow>("l_c = 1.0").unwrap_err().to_string();
        assert!(e.contains("unknown field `l_c`"), "{e}");
    }
}
