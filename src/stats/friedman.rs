//! Friedman's test over a blocks x treatments table (blocks: problems or cells; treatments:
//! optimisers; the smallest value ranks 1), with the tie-corrected statistic, mean ranks, Nemenyi's
//! critical difference (Demsar 2006) and pairwise z-tests adjusted by Holm.

use super::holm::holm;
use super::ranks::{midranks, tie_sum};
use super::{check_finite, normal_cdf, StatsError};

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Friedman {
    pub(crate) blocks: usize,
    pub(crate) treatments: usize,
    pub(crate) chi_squared: f64,
    pub(crate) df: usize,
    pub(crate) p_value: f64,
    pub(crate) mean_ranks: Vec<f64>,
    /// Nemenyi critical difference at alpha = 0.05 (None when k > 10).
    pub(crate) critical_difference: Option<f64>,
    /// (i, j, z, p, Holm-adjusted p) for every pair i < j.
    pub(crate) pairwise: Vec<(usize, usize, f64, f64, f64)>,
}

/// Critical values q_0.05 of the Studentised range divided by sqrt 2 (Demsar 2006, Table 5a), k = 2..10.
pub(crate) const NEMENYI_Q05: [f64; 9] =
    [1.960, 2.343, 2.569, 2.728, 2.850, 2.949, 3.031, 3.102, 3.164];

/// `table[b][t]`: value of treatment t on block b.
pub(crate) fn friedman(table: &[Vec<f64>]) -> Result<Friedman, StatsError> {
    let n = table.len();
    if n < 2 {
        return Err(StatsError::TooFew(format!("{n} blocks, at least 2 needed")));
    }
    let k = table[0].len();
    if k < 2 || table.iter().any(|r| r.len() != k) {
        return Err(StatsError::TooFew(
            "every block needs the same number (at least 2) of treatments".into(),
        ));
    }
    let mut sums = vec![0.0; k];
    let mut ties_total = 0.0;
    for row in table {
        check_finite(row)?;
        let (r, ties) = midranks(row);
        ties_total += tie_sum(&ties);
        for (s, v) in sums.iter_mut().zip(r) {
            *s += v;
        }
    }
    let (nf, kf) = (n as f64, k as f64);
    let stat = 12.0 / (nf * kf * (kf + 1.0)) * sums.iter().map(|r| r * r).sum::<f64>()
        - 3.0 * nf * (kf + 1.0);
    let chi = stat / (1.0 - ties_total / (nf * (kf * kf * kf - kf)));
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    // The survival function, not 1 - cdf: large statistics keep their tiny p-values.
    let p_value = ChiSquared::new(kf - 1.0).expect("k >= 2").sf(chi);
    let mean_ranks: Vec<f64> = sums.iter().map(|s| s / nf).collect();
    let se = (kf * (kf + 1.0) / (6.0 * nf)).sqrt();
    let critical_difference = NEMENYI_Q05.get(k.wrapping_sub(2)).map(|q| q * se);
    let mut pairs = Vec::new();
    for i in 0..k {
        for j in i + 1..k {
            let z = (mean_ranks[i] - mean_ranks[j]) / se;
            pairs.push((i, j, z, (2.0 * normal_cdf(-z.abs())).min(1.0)));
        }
    }
    let adjusted = holm(&pairs.iter().map(|p| p.3).collect::<Vec<f64>>());
    let pairwise =
        pairs.into_iter().zip(adjusted).map(|((i, j, z, p), a)| (i, j, z, p, a)).collect();
    Ok(Friedman {
        blocks: n,
        treatments: k,
        chi_squared: chi,
        df: k - 1,
        p_value,
        mean_ranks,
        critical_difference,
        pairwise,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// R's friedman.test example: RoundingTimes (Hollander & Wolfe 1973, p. 140): Friedman
    /// chi-squared = 11.143, df = 2, p-value = 0.003805.
    /// 140 blocks ranked alike by 3 treatments: chi-squared = 280 on 2 df, whose upper tail is
    /// exactly exp(-140) ~ 1.6e-61 (a p-value 1 - cdf would round to 0).
    #[test]
    fn tiny_p_values_survive() {
        let table: Vec<Vec<f64>> = (0..140).map(|b| vec![3.0 + b as f64, 2.0, 1.0]).collect();
        let f = friedman(&table).unwrap();
        assert!((f.chi_squared - 280.0).abs() < 1e-9);
        assert!((f.p_value / (-140f64).exp() - 1.0).abs() < 1e-6, "{}", f.p_value);
    }

    #[test]
    fn rounding_times() {
        let v = [
            5.40, 5.50, 5.55, 5.85, 5.70, 5.75, 5.20, 5.60, 5.50, 5.55, 5.50, 5.40, 5.90, 5.85,
            5.70, 5.45, 5.55, 5.60, 5.40, 5.40, 5.35, 5.45, 5.50, 5.35, 5.25, 5.15, 5.00, 5.85,
            5.80, 5.70, 5.25, 5.20, 5.10, 5.65, 5.55, 5.45, 5.60, 5.35, 5.45, 5.05, 5.00, 4.95,
            5.50, 5.50, 5.40, 5.45, 5.55, 5.50, 5.55, 5.55, 5.35, 5.45, 5.50, 5.55, 5.50, 5.45,
            5.25, 5.65, 5.60, 5.40, 5.70, 5.65, 5.55, 6.30, 6.30, 6.25,
        ];
        let table: Vec<Vec<f64>> = v.chunks(3).map(|c| c.to_vec()).collect();
        assert_eq!(table.len(), 22);
        let f = friedman(&table).unwrap();
        assert!((f.chi_squared - 11.143).abs() < 5e-4, "{}", f.chi_squared);
        assert!((f.p_value - 0.003805).abs() < 5e-6, "{}", f.p_value);
        assert_eq!(f.df, 2);
    }

    /// Demsar (2006) section 3.2.2: four methods, 14 data sets, CD = 2.569 sqrt(4*5/(6*14)) = 1.25.
    #[test]
    fn nemenyi_cd_and_holm_pairs() {
        let table: Vec<Vec<f64>> =
            (0..14).map(|b| vec![1.0 + (b % 3) as f64, 2.0, 3.0, 4.0 - (b % 2) as f64]).collect();
        let f = friedman(&table).unwrap();
        assert!((f.critical_difference.unwrap() - 2.569 * (20.0f64 / 84.0).sqrt()).abs() < 1e-12);
        assert_eq!(f.pairwise.len(), 6);
        assert!(f.pairwise.iter().all(|p| p.4 >= p.3));
        assert!((f.mean_ranks.iter().sum::<f64>() - 10.0).abs() < 1e-12);
    }
}
