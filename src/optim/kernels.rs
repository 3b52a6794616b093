//! The optimisers' per-coordinate loops, compiled twice (baseline and AVX2) and picked at run
//! time. Results are bit-identical between the two: every operation is an IEEE multiply, add or
//! compare in the same order (no fused multiply-add), only the vector width differs.
//!
//! Clamping is written as `if v < lo { lo } else { v }` then `if v > hi { hi } else { v }`: the
//! same value as `max(lo).min(hi)` for every number (and NaN passes through), but it compiles to
//! one vector max and one vector min instead of NaN-aware blends.

use super::sampling::two_units;

#[inline(always)]
fn clamp(v: f64, lo: f64, hi: f64) -> f64 {
    let v = if v < lo { lo } else { v };
    if v > hi {
        hi
    } else {
        v
    }
}

#[inline(always)]
fn de_mutant_generic(t: &mut [f64], a: &[f64], b: &[f64], c: &[f64], f: f64, lo: &[f64], hi: &[f64]) {
    let n = t.len();
    let (a, b, c, lo, hi) = (&a[..n], &b[..n], &c[..n], &lo[..n], &hi[..n]);
    for j in 0..n {
        t[j] = clamp(a[j] + f * (b[j] - c[j]), lo[j], hi[j]);
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn de_mutant_avx2(t: &mut [f64], a: &[f64], b: &[f64], c: &[f64], f: f64, lo: &[f64], hi: &[f64]) {
    de_mutant_generic(t, a, b, c, f, lo, hi)
}

/// t = clamp(a + f (b - c)) per coordinate (DE/rand/1 mutant).
pub fn de_mutant(t: &mut [f64], a: &[f64], b: &[f64], c: &[f64], f: f64, lo: &[f64], hi: &[f64]) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU reports AVX2.
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

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn pso_move_generic(x: &mut [f64], v: &mut [f64], p: &[f64], g: &[f64], words: &[u64], co: PsoCoefficients, vmax: &[f64], lo: &[f64], hi: &[f64]) {
    let n = x.len();
    let (v, p, g, words, vmax, lo, hi) = (&mut v[..n], &p[..n], &g[..n], &words[..n], &vmax[..n], &lo[..n], &hi[..n]);
    for j in 0..n {
        let (r1, r2) = two_units(words[j]);
        let vj = co.k * (v[j] + co.c1 * r1 * (p[j] - x[j]) + co.c2 * r2 * (g[j] - x[j]));
        let vj = clamp(vj, -vmax[j], vmax[j]);
        v[j] = vj;
        x[j] = clamp(x[j] + vj, lo[j], hi[j]);
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
fn pso_move_avx2(x: &mut [f64], v: &mut [f64], p: &[f64], g: &[f64], words: &[u64], co: PsoCoefficients, vmax: &[f64], lo: &[f64], hi: &[f64]) {
    pso_move_generic(x, v, p, g, words, co, vmax, lo, hi)
}

/// One constricted PSO move of one particle; r1, r2 are the 32-bit halves of `words[j]`.
#[allow(clippy::too_many_arguments)]
pub fn pso_move(x: &mut [f64], v: &mut [f64], p: &[f64], g: &[f64], words: &[u64], co: PsoCoefficients, vmax: &[f64], lo: &[f64], hi: &[f64]) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU reports AVX2.
            return unsafe { pso_move_avx2(x, v, p, g, words, co, vmax, lo, hi) };
        }
    }
    pso_move_generic(x, v, p, g, words, co, vmax, lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;
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
    fn dispatched_copies_are_bit_identical() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let n = 1001;
        let mut r = || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0;
        let (a, b, c): (Vec<f64>, Vec<f64>, Vec<f64>) = ((0..n).map(|_| r()).collect(), (0..n).map(|_| r()).collect(), (0..n).map(|_| r()).collect());
        let (lo, hi) = (vec![-1.0; n], vec![1.5; n]);
        let mut t1 = vec![0.0; n];
        let mut t2 = vec![0.0; n];
        de_mutant_generic(&mut t1, &a, &b, &c, 0.3, &lo, &hi);
        de_mutant(&mut t2, &a, &b, &c, 0.3, &lo, &hi);
        assert_eq!(t1, t2);
        for j in 0..n {
            assert_eq!(t1[j], (a[j] + 0.3 * (b[j] - c[j])).clamp(-1.0, 1.5));
        }
        let words: Vec<u64> = (0..n as u64).map(|k| k.wrapping_mul(0x9e37_79b9_7f4a_7c15)).collect();
        let co = PsoCoefficients { k: 0.729, c1: 2.05, c2: 2.05 };
        let vmax = vec![0.4; n];
        let (mut x1, mut v1) = (a.clone(), b.clone());
        let (mut x2, mut v2) = (a.clone(), b.clone());
        pso_move_generic(&mut x1, &mut v1, &c, &hi, &words, co, &vmax, &lo, &hi);
        pso_move(&mut x2, &mut v2, &c, &hi, &words, co, &vmax, &lo, &hi);
        assert_eq!((x1, v1), (x2, v2));
    }
}
