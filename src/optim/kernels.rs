//! The optimisers' per-coordinate loops, compiled twice (baseline and AVX2 with FMA; the PSO move
//! also hand-written for AVX-512VL) and picked at run time. Results are bit-identical between the
//! copies: every operation is an IEEE multiply, add, fused multiply-add (`f64::mul_add`, one
//! rounding in every copy: a hardware instruction in the AVX2 copy, the C library's `fma` in the
//! baseline one) or compare in the same order, or exact integer arithmetic; only the vector width
//! differs.
//!
//! Clamping is written as `if v < lo { lo } else { v }` then `if v > hi { hi } else { v }`: the
//! same value as `max(lo).min(hi)` for every number (and NaN passes through), but it compiles to
//! one vector max and one vector min instead of NaN-aware blends.

use super::sampling::{two_units_plus_one, xoshiro_next, BulkLanes, LANES};
use std::ops::Range;

#[inline(always)]
fn clamp(v: f64, lo: f64, hi: f64) -> f64 {
    let v = if v < lo { lo } else { v };
    if v > hi {
        hi
    } else {
        v
    }
}

/// One gene of the DE/rand/1 mutant, clamp(a + f (b - c)), the same number as [`de_mutant`] gives.
#[inline(always)]
pub fn de_mutant_gene(a: f64, b: f64, c: f64, f: f64, lo: f64, hi: f64) -> f64 {
    clamp(f.mul_add(b - c, a), lo, hi)
}

#[inline(always)]
fn de_mutant_generic(t: &mut [f64], a: &[f64], b: &[f64], c: &[f64], f: f64, lo: &[f64], hi: &[f64]) {
    let n = t.len();
    let (a, b, c, lo, hi) = (&a[..n], &b[..n], &c[..n], &lo[..n], &hi[..n]);
    for j in 0..n {
        t[j] = de_mutant_gene(a[j], b[j], c[j], f, lo[j], hi[j]);
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn de_mutant_avx2(t: &mut [f64], a: &[f64], b: &[f64], c: &[f64], f: f64, lo: &[f64], hi: &[f64]) {
    de_mutant_generic(t, a, b, c, f, lo, hi)
}

/// Whether this CPU runs the AVX2 + FMA copies.
#[cfg(target_arch = "x86_64")]
#[inline]
pub fn avx2_fma() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

/// t = clamp(a + f (b - c)) per coordinate (DE/rand/1 mutant), a + f (b - c) fused.
pub fn de_mutant(t: &mut [f64], a: &[f64], b: &[f64], c: &[f64], f: f64, lo: &[f64], hi: &[f64]) {
    #[cfg(target_arch = "x86_64")]
    {
        if avx2_fma() {
            // SAFETY: the CPU reports AVX2 and FMA.
            return unsafe { de_mutant_avx2(t, a, b, c, f, lo, hi) };
        }
    }
    de_mutant_generic(t, a, b, c, f, lo, hi)
}

/// PSO constants of one move.
#[derive(Debug, Clone, Copy)]
pub struct PsoCoefficients {
    pub k: f64,
    pub c1: f64,
    pub c2: f64,
}

/// The box of a PSO run per coordinate: positions in [lo, hi], velocities in [-vmax, vmax].
#[derive(Debug, Clone, Copy)]
pub struct PsoBounds<'a> {
    pub lo: &'a [f64],
    pub hi: &'a [f64],
    pub vmax: &'a [f64],
}

impl<'a> PsoBounds<'a> {
    /// The box of coordinates `r` only.
    fn range(&self, r: Range<usize>) -> PsoBounds<'a> {
        PsoBounds { lo: &self.lo[r.clone()], hi: &self.hi[r.clone()], vmax: &self.vmax[r] }
    }
}

#[inline(always)]
fn pso_move_block(x: &mut [f64], v: &mut [f64], p: &[f64], g: &[f64], b: PsoBounds, s: [&mut [u64]; 4], co: PsoCoefficients) {
    let n = x.len();
    let (v, p, g, lo, hi, vmax) = (&mut v[..n], &p[..n], &g[..n], &b.lo[..n], &b.hi[..n], &b.vmax[..n]);
    let [s0, s1, s2, s3] = s;
    let (s0, s1, s2, s3) = (&mut s0[..n], &mut s1[..n], &mut s2[..n], &mut s3[..n]);
    for j in 0..n {
        // The state goes through values, not `&mut`: the compiler then keeps it in registers
        // instead of reloading each word after every store.
        let (word, [n0, n1, n2, n3]) = xoshiro_next([s0[j], s1[j], s2[j], s3[j]]);
        (s0[j], s1[j], s2[j], s3[j]) = (n0, n1, n2, n3);
        let (u1, u2) = two_units_plus_one(word);
        // c r = c (u - 1) with r = u - 1 exact, so c u - c in one rounding is the same number.
        let (a1, a2) = (co.c1.mul_add(u1, -co.c1), co.c2.mul_add(u2, -co.c2));
        let vj = co.k * a2.mul_add(g[j] - x[j], a1.mul_add(p[j] - x[j], v[j]));
        let vj = clamp(vj, -vmax[j], vmax[j]);
        v[j] = vj;
        x[j] = clamp(x[j] + vj, lo[j], hi[j]);
    }
}

#[inline(always)]
fn pso_move_generic(x: &mut [f64], v: &mut [f64], p: &[f64], g: &[f64], rng: &mut BulkLanes, co: PsoCoefficients, b: PsoBounds) {
    let n = x.len();
    for start in (0..n).step_by(LANES) {
        let r = start..(start + LANES).min(n);
        let m = r.len();
        let [s0, s1, s2, s3] = rng.state_mut();
        let s = [&mut s0[..m], &mut s1[..m], &mut s2[..m], &mut s3[..m]];
        pso_move_block(&mut x[r.clone()], &mut v[r.clone()], &p[r.clone()], &g[r.clone()], b.range(r), s, co);
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn pso_move_avx2(x: &mut [f64], v: &mut [f64], p: &[f64], g: &[f64], rng: &mut BulkLanes, co: PsoCoefficients, b: PsoBounds) {
    pso_move_generic(x, v, p, g, rng, co, b)
}

/// The PSO move in 256-bit AVX-512VL instructions: native 64-bit rotates and three-input logic
/// cut the random-number part of the loop; the same integer operations and the same IEEE
/// operations in the same order as [`pso_move_block`], so the same bits. (Left to the compiler,
/// AVX-512 code uses 512-bit vectors, which this Zen 4 runs in two halves, slower.)
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
fn pso_move_avx512vl(x: &mut [f64], v: &mut [f64], p: &[f64], g: &[f64], rng: &mut BulkLanes, co: PsoCoefficients, b: PsoBounds) {
    use std::arch::x86_64::*;
    const XOR3: i32 = 0x96; // a ^ b ^ c
    const AND_OR: i32 = 0xEA; // (a & b) | c
    let n = x.len();
    let (v, p, g, lo, hi, vmax) = (&mut v[..n], &p[..n], &g[..n], &b.lo[..n], &b.hi[..n], &b.vmax[..n]);
    let mantissa_top32 = _mm256_set1_epi64x(0x000f_ffff_fff0_0000);
    let one = _mm256_set1_epi64x(0x3ff0_0000_0000_0000);
    let (c1, c2, k) = (_mm256_set1_pd(co.c1), _mm256_set1_pd(co.c2), _mm256_set1_pd(co.k));
    let (nc1, nc2) = (_mm256_set1_pd(-co.c1), _mm256_set1_pd(-co.c2));
    let sign = _mm256_set1_pd(-0.0);
    for start in (0..n).step_by(LANES) {
        let m = (n - start).min(LANES);
        let [s0, s1, s2, s3] = rng.state_mut();
        let vec_end = m - m % 4;
        for l in (0..vec_end).step_by(4) {
            let j = start + l;
            // SAFETY: l + 4 <= m <= LANES bounds the lane reads and writes; j + 4 <= n bounds
            // every coordinate slice (all re-sliced to n above).
            unsafe {
                let a0 = _mm256_loadu_si256(s0.as_ptr().add(l).cast());
                let a1 = _mm256_loadu_si256(s1.as_ptr().add(l).cast());
                let a2 = _mm256_loadu_si256(s2.as_ptr().add(l).cast());
                let a3 = _mm256_loadu_si256(s3.as_ptr().add(l).cast());
                let word = _mm256_add_epi64(_mm256_rol_epi64::<23>(_mm256_add_epi64(a0, a3)), a0);
                let t = _mm256_slli_epi64::<17>(a1);
                let n0 = _mm256_ternarylogic_epi64::<XOR3>(a0, a3, a1);
                let n1 = _mm256_ternarylogic_epi64::<XOR3>(a1, a2, a0);
                let n2 = _mm256_ternarylogic_epi64::<XOR3>(a2, a0, t);
                let n3 = _mm256_rol_epi64::<45>(_mm256_xor_si256(a3, a1));
                _mm256_storeu_si256(s0.as_mut_ptr().add(l).cast(), n0);
                _mm256_storeu_si256(s1.as_mut_ptr().add(l).cast(), n1);
                _mm256_storeu_si256(s2.as_mut_ptr().add(l).cast(), n2);
                _mm256_storeu_si256(s3.as_mut_ptr().add(l).cast(), n3);
                let u1 = _mm256_castsi256_pd(_mm256_ternarylogic_epi64::<AND_OR>(_mm256_srli_epi64::<12>(word), mantissa_top32, one));
                let u2 = _mm256_castsi256_pd(_mm256_ternarylogic_epi64::<AND_OR>(_mm256_slli_epi64::<20>(word), mantissa_top32, one));
                let (w1, w2) = (_mm256_fmadd_pd(c1, u1, nc1), _mm256_fmadd_pd(c2, u2, nc2));
                let xj = _mm256_loadu_pd(x.as_ptr().add(j));
                let dp = _mm256_sub_pd(_mm256_loadu_pd(p.as_ptr().add(j)), xj);
                let dg = _mm256_sub_pd(_mm256_loadu_pd(g.as_ptr().add(j)), xj);
                let vel = _mm256_fmadd_pd(w2, dg, _mm256_fmadd_pd(w1, dp, _mm256_loadu_pd(v.as_ptr().add(j))));
                let vel = _mm256_mul_pd(k, vel);
                // max(a, b) is a > b ? a : b, so max(lo, v) = v < lo ? lo : v, as `clamp`.
                let vm = _mm256_loadu_pd(vmax.as_ptr().add(j));
                let vel = _mm256_min_pd(vm, _mm256_max_pd(_mm256_xor_pd(vm, sign), vel));
                _mm256_storeu_pd(v.as_mut_ptr().add(j), vel);
                let xn = _mm256_add_pd(xj, vel);
                let xn = _mm256_min_pd(_mm256_loadu_pd(hi.as_ptr().add(j)), _mm256_max_pd(_mm256_loadu_pd(lo.as_ptr().add(j)), xn));
                _mm256_storeu_pd(x.as_mut_ptr().add(j), xn);
            }
        }
        if vec_end < m {
            let r = start + vec_end..start + m;
            let s = [&mut s0[vec_end..m], &mut s1[vec_end..m], &mut s2[vec_end..m], &mut s3[vec_end..m]];
            pso_move_block(&mut x[r.clone()], &mut v[r.clone()], &p[r.clone()], &g[r.clone()], b.range(r), s, co);
        }
    }
}

/// Whether this CPU runs the AVX-512VL copies (256-bit vectors, 32 registers; compiled with
/// AVX2, FMA, AVX-512F and AVX-512VL).
#[cfg(target_arch = "x86_64")]
pub fn avx512vl() -> bool {
    avx2_fma() && std::arch::is_x86_feature_detected!("avx512f") && std::arch::is_x86_feature_detected!("avx512vl")
}

/// One constricted PSO move of one particle. Coordinate j takes r1, r2 from the two 32-bit
/// halves of the next word of lane j % LANES of `rng` (the generation and the move are one
/// vectorised loop).
pub fn pso_move(x: &mut [f64], v: &mut [f64], p: &[f64], g: &[f64], rng: &mut BulkLanes, co: PsoCoefficients, bounds: PsoBounds) {
    #[cfg(target_arch = "x86_64")]
    {
        if avx512vl() {
            // SAFETY: the CPU reports AVX2, FMA, AVX-512F and AVX-512VL.
            return unsafe { pso_move_avx512vl(x, v, p, g, rng, co, bounds) };
        }
        if avx2_fma() {
            // SAFETY: the CPU reports AVX2 and FMA.
            return unsafe { pso_move_avx2(x, v, p, g, rng, co, bounds) };
        }
    }
    pso_move_generic(x, v, p, g, rng, co, bounds)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::sampling::{two_units, xoshiro_step};
    use rand::{RngCore, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn clamp_matches_max_min_and_keeps_nan() {
        for v in [-3.0, -1.0, 0.0, 0.5, 1.0, 7.0, f64::INFINITY, f64::NEG_INFINITY] {
            assert_eq!(clamp(v, -1.0, 1.0), v.clamp(-1.0, 1.0));
        }
        assert!(clamp(f64::NAN, -1.0, 1.0).is_nan());
    }

    #[test]
    fn dispatched_copies_are_bit_identical_and_follow_the_formulas() {
        for n in [1001, 7] {
            copies_agree(n);
        }
    }

    fn copies_agree(n: usize) {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut r = || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0;
        let (a, b, c): (Vec<f64>, Vec<f64>, Vec<f64>) = ((0..n).map(|_| r()).collect(), (0..n).map(|_| r()).collect(), (0..n).map(|_| r()).collect());
        let (lo, hi) = (vec![-1.0; n], vec![1.5; n]);
        let mut t1 = vec![0.0; n];
        let mut t2 = vec![0.0; n];
        de_mutant_generic(&mut t1, &a, &b, &c, 0.3, &lo, &hi);
        de_mutant(&mut t2, &a, &b, &c, 0.3, &lo, &hi);
        assert_eq!(t1, t2);
        for j in 0..n {
            assert_eq!(t1[j], 0.3f64.mul_add(b[j] - c[j], a[j]).clamp(-1.0, 1.5));
        }
        let co = PsoCoefficients { k: 0.729, c1: 2.05, c2: 2.05 };
        let vmax: Vec<f64> = lo.iter().zip(&hi).map(|(l, h)| 0.2 * (h - l)).collect();
        let bounds = PsoBounds { lo: &lo, hi: &hi, vmax: &vmax };
        let gen = BulkLanes::from_rng(&mut ChaCha8Rng::seed_from_u64(2));
        let (mut x1, mut v1, mut g1) = (a.clone(), b.clone(), gen.clone());
        let (mut x2, mut v2, mut g2) = (a.clone(), b.clone(), gen.clone());
        for _ in 0..2 {
            pso_move_generic(&mut x1, &mut v1, &c, &hi, &mut g1, co, bounds);
            pso_move(&mut x2, &mut v2, &c, &hi, &mut g2, co, bounds);
        }
        assert_eq!((&x1, &v1), (&x2, &v2));
        // Each compiled copy this CPU can run, not only the one `pso_move` picks.
        #[cfg(target_arch = "x86_64")]
        {
            type Move = unsafe fn(&mut [f64], &mut [f64], &[f64], &[f64], &mut BulkLanes, PsoCoefficients, PsoBounds);
            let copies: [(bool, Move); 2] = [(avx2_fma(), pso_move_avx2), (avx512vl(), pso_move_avx512vl)];
            for (_, copy) in copies.into_iter().filter(|c| c.0) {
                let (mut x3, mut v3, mut g3) = (a.clone(), b.clone(), gen.clone());
                for _ in 0..2 {
                    // SAFETY: the CPU reports the copy's features.
                    unsafe { copy(&mut x3, &mut v3, &c, &hi, &mut g3, co, bounds) };
                }
                assert_eq!((&x1, &v1), (&x3, &v3));
                assert_eq!(g1.state_mut(), g3.state_mut());
            }
        }
        // The scalar formula, coordinate j drawing the next word of lane j % LANES.
        let mut g3 = gen.clone();
        let (mut x3, mut v3) = (a.clone(), b.clone());
        for _ in 0..2 {
            for j in 0..n {
                let [s0, s1, s2, s3] = g3.state_mut();
                let l = j % LANES;
                let (r1, r2) = two_units(xoshiro_step(&mut s0[l], &mut s1[l], &mut s2[l], &mut s3[l]));
                let vmax = 0.2 * (1.5 - -1.0);
                let (u1, u2) = (r1 + 1.0, r2 + 1.0);
                // The folded c u - c is exactly c r.
                assert_eq!((2.05f64.mul_add(u1, -2.05), 2.05f64.mul_add(u2, -2.05)), (2.05 * r1, 2.05 * r2));
                let vj: f64 = (0.729 * (2.05 * r2).mul_add(hi[j] - x3[j], (2.05 * r1).mul_add(c[j] - x3[j], v3[j]))).clamp(-vmax, vmax);
                v3[j] = vj;
                x3[j] = (x3[j] + vj).clamp(-1.0, 1.5);
            }
        }
        assert_eq!((x1, v1), (x3, v3));
        assert_eq!(g1.state_mut(), g3.state_mut());
    }
}
