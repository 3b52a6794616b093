//! The thesis' control-net problem (Chapter 6; fitness Eq. 6.2 = Eq. 5.13) with a fast fitness.
//!
//! Decision vector: the distinct control points of approach B, one per control-net class number,
//! xyz interleaved. A surface point depends on only 4 x 4 control points, so the fitness is the
//! separable sparse tensor product D^G = Nu (P Nv^T): first Q = P Nv^T over the four non-zeros of
//! each v-row, then each grid row as four scaled rows of Q (contiguous, so it vectorises), in
//! structure-of-arrays layout with no allocation per call. The top view is evaluated only at its
//! interior, since a border class is scored once, on the bottom view (Eq. 5.13).

use super::problem::Problem;
use crate::double_net::{DoubleNet, View};
use crate::geom::Point3;
use crate::spline::ControlNetParts;
use std::cell::RefCell;

/// The control-net problem: the parts from the spline fit, and a box.
pub struct ControlNetProblem {
    parts: ControlNetParts,
    class: [Vec<u32>; 2],
    data: [[Vec<f64>; 3]; 2],
    lo: Vec<f64>,
    hi: Vec<f64>,
    /// Per-axis box the bounds were made from (lower, upper).
    pub box_axes: (Point3, Point3),
}

#[derive(Default)]
struct Scratch {
    /// P of one view, per coordinate, row-major (a * cn_y + b).
    p: [Vec<f64>; 3],
    /// S = Nu P, per coordinate, row-major (i * cn_y + b).
    s: [Vec<f64>; 3],
    /// S transposed (b * nx + i).
    st: [Vec<f64>; 3],
    /// One column of D^G (over i) per coordinate.
    col: [Vec<f64>; 3],
}

/// out = w0 a + w1 b + w2 c + w3 d, element-wise (equal lengths, so the loop vectorises).
#[inline(always)]
fn lin4(out: &mut [f64], a: &[f64], b: &[f64], c: &[f64], d: &[f64], w: [f64; 4]) {
    let n = out.len();
    let (a, b, c, d) = (&a[..n], &b[..n], &c[..n], &d[..n]);
    for k in 0..n {
        out[k] = w[0] * a[k] + w[1] * b[k] + w[2] * c[k] + w[3] * d[k];
    }
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

impl ControlNetProblem {
    /// Bounds per axis: the smallest box holding the grid data and the initial control points,
    /// widened on each side by `margin` times its size (0: exactly that box).
    pub fn new(parts: ControlNetParts, margin: f64) -> ControlNetProblem {
        let cn = DoubleNet::new(parts.cn_x, parts.cn_y).expect("control net sides at least 4");
        let class = View::BOTH.map(|v| cn.classes(v).iter().map(|&c| c as u32).collect::<Vec<u32>>());
        let (nx, ny) = (parts.nx, parts.ny);
        // Data transposed (j * nx + i), the order the columns of D^G come in.
        let data = [&parts.data_bottom, &parts.data_top].map(|d| [0, 1, 2].map(|c| (0..nx * ny).map(|k| d[(k % nx) * ny + k / nx][c]).collect::<Vec<f64>>()));
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        let points = parts.data_bottom.iter().chain(&parts.data_top).copied().chain(parts.x0.chunks(3).map(|c| [c[0], c[1], c[2]]));
        for p in points {
            for c in 0..3 {
                lo[c] = lo[c].min(p[c]);
                hi[c] = hi[c].max(p[c]);
            }
        }
        for c in 0..3 {
            let w = (hi[c] - lo[c]) * margin;
            lo[c] -= w;
            hi[c] += w;
        }
        let n = parts.x0.len();
        ControlNetProblem { class, data, lo: (0..n).map(|k| lo[k % 3]).collect(), hi: (0..n).map(|k| hi[k % 3]).collect(), box_axes: (lo, hi), parts }
    }

    pub fn parts(&self) -> &ControlNetParts {
        &self.parts
    }

    /// Walk every scored position: `visit(view, i, j, fitted point)`, column by column (j outer).
    fn forward(&self, x: &[f64], mut visit: impl FnMut(usize, usize, usize, [f64; 3])) {
        self.forward_columns(x, |view, j, rows, col| {
            for i in rows {
                visit(view, i, j, [col[0][i], col[1][i], col[2][i]]);
            }
        });
    }

    /// Walk every scored grid column j of each view: `visit(view, j, scored rows, fitted x/y/z of
    /// the column indexed by i)`. S = Nu P runs along contiguous rows of P, then S is transposed so
    /// that each column of D^G = S Nv^T is four scaled contiguous rows of S^T.
    fn forward_columns(&self, x: &[f64], mut visit: impl FnMut(usize, usize, std::ops::Range<usize>, &[Vec<f64>; 3])) {
        let p = &self.parts;
        let (nx, ny, cn_x, cn_y) = (p.nx, p.ny, p.cn_x, p.cn_y);
        SCRATCH.with(|s| {
            let mut s = s.borrow_mut();
            let s = &mut *s;
            if s.p[0].len() != cn_x * cn_y || s.s[0].len() != nx * cn_y {
                for c in 0..3 {
                    s.p[c] = vec![0.0; cn_x * cn_y];
                    s.s[c] = vec![0.0; nx * cn_y];
                    s.st[c] = vec![0.0; cn_y * nx];
                    s.col[c] = vec![0.0; nx];
                }
            }
            for view in 0..2 {
                for (k, &cls) in self.class[view].iter().enumerate() {
                    let at = 3 * cls as usize;
                    s.p[0][k] = x[at];
                    s.p[1][k] = x[at + 1];
                    s.p[2][k] = x[at + 2];
                }
                let rows = if view == 0 { 0..nx } else { 1..nx - 1 };
                for c in 0..3 {
                    let (pc, sc) = (&s.p[c], &mut s.s[c]);
                    for i in rows.clone() {
                        let (f, w) = (p.nu.first[i], p.nu.w[i]);
                        let block = &pc[f * cn_y..(f + 4) * cn_y];
                        let (p0, rest) = block.split_at(cn_y);
                        let (p1, rest) = rest.split_at(cn_y);
                        let (p2, p3) = rest.split_at(cn_y);
                        let out = &mut sc[i * cn_y..(i + 1) * cn_y];
                        lin4(out, p0, p1, p2, p3, w);
                    }
                    let st = &mut s.st[c];
                    for i in rows.clone() {
                        for b in 0..cn_y {
                            st[b * nx + i] = sc[i * cn_y + b];
                        }
                    }
                }
                let cols = if view == 0 { 0..ny } else { 1..ny - 1 };
                for j in cols {
                    let (f, w) = (p.nv.first[j], p.nv.w[j]);
                    for c in 0..3 {
                        let block = &s.st[c][f * nx..(f + 4) * nx];
                        let (s0, rest) = block.split_at(nx);
                        let (s1, rest) = rest.split_at(nx);
                        let (s2, s3) = rest.split_at(nx);
                        let r = rows.clone();
                        lin4(&mut s.col[c][r.clone()], &s0[r.clone()], &s1[r.clone()], &s2[r.clone()], &s3[r], w);
                    }
                    visit(view, j, rows.clone(), &s.col);
                }
            }
        });
    }
}

impl Problem for ControlNetProblem {
    fn dim(&self) -> usize {
        self.parts.x0.len()
    }
    fn initial_point(&self) -> &[f64] {
        &self.parts.x0
    }
    fn bounds(&self) -> (&[f64], &[f64]) {
        (&self.lo, &self.hi)
    }
    /// Eq. 6.2: sum over the NOV grid classes of |D - D^G|.
    fn fitness(&self, x: &[f64]) -> f64 {
        let nx = self.parts.nx;
        let mut e = 0.0;
        self.forward_columns(x, |view, j, rows, col| {
            let d = &self.data[view];
            let (lo, hi) = (j * nx + rows.start, j * nx + rows.end);
            let (dx, dy, dz) = (&d[0][lo..hi], &d[1][lo..hi], &d[2][lo..hi]);
            let (gx, gy, gz) = (&col[0][rows.clone()], &col[1][rows.clone()], &col[2][rows.clone()]);
            // Four partial sums in a fixed order: the square roots vectorise, the result is the same
            // whatever the thread.
            let mut acc = [0.0f64; 4];
            let n4 = gx.len() / 4 * 4;
            for k in (0..n4).step_by(4) {
                for l in 0..4 {
                    let (a, b, c) = (gx[k + l] - dx[k + l], gy[k + l] - dy[k + l], gz[k + l] - dz[k + l]);
                    acc[l] += (a * a + b * b + c * c).sqrt();
                }
            }
            for k in n4..gx.len() {
                let (a, b, c) = (gx[k] - dx[k], gy[k] - dy[k], gz[k] - dz[k]);
                acc[k - n4] += (a * a + b * b + c * c).sqrt();
            }
            e += (acc[0] + acc[1]) + (acc[2] + acc[3]);
        });
        e
    }
}

impl ControlNetProblem {
    /// Number of scored positions (NOV of the grid): the residual terms of the fitness.
    pub fn terms(&self) -> usize {
        let (nx, ny) = (self.parts.nx, self.parts.ny);
        nx * ny + (nx - 2) * (ny - 2)
    }

    /// The fitted two-view grid D^G of a decision vector (the top view's border is the bottom's:
    /// both views share their border control points).
    pub fn fitted_grid(&self, x: &[f64]) -> crate::double_net::TwoViewGrid {
        let (nx, ny) = (self.parts.nx, self.parts.ny);
        let mut bottom = vec![[0.0; 3]; nx * ny];
        let mut top = vec![[0.0; 3]; nx * ny];
        self.forward(x, |view, i, j, g| {
            if view == 0 {
                bottom[i * ny + j] = g;
            } else {
                top[i * ny + j] = g;
            }
        });
        for i in 0..nx {
            for j in 0..ny {
                if i == 0 || j == 0 || i + 1 == nx || j + 1 == ny {
                    top[i * ny + j] = bottom[i * ny + j];
                }
            }
        }
        crate::double_net::TwoViewGrid { nx, ny, bottom, top }
    }

    /// The residuals D^G - D at every scored position (bottom view, then the top interior;
    /// column by column).
    pub fn residuals(&self, x: &[f64], out: &mut Vec<[f64; 3]>) {
        out.clear();
        let nx = self.parts.nx;
        self.forward(x, |view, i, j, g| {
            let d = &self.data[view];
            let at = j * nx + i;
            out.push([g[0] - d[0][at], g[1] - d[1][at], g[2] - d[2][at]]);
        });
    }

    /// The sparse rows of x -> D^G, one per scored position (same order as `residuals`): the
    /// (control-net class, weight) pairs and the data point, so that r_k = sum w P_class - d_k.
    pub fn rows(&self) -> Vec<(Vec<(u32, f64)>, [f64; 3])> {
        let p = &self.parts;
        let (nx, ny, cn_y) = (p.nx, p.ny, p.cn_y);
        let mut out = Vec::new();
        for view in 0..2 {
            let cols = if view == 0 { 0..ny } else { 1..ny - 1 };
            for j in cols {
                let rows = if view == 0 { 0..nx } else { 1..nx - 1 };
                for i in rows {
                    let mut entries = Vec::with_capacity(16);
                    for s in 0..4 {
                        for t in 0..4 {
                            let w = p.nu.w[i][s] * p.nv.w[j][t];
                            if w != 0.0 {
                                entries.push((self.class[view][(p.nu.first[i] + s) * cn_y + p.nv.first[j] + t], w));
                            }
                        }
                    }
                    let at = j * nx + i;
                    let d = &self.data[view];
                    out.push((entries, [d[0][at], d[1][at], d[2][at]]));
                }
            }
        }
        out
    }

    /// The adjoint of x -> D^G: g = sum_k A_k^T y_k.
    pub fn apply_transpose(&self, y: &[[f64; 3]], out: &mut [f64]) {
        let p = &self.parts;
        let (nx, ny, cn_x, cn_y) = (p.nx, p.ny, p.cn_x, p.cn_y);
        out.iter_mut().for_each(|v| *v = 0.0);
        let mut k = 0;
        for view in 0..2 {
            // Adjoint of the row stage: yq = Nu^T Y.
            let mut yq = vec![[0.0; 3]; cn_x * ny];
            let rows = if view == 0 { 0..nx } else { 1..nx - 1 };
            let cols = if view == 0 { 0..ny } else { 1..ny - 1 };
            for j in cols {
                for i in rows.clone() {
                    let (f, w) = (p.nu.first[i], p.nu.w[i]);
                    let yy = y[k];
                    k += 1;
                    for t in 0..4 {
                        for c in 0..3 {
                            yq[(f + t) * ny + j][c] += w[t] * yy[c];
                        }
                    }
                }
            }
            // Adjoint of Q = P Nv^T, then of the gather by class.
            for a in 0..cn_x {
                for j in 0..ny {
                    let (f, w) = (p.nv.first[j], p.nv.w[j]);
                    let yy = yq[a * ny + j];
                    for t in 0..4 {
                        let cls = self.class[view][a * cn_y + f + t] as usize;
                        for c in 0..3 {
                            out[3 * cls + c] += w[t] * yy[c];
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
pub mod tests {
    use super::*;
    use crate::spline::{fit_two_view, Approach, Parameterisation};

    pub fn problem(nx: usize, ny: usize, cn_x: usize, cn_y: usize) -> ControlNetProblem {
        let g = crate::spline::approach::tests::test_grid(nx, ny, 0.03);
        let fit = fit_two_view(&g, cn_x, cn_y, Parameterisation::ChordLength, Approach::Improved).unwrap();
        ControlNetProblem::new(fit.control_net_parts(&g).unwrap(), 0.0)
    }

    #[test]
    fn fast_fitness_equals_the_dense_reference() {
        for (nx, ny, cx, cy) in [(20, 20, 18, 18), (18, 30, 4, 16), (12, 9, 6, 5)] {
            let pr = problem(nx, ny, cx, cy);
            let mut x = pr.parts().x0.clone();
            for (k, v) in x.iter_mut().enumerate() {
                *v += 1e-3 * ((k * 7919) % 13) as f64;
            }
            for point in [pr.parts().x0.clone(), x] {
                let fast = pr.fitness(&point);
                let dense = pr.parts().surface_error(&point);
                assert!((fast - dense).abs() <= 1e-12 * dense, "{nx}x{ny} {cx}x{cy}: {fast} vs {dense}");
            }
        }
    }

    #[test]
    fn fitted_grid_is_approach_b_at_the_start() {
        let g = crate::spline::approach::tests::test_grid(14, 11, 0.03);
        let fit = fit_two_view(&g, 8, 7, Parameterisation::ChordLength, Approach::Improved).unwrap();
        let pr = ControlNetProblem::new(fit.control_net_parts(&g).unwrap(), 0.0);
        let grid = pr.fitted_grid(pr.initial_point());
        for (a, b) in grid.bottom.iter().chain(&grid.top).zip(fit.fitted_bottom.iter().chain(&fit.fitted_top)) {
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() < 1e-12, "{a:?} vs {b:?}");
            }
        }
    }

    #[test]
    fn transpose_is_the_adjoint() {
        let pr = problem(12, 10, 7, 6);
        let n = pr.dim();
        let x: Vec<f64> = (0..n).map(|k| ((k * 31) % 17) as f64 / 17.0).collect();
        let zero = vec![0.0; n];
        let (mut r, mut r0) = (Vec::new(), Vec::new());
        pr.residuals(&x, &mut r);
        pr.residuals(&zero, &mut r0);
        let y: Vec<[f64; 3]> = (0..r.len()).map(|k| [((k * 3) % 7) as f64 - 3.0, ((k * 5) % 11) as f64 - 5.0, (k % 3) as f64]).collect();
        // <A x, y> = <x, A^T y> with A x = r(x) - r(0).
        let lhs: f64 = r.iter().zip(&r0).zip(&y).map(|((a, b), yy)| (0..3).map(|c| (a[c] - b[c]) * yy[c]).sum::<f64>()).sum();
        let mut g = vec![0.0; n];
        pr.apply_transpose(&y, &mut g);
        let rhs: f64 = g.iter().zip(&x).map(|(a, b)| a * b).sum();
        assert!((lhs - rhs).abs() < 1e-9 * lhs.abs().max(1.0), "{lhs} vs {rhs}");
        assert_eq!(r.len(), pr.terms());
    }
}
