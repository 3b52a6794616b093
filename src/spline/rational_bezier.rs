//! Rational quadratic Bezier curves and the four-patch G1 rational bi-quadratic Bezier surface of
//! seed 002 (Yahya): a 5x5 global net p_ij (i, j = 0..4), patch (a, b) uses rows 2a..2a+2 and
//! columns 2b..2b+2. Fixed from the data: p00, p02, p04, p20, p22, p24, p40, p42, p44. Free (the
//! optimiser's variables): p01, p10, p11, p12, p14, p21, p41 and the weight w11. Every other net
//! entry is determined by the joins: across row 2 and column 2 the homogeneous net is reflected,
//! W_3j P_3j = 2 W_2j P_2j - W_1j P_1j and W_3j = 2 W_2j - W_1j (likewise for columns), which makes
//! the homogeneous surface C1 and therefore the rational surface C1, hence G1, across both joins.
//! All weights are 1 except W11 = W33 = w and W13 = W31 = 2 - w, so w must lie in (0, 2).
//! This is exactly the paper's list of free entries (its section 2.1); the reflection rule is our
//! reading, the surviving text stops before its section 3.2. Pure: no I/O.

#![allow(clippy::needless_range_loop)] // index loops over 3x3 nets and coordinates read clearer

use crate::optim::Problem;

/// Quadratic Bernstein basis at t.
#[inline]
pub(crate) fn bernstein2(t: f64) -> [f64; 3] {
    let s = 1.0 - t;
    [s * s, 2.0 * s * t, t * t]
}

/// Rational quadratic Bezier curve (conic) r(t) = (B0 b0 + w B1 b1 + B2 b2) / (B0 + w B1 + B2).
pub(crate) fn conic_point<const D: usize>(b: &[[f64; D]; 3], w: f64, t: f64) -> [f64; D] {
    let bb = bernstein2(t);
    let den = bb[0] + w * bb[1] + bb[2];
    let mut out = [0.0; D];
    for (k, o) in out.iter_mut().enumerate() {
        *o = (bb[0] * b[0][k] + w * bb[1] * b[1][k] + bb[2] * b[2][k]) / den;
    }
    out
}

/// Bi-quadratic rational Bezier patch with 3x3 points and weights, at (u, v): u runs along the
/// first index (rows), v along the second.
#[cfg(test)]
pub(crate) fn patch_point(p: &[[[f64; 3]; 3]; 3], w: &[[f64; 3]; 3], u: f64, v: f64) -> [f64; 3] {
    let bu = bernstein2(u);
    let bv = bernstein2(v);
    let mut num = [0.0; 3];
    let mut den = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            let c = bu[i] * bv[j] * w[i][j];
            den += c;
            for k in 0..3 {
                num[k] += c * p[i][j][k];
            }
        }
    }
    [num[0] / den, num[1] / den, num[2] / den]
}

/// Homogeneous patch value and its u- and v-derivatives (numerator 3-vector and denominator).
#[cfg(test)]
fn patch_homog(
    p: &[[[f64; 3]; 3]; 3],
    w: &[[f64; 3]; 3],
    u: f64,
    v: f64,
    du: usize,
    dv: usize,
) -> ([f64; 3], f64) {
    let basis = |t: f64, d: usize| -> [f64; 3] {
        match d {
            0 => bernstein2(t),
            _ => [-2.0 * (1.0 - t), 2.0 - 4.0 * t, 2.0 * t],
        }
    };
    let bu = basis(u, du);
    let bv = basis(v, dv);
    let mut num = [0.0; 3];
    let mut den = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            let c = bu[i] * bv[j] * w[i][j];
            den += c;
            for k in 0..3 {
                num[k] += c * p[i][j][k];
            }
        }
    }
    (num, den)
}

/// Partial derivatives (S_u, S_v) of a rational patch by the quotient rule.
#[cfg(test)]
pub(crate) fn patch_derivatives(
    p: &[[[f64; 3]; 3]; 3],
    w: &[[f64; 3]; 3],
    u: f64,
    v: f64,
) -> ([f64; 3], [f64; 3]) {
    let (n, d) = patch_homog(p, w, u, v, 0, 0);
    let (nu, du) = patch_homog(p, w, u, v, 1, 0);
    let (nv, dv) = patch_homog(p, w, u, v, 0, 1);
    let mut su = [0.0; 3];
    let mut sv = [0.0; 3];
    for k in 0..3 {
        su[k] = (nu[k] * d - n[k] * du) / (d * d);
        sv[k] = (nv[k] * d - n[k] * dv) / (d * d);
    }
    (su, sv)
}

/// Number of optimisation variables: 7 free points x 3 coordinates + w11.
pub(crate) const FREE_DIM: usize = 22;
/// The free net entries (i, j) in the order of the decision vector.
pub(crate) const FREE_ENTRIES: [(usize, usize); 7] =
    [(0, 1), (1, 0), (1, 1), (1, 2), (1, 4), (2, 1), (4, 1)];
/// The fixed net entries, taken from the data.
pub(crate) const FIXED_ENTRIES: [(usize, usize); 9] =
    [(0, 0), (0, 2), (0, 4), (2, 0), (2, 2), (2, 4), (4, 0), (4, 2), (4, 4)];

/// The four-patch surface: a full 5x5 net and weights.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct FourPatchSurface {
    pub(crate) p: [[[f64; 3]; 5]; 5],
    pub(crate) w: [[f64; 5]; 5],
}

impl FourPatchSurface {
    /// Build the net from the nine fixed points (in `FIXED_ENTRIES` order) and the decision
    /// vector x (7 free points in `FREE_ENTRIES` order, then w11). Requires 0 < w11 < 2.
    pub(crate) fn from_free(fixed: &[[f64; 3]; 9], x: &[f64]) -> FourPatchSurface {
        assert_eq!(x.len(), FREE_DIM, "four-patch surface takes {FREE_DIM} variables");
        let mut p = [[[f64::NAN; 3]; 5]; 5];
        for (k, &(i, j)) in FIXED_ENTRIES.iter().enumerate() {
            p[i][j] = fixed[k];
        }
        for (k, &(i, j)) in FREE_ENTRIES.iter().enumerate() {
            p[i][j] = [x[3 * k], x[3 * k + 1], x[3 * k + 2]];
        }
        let w11 = x[21];
        let mut w = [[1.0; 5]; 5];
        w[1][1] = w11;
        w[3][3] = w11;
        w[1][3] = 2.0 - w11;
        w[3][1] = 2.0 - w11;
        // Homogeneous reflection of entry `a` through `m` into `r`: W_r P_r = 2 W_m P_m - W_a P_a.
        let reflect = |p: &mut [[[f64; 3]; 5]; 5],
                       w: &[[f64; 5]; 5],
                       r: (usize, usize),
                       m: (usize, usize),
                       a: (usize, usize)| {
            for k in 0..3 {
                p[r.0][r.1][k] = (2.0 * w[m.0][m.1] * p[m.0][m.1][k]
                    - w[a.0][a.1] * p[a.0][a.1][k])
                    / w[r.0][r.1];
            }
        };
        // Column 3 from columns 1 and 2 in rows 0, 1, 2, 4.
        for i in [0, 1, 2, 4] {
            reflect(&mut p, &w, (i, 3), (i, 2), (i, 1));
        }
        // Row 3 from rows 1 and 2 (all five columns; column 3 then agrees with the column rule).
        for j in 0..5 {
            reflect(&mut p, &w, (3, j), (2, j), (1, j));
        }
        FourPatchSurface { p, w }
    }

    /// The 3x3 net and weights of patch (a, b), a, b in {0, 1}.
    pub(crate) fn patch(&self, a: usize, b: usize) -> ([[[f64; 3]; 3]; 3], [[f64; 3]; 3]) {
        let mut p = [[[0.0; 3]; 3]; 3];
        let mut w = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                p[i][j] = self.p[2 * a + i][2 * b + j];
                w[i][j] = self.w[2 * a + i][2 * b + j];
            }
        }
        (p, w)
    }

    /// Global parameters (s, t) in [0,1]^2 -> (patch a, patch b, local u, local v).
    pub(crate) fn locate(s: f64, t: f64) -> (usize, usize, f64, f64) {
        let a = if s < 0.5 { 0 } else { 1 };
        let b = if t < 0.5 { 0 } else { 1 };
        (a, b, 2.0 * s - a as f64, 2.0 * t - b as f64)
    }

    /// Surface point at global parameters (s, t) in [0,1]^2.
    #[cfg(test)]
    pub(crate) fn point(&self, s: f64, t: f64) -> [f64; 3] {
        let (a, b, u, v) = Self::locate(s, t);
        let (p, w) = self.patch(a, b);
        patch_point(&p, &w, u, v)
    }
}

/// Sample grid of a height function for the surface problem: n x n points (n odd, >= 5) at
/// uniform global parameters s_i = i/(n-1), t_j = j/(n-1).
#[derive(Debug, Clone)]
pub(crate) struct GridData {
    pub(crate) n: usize,
    /// Row-major, point (i, j) at index i*n + j; i runs along s, j along t.
    pub(crate) points: Vec<[f64; 3]>,
}

impl GridData {
    pub(crate) fn at(&self, i: usize, j: usize) -> [f64; 3] {
        self.points[i * self.n + j]
    }
    /// The data point at global parameter (s, t) on the grid, bilinearly interpolated.
    pub(crate) fn interp(&self, s: f64, t: f64) -> [f64; 3] {
        let m = (self.n - 1) as f64;
        let (fs, ft) = (s * m, t * m);
        let (i0, j0) =
            ((fs.floor() as usize).min(self.n - 2), (ft.floor() as usize).min(self.n - 2));
        let (a, b) = (fs - i0 as f64, ft - j0 as f64);
        let mut out = [0.0; 3];
        for k in 0..3 {
            out[k] = (1.0 - a) * (1.0 - b) * self.at(i0, j0)[k]
                + a * (1.0 - b) * self.at(i0 + 1, j0)[k]
                + (1.0 - a) * b * self.at(i0, j0 + 1)[k]
                + a * b * self.at(i0 + 1, j0 + 1)[k];
        }
        out
    }
}

/// The four test surfaces of SPEC 7 on the domains we chose (the paper gives none): data are the
/// exact function values (no noise) on a uniform n x n grid of the domain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum TestSurface {
    /// f = sin(x) cos(y) + 0.91 on [0, pi]^2 (paper's Surface 1 of Chapter 4).
    Surface1,
    /// f = (1 + 2 exp(-3 (sqrt(x^2+y^2) - 6.7)))^-0.5 on [-10, 10]^2 (Surface 2 of Chapter 4).
    Surface2,
    /// f = 24.234 r2 (0.75 - r2), r2 = (x-0.5)^2 + (y-0.5)^2 on [0, 1]^2 (Surface 1 of Chapter 5).
    Surface3,
    /// f = 2 (x^2 + y^2) on [-1, 1]^2 (Surface 2 of Chapter 5).
    Surface4,
}

impl TestSurface {
    pub(crate) const ALL: [TestSurface; 4] = [
        TestSurface::Surface1,
        TestSurface::Surface2,
        TestSurface::Surface3,
        TestSurface::Surface4,
    ];

    pub(crate) fn by_name(name: &str) -> Option<TestSurface> {
        TestSurface::ALL.into_iter().find(|s| s.name() == name)
    }
    pub(crate) fn name(self) -> &'static str {
        match self {
            TestSurface::Surface1 => "surface1",
            TestSurface::Surface2 => "surface2",
            TestSurface::Surface3 => "surface3",
            TestSurface::Surface4 => "surface4",
        }
    }
    pub(crate) fn formula(self) -> &'static str {
        match self {
            TestSurface::Surface1 => "sin(x)cos(y)+0.91 on [0,pi]^2",
            TestSurface::Surface2 => "(1+2exp(-3(sqrt(x^2+y^2)-6.7)))^-0.5 on [-10,10]^2",
            TestSurface::Surface3 => "24.234 r2(0.75-r2), r2=(x-.5)^2+(y-.5)^2 on [0,1]^2",
            TestSurface::Surface4 => "2(x^2+y^2) on [-1,1]^2",
        }
    }
    /// (lower, upper) of the square domain.
    pub(crate) fn domain(self) -> (f64, f64) {
        match self {
            TestSurface::Surface1 => (0.0, std::f64::consts::PI),
            TestSurface::Surface2 => (-10.0, 10.0),
            TestSurface::Surface3 => (0.0, 1.0),
            TestSurface::Surface4 => (-1.0, 1.0),
        }
    }
    pub(crate) fn eval(self, x: f64, y: f64) -> f64 {
        match self {
            TestSurface::Surface1 => x.sin() * y.cos() + 0.91,
            TestSurface::Surface2 => {
                (1.0 + 2.0 * (-3.0 * ((x * x + y * y).sqrt() - 6.7)).exp()).powf(-0.5)
            }
            TestSurface::Surface3 => {
                let r2 = (x - 0.5).powi(2) + (y - 0.5).powi(2);
                24.234 * r2 * (0.75 - r2)
            }
            TestSurface::Surface4 => 2.0 * (x * x + y * y),
        }
    }
    /// n x n samples; grid index i runs along x, j along y.
    pub(crate) fn grid(self, n: usize) -> GridData {
        let (lo, hi) = self.domain();
        let m = (n - 1) as f64;
        let points = (0..n * n)
            .map(|k| {
                let x = lo + (hi - lo) * (k / n) as f64 / m;
                let y = lo + (hi - lo) * (k % n) as f64 / m;
                [x, y, self.eval(x, y)]
            })
            .collect();
        GridData { n, points }
    }
}

/// Sum of squared errors between the data grid and the four-patch surface at the same
/// parameters; variables: the 7 free points and w11 (22 numbers).
pub(crate) struct SurfaceSse {
    pub(crate) data: GridData,
    pub(crate) fixed: [[f64; 3]; 9],
    /// (patch a, b, Bernstein products bu[i]*bv[j] row-major) per data point, precomputed.
    cache: Vec<(usize, usize, [f64; 9])>,
    x0: Vec<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
}

impl SurfaceSse {
    /// Fixed points from the data at the edges and middles (grid indices 0, (n-1)/2, n-1); the
    /// initial free points are the data at their net positions (s, t) = (i/4, j/4), w11 = 1; the
    /// box is the data's bounding box widened by `margin` times its extent per axis, and
    /// w11 in [w_min, 2 - w_min].
    pub(crate) fn new(data: GridData, margin: f64, w_min: f64) -> SurfaceSse {
        let n = data.n;
        assert!(n >= 5 && n % 2 == 1, "grid size must be odd and >= 5");
        let idx = |e: usize| e * (n - 1) / 4;
        let mut fixed = [[0.0; 3]; 9];
        for (k, &(i, j)) in FIXED_ENTRIES.iter().enumerate() {
            fixed[k] = data.at(idx(i), idx(j));
        }
        let mut x0 = Vec::with_capacity(FREE_DIM);
        for &(i, j) in FREE_ENTRIES.iter() {
            x0.extend_from_slice(&data.interp(i as f64 / 4.0, j as f64 / 4.0));
        }
        x0.push(1.0);
        let mut lo = vec![0.0; FREE_DIM];
        let mut hi = vec![0.0; FREE_DIM];
        for k in 0..3 {
            let mn = data.points.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
            let mx = data.points.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
            let ext = (mx - mn).max(1e-9);
            for f in 0..7 {
                lo[3 * f + k] = mn - margin * ext;
                hi[3 * f + k] = mx + margin * ext;
            }
        }
        lo[21] = w_min;
        hi[21] = 2.0 - w_min;
        let m = (n - 1) as f64;
        let mut cache = Vec::with_capacity(n * n);
        for i in 0..n {
            for j in 0..n {
                let (a, b, u, v) = FourPatchSurface::locate(i as f64 / m, j as f64 / m);
                let (bu, bv) = (bernstein2(u), bernstein2(v));
                let mut c = [0.0; 9];
                for r in 0..3 {
                    for q in 0..3 {
                        c[3 * r + q] = bu[r] * bv[q];
                    }
                }
                cache.push((a, b, c));
            }
        }
        SurfaceSse { data, fixed, cache, x0, lo, hi }
    }

    pub(crate) fn surface(&self, x: &[f64]) -> FourPatchSurface {
        FourPatchSurface::from_free(&self.fixed, x)
    }

    pub(crate) fn n_points(&self) -> usize {
        self.data.points.len()
    }
}

impl Problem for SurfaceSse {
    fn dim(&self) -> usize {
        FREE_DIM
    }
    fn initial_point(&self) -> &[f64] {
        &self.x0
    }
    fn bounds(&self) -> (&[f64], &[f64]) {
        (&self.lo, &self.hi)
    }
    fn fitness(&self, x: &[f64]) -> f64 {
        if !(x[21] > 0.0 && x[21] < 2.0) {
            return f64::INFINITY;
        }
        let s = self.surface(x);
        let patches = [[s.patch(0, 0), s.patch(0, 1)], [s.patch(1, 0), s.patch(1, 1)]];
        let mut sse = 0.0;
        for (d, (a, b, c)) in self.data.points.iter().zip(&self.cache) {
            let (p, w) = &patches[*a][*b];
            let mut num = [0.0; 3];
            let mut den = 0.0;
            for r in 0..3 {
                for q in 0..3 {
                    let cw = c[3 * r + q] * w[r][q];
                    den += cw;
                    for k in 0..3 {
                        num[k] += cw * p[r][q][k];
                    }
                }
            }
            for k in 0..3 {
                let e = num[k] / den - d[k];
                sse += e * e;
            }
        }
        sse
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    }
    fn unit(a: [f64; 3]) -> [f64; 3] {
        let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        [a[0] / n, a[1] / n, a[2] / n]
    }

    fn random_surface(seed: u64) -> FourPatchSurface {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut fixed = [[0.0; 3]; 9];
        for (k, &(i, j)) in FIXED_ENTRIES.iter().enumerate() {
            fixed[k] = [
                i as f64 + rng.gen_range(-0.3..0.3),
                j as f64 + rng.gen_range(-0.3..0.3),
                rng.gen_range(-1.0..1.0),
            ];
        }
        let mut x = Vec::new();
        for &(i, j) in FREE_ENTRIES.iter() {
            x.extend_from_slice(&[
                i as f64 + rng.gen_range(-0.3..0.3),
                j as f64 + rng.gen_range(-0.3..0.3),
                rng.gen_range(-1.0..1.0),
            ]);
        }
        x.push(rng.gen_range(0.3..1.7));
        FourPatchSurface::from_free(&fixed, &x)
    }

    #[test]
    fn g1_across_both_joins_tangent_planes_agree() {
        for seed in 0..5 {
            let s = random_surface(seed);
            for k in 0..=20 {
                let t = k as f64 / 20.0;
                // Join along rows: patch (0,b) at u=1 against patch (1,b) at u=0.
                for b in 0..2 {
                    let (p0, w0) = s.patch(0, b);
                    let (p1, w1) = s.patch(1, b);
                    let a = patch_point(&p0, &w0, 1.0, t);
                    let c = patch_point(&p1, &w1, 0.0, t);
                    for q in 0..3 {
                        assert!((a[q] - c[q]).abs() < 1e-12, "position gap");
                    }
                    let (su0, sv0) = patch_derivatives(&p0, &w0, 1.0, t);
                    let (su1, sv1) = patch_derivatives(&p1, &w1, 0.0, t);
                    let n0 = unit(cross(su0, sv0));
                    let n1 = unit(cross(su1, sv1));
                    for q in 0..3 {
                        assert!(
                            (n0[q] - n1[q]).abs() < 1e-12,
                            "normal differs across row join: {n0:?} {n1:?}"
                        );
                    }
                }
                // Join along columns: patch (a,0) at v=1 against patch (a,1) at v=0.
                for a in 0..2 {
                    let (p0, w0) = s.patch(a, 0);
                    let (p1, w1) = s.patch(a, 1);
                    let (su0, sv0) = patch_derivatives(&p0, &w0, t, 1.0);
                    let (su1, sv1) = patch_derivatives(&p1, &w1, t, 0.0);
                    let n0 = unit(cross(su0, sv0));
                    let n1 = unit(cross(su1, sv1));
                    for q in 0..3 {
                        assert!(
                            (n0[q] - n1[q]).abs() < 1e-12,
                            "normal differs across column join: {n0:?} {n1:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn paraboloid_is_recovered_exactly_by_its_free_points() {
        // f = 2(x^2 + y^2) on [-1,1]^2 is a C1 piecewise quadratic: with knots X_0..X_4 (even =
        // patch ends, odd = midpoints) its Bezier ordinates are 2(cx_i + cy_j), cx = X_i^2 at even
        // i and X_{i-1} X_{i+1} at odd i, w11 = 1. Giving only the seven free points, the joins
        // must rebuild the rest so that the SSE is zero.
        let n = 9;
        let prob = SurfaceSse::new(TestSurface::Surface4.grid(n), 0.25, 0.01);
        let knot = |i: usize| -1.0 + 0.5 * i as f64;
        let c = |i: usize| {
            if i.is_multiple_of(2) {
                knot(i) * knot(i)
            } else {
                knot(i - 1) * knot(i + 1)
            }
        };
        let mut x = Vec::new();
        for &(i, j) in FREE_ENTRIES.iter() {
            x.extend_from_slice(&[knot(i), knot(j), 2.0 * (c(i) + c(j))]);
        }
        x.push(1.0);
        assert!(prob.fitness(&x) < 1e-26, "{}", prob.fitness(&x));
        // A wrong free ordinate is seen.
        x[2] += 1e-3;
        assert!(prob.fitness(&x) > 1e-9);
    }

    #[test]
    fn rational_quadratic_reproduces_circular_arc() {
        // Arc of radius 2 centred at the origin, half-angle theta: b1 on the tangents'
        // intersection, w = cos(theta).
        for &theta in &[0.3f64, 0.7, 1.2] {
            let r = 2.0;
            let b = [
                [r * theta.cos(), -r * theta.sin()],
                [r / theta.cos(), 0.0],
                [r * theta.cos(), r * theta.sin()],
            ];
            for k in 0..=50 {
                let p = conic_point(&b, theta.cos(), k as f64 / 50.0);
                let rad = (p[0] * p[0] + p[1] * p[1]).sqrt();
                assert!((rad - r).abs() < 1e-13, "radius {rad}");
            }
        }
    }

    #[test]
    fn bilinear_data_is_recovered_exactly_and_fitness_matches_direct_sum() {
        // A plane is reproduced by a polynomial net whose free points lie on it (w11 = 1).
        let n = 9;
        let plane = |s: f64, t: f64| [3.0 * s, 2.0 * t, 0.5 + s - 2.0 * t];
        let m = (n - 1) as f64;
        let points = (0..n * n).map(|k| plane((k / n) as f64 / m, (k % n) as f64 / m)).collect();
        let prob = SurfaceSse::new(GridData { n, points }, 0.1, 0.01);
        assert!(prob.fitness(prob.initial_point()) < 1e-24);
        // Any other point: fitness equals the direct sum through FourPatchSurface::point.
        let mut x = prob.initial_point().to_vec();
        x[2] += 0.3;
        x[7] -= 0.2;
        x[21] = 1.4;
        let s = prob.surface(&x);
        let mut direct = 0.0;
        for i in 0..n {
            for j in 0..n {
                let p = s.point(i as f64 / m, j as f64 / m);
                let d = plane(i as f64 / m, j as f64 / m);
                direct += (0..3).map(|k| (p[k] - d[k]).powi(2)).sum::<f64>();
            }
        }
        let f = prob.fitness(&x);
        assert!(f > 1e-6 && (f - direct).abs() < 1e-12 * direct.max(1.0), "{f} vs {direct}");
        assert_eq!(
            prob.fitness(&{
                let mut y = x.clone();
                y[21] = 2.0;
                y
            }),
            f64::INFINITY
        );
    }
}
