//! Allocation-free least-squares Y for the parameter search (seed 003's fitness): the grid layout
//! by the separable projection with small Householder QRs, the scattered layout by the normal
//! equations of the (du+1)(dv+1)-unknown Bernstein system built from the tensor structure.
//! Both return `None` when the system is (nearly) rank deficient, and the caller then takes the
//! SVD paths of the parent module, so rank deficiency behaves exactly as there (minimum norm).
//!
//! The bulk of the work is products of matrices: [`gemm_nt`] of rows of a common padded length
//! (the 11 x 11 moments and the right-hand sides of the scattered layout, (Qu^T D) Qv of the
//! grids), [`gemm_tn`] by outer products over the grid's rows (Qu^T D, whose sums are only 29 or
//! 41 long), and the grids' Householder QRs, column-major over padded columns; every hot loop is
//! 4 lanes wide.
//!
//! Determinism: every sum has a fixed order written in the code: the long dot products keep 4
//! partial sums (entry k into lane k mod 4, each a chain of fused multiply-adds `f64::mul_add`,
//! one rounding in every copy) combined as (s0 + s2) + (s1 + s3); the Householder steps' dot
//! products keep 8 ([`dot8`]); [`gemm_tn`]'s sums are one chain each. The AVX2 + FMA copy is the
//! same Rust compiled with `target_feature` (wider vectors and hardware FMA only; rustc never
//! reassociates) plus a few hand-written AVX2 kernels, so all copies give the same bits (an
//! AVX-512VL compilation gained under 5% and was removed: docs/speed.md); `SOMNURBS_SIMD=scalar` forces the
//! baseline copy (whose `mul_add` is the C library's correctly rounded `fma`, slow but identical).

#[cfg(target_arch = "x86_64")]
use super::Isa;
use crate::geom::Point3;
use crate::spline::bezier::GridData;
use std::cell::RefCell;
use std::mem::MaybeUninit;

/// Highest degree of the fast paths (the doubled degree's basis must fit [`MAXB`]).
const MAXD: usize = 15;
/// Length of the stack Bernstein buffers (degree 2 * MAXD).
const MAXB: usize = 2 * MAXD + 1;
/// Padding of the per-point rows and grid columns (a multiple of [`W`] and of the 8-point
/// chunks of [`basis_rows`]).
const LANES: usize = 8;
/// Lanes of the long dot products: entry k adds into partial sum k mod W.
const W: usize = 4;
/// Relative Cholesky pivot below which the normal equations are refused (SVD fallback): the
/// squared pivot L_ii^2 must exceed `PIVOT_REL` times the largest diagonal entry of G, which
/// bounds cond(G) from below by 1 / PIVOT_REL before the factorisation is trusted.
const PIVOT_REL: f64 = 1e-10;
/// Y below this fraction of sum |P|^2 is recomputed from the residual (cancellation).
const CANCEL_REL: f64 = 1e-6;

/// Reused buffers of one thread (no allocation per evaluation once grown).
#[derive(Default)]
pub(crate) struct Scratch {
    /// The clamped (and, for grids, sorted) decision vector.
    pub(crate) x: Vec<f64>,
    bu: Vec<f64>,
    bv: Vec<f64>,
    bu2: Vec<f64>,
    bv2: Vec<f64>,
    q: Vec<f64>,
    m: Vec<f64>,
    gq: Vec<f64>,
    acc: Vec<f64>,
    l: Vec<f64>,
    c: Vec<f64>,
    r: Vec<f64>,
    qa: Vec<f64>,
    qb: Vec<f64>,
    t: Vec<f64>,
    /// The rows P_c bv_b of the portable right-hand sides ([`rhs_acc`]).
    pv: Vec<f64>,
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// Run `f` with this thread's scratch buffers.
pub(crate) fn with_scratch<R>(f: impl FnOnce(&mut Scratch) -> R) -> R {
    SCRATCH.with(|s| f(&mut s.borrow_mut()))
}

fn grow(v: &mut Vec<f64>, n: usize) {
    if v.len() < n {
        v.resize(n, 0.0);
    }
}

/// Grow `v` to hold `n` entries from its first 64-byte boundary and return that offset, so that
/// the kernels' 4-lane loads and stores never straddle two cache lines.
fn align64(v: &mut Vec<f64>, n: usize) -> usize {
    grow(v, n + 8);
    v.as_ptr().align_offset(64).min(8)
}

/// The length of a padded row or column of n entries (the next multiple of [`LANES`]).
pub(crate) fn padded(n: usize) -> usize {
    n.div_ceil(LANES) * LANES
}

/// Binomial coefficient C(n, k) = prod_j (n - j) / (j + 1) as f64 (exact for the degrees here).
const fn binom(n: usize, k: usize) -> f64 {
    let mut acc = 1.0;
    let mut j = 0;
    while j < k {
        acc = acc * (n - j) as f64 / (j + 1) as f64;
        j += 1;
    }
    acc
}

/// C(n, k) for n, k < [`MAXB`] (zero for k > n), evaluated at compile time.
const BINOM: [[f64; MAXB]; MAXB] = {
    let mut t = [[0.0; MAXB]; MAXB];
    let mut n = 0;
    while n < MAXB {
        let mut k = 0;
        while k <= n {
            t[n][k] = binom(n, k);
            k += 1;
        }
        n += 1;
    }
    t
};

/// The Bernstein polynomials (seed 003, Eq. 3) without their binomials at every t_k:
/// m_a = t^a (1-t)^(n-a) for a in 0..=n into `out` and m2_i = t^i (1-t)^(2n-i) for i in 0..=2n
/// into `out2`, the latter as the product m2_i = m_(i-c) m_c with c = min(i, n); i-major, rows
/// `stride` apart (the multiple of 8 that [`padded`] gives for `t.len()`), 8 points at a time,
/// zero past `t.len()` (the padding lanes' powers of t start from 0). `V` picks the explicit
/// AVX2 copy (the same products in the same order, so the same bits).
#[inline(always)]
fn monomial_rows<const V: bool>(
    n: usize,
    t: &[f64],
    stride: usize,
    out: &mut [f64],
    out2: &mut [f64],
) {
    assert!(!t.is_empty() && stride == padded(t.len()) && n <= MAXD);
    assert!(out.len() >= (n + 1) * stride && out2.len() >= (2 * n + 1) * stride);
    #[cfg(target_arch = "x86_64")]
    if V {
        // SAFETY: V is only set by the copies compiled with AVX2 + FMA; the sizes are checked.
        unsafe { monomial_rows_avx2(n, t, stride, out, out2) };
        return;
    }
    let mut pt = [[0.0f64; 8]; MAXD + 1];
    let mut ps = [[0.0f64; 8]; MAXD + 1];
    let mut mr = [[0.0f64; 8]; MAXD + 1];
    for k0 in (0..stride).step_by(8) {
        powers8(n, t, k0, &mut pt, &mut ps);
        for a in 0..=n {
            for l in 0..8 {
                mr[a][l] = pt[a][l] * ps[n - a][l];
            }
            out[a * stride + k0..a * stride + k0 + 8].copy_from_slice(&mr[a]);
        }
        for i in 0..=2 * n {
            let c = i.min(n);
            let row = &mut out2[i * stride + k0..i * stride + k0 + 8];
            for l in 0..8 {
                row[l] = mr[i - c][l] * mr[c][l];
            }
        }
    }
}

/// [`monomial_rows`]' AVX2 copy: the degree as a constant (so every loop unrolls and the
/// powers stay at fixed places), 8 points (two registers) at a time.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn monomial_rows_avx2(
    n: usize,
    t: &[f64],
    stride: usize,
    out: &mut [f64],
    out2: &mut [f64],
) {
    macro_rules! by_degree {
        ($($d:literal)*) => {
            match n {
                $($d => monomial_rows_avx2_n::<$d>(t, stride, out, out2),)*
                _ => unreachable!("degree {n} above MAXD"),
            }
        };
    }
    by_degree!(0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15)
}

/// [`monomial_rows_avx2`] for degree N (exclusive ranges, so that every loop unrolls).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn monomial_rows_avx2_n<const N: usize>(
    t: &[f64],
    stride: usize,
    out: &mut [f64],
    out2: &mut [f64],
) {
    use std::arch::x86_64::*;
    assert!(N <= MAXD && out.len() >= (N + 1) * stride && out2.len() >= (2 * N + 1) * stride);
    let (po, po2) = (out.as_mut_ptr(), out2.as_mut_ptr());
    let one = _mm256_set1_pd(1.0);
    for k0 in (0..stride).step_by(2 * W) {
        let (tp, kp) = lanes8(t, k0);
        for h in 0..2 {
            let tv = _mm256_loadu_pd(tp.as_ptr().add(h * W));
            let sv = _mm256_sub_pd(one, tv);
            // only entries 0..=N are written and read: no fill of the unused ones
            let mut pt = [MaybeUninit::<__m256d>::uninit(); MAXD + 1];
            let mut ps = [MaybeUninit::<__m256d>::uninit(); MAXD + 1];
            let mut mr = [MaybeUninit::<__m256d>::uninit(); MAXD + 1];
            let (mut a, mut b) = (_mm256_loadu_pd(kp.as_ptr().add(h * W)), one);
            pt[0].write(a);
            ps[0].write(b);
            for i in 1..N + 1 {
                a = _mm256_mul_pd(a, tv);
                b = _mm256_mul_pd(b, sv);
                pt[i].write(a);
                ps[i].write(b);
            }
            for i in 0..N + 1 {
                let r = _mm256_mul_pd(pt[i].assume_init(), ps[N - i].assume_init());
                mr[i].write(r);
                _mm256_storeu_pd(po.add(i * stride + k0 + h * W), r);
            }
            for i in 0..2 * N + 1 {
                let c = if i < N { i } else { N };
                let r = _mm256_mul_pd(mr[i - c].assume_init(), mr[c].assume_init());
                _mm256_storeu_pd(po2.add(i * stride + k0 + h * W), r);
            }
        }
    }
}

/// Bernstein polynomials B^n_i(t_k) = C(n,i) (t^i (1-t)^(n-i)) for every t_k, stored i-major
/// (row i holds all k, `stride` apart, the multiple of 8 that [`padded`] gives for `t.len()`);
/// rows zero past `t.len()` (t^i and (1-t)^j by repeated multiplication, 8 points at a time; the
/// padding lanes' powers of t start from 0 instead of 1, so their rows are zero without a
/// separate fill).
#[inline(always)]
fn basis_rows<const V: bool>(n: usize, t: &[f64], stride: usize, out: &mut [f64]) {
    let np = t.len();
    assert!(np > 0 && stride == padded(np) && n <= MAXD && out.len() >= (n + 1) * stride);
    #[cfg(target_arch = "x86_64")]
    if V {
        // SAFETY: V is only set by the copies compiled with AVX2 + FMA; the sizes are checked.
        unsafe { basis_rows_avx2(n, t, stride, out) };
        return;
    }
    basis_rows_scalar(n, t, stride, out)
}

/// [`basis_rows`]' AVX2 copy: 8 points (two registers) at a time, four independent chains of
/// powers, the same products in the same order.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn basis_rows_avx2(n: usize, t: &[f64], stride: usize, out: &mut [f64]) {
    use std::arch::x86_64::*;
    let po = out.as_mut_ptr();
    let mut pt = [[_mm256_setzero_pd(); 2]; MAXD + 1];
    let mut ps = [[_mm256_setzero_pd(); 2]; MAXD + 1];
    let one = _mm256_set1_pd(1.0);
    for k0 in (0..stride).step_by(2 * W) {
        let (tp, kp) = lanes8(t, k0);
        let tv = [_mm256_loadu_pd(tp.as_ptr()), _mm256_loadu_pd(tp.as_ptr().add(W))];
        let sv = [_mm256_sub_pd(one, tv[0]), _mm256_sub_pd(one, tv[1])];
        let mut a = [_mm256_loadu_pd(kp.as_ptr()), _mm256_loadu_pd(kp.as_ptr().add(W))];
        let mut b = [one, one];
        pt[0] = a;
        ps[0] = b;
        for i in 1..=n {
            a = [_mm256_mul_pd(a[0], tv[0]), _mm256_mul_pd(a[1], tv[1])];
            b = [_mm256_mul_pd(b[0], sv[0]), _mm256_mul_pd(b[1], sv[1])];
            pt[i] = a;
            ps[i] = b;
        }
        for i in 0..=n {
            let w = _mm256_set1_pd(BINOM[n][i]);
            for h in 0..2 {
                let r = _mm256_mul_pd(w, _mm256_mul_pd(pt[i][h], ps[n - i][h]));
                _mm256_storeu_pd(po.add(i * stride + k0 + h * W), r);
            }
        }
    }
}

/// [`basis_rows`] in portable Rust (the baseline copy), 8 points at a time.
#[inline(always)]
fn basis_rows_scalar(n: usize, t: &[f64], stride: usize, out: &mut [f64]) {
    let mut pt = [[0.0f64; 8]; MAXD + 1];
    let mut ps = [[0.0f64; 8]; MAXD + 1];
    for k0 in (0..stride).step_by(8) {
        powers8(n, t, k0, &mut pt, &mut ps);
        for i in 0..=n {
            let w = BINOM[n][i];
            let row = &mut out[i * stride + k0..i * stride + k0 + 8];
            for l in 0..8 {
                row[l] = w * (pt[i][l] * ps[n - i][l]);
            }
        }
    }
}

/// The 8 values of `t` from k0, zero past its end, and the mask that is 1 where a value exists
/// and 0 in the padding (the start of the powers of t, so every row is zero there).
#[inline(always)]
fn lanes8(t: &[f64], k0: usize) -> ([f64; 8], [f64; 8]) {
    let m = t.len().saturating_sub(k0).min(8);
    let (mut tp, mut keep) = ([0.0f64; 8], [1.0f64; 8]);
    if m == 8 {
        tp.copy_from_slice(&t[k0..k0 + 8]);
    } else {
        tp[..m].copy_from_slice(&t[k0..k0 + m]);
        keep[m..].fill(0.0);
    }
    (tp, keep)
}

/// The powers t^i and (1-t)^i, i in 0..=n, of the 8 values of `t` from k0 (8 lanes, a chain of
/// products each; past `t.len()` t is 0 and the powers of t start from 0 instead of 1, so every
/// product with them is zero in the padding).
#[inline(always)]
fn powers8(
    n: usize,
    t: &[f64],
    k0: usize,
    pt: &mut [[f64; 8]; MAXD + 1],
    ps: &mut [[f64; 8]; MAXD + 1],
) {
    let (tp, keep) = lanes8(t, k0);
    let mut s1 = [0.0f64; 8];
    for l in 0..8 {
        s1[l] = 1.0 - tp[l];
    }
    let (mut a, mut b) = (keep, [1.0f64; 8]);
    pt[0] = a;
    ps[0] = b;
    for i in 1..=n {
        for l in 0..8 {
            a[l] *= tp[l];
            b[l] *= s1[l];
        }
        pt[i] = a;
        ps[i] = b;
    }
}

/// The dot product sum_k a_k b_k of two equally long slices in [`W`] partial sums (entry k into
/// lane k mod W by fused multiply-adds, whole chunks only), (s0 + s2) + (s1 + s3), then the
/// remainder in order.
#[inline(always)]
fn dot4(a: &[f64], b: &[f64]) -> f64 {
    let b = &b[..a.len()];
    let (ac, at) = a.as_chunks::<W>();
    let (bc, bt) = b.as_chunks::<W>();
    let mut h = [0.0f64; W];
    for (x, y) in ac.iter().zip(bc) {
        for l in 0..W {
            h[l] = x[l].mul_add(y[l], h[l]);
        }
    }
    let mut t = (h[0] + h[2]) + (h[1] + h[3]);
    for (x, y) in at.iter().zip(bt) {
        t = x.mul_add(*y, t);
    }
    t
}

/// out[i os + j] = sum_k a_ik b_jk for the `ra` rows of `a` and the `rb` rows of `b` (row-major,
/// rows `len` long, len a multiple of [`W`]): each sum in W partial sums (entry k into lane
/// k mod W, a chain of fused multiply-adds), combined as (s0 + s2) + (s1 + s3). Blocks of
/// 2 x 4 rows share their loads in registers; the value of every sum is independent of the
/// blocking (edge blocks repeat the last row and drop its results). `V` picks the explicit
/// AVX2 + FMA kernel (the same lanes, the same bits) in the vector copies.
#[inline(always)]
fn gemm_nt<const V: bool>(
    a: &[f64],
    ra: usize,
    b: &[f64],
    rb: usize,
    len: usize,
    out: &mut [f64],
    os: usize,
) {
    assert!(
        len.is_multiple_of(W) && ra > 0 && rb > 0 && a.len() >= ra * len && b.len() >= rb * len
    );
    assert!(out.len() > (ra - 1) * os + rb - 1);
    #[cfg(target_arch = "x86_64")]
    if V {
        // SAFETY: V is only set by the copies compiled with AVX2 + FMA; the sizes are checked.
        unsafe { gemm_nt_avx2(a, ra, b, rb, len, out, os) };
        return;
    }
    gemm_nt_scalar(a, ra, b, rb, len, out, os)
}

/// out[a w + j] = sum_i q[a lq + i] r[i w + j] for a < k, j < w (w a multiple of 24): the
/// columns of `q` (lq apart, n long) against the n rows of `r`, each sum one chain of fused
/// multiply-adds in the order of i from zero, so it has no lanes to combine and the same bits
/// whatever the blocking. `V` picks the explicit AVX2 + FMA kernel.
#[inline(always)]
fn gemm_tn<const V: bool>(
    q: &[f64],
    lq: usize,
    k: usize,
    r: &[f64],
    n: usize,
    w: usize,
    out: &mut [f64],
) {
    assert!(w.is_multiple_of(24) && k > 0 && n > 0 && n <= lq);
    assert!(q.len() >= (k - 1) * lq + n && r.len() >= n * w && out.len() >= k * w);
    #[cfg(target_arch = "x86_64")]
    if V {
        // SAFETY: V is only set by the copies compiled with AVX2 + FMA; the sizes are checked.
        unsafe { gemm_tn_avx2(q, lq, k, r, n, w, out) };
        return;
    }
    for a in 0..k {
        let o = &mut out[a * w..(a + 1) * w];
        o.fill(0.0);
        for (i, ri) in r.chunks_exact(w).take(n).enumerate() {
            let x = q[a * lq + i];
            for (oj, rj) in o.iter_mut().zip(ri) {
                *oj = x.mul_add(*rj, *oj);
            }
        }
    }
}

/// [`gemm_tn`] by register blocks of M rows of the output (k split into blocks of at most 5,
/// as even as possible) by 8 or 12 columns, accumulated over all n rows of `r` in registers.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn gemm_tn_avx2(
    q: &[f64],
    lq: usize,
    k: usize,
    r: &[f64],
    n: usize,
    w: usize,
    out: &mut [f64],
) {
    let blocks = k.div_ceil(5);
    let mut a0 = 0;
    for b in 0..blocks {
        // the rest as even as possible: never more than 5, as k - a0 <= 5 (blocks - b)
        let m = (k - a0) / (blocks - b);
        let (pq, po) = (q.as_ptr().add(a0 * lq), out.as_mut_ptr().add(a0 * w));
        match m {
            1 => tn_rows_avx2::<1, 3>(pq, lq, r.as_ptr(), n, w, po),
            2 => tn_rows_avx2::<2, 3>(pq, lq, r.as_ptr(), n, w, po),
            3 => tn_rows_avx2::<3, 3>(pq, lq, r.as_ptr(), n, w, po),
            4 => tn_rows_avx2::<4, 2>(pq, lq, r.as_ptr(), n, w, po),
            _ => tn_rows_avx2::<5, 2>(pq, lq, r.as_ptr(), n, w, po),
        }
        a0 += m;
    }
    debug_assert_eq!(a0, k);
}

/// M output rows of [`gemm_tn_avx2`], NJ vectors of 4 columns at a time: per row i of `r`, NJ
/// loads, M broadcasts and M NJ fused multiply-adds.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
unsafe fn tn_rows_avx2<const M: usize, const NJ: usize>(
    q: *const f64,
    lq: usize,
    r: *const f64,
    n: usize,
    w: usize,
    out: *mut f64,
) {
    use std::arch::x86_64::*;
    for j0 in (0..w).step_by(4 * NJ) {
        let mut acc = [[_mm256_setzero_pd(); NJ]; M];
        for i in 0..n {
            let ri = r.add(i * w + j0);
            let y: [__m256d; NJ] = std::array::from_fn(|v| _mm256_loadu_pd(ri.add(4 * v)));
            for (m, am) in acc.iter_mut().enumerate() {
                let x = _mm256_broadcast_sd(&*q.add(m * lq + i));
                for (v, amv) in am.iter_mut().enumerate() {
                    *amv = _mm256_fmadd_pd(x, y[v], *amv);
                }
            }
        }
        for (m, am) in acc.iter().enumerate() {
            for (v, amv) in am.iter().enumerate() {
                _mm256_storeu_pd(out.add(m * w + j0 + 4 * v), *amv);
            }
        }
    }
}

/// The register block of [`gemm_nt_avx2`] and [`gemm_nt_acc_avx2`]: acc[4 m + n] += a_m b_n
/// lane by lane over the `len / W` lane groups of rows a_0, a_1 and b_0..b_3 (one fused
/// multiply-add per group and accumulator, groups in order; two groups per turn of the loop).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
unsafe fn fma_2x4_avx2(
    a: [*const f64; 2],
    b: [*const f64; 4],
    len: usize,
    acc: &mut [std::arch::x86_64::__m256d; 8],
) {
    use std::arch::x86_64::*;
    let step = |k: usize, acc: &mut [__m256d; 8]| {
        let (x0, x1) = (_mm256_loadu_pd(a[0].add(k)), _mm256_loadu_pd(a[1].add(k)));
        for n in 0..4 {
            let y = _mm256_loadu_pd(b[n].add(k));
            acc[n] = _mm256_fmadd_pd(x0, y, acc[n]);
            acc[4 + n] = _mm256_fmadd_pd(x1, y, acc[4 + n]);
        }
    };
    let groups = len / W;
    let mut q = 0;
    while q + 2 <= groups {
        step(q * W, acc);
        step((q + 1) * W, acc);
        q += 2;
    }
    if q < groups {
        step(q * W, acc);
    }
}

/// The four sums (h0 + h2) + (h1 + h3) of the lanes h of `v[0..4]`, as one vector in order
/// (the same additions as the scalar reduction, so the same bits).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
unsafe fn hsum4_avx2(v: [std::arch::x86_64::__m256d; 4]) -> std::arch::x86_64::__m256d {
    use std::arch::x86_64::*;
    // (h0 + h2, h1 + h3) of v[0] in the low half and of v[2] in the high half; v[1], v[3] alike
    let lo_hi = |x, y| {
        _mm256_add_pd(_mm256_permute2f128_pd::<0x20>(x, y), _mm256_permute2f128_pd::<0x31>(x, y))
    };
    let (t02, t13) = (lo_hi(v[0], v[2]), lo_hi(v[1], v[3]));
    // hadd: (t02[0] + t02[1], t13[0] + t13[1], t02[2] + t02[3], t13[2] + t13[3])
    _mm256_hadd_pd(t02, t13)
}

/// [`gemm_nt`]'s 2 x 4 register blocks in AVX2 + FMA registers: lane l of each accumulator is
/// partial sum l; loads through raw pointers (the caller checked every row fits).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn gemm_nt_avx2(
    a: &[f64],
    ra: usize,
    b: &[f64],
    rb: usize,
    len: usize,
    out: &mut [f64],
    os: usize,
) {
    use std::arch::x86_64::*;
    let (pa, pb) = (a.as_ptr(), b.as_ptr());
    for i0 in (0..ra).step_by(2) {
        let a0 = pa.add(i0 * len);
        let a1 = pa.add((i0 + 1).min(ra - 1) * len);
        for j0 in (0..rb).step_by(4) {
            let b0 = pb.add(j0 * len);
            let b1 = pb.add((j0 + 1).min(rb - 1) * len);
            let b2 = pb.add((j0 + 2).min(rb - 1) * len);
            let b3 = pb.add((j0 + 3).min(rb - 1) * len);
            let mut acc = [_mm256_setzero_pd(); 8];
            fma_2x4_avx2([a0, a1], [b0, b1, b2, b3], len, &mut acc);
            for (m, am) in acc.chunks_exact(4).enumerate().take(ra - i0) {
                let sums = hsum4_avx2([am[0], am[1], am[2], am[3]]);
                let row = &mut out[(i0 + m) * os + j0..];
                if rb - j0 >= 4 {
                    _mm256_storeu_pd(row[..4].as_mut_ptr(), sums);
                } else {
                    let mut h = [0.0f64; 4];
                    _mm256_storeu_pd(h.as_mut_ptr(), sums);
                    row[..rb - j0].copy_from_slice(&h[..rb - j0]);
                }
            }
        }
    }
}

/// The register blocks of the portable product kernels: `f(i0, j0, a rows, b rows)` for every
/// block of MR rows of `a` (from i0) and NR rows of `b` (from j0), each row as its `len / W`
/// lane groups; edge blocks repeat the last row (the caller drops those results).
#[inline(always)]
fn for_blocks(
    a: &[f64],
    ra: usize,
    b: &[f64],
    rb: usize,
    len: usize,
    mut f: impl FnMut(usize, usize, &[&[[f64; W]]; MR], &[&[[f64; W]]; NR]),
) {
    let nc = len / W;
    for i0 in (0..ra).step_by(MR) {
        let ar: [&[[f64; W]]; MR] = std::array::from_fn(|m| {
            let i = (i0 + m).min(ra - 1);
            &a[i * len..(i + 1) * len].as_chunks().0[..nc]
        });
        for j0 in (0..rb).step_by(NR) {
            let br: [&[[f64; W]]; NR] = std::array::from_fn(|n| {
                let j = (j0 + n).min(rb - 1);
                &b[j * len..(j + 1) * len].as_chunks().0[..nc]
            });
            f(i0, j0, &ar, &br);
        }
    }
}

/// Rows of `a` and of `b` per register block of the portable product kernels.
const MR: usize = 2;
const NR: usize = 4;

/// The portable register block of the product kernels: acc[m][n][l] += a_m[c][l] b_n[c][l] over
/// the columns c < nc, one fused multiply-add per lane in column order.
#[inline(always)]
fn block_fma(
    ar: &[&[[f64; W]]; MR],
    br: &[&[[f64; W]]; NR],
    nc: usize,
    acc: &mut [[[f64; W]; NR]; MR],
) {
    for c in 0..nc {
        let mut xa = [[0.0f64; W]; MR];
        let mut xb = [[0.0f64; W]; NR];
        for m in 0..MR {
            xa[m] = ar[m][c];
        }
        for n in 0..NR {
            xb[n] = br[n][c];
        }
        for m in 0..MR {
            for n in 0..NR {
                for l in 0..W {
                    acc[m][n][l] = xa[m][l].mul_add(xb[n][l], acc[m][n][l]);
                }
            }
        }
    }
}

/// [`gemm_nt`] in portable Rust (the baseline copy's kernel).
#[inline(always)]
fn gemm_nt_scalar(
    a: &[f64],
    ra: usize,
    b: &[f64],
    rb: usize,
    len: usize,
    out: &mut [f64],
    os: usize,
) {
    for_blocks(a, ra, b, rb, len, |i0, j0, ar, br| {
        let mut acc = [[[0.0f64; W]; NR]; MR];
        block_fma(ar, br, len / W, &mut acc);
        for (m, am) in acc.iter().enumerate().take(ra - i0) {
            for (n, h) in am.iter().enumerate().take(rb - j0) {
                out[(i0 + m) * os + j0 + n] = (h[0] + h[2]) + (h[1] + h[3]);
            }
        }
    });
}

/// acc[(i rb + j) W + l] += sum_(k = l mod W) a_ik b_jk for the `ra` rows of `a` and the `rb` rows
/// of `b` (row-major, rows `len` long, len a multiple of [`W`]): [`gemm_nt`]'s partial sums
/// (entry k into lane k mod W, a chain of fused multiply-adds) left open, so that a product
/// over consecutive column blocks gives the same lanes as one product over all columns. Blocks
/// of 2 x 4 rows in registers (edge blocks repeat the last row and drop its results); `V` picks
/// the explicit AVX2 + FMA kernel (the same lanes, the same bits) in the vector copies.
#[inline(always)]
fn gemm_nt_acc<const V: bool>(
    a: &[f64],
    ra: usize,
    b: &[f64],
    rb: usize,
    len: usize,
    acc: &mut [f64],
) {
    assert!(
        len.is_multiple_of(W) && ra > 0 && rb > 0 && a.len() >= ra * len && b.len() >= rb * len
    );
    assert!(acc.len() >= ra * rb * W);
    #[cfg(target_arch = "x86_64")]
    if V {
        // SAFETY: V is only set by the copies compiled with AVX2 + FMA; the sizes are checked.
        unsafe { gemm_nt_acc_avx2(a, ra, b, rb, len, acc) };
        return;
    }
    gemm_nt_acc_scalar(a, ra, b, rb, len, acc)
}

/// [`gemm_nt_acc`]'s 2 x 4 register blocks in AVX2 + FMA registers (lane l of each register is
/// partial sum l); loads through raw pointers (the caller checked every row fits).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn gemm_nt_acc_avx2(
    a: &[f64],
    ra: usize,
    b: &[f64],
    rb: usize,
    len: usize,
    acc: &mut [f64],
) {
    use std::arch::x86_64::*;
    let (pa, pb, pc) = (a.as_ptr(), b.as_ptr(), acc.as_mut_ptr());
    for i0 in (0..ra).step_by(2) {
        let i1 = (i0 + 1).min(ra - 1);
        let (a0, a1) = (pa.add(i0 * len), pa.add(i1 * len));
        let (c0, c1) = (pc.add(i0 * rb * W), pc.add(i1 * rb * W));
        for j0 in (0..rb).step_by(4) {
            let (j1, j2, j3) = ((j0 + 1).min(rb - 1), (j0 + 2).min(rb - 1), (j0 + 3).min(rb - 1));
            let (b0, b1, b2, b3) =
                (pb.add(j0 * len), pb.add(j1 * len), pb.add(j2 * len), pb.add(j3 * len));
            // a repeated edge row or column loads the same sums and computes the same values
            // as its original, so storing all eight writes the same bits twice
            let mut acc = [
                _mm256_loadu_pd(c0.add(j0 * W)),
                _mm256_loadu_pd(c0.add(j1 * W)),
                _mm256_loadu_pd(c0.add(j2 * W)),
                _mm256_loadu_pd(c0.add(j3 * W)),
                _mm256_loadu_pd(c1.add(j0 * W)),
                _mm256_loadu_pd(c1.add(j1 * W)),
                _mm256_loadu_pd(c1.add(j2 * W)),
                _mm256_loadu_pd(c1.add(j3 * W)),
            ];
            fma_2x4_avx2([a0, a1], [b0, b1, b2, b3], len, &mut acc);
            let [h0, h1, h2, h3, h4, h5, h6, h7] = acc;
            _mm256_storeu_pd(c0.add(j0 * W), h0);
            _mm256_storeu_pd(c0.add(j1 * W), h1);
            _mm256_storeu_pd(c0.add(j2 * W), h2);
            _mm256_storeu_pd(c0.add(j3 * W), h3);
            _mm256_storeu_pd(c1.add(j0 * W), h4);
            _mm256_storeu_pd(c1.add(j1 * W), h5);
            _mm256_storeu_pd(c1.add(j2 * W), h6);
            _mm256_storeu_pd(c1.add(j3 * W), h7);
        }
    }
}

/// [`gemm_nt_acc`] in portable Rust (the baseline copy's kernel).
#[inline(always)]
fn gemm_nt_acc_scalar(a: &[f64], ra: usize, b: &[f64], rb: usize, len: usize, acc: &mut [f64]) {
    for_blocks(a, ra, b, rb, len, |i0, j0, ar, br| {
        let mut h = [[[0.0f64; W]; NR]; MR];
        for (m, hm) in h.iter_mut().enumerate() {
            for (n, hmn) in hm.iter_mut().enumerate() {
                let at = ((i0 + m).min(ra - 1) * rb + (j0 + n).min(rb - 1)) * W;
                hmn.copy_from_slice(&acc[at..at + W]);
            }
        }
        block_fma(ar, br, len / W, &mut h);
        for (m, hm) in h.iter().enumerate().take(ra - i0) {
            for (n, hmn) in hm.iter().enumerate().take(rb - j0) {
                let at = ((i0 + m) * rb + j0 + n) * W;
                acc[at..at + W].copy_from_slice(hmn);
            }
        }
    });
}

/// Scattered points as [`scattered_sse`] reads them: their number, their coordinates in
/// [`moments`]' layout (per block of [`BLK`] points the x, y and z rows, [`BLK`] apart, zero past
/// the last point; laid out once per problem instead of once per evaluation) and sum_k |P_k|^2.
#[derive(Debug, Clone)]
pub(crate) struct ScatteredData {
    len: usize,
    blocks: Vec<f64>,
    norm2: f64,
}

impl ScatteredData {
    pub(crate) fn new(pts: &[Point3]) -> ScatteredData {
        let mut blocks = vec![0.0; pts.len().div_ceil(BLK) * 3 * BLK];
        for (k, p) in pts.iter().enumerate() {
            for co in 0..3 {
                blocks[Self::at(k, co)] = p[co];
            }
        }
        let norm2 = pts.iter().flat_map(|p| p.iter()).map(|c| c * c).sum();
        ScatteredData { len: pts.len(), blocks, norm2 }
    }

    /// Where coordinate `co` of point k lies in `blocks`.
    fn at(k: usize, co: usize) -> usize {
        (3 * (k / BLK) + co) * BLK + k % BLK
    }

    /// Point k, read back from its block rows.
    fn point(&self, k: usize) -> Point3 {
        std::array::from_fn(|co| self.blocks[Self::at(k, co)])
    }
}

/// Y of the least-squares degree-(du, dv) Bezier surface through the scattered points at the
/// parameters x = (u_0, v_0, u_1, v_1, ...), by the normal equations G c = g with G = B^T B,
/// g = B^T P (B_k = kron(bu(u_k), bv(v_k))). The tensor structure gives, with the monomials
/// m^n_a(t) = t^a (1-t)^(n-a) (B^n_a = C(n,a) m^n_a, m^n_a m^n_c = m^2n_(a+c)),
/// G[(a,b),(c,d)] = C(du,a) C(du,c) C(dv,b) C(dv,d) M[a+c][b+d], M = sum_k m^2du(u_k) m^2dv(v_k)^T,
/// and g_(a,b) = C(du,a) C(dv,b) sum_k m^du_a(u_k) m^dv_b(v_k) P_k. With G = U^T U and
/// z = U^-T g, Y = |P|^2 - 2 g.c + c^T G c = |P|^2 - |z|^2 (the back substitution for c is
/// skipped); below 1e-6 |P|^2 c is solved for, refined once and Y summed from the residuals.
/// `None` if a Cholesky pivot is below [`PIVOT_REL`].
pub(crate) fn scattered_sse(
    du: usize,
    dv: usize,
    x: &[f64],
    data: &ScatteredData,
    s: &mut Scratch,
) -> Option<f64> {
    if du > MAXD || dv > MAXD || data.len == 0 || x.len() != 2 * data.len {
        return None;
    }
    #[cfg(target_arch = "x86_64")]
    match super::chosen() {
        // SAFETY: the dispatcher checked that the CPU has the copy's features.
        Isa::Avx2 | Isa::Avx512Vl => return unsafe { scattered_sse_avx2(du, dv, x, data, s) },
        Isa::Baseline => {}
    }
    scattered_sse_body::<false>(du, dv, x, data, s)
}

/// [`scattered_sse_body`] compiled for AVX2 + FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn scattered_sse_avx2(
    du: usize,
    dv: usize,
    x: &[f64],
    data: &ScatteredData,
    s: &mut Scratch,
) -> Option<f64> {
    scattered_sse_body::<true>(du, dv, x, data, s)
}

#[inline(always)]
fn scattered_sse_body<const V: bool>(
    du: usize,
    dv: usize,
    x: &[f64],
    data: &ScatteredData,
    s: &mut Scratch,
) -> Option<f64> {
    let (ku, kv) = (du + 1, dv + 1);
    let n = ku * kv;
    moments::<V>(du, dv, x, data, s);
    // the upper triangle of G from the moments straight into the factor's buffer, g from gq
    // (gq[(a, c), b] = sum_k bu_a P_c bv_b)
    let lo = align64(&mut s.l, n * n);
    grow(&mut s.c, 3 * n);
    let m2 = 2 * dv + 1;
    // the binomials the monomial rows left out: C(du,a) C(du,c) C(dv,b) C(dv,d) is an integer
    // below 2^53 for every degree up to MAXD (C(15,7)^4 < 1.8e15), so exact
    let (cu, cv) = (&BINOM[du], &BINOM[dv]);
    for a in 0..ku {
        for b in 0..kv {
            let wab = cu[a] * cv[b];
            let row = &mut s.l[lo + (a * kv + b) * n..lo + (a * kv + b + 1) * n];
            for c in a..ku {
                let mrow = &s.m[(a + c) * m2 + b..];
                let d0 = if c == a { b } else { 0 };
                for d in d0..kv {
                    row[c * kv + d] = (wab * (cu[c] * cv[d])) * mrow[d];
                }
            }
            for co in 0..3 {
                s.c[co * n + a * kv + b] = wab * s.gq[(a * 3 + co) * kv + b];
            }
        }
    }
    if !cholesky::<V>(&mut s.l[lo..lo + n * n], n) {
        return None;
    }
    // z = U^-T g: Y = |P|^2 - 2 g.c + c^T G c = |P|^2 - |z|^2 (c = U^-1 z, c^T G c = |U c|^2)
    forward_solve(&s.l[lo..lo + n * n], n, &mut s.c[..3 * n]);
    let y = data.norm2 - dot4(&s.c[..3 * n], &s.c[..3 * n]);
    if y > CANCEL_REL * data.norm2 {
        return Some(y);
    }
    back_solve(&s.l[lo..lo + n * n], n, &mut s.c[..3 * n]);
    Some(refined_residual(du, dv, x, data, lo, s))
}

/// Points per block of [`moments`]' fused pass (the block's basis rows stay in L1).
const BLK: usize = 64;

/// The moments M (i-major (2du+1) x (2dv+1)) and gq ((du+1) * 3 rows of dv+1) of
/// [`scattered_sse`] (binomials left out), block by block of [`BLK`] points: the block's
/// i-major monomial rows ([`monomial_rows`]), then M's product ([`gemm_nt_acc`]) and the
/// right-hand sides' ([`rhs_acc`], the coordinates from the `data`'s block rows) accumulate into
/// 4-lane partial sums that run on across the blocks, so every sum has the order of one product
/// over all points (lane k mod 4).
#[inline(always)]
fn moments<const V: bool>(du: usize, dv: usize, x: &[f64], data: &ScatteredData, s: &mut Scratch) {
    let np = data.len;
    let (ku, kv) = (du + 1, dv + 1);
    let (ku2, kv2) = (2 * du + 1, 2 * dv + 1);
    // every buffer from a 64-byte boundary (rows BLK long stay aligned)
    let nacc = W * (ku2 * kv2 + ku * 3 * kv);
    let o = [
        align64(&mut s.q, 2 * BLK),
        align64(&mut s.bu, ku * BLK),
        align64(&mut s.bv, kv * BLK),
        align64(&mut s.bu2, ku2 * BLK),
        align64(&mut s.bv2, kv2 * BLK),
        // the P_c bv_b rows only for the portable copy (the AVX2 copy forms them in registers)
        align64(&mut s.pv, if V { 0 } else { 3 * kv * BLK }),
        align64(&mut s.acc, nacc),
    ];
    let (bu, bv) = (&mut s.bu[o[1]..], &mut s.bv[o[2]..]);
    let (bu2, bv2, pv) = (&mut s.bu2[o[3]..], &mut s.bv2[o[4]..], &mut s.pv[o[5]..]);
    let (macc, gacc) = s.acc[o[6]..o[6] + nacc].split_at_mut(W * ku2 * kv2);
    macc.fill(0.0);
    gacc.fill(0.0);
    for k0 in (0..np).step_by(BLK) {
        let m = (np - k0).min(BLK);
        let len = padded(m);
        // the block's parameters (q[0..BLK], q[BLK..2 BLK]) and coordinates (3 rows of BLK)
        let tq = &mut s.q[o[0]..o[0] + 2 * BLK];
        for (k, uv) in x[2 * k0..2 * (k0 + m)].chunks_exact(2).enumerate() {
            tq[k] = uv[0];
            tq[BLK + k] = uv[1];
        }
        let pq = &data.blocks[3 * k0..3 * (k0 + BLK)];
        monomial_rows::<V>(du, &tq[..m], len, bu, bu2);
        monomial_rows::<V>(dv, &tq[BLK..BLK + m], len, bv, bv2);
        gemm_nt_acc::<V>(bu2, ku2, bv2, kv2, len, macc);
        rhs_acc::<V>([bu, bv], [ku, kv], pq, len, pv, gacc);
    }
    grow(&mut s.m, ku2 * kv2);
    grow(&mut s.gq, ku * 3 * kv);
    for (o, h) in s.m.iter_mut().zip(macc.as_chunks::<W>().0) {
        *o = (h[0] + h[2]) + (h[1] + h[3]);
    }
    for (o, h) in s.gq.iter_mut().zip(gacc.as_chunks::<W>().0) {
        *o = (h[0] + h[2]) + (h[1] + h[3]);
    }
}

/// The right-hand sides' partial sums of [`moments`]: [`gemm_nt_acc`] of the `ku` rows of `bu`
/// against the 3 kv rows P_c bv_b ((c, b)-major), with `pq` the block's coordinates (rows [`BLK`]
/// apart, zero past the points as `bv` is). The portable copy forms those rows in `pv`; the AVX2
/// copy ([`rhs_acc_avx2`]) forms each in registers where it is used and stores none (the same
/// products and fused multiply-adds in the same order, so the same bits).
#[inline(always)]
fn rhs_acc<const V: bool>(
    [bu, bv]: [&[f64]; 2],
    [ku, kv]: [usize; 2],
    pq: &[f64],
    len: usize,
    pv: &mut [f64],
    acc: &mut [f64],
) {
    assert!(len.is_multiple_of(W) && len <= BLK && pq.len() >= 2 * BLK + len);
    assert!(bu.len() >= ku * len && bv.len() >= kv * len && acc.len() >= ku * 3 * kv * W);
    #[cfg(target_arch = "x86_64")]
    if V {
        // SAFETY: V is only set by the copies compiled with AVX2 + FMA; the sizes are checked.
        unsafe { rhs_acc_avx2([bu, bv], [ku, kv], pq, len, acc) };
        return;
    }
    for co in 0..3 {
        let pc = &pq[co * BLK..co * BLK + len];
        for b in 0..kv {
            let out = &mut pv[(co * kv + b) * len..(co * kv + b + 1) * len];
            for ((o, p), bv) in out.iter_mut().zip(pc).zip(&bv[b * len..(b + 1) * len]) {
                *o = p * bv;
            }
        }
    }
    gemm_nt_acc::<false>(bu, ku, pv, 3 * kv, len, acc);
}

/// [`rhs_acc`] in AVX2 + FMA registers: blocks of up to 6 rows of `bu` by 2 rows P_c bv_b, each
/// P_c bv_b formed once per block and lane group (no stored rows, no repeated edge rows).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn rhs_acc_avx2(
    [bu, bv]: [&[f64]; 2],
    [ku, kv]: [usize; 2],
    pq: &[f64],
    len: usize,
    acc: &mut [f64],
) {
    let rb = 3 * kv;
    for co in 0..3 {
        for b0 in (0..kv).step_by(2) {
            let j0 = co * kv + b0;
            let rows = (pq.as_ptr().add(co * BLK), bv.as_ptr().add(b0 * len));
            for a0 in (0..ku).step_by(6) {
                let (pa, pc) =
                    (bu.as_ptr().add(a0 * len), acc.as_mut_ptr().add((a0 * rb + j0) * W));
                macro_rules! by_rows {
                    ($($m:literal)*) => {
                        match ((ku - a0).min(6), kv - b0 >= 2) {
                            $(($m, true) => rhs_block_avx2::<$m, 2>(pa, rows, len, pc, rb),
                              ($m, false) => rhs_block_avx2::<$m, 1>(pa, rows, len, pc, rb),)*
                            _ => unreachable!(),
                        }
                    };
                }
                by_rows!(1 2 3 4 5 6)
            }
        }
    }
}

/// One register block of [`rhs_acc_avx2`]: `acc[m][n] += a_m (P bv_n)` over the `len` points,
/// `MA` rows of a (`len` apart from `pa`), `NB` rows of bv (from `rows.1`) with the coordinate row
/// `rows.0`; the sums at `pc + (m rb + n) W`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn rhs_block_avx2<const MA: usize, const NB: usize>(
    pa: *const f64,
    rows: (*const f64, *const f64),
    len: usize,
    pc: *mut f64,
    rb: usize,
) {
    use std::arch::x86_64::*;
    let (pp, pb) = rows;
    let mut h = [[_mm256_setzero_pd(); NB]; MA];
    for (m, hm) in h.iter_mut().enumerate() {
        for (n, hmn) in hm.iter_mut().enumerate() {
            *hmn = _mm256_loadu_pd(pc.add((m * rb + n) * W));
        }
    }
    let mut k = 0;
    while k < len {
        let p = _mm256_loadu_pd(pp.add(k));
        let pv: [__m256d; NB] =
            std::array::from_fn(|n| _mm256_mul_pd(p, _mm256_loadu_pd(pb.add(n * len + k))));
        for (m, hm) in h.iter_mut().enumerate() {
            let x = _mm256_loadu_pd(pa.add(m * len + k));
            for (hmn, pvn) in hm.iter_mut().zip(&pv) {
                *hmn = _mm256_fmadd_pd(x, *pvn, *hmn);
            }
        }
        k += W;
    }
    for (m, hm) in h.iter().enumerate() {
        for (n, hmn) in hm.iter().enumerate() {
            _mm256_storeu_pd(pc.add((m * rb + n) * W), *hmn);
        }
    }
}

/// Near-exact fit: one step of iterative refinement (c += G^-1 B^T (P - B c)) and Y summed from
/// the residuals sum_k |P_k - B_k c|^2, so a tiny Y keeps its relative precision. Uses the
/// Cholesky factor and solution left in the scratch by [`scattered_sse`].
fn refined_residual(
    du: usize,
    dv: usize,
    x: &[f64],
    data: &ScatteredData,
    lo: usize,
    s: &mut Scratch,
) -> f64 {
    let (ku, kv) = (du + 1, dv + 1);
    let n = ku * kv;
    let residual = |c: &[f64], acc: &mut [f64]| -> f64 {
        acc.fill(0.0);
        let mut y = 0.0;
        let (mut bu, mut bv) = ([0.0; MAXB], [0.0; MAXB]);
        for (k, uv) in x.chunks_exact(2).enumerate() {
            crate::spline::bezier::bernstein_into(du, uv[0], &mut bu[..ku]);
            crate::spline::bezier::bernstein_into(dv, uv[1], &mut bv[..kv]);
            let mut e = data.point(k);
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
    chol_solve(&s.l[lo..lo + n * n], n, &mut corr);
    for (c, d) in s.c[..3 * n].iter_mut().zip(&corr) {
        *c += d;
    }
    let y = residual(&s.c[..3 * n], &mut corr);
    s.r = corr;
    y
}

/// Cholesky G = U^T U in place in the n x n row-major `u`, which holds G's upper triangle on
/// entry (row j of U = column j of L), right-looking so that each step updates whole rows; false
/// if a squared pivot U_jj^2 is at most [`PIVOT_REL`] times max_i G_ii (or not finite). The
/// updates run over whole groups of [`W`] columns from the group holding the diagonal, so they
/// also write a few entries below it: the strict lower triangle is scratch, never read.
#[inline(always)]
fn cholesky<const V: bool>(u: &mut [f64], n: usize) -> bool {
    let dmax = (0..n).fold(0.0f64, |m, i| m.max(u[i * n + i]));
    if !(dmax > 0.0 && dmax.is_finite()) {
        return false;
    }
    #[cfg(target_arch = "x86_64")]
    if V {
        // SAFETY: V is only set by the copies compiled with AVX2 + FMA.
        return unsafe { cholesky_avx2(u, n, dmax) };
    }
    for j in 0..n {
        if !pivot_row(u, n, j, dmax) {
            return false;
        }
        let (top, rest) = u.split_at_mut((j + 1) * n);
        let rowj = &top[j * n..];
        for (i, rowi) in (j + 1..n).zip(rest.chunks_exact_mut(n)) {
            let f = rowj[i];
            let i0 = i / W * W;
            let (xc, xt) = rowi[i0..].as_chunks_mut::<W>();
            let (yc, yt) = rowj[i0..].as_chunks::<W>();
            for (x, y) in xc.iter_mut().zip(yc) {
                for l in 0..W {
                    x[l] = (-f).mul_add(y[l], x[l]);
                }
            }
            for (x, y) in xt.iter_mut().zip(yt) {
                *x = (-f).mul_add(*y, *x);
            }
        }
    }
    true
}

/// Row j of U: its pivot checked against [`PIVOT_REL`] `dmax` (false if below or not a number),
/// then the row from the diagonal divided by the pivot's square root.
#[inline(always)]
fn pivot_row(u: &mut [f64], n: usize, j: usize, dmax: f64) -> bool {
    let d = u[j * n + j];
    if d.is_nan() || d <= PIVOT_REL * dmax {
        return false;
    }
    let r = d.sqrt();
    for x in u[j * n + j..(j + 1) * n].iter_mut() {
        *x /= r;
    }
    true
}

/// Steps of [`cholesky_avx2`] whose updates of the rows below them run in one pass.
const CHOL_STEPS: usize = 4;

/// [`cholesky`] in AVX2 + FMA: steps in groups of [`CHOL_STEPS`]. A group's own rows take its
/// steps one by one; every row below takes all of them in one pass over its columns (each entry
/// loaded and stored once, its fused multiply-adds in step order), so every entry gets the same
/// operations in the same order as in the portable loop: the same bits.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn cholesky_avx2(u: &mut [f64], n: usize, dmax: f64) -> bool {
    let mut j0 = 0;
    while j0 < n {
        let j1 = (j0 + CHOL_STEPS).min(n);
        for j in j0..j1 {
            if !pivot_row(u, n, j, dmax) {
                return false;
            }
            let (top, rest) = u.split_at_mut((j + 1) * n);
            rank_rows_avx2::<1>(&top[j * n..], rest, j + 1..j1, n);
        }
        let (top, rest) = u.split_at_mut(j1 * n);
        match j1 - j0 {
            4 => rank_rows_avx2::<4>(&top[j0 * n..], rest, j1..n, n),
            3 => rank_rows_avx2::<3>(&top[j0 * n..], rest, j1..n, n),
            2 => rank_rows_avx2::<2>(&top[j0 * n..], rest, j1..n, n),
            _ => rank_rows_avx2::<1>(&top[j0 * n..], rest, j1..n, n),
        }
        j0 = j1;
    }
    true
}

/// The `S` steps whose rows are `rows` (S rows of n, finished) on the rows i in `to` (rows
/// 0.. of `rest` from `to.start`): x_k = fma(-U_si, U_sk, x_k) for s in step order, each group of
/// [`W`] columns from the one holding column i loaded and stored once, then the remaining columns
/// one by one.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn rank_rows_avx2<const S: usize>(
    rows: &[f64],
    rest: &mut [f64],
    to: std::ops::Range<usize>,
    n: usize,
) {
    use std::arch::x86_64::*;
    let from = to.start;
    assert!(rows.len() >= S * n && to.end <= n && rest.len() >= to.len() * n);
    let (py, px) = (rows.as_ptr(), rest.as_mut_ptr());
    for i in to {
        let f: [f64; S] = std::array::from_fn(|s| *py.add(s * n + i));
        let nf = f.map(|f| _mm256_set1_pd(-f));
        let row = px.add((i - from) * n);
        let i0 = i / W * W;
        let whole = i0 + (n - i0) / W * W;
        let mut k = i0;
        while k < whole {
            let mut r = _mm256_loadu_pd(row.add(k));
            for (s, nfs) in nf.iter().enumerate() {
                r = _mm256_fmadd_pd(*nfs, _mm256_loadu_pd(py.add(s * n + k)), r);
            }
            _mm256_storeu_pd(row.add(k), r);
            k += W;
        }
        while k < n {
            let mut r = *row.add(k);
            for (s, fs) in f.iter().enumerate() {
                r = (-fs).mul_add(*py.add(s * n + k), r);
            }
            *row.add(k) = r;
            k += 1;
        }
    }
}

/// Forward substitution U^T z = b in place for the three right-hand sides of `c` (three rows of
/// n): z_j = (b_j - sum_(i<j) U_ij z_i) / U_jj, by row-wise fused updates.
#[inline(always)]
fn forward_solve(u: &[f64], n: usize, c: &mut [f64]) {
    for col in c.chunks_exact_mut(n).take(3) {
        for j in 0..n {
            let y = col[j] / u[j * n + j];
            col[j] = y;
            for (x, uj) in col[j + 1..].iter_mut().zip(&u[j * n + j + 1..(j + 1) * n]) {
                *x = (-y).mul_add(*uj, *x);
            }
        }
    }
}

/// Back substitution U c = z in place for the three right-hand sides of `c`:
/// c_j = (z_j - sum_(i>j) U_ji c_i) / U_jj.
#[inline(always)]
fn back_solve(u: &[f64], n: usize, c: &mut [f64]) {
    for col in c.chunks_exact_mut(n).take(3) {
        for j in (0..n).rev() {
            let s = dots_any(&u[j * n + j + 1..(j + 1) * n], [&col[j + 1..]])[0];
            col[j] = (col[j] - s) / u[j * n + j];
        }
    }
}

/// Solve U^T U c = b in place for the three right-hand sides of `c` (three rows of n).
#[inline(always)]
fn chol_solve(u: &[f64], n: usize, c: &mut [f64]) {
    forward_solve(u, n, c);
    back_solve(u, n, c);
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

/// Longest slice [`sort_params`] ranks with AVX2 (longer ones take the std sort).
const RANK_MAX: usize = 128;

/// Sort `t` ascending by [`f64::total_cmp`] (seed 003's grid parameters, twice per evaluation).
/// The AVX2 copy ranks every entry by comparisons against all others instead of the std sort
/// (about 0.7 us for 41 values on Zen 3); keys equal under `total_cmp` are equal bits, so every
/// correct sort gives the same slice, bit for bit.
pub(crate) fn sort_params(t: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    if t.len() <= RANK_MAX && super::use_avx2() {
        // SAFETY: `use_avx2` is true only when this CPU has AVX2 + FMA; the length is checked.
        unsafe { rank_sort_avx2(t) };
        return;
    }
    t.sort_by(f64::total_cmp);
}

/// [`sort_params`] by ranks: with i64 keys ordered as `total_cmp` orders the values,
/// rank_i = #{j < i: k_j <= k_i} + #{j > i: k_j < k_i} (distinct ranks 0..n, ties kept in
/// order), four i per register against every j, then `t[rank_i] = old t_i`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn rank_sort_avx2(t: &mut [f64]) {
    use std::arch::x86_64::*;
    let n = t.len();
    assert!(n <= RANK_MAX);
    let mut keys = [0i64; RANK_MAX];
    let mut vals = [0.0f64; RANK_MAX];
    for (i, &x) in t.iter().enumerate() {
        let b = x.to_bits() as i64;
        // total_cmp's key: flip the magnitude bits of negative values
        keys[i] = b ^ (((b >> 63) as u64) >> 1) as i64;
        vals[i] = x;
    }
    let kp = keys.as_ptr();
    for b0 in (0..n).step_by(W) {
        let ki = _mm256_loadu_si256(kp.add(b0) as *const __m256i);
        // lanes past n hold key 0 and are never stored
        let mut acc = _mm256_setzero_si256();
        for j in 0..b0 {
            // k_j > k_i: one fewer of the b0 earlier entries at or below k_i
            acc = _mm256_add_epi64(acc, _mm256_cmpgt_epi64(_mm256_set1_epi64x(*kp.add(j)), ki));
        }
        let idx = _mm256_setr_epi64x(b0 as i64, b0 as i64 + 1, b0 as i64 + 2, b0 as i64 + 3);
        for j in b0..(b0 + W).min(n) {
            let kj = _mm256_set1_epi64x(*kp.add(j));
            let before = _mm256_cmpgt_epi64(idx, _mm256_set1_epi64x(j as i64));
            let counted = _mm256_or_si256(
                _mm256_cmpgt_epi64(ki, kj),
                _mm256_and_si256(before, _mm256_cmpeq_epi64(ki, kj)),
            );
            acc = _mm256_sub_epi64(acc, counted);
        }
        for j in b0 + W..n {
            acc = _mm256_sub_epi64(acc, _mm256_cmpgt_epi64(ki, _mm256_set1_epi64x(*kp.add(j))));
        }
        let mut r = [0i64; W];
        _mm256_storeu_si256(r.as_mut_ptr() as *mut __m256i, acc);
        for (l, &rl) in r.iter().enumerate().take(n - b0) {
            let rank = b0 as i64 + rl;
            debug_assert!((0..n as i64).contains(&rank));
            t[rank as usize] = vals[b0 + l];
        }
    }
}

/// Thin Q of the Householder QR of the n x (deg+1) Bernstein collocation matrix A at the sorted
/// parameters `t` (A = Q R), column-major into `q` (deg+1 columns `lp` = [`padded`](n) long, zero
/// past n); `None` unless n > deg and every |R_jj| exceeds 1e-8 max |R_ii| (the test of the
/// parent module's `column_basis`, whose SVD then takes over). Reflector j is
/// H_j = I - beta_j v_j v_j^T with v_j zero above row j, kept as full padded columns so that every
/// update is 4 lanes over the rows; `work` holds A (reduced in place) and the reflectors.
#[inline(always)]
fn thin_q<const V: bool>(
    deg: usize,
    t: &[f64],
    q: &mut Vec<f64>,
    work: &mut Vec<f64>,
) -> Option<()> {
    let (n, k, lp) = (t.len(), deg + 1, padded(t.len()));
    if n <= deg || deg > MAXD {
        return None;
    }
    grow(work, 2 * k * lp);
    let (a, refl) = work.split_at_mut(k * lp);
    basis_rows::<V>(deg, t, lp, a); // column j of A = row j here
    let mut diag = [0.0f64; MAXB];
    let mut beta = [0.0f64; MAXB];
    for j in 0..k {
        let v = &mut refl[j * lp..(j + 1) * lp];
        v.copy_from_slice(&a[j * lp..(j + 1) * lp]);
        v[..j].fill(0.0);
        let norm = dot8(v, v).sqrt();
        let alpha = if v[j] > 0.0 { -norm } else { norm };
        diag[j] = alpha;
        // |v - alpha e_j|^2 = 2 norm (norm + |v_j|): no second dot product on the critical path
        let vv = 2.0 * norm * (norm + v[j].abs());
        v[j] -= alpha;
        beta[j] = if vv > 0.0 { 2.0 / vv } else { 0.0 };
        reflect_cols::<V>(v, beta[j], &mut a[(j + 1) * lp..k * lp], lp);
    }
    let rmax = diag[..k].iter().fold(0.0f64, |m, d| m.max(d.abs()));
    if !diag[..k].iter().all(|d| d.abs() > 1e-8 * rmax) {
        return None;
    }
    // Q = H_0 ... H_(k-1) [I; 0]; H_j leaves columns c < j (= e_c) unchanged
    grow(q, k * lp);
    q[..k * lp].fill(0.0);
    for c in 0..k {
        q[c * lp + c] = 1.0;
    }
    for j in (0..k).rev() {
        let v = &refl[j * lp..(j + 1) * lp];
        reflect_cols::<V>(v, beta[j], &mut q[j * lp..k * lp], lp);
    }
    Some(())
}

/// Apply H = I - beta v v^T to each `lp`-long column of `cols` (lp a multiple of [`LANES`]):
/// x -= (beta (v . x)) v by fused multiply-adds, the dot product as in [`dot8`]. `V` picks the
/// AVX2 + FMA kernel, which takes four columns at a time (the columns are independent and each
/// sum keeps its order, so the bits are those of one column after another).
#[inline(always)]
fn reflect_cols<const V: bool>(v: &[f64], beta: f64, cols: &mut [f64], lp: usize) {
    assert!(lp.is_multiple_of(LANES) && v.len() == lp && cols.len().is_multiple_of(lp));
    #[cfg(target_arch = "x86_64")]
    if V {
        // SAFETY: V is only set by the copies compiled with AVX2 + FMA; the sizes are checked.
        unsafe { reflect_cols_avx2(v, beta, cols, lp) };
        return;
    }
    for x in cols.chunks_exact_mut(lp) {
        axpy(-(beta * dot8(v, x)), v, x);
    }
}

/// [`reflect_cols`] in AVX2 + FMA registers: four columns' dot products in two accumulators
/// each (lanes 0-3 and 4-7 of [`dot8`]), reduced by [`hsum4_avx2`], then the four updates.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn reflect_cols_avx2(v: &[f64], beta: f64, cols: &mut [f64], lp: usize) {
    use std::arch::x86_64::*;
    let pv = v.as_ptr();
    let mut quads = cols.chunks_exact_mut(4 * lp);
    for g in &mut quads {
        let p = g.as_mut_ptr();
        let mut acc = [[_mm256_setzero_pd(); 2]; 4];
        for k in (0..lp).step_by(LANES) {
            let (x0, x1) = (_mm256_loadu_pd(pv.add(k)), _mm256_loadu_pd(pv.add(k + 4)));
            for (r, a) in acc.iter_mut().enumerate() {
                a[0] = _mm256_fmadd_pd(x0, _mm256_loadu_pd(p.add(r * lp + k)), a[0]);
                a[1] = _mm256_fmadd_pd(x1, _mm256_loadu_pd(p.add(r * lp + k + 4)), a[1]);
            }
        }
        let d = hsum4_avx2(acc.map(|a| _mm256_add_pd(a[0], a[1])));
        // -(beta d) for the four dot products d, each in all lanes
        let f = _mm256_xor_pd(_mm256_mul_pd(_mm256_set1_pd(beta), d), _mm256_set1_pd(-0.0));
        let fb = [
            _mm256_permute4x64_pd::<0x00>(f),
            _mm256_permute4x64_pd::<0x55>(f),
            _mm256_permute4x64_pd::<0xAA>(f),
            _mm256_permute4x64_pd::<0xFF>(f),
        ];
        for k in (0..lp).step_by(W) {
            let x = _mm256_loadu_pd(pv.add(k));
            for (r, fr) in fb.iter().enumerate() {
                let q = p.add(r * lp + k);
                _mm256_storeu_pd(q, _mm256_fmadd_pd(*fr, x, _mm256_loadu_pd(q)));
            }
        }
    }
    reflect_cols::<false>(v, beta, quads.into_remainder(), lp);
}

/// The dot product of two equally long slices (a multiple of [`LANES`] long) in 8 partial sums
/// (entry k into lane k mod 8 by fused multiply-adds), t_l = s_l + s_(l+4), then
/// (t0 + t2) + (t1 + t3): the Householder steps' dot products, whose chains are half as long as
/// [`dot4`]'s.
#[inline(always)]
fn dot8(a: &[f64], b: &[f64]) -> f64 {
    assert!(a.len().is_multiple_of(LANES));
    let (ac, _) = a.as_chunks::<LANES>();
    let (bc, _) = b[..a.len()].as_chunks::<LANES>();
    let mut h = [0.0f64; LANES];
    for (x, y) in ac.iter().zip(bc) {
        for l in 0..LANES {
            h[l] = x[l].mul_add(y[l], h[l]);
        }
    }
    let t: [f64; 4] = std::array::from_fn(|l| h[l] + h[l + 4]);
    (t[0] + t[2]) + (t[1] + t[3])
}

/// x += f v by fused multiply-adds.
#[inline(always)]
fn axpy(f: f64, v: &[f64], x: &mut [f64]) {
    for (xi, vi) in x.iter_mut().zip(v) {
        *xi = f.mul_add(*vi, *xi);
    }
}

/// Y of the grid fit by the separable projection Y = |D|^2 - sum_c |Qu^T D_c Qv|^2 (see
/// [`crate::spline::bezier::grid_sse`]) with the thin Qs from [`thin_q`]; `None` when a collocation matrix is
/// (nearly) rank deficient or a grid side exceeds 128. Below 1e-6 |D|^2 the residual
/// D_c - Qu C_c Qv^T is summed instead.
pub(crate) fn grid_sse(
    du: usize,
    dv: usize,
    u: &[f64],
    v: &[f64],
    data: &GridData,
    s: &mut Scratch,
) -> Option<f64> {
    #[cfg(target_arch = "x86_64")]
    match super::chosen() {
        // SAFETY: the dispatcher checked that the CPU has the copy's features.
        Isa::Avx2 | Isa::Avx512Vl => return unsafe { grid_sse_avx2(du, dv, u, v, data, s) },
        Isa::Baseline => {}
    }
    grid_sse_body::<false>(du, dv, u, v, data, s)
}

/// [`grid_sse_body`] compiled for AVX2 + FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn grid_sse_avx2(
    du: usize,
    dv: usize,
    u: &[f64],
    v: &[f64],
    data: &GridData,
    s: &mut Scratch,
) -> Option<f64> {
    grid_sse_body::<true>(du, dv, u, v, data, s)
}

#[inline(always)]
fn grid_sse_body<const V: bool>(
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
    let (lu, lv) = (padded(nu), padded(nv));
    thin_q::<V>(du, u, &mut s.qa, &mut s.l)?;
    thin_q::<V>(dv, v, &mut s.qb, &mut s.l)?;
    // T = Qu^T [D_x D_y D_z]: row a holds coordinate c's nv entries at c lv.. (zero padded,
    // as the data rows are)
    let w = 3 * lv;
    grow(&mut s.t, ku * w);
    gemm_tn::<V>(&s.qa, lu, ku, &data.rows, nu, w, &mut s.t);
    // C = T_c Qv: row 3a + c of T (lv long) against column b of Qv, into s.c[(3a + c) kv + b]
    let nc = 3 * ku * kv;
    grow(&mut s.c, nc);
    gemm_nt::<V>(&s.t, 3 * ku, &s.qb, kv, lv, &mut s.c, kv);
    let kept = dot4(&s.c[..nc], &s.c[..nc]);
    let y = data.norm2 - kept;
    if y > CANCEL_REL * data.norm2 {
        return Some(y);
    }
    Some(grid_residual(ku, kv, data, s))
}

/// The grid's residual sum_c |D_c - Qu C_c Qv^T|^2 from the Qs and C left in the scratch by
/// [`grid_sse_body`] (the near-exact fit, where |D|^2 - |C|^2 cancels).
fn grid_residual(ku: usize, kv: usize, data: &GridData, s: &mut Scratch) -> f64 {
    let (nu, nv) = (data.nu, data.nv);
    let (lu, lv) = (padded(nu), padded(nv));
    let mut sse = 0.0;
    grow(&mut s.t, nu * kv);
    for co in 0..3 {
        // Qu C_c (nu x kv) into s.t
        for i in 0..nu {
            for b in 0..kv {
                let mut acc = 0.0;
                for a in 0..ku {
                    acc += s.qa[a * lu + i] * s.c[(3 * a + co) * kv + b];
                }
                s.t[i * kv + b] = acc;
            }
        }
        for i in 0..nu {
            for j in 0..nv {
                let mut fit = 0.0;
                for b in 0..kv {
                    fit += s.t[i * kv + b] * s.qb[b * lv + j];
                }
                let e = data.rows[(3 * i + co) * lv + j] - fit;
                sse += e * e;
            }
        }
    }
    sse
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::Problem;
    use crate::spline::bezier::{add_noise, example3, fit_poles, grid_sse_qr, BezierSurface};
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

    /// The AVX2 rank sort gives std's `total_cmp` sort bit for bit: random values, many ties,
    /// signed zeros, NaNs of both signs and infinities, every length it ranks and two it does not.
    #[test]
    fn sort_params_equals_std_sort_bit_for_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(41);
        let special = [0.0, -0.0, 1.0, 0.5, f64::NAN, -f64::NAN, f64::INFINITY, -1.0, 1e-300];
        for n in (1..=RANK_MAX).chain([RANK_MAX + 1, 200]) {
            for round in 0..4 {
                let t: Vec<f64> = (0..n)
                    .map(|_| match round {
                        0 => rng.gen::<f64>(),
                        // many ties
                        1 => (rng.gen_range(0..5) as f64) / 4.0,
                        _ => special[rng.gen_range(0..special.len())],
                    })
                    .collect();
                let mut want = t.clone();
                want.sort_by(f64::total_cmp);
                let mut got = t.clone();
                sort_params(&mut got);
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&got), bits(&want), "n {n} round {round}");
            }
        }
    }

    /// The AVX2 + FMA product kernel equals the portable one bit for bit, edge blocks included,
    /// and both equal the plain sums sum_k a_ik b_jk to rounding.
    #[test]
    fn gemm_kernels_agree_bit_for_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(35);
        for (ra, rb, len) in [(1, 1, 4), (3, 5, 8), (11, 11, 632), (10, 41, 48), (30, 10, 48)] {
            let a: Vec<f64> = (0..ra * len).map(|_| rng.gen_range(-1.0..1.0)).collect();
            let b: Vec<f64> = (0..rb * len).map(|_| rng.gen_range(-1.0..1.0)).collect();
            let mut o1 = vec![f64::NAN; ra * rb];
            gemm_nt_scalar(&a, ra, &b, rb, len, &mut o1, rb);
            for i in 0..ra {
                for j in 0..rb {
                    let (x, y) = (&a[i * len..(i + 1) * len], &b[j * len..(j + 1) * len]);
                    let exact: f64 = x.iter().zip(y).map(|(p, q)| p * q).sum();
                    let scale: f64 = x.iter().zip(y).map(|(p, q)| (p * q).abs()).sum();
                    assert!((o1[i * rb + j] - exact).abs() <= 1e-14 * scale, "({ra},{rb},{len})");
                }
            }
            #[cfg(target_arch = "x86_64")]
            if super::super::avx2_fma() {
                let mut o2 = vec![f64::NAN; ra * rb];
                unsafe { gemm_nt_avx2(&a, ra, &b, rb, len, &mut o2, rb) };
                let bits = |o: &[f64]| o.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&o1), bits(&o2), "({ra},{rb},{len})");
            }
        }
    }

    /// The outer-product kernel's AVX2 copy equals the portable one bit for bit for every block
    /// size (k = 1..15 rows split into blocks of at most 5), and both equal the plain sums.
    #[test]
    fn gemm_tn_copies_agree_bit_for_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(36);
        for (k, n, lq, w) in [(1, 1, 8, 24), (6, 29, 32, 96), (10, 41, 48, 144), (15, 20, 24, 48)]
            .into_iter()
            .chain((2..15).map(|k| (k, 9, 16, 24)))
        {
            let q: Vec<f64> = (0..k * lq).map(|_| rng.gen_range(-1.0..1.0)).collect();
            let r: Vec<f64> = (0..n * w).map(|_| rng.gen_range(-1.0..1.0)).collect();
            let mut o1 = vec![f64::NAN; k * w];
            gemm_tn::<false>(&q, lq, k, &r, n, w, &mut o1);
            for a in 0..k {
                for j in 0..w {
                    let terms = (0..n).map(|i| q[a * lq + i] * r[i * w + j]);
                    let exact: f64 = terms.clone().sum();
                    let scale: f64 = terms.map(f64::abs).sum();
                    assert!((o1[a * w + j] - exact).abs() <= 1e-14 * scale, "k={k} n={n}");
                }
            }
            #[cfg(target_arch = "x86_64")]
            if super::super::avx2_fma() {
                let mut o2 = vec![f64::NAN; k * w];
                unsafe { gemm_tn_avx2(&q, lq, k, &r, n, w, &mut o2) };
                let bits = |o: &[f64]| o.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&o1), bits(&o2), "k={k} n={n} w={w}");
            }
        }
    }

    /// The Householder update of both copies is bit-identical (groups of four columns and the
    /// rest), and equals x - beta (v . x) v to rounding.
    #[test]
    fn reflect_cols_copies_agree_bit_for_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(37);
        for (cols, lp) in [(1, 8), (3, 16), (4, 48), (9, 48), (10, 32)] {
            let v: Vec<f64> = (0..lp).map(|_| rng.gen_range(-1.0..1.0)).collect();
            let x: Vec<f64> = (0..cols * lp).map(|_| rng.gen_range(-1.0..1.0)).collect();
            let beta = 2.0 / v.iter().map(|t| t * t).sum::<f64>();
            let mut x1 = x.clone();
            reflect_cols::<false>(&v, beta, &mut x1, lp);
            for (c, xc) in x.chunks(lp).enumerate() {
                let d: f64 = v.iter().zip(xc).map(|(a, b)| a * b).sum();
                for i in 0..lp {
                    let want = xc[i] - beta * d * v[i];
                    assert!((x1[c * lp + i] - want).abs() <= 1e-13, "cols={cols} lp={lp}");
                }
            }
            #[cfg(target_arch = "x86_64")]
            if super::super::avx2_fma() {
                let mut x2 = x.clone();
                unsafe { reflect_cols_avx2(&v, beta, &mut x2, lp) };
                let bits = |o: &[f64]| o.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&x1), bits(&x2), "cols={cols} lp={lp}");
            }
        }
    }

    /// The Bernstein rows of both copies are bit-identical, equal the recursive values of
    /// `bernstein_into` to rounding and are zero in the padding, for every partial last chunk.
    #[test]
    fn basis_rows_copies_agree_and_pad_with_zeros() {
        let mut rng = ChaCha8Rng::seed_from_u64(37);
        for n in [1, 3, 5, 9, 15] {
            for np in [1, 3, 4, 5, 8, 9, 13, 17, 64] {
                let t: Vec<f64> = (0..np).map(|_| rng.gen_range(0.0..1.0)).collect();
                let stride = padded(np);
                let run = |v: bool| {
                    let mut o = vec![f64::NAN; (n + 1) * stride];
                    if v {
                        basis_rows::<true>(n, &t, stride, &mut o);
                    } else {
                        basis_rows::<false>(n, &t, stride, &mut o);
                    }
                    o
                };
                let o = run(false);
                let mut b = [0.0; MAXB];
                for (k, &tk) in t.iter().enumerate() {
                    crate::spline::bezier::bernstein_into(n, tk, &mut b[..=n]);
                    for i in 0..=n {
                        assert!((o[i * stride + k] - b[i]).abs() <= 1e-14, "n={n} k={k}");
                    }
                }
                for i in 0..=n {
                    assert!(o[i * stride + np..(i + 1) * stride].iter().all(|&x| x == 0.0));
                }
                #[cfg(target_arch = "x86_64")]
                if super::super::avx2_fma() {
                    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(&run(true)), bits(&o), "n={n} np={np}");
                }
            }
        }
    }

    /// The monomial rows equal t^a (1-t)^(n-a) and t^i (1-t)^(2n-i) (powi, to a few roundings
    /// relative) and are exactly zero in the padding, for every partial last chunk; the AVX2
    /// copy gives the same bits.
    #[test]
    fn monomial_rows_equal_powers_and_pad_with_zeros() {
        let mut rng = ChaCha8Rng::seed_from_u64(38);
        for n in [1, 3, 5, 9, 15] {
            for np in [1, 3, 8, 9, 13, 64] {
                let t: Vec<f64> = (0..np).map(|_| rng.gen_range(0.0..1.0)).collect();
                let stride = padded(np);
                let run = |v: bool| {
                    let mut o = vec![f64::NAN; (n + 1) * stride];
                    let mut o2 = vec![f64::NAN; (2 * n + 1) * stride];
                    if v {
                        monomial_rows::<true>(n, &t, stride, &mut o, &mut o2);
                    } else {
                        monomial_rows::<false>(n, &t, stride, &mut o, &mut o2);
                    }
                    (o, o2)
                };
                let (o, o2) = run(false);
                #[cfg(target_arch = "x86_64")]
                if super::super::avx2_fma() {
                    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    let (p, p2) = run(true);
                    assert_eq!((bits(&p), bits(&p2)), (bits(&o), bits(&o2)), "n={n} np={np}");
                }
                for (deg, rows) in [(n, &o), (2 * n, &o2)] {
                    for (k, &tk) in t.iter().enumerate() {
                        for i in 0..=deg {
                            let want = tk.powi(i as i32) * (1.0 - tk).powi((deg - i) as i32);
                            let got = rows[i * stride + k];
                            assert!((got - want).abs() <= 1e-14 * want, "n={n} k={k} i={i}");
                        }
                    }
                    for i in 0..=deg {
                        assert!(rows[i * stride + np..(i + 1) * stride].iter().all(|&x| x == 0.0));
                    }
                }
            }
        }
    }

    /// The Cholesky factor of both copies is bit-identical (sizes with and without a partial
    /// last group of columns) and reproduces G: U^T U = G to rounding.
    #[test]
    fn cholesky_copies_agree_bit_for_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(39);
        for n in [1, 3, 5, 9, 20, 36, 37] {
            let a: Vec<f64> = (0..n * (n + 3)).map(|_| rng.gen_range(-1.0..1.0)).collect();
            let g: Vec<f64> = (0..n * n)
                .map(|ij| {
                    (0..n + 3).map(|k| a[ij / n * (n + 3) + k] * a[ij % n * (n + 3) + k]).sum()
                })
                .collect();
            let mut u1 = g.clone();
            assert!(cholesky::<false>(&mut u1, n), "n={n}");
            for i in 0..n {
                for j in i..n {
                    let v: f64 = (0..=i).map(|k| u1[k * n + i] * u1[k * n + j]).sum();
                    assert!((v - g[i * n + j]).abs() <= 1e-12 * g[i * n + i].max(1.0), "n={n}");
                }
            }
            #[cfg(target_arch = "x86_64")]
            if super::super::avx2_fma() {
                let mut u2 = g.clone();
                assert!(unsafe { cholesky_avx2_for_test(&mut u2, n) });
                let upper = |u: &[f64]| {
                    (0..n)
                        .flat_map(|i| (i..n).map(move |j| u[i * n + j].to_bits()))
                        .collect::<Vec<_>>()
                };
                assert_eq!(upper(&u1), upper(&u2), "n={n}");
            }
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn cholesky_avx2_for_test(u: &mut [f64], n: usize) -> bool {
        cholesky::<true>(u, n)
    }

    /// The accumulating product kernel run over consecutive column blocks leaves the same lanes
    /// as [`gemm_nt`] over all columns (same bits after (s0 + s2) + (s1 + s3)), edge blocks
    /// included, and its AVX2 + FMA copy equals the portable one bit for bit.
    #[test]
    fn blocked_accumulating_gemm_equals_whole_product_bit_for_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(36);
        for (ra, rb, len, blk) in
            [(1, 1, 8, 4), (11, 11, 632, 64), (6, 18, 56, 8), (3, 5, 48, 16), (5, 6, 16, 8)]
        {
            let a: Vec<f64> = (0..ra * len).map(|_| rng.gen_range(-1.0..1.0)).collect();
            let b: Vec<f64> = (0..rb * len).map(|_| rng.gen_range(-1.0..1.0)).collect();
            let mut whole = vec![f64::NAN; ra * rb];
            gemm_nt_scalar(&a, ra, &b, rb, len, &mut whole, rb);
            let blocked = |avx: bool| {
                let mut acc = vec![0.0; W * ra * rb];
                for k0 in (0..len).step_by(blk) {
                    let l = blk.min(len - k0);
                    let cut = |m: &[f64], r: usize| -> Vec<f64> {
                        (0..r).flat_map(|i| m[i * len + k0..i * len + k0 + l].to_vec()).collect()
                    };
                    let (ab, bb) = (cut(&a, ra), cut(&b, rb));
                    if avx {
                        #[cfg(target_arch = "x86_64")]
                        unsafe {
                            gemm_nt_acc_avx2(&ab, ra, &bb, rb, l, &mut acc)
                        };
                    } else {
                        gemm_nt_acc_scalar(&ab, ra, &bb, rb, l, &mut acc);
                    }
                }
                acc.chunks_exact(W)
                    .map(|h| ((h[0] + h[2]) + (h[1] + h[3])).to_bits())
                    .collect::<Vec<_>>()
            };
            let bits: Vec<u64> = whole.iter().map(|x| x.to_bits()).collect();
            assert_eq!(blocked(false), bits, "({ra},{rb},{len})");
            #[cfg(target_arch = "x86_64")]
            if super::super::avx2_fma() {
                assert_eq!(blocked(true), bits, "AVX2 ({ra},{rb},{len})");
            }
        }
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
        // (7, 2): more rows of bu than one register block holds, an odd number of bv rows
        let tall = {
            let s = random_surface(7, 2, &mut rng);
            (0..130).map(|_| s.eval(rng.gen_range(0.0..1.0), rng.gen_range(0.0..1.0))).collect()
        };
        for (du, dv, mut pts) in [(5, 5, ex3), (3, 4, mixed), (7, 2, tall)] {
            add_noise(&mut pts, 18.0, &mut rng);
            let data = ScatteredData::new(&pts);
            for _ in 0..5 {
                let x: Vec<f64> = (0..2 * pts.len()).map(|_| rng.gen_range(0.0..1.0)).collect();
                let mut s = Scratch::default();
                let y = scattered_sse_body::<false>(du, dv, &x, &data, &mut s).expect("well posed");
                let y_svd = svd_y(du, dv, &x, &pts);
                assert!((y - y_svd).abs() <= 1e-10 * y_svd, "({du},{dv}): {y} vs {y_svd}");
                #[cfg(target_arch = "x86_64")]
                {
                    use crate::simd::avx2_fma;
                    if avx2_fma() {
                        let y2 = unsafe { scattered_sse_avx2(du, dv, &x, &data, &mut s) };
                        assert_eq!(y2.map(f64::to_bits), Some(y.to_bits()), "AVX2 ({du},{dv})");
                    }
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
        let y = scattered_sse_body::<false>(5, 5, &x, &ScatteredData::new(&pts), &mut s).unwrap();
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
        let y = scattered_sse_body::<false>(5, 5, &x, &ScatteredData::new(&pts), &mut s).unwrap();
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
        assert!(scattered_sse_body::<false>(5, 5, &x, &ScatteredData::new(&pts), &mut s).is_none());
        let prob = crate::spline::bezier::BezierParamProblem::new(
            5,
            5,
            crate::spline::bezier::Layout::Scattered,
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
            let mut pts =
                crate::spline::bezier::height_grid(crate::spline::bezier::peaks, n, -3.0, 3.0);
            add_noise(&mut pts, 12.5, &mut rng);
            let data = GridData::new(&pts, n, n);
            for _ in 0..4 {
                let mut u: Vec<f64> = (0..n).map(|_| rng.gen_range(0.0..1.0)).collect();
                let mut v: Vec<f64> = (0..n).map(|_| rng.gen_range(0.0..1.0)).collect();
                u.sort_by(f64::total_cmp);
                v.sort_by(f64::total_cmp);
                let mut s = Scratch::default();
                let y = grid_sse_body::<false>(d, d, &u, &v, &data, &mut s).expect("full rank");
                let y_qr = grid_sse_qr(d, d, &u, &v, &data);
                assert!((y - y_qr).abs() <= 1e-10 * y_qr, "n={n}: {y} vs {y_qr}");
                #[cfg(target_arch = "x86_64")]
                {
                    use crate::simd::avx2_fma;
                    if avx2_fma() {
                        let y2 = unsafe { grid_sse_avx2(d, d, &u, &v, &data, &mut s) };
                        assert_eq!(y2.map(f64::to_bits), Some(y.to_bits()), "AVX2 n={n}");
                    }
                }
            }
            let u: Vec<f64> = (0..n).map(|i| (i % 3) as f64 / 2.0).collect();
            let v: Vec<f64> = (0..n).map(|j| j as f64 / (n - 1) as f64).collect();
            let mut u = u;
            u.sort_by(f64::total_cmp);
            assert!(grid_sse_body::<false>(d, d, &u, &v, &data, &mut Scratch::default()).is_none());
        }
    }
}
