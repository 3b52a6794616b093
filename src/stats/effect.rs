//! Vargha-Delaney A12: the probability that a value drawn from x is larger than one drawn from y,
//! ties counting half. For minimisation, A12 < 0.5 means x tends to be better (smaller).

/// A12 = P(X > Y) + 0.5 P(X = Y).
pub fn a12(x: &[f64], y: &[f64]) -> f64 {
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

/// Vargha & Delaney's magnitude of |A12 - 0.5|: thresholds 0.56, 0.64, 0.71.
pub fn magnitude(a: f64) -> &'static str {
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
        assert_eq!(magnitude(0.53), "negligible");
    }
}
