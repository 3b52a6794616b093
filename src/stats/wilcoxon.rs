//! Wilcoxon signed-rank test for paired samples (differences x - y; zero differences dropped,
//! Wilcoxon's method). Exact p-value from the distribution of W+ when n <= 50 and there are no ties;
//! otherwise the normal approximation with tie and continuity corrections (as R's wilcox.test).

use super::ranks::{midranks, tie_sum};
use super::{check_finite, normal_approximation, Alternative, Method, StatsError};

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SignedRank {
    /// Non-zero differences used.
    pub(crate) n: usize,
    /// Sum of the ranks of the positive differences (R's V).
    pub(crate) w_plus: f64,
    pub(crate) w_minus: f64,
    pub(crate) z: Option<f64>,
    pub(crate) p_value: f64,
    pub(crate) method: Method,
    /// Matched-pairs rank-biserial correlation (W+ - W-) / (W+ + W-).
    pub(crate) rank_biserial: f64,
}

/// Number of subsets of {1..n} with each sum 0..=n(n+1)/2.
fn subset_sum_counts(n: usize) -> Vec<f64> {
    let max = n * (n + 1) / 2;
    let mut c = vec![0.0; max + 1];
    c[0] = 1.0;
    for k in 1..=n {
        for s in (k..=max).rev() {
            c[s] += c[s - k];
        }
    }
    c
}

/// The smallest two-sided p-value the exact signed-rank test can give with `n` pairs: both
/// extremes of W+ (0 and n(n+1)/2) have one subset each, so 2 / 2^n (capped at 1; n = 3 gives
/// 0.25). From the exact distribution up to n = 50 (where [`signed_rank`] uses it), by the closed
/// form above that. With fewer than `n` non-zero differences, or with ties, it can only be larger.
pub(crate) fn min_p_two_sided(n: usize) -> f64 {
    if n == 0 {
        return 1.0;
    }
    let p = if n <= 50 {
        let c = subset_sum_counts(n);
        2.0 * c[0] / c.iter().sum::<f64>()
    } else {
        2.0 * 0.5f64.powi(n.min(i32::MAX as usize) as i32)
    };
    p.min(1.0)
}

pub(crate) fn signed_rank(
    x: &[f64],
    y: &[f64],
    alt: Alternative,
) -> Result<SignedRank, StatsError> {
    if x.len() != y.len() {
        return Err(StatsError::LengthMismatch(x.len(), y.len()));
    }
    check_finite(x)?;
    check_finite(y)?;
    let d: Vec<f64> = x.iter().zip(y).map(|(a, b)| a - b).filter(|v| *v != 0.0).collect();
    let n = d.len();
    if n == 0 {
        return Err(StatsError::AllZero);
    }
    let (ranks, ties) = midranks(&d.iter().map(|v| v.abs()).collect::<Vec<f64>>());
    // + 0.0: an empty f64 sum is -0.0, which would print as "-0".
    let w_plus: f64 =
        d.iter().zip(&ranks).filter(|(v, _)| **v > 0.0).map(|(_, r)| r).sum::<f64>() + 0.0;
    let total = (n * (n + 1)) as f64 / 2.0;
    let w_minus = total - w_plus;
    let rank_biserial = (w_plus - w_minus) / total;
    if n <= 50 && ties.is_empty() {
        let c = subset_sum_counts(n);
        let all: f64 = c.iter().sum();
        let v = w_plus.round() as usize;
        let le: f64 = c[..=v].iter().sum::<f64>() / all;
        let ge: f64 = c[v..].iter().sum::<f64>() / all;
        let p = match alt {
            Alternative::Greater => ge,
            Alternative::TwoSided => (2.0 * le.min(ge)).min(1.0),
        };
        return Ok(SignedRank {
            n,
            w_plus,
            w_minus,
            z: None,
            p_value: p,
            method: Method::Exact,
            rank_biserial,
        });
    }
    let nf = n as f64;
    let mean = nf * (nf + 1.0) / 4.0;
    let var = nf * (nf + 1.0) * (2.0 * nf + 1.0) / 24.0 - tie_sum(&ties) / 48.0;
    let (z, p) = normal_approximation(w_plus - mean, var, alt);
    Ok(SignedRank {
        n,
        w_plus,
        w_minus,
        z: Some(z),
        p_value: p,
        method: Method::Normal,
        rank_biserial,
    })
}

#[cfg(test)]
mod tests {
    use super::super::normal_cdf;
    use super::*;

    /// Hollander & Wolfe (1973), depression scores; R: wilcox.test(x, y, paired = TRUE,
    /// alternative = "greater") gives V = 40, p-value = 0.01953.
    #[test]
    #[allow(clippy::approx_constant)] // 3.14 is a depression score, not pi
    fn hollander_wolfe_depression_exact() {
        let x = [1.83, 0.50, 1.62, 2.48, 1.68, 1.88, 1.55, 3.06, 1.30];
        let y = [0.878, 0.647, 0.598, 2.05, 1.06, 1.29, 1.06, 3.14, 1.29];
        let r = signed_rank(&x, &y, Alternative::Greater).unwrap();
        assert_eq!((r.n, r.w_plus, r.method), (9, 40.0, Method::Exact));
        assert!((r.p_value - 0.01953).abs() < 5e-6, "{}", r.p_value);
        // Exact two-sided = 2 x one-sided here: 0.03906.
        assert!(
            (signed_rank(&x, &y, Alternative::TwoSided).unwrap().p_value - 0.0390625).abs() < 1e-12
        );
    }

    /// With ties the normal approximation: d = (1, 2, 2, 3, -4, 5, 6, 7, 8, 9, 10, 11) by hand:
    /// ranks of |d| 1, 2.5, 2.5, 4, ..., 12; W+ = 78 - 5 = 73; mean 39, var = 12*13*25/24 - 6/48
    /// = 162.375; z = (73 - 39 - 0.5) / sqrt(162.375) = 2.62897.
    #[test]
    fn normal_approximation_with_ties_by_hand() {
        let d = [1.0, 2.0, 2.0, 3.0, -4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0];
        let zero = [0.0; 12];
        let r = signed_rank(&d, &zero, Alternative::TwoSided).unwrap();
        assert_eq!((r.w_plus, r.method), (73.0, Method::Normal));
        let z = (73.0 - 39.0 - 0.5) / 162.375f64.sqrt();
        assert!((r.z.unwrap() - z).abs() < 1e-12);
        assert!((r.p_value - 2.0 * normal_cdf(-z)).abs() < 1e-15);
        assert!(r.p_value > 0.008 && r.p_value < 0.009, "{}", r.p_value);
    }

    /// sign(0) = 0 (R, scipy): d = (-2, 0, 1, 1) keeps (-2, 1, 1), ranks 3, 1.5, 1.5 (a tie, so the
    /// normal path), W+ = 3 = n(n+1)/4: z = 0 and p = 1, as scipy.stats.wilcoxon(x, y,
    /// correction=True, method="approx") and R's wilcox.test give (0.785 with signum's 1 for 0).
    #[test]
    fn statistic_at_its_mean_gives_p_one() {
        let r = signed_rank(&[1.0, 2.0, 2.0, 3.0], &[3.0, 2.0, 1.0, 2.0], Alternative::TwoSided)
            .unwrap();
        assert_eq!((r.n, r.w_plus, r.method), (3, 3.0, Method::Normal));
        assert_eq!((r.z, r.p_value), (Some(0.0), 1.0));
        // No positive difference: W+ is +0, not -0.
        let r = signed_rank(&[1.0, 1.0, 1.0], &[2.0, 2.0, 3.0], Alternative::TwoSided).unwrap();
        assert!(r.w_plus == 0.0 && r.w_plus.is_sign_positive(), "{}", r.w_plus);
    }

    #[test]
    fn distribution_sums_to_one_and_errors() {
        let c = subset_sum_counts(10);
        assert_eq!(c.iter().sum::<f64>(), 1024.0);
        assert_eq!(signed_rank(&[1.0], &[1.0], Alternative::TwoSided), Err(StatsError::AllZero));
        assert_eq!(
            signed_rank(&[1.0], &[1.0, 2.0], Alternative::TwoSided),
            Err(StatsError::LengthMismatch(1, 2))
        );
    }

    /// Closed forms: 2 / 2^n two-sided (n = 3: 0.25, so 3 repeats never reach 0.05; n = 6:
    /// 0.03125, the first below 0.05), and the test itself attains it.
    #[test]
    fn smallest_attainable_p() {
        assert_eq!(min_p_two_sided(3), 0.25);
        assert_eq!(min_p_two_sided(1), 1.0);
        assert_eq!(min_p_two_sided(0), 1.0);
        assert_eq!(min_p_two_sided(5), 0.0625);
        assert_eq!(min_p_two_sided(6), 0.03125);
        assert_eq!(min_p_two_sided(60), 2.0 * 0.5f64.powi(60));
        let r = signed_rank(&[1.0, 2.0, 3.0], &[2.0, 4.0, 6.0], Alternative::TwoSided).unwrap();
        assert_eq!(r.p_value, min_p_two_sided(3));
    }
}
