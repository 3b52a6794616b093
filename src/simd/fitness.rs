//! The control-net fitness (Eq. 6.2; see [`crate::spline::control_net`] for the problem and its
//! layout): the portable copy ([`kernel`], compiler-vectorised) beside the AVX2 copy, whose first
//! pass is fused with the transpose ([`fused`]), and the tests that they give the same bits.

use crate::optim::aligned::Aligned;
use crate::spline::control_net::ControlNetProblem;
use crate::spline::SparseBasis;
use std::ops::Range;

#[cfg(target_arch = "x86_64")]
#[doc(hidden)]
pub use fused::building_blocks;

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

/// Eq. 6.2 of `x` (of the problem's length) in the problem's copy ([`ControlNetProblem::isa`]),
/// laying `scratch` out for the problem's shape first.
pub(crate) fn fitness(pb: &ControlNetProblem, x: &[f64], scratch: &mut Scratch) -> f64 {
    let p = &pb.parts;
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
    match pb.isa {
        // SAFETY: `with_isa` and `simd::simd` only select AVX2 when this CPU reports it.
        #[cfg(target_arch = "x86_64")]
        super::Isa::Avx2 | super::Isa::Avx512Vl => unsafe { fused::kernel_avx2(pb, x, scratch) },
        _ => kernel(pb, x, scratch),
    }
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
pub(crate) const CHUNK: usize = 4;

pub(crate) fn padded(n: usize) -> usize {
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

/// The kernel in 256-bit AVX2 + FMA instructions (an AVX-512VL copy of this body, with the
/// second pass over up to five chunks at once, gained under 5% on a Sapphire Rapids class Xeon
/// and was removed; docs/speed.md).
///
/// - First pass fused with the transpose: four grid rows (one chunk of lanes) at a time, each
///   row's four-control-row sum over four consecutive k is one vector, and the four vectors are
///   transposed in registers and stored straight into RT (no R buffer, no second pass over it).
///   Its sixteen broadcast weights stay on the stack and are read as memory operands. On the AVX2-only Zen 3 this copy
///   took 1.60-1.68 us against 1.90-2.00 us for the compiler-vectorised [`kernel`]; a variant
///   that kept two lanes' eight weights in registers (pairs of lanes, 128-bit stores) and one
///   that also shared the rows of two lanes were no faster there (2026-12-03), so the one body
///   serves both.
/// - Second pass chunk by chunk, right after the chunk's first pass (its RT rows still in L1).
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
            if !crate::simd::avx2_fma() {
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
            if !crate::simd::avx2_fma() {
                return None;
            }
            // SAFETY: the CPU has AVX2 and FMA; every column reads RT rows below k3p and its
            // own three data rows (asserted).
            Some(unsafe { second_pass_avx2(n, nv, k3p, data, rt) })
        }
    }

    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn kernel_avx2(pb: &ControlNetProblem, x: &[f64], s: &mut Scratch) -> f64 {
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
            let out = s.rt_b.as_mut_ptr();
            by_lanes!(valid, segment(&src, k3, &w, k3, out));
            let data = pb.data_b.as_ptr().add(ch * ny * 3 * CHUNK);
            add_group::<1>(&mut bottom, 0..ny, k3p, &parts.nv, data, out);
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
            let out = s.rt_t.as_mut_ptr();
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
            let data = pb.data_t.as_ptr().add(ch * (ny - 2) * 3 * CHUNK);
            add_group::<1>(&mut top, 1..ny - 1, k3p, &parts.nv, data, out);
        }
        bottom + top
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::problem::Problem;
    use crate::simd::Isa;
    use crate::spline::control_net::test_support::*;
    use crate::spline::control_net::BoxSpec;

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
}
