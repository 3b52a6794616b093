//! Clamped knot vectors from parameters.
//!
//! The thesis names the averaging method (Eq. 2.9-2.11), defined when there are as many control
//! points as parameters. A control net smaller than the grid needs The NURBS Book's generalisation,
//! eq. 9.68-9.69: d = (m + 1) / (n - p + 1); for j = 1..n-p, i = int(j d), a = j d - i,
//! u_{p+j} = (1 - a) t_{i-1} + a t_i. (SPEC 3 says this reduces to averaging when the sizes match;
//! it does not, so the two cases are kept apart: averaging when n_ctrl == parameters, 9.69 below.)

/// Clamped knot vector of degree `p` for `n_ctrl` control points fitted to `params` (non-decreasing,
/// first 0, last 1). Errors when n_ctrl > params.len() or n_ctrl < p + 1.
pub fn knot_vector(params: &[f64], n_ctrl: usize, p: usize) -> Result<Vec<f64>, String> {
    let m1 = params.len();
    if n_ctrl < p + 1 {
        return Err(format!("{n_ctrl} control points are too few for degree {p} (at least {})", p + 1));
    }
    if n_ctrl > m1 {
        return Err(format!("{n_ctrl} control points exceed the {m1} data parameters"));
    }
    let n = n_ctrl - 1;
    let mut k = vec![0.0; n_ctrl + p + 1];
    for x in k.iter_mut().skip(n + 1) {
        *x = 1.0;
    }
    if n_ctrl == m1 {
        // Eq. 2.10: T_{j+p} = (1/p) sum_{i=j}^{j+p-1} t_i, j = 1..n-p.
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
    fn averaging_when_sizes_match() {
        let t = [0.0, 0.1, 0.3, 0.6, 0.7, 1.0];
        let k = knot_vector(&t, 6, 3).unwrap();
        let want = [0.0, 0.0, 0.0, 0.0, (0.1 + 0.3 + 0.6) / 3.0, (0.3 + 0.6 + 0.7) / 3.0, 1.0, 1.0, 1.0, 1.0];
        for (a, b) in k.iter().zip(want) {
            assert!((a - b).abs() < 1e-15, "{k:?}");
        }
    }

    #[test]
    fn nurbs_book_9_69_for_smaller_nets() {
        // m + 1 = 20 uniform parameters, n + 1 = 6: d = 20/3.
        let t: Vec<f64> = (0..20).map(|k| k as f64 / 19.0).collect();
        let k = knot_vector(&t, 6, 3).unwrap();
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
    fn refuses_impossible_sizes() {
        let t = [0.0, 0.5, 1.0, 1.0];
        assert!(knot_vector(&t, 3, 3).is_err());
        assert!(knot_vector(&t, 5, 3).is_err());
    }
}
