//! The sawtooth profile: points p1..p4 of every tooth (4.2.2, Eq. 4.21-4.28, listing D.1
//! lines 57-107) and the design constraints of 5.2 (Eq. 5.2-5.9, listing D.5/D.6).
//!
//! Every tooth is the same shape shifted by the pitch vector, so the profile stores one tooth
//! relative to its own p1 (in the global orientation) and the pitch vector; tooth j's points
//! are `j * pitch + offset`. Kernels keep particle positions relative to a tooth's p1, which
//! keeps coordinates small enough for f32 (issue 3's precision strategy).

use super::design::Design;
use super::validity::Invalid;

pub type V2 = [f64; 2];

#[inline]
pub fn rot(v: V2, angle: f64) -> V2 {
    let (s, c) = angle.sin_cos();
    [c * v[0] - s * v[1], s * v[0] + c * v[1]]
}

/// Catch geometry in the tooth's local frame (x along the base, y normal to it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalTooth {
    /// Tooth angle φ = atan(l_b / l_a) (Eq. 4.23).
    pub phi: f64,
    /// p2 = (l_a, l_b) (listing D.1 line 80-81).
    pub p2: V2,
    /// Catch-arc centre p3 (Eq. 4.24, 4.26).
    pub p3: V2,
    /// Catch foot p4 = (x4, 0) (Eq. 4.27).
    pub p4: V2,
}

impl LocalTooth {
    /// Eq. 4.23-4.27. Returns the raw numbers even when the design is invalid (x3 may be NaN
    /// when the arc misses p2); `check_design` turns those cases into reasons.
    pub fn new(d: &Design) -> Self {
        let phi = (d.l_b / d.l_a).atan();
        let omega = d.omega_deg.to_radians();
        let y3 = d.r * omega.cos(); // Eq. 4.24
        let x3 = d.l_a + (d.r * d.r - (d.l_b - y3).powi(2)).sqrt(); // Eq. 4.26
        let x4 = x3 - d.r * omega.sin(); // Eq. 4.27
        LocalTooth { phi, p2: [d.l_a, d.l_b], p3: [x3, y3], p4: [x4, 0.0] }
    }
}

/// Check a design against the rules of 5.2 and the viability checks of 5.3.1 (except the
/// spill check, which needs the environment and lives in `fill`).
pub fn check_design(d: &Design) -> Result<LocalTooth, Invalid> {
    let fields = [
        ("l_c", d.l_c),
        ("l_a", d.l_a),
        ("l_b", d.l_b),
        ("r", d.r),
        ("omega_deg", d.omega_deg),
        ("delta_deg", d.delta_deg),
        ("v0", d.v0),
        ("a", d.a),
    ];
    for (field, value) in fields {
        if !value.is_finite() {
            return Err(Invalid::NotFinite { field, value });
        }
    }
    for (field, value) in [("l_c", d.l_c), ("l_a", d.l_a), ("l_b", d.l_b), ("r", d.r), ("v0", d.v0), ("a", d.a)] {
        if value <= 0.0 {
            return Err(Invalid::NotPositive { field, value });
        }
    }
    if !(d.omega_deg > 0.0 && d.omega_deg < 180.0) {
        return Err(Invalid::OmegaRange(d.omega_deg));
    }
    if !(d.delta_deg > -90.0 && d.delta_deg < 90.0) {
        return Err(Invalid::DeltaRange(d.delta_deg));
    }
    // Eq. 5.2: l_b <= r <= l_a <= l_c
    for (rule, lhs, rhs) in [("l_b <= r", d.l_b, d.r), ("r <= l_a", d.r, d.l_a), ("l_a <= l_c", d.l_a, d.l_c)] {
        if lhs > rhs {
            return Err(Invalid::Chain { rule, lhs_mm: lhs * 1e3, rhs_mm: rhs * 1e3 });
        }
    }
    let t = LocalTooth::new(d);
    // c1 (Eq. 5.4)
    let c1 = (t.p2[1] - t.p3[1]).abs() - d.r;
    if c1 > 0.0 {
        return Err(Invalid::CatchMissesPeak { excess_mm: c1 * 1e3 });
    }
    // c2 (Eq. 5.5)
    let x4 = t.p4[0];
    if x4 > d.l_c {
        return Err(Invalid::CatchOverlapsNextTooth { excess_mm: (x4 - d.l_c) * 1e3 });
    }
    // c3 (Eq. 5.6)
    if x4 < 0.0 {
        return Err(Invalid::CatchBehindToothStart { x4_mm: x4 * 1e3 });
    }
    // Arc-ramp second intersection (Eq. 5.8-5.9, D.6 lines 49-56 incl. its 1e-5 tolerance in mm).
    let ramp_length = d.l_a.hypot(d.l_b);
    let p_proj = t.p3[0] * t.phi.cos() + t.p3[1] * t.phi.sin();
    let t2 = 2.0 * p_proj - ramp_length;
    let tol = 1e-8; // 1e-5 mm
    if t2 > tol && t2 < ramp_length - tol {
        return Err(Invalid::CatchCutsRamp { t2_mm: t2 * 1e3 });
    }
    Ok(t)
}

/// One tooth in global orientation plus the pitch: the whole profile.
#[derive(Clone, Debug, PartialEq)]
pub struct Profile {
    /// Conveyor angle α, radians.
    pub alpha: f64,
    pub teeth: u32,
    pub pitch_len: f64,
    /// l_c (cos α, sin α): p1 of tooth j is j * pitch (Eq. 4.21), tooth 0 at the origin.
    pub pitch: V2,
    /// p2, p3, p4 relative to the tooth's p1, global orientation (Eq. 4.22, 4.28).
    pub p2: V2,
    pub p3: V2,
    pub p4: V2,
    pub radius: f64,
    pub local: LocalTooth,
}

impl Profile {
    pub fn new(d: &Design, local: LocalTooth, alpha_deg: f64, teeth: u32) -> Self {
        let alpha = alpha_deg.to_radians();
        Profile {
            alpha,
            teeth,
            pitch_len: d.l_c,
            pitch: [d.l_c * alpha.cos(), d.l_c * alpha.sin()],
            p2: rot(local.p2, alpha),
            p3: rot(local.p3, alpha),
            p4: rot(local.p4, alpha),
            radius: d.r,
            local,
        }
    }

    /// Global position of tooth `j`'s p1 (0-based).
    pub fn p1_of(&self, j: u32) -> V2 {
        [self.pitch[0] * j as f64, self.pitch[1] * j as f64]
    }

    pub fn point_of(&self, j: u32, offset: V2) -> V2 {
        let p1 = self.p1_of(j);
        [p1[0] + offset[0], p1[1] + offset[1]]
    }

    /// Angles of p2 and p4 seen from p3, with p4's unwrapped past p2's (listing lines 94-103).
    pub fn catch_arc_angles(&self) -> (f64, f64) {
        let a2 = (self.p2[1] - self.p3[1]).atan2(self.p2[0] - self.p3[0]);
        let mut a4 = (self.p4[1] - self.p3[1]).atan2(self.p4[0] - self.p3[0]);
        if a4 < a2 {
            a4 += 2.0 * std::f64::consts::PI;
        }
        (a2, a4)
    }

    /// Unit normals pointing into the air: base, ramp (listing lines 52-53) and the catch
    /// chord p2-p4 (listing line 106).
    pub fn normals(&self) -> [V2; 3] {
        let a = self.alpha;
        let phi = self.local.phi;
        let base = [-a.sin(), a.cos()];
        let ramp = [-(a + phi).sin(), (a + phi).cos()];
        let d = [self.p2[0] - self.p4[0], self.p2[1] - self.p4[1]];
        let n = d[0].hypot(d[1]);
        let catch = [d[1] / n, -d[0] / n];
        [base, ramp, catch]
    }

    /// Eq. 4.56 / listing line 346: the 1-based tooth a final x position bins to. Positions on
    /// tooth j's ramp count for tooth j-1.
    pub fn tooth_of_x(&self, x: f64) -> i64 {
        ((x - self.p2[0]) / self.pitch[0]).floor() as i64 + 1
    }

    /// Listing D.1 lines 347-351: the distance credited to a particle resting in (1-based)
    /// tooth `j`: the global x of that tooth's p4, 0 for the first tooth (erratum 16).
    pub fn credited_distance(&self, tooth_1based: i64) -> f64 {
        if tooth_1based > 1 {
            self.pitch[0] * (tooth_1based - 1) as f64 + self.p4[0]
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation_rig_geometry_matches_hand_calculation() {
        // Table 4.3: l_a 15, l_b 5, r 5, ω 60°: y3 = 2.5, x3 = 15 + sqrt(25 - 6.25), x4 = x3 - 5 sin 60°.
        let t = check_design(&Design::validation_rig()).unwrap();
        assert!((t.p3[1] - 2.5e-3).abs() < 1e-12);
        let x3 = 15e-3 + (25e-6f64 - 6.25e-6).sqrt();
        assert!((t.p3[0] - x3).abs() < 1e-12);
        assert!((t.p4[0] - (x3 - 5e-3 * 60f64.to_radians().sin())).abs() < 1e-12);
    }

    #[test]
    fn chain_violation_is_named() {
        let mut d = Design::validation_rig();
        d.r = 20e-3; // r > l_a
        match check_design(&d) {
            Err(Invalid::Chain { rule, .. }) => assert_eq!(rule, "r <= l_a"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn catch_normal_points_forward_into_the_cavity() {
        let d = Design::lunar_solution_c();
        let t = check_design(&d).unwrap();
        let p = Profile::new(&d, t, 35.0, 10);
        let [_, _, catch] = p.normals();
        assert!(catch[0] > 0.0, "{catch:?}");
    }
}
