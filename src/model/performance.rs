//! The performance model: stroke, wires, cooling, frequency, mass flow, specific energy
//! (3.4.3, 5.3.1, Eq. 3.6-3.10, 5.10-5.16; listing D.7 and D.8).

use serde::Serialize;

use super::design::Design;
use super::scenario::{PerformanceParams, Scenario};

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Performance {
    /// l_stroke = v0² / (2a), m (5.3.1).
    pub stroke_m: f64,
    /// Wires needed, Eq. 3.6 with the bias force of D.5.
    pub n_wire: u32,
    /// Cooling time, s (Eq. 5.15 / D.8; erratum 14).
    pub t_cool_s: f64,
    /// Operating stroke frequency min(f, f_max), Hz (D.7 line 45).
    pub f_stroke_hz: f64,
    /// Unclipped frequency 1 / (t_up + t_down + t_cool), Hz (Eq. 5.11-5.13).
    pub f_dynamic_hz: f64,
    /// Mass flow ṁ = m_regolith (d_avg / l_conv) f, kg/s (Eq. 5.16).
    pub m_dot_kg_s: f64,
    /// Specific energy W_spec = P_avg / ṁ, J/kg (Eq. 3.10); None when ṁ ≈ 0
    /// (the listing returns the sentinel 1000042 there).
    pub w_spec_j_kg: Option<f64>,
    /// Average heating power P_avg = W_stroke f, W.
    pub p_avg_w: f64,
    /// Regolith mass on the conveyor, kg (Eq. 5.10 with D.7's tooth count, erratum 20).
    pub regolith_mass_kg: f64,
    /// Heating energy per stroke, J (Eq. 3.7 × n_wire).
    pub stroke_energy_j: f64,
}

/// Stefan-Boltzmann constant as D.8 writes it, W/(m² K⁴).
pub const STEFAN_BOLTZMANN: f64 = 5.6703e-8;

/// Eq. 5.15 / D.8: t_cool = ρ r c_p / (6 σ ε) (1/T_low³ - 1/T_high³), r the wire radius.
pub fn cooling_time(p: &PerformanceParams) -> f64 {
    let r = p.wire_diameter / 2.0;
    p.wire_density * r * p.wire_heat_capacity / (6.0 * STEFAN_BOLTZMANN * p.wire_emissivity)
        * (1.0 / p.t_low.powi(3) - 1.0 / p.t_high.powi(3))
}

/// D.7. `d_avg_m` and `fill_area_m2` come from the simulation; g and α are the configured
/// ones (the listing uses the configured α here even where its simulation forced 35°).
pub fn performance(s: &Scenario, d: &Design, d_avg_m: f64, fill_area_m2: f64) -> Performance {
    let p = &s.performance;
    let stroke = d.v0 * d.v0 / (2.0 * d.a);
    let sled_mass = p.sled_thickness * p.sled_width * p.conveyor_length * p.sled_density;
    // D.7 line 26: floor(l_conv / l_c) teeth on the conveyor (erratum 20).
    let teeth = (p.conveyor_length / d.l_c + 1e-12).floor();
    let regolith_mass = fill_area_m2 * teeth * p.regolith_width * s.material.bulk_density;
    let total = sled_mass + regolith_mass;
    let force = total * (d.a + s.environment.g * s.environment.alpha_deg.to_radians().sin());
    let wire_area = std::f64::consts::PI * (p.wire_diameter / 2.0).powi(2);
    let bias = p.wire_bias_stress * wire_area;
    let n_wire = (force / (p.wire_force - bias)).ceil().max(0.0) as u32; // Eq. 3.6
    let wire_length = stroke / p.contraction_ratio;
    // Eq. 3.7-3.8 per wire, times n_wire (D.7 line 40)
    let stroke_energy =
        p.wire_delta_t * p.wire_heat_capacity * wire_area * p.wire_density * wire_length * n_wire as f64;
    let t_cool = cooling_time(p);
    let t_stroke = d.v0 / d.a + stroke / p.downstroke_speed; // Eq. 5.12-5.13
    let f_dynamic = 1.0 / (t_stroke + t_cool); // Eq. 5.11
    let f_op = f_dynamic.min(p.f_max);
    let m_dot = regolith_mass * (d_avg_m / p.conveyor_length) * f_op; // Eq. 5.16
    let p_avg = stroke_energy * f_op;
    Performance {
        stroke_m: stroke,
        n_wire,
        t_cool_s: t_cool,
        f_stroke_hz: f_op,
        f_dynamic_hz: f_dynamic,
        m_dot_kg_s: m_dot,
        w_spec_j_kg: if m_dot > 1e-9 { Some(p_avg / m_dot) } else { None },
        p_avg_w: p_avg,
        regolith_mass_kg: regolith_mass,
        stroke_energy_j: stroke_energy,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cooling_time_is_27_54_s() {
        let t = cooling_time(&PerformanceParams::default());
        assert!((t - 27.54).abs() < 0.005, "{t}");
    }

    #[test]
    fn lunar_solution_c_stroke_and_frequency() {
        let d = Design::lunar_solution_c();
        let p = performance(&Scenario::lunar(), &d, 0.17, 1.154e-3);
        assert!((p.stroke_m * 1e3 - 11.01).abs() < 0.005, "{}", p.stroke_m);
        assert!((p.f_stroke_hz - 0.03598).abs() < 0.000005, "{}", p.f_stroke_hz);
    }
}
