//! Descriptive statistics over repeats, shared by the reports: the mean and the sample variance
//! (divisor n - 1, as MATLAB's `var` and the papers' tables use).

/// (mean, sample variance); the variance of fewer than two values is 0.
pub fn mean_var(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = if v.len() > 1 {
        v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0)
    } else {
        0.0
    };
    (m, var)
}

/// (mean, sample standard deviation).
pub fn mean_std(v: &[f64]) -> (f64, f64) {
    let (m, var) = mean_var(v);
    (m, var.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn textbook_mean_and_sample_variance() {
        // 2, 4, 4, 4, 5, 5, 7, 9: mean 5, squared deviations sum to 32, sample variance 32 / 7.
        let (m, var) = mean_var(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]);
        assert_eq!(m, 5.0);
        assert!((var - 32.0 / 7.0).abs() < 1e-15);
        assert_eq!(mean_std(&[3.0]), (3.0, 0.0));
    }
}
