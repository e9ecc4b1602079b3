//! Restitution at an impact (4.1.2, Eq. 4.3-4.14, and the bounce of 4.2.4, Eq. 4.47-4.49),
//! by the thesis's law or by the DEM's (`ContactLaw`): the same bounce of Eq. 4.47-4.49 with
//! another k_n and k_t.

use super::real::Real;
pub use super::scenario::{check_tangential_table, TANGENTIAL_NODES, TANGENTIAL_PSI};
use super::scenario::{Collision, ContactLaw, Material, PhysicsMode};
use crate::lane::{Lane, LaneMask};

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

/// The plastic limit speed `collision` uses, m/s: the stated one (`[collision] v_limit_m_s`,
/// a calibration parameter), else Eq. 4.7's from the material.
pub fn limit_speed(collision: &Collision, material: &Material) -> f64 {
    collision.v_limit_m_s.unwrap_or_else(|| limit_velocity(material))
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
    /// The DEM's law: k_t from `tangential_table` (the fields above but k_elastic and
    /// mu_friction unused).
    pub dem: bool,
    /// The DEM law's k_t at each ψ of [`TANGENTIAL_PSI`] (zeros with the thesis's law).
    pub tangential_table: [T; TANGENTIAL_NODES],
}

impl Restitution<f64> {
    pub fn new(mode: PhysicsMode, collision: &Collision, material: &Material) -> Self {
        let physical = mode == PhysicsMode::Physical;
        let dem = collision.law == ContactLaw::Dem;
        let mut tangential_table = [0.0; TANGENTIAL_NODES];
        if dem {
            tangential_table.copy_from_slice(&collision.tangential_ratio);
        }
        Restitution {
            k_elastic: collision.k_elastic,
            mu_friction: collision.mu_friction,
            tangential_factor: if physical { 3.5 } else { 1.0 / 3.5 },
            plastic: physical && !dem,
            v_limit: limit_speed(collision, material),
            clamp_tangential: physical,
            dem,
            tangential_table,
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
            dem: self.dem,
            tangential_table: self.tangential_table.map(|v| U::c(v.f64())),
        }
    }

    /// The DEM law's k_t at ψ = |v_t| / (μ (1 + k_n) |v_n|): linear between the table's
    /// nodes; past the last node the Coulomb form 1 − c/ψ through the last node (sliding
    /// throughout the contact, where a sphere's k_t is 1 − μ (1 + e) |v_n|/|v_t|).
    #[inline(always)]
    pub fn dem_tangential(&self, psi: T) -> T {
        T::from_one(self.dem_tangential_on(psi.to_one()))
    }

    /// Rebound velocity for impact velocity `v` on a surface with unit normal `n` (into the air).
    #[inline(always)]
    pub fn bounce(&self, v: [T; 2], n: [T; 2]) -> [T; 2] {
        self.bounce_on(v.map(T::to_one), n.map(T::to_one)).map(T::from_one)
    }
}

impl<S: Copy + Into<f64>> Restitution<S> {
    /// [`Restitution::dem_tangential`] on lanes (`crate::lane`): the node below ψ found by
    /// selects over the table (the scalar walk stops at the same node, the nodes rising),
    /// both forms computed and the one ψ asks for kept.
    #[inline(always)]
    pub fn dem_tangential_on<L: Lane<Scalar = S>>(&self, psi: L) -> L {
        // (no closures here: the lanes' `#[target_feature]` code inlines plain calls only)
        let one = L::splat(1.0);
        let last = TANGENTIAL_NODES - 1;
        let (psi_last, k_last) = (L::splat(TANGENTIAL_PSI[last]), L::splat(self.tangential_table[last].into()));
        // also ψ = ∞ (no friction or no normal speed): the tangential speed is kept
        let coulomb = one - (one - k_last) * psi_last / psi;
        let (mut p0, mut p1) = (L::splat(TANGENTIAL_PSI[0]), L::splat(TANGENTIAL_PSI[1]));
        let (mut k0, mut k1) = (L::splat(self.tangential_table[0].into()), L::splat(self.tangential_table[1].into()));
        for i in 1..last {
            let past = !psi.lt(L::splat(TANGENTIAL_PSI[i]));
            p0 = L::select(past, L::splat(TANGENTIAL_PSI[i]), p0);
            p1 = L::select(past, L::splat(TANGENTIAL_PSI[i + 1]), p1);
            k0 = L::select(past, L::splat(self.tangential_table[i].into()), k0);
            k1 = L::select(past, L::splat(self.tangential_table[i + 1].into()), k1);
        }
        let between = k0 + (k1 - k0) * (psi - p0) / (p1 - p0);
        L::select(psi.lt(psi_last), between, coulomb)
    }

    /// Eq. 4.47-4.49 with the thesis's k_n (Eq. 4.9) and k_t (Eq. 4.14, or the listing's
    /// line 316), or the DEM's: the rebound velocity for impact velocity `v` on a surface
    /// with unit normal `n` (into the air), on lanes (`crate::lane`). Written once for the
    /// scalar kernel ([`Restitution::bounce`], f64 and f32) and the cpu engine's SIMD lanes:
    /// each branch a select of both sides, so every lane gives the scalar law's bits.
    #[inline(always)]
    pub fn bounce_on<L: Lane<Scalar = S>>(&self, v: [L; 2], n: [L; 2]) -> [L; 2] {
        let (k_elastic, v_limit) = (L::splat(self.k_elastic.into()), L::splat(self.v_limit.into()));
        let (mu, tangential_factor) = (L::splat(self.mu_friction.into()), L::splat(self.tangential_factor.into()));
        let (zero, one) = (L::splat(0.0), L::splat(1.0));
        let vn_s = v[0] * n[0] + v[1] * n[1]; // Eq. 4.47
        let vn = [vn_s * n[0], vn_s * n[1]];
        let vt = [v[0] - vn[0], v[1] - vn[1]]; // Eq. 4.48
        let vn_abs = vn_s.abs();
        let vt_abs = (vt[0] * vt[0] + vt[1] * vt[1]).sqrt();
        // Eq. 4.9: k_plastic = k_elastic (v_limit / |v_n|)^(1/4) above the limit velocity.
        // (a side no lane takes is not computed: one number's bounce stays a branch)
        let above = vn_abs.gt(v_limit);
        let k_norm = if self.plastic && above.any() {
            L::select(above, k_elastic * (v_limit / vn_abs).sqrt().sqrt(), k_elastic)
        } else {
            k_elastic
        };
        // Eq. 4.14 (or the listing's line 316): k_t = 1 - c μ (k_n + 1) |v_n| / |v_t|.
        let k_tang = if self.dem {
            // the DEM's measured k_t(ψ); a zero friction impulse makes ψ infinite
            let impulse = mu * (k_norm + one) * vn_abs;
            self.dem_tangential_on(L::select(impulse.gt(zero), vt_abs / impulse, L::splat(f64::INFINITY)))
        } else {
            let sliding = vt_abs.gt(zero);
            let k_tang = if sliding.any() {
                L::select(sliding, one - tangential_factor * mu * (k_norm + one) * vn_abs / vt_abs, zero)
            } else {
                zero
            };
            if self.clamp_tangential {
                k_tang.max(zero).min(one)
            } else {
                k_tang
            }
        };
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
        let r = Restitution::new(PhysicsMode::Physical, &Collision::thesis(0.8, 0.1), &Material::lunar_regolith());
        let out = r.bounce([0.0, -0.01], [0.0, 1.0]);
        assert!((out[1] - 0.008).abs() < 1e-12);
        assert_eq!(out[0], 0.0);
    }

    #[test]
    fn plastic_branch_lowers_the_normal_cor() {
        let r = Restitution::new(PhysicsMode::Physical, &Collision::thesis(0.8, 0.0), &Material::lunar_regolith());
        let out = r.bounce([0.0, -1.0], [0.0, 1.0]);
        let expected = 0.8 * (r.v_limit / 1.0f64).powf(0.25);
        assert!((out[1] - expected).abs() < 1e-12);
        let listing = Restitution::new(PhysicsMode::Listing, &Collision::thesis(0.8, 0.0), &Material::lunar_regolith());
        assert!((listing.bounce([0.0, -1.0], [0.0, 1.0])[1] - 0.8).abs() < 1e-12);
    }

    #[test]
    fn tangential_cor_is_clamped_in_physical_mode_only() {
        let m = Material::lunar_regolith();
        // steep impact: |v_n| >> |v_t| makes Eq. 4.14 strongly negative
        let v = [0.01, -1.0];
        let phys = Restitution::new(PhysicsMode::Physical, &Collision::thesis(0.8, 0.5), &m).bounce(v, [0.0, 1.0]);
        assert_eq!(phys[0], 0.0);
        let list = Restitution::new(PhysicsMode::Listing, &Collision::thesis(0.8, 0.5), &m).bounce(v, [0.0, 1.0]);
        assert!(list[0] < 0.0);
    }

    fn dem_law(e: f64, mu: f64, table: [f64; TANGENTIAL_NODES]) -> Restitution<f64> {
        let c = Collision { law: ContactLaw::Dem, tangential_ratio: table.to_vec(), ..Collision::thesis(e, mu) };
        Restitution::new(PhysicsMode::Physical, &c, &Material::lunar_regolith())
    }

    /// The DEM's law: one normal COR at every speed (no plastic branch), k_t read from the
    /// table at ψ = |v_t| / (μ (1 + e) |v_n|), Coulomb's 1 − c/ψ past its last node.
    #[test]
    fn the_dem_law_keeps_one_normal_cor_and_reads_k_t_from_its_table() {
        let coulomb = TANGENTIAL_PSI.map(|p| if p > 0.0 { (1.0 - 1.0 / p).max(-0.9) } else { -0.9 });
        let r = dem_law(0.872, 0.106, coulomb);
        for vn in [0.005, 0.3, 1.5] {
            let out = r.bounce([0.0, -vn], [0.0, 1.0]);
            assert!((out[1] / vn - 0.872).abs() < 1e-12, "k_n {} at {vn} m/s", out[1] / vn);
        }
        let impulse = 0.106 * 1.872;
        for psi in [0.1, 0.6, 1.0, 1.4, 2.5, 5.0, 8.0, 20.0] {
            let vt = psi * impulse * 0.5;
            let out = r.bounce([vt, -0.5], [0.0, 1.0]);
            let want = if psi >= 8.0 {
                1.0 - (1.0 - coulomb[TANGENTIAL_NODES - 1]) * 8.0 / psi
            } else {
                let i = TANGENTIAL_PSI.iter().rposition(|&p| p <= psi).unwrap();
                let f = (psi - TANGENTIAL_PSI[i]) / (TANGENTIAL_PSI[i + 1] - TANGENTIAL_PSI[i]);
                coulomb[i] + f * (coulomb[i + 1] - coulomb[i])
            };
            assert!((out[0] / vt - want).abs() < 1e-12, "psi {psi}: k_t {} want {want}", out[0] / vt);
        }
        // past the table the law is Coulomb's sliding bounce: 1 - 1/psi
        let out = r.bounce([20.0 * impulse, -1.0], [0.0, 1.0]);
        assert!((out[0] / (20.0 * impulse) - (1.0 - 1.0 / 20.0)).abs() < 1e-12);
        // no friction keeps the tangential speed; a reversed table reverses it
        assert_eq!(dem_law(0.872, 0.0, coulomb).bounce([0.3, -0.5], [0.0, 1.0])[0], 0.3);
        let back = dem_law(0.872, 0.106, [-0.9; TANGENTIAL_NODES]).bounce([0.01, -0.5], [0.0, 1.0]);
        assert!((back[0] + 0.009).abs() < 1e-12, "{back:?}");
    }

    #[test]
    fn a_tangential_table_is_checked_by_name() {
        assert!(check_tangential_table(&[0.5; TANGENTIAL_NODES]).is_ok());
        assert!(check_tangential_table(&[0.5; 3]).unwrap_err().contains("must hold"));
        let mut t = [0.5; TANGENTIAL_NODES];
        t[4] = 1.5;
        assert!(check_tangential_table(&t).unwrap_err().contains("value 5 must lie in [-1, 1]"));
        t[4] = f64::NAN;
        assert!(check_tangential_table(&t).is_err());
    }
}
