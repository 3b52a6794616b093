//! Geometry between the data points: a fitted surface evaluated on a dense parameter grid.
//!
//! Eq. 5.13 measures a fit only at the data parameters, where a least-squares surface is pulled
//! towards the data; between them an ill-posed fit (a net nearly as large as the grid, knots that
//! leave a span with little data) can swing far outside the data. These measures look there:
//! - `excursion`: the largest distance of a dense surface point from the data's bounding box;
//! - `max_control`: the largest absolute control-point coordinate of either net;
//! - `border_gap`: the largest distance between the two surfaces along the whole shared border,
//!   points matched by their (fractional) grid index, each view's parameter interpolated linearly
//!   between its data parameters (at the data parameters this is the gap of Chapter 5).
//!
//! The dense parameters of a direction are its data parameters, `factor - 1` equally spaced
//! points inside each interval between them, and every knot-span midpoint, so no span is skipped.

use super::basis::basis_matrix;
use super::fit::fitted_grid;
use super::surface::BSplineSurface;
use crate::geom::{self, Point3};

/// The sampling density the harness uses: 4 points per data interval (at least 4x the data).
pub(crate) const DENSE_FACTOR: usize = 4;

/// What counts as "near the data": an excursion of at most this fraction of the longest side of
/// the data's bounding box (a tenth of the unit box's side for the thesis' normalised data; see
/// `families::maps::near_bound`).
pub(crate) const NEAR: f64 = 0.1;

/// The dense measures of a pair of surfaces.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DenseGeometry {
    pub excursion: f64,
    pub max_control: f64,
    pub border_gap: f64,
}

/// Sorted dense parameters: `params` refined `factor` times, plus the midpoints of the non-empty
/// knot spans.
pub(crate) fn dense_params(params: &[f64], knots: &[f64], factor: usize) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::with_capacity(params.len() * factor + knots.len());
    for w in params.windows(2) {
        for s in 0..factor {
            out.push(w[0] + (w[1] - w[0]) * s as f64 / factor as f64);
        }
    }
    out.extend(params.last());
    out.extend(knots.windows(2).filter(|w| w[1] > w[0]).map(|w| 0.5 * (w[0] + w[1])));
    out.sort_by(f64::total_cmp);
    out.dedup();
    out
}

/// The smallest axis-aligned box holding `points`.
pub(crate) fn bounding_box<'a>(points: impl IntoIterator<Item = &'a Point3>) -> (Point3, Point3) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    (lo, hi)
}

/// Euclidean distance from `p` to the box [lo, hi] (0 inside).
pub(crate) fn distance_to_box(p: Point3, lo: Point3, hi: Point3) -> f64 {
    let mut s = 0.0;
    for c in 0..3 {
        let d = (lo[c] - p[c]).max(p[c] - hi[c]).max(0.0);
        s += d * d;
    }
    s.sqrt()
}

/// `surf` at every dense (u, v), row-major over u; returns the points and the dense u and v.
pub(crate) fn dense_grid(
    surf: &BSplineSurface,
    params_u: &[f64],
    params_v: &[f64],
    factor: usize,
) -> (Vec<Point3>, Vec<f64>, Vec<f64>) {
    let du = dense_params(params_u, &surf.knots_u, factor);
    let dv = dense_params(params_v, &surf.knots_v, factor);
    let nu = basis_matrix(&du, &surf.knots_u, surf.p, surf.cn_x);
    let nv = basis_matrix(&dv, &surf.knots_v, surf.q, surf.cn_y);
    (fitted_grid(&surf.control, &nu, &nv), du, dv)
}

/// A wireframe for pictures: points and the edges (index pairs) between them.
pub(crate) type Wireframe = (Vec<Point3>, Vec<(u32, u32)>);

/// A wireframe of `surf` for pictures: the iso-parameter lines through the data parameters, each
/// drawn through the dense parameters of the other direction, so whatever the surface does between
/// the data points shows.
pub(crate) fn dense_wireframe(
    surf: &BSplineSurface,
    params_u: &[f64],
    params_v: &[f64],
    factor: usize,
) -> Wireframe {
    let (points, du, dv) = dense_grid(surf, params_u, params_v, factor);
    let (mu, mv) = (du.len(), dv.len());
    let id = |i: usize, j: usize| (i * mv + j) as u32;
    let is_data = |d: &[f64], x: f64| d.contains(&x);
    let mut edges = Vec::new();
    for i in (0..mu).filter(|&i| is_data(params_u, du[i])) {
        edges.extend((0..mv - 1).map(|j| (id(i, j), id(i, j + 1))));
    }
    for j in (0..mv).filter(|&j| is_data(params_v, dv[j])) {
        edges.extend((0..mu - 1).map(|i| (id(i, j), id(i + 1, j))));
    }
    (points, edges)
}

/// Linear interpolation of data parameters at a fractional index s in [0, n - 1].
fn at_index(params: &[f64], s: f64) -> f64 {
    let k = (s.floor() as usize).min(params.len() - 2);
    let f = s - k as f64;
    params[k] + (params[k + 1] - params[k]) * f
}

/// The dense measures of a two-view pair: `surfaces` = [bottom, top] with their data parameters
/// `params` = [(u, v) of bottom, (u, v) of top]; `data` is every map point (for the box).
pub(crate) fn dense_geometry(
    surfaces: [&BSplineSurface; 2],
    params: [(&[f64], &[f64]); 2],
    data: &[Point3],
    factor: usize,
) -> DenseGeometry {
    let (lo, hi) = bounding_box(data);
    let mut g = DenseGeometry::default();
    for (surf, (u, v)) in surfaces.iter().zip(params) {
        let (pts, _, _) = dense_grid(surf, u, v, factor);
        g.excursion = pts.iter().fold(g.excursion, |m, p| m.max(distance_to_box(*p, lo, hi)));
        g.max_control = surf.control.iter().flatten().fold(g.max_control, |m, c| m.max(c.abs()));
    }
    // Along the four border lines, matched by fractional grid index.
    let [(ub, vb), (ut, vt)] = params;
    let (nx, ny) = (ub.len(), vb.len());
    let steps = |n: usize| (0..=(n - 1) * factor).map(move |k| k as f64 / factor as f64);
    let mut gap = 0.0f64;
    let mut check = |pb: (f64, f64), pt: (f64, f64)| {
        gap = gap.max(geom::dist(surfaces[0].eval(pb.0, pb.1), surfaces[1].eval(pt.0, pt.1)));
    };
    for s in steps(ny) {
        for i in [0, nx - 1] {
            check((ub[i], at_index(vb, s)), (ut[i], at_index(vt, s)));
        }
    }
    for s in steps(nx) {
        for j in [0, ny - 1] {
            check((at_index(ub, s), vb[j]), (at_index(ut, s), vt[j]));
        }
    }
    g.border_gap = gap;
    g
}

#[cfg(test)]
mod tests {
    use super::super::knots::{knot_vector, KnotRule};
    use super::*;

    #[test]
    fn dense_params_refine_and_cover_every_span() {
        let t = [0.0, 0.5, 1.0];
        let k = [0.0, 0.0, 0.0, 0.0, 0.1, 1.0, 1.0, 1.0, 1.0];
        let d = dense_params(&t, &k, 4);
        assert_eq!(d, vec![0.0, 0.05, 0.125, 0.25, 0.375, 0.5, 0.55, 0.625, 0.75, 0.875, 1.0]);
    }

    #[test]
    fn box_distance_closed_form() {
        let (lo, hi) = bounding_box(&[[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]]);
        assert_eq!((lo, hi), ([0.0; 3], [1.0, 2.0, 3.0]));
        assert_eq!(distance_to_box([0.5, 1.0, 1.0], lo, hi), 0.0);
        assert_eq!(distance_to_box([4.0, 6.0, 1.0], lo, hi), 5.0);
        assert_eq!(distance_to_box([-3.0, 1.0, 7.0], lo, hi), 5.0);
    }

    /// A bilinear patch written as a cubic B-spline (control points on the plane z = x + y in the
    /// unit square) stays in the unit-square box: excursion 0. Lifting one interior control point
    /// by h lifts the surface by h times the largest value of that point's basis function
    /// product, a closed form checked here.
    #[test]
    fn excursion_of_a_known_bounded_spline_and_a_bump() {
        let t: Vec<f64> = (0..10).map(|k| k as f64 / 9.0).collect();
        let (cn, p) = (6, 3);
        let knots = knot_vector(&t, cn, p, KnotRule::NurbsBook).unwrap();
        // Greville abscissae reproduce linear functions exactly.
        let grev: Vec<f64> =
            (0..cn).map(|a| knots[a + 1..a + 1 + p].iter().sum::<f64>() / p as f64).collect();
        let control: Vec<Point3> = (0..cn * cn)
            .map(|k| [grev[k / cn], grev[k % cn], (grev[k / cn] + grev[k % cn]) / 2.0])
            .collect();
        let mut surf = BSplineSurface {
            p,
            q: p,
            knots_u: knots.clone(),
            knots_v: knots.clone(),
            cn_x: cn,
            cn_y: cn,
            control,
        };
        let data: Vec<Point3> =
            t.iter().flat_map(|&u| t.iter().map(move |&v| [u, v, (u + v) / 2.0])).collect();
        let g = dense_geometry([&surf, &surf], [(&t, &t), (&t, &t)], &data, DENSE_FACTOR);
        assert!(g.excursion < 1e-12 && g.border_gap == 0.0, "{g:?}");
        assert!((g.max_control - 1.0).abs() < 1e-12);
        // Raise control point (2, 3) by h = 10: the largest rise is h max N_2(u) N_3(v).
        let h = 10.0;
        surf.control[2 * cn + 3][2] += h;
        let fine: Vec<f64> = (0..=2000).map(|k| k as f64 / 2000.0).collect();
        let peak = |a: usize| {
            fine.iter().map(|&u| basis_matrix(&[u], &knots, p, cn)[(0, a)]).fold(0.0, f64::max)
        };
        let rise = h * peak(2) * peak(3);
        let g = dense_geometry([&surf, &surf], [(&t, &t), (&t, &t)], &data, DENSE_FACTOR);
        // The peak of z = (u+v)/2 + rise lies over a point whose plane height is below 1, so the
        // excursion is at least rise - (1 - lowest plane height) and at most rise.
        assert!(
            g.excursion <= rise + 1e-9 && g.excursion > rise - 1.0,
            "{} vs {rise}",
            g.excursion
        );
        assert!((g.max_control - (h + (grev[2] + grev[3]) / 2.0)).abs() < 1e-12);
    }
}
