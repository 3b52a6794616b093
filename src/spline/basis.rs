//! B-spline basis functions by the Cox-de Boor recursion (thesis Eq. 2.2-2.3; The NURBS Book
//! A2.1 FindSpan and A2.2 BasisFuns), dense basis matrices and the sparse form Chapter 6 uses.

use nalgebra::DMatrix;

/// Knot span index of `u` for `n_ctrl` control points of degree `p` (A2.1); `u = 1` (the last knot)
/// belongs to the last non-empty span, so that the clamped curve reaches its last control point.
pub(crate) fn find_span(n_ctrl: usize, p: usize, u: f64, knots: &[f64]) -> usize {
    let n = n_ctrl - 1;
    if u >= knots[n + 1] {
        return n;
    }
    if u <= knots[p] {
        return p;
    }
    let (mut low, mut high) = (p, n + 1);
    let mut mid = (low + high) / 2;
    while u < knots[mid] || u >= knots[mid + 1] {
        if u < knots[mid] {
            high = mid;
        } else {
            low = mid;
        }
        mid = (low + high) / 2;
    }
    mid
}

/// The p + 1 non-zero basis functions N_{span-p..span, p}(u) (A2.2).
pub(crate) fn basis_funs(span: usize, u: f64, p: usize, knots: &[f64]) -> Vec<f64> {
    let mut n = vec![0.0; p + 1];
    let mut left = vec![0.0; p + 1];
    let mut right = vec![0.0; p + 1];
    basis_funs_into(
        p,
        |j| u - knots[span + 1 - j],
        |j| knots[span + j] - u,
        (&mut n, &mut left, &mut right),
    );
    n
}

/// A2.2's recurrence into `n` (the p + 1 values) with the scratch `left`, `right` (each at least
/// p + 1 long), from the knot distances `below(j)` = u - t_{span+1-j} and `above(j)` =
/// t_{span+j} - u, j = 1..p (no allocation).
pub(crate) fn basis_funs_into(
    p: usize,
    below: impl Fn(usize) -> f64,
    above: impl Fn(usize) -> f64,
    (n, left, right): (&mut [f64], &mut [f64], &mut [f64]),
) {
    n[0] = 1.0;
    for j in 1..=p {
        left[j] = below(j);
        right[j] = above(j);
        let mut saved = 0.0;
        for r in 0..j {
            let temp = n[r] / (right[r + 1] + left[j - r]);
            n[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        n[j] = saved;
    }
}

/// Cubic basis in sparse form: for each parameter, the index of the first of its four non-zero
/// basis functions and their values.
#[derive(Debug, Clone, PartialEq)]
pub struct SparseBasis {
    pub first: Vec<usize>,
    pub w: Vec<[f64; 4]>,
}

impl SparseBasis {
    /// Cubic basis at each parameter.
    pub fn cubic(params: &[f64], knots: &[f64], n_ctrl: usize) -> SparseBasis {
        let (mut first, mut w) =
            (Vec::with_capacity(params.len()), Vec::with_capacity(params.len()));
        for &u in params {
            let span = find_span(n_ctrl, 3, u, knots);
            let b = basis_funs(span, u, 3, knots);
            first.push(span - 3);
            w.push([b[0], b[1], b[2], b[3]]);
        }
        SparseBasis { first, w }
    }

    /// The dense matrix (rows: parameters, columns: control points).
    pub fn dense(&self, n_ctrl: usize) -> DMatrix<f64> {
        let mut m = DMatrix::zeros(self.first.len(), n_ctrl);
        for (r, (&f, w)) in self.first.iter().zip(&self.w).enumerate() {
            for k in 0..4 {
                m[(r, f + k)] = w[k];
            }
        }
        m
    }
}

/// Dense basis matrix of degree `p` (rows: parameters, columns: the `n_ctrl` basis functions).
pub(crate) fn basis_matrix(params: &[f64], knots: &[f64], p: usize, n_ctrl: usize) -> DMatrix<f64> {
    let mut m = DMatrix::zeros(params.len(), n_ctrl);
    for (r, &u) in params.iter().enumerate() {
        let span = find_span(n_ctrl, p, u, knots);
        for (k, v) in basis_funs(span, u, p, knots).into_iter().enumerate() {
            m[(r, span - p + k)] = v;
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn knots() -> Vec<f64> {
        vec![0.0, 0.0, 0.0, 0.0, 0.15, 0.4, 0.45, 0.8, 1.0, 1.0, 1.0, 1.0]
    }

    #[test]
    fn partition_of_unity_and_non_negativity() {
        let k = knots();
        for s in 0..=1000 {
            let u = s as f64 / 1000.0;
            let span = find_span(8, 3, u, &k);
            let b = basis_funs(span, u, 3, &k);
            assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-14, "u = {u}");
            assert!(b.iter().all(|&x| x >= -1e-15));
        }
    }

    #[test]
    fn clamped_ends_are_exact_unit_vectors() {
        let k = knots();
        let m = basis_matrix(&[0.0, 1.0], &k, 3, 8);
        for c in 0..8 {
            assert_eq!(m[(0, c)], if c == 0 { 1.0 } else { 0.0 });
            assert_eq!(m[(1, c)], if c == 7 { 1.0 } else { 0.0 });
        }
    }

    #[test]
    fn cox_de_boor_recursion_by_definition() {
        // Eq. 2.2-2.3 evaluated literally, against A2.2.
        fn n(i: usize, p: usize, u: f64, t: &[f64]) -> f64 {
            if p == 0 {
                return if t[i] <= u && u < t[i + 1] { 1.0 } else { 0.0 };
            }
            let a = if t[i + p] > t[i] {
                (u - t[i]) / (t[i + p] - t[i]) * n(i, p - 1, u, t)
            } else {
                0.0
            };
            let b = if t[i + p + 1] > t[i + 1] {
                (t[i + p + 1] - u) / (t[i + p + 1] - t[i + 1]) * n(i + 1, p - 1, u, t)
            } else {
                0.0
            };
            a + b
        }
        let k = knots();
        for s in 0..100 {
            let u = s as f64 / 100.0;
            let m = basis_matrix(&[u], &k, 3, 8);
            for i in 0..8 {
                assert!((m[(0, i)] - n(i, 3, u, &k)).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn sparse_equals_dense() {
        let k = knots();
        let params: Vec<f64> = (0..=20).map(|s| s as f64 / 20.0).collect();
        assert_eq!(SparseBasis::cubic(&params, &k, 8).dense(8), basis_matrix(&params, &k, 3, 8));
    }
}
