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
//! library's `fma` in the baseline copy), so the copies (picked at run time: baseline, AVX2,
//! AVX-512VL; `SOMNURBS_SIMD` forces one) give bit-identical results.
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

pub use crate::optim::kernels::Isa;
#[cfg(target_arch = "x86_64")]
#[doc(hidden)]
pub use fused::building_blocks;

/// The control-net problem: minimise Eq. 6.2 over the distinct control points inside a box.
#[derive(Debug, Clone)]
pub struct ControlNetProblem {
    parts: ControlNetParts,
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
    data_b: Aligned,
    data_t: Aligned,
    isa: Isa,
    /// Sparse rows of the sum-of-norms form (16 control points per grid class).
    term_points: Vec<[usize; 16]>,
    term_coef: Vec<[f64; 16]>,
    term_data: Vec<Point3>,
}

/// Work space of one evaluation (one per thread through [`Problem::fitness`]).
#[derive(Debug, Clone, Default)]
pub struct Scratch {
    /// (nx, ny, cn_x, cn_y) the buffers are laid out for.
    key: (usize, usize, usize, usize),
    r_b: Vec<f64>,
    r_t: Vec<f64>,
    rt_b: Aligned,
    rt_t: Aligned,
    /// The top view's first and last four interior-run rows (stride 3 cn_y - 6), for the
    /// vector copies.
    edge: Vec<f64>,
}

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

/// Pass 1 of one grid row: R = sum_t Nu[i][t] P[first_i + t] over whole control rows,
/// vectorised along the row (four source rows, weights `w`).
#[inline(always)]
fn lin4(out: &mut [f64], a: &[f64], b: &[f64], c: &[f64], d: &[f64], w: &[f64; 4]) {
    let n = out.len();
    let (a, b, c, d) = (&a[..n], &b[..n], &c[..n], &d[..n]);
    for k in 0..n {
        out[k] = w[3].mul_add(d[k], w[2].mul_add(c[k], w[1].mul_add(b[k], w[0] * a[k])));
    }
}

/// Vector lanes (grid rows) are processed in chunks of this many; lane counts are padded to a
/// multiple, and padded lanes hold zeros, so they add exact zeros.
const CHUNK: usize = 4;

fn padded(n: usize) -> usize {
    n.div_ceil(CHUNK) * CHUNK
}

/// Transpose a view's pass-1 rows `r` (row li at li * k3p) into chunk-major RT[chunk][k][lane],
/// four lanes per store (rows past `lanes` are zero rows of R).
#[inline(always)]
fn transpose_rows(lanes: usize, k3p: usize, r: &[f64], rt: &mut [f64]) {
    for ch in 0..lanes.div_ceil(CHUNK) {
        let src: [&[f64]; CHUNK] =
            std::array::from_fn(|l| &r[(ch * CHUNK + l) * k3p..(ch * CHUNK + l + 1) * k3p]);
        let dst = &mut rt[ch * k3p * CHUNK..(ch + 1) * k3p * CHUNK];
        for (k, out) in dst.chunks_exact_mut(CHUNK).enumerate() {
            for l in 0..CHUNK {
                out[l] = src[l][k];
            }
        }
    }
}

/// Sum of distances |D - D^G| of one view over `lanes` grid rows and the grid columns `cols`,
/// from its transposed pass-1 result `rt` (chunk-major RT[chunk][k][lane], k < k3p, zeros in
/// every padded lane). `data`: chunk-major [chunk][column][c][lane].
/// Pass 2 and distances: per chunk of lanes, over all grid columns, in registers:
/// D^G = sum_t Nv[j][t] RT[first_j + t] (Eq. 5.3), fused multiply-adds in a fixed order.
#[inline(always)]
fn pass2_error(
    lanes: usize,
    cols: Range<usize>,
    k3p: usize,
    nv: &SparseBasis,
    data: &[f64],
    rt: &[f64],
) -> f64 {
    let nc = cols.len();
    if lanes == 0 || nc == 0 {
        return 0.0;
    }
    let mut total = 0.0;
    for ch in 0..lanes.div_ceil(CHUNK) {
        let block = &rt[ch * k3p * CHUNK..(ch + 1) * k3p * CHUNK];
        let dchunk = &data[ch * nc * 3 * CHUNK..(ch + 1) * nc * 3 * CHUNK];
        let mut acc = [0.0; CHUNK];
        for (lj, j) in cols.clone().enumerate() {
            let base = nv.first[j] * 3 * CHUNK;
            let q: &[f64; 12 * CHUNK] = block[base..base + 12 * CHUNK].try_into().expect("12 rows");
            let d: &[f64; 3 * CHUNK] =
                dchunk[lj * 3 * CHUNK..(lj + 1) * 3 * CHUNK].try_into().expect("3 rows");
            let w = &nv.w[j];
            // Row (t, c) of the 4 x 3 block starts at (3 t + c) * CHUNK.
            for l in 0..CHUNK {
                let ex = w[3].mul_add(
                    q[9 * CHUNK + l],
                    w[2].mul_add(
                        q[6 * CHUNK + l],
                        w[1].mul_add(q[3 * CHUNK + l], w[0].mul_add(q[l], -d[l])),
                    ),
                );
                let ey = w[3].mul_add(
                    q[10 * CHUNK + l],
                    w[2].mul_add(
                        q[7 * CHUNK + l],
                        w[1].mul_add(q[4 * CHUNK + l], w[0].mul_add(q[CHUNK + l], -d[CHUNK + l])),
                    ),
                );
                let ez = w[3].mul_add(
                    q[11 * CHUNK + l],
                    w[2].mul_add(
                        q[8 * CHUNK + l],
                        w[1].mul_add(
                            q[5 * CHUNK + l],
                            w[0].mul_add(q[2 * CHUNK + l], -d[2 * CHUNK + l]),
                        ),
                    ),
                );
                acc[l] += ez.mul_add(ez, ey.mul_add(ey, ex * ex)).sqrt();
            }
        }
        for a in acc {
            total += a;
        }
    }
    total
}

/// Sum of distances of one view from its pass-1 rows `r` (row li at li * k3p, zero padded):
/// transpose into `rt`, then [`pass2_error`].
#[inline(always)]
fn view_error(
    lanes: usize,
    cols: Range<usize>,
    k3: usize,
    nv: &SparseBasis,
    data: &[f64],
    r: &[f64],
    rt: &mut [f64],
) -> f64 {
    let k3p = padded(k3);
    transpose_rows(lanes, k3p, r, rt);
    pass2_error(lanes, cols, k3p, nv, data, rt)
}

#[inline(always)]
fn kernel(pb: &ControlNetProblem, x: &[f64], s: &mut Scratch) -> f64 {
    let parts = &pb.parts;
    let (nx, ny, cx, k3) = (parts.nx, parts.ny, parts.cn_x, 3 * parts.cn_y);
    let k3p = padded(k3);
    let nu = &parts.nu;
    // Bottom view: its classes are 0..cn_x*cn_y in row-major order, so its P is a prefix of x.
    for i in 0..nx {
        let f = nu.first[i] * k3;
        lin4(
            &mut s.r_b[i * k3p..i * k3p + k3],
            &x[f..f + k3],
            &x[f + k3..f + 2 * k3],
            &x[f + 2 * k3..f + 3 * k3],
            &x[f + 3 * k3..f + 4 * k3],
            &nu.w[i],
        );
    }
    let bottom = view_error(nx, 0..ny, k3, &parts.nv, &pb.data_b, &s.r_b, &mut s.rt_b);
    // Top view, read in place: its P rows 0 and cn_x - 1 are the bottom's, and every other row
    // is a bottom border class, the row's own interior classes (contiguous in x after the
    // bottom's), then a bottom border class. Pass 1 is column-wise, so the border columns of
    // its R are the bottom's R at the same grid row; only the interior columns are computed.
    let ki = k3 - 6;
    let top_interior = 3 * cx * parts.cn_y;
    let row = |a: usize| -> &[f64] {
        let o = if a == 0 || a == cx - 1 { a * k3 + 3 } else { top_interior + (a - 1) * ki };
        &x[o..o + ki]
    };
    for li in 0..nx - 2 {
        let i = li + 1;
        let f = nu.first[i];
        let (rb, out) = (&s.r_b[i * k3p..i * k3p + k3], &mut s.r_t[li * k3p..li * k3p + k3]);
        lin4(&mut out[3..3 + ki], row(f), row(f + 1), row(f + 2), row(f + 3), &nu.w[i]);
        out[..3].copy_from_slice(&rb[..3]);
        out[3 + ki..].copy_from_slice(&rb[3 + ki..]);
    }
    let top = view_error(nx - 2, 1..ny - 1, k3, &parts.nv, &pb.data_t, &s.r_t, &mut s.rt_t);
    bottom + top
}

/// The kernel in 256-bit vector instructions, compiled twice: for AVX2 + FMA (16 vector
/// registers) and for AVX-512VL (32).
///
/// - First pass fused with the transpose: four grid rows (one chunk of lanes) at a time, each
///   row's four-control-row sum over four consecutive k is one vector, and the four vectors are
///   transposed in registers and stored straight into RT (no R buffer, no second pass over it).
///   Its sixteen broadcast weights take half of AVX-512VL's 32 registers; the AVX2 copy keeps
///   them on the stack and reads them as memory operands. On the AVX2-only Zen 3 this copy
///   took 1.60-1.68 us against 1.90-2.00 us for the compiler-vectorised [`kernel`]; a variant
///   that kept two lanes' eight weights in registers (pairs of lanes, 128-bit stores) and one
///   that also shared the rows of two lanes were no faster there (2026-12-03), so the one body
///   serves both.
/// - Second pass over up to five chunks at once, grid columns outside: the column's weights are
///   broadcast once for all of them.
///
/// The arithmetic is that of [`lin4`] and [`pass2_error`] (the same multiplies, fused
/// multiply-adds, square roots and additions in the same order per lane), so the result is
/// bit-identical to the other copies (tested).
///
/// Safety: every pointer read here is a control row of `x` (checked by `fitness_with` to have
/// 3 NOV values) or of the scratch's `edge` copy, read at k < the row's length; the first basis
/// indices satisfy first + 4 <= control-net size (checked by `ControlNetProblem::new`), so four
/// rows from the first are inside the net; RT and the data hold `chunks` chunks (sized by
/// `fitness_with` and `new`).
#[cfg(target_arch = "x86_64")]
mod fused {
    use super::{padded, ControlNetProblem, Scratch, CHUNK};
    use std::arch::x86_64::*;

    /// R for one grid row over four consecutive k: sum_t w[t] P[row t][k..k + 4], rows `s`
    /// apart from `p`.
    #[inline(always)]
    unsafe fn row4(p: *const f64, s: usize, w: &[__m256d; 4]) -> __m256d {
        let r = _mm256_mul_pd(w[0], _mm256_loadu_pd(p));
        let r = _mm256_fmadd_pd(w[1], _mm256_loadu_pd(p.add(s)), r);
        let r = _mm256_fmadd_pd(w[2], _mm256_loadu_pd(p.add(2 * s)), r);
        _mm256_fmadd_pd(w[3], _mm256_loadu_pd(p.add(3 * s)), r)
    }

    /// One block: the rows of the first `VALID` lanes over k..k + 4 (from `src[l] + off`; the
    /// other lanes are zeros), transposed, and its four k rows stored at `out + 4 k`.
    #[inline(always)]
    unsafe fn block<const VALID: usize>(
        src: &[*const f64; CHUNK],
        s: usize,
        w: &[[__m256d; 4]; CHUNK],
        off: usize,
        out: *mut f64,
    ) {
        let mut r = [_mm256_setzero_pd(); CHUNK];
        for l in 0..VALID {
            r[l] = row4(src[l].add(off), s, &w[l]);
        }
        let t0 = _mm256_unpacklo_pd(r[0], r[1]);
        let t1 = _mm256_unpackhi_pd(r[0], r[1]);
        let t2 = _mm256_unpacklo_pd(r[2], r[3]);
        let t3 = _mm256_unpackhi_pd(r[2], r[3]);
        let o = [
            _mm256_permute2f128_pd::<0x20>(t0, t2),
            _mm256_permute2f128_pd::<0x20>(t1, t3),
            _mm256_permute2f128_pd::<0x31>(t0, t2),
            _mm256_permute2f128_pd::<0x31>(t1, t3),
        ];
        for (q, v) in o.iter().enumerate() {
            _mm256_storeu_pd(out.add(q * CHUNK), *v);
        }
    }

    /// A run of `len` (>= 4) consecutive k, read at `src[l]` (stride `s` between control rows)
    /// and written to RT rows from `out` on: whole blocks, then one last block ending at `len`
    /// that recomputes up to three k (and rewrites them with the same bits).
    #[inline(always)]
    #[allow(clippy::pointers_in_nomem_asm_block)]
    unsafe fn segment<const VALID: usize>(
        src: &[*const f64; CHUNK],
        s: usize,
        w: &[[__m256d; 4]; CHUNK],
        len: usize,
        out: *mut f64,
    ) {
        // The lanes' pointers move with the block and each load is one pointer plus a multiple
        // of the stride. The empty `asm!` hides the pointers' progression from the compiler,
        // which would otherwise keep all sixteen row pointers apart (more than the general
        // registers hold, so reloaded from the stack in every block).
        let mut k = 0;
        let mut at = *src;
        while k + 4 <= len {
            for p in at.iter_mut().take(VALID) {
                // The asm is empty: it reads and writes no memory, it only passes the pointer on.
                std::arch::asm!(
                    "/* {0} */",
                    inout(reg) * p,
                    options(pure, nomem, nostack, preserves_flags)
                );
            }
            block::<VALID>(&at, s, w, 0, out.add(k * CHUNK));
            for p in at.iter_mut() {
                *p = p.add(4);
            }
            k += 4;
        }
        if k < len {
            block::<VALID>(src, s, w, len - 4, out.add((len - 4) * CHUNK));
        }
    }

    /// `f::<VALID>(args)` for `valid` (1..=4) real lanes: the loops compiled once per count.
    macro_rules! by_lanes {
        ($valid:expr, $f:ident($($arg:expr),*)) => {
            match $valid {
                4 => $f::<4>($($arg),*),
                3 => $f::<3>($($arg),*),
                2 => $f::<2>($($arg),*),
                _ => $f::<1>($($arg),*),
            }
        };
    }

    /// The broadcast weights Nu[i0 + l][t] of the chunk's first `valid` lanes (zeros after).
    #[inline(always)]
    unsafe fn weights(
        nu: &crate::spline::SparseBasis,
        i0: usize,
        valid: usize,
    ) -> [[__m256d; 4]; CHUNK] {
        let mut w = [[_mm256_setzero_pd(); 4]; CHUNK];
        for (l, wl) in w.iter_mut().enumerate().take(valid) {
            for (t, wt) in wl.iter_mut().enumerate() {
                *wt = _mm256_set1_pd(nu.w[i0 + l][t]);
            }
        }
        w
    }

    /// [`pass2_error`] over `G` chunks at once, grid columns outside and chunks inside: the
    /// column's four broadcast weights serve all `G` chunks and each chunk keeps its running sum
    /// in a register. Per lane the same operations in the same order, so the same bits.
    #[inline(always)]
    unsafe fn pass2_group<const G: usize>(
        cols: std::ops::Range<usize>,
        k3p: usize,
        nv: &crate::spline::SparseBasis,
        data: *const f64,
        rt: *const f64,
    ) -> [__m256d; G] {
        let nc = cols.len();
        let mut acc = [_mm256_setzero_pd(); G];
        for (lj, j) in cols.enumerate() {
            let w = &nv.w[j];
            let (w0, w1, w2, w3) = (
                _mm256_set1_pd(w[0]),
                _mm256_set1_pd(w[1]),
                _mm256_set1_pd(w[2]),
                _mm256_set1_pd(w[3]),
            );
            let base = nv.first[j] * 3 * CHUNK;
            for (g, a) in acc.iter_mut().enumerate() {
                let q = rt.add(g * k3p * CHUNK + base);
                let d = data.add((g * nc + lj) * 3 * CHUNK);
                let mut e = [_mm256_setzero_pd(); 3];
                for (c, ec) in e.iter_mut().enumerate() {
                    let v = _mm256_fmsub_pd(
                        w0,
                        _mm256_loadu_pd(q.add(c * CHUNK)),
                        _mm256_loadu_pd(d.add(c * CHUNK)),
                    );
                    let v = _mm256_fmadd_pd(w1, _mm256_loadu_pd(q.add((3 + c) * CHUNK)), v);
                    let v = _mm256_fmadd_pd(w2, _mm256_loadu_pd(q.add((6 + c) * CHUNK)), v);
                    *ec = _mm256_fmadd_pd(w3, _mm256_loadu_pd(q.add((9 + c) * CHUNK)), v);
                }
                let sq = _mm256_mul_pd(e[0], e[0]);
                let sq = _mm256_fmadd_pd(e[1], e[1], sq);
                let sq = _mm256_fmadd_pd(e[2], e[2], sq);
                *a = _mm256_add_pd(*a, _mm256_sqrt_pd(sq));
            }
        }
        acc
    }

    /// [`pass2_error`] in groups of up to five chunks ([`pass2_group`]).
    #[inline(always)]
    unsafe fn pass2_grouped(
        lanes: usize,
        cols: std::ops::Range<usize>,
        k3p: usize,
        nv: &crate::spline::SparseBasis,
        data: &[f64],
        rt: &[f64],
    ) -> f64 {
        let nc = cols.len();
        if lanes == 0 || nc == 0 {
            return 0.0;
        }
        let chunks = lanes.div_ceil(CHUNK);
        debug_assert!(rt.len() >= chunks * k3p * CHUNK && data.len() >= chunks * nc * 3 * CHUNK);
        debug_assert!(cols.clone().all(|j| (nv.first[j] + 4) * 3 <= k3p));
        let (dp, rp) = (data.as_ptr(), rt.as_ptr());
        let mut total = 0.0;
        let mut ch = 0;
        while ch < chunks {
            let g = (chunks - ch).min(5);
            let (d, r) = (dp.add(ch * nc * 3 * CHUNK), rp.add(ch * k3p * CHUNK));
            match g {
                5 => add_group::<5>(&mut total, cols.clone(), k3p, nv, d, r),
                4 => add_group::<4>(&mut total, cols.clone(), k3p, nv, d, r),
                3 => add_group::<3>(&mut total, cols.clone(), k3p, nv, d, r),
                2 => add_group::<2>(&mut total, cols.clone(), k3p, nv, d, r),
                _ => add_group::<1>(&mut total, cols.clone(), k3p, nv, d, r),
            }
            ch += g;
        }
        total
    }

    /// [`pass2_group`] of the `G` chunks from `data` and `rt`, its per-lane sums added to `total`
    /// in chunk and lane order (one order for every schedule, so the same bits).
    #[inline(always)]
    unsafe fn add_group<const G: usize>(
        total: &mut f64,
        cols: std::ops::Range<usize>,
        k3p: usize,
        nv: &crate::spline::SparseBasis,
        data: *const f64,
        rt: *const f64,
    ) {
        let acc = pass2_group::<G>(cols, k3p, nv, data, rt);
        let mut sums = [[0.0; CHUNK]; G];
        for g in 0..G {
            _mm256_storeu_pd(sums[g].as_mut_ptr(), acc[g]);
        }
        for lane_sums in &sums {
            for v in lane_sums {
                *total += v;
            }
        }
    }

    /// The AVX2 copy's two building blocks run alone, over and over, for the optim bench's
    /// floor (`benches/optim/floor.rs`); not part of the interface.
    #[doc(hidden)]
    pub mod building_blocks {
        use super::{add_group, segment, CHUNK};
        use crate::spline::SparseBasis;
        use std::arch::x86_64::*;

        /// `n` times [`segment`] of `k` values from the lanes' rows `src` into `out`.
        #[target_feature(enable = "avx2,fma")]
        unsafe fn segments(
            n: usize,
            src: &[*const f64; CHUNK],
            s: usize,
            w: &[[f64; 4]; CHUNK],
            k: usize,
            out: *mut f64,
        ) {
            let wv = w.map(|wl| wl.map(|v| _mm256_set1_pd(v)));
            for _ in 0..n {
                segment::<4>(src, s, &wv, k, std::hint::black_box(out));
            }
        }

        /// `n` times the first pass of one chunk of four grid rows over `out.len() / 4` k (at
        /// least 4): lanes 0, 1 from control row 0 and lanes 2, 3 from row 1 of `rows` (rows
        /// `s` apart), weights `w` per lane, transposed into `out`. None without AVX2 and FMA.
        pub fn first_pass(
            n: usize,
            rows: &[f64],
            s: usize,
            w: &[[f64; 4]; 4],
            out: &mut [f64],
        ) -> Option<()> {
            let k = out.len() / CHUNK;
            assert!(k >= 4 && k <= s && out.len().is_multiple_of(CHUNK) && rows.len() >= 4 * s + k);
            if !crate::optim::kernels::avx2_fma() {
                return None;
            }
            let src: [*const f64; CHUNK] = std::array::from_fn(|l| rows[(l / 2) * s..].as_ptr());
            // SAFETY: the CPU has AVX2 and FMA; lane l reads rows l / 2 + t (t < 4, so below
            // row 5) at k < out.len() / 4 <= s (asserted), and writes out whole.
            unsafe { segments(n, &src, s, w, k, out.as_mut_ptr()) };
            Some(())
        }

        #[target_feature(enable = "avx2,fma")]
        unsafe fn second_pass_avx2(
            n: usize,
            nv: &SparseBasis,
            k3p: usize,
            data: &[f64],
            rt: &[f64],
        ) -> f64 {
            let mut total = 0.0;
            for _ in 0..n {
                add_group::<1>(&mut total, 0..nv.first.len(), k3p, nv, data.as_ptr(), rt.as_ptr());
                total = std::hint::black_box(total);
            }
            total
        }

        /// `n` times the second pass of one chunk over all of `nv`'s grid columns, from its
        /// transposed rows `rt` (k3p rows of 4 lanes) and data (3 rows of 4 lanes per column).
        /// None without AVX2 and FMA.
        pub fn second_pass(
            n: usize,
            nv: &SparseBasis,
            k3p: usize,
            data: &[f64],
            rt: &[f64],
        ) -> Option<f64> {
            let nc = nv.first.len();
            assert!(nv.w.len() == nc && rt.len() >= k3p * CHUNK && data.len() >= nc * 3 * CHUNK);
            assert!(nv.first.iter().all(|&f| (f + 4) * 3 <= k3p));
            if !crate::optim::kernels::avx2_fma() {
                return None;
            }
            // SAFETY: the CPU has AVX2 and FMA; every column reads RT rows below k3p and its
            // own three data rows (asserted).
            Some(unsafe { second_pass_avx2(n, nv, k3p, data, rt) })
        }
    }

    #[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
    pub(super) unsafe fn kernel_avx512vl(
        pb: &ControlNetProblem,
        x: &[f64],
        s: &mut Scratch,
    ) -> f64 {
        body::<false>(pb, x, s)
    }

    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn kernel_avx2(pb: &ControlNetProblem, x: &[f64], s: &mut Scratch) -> f64 {
        body::<true>(pb, x, s)
    }

    #[inline(always)]
    unsafe fn body<const CHUNKWISE: bool>(
        pb: &ControlNetProblem,
        x: &[f64],
        s: &mut Scratch,
    ) -> f64 {
        let parts = &pb.parts;
        let (nx, ny, cx, k3) = (parts.nx, parts.ny, parts.cn_x, 3 * parts.cn_y);
        let k3p = padded(k3);
        let nu = &parts.nu;
        let xp = x.as_ptr();
        // Bottom view: control row a starts at a * k3 in x.
        let mut bottom = 0.0;
        for ch in 0..nx.div_ceil(CHUNK) {
            let i0 = ch * CHUNK;
            let valid = (nx - i0).min(CHUNK);
            let mut src = [xp; CHUNK];
            for l in 0..valid {
                src[l] = xp.add(nu.first[i0 + l] * k3);
            }
            let w = weights(nu, i0, valid);
            let out = s.rt_b.as_mut_ptr().add(if CHUNKWISE { 0 } else { ch * k3p * CHUNK });
            by_lanes!(valid, segment(&src, k3, &w, k3, out));
            if CHUNKWISE {
                let data = pb.data_b.as_ptr().add(ch * ny * 3 * CHUNK);
                add_group::<1>(&mut bottom, 0..ny, k3p, &parts.nv, data, out);
            }
        }
        if !CHUNKWISE {
            bottom = pass2_grouped(nx, 0..ny, k3p, &parts.nv, &pb.data_b, &s.rt_b);
        }
        // Top view, lanes li = grid rows li + 1. Its k < 3 and k >= k3 - 3 are bottom border
        // classes (the bottom's rows, read as such); its k in 3..k3 - 3 come from rows of ki
        // values: rows 1..cx - 1 are the top's interior classes, contiguous in x after the
        // bottom's, and rows 0 and cx - 1 are the bottom's border rows at offset 3. Rows 0..4 and
        // cx - 4..cx are copied into `edge` (stride ki), so every lane reads 4 rows at stride ki.
        let ki = k3 - 6;
        let top_interior = 3 * cx * parts.cn_y;
        let lanes = nx - 2;
        if lanes == 0 || ny < 3 {
            return bottom;
        }
        let row = |a: usize| -> usize {
            if a == 0 || a == cx - 1 {
                a * k3 + 3
            } else {
                top_interior + (a - 1) * ki
            }
        };
        assert!(s.edge.len() >= 8 * ki);
        for (e, first_row) in [0, cx - 4].into_iter().enumerate() {
            for t in 0..4 {
                // Inline vector copies (ki >= 6): shorter than calls to memcpy.
                let (from, to) =
                    (xp.add(row(first_row + t)), s.edge.as_mut_ptr().add((4 * e + t) * ki));
                let mut k = 0;
                while k + 4 <= ki {
                    _mm256_storeu_pd(to.add(k), _mm256_loadu_pd(from.add(k)));
                    k += 4;
                }
                _mm256_storeu_pd(to.add(ki - 4), _mm256_loadu_pd(from.add(ki - 4)));
            }
        }
        let edge = s.edge.as_ptr();
        let mut top = 0.0;
        for ch in 0..lanes.div_ceil(CHUNK) {
            let li0 = ch * CHUNK;
            let valid = (lanes - li0).min(CHUNK);
            let w = weights(nu, li0 + 1, valid);
            let out = s.rt_t.as_mut_ptr().add(if CHUNKWISE { 0 } else { ch * k3p * CHUNK });
            let (mut border, mut inner) = ([xp; CHUNK], [xp; CHUNK]);
            for l in 0..valid {
                let a = nu.first[li0 + l + 1];
                border[l] = xp.add(a * k3);
                inner[l] = if a == 0 {
                    edge
                } else if a + 4 == cx {
                    edge.add(4 * ki)
                } else {
                    xp.add(row(a))
                };
            }
            // k 0..4 and k3 - 4..k3 from the bottom's rows; k = 3 and k3 - 4 are interior and
            // are rewritten by the interior run below.
            by_lanes!(valid, block(&border, k3, &w, 0, out));
            by_lanes!(valid, block(&border, k3, &w, k3 - 4, out.add((k3 - 4) * CHUNK)));
            by_lanes!(valid, segment(&inner, ki, &w, ki, out.add(3 * CHUNK)));
            if CHUNKWISE {
                let data = pb.data_t.as_ptr().add(ch * (ny - 2) * 3 * CHUNK);
                add_group::<1>(&mut top, 1..ny - 1, k3p, &parts.nv, data, out);
            }
        }
        if !CHUNKWISE {
            top = pass2_grouped(lanes, 1..ny - 1, k3p, &parts.nv, &pb.data_t, &s.rt_t);
        }
        bottom + top
    }
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
            isa: crate::optim::kernels::simd()?,
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
        let p = &self.parts;
        let key = (p.nx, p.ny, p.cn_x, p.cn_y);
        if scratch.key != key {
            // Fresh zeroed buffers: the padded lanes of RT must stay zero.
            let k3p = padded(3 * p.cn_y);
            let (lb, lt) = (padded(p.nx), padded(p.nx - 2));
            *scratch = Scratch {
                key,
                r_b: vec![0.0; lb * k3p],
                r_t: vec![0.0; lt * k3p],
                rt_b: Aligned::zeros(lb * k3p),
                rt_t: Aligned::zeros(lt * k3p),
                edge: vec![0.0; 8 * (3 * p.cn_y - 6)],
            };
        }
        match self.isa {
            // SAFETY: `with_isa` and `kernels::simd` only select AVX2 when this CPU reports it.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { fused::kernel_avx2(self, x, scratch) },
            // SAFETY: as above, for AVX-512F and AVX-512VL.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512Vl => unsafe { fused::kernel_avx512vl(self, x, scratch) },
            _ => kernel(self, x, scratch),
        }
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
    pub fn test_parts(nx: usize, ny: usize, cn_x: usize, cn_y: usize) -> ControlNetParts {
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
    pub fn sphere_problem(
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
    fn all_kernel_copies_are_bit_identical() {
        // Square and oblong grids and nets, lane counts with and without padding, the smallest net.
        for (nx, ny, cx, cy) in [
            (20, 20, 18, 18),
            (18, 30, 16, 28),
            (20, 20, 6, 6),
            (9, 7, 4, 5),
            (7, 9, 5, 4),
            (5, 5, 4, 4),
            (4, 4, 4, 4),
            (6, 9, 4, 6),
        ] {
            let pb = sphere_problem(nx, ny, cx, cy, BoxSpec::DataRange);
            let x: Vec<f64> = pb
                .initial_point()
                .iter()
                .enumerate()
                .map(|(k, v)| v + 1e-4 * (k % 5) as f64)
                .collect();
            let base = pb.clone().with_isa(Isa::Baseline).fitness(&x);
            for isa in Isa::ALL {
                assert_eq!(
                    pb.clone().with_isa(isa).fitness(&x).to_bits(),
                    base.to_bits(),
                    "{nx}x{ny} cn {cx}x{cy} {isa:?}"
                );
            }
        }
    }

    /// The bench's building blocks do the kernel's work: the first pass gives lin4's rows
    /// transposed, the second pass pass2_error's sum, bit for bit.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn building_blocks_compute_the_portable_passes() {
        use super::building_blocks::{first_pass, second_pass};
        let (s, k) = (30, 26);
        let rows: Vec<f64> = (0..5 * s).map(|i| (i as f64 * 0.37).sin()).collect();
        let w = [
            [0.1, 0.6, 0.25, 0.05],
            [0.05, 0.5, 0.4, 0.05],
            [0.2, 0.6, 0.15, 0.05],
            [0.3, 0.3, 0.3, 0.1],
        ];
        let mut out = vec![f64::NAN; CHUNK * k];
        if first_pass(2, &rows, s, &w, &mut out).is_none() {
            return; // no AVX2 here: the portable copy is the only one
        }
        let mut r = vec![0.0; CHUNK * k];
        for l in 0..CHUNK {
            let row = |t: usize| &rows[(l / 2 + t) * s..(l / 2 + t) * s + k];
            lin4(&mut r[l * k..(l + 1) * k], row(0), row(1), row(2), row(3), &w[l]);
        }
        let mut rt = vec![0.0; CHUNK * k];
        transpose_rows(CHUNK, k, &r, &mut rt);
        assert!(out.iter().zip(&rt).all(|(a, b)| a.to_bits() == b.to_bits()));
        let nv = SparseBasis {
            first: vec![0, 1, 1, 2, 4],
            w: w.iter().cycle().take(5).copied().collect(),
        };
        let data: Vec<f64> = (0..5 * 3 * CHUNK).map(|i| (i as f64 * 0.11).cos()).collect();
        let (k3p, expected) = (24, pass2_error(CHUNK, 0..5, 24, &nv, &data, &rt));
        assert_eq!(
            second_pass(1, &nv, k3p, &data, &rt).map(f64::to_bits),
            Some(expected.to_bits())
        );
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
