//! The two fit objectives: the thesis's sum of squared errors (Eq. 4.62, listing D.4) and a
//! Dirichlet-multinomial likelihood of the individual runs.
//!
//! Both compare *bins*: the setup's teeth (tooth 1 first) and one last bin for particles lost
//! off the conveyor, as D.4's 21-element `target_dist` (20 teeth + "left the conveyor").
//! Measured data cover only the weighed teeth; the teeth beyond them and the lost bin count
//! as measured 0 (what D.4 did). Simulated bins are fractions of launched particles
//! ([`SimOutcome::distribution`] plus [`SimOutcome::lost_fraction`], summing to 1); measured
//! bins are fractions of the recovered mass.
//!
//! # Why a Dirichlet-multinomial, and on what counts
//!
//! The SSE sees only the mean distribution and weighs every tooth alike, whatever the
//! run-to-run scatter. A likelihood of the individual runs uses that scatter. Each run is a
//! composition (tooth masses that sum to the recovered mass), so it is modelled as a
//! Dirichlet-multinomial draw with mean the simulated distribution `p` and a concentration
//! `α0` (its variance is N p (1-p) (N + α0)/(1 + α0): α0 → ∞ is a multinomial, small α0 is
//! strong over-dispersion between runs).
//!
//! - **Counts are scale units.** The scale is the only counter of the experiment: a tooth
//!   mass is an integer number of resolution steps (0.1 g for Tests 1-2, 0.01 g for Test 3,
//!   App. B), so `n_ij = round(m_ij / resolution)`. A unit is not an independent grain (a
//!   0.01 g step holds thousands of beads that move together); that mismatch is exactly
//!   what the fitted concentration absorbs, so the unit only sets N.
//! - **A tooth measured 0 is possible.** Under a plain Dirichlet on the run fractions a
//!   zero fraction has density 0 or ∞ (Γ terms in log x_j), and Tests 1-3 have zeros in
//!   every padded tooth; with the quantised counts a 0 is simply "less than one scale step".
//!   A Dirichlet-multinomial bin with n_j = 0 contributes Γ(α0 p_j)/Γ(α0 p_j) = 1: the price
//!   of simulated mass in a bin measured empty is paid, correctly, through the smaller p of
//!   the bins that were measured.
//! - **A simulated bin that is empty is not impossible either.** With 1000 particles an
//!   empty simulated bin means "below about 1/1000", not probability 0; in every bin that
//!   some run fills, `p` is floored at [`floor_for`] (half a particle) and then renormalised
//!   ([`model_probabilities`]), so the log-likelihood stays finite. Bins no run fills need
//!   no floor (their term is 1 whatever p is); flooring them too would move up to
//!   (bins × ½ particle) of probability away from the measured teeth, a mean misfit the
//!   concentration would have to absorb.
//! - **The concentration is profiled out**: for each simulated `p` the log-likelihood is
//!   maximised over log α0 (a grid on [1e-3, 1e9] and a golden-section refinement), so the
//!   GA still searches only the physics parameters and the objective stays deterministic.
//!
//! The objective minimised is the negative log-likelihood, multinomial coefficients
//! included (it is a proper log-probability of the quantised data).
//!
//! Caveat: with the concentration free, a mean the model cannot match is partly explained
//! as over-dispersion (a small α0), and the likelihood then weighs a bin the model leaves
//! (nearly) empty but every run fills — such as Test 3's tooth 4 — far more than the SSE
//! does. `fit` reports the NLL and α0 of the runs under their own mean distribution next to
//! the fitted ones.

use crate::model::SimOutcome;

/// The simulated bins of one outcome: the per-tooth fractions, then the lost fraction.
pub fn simulated_bins(sim: &SimOutcome) -> Vec<f64> {
    let mut b = sim.distribution.clone();
    b.push(sim.lost_fraction);
    b
}

/// The measured bins: `fractions` (tooth 1 first) padded with zeros to `teeth`, then a lost
/// bin of 0. `fractions.len()` must not exceed `teeth`.
pub fn measured_bins(fractions: &[f64], teeth: usize) -> Vec<f64> {
    let mut b = vec![0.0; teeth + 1];
    b[..fractions.len()].copy_from_slice(fractions);
    b
}

/// Eq. 4.62 in percentage points squared: Σ_bins (100 sim − 100 measured)², both given as
/// fractions of equal length (listing D.4's `sum((sim_dist - target_dist).^2)`).
pub fn sse_percent2(sim: &[f64], measured: &[f64]) -> f64 {
    debug_assert_eq!(sim.len(), measured.len());
    sim.iter().zip(measured).map(|(s, m)| (100.0 * (s - m)).powi(2)).sum()
}

/// The handling loss s in [0, max_loss] that brings `sim` (teeth, then the not-recovered
/// bin) closest to `measured` when (1 − s)·sim is recovered and s is lost, and the bins
/// so adjusted. Least squares in s is a parabola: its vertex, clamped.
pub fn handling_loss(sim: &[f64], measured: &[f64], max_loss: f64) -> (f64, Vec<f64>) {
    let last = sim.len() - 1;
    // residual(s)_j = a_j + s d_j
    let (mut ad, mut dd) = (0.0, 0.0);
    for j in 0..sim.len() {
        let a = sim[j] - measured[j];
        let d = if j == last { 1.0 - sim[j] } else { -sim[j] };
        ad += a * d;
        dd += d * d;
    }
    let s = if dd > 0.0 { (-ad / dd).clamp(0.0, max_loss.max(0.0)) } else { 0.0 };
    let adjusted = sim.iter().enumerate().map(|(j, p)| (1.0 - s) * p + if j == last { s } else { 0.0 }).collect();
    (s, adjusted)
}

/// Eq. 4.61 in percentage points: the mean absolute error over the bins.
pub fn mae_percent(sim: &[f64], measured: &[f64]) -> f64 {
    let n = sim.len().max(1) as f64;
    sim.iter().zip(measured).map(|(s, m)| (100.0 * (s - m)).abs()).sum::<f64>() / n
}

/// The probability floor for a simulation with `particles` launched particles: half a
/// particle (an empty simulated bin means "fewer than one in `particles`").
pub fn floor_for(particles: u32) -> f64 {
    0.5 / particles.max(1) as f64
}

/// The Dirichlet-multinomial mean for simulated bins `sim`: floored at `eps` in every bin
/// that some run of `counts` fills, then renormalised to sum 1.
pub fn model_probabilities(counts: &[Vec<f64>], sim: &[f64], eps: f64) -> Vec<f64> {
    let q: Vec<f64> = sim
        .iter()
        .enumerate()
        .map(|(j, v)| {
            let v = if v.is_finite() { v.max(0.0) } else { 0.0 };
            if counts.iter().any(|n| n.get(j).is_some_and(|c| *c > 0.0)) {
                v.max(eps)
            } else {
                v
            }
        })
        .collect();
    let s: f64 = q.iter().sum();
    q.iter().map(|v| v / s).collect()
}

/// Tooth masses of one run in scale units, padded like [`measured_bins`]
/// (`round(m / resolution)`).
pub fn quantised_counts(teeth_g: &[f64], teeth: usize, resolution_g: f64) -> Vec<f64> {
    let mut c = vec![0.0; teeth + 1];
    for (slot, m) in c.iter_mut().zip(teeth_g) {
        *slot = (m / resolution_g).round().max(0.0);
    }
    c
}

/// The coarsest decimal resolution (1, 0.1, ... 1e-6 g) on which every mass is an integer
/// multiple; 1e-6 when none is.
pub fn infer_resolution(masses: impl IntoIterator<Item = f64>) -> f64 {
    let masses: Vec<f64> = masses.into_iter().collect();
    for k in 0..=6 {
        let r = 10f64.powi(-k);
        if masses.iter().all(|m| {
            let u = m / r;
            (u - u.round()).abs() < 1e-6 * u.abs().max(1.0)
        }) {
            return r;
        }
    }
    1e-6
}

/// ln Γ(x) for x > 0 (Lanczos, g = 7, 9 terms; relative error ~1e-15; reflection below 0.5).
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Γ(x) Γ(1 − x) = π / sin(πx)
        return (std::f64::consts::PI / (std::f64::consts::PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Σ_runs log DirMult(n_run | α = alpha0 · p), multinomial coefficients included. `p` must
/// sum to 1 and be > 0 wherever a count is (see [`model_probabilities`]); bins with n = 0
/// contribute nothing.
pub fn dm_log_likelihood(counts: &[Vec<f64>], p: &[f64], alpha0: f64) -> f64 {
    let lg_a0 = ln_gamma(alpha0);
    let mut ll = 0.0;
    for n in counts {
        let total: f64 = n.iter().sum();
        ll += lg_a0 - ln_gamma(total + alpha0) + ln_gamma(total + 1.0);
        for (nj, pj) in n.iter().zip(p) {
            if *nj > 0.0 {
                let a = alpha0 * pj;
                ll += ln_gamma(nj + a) - ln_gamma(a) - ln_gamma(nj + 1.0);
            }
        }
    }
    ll
}

/// The negative log-likelihood with the concentration profiled out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Profiled {
    /// −max over α0 of the log-likelihood.
    pub nll: f64,
    /// The maximising concentration α0 (at 1e9 the runs scatter no more than a multinomial).
    pub concentration: f64,
}

/// Bounds of the profiled concentration.
pub const CONCENTRATION_RANGE: (f64, f64) = (1e-3, 1e9);

/// [`dm_log_likelihood`] of the runs' `counts` under the simulated bins `sim` (see
/// [`model_probabilities`] for `eps`), maximised over the concentration (grid on log α0,
/// then golden section).
pub fn profile_nll(counts: &[Vec<f64>], sim: &[f64], eps: f64) -> Profiled {
    let p = model_probabilities(counts, sim, eps);
    let f = |la: f64| -dm_log_likelihood(counts, &p, la.exp());
    let (lo, hi) = (CONCENTRATION_RANGE.0.ln(), CONCENTRATION_RANGE.1.ln());
    const GRID: usize = 49;
    let step = (hi - lo) / (GRID - 1) as f64;
    let mut best = (0, f64::INFINITY);
    for i in 0..GRID {
        let v = f(lo + step * i as f64);
        if v < best.1 {
            best = (i, v);
        }
    }
    let (mut a, mut b) = (lo + step * best.0.saturating_sub(1) as f64, lo + step * (best.0 + 1).min(GRID - 1) as f64);
    let r = (5f64.sqrt() - 1.0) / 2.0;
    let (mut c, mut d) = (b - r * (b - a), a + r * (b - a));
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..40 {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - r * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + r * (b - a);
            fd = f(d);
        }
    }
    let (la, v) = [(c, fc), (d, fd), (lo + step * best.0 as f64, best.1)]
        .into_iter()
        .fold((0.0, f64::INFINITY), |acc, (x, v)| if v < acc.1 { (x, v) } else { acc });
    Profiled { nll: v, concentration: la.exp() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sse_of_identical_distributions_is_zero() {
        let d = measured_bins(&[0.42, 0.33, 0.21, 0.04], 20);
        assert_eq!(d.len(), 21);
        assert_eq!(sse_percent2(&d, &d), 0.0);
        assert_eq!(mae_percent(&d, &d), 0.0);
    }

    #[test]
    fn sse_is_in_percent_squared() {
        // one bin 10 points off, another -10: 200 %²
        assert!((sse_percent2(&[0.5, 0.5, 0.0], &[0.4, 0.6, 0.0]) - 200.0).abs() < 1e-9);
        // D.4's Test 2 target against all particles in tooth 2
        let t = measured_bins(&[0.3608, 0.2835, 0.2680, 0.0876], 20);
        let mut s = vec![0.0; 21];
        s[1] = 1.0;
        let want = 36.08f64.powi(2) + (100.0 - 28.35f64).powi(2) + 26.80f64.powi(2) + 8.76f64.powi(2);
        assert!((sse_percent2(&s, &t) - want).abs() < 1e-6);
    }

    #[test]
    fn ln_gamma_matches_known_values() {
        assert!(ln_gamma(1.0).abs() < 1e-13);
        assert!(ln_gamma(2.0).abs() < 1e-13);
        assert!((ln_gamma(0.5) - std::f64::consts::PI.sqrt().ln()).abs() < 1e-13);
        assert!((ln_gamma(10.0) - 362_880f64.ln()).abs() < 1e-11);
        // Stirling for a large argument
        let x = 1e8f64;
        let stirling = (x - 0.5) * x.ln() - x + 0.5 * (2.0 * std::f64::consts::PI).ln() + 1.0 / (12.0 * x);
        assert!((ln_gamma(x) - stirling).abs() / stirling < 1e-13);
        // small argument: Γ(x) ≈ 1/x
        assert!((ln_gamma(1e-6) - (1e6f64).ln()).abs() < 1e-5);
    }

    #[test]
    fn dm_reduces_to_a_probability_distribution() {
        // all compositions of N = 3 into 3 bins sum to probability 1
        let p = [0.2, 0.5, 0.3];
        for a0 in [0.5, 3.0, 1e4] {
            let mut total = 0.0;
            for i in 0..=3 {
                for j in 0..=(3 - i) {
                    let n = vec![i as f64, j as f64, (3 - i - j) as f64];
                    total += dm_log_likelihood(&[n], &p, a0).exp();
                }
            }
            assert!((total - 1.0).abs() < 1e-10, "alpha0 {a0}: {total}");
        }
    }

    #[test]
    fn likelihood_is_finite_when_a_simulated_bin_is_empty() {
        // measured mass in tooth 4, the simulation puts nothing there
        let counts = vec![
            quantised_counts(&[0.94, 0.49, 0.41, 0.05], 20, 0.01),
            quantised_counts(&[0.85, 0.65, 0.43, 0.06], 20, 0.01),
        ];
        let mut sim = vec![0.0; 21];
        sim[0] = 0.45;
        sim[1] = 0.35;
        sim[2] = 0.20;
        let p = profile_nll(&counts, &sim, floor_for(1000));
        assert!(p.nll.is_finite() && p.nll > 0.0, "{p:?}");
        assert!(p.concentration.is_finite());
        // putting the missing mass in tooth 4 is better
        let mut better = sim.clone();
        better[0] = 0.42;
        better[3] = 0.03;
        assert!(profile_nll(&counts, &better, floor_for(1000)).nll < p.nll);
        // all mass in one empty-measured bin is finite, too
        let mut worst = vec![0.0; 21];
        worst[20] = 1.0;
        assert!(profile_nll(&counts, &worst, floor_for(1000)).nll.is_finite());
    }

    #[test]
    fn profiled_concentration_follows_the_scatter() {
        // identical runs: no over-dispersion beyond... the concentration runs to large values
        let same: Vec<Vec<f64>> = (0..10).map(|_| vec![40.0, 30.0, 30.0]).collect();
        let scattered: Vec<Vec<f64>> =
            (0..10).map(|i| if i % 2 == 0 { vec![70.0, 10.0, 20.0] } else { vec![10.0, 50.0, 40.0] }).collect();
        let p = [0.4, 0.3, 0.3];
        let a = profile_nll(&same, &p, 1e-6);
        let b = profile_nll(&scattered, &p, 1e-6);
        assert!(a.concentration > 1e3, "{a:?}");
        assert!(b.concentration < 100.0, "{b:?}");
        // the profile is a maximum: nearby concentrations are not better
        for f in [0.8, 1.25] {
            assert!(-dm_log_likelihood(&scattered, &p, b.concentration * f) >= b.nll - 1e-9);
        }
    }

    #[test]
    fn resolution_is_inferred_from_the_digits() {
        assert_eq!(infer_resolution([0.94, 0.49, 0.05]), 0.01);
        assert_eq!(infer_resolution([0.9, 0.4, 1.0]), 0.1);
        assert_eq!(infer_resolution([2.0, 3.0]), 1.0);
        assert_eq!(quantised_counts(&[0.94, 0.05], 3, 0.01), vec![94.0, 5.0, 0.0, 0.0]);
    }

    #[test]
    fn floor_only_where_runs_have_mass_and_renormalises() {
        let counts = vec![vec![5.0, 0.0, 0.0], vec![3.0, 2.0, 0.0]];
        let q = model_probabilities(&counts, &[1.0, 0.0, 0.0], 0.01);
        assert!((q.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!(q[1] > 0.0, "a bin some run fills is floored: {q:?}");
        assert_eq!(q[2], 0.0, "a bin no run fills is left alone: {q:?}");
        // a perfect mean model of tightly scattered runs: a large concentration, not one
        // forced down by floor mass in the empty bins
        let runs: Vec<Vec<f64>> = (0..6).map(|i| vec![0.0, 500.0 + i as f64, 1500.0 - i as f64, 0.0, 0.0]).collect();
        let p = profile_nll(&runs, &[0.0, 0.25, 0.75, 0.0, 0.0], 0.5 / 300.0);
        assert!(p.concentration > 1e4, "{p:?}");
    }
}
