//! Cuckoo search's Levy steps (Mantegna's method, beta = 3/2) drawn in bulk: one vectorised pass
//! per nest instead of three library normal draws and a Newton cube root per coordinate.
//!
//! Mantegna's step times the flight's own normal factor is L = u psi / |v|^(1/beta) with u, v, psi
//! independent, u ~ N(0, sigma_u^2), v, psi ~ N(0, 1). The normals come from Box-Muller pairs
//! (z1, z2) = r (cos theta, sin theta), r^2 = 2E, E ~ Exp(1), theta ~ U[0, 2 pi), drawn so that
//! nothing is wasted:
//! - u psi: the product of the two normals of one pair is r^2 cos theta sin theta = E sin 2 theta,
//!   and 2 theta (mod 2 pi) is uniform, so u psi = sigma_u E sin theta' exactly in law: one
//!   logarithm and one sine per coordinate for two normals.
//! - v^2 of two coordinates: one pair gives v1^2 = 2E cos^2 theta and v2^2 = 2E sin^2 theta; then
//!   |v|^(-2/3) = (v^2)^(-1/3) by Newton's iteration (no square root, no power function).
//! - A uniform angle is reduced without multiplying by pi and folding: |sin| and |cos| of a
//!   uniform angle are, with probability 1/2 each, sin t and cos t of t ~ U(0, pi/4) (the
//!   circle's symmetries), so one random bit picks the function, one bit the sign, and the
//!   remaining 31 bits give t; sin t and cos t are Taylor polynomials on (0, pi/4), exact to
//!   about 1e-14 relative even for the tiny values that make the heavy tail.
//!
//! Every uniform is (k + 1/2) 2^-32 from 32 random bits (or (k + 1/2) 2^-31 from 31 bits beside a
//! sign or swap bit), in (0, 1): no logarithm of 0, no angle at 0, so every step is finite
//! (E <= 22.9, |v|^2 >= 1e-29); a 32-bit uniform moves the law by at most 2^-32 in each
//! probability. The functions are written in IEEE additions, multiplications, divisions and
//! fused multiply-adds (`f64::mul_add`, one rounding: the AVX2 copy's `vfmadd`, the baseline
//! copy's C library `fma`), so the baseline and AVX2 copies (the same Rust, compiled twice) give
//! the same bits on every x86-64. Words come from four xoshiro256++ lanes ([`DeLanes`], seeded
//! from the run's ChaCha8 stream), each 64-bit word giving two 32-bit fields: chunk after chunk of
//! [`CHUNK`] coordinates, each consuming 3 CHUNK / 8 steps of the four lanes, word m of a chunk
//! from lane m % 4 at step m / 4 (layout at [`chunk`]).

// Index loops over the chunk's parallel arrays read more plainly than zipped iterators here.
#![allow(clippy::needless_range_loop)]

use super::sampling::DeLanes;
#[cfg(test)]
use super::sampling::DE_LANES;

/// Coordinates per chunk of words (a whole chunk of words is drawn even when fewer are needed).
pub const CHUNK: usize = 128;
const HALF: usize = CHUNK / 2;
/// 64-bit words per chunk: 32-bit fields for E and the angle of each coordinate's u psi
/// (2 CHUNK fields), E and the angle of each pair's v^2 (CHUNK fields).
const WORDS: usize = 3 * HALF;

const ONE: u64 = 0x3ff0_0000_0000_0000;
const MANT: u64 = (1 << 52) - 1;
/// 2^-33 and 2^-32: half the step of a 32-bit and of a 31-bit uniform.
const HALF_STEP_32: f64 = 1.0 / (1u64 << 33) as f64;
const HALF_STEP_31: f64 = 1.0 / (1u64 << 32) as f64;
/// Bits of sqrt(1/2) (checked in the tests).
const SQRT_HALF_BITS: u64 = 0x3fe6_a09e_667f_3bcd;
const TWO52: f64 = (1u64 << 52) as f64;
const FRAC_PI_4: f64 = std::f64::consts::FRAC_PI_4;
const LN2: f64 = std::f64::consts::LN_2;

/// 1/n! for n <= 20 (n! exact below 2^63, one rounding).
const INV_FACT: [f64; 21] = {
    let mut t = [1.0; 21];
    let mut f = 1u64;
    let mut n = 1;
    while n < 21 {
        f *= n as u64;
        t[n] = 1.0 / f as f64;
        n += 1;
    }
    t
};

/// The uniform (k + 1/2) 2^-32 in (0, 1) from the 32 bits k of `w` at bit `shift` upwards
/// (`shift` 0 or 32), built from the bits (k at the top of the mantissa of 1 + k 2^-32).
#[inline(always)]
fn open_unit32(w: u64, shift: u32) -> f64 {
    (f64::from_bits((((w >> shift) & 0xffff_ffff) << 20) | ONE) - 1.0) + HALF_STEP_32
}

/// The uniform (k + 1/2) 2^-31 in (0, 1) from the 31 bits k of `w` at bit `shift` upwards (bit
/// `shift + 31` is left for a sign or a choice).
#[inline(always)]
fn open_unit31(w: u64, shift: u32) -> f64 {
    (f64::from_bits((((w >> shift) & 0x7fff_ffff) << 21) | ONE) - 1.0) + HALF_STEP_31
}

/// Horner's rule with fused multiply-adds: c[0] + z (c[1] + z (c[2] + ...)).
#[inline(always)]
fn horner<const N: usize>(z: f64, c: [f64; N]) -> f64 {
    let mut p = c[N - 1];
    for k in (0..N - 1).rev() {
        p = p.mul_add(z, c[k]);
    }
    p
}

/// -ln u for u in (0, 1): u = m 2^e with m in [sqrt(1/2), sqrt 2) taken from the bits,
/// ln m = 2 atanh s = 2 (s + s^3/3 + ... + s^15/15), s = (m - 1)/(m + 1), |s| <= 0.1716 (the
/// series' remainder is below 4e-14 relative). Relative error below 1e-13.
#[inline(always)]
pub fn neg_ln(u: f64) -> f64 {
    let bits = u.to_bits();
    // e + 1023 of u's representation with the mantissa in [sqrt(1/2), sqrt 2).
    let eb = (bits + (ONE - SQRT_HALF_BITS)) >> 52;
    let m = f64::from_bits(bits.wrapping_sub((eb << 52).wrapping_sub(ONE)));
    let e = f64::from_bits(0x4330_0000_0000_0000 | eb) - (TWO52 + 1023.0);
    let s = (m - 1.0) / (m + 1.0);
    let z = s * s;
    let p =
        horner(z, [1.0 / 3.0, 1.0 / 5.0, 1.0 / 7.0, 1.0 / 9.0, 1.0 / 11.0, 1.0 / 13.0, 1.0 / 15.0]);
    let s2 = s + s;
    -(e.mul_add(LN2, s2.mul_add(z * p, s2)))
}

/// (sin t, cos t) for t = h pi/4, h in (0, 1): Taylor polynomials to t^13 and t^14 (remainders
/// below 3e-14 relative and 1e-15 on (0, pi/4)).
#[inline(always)]
pub fn sin_cos_octant(h: f64) -> (f64, f64) {
    let f = |n: usize| INV_FACT[n];
    let t = h * FRAC_PI_4;
    let z = t * t;
    let sp = horner(z, [-f(3), f(5), -f(7), f(9), -f(11), f(13)]);
    let cp = horner(z, [-f(2), f(4), -f(6), f(8), -f(10), f(12), -f(14)]);
    (t.mul_add(z * sp, t), z.mul_add(cp, 1.0))
}

/// a^(-1/3) for a normal positive a: a first guess from the exponent bits (bits / 3 by a
/// floating-point multiply, within about 10%), then four Newton steps
/// r <- r (4/3 - (a/3) r^3) (the error squares at each). Relative error below 5e-15 (2.9e-15 at
/// worst in the test).
#[inline(always)]
pub fn inv_cbrt(a: f64) -> f64 {
    let hi = a.to_bits() >> 12;
    let third = (f64::from_bits(0x4330_0000_0000_0000 | hi) - TWO52) * (1.0 / 3.0);
    let q = (third + TWO52).to_bits() & MANT;
    let mut r = f64::from_bits(0x553e_f0ff_289d_d796u64.wrapping_sub(q << 12));
    let neg_a3 = a * (-1.0 / 3.0);
    for _ in 0..4 {
        let r3 = r * r * r;
        r *= neg_a3.mul_add(r3, 4.0 / 3.0);
    }
    r
}

/// sin t for t = h pi/2, h in (0, 1): the Taylor polynomial to t^17 (remainder below 5e-14 on
/// (0, pi/2), where sin t >= 2t/pi).
#[inline(always)]
pub fn sin_quadrant(h: f64) -> f64 {
    let f = |n: usize| INV_FACT[n];
    let t = h * std::f64::consts::FRAC_PI_2;
    let z = t * t;
    let p = horner(z, [-f(3), f(5), -f(7), f(9), -f(11), f(13), -f(15), f(17)]);
    t.mul_add(z * p, t)
}

/// sigma E sin(theta) for a uniform angle theta, from the 32-bit fields at bit `shift` of two
/// words: |sin theta| is sin t for t ~ U(0, pi/2) (the circle's symmetries); the field's top bit
/// of `angle` is the sign, its other 31 bits give t; E = -ln u from the field of `e_word`.
#[inline(always)]
fn product(e_word: u64, angle: u64, shift: u32, sigma: f64) -> f64 {
    let trig = sin_quadrant(open_unit31(angle, shift));
    let trig = f64::from_bits(trig.to_bits() ^ ((angle >> (shift + 31)) << 63));
    sigma * neg_ln(open_unit32(e_word, shift)) * trig
}

/// One chunk of Levy factors: `out[j]` = sigma u_j psi_j / |v_j|^(2/3) for j < CHUNK, all from
/// `words`: words k < HALF hold E of coordinates k (low 32 bits) and k + HALF (high), words
/// HALF + k their angles likewise; word 2 HALF + k holds the pair of coordinates k and k + HALF:
/// E (low 32 bits), the octant angle (bits 32..63) and which of the two takes the sine (bit 63).
#[inline(always)]
fn chunk(out: &mut [f64; CHUNK], words: &[u64; WORDS], sigma: f64) {
    let (e_words, rest) = words.split_at(HALF);
    let (angles, pairs) = rest.split_at(HALF);
    let (lo, hi) = out.split_at_mut(HALF);
    for k in 0..HALF {
        lo[k] = product(e_words[k], angles[k], 0, sigma);
        hi[k] = product(e_words[k], angles[k], 32, sigma);
    }
    for k in 0..HALF {
        let w = pairs[k];
        let r2 = 2.0 * neg_ln(open_unit32(w, 0));
        let (s, c) = sin_cos_octant(open_unit31(w, 32));
        let swap = w & (1 << 63) != 0;
        let (a, b) = if swap { (s, c) } else { (c, s) };
        lo[k] *= inv_cbrt(r2 * (a * a));
        hi[k] *= inv_cbrt(r2 * (b * b));
    }
}

/// `out[j]` = sigma_u u_j psi_j / |v_j|^(2/3) (Mantegna, beta = 3/2, times the flight's normal
/// psi) for every j, chunk by chunk from `rng` (see the module).
#[inline(always)]
fn fill_body(out: &mut [f64], sigma: f64, rng: &mut DeLanes) {
    let mut words = [0u64; WORDS];
    let mut buf = [0.0f64; CHUNK];
    for piece in out.chunks_mut(CHUNK) {
        super::kernels::lanes_fill(&mut words, rng);
        chunk(&mut buf, &words, sigma);
        piece.copy_from_slice(&buf[..piece.len()]);
    }
}

/// The vectors of one Levy flight: the nest `x`, the best nest `b` and the box.
#[derive(Debug, Clone, Copy)]
pub struct FlightSources<'a> {
    pub x: &'a [f64],
    pub b: &'a [f64],
    pub lo: &'a [f64],
    pub hi: &'a [f64],
}

/// One flight's words and factors, chunk by chunk (kept by the caller across flights, so that
/// nothing is allocated or cleared per flight).
#[derive(Debug, Clone)]
pub struct LevyScratch {
    words: [u64; WORDS],
    factors: [f64; CHUNK],
}

impl Default for LevyScratch {
    fn default() -> LevyScratch {
        LevyScratch { words: [0; WORDS], factors: [0.0; CHUNK] }
    }
}

/// One coordinate of a Levy flight: x + alpha L (x - b) clamped to [lo, hi] (x itself if that
/// is NaN, from 0 * inf).
#[inline(always)]
pub fn flight_coordinate(x: f64, b: f64, lo: f64, hi: f64, alpha: f64, l: f64) -> f64 {
    let nj = x + alpha * l * (x - b);
    if nj.is_nan() {
        x
    } else {
        super::kernels::clamp(nj, lo, hi)
    }
}

/// [`levy_flight`] in one pass: each chunk's factors go straight into its coordinates' flight,
/// while they are in L1 (the same draws and operations as [`fill_body`] followed by
/// [`flight_coordinate`] per coordinate, so the same bits).
#[inline(always)]
fn flight_body(
    c: &mut [f64],
    src: FlightSources,
    alpha: f64,
    sigma: f64,
    rng: &mut DeLanes,
    scratch: &mut LevyScratch,
) {
    let n = c.len();
    let (x, b, lo, hi) = (&src.x[..n], &src.b[..n], &src.lo[..n], &src.hi[..n]);
    for (k, piece) in c.chunks_mut(CHUNK).enumerate() {
        super::kernels::lanes_fill(&mut scratch.words, rng);
        chunk(&mut scratch.factors, &scratch.words, sigma);
        let (from, m) = (k * CHUNK, piece.len());
        let (x, b, lo, hi) = (&x[from..from + m], &b[from..from + m], &lo[from..], &hi[from..]);
        let (lo, hi, l) = (&lo[..m], &hi[..m], &scratch.factors[..m]);
        for j in 0..m {
            piece[j] = flight_coordinate(x[j], b[j], lo[j], hi[j], alpha, l[j]);
        }
    }
}

fn flight_generic(
    c: &mut [f64],
    src: FlightSources,
    alpha: f64,
    sigma: f64,
    rng: &mut DeLanes,
    scratch: &mut LevyScratch,
) {
    flight_body(c, src, alpha, sigma, rng, scratch)
}

/// The same Rust compiled for AVX2 (vectorised by the compiler, no fused multiply-add).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn flight_avx2(
    c: &mut [f64],
    src: FlightSources,
    alpha: f64,
    sigma: f64,
    rng: &mut DeLanes,
    scratch: &mut LevyScratch,
) {
    flight_body(c, src, alpha, sigma, rng, scratch)
}

/// One Levy flight (beta = 3/2) of a nest into `c` (of the nest's length): coordinate j is
/// [`flight_coordinate`] of the factor sigma_u u psi / |v|^(2/3) that [`levy_fill`] would draw
/// for it from `rng` (the same words and the same bits), in the copy the run's SIMD choice names.
pub fn levy_flight(
    c: &mut [f64],
    src: FlightSources,
    alpha: f64,
    sigma_u: f64,
    rng: &mut DeLanes,
    scratch: &mut LevyScratch,
) {
    #[cfg(target_arch = "x86_64")]
    {
        if super::kernels::use_avx2() {
            // SAFETY: use_avx2 is true only when the CPU reports AVX2 and FMA.
            return unsafe { flight_avx2(c, src, alpha, sigma_u, rng, scratch) };
        }
    }
    flight_generic(c, src, alpha, sigma_u, rng, scratch)
}

fn fill_generic(out: &mut [f64], sigma: f64, rng: &mut DeLanes) {
    fill_body(out, sigma, rng)
}

/// The same Rust compiled for AVX2 (the compiler vectorises the chunk's loops; no fused
/// multiply-add, so the same bits).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn fill_avx2(out: &mut [f64], sigma: f64, rng: &mut DeLanes) {
    fill_body(out, sigma, rng)
}

/// Fill `out` with Levy factors sigma_u u psi / |v|^(2/3) (beta = 3/2), in the copy the run's
/// SIMD choice ([`super::kernels::simd`]) names; the same bits from every copy.
pub fn levy_fill(out: &mut [f64], sigma_u: f64, rng: &mut DeLanes) {
    #[cfg(target_arch = "x86_64")]
    {
        if super::kernels::use_avx2() {
            // SAFETY: use_avx2 is true only when the CPU reports AVX2 and FMA.
            return unsafe { fill_avx2(out, sigma_u, rng) };
        }
    }
    fill_generic(out, sigma_u, rng)
}

/// The baseline copy (the tests' reference for the dispatched one).
#[cfg(test)]
pub fn levy_fill_baseline(out: &mut [f64], sigma_u: f64, rng: &mut DeLanes) {
    fill_generic(out, sigma_u, rng)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::sampling::{mantegna_sigma_u, symmetric};
    use rand::{RngCore, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    const HALF_ULP: f64 = 1.0 / (1u64 << 53) as f64;

    /// The uniform (k + 1/2) 2^-52 from the top 52 bits of `w` (the probes of the accuracy
    /// tests, finer than the 32-bit uniforms the sampler uses).
    fn open_unit52(w: u64) -> f64 {
        ((w >> 12) as f64 + 0.5) * (1.0 / (1u64 << 52) as f64)
    }

    #[test]
    fn constants_are_what_they_say() {
        assert_eq!(SQRT_HALF_BITS, 0.5f64.sqrt().to_bits());
        assert_eq!(open_unit32(0, 0), HALF_STEP_32);
        assert_eq!(open_unit32(u64::MAX, 32), 1.0 - HALF_STEP_32);
        assert_eq!(open_unit31(u64::MAX, 0), 1.0 - HALF_STEP_31);
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        for _ in 0..1000 {
            let w = rng.next_u64();
            let (lo, hi) = (w & 0xffff_ffff, w >> 32);
            assert_eq!(open_unit32(w, 0), (lo as f64 + 0.5) / 4_294_967_296.0);
            assert_eq!(open_unit32(w, 32), (hi as f64 + 0.5) / 4_294_967_296.0);
            assert_eq!(open_unit31(w, 0), ((lo & 0x7fff_ffff) as f64 + 0.5) / 2_147_483_648.0);
            assert_eq!(open_unit31(w, 32), ((hi & 0x7fff_ffff) as f64 + 0.5) / 2_147_483_648.0);
        }
    }

    #[test]
    fn neg_ln_matches_the_library() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let mut worst = 0.0f64;
        let probes = [
            HALF_ULP,
            1.0 - HALF_ULP,
            0.5,
            0.5f64.sqrt(),
            0.5f64.sqrt() * (1.0 + f64::EPSILON),
            0.25,
            0.999,
            1e-10,
        ];
        for u in (0..200_000).map(|_| open_unit52(rng.next_u64())).chain(probes) {
            let want = -u.ln();
            let got = neg_ln(u);
            worst = worst.max(((got - want) / want).abs());
        }
        println!("worst relative error {worst:e}");
        assert!(worst < 1e-13, "worst relative error {worst:e}");
    }

    #[test]
    fn octant_sine_and_cosine_match_the_library() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut worst = 0.0f64;
        for h in
            (0..200_000).map(|_| open_unit52(rng.next_u64())).chain([HALF_ULP, 1.0 - HALF_ULP, 0.5])
        {
            let t = h * FRAC_PI_4;
            let (s, c) = sin_cos_octant(h);
            worst = worst.max(((s - t.sin()) / t.sin()).abs()).max(((c - t.cos()) / t.cos()).abs());
        }
        println!("worst relative error {worst:e}");
        assert!(worst < 1e-13, "worst relative error {worst:e}");
    }

    #[test]
    fn quadrant_sine_matches_the_library() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut worst = 0.0f64;
        for h in
            (0..200_000).map(|_| open_unit52(rng.next_u64())).chain([HALF_ULP, 1.0 - HALF_ULP, 0.5])
        {
            let want = (h * std::f64::consts::FRAC_PI_2).sin();
            worst = worst.max(((sin_quadrant(h) - want) / want).abs());
        }
        println!("worst relative error {worst:e}");
        assert!(worst < 1e-13, "worst relative error {worst:e}");
    }

    #[test]
    fn inverse_cube_root_matches_powf() {
        let mut rng = ChaCha8Rng::seed_from_u64(6);
        let mut worst = 0.0f64;
        for _ in 0..200_000 {
            let a = 10f64.powf(symmetric(&mut rng, 60.0)) * (1.0 + open_unit52(rng.next_u64()));
            let want = a.powf(-1.0 / 3.0);
            worst = worst.max(((inv_cbrt(a) - want) / want).abs());
        }
        println!("worst relative error {worst:e}");
        assert!(worst < 5e-15, "worst relative error {worst:e}");
    }

    /// The dispatched copy gives the baseline copy's bits, for lengths around the chunk size, and
    /// leaves the generators in the same state.
    #[test]
    fn copies_are_bit_identical() {
        for n in [1, 3, 127, 128, 129, 1740] {
            let mut a = DeLanes::from_rng(&mut ChaCha8Rng::seed_from_u64(n as u64));
            let mut b = a.clone();
            let (mut x, mut y) = (vec![0.0; n], vec![0.0; n]);
            for _ in 0..3 {
                levy_fill(&mut x, 0.7, &mut a);
                levy_fill_baseline(&mut y, 0.7, &mut b);
                assert!(x.iter().zip(&y).all(|(p, q)| p.to_bits() == q.to_bits()), "n {n}");
            }
            assert_eq!(a, b);
        }
    }

    /// A fused flight gives the bits of the factors from `levy_fill` followed by the flight's
    /// formula, in the dispatched and the baseline copy, for lengths around the chunk size, with
    /// coordinates at, inside and beyond the box; and the generators end in the same state.
    #[test]
    fn fused_flight_is_fill_then_step() {
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
            levy_fill_baseline(&mut l, 0.7, &mut want_lanes);
            let want: Vec<f64> =
                (0..n).map(|j| flight_coordinate(x[j], b[j], lo[j], hi[j], 0.3, l[j])).collect();
            assert!(want.iter().enumerate().any(|(j, w)| *w == hi[j]) || n < 100);
            assert!(want.iter().enumerate().any(|(j, w)| *w == lo[j]) || n < 100);
            assert!(want.iter().enumerate().any(|(j, w)| *w > lo[j] && *w < hi[j]) || n < 100);
            let mut scratch = LevyScratch::default();
            for fused in [levy_flight, flight_generic] {
                let (mut got, mut got_lanes) = (vec![0.0; n], lanes.clone());
                fused(&mut got, src, 0.3, 0.7, &mut got_lanes, &mut scratch);
                assert!(got.iter().zip(&want).all(|(p, q)| p.to_bits() == q.to_bits()), "n {n}");
                assert_eq!(got_lanes, want_lanes);
            }
        }
        assert_eq!(flight_coordinate(1.0, 0.0, -2.0, 2.0, 0.0, f64::INFINITY), 1.0);
    }

    /// The law of L = sigma u psi / |v|^(2/3) against a direct simulation from independent
    /// normals (rand_distr's ziggurat and powf: another code path): the fractions beyond
    /// several thresholds, the sign, and the moments of the two halves.
    #[test]
    fn levy_factors_have_mantegnas_law() {
        use rand::Rng;
        use rand_distr::StandardNormal;
        let sigma = mantegna_sigma_u(1.5);
        let n = 400_000;
        let mut got = vec![0.0; n];
        levy_fill(&mut got, sigma, &mut DeLanes::from_rng(&mut ChaCha8Rng::seed_from_u64(9)));
        let mut r = ChaCha8Rng::seed_from_u64(10);
        let want: Vec<f64> = (0..n)
            .map(|_| {
                let (u, v, p): (f64, f64, f64) =
                    (r.sample(StandardNormal), r.sample(StandardNormal), r.sample(StandardNormal));
                sigma * u * p * v.abs().powf(-2.0 / 3.0)
            })
            .collect();
        let frac =
            |s: &[f64], t: f64| s.iter().filter(|x| x.abs() > t).count() as f64 / s.len() as f64;
        for t in [0.05, 0.3, 1.0, 3.0, 10.0, 100.0] {
            let (a, b) = (frac(&got, t), frac(&want, t));
            let sd = (b * (1.0 - b) / n as f64).sqrt() * 2f64.sqrt();
            assert!((a - b).abs() < 5.0 * sd, "t {t}: {a} vs {b}");
        }
        let pos = got.iter().filter(|x| **x > 0.0).count() as f64 / n as f64;
        assert!((pos - 0.5).abs() < 0.004, "{pos}");
        // Each half of the product alone: E|u psi| = sigma 2/pi, E (v^2)^(-1/3) has no finite
        // variance, so compare the median of |v|^(-2/3): (median |v| = 0.6745)^(-2/3) = 1.3006.
        let mut words = [0u64; WORDS];
        let mut lanes = DeLanes::from_rng(&mut ChaCha8Rng::seed_from_u64(11));
        let (mut abs_prod, mut inv) = (0.0, Vec::new());
        let rounds = 2000;
        for _ in 0..rounds {
            for w in words.chunks_mut(DE_LANES) {
                w.copy_from_slice(&lanes.next_words());
            }
            for k in 0..HALF {
                for shift in [0, 32] {
                    abs_prod += product(words[k], words[HALF + k], shift, 1.0).abs();
                }
            }
            for k in 0..HALF {
                let w = words[2 * HALF + k];
                let r2 = 2.0 * neg_ln(open_unit32(w, 0));
                let (s, c) = sin_cos_octant(open_unit31(w, 32));
                inv.push(inv_cbrt(r2 * s * s));
                inv.push(inv_cbrt(r2 * c * c));
            }
        }
        let m = abs_prod / (rounds * CHUNK) as f64;
        assert!((m - 2.0 / std::f64::consts::PI).abs() < 0.004, "{m}");
        inv.sort_by(f64::total_cmp);
        let med = inv[inv.len() / 2];
        assert!((med - 0.674_489_75f64.powf(-2.0 / 3.0)).abs() < 0.005, "{med}");
    }
}
