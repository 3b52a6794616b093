//! Least-squares control nets (thesis Eq. 5.5-5.6) and evaluation at the data parameters (Eq. 5.12).
//!
//! With D the nx x ny grid of one coordinate, Nu (nx x cn_x) and Nv (ny x cn_y) the basis matrices
//! at the data parameters, the control net is P = (Nu^T Nu)^-1 Nu^T D Nv (Nv^T Nv)^-1 (the
//! orientation in which the thesis' shapes agree), solved with two Cholesky factorisations, never an
//! explicit inverse. The fitted grid is D^G = Nu P Nv^T, computed as Nu (P Nv^T) so that a row of
//! Nu that is a unit vector (u = 0 or 1 on a clamped knot vector) copies a row of P Nv^T exactly.

use crate::geom::Point3;
use nalgebra::{Cholesky, DMatrix};

/// Least-squares control net of one view: `cn_x x cn_y` points, row-major.
pub(crate) fn least_squares_net(
    view: &[Point3],
    nu: &DMatrix<f64>,
    nv: &DMatrix<f64>,
) -> Result<Vec<Point3>, String> {
    let (nx, cn_x) = nu.shape();
    let (ny, cn_y) = nv.shape();
    let a = Cholesky::new(nu.transpose() * nu).ok_or(
        "the u-direction normal equations are singular (a knot span holds no data parameter)",
    )?;
    let b = Cholesky::new(nv.transpose() * nv).ok_or(
        "the v-direction normal equations are singular (a knot span holds no data parameter)",
    )?;
    let mut net = vec![[0.0; 3]; cn_x * cn_y];
    for c in 0..3 {
        let d = DMatrix::from_fn(nx, ny, |i, j| view[i * ny + j][c]);
        let m = nu.transpose() * d * nv; // cn_x x cn_y
        let x = a.solve(&m); // (Nu^T Nu)^-1 M
        let p = b.solve(&x.transpose()).transpose(); // X (Nv^T Nv)^-1, Nv^T Nv symmetric
        for ai in 0..cn_x {
            for bj in 0..cn_y {
                net[ai * cn_y + bj][c] = p[(ai, bj)];
            }
        }
    }
    Ok(net)
}

/// Penalised least squares (beyond the thesis; `[fit] fairness`): the net minimising
/// ||Nu P Nv^T - D||^2 + lambda s (||Du P||^2 + ||P Dv^T||^2) per coordinate, with Du, Dv the second
/// differences of the control net along u and v and s = (nx ny) / (cn_x cn_y) (the mean data
/// weight of a control point, so that lambda means the same for every net size). Solved on the
/// Kronecker form of the normal equations (at most a few hundred unknowns) by Cholesky. With
/// lambda = 0 it is Eq. 5.5-5.6 up to rounding; use [`least_squares_net`] then.
pub(crate) fn faired_net(
    view: &[Point3],
    nu: &DMatrix<f64>,
    nv: &DMatrix<f64>,
    lambda: f64,
) -> Result<Vec<Point3>, String> {
    let (nx, cn_x) = nu.shape();
    let (ny, cn_y) = nv.shape();
    let uu = nu.transpose() * nu;
    let vv = nv.transpose() * nv;
    let second = |n: usize| -> DMatrix<f64> {
        let mut d = DMatrix::zeros(n.saturating_sub(2), n);
        for r in 0..n.saturating_sub(2) {
            d[(r, r)] = 1.0;
            d[(r, r + 1)] = -2.0;
            d[(r, r + 2)] = 1.0;
        }
        d.transpose() * d
    };
    let (du, dv) = (second(cn_x), second(cn_y));
    let w = lambda * (nx * ny) as f64 / (cn_x * cn_y) as f64;
    // Unknown index a + cn_x b (column-major vec of the cn_x x cn_y net).
    let n = cn_x * cn_y;
    let h = DMatrix::from_fn(n, n, |r, c| {
        let (a, b, a2, b2) = (r % cn_x, r / cn_x, c % cn_x, c / cn_x);
        let mut x = vv[(b, b2)] * uu[(a, a2)];
        if b == b2 {
            x += w * du[(a, a2)];
        }
        if a == a2 {
            x += w * dv[(b, b2)];
        }
        x
    });
    let chol = Cholesky::new(h).ok_or("the penalised normal equations are singular")?;
    let mut net = vec![[0.0; 3]; n];
    for c in 0..3 {
        let d = DMatrix::from_fn(nx, ny, |i, j| view[i * ny + j][c]);
        let m = nu.transpose() * d * nv; // cn_x x cn_y
        let rhs = nalgebra::DVector::from_fn(n, |r, _| m[(r % cn_x, r / cn_x)]);
        let p = chol.solve(&rhs);
        for r in 0..n {
            net[(r % cn_x) * cn_y + r / cn_x][c] = p[r];
        }
    }
    Ok(net)
}

/// The corner rule: the four corner control points := the four corner data points.
pub(crate) fn pin_corners(
    net: &mut [Point3],
    cn_x: usize,
    cn_y: usize,
    view: &[Point3],
    nx: usize,
    ny: usize,
) {
    net[0] = view[0];
    net[cn_y - 1] = view[ny - 1];
    net[(cn_x - 1) * cn_y] = view[(nx - 1) * ny];
    net[cn_x * cn_y - 1] = view[nx * ny - 1];
}

/// D^G = Nu (P Nv^T): the surface at every data parameter, row-major.
pub(crate) fn fitted_grid(net: &[Point3], nu: &DMatrix<f64>, nv: &DMatrix<f64>) -> Vec<Point3> {
    let (nx, cn_x) = nu.shape();
    let (ny, cn_y) = nv.shape();
    // Q = P Nv^T: cn_x x ny.
    let mut q = vec![[0.0; 3]; cn_x * ny];
    for a in 0..cn_x {
        for j in 0..ny {
            let mut s = [0.0; 3];
            for b in 0..cn_y {
                let w = nv[(j, b)];
                if w != 0.0 {
                    let p = net[a * cn_y + b];
                    for c in 0..3 {
                        s[c] += w * p[c];
                    }
                }
            }
            q[a * ny + j] = s;
        }
    }
    let mut out = vec![[0.0; 3]; nx * ny];
    for i in 0..nx {
        for j in 0..ny {
            let mut s = [0.0; 3];
            for a in 0..cn_x {
                let w = nu[(i, a)];
                if w != 0.0 {
                    for c in 0..3 {
                        s[c] += w * q[a * ny + j][c];
                    }
                }
            }
            out[i * ny + j] = s;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::{
        basis::basis_matrix,
        knots::{knot_vector, KnotRule},
        surface::BSplineSurface,
    };
    use super::*;
    use rand::{Rng, SeedableRng};

    /// A grid sampled from a known cubic B-spline surface is recovered to ~1e-10.
    #[test]
    fn exact_recovery_of_a_known_spline() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (nx, ny, cn_x, cn_y) = (20, 17, 9, 7);
        let mut us: Vec<f64> = (0..nx).map(|_| rng.gen()).collect();
        let mut vs: Vec<f64> = (0..ny).map(|_| rng.gen()).collect();
        us.sort_by(|a, b| a.total_cmp(b));
        vs.sort_by(|a, b| a.total_cmp(b));
        us[0] = 0.0;
        vs[0] = 0.0;
        us[nx - 1] = 1.0;
        vs[ny - 1] = 1.0;
        let ku = knot_vector(&us, cn_x, 3, KnotRule::NurbsBook).unwrap();
        let kv = knot_vector(&vs, cn_y, 3, KnotRule::NurbsBook).unwrap();
        let control: Vec<Point3> =
            (0..cn_x * cn_y).map(|_| [rng.gen(), rng.gen(), rng.gen()]).collect();
        let surf = BSplineSurface {
            p: 3,
            q: 3,
            knots_u: ku.clone(),
            knots_v: kv.clone(),
            cn_x,
            cn_y,
            control: control.clone(),
        };
        let grid = surf.eval_grid(&us, &vs);
        let nu = basis_matrix(&us, &ku, 3, cn_x);
        let nv = basis_matrix(&vs, &kv, 3, cn_y);
        let mut net = least_squares_net(&grid, &nu, &nv).unwrap();
        for (a, b) in net.iter().zip(&control) {
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() < 1e-10, "{a:?} vs {b:?}");
            }
        }
        // The clamped surface interpolates its corner control points, so pinning changes nothing.
        let before = net.clone();
        pin_corners(&mut net, cn_x, cn_y, &grid, nx, ny);
        for (a, b) in net.iter().zip(&before) {
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() < 1e-10);
            }
        }
        let fitted = fitted_grid(&net, &nu, &nv);
        for (a, b) in fitted.iter().zip(&grid) {
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() < 1e-10);
            }
        }
        // The penalised fit with lambda = 0 is the plain least squares; a large lambda flattens the
        // net towards a bilinear one (second differences vanish) and never reproduces the wiggles.
        let faired = faired_net(&grid, &nu, &nv, 0.0).unwrap();
        for (a, b) in faired.iter().zip(&control) {
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() < 1e-8, "{a:?} vs {b:?}");
            }
        }
        let flat = faired_net(&grid, &nu, &nv, 1e9).unwrap();
        for a in 0..cn_x {
            for b in 1..cn_y - 1 {
                for c in 0..3 {
                    let d2 = flat[a * cn_y + b - 1][c] - 2.0 * flat[a * cn_y + b][c]
                        + flat[a * cn_y + b + 1][c];
                    assert!(d2.abs() < 1e-6, "second difference {d2}");
                }
            }
        }
        // The evaluator of the surface agrees with the matrix form.
        let again = BSplineSurface { control: net.clone(), ..surf }.eval_grid(&us, &vs);
        for (a, b) in again.iter().zip(&fitted) {
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() < 1e-12);
            }
        }
    }
}
