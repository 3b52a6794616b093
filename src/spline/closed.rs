//! B-spline surfaces closed (periodic) in u and open (clamped) in v, fitted to ring-organised data
//! (seed 004, Chaurasiya & Agarwal 2013: a cylinder). Pure: no I/O.
//!
//! Around (u): the closed uniform basis of the paper's Eq. 5, N_{i,k}(u) = N_{0,k}((u - i) mod N)
//! with integer knots and u in [0, N), N control points, order k (degree k - 1). Computed with the
//! open code's A2.2 on the knots t_j = j - (k - 1): the functions non-zero on span [s, s + 1) are
//! the extended B_s..B_{s+k-1}, B_j supported on [j - k + 1, j + 1), i.e. Eq. 5's N_i with
//! i = (j - k + 1) mod N.
//! Up (v): the clamped knot vector of `knots::knot_vector` for the rows of the net, v in [0, 1].
//!
//! The analytical method (section II.C): each data point gets (u, v) from chord lengths, Eq. 8:
//! u along its ring (closed: the closing chord counts, u_max = N), v along the rings (the chord
//! between consecutive ring centroids); the net solves the least squares [C][B] = [D] by SVD
//! (Eq. 11-13). The GA's problem ([`RingNetProblem`]) searches the (x, y) of every column of the
//! net (shared by its rows: the paper's string length is 2 x bits per control point) in a box
//! around the analytical net, with the analytical z fixed; fitness = RMS distance of the data to
//! the surface at their parameters (Eq. 9 as an RMS, the unit of the paper's Tables II and III).

use super::basis::{basis_funs, find_span};
use super::knots::{knot_vector, KnotRule};
use super::SplineError;
use crate::geom::Point3;
use crate::optim::Problem;
use nalgebra::DMatrix;

/// The `order` non-zero closed basis functions at u (taken mod n): (first control index, values);
/// the l-th value belongs to control point (first + l) mod n.
pub fn periodic_basis(n: usize, order: usize, u: f64) -> (usize, Vec<f64>) {
    let p = order - 1;
    let nf = n as f64;
    let mut w = u.rem_euclid(nf);
    if w >= nf {
        w = 0.0;
    }
    let s = (w.floor() as usize).min(n - 1);
    // Extended uniform knots t_j = j - p around span s: only t_{s+1..s+2p} are read by A2.2.
    let knots: Vec<f64> = (0..s + 2 * p + 2).map(|j| j as f64 - p as f64).collect();
    let vals = basis_funs(s + p, w, p, &knots);
    ((s + n - p % n) % n, vals)
}

/// The surface: `n_around` x `rows` control points, P(i around, j up) at `i * rows + j`.
#[derive(Debug, Clone, PartialEq)]
pub struct ClosedSurface {
    pub order_around: usize,
    pub order_up: usize,
    pub n_around: usize,
    pub rows: usize,
    pub knots_v: Vec<f64>,
    pub control: Vec<Point3>,
}

impl ClosedSurface {
    pub fn eval(&self, u: f64, v: f64) -> Point3 {
        let (first, bu) = periodic_basis(self.n_around, self.order_around, u);
        let q = self.order_up - 1;
        let sv = find_span(self.rows, q, v, &self.knots_v);
        let bv = basis_funs(sv, v, q, &self.knots_v);
        let mut s = [0.0; 3];
        for (l, a) in bu.iter().enumerate() {
            let i = (first + l) % self.n_around;
            for (m, b) in bv.iter().enumerate() {
                let c = self.control[i * self.rows + sv - q + m];
                for x in 0..3 {
                    s[x] += a * b * c[x];
                }
            }
        }
        s
    }
}

pub use crate::data::cylinder::RingData;

/// The shape of a fit: orders and net size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosedNetShape {
    pub order_around: usize,
    pub order_up: usize,
    pub n_around: usize,
    pub rows: usize,
}

impl ClosedNetShape {
    pub fn check(&self, data: &RingData) -> Result<(), SplineError> {
        if self.order_around < 2 || self.n_around < self.order_around {
            return Err(SplineError::ControlNet(format!("{} control points around are too few for order {} (at least the order, and order >= 2)", self.n_around, self.order_around)));
        }
        if self.order_up < 2 || self.rows < self.order_up {
            return Err(SplineError::ControlNet(format!(
                "{} rows are too few for order {} up (at least the order, and order >= 2)",
                self.rows, self.order_up
            )));
        }
        if data.rings.len() < self.rows {
            return Err(SplineError::Grid(format!(
                "{} rings for {} rows of control points",
                data.rings.len(),
                self.rows
            )));
        }
        if let Some(k) = data.rings.iter().position(|r| r.len() < self.n_around) {
            return Err(SplineError::Grid(format!(
                "ring {k} has {} points for {} control points around",
                data.rings[k].len(),
                self.n_around
            )));
        }
        Ok(())
    }
}

/// The analytical fit: the surface, each point's (u, v), and its RMS error.
#[derive(Debug, Clone)]
pub struct ClosedFit {
    pub surface: ClosedSurface,
    pub uv: Vec<(f64, f64)>,
    pub rms: f64,
}

/// Chord-length parameters and the SVD least-squares net (the paper's analytical method).
pub fn fit_closed(data: &RingData, shape: ClosedNetShape) -> Result<ClosedFit, SplineError> {
    shape.check(data)?;
    let vs = data.row_parameters();
    let knots_v = knot_vector(&vs, shape.rows, shape.order_up - 1, KnotRule::NurbsBook)
        .map_err(SplineError::ControlNet)?;
    let mut uv = Vec::with_capacity(data.n_points());
    for (ring, &v) in data.rings.iter().zip(&vs) {
        uv.extend(RingData::ring_parameters(ring, shape.n_around).into_iter().map(|u| (u, v)));
    }
    let points: Vec<Point3> = data.points().copied().collect();
    fit_closed_at(&points, uv, shape, knots_v)
}

/// The SVD least-squares net (Eq. 11-13, minimum-norm if rank deficient) for points with given
/// parameters and knots up.
pub fn fit_closed_at(
    points: &[Point3],
    uv: Vec<(f64, f64)>,
    shape: ClosedNetShape,
    knots_v: Vec<f64>,
) -> Result<ClosedFit, SplineError> {
    if uv.len() != points.len() || points.is_empty() {
        return Err(SplineError::Grid(format!(
            "{} parameters for {} points",
            uv.len(),
            points.len()
        )));
    }
    let (n, q) = (points.len(), shape.order_up - 1);
    let ncols = shape.n_around * shape.rows;
    let mut c = DMatrix::zeros(n, ncols);
    for (r, &(u, v)) in uv.iter().enumerate() {
        let (first, bu) = periodic_basis(shape.n_around, shape.order_around, u);
        let sv = find_span(shape.rows, q, v, &knots_v);
        let bv = basis_funs(sv, v, q, &knots_v);
        for (l, a) in bu.iter().enumerate() {
            let i = (first + l) % shape.n_around;
            for (m, b) in bv.iter().enumerate() {
                c[(r, i * shape.rows + sv - q + m)] += a * b;
            }
        }
    }
    let d = DMatrix::from_fn(n, 3, |r, x| points[r][x]);
    let b = c
        .clone()
        .svd(true, true)
        .solve(&d, 1e-12)
        .map_err(|e| SplineError::Singular(e.to_string()))?;
    let resid = &c * &b - &d;
    let rms = (resid.iter().map(|e| e * e).sum::<f64>() / n as f64).sqrt();
    let control = (0..ncols).map(|k| [b[(k, 0)], b[(k, 1)], b[(k, 2)]]).collect();
    let surface = ClosedSurface {
        order_around: shape.order_around,
        order_up: shape.order_up,
        n_around: shape.n_around,
        rows: shape.rows,
        knots_v,
        control,
    };
    Ok(ClosedFit { surface, uv, rms })
}

/// The GA's problem: decision vector (x_0, y_0, ..., x_{N-1}, y_{N-1}), the (x, y) of every column
/// of the net (all its rows share them), z of the net fixed at the analytical fit's; box: the
/// analytical column's (x, y) (averaged over its rows) +- `search_range`; fitness = RMS error.
pub struct RingNetProblem {
    fit: ClosedFit,
    /// Per point: the `order_around` non-zero basis values and the positions 2 i of their
    /// control columns' x in the decision vector (wrapped around once, here).
    w: Vec<f64>,
    at: Vec<usize>,
    target: Vec<[f64; 2]>,
    /// Sum over the points of the squared z error (fixed by the analytical z of the net).
    z_sse: f64,
    x0: Vec<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
}

impl RingNetProblem {
    pub fn new(data: &RingData, fit: ClosedFit, search_range: f64) -> RingNetProblem {
        let s = &fit.surface;
        let (n, rows, k) = (s.n_around, s.rows, s.order_around);
        let x0: Vec<f64> = (0..n)
            .flat_map(|i| {
                let col = &s.control[i * rows..(i + 1) * rows];
                let m = rows as f64;
                [
                    col.iter().map(|p| p[0]).sum::<f64>() / m,
                    col.iter().map(|p| p[1]).sum::<f64>() / m,
                ]
            })
            .collect();
        let (mut at, mut w, mut target, mut z_sse) = (Vec::new(), Vec::new(), Vec::new(), 0.0);
        for (p, &(u, v)) in data.points().zip(&fit.uv) {
            let (f, bu) = periodic_basis(n, k, u);
            at.extend((0..k).map(|l| 2 * ((f + l) % n)));
            w.extend_from_slice(&bu);
            target.push([p[0], p[1]]);
            z_sse += (s.eval(u, v)[2] - p[2]).powi(2);
        }
        let lo = x0.iter().map(|v| v - search_range).collect();
        let hi = x0.iter().map(|v| v + search_range).collect();
        RingNetProblem { fit, w, at, target, z_sse, x0, lo, hi }
    }

    pub fn n_points(&self) -> usize {
        self.target.len()
    }

    /// The analytical fit the problem was built on.
    pub fn analytical(&self) -> &ClosedFit {
        &self.fit
    }

    /// The surface of a decision vector.
    pub fn surface(&self, x: &[f64]) -> ClosedSurface {
        let mut s = self.fit.surface.clone();
        for (k, c) in s.control.iter_mut().enumerate() {
            let i = k / s.rows;
            c[0] = x[2 * i];
            c[1] = x[2 * i + 1];
        }
        s
    }
}

impl Problem for RingNetProblem {
    fn dim(&self) -> usize {
        self.x0.len()
    }
    fn initial_point(&self) -> &[f64] {
        &self.x0
    }
    fn bounds(&self) -> (&[f64], &[f64]) {
        (&self.lo, &self.hi)
    }
    fn fitness(&self, x: &[f64]) -> f64 {
        let k = self.fit.surface.order_around;
        let mut sse = self.z_sse;
        for ((t, w), at) in
            self.target.iter().zip(self.w.chunks_exact(k)).zip(self.at.chunks_exact(k))
        {
            let (mut px, mut py) = (0.0, 0.0);
            for (a, &j) in w.iter().zip(at) {
                px += a * x[j];
                py += a * x[j + 1];
            }
            sse += (px - t[0]).powi(2) + (py - t[1]).powi(2);
        }
        (sse / self.target.len() as f64).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn periodic_basis_partition_of_unity_and_shift_invariance() {
        for (n, k) in [(5, 2), (5, 3), (7, 3), (8, 4), (3, 3)] {
            for s in 0..=400 {
                let u = s as f64 * n as f64 / 400.0;
                let (first, b) = periodic_basis(n, k, u);
                assert_eq!(b.len(), k);
                assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-14, "n {n} k {k} u {u}");
                assert!(b.iter().all(|&x| x >= -1e-15));
                // Eq. 5: N_i(u) = N_0((u - i) mod n): shifting u by one shifts the indices by one.
                let (f2, b2) = periodic_basis(n, k, u + 1.0);
                assert_eq!(f2, (first + 1) % n);
                for (a, c) in b.iter().zip(&b2) {
                    assert!((a - c).abs() < 1e-12);
                }
            }
        }
    }

    #[test]
    fn periodic_quadratic_closed_form() {
        // Uniform quadratic B-spline on span [s, s+1), t = u - s: (1-t)^2/2, (1+2t-2t^2)/2, t^2/2.
        for s in 0..200 {
            let u = 2.0 + s as f64 / 200.0;
            let t = u - 2.0;
            let (first, b) = periodic_basis(6, 3, u);
            assert_eq!(first, 0);
            let want =
                [(1.0 - t) * (1.0 - t) / 2.0, (1.0 + 2.0 * t - 2.0 * t * t) / 2.0, t * t / 2.0];
            for (a, w) in b.iter().zip(want) {
                assert!((a - w).abs() < 1e-14);
            }
        }
        // Closed: u = n wraps to u = 0.
        assert_eq!(periodic_basis(6, 3, 6.0), periodic_basis(6, 3, 0.0));
    }

    #[test]
    fn exact_recovery_of_a_known_closed_surface() {
        // A known closed surface sampled at random (u, v): the fit at those parameters recovers
        // its net and reproduces its samples.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for (n, k, rows, q) in [(7, 3, 2, 2), (9, 4, 4, 3), (5, 2, 3, 2)] {
            let knots_v = knot_vector(
                &(0..20).map(|s| s as f64 / 19.0).collect::<Vec<_>>(),
                rows,
                q - 1,
                KnotRule::NurbsBook,
            )
            .unwrap();
            let control: Vec<Point3> =
                (0..n * rows).map(|_| [rng.gen(), rng.gen(), rng.gen()]).collect();
            let surf = ClosedSurface {
                order_around: k,
                order_up: q,
                n_around: n,
                rows,
                knots_v: knots_v.clone(),
                control: control.clone(),
            };
            let uv: Vec<(f64, f64)> =
                (0..600).map(|_| (rng.gen::<f64>() * n as f64, rng.gen::<f64>())).collect();
            let pts: Vec<Point3> = uv.iter().map(|&(u, v)| surf.eval(u, v)).collect();
            let fit = fit_closed_at(
                &pts,
                uv,
                ClosedNetShape { order_around: k, order_up: q, n_around: n, rows },
                knots_v,
            )
            .unwrap();
            assert!(fit.rms < 1e-12, "{}", fit.rms);
            for (a, b) in fit.surface.control.iter().zip(&control) {
                for c in 0..3 {
                    assert!((a[c] - b[c]).abs() < 1e-10, "{a:?} {b:?}");
                }
            }
        }
    }

    /// The paper's whole analytical path on rings of an exact circle of radius 5: the quadratic
    /// closed fit's error falls with N (roughly as N^-4) and is small at N = 20; the GA problem's
    /// fitness at its start equals the analytical RMS.
    #[test]
    fn analytical_method_on_exact_circle_rings() {
        let pts = crate::data::generators::cylinder();
        let rings: Vec<Vec<Point3>> = pts.chunks(76).map(|c| c.to_vec()).collect();
        let data = RingData { rings };
        let rms = |n| {
            fit_closed(&data, ClosedNetShape { order_around: 3, order_up: 2, n_around: n, rows: 2 })
                .unwrap()
                .rms
        };
        let (r5, r10, r20) = (rms(5), rms(10), rms(20));
        assert!(r5 > r10 && r10 > r20, "{r5} {r10} {r20}");
        assert!(r20 < 1e-3 && r10 / r20 > 8.0, "{r10} {r20}");
        let fit = fit_closed(
            &data,
            ClosedNetShape { order_around: 3, order_up: 2, n_around: 7, rows: 2 },
        )
        .unwrap();
        // z is linear in v and the rows sit at z = 0 and 5.
        for (k, c) in fit.surface.control.iter().enumerate() {
            assert!((c[2] - if k % 2 == 0 { 0.0 } else { 5.0 }).abs() < 1e-9, "{c:?}");
        }
        let problem = RingNetProblem::new(&data, fit.clone(), 0.1);
        assert_eq!(problem.dim(), 14);
        assert!((problem.fitness(problem.initial_point()) - fit.rms).abs() < 1e-12);
        // The fitness is the RMS distance to the surface evaluated point by point.
        let x: Vec<f64> = problem
            .initial_point()
            .iter()
            .enumerate()
            .map(|(j, v)| v + 0.01 * (j as f64).cos())
            .collect();
        let s = problem.surface(&x);
        let direct = (data
            .points()
            .zip(&fit.uv)
            .map(|(p, &(u, v))| crate::geom::dist2(*p, s.eval(u, v)))
            .sum::<f64>()
            / data.n_points() as f64)
            .sqrt();
        assert!((problem.fitness(&x) - direct).abs() < 1e-12);
        // Too few points or control points are refused by name.
        assert!(fit_closed(
            &data,
            ClosedNetShape { order_around: 3, order_up: 2, n_around: 2, rows: 2 }
        )
        .is_err());
        assert!(fit_closed(
            &data,
            ClosedNetShape { order_around: 3, order_up: 3, n_around: 7, rows: 2 }
        )
        .is_err());
    }
}
