//! The model's polydisperse size law (`effects::Polydisperse`) as DEM size classes.
//!
//! The model draws each simulated grain's diameter from the *mass-weighted* size law q₃(d)
//! (every grain stands for an equal mass) around the mass-median size d_ref, and gives it the
//! Stokes drag k_drag (d_ref/d)² (Eq. 4.16, 4.20: b/m ∝ 1/d²). A DEM case has real grains,
//! so the law becomes `SIZE_CLASSES` classes of equal mass: class k is q₃'s quantile at
//! u = (k + ½)/K (the middle of its equal-mass slice), carries 1/K of the fill mass, and so
//! holds (M/K)/m_k grains. Each class has its own drag γ_k = m_k k_drag (d_ref/d_k)²
//! (∝ d_k: Stokes 3πηd), applied in the case as one `fix viscous` per class group.
//!
//! The quantiles of q₃: log-normal form, d = d_ref exp(σ Φ⁻¹(u)) (a log-normal q₀ has a
//! log-normal q₃ of the same σ whose median is the mass median, `effects::Polydisperse`);
//! uniform form, q₀ uniform on [d_ref e^{-√3σ}, d_ref e^{√3σ}], so q₃ ∝ d³ there and
//! d⁴ = a⁴ + u (b⁴ − a⁴).

use serde::Serialize;

use crate::model::effects::{Polydisperse, SizeForm};

/// Size classes a polydisperse case is cut into. Five equal-mass classes put the extreme
/// classes at q₃'s 10th and 90th percentiles (σ = 0.3: 0.68 and 1.47 d_ref).
pub const SIZE_CLASSES: usize = 5;

/// One size class of the case.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SizeClass {
    pub diameter_m: f64,
    /// Grains of this class in the case.
    pub grains: u32,
    /// The class's share of the grains' mass (1/K by the law, up to whole grains).
    pub mass_fraction: f64,
    /// Stokes drag γ = m k_drag (d_ref/d)² of one grain of this class, kg/s; None in vacuum.
    pub drag_gamma_kg_s: Option<f64>,
}

/// Φ(z), the standard normal CDF, by Simpson's rule on the density from 0 to z (error
/// below 1e-12 for |z| ≤ 8 with the 400 intervals used).
fn normal_cdf(z: f64) -> f64 {
    let n = 400;
    let h = z / n as f64;
    let pdf = |t: f64| (-0.5 * t * t).exp() / (2.0 * std::f64::consts::PI).sqrt();
    let inner: f64 = (1..n).map(|i| pdf(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 }).sum();
    0.5 + h / 3.0 * (pdf(0.0) + inner + pdf(z))
}

/// Φ⁻¹(u) for u in (0, 1), by bisection on [`normal_cdf`].
pub fn normal_quantile(u: f64) -> f64 {
    let (mut lo, mut hi) = (-8.0, 8.0);
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if normal_cdf(mid) < u {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Each class's diameter over d_ref: q₃'s quantiles at the middles of K equal-mass slices.
pub fn class_ratios(law: &Polydisperse) -> Vec<f64> {
    let s = law.sigma_ln;
    (0..SIZE_CLASSES)
        .map(|k| {
            let u = (k as f64 + 0.5) / SIZE_CLASSES as f64;
            match law.form {
                SizeForm::Lognormal => (s * normal_quantile(u)).exp(),
                SizeForm::Uniform => {
                    let (a4, b4) = ((-4.0 * 3f64.sqrt() * s).exp(), (4.0 * 3f64.sqrt() * s).exp());
                    (a4 + u * (b4 - a4)).powf(0.25)
                }
            }
        })
        .collect()
}

/// The mass-median diameter at which the classes of `law` hold about `n` grains in all when
/// each carries 1/K of a fill whose mass is that of `n` grains of `mono_d` (the
/// monodisperse mass-matching diameter): N ∝ mean_k (d_ref c_k)⁻³ · d_ref, so
/// d_ref = mono_d · √(mean_k c_k⁻³).
pub fn reference_diameter(law: &Polydisperse, mono_d: f64) -> f64 {
    let r = class_ratios(law);
    mono_d * (r.iter().map(|c| c.powi(-3)).sum::<f64>() / r.len() as f64).sqrt()
}

/// The classes of `law` around `d_ref` for a fill of `fill_mass_kg`, grains of density
/// `rho_p`, and the scenario's Stokes k_drag (None in vacuum). Each class gets the whole
/// number of grains nearest its 1/K of the mass (at least one).
pub fn size_classes(
    law: &Polydisperse,
    d_ref: f64,
    fill_mass_kg: f64,
    rho_p: f64,
    k_drag: Option<f64>,
) -> Vec<SizeClass> {
    let ratios = class_ratios(law);
    let share = fill_mass_kg / ratios.len() as f64;
    let mut classes: Vec<SizeClass> = ratios
        .iter()
        .map(|c| {
            let d = d_ref * c;
            let m = grain_mass(d, rho_p);
            SizeClass {
                diameter_m: d,
                grains: ((share / m).round() as u32).max(1),
                mass_fraction: 0.0,
                drag_gamma_kg_s: k_drag.map(|k| m * k / (c * c)),
            }
        })
        .collect();
    let total: f64 = classes.iter().map(|c| c.grains as f64 * grain_mass(c.diameter_m, rho_p)).sum();
    for c in &mut classes {
        c.mass_fraction = c.grains as f64 * grain_mass(c.diameter_m, rho_p) / total;
    }
    classes
}

/// Mass of a sphere of diameter `d` and density `rho`, kg.
pub fn grain_mass(d: f64, rho: f64) -> f64 {
    rho * std::f64::consts::PI * d.powi(3) / 6.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lognormal(sigma_ln: f64) -> Polydisperse {
        Polydisperse { sigma_ln, form: SizeForm::Lognormal }
    }

    #[test]
    fn the_normal_quantile_inverts_the_cdf_at_known_points() {
        assert!(normal_quantile(0.5).abs() < 1e-9);
        // Φ(1.959964) = 0.975, Φ(-1.281552) = 0.1 (tables)
        assert!((normal_quantile(0.975) - 1.959964).abs() < 1e-5);
        assert!((normal_quantile(0.1) + 1.281552).abs() < 1e-5);
    }

    #[test]
    fn the_classes_are_the_mass_weighted_laws_equal_mass_quantiles() {
        let r = class_ratios(&lognormal(0.3));
        assert_eq!(r.len(), SIZE_CLASSES);
        // symmetric in ln d around the mass median, the middle class at d_ref
        assert!((r[2] - 1.0).abs() < 1e-9);
        assert!((r[0].ln() + r[4].ln()).abs() < 1e-9 && (r[1].ln() + r[3].ln()).abs() < 1e-9);
        assert!((r[4].ln() - 0.3 * 1.281552).abs() < 1e-5, "{r:?}");
        // uniform: q₃ ∝ d³ on [e^{-√3σ}, e^{√3σ}]: inside the range, increasing, above the
        // number median 1 (mass sits in the large grains)
        let u = class_ratios(&Polydisperse { sigma_ln: 0.3, form: SizeForm::Uniform });
        let (a, b) = ((-(3f64.sqrt()) * 0.3).exp(), (3f64.sqrt() * 0.3).exp());
        assert!(u.windows(2).all(|w| w[0] < w[1]) && u[0] > a && u[4] < b && u[2] > 1.0, "{u:?}");
        // σ = 0: one size
        assert!(class_ratios(&lognormal(0.0)).iter().all(|c| (c - 1.0).abs() < 1e-12));
    }

    #[test]
    fn every_class_carries_a_fifth_of_the_mass_and_its_drag_grows_with_its_size() {
        let (rho, d_ref, k) = (2500.0, 500e-6, 5.347);
        let fill = 150.0 * grain_mass(d_ref, rho);
        let c = size_classes(&lognormal(0.3), d_ref, fill, rho, Some(k));
        let mass: f64 = c.iter().map(|c| c.grains as f64 * grain_mass(c.diameter_m, rho)).sum();
        assert!((mass / fill - 1.0).abs() < 0.02, "whole grains carry the fill mass: {}", mass / fill);
        for s in &c {
            assert!((s.mass_fraction - 0.2).abs() < 0.02, "{c:?}");
            // γ = m k (d_ref/d)²: Stokes 3πηd, proportional to d
            let g = s.drag_gamma_kg_s.unwrap();
            let expected = grain_mass(d_ref, rho) * k * s.diameter_m / d_ref;
            assert!((g / expected - 1.0).abs() < 1e-9);
        }
        // small grains are many: the smallest class holds the most grains
        assert!(c[0].grains > c[4].grains * 5, "{c:?}");
        assert!(size_classes(&lognormal(0.3), d_ref, fill, rho, None).iter().all(|s| s.drag_gamma_kg_s.is_none()));
    }

    #[test]
    fn the_reference_diameter_keeps_about_the_asked_grain_count() {
        let (rho, mono_d, n) = (2500.0, 500e-6, 150u32);
        let law = lognormal(0.3);
        let d_ref = reference_diameter(&law, mono_d);
        // the fill's mass scales with the slab depth, k·d_ref (`grains`): the mono fill's mass
        // times d_ref / mono_d
        let fill = n as f64 * grain_mass(mono_d, rho) * d_ref / mono_d;
        let total: u32 = size_classes(&law, d_ref, fill, rho, None).iter().map(|c| c.grains).sum();
        assert!((total as f64 / n as f64 - 1.0).abs() < 0.05, "{total} grains for {n}");
    }
}
