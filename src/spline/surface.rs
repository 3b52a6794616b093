//! A (non-rational) B-spline surface S(u, v) = sum_i sum_j N_{i,p}(u) N_{j,q}(v) P_{i,j} (Eq. 2.4).

use super::basis::{basis_funs, find_span};
use crate::geom::Point3;

/// Control net row-major: P_{a,b} at `a * cn_y + b`; u runs along a, v along b.
#[derive(Debug, Clone, PartialEq)]
pub struct BSplineSurface {
    pub p: usize,
    pub q: usize,
    pub knots_u: Vec<f64>,
    pub knots_v: Vec<f64>,
    pub cn_x: usize,
    pub cn_y: usize,
    pub control: Vec<Point3>,
}

impl BSplineSurface {
    /// S(u, v) (The NURBS Book A3.5).
    pub fn eval(&self, u: f64, v: f64) -> Point3 {
        let su = find_span(self.cn_x, self.p, u, &self.knots_u);
        let sv = find_span(self.cn_y, self.q, v, &self.knots_v);
        let nu = basis_funs(su, u, self.p, &self.knots_u);
        let nv = basis_funs(sv, v, self.q, &self.knots_v);
        let mut s = [0.0; 3];
        for (k, bu) in nu.iter().enumerate() {
            let a = su - self.p + k;
            let mut row = [0.0; 3];
            for (l, bv) in nv.iter().enumerate() {
                let c = self.control[a * self.cn_y + sv - self.q + l];
                for x in 0..3 {
                    row[x] += bv * c[x];
                }
            }
            for x in 0..3 {
                s[x] += bu * row[x];
            }
        }
        s
    }

    /// S at every (u_i, v_j), row-major over i.
    pub fn eval_grid(&self, us: &[f64], vs: &[f64]) -> Vec<Point3> {
        us.iter().flat_map(|&u| vs.iter().map(move |&v| self.eval(u, v))).collect()
    }
}
