//! The two ways of fitting the two DNSOM surfaces (thesis Section 5.2): conventional (A), each
//! view alone, and improved (B), shared parameters and averaged border control points.
//!
//! Every choice, so that an independent implementation gets the same surface errors:
//! - Grids are row-major (i * ny + j); u runs along i (nx values), v along j (ny values).
//! - Parameters: per column j the polyline over i, per row i the polyline over j (Eq. 2.7/2.8,
//!   the exponential alpha by [`FitOptions::param`]), averaged (Eq. 5.1, 5.2; or the middle
//!   column and row alone, the same reading). B averages the two views' parameters (Eq. 5.3, 5.4).
//! - Knots: clamped cubic by the named rule of [`FitOptions::knots`] (see `knots`: Eq. 2.10
//!   literally, or The NURBS Book 9.68-9.69). A and B differ only through their parameters.
//! - Control nets: least squares per coordinate (`fit`), then for B every border control point
//!   (a = 0, cn_x - 1, b = 0, cn_y - 1: one class number in the double net) becomes the mean of
//!   the two nets' (Eq. 5.7); then the corner rule on each net (corner control point := corner data
//!   point; corners are border data, the same in both views, so the order of the two steps does not
//!   change them).
//! - Surface error (Eq. 5.13): for B, the sum over the NOV grid class numbers of |D - D^G|, a
//!   border class taken at its first allocation (the bottom view). For A by the named reading
//!   [`ErrorA`]: over all 2 nx ny map neurons, each view against its own fit (`per_surface`), or
//!   Eq. 5.13 as for B (`nov_bottom`). Gap: the largest |D^G_bottom - D^G_top| over
//!   the border positions; B has gap 0 exactly, since its border rows and columns of D^G are
//!   copies of the same shared control points.

use super::basis::{basis_matrix, SparseBasis};
use super::fit::{faired_net, fitted_grid, least_squares_net, pin_corners};
use super::knots::{knot_vector, KnotRule};
use super::param::{grid_params_with, ParamReading, Parameterisation};
use super::surface::BSplineSurface;
use super::SplineError;
pub(crate) use crate::double_net::TwoViewGrid;
use crate::double_net::{DoubleNet, View};
use crate::geom::{self, Point3};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// How approach A's surface error is scored (thesis Section 5.2.4 defines Eq. 5.13 "for the
/// improved approach" only; a named reading, docs/readings.md).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default, Serialize, Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum ErrorA {
    /// Sum of |D - D^G| over all 2 nx ny map neurons, each surface against its own fitted points
    /// (shared border neurons once per surface), as the conventional approach of the thesis' [23]
    /// treats each surface separately.
    #[default]
    PerSurface,
    /// Eq. 5.13 over the NOV class numbers, a shared border class scored on the bottom surface.
    NovBottom,
}

impl ErrorA {
    pub const ALL: [ErrorA; 2] = [ErrorA::PerSurface, ErrorA::NovBottom];

    /// The spec value.
    pub fn name(self) -> &'static str {
        match self {
            ErrorA::PerSurface => "per_surface",
            ErrorA::NovBottom => "nov_bottom",
        }
    }
}

impl fmt::Display for ErrorA {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ErrorA {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        ErrorA::ALL
            .into_iter()
            .find(|e| e.name() == s)
            .ok_or_else(|| format!("unknown reading `{s}` (expected per_surface or nov_bottom)"))
    }
}

/// The named readings and options of a two-surface fit. `Default` is the thesis plan's reading.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FitOptions {
    pub knots: KnotRule,
    pub error_a: ErrorA,
    /// Penalised least squares weight (0: the thesis' plain least squares; see `fit::faired_net`).
    pub fairness: f64,
    /// Eq. 2.8's exponential alpha and Eq. 5.1/5.2's rows (see `param::ParamReading`).
    pub param: ParamReading,
}

/// Conventional (A) or improved (B) (in a spec by letter or name, as [`FromStr`] reads it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Deserialize)]
#[serde(try_from = "String")]
pub enum Approach {
    Conventional,
    Improved,
}

impl Approach {
    /// "A" or "B", as the thesis' tables.
    pub fn letter(self) -> &'static str {
        match self {
            Approach::Conventional => "A",
            Approach::Improved => "B",
        }
    }
}

impl fmt::Display for Approach {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.letter())
    }
}

impl TryFrom<String> for Approach {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        s.parse()
    }
}

impl FromStr for Approach {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        // The thesis' letter or the name, as written here (no other case).
        match s {
            "A" | "conventional" => Ok(Approach::Conventional),
            "B" | "improved" => Ok(Approach::Improved),
            _ => Err(format!("unknown approach `{s}` (expected A/conventional or B/improved)")),
        }
    }
}

impl TwoViewGrid {
    /// Sizes, finiteness and the shared border.
    pub fn validate(&self) -> Result<(), SplineError> {
        if self.nx < 2 || self.ny < 2 {
            return Err(SplineError::Grid(format!(
                "the grid is {}x{}; both sides must be at least 2",
                self.nx, self.ny
            )));
        }
        for (name, v) in [("bottom", &self.bottom), ("top", &self.top)] {
            if v.len() != self.nx * self.ny {
                return Err(SplineError::Grid(format!(
                    "the {name} view has {} points, {}x{} needs {}",
                    v.len(),
                    self.nx,
                    self.ny,
                    self.nx * self.ny
                )));
            }
            if let Some(k) = v.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
                return Err(SplineError::Grid(format!(
                    "the {name} view has a non-finite point at ({}, {})",
                    k / self.ny,
                    k % self.ny
                )));
            }
        }
        for i in 0..self.nx {
            for j in 0..self.ny {
                if (i == 0 || j == 0 || i + 1 == self.nx || j + 1 == self.ny)
                    && self.bottom[i * self.ny + j] != self.top[i * self.ny + j]
                {
                    return Err(SplineError::Grid(format!("the views differ at border position ({i}, {j}); a two-view grid shares its border")));
                }
            }
        }
        Ok(())
    }

    fn view(&self, v: View) -> &[Point3] {
        match v {
            View::Bottom => &self.bottom,
            View::Top => &self.top,
        }
    }
}

/// A fitted pair of surfaces and its measures.
#[derive(Debug, Clone)]
pub struct TwoSurfaceFit {
    pub approach: Approach,
    pub param: Parameterisation,
    /// Data parameters per view (for B both views hold the same).
    pub params_u: [Vec<f64>; 2],
    pub params_v: [Vec<f64>; 2],
    pub bottom: BSplineSurface,
    pub top: BSplineSurface,
    /// D^G of each view at its data parameters, row-major.
    pub fitted_bottom: Vec<Point3>,
    pub fitted_top: Vec<Point3>,
    /// Eq. 5.13.
    pub surface_error: f64,
    /// Largest distance between the two fitted surfaces at the shared border positions.
    pub gap: f64,
}

struct ViewFit {
    u: Vec<f64>,
    v: Vec<f64>,
    knots_u: Vec<f64>,
    knots_v: Vec<f64>,
    net: Vec<Point3>,
}

/// Fit both views of `grid` with a `cn_x x cn_y` cubic control net each (Eq. 5.1-5.7, 5.12, 5.13).
pub fn fit_two_view(
    grid: &TwoViewGrid,
    cn_x: usize,
    cn_y: usize,
    param: Parameterisation,
    approach: Approach,
    opts: &FitOptions,
) -> Result<TwoSurfaceFit, SplineError> {
    grid.validate()?;
    if cn_x < 4 || cn_y < 4 {
        return Err(SplineError::ControlNet(format!(
            "control net {cn_x}x{cn_y} is smaller than 4 (cubic needs p + 1 = 4 a side)"
        )));
    }
    if cn_x > grid.nx || cn_y > grid.ny {
        return Err(SplineError::ControlNet(format!(
            "control net {cn_x}x{cn_y} is larger than the grid {}x{}",
            grid.nx, grid.ny
        )));
    }
    let (nx, ny) = (grid.nx, grid.ny);
    let own = [
        grid_params_with(&grid.bottom, nx, ny, param, &opts.param),
        grid_params_with(&grid.top, nx, ny, param, &opts.param),
    ];
    let params: [(Vec<f64>, Vec<f64>); 2] = match approach {
        Approach::Conventional => own,
        Approach::Improved => {
            let mean = |a: &[f64], b: &[f64]| {
                a.iter().zip(b).map(|(x, y)| (x + y) / 2.0).collect::<Vec<f64>>()
            };
            let u = mean(&own[0].0, &own[1].0);
            let v = mean(&own[0].1, &own[1].1);
            [(u.clone(), v.clone()), (u, v)]
        }
    };
    let mut fits = Vec::with_capacity(2);
    for (k, view) in View::BOTH.iter().enumerate() {
        let (u, v) = params[k].clone();
        let knots_u = knot_vector(&u, cn_x, 3, opts.knots).map_err(SplineError::ControlNet)?;
        let knots_v = knot_vector(&v, cn_y, 3, opts.knots).map_err(SplineError::ControlNet)?;
        let nu = basis_matrix(&u, &knots_u, 3, cn_x);
        let nv = basis_matrix(&v, &knots_v, 3, cn_y);
        let net = if opts.fairness > 0.0 {
            faired_net(grid.view(*view), &nu, &nv, opts.fairness)
        } else {
            least_squares_net(grid.view(*view), &nu, &nv)
        };
        let net = net.map_err(SplineError::Singular)?;
        fits.push(ViewFit { u, v, knots_u, knots_v, net });
    }
    if approach == Approach::Improved {
        for a in 0..cn_x {
            for b in 0..cn_y {
                if a == 0 || b == 0 || a + 1 == cn_x || b + 1 == cn_y {
                    let at = a * cn_y + b;
                    let mean = geom::scale(geom::add(fits[0].net[at], fits[1].net[at]), 0.5);
                    fits[0].net[at] = mean;
                    fits[1].net[at] = mean;
                }
            }
        }
    }
    for (k, view) in View::BOTH.iter().enumerate() {
        pin_corners(&mut fits[k].net, cn_x, cn_y, grid.view(*view), nx, ny);
    }
    let fitted: Vec<Vec<Point3>> = fits
        .iter()
        .map(|f| {
            fitted_grid(
                &f.net,
                &basis_matrix(&f.u, &f.knots_u, 3, cn_x),
                &basis_matrix(&f.v, &f.knots_v, 3, cn_y),
            )
        })
        .collect();
    let net = DoubleNet::new(nx, ny).expect("validated sides");
    let surface_error = match (approach, opts.error_a) {
        (Approach::Conventional, ErrorA::PerSurface) => {
            per_surface_error(grid, &fitted[0], &fitted[1])
        }
        _ => surface_error(grid, &net, &fitted[0], &fitted[1]),
    };
    let gap = border_gap(&net, &fitted[0], &fitted[1]);
    let surface = |f: &ViewFit| BSplineSurface {
        p: 3,
        q: 3,
        knots_u: f.knots_u.clone(),
        knots_v: f.knots_v.clone(),
        cn_x,
        cn_y,
        control: f.net.clone(),
    };
    let (bottom, top) = (surface(&fits[0]), surface(&fits[1]));
    let mut fitted = fitted.into_iter();
    Ok(TwoSurfaceFit {
        approach,
        param,
        params_u: [fits[0].u.clone(), fits[1].u.clone()],
        params_v: [fits[0].v.clone(), fits[1].v.clone()],
        bottom,
        top,
        fitted_bottom: fitted.next().unwrap_or_default(),
        fitted_top: fitted.next().unwrap_or_default(),
        surface_error,
        gap,
    })
}

/// Eq. 5.13: sum over the NOV grid classes of |D - D^G| at each class's first allocation.
pub(crate) fn surface_error(
    grid: &TwoViewGrid,
    net: &DoubleNet,
    fitted_bottom: &[Point3],
    fitted_top: &[Point3],
) -> f64 {
    (0..net.nov())
        .map(|c| {
            let (view, i, j) = net.first_allocation(c);
            let at = net.at(i, j);
            match view {
                View::Bottom => geom::dist(grid.bottom[at], fitted_bottom[at]),
                View::Top => geom::dist(grid.top[at], fitted_top[at]),
            }
        })
        .sum()
}

/// Approach A's error under `per_surface`: sum of |D - D^G| over every position of both views.
pub(crate) fn per_surface_error(
    grid: &TwoViewGrid,
    fitted_bottom: &[Point3],
    fitted_top: &[Point3],
) -> f64 {
    let one = |data: &[Point3], fitted: &[Point3]| {
        data.iter().zip(fitted).map(|(d, g)| geom::dist(*d, *g)).sum::<f64>()
    };
    one(&grid.bottom, fitted_bottom) + one(&grid.top, fitted_top)
}

/// Largest distance between the fitted surfaces over the shared border positions.
pub(crate) fn border_gap(net: &DoubleNet, fitted_bottom: &[Point3], fitted_top: &[Point3]) -> f64 {
    let mut gap = 0.0f64;
    for i in 0..net.nx {
        for j in 0..net.ny {
            if net.is_border(i, j) {
                gap = gap.max(geom::dist(fitted_bottom[net.at(i, j)], fitted_top[net.at(i, j)]));
            }
        }
    }
    gap
}

/// What Chapter 6 optimises: approach B's shared data parameters as sparse cubic bases, the grid,
/// and the distinct control points by control-net class (xyz interleaved).
#[derive(Debug, Clone)]
pub struct ControlNetParts {
    pub nx: usize,
    pub ny: usize,
    pub cn_x: usize,
    pub cn_y: usize,
    pub nu: SparseBasis,
    pub nv: SparseBasis,
    pub data_bottom: Vec<Point3>,
    pub data_top: Vec<Point3>,
    pub x0: Vec<f64>,
    /// B's shared data parameters and knot vectors (for evaluating a net between the data).
    pub params_u: Vec<f64>,
    pub params_v: Vec<f64>,
    pub knots_u: Vec<f64>,
    pub knots_v: Vec<f64>,
}

impl TwoSurfaceFit {
    /// The surfaces between the data points (see `geometry`), sampled `DENSE_FACTOR` times finer.
    pub fn dense_geometry(&self, grid: &TwoViewGrid) -> super::DenseGeometry {
        let data: Vec<Point3> = grid.bottom.iter().chain(&grid.top).copied().collect();
        let params = [
            (&self.params_u[0][..], &self.params_v[0][..]),
            (&self.params_u[1][..], &self.params_v[1][..]),
        ];
        super::geometry::dense_geometry(
            [&self.bottom, &self.top],
            params,
            &data,
            super::DENSE_FACTOR,
        )
    }

    /// Dense wireframes (bottom, top) of the fitted surfaces, for pictures.
    pub fn dense_wireframes(&self) -> [super::geometry::Wireframe; 2] {
        [(&self.bottom, 0), (&self.top, 1)].map(|(s, k)| {
            super::geometry::dense_wireframe(
                s,
                &self.params_u[k],
                &self.params_v[k],
                super::DENSE_FACTOR,
            )
        })
    }

    /// The control-net problem of Chapter 6 (approach B only: one set of knots and parameters).
    pub fn control_net_parts(&self, grid: &TwoViewGrid) -> Result<ControlNetParts, SplineError> {
        if self.approach != Approach::Improved {
            return Err(SplineError::ControlNet(
                "the control-net problem is defined on approach B".into(),
            ));
        }
        let (cn_x, cn_y) = (self.bottom.cn_x, self.bottom.cn_y);
        let cn = DoubleNet::new(cn_x, cn_y).expect("control nets at least 4 a side");
        let mut x0 = vec![0.0; 3 * cn.nov()];
        for c in 0..cn.nov() {
            let (view, a, b) = cn.first_allocation(c);
            let p = match view {
                View::Bottom => self.bottom.control[a * cn_y + b],
                View::Top => self.top.control[a * cn_y + b],
            };
            x0[3 * c..3 * c + 3].copy_from_slice(&p);
        }
        Ok(ControlNetParts {
            nx: grid.nx,
            ny: grid.ny,
            cn_x,
            cn_y,
            nu: SparseBasis::cubic(&self.params_u[0], &self.bottom.knots_u, cn_x),
            nv: SparseBasis::cubic(&self.params_v[0], &self.bottom.knots_v, cn_y),
            data_bottom: grid.bottom.clone(),
            data_top: grid.top.clone(),
            x0,
            params_u: self.params_u[0].clone(),
            params_v: self.params_v[0].clone(),
            knots_u: self.bottom.knots_u.clone(),
            knots_v: self.bottom.knots_v.clone(),
        })
    }
}

impl ControlNetParts {
    /// Dense wireframes (bottom, top) of a decision vector's surfaces, for pictures.
    pub fn dense_wireframes(&self, x: &[f64]) -> [super::geometry::Wireframe; 2] {
        self.surfaces(x).map(|s| {
            super::geometry::dense_wireframe(
                &s,
                &self.params_u,
                &self.params_v,
                super::DENSE_FACTOR,
            )
        })
    }

    /// The surfaces (bottom, top) of a decision vector sampled `DENSE_FACTOR` times finer than
    /// the data parameters: (points row-major, rows, columns) each, for 3-D views.
    pub fn dense_grids(&self, x: &[f64]) -> [(Vec<Point3>, usize, usize); 2] {
        self.surfaces(x).map(|s| {
            let (points, du, dv) = super::geometry::dense_grid(
                &s,
                &self.params_u,
                &self.params_v,
                super::DENSE_FACTOR,
            );
            (points, du.len(), dv.len())
        })
    }

    /// The dense geometry of a decision vector's surfaces (B's shared parameters and knots).
    pub fn dense_geometry(&self, x: &[f64]) -> super::DenseGeometry {
        let [bottom, top] = self.surfaces(x);
        let u = &self.params_u[..];
        let v = &self.params_v[..];
        let data: Vec<Point3> = self.data_bottom.iter().chain(&self.data_top).copied().collect();
        super::geometry::dense_geometry(
            [&bottom, &top],
            [(u, v), (u, v)],
            &data,
            super::DENSE_FACTOR,
        )
    }

    /// The two surfaces (bottom, top) of a decision vector x (one point per control-net class).
    pub fn surfaces(&self, x: &[f64]) -> [BSplineSurface; 2] {
        let cn = DoubleNet::new(self.cn_x, self.cn_y).expect("sides at least 4");
        View::BOTH.map(|view| BSplineSurface {
            p: 3,
            q: 3,
            knots_u: self.knots_u.clone(),
            knots_v: self.knots_v.clone(),
            cn_x: self.cn_x,
            cn_y: self.cn_y,
            control: (0..self.cn_x * self.cn_y)
                .map(|k| {
                    let c = cn.class(view, k / self.cn_y, k % self.cn_y);
                    [x[3 * c], x[3 * c + 1], x[3 * c + 2]]
                })
                .collect(),
        })
    }

    /// Eq. 6.2 (= Eq. 5.13) for a decision vector x, the plain dense way (the reference the fast
    /// fitness of Chapter 6 is tested against).
    pub fn surface_error(&self, x: &[f64]) -> f64 {
        let grid_net = DoubleNet::new(self.nx, self.ny).expect("sides at least 2");
        let nu = self.nu.dense(self.cn_x);
        let nv = self.nv.dense(self.cn_y);
        let [bottom, top] = self.surfaces(x);
        let fb = fitted_grid(&bottom.control, &nu, &nv);
        let ft = fitted_grid(&top.control, &nu, &nv);
        let grid = TwoViewGrid {
            nx: self.nx,
            ny: self.ny,
            bottom: self.data_bottom.clone(),
            top: self.data_top.clone(),
        };
        surface_error(&grid, &grid_net, &fb, &ft)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A lumpy closed two-view grid: a noisy sphere cut at the equator, built on the shared border.
    pub(crate) fn test_grid(nx: usize, ny: usize, noise: f64) -> TwoViewGrid {
        let net = DoubleNet::new(nx, ny).unwrap();
        let mut bottom = vec![[0.0; 3]; nx * ny];
        let mut top = vec![[0.0; 3]; nx * ny];
        for i in 0..nx {
            for j in 0..ny {
                let (s, t) = (
                    i as f64 / (nx - 1) as f64 * 2.0 - 1.0,
                    j as f64 / (ny - 1) as f64 * 2.0 - 1.0,
                );
                let r = s.abs().max(t.abs());
                let h = if net.is_border(i, j) { 0.0 } else { (1.0 - r * r).sqrt() * 0.5 };
                let wobble =
                    if net.is_border(i, j) { 0.0 } else { noise * ((7 * i + 3 * j) as f64).sin() };
                bottom[i * ny + j] = [0.5 + 0.5 * s, 0.5 + 0.5 * t, 0.5 - h - wobble];
                top[i * ny + j] = [0.5 + 0.5 * s, 0.5 + 0.5 * t, 0.5 + h + 0.7 * wobble];
            }
        }
        TwoViewGrid { nx, ny, bottom, top }
    }

    #[test]
    fn improved_has_no_gap_conventional_has_one() {
        let g = test_grid(20, 20, 0.02);
        for p in Parameterisation::ALL {
            for cn in [6, 10, 18] {
                let b = fit_two_view(&g, cn, cn, p, Approach::Improved, &FitOptions::default())
                    .unwrap();
                assert_eq!(b.gap, 0.0, "{p} {cn}");
                let a = fit_two_view(&g, cn, cn, p, Approach::Conventional, &FitOptions::default())
                    .unwrap();
                assert!(a.gap > 0.0, "{p} {cn}");
                assert!(a.surface_error > 0.0 && b.surface_error > 0.0);
            }
        }
        let g = test_grid(18, 30, 0.02);
        assert_eq!(
            fit_two_view(
                &g,
                16,
                28,
                Parameterisation::ChordLength,
                Approach::Improved,
                &FitOptions::default()
            )
            .unwrap()
            .gap,
            0.0
        );
    }

    /// Hand-computed: a 4x5 map, bottom fitted 0.1 off everywhere, top fitted exactly but for a
    /// border position 5 off (3-4-5) and an interior one 1 off. per_surface counts all 40
    /// positions: 20 * 0.1 + 5 + 1 = 8; Eq. 5.13 counts the NOV = 26 classes, the border on the
    /// bottom view: 20 * 0.1 + 1 = 3.
    #[test]
    fn per_surface_and_nov_bottom_errors_by_hand() {
        let g = test_grid(4, 5, 0.0);
        let net = DoubleNet::new(4, 5).unwrap();
        assert_eq!(net.nov(), 26);
        let fb: Vec<Point3> = g.bottom.iter().map(|p| [p[0], p[1], p[2] + 0.1]).collect();
        let mut ft = g.top.clone();
        ft[net.at(0, 2)] = geom::add(ft[net.at(0, 2)], [3.0, 4.0, 0.0]);
        ft[net.at(1, 1)] = geom::add(ft[net.at(1, 1)], [0.0, 0.0, 1.0]);
        assert!((per_surface_error(&g, &fb, &ft) - 8.0).abs() < 1e-12);
        assert!((surface_error(&g, &net, &fb, &ft) - 3.0).abs() < 1e-12);
    }

    /// Under per_surface, A's error is the sum of both views' own residuals, so it is never below
    /// Eq. 5.13 of the same fit; the two readings differ only for A.
    #[test]
    fn error_readings_change_a_only() {
        let g = test_grid(20, 20, 0.02);
        for cn in [6, 12] {
            let per = FitOptions::default();
            let nov = FitOptions { error_a: ErrorA::NovBottom, ..per };
            let (a1, a2) = (
                fit_two_view(
                    &g,
                    cn,
                    cn,
                    Parameterisation::ChordLength,
                    Approach::Conventional,
                    &per,
                )
                .unwrap(),
                fit_two_view(
                    &g,
                    cn,
                    cn,
                    Parameterisation::ChordLength,
                    Approach::Conventional,
                    &nov,
                )
                .unwrap(),
            );
            assert!(a1.surface_error > a2.surface_error);
            let (b1, b2) = (
                fit_two_view(&g, cn, cn, Parameterisation::ChordLength, Approach::Improved, &per)
                    .unwrap(),
                fit_two_view(&g, cn, cn, Parameterisation::ChordLength, Approach::Improved, &nov)
                    .unwrap(),
            );
            assert_eq!(b1.surface_error.to_bits(), b2.surface_error.to_bits());
        }
    }

    /// B's border curves are built from the same averaged control points on the same knots: the
    /// dense border gap is exactly 0; A's is at least its gap at the data parameters.
    #[test]
    fn dense_gap_and_excursion() {
        let g = test_grid(20, 20, 0.02);
        for knots in KnotRule::ALL {
            let o = FitOptions { knots, ..FitOptions::default() };
            let b = fit_two_view(&g, 10, 10, Parameterisation::ChordLength, Approach::Improved, &o)
                .unwrap();
            let gb = b.dense_geometry(&g);
            assert_eq!(gb.border_gap, 0.0);
            let a =
                fit_two_view(&g, 10, 10, Parameterisation::ChordLength, Approach::Conventional, &o)
                    .unwrap();
            let ga = a.dense_geometry(&g);
            assert!(ga.border_gap >= a.gap && a.gap > 0.0, "{ga:?} {}", a.gap);
            assert!(gb.excursion.is_finite() && gb.max_control > 0.0);
            // The optimiser's view of B gives the same surfaces, so the same measures.
            let parts = b.control_net_parts(&g).unwrap();
            assert_eq!(parts.dense_geometry(&parts.x0), gb);
        }
    }

    #[test]
    fn error_is_zero_when_the_net_is_as_large_as_the_grid() {
        // n_ctrl = n_params: the least squares interpolates every data point.
        let g = test_grid(9, 11, 0.03);
        let a = fit_two_view(
            &g,
            9,
            11,
            Parameterisation::ChordLength,
            Approach::Conventional,
            &FitOptions::default(),
        )
        .unwrap();
        assert!(a.surface_error < 1e-9, "{}", a.surface_error);
    }

    #[test]
    fn bad_sizes_are_refused() {
        let g = test_grid(10, 10, 0.0);
        assert!(fit_two_view(
            &g,
            3,
            8,
            Parameterisation::Uniform,
            Approach::Improved,
            &FitOptions::default()
        )
        .unwrap_err()
        .to_string()
        .contains("smaller than 4"));
        assert!(fit_two_view(
            &g,
            11,
            8,
            Parameterisation::Uniform,
            Approach::Improved,
            &FitOptions::default()
        )
        .unwrap_err()
        .to_string()
        .contains("larger than the grid"));
        let mut bad = g.clone();
        bad.top[17][1] = f64::NAN;
        assert!(fit_two_view(
            &bad,
            6,
            6,
            Parameterisation::Uniform,
            Approach::Improved,
            &FitOptions::default()
        )
        .unwrap_err()
        .to_string()
        .contains("non-finite"));
        let mut bad = g.clone();
        bad.top[0][0] += 1.0;
        assert!(fit_two_view(
            &bad,
            6,
            6,
            Parameterisation::Uniform,
            Approach::Improved,
            &FitOptions::default()
        )
        .unwrap_err()
        .to_string()
        .contains("border position (0, 0)"));
        bad.top.pop();
        assert!(fit_two_view(
            &bad,
            6,
            6,
            Parameterisation::Uniform,
            Approach::Improved,
            &FitOptions::default()
        )
        .is_err());
    }

    #[test]
    fn control_net_parts_reproduce_the_surface_error() {
        let g = test_grid(20, 20, 0.02);
        for cn in [(6, 6), (12, 9), (18, 18)] {
            let b = fit_two_view(
                &g,
                cn.0,
                cn.1,
                Parameterisation::Centripetal,
                Approach::Improved,
                &FitOptions::default(),
            )
            .unwrap();
            let parts = b.control_net_parts(&g).unwrap();
            assert_eq!(parts.x0.len(), 3 * DoubleNet::new(cn.0, cn.1).unwrap().nov());
            let e = parts.surface_error(&parts.x0);
            assert!(
                (e - b.surface_error).abs() <= 1e-12 * b.surface_error,
                "{e} vs {}",
                b.surface_error
            );
        }
    }
}
