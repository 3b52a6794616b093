//! Allocation-free least-squares Y for the parameter search (seed 003's fitness): the grid layout
//! by the separable projection with small stack-style Householder QRs, the scattered layout by the
//! normal equations of the (du+1)(dv+1)-unknown Bernstein system built from the tensor structure.
//! Both return `None` when the system is (nearly) rank deficient, and the caller then takes the
//! SVD paths of the parent module, so rank deficiency behaves exactly as there (minimum norm).
//!
//! Determinism: every loop is plain IEEE multiplies and adds in a fixed order (no `mul_add`, no
//! reassociation); the dot products over the points keep 8 fixed partial sums (lane k mod 8)
//! combined in a fixed tree. The AVX2 copy is the same Rust compiled with `target_feature(avx2)`
//! (wider vectors only; rustc never fuses a multiply and an add on its own), so the copies give
//! the same bits; `SOMNURBS_SIMD=scalar` forces the baseline copy.

use super::GridData;
use crate::geom::Point3;
use std::cell::RefCell;

/// Highest degree of the fast paths (the doubled degree's basis must fit [`MAXB`]).
const MAXD: usize = 15;
/// Length of the stack Bernstein buffers (degree 2 * MAXD).
const MAXB: usize = 2 * MAXD + 1;
/// Padding of the per-point rows (a multiple of the dot products' 8 lanes).
const LANES: usize = 16;
/// Relative Cholesky pivot below which the normal equations are refused (SVD fallback): the
/// squared pivot L_ii^2 must exceed `PIVOT_REL` times the largest diagonal entry of G, which
/// bounds cond(G) from below by 1 / PIVOT_REL before the factorisation is trusted.
const PIVOT_REL: f64 = 1e-10;
/// Y below this fraction of sum |P|^2 is recomputed from the residual (cancellation).
const CANCEL_REL: f64 = 1e-6;

/// Reused buffers of one thread (no allocation per evaluation once grown).
#[derive(Default)]
pub(super) struct Scratch {
    /// The clamped (and, for grids, sorted) decision vector.
    pub x: Vec<f64>,
    bu: Vec<f64>,
    bv: Vec<f64>,
    bu2: Vec<f64>,
    bv2: Vec<f64>,
    q: Vec<f64>,
    m: Vec<f64>,
    gq: Vec<f64>,
    g: Vec<f64>,
    l: Vec<f64>,
    c: Vec<f64>,
    r: Vec<f64>,
    qa: Vec<f64>,
    qb: Vec<f64>,
    t: Vec<f64>,
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// Run `f` with this thread's scratch buffers.
pub(super) fn with_scratch<R>(f: impl FnOnce(&mut Scratch) -> R) -> R {
    SCRATCH.with(|s| f(&mut s.borrow_mut()))
}

fn grow(v: &mut Vec<f64>, n: usize) {
    if v.len() < n {
        v.resize(n, 0.0);
    }
}

/// Whether the AVX2 copies run (the optimisers' `SOMNURBS_SIMD` choice).
fn avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        crate::optim::kernels::use_avx2()
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Binomial coefficient C(n, k) as f64 (exact for the degrees here).
fn binom(n: usize, k: usize) -> f64 {
    (0..k).fold(1.0, |acc, j| acc * (n - j) as f64 / (j + 1) as f64)
}

/// w^n_ac = C(n,a) C(n,c) / C(2n,a+c) for a, c in 0..=n, row-major (n+1) x (n+1).
fn product_weights(n: usize, w: &mut [f64; (MAXD + 1) * (MAXD + 1)]) {
    let mut b = [0.0f64; MAXB];
    let mut b2 = [0.0f64; MAXB];
    for i in 0..=n {
        b[i] = binom(n, i);
    }
    for i in 0..=2 * n {
        b2[i] = binom(2 * n, i);
    }
    for a in 0..=n {
        for c in 0..=n {
            w[a * (n + 1) + c] = b[a] * b[c] / b2[a + c];
        }
    }
}

/// Bernstein polynomials B^n_i(t_k) = C(n,i) t^i (1-t)^(n-i) for every t_k, stored i-major
/// (row i holds all k, `stride` apart); rows padded with zeros past `t.len()`.
#[inline(always)]
fn basis_rows(n: usize, t: &[f64], stride: usize, out: &mut [f64]) {
    let np = t.len();
    let mut binoms = [0.0f64; MAXB];
    for (i, b) in binoms[..=n].iter_mut().enumerate() {
        *b = binom(n, i);
    }
    // lane by lane over chunks of 8 points (t padded with zeros): t^i up, then (1-t)^(n-i) down
    let mut tpad = [0.0f64; 8];
    for k0 in (0..stride).step_by(8) {
        let m = np.saturating_sub(k0).min(8);
        tpad.fill(0.0);
        if m > 0 {
            tpad[..m].copy_from_slice(&t[k0..k0 + m]);
        }
        let mut tp = [1.0f64; 8];
        for i in 0..=n {
            out[i * stride + k0..i * stride + k0 + 8].copy_from_slice(&tp);
            for l in 0..8 {
                tp[l] *= tpad[l];
            }
        }
        let mut sp = [1.0f64; 8];
        for i in (0..=n).rev() {
            let w = binoms[i];
            let row = &mut out[i * stride + k0..i * stride + k0 + 8];
            for l in 0..8 {
                row[l] = w * (row[l] * sp[l]);
                sp[l] *= 1.0 - tpad[l];
            }
        }
    }
    for i in 0..=n {
        out[i * stride + np..(i + 1) * stride].fill(0.0);
    }
}

/// The R dot products sum_k a_k b_rk over a multiple of 8 entries, each in 8 fixed partial sums
/// (lane k mod 8) combined in a fixed tree; R rows at once share the loads of `a` (the value of
/// each product does not depend on R).
#[inline(always)]
fn dots<const R: usize>(a: &[f64], b: [&[f64]; R]) -> [f64; R] {
    let b = b.map(|r| &r[..a.len()]);
    let mut acc = [[0.0f64; 8]; R];
    for (ch, x) in a.chunks_exact(8).enumerate() {
        for r in 0..R {
            let y = &b[r][ch * 8..ch * 8 + 8];
            for l in 0..8 {
                acc[r][l] += x[l] * y[l];
            }
        }
    }
    acc.map(|h| ((h[0] + h[4]) + (h[2] + h[6])) + ((h[1] + h[5]) + (h[3] + h[7])))
}

/// Y of the least-squares degree-(du, dv) Bezier surface through scattered `pts` at the
/// parameters x = (u_0, v_0, u_1, v_1, ...), by the normal equations G c = g with G = B^T B,
/// g = B^T P (B_k = kron(bu(u_k), bv(v_k))). The tensor structure gives
/// G[(a,b),(c,d)] = w^du_ac w^dv_bd M[a+c][b+d] with M = sum_k B^2du(u_k) B^2dv(v_k)^T and
/// w^n_ac = C(n,a) C(n,c) / C(2n,a+c) (B^n_a B^n_c = w^n_ac B^2n_(a+c)). Y = |P|^2 - 2 g.c + c^T G c
/// (second order in the solution's error); below 1e-6 |P|^2 the solution is refined once and Y
/// summed from the residuals. `None` if a Cholesky pivot is below [`PIVOT_REL`].
pub(super) fn scattered_sse(
    du: usize,
    dv: usize,
    x: &[f64],
    pts: &[Point3],
    p2: f64,
    s: &mut Scratch,
) -> Option<f64> {
    if du > MAXD || dv > MAXD || pts.is_empty() || x.len() != 2 * pts.len() {
        return None;
    }
    #[cfg(target_arch = "x86_64")]
    if avx2() {
        // SAFETY: AVX2 is present (checked by the dispatcher).
        return unsafe { scattered_sse_avx2(du, dv, x, pts, p2, s) };
    }
    scattered_sse_body(du, dv, x, pts, p2, s)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn scattered_sse_avx2(
    du: usize,
    dv: usize,
    x: &[f64],
    pts: &[Point3],
    p2: f64,
    s: &mut Scratch,
) -> Option<f64> {
    scattered_sse_body(du, dv, x, pts, p2, s)
}

#[inline(always)]
fn scattered_sse_body(
    du: usize,
    dv: usize,
    x: &[f64],
    pts: &[Point3],
    p2: f64,
    s: &mut Scratch,
) -> Option<f64> {
    let np = pts.len();
    let stride = np.div_ceil(LANES) * LANES;
    let (ku, kv) = (du + 1, dv + 1);
    let n = ku * kv;
    moments(du, dv, x, pts, stride, s);
    // G from the moments, g from gq (gq[(a, c), b] = sum_k bu_a P_c bv_b)
    grow(&mut s.g, n * n);
    grow(&mut s.l, n * n);
    grow(&mut s.c, 3 * n);
    let m2 = 2 * dv + 1;
    let (mut wus, mut wvs) = ([0.0; (MAXD + 1) * (MAXD + 1)], [0.0; (MAXD + 1) * (MAXD + 1)]);
    product_weights(du, &mut wus);
    product_weights(dv, &mut wvs);
    for a in 0..ku {
        for b in 0..kv {
            for c in 0..ku {
                let wu = wus[a * ku + c];
                for d in 0..kv {
                    let wv = wvs[b * kv + d];
                    s.g[(a * kv + b) * n + c * kv + d] = (wu * wv) * s.m[(a + c) * m2 + b + d];
                }
            }
            for co in 0..3 {
                s.c[co * n + a * kv + b] = s.gq[(a * 3 + co) * kv + b];
            }
        }
    }
    s.r.clear();
    s.r.extend_from_slice(&s.c[..3 * n]); // g, kept for Y
    if !cholesky(&s.g[..n * n], &mut s.l[..n * n], n) {
        return None;
    }
    chol_solve(&s.l[..n * n], n, &mut s.c[..3 * n]);
    // Y = |P|^2 - 2 g.c + c^T G c
    let (c, g) = (&s.c[..3 * n], &s.g[..n * n]);
    let gc = dots_any(&s.r[..3 * n], [c])[0];
    let mut cgc = 0.0;
    for i in 0..n {
        let h = dots_any(&g[i * n..(i + 1) * n], [&c[..n], &c[n..2 * n], &c[2 * n..]]);
        cgc += (c[i] * h[0] + c[n + i] * h[1]) + c[2 * n + i] * h[2];
    }
    let y = p2 - 2.0 * gc + cgc;
    if y > CANCEL_REL * p2 {
        return Some(y);
    }
    Some(refined_residual(du, dv, x, pts, s))
}

/// The moments M (i-major (2du+1) x (2dv+1)) and gq ((du+1) * 3 rows of dv+1) of
/// [`scattered_sse`], from i-major basis rows of all points.
#[inline(always)]
fn moments(du: usize, dv: usize, x: &[f64], pts: &[Point3], stride: usize, s: &mut Scratch) {
    let np = pts.len();
    let (ku, kv) = (du + 1, dv + 1);
    let (ku2, kv2) = (2 * du + 1, 2 * dv + 1);
    // parameters into the (padded) rows of bu / bv as scratch for the t values
    grow(&mut s.q, 5 * stride);
    {
        let (tu, rest) = s.q.split_at_mut(stride);
        let (tv, _) = rest.split_at_mut(stride);
        for (k, uv) in x.chunks_exact(2).enumerate() {
            tu[k] = uv[0];
            tv[k] = uv[1];
        }
    }
    grow(&mut s.bu, ku * stride);
    grow(&mut s.bv, kv * stride);
    grow(&mut s.bu2, ku2 * stride);
    grow(&mut s.bv2, kv2 * stride);
    basis_rows(du, &s.q[..np], stride, &mut s.bu);
    basis_rows(2 * du, &s.q[..np], stride, &mut s.bu2);
    basis_rows(dv, &s.q[stride..stride + np], stride, &mut s.bv);
    basis_rows(2 * dv, &s.q[stride..stride + np], stride, &mut s.bv2);
    grow(&mut s.m, ku2 * kv2);
    fn row(m: &[f64], i: usize, stride: usize) -> &[f64] {
        &m[i * stride..(i + 1) * stride]
    }
    for a in 0..ku2 {
        let ra = row(&s.bu2, a, stride);
        let mut b = 0;
        while b + 4 <= kv2 {
            let bv2 = &s.bv2;
            let d = dots(
                ra,
                [
                    row(bv2, b, stride),
                    row(bv2, b + 1, stride),
                    row(bv2, b + 2, stride),
                    row(bv2, b + 3, stride),
                ],
            );
            s.m[a * kv2 + b..a * kv2 + b + 4].copy_from_slice(&d);
            b += 4;
        }
        for b in b..kv2 {
            s.m[a * kv2 + b] = dots(ra, [row(&s.bv2, b, stride)])[0];
        }
    }
    // gq[(a, c) * kv + b] = sum_k (bu_a(u_k) P_kc) bv_b(v_k); the product rows go to q[2..5]
    grow(&mut s.gq, ku * 3 * kv);
    let (_, prod) = s.q.split_at_mut(2 * stride);
    for a in 0..ku {
        let ra = &s.bu[a * stride..a * stride + np];
        for co in 0..3 {
            let row = &mut prod[co * stride..co * stride + np];
            for ((o, ba), p) in row.iter_mut().zip(ra).zip(pts) {
                *o = ba * p[co];
            }
        }
        for b in 0..kv {
            let d = dots(
                row(&s.bv, b, stride),
                [row(prod, 0, stride), row(prod, 1, stride), row(prod, 2, stride)],
            );
            for co in 0..3 {
                s.gq[(a * 3 + co) * kv + b] = d[co];
            }
        }
    }
}

/// Near-exact fit: one step of iterative refinement (c += G^-1 B^T (P - B c)) and Y summed from
/// the residuals sum_k |P_k - B_k c|^2, so a tiny Y keeps its relative precision. Uses the
/// Cholesky factor and solution left in the scratch by [`scattered_sse`].
fn refined_residual(du: usize, dv: usize, x: &[f64], pts: &[Point3], s: &mut Scratch) -> f64 {
    let (ku, kv) = (du + 1, dv + 1);
    let n = ku * kv;
    let residual = |c: &[f64], acc: &mut [f64]| -> f64 {
        acc.fill(0.0);
        let mut y = 0.0;
        let (mut bu, mut bv) = ([0.0; MAXB], [0.0; MAXB]);
        for (uv, p) in x.chunks_exact(2).zip(pts) {
            super::bernstein_into(du, uv[0], &mut bu[..ku]);
            super::bernstein_into(dv, uv[1], &mut bv[..kv]);
            let mut e = *p;
            for a in 0..ku {
                for b in 0..kv {
                    let w = bu[a] * bv[b];
                    for co in 0..3 {
                        e[co] -= w * c[co * n + a * kv + b];
                    }
                }
            }
            for a in 0..ku {
                for b in 0..kv {
                    let w = bu[a] * bv[b];
                    for co in 0..3 {
                        acc[co * n + a * kv + b] += w * e[co];
                    }
                }
            }
            y += e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
        }
        y
    };
    let mut corr = std::mem::take(&mut s.r);
    corr.resize(3 * n, 0.0);
    residual(&s.c[..3 * n], &mut corr);
    chol_solve(&s.l[..n * n], n, &mut corr);
    for (c, d) in s.c[..3 * n].iter_mut().zip(&corr) {
        *c += d;
    }
    let y = residual(&s.c[..3 * n], &mut corr);
    s.r = corr;
    y
}

/// Cholesky G = U^T U of the n x n row-major `g` into `u` (upper triangle, row j of U = column j
/// of L), right-looking so that each step updates whole rows; false if a squared pivot U_jj^2 is
/// at most [`PIVOT_REL`] times max_i G_ii (or not finite).
fn cholesky(g: &[f64], u: &mut [f64], n: usize) -> bool {
    let dmax = (0..n).fold(0.0f64, |m, i| m.max(g[i * n + i]));
    if !(dmax > 0.0 && dmax.is_finite()) {
        return false;
    }
    u[..n * n].copy_from_slice(&g[..n * n]);
    for j in 0..n {
        let d = u[j * n + j];
        if d.is_nan() || d <= PIVOT_REL * dmax {
            return false;
        }
        let r = d.sqrt();
        let (top, rest) = u.split_at_mut((j + 1) * n);
        let rowj = &mut top[j * n + j..];
        for x in rowj.iter_mut() {
            *x /= r;
        }
        for (i, rowi) in (j + 1..n).zip(rest.chunks_exact_mut(n)) {
            let f = rowj[i - j];
            for (x, y) in rowi[i..].iter_mut().zip(&rowj[i - j..]) {
                *x -= f * y;
            }
        }
    }
    true
}

/// Solve U^T U c = b in place for the three right-hand sides of `c` (three rows of n).
fn chol_solve(u: &[f64], n: usize, c: &mut [f64]) {
    for col in c.chunks_exact_mut(n).take(3) {
        for j in 0..n {
            let y = col[j] / u[j * n + j];
            col[j] = y;
            for (x, uj) in col[j + 1..].iter_mut().zip(&u[j * n + j + 1..(j + 1) * n]) {
                *x -= uj * y;
            }
        }
        for j in (0..n).rev() {
            let s = dots_any(&u[j * n + j + 1..(j + 1) * n], [&col[j + 1..]])[0];
            col[j] = (col[j] - s) / u[j * n + j];
        }
    }
}

/// The R dot products sum_k a_k b_rk of any length: 4 fixed partial sums (lane k mod 4) over the
/// whole chunks, combined as (s0 + s2) + (s1 + s3), then the remainder in order.
#[inline(always)]
fn dots_any<const R: usize>(a: &[f64], b: [&[f64]; R]) -> [f64; R] {
    let b = b.map(|r| &r[..a.len()]);
    let mut acc = [[0.0f64; 4]; R];
    let whole = a.len() / 4 * 4;
    for (ch, x) in a[..whole].chunks_exact(4).enumerate() {
        for r in 0..R {
            let y = &b[r][ch * 4..ch * 4 + 4];
            for l in 0..4 {
                acc[r][l] += x[l] * y[l];
            }
        }
    }
    let mut out = [0.0; R];
    for r in 0..R {
        let mut t = (acc[r][0] + acc[r][2]) + (acc[r][1] + acc[r][3]);
        for (x, y) in a[whole..].iter().zip(&b[r][whole..]) {
            t += x * y;
        }
        out[r] = t;
    }
    out
}

/// Thin Q (n x k, row-major) of the Householder QR of the n x (deg+1) Bernstein collocation
/// matrix at the sorted parameters `t` (A = Q R); `None` unless n > deg and every |R_ii| exceeds
/// 1e-8 max |R_jj| (the test of the parent module's `column_basis`, whose SVD then takes over).
/// Row-major throughout so that each reflector updates whole rows (vectorisable); `work` holds
/// A (reduced in place) and then the reflectors.
#[inline(always)]
fn thin_q(deg: usize, t: &[f64], q: &mut Vec<f64>, work: &mut Vec<f64>) -> Option<()> {
    let (n, k) = (t.len(), deg + 1);
    if n <= deg || deg > MAXD {
        return None;
    }
    grow(work, n * k + n * k);
    let (a, refl) = work.split_at_mut(n * k);
    for (i, &ti) in t.iter().enumerate() {
        super::bernstein_into(deg, ti, &mut a[i * k..(i + 1) * k]);
    }
    let mut diag = [0.0f64; MAXB];
    let mut beta = [0.0f64; MAXB];
    let mut f = [0.0f64; MAXB];
    for j in 0..k {
        let v = &mut refl[j * n..(j + 1) * n];
        for i in j..n {
            v[i] = a[i * k + j];
        }
        let norm = dots_any(&v[j..], [&v[j..]])[0].sqrt();
        let alpha = if v[j] > 0.0 { -norm } else { norm };
        diag[j] = alpha;
        v[j] -= alpha;
        let vv = dots_any(&v[j..], [&v[j..]])[0];
        beta[j] = if vv > 0.0 { 2.0 / vv } else { 0.0 };
        reflect(&v[j..n], beta[j], &mut a[j * k..], k, j + 1, &mut f);
    }
    let rmax = diag[..k].iter().fold(0.0f64, |m, d| m.max(d.abs()));
    if !diag[..k].iter().all(|d| d.abs() > 1e-8 * rmax) {
        return None;
    }
    // Q = H_0 ... H_(k-1) [I; 0]; H_j only touches rows j.. and columns j.. of the partial product
    grow(q, n * k);
    q[..n * k].fill(0.0);
    for c in 0..k {
        q[c * k + c] = 1.0;
    }
    for j in (0..k).rev() {
        reflect(&refl[j * n + j..(j + 1) * n], beta[j], &mut q[j * k..n * k], k, j, &mut f);
    }
    Some(())
}

/// Apply H = I - beta v v^T to the rows of the row-major block `m` (row stride k), columns
/// c0..k: f_c = sum_i v_i m_ic, then m_ic -= (beta f_c) v_i (whole-row updates).
#[inline(always)]
fn reflect(v: &[f64], beta: f64, m: &mut [f64], k: usize, c0: usize, f: &mut [f64; MAXB]) {
    if c0 >= k {
        return;
    }
    let f = &mut f[c0..k];
    f.fill(0.0);
    for (vi, row) in v.iter().zip(m.chunks_exact(k)) {
        for (fc, x) in f.iter_mut().zip(&row[c0..]) {
            *fc += vi * x;
        }
    }
    for fc in f.iter_mut() {
        *fc *= beta;
    }
    for (vi, row) in v.iter().zip(m.chunks_exact_mut(k)) {
        for (x, fc) in row[c0..].iter_mut().zip(f.iter()) {
            *x -= fc * vi;
        }
    }
}

/// Y of the grid fit by the separable projection Y = |D|^2 - sum_c |Qu^T D_c Qv|^2 (see
/// [`super::grid_sse`]) with the thin Qs from [`thin_q`]; `None` when a collocation matrix is
/// (nearly) rank deficient or a grid side exceeds 128. Below 1e-6 |D|^2 the residual
/// D_c - Qu C_c Qv^T is summed instead.
pub(super) fn grid_sse(
    du: usize,
    dv: usize,
    u: &[f64],
    v: &[f64],
    data: &GridData,
    s: &mut Scratch,
) -> Option<f64> {
    #[cfg(target_arch = "x86_64")]
    if avx2() {
        // SAFETY: AVX2 is present (checked by the dispatcher).
        return unsafe { grid_sse_avx2(du, dv, u, v, data, s) };
    }
    grid_sse_body(du, dv, u, v, data, s)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn grid_sse_avx2(
    du: usize,
    dv: usize,
    u: &[f64],
    v: &[f64],
    data: &GridData,
    s: &mut Scratch,
) -> Option<f64> {
    grid_sse_body(du, dv, u, v, data, s)
}

#[inline(always)]
fn grid_sse_body(
    du: usize,
    dv: usize,
    u: &[f64],
    v: &[f64],
    data: &GridData,
    s: &mut Scratch,
) -> Option<f64> {
    let (nu, nv) = (u.len(), v.len());
    if nu != data.nu || nv != data.nv {
        return None;
    }
    let (ku, kv) = (du + 1, dv + 1);
    thin_q(du, u, &mut s.qa, &mut s.l)?;
    thin_q(dv, v, &mut s.qb, &mut s.l)?;
    // T = Qu^T [D_x D_y D_z] (ku x 3 nv), rows of `data.rows` are (x row, y row, z row) of i
    let w = 3 * nv;
    grow(&mut s.t, ku * w);
    s.t[..ku * w].fill(0.0);
    for i in 0..nu {
        let drow = &data.rows[i * w..(i + 1) * w];
        for a in 0..ku {
            let f = s.qa[i * ku + a];
            for (t, d) in s.t[a * w..(a + 1) * w].iter_mut().zip(drow) {
                *t += f * d;
            }
        }
    }
    // C_c = T_c Qv (ku x kv per coordinate), in s.c as [c][a][b]
    grow(&mut s.c, 3 * ku * kv);
    s.c[..3 * ku * kv].fill(0.0);
    for co in 0..3 {
        for j in 0..nv {
            let qrow = &s.qb[j * kv..(j + 1) * kv];
            for a in 0..ku {
                let f = s.t[a * w + co * nv + j];
                let crow = &mut s.c[(co * ku + a) * kv..(co * ku + a + 1) * kv];
                for (c, q) in crow.iter_mut().zip(qrow) {
                    *c += f * q;
                }
            }
        }
    }
    let kept = s.c[..3 * ku * kv].iter().fold(0.0, |acc, c| acc + c * c);
    let y = data.norm2 - kept;
    if y > CANCEL_REL * data.norm2 {
        return Some(y);
    }
    // residual D_c - (Qu C_c) Qv^T, with Qu C_c (nu x kv) in s.t
    let mut sse = 0.0;
    grow(&mut s.t, nu * kv);
    for co in 0..3 {
        for i in 0..nu {
            for b in 0..kv {
                let mut acc = 0.0;
                for a in 0..ku {
                    acc += s.qa[i * ku + a] * s.c[(co * ku + a) * kv + b];
                }
                s.t[i * kv + b] = acc;
            }
        }
        for i in 0..nu {
            for j in 0..nv {
                let mut fit = 0.0;
                for b in 0..kv {
                    fit += s.t[i * kv + b] * s.qb[j * kv + b];
                }
                let e = data.rows[i * w + co * nv + j] - fit;
                sse += e * e;
            }
        }
    }
    Some(sse)
}

#[cfg(test)]
mod tests {
    use super::super::{add_noise, example3, fit_poles, grid_sse_qr, BezierSurface};
    use super::*;
    use crate::optim::Problem;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn svd_y(du: usize, dv: usize, x: &[f64], pts: &[Point3]) -> f64 {
        let uv: Vec<(f64, f64)> = x.chunks(2).map(|c| (c[0], c[1])).collect();
        fit_poles(du, dv, &uv, pts).unwrap().1
    }

    fn norm2(pts: &[Point3]) -> f64 {
        pts.iter().flat_map(|p| p.iter()).map(|c| c * c).sum()
    }

    fn random_surface(du: usize, dv: usize, rng: &mut ChaCha8Rng) -> BezierSurface {
        let poles = (0..(du + 1) * (dv + 1))
            .map(|_| [rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0)])
            .collect();
        BezierSurface { du, dv, poles }
    }

    /// Normal-equation Y equals the QR + SVD Y (fit_poles) on noisy scattered data at random
    /// parameters, for Example III's layout and a mixed-degree one; both copies give the same bits.
    #[test]
    fn scattered_normal_equations_equal_svd() {
        let mut rng = ChaCha8Rng::seed_from_u64(31);
        let (_, ex3) = example3(628, &mut rng);
        let mixed = {
            let s = random_surface(3, 4, &mut rng);
            (0..150).map(|_| s.eval(rng.gen_range(0.0..1.0), rng.gen_range(0.0..1.0))).collect()
        };
        for (du, dv, mut pts) in [(5, 5, ex3), (3, 4, mixed)] {
            add_noise(&mut pts, 18.0, &mut rng);
            let p2 = norm2(&pts);
            for _ in 0..5 {
                let x: Vec<f64> = (0..2 * pts.len()).map(|_| rng.gen_range(0.0..1.0)).collect();
                let mut s = Scratch::default();
                let y = scattered_sse_body(du, dv, &x, &pts, p2, &mut s).expect("well posed");
                let y_svd = svd_y(du, dv, &x, &pts);
                assert!((y - y_svd).abs() <= 1e-10 * y_svd, "({du},{dv}): {y} vs {y_svd}");
                #[cfg(target_arch = "x86_64")]
                if std::arch::is_x86_feature_detected!("avx2") {
                    let y2 = unsafe { scattered_sse_avx2(du, dv, &x, &pts, p2, &mut s) };
                    assert_eq!(y2.map(f64::to_bits), Some(y.to_bits()));
                }
            }
        }
    }

    /// Closed form: points on a degree-(5,5) surface at their true parameters give Y = 0 up to
    /// rounding and the normal equations return the surface's poles; with noise of 1e-7 the tiny
    /// Y (cancellation branch) still equals the SVD Y to 1e-8 relative.
    #[test]
    fn scattered_near_interpolation_keeps_relative_precision() {
        let mut rng = ChaCha8Rng::seed_from_u64(32);
        let (surf, _) = example3(10, &mut rng);
        let x: Vec<f64> = (0..2 * 300).map(|_| rng.gen_range(0.0..1.0)).collect();
        let mut pts: Vec<Point3> = x.chunks(2).map(|c| surf.eval(c[0], c[1])).collect();
        let mut s = Scratch::default();
        let y = scattered_sse_body(5, 5, &x, &pts, norm2(&pts), &mut s).unwrap();
        assert!(y < 1e-24, "Y = {y}");
        for (k, p) in surf.poles.iter().enumerate() {
            for co in 0..3 {
                assert!((s.c[co * 36 + k] - p[co]).abs() < 1e-9, "pole {k}");
            }
        }
        for p in pts.iter_mut() {
            for c in p.iter_mut() {
                *c += 1e-7 * rng.gen_range(-1.0..1.0);
            }
        }
        let y = scattered_sse_body(5, 5, &x, &pts, norm2(&pts), &mut s).unwrap();
        let y_svd = svd_y(5, 5, &x, &pts);
        assert!(y < 1e-6 * norm2(&pts) && y > 0.0);
        assert!((y - y_svd).abs() <= 1e-8 * y_svd, "{y} vs {y_svd}");
    }

    /// Repeated parameters (only 4 distinct u): G is singular, the fast path refuses, and the
    /// problem's fitness is the SVD path's minimum-norm Y exactly.
    #[test]
    fn scattered_rank_deficiency_falls_back_to_svd() {
        let mut rng = ChaCha8Rng::seed_from_u64(33);
        let (_, mut pts) = example3(200, &mut rng);
        add_noise(&mut pts, 18.0, &mut rng);
        let x: Vec<f64> = (0..400)
            .map(|k| if k % 2 == 0 { (k / 2 % 4) as f64 / 3.0 } else { rng.gen_range(0.0..1.0) })
            .collect();
        let mut s = Scratch::default();
        assert!(scattered_sse_body(5, 5, &x, &pts, norm2(&pts), &mut s).is_none());
        let prob = super::super::BezierParamProblem::new(
            5,
            5,
            super::super::Layout::Scattered,
            pts.clone(),
            x.clone(),
        )
        .unwrap();
        assert_eq!(prob.fitness(&x), svd_y(5, 5, &x, &pts));
    }

    /// The stack-QR grid Y equals nalgebra's QR Y on the examples' grids; both copies agree
    /// bit for bit; clustered-to-rank-deficient parameters are refused (fallback).
    #[test]
    fn grid_fast_equals_qr_and_refuses_rank_deficiency() {
        let mut rng = ChaCha8Rng::seed_from_u64(34);
        for (n, d) in [(29, 5), (41, 9), (13, 5)] {
            let mut pts = super::super::height_grid(super::super::peaks, n, -3.0, 3.0);
            add_noise(&mut pts, 12.5, &mut rng);
            let data = GridData::new(&pts, n, n);
            for _ in 0..4 {
                let mut u: Vec<f64> = (0..n).map(|_| rng.gen_range(0.0..1.0)).collect();
                let mut v: Vec<f64> = (0..n).map(|_| rng.gen_range(0.0..1.0)).collect();
                u.sort_by(f64::total_cmp);
                v.sort_by(f64::total_cmp);
                let mut s = Scratch::default();
                let y = grid_sse_body(d, d, &u, &v, &data, &mut s).expect("full rank");
                let y_qr = grid_sse_qr(d, d, &u, &v, &data);
                assert!((y - y_qr).abs() <= 1e-10 * y_qr, "n={n}: {y} vs {y_qr}");
                #[cfg(target_arch = "x86_64")]
                if std::arch::is_x86_feature_detected!("avx2") {
                    let y2 = unsafe { grid_sse_avx2(d, d, &u, &v, &data, &mut s) };
                    assert_eq!(y2.map(f64::to_bits), Some(y.to_bits()));
                }
            }
            let u: Vec<f64> = (0..n).map(|i| (i % 3) as f64 / 2.0).collect();
            let v: Vec<f64> = (0..n).map(|j| j as f64 / (n - 1) as f64).collect();
            let mut u = u;
            u.sort_by(f64::total_cmp);
            assert!(grid_sse_body(d, d, &u, &v, &data, &mut Scratch::default()).is_none());
        }
    }
}
