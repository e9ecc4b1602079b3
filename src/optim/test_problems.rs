//! Standard benchmark problems with known Pareto fronts, for testing the optimiser.
//!
//! - ZDT1, ZDT2: Zitzler, Deb, Thiele (2000), 30 variables in [0, 1], convex / concave fronts.
//! - BNH: Binh and Korn (1997), 2 variables, 2 inequality constraints (Deb's book, 2001).
//!
//! "True" hypervolumes are computed from a dense sampling of the analytic front, which
//! underestimates the continuous value by O(1/n) (about 1e-5 relative for n = 10 000).

use super::hypervolume::hypervolume_2d;
use super::nsga2::{BatchProblem, Evaluation};

/// Points sampled on the true fronts when computing their hypervolume.
pub const FRONT_SAMPLES: usize = 10_000;

fn zdt_g(x: &[f64]) -> f64 {
    1.0 + 9.0 * x[1..].iter().sum::<f64>() / (x.len() - 1) as f64
}

fn sampled_hypervolume(f: impl Fn(f64) -> [f64; 2], reference: [f64; 2]) -> f64 {
    let pts: Vec<[f64; 2]> = (0..FRONT_SAMPLES).map(|i| f(i as f64 / (FRONT_SAMPLES - 1) as f64)).collect();
    hypervolume_2d(&pts, reference)
}

/// ZDT1: f1 = x1, f2 = g (1 - sqrt(f1 / g)); front at g = 1: f2 = 1 - sqrt(f1), convex.
#[derive(Clone, Debug)]
pub struct Zdt1 {
    pub n: usize,
}

impl Default for Zdt1 {
    fn default() -> Self {
        Zdt1 { n: 30 }
    }
}

impl Zdt1 {
    pub fn true_hypervolume(reference: [f64; 2]) -> f64 {
        sampled_hypervolume(|t| [t, 1.0 - t.sqrt()], reference)
    }
}

impl BatchProblem for Zdt1 {
    fn dim(&self) -> usize {
        self.n
    }
    fn n_objectives(&self) -> usize {
        2
    }
    fn bounds(&self) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0; self.n], vec![1.0; self.n])
    }
    fn evaluate_batch(&mut self, xs: &[Vec<f64>], _generation: u64) -> Vec<Evaluation> {
        xs.iter()
            .map(|x| {
                let g = zdt_g(x);
                Evaluation { objectives: vec![x[0], g * (1.0 - (x[0] / g).sqrt())], violation: 0.0 }
            })
            .collect()
    }
}

/// ZDT2: f1 = x1, f2 = g (1 - (f1 / g)^2); front at g = 1: f2 = 1 - f1^2, concave.
#[derive(Clone, Debug)]
pub struct Zdt2 {
    pub n: usize,
}

impl Default for Zdt2 {
    fn default() -> Self {
        Zdt2 { n: 30 }
    }
}

impl Zdt2 {
    pub fn true_hypervolume(reference: [f64; 2]) -> f64 {
        sampled_hypervolume(|t| [t, 1.0 - t * t], reference)
    }
}

impl BatchProblem for Zdt2 {
    fn dim(&self) -> usize {
        self.n
    }
    fn n_objectives(&self) -> usize {
        2
    }
    fn bounds(&self) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0; self.n], vec![1.0; self.n])
    }
    fn evaluate_batch(&mut self, xs: &[Vec<f64>], _generation: u64) -> Vec<Evaluation> {
        xs.iter()
            .map(|x| {
                let g = zdt_g(x);
                let r = x[0] / g;
                Evaluation { objectives: vec![x[0], g * (1.0 - r * r)], violation: 0.0 }
            })
            .collect()
    }
}

/// BNH: minimise f1 = 4 x1^2 + 4 x2^2 and f2 = (x1 - 5)^2 + (x2 - 5)^2 subject to
/// g1 = (x1 - 5)^2 + x2^2 <= 25 and g2 = (x1 - 8)^2 + (x2 + 3)^2 >= 7.7,
/// x1 in [0, 5], x2 in [0, 3]. Violation = sum of the positive constraint excesses.
#[derive(Clone, Debug, Default)]
pub struct Bnh;

impl Bnh {
    pub fn objectives(x: &[f64]) -> [f64; 2] {
        [4.0 * x[0] * x[0] + 4.0 * x[1] * x[1], (x[0] - 5.0).powi(2) + (x[1] - 5.0).powi(2)]
    }

    pub fn violation(x: &[f64]) -> f64 {
        let g1 = (x[0] - 5.0).powi(2) + x[1] * x[1] - 25.0;
        let g2 = 7.7 - (x[0] - 8.0).powi(2) - (x[1] + 3.0).powi(2);
        g1.max(0.0) + g2.max(0.0)
    }

    /// Pareto set: x1 = x2 in [0, 3], then x2 = 3 with x1 in [3, 5] (both segments feasible),
    /// parametrised by t in [0, 1] with equal parameter length on each segment.
    pub fn true_hypervolume(reference: [f64; 2]) -> f64 {
        sampled_hypervolume(
            |t| {
                let s = 5.0 * t;
                let x = if s <= 3.0 { [s, s] } else { [s, 3.0] };
                Self::objectives(&x)
            },
            reference,
        )
    }
}

impl BatchProblem for Bnh {
    fn dim(&self) -> usize {
        2
    }
    fn n_objectives(&self) -> usize {
        2
    }
    fn bounds(&self) -> (Vec<f64>, Vec<f64>) {
        (vec![0.0, 0.0], vec![5.0, 3.0])
    }
    fn evaluate_batch(&mut self, xs: &[Vec<f64>], _generation: u64) -> Vec<Evaluation> {
        xs.iter()
            .map(|x| Evaluation { objectives: Self::objectives(x).to_vec(), violation: Self::violation(x) })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn true_hypervolumes_match_the_integrals() {
        // Reference (1.1, 1.1): HV = 1.21 - integral of the front over [0, 1].
        let r = [1.1, 1.1];
        assert!((Zdt1::true_hypervolume(r) - (1.21 - 1.0 / 3.0)).abs() < 1e-4);
        assert!((Zdt2::true_hypervolume(r) - (1.21 - 2.0 / 3.0)).abs() < 1e-4);
    }

    #[test]
    fn zdt_optimum_lies_on_the_front() {
        let mut x = vec![0.0; 30];
        x[0] = 0.25;
        let e = Zdt1::default().evaluate_batch(&[x.clone()], 0);
        assert_eq!(e[0].objectives, vec![0.25, 0.5]);
        let e = Zdt2::default().evaluate_batch(&[x], 0);
        assert_eq!(e[0].objectives, vec![0.25, 1.0 - 0.0625]);
    }

    #[test]
    fn bnh_front_is_feasible_and_constraints_bite() {
        for i in 0..=50 {
            let s = 5.0 * i as f64 / 50.0;
            let x = if s <= 3.0 { [s, s] } else { [s, 3.0] };
            assert_eq!(Bnh::violation(&x), 0.0, "{x:?}");
        }
        // (0, 3): g1 = 25 + 9 - 25 = 9 > 0.
        assert!((Bnh::violation(&[0.0, 3.0]) - 9.0).abs() < 1e-12);
        // g2's forbidden disc lies outside the box; check it at its centre: 7.7.
        assert!((Bnh::violation(&[8.0, -3.0]) - 7.7).abs() < 1e-12);
        let hv = Bnh::true_hypervolume([140.0, 50.0]);
        assert!(hv > 4000.0 && hv < 140.0 * 46.0, "hv = {hv}");
    }
}
