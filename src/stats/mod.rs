//! Nonparametric statistics for comparing optimisers: Wilcoxon signed-rank (paired), Wilcoxon
//! rank-sum / Mann-Whitney U (independent), Friedman with Holm-corrected post-hoc comparisons and
//! Nemenyi's critical difference, and the Vargha-Delaney A12 effect size. Pure functions over
//! slices; distributions from statrs.

pub(crate) mod bayes;
pub(crate) mod describe;
pub(crate) mod effect;
pub(crate) mod friedman;
pub(crate) mod holm;
pub(crate) mod proportion;
pub(crate) mod rank_sum;
pub(crate) mod ranks;
pub(crate) mod runtime;
pub(crate) mod wilcoxon;

use thiserror::Error;

/// The alternative hypothesis, for x relative to y (the reports test two-sided; the one-sided
/// alternative is checked against R in the tests; swap x and y for "smaller").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) enum Alternative {
    TwoSided,
    /// x tends to be larger than y.
    Greater,
}

/// How a p-value was computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Method {
    Exact,
    Normal,
}

#[derive(Debug, Error, PartialEq)]
pub(crate) enum StatsError {
    #[error("samples differ in length ({0} and {1}) for a paired test")]
    LengthMismatch(usize, usize),
    #[error("too few observations: {0}")]
    TooFew(String),
    #[error("all differences are zero")]
    AllZero,
    #[error("non-finite value in the data")]
    NonFinite,
}

fn check_finite(v: &[f64]) -> Result<(), StatsError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(StatsError::NonFinite)
    }
}

/// Standard normal upper tail P(Z >= z).
fn normal_sf(z: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    let n = Normal::new(0.0, 1.0).expect("standard normal");
    n.sf(z)
}

/// Standard normal lower tail P(Z <= z).
fn normal_cdf(z: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    Normal::new(0.0, 1.0).expect("standard normal").cdf(z)
}

/// The sign of `v` as R's and scipy's `sign`: -1, 0 or 1 (f64::signum is 1 for 0.0).
fn sign(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Normal approximation with continuity correction: (z, p) for a statistic `diff` = S - E[S] with
/// variance `var`, as R's wilcox.test computes it (no correction when S equals its mean, so p = 1
/// two-sided there).
fn normal_approximation(diff: f64, var: f64, alt: Alternative) -> (f64, f64) {
    let correction = match alt {
        Alternative::TwoSided => 0.5 * sign(diff),
        Alternative::Greater => 0.5,
    };
    let z = (diff - correction) / var.sqrt();
    let p = match alt {
        Alternative::Greater => normal_sf(z),
        Alternative::TwoSided => (2.0 * normal_cdf(-z.abs())).min(1.0),
    };
    (z, p)
}
