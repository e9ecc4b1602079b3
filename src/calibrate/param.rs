//! The parameters a calibration fits (listing D.4's `k_elastic`, `mu_fric`, `k_drag`): their
//! names on the command line and in the outputs, their bounds, and how each sets and reads a
//! scenario. Every client of the calibration engine (`fit`, `diagnose`) speaks of them so.

use anyhow::bail;
use serde::Serialize;

use crate::model::Scenario;

/// A fitted scenario parameter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Param {
    /// Elastic normal coefficient of restitution, `collision.k_elastic`.
    KElastic,
    /// Friction coefficient of the tangential COR, `collision.mu_friction`.
    MuFric,
    /// Stokes drag parameter, 1/s, `environment.k_drag`.
    KDrag,
    /// The thesis law's plastic limit speed, m/s, `collision.v_limit_m_s` (Eq. 4.9; Eq. 4.7
    /// gives it from the material where it is not fitted): how fast k_n falls with speed.
    VLimit,
}

impl Param {
    pub const ALL: [Param; 4] = [Param::KElastic, Param::MuFric, Param::KDrag, Param::VLimit];

    /// The name on the command line and in the outputs.
    pub fn name(self) -> &'static str {
        match self {
            Param::KElastic => "k_elastic",
            Param::MuFric => "mu_fric",
            Param::KDrag => "k_drag",
            Param::VLimit => "v_limit",
        }
    }

    /// Listing D.4's bounds (`lb = [0.01, 0.01, 0.1]`, `ub = [1, 1, 15]`); v_limit from a
    /// little below the lunar material's Eq. 4.7 value (0.0135 m/s) to 2 m/s, above the
    /// conveyor's impacts (k_n then k_elastic at every speed, the DEM's constant COR).
    pub fn bounds(self) -> (f64, f64) {
        match self {
            Param::KElastic | Param::MuFric => (0.01, 1.0),
            Param::KDrag => (0.1, 15.0),
            Param::VLimit => (0.001, 2.0),
        }
    }

    pub fn apply(self, s: &mut Scenario, v: f64) {
        match self {
            Param::KElastic => s.collision.k_elastic = v,
            Param::MuFric => s.collision.mu_friction = v,
            Param::KDrag => s.environment.k_drag = Some(v),
            Param::VLimit => s.collision.v_limit_m_s = Some(v),
        }
    }

    /// Where the parameter lives in a config file: its table and key.
    pub fn config_key(self) -> (&'static str, &'static str) {
        match self {
            Param::KElastic => ("collision", "k_elastic"),
            Param::MuFric => ("collision", "mu_friction"),
            Param::KDrag => ("environment", "k_drag_per_s"),
            Param::VLimit => ("collision", "v_limit_m_s"),
        }
    }

    /// Why the parameter cannot be fitted on a condition of `scenario` (its setup `setup`),
    /// or None: k_drag needs air; v_limit the text's physics with the thesis's contact law
    /// (the listing's mode never uses the plastic law, errata 6 and 19; the DEM's law has one
    /// constant COR).
    pub fn refusal(self, s: &Scenario, setup: &str) -> Option<String> {
        match self {
            Param::KDrag if s.environment.k_drag.is_none() => {
                Some(format!("k_drag does not apply: the setup {setup} is in vacuum (no environment.k_drag)"))
            }
            Param::VLimit if s.mode != crate::model::PhysicsMode::Physical => Some(format!(
                "v_limit does not apply: the setup {setup} runs the listing's mode, which never uses the plastic law (errata 6, 19)"
            )),
            Param::VLimit if s.collision.law != crate::model::ContactLaw::Thesis => Some(format!(
                "v_limit does not apply: the setup {setup} runs the DEM's contact law (one constant COR, no plastic branch)"
            )),
            _ => None,
        }
    }

    /// The scenario's value (k_drag 0 in vacuum).
    pub fn get(self, s: &Scenario) -> f64 {
        match self {
            Param::KElastic => s.collision.k_elastic,
            Param::MuFric => s.collision.mu_friction,
            Param::KDrag => s.environment.k_drag.unwrap_or(0.0),
            Param::VLimit => crate::model::collision::limit_speed(&s.collision, &s.material),
        }
    }
}

/// Every parameter's name, comma-separated, for the errors that list what is known.
pub fn known_names() -> String {
    Param::ALL.iter().map(|p| p.name()).collect::<Vec<_>>().join(", ")
}

/// A comma list of parameter names (`k_elastic,mu_fric,k_drag`), each once.
pub fn parse_params(list: &str) -> anyhow::Result<Vec<Param>> {
    let mut out = Vec::new();
    for name in list.split(',').map(str::trim) {
        if name.is_empty() {
            bail!("empty parameter name in `{list}` (known: {})", known_names());
        }
        let Some(p) = Param::ALL.iter().copied().find(|p| p.name() == name) else {
            bail!("unknown parameter `{name}` (known: {})", known_names());
        };
        if out.contains(&p) {
            bail!("parameter `{name}` given twice");
        }
        out.push(p);
    }
    Ok(out)
}

/// `NAME=VALUE,...` (e.g. `k_elastic=0.854,mu_fric=0.133,k_drag=5.347`): the parameters
/// and their values, for [`evaluate_at`].
pub fn parse_assignments(list: &str) -> anyhow::Result<(Vec<Param>, Vec<f64>)> {
    let mut names = Vec::new();
    let mut values = Vec::new();
    for item in list.split(',').map(str::trim) {
        let Some((name, value)) = item.split_once('=') else {
            bail!("expected NAME=VALUE, got `{item}` (known names: {})", known_names());
        };
        let v: f64 =
            value.trim().parse().map_err(|_| anyhow::anyhow!("`{}`: not a number: `{}`", name.trim(), value.trim()))?;
        if !v.is_finite() {
            bail!("`{}` must be finite, got {v}", name.trim());
        }
        names.push(name.trim().to_string());
        values.push(v);
    }
    let params = parse_params(&names.join(","))?;
    Ok((params, values))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_parse_and_unknown_names_are_named() {
        assert_eq!(parse_params("k_elastic,mu_fric,k_drag,v_limit").unwrap(), Param::ALL.to_vec());
        assert_eq!(parse_params(" k_drag ").unwrap(), vec![Param::KDrag]);
        let e = parse_params("k_drag,gravity").unwrap_err().to_string();
        assert!(e.contains("`gravity`") && e.contains("k_elastic, mu_fric, k_drag, v_limit"), "{e}");
        assert!(parse_params("k_drag,k_drag").unwrap_err().to_string().contains("twice"));
        assert!(parse_params("").unwrap_err().to_string().contains("empty"));
    }

    #[test]
    fn params_apply_to_the_scenario() {
        let mut s = Scenario::preset(crate::model::EnvPreset::Lunar);
        Param::KDrag.apply(&mut s, 3.0);
        Param::MuFric.apply(&mut s, 0.2);
        Param::KElastic.apply(&mut s, 0.5);
        assert_eq!(s.environment.k_drag, Some(3.0));
        assert_eq!((s.collision.k_elastic, s.collision.mu_friction), (0.5, 0.2));
        // v_limit unstated is Eq. 4.7's (0.0135 m/s for lunar regolith); stated, the law uses it
        assert!((Param::VLimit.get(&s) - 0.0135).abs() < 5e-5);
        Param::VLimit.apply(&mut s, 0.3);
        assert_eq!(s.collision.v_limit_m_s, Some(0.3));
        assert_eq!(Param::ALL.map(|p| p.get(&s)), [0.5, 0.2, 3.0, 0.3]);
        let law = crate::model::collision::Restitution::new(s.mode, &s.collision, &s.material);
        // an impact at 0.2 m/s is below the stated limit: it keeps k_elastic of its normal speed
        let out = law.bounce([0.0, -0.2], [0.0, 1.0]);
        assert!((out[1] - 0.5 * 0.2).abs() < 1e-12, "{out:?}");
        // at 1.2 m/s: k_elastic (0.3 / 1.2)^¼ (Eq. 4.9)
        let out = law.bounce([0.0, -1.2], [0.0, 1.0]);
        assert!((out[1] / 1.2 - 0.5 * 0.25f64.powf(0.25)).abs() < 1e-12, "{out:?}");
    }

    #[test]
    fn assignments_parse() {
        let (p, v) = parse_assignments("k_elastic=0.854, mu_fric=0.133,k_drag=5.347,v_limit=0.2").unwrap();
        assert_eq!(p, Param::ALL.to_vec());
        assert_eq!(v, vec![0.854, 0.133, 5.347, 0.2]);
        for (bad, needle) in
            [("k_drag", "NAME=VALUE"), ("k_drag=x", "not a number"), ("g=1", "`g`"), ("k_drag=inf", "finite")]
        {
            let e = parse_assignments(bad).unwrap_err().to_string();
            // the library names the value; the CLI adds the flag (tests/fit.rs)
            assert!(!e.contains("--") && e.contains(needle), "{bad}: {e}");
        }
    }
}
