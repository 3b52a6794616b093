//! Cuckoo search's Levy factors sigma_u T from the quantile table of
//! [`crate::optim::levy::LevyTable`] (one 32-bit field, one table look-up and a cubic per
//! coordinate), and one Levy flight in one pass: the portable copy beside the AVX2 copy.
//!
//! The baseline copy computes each factor in scalar IEEE operations and `f64::mul_add`; the AVX2
//! copy does the same operations four lanes at a time (each lane's coefficient row loaded whole
//! and transposed in registers, `vfmadd`), so the copies give the same bits. Words come from four
//! xoshiro256++ lanes ([`DeLanes`], seeded from the run's ChaCha8 stream): chunk after chunk of
//! [`CHUNK`] coordinates, each consuming HALF / 4 steps of the four lanes; word k of a chunk
//! (lane k % 4, step k / 4) holds the field of coordinate k (low 32 bits) and of coordinate
//! k + HALF (high 32 bits).

use crate::optim::levy::{
    LevyTable, CHUNK, FIRST_EXP, HALF, HALF_STEP_30, K_MASK, MANT, ONE, SEG_BITS, SIDE, TABLE_LEN,
};
use crate::optim::sampling::DeLanes;

/// The uniform r' = (k + 1/2) 2^-30 of a field's 30 bits k.
#[inline(always)]
fn field_unit(field: u64) -> f64 {
    (f64::from_bits(((field & K_MASK) << 22) | ONE) - 1.0) + HALF_STEP_30
}

/// One Levy factor sigma T from a 32-bit field (see the module): sign bit 31, side bit 30.
#[inline(always)]
fn factor(table: &LevyTable, field: u64, sigma: f64) -> f64 {
    let t = table.magnitude((field >> 30) & 1 == 1, field_unit(field));
    f64::from_bits((t * sigma).to_bits() ^ (((field >> 31) & 1) << 63))
}

/// One chunk of factors in scalar operations: `out[k]` from the low field of word k,
/// `out[k + HALF]` from its high field.
fn chunk_scalar(out: &mut [f64; CHUNK], words: &[u64; HALF], table: &LevyTable, sigma: f64) {
    for k in 0..HALF {
        out[k] = factor(table, words[k] & 0xffff_ffff, sigma);
        out[k + HALF] = factor(table, words[k] >> 32, sigma);
    }
}

/// [`chunk_scalar`] four lanes at a time: the same operations (integer shifts and masks, IEEE
/// subtract and add, the coefficient rows loaded and transposed, `vfmadd`, multiply, sign xor), the
/// same bits.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn chunk_avx2(out: &mut [f64; CHUNK], words: &[u64; HALF], table: &LevyTable, sigma: f64) {
    use std::arch::x86_64::*;
    let base: *const f64 = table.coef.as_ptr().cast();
    // SAFETY: loads and stores of words[4 q..4 q + 4] and out[..] within bounds; every row loaded
    // is row * 4 .. row * 4 + 4 with row masked below TABLE_LEN, inside the coefficient array.
    unsafe {
        let one = _mm256_set1_epi64x(ONE as i64);
        let onef = _mm256_set1_pd(1.0);
        let half = _mm256_set1_pd(HALF_STEP_30);
        let kmask = _mm256_set1_epi64x(K_MASK as i64);
        let mant = _mm256_set1_epi64x(MANT as i64);
        let low32 = _mm256_set1_epi64x(0xffff_ffff);
        let first = _mm256_set1_epi64x((FIRST_EXP << SEG_BITS) as i64);
        let side = _mm256_set1_epi64x(SIDE as i64);
        let bit = _mm256_set1_epi64x(1);
        let rows = _mm256_set1_epi64x(TABLE_LEN as i64 - 1);
        let sig = _mm256_set1_pd(sigma);
        for q in 0..HALF / 4 {
            let w = _mm256_loadu_si256(words.as_ptr().add(4 * q).cast());
            for (h, field) in
                [_mm256_and_si256(w, low32), _mm256_srli_epi64::<32>(w)].into_iter().enumerate()
            {
                let k =
                    _mm256_or_si256(_mm256_slli_epi64::<22>(_mm256_and_si256(field, kmask)), one);
                let r = _mm256_add_pd(_mm256_sub_pd(_mm256_castsi256_pd(k), onef), half);
                let bits = _mm256_castpd_si256(r);
                let up = _mm256_and_si256(_mm256_srli_epi64::<30>(field), bit);
                let off = _mm256_and_si256(_mm256_sub_epi64(_mm256_setzero_si256(), up), side);
                let seg =
                    _mm256_sub_epi64(_mm256_srli_epi64::<{ 52 - SEG_BITS as i32 }>(bits), first);
                let row = _mm256_and_si256(_mm256_add_epi64(seg, off), rows);
                let fb = _mm256_or_si256(
                    _mm256_and_si256(_mm256_slli_epi64::<{ SEG_BITS as i32 }>(bits), mant),
                    one,
                );
                let f = _mm256_sub_pd(_mm256_castsi256_pd(fb), onef);
                // Each lane's four coefficients are one 32-byte row: four row loads and a 4 x 4
                // transpose in registers (four gathers of one coefficient each cost more on Zen 3).
                let mut at = [0u64; 4];
                _mm256_storeu_si256(at.as_mut_ptr().cast(), _mm256_slli_epi64::<2>(row));
                let r = [
                    _mm256_loadu_pd(base.add(at[0] as usize)),
                    _mm256_loadu_pd(base.add(at[1] as usize)),
                    _mm256_loadu_pd(base.add(at[2] as usize)),
                    _mm256_loadu_pd(base.add(at[3] as usize)),
                ];
                let (t0, t1) = (_mm256_unpacklo_pd(r[0], r[1]), _mm256_unpackhi_pd(r[0], r[1]));
                let (t2, t3) = (_mm256_unpacklo_pd(r[2], r[3]), _mm256_unpackhi_pd(r[2], r[3]));
                let c0 = _mm256_permute2f128_pd::<0x20>(t0, t2);
                let c1 = _mm256_permute2f128_pd::<0x20>(t1, t3);
                let c2 = _mm256_permute2f128_pd::<0x31>(t0, t2);
                let c3 = _mm256_permute2f128_pd::<0x31>(t1, t3);
                let t = _mm256_fmadd_pd(_mm256_fmadd_pd(_mm256_fmadd_pd(c3, f, c2), f, c1), f, c0);
                let sign = _mm256_slli_epi64::<63>(_mm256_srli_epi64::<31>(field));
                let l = _mm256_xor_pd(_mm256_mul_pd(t, sig), _mm256_castsi256_pd(sign));
                _mm256_storeu_pd(out.as_mut_ptr().add(h * HALF + 4 * q), l);
            }
        }
    }
}

/// One chunk of factors in the copy the run's SIMD choice names.
#[inline(always)]
fn chunk(out: &mut [f64; CHUNK], words: &[u64; HALF], table: &LevyTable, sigma: f64, avx2: bool) {
    #[cfg(target_arch = "x86_64")]
    {
        if avx2 {
            // SAFETY: avx2 is true only when the CPU reports AVX2 and FMA (use_avx2).
            return unsafe { chunk_avx2(out, words, table, sigma) };
        }
    }
    let _ = avx2;
    chunk_scalar(out, words, table, sigma)
}

/// `out[j]` = sigma_u T_j for every j, chunk by chunk from `rng` (see the module), in the scalar
/// (`avx2` false) or the AVX2 copy.
#[cfg(test)]
fn fill_with(out: &mut [f64], sigma: f64, table: &LevyTable, rng: &mut DeLanes, avx2: bool) {
    let mut words = [0u64; HALF];
    let mut buf = [0.0f64; CHUNK];
    for piece in out.chunks_mut(CHUNK) {
        super::moves::lanes_fill(&mut words, rng);
        chunk(&mut buf, &words, table, sigma, avx2);
        piece.copy_from_slice(&buf[..piece.len()]);
    }
}

/// The vectors of one Levy flight: the nest `x`, the best nest `b` and the box.
#[derive(Debug, Clone, Copy)]
pub(crate) struct FlightSources<'a> {
    pub(crate) x: &'a [f64],
    pub(crate) b: &'a [f64],
    pub(crate) lo: &'a [f64],
    pub(crate) hi: &'a [f64],
}

/// One flight's words and factors, chunk by chunk (kept by the caller across flights, so that
/// nothing is allocated or cleared per flight).
#[derive(Debug, Clone)]
pub(crate) struct LevyScratch {
    words: [u64; HALF],
    factors: [f64; CHUNK],
}

impl Default for LevyScratch {
    fn default() -> LevyScratch {
        LevyScratch { words: [0; HALF], factors: [0.0; CHUNK] }
    }
}

/// One coordinate of a Levy flight: x + alpha L (x - b) clamped to [lo, hi] (x itself if that
/// is NaN, from 0 * inf).
#[inline(always)]
pub(crate) fn flight_coordinate(x: f64, b: f64, lo: f64, hi: f64, alpha: f64, l: f64) -> f64 {
    let nj = x + alpha * l * (x - b);
    if nj.is_nan() {
        x
    } else {
        super::clamp(nj, lo, hi)
    }
}

/// The parameters of one flight's factors: the table, sigma_u and the step alpha.
#[derive(Debug, Clone, Copy)]
pub(crate) struct FlightLaw<'a> {
    pub(crate) table: &'a LevyTable,
    pub(crate) sigma_u: f64,
    pub(crate) alpha: f64,
}

/// [`levy_flight`] in one pass: each chunk's factors go straight into its coordinates' flight,
/// while they are in L1 (the same draws and operations as [`levy_fill`] followed by
/// [`flight_coordinate`] per coordinate, so the same bits).
#[inline(always)]
fn flight_body(
    c: &mut [f64],
    src: FlightSources,
    law: FlightLaw,
    rng: &mut DeLanes,
    scratch: &mut LevyScratch,
    avx2: bool,
) {
    let n = c.len();
    let (x, b, lo, hi) = (&src.x[..n], &src.b[..n], &src.lo[..n], &src.hi[..n]);
    for (k, piece) in c.chunks_mut(CHUNK).enumerate() {
        super::moves::lanes_fill(&mut scratch.words, rng);
        chunk(&mut scratch.factors, &scratch.words, law.table, law.sigma_u, avx2);
        let (from, m) = (k * CHUNK, piece.len());
        let (x, b, lo, hi) = (&x[from..from + m], &b[from..from + m], &lo[from..], &hi[from..]);
        let (lo, hi, l) = (&lo[..m], &hi[..m], &scratch.factors[..m]);
        for j in 0..m {
            piece[j] = flight_coordinate(x[j], b[j], lo[j], hi[j], law.alpha, l[j]);
        }
    }
}

fn flight_generic(
    c: &mut [f64],
    src: FlightSources,
    law: FlightLaw,
    rng: &mut DeLanes,
    scratch: &mut LevyScratch,
) {
    flight_body(c, src, law, rng, scratch, false)
}

/// The AVX2 copy: the factors by [`chunk_avx2`], the flight's loop vectorised by the compiler
/// (no fused multiply-add there, so the same bits).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn flight_avx2(
    c: &mut [f64],
    src: FlightSources,
    law: FlightLaw,
    rng: &mut DeLanes,
    scratch: &mut LevyScratch,
) {
    flight_body(c, src, law, rng, scratch, true)
}

/// One Levy flight of a nest into `c` (of the nest's length): coordinate j is
/// [`flight_coordinate`] of the factor sigma_u T that [`levy_fill`] would draw for it from `rng`
/// (the same words and the same bits), in the copy the run's SIMD choice names.
pub(crate) fn levy_flight(
    c: &mut [f64],
    src: FlightSources,
    law: FlightLaw,
    rng: &mut DeLanes,
    scratch: &mut LevyScratch,
) {
    #[cfg(target_arch = "x86_64")]
    {
        if super::use_avx2() {
            // SAFETY: use_avx2 is true only when the CPU reports AVX2 and FMA.
            return unsafe { flight_avx2(c, src, law, rng, scratch) };
        }
    }
    flight_generic(c, src, law, rng, scratch)
}

/// Fill `out` with Levy factors sigma_u T (T = u psi / |v|^(1/beta), beta the table's), in the
/// copy the run's SIMD choice ([`super::simd`]) names; the same bits from every copy.
#[cfg(test)]
pub(crate) fn levy_fill(out: &mut [f64], sigma_u: f64, table: &LevyTable, rng: &mut DeLanes) {
    fill_with(out, sigma_u, table, rng, super::use_avx2())
}

/// The baseline copy (the tests' reference for the dispatched one).
#[cfg(test)]
pub(crate) fn levy_fill_baseline(
    out: &mut [f64],
    sigma_u: f64,
    table: &LevyTable,
    rng: &mut DeLanes,
) {
    fill_with(out, sigma_u, table, rng, false)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::levy::SEGS;
    use rand::{RngCore, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The sign bit flips the factor exactly; the index and fraction are the octave, segment and
    /// position of r' = (k + 1/2) 2^-30.
    #[test]
    fn fields_map_to_the_grid() {
        let table = LevyTable::shared(1.5);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..10_000 {
            let field = rng.next_u64() & 0xffff_ffff;
            let (a, b) = (factor(&table, field, 0.7), factor(&table, field ^ (1 << 31), 0.7));
            assert_eq!(a.to_bits(), (-b).to_bits());
            let r = field_unit(field);
            assert_eq!(r, ((field & K_MASK) as f64 + 0.5) / (1u64 << 30) as f64);
            let e = r.log2().floor();
            let pos = (r / e.exp2() - 1.0) * SEGS as f64;
            let bits = r.to_bits();
            let i = ((bits >> (52 - SEG_BITS)) - (FIRST_EXP << SEG_BITS)) as usize;
            assert_eq!(i, (e as i64 + 31) as usize * SEGS + pos.floor() as usize);
            let f = f64::from_bits(((bits << SEG_BITS) & MANT) | ONE) - 1.0;
            assert_eq!(f, pos - pos.floor());
        }
        assert_eq!(field_unit(0), HALF_STEP_30);
        assert_eq!(field_unit(K_MASK), 1.0 - HALF_STEP_30);
    }

    /// The dispatched copy gives the baseline copy's bits, for lengths around the chunk size, and
    /// leaves the generators in the same state.
    #[test]
    fn copies_are_bit_identical() {
        let table = LevyTable::shared(1.5);
        for n in [1, 3, 127, 128, 129, 1740] {
            let mut a = DeLanes::from_rng(&mut ChaCha8Rng::seed_from_u64(n as u64));
            let mut b = a.clone();
            let (mut x, mut y) = (vec![0.0; n], vec![0.0; n]);
            for _ in 0..3 {
                levy_fill(&mut x, 0.7, &table, &mut a);
                levy_fill_baseline(&mut y, 0.7, &table, &mut b);
                assert!(x.iter().zip(&y).all(|(p, q)| p.to_bits() == q.to_bits()), "n {n}");
            }
            assert_eq!(a, b);
        }
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
            let mut rng = ChaCha8Rng::seed_from_u64(8);
            for _ in 0..200 {
                let words: [u64; HALF] = std::array::from_fn(|_| rng.next_u64());
                let (mut p, mut q) = ([0.0; CHUNK], [0.0; CHUNK]);
                chunk_scalar(&mut p, &words, &table, 0.7);
                // SAFETY: the CPU reports AVX2 and FMA.
                unsafe { chunk_avx2(&mut q, &words, &table, 0.7) };
                assert!(p.iter().zip(&q).all(|(a, b)| a.to_bits() == b.to_bits()));
            }
        }
    }

    /// A fused flight gives the bits of the factors from `levy_fill` followed by the flight's
    /// formula, in the dispatched and the baseline copy, for lengths around the chunk size, with
    /// coordinates at, inside and beyond the box; and the generators end in the same state.
    #[test]
    fn fused_flight_is_fill_then_step() {
        use crate::optim::sampling::symmetric;
        let table = LevyTable::shared(1.5);
        let mut r = ChaCha8Rng::seed_from_u64(12);
        for n in [1, 5, 127, 128, 129, 300, 1740] {
            let x: Vec<f64> = (0..n).map(|_| symmetric(&mut r, 1.0)).collect();
            let b: Vec<f64> = (0..n).map(|_| symmetric(&mut r, 1.0)).collect();
            let lo: Vec<f64> = x.iter().map(|v| v - 0.05).collect();
            let hi: Vec<f64> =
                x.iter().enumerate().map(|(j, v)| v + 0.05 * (j % 3) as f64).collect();
            let src = FlightSources { x: &x, b: &b, lo: &lo, hi: &hi };
            let lanes = DeLanes::from_rng(&mut ChaCha8Rng::seed_from_u64(n as u64));
            let (mut want_lanes, mut l) = (lanes.clone(), vec![0.0; n]);
            levy_fill_baseline(&mut l, 0.7, &table, &mut want_lanes);
            let want: Vec<f64> =
                (0..n).map(|j| flight_coordinate(x[j], b[j], lo[j], hi[j], 0.3, l[j])).collect();
            assert!(want.iter().enumerate().any(|(j, w)| *w == hi[j]) || n < 100);
            assert!(want.iter().enumerate().any(|(j, w)| *w == lo[j]) || n < 100);
            assert!(want.iter().enumerate().any(|(j, w)| *w > lo[j] && *w < hi[j]) || n < 100);
            let mut scratch = LevyScratch::default();
            let law = FlightLaw { table: &table, sigma_u: 0.7, alpha: 0.3 };
            for fused in [levy_flight, flight_generic] {
                let (mut got, mut got_lanes) = (vec![0.0; n], lanes.clone());
                fused(&mut got, src, law, &mut got_lanes, &mut scratch);
                assert!(got.iter().zip(&want).all(|(p, q)| p.to_bits() == q.to_bits()), "n {n}");
                assert_eq!(got_lanes, want_lanes);
            }
        }
        assert_eq!(flight_coordinate(1.0, 0.0, -2.0, 2.0, 0.0, f64::INFINITY), 1.0);
    }
}

/// Measurements for `cargo bench --bench optim`: ns per factor of each compiled copy of a Levy
/// flight's factors (one chunk of 128, data in L1, best of 30 batches).
#[cfg(target_arch = "x86_64")]
#[doc(hidden)]
pub mod timing {
    use super::*;
    use std::time::Instant;

    /// One line per compiled copy this CPU has.
    pub fn report() -> Vec<String> {
        let table = LevyTable::shared(1.5);
        let words: [u64; HALF] =
            std::array::from_fn(|k| (k as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let mut out = [0.0; CHUNK];
        type Chunk = unsafe fn(&mut [f64; CHUNK], &[u64; HALF], &LevyTable, f64);
        let copies: [(&str, bool, Chunk); 2] = [
            ("baseline", true, |o, w, t, s| chunk_scalar(o, w, t, s)),
            ("avx2", crate::simd::avx2_fma(), chunk_avx2),
        ];
        let mut lines = Vec::new();
        for (name, _, copy) in copies.into_iter().filter(|c| c.1) {
            let reps = 2000;
            let best = (0..30)
                .map(|_| {
                    let t = Instant::now();
                    for _ in 0..reps {
                        // SAFETY: the CPU reports the copy's features.
                        unsafe { copy(&mut out, std::hint::black_box(&words), &table, 0.7) };
                        std::hint::black_box(&out);
                    }
                    t.elapsed().as_secs_f64() * 1e9 / (reps * CHUNK) as f64
                })
                .fold(f64::INFINITY, f64::min);
            lines.push(format!("Levy factors {name}: {best:.3} ns per factor"));
        }
        lines
    }
}
