//! Restitution at an impact (4.1.2, Eq. 4.3-4.14, and the bounce of 4.2.4, Eq. 4.47-4.49).

use super::real::Real;
use super::scenario::{Material, PhysicsMode};

/// Plastic limit velocity v_limit, m/s (Eq. 4.7 as repaired by erratum 1):
/// v_limit = π² p_limit^(5/2) / (sqrt(40 ρ_particle) E*²), with E* from Eq. 4.4 and
/// p_limit the lower of 1.6 Y_conveyor and Y_particle (Eq. 4.6).
pub fn limit_velocity(m: &Material) -> f64 {
    let (p, c) = (&m.particle, &m.conveyor);
    let e_star =
        1.0 / ((1.0 - c.poisson_ratio.powi(2)) / c.youngs_modulus + (1.0 - p.poisson_ratio.powi(2)) / p.youngs_modulus);
    let p_limit = (1.6 * c.strength).min(p.strength);
    std::f64::consts::PI.powi(2) * p_limit.powf(2.5) / ((40.0 * p.density).sqrt() * e_star * e_star)
}

/// The restitution law, as flat numbers a kernel can carry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Restitution<T> {
    pub k_elastic: T,
    pub mu_friction: T,
    /// Multiplier of μ in k_tang: 3.5 (Eq. 4.14) or 1/3.5 (listing D.1 line 316, erratum 18).
    pub tangential_factor: T,
    /// Use k_plastic above v_limit (Eq. 4.9); the listing never does (errata 6, 19).
    pub plastic: bool,
    /// v_limit, m/s.
    pub v_limit: T,
    /// Clamp k_tang to [0, 1] (4.1.2); the listing does not (erratum 7).
    pub clamp_tangential: bool,
}

impl Restitution<f64> {
    pub fn new(mode: PhysicsMode, k_elastic: f64, mu_friction: f64, material: &Material) -> Self {
        let physical = mode == PhysicsMode::Physical;
        Restitution {
            k_elastic,
            mu_friction,
            tangential_factor: if physical { 3.5 } else { 1.0 / 3.5 },
            plastic: physical,
            v_limit: limit_velocity(material),
            clamp_tangential: physical,
        }
    }
}

impl<T: Real> Restitution<T> {
    pub fn cast<U: Real>(&self) -> Restitution<U> {
        Restitution {
            k_elastic: U::c(self.k_elastic.f64()),
            mu_friction: U::c(self.mu_friction.f64()),
            tangential_factor: U::c(self.tangential_factor.f64()),
            plastic: self.plastic,
            v_limit: U::c(self.v_limit.f64()),
            clamp_tangential: self.clamp_tangential,
        }
    }

    /// Rebound velocity for impact velocity `v` on a surface with unit normal `n` (into the air).
    #[inline(always)]
    pub fn bounce(&self, v: [T; 2], n: [T; 2]) -> [T; 2] {
        let vn_s = v[0] * n[0] + v[1] * n[1]; // Eq. 4.47
        let vn = [vn_s * n[0], vn_s * n[1]];
        let vt = [v[0] - vn[0], v[1] - vn[1]]; // Eq. 4.48
        let vn_abs = vn_s.abs();
        let vt_abs = (vt[0] * vt[0] + vt[1] * vt[1]).sqrt();
        // Eq. 4.9: k_plastic = k_elastic (v_limit / |v_n|)^(1/4) above the limit velocity.
        let k_norm = if self.plastic && vn_abs > self.v_limit {
            self.k_elastic * (self.v_limit / vn_abs).sqrt().sqrt()
        } else {
            self.k_elastic
        };
        // Eq. 4.14 (or the listing's line 316): k_t = 1 - c μ (k_n + 1) |v_n| / |v_t|.
        let mut k_tang = if vt_abs > T::zero() {
            T::one() - self.tangential_factor * self.mu_friction * (k_norm + T::one()) * vn_abs / vt_abs
        } else {
            T::zero()
        };
        if self.clamp_tangential {
            k_tang = k_tang.max(T::zero()).min(T::one());
        }
        // Eq. 4.49
        [k_tang * vt[0] - k_norm * vn[0], k_tang * vt[1] - k_norm * vn[1]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limit_velocity_is_the_quoted_0_0135() {
        let v = limit_velocity(&Material::lunar_regolith());
        assert!((v - 0.0135).abs() < 0.00005, "{v}");
    }

    #[test]
    fn normal_impact_reverses_with_k_elastic_below_the_limit() {
        let r = Restitution::new(PhysicsMode::Physical, 0.8, 0.1, &Material::lunar_regolith());
        let out = r.bounce([0.0, -0.01], [0.0, 1.0]);
        assert!((out[1] - 0.008).abs() < 1e-12);
        assert_eq!(out[0], 0.0);
    }

    #[test]
    fn plastic_branch_lowers_the_normal_cor() {
        let r = Restitution::new(PhysicsMode::Physical, 0.8, 0.0, &Material::lunar_regolith());
        let out = r.bounce([0.0, -1.0], [0.0, 1.0]);
        let expected = 0.8 * (r.v_limit / 1.0f64).powf(0.25);
        assert!((out[1] - expected).abs() < 1e-12);
        let listing = Restitution::new(PhysicsMode::Listing, 0.8, 0.0, &Material::lunar_regolith());
        assert!((listing.bounce([0.0, -1.0], [0.0, 1.0])[1] - 0.8).abs() < 1e-12);
    }

    #[test]
    fn tangential_cor_is_clamped_in_physical_mode_only() {
        let m = Material::lunar_regolith();
        // steep impact: |v_n| >> |v_t| makes Eq. 4.14 strongly negative
        let v = [0.01, -1.0];
        let phys = Restitution::new(PhysicsMode::Physical, 0.8, 0.5, &m).bounce(v, [0.0, 1.0]);
        assert_eq!(phys[0], 0.0);
        let list = Restitution::new(PhysicsMode::Listing, 0.8, 0.5, &m).bounce(v, [0.0, 1.0]);
        assert!(list[0] < 0.0);
    }
}
