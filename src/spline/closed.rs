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
use serde::{Deserialize, Serialize};

/// The `order` non-zero closed basis functions at u (taken mod n): (first control index, values);
/// the l-th value belongs to control point (first + l) mod n.
pub(crate) fn periodic_basis(n: usize, order: usize, u: f64) -> (usize, Vec<f64>) {
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
pub(crate) struct ClosedSurface {
    pub(crate) order_around: usize,
    pub(crate) order_up: usize,
    pub(crate) n_around: usize,
    pub(crate) rows: usize,
    pub(crate) knots_v: Vec<f64>,
    pub(crate) control: Vec<Point3>,
}

impl ClosedSurface {
    pub(crate) fn eval(&self, u: f64, v: f64) -> Point3 {
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

pub(crate) use crate::data::cylinder::RingData;

/// The shape of a fit: orders and net size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ClosedNetShape {
    pub(crate) order_around: usize,
    pub(crate) order_up: usize,
    pub(crate) n_around: usize,
    pub(crate) rows: usize,
}

impl ClosedNetShape {
    pub(crate) fn check(&self, data: &RingData) -> Result<(), SplineError> {
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
pub(crate) struct ClosedFit {
    pub(crate) surface: ClosedSurface,
    pub(crate) uv: Vec<(f64, f64)>,
    pub(crate) rms: f64,
}

/// Chord-length parameters and the SVD least-squares net (the paper's analytical method).
pub(crate) fn fit_closed(data: &RingData, shape: ClosedNetShape) -> Result<ClosedFit, SplineError> {
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
pub(crate) fn fit_closed_at(
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

/// How the GA's RMS error measures a data point's distance to the surface (seed 004's Eq. 9
/// against its "RMS values of modelled curve and data points", Table II).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PointError {
    /// At the point's own chord-length parameters (Eq. 9 as written: the least-squares net is
    /// its exact minimum).
    #[default]
    AtParameters,
    /// At the point's foot on the surface: its (x, y) distance to the closed curve of the
    /// columns' (x, y), u re-found by Gauss-Newton from its chord-length u; z at its parameters.
    ClosestPoint,
}

/// The `p + 1` uniform B-splines of degree p non-zero on a unit span, at t in [0, 1) of it
/// (A2.2 on the integer knots, without allocation; p <= 7).
fn uniform_span_basis(p: usize, t: f64) -> [f64; 8] {
    debug_assert!(p <= 7, "degree {p} above 7");
    let (mut out, mut left, mut right) = ([0.0; 8], [0.0; 8], [0.0; 8]);
    // The span [0, 1) of the knots ..., -1, 0, 1, 2, ...: u - t_{1-j} = t + j - 1, t_j - u = j - t.
    super::basis::basis_funs_into(
        p,
        |j| t + (j - 1) as f64,
        |j| j as f64 - t,
        (&mut out, &mut left, &mut right),
    );
    out
}

/// The point of the closed curve of `xy` = (x_0, y_0, x_1, y_1, ...) at u and its derivative.
fn curve_and_tangent(xy: &[f64], n: usize, order: usize, u: f64) -> ([f64; 2], [f64; 2]) {
    let nf = n as f64;
    let mut w = u.rem_euclid(nf);
    if w >= nf {
        w = 0.0;
    }
    let s = (w.floor() as usize).min(n - 1);
    let (p, t) = (order - 1, w - s as f64);
    // The l-th value of degree p belongs to control point s - p + l (as in `periodic_basis`).
    let b = uniform_span_basis(p, t);
    let mut c = [0.0; 2];
    for (l, a) in b.iter().take(p + 1).enumerate() {
        let i = (s + l + n - p % n) % n;
        c[0] += a * xy[2 * i];
        c[1] += a * xy[2 * i + 1];
    }
    // Uniform knots: B'_{j,k} = B_{j,k-1} - B_{j+1,k-1}, so C' = sum_j B_{j,k-1} (P_j - P_{j-1}),
    // the degree p - 1 functions on the span belonging to s - p + 1 + l.
    let b1 = uniform_span_basis(p - 1, t);
    let mut d = [0.0; 2];
    for (l, a) in b1.iter().take(p).enumerate() {
        let i = (s + 1 + l + 2 * n - p % n) % n;
        let h = (i + n - 1) % n;
        d[0] += a * (xy[2 * i] - xy[2 * h]);
        d[1] += a * (xy[2 * i + 1] - xy[2 * h + 1]);
    }
    (c, d)
}

/// The squared distance from `p` to the closed curve of `xy` (order `order`, `n` points) at the
/// foot point nearest u0: Gauss-Newton on |C(u) - p|^2 from u0, steps at most half a span.
pub(crate) fn foot_distance_sq(xy: &[f64], n: usize, order: usize, p: [f64; 2], u0: f64) -> f64 {
    let mut u = u0;
    for _ in 0..12 {
        let (c, d) = curve_and_tangent(xy, n, order, u);
        let dd = d[0] * d[0] + d[1] * d[1];
        if dd <= 0.0 {
            break;
        }
        let step = (((c[0] - p[0]) * d[0] + (c[1] - p[1]) * d[1]) / dd).clamp(-0.5, 0.5);
        u -= step;
        if step.abs() < 1e-13 {
            break;
        }
    }
    let (c, _) = curve_and_tangent(xy, n, order, u);
    (c[0] - p[0]).powi(2) + (c[1] - p[1]).powi(2)
}

/// The GA's problem: decision vector (x_0, y_0, ..., x_{N-1}, y_{N-1}), the (x, y) of every column
/// of the net (all its rows share them), z of the net fixed at the analytical fit's; box: the
/// analytical column's (x, y) (averaged over its rows) +- `search_range`; fitness = RMS error.
pub(crate) struct RingNetProblem {
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
    measure: PointError,
    /// For `ClosestPoint`: the distinct ((x, y), chord-length u) of the data and their counts
    /// (the lattice repeats its rings level by level).
    feet: Vec<([f64; 2], f64, f64)>,
}

impl RingNetProblem {
    pub(crate) fn new(data: &RingData, fit: ClosedFit, search_range: f64) -> RingNetProblem {
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
        RingNetProblem {
            fit,
            w,
            at,
            target,
            z_sse,
            x0,
            lo,
            hi,
            measure: PointError::AtParameters,
            feet: Vec::new(),
        }
    }

    /// The same problem with its fitness measured by `measure`.
    pub(crate) fn with_measure(mut self, measure: PointError) -> RingNetProblem {
        self.measure = measure;
        self.feet.clear();
        if measure == PointError::ClosestPoint {
            let mut seen = std::collections::HashMap::new();
            for (t, &(u, _)) in self.target.iter().zip(&self.fit.uv) {
                let key = (t[0].to_bits(), t[1].to_bits(), u.to_bits());
                let k = *seen.entry(key).or_insert(self.feet.len());
                if k == self.feet.len() {
                    self.feet.push((*t, u, 0.0));
                }
                self.feet[k].2 += 1.0;
            }
        }
        self
    }

    /// The analytical net's RMS error in the problem's measure (its columns' (x, y)).
    pub(crate) fn analytical_rms(&self) -> f64 {
        match self.measure {
            PointError::AtParameters => self.fit.rms,
            PointError::ClosestPoint => self.fitness(&self.x0),
        }
    }

    pub(crate) fn n_points(&self) -> usize {
        self.target.len()
    }

    /// The analytical fit the problem was built on.
    pub(crate) fn analytical(&self) -> &ClosedFit {
        &self.fit
    }

    /// The surface of a decision vector.
    pub(crate) fn surface(&self, x: &[f64]) -> ClosedSurface {
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
        if self.measure == PointError::ClosestPoint {
            let n = self.fit.surface.n_around;
            for &(t, u, count) in &self.feet {
                sse += count * foot_distance_sq(x, n, k, t, u);
            }
            return (sse / self.target.len() as f64).sqrt();
        }
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

    #[test]
    fn uniform_span_basis_is_the_periodic_one() {
        for (n, k) in [(5, 2), (7, 3), (8, 4), (9, 8)] {
            for s in 0..=300 {
                let u = s as f64 * n as f64 / 301.0;
                let (_, want) = periodic_basis(n, k, u);
                let got = uniform_span_basis(k - 1, u - u.floor());
                for (a, b) in got.iter().zip(&want) {
                    assert!((a - b).abs() < 1e-13, "n {n} k {k} u {u}");
                }
            }
        }
    }

    #[test]
    fn curve_tangent_matches_finite_differences() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for (n, k) in [(5, 2), (7, 3), (8, 4)] {
            let xy: Vec<f64> = (0..2 * n).map(|_| rng.gen::<f64>()).collect();
            for s in 0..50 {
                // Off the knots, where the curve is smooth.
                let u = (s as f64 + 0.37) * n as f64 / 50.0;
                let (_, d) = curve_and_tangent(&xy, n, k, u);
                let h = 1e-6;
                let (a, _) = curve_and_tangent(&xy, n, k, u + h);
                let (b, _) = curve_and_tangent(&xy, n, k, u - h);
                for c in 0..2 {
                    let fd = (a[c] - b[c]) / (2.0 * h);
                    assert!((d[c] - fd).abs() < 1e-6, "n {n} k {k} u {u}: {} vs {fd}", d[c]);
                }
            }
        }
    }

    #[test]
    fn foot_distance_closed_forms() {
        // Order 2 closes the polygon of its control points: the square (+-1, +-1), with P_3 at
        // u = 0, P_0 = (1, -1) at u = 1, P_1 = (1, 1) at u = 2 and P_2 = (-1, 1) at u = 3.
        let sq = [1.0, -1.0, 1.0, 1.0, -1.0, 1.0, -1.0, -1.0];
        // Above the edge P_1 P_2 by 0.2: distance 0.2, from a start on the next edge down.
        let d = foot_distance_sq(&sq, 4, 2, [0.3, 1.2], 1.0);
        assert!((d - 0.04).abs() < 1e-12, "{d}");
        // Inside, 0.1 from the edge P_0 P_1 (x = 1), from a start on it.
        let d = foot_distance_sq(&sq, 4, 2, [0.9, 0.0], 1.3);
        assert!((d - 0.01).abs() < 1e-12, "{d}");
        // A point of a quadratic closed curve is found at distance 0 from a start 0.3 away.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let xy: Vec<f64> = (0..7)
            .flat_map(|i| {
                let t = i as f64 * std::f64::consts::TAU / 7.0;
                [5.0 * t.cos(), 5.0 * t.sin()]
            })
            .collect();
        for _ in 0..20 {
            let u = rng.gen::<f64>() * 7.0;
            let (c, _) = curve_and_tangent(&xy, 7, 3, u);
            assert!(foot_distance_sq(&xy, 7, 3, c, u + 0.3) < 1e-20);
        }
    }

    /// The foot-point measure is never above the at-parameter one (the foot is the nearest
    /// point, the parameter's point one of the candidates) and is below it on the lattice.
    #[test]
    fn closest_point_measure_is_at_most_the_parameter_one() {
        let data = crate::data::cylinder::sort_into_rings(
            &crate::data::cylinder::lattice_cylinder(5.0, 5.0, 0.1, 0.1),
            1e-4,
        );
        let shape = ClosedNetShape { order_around: 3, order_up: 2, n_around: 7, rows: 2 };
        let fit = fit_closed(&data, shape).unwrap();
        let at = RingNetProblem::new(&data, fit.clone(), 0.25);
        let foot =
            RingNetProblem::new(&data, fit.clone(), 0.25).with_measure(PointError::ClosestPoint);
        assert_eq!(at.analytical_rms(), fit.rms);
        assert!(foot.analytical_rms() < 0.9 * fit.rms, "{} {}", foot.analytical_rms(), fit.rms);
        for j in 0..10 {
            let x: Vec<f64> = at
                .initial_point()
                .iter()
                .enumerate()
                .map(|(i, v)| v + 0.02 * ((i * j) as f64).sin())
                .collect();
            assert!(foot.fitness(&x) <= at.fitness(&x) + 1e-12);
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
