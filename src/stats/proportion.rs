//! Intervals for a proportion k/n and for the difference of two: Wilson's score interval
//! (Wilson 1927; Newcombe 1998a, method 3) and Newcombe's hybrid score interval for p1 - p2
//! (Newcombe 1998b, method 10), the two that keep their coverage at the small counts and at the
//! 0% and 100% ends that claim counts reach.

/// The standard normal quantile for a two-sided 95% interval.
pub(crate) const Z95: f64 = 1.959_963_984_540_054;

/// Wilson's score interval for k successes in n trials (`(0, 1)` for n = 0).
pub(crate) fn wilson(k: usize, n: usize, z: f64) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let (k, n) = (k.min(n) as f64, n as f64);
    let p = k / n;
    let z2 = z * z;
    let centre = (p + z2 / (2.0 * n)) / (1.0 + z2 / n);
    let half = z / (1.0 + z2 / n) * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt();
    // The closed ends k = 0 and k = n are exact (no rounding below 0 or above 1).
    let lo = if k == 0.0 { 0.0 } else { (centre - half).max(0.0) };
    let hi = if k == n { 1.0 } else { (centre + half).min(1.0) };
    (lo, hi)
}

/// Newcombe's hybrid score interval for p1 - p2, p1 = k1/n1 and p2 = k2/n2 independent, from the
/// two Wilson intervals.
pub(crate) fn difference(k1: usize, n1: usize, k2: usize, n2: usize, z: f64) -> (f64, f64) {
    let p = |k: usize, n: usize| if n == 0 { 0.5 } else { k.min(n) as f64 / n as f64 };
    let (p1, p2) = (p(k1, n1), p(k2, n2));
    let ((l1, u1), (l2, u2)) = (wilson(k1, n1, z), wilson(k2, n2, z));
    let d = p1 - p2;
    (
        d - ((p1 - l1).powi(2) + (u2 - p2).powi(2)).sqrt(),
        d + ((u1 - p1).powi(2) + (p2 - l2).powi(2)).sqrt(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_ends_are_the_closed_forms() {
        // k = 0: (0, z^2 / (n + z^2)); k = n: (n / (n + z^2), 1).
        let z2 = Z95 * Z95;
        let (lo, hi) = wilson(0, 10, Z95);
        assert_eq!(lo, 0.0);
        assert!((hi - z2 / (10.0 + z2)).abs() < 1e-15);
        let (lo, hi) = wilson(10, 10, Z95);
        assert!((lo - 10.0 / (10.0 + z2)).abs() < 1e-15);
        assert_eq!(hi, 1.0);
        assert_eq!(wilson(0, 0, Z95), (0.0, 1.0));
    }

    #[test]
    fn wilson_and_newcombe_match_the_published_examples() {
        // Newcombe (1998a), Table I: 81/263 -> 0.2553 to 0.3662 (method 3).
        let (lo, hi) = wilson(81, 263, Z95);
        assert!((lo - 0.2553).abs() < 5e-5 && (hi - 0.3662).abs() < 5e-5, "{lo} {hi}");
        // Newcombe (1998b), Table II, example (a): 56/70 - 48/80 -> 0.0524 to 0.3339 (method 10).
        let (lo, hi) = difference(56, 70, 48, 80, Z95);
        assert!((lo - 0.0524).abs() < 5e-5 && (hi - 0.3339).abs() < 5e-5, "{lo} {hi}");
        // Examples (b) 9/10 - 3/10 -> 0.1705 to 0.8090 and (d) 5/56 - 0/29 -> -0.0381 to 0.1926.
        let (lo, hi) = difference(9, 10, 3, 10, Z95);
        assert!((lo - 0.1705).abs() < 5e-5 && (hi - 0.8090).abs() < 5e-5, "{lo} {hi}");
        let (lo, hi) = difference(5, 56, 0, 29, Z95);
        assert!((lo + 0.0381).abs() < 5e-5 && (hi - 0.1926).abs() < 5e-5, "{lo} {hi}");
    }
}
