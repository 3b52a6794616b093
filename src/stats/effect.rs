//! Vargha-Delaney A12 (Vargha & Delaney 2000): the probability that a value drawn from one sample
//! is larger than one drawn from the other, ties counting half. [`a12`] is the textbook P(X > Y) +
//! 0.5 P(X = Y); for minimisation `compare` reports [`a12_x_better`] = P(X < Y) + 0.5 P(X = Y) =
//! 1 - A12, so a value above 0.5 means x tends to be better (smaller).

/// A12 = P(X > Y) + 0.5 P(X = Y) (NaN when a sample is empty).
pub(crate) fn a12(x: &[f64], y: &[f64]) -> f64 {
    if x.is_empty() || y.is_empty() {
        return f64::NAN;
    }
    let mut s = 0.0;
    for a in x {
        for b in y {
            s += if a > b {
                1.0
            } else if a == b {
                0.5
            } else {
                0.0
            };
        }
    }
    s / (x.len() * y.len()) as f64
}

/// A12 by direction for minimisation: P(X < Y) + 0.5 P(X = Y), the probability that a run of x
/// ends below (better than) a run of y, ties counting half; > 0.5 means x better.
pub(crate) fn a12_x_better(x: &[f64], y: &[f64]) -> f64 {
    a12(y, x)
}

/// Vargha & Delaney's magnitude of |A12 - 0.5|: thresholds 0.56, 0.64, 0.71.
pub(crate) fn magnitude(a: f64) -> &'static str {
    let d = (a - 0.5).abs() + 0.5;
    if d < 0.56 {
        "negligible"
    } else if d < 0.64 {
        "small"
    } else if d < 0.71 {
        "medium"
    } else {
        "large"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hand_cases() {
        assert_eq!(a12(&[3.0, 4.0], &[1.0, 2.0]), 1.0);
        assert_eq!(a12(&[1.0, 2.0], &[1.0, 2.0]), 0.5);
        // x = (1, 3), y = (2, 2): pairs 1>2 no, 1>2 no, 3>2, 3>2 -> 2/4.
        assert_eq!(a12(&[1.0, 3.0], &[2.0, 2.0]), 0.5);
        assert_eq!(a12(&[2.0], &[1.0, 2.0, 3.0]), 0.5);
        assert_eq!(magnitude(0.2), "large");
        assert_eq!(magnitude(1.0), "large");
        assert_eq!(magnitude(0.53), "negligible");
    }

    /// Minimisation: x = (1, 2) always below y = (3, 4), so x is better: a12_x_better = 1 while
    /// the textbook A12 = P(X > Y) = 0; a tie counts half either way.
    #[test]
    fn direction_for_minimisation() {
        let (x, y) = ([1.0, 2.0], [3.0, 4.0]);
        assert_eq!((a12_x_better(&x, &y), a12(&x, &y)), (1.0, 0.0));
        assert_eq!(a12_x_better(&y, &x), 0.0);
        // x = (1, 3), y = (2, 3): P(X < Y) = 2/4 (1<2, 1<3), ties 1/4 (3=3): 0.5 + 0.125.
        assert_eq!(a12_x_better(&[1.0, 3.0], &[2.0, 3.0]), 0.625);
        assert!(a12_x_better(&[], &[1.0]).is_nan());
    }
}
