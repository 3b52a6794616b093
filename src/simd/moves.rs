//! The optimisers' per-coordinate loops (DE's trial, PSO's move, the words of DE's four lanes
//! for cuckoo search), each a portable copy beside its copies hand-written in 256-bit vector
//! instructions (one macro body per ISA), picked at run time. Results are bit-identical between
//! the copies: every operation is an IEEE multiply, add, fused multiply-add (`f64::mul_add`, one
//! rounding in every copy: a hardware instruction in the vector copies, the C library's `fma` in
//! the baseline one) or compare in the same order, or exact integer arithmetic; only the vector
//! width differs. Clamping is [`super::clamp`].

use super::clamp;
#[cfg(target_arch = "x86_64")]
use super::{avx2_fma, avx512vl, use_avx2, use_avx512};
use crate::optim::sampling::{two_units_plus_one, DeLanes, PsoLanes, DE_LANES, PSO_LANES};

/// One gene of the DE/rand/1 mutant, clamp(a + f (b - c)), a + f (b - c) fused.
#[inline(always)]
pub(crate) fn de_mutant_gene(a: f64, b: f64, c: f64, f: f64, lo: f64, hi: f64) -> f64 {
    clamp(f.mul_add(b - c, a), lo, hi)
}

/// Genes per step of DE's four crossover lanes: gene 8q + i (i < 4) takes the low 32 bits of
/// lane i's word of step q, gene 8q + 4 + i its high 32 bits.
const DE_BLOCK: usize = 2 * DE_LANES;

/// The DE/rand/1/bin trial of `from..n` (`from` a multiple of [`DE_BLOCK`]) one gene at a time:
/// each block of eight genes steps the four lanes once (also a partial last block); gene j is
/// the mutant's when its 32-bit uniform h is below `threshold`, else the target's.
#[inline(always)]
fn de_trial_scalar(
    t: &mut [f64],
    src: DeSources,
    f: f64,
    rng: &mut DeLanes,
    threshold: u64,
    from: usize,
) {
    let n = t.len();
    for start in (from..n).step_by(DE_BLOCK) {
        let words = rng.next_words();
        let end = (start + DE_BLOCK).min(n);
        for (i, tj) in t[start..end].iter_mut().enumerate() {
            let j = start + i;
            let h = if i < DE_LANES { words[i] & 0xffff_ffff } else { words[i - DE_LANES] >> 32 };
            *tj = if h < threshold {
                de_mutant_gene(src.a[j], src.b[j], src.c[j], f, src.lo[j], src.hi[j])
            } else {
                src.x[j]
            };
        }
    }
}

/// The vectors a trial is built from: donors a, b, c (mutant a + F (b - c)), target x, box.
#[derive(Debug, Clone, Copy)]
pub(crate) struct DeSources<'a> {
    pub(crate) a: &'a [f64],
    pub(crate) b: &'a [f64],
    pub(crate) c: &'a [f64],
    pub(crate) x: &'a [f64],
    pub(crate) lo: &'a [f64],
    pub(crate) hi: &'a [f64],
}

impl<'a> DeSources<'a> {
    /// Every vector cut to length n (so the loops index without bounds checks).
    fn cut(self, n: usize) -> DeSources<'a> {
        DeSources {
            a: &self.a[..n],
            b: &self.b[..n],
            c: &self.c[..n],
            x: &self.x[..n],
            lo: &self.lo[..n],
            hi: &self.hi[..n],
        }
    }
}

#[inline(always)]
fn de_trial_generic(t: &mut [f64], src: DeSources, f: f64, rng: &mut DeLanes, threshold: u64) {
    de_trial_scalar(t, src.cut(t.len()), f, rng, threshold, 0);
}

/// [`de_trial_scalar`] in 256-bit instructions: the four lanes' state in four registers for the
/// whole trial (stored once at the end), eight genes per step, each gene's choice a compare and a
/// blend; the same integer and IEEE operations, so the same bits.
#[cfg(target_arch = "x86_64")]
macro_rules! de_trial_simd {
    ($isa:ident, $t:ident, $src:ident, $f:ident, $rng:ident, $threshold:ident) => {{
        use std::arch::x86_64::*;
        let n = $t.len();
        let src = $src.cut(n);
        let full = n - n % DE_BLOCK;
        let state = $rng.state_mut();
        // SAFETY (all blocks below): every row holds DE_LANES = 4 words; j + 8 <= full <= n
        // bounds every vector (all cut to n).
        let mut s: [__m256i; 4] =
            unsafe { [0, 1, 2, 3].map(|r| _mm256_loadu_si256(state[r].as_ptr().cast())) };
        let (fv, thr, low32) = (
            _mm256_set1_pd($f),
            _mm256_set1_epi64x($threshold as i64),
            _mm256_set1_epi64x(0xffff_ffff),
        );
        // A macro, not a closure: closures do not inherit the function's target features.
        macro_rules! gene4 {
            ($j:expr, $h:expr) => {{
                let j: usize = $j;
                let b_c = _mm256_sub_pd(
                    _mm256_loadu_pd(src.b.as_ptr().add(j)),
                    _mm256_loadu_pd(src.c.as_ptr().add(j)),
                );
                let m = _mm256_fmadd_pd(fv, b_c, _mm256_loadu_pd(src.a.as_ptr().add(j)));
                // max(lo, m) = m < lo ? lo : m and min(hi, .) likewise, as `clamp`.
                let m = _mm256_min_pd(
                    _mm256_loadu_pd(src.hi.as_ptr().add(j)),
                    _mm256_max_pd(_mm256_loadu_pd(src.lo.as_ptr().add(j)), m),
                );
                let t = simd!($isa, choose, $h, thr, _mm256_loadu_pd(src.x.as_ptr().add(j)), m);
                _mm256_storeu_pd($t.as_mut_ptr().add(j), t);
            }};
        }
        for j in (0..full).step_by(DE_BLOCK) {
            unsafe {
                let w = xoshiro4!($isa, s);
                gene4!(j, _mm256_and_si256(w, low32));
                gene4!(j + 4, _mm256_srli_epi64::<32>(w));
            }
        }
        for (r, row) in s.iter().enumerate() {
            unsafe { _mm256_storeu_si256(state[r].as_mut_ptr().cast(), *row) };
        }
        de_trial_scalar($t, src, $f, $rng, $threshold, full);
    }};
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn de_trial_avx2(t: &mut [f64], src: DeSources, f: f64, rng: &mut DeLanes, threshold: u64) {
    de_trial_simd!(avx2, t, src, f, rng, threshold)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
fn de_trial_avx512vl(t: &mut [f64], src: DeSources, f: f64, rng: &mut DeLanes, threshold: u64) {
    de_trial_simd!(avx512vl, t, src, f, rng, threshold)
}

/// The DE/rand/1/bin trial before its forced gene: t_j = clamp(a_j + F (b_j - c_j)) (fused)
/// where gene j's 32-bit uniform h_j < `threshold` ([`crate::optim::sampling::bernoulli_threshold_32`]
/// of CR), else x_j; one pass, the uniforms drawn from `rng` as in `de_trial_scalar`.
pub(crate) fn de_trial(t: &mut [f64], src: DeSources, f: f64, rng: &mut DeLanes, threshold: u64) {
    #[cfg(target_arch = "x86_64")]
    {
        if use_avx512() {
            // SAFETY: the CPU reports AVX2, FMA, AVX-512F and AVX-512VL.
            return unsafe { de_trial_avx512vl(t, src, f, rng, threshold) };
        }
        if use_avx2() {
            // SAFETY: the CPU reports AVX2 and FMA.
            return unsafe { de_trial_avx2(t, src, f, rng, threshold) };
        }
    }
    de_trial_generic(t, src, f, rng, threshold)
}

/// Fill `words` (a multiple of 4 long) with the next words of DE's four lanes: word m from lane
/// m % 4 at step m / 4 (cuckoo search's bulk Levy draws). The AVX2 copy keeps the state in four
/// registers (the same integer operations, so the same words).
pub(crate) fn lanes_fill(words: &mut [u64], rng: &mut DeLanes) {
    assert_eq!(words.len() % DE_LANES, 0, "whole steps of the four lanes");
    #[cfg(target_arch = "x86_64")]
    {
        if use_avx2() {
            // SAFETY: the CPU reports AVX2 and FMA.
            return unsafe { lanes_fill_avx2(words, rng) };
        }
    }
    for w in words.chunks_exact_mut(DE_LANES) {
        w.copy_from_slice(&rng.next_words());
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn lanes_fill_avx2(words: &mut [u64], rng: &mut DeLanes) {
    use std::arch::x86_64::*;
    let state = rng.state_mut();
    // SAFETY: every state row holds 4 words; every store writes words[4 q..4 q + 4], q < len / 4.
    unsafe {
        let mut s: [__m256i; 4] =
            [0, 1, 2, 3].map(|r| _mm256_loadu_si256(state[r].as_ptr().cast()));
        for w in words.chunks_exact_mut(DE_LANES) {
            let word = xoshiro4!(avx2, s);
            _mm256_storeu_si256(w.as_mut_ptr().cast(), word);
        }
        for (r, row) in s.iter().enumerate() {
            _mm256_storeu_si256(state[r].as_mut_ptr().cast(), *row);
        }
    }
}

/// PSO constants of one move.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PsoCoefficients {
    pub(crate) k: f64,
    pub(crate) c1: f64,
    pub(crate) c2: f64,
}

/// The box of a PSO run per coordinate: positions in [lo, hi], velocities in [-vmax, vmax] with
/// vmax = vmax_fraction (vhi - vlo), computed in the move (one rounding each, the same bits as a
/// stored vmax). `vlo`, `vhi` are the range the clamp is a fraction of: `lo`, `hi` themselves
/// (the search box) or the data set's range (`Pso::vmax_range`); when they are the same slices
/// the move reads the same cache lines twice.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PsoBounds<'a> {
    pub(crate) lo: &'a [f64],
    pub(crate) hi: &'a [f64],
    pub(crate) vlo: &'a [f64],
    pub(crate) vhi: &'a [f64],
    pub(crate) vmax_fraction: f64,
}

impl<'a> PsoBounds<'a> {
    /// Positions in [lo, hi] and the clamp a fraction of that box's width.
    pub(crate) fn search_box(lo: &'a [f64], hi: &'a [f64], vmax_fraction: f64) -> PsoBounds<'a> {
        PsoBounds { lo, hi, vlo: lo, vhi: hi, vmax_fraction }
    }
}

/// One coordinate's move from its 64-bit word: (new x, new v).
#[allow(clippy::too_many_arguments)] // one coordinate's values, as the vector copies read them
#[inline(always)]
fn pso_coordinate(
    x: f64,
    v: f64,
    p: f64,
    g: f64,
    lo: f64,
    hi: f64,
    vmax: f64,
    word: u64,
    co: PsoCoefficients,
) -> (f64, f64) {
    let (u1, u2) = two_units_plus_one(word);
    // c r = c (u - 1) with r = u - 1 exact, so c u - c in one rounding is the same number.
    let (a1, a2) = (co.c1.mul_add(u1, -co.c1), co.c2.mul_add(u2, -co.c2));
    let vj = clamp(co.k * a2.mul_add(g - x, a1.mul_add(p - x, v)), -vmax, vmax);
    (clamp(x + vj, lo, hi), vj)
}

/// The move of coordinates `from..n` of position `x` into `out`, coordinate j taking the next
/// word of lane j % 8 (the baseline copy from 0; the vector copies for the coordinates after their
/// last whole vector).
#[allow(clippy::too_many_arguments)] // the vector copies' arguments and where they stopped
#[inline(always)]
fn pso_move_scalar(
    out: &mut [f64],
    x: &[f64],
    v: &mut [f64],
    p: &[f64],
    g: &[f64],
    b: PsoBounds,
    rng: &mut PsoLanes,
    co: PsoCoefficients,
    from: usize,
) {
    let n = out.len();
    let (x, v, p, g, lo, hi) = (&x[..n], &mut v[..n], &p[..n], &g[..n], &b.lo[..n], &b.hi[..n]);
    let (vlo, vhi) = (&b.vlo[..n], &b.vhi[..n]);
    for j in from..n {
        let word = rng.next_word(j % PSO_LANES);
        let vmax = b.vmax_fraction * (vhi[j] - vlo[j]);
        (out[j], v[j]) = pso_coordinate(x[j], v[j], p[j], g[j], lo[j], hi[j], vmax, word, co);
    }
}

#[allow(clippy::too_many_arguments)] // the move's vectors, generators, constants and box
fn pso_move_generic(
    out: &mut [f64],
    x: &[f64],
    v: &mut [f64],
    p: &[f64],
    g: &[f64],
    rng: &mut PsoLanes,
    co: PsoCoefficients,
    b: PsoBounds,
) {
    pso_move_scalar(out, x, v, p, g, b, rng, co, 0)
}

/// The PSO move in 256-bit instructions: the eight lanes' state in eight registers for the whole
/// move (stored once at the end); the same integer operations and the same IEEE operations in
/// the same order as [`pso_move_scalar`], so the same bits. (Left to the compiler, the lanes are
/// not vectorised, and AVX-512 code uses 512-bit vectors, which this Zen 4 runs in two halves.)
#[cfg(target_arch = "x86_64")]
macro_rules! pso_move_simd {
    ($isa:ident, $out:ident, $x:ident, $v:ident, $p:ident, $g:ident, $rng:ident, $co:ident, $b:ident) => {{
        use std::arch::x86_64::*;
        let (out, co) = ($out, $co);
        let n = out.len();
        let (x, v, p, g, lo, hi) =
            (&$x[..n], &mut $v[..n], &$p[..n], &$g[..n], &$b.lo[..n], &$b.hi[..n]);
        let (vlo, vhi) = (&$b.vlo[..n], &$b.vhi[..n]);
        let fraction = _mm256_set1_pd($b.vmax_fraction);
        let mantissa_top32 = _mm256_set1_epi64x(0x000f_ffff_fff0_0000);
        let one = _mm256_set1_epi64x(0x3ff0_0000_0000_0000);
        let (c1, c2, k) = (_mm256_set1_pd(co.c1), _mm256_set1_pd(co.c2), _mm256_set1_pd(co.k));
        let (nc1, nc2) = (_mm256_set1_pd(-co.c1), _mm256_set1_pd(-co.c2));
        let sign = _mm256_set1_pd(-0.0);
        let state = $rng.state_mut();
        // Lanes 0-3 (coordinates 8q..8q+3) and 4-7 (8q+4..8q+7), one register per state row
        // each. SAFETY (all blocks below): every row holds PSO_LANES = 8 words; j + 4 <= n
        // bounds every coordinate slice (all cut to n above).
        let mut low: [__m256i; 4] =
            unsafe { [0, 1, 2, 3].map(|r| _mm256_loadu_si256(state[r].as_ptr().cast())) };
        let mut high: [__m256i; 4] =
            unsafe { [0, 1, 2, 3].map(|r| _mm256_loadu_si256(state[r].as_ptr().add(4).cast())) };
        // A macro, not a closure: closures do not inherit the function's target features.
        macro_rules! move4 {
            ($j:expr, $word:expr) => {{
                let (j, word): (usize, __m256i) = ($j, $word);
                let u1 = _mm256_castsi256_pd(simd!(
                    $isa,
                    and_or,
                    _mm256_srli_epi64::<12>(word),
                    mantissa_top32,
                    one
                ));
                let u2 = _mm256_castsi256_pd(simd!(
                    $isa,
                    and_or,
                    _mm256_slli_epi64::<20>(word),
                    mantissa_top32,
                    one
                ));
                let (w1, w2) = (_mm256_fmadd_pd(c1, u1, nc1), _mm256_fmadd_pd(c2, u2, nc2));
                let xj = _mm256_loadu_pd(x.as_ptr().add(j));
                let dp = _mm256_sub_pd(_mm256_loadu_pd(p.as_ptr().add(j)), xj);
                let dg = _mm256_sub_pd(_mm256_loadu_pd(g.as_ptr().add(j)), xj);
                let vel = _mm256_fmadd_pd(
                    w2,
                    dg,
                    _mm256_fmadd_pd(w1, dp, _mm256_loadu_pd(v.as_ptr().add(j))),
                );
                let vel = _mm256_mul_pd(k, vel);
                // max(a, b) is a > b ? a : b, so max(lo, v) = v < lo ? lo : v, as `clamp`.
                let (hij, loj) =
                    (_mm256_loadu_pd(hi.as_ptr().add(j)), _mm256_loadu_pd(lo.as_ptr().add(j)));
                let vm = _mm256_mul_pd(
                    fraction,
                    _mm256_sub_pd(
                        _mm256_loadu_pd(vhi.as_ptr().add(j)),
                        _mm256_loadu_pd(vlo.as_ptr().add(j)),
                    ),
                );
                let vel = _mm256_min_pd(vm, _mm256_max_pd(_mm256_xor_pd(vm, sign), vel));
                _mm256_storeu_pd(v.as_mut_ptr().add(j), vel);
                let xn = _mm256_add_pd(xj, vel);
                let xn = _mm256_min_pd(hij, _mm256_max_pd(loj, xn));
                _mm256_storeu_pd(out.as_mut_ptr().add(j), xn);
            }};
        }
        let full = n - n % PSO_LANES;
        for j in (0..full).step_by(PSO_LANES) {
            unsafe {
                move4!(j, xoshiro4!($isa, low));
                move4!(j + 4, xoshiro4!($isa, high));
            }
        }
        let mut done = full;
        if n - full >= 4 {
            unsafe { move4!(full, xoshiro4!($isa, low)) };
            done += 4;
        }
        for (r, (lw, hg)) in low.iter().zip(&high).enumerate() {
            unsafe {
                _mm256_storeu_si256(state[r].as_mut_ptr().cast(), *lw);
                _mm256_storeu_si256(state[r].as_mut_ptr().add(4).cast(), *hg);
            }
        }
        let bounds = PsoBounds { lo, hi, vlo, vhi, vmax_fraction: $b.vmax_fraction };
        pso_move_scalar(out, x, v, p, g, bounds, $rng, co, done);
    }};
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[allow(clippy::too_many_arguments)] // the move's vectors, generators, constants and box
fn pso_move_avx2(
    out: &mut [f64],
    x: &[f64],
    v: &mut [f64],
    p: &[f64],
    g: &[f64],
    rng: &mut PsoLanes,
    co: PsoCoefficients,
    b: PsoBounds,
) {
    pso_move_simd!(avx2, out, x, v, p, g, rng, co, b)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,avx512f,avx512vl")]
#[allow(clippy::too_many_arguments)] // the move's vectors, generators, constants and box
fn pso_move_avx512vl(
    out: &mut [f64],
    x: &[f64],
    v: &mut [f64],
    p: &[f64],
    g: &[f64],
    rng: &mut PsoLanes,
    co: PsoCoefficients,
    b: PsoBounds,
) {
    pso_move_simd!(avx512vl, out, x, v, p, g, rng, co, b)
}

/// One constricted PSO move of one particle from position `x` into `out` (of x's length; the
/// velocity `v` in place). Coordinate j takes r1, r2 from the two 32-bit halves of the next word
/// of lane j % 8 of `rng` (the generation and the move are one vectorised loop). Out of place,
/// so that the caller can keep a particle's position and personal best in one buffer while they
/// are equal, and swap buffers instead of copying when the personal best moves.
#[allow(clippy::too_many_arguments)] // the move's vectors, generators, constants and box
pub(crate) fn pso_move(
    out: &mut [f64],
    x: &[f64],
    v: &mut [f64],
    p: &[f64],
    g: &[f64],
    rng: &mut PsoLanes,
    co: PsoCoefficients,
    bounds: PsoBounds,
) {
    #[cfg(target_arch = "x86_64")]
    {
        if use_avx512() {
            // SAFETY: the CPU reports AVX2, FMA, AVX-512F and AVX-512VL.
            return unsafe { pso_move_avx512vl(out, x, v, p, g, rng, co, bounds) };
        }
        if use_avx2() {
            // SAFETY: the CPU reports AVX2 and FMA.
            return unsafe { pso_move_avx2(out, x, v, p, g, rng, co, bounds) };
        }
    }
    pso_move_generic(out, x, v, p, g, rng, co, bounds)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::sampling::{bernoulli_threshold_32, two_units, xoshiro_step};
    use rand::{RngCore, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn dispatched_copies_are_bit_identical_and_follow_the_formulas() {
        for n in [1001, 7, 1, 4, 8, 12, 13, 16, 108] {
            copies_agree(n);
        }
    }

    fn copies_agree(n: usize) {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut r = || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0;
        let mut vector = || -> Vec<f64> { (0..n).map(|_| r()).collect() };
        let (a, b, c, x) = (vector(), vector(), vector(), vector());
        let (lo, hi) = (vec![-1.0; n], vec![1.5; n]);
        let src = DeSources { a: &a, b: &b, c: &c, x: &x, lo: &lo, hi: &hi };
        #[cfg(target_arch = "x86_64")]
        type Trial = unsafe fn(&mut [f64], DeSources, f64, &mut DeLanes, u64);
        #[cfg(target_arch = "x86_64")]
        let trial_copies: [(bool, Trial); 2] =
            [(avx2_fma(), de_trial_avx2), (avx512vl(), de_trial_avx512vl)];
        for cr in [0.0, 0.3, 0.8, 1.0] {
            let threshold = bernoulli_threshold_32(cr);
            let lanes = DeLanes::from_rng(&mut ChaCha8Rng::seed_from_u64(3));
            // Two trials in a row from the same lanes (the second continues the first's streams).
            let trials = |mut lanes: DeLanes, copy: &dyn Fn(&mut [f64], &mut DeLanes)| {
                let (mut t1, mut t2) = (vec![0.0; n], vec![0.0; n]);
                copy(&mut t1, &mut lanes);
                copy(&mut t2, &mut lanes);
                (t1, t2, lanes)
            };
            let generic =
                trials(lanes.clone(), &|t, l| de_trial_generic(t, src, 0.3, l, threshold));
            assert_eq!(
                generic,
                trials(lanes.clone(), &|t, l| de_trial(t, src, 0.3, l, threshold)),
                "n {n} cr {cr}"
            );
            #[cfg(target_arch = "x86_64")]
            for (_, copy) in trial_copies.iter().filter(|c| c.0) {
                // SAFETY: the CPU reports the copy's features.
                assert_eq!(
                    generic,
                    trials(lanes.clone(), &|t, l| unsafe { copy(t, src, 0.3, l, threshold) }),
                    "n {n} cr {cr}"
                );
            }
            // The formula: block q of eight genes steps the four lanes once; gene 8q + i takes
            // the low half of lane i's word (i < 4), gene 8q + 4 + i the high half.
            let mut single = lanes.clone();
            for t in [&generic.0, &generic.1] {
                for q in 0..n.div_ceil(8) {
                    let [s0, s1, s2, s3] = single.state_mut();
                    let words: Vec<u64> = (0..4)
                        .map(|l| xoshiro_step(&mut s0[l], &mut s1[l], &mut s2[l], &mut s3[l]))
                        .collect();
                    for j in 8 * q..(8 * q + 8).min(n) {
                        let i = j - 8 * q;
                        let h = if i < 4 { words[i] as u32 } else { (words[i - 4] >> 32) as u32 };
                        let mutant = 0.3f64.mul_add(b[j] - c[j], a[j]).clamp(-1.0, 1.5);
                        let take = (h as u64) < threshold;
                        assert_eq!(
                            t[j],
                            if take { mutant } else { x[j] },
                            "n {n} cr {cr} gene {j}"
                        );
                        if cr == 0.0 || cr == 1.0 {
                            assert_eq!(take, cr == 1.0);
                        }
                    }
                }
            }
            assert_eq!(single, generic.2);
        }
        let co = PsoCoefficients { k: 0.729, c1: 2.05, c2: 2.05 };
        let bounds = PsoBounds::search_box(&lo, &hi, 0.2);
        let gen = PsoLanes::from_rng(&mut ChaCha8Rng::seed_from_u64(2));
        let (mut x1, mut v1, mut g1) = (a.clone(), b.clone(), gen.clone());
        let (mut x2, mut v2, mut g2) = (a.clone(), b.clone(), gen.clone());
        for _ in 0..2 {
            let (from1, from2) = (x1.clone(), x2.clone());
            pso_move_generic(&mut x1, &from1, &mut v1, &c, &hi, &mut g1, co, bounds);
            pso_move(&mut x2, &from2, &mut v2, &c, &hi, &mut g2, co, bounds);
        }
        assert_eq!((&x1, &v1, &g1), (&x2, &v2, &g2));
        // Each compiled copy this CPU can run, not only the one `pso_move` picks.
        #[cfg(target_arch = "x86_64")]
        {
            type Move = unsafe fn(
                &mut [f64],
                &[f64],
                &mut [f64],
                &[f64],
                &[f64],
                &mut PsoLanes,
                PsoCoefficients,
                PsoBounds,
            );
            let copies: [(bool, Move); 2] =
                [(avx2_fma(), pso_move_avx2), (avx512vl(), pso_move_avx512vl)];
            for (_, copy) in copies.into_iter().filter(|c| c.0) {
                let (mut x3, mut v3, mut g3) = (a.clone(), b.clone(), gen.clone());
                for _ in 0..2 {
                    // SAFETY: the CPU reports the copy's features.
                    let from = x3.clone();
                    unsafe { copy(&mut x3, &from, &mut v3, &c, &hi, &mut g3, co, bounds) };
                }
                assert_eq!((&x1, &v1, &g1), (&x3, &v3, &g3), "n {n}");
            }
        }
        // The scalar formula, coordinate j drawing the next word of lane j % 8.
        let mut g3 = gen.clone();
        let (mut x3, mut v3) = (a.clone(), b.clone());
        for _ in 0..2 {
            for j in 0..n {
                let [s0, s1, s2, s3] = g3.state_mut();
                let l = j % PSO_LANES;
                let (r1, r2) =
                    two_units(xoshiro_step(&mut s0[l], &mut s1[l], &mut s2[l], &mut s3[l]));
                let vmax = 0.2 * (1.5 - -1.0);
                let (u1, u2) = (r1 + 1.0, r2 + 1.0);
                // The folded c u - c is exactly c r.
                assert_eq!(
                    (2.05f64.mul_add(u1, -2.05), 2.05f64.mul_add(u2, -2.05)),
                    (2.05 * r1, 2.05 * r2)
                );
                let vj: f64 = (0.729
                    * (2.05 * r2).mul_add(hi[j] - x3[j], (2.05 * r1).mul_add(c[j] - x3[j], v3[j])))
                .clamp(-vmax, vmax);
                v3[j] = vj;
                x3[j] = (x3[j] + vj).clamp(-1.0, 1.5);
            }
        }
        assert_eq!((x1, v1, g1), (x3, v3, g3));
    }

    /// Genes come from the mutant at the rate CR (within five standard deviations), each lane
    /// and half alike.
    #[test]
    fn trial_genes_come_from_the_mutant_at_rate_cr() {
        let n = 1000;
        let (a, b, c, x) = (vec![1.0; n], vec![0.0; n], vec![0.0; n], vec![2.0; n]);
        let (lo, hi) = (vec![-5.0; n], vec![5.0; n]);
        let src = DeSources { a: &a, b: &b, c: &c, x: &x, lo: &lo, hi: &hi };
        let mut lanes = DeLanes::from_rng(&mut ChaCha8Rng::seed_from_u64(9));
        let mut t = vec![0.0; n];
        for cr in [0.01, 0.5, 0.8] {
            let trials = 400;
            let mut by_slot = [0usize; 8];
            for _ in 0..trials {
                de_trial(&mut t, src, 0.3, &mut lanes, bernoulli_threshold_32(cr));
                for (j, &tj) in t.iter().enumerate() {
                    if tj == 1.0 {
                        by_slot[j % 8] += 1;
                    }
                }
            }
            let per_slot = (trials * n / 8) as f64;
            for (slot, &k) in by_slot.iter().enumerate() {
                let sd = (per_slot * cr * (1.0 - cr)).sqrt();
                assert!(
                    (k as f64 - per_slot * cr).abs() < 5.0 * sd,
                    "cr {cr} slot {slot}: {k} of {per_slot}"
                );
            }
        }
    }
}

/// Measurements for `cargo bench --bench optim`: ns per coordinate of each compiled copy of the
/// DE trial and the PSO move on a 12x12 net's 432 coordinates (best of 30 batches).
#[cfg(target_arch = "x86_64")]
#[doc(hidden)]
pub mod timing {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use std::time::Instant;

    fn best_ns(n: usize, mut f: impl FnMut()) -> f64 {
        let reps = 2000;
        (0..30)
            .map(|_| {
                let t = Instant::now();
                for _ in 0..reps {
                    f();
                }
                t.elapsed().as_secs_f64() * 1e9 / (reps * n) as f64
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// One line per compiled copy this CPU has: the DE trial's ns per gene, the PSO move's ns per
    /// coordinate.
    pub fn report() -> Vec<String> {
        let mut out = Vec::new();
        let n = 432;
        let v: Vec<f64> = (0..n).map(|j| (j as f64 * 0.37).sin()).collect();
        let (lo, hi) = (vec![-1.0; n], vec![1.0; n]);
        let src = DeSources { a: &v, b: &lo, c: &hi, x: &v, lo: &lo, hi: &hi };
        let mut lanes = DeLanes::from_rng(&mut ChaCha8Rng::seed_from_u64(1));
        let mut t = vec![0.0; n];
        let threshold = crate::optim::sampling::bernoulli_threshold_32(0.8);
        type Trial = unsafe fn(&mut [f64], DeSources, f64, &mut DeLanes, u64);
        let trials: [(&str, bool, Trial); 3] = [
            ("baseline", true, |t, s, f, l, th| de_trial_generic(t, s, f, l, th)),
            ("avx2", avx2_fma(), de_trial_avx2),
            ("avx512vl", avx512vl(), de_trial_avx512vl),
        ];
        for (name, _, copy) in trials.into_iter().filter(|c| c.1) {
            // SAFETY: the CPU reports the copy's features.
            out.push(format!(
                "DE trial {name}: {:.3} ns per gene",
                best_ns(n, || unsafe { copy(&mut t, src, 0.3, &mut lanes, threshold) })
            ));
        }
        let bounds = PsoBounds::search_box(&lo, &hi, 0.5);
        let co = PsoCoefficients { k: 0.729, c1: 2.05, c2: 2.05 };
        let mut gen = PsoLanes::from_rng(&mut ChaCha8Rng::seed_from_u64(2));
        let (mut x, mut vel, mut moved) = (v.clone(), vec![0.0; n], vec![0.0; n]);
        type Move = unsafe fn(
            &mut [f64],
            &[f64],
            &mut [f64],
            &[f64],
            &[f64],
            &mut PsoLanes,
            PsoCoefficients,
            PsoBounds,
        );
        let moves: [(&str, bool, Move); 3] = [
            ("baseline", true, |o, x, v, p, g, r, c, b| pso_move_generic(o, x, v, p, g, r, c, b)),
            ("avx2", avx2_fma(), pso_move_avx2),
            ("avx512vl", avx512vl(), pso_move_avx512vl),
        ];
        for (name, _, copy) in moves.into_iter().filter(|c| c.1) {
            // SAFETY: the CPU reports the copy's features.
            out.push(format!(
                "PSO move {name}: {:.3} ns per coordinate",
                best_ns(n, || {
                    unsafe { copy(&mut moved, &x, &mut vel, &v, &hi, &mut gen, co, bounds) };
                    std::mem::swap(&mut x, &mut moved);
                })
            ));
        }
        out
    }
}
