//! A small bounded Nelder-Mead (Lagarias et al. 1998 coefficients: reflection 1, expansion
//! 2, contraction 1/2, shrink 1/2) on the unit box, for cheap local refits (bootstrap).
//! Points are clamped to [0, 1]^d before every evaluation, so the objective is only ever
//! called inside the bounds. It tolerates the piecewise-constant objectives of a
//! finite-particle simulation: it stops at the evaluation budget or when the simplex has
//! collapsed below `x_tol`.

/// Result of a minimisation.
#[derive(Clone, Debug, PartialEq)]
pub struct Minimum {
    pub x: Vec<f64>,
    pub value: f64,
    pub evaluations: usize,
}

/// Minimise `f` over [0, 1]^d from `start` with an initial simplex of edge `step` (each
/// vertex moves one coordinate by `step`, inward when that would leave the box), using at
/// most `max_evals` evaluations (at least d + 1 are always made).
pub fn minimise(mut f: impl FnMut(&[f64]) -> f64, start: &[f64], step: f64, max_evals: usize, x_tol: f64) -> Minimum {
    let d = start.len();
    let clamp = |x: &mut Vec<f64>| {
        for v in x.iter_mut() {
            *v = if v.is_nan() { 0.5 } else { v.clamp(0.0, 1.0) };
        }
    };
    let mut evals = 0usize;
    let mut eval = |x: &[f64], evals: &mut usize| {
        *evals += 1;
        let v = f(x);
        if v.is_nan() {
            f64::INFINITY
        } else {
            v
        }
    };
    let mut x0 = start.to_vec();
    clamp(&mut x0);
    let mut simplex: Vec<(Vec<f64>, f64)> = Vec::with_capacity(d + 1);
    let v0 = eval(&x0, &mut evals);
    simplex.push((x0.clone(), v0));
    for i in 0..d {
        let mut x = x0.clone();
        x[i] = if x[i] + step <= 1.0 { x[i] + step } else { x[i] - step };
        clamp(&mut x);
        let v = eval(&x, &mut evals);
        simplex.push((x, v));
    }
    let order = |s: &mut Vec<(Vec<f64>, f64)>| s.sort_by(|a, b| a.1.total_cmp(&b.1));
    while evals < max_evals && d > 0 {
        order(&mut simplex);
        let size = simplex[1..]
            .iter()
            .map(|(x, _)| x.iter().zip(&simplex[0].0).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max))
            .fold(0.0, f64::max);
        if size < x_tol {
            break;
        }
        let centroid: Vec<f64> =
            (0..d).map(|j| simplex[..d].iter().map(|(x, _)| x[j]).sum::<f64>() / d as f64).collect();
        let towards = |t: f64| -> Vec<f64> {
            let worst = &simplex[d].0;
            let mut x: Vec<f64> = centroid.iter().zip(worst).map(|(c, w)| c + t * (c - w)).collect();
            clamp(&mut x);
            x
        };
        let xr = towards(1.0);
        let fr = eval(&xr, &mut evals);
        if fr < simplex[0].1 {
            let xe = towards(2.0);
            let fe = eval(&xe, &mut evals);
            simplex[d] = if fe < fr { (xe, fe) } else { (xr, fr) };
        } else if fr < simplex[d - 1].1 {
            simplex[d] = (xr, fr);
        } else {
            // outside contraction when the reflection beat the worst, else inside
            let (xc, fc) = if fr < simplex[d].1 {
                let x = towards(0.5);
                let v = eval(&x, &mut evals);
                (x, v)
            } else {
                let x = towards(-0.5);
                let v = eval(&x, &mut evals);
                (x, v)
            };
            if fc < fr.min(simplex[d].1) {
                simplex[d] = (xc, fc);
            } else {
                // shrink towards the best vertex
                let best = simplex[0].0.clone();
                for vertex in simplex.iter_mut().skip(1) {
                    let mut x: Vec<f64> = best.iter().zip(&vertex.0).map(|(b, v)| b + 0.5 * (v - b)).collect();
                    clamp(&mut x);
                    let v = eval(&x, &mut evals);
                    *vertex = (x, v);
                }
            }
        }
    }
    order(&mut simplex);
    let (x, value) = simplex.swap_remove(0);
    Minimum { x, value, evaluations: evals }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_minimum_of_a_quadratic_inside_the_box() {
        let m = minimise(|x| (x[0] - 0.3).powi(2) + 2.0 * (x[1] - 0.7).powi(2), &[0.5, 0.5], 0.1, 400, 1e-9);
        assert!((m.x[0] - 0.3).abs() < 1e-4 && (m.x[1] - 0.7).abs() < 1e-4, "{m:?}");
        assert!(m.evaluations <= 400 + 2);
    }

    #[test]
    fn stays_in_the_box_and_finds_a_boundary_minimum() {
        let m = minimise(
            |x| {
                assert!(x.iter().all(|v| (0.0..=1.0).contains(v)));
                (x[0] + 1.0).powi(2)
            },
            &[0.9],
            0.2,
            100,
            1e-9,
        );
        assert!(m.x[0] < 1e-3, "{m:?}");
    }

    #[test]
    fn respects_the_budget() {
        let mut n = 0;
        let m = minimise(
            |x| {
                n += 1;
                x.iter().map(|v| (v - 0.1).powi(2)).sum()
            },
            &[0.5, 0.5, 0.5],
            0.1,
            20,
            0.0,
        );
        assert_eq!(n, m.evaluations);
        // the last step may finish a shrink (d more evaluations)
        assert!(m.evaluations <= 20 + 3, "{}", m.evaluations);
    }
}
