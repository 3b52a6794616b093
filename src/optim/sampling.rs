//! Cheap random draws for the optimisers' inner loops.
//!
//! A ChaCha8 64-bit draw costs about 2 ns here, as much as a quarter of a fitness evaluation per
//! few hundred genes, so the per-gene loops must not draw one ChaCha8 uniform per gene. The
//! vectorised loops (PSO's move, DE's trial) draw from interleaved xoshiro256++ lanes held in
//! registers ([`BulkLanes`]). Elsewhere (GA's mutation, cuckoo search's discovery), per-gene
//! Bernoulli(p) choices are made by geometric skips (one draw per *event*, not per gene), and the
//! skip itself mostly costs 12 random bits and a table look-up instead of a 53-bit uniform and a
//! logarithm, with exactly the distribution of the logarithm formula (see [`Geometric`]).

use rand::RngCore;
use rand_chacha::ChaCha8Rng;

const TWO_POW_M53: f64 = 1.0 / (1u64 << 53) as f64;

/// A uniform in [0, 1) with 53 random bits.
#[inline]
pub(crate) fn unit(rng: &mut ChaCha8Rng) -> f64 {
    unit_from(rng.next_u64())
}

/// The uniform in [0, 1) of [`unit`] from its 64-bit draw `w`: (w >> 11) 2^-53.
#[inline(always)]
pub(crate) fn unit_from(w: u64) -> f64 {
    (w >> 11) as f64 * TWO_POW_M53
}

/// A uniform in [-r, r) around 0 (53 random bits).
#[inline]
pub(crate) fn symmetric(rng: &mut ChaCha8Rng, r: f64) -> f64 {
    symmetric_from(rng.next_u64(), r)
}

/// The uniform of [`symmetric`] from its 64-bit draw `w`: r (2 u - 1), u = [`unit_from`] w.
#[inline(always)]
pub(crate) fn symmetric_from(w: u64, r: f64) -> f64 {
    r * (2.0 * unit_from(w) - 1.0)
}

/// Two independent uniforms in [1, 2), 32 random bits each, from one 64-bit draw: 1 + h 2^-32 and
/// 1 + l 2^-32 for the high and low halves h, l, built from the bits (the 32 bits placed at the
/// top of the mantissa), which vectorises (x86 has no vector conversion from 64-bit integers
/// before AVX-512). Subtracting 1 is exact and gives the uniforms h 2^-32, l 2^-32 in [0, 1)
/// (`h as f64 * 2^-32`, tested), so a caller may fold it into a fused multiply-add:
/// c u - c = c (u - 1) in one rounding.
#[inline(always)]
pub(crate) fn two_units_plus_one(word: u64) -> (f64, f64) {
    const ONE: u64 = 0x3ff0_0000_0000_0000;
    const MANTISSA_TOP32: u64 = 0x000f_ffff_fff0_0000;
    (
        f64::from_bits(((word >> 12) & MANTISSA_TOP32) | ONE),
        f64::from_bits(((word << 20) & MANTISSA_TOP32) | ONE),
    )
}

/// The uniforms in [0, 1) themselves (the tests' reference for the folded form).
#[cfg(test)]
pub(crate) fn two_units(word: u64) -> (f64, f64) {
    let (hi, lo) = two_units_plus_one(word);
    (hi - 1.0, lo - 1.0)
}

/// Lanes of PSO's generators ([`PsoLanes`]): coordinate j of a move draws from lane j % 8.
pub(crate) const PSO_LANES: usize = 8;
/// Lanes of DE's crossover generators ([`DeLanes`]): one step of the four lanes decides eight
/// genes.
pub(crate) const DE_LANES: usize = 4;

/// `L` independent xoshiro256++ generators, each seeded from 256 bits of the run's ChaCha8
/// stream, for the per-coordinate words of the vectorised loops (PSO's r1 and r2, DE's crossover
/// choices). One xoshiro256++ is a serial chain (each state depends on the previous one, about 3
/// cycles per word); independent lanes step in parallel, one vector instruction for all of them.
/// The state is kept as four rows over the lanes (structure of arrays), so that a vector loop
/// holds each row in one or two registers for a whole pass over a vector and stores it once at
/// the end. Each lane is exactly `Xoshiro256PlusPlus` from its seed.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct BulkLanes<const L: usize> {
    s: [[u64; L]; 4],
}

/// PSO's generators: eight lanes, two 256-bit registers per state row.
pub(crate) type PsoLanes = BulkLanes<PSO_LANES>;
/// DE's crossover generators: four lanes, one 256-bit register per state row.
pub(crate) type DeLanes = BulkLanes<DE_LANES>;

impl<const L: usize> BulkLanes<L> {
    /// Lane l takes the l-th 4 words of the stream as its state (an all-zero state, probability
    /// 2^-256, would stay zero forever, so it is replaced by one word 1).
    pub(crate) fn from_rng(rng: &mut ChaCha8Rng) -> BulkLanes<L> {
        let mut s = [[0u64; L]; 4];
        for l in 0..L {
            for row in s.iter_mut() {
                row[l] = rng.next_u64();
            }
            if s.iter().all(|row| row[l] == 0) {
                s[0][l] = 1;
            }
        }
        BulkLanes { s }
    }

    /// The four state rows over the lanes.
    #[inline(always)]
    pub(crate) fn state_mut(&mut self) -> &mut [[u64; L]; 4] {
        &mut self.s
    }

    /// The next word of lane `l`.
    #[inline(always)]
    pub(crate) fn next_word(&mut self, l: usize) -> u64 {
        let (word, [a, b, c, d]) =
            xoshiro_next([self.s[0][l], self.s[1][l], self.s[2][l], self.s[3][l]]);
        (self.s[0][l], self.s[1][l], self.s[2][l], self.s[3][l]) = (a, b, c, d);
        word
    }

    /// The next word of every lane (lane l's word at index l).
    #[inline(always)]
    pub(crate) fn next_words(&mut self) -> [u64; L] {
        std::array::from_fn(|l| self.next_word(l))
    }
}

/// The 32-bit threshold of a Bernoulli(p) choice made by one 32-bit uniform h: h < threshold
/// with probability floor(p 2^32) / 2^32, within 2^-32 of p (exactly 0 and 1 at p = 0 and 1).
pub(crate) fn bernoulli_threshold_32(p: f64) -> u64 {
    let p = if p.is_nan() { 0.0 } else { p.clamp(0.0, 1.0) };
    (p * 4_294_967_296.0).floor() as u64
}

/// One xoshiro256++ output and state step of one lane, in the shape of Blackman & Vigna's
/// reference `next` (the tests' reference for [`xoshiro_next`]).
#[cfg(test)]
pub(crate) fn xoshiro_step(s0: &mut u64, s1: &mut u64, s2: &mut u64, s3: &mut u64) -> u64 {
    let (out, [a, b, c, d]) = xoshiro_next([*s0, *s1, *s2, *s3]);
    (*s0, *s1, *s2, *s3) = (a, b, c, d);
    out
}

/// One xoshiro256++ step on values (Blackman & Vigna's reference `next`): (output, next state). A loop over lanes that loads the four words,
/// calls this and stores the four results keeps the state in registers (through `&mut` the
/// compiler reloads each word after every store).
#[inline(always)]
pub(crate) fn xoshiro_next(s: [u64; 4]) -> (u64, [u64; 4]) {
    let out = s[0].wrapping_add(s[3]).rotate_left(23).wrapping_add(s[0]);
    let t = s[1] << 17;
    let s2 = s[2] ^ s[0];
    let s3 = s[3] ^ s[1];
    let s1 = s[1] ^ s2;
    let s0 = s[0] ^ s3;
    (out, [s0, s1, s2 ^ t, s3.rotate_left(45)])
}

/// A uniform index in 0..n (n >= 1), unbiased (Lemire's multiply-and-reject).
#[inline]
pub(crate) fn index(rng: &mut ChaCha8Rng, n: usize) -> usize {
    debug_assert!(n >= 1);
    let n64 = n as u64;
    let threshold = n64.wrapping_neg() % n64;
    loop {
        let m = (rng.next_u64() as u128) * (n64 as u128);
        if (m as u64) >= threshold {
            return (m >> 64) as usize;
        }
    }
}

/// Random bits handed out a few at a time from 64-bit draws (leftover bits of a word that
/// cannot serve a request are discarded, so the stream stays a pure function of the seed).
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct BitPool {
    word: u64,
    left: u32,
}

impl BitPool {
    pub(crate) fn new() -> BitPool {
        BitPool::default()
    }

    /// `n` (1..=32) fresh random bits as the low bits of the result.
    #[inline(always)]
    pub(crate) fn take(&mut self, n: u32, rng: &mut ChaCha8Rng) -> u64 {
        debug_assert!((1..=32).contains(&n));
        if self.left < n {
            self.word = rng.next_u64();
            self.left = 64;
        }
        let v = self.word & ((1u64 << n) - 1);
        self.word >>= n;
        self.left -= n;
        v
    }
}

const BUCKET_BITS: u32 = 12;
const LOW_BITS: u32 = 53 - BUCKET_BITS;
const MIXED: u16 = u16::MAX;

/// The number of failures before the first success in Bernoulli(p) trials (a geometric skip):
/// walking a vector with `position += 1 + skip` visits each coordinate independently with
/// probability p, exactly as one Bernoulli(p) draw per coordinate would, but with one draw per
/// visited coordinate.
///
/// The skip is the inversion formula G = floor(ln U / ln(1 - p)) on a 53-bit uniform
/// U = (k + 1) 2^-53 in (0, 1], so P(G >= g) = P(U <= (1 - p)^g) = (1 - p)^g up to the 2^-53
/// resolution of U. To avoid the logarithm, U is drawn most-significant bits first: its top 12
/// bits pick one of 4096 buckets, and a table (built from the same formula at the two ends of
/// each bucket; G is monotone in U) gives G directly whenever the whole bucket maps to one value.
/// Only in the few buckets that straddle a jump of G are the remaining 41 bits drawn and the
/// formula evaluated. The result is the formula's value for a uniformly drawn 53-bit U either way,
/// so the distribution is exactly that of the formula; only the bit consumption differs.
#[derive(Debug, Clone)]
pub(crate) struct Geometric {
    p: f64,
    inv_ln_q: f64,
    table: Option<Box<[u16]>>,
}

impl Geometric {
    /// Skips for success probability `p` (clamped into [0, 1]).
    pub(crate) fn new(p: f64) -> Geometric {
        let p = if p.is_nan() { 0.0 } else { p.clamp(0.0, 1.0) };
        let inv_ln_q = if p > 0.0 && p < 1.0 { 1.0 / (-p).ln_1p() } else { 0.0 };
        let mut g = Geometric { p, inv_ln_q, table: None };
        // For small p nearly every bucket straddles a jump and events are rare anyway.
        if (0.02..1.0).contains(&p) {
            let table: Vec<u16> = (0..1u64 << BUCKET_BITS)
                .map(|b| {
                    let hi = g.formula(((b + 1) << LOW_BITS) - 1);
                    let lo = g.formula(b << LOW_BITS);
                    if hi == lo && hi < MIXED as usize {
                        hi as u16
                    } else {
                        MIXED
                    }
                })
                .collect();
            g.table = Some(table.into_boxed_slice());
        }
        g
    }

    /// G for the 53-bit integer k (U = (k + 1) 2^-53).
    #[inline(never)]
    fn formula(&self, k: u64) -> usize {
        let u = (k + 1) as f64 * TWO_POW_M53;
        let g = (u.ln() * self.inv_ln_q).floor();
        if g >= 1e18 {
            usize::MAX
        } else {
            g as usize
        }
    }

    /// One skip; `usize::MAX` when p = 0 (no coordinate is ever visited).
    #[inline(always)]
    pub(crate) fn skip(&self, pool: &mut BitPool, rng: &mut ChaCha8Rng) -> usize {
        if self.p <= 0.0 {
            return usize::MAX;
        }
        if self.p >= 1.0 {
            return 0;
        }
        match &self.table {
            Some(table) => {
                let b = pool.take(BUCKET_BITS, rng);
                let g = table[b as usize];
                if g != MIXED {
                    g as usize
                } else {
                    let low = rng.next_u64() >> (64 - LOW_BITS);
                    self.formula((b << LOW_BITS) | low)
                }
            }
            None => self.formula(rng.next_u64() >> 11),
        }
    }

    /// The next visited position after `pos` (walk: `j = skip(); while j < n { ..; j = next_after(j) }`).
    #[inline(always)]
    pub(crate) fn next_after(&self, pos: usize, pool: &mut BitPool, rng: &mut ChaCha8Rng) -> usize {
        pos.saturating_add(1).saturating_add(self.skip(pool, rng))
    }

    /// Call `visit(j)` for each j in 0..n chosen independently with probability p, in order: the
    /// positions and the random bits drawn are exactly those of the walk with `skip` and
    /// `next_after`, with the table's checks hoisted out of the loop.
    #[inline]
    pub(crate) fn for_each<F: FnMut(usize)>(
        &self,
        n: usize,
        pool: &mut BitPool,
        rng: &mut ChaCha8Rng,
        mut visit: F,
    ) {
        let table: Option<&[u16; 1 << BUCKET_BITS]> =
            self.table.as_deref().map(|t| t.try_into().expect("4096 buckets"));
        match table {
            Some(table) if self.p > 0.0 && self.p < 1.0 => {
                // A skip is at most MIXED - 1 from the table, or the formula's value (which may
                // be huge, hence the saturating add).
                let mut pos = 0usize;
                loop {
                    let b = pool.take(BUCKET_BITS, rng);
                    let g = table[b as usize];
                    let g = if g != MIXED {
                        g as usize
                    } else {
                        let low = rng.next_u64() >> (64 - LOW_BITS);
                        self.formula((b << LOW_BITS) | low)
                    };
                    pos = pos.saturating_add(g);
                    if pos >= n {
                        return;
                    }
                    visit(pos);
                    pos += 1;
                }
            }
            _ => {
                let mut pos = self.skip(pool, rng);
                while pos < n {
                    visit(pos);
                    pos = pos.saturating_add(1).saturating_add(self.skip(pool, rng));
                }
            }
        }
    }
}

/// Mantegna's sigma_u for Levy exponent beta (seed 003 Eq. 8):
/// [Gamma(1+b) sin(pi b/2) / (Gamma((1+b)/2) b 2^((b-1)/2))]^(1/b).
pub(crate) fn mantegna_sigma_u(beta: f64) -> f64 {
    use statrs::function::gamma::gamma;
    let num = gamma(1.0 + beta) * (std::f64::consts::PI * beta / 2.0).sin();
    let den = gamma((1.0 + beta) / 2.0) * beta * 2f64.powf((beta - 1.0) / 2.0);
    (num / den).powf(1.0 / beta)
}

/// |v|^(-2/3) without a library call (inverse cube root by Newton's method, no division, then
/// squared): the Mantegna denominator |v|^(1/beta) for beta = 1.5, in pure IEEE arithmetic so it
/// is the same on every platform. Relative error < 1e-14; 0 and subnormals give +inf.
#[inline]
#[cfg(test)]
pub(crate) fn inv_abs_pow_two_thirds(v: f64) -> f64 {
    let a = v.abs();
    if a.is_nan() {
        return f64::NAN;
    }
    if a < f64::MIN_POSITIVE {
        return f64::INFINITY;
    }
    if a == f64::INFINITY {
        return 0.0;
    }
    // Initial guess of a^(-1/3) from the exponent bits (|error| < 10%).
    let bits = a.to_bits();
    let mut r = f64::from_bits(0x553e_f0ff_289d_d796u64.wrapping_sub(bits / 3));
    // r <- r (4 - a r^3) / 3 converges quadratically to a^(-1/3).
    for _ in 0..5 {
        let r3 = r * r * r;
        r = r * (4.0 - a * r3) * (1.0 / 3.0);
    }
    r * r
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_xoshiro::Xoshiro256PlusPlus;

    #[test]
    fn table_agrees_with_the_formula_inside_every_pure_bucket() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for p in [0.02, 0.2, 0.25, 0.5, 0.8, 0.99] {
            let g = Geometric::new(p);
            let table = g.table.as_ref().expect("table for p >= 0.02");
            let mut pure = 0;
            for (b, &t) in table.iter().enumerate() {
                if t == MIXED {
                    continue;
                }
                pure += 1;
                for _ in 0..4 {
                    let k = ((b as u64) << LOW_BITS) | (rng.next_u64() >> (64 - LOW_BITS));
                    assert_eq!(g.formula(k), t as usize, "p {p} bucket {b}");
                }
            }
            assert!(pure > 0, "p {p}");
        }
        // Most buckets are pure for the crossover rates that matter.
        let t = Geometric::new(0.2).table.unwrap();
        let mixed = t.iter().filter(|&&v| v == MIXED).count();
        assert!(mixed < 80, "{mixed} mixed buckets of 4096");
    }

    /// The hoisted walk visits the same positions and draws the same bits as skip/next_after,
    /// and leaves the same pool behind, walk after walk, from a fresh pool or one left with odd
    /// leftovers by other takes.
    #[test]
    fn for_each_is_the_skip_walk() {
        for p in [0.0, 0.01, 0.2, 0.5, 0.9, 1.0] {
            let g = Geometric::new(p);
            for n in [0, 1, 7, 1740, 20_000] {
                for pre in [0, 5, 7, 13] {
                    let (mut r1, mut r2) =
                        (ChaCha8Rng::seed_from_u64(11), ChaCha8Rng::seed_from_u64(11));
                    let (mut b1, mut b2) = (BitPool::new(), BitPool::new());
                    if pre > 0 {
                        assert_eq!(b1.take(pre, &mut r1), b2.take(pre, &mut r2));
                    }
                    for walk in 0..4 {
                        let mut walked = Vec::new();
                        let mut j = g.skip(&mut b1, &mut r1);
                        while j < n {
                            walked.push(j);
                            j = g.next_after(j, &mut b1, &mut r1);
                        }
                        let mut visited = Vec::new();
                        g.for_each(n, &mut b2, &mut r2, |j| visited.push(j));
                        assert_eq!(visited, walked, "p {p}, n {n}, pre {pre}, walk {walk}");
                        assert_eq!(b1, b2, "p {p}, n {n}, pre {pre}, walk {walk}");
                    }
                    assert_eq!(r1.next_u64(), r2.next_u64(), "p {p}, n {n}");
                }
            }
        }
    }

    #[test]
    fn skips_give_the_bernoulli_rate_and_the_geometric_law() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for p in [0.01, 0.2, 0.5, 0.9] {
            let g = Geometric::new(p);
            let mut pool = BitPool::new();
            let n = 400_000;
            let mut hits = 0usize;
            g.for_each(n, &mut pool, &mut rng, |_| hits += 1);
            let sd = (n as f64 * p * (1.0 - p)).sqrt();
            assert!((hits as f64 - n as f64 * p).abs() < 5.0 * sd, "p {p}: {hits} of {n}");
            // P(G = 0) = p and P(G = 1) = p (1 - p).
            let draws = 200_000;
            let (mut g0, mut g1) = (0usize, 0usize);
            for _ in 0..draws {
                match g.skip(&mut pool, &mut rng) {
                    0 => g0 += 1,
                    1 => g1 += 1,
                    _ => {}
                }
            }
            for (count, q) in [(g0, p), (g1, p * (1.0 - p))] {
                let sd = (draws as f64 * q * (1.0 - q)).sqrt();
                assert!(
                    (count as f64 - draws as f64 * q).abs() < 5.0 * sd + 1.0,
                    "p {p}: {count} vs {}",
                    draws as f64 * q
                );
            }
        }
    }

    #[test]
    fn skips_at_the_extremes() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut pool = BitPool::new();
        assert_eq!(Geometric::new(0.0).skip(&mut pool, &mut rng), usize::MAX);
        assert_eq!(Geometric::new(1.0).skip(&mut pool, &mut rng), 0);
        let mut all = 0;
        Geometric::new(1.0).for_each(37, &mut pool, &mut rng, |_| all += 1);
        assert_eq!(all, 37);
        let mut none = 0;
        Geometric::new(0.0).for_each(37, &mut pool, &mut rng, |_| none += 1);
        assert_eq!(none, 0);
    }

    #[test]
    fn mantegna_sigma_for_beta_one_and_a_half() {
        // Yang's reference code: sigma_u = 0.6966 for beta = 3/2.
        assert!(
            (mantegna_sigma_u(1.5) - 0.696_574_502_557_0).abs() < 1e-9,
            "{}",
            mantegna_sigma_u(1.5)
        );
        // beta = 1: Gamma(2) sin(pi/2) / (Gamma(1) 1 2^0) = 1.
        assert!((mantegna_sigma_u(1.0) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn inverse_two_thirds_power_matches_powf() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        for _ in 0..100_000 {
            let e = symmetric(&mut rng, 30.0);
            let v = symmetric(&mut rng, 1.0) * 10f64.powf(e);
            if v == 0.0 {
                continue;
            }
            let want = v.abs().powf(-2.0 / 3.0);
            let got = inv_abs_pow_two_thirds(v);
            assert!(((got - want) / want).abs() < 1e-14, "{v}: {got} vs {want}");
        }
        assert_eq!(inv_abs_pow_two_thirds(0.0), f64::INFINITY);
        assert_eq!(inv_abs_pow_two_thirds(f64::INFINITY), 0.0);
    }

    #[test]
    fn two_units_are_the_halves_times_two_to_the_minus_32() {
        let mut rng = ChaCha8Rng::seed_from_u64(6);
        let scale = 1.0 / (1u64 << 32) as f64;
        for w in (0..10_000).map(|_| rng.next_u64()).chain([0, u64::MAX, 1 << 32, 0xffff_ffff]) {
            let (h, l) = two_units(w);
            assert_eq!(
                (h.to_bits(), l.to_bits()),
                (
                    ((w >> 32) as f64 * scale).to_bits(),
                    ((w & 0xffff_ffff) as f64 * scale).to_bits()
                ),
                "{w:x}"
            );
        }
    }

    #[test]
    fn every_lane_is_xoshiro256_plus_plus() {
        fn lanes_agree<const L: usize>() {
            let mut rng = ChaCha8Rng::seed_from_u64(8);
            let mut lanes = BulkLanes::<L>::from_rng(&mut rng.clone());
            let mut single: Vec<Xoshiro256PlusPlus> = (0..L)
                .map(|_| {
                    let mut seed = [0u8; 32];
                    for k in 0..4 {
                        seed[8 * k..8 * k + 8].copy_from_slice(&rng.next_u64().to_le_bytes());
                    }
                    Xoshiro256PlusPlus::from_seed(seed)
                })
                .collect();
            let mut stepped = lanes.clone();
            for _ in 0..100 {
                let [s0, s1, s2, s3] = lanes.state_mut();
                let words = stepped.next_words();
                for l in 0..L {
                    let want = single[l].next_u64();
                    assert_eq!(
                        xoshiro_step(&mut s0[l], &mut s1[l], &mut s2[l], &mut s3[l]),
                        want,
                        "lane {l}"
                    );
                    assert_eq!(words[l], want, "lane {l}");
                }
            }
            assert_eq!(lanes, stepped);
        }
        lanes_agree::<PSO_LANES>();
        lanes_agree::<DE_LANES>();
        lanes_agree::<1>();
    }

    #[test]
    fn bernoulli_thresholds() {
        assert_eq!(bernoulli_threshold_32(0.0), 0);
        assert_eq!(bernoulli_threshold_32(1.0), 1 << 32);
        assert_eq!(bernoulli_threshold_32(0.5), 1 << 31);
        assert_eq!(bernoulli_threshold_32(f64::NAN), 0);
        assert_eq!(bernoulli_threshold_32(2.0), 1 << 32);
        for p in [0.8, 0.01, 0.3, 1e-12] {
            let t = bernoulli_threshold_32(p) as f64 / 4_294_967_296.0;
            assert!(t <= p && p - t < 2.4e-10, "{p}: {t}");
        }
    }

    #[test]
    fn uniform_helpers_stay_in_range() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..10_000 {
            let u = unit(&mut rng);
            assert!((0.0..1.0).contains(&u));
            let (a, b) = two_units(rng.next_u64());
            assert!((0.0..1.0).contains(&a) && (0.0..1.0).contains(&b));
            assert!(index(&mut rng, 7) < 7);
            let s = symmetric(&mut rng, 5e-6);
            assert!(s.abs() <= 5e-6);
        }
        let mut counts = [0usize; 5];
        for _ in 0..50_000 {
            counts[index(&mut rng, 5)] += 1;
        }
        for c in counts {
            assert!((c as f64 - 10_000.0).abs() < 500.0, "{counts:?}");
        }
    }
}
