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
//!   remaining 52 bits give t; sin t and cos t are Taylor polynomials on (0, pi/4), exact to a few
//!   units in the last place even for the tiny values that make the heavy tail.
//!
//! Every uniform is (k + 1/2) 2^-52 from 52 random bits, in (0, 1): no logarithm of 0, no angle
//! at 0, so every step is finite (|E| <= 36.8, |v|^2 >= 1e-48). The functions are written in IEEE
//! additions, multiplications and divisions only (no fused multiply-add, no library call), so the
//! baseline and AVX2 copies (the same Rust, compiled twice; the compiler never fuses) give the
//! same bits on every x86-64. Words come from four xoshiro256++ lanes ([`DeLanes`], seeded from
//! the run's ChaCha8 stream): chunk after chunk of [`CHUNK`] coordinates, each consuming
//! 3 CHUNK / 4 steps of the four lanes, word m of a chunk from lane m % 4 at step m / 4.

// Index loops over the chunk's parallel arrays read more plainly than zipped iterators here.
#![allow(clippy::needless_range_loop)]

use super::sampling::DeLanes;
#[cfg(test)]
use super::sampling::DE_LANES;

/// Coordinates per chunk of words (a whole chunk of words is drawn even when fewer are needed).
pub const CHUNK: usize = 128;
const HALF: usize = CHUNK / 2;
/// Words per chunk: E and angle of each coordinate's u psi (2 CHUNK), E and angle of each pair's
/// v^2 (CHUNK).
const WORDS: usize = 3 * CHUNK;

const ONE: u64 = 0x3ff0_0000_0000_0000;
const MANT: u64 = (1 << 52) - 1;
const HALF_ULP: f64 = 1.0 / (1u64 << 53) as f64;
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

/// The uniform (k + 1/2) 2^-52 in (0, 1) from 52 bits k of `w` at bit `shift` upwards.
#[inline(always)]
fn open_unit(w: u64, shift: u32) -> f64 {
    (f64::from_bits(((w >> shift) & MANT) | ONE) - 1.0) + HALF_ULP
}

/// -ln u for u in (0, 1): u = m 2^e with m in [sqrt(1/2), sqrt 2) taken from the bits,
/// ln m = 2 atanh s = 2 (s + s^3/3 + ... + s^21/21), s = (m - 1)/(m + 1), |s| <= 0.1716 (the
/// series' remainder is below 1e-18 relative). Relative error a few 1e-16.
#[inline(always)]
pub fn neg_ln(u: f64) -> f64 {
    let bits = u.to_bits();
    // e + 1023 of u's representation with the mantissa in [sqrt(1/2), sqrt 2).
    let eb = (bits + (ONE - SQRT_HALF_BITS)) >> 52;
    let m = f64::from_bits(bits.wrapping_sub((eb << 52).wrapping_sub(ONE)));
    let e = f64::from_bits(0x4330_0000_0000_0000 | eb) - (TWO52 + 1023.0);
    let s = (m - 1.0) / (m + 1.0);
    let z = s * s;
    let p = 1.0 / 3.0
        + z * (1.0 / 5.0
            + z * (1.0 / 7.0
                + z * (1.0 / 9.0
                    + z * (1.0 / 11.0
                        + z * (1.0 / 13.0
                            + z * (1.0 / 15.0
                                + z * (1.0 / 17.0 + z * (1.0 / 19.0 + z * (1.0 / 21.0)))))))));
    let s2 = s + s;
    -(e * LN2 + (s2 + s2 * (z * p)))
}

/// (sin t, cos t) for t = h pi/4, h in (0, 1): Taylor polynomials to t^15 and t^16 (remainders
/// below 5e-17 and 2e-18 on (0, pi/4)).
#[inline(always)]
pub fn sin_cos_octant(h: f64) -> (f64, f64) {
    const fn inv_fact(n: usize) -> f64 {
        INV_FACT[n]
    }
    let t = h * FRAC_PI_4;
    let z = t * t;
    let sp = -inv_fact(3)
        + z * (inv_fact(5)
            + z * (-inv_fact(7)
                + z * (inv_fact(9)
                    + z * (-inv_fact(11) + z * (inv_fact(13) + z * -inv_fact(15))))));
    let cp = -inv_fact(2)
        + z * (inv_fact(4)
            + z * (-inv_fact(6)
                + z * (inv_fact(8)
                    + z * (-inv_fact(10)
                        + z * (inv_fact(12) + z * (-inv_fact(14) + z * inv_fact(16)))))));
    (t + t * (z * sp), 1.0 + z * cp)
}

/// a^(-1/3) for a normal positive a: a first guess from the exponent bits (bits / 3 by a
/// floating-point multiply, within about 10%), then five Newton steps r <- r (4 - a r^3) / 3
/// (the error squares at each). Relative error below 5e-15 (2.9e-15 at worst in the test).
#[inline(always)]
pub fn inv_cbrt(a: f64) -> f64 {
    let hi = a.to_bits() >> 12;
    let third = (f64::from_bits(0x4330_0000_0000_0000 | hi) - TWO52) * (1.0 / 3.0);
    let q = (third + TWO52).to_bits() & MANT;
    let mut r = f64::from_bits(0x553e_f0ff_289d_d796u64.wrapping_sub(q << 12));
    for _ in 0..5 {
        let r3 = r * r * r;
        r = r * (4.0 - a * r3) * (1.0 / 3.0);
    }
    r
}

/// sin t for t = h pi/2, h in (0, 1): the Taylor polynomial to t^19 (remainder below 3e-16 on
/// (0, pi/2), where sin t >= 2t/pi).
#[inline(always)]
pub fn sin_quadrant(h: f64) -> f64 {
    let t = h * std::f64::consts::FRAC_PI_2;
    let z = t * t;
    let p = -INV_FACT[3]
        + z * (INV_FACT[5]
            + z * (-INV_FACT[7]
                + z * (INV_FACT[9]
                    + z * (-INV_FACT[11]
                        + z * (INV_FACT[13]
                            + z * (-INV_FACT[15] + z * (INV_FACT[17] + z * -INV_FACT[19])))))));
    t + t * (z * p)
}

/// sigma E sin(theta) for a uniform angle theta: |sin theta| is sin t for t ~ U(0, pi/2) (the
/// circle's symmetries); bit 63 of `angle` is the sign, bits 11..63 give t; E from the other
/// word.
#[inline(always)]
fn product(e_word: u64, angle: u64, sigma: f64) -> f64 {
    let trig = sin_quadrant(open_unit(angle, 11));
    let trig = f64::from_bits(trig.to_bits() ^ (angle & (1 << 63)));
    sigma * neg_ln(open_unit(e_word, 12)) * trig
}

/// One chunk of Levy factors: `out[j]` = sigma u_j psi_j / |v_j|^(2/3) for j < CHUNK, all from
/// `words` (laid out as described in the module).
#[inline(always)]
fn chunk(out: &mut [f64; CHUNK], words: &[u64; WORDS], sigma: f64) {
    let (e_words, rest) = words.split_at(CHUNK);
    let (angles, rest) = rest.split_at(CHUNK);
    let (ev, av) = rest.split_at(HALF);
    for j in 0..CHUNK {
        out[j] = product(e_words[j], angles[j], sigma);
    }
    let (lo, hi) = out.split_at_mut(HALF);
    for k in 0..HALF {
        let r2 = 2.0 * neg_ln(open_unit(ev[k], 12));
        let w = av[k];
        let (s, c) = sin_cos_octant(open_unit(w, 10));
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

    #[test]
    fn constants_are_what_they_say() {
        assert_eq!(SQRT_HALF_BITS, 0.5f64.sqrt().to_bits());
        assert_eq!(open_unit(0, 12), HALF_ULP);
        assert_eq!(open_unit(u64::MAX, 12), 1.0 - HALF_ULP);
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
        for u in (0..200_000).map(|_| open_unit(rng.next_u64(), 12)).chain(probes) {
            let want = -u.ln();
            let got = neg_ln(u);
            worst = worst.max(((got - want) / want).abs());
        }
        assert!(worst < 1e-15, "worst relative error {worst:e}");
    }

    #[test]
    fn octant_sine_and_cosine_match_the_library() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut worst = 0.0f64;
        for h in (0..200_000).map(|_| open_unit(rng.next_u64(), 10)).chain([
            HALF_ULP,
            1.0 - HALF_ULP,
            0.5,
        ]) {
            let t = h * FRAC_PI_4;
            let (s, c) = sin_cos_octant(h);
            worst = worst.max(((s - t.sin()) / t.sin()).abs()).max(((c - t.cos()) / t.cos()).abs());
        }
        assert!(worst < 1e-15, "worst relative error {worst:e}");
    }

    #[test]
    fn quadrant_sine_matches_the_library() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut worst = 0.0f64;
        for h in (0..200_000).map(|_| open_unit(rng.next_u64(), 11)).chain([
            HALF_ULP,
            1.0 - HALF_ULP,
            0.5,
        ]) {
            let want = (h * std::f64::consts::FRAC_PI_2).sin();
            worst = worst.max(((sin_quadrant(h) - want) / want).abs());
        }
        assert!(worst < 1e-15, "worst relative error {worst:e}");
    }

    #[test]
    fn inverse_cube_root_matches_powf() {
        let mut rng = ChaCha8Rng::seed_from_u64(6);
        let mut worst = 0.0f64;
        for _ in 0..200_000 {
            let a = 10f64.powf(symmetric(&mut rng, 60.0)) * (1.0 + open_unit(rng.next_u64(), 12));
            let want = a.powf(-1.0 / 3.0);
            worst = worst.max(((inv_cbrt(a) - want) / want).abs());
        }
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
            for j in 0..CHUNK {
                abs_prod += product(words[j], words[CHUNK + j], 1.0).abs();
            }
            for k in 0..HALF {
                let r2 = 2.0 * neg_ln(open_unit(words[2 * CHUNK + k], 12));
                let (s, c) = sin_cos_octant(open_unit(words[2 * CHUNK + HALF + k], 10));
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
