//! The sled's motion as the model assumes it (5.3.1): from rest it accelerates at `a` along
//! the launch direction (α + launch offset + δ, listing lines 35/167) until it reaches `v0`,
//! then stops. Optionally it rests `delay_s` and returns down the slope (or back along the
//! launch direction) at `return_speed_m_s` until it has travelled back the stroke
//! v0²/(2a) — the `sled-motion` effect, or a setup's `[measurement] motion_delay_s` and
//! `motion_return_speed_m_s`. In the case this is the mesh's velocity, a LIGGGHTS
//! equal-style expression of the stroke time t (`fix move/mesh ... linear/variable`).

use serde::Serialize;

use crate::model::effects::MotionDirection;
use crate::model::{Design, Scenario};

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Return {
    pub delay_s: f64,
    pub speed_m_s: f64,
    /// Unit vector of the return (x, y).
    pub direction: [f64; 2],
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SledMotion {
    pub a_m_s2: f64,
    pub v0_m_s: f64,
    /// Unit vector of the launch direction (x, y).
    pub launch: [f64; 2],
    pub ret: Option<Return>,
}

impl SledMotion {
    /// The stroke of `d` under `s`; `known` is a setup's stated return (delay, speed), used
    /// when the scenario's `sled-motion` effect is off.
    pub fn new(s: &Scenario, d: &Design, launch_angle: f64, known: Option<(f64, f64)>) -> Self {
        let launch = [launch_angle.cos(), launch_angle.sin()];
        let alpha = s.environment.alpha_deg.to_radians();
        let down_slope = [-alpha.cos(), -alpha.sin()];
        let ret = match (s.effects.sled_motion, known) {
            (Some(m), _) => Some(Return {
                delay_s: m.delay_s,
                speed_m_s: m.return_speed_m_s,
                direction: match m.direction {
                    MotionDirection::Slope => down_slope,
                    MotionDirection::Launch => [-launch[0], -launch[1]],
                },
            }),
            (None, Some((delay_s, speed_m_s))) => Some(Return { delay_s, speed_m_s, direction: down_slope }),
            (None, None) => None,
        };
        SledMotion { a_m_s2: d.a, v0_m_s: d.v0, launch, ret }
    }

    /// End of the acceleration, s.
    pub fn t_launch(&self) -> f64 {
        self.v0_m_s / self.a_m_s2
    }

    /// l_stroke = v0²/(2a), m.
    pub fn stroke_m(&self) -> f64 {
        self.v0_m_s * self.v0_m_s / (2.0 * self.a_m_s2)
    }

    /// The return's start and end, s.
    pub fn return_window(&self) -> Option<(f64, f64)> {
        self.ret.map(|r| {
            let t0 = self.t_launch() + r.delay_s;
            (t0, t0 + self.stroke_m() / r.speed_m_s)
        })
    }

    /// When the sled has stopped for good, s.
    pub fn t_still(&self) -> f64 {
        self.return_window().map_or(self.t_launch(), |w| w.1)
    }

    /// Mesh displacement at stroke time t (x, y), m.
    pub fn displacement(&self, t: f64) -> [f64; 2] {
        let t = t.max(0.0);
        let ta = t.min(self.t_launch());
        let along = 0.5 * self.a_m_s2 * ta * ta;
        let mut d = [along * self.launch[0], along * self.launch[1]];
        if let (Some(r), Some((t0, t1))) = (self.ret, self.return_window()) {
            let back = r.speed_m_s * (t.clamp(t0, t1) - t0);
            d[0] += back * r.direction[0];
            d[1] += back * r.direction[1];
        }
        d
    }

    /// LIGGGHTS equal-style expressions of the mesh velocity's x and y in terms of the
    /// variable `t` (stroke time, s): logical factors switch the phases on and off.
    pub fn velocity_expressions(&self, t: &str) -> [String; 2] {
        let ta = self.t_launch();
        let accel = |c: f64| format!("(v_{t}>0)*(v_{t}<{ta:e})*{:e}*v_{t}", self.a_m_s2 * c);
        let mut out = [accel(self.launch[0]), accel(self.launch[1])];
        if let (Some(r), Some((t0, t1))) = (self.ret, self.return_window()) {
            for (k, o) in out.iter_mut().enumerate() {
                o.push_str(&format!("+(v_{t}>={t0:e})*(v_{t}<{t1:e})*{:e}", r.speed_m_s * r.direction[k]));
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stroke_ends_at_v0_after_v0_over_a_and_the_return_brings_the_sled_back() {
        let mut s = Scenario::earth();
        let d = Design::validation_rig();
        let m = SledMotion::new(&s, &d, 0.7, None);
        assert!((m.t_launch() - 1.0 / 60.0).abs() < 1e-15);
        let end = m.displacement(10.0);
        assert!((end[0].hypot(end[1]) - 1.0 / 120.0).abs() < 1e-15);
        assert!(m.ret.is_none());
        s.effects.set_from_cli("sled-motion=0.05,0.1").unwrap();
        let m = SledMotion::new(&s, &d, 0.7, Some((5.0, 0.05)));
        assert_eq!(m.ret.unwrap().delay_s, 0.05, "the effect wins over the setup's statement");
        let back = m.displacement(100.0);
        // launched along 0.7 rad, returned down the 35° slope by the same length
        let along_slope = |v: [f64; 2]| v[0] * 35f64.to_radians().cos() + v[1] * 35f64.to_radians().sin();
        assert!((along_slope(back) - (along_slope(end) - m.stroke_m())).abs() < 1e-12);
        let e = m.velocity_expressions("t");
        assert!(e[0].contains("v_t<") && e[0].contains("v_t>="), "{}", e[0]);
    }
}
