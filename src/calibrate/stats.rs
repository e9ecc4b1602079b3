//! The few sample statistics the calibrations report (bootstrap intervals, standard errors).

/// Sample standard deviation (n − 1) of the finite values; NaN with fewer than two.
pub fn sample_sd(v: &[f64]) -> f64 {
    let v: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if v.len() < 2 {
        return f64::NAN;
    }
    let m = v.iter().sum::<f64>() / v.len() as f64;
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

/// Percentile `q` in [0, 1] of `v` (linear interpolation between order statistics, NaNs
/// left out); NaN for no values.
pub fn percentile(v: &[f64], q: f64) -> f64 {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| !x.is_nan()).collect();
    if s.is_empty() {
        return f64::NAN;
    }
    s.sort_by(f64::total_cmp);
    let pos = q.clamp(0.0, 1.0) * (s.len() - 1) as f64;
    let (i, f) = (pos.floor() as usize, pos.fract());
    if i + 1 < s.len() {
        s[i] + f * (s[i + 1] - s[i])
    } else {
        s[i]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_interpolate_and_sd_uses_n_minus_one() {
        let v = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(percentile(&v, 0.0), 1.0);
        assert_eq!(percentile(&v, 0.5), 3.0);
        assert!((percentile(&v, 0.16) - 1.64).abs() < 1e-12);
        assert!(percentile(&[], 0.5).is_nan());
        assert!((sample_sd(&[1.0, 3.0]) - 2f64.sqrt()).abs() < 1e-12);
        assert!((sample_sd(&[1.0, f64::NAN, 3.0]) - 2f64.sqrt()).abs() < 1e-12);
        assert!(sample_sd(&[1.0]).is_nan());
    }
}
