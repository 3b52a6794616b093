//! The thesis' control-net problem (Chapter 6; fitness Eq. 6.2 = Eq. 5.13) with a fitness fast
//! enough for 80 000 - 160 000 evaluations per run.
//!
//! Decision vector: the distinct control points of the double control net, one per 0-based
//! control-net class, xyz interleaved (thesis Fig. 6.2). The fitted surface of view V at grid
//! point (i, j) is sum_ab Nu[i][a] Nv[j][b] P_V[a][b], and only 4 x 4 control points are
//! non-zero there, so the surface is the separable sparse tensor product Nu (P Nv^T) done in two
//! passes of four scaled rows each. A band product can be vectorised only across the index it
//! does not reduce, and the two passes reduce different axes, so one transpose is unavoidable:
//! the first pass runs along control rows (contiguous in x), its result is transposed once, and
//! the second pass and the distances run with grid rows i as vector lanes (structure of arrays:
//! x, y, z apart; chunks of 4 lanes, padded with zeros), accumulating per lane in registers. No
//! allocation per call; the summation order is fixed, and every multiply-add is fused
//! (`f64::mul_add`: one rounding, a hardware instruction in the AVX2 + FMA copy and the C
//! library's `fma` in the baseline copy), so the copies (in [`crate::simd::fitness`], picked
//! at run time: baseline, AVX2; `SOMNURBS_SIMD` forces one) give bit-identical results.
//!
//! A border grid class is scored once, on the bottom view (Eq. 5.13): the top view is evaluated
//! at its interior grid points only. The top view's control points are read in place: its
//! border classes are the bottom's, so the border columns of its first pass are the bottom's.

use super::{ControlNetParts, SparseBasis};
use crate::double_net::{DoubleNet, TwoViewGrid, View};
use crate::geom::Point3;
use crate::optim::aligned::Aligned;
use crate::optim::exact::{solve_exact, ExactOptions, ExactResult, SumOfNorms, Term};
use crate::optim::problem::Problem;
use crate::optim::OptimError;
use crate::simd::fitness::{padded, CHUNK};
use std::cell::RefCell;
use std::ops::Range;

/// The search box of the control-point coordinates, per axis.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum BoxSpec {
    /// Min/max of the grid data per axis (thesis: "the range of the dataset").
    #[default]
    DataRange,
    /// The data range grown by `fraction` of its width on each side.
    Widened { fraction: f64 },
    /// The smallest box holding the data and the initial control points x0, grown by
    /// `fraction` of its width on each side: x0 is always feasible (the data range alone can cut
    /// through approach B's control points, which a cubic fit places outside the data near
    /// the ends and for near-square nets).
    Cover { fraction: f64 },
    /// An explicit box.
    Axes { lower: Point3, upper: Point3 },
    /// Every coordinate within `half_width` of its value in x0 (approach B): the thesis' reading
    /// of Table 6.1's "control point coordinate range [-5e-6, 5e-6]", a search space around B.
    AroundStart { half_width: f64 },
}

pub(crate) use crate::simd::Isa;

/// The control-net problem: minimise Eq. 6.2 over the distinct control points inside a box.
#[derive(Debug, Clone)]
pub struct ControlNetProblem {
    pub(crate) parts: ControlNetParts,
    net: DoubleNet,
    lower: Aligned,
    upper: Aligned,
    box_axes: (Point3, Point3),
    /// The grid data's box per coordinate (min, max along the coordinate's axis): the thesis'
    /// "range of the dataset" ([`Problem::data_range`]).
    data_lower: Aligned,
    data_upper: Aligned,
    /// Grid data, per grid column j, per coordinate, over the lanes i: bottom all (i, j), top
    /// the interior only.
    pub(crate) data_b: Aligned,
    pub(crate) data_t: Aligned,
    pub(crate) isa: Isa,
    /// Sparse rows of the sum-of-norms form (16 control points per grid class).
    term_points: Vec<[usize; 16]>,
    term_coef: Vec<[f64; 16]>,
    term_data: Vec<Point3>,
}

pub(crate) use crate::simd::fitness::Scratch;

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

fn finite(p: &Point3) -> bool {
    p.iter().all(|v| v.is_finite())
}

fn check_basis(
    name: &str,
    b: &SparseBasis,
    n_grid: usize,
    n_ctrl: usize,
) -> Result<(), OptimError> {
    if b.first.len() != n_grid || b.w.len() != n_grid {
        return Err(OptimError::ControlNet(format!(
            "{name} must have {n_grid} entries (one per grid index), has {} first indices and {} weight sets",
            b.first.len(),
            b.w.len()
        )));
    }
    for (k, (&f, w)) in b.first.iter().zip(&b.w).enumerate() {
        if f + 4 > n_ctrl {
            return Err(OptimError::ControlNet(format!(
                "{name}[{k}]: first basis index {f} + 4 exceeds {n_ctrl} control points"
            )));
        }
        if !w.iter().all(|v| v.is_finite()) {
            return Err(OptimError::ControlNet(format!(
                "{name}[{k}]: weights {w:?} are not finite"
            )));
        }
    }
    Ok(())
}

/// Check that the parts of a control-net problem fit together.
fn validate_parts(p: &ControlNetParts) -> Result<(), OptimError> {
    if p.nx < 2 || p.ny < 2 {
        return Err(OptimError::ControlNet(format!("grid {}x{} is smaller than 2x2", p.nx, p.ny)));
    }
    if p.cn_x < 4 || p.cn_y < 4 {
        return Err(OptimError::ControlNet(format!(
            "control net {}x{} is smaller than 4x4 (cubic)",
            p.cn_x, p.cn_y
        )));
    }
    check_basis("nu", &p.nu, p.nx, p.cn_x)?;
    check_basis("nv", &p.nv, p.ny, p.cn_y)?;
    for (name, d) in [("data_bottom", &p.data_bottom), ("data_top", &p.data_top)] {
        if d.len() != p.nx * p.ny {
            return Err(OptimError::ControlNet(format!(
                "{name} has {} points, the {}x{} grid needs {}",
                d.len(),
                p.nx,
                p.ny,
                p.nx * p.ny
            )));
        }
        if let Some(k) = d.iter().position(|p| !finite(p)) {
            return Err(OptimError::ControlNet(format!("{name}[{k}] = {:?} is not finite", d[k])));
        }
    }
    let nov = 2 * (p.cn_x * p.cn_y - p.cn_x - p.cn_y + 2);
    if p.x0.len() != 3 * nov {
        return Err(OptimError::ControlNet(format!(
            "x0 has {} values, a {}x{} double control net has NOV = {nov} classes, so 3 * NOV = {}",
            p.x0.len(),
            p.cn_x,
            p.cn_y,
            3 * nov
        )));
    }
    if let Some(k) = p.x0.iter().position(|v| !v.is_finite()) {
        return Err(OptimError::ControlNet(format!("x0[{k}] = {} is not finite", p.x0[k])));
    }
    Ok(())
}

/// The search box per axis (lower, upper) of `bounds`, from the data's box `data` and the start
/// `x0` (xyz interleaved).
fn box_axes(
    bounds: BoxSpec,
    data: ([f64; 3], [f64; 3]),
    x0: &[f64],
) -> Result<([f64; 3], [f64; 3]), OptimError> {
    let (dlo, dhi) = data;
    Ok(match bounds {
        BoxSpec::DataRange => (dlo, dhi),
        BoxSpec::Widened { fraction } | BoxSpec::Cover { fraction } => {
            if !(fraction >= 0.0 && fraction.is_finite()) {
                return Err(OptimError::param(
                    "bounds.fraction",
                    format!("must be finite and >= 0, got {fraction}"),
                ));
            }
            let (mut lo, mut hi) = (dlo, dhi);
            if matches!(bounds, BoxSpec::Cover { .. }) {
                for (k, &v) in x0.iter().enumerate() {
                    lo[k % 3] = lo[k % 3].min(v);
                    hi[k % 3] = hi[k % 3].max(v);
                }
            }
            for a in 0..3 {
                let w = hi[a] - lo[a];
                lo[a] -= fraction * w;
                hi[a] += fraction * w;
            }
            (lo, hi)
        }
        BoxSpec::AroundStart { half_width } => {
            if !(half_width > 0.0 && half_width.is_finite()) {
                return Err(OptimError::param(
                    "search_range",
                    format!("must be finite and > 0, got {half_width}"),
                ));
            }
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for (k, &v) in x0.iter().enumerate() {
                lo[k % 3] = lo[k % 3].min(v - half_width);
                hi[k % 3] = hi[k % 3].max(v + half_width);
            }
            (lo, hi)
        }
        BoxSpec::Axes { lower, upper } => {
            if let Some(a) =
                (0..3).find(|&a| lower[a].partial_cmp(&upper[a]).is_none_or(|o| o.is_gt()))
            {
                return Err(OptimError::param(
                    "bounds",
                    format!("axis {a}: lower {} is not <= upper {}", lower[a], upper[a]),
                ));
            }
            (lower, upper)
        }
    })
}

impl ControlNetProblem {
    /// Check the parts, lay out the kernel's data and build the box.
    pub fn new(parts: ControlNetParts, bounds: BoxSpec) -> Result<ControlNetProblem, OptimError> {
        validate_parts(&parts)?;
        let net =
            DoubleNet::new(parts.cn_x, parts.cn_y).expect("control net checked to be at least 4x4");
        let (nx, ny) = (parts.nx, parts.ny);
        let all: Vec<Point3> = parts.data_bottom.iter().chain(&parts.data_top).copied().collect();
        let (dlo, dhi) = crate::geom::bounding_box(&all).expect("grid has points");
        let box_axes = box_axes(bounds.clone(), (dlo, dhi), &parts.x0)?;
        let nov = net.nov();
        let (lower, upper): (Vec<f64>, Vec<f64>) = match bounds {
            BoxSpec::AroundStart { half_width } => {
                parts.x0.iter().map(|&v| (v - half_width, v + half_width)).unzip()
            }
            _ => (
                (0..3 * nov).map(|k| box_axes.0[k % 3]).collect(),
                (0..3 * nov).map(|k| box_axes.1[k % 3]).collect(),
            ),
        };
        // Grid data chunk-major: [chunk of CHUNK grid rows][grid column][xyz][lane], zero padded.
        let layout = |d: &[Point3], rows: Range<usize>, cols: Range<usize>| {
            let (lanes, nc) = (rows.len(), cols.len());
            let mut out = Aligned::zeros(padded(lanes) * nc * 3);
            for (lj, j) in cols.enumerate() {
                for c in 0..3 {
                    for (li, i) in rows.clone().enumerate() {
                        let (ch, l) = (li / CHUNK, li % CHUNK);
                        out[((ch * nc + lj) * 3 + c) * CHUNK + l] = d[i * ny + j][c];
                    }
                }
            }
            out
        };
        let data_b = layout(&parts.data_bottom, 0..nx, 0..ny);
        let data_t = layout(&parts.data_top, 1..nx - 1, 1..ny - 1);
        // Sum-of-norms rows, in grid class order (bottom all, then top interior).
        let mut term_points = Vec::new();
        let mut term_coef = Vec::new();
        let mut term_data = Vec::new();
        for (view, data) in [(View::Bottom, &parts.data_bottom), (View::Top, &parts.data_top)] {
            for i in 0..nx {
                for j in 0..ny {
                    let border = i == 0 || j == 0 || i + 1 == nx || j + 1 == ny;
                    if view == View::Top && border {
                        continue;
                    }
                    let (fu, fv) = (parts.nu.first[i], parts.nv.first[j]);
                    let mut pts = [0usize; 16];
                    let mut cf = [0.0; 16];
                    for ta in 0..4 {
                        for tb in 0..4 {
                            pts[ta * 4 + tb] = net.class(view, fu + ta, fv + tb);
                            cf[ta * 4 + tb] = parts.nu.w[i][ta] * parts.nv.w[j][tb];
                        }
                    }
                    term_points.push(pts);
                    term_coef.push(cf);
                    term_data.push(data[i * ny + j]);
                }
            }
        }
        Ok(ControlNetProblem {
            parts,
            net,
            lower: Aligned::from_slice(&lower),
            upper: Aligned::from_slice(&upper),
            box_axes,
            data_lower: (0..3 * nov).map(|k| dlo[k % 3]).collect(),
            data_upper: (0..3 * nov).map(|k| dhi[k % 3]).collect(),
            data_b,
            data_t,
            isa: crate::simd::simd()?,
            term_points,
            term_coef,
            term_data,
        })
    }

    /// Use another compiled copy of the kernel (ignored if this CPU lacks it); for tests and
    /// measurements.
    pub fn with_isa(mut self, isa: Isa) -> ControlNetProblem {
        if isa.supported() {
            self.isa = isa;
        }
        self
    }

    pub fn isa(&self) -> Isa {
        self.isa
    }

    pub fn parts(&self) -> &ControlNetParts {
        &self.parts
    }

    /// SHA-256 of everything the fitness (Eq. 6.2) and the search box depend on: the grid data,
    /// the net's size, the basis at the data parameters, the start x0 and the box. Two problems
    /// with the same digest give every optimiser the same run (the kernel copy, `isa`, gives
    /// the same bits and is left out).
    pub fn digest(&self) -> [u8; 32] {
        use sha2::{Digest, Sha256};
        let mut h = Sha256::new();
        let mut floats = |name: &str, v: &[f64]| {
            h.update(name.as_bytes());
            h.update((v.len() as u64).to_le_bytes());
            for x in v {
                h.update(x.to_bits().to_le_bytes());
            }
        };
        let p = &self.parts;
        let sizes = [p.nx, p.ny, p.cn_x, p.cn_y].map(|n| n as f64);
        floats("sizes", &sizes);
        for (name, pts) in [("bottom", &p.data_bottom), ("top", &p.data_top)] {
            floats(name, &pts.iter().flatten().copied().collect::<Vec<_>>());
        }
        for (name, b) in [("nu", &p.nu), ("nv", &p.nv)] {
            floats(name, &b.first.iter().map(|&f| f as f64).collect::<Vec<_>>());
            floats(name, &b.w.iter().flatten().copied().collect::<Vec<_>>());
        }
        floats("x0", &p.x0);
        floats("lower", &self.lower);
        floats("upper", &self.upper);
        floats("box", &[self.box_axes.0, self.box_axes.1].concat());
        h.finalize().into()
    }

    /// The class layout of the double control net.
    pub fn net(&self) -> &DoubleNet {
        &self.net
    }

    /// The search box per axis (lower, upper); for `AroundStart`, the hull of the per-coordinate
    /// boxes.
    pub fn box_axes(&self) -> (Point3, Point3) {
        self.box_axes
    }

    /// How many coordinates of x0 lie outside the box (they are clamped in the initial
    /// population; a box that cuts x0 changes the problem, so report it).
    pub fn initial_outside_box(&self) -> usize {
        self.parts
            .x0
            .iter()
            .enumerate()
            .filter(|(k, v)| **v < self.lower[*k] || **v > self.upper[*k])
            .count()
    }

    /// Eq. 6.2 with caller-owned scratch (no thread-local look-up). NaN if `x` has the wrong
    /// length.
    pub fn fitness_with(&self, x: &[f64], scratch: &mut Scratch) -> f64 {
        if x.len() != self.lower.len() {
            return f64::NAN;
        }
        crate::simd::fitness::fitness(self, x, scratch)
    }

    /// The exact optimum of Eq. 6.2 inside this problem's box, from x0 (clamped), with its
    /// certificate (see `exact`).
    pub fn exact_optimum(&self, opts: &ExactOptions) -> Result<ExactResult, OptimError> {
        solve_exact(self, &self.lower, &self.upper, &self.parts.x0, opts)
    }

    /// The fitted surface points D^G of both views (row-major, i * ny + j) for control points x.
    pub fn surface(&self, x: &[f64]) -> TwoViewGrid {
        let p = &self.parts;
        let mut out = [vec![[0.0; 3]; p.nx * p.ny], vec![[0.0; 3]; p.nx * p.ny]];
        for (v, view) in View::BOTH.iter().enumerate() {
            for i in 0..p.nx {
                for j in 0..p.ny {
                    let mut s = [0.0; 3];
                    for ta in 0..4 {
                        for tb in 0..4 {
                            let w = p.nu.w[i][ta] * p.nv.w[j][tb];
                            let cl = self.net.class(*view, p.nu.first[i] + ta, p.nv.first[j] + tb);
                            for c in 0..3 {
                                s[c] += w * x[3 * cl + c];
                            }
                        }
                    }
                    out[v][i * p.ny + j] = s;
                }
            }
        }
        let [bottom, top] = out;
        TwoViewGrid { nx: p.nx, ny: p.ny, bottom, top }
    }
}

impl Problem for ControlNetProblem {
    fn dim(&self) -> usize {
        self.lower.len()
    }

    fn initial_point(&self) -> &[f64] {
        &self.parts.x0
    }

    fn bounds(&self) -> (&[f64], &[f64]) {
        (&self.lower, &self.upper)
    }

    fn data_range(&self) -> Option<(&[f64], &[f64])> {
        Some((&self.data_lower, &self.data_upper))
    }

    fn fitness(&self, x: &[f64]) -> f64 {
        SCRATCH.with(|s| self.fitness_with(x, &mut s.borrow_mut()))
    }
}

impl SumOfNorms for ControlNetProblem {
    fn n_points(&self) -> usize {
        self.net.nov()
    }

    fn n_terms(&self) -> usize {
        self.term_data.len()
    }

    fn term(&self, k: usize) -> Term<'_> {
        Term { points: &self.term_points[k], coefs: &self.term_coef[k], data: self.term_data[k] }
    }

    /// Elimination order with a narrow profile: the double net is a closed surface (two discs
    /// glued along their border), cut into slices across its longer control-net axis; each slice
    /// is a ring of about 2 x (shorter side) points, and a point couples only with points at most
    /// 3 slices away.
    fn point_order(&self) -> Option<Vec<usize>> {
        let (cx, cy) = (self.parts.cn_x, self.parts.cn_y);
        let net = &self.net;
        let mut order = Vec::with_capacity(net.nov());
        let mut seen = vec![false; net.nov()];
        let mut push = |c: usize, order: &mut Vec<usize>| {
            if !seen[c] {
                seen[c] = true;
                order.push(c);
            }
        };
        if cx >= cy {
            for a in 0..cx {
                for b in 0..cy {
                    push(net.class(View::Bottom, a, b), &mut order);
                }
                for b in (0..cy).rev() {
                    push(net.class(View::Top, a, b), &mut order);
                }
            }
        } else {
            for b in 0..cy {
                for a in 0..cx {
                    push(net.class(View::Bottom, a, b), &mut order);
                }
                for a in (0..cx).rev() {
                    push(net.class(View::Top, a, b), &mut order);
                }
            }
        }
        Some(order)
    }
}

/// Synthetic control-net problems for tests: the spline module's lumpy two-view test grid, fitted
/// by approach B (chord length), shared by the tests of this module and of `exact`.
#[cfg(test)]
pub(crate) mod test_support {
    use super::*;
    use crate::spline::{fit_two_view, Approach, Parameterisation};

    /// Approach B's parts for a `cn_x` x `cn_y` net on an `nx` x `ny` test grid.
    pub(crate) fn test_parts(nx: usize, ny: usize, cn_x: usize, cn_y: usize) -> ControlNetParts {
        let grid = crate::spline::approach::tests::test_grid(nx, ny, 0.02);
        let fit = fit_two_view(
            &grid,
            cn_x,
            cn_y,
            Parameterisation::ChordLength,
            Approach::Improved,
            &Default::default(),
        )
        .expect("test fit");
        fit.control_net_parts(&grid).expect("approach B")
    }

    /// The control-net problem of [`test_parts`] in the given box.
    pub(crate) fn sphere_problem(
        nx: usize,
        ny: usize,
        cn_x: usize,
        cn_y: usize,
        bounds: BoxSpec,
    ) -> ControlNetProblem {
        ControlNetProblem::new(test_parts(nx, ny, cn_x, cn_y), bounds).unwrap()
    }
}

#[cfg(test)]
mod tests {
    use super::test_support::*;
    use super::*;

    /// The obvious reference: every grid class of Eq. 5.13, each surface point as the dense
    /// double sum over all control points of the view.
    fn dense_reference(pb: &ControlNetProblem, x: &[f64]) -> f64 {
        let p = pb.parts();
        let net = pb.net();
        let dense = |b: &SparseBasis, g: usize, a: usize| {
            let f = b.first[g];
            if a >= f && a < f + 4 {
                b.w[g][a - f]
            } else {
                0.0
            }
        };
        let mut total = 0.0;
        for (view, data) in [(View::Bottom, &p.data_bottom), (View::Top, &p.data_top)] {
            for i in 0..p.nx {
                for j in 0..p.ny {
                    let border = i == 0 || j == 0 || i + 1 == p.nx || j + 1 == p.ny;
                    if view == View::Top && border {
                        continue;
                    }
                    let mut s = [0.0; 3];
                    for a in 0..p.cn_x {
                        for b in 0..p.cn_y {
                            let w = dense(&p.nu, i, a) * dense(&p.nv, j, b);
                            let cl = net.class(view, a, b);
                            for c in 0..3 {
                                s[c] += w * x[3 * cl + c];
                            }
                        }
                    }
                    total += crate::geom::dist(s, data[i * p.ny + j]);
                }
            }
        }
        total
    }

    #[test]
    fn fast_fitness_equals_the_dense_reference() {
        for (nx, ny, cx, cy) in
            [(20, 20, 18, 18), (18, 30, 16, 28), (9, 7, 4, 5), (5, 5, 4, 4), (4, 4, 4, 4)]
        {
            let pb = sphere_problem(nx, ny, cx, cy, BoxSpec::DataRange);
            let mut x = pb.initial_point().to_vec();
            for (k, v) in x.iter_mut().enumerate() {
                *v += 1e-3 * ((k * 7919) % 101) as f64 / 101.0;
            }
            for xs in [pb.initial_point().to_vec(), x] {
                let want = dense_reference(&pb, &xs);
                for isa in Isa::ALL {
                    let q = pb.clone().with_isa(isa);
                    let got = q.fitness(&xs);
                    // 1e-12 relative; near interpolation (least-squares x0 of a large net) the
                    // sum itself is ~1e-5 and both sides carry ~1e-16 absolute rounding per term.
                    let tol = 1e-12 * want + 1e-15 * pb.n_terms() as f64;
                    assert!(
                        (got - want).abs() < tol,
                        "{nx}x{ny} cn {cx}x{cy} {isa:?}: {got} vs {want}"
                    );
                }
            }
        }
    }

    #[test]
    fn surface_and_sum_of_norms_agree_with_the_fitness() {
        let pb = sphere_problem(12, 10, 6, 5, BoxSpec::DataRange);
        let x = pb.initial_point();
        let TwoViewGrid { bottom: sb, top: st, .. } = pb.surface(x);
        let p = pb.parts();
        // Border grid points of the two views coincide (shared border classes).
        for i in 0..p.nx {
            for j in 0..p.ny {
                if i == 0 || j == 0 || i + 1 == p.nx || j + 1 == p.ny {
                    assert!(crate::geom::dist(sb[i * p.ny + j], st[i * p.ny + j]) < 1e-14);
                }
            }
        }
        let mut r = vec![[0.0; 3]; pb.n_terms()];
        pb.residuals(x, &mut r);
        let f: f64 = r.iter().map(|v| crate::geom::norm(*v)).sum();
        assert!((f - pb.fitness(x)).abs() < 1e-12 * f);
        assert_eq!(pb.n_terms(), DoubleNet::new(p.nx, p.ny).unwrap().nov());
        let order = pb.point_order().unwrap();
        let mut sorted = order.clone();
        sorted.sort();
        assert_eq!(sorted, (0..pb.n_points()).collect::<Vec<_>>());
    }

    #[test]
    fn box_defaults_to_the_data_range_and_can_widen() {
        let pb = sphere_problem(10, 10, 6, 6, BoxSpec::DataRange);
        let (lo, hi) = pb.box_axes();
        let all: Vec<Point3> =
            pb.parts().data_bottom.iter().chain(&pb.parts().data_top).copied().collect();
        assert_eq!(crate::geom::bounding_box(&all).unwrap(), (lo, hi));
        let (l, u) = pb.bounds();
        assert_eq!((l[4], u[4]), (lo[1], hi[1]));
        let wide =
            ControlNetProblem::new(pb.parts().clone(), BoxSpec::Widened { fraction: 0.5 }).unwrap();
        let (wl, wh) = wide.box_axes();
        for a in 0..3 {
            assert!((wh[a] - wl[a] - 2.0 * (hi[a] - lo[a])).abs() < 1e-12);
        }
        assert!(wide.initial_outside_box() <= pb.initial_outside_box());
        // Cover always holds x0; with fraction 0 it is the hull of data and x0 per axis.
        let big = sphere_problem(20, 20, 18, 18, BoxSpec::DataRange);
        assert!(
            big.initial_outside_box() > 0,
            "a near-square least-squares net overshoots the data"
        );
        let cover =
            ControlNetProblem::new(big.parts().clone(), BoxSpec::Cover { fraction: 0.0 }).unwrap();
        assert_eq!(cover.initial_outside_box(), 0);
        let (cl, ch) = cover.box_axes();
        let x0 = big.initial_point();
        for a in 0..3 {
            let lo = x0.iter().skip(a).step_by(3).fold(big.box_axes().0[a], |m, &v| m.min(v));
            let hi = x0.iter().skip(a).step_by(3).fold(big.box_axes().1[a], |m, &v| m.max(v));
            assert_eq!((cl[a], ch[a]), (lo, hi));
        }
    }

    #[test]
    fn box_around_the_start_holds_each_coordinate_near_b() {
        let pb = sphere_problem(10, 10, 6, 6, BoxSpec::AroundStart { half_width: 5e-6 });
        let (lo, hi) = pb.bounds();
        for (k, &v) in pb.initial_point().iter().enumerate() {
            assert_eq!((lo[k], hi[k]), (v - 5e-6, v + 5e-6));
        }
        assert_eq!(pb.initial_outside_box(), 0);
        assert!(ControlNetProblem::new(
            pb.parts().clone(),
            BoxSpec::AroundStart { half_width: 0.0 }
        )
        .unwrap_err()
        .to_string()
        .contains("search_range"));
    }

    #[test]
    fn malformed_parts_are_named() {
        let pb = sphere_problem(6, 6, 4, 4, BoxSpec::DataRange);
        let mut parts = pb.parts().clone();
        parts.x0.pop();
        let e = ControlNetProblem::new(parts, BoxSpec::DataRange).unwrap_err().to_string();
        assert!(e.contains("x0 has 59 values") && e.contains("NOV = 20"), "{e}");
        let mut parts = pb.parts().clone();
        parts.nu.first[2] = 1;
        let e = ControlNetProblem::new(parts, BoxSpec::DataRange).unwrap_err().to_string();
        assert!(e.contains("nu[2]"), "{e}");
        let mut parts = pb.parts().clone();
        parts.data_top[5][1] = f64::NAN;
        let e = ControlNetProblem::new(parts, BoxSpec::DataRange).unwrap_err().to_string();
        assert!(e.contains("data_top[5]"), "{e}");
        let e = ControlNetProblem::new(
            pb.parts().clone(),
            BoxSpec::Axes { lower: [0.0; 3], upper: [1.0, -1.0, 1.0] },
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("axis 1"), "{e}");
        assert!(pb.fitness(&[0.0; 5]).is_nan());
    }
}
