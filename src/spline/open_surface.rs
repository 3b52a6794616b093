//! One open cubic B-spline surface fitted to an `nx x ny` grid (seed 001), and its control-net
//! problem: minimise Eq. 5.13 restricted to one view, F(P) = sum_ij |S(u_i, v_j) - D_ij|, over the
//! `cn_x x cn_y` control points (xyz interleaved, row-major), evaluated by the sparse 4 x 4 tensor
//! product S_ij = sum_k Nu[i][k] sum_l Nv[j][l] P[fu_i + k][fv_j + l].
//!
//! The start x0 is the plain least-squares net (Eq. 5.5-5.6; no corner pinning: with one view there
//! is no border shared with a second surface). The box is the smallest one holding the data and
//! x0, grown by `margin` of its width per side.

use super::basis::basis_matrix;
use super::fit::least_squares_net;
use super::knots::{knot_vector, KnotRule};
use super::param::grid_params;
use super::{BSplineSurface, Parameterisation, SparseBasis};
use crate::geom::{self, Point3};
use crate::optim::problem::Problem;

#[derive(Debug, Clone)]
pub struct OpenSurfaceProblem {
    pub grid: Vec<Point3>,
    pub nx: usize,
    pub ny: usize,
    pub cn_x: usize,
    pub cn_y: usize,
    pub us: Vec<f64>,
    pub vs: Vec<f64>,
    pub knots_u: Vec<f64>,
    pub knots_v: Vec<f64>,
    bu: SparseBasis,
    bv: SparseBasis,
    x0: Vec<f64>,
    lower: Vec<f64>,
    upper: Vec<f64>,
}

impl OpenSurfaceProblem {
    /// Parameterise the grid, build the knot vectors, fit the least-squares net.
    pub fn new(
        grid: &[Point3],
        nx: usize,
        ny: usize,
        cn_x: usize,
        cn_y: usize,
        param: Parameterisation,
        margin: f64,
    ) -> Result<OpenSurfaceProblem, String> {
        if grid.len() != nx * ny {
            return Err(format!("grid has {} points, expected {nx} x {ny}", grid.len()));
        }
        if !(margin >= 0.0 && margin.is_finite()) {
            return Err(format!("box margin must be >= 0, got {margin}"));
        }
        let (us, vs) = grid_params(grid, nx, ny, param);
        let knots_u =
            knot_vector(&us, cn_x, 3, KnotRule::NurbsBook).map_err(|e| format!("u: {e}"))?;
        let knots_v =
            knot_vector(&vs, cn_y, 3, KnotRule::NurbsBook).map_err(|e| format!("v: {e}"))?;
        let net = least_squares_net(
            grid,
            &basis_matrix(&us, &knots_u, 3, cn_x),
            &basis_matrix(&vs, &knots_v, 3, cn_y),
        )?;
        let x0: Vec<f64> = net.iter().flat_map(|p| p.iter().copied()).collect();
        let all: Vec<Point3> = grid.iter().chain(&net).copied().collect();
        let (lo, hi) = geom::bounding_box(&all).ok_or("empty grid")?;
        let lower: Vec<f64> =
            (0..x0.len()).map(|k| lo[k % 3] - margin * (hi[k % 3] - lo[k % 3])).collect();
        let upper: Vec<f64> =
            (0..x0.len()).map(|k| hi[k % 3] + margin * (hi[k % 3] - lo[k % 3])).collect();
        let bu = SparseBasis::cubic(&us, &knots_u, cn_x);
        let bv = SparseBasis::cubic(&vs, &knots_v, cn_y);
        Ok(OpenSurfaceProblem {
            grid: grid.to_vec(),
            nx,
            ny,
            cn_x,
            cn_y,
            us,
            vs,
            knots_u,
            knots_v,
            bu,
            bv,
            x0,
            lower,
            upper,
        })
    }

    /// The surface of a decision vector.
    pub fn surface(&self, x: &[f64]) -> BSplineSurface {
        let control = x.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        BSplineSurface {
            p: 3,
            q: 3,
            knots_u: self.knots_u.clone(),
            knots_v: self.knots_v.clone(),
            cn_x: self.cn_x,
            cn_y: self.cn_y,
            control,
        }
    }

    /// The fitted grid S(u_i, v_j), row-major, by the sparse tensor product.
    pub fn fitted(&self, x: &[f64]) -> Vec<Point3> {
        // Q[a][j] = sum_l Nv[j][l] P[a][fv_j + l], a over control rows.
        let (cx, cy, ny) = (self.cn_x, self.cn_y, self.ny);
        let mut q = vec![[0.0; 3]; cx * ny];
        for a in 0..cx {
            for j in 0..ny {
                let (f, w) = (self.bv.first[j], self.bv.w[j]);
                let mut s = [0.0; 3];
                for (l, wl) in w.iter().enumerate() {
                    let o = 3 * (a * cy + f + l);
                    for c in 0..3 {
                        s[c] += wl * x[o + c];
                    }
                }
                q[a * ny + j] = s;
            }
        }
        let mut out = Vec::with_capacity(self.nx * ny);
        for i in 0..self.nx {
            let (f, w) = (self.bu.first[i], self.bu.w[i]);
            for j in 0..ny {
                let mut s = [0.0; 3];
                for k in 0..4 {
                    let r = q[(f + k) * ny + j];
                    for c in 0..3 {
                        s[c] += w[k] * r[c];
                    }
                }
                out.push(s);
            }
        }
        out
    }
}

impl Problem for OpenSurfaceProblem {
    fn dim(&self) -> usize {
        self.x0.len()
    }
    fn initial_point(&self) -> &[f64] {
        &self.x0
    }
    fn bounds(&self) -> (&[f64], &[f64]) {
        (&self.lower, &self.upper)
    }
    fn fitness(&self, x: &[f64]) -> f64 {
        self.fitted(x).iter().zip(&self.grid).map(|(s, d)| geom::dist(*s, *d)).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spline::fit::fitted_grid;
    use rand::{Rng, SeedableRng};

    fn wavy_grid(nx: usize, ny: usize) -> Vec<Point3> {
        (0..nx * ny)
            .map(|k| {
                let (i, j) = ((k / ny) as f64, (k % ny) as f64);
                let (x, y) = (i * i / 40.0, j / 3.0);
                [x, y, (x * 2.0).sin() * y.cos()]
            })
            .collect()
    }

    /// The sparse fitness equals a dense computation D^G = Nu P Nv^T at random points.
    #[test]
    fn fitness_equals_dense_reference() {
        let (nx, ny, cx, cy) = (15, 11, 7, 5);
        let grid = wavy_grid(nx, ny);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for param in Parameterisation::ALL {
            let pr = OpenSurfaceProblem::new(&grid, nx, ny, cx, cy, param, 0.1).unwrap();
            let nu = basis_matrix(&pr.us, &pr.knots_u, 3, cx);
            let nv = basis_matrix(&pr.vs, &pr.knots_v, 3, cy);
            for _ in 0..5 {
                let x: Vec<f64> =
                    pr.initial_point().iter().map(|v| v + rng.gen_range(-0.3..0.3)).collect();
                let net: Vec<Point3> = x.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
                // Dense triple loop, independent of the two-pass code.
                let mut want = 0.0;
                for i in 0..nx {
                    for j in 0..ny {
                        let mut s = [0.0; 3];
                        for a in 0..cx {
                            for b in 0..cy {
                                for c in 0..3 {
                                    s[c] += nu[(i, a)] * nv[(j, b)] * net[a * cy + b][c];
                                }
                            }
                        }
                        want += geom::dist(s, grid[i * ny + j]);
                    }
                }
                let got = pr.fitness(&x);
                assert!((got - want).abs() <= 1e-12 * want.max(1.0), "{param}: {got} vs {want}");
                let dense: f64 = fitted_grid(&net, &nu, &nv)
                    .iter()
                    .zip(&grid)
                    .map(|(s, d)| geom::dist(*s, *d))
                    .sum();
                assert!((got - dense).abs() <= 1e-12 * want.max(1.0));
            }
            // The least-squares start lies in its box and fits this smooth grid closely.
            let (lo, hi) = pr.bounds();
            assert!(pr.initial_point().iter().enumerate().all(|(k, v)| *v >= lo[k] && *v <= hi[k]));
        }
    }

    /// A grid sampled from a known open cubic B-spline at the uniform parameters is recovered
    /// exactly by the uniform parameterisation: same knots, same control net, zero error.
    #[test]
    fn exact_recovery_of_a_known_open_surface() {
        let (nx, ny, cx, cy) = (18, 14, 8, 6);
        let us: Vec<f64> = (0..nx).map(|k| k as f64 / (nx - 1) as f64).collect();
        let vs: Vec<f64> = (0..ny).map(|k| k as f64 / (ny - 1) as f64).collect();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        // A genuinely open patch: control points on a perturbed plane.
        let control: Vec<Point3> = (0..cx * cy)
            .map(|k| {
                [
                    (k / cy) as f64 + rng.gen_range(-0.2..0.2),
                    (k % cy) as f64 + rng.gen_range(-0.2..0.2),
                    rng.gen_range(-1.0..1.0),
                ]
            })
            .collect();
        let truth = BSplineSurface {
            p: 3,
            q: 3,
            knots_u: knot_vector(&us, cx, 3, KnotRule::NurbsBook).unwrap(),
            knots_v: knot_vector(&vs, cy, 3, KnotRule::NurbsBook).unwrap(),
            cn_x: cx,
            cn_y: cy,
            control: control.clone(),
        };
        let grid = truth.eval_grid(&us, &vs);
        let pr =
            OpenSurfaceProblem::new(&grid, nx, ny, cx, cy, Parameterisation::Uniform, 0.0).unwrap();
        // The same knots up to rounding (the uniform parameters are averaged over the columns).
        assert!(pr
            .knots_u
            .iter()
            .zip(&truth.knots_u)
            .chain(pr.knots_v.iter().zip(&truth.knots_v))
            .all(|(a, b)| (a - b).abs() < 1e-14));
        for (a, b) in pr.initial_point().chunks_exact(3).zip(&control) {
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() < 1e-9, "{a:?} vs {b:?}");
            }
        }
        assert!(pr.fitness(pr.initial_point()) < 1e-9);
        // The surface evaluator agrees with the fitted grid.
        let s = pr.surface(pr.initial_point());
        for (a, b) in s.eval_grid(&pr.us, &pr.vs).iter().zip(pr.fitted(pr.initial_point())) {
            assert!(geom::dist(*a, b) < 1e-12);
        }
    }

    #[test]
    fn refuses_bad_shapes() {
        let grid = wavy_grid(6, 6);
        assert!(OpenSurfaceProblem::new(&grid, 6, 5, 4, 4, Parameterisation::Uniform, 0.0).is_err());
        assert!(OpenSurfaceProblem::new(&grid, 6, 6, 7, 4, Parameterisation::Uniform, 0.0).is_err());
        assert!(
            OpenSurfaceProblem::new(&grid, 6, 6, 4, 4, Parameterisation::Uniform, -1.0).is_err()
        );
    }
}
