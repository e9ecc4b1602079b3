//! The Levenberg–Marquardt step of a least-squares polish (Levenberg 1944, Marquardt 1963;
//! Nocedal & Wright, *Numerical Optimization*, 2nd ed., §10.3): for residuals r(u) with a
//! Jacobian J, the step Δ solving (JᵀJ + λ·diag(JᵀJ)) Δ = −Jᵀr, in the unit box of a
//! model's space. Small λ is the Gauss–Newton step, large λ a short step along the scaled
//! gradient. The SSE objective (Eq. 4.62) is a sum of squares of the bins' residuals, so one
//! Jacobian (d simulations by forward differences, common random numbers) buys a step in
//! all d parameters at once, where a compass search spends 2d simulations on one axis.

/// The residual vector of simulated bins against measured ones, percentage points: the SSE
/// objective is its squared norm.
pub fn residuals(bins: &[Vec<f64>], measured: &[&[f64]]) -> Vec<f64> {
    bins.iter().zip(measured).flat_map(|(b, m)| b.iter().zip(m.iter()).map(|(s, q)| 100.0 * (s - q))).collect()
}

/// The normal equations of a Jacobian (columns `jac`, one per parameter) and residual `r`:
/// JᵀJ and Jᵀr.
pub fn normal_equations(jac: &[Vec<f64>], r: &[f64]) -> (Vec<Vec<f64>>, Vec<f64>) {
    let d = jac.len();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let a = (0..d).map(|i| (0..d).map(|k| dot(&jac[i], &jac[k])).collect()).collect();
    let g = (0..d).map(|i| dot(&jac[i], r)).collect();
    (a, g)
}

/// The damped step Δ for damping `lambda`: (A + λ·diag(A)) Δ = −g, the diagonal floored so
/// that a parameter the bins do not see (a zero column) stays put; each component limited
/// to ±`max_step`. None when the system is singular even so.
pub fn step(a: &[Vec<f64>], g: &[f64], lambda: f64, max_step: f64) -> Option<Vec<f64>> {
    let d = g.len();
    let top = (0..d).map(|i| a[i][i]).fold(0.0f64, f64::max);
    if top <= 0.0 {
        return None;
    }
    let mut m: Vec<Vec<f64>> = a.to_vec();
    for (i, row) in m.iter_mut().enumerate() {
        row[i] += lambda * a[i][i].max(1e-9 * top) + 1e-12 * top;
    }
    let rhs: Vec<f64> = g.iter().map(|v| -v).collect();
    solve(m, rhs).map(|x| x.into_iter().map(|v| v.clamp(-max_step, max_step)).collect())
}

/// Gaussian elimination with partial pivoting.
fn solve(mut m: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    for c in 0..n {
        let p = (c..n).max_by(|i, k| m[*i][c].abs().total_cmp(&m[*k][c].abs()))?;
        if m[p][c].abs() < 1e-300 || !m[p][c].is_finite() {
            return None;
        }
        m.swap(c, p);
        b.swap(c, p);
        let (top, below) = m.split_at_mut(c + 1);
        let pivot = &top[c];
        for (i, row) in below.iter_mut().enumerate() {
            let f = row[c] / pivot[c];
            for (x, p) in row[c..].iter_mut().zip(&pivot[c..]) {
                *x -= f * p;
            }
            b[c + 1 + i] -= f * b[c];
        }
    }
    let mut x = vec![0.0; n];
    for r in (0..n).rev() {
        let s: f64 = (r + 1..n).map(|k| m[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / m[r][r];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a linear least-squares problem the undamped step lands on the minimum at once.
    #[test]
    fn the_gauss_newton_step_solves_a_linear_problem() {
        // r(u) = J u + r0 with J = [[1, 0], [0, 2], [1, 1]]; at u = 0, r = r0
        let jac = vec![vec![1.0, 0.0, 1.0], vec![0.0, 2.0, 1.0]];
        let r0 = vec![-1.0, -2.0, -3.0];
        let (a, g) = normal_equations(&jac, &r0);
        let du = step(&a, &g, 0.0, 10.0).unwrap();
        // the normal equations' solution: JᵀJ = [[2, 1], [1, 5]], Jᵀr0 = [-4, -7] → u = [13/9, 10/9]
        assert!((du[0] - 13.0 / 9.0).abs() < 1e-9 && (du[1] - 10.0 / 9.0).abs() < 1e-9, "{du:?}");
        // damping shortens the step, and the limit caps each component
        let damped = step(&a, &g, 10.0, 10.0).unwrap();
        assert!(damped.iter().zip(&du).all(|(s, f)| s.abs() < f.abs()), "{damped:?}");
        assert_eq!(step(&a, &g, 0.0, 0.5).unwrap(), vec![0.5, 0.5]);
    }

    #[test]
    fn a_parameter_the_bins_do_not_see_stays_put() {
        let jac = vec![vec![1.0, 1.0], vec![0.0, 0.0]];
        let (a, g) = normal_equations(&jac, &[1.0, 1.0]);
        let du = step(&a, &g, 0.0, 1.0).unwrap();
        assert!((du[0] + 1.0).abs() < 1e-6 && du[1] == 0.0, "{du:?}");
        assert_eq!(step(&[vec![0.0]], &[0.0], 0.0, 1.0), None);
    }

    #[test]
    fn residuals_are_percentage_points_over_every_condition() {
        let r = residuals(&[vec![0.5, 0.5], vec![1.0]], &[&[0.4, 0.6], &[0.9]]);
        assert!(r.iter().zip([10.0, -10.0, 10.0]).all(|(a, b)| (a - b).abs() < 1e-9), "{r:?}");
    }
}
