//! A shared parameter that varies across the conditions of a joint calibration (issue 43,
//! item 1). A calibration made in one regime does not carry to another (docs/dem.md: the deep
//! fill's k_elastic and μ fit their own campaign and miss the v0 and slope campaigns by
//! 400-2100 %²), because the model's k_elastic and μ are effective values of one bounce that
//! absorb regime-dependent losses. Where the data ask for it, a parameter may then vary with
//! a stated variable of the condition in a stated form: here linear,
//! p(condition) = p + slope · (variable − the conditions' mean), clamped into the
//! parameter's bounds. The slope is one more searched dimension of the space.

use super::condition::Condition;
use super::param::Param;

/// What a varying parameter depends on: a quantity every condition states.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Covariate {
    /// The launch speed v0 (m/s, [design] v0_m_s).
    V0,
    /// The sled's acceleration a (m/s², [design] a_m_s2).
    A,
    /// The conveyor's slope α (degrees, [environment] alpha_deg).
    Alpha,
}

impl Covariate {
    pub const ALL: [Covariate; 3] = [Covariate::V0, Covariate::A, Covariate::Alpha];

    /// The name as the setups spell it (with its unit).
    pub fn name(self) -> &'static str {
        match self {
            Covariate::V0 => "v0_m_s",
            Covariate::A => "a_m_s2",
            Covariate::Alpha => "alpha_deg",
        }
    }

    /// The condition's value, in the unit of [`Self::name`].
    pub fn of(self, c: &Condition) -> f64 {
        match self {
            Covariate::V0 => c.design.v0,
            Covariate::A => c.design.a,
            Covariate::Alpha => c.base.environment.alpha_deg,
        }
    }
}

/// One parameter varying linearly with one covariate over a set of conditions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Varying {
    pub param: Param,
    pub covariate: Covariate,
    /// The conditions' mean of the covariate: the shared value is the parameter there.
    pub centre: f64,
    /// The slope's search box is ±this: the parameter's whole range across the conditions'
    /// range of the covariate.
    pub slope_bound: f64,
}

impl Varying {
    /// `param` linear in `covariate` over `conditions`; refused where the conditions do not
    /// spread the covariate (a slope they cannot see).
    pub fn new(param: Param, covariate: Covariate, conditions: &[Condition]) -> Result<Self, String> {
        let values: Vec<f64> = conditions.iter().map(|c| covariate.of(c)).collect();
        let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        // NaN-safe: a spread that is not a positive number is none
        if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
            return Err(format!(
                "{} cannot vary with {}: every condition has {} = {lo} (it needs at least two values)",
                param.name(),
                covariate.name(),
                covariate.name()
            ));
        }
        let (p_lo, p_hi) = param.bounds();
        Ok(Varying {
            param,
            covariate,
            centre: values.iter().sum::<f64>() / values.len() as f64,
            slope_bound: (p_hi - p_lo) / (hi - lo),
        })
    }

    /// The slope's name in the space (e.g. `k_elastic_slope_v0_m_s`: k_elastic per m/s).
    pub fn slope_name(&self) -> &'static str {
        use Covariate::*;
        use Param::*;
        match (self.param, self.covariate) {
            (KElastic, V0) => "k_elastic_slope_v0_m_s",
            (KElastic, A) => "k_elastic_slope_a_m_s2",
            (KElastic, Alpha) => "k_elastic_slope_alpha_deg",
            (MuFric, V0) => "mu_fric_slope_v0_m_s",
            (MuFric, A) => "mu_fric_slope_a_m_s2",
            (MuFric, Alpha) => "mu_fric_slope_alpha_deg",
            (KDrag, V0) => "k_drag_slope_v0_m_s",
            (KDrag, A) => "k_drag_slope_a_m_s2",
            (KDrag, Alpha) => "k_drag_slope_alpha_deg",
            (VLimit, V0) => "v_limit_slope_v0_m_s",
            (VLimit, A) => "v_limit_slope_a_m_s2",
            (VLimit, Alpha) => "v_limit_slope_alpha_deg",
        }
    }

    pub fn slope_bounds(&self) -> (f64, f64) {
        (-self.slope_bound, self.slope_bound)
    }

    /// The parameter in condition `c` from its shared value `at_centre` and `slope`.
    pub fn value_in(&self, at_centre: f64, slope: f64, c: &Condition) -> f64 {
        let (lo, hi) = self.param.bounds();
        (at_centre + slope * (self.covariate.of(c) - self.centre)).clamp(lo, hi)
    }
}

/// `--vary k_elastic:v0_m_s,mu_fric:alpha_deg`: (parameter, covariate) pairs, each parameter
/// at most once.
pub fn parse_varying(list: &str) -> anyhow::Result<Vec<(Param, Covariate)>> {
    let mut out: Vec<(Param, Covariate)> = Vec::new();
    for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let Some((p, c)) = item.split_once(':') else {
            anyhow::bail!("`{item}` is not PARAM:VARIABLE (e.g. k_elastic:v0_m_s)");
        };
        let param = super::param::parse_params(p.trim())?;
        let [param] = param[..] else {
            anyhow::bail!("`{item}`: one parameter before the colon");
        };
        let covariate = Covariate::ALL.into_iter().find(|v| v.name() == c.trim()).ok_or_else(|| {
            let known: Vec<&str> = Covariate::ALL.iter().map(|v| v.name()).collect();
            anyhow::anyhow!("`{}` is not a variable a parameter can vary with (known: {})", c.trim(), known.join(", "))
        })?;
        if out.iter().any(|(q, _)| *q == param) {
            anyhow::bail!("{} varies more than once", param.name());
        }
        out.push((param, covariate));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::condition::test3;

    fn at_v0(v0: f64) -> Condition {
        let mut c = test3();
        c.design.v0 = v0;
        c
    }

    #[test]
    fn a_linear_parameter_is_its_shared_value_at_the_mean_and_moves_by_its_slope() {
        let conds = [at_v0(1.0), at_v0(1.2), at_v0(1.4)];
        let v = Varying::new(Param::KElastic, Covariate::V0, &conds).unwrap();
        assert!((v.centre - 1.2).abs() < 1e-12);
        // k_elastic's range (0.01..1) across 0.4 m/s
        assert!((v.slope_bound - 0.99 / 0.4).abs() < 1e-12);
        assert!((v.value_in(0.6, 0.5, &conds[1]) - 0.6).abs() < 1e-12);
        assert!((v.value_in(0.6, 0.5, &conds[2]) - 0.7).abs() < 1e-12);
        assert!((v.value_in(0.6, 0.5, &conds[0]) - 0.5).abs() < 1e-12);
        // never outside the parameter's bounds
        assert_eq!(v.value_in(0.9, 2.0, &conds[2]), 1.0);
        assert_eq!(v.value_in(0.1, 2.0, &conds[0]), 0.01);
    }

    #[test]
    fn a_variable_the_conditions_do_not_spread_is_refused_by_name() {
        let conds = [at_v0(1.1), at_v0(1.1)];
        let e = Varying::new(Param::MuFric, Covariate::V0, &conds).unwrap_err();
        assert!(e.contains("mu_fric cannot vary with v0_m_s"), "{e}");
    }

    #[test]
    fn the_flag_names_a_parameter_and_a_variable() {
        let v = parse_varying("k_elastic:v0_m_s, mu_fric:alpha_deg").unwrap();
        assert_eq!(v, [(Param::KElastic, Covariate::V0), (Param::MuFric, Covariate::Alpha)]);
        assert!(parse_varying("k_elastic").unwrap_err().to_string().contains("PARAM:VARIABLE"));
        assert!(parse_varying("k_elastic:speed").unwrap_err().to_string().contains("known: v0_m_s, a_m_s2, alpha_deg"));
        assert!(parse_varying("k_elastic:v0_m_s,k_elastic:a_m_s2").unwrap_err().to_string().contains("more than once"));
        assert!(parse_varying("k_el:v0_m_s").is_err());
    }
}
