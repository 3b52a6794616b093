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

    /// The surface under the axis-wise affine map x -> offset + scale x (a normalised frame taken
    /// back to the data's: [`crate::data::frame::Frame`]). Exact on the control points: the basis
    /// functions sum to 1 at every (u, v), so S'(u, v) = offset + scale S(u, v).
    pub fn affine(&self, offset: Point3, scale: Point3) -> BSplineSurface {
        let control = self.control.iter().map(|&c| crate::geom::affine(offset, scale, c)).collect();
        BSplineSurface { control, ..self.clone() }
    }

    /// S at every (u_i, v_j), row-major over i.
    pub fn eval_grid(&self, us: &[f64], vs: &[f64]) -> Vec<Point3> {
        us.iter().flat_map(|&u| vs.iter().map(move |&v| self.eval(u, v))).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spline::knots::{knot_vector, KnotRule};
    use rand::{Rng, SeedableRng};

    #[test]
    fn an_affine_map_of_the_control_points_maps_every_surface_point() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let t =
            |n: usize| (0..n).map(|k| (k as f64 / (n - 1) as f64).powf(1.2)).collect::<Vec<_>>();
        let (cn_x, cn_y) = (7, 5);
        let s = BSplineSurface {
            p: 3,
            q: 3,
            knots_u: knot_vector(&t(12), cn_x, 3, KnotRule::NurbsBook).unwrap(),
            knots_v: knot_vector(&t(9), cn_y, 3, KnotRule::Eq2_10).unwrap(),
            cn_x,
            cn_y,
            control: (0..cn_x * cn_y).map(|_| [rng.gen(), rng.gen(), rng.gen()]).collect(),
        };
        let (offset, scale) = ([-3.0, 10.0, 0.0], [8.0, 1.0, 100.0]);
        let d = s.affine(offset, scale);
        for i in 0..=20 {
            for j in 0..=20 {
                let (u, v) = (i as f64 / 20.0, (j as f64 / 20.0).powi(2));
                let (p, q) = (s.eval(u, v), d.eval(u, v));
                for a in 0..3 {
                    let want = offset[a] + scale[a] * p[a];
                    assert!((q[a] - want).abs() <= 1e-12 * (1.0 + want.abs()), "{u} {v}: {q:?}");
                }
            }
        }
        assert_eq!((d.knots_u.clone(), d.cn_x), (s.knots_u.clone(), s.cn_x));
    }
}
