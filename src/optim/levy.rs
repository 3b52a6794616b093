//! Cuckoo search's Levy factors by a quantile table: one 32-bit uniform, one table look-up and a
//! cubic per coordinate, no transcendental call.
//!
//! The flight's factor is L = sigma_u T with T = u psi / |v|^(1/beta), u, psi, v independent
//! N(0, 1) (Mantegna's step u / |v|^(1/beta) times the flight's own normal psi). T is symmetric;
//! its magnitude has the CDF G(t) = P(|T| <= t) = E_v[P(|u psi| <= t |v|^(1/beta))], where the
//! product of two normals has |u psi| = E |sin theta| in law (Box-Muller), so
//! P(|u psi| > c) = (2/pi) int_0^(pi/2) exp(-c / sin theta) d theta, which the substitution
//! theta = 2 atan(e^s) (sin theta = sech s, d theta = sech s ds) makes a doubly decaying
//! integral (1/pi) int exp(-c cosh s) sech s ds on the whole line, done by the trapezoid rule
//! ([`product_cdf`]). The outer expectation is over y = ln|v| (density
//! sqrt(2/pi) exp(y - e^(2y)/2)), again by the trapezoid rule, on a log-t grid whose step is the
//! y step over beta, so every c = t |v|^(1/beta) lies on one log-c grid and G on the whole grid is
//! a discrete convolution ([`CdfGrid`]). Both tails are kept apart (P(|T| <= t) and P(|T| > t)
//! each summed from positive terms), so tiny probabilities keep their relative accuracy.
//!
//! Sampling ([`LevyTable`]): a 32-bit field is a sign bit (bit 31), a side bit (bit 30: the lower
//! or the upper tail of |T|) and 30 bits k giving r' = (k + 1/2) 2^-30 in (0, 1); the tail
//! probability is r'/2. The f64 r' itself is the per-octave grid: its exponent (31 octaves,
//! 2^-31 .. 2^-1) and the top 5 mantissa bits pick one of 31 x 32 segments per side, the other
//! mantissa bits are the fraction f in [0, 1), and the segment's cubic in f (fitted at four
//! Chebyshev points to the exact quantiles) gives |T|. Every r' the 30 bits can give lies in the
//! table, the deepest octave down to tail probability 2^-32, so no asymptotic formula is needed.
//! Per side 992 segments of 4 coefficients: 63 KB for both. The cubic errs below about 1e-7
//! relative, the quadrature far less.
//!
//! The factors themselves (the portable copy and its AVX2 copy, one flight in one pass) are drawn
//! in [`crate::simd::levy`], the fast paths' home, from this module's [`LevyTable`].

// Index loops over the chunk's parallel arrays read more plainly than zipped iterators here.
#![allow(clippy::needless_range_loop)]

use std::sync::{Arc, Mutex};

/// Coordinates per chunk of words (a whole chunk of words is drawn even when fewer are needed).
pub(crate) const CHUNK: usize = 128;
pub(crate) const HALF: usize = CHUNK / 2;

pub(crate) const ONE: u64 = 0x3ff0_0000_0000_0000;
pub(crate) const MANT: u64 = (1 << 52) - 1;
/// The 30 bits k of a field.
pub(crate) const K_MASK: u64 = (1 << 30) - 1;
/// 2^-31: half the step of a 30-bit uniform.
pub(crate) const HALF_STEP_30: f64 = 1.0 / (1u64 << 31) as f64;
/// Segments per octave (the top 5 mantissa bits of r').
pub(crate) const SEG_BITS: u32 = 5;
pub(crate) const SEGS: usize = 1 << SEG_BITS;
/// Octaves of r': exponents -31 ..= -1.
const OCTAVES: usize = 31;
/// Biased exponent of the first octave (2^-31).
pub(crate) const FIRST_EXP: u64 = 1023 - 31;
/// Segments per side.
pub(crate) const SIDE: usize = OCTAVES * SEGS;
/// Table rows (both sides, padded to a power of two so that the index mask bounds it).
pub(crate) const TABLE_LEN: usize = 2048;

/// Trapezoid step in s of [`product_cdf`] and in y = ln|v| of the outer integral (both
/// integrands are analytic in strips of half-width pi/2 and pi/4: errors near exp(-pi^2 / 0.3)
/// = 5e-15 and exp(-2 pi (pi/4) / 0.1) = 4e-22 relative).
const H_S: f64 = 0.3;
const H_Y: f64 = 0.1;
/// The top of the y range of the outer integral (the density of ln|v| is below 1e-300 above);
/// the bottom is [`y_min`].
const Y_MAX: f64 = 3.6;
/// The ln t range of the grid: G(t) < 1e-12 below, 1 - G(t) < 2^-34 above (ln t > 30/beta + 3).
const LN_T_MIN: f64 = -32.0;

/// The s nodes of [`product_cdf`]: cosh s_k, the trapezoid weights (1 or 2) sech s_k and the
/// sums of the weights from k on (s_k = k H_S up to 700).
#[derive(Debug, Clone)]
pub(crate) struct SechNodes {
    cosh: Vec<f64>,
    weight: Vec<f64>,
    suffix: Vec<f64>,
}

impl SechNodes {
    /// The nodes up to s = 700.
    pub(crate) fn new() -> SechNodes {
        let n = (700.0 / H_S) as usize;
        let cosh: Vec<f64> = (0..=n).map(|k| (k as f64 * H_S).cosh()).collect();
        let weight: Vec<f64> =
            cosh.iter().enumerate().map(|(k, c)| if k == 0 { 1.0 } else { 2.0 } / c).collect();
        let mut suffix = vec![0.0; n + 2];
        for k in (0..=n).rev() {
            suffix[k] = suffix[k + 1] + weight[k];
        }
        SechNodes { cosh, weight, suffix }
    }

    /// (P(|u psi| <= c), P(|u psi| > c)) for independent standard normals u, psi:
    /// P(|u psi| > c) = (1/pi) int exp(-c cosh s) sech s ds over the real line, and the
    /// complement with 1 - exp(-c cosh s) (-expm1 below 1/4), by the trapezoid rule; once
    /// c cosh s > c + 40 the upper terms are below 4e-18 of the first and the lower terms are
    /// the weights, summed ahead.
    pub(crate) fn product_cdf(&self, c: f64) -> (f64, f64) {
        if c <= 0.0 {
            return (0.0, 1.0);
        }
        let (mut lower, mut upper, mut k) = (0.0, 0.0, 0);
        let stop = c + 40.0;
        while k < self.cosh.len() {
            let x = c * self.cosh[k];
            if x > stop {
                break;
            }
            let e = (-x).exp();
            let l = if x < 0.25 { -(-x).exp_m1() } else { 1.0 - e };
            lower += self.weight[k] * l;
            upper += self.weight[k] * e;
            k += 1;
        }
        lower += self.suffix[k];
        let scale = H_S / std::f64::consts::PI;
        (lower * scale, upper * scale)
    }
}

impl Default for SechNodes {
    fn default() -> SechNodes {
        SechNodes::new()
    }
}

/// (P(|u psi| <= c), P(|u psi| > c)) for independent standard normals ([`SechNodes::product_cdf`]
/// on fresh nodes).
#[cfg(test)]
pub(crate) fn product_cdf(c: f64) -> (f64, f64) {
    SechNodes::new().product_cdf(c)
}

/// The bottom of the y range for beta: the upper tail at the grid's largest t,
/// about e^(-(30 + 3 beta)), takes its mass from y near -(30 + 3 beta); the density
/// below y_min integrates to about e^(y_min) = 1e-9 of that.
fn y_min(beta: f64) -> f64 {
    -(51.0 + 3.0 * beta)
}

/// Density of y = ln|v| for v ~ N(0, 1): sqrt(2/pi) exp(y - e^(2y)/2).
pub(crate) fn ln_abs_normal_density(y: f64) -> f64 {
    (2.0 / std::f64::consts::PI).sqrt() * (y - 0.5 * (2.0 * y).exp()).exp()
}

/// Nodes y_j of the outer integral.
fn y_nodes(beta: f64) -> impl Iterator<Item = f64> {
    let lo = y_min(beta);
    let n = ((Y_MAX - lo) / H_Y).round() as usize;
    (0..=n).map(move |j| lo + j as f64 * H_Y)
}

/// (G(t), 1 - G(t)) of |T| = |u psi| / |v|^(1/beta) computed directly:
/// G(t) = int p(y) P(|u psi| <= t e^(y/beta)) dy (p the density of ln|v|), trapezoid in y.
#[cfg(test)]
pub(crate) fn levy_cdf(t: f64, beta: f64) -> (f64, f64) {
    let (mut lower, mut upper) = (0.0, 0.0);
    let nodes = SechNodes::new();
    for y in y_nodes(beta) {
        let p = ln_abs_normal_density(y);
        let (l, u) = nodes.product_cdf(t * (y / beta).exp());
        lower += p * l;
        upper += p * u;
    }
    (lower * H_Y, upper * H_Y)
}

/// ln G(t_m) and ln(1 - G(t_m)) on the grid ln t_m = LN_T_MIN + m H_Y / beta (the convolution
/// of [`levy_cdf`]'s sums, every c on one log grid).
#[derive(Debug, Clone)]
pub(crate) struct CdfGrid {
    step: f64,
    ln_lower: Vec<f64>,
    ln_upper: Vec<f64>,
}

impl CdfGrid {
    /// The grid for exponent beta.
    pub(crate) fn new(beta: f64) -> CdfGrid {
        let step = H_Y / beta;
        let m = ((30.0 / beta + 3.0 - LN_T_MIN) / step).ceil() as usize + 1;
        let dens: Vec<f64> = y_nodes(beta).map(ln_abs_normal_density).collect();
        let c0 = LN_T_MIN + y_min(beta) / beta;
        let nodes = SechNodes::new();
        let tails: Vec<(f64, f64)> =
            (0..m + dens.len()).map(|k| nodes.product_cdf((c0 + k as f64 * step).exp())).collect();
        let (mut ln_lower, mut ln_upper) = (Vec::with_capacity(m), Vec::with_capacity(m));
        for i in 0..m {
            let (mut l, mut u) = (0.0, 0.0);
            for (j, p) in dens.iter().enumerate() {
                l += p * tails[i + j].0;
                u += p * tails[i + j].1;
            }
            ln_lower.push((l * H_Y).ln());
            ln_upper.push((u * H_Y).ln());
        }
        CdfGrid { step, ln_lower, ln_upper }
    }

    /// The t with P(|T| <= t) = r (`upper` false) or P(|T| > t) = r (`upper` true), r <= 1/2:
    /// six-point Lagrange interpolation of ln t against ln r on the grid.
    pub(crate) fn quantile(&self, upper: bool, r: f64) -> f64 {
        let target = if upper { -r.ln() } else { r.ln() };
        let psi = |i: usize| if upper { -self.ln_upper[i] } else { self.ln_lower[i] };
        let n = self.ln_lower.len();
        // The first node at or above the target (binary search; psi increases).
        let (mut first, mut end) = (0, n);
        while first < end {
            let mid = (first + end) / 2;
            if psi(mid) < target {
                first = mid + 1;
            } else {
                end = mid;
            }
        }
        let start = first.saturating_sub(3).min(n - 6);
        let mut x = 0.0;
        for a in start..start + 6 {
            let mut w = 1.0;
            for b in start..start + 6 {
                if b != a {
                    w *= (target - psi(b)) / (psi(a) - psi(b));
                }
            }
            x += w * (LN_T_MIN + a as f64 * self.step);
        }
        x.exp()
    }
}

/// Chebyshev points of [0, 1] for the segments' cubics.
fn cheb_nodes() -> [f64; 4] {
    std::array::from_fn(|i| 0.5 - 0.5 * ((2 * i + 1) as f64 * std::f64::consts::PI / 8.0).cos())
}

/// Monomial coefficients c with sum_k c_k f_i^k = v_i (the cubic through four points), by
/// Gaussian elimination with partial pivoting on the Vandermonde system.
fn cubic_through(f: [f64; 4], v: [f64; 4]) -> [f64; 4] {
    let mut a: [[f64; 5]; 4] =
        std::array::from_fn(|i| [1.0, f[i], f[i] * f[i], f[i].powi(3), v[i]]);
    for col in 0..4 {
        let p =
            (col..4).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs())).unwrap_or(col);
        a.swap(col, p);
        for row in col + 1..4 {
            let m = a[row][col] / a[col][col];
            for k in col..5 {
                a[row][k] -= m * a[col][k];
            }
        }
    }
    let mut c = [0.0; 4];
    for row in (0..4).rev() {
        let s: f64 = (row + 1..4).map(|k| a[row][k] * c[k]).sum();
        c[row] = (a[row][4] - s) / a[row][row];
    }
    c
}

/// The quantile table of |T| for one beta (see the module).
#[derive(Debug, Clone)]
pub(crate) struct LevyTable {
    beta: f64,
    pub(crate) coef: Box<[[f64; 4]; TABLE_LEN]>,
}

/// Tables built so far in this process, by beta (each built once).
static TABLES: Mutex<Vec<Arc<LevyTable>>> = Mutex::new(Vec::new());

impl LevyTable {
    /// Build the table for exponent beta in (0, 2): the exact quantiles at each segment's four
    /// Chebyshev points and the cubic through them.
    pub(crate) fn new(beta: f64) -> LevyTable {
        let grid = CdfGrid::new(beta);
        let mut coef = Box::new([[0.0; 4]; TABLE_LEN]);
        let nodes = cheb_nodes();
        for side in 0..2 {
            for o in 0..OCTAVES {
                let base = (2.0f64).powi(o as i32 - 31);
                for s in 0..SEGS {
                    let v = nodes.map(|f| {
                        let r = base * (1.0 + (s as f64 + f) / SEGS as f64);
                        grid.quantile(side == 1, 0.5 * r)
                    });
                    coef[side * SIDE + o * SEGS + s] = cubic_through(nodes, v);
                }
            }
        }
        LevyTable { beta, coef }
    }

    /// The table for beta, built at the first call in the process and shared after.
    pub(crate) fn shared(beta: f64) -> Arc<LevyTable> {
        let mut tables = TABLES.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(t) = tables.iter().find(|t| t.beta.to_bits() == beta.to_bits()) {
            return t.clone();
        }
        let t = Arc::new(LevyTable::new(beta));
        tables.push(t.clone());
        t
    }

    /// |T| at r' in (0, 1) (tail probability r'/2) of the lower (`upper` false) or upper side:
    /// the segment's cubic c0 + f (c1 + f (c2 + f c3)) by fused multiply-adds.
    #[inline(always)]
    pub(crate) fn magnitude(&self, upper: bool, r: f64) -> f64 {
        let bits = r.to_bits();
        let i =
            ((bits >> (52 - SEG_BITS)) - (FIRST_EXP << SEG_BITS)) as usize + upper as usize * SIDE;
        let f = f64::from_bits(((bits << SEG_BITS) & MANT) | ONE) - 1.0;
        let c = &self.coef[i & (TABLE_LEN - 1)];
        c[3].mul_add(f, c[2]).mul_add(f, c[1]).mul_add(f, c[0])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::sampling::mantegna_sigma_u;
    use crate::optim::sampling::DeLanes;
    use crate::simd::levy::levy_fill;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use rand_distr::StandardNormal;

    /// E|u psi| = (E|z|)^2 = 2/pi = int_0^inf P(|u psi| > c) dc, by the trapezoid rule in ln c;
    /// the two tails add to 1; P(|u psi| > c) against a direct simulation at a few c.
    #[test]
    fn product_tails_are_the_product_law() {
        let h = 0.02;
        let mean: f64 = (0..3000)
            .map(|i| -45.0 + i as f64 * h)
            .map(|x| product_cdf(x.exp()).1 * x.exp())
            .sum::<f64>()
            * h;
        assert!((mean - 2.0 / std::f64::consts::PI).abs() < 1e-12, "{mean}");
        for c in [1e-14, 1e-5, 0.1, 1.0, 7.0, 30.0] {
            let (l, u) = product_cdf(c);
            // The trapezoid sum of the weights sech s_k is 1 to about 4 exp(-pi^2 / H_S) = 2e-14.
            assert!((l + u - 1.0).abs() < 5e-14, "c {c}: {l} + {u}");
        }
        let mut r = ChaCha8Rng::seed_from_u64(1);
        let n = 400_000;
        let sims: Vec<f64> = (0..n)
            .map(|_| {
                let (a, b): (f64, f64) = (r.sample(StandardNormal), r.sample(StandardNormal));
                (a * b).abs()
            })
            .collect();
        for c in [0.01, 0.3, 1.0, 4.0] {
            let p = product_cdf(c).1;
            let got = sims.iter().filter(|x| **x > c).count() as f64 / n as f64;
            assert!(
                (got - p).abs() < 5.0 * (p * (1.0 - p) / n as f64).sqrt(),
                "c {c}: {got} vs {p}"
            );
        }
    }

    /// The table's |T| at r' (the same index and fraction as the sampler, any f64 r').
    fn table_quantile(t: &LevyTable, upper: bool, r: f64) -> f64 {
        t.magnitude(upper, r)
    }

    /// The table's quantiles put the directly computed CDF at the asked probability, within 1e-6
    /// relative, at random points of every octave of both sides, for several beta.
    #[test]
    fn table_quantiles_match_the_quadrature() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        for (beta, points) in [(1.5, 120), (1.0, 30), (1.9, 30), (0.7, 30)] {
            let table = LevyTable::new(beta);
            let mut worst = 0.0f64;
            for i in 0..points {
                let upper = i % 2 == 1;
                // r' log-uniform over the 31 octaves, then the tail probability r'/2.
                let r = (2.0f64).powf(-31.0 * rng.gen::<f64>()).min(1.0 - 1e-12);
                let t = table_quantile(&table, upper, r);
                let (lo, up) = levy_cdf(t, beta);
                let got = if upper { up } else { lo };
                worst = worst.max((got / (0.5 * r) - 1.0).abs());
            }
            println!("beta {beta}: worst relative CDF error {worst:e}");
            assert!(worst < 1e-6, "beta {beta}: worst {worst:e}");
        }
    }

    /// Quantiles 0.5, 0.9, 0.99, 0.999 of |T| (beta = 3/2) from the table against the CDF; the
    /// median from both sides agrees.
    #[test]
    fn table_quantiles_at_named_probabilities() {
        let table = LevyTable::shared(1.5);
        let top = 1.0 - HALF_STEP_30;
        let (m_lo, m_up) = (table_quantile(&table, false, top), table_quantile(&table, true, top));
        assert!((m_lo / m_up - 1.0).abs() < 1e-6, "{m_lo} {m_up}");
        for p in [0.9, 0.99, 0.999] {
            let t = table_quantile(&table, true, 2.0 * (1.0 - p));
            let (g, _) = levy_cdf(t, 1.5);
            assert!(((1.0 - g) / (1.0 - p) - 1.0).abs() < 1e-6, "p {p}: G = {g}");
        }
        let (g, _) = levy_cdf(m_lo, 1.5);
        assert!((g - 0.5).abs() < 1e-6, "{g}");
    }

    /// The sampled law of L = sigma u psi / |v|^(1/beta) against a direct simulation from
    /// independent normals (rand_distr's ziggurat and powf): two-sample Kolmogorov-Smirnov
    /// statistic of |L| below its 0.1% critical value, the fractions beyond several thresholds
    /// (deep into the tail), and the sign.
    #[test]
    fn levy_factors_have_mantegnas_law() {
        for beta in [1.5, 1.1] {
            let sigma = mantegna_sigma_u(beta);
            let table = LevyTable::shared(beta);
            let n = 400_000;
            let mut got = vec![0.0; n];
            let mut lanes = DeLanes::from_rng(&mut ChaCha8Rng::seed_from_u64(9));
            levy_fill(&mut got, sigma, &table, &mut lanes);
            let mut r = ChaCha8Rng::seed_from_u64(10);
            let mut want: Vec<f64> = (0..n)
                .map(|_| {
                    let (u, v, p): (f64, f64, f64) = (
                        r.sample(StandardNormal),
                        r.sample(StandardNormal),
                        r.sample(StandardNormal),
                    );
                    sigma * u * p * v.abs().powf(-1.0 / beta)
                })
                .collect();
            let frac = |s: &[f64], t: f64| {
                s.iter().filter(|x| x.abs() > t).count() as f64 / s.len() as f64
            };
            for t in [0.01, 0.3, 1.0, 3.0, 10.0, 100.0, 1000.0] {
                let (a, b) = (frac(&got, t), frac(&want, t));
                let sd = (b * (1.0 - b) / n as f64).sqrt() * 2f64.sqrt();
                assert!((a - b).abs() < 5.0 * sd + 1e-5, "beta {beta} t {t}: {a} vs {b}");
            }
            let pos = got.iter().filter(|x| **x > 0.0).count() as f64 / n as f64;
            assert!((pos - 0.5).abs() < 0.004, "{pos}");
            let mut a: Vec<f64> = got.iter().map(|x| x.abs()).collect();
            a.sort_by(f64::total_cmp);
            want.iter_mut().for_each(|x| *x = x.abs());
            want.sort_by(f64::total_cmp);
            let (mut i, mut j, mut d) = (0, 0, 0.0f64);
            while i < n && j < n {
                if a[i] <= want[j] {
                    i += 1;
                } else {
                    j += 1;
                }
                d = d.max((i as f64 - j as f64).abs() / n as f64);
            }
            let crit = 1.95 * (2.0 / n as f64).sqrt();
            assert!(d < crit, "beta {beta}: KS {d} >= {crit}");
        }
    }
}
