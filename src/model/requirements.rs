//! The thesis's own requirements (Table 2.2, 2.4.1) as data, and the verdict on one
//! evaluated design: what the model can compute is judged with a margin, the rest is listed
//! as not assessed (the thesis judged its final design only afterwards, Table 5.5).
//!
//! **Operating point.** An SMA conveyor may stroke slower than its cooling limit: mass flow
//! and heating power both scale with the stroke frequency (Eq. 5.16, P_avg = W_stroke f),
//! so W_spec stays fixed and the design is judged at the frequency its operator would pick:
//! the highest feed rate up to the 48 kg/h target that keeps within the power limit, but
//! never below the 6 kg/h minimum while the design can deliver it. Each requirement can then
//! fail on its own: the feed rate when even the cooling-limited frequency delivers less than
//! the minimum, the power when the minimum feed rate already draws more than the limit.
//! Judging at the full frequency instead (as Table 5.5 did) would reject a design for being
//! able to go faster than needed.

use serde::{Deserialize, Serialize};

use super::design::Design;
use super::performance::{performance, Performance};
use super::scenario::{PerformanceParams, Scenario};

const SECONDS_PER_HOUR: f64 = 3600.0;

/// Requirements the model can compute, in the units of Table 2.2.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Requirements {
    /// Where they come from: `table-2.2` or the file they were read from.
    #[serde(default = "preset_name")]
    pub source: String,
    /// Req. 1.1: minimum feed rate, kg/h (2.4.1: 15 kg in 2.5 h = 6 kg/h).
    pub feed_rate_min_kg_h: f64,
    /// Req. 1.1: target feed rate, kg/h (Team BREMEN's 48 kg/h); a target, not a limit.
    pub feed_rate_target_kg_h: f64,
    /// Req. 1.4: largest average power draw, W.
    pub power_max_w: f64,
    /// Req. 1.6.3: the conveyor slopes the one design must work at, degrees.
    pub slope_min_deg: f64,
    pub slope_max_deg: f64,
    /// Req. 1.6.1: horizontal transport length, m; the sled is l_total = l_hor / cos(α_max)
    /// long (Eq. 3.1: 1.3054 m at 40°), and the SMA wire must fit along it (5.5).
    pub transport_length_m: f64,
}

fn preset_name() -> String {
    PRESET_TABLE_2_2.to_string()
}

/// Relative excess over a requirement that still counts as met: rounding only (a
/// power-limited operating point meets its limit only to the last bit).
pub const REQUIREMENT_TOLERANCE: f64 = 1e-9;

/// The name of the built-in preset.
pub const PRESET_TABLE_2_2: &str = "table-2.2";

/// Requirements of Table 2.2 the model cannot assess (Table 5.5 lists them as N/A).
pub const NOT_ASSESSED: [(&str, &str); 6] = [
    ("1.3", "system mass"),
    ("1.5", "dust generation"),
    ("1.7", "flow continuity"),
    ("2.x", "RAMS (reliability, availability, maintainability)"),
    ("3.x", "environmental conditions (vacuum, temperature, radiation, particle size)"),
    ("4.x", "interfaces, modularity and outer dimensions"),
];

impl Requirements {
    /// Table 2.2 as far as the model can compute it.
    pub fn table_2_2() -> Self {
        Requirements {
            source: preset_name(),
            feed_rate_min_kg_h: 6.0,
            feed_rate_target_kg_h: 48.0,
            power_max_w: 5.0,
            slope_min_deg: 0.0,
            slope_max_deg: 40.0,
            transport_length_m: 1.0,
        }
    }

    /// The built-in set named `name`.
    pub fn preset(name: &str) -> Option<Self> {
        (name == PRESET_TABLE_2_2).then(Self::table_2_2)
    }

    /// Every rule a requirement set must follow; the error names the field.
    pub fn validate(&self) -> Result<(), String> {
        use crate::schema as b;
        for (bound, name, v) in [
            (&b::REQ_FEED_RATE, "feed_rate_min_kg_h", self.feed_rate_min_kg_h),
            (&b::REQ_FEED_RATE, "feed_rate_target_kg_h", self.feed_rate_target_kg_h),
            (&b::REQ_POWER, "power_max_w", self.power_max_w),
            (&b::REQ_TRANSPORT_LENGTH, "transport_length_m", self.transport_length_m),
        ] {
            bound.check(&format!("requirements.{name}"), v)?;
        }
        if self.feed_rate_target_kg_h < self.feed_rate_min_kg_h {
            return Err(format!(
                "requirements.feed_rate_target_kg_h ({}) must be at least feed_rate_min_kg_h ({})",
                self.feed_rate_target_kg_h, self.feed_rate_min_kg_h
            ));
        }
        for (name, v) in [("slope_min_deg", self.slope_min_deg), ("slope_max_deg", self.slope_max_deg)] {
            b::REQ_SLOPE.check(&format!("requirements.{name}"), v)?;
        }
        if self.slope_min_deg > self.slope_max_deg {
            return Err(format!(
                "requirements.slope_min_deg ({}) must not exceed slope_max_deg ({})",
                self.slope_min_deg, self.slope_max_deg
            ));
        }
        Ok(())
    }

    /// Eq. 3.1: l_total = l_hor / cos(α_max), m.
    pub fn sled_length_m(&self) -> f64 {
        self.transport_length_m / self.slope_max_deg.to_radians().cos()
    }

    /// The verdict on one design evaluated at one slope.
    pub fn assess(&self, p: &Performance, perf: &PerformanceParams, lost_fraction: f64) -> Assessment {
        let op = self.operating_point(p);
        let m_dot_max_kg_h = p.m_dot_kg_s * SECONDS_PER_HOUR;
        let wire_length_m = p.stroke_m / perf.contraction_ratio; // 5.5: l_wire = l_stroke / ε
        let sled_length_m = self.sled_length_m();
        Assessment {
            feed_rate: Verdict::limit(op.m_dot_kg_h - self.feed_rate_min_kg_h, self.feed_rate_min_kg_h),
            feed_rate_target_met: op.m_dot_kg_h >= self.feed_rate_target_kg_h * (1.0 - 1e-12),
            power: Verdict::limit(self.power_max_w - op.p_avg_w, self.power_max_w),
            wire_length: Verdict::limit(sled_length_m - wire_length_m, sled_length_m),
            m_dot_max_kg_h,
            wire_length_m,
            sled_length_m,
            lost_fraction,
            operating_point: op,
        }
    }

    /// The verdict on a design the model rejects at this scenario (e.g. 5.3.1's spill check):
    /// it delivers nothing there (D.7 with no travel and no fill: ṁ = 0, no W_spec) and loses
    /// everything, while its stroke still sets the wire.
    pub fn assess_rejected(&self, s: &Scenario, d: &Design) -> Assessment {
        self.assess(&performance(s, d, 0.0, 0.0), &s.performance, 1.0)
    }

    /// See the module doc: the highest feed rate up to the target within the power limit,
    /// held at the minimum where the power limit would push it lower.
    pub fn operating_point(&self, p: &Performance) -> OperatingPoint {
        let m_max = p.m_dot_kg_s * SECONDS_PER_HOUR;
        let Some(w_spec) = p.w_spec_j_kg.filter(|_| m_max > 0.0) else {
            return OperatingPoint { f_stroke_hz: 0.0, m_dot_kg_h: 0.0, p_avg_w: 0.0, limit: Limit::Capacity };
        };
        let m_at_power = self.power_max_w / w_spec * SECONDS_PER_HOUR; // P = W_spec ṁ
        let (mut m, mut limit) = (m_max, Limit::Capacity);
        if self.feed_rate_target_kg_h < m {
            (m, limit) = (self.feed_rate_target_kg_h, Limit::Target);
        }
        if m_at_power < m {
            (m, limit) = (m_at_power, Limit::Power);
        }
        if m < self.feed_rate_min_kg_h {
            // back up to the minimum feed rate, or to all the design delivers
            (m, limit) = if m_max < self.feed_rate_min_kg_h {
                (m_max, Limit::Capacity)
            } else {
                (self.feed_rate_min_kg_h, Limit::Minimum)
            };
        }
        let share = m / m_max;
        OperatingPoint {
            f_stroke_hz: p.f_stroke_hz * share,
            m_dot_kg_h: m,
            p_avg_w: w_spec * m / SECONDS_PER_HOUR,
            limit,
        }
    }
}

/// Where the design is run (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct OperatingPoint {
    pub f_stroke_hz: f64,
    pub m_dot_kg_h: f64,
    pub p_avg_w: f64,
    pub limit: Limit,
}

/// What sets the operating feed rate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Limit {
    /// The cooling-limited frequency (Eq. 5.11): the design delivers no more.
    Capacity,
    /// The target feed rate: running faster gains nothing the requirements ask for.
    Target,
    /// The power limit: faster would draw more than allowed.
    Power,
    /// Held at the minimum feed rate although that exceeds the power limit.
    Minimum,
}

impl Limit {
    pub fn as_str(self) -> &'static str {
        match self {
            Limit::Capacity => "capacity",
            Limit::Target => "target",
            Limit::Power => "power",
            Limit::Minimum => "minimum",
        }
    }
}

/// One requirement's outcome: the margin in the requirement's unit (positive = met) and the
/// same relative to the limit, which is what the optimiser's constraints use.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Verdict {
    pub margin: f64,
    pub relative_margin: f64,
}

impl Verdict {
    fn limit(margin: f64, scale: f64) -> Self {
        Verdict { margin, relative_margin: margin / scale }
    }
    /// Met, allowing for rounding: at a power-limited operating point P = W_spec ṁ equals
    /// the limit only to the last bit.
    pub fn met(&self) -> bool {
        self.relative_margin >= -REQUIREMENT_TOLERANCE
    }
}

/// The assessable requirements of Table 2.2 for one design at one slope.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Assessment {
    /// 1.1 minimum feed rate at the operating point, margin in kg/h.
    pub feed_rate: Verdict,
    /// 1.1 target reached at the operating point.
    pub feed_rate_target_met: bool,
    /// 1.4 power at the operating point, margin in W.
    pub power: Verdict,
    /// 5.5 / Eq. 3.1 wire length within the sled, margin in m.
    pub wire_length: Verdict,
    pub m_dot_max_kg_h: f64,
    pub wire_length_m: f64,
    pub sled_length_m: f64,
    /// 1.2 material loss: reported, the thesis sets no limit ("minimised").
    pub lost_fraction: f64,
    pub operating_point: OperatingPoint,
}

impl Assessment {
    pub fn compliant(&self) -> bool {
        self.feed_rate.met() && self.power.met() && self.wire_length.met()
    }

    /// Constraint values c <= 0 feasible, relative to each limit (Deb's rules add them).
    pub fn constraints(&self) -> [f64; 3] {
        [-self.feed_rate.relative_margin, -self.power.relative_margin, -self.wire_length.relative_margin]
    }

    /// The largest of [`Self::constraints`]: > 0 when some requirement fails.
    pub fn worst_constraint(&self) -> f64 {
        self.constraints().into_iter().fold(f64::NEG_INFINITY, f64::max)
    }

    /// The requirement that fails by the largest relative amount, if any.
    pub fn binding(&self) -> Option<&'static str> {
        let named =
            [("1.1 feed rate", self.feed_rate), ("1.4 power", self.power), ("5.5 wire length", self.wire_length)];
        named
            .iter()
            .filter(|(_, v)| !v.met())
            .min_by(|a, b| a.1.relative_margin.total_cmp(&b.1.relative_margin))
            .map(|(n, _)| *n)
    }
}

/// The worst case over the slopes a design was evaluated at (req. 1.6.3): compliant only if
/// compliant at every slope; the assessment shown is the one at the slope that fails worst,
/// or, when all pass, the one with the lowest feed rate at its operating point (the slope
/// that limits the conveyor; margins alone tie where every slope is power-limited).
pub fn worst_over_slopes(per_slope: &[(f64, Assessment)]) -> Option<(f64, Assessment)> {
    let key = |a: &Assessment| {
        let c = a.worst_constraint();
        if c > REQUIREMENT_TOLERANCE {
            (1.0_f64, c)
        } else {
            (0.0, -a.operating_point.m_dot_kg_h)
        }
    };
    per_slope
        .iter()
        .max_by(|a, b| {
            let (ka, kb) = (key(&a.1), key(&b.1));
            ka.0.total_cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
        })
        .cloned()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A performance record with the figures that matter here (the rest zero).
    fn perf(m_dot_kg_h: f64, w_spec: f64, f_hz: f64, stroke_m: f64) -> Performance {
        let m = m_dot_kg_h / 3600.0;
        Performance {
            stroke_m,
            n_wire: 1,
            t_cool_s: 0.0,
            f_stroke_hz: f_hz,
            f_dynamic_hz: f_hz,
            m_dot_kg_s: m,
            w_spec_j_kg: Some(w_spec),
            p_avg_w: w_spec * m,
            regolith_mass_kg: 0.0,
            stroke_energy_j: 0.0,
        }
    }

    #[test]
    fn sled_length_is_eq_3_1() {
        // 1 m / cos 40° = 1.3054 m (3.4.3)
        assert!((Requirements::table_2_2().sled_length_m() - 1.3054).abs() < 5e-5);
    }

    #[test]
    fn thesis_solution_c_runs_power_limited_below_the_target() {
        // Table 5.5: 70.272 kg/h at 8.017 W, i.e. W_spec = 8.017 / (70.272/3600) = 410.7 J/kg.
        // Hand-worked: at 5 W it delivers 5 / 410.7 × 3600 = 43.83 kg/h, 62.4 % of the full
        // frequency; 43.83 ≥ 6 (met, margin 37.83 kg/h), < 48 (target missed), P = 5 W.
        let w = 8.017 / (70.272 / 3600.0);
        let p = perf(70.272, w, 0.03598, 0.011);
        let r = Requirements::table_2_2();
        let a = r.assess(&p, &PerformanceParams::default(), 0.1);
        let op = a.operating_point;
        assert_eq!(op.limit, Limit::Power);
        assert!((op.m_dot_kg_h - 43.828).abs() < 0.01, "{op:?}");
        assert!((op.p_avg_w - 5.0).abs() < 1e-9);
        assert!((op.f_stroke_hz - 0.03598 * 43.828 / 70.272).abs() < 1e-5);
        assert!((a.feed_rate.margin - 37.828).abs() < 0.01);
        assert!(!a.feed_rate_target_met);
        assert!(a.power.met() && a.power.margin.abs() < 1e-9);
        // 11 mm stroke / 5 % = 0.22 m of wire (5.5: "220 mm"), 1.0854 m shorter than the sled
        assert!((a.wire_length_m - 0.22).abs() < 1e-12);
        assert!((a.wire_length.margin - (1.3054 - 0.22)).abs() < 1e-4);
        assert!(a.compliant());
        assert_eq!(a.binding(), None);
    }

    #[test]
    fn a_cheap_fast_design_runs_at_the_target() {
        // 131 kg/h at 100 J/kg: 48 kg/h draws 100 × 48 / 3600 = 1.333 W
        let a = Requirements::table_2_2().assess(&perf(131.0, 100.0, 0.5, 0.01), &PerformanceParams::default(), 0.0);
        assert_eq!(a.operating_point.limit, Limit::Target);
        assert!((a.operating_point.p_avg_w - 4.0 / 3.0).abs() < 1e-9);
        assert!((a.power.margin - (5.0 - 4.0 / 3.0)).abs() < 1e-9);
        assert!(a.feed_rate_target_met && a.compliant());
    }

    #[test]
    fn a_slow_design_fails_the_feed_rate_at_capacity() {
        // 4 kg/h at 1000 J/kg: runs flat out (1.111 W) and still misses 6 kg/h by 2 kg/h
        let a = Requirements::table_2_2().assess(&perf(4.0, 1000.0, 0.02, 0.01), &PerformanceParams::default(), 0.0);
        assert_eq!(a.operating_point.limit, Limit::Capacity);
        assert!((a.feed_rate.margin + 2.0).abs() < 1e-9);
        assert!((a.feed_rate.relative_margin + 1.0 / 3.0).abs() < 1e-12);
        assert!(a.power.met());
        assert_eq!(a.binding(), Some("1.1 feed rate"));
    }

    #[test]
    fn a_slow_expensive_design_fails_both_at_capacity() {
        // 4 kg/h at 6000 J/kg: flat out it draws 6.667 W and still misses 6 kg/h
        let a = Requirements::table_2_2().assess(&perf(4.0, 6000.0, 0.02, 0.01), &PerformanceParams::default(), 0.0);
        assert_eq!(a.operating_point.limit, Limit::Capacity);
        assert!((a.operating_point.p_avg_w - 20.0 / 3.0).abs() < 1e-9);
        assert!(!a.feed_rate.met() && !a.power.met());
        // -1/3 of the feed rate against -1/3 of the power: both fail by the same share
        assert!((a.feed_rate.relative_margin + 1.0 / 3.0).abs() < 1e-12);
        assert!((a.power.relative_margin + 1.0 / 3.0).abs() < 1e-12);
    }

    #[test]
    fn an_expensive_design_is_held_at_the_minimum_and_fails_the_power() {
        // 20 kg/h at 6000 J/kg: 5 W buys 3 kg/h < 6, so it runs at 6 kg/h drawing 10 W
        let a = Requirements::table_2_2().assess(&perf(20.0, 6000.0, 0.1, 0.01), &PerformanceParams::default(), 0.0);
        assert_eq!(a.operating_point.limit, Limit::Minimum);
        assert!((a.operating_point.p_avg_w - 10.0).abs() < 1e-9);
        assert!((a.power.margin + 5.0).abs() < 1e-9 && (a.power.relative_margin + 1.0).abs() < 1e-12);
        assert!(a.feed_rate.met() && a.feed_rate.margin.abs() < 1e-9);
        assert_eq!(a.binding(), Some("1.4 power"));
    }

    #[test]
    fn a_long_stroke_needs_a_wire_longer_than_the_sled() {
        // 5.5: solution B's 90.18 mm stroke needs 1.8036 m of wire, 0.498 m more than the sled
        let a = Requirements::table_2_2().assess(&perf(131.0, 100.0, 0.5, 0.09018), &PerformanceParams::default(), 0.0);
        assert!((a.wire_length_m - 1.8036).abs() < 1e-9);
        assert!((a.wire_length.margin + 0.4982).abs() < 1e-4, "{:?}", a.wire_length);
        assert!(!a.compliant());
        assert_eq!(a.binding(), Some("5.5 wire length"));
    }

    #[test]
    fn no_mass_flow_fails_the_feed_rate_by_all_of_it() {
        let mut p = perf(0.0, 1.0, 0.03, 0.01);
        p.w_spec_j_kg = None;
        let a = Requirements::table_2_2().assess(&p, &PerformanceParams::default(), 1.0);
        assert_eq!(a.constraints()[0], 1.0);
        assert!(!a.compliant());
    }

    #[test]
    fn worst_slope_is_the_one_that_fails_most() {
        let r = Requirements::table_2_2();
        let pp = PerformanceParams::default();
        let ok = r.assess(&perf(60.0, 300.0, 0.1, 0.01), &pp, 0.0);
        let bad = r.assess(&perf(5.0, 300.0, 0.1, 0.01), &pp, 0.0);
        let (alpha, worst) = worst_over_slopes(&[(0.0, ok.clone()), (40.0, bad.clone()), (20.0, ok.clone())]).unwrap();
        assert_eq!(alpha, 40.0);
        assert_eq!(worst, bad);
        // all compliant and power-limited (margins tie at 0): the slope with the lowest feed rate
        let fast = r.assess(&perf(90.0, 300.0, 0.1, 0.01), &pp, 0.0);
        let slow = r.assess(&perf(90.0, 400.0, 0.1, 0.01), &pp, 0.0);
        assert!(fast.compliant() && slow.compliant());
        let (alpha, _) = worst_over_slopes(&[(1.0, fast.clone()), (40.0, slow), (20.0, fast)]).unwrap();
        assert_eq!(alpha, 40.0);
    }

    #[test]
    fn validation_names_the_field() {
        let mut r = Requirements::table_2_2();
        r.power_max_w = f64::NAN;
        assert!(r.validate().unwrap_err().contains("requirements.power_max_w"));
        let mut r = Requirements::table_2_2();
        r.slope_max_deg = 85.0;
        assert!(r.validate().unwrap_err().contains("requirements.slope_max_deg"));
        let mut r = Requirements::table_2_2();
        r.feed_rate_target_kg_h = 1.0;
        assert!(r.validate().unwrap_err().contains("feed_rate_target_kg_h"));
        assert!(Requirements::table_2_2().validate().is_ok());
    }
}
