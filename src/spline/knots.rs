//! Clamped knot vectors from parameters (thesis Eq. 2.9-2.11), under a named reading.
//!
//! The thesis gives only the averaging method, Eq. 2.9-2.11, written for as many control points as
//! parameters, and does not say what it does when the control net is smaller than the grid (every
//! Chapter 5 net but none of its formulas). Two readings are kept, by name (docs/readings.md):
//! - [`KnotRule::Eq2_10`]: Eq. 2.10 applied literally with n = CN - 1, T_{j+p} = (1/p)
//!   sum_{i=j}^{j+p-1} t_i for j = 1..n-p, so a smaller net uses only the first parameters
//!   t_1..t_{CN-2}. This is the reading that reproduces the thesis' errors (Appendices E, F).
//! - [`KnotRule::NurbsBook`]: The NURBS Book eq. 9.68-9.69, d = (m + 1) / (n - p + 1); for
//!   j = 1..n-p, i = int(j d), a = j d - i, u_{p+j} = (1 - a) t_{i-1} + a t_i. Spreads the knots
//!   over all parameters; not cited by the thesis.
//!
//! Both are plain averaging when CN equals the number of parameters.

use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// How interior knots are placed when the net is smaller than the grid.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default, Serialize, Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum KnotRule {
    /// Eq. 2.10 literally, with n = CN - 1 (the thesis' own formula).
    #[default]
    #[serde(rename = "eq2_10")]
    Eq2_10,
    /// The NURBS Book eq. 9.68-9.69.
    NurbsBook,
}

impl KnotRule {
    pub const ALL: [KnotRule; 2] = [KnotRule::Eq2_10, KnotRule::NurbsBook];

    /// The spec value.
    pub fn name(self) -> &'static str {
        match self {
            KnotRule::Eq2_10 => "eq2_10",
            KnotRule::NurbsBook => "nurbs_book",
        }
    }
}

impl fmt::Display for KnotRule {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for KnotRule {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        KnotRule::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| format!("unknown knot rule `{s}` (expected eq2_10 or nurbs_book)"))
    }
}

/// Clamped knot vector of degree `p` for `n_ctrl` control points fitted to `params` (non-decreasing,
/// first 0, last 1) by `rule`. Errors when n_ctrl > params.len() or n_ctrl < p + 1.
pub(crate) fn knot_vector(
    params: &[f64],
    n_ctrl: usize,
    p: usize,
    rule: KnotRule,
) -> Result<Vec<f64>, String> {
    let m1 = params.len();
    if n_ctrl < p + 1 {
        return Err(format!(
            "{n_ctrl} control points are too few for degree {p} (at least {})",
            p + 1
        ));
    }
    if n_ctrl > m1 {
        return Err(format!("{n_ctrl} control points exceed the {m1} data parameters"));
    }
    let n = n_ctrl - 1;
    let mut k = vec![0.0; n_ctrl + p + 1];
    for x in k.iter_mut().skip(n + 1) {
        *x = 1.0;
    }
    if n_ctrl == m1 || rule == KnotRule::Eq2_10 {
        // Eq. 2.10: T_{j+p} = (1/p) sum_{i=j}^{j+p-1} t_i, j = 1..n-p (i <= n - 1 < m1: in range).
        for j in 1..=n.saturating_sub(p) {
            k[j + p] = params[j..j + p].iter().sum::<f64>() / p as f64;
        }
    } else {
        let d = m1 as f64 / (n - p + 1) as f64;
        for j in 1..=n - p {
            let jd = j as f64 * d;
            let i = jd.floor() as usize;
            let a = jd - i as f64;
            k[p + j] = (1.0 - a) * params[i - 1] + a * params[i];
        }
    }
    Ok(k)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn averaging_when_sizes_match_under_both_rules() {
        let t = [0.0, 0.1, 0.3, 0.6, 0.7, 1.0];
        let want = [
            0.0,
            0.0,
            0.0,
            0.0,
            (0.1 + 0.3 + 0.6) / 3.0,
            (0.3 + 0.6 + 0.7) / 3.0,
            1.0,
            1.0,
            1.0,
            1.0,
        ];
        for rule in KnotRule::ALL {
            let k = knot_vector(&t, 6, 3, rule).unwrap();
            for (a, b) in k.iter().zip(want) {
                assert!((a - b).abs() < 1e-15, "{rule}: {k:?}");
            }
        }
    }

    #[test]
    fn eq2_10_literal_example() {
        // 20 uniform parameters, CN = 6: n = 5, j = 1..2: T_4 = (t1+t2+t3)/3 = 2/19, T_5 = 3/19.
        let t: Vec<f64> = (0..20).map(|k| k as f64 / 19.0).collect();
        let k = knot_vector(&t, 6, 3, KnotRule::Eq2_10).unwrap();
        let want = [0.0, 0.0, 0.0, 0.0, 0.105263, 0.157895, 1.0, 1.0, 1.0, 1.0];
        assert_eq!(k.len(), want.len());
        for (a, b) in k.iter().zip(want) {
            assert!((a - b).abs() < 5e-7, "{k:?}");
        }
        assert!((k[4] - 2.0 / 19.0).abs() < 1e-15 && (k[5] - 3.0 / 19.0).abs() < 1e-15);
    }

    #[test]
    fn nurbs_book_9_69_for_smaller_nets() {
        // m + 1 = 20 uniform parameters, n + 1 = 6: d = 20/3.
        let t: Vec<f64> = (0..20).map(|k| k as f64 / 19.0).collect();
        let k = knot_vector(&t, 6, 3, KnotRule::NurbsBook).unwrap();
        assert_eq!(k.len(), 10);
        let d = 20.0 / 3.0;
        for j in 1..=2 {
            let jd = j as f64 * d;
            let i = jd.floor() as usize;
            let a = jd - i as f64;
            assert!((k[3 + j] - ((1.0 - a) * t[i - 1] + a * t[i])).abs() < 1e-15);
        }
        assert!(k.windows(2).all(|w| w[0] <= w[1]));
        // Every knot span holds at least one parameter (Schoenberg-Whitney for the least squares).
        for s in 3..6 {
            assert!(t.iter().any(|&u| u >= k[s] && u <= k[s + 1]));
        }
    }

    #[test]
    fn refuses_impossible_sizes_and_names_round_trip() {
        let t = [0.0, 0.5, 1.0, 1.0];
        for rule in KnotRule::ALL {
            assert!(knot_vector(&t, 3, 3, rule).is_err());
            assert!(knot_vector(&t, 5, 3, rule).is_err());
            assert_eq!(rule.name().parse::<KnotRule>().unwrap(), rule);
        }
        assert!("9.69".parse::<KnotRule>().is_err());
    }
}
