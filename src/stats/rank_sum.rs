//! Wilcoxon rank-sum / Mann-Whitney U test for two independent samples. W = sum of the ranks of x
//! minus n1(n1+1)/2 (R's W, which equals U of x). Exact p-value when both samples have at most 50
//! values and there are no ties; otherwise the normal approximation with tie and continuity
//! corrections.

use super::ranks::{midranks, tie_sum};
use super::{check_finite, normal_approximation, Alternative, Method, StatsError};

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RankSum {
    /// U statistic of x (R's W).
    pub(crate) w: f64,
    pub(crate) z: Option<f64>,
    pub(crate) p_value: f64,
    pub(crate) method: Method,
}

/// Counts of U = 0..=n1 n2 over all ways to interleave the samples (DP over ranks).
fn u_counts(n1: usize, n2: usize) -> Vec<f64> {
    // f[j][u]: ways to pick j of the first i items of the merged order with U-contribution u.
    let max = n1 * n2;
    let mut f = vec![vec![0.0; max + 1]; n1 + 1];
    f[0][0] = 1.0;
    for i in 0..(n1 + n2) {
        for j in (0..n1.min(i + 1)).rev() {
            // Choosing item i (0-based) as the (j+1)-th x contributes (i - j) y-values below it.
            let add = i - j;
            if add > n2 {
                continue;
            }
            for u in (0..=max - add).rev() {
                let v = f[j][u];
                if v != 0.0 {
                    f[j + 1][u + add] += v;
                }
            }
        }
    }
    f.swap_remove(n1)
}

/// The smallest two-sided p-value the exact rank-sum test can give with samples of `n1` and `n2`
/// values: each extreme of U (0 and n1 n2) has one arrangement of the C(n1 + n2, n1), so
/// 2 / C(n1 + n2, n1) (capped at 1; 3 vs 3 gives 0.1). From the exact distribution where
/// [`rank_sum`] uses it (both at most 50), by the closed form (in logs) beyond. Ties only make it
/// larger.
pub(crate) fn min_p_two_sided(n1: usize, n2: usize) -> f64 {
    if n1 == 0 || n2 == 0 {
        return 1.0;
    }
    let p = if n1 <= 50 && n2 <= 50 {
        let c = u_counts(n1, n2);
        2.0 * c[0] / c.iter().sum::<f64>()
    } else {
        // ln C(n1 + n2, n1) = sum_{k=1..n1} ln((n2 + k) / k).
        let (a, b) = (n1.min(n2), n1.max(n2));
        let ln_c: f64 = (1..=a).map(|k| ((b + k) as f64 / k as f64).ln()).sum();
        2.0 * (-ln_c).exp()
    };
    p.min(1.0)
}

pub(crate) fn rank_sum(x: &[f64], y: &[f64], alt: Alternative) -> Result<RankSum, StatsError> {
    check_finite(x)?;
    check_finite(y)?;
    let (n1, n2) = (x.len(), y.len());
    if n1 == 0 || n2 == 0 {
        return Err(StatsError::TooFew("both samples need at least one value".into()));
    }
    let all: Vec<f64> = x.iter().chain(y).copied().collect();
    let (ranks, ties) = midranks(&all);
    let w = ranks[..n1].iter().sum::<f64>() - (n1 * (n1 + 1)) as f64 / 2.0;
    if n1 <= 50 && n2 <= 50 && ties.is_empty() {
        let c = u_counts(n1, n2);
        let total: f64 = c.iter().sum();
        let u = w.round() as usize;
        let le = c[..=u].iter().sum::<f64>() / total;
        let ge = c[u..].iter().sum::<f64>() / total;
        let p = match alt {
            Alternative::Greater => ge,
            Alternative::TwoSided => (2.0 * le.min(ge)).min(1.0),
        };
        return Ok(RankSum { w, z: None, p_value: p, method: Method::Exact });
    }
    let (a, b) = (n1 as f64, n2 as f64);
    let n = a + b;
    let mean = a * b / 2.0;
    let var = a * b / 12.0 * ((n + 1.0) - tie_sum(&ties) / (n * (n - 1.0)));
    let (z, p) = normal_approximation(w - mean, var, alt);
    Ok(RankSum { w, z: Some(z), p_value: p, method: Method::Normal })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// R's wilcox.test example (Hollander & Wolfe 1973, p. 69): W = 35, p-value = 0.1272 (greater).
    #[test]
    fn r_example_exact() {
        let x = [0.80, 0.83, 1.89, 1.04, 1.45, 1.38, 1.91, 1.64, 0.73, 1.46];
        let y = [1.15, 0.88, 0.90, 0.74, 1.21];
        let r = rank_sum(&x, &y, Alternative::Greater).unwrap();
        assert_eq!((r.w, r.method), (35.0, Method::Exact));
        assert!((r.p_value - 0.1272).abs() < 5e-5, "{}", r.p_value);
    }

    #[test]
    fn exact_distribution_sums_to_binomial_and_is_symmetric() {
        let c = u_counts(4, 6);
        assert_eq!(c.iter().sum::<f64>(), 210.0); // C(10, 4)
        for u in 0..=24 {
            assert_eq!(c[u], c[24 - u]);
        }
    }

    /// sign(0) = 0: x = (1, 2, 2, 3), y = (3, 2, 1, 2): ranks 1.5, 4.5, 4.5, 7.5 | 7.5, 4.5, 1.5,
    /// 4.5 (ties, so the normal path), W = 18 - 10 = 8 = n1 n2 / 2: p = 1 as in scipy.stats.mannwhitneyu and
    /// R (0.876 with signum's 1 for 0).
    #[test]
    fn statistic_at_its_mean_gives_p_one() {
        let r =
            rank_sum(&[1.0, 2.0, 2.0, 3.0], &[3.0, 2.0, 1.0, 2.0], Alternative::TwoSided).unwrap();
        assert_eq!((r.w, r.method), (8.0, Method::Normal));
        assert_eq!((r.z, r.p_value), (Some(0.0), 1.0));
    }

    /// Tied case by hand: x = (1, 2, 2), y = (2, 3, 4, 5): ranks 1, 3, 3 | 3, 5, 6, 7; W = 7 - 6 = 1;
    /// mean 6, var = 12/12 (8 - 24/42) = 7.428571; two-sided z = (1 - 6 + 0.5)/sqrt(var).
    #[test]
    fn ties_use_the_corrected_normal() {
        let r = rank_sum(&[1.0, 2.0, 2.0], &[2.0, 3.0, 4.0, 5.0], Alternative::TwoSided).unwrap();
        assert_eq!((r.w, r.method), (1.0, Method::Normal));
        let z = (1.0 - 6.0 + 0.5) / (8.0f64 - 24.0 / 42.0).sqrt();
        assert!((r.z.unwrap() - z).abs() < 1e-12);
    }

    /// Closed forms: 2 / C(n1 + n2, n1) two-sided (3 vs 3: 2/20 = 0.1; 4 vs 4: 2/70), and the test
    /// attains it on separated samples.
    #[test]
    fn smallest_attainable_p() {
        assert!((min_p_two_sided(3, 3) - 0.1).abs() < 1e-15);
        assert!((min_p_two_sided(4, 4) - 2.0 / 70.0).abs() < 1e-15);
        assert!((min_p_two_sided(2, 5) - 2.0 / 21.0).abs() < 1e-15);
        assert_eq!((min_p_two_sided(1, 1), min_p_two_sided(0, 3)), (1.0, 1.0));
        // Beyond the exact range, the closed form: 2 / C(102, 51) = 5.0048940999e-30.
        let p = min_p_two_sided(51, 51);
        assert!((p / 5.0048940999241115e-30 - 1.0).abs() < 1e-9, "{p}");
        let r = rank_sum(&[1.0, 2.0, 3.0], &[4.0, 5.0, 6.0], Alternative::TwoSided).unwrap();
        assert!((r.p_value - min_p_two_sided(3, 3)).abs() < 1e-15);
    }
}
