//! The exact solver's envelope (profile) Cholesky factorisation L L^T, the portable copy beside
//! its AVX2 copy (the same Rust compiled with `target_feature`: wider vectors for [`dot`]'s
//! eight accumulators, no fused multiply-add, since rustc never contracts `a * b + c`), and the
//! fixed-order dot product the solver's triangular solves share. (An AVX-512F compilation gained
//! nothing measurable on a Sapphire Rapids class Xeon and was removed: docs/speed.md.)

/// Dot product with eight interleaved accumulators summed in a fixed order (vectorises; the
/// same result on every instruction set).
#[inline(always)]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len();
    let b = &b[..n];
    let mut acc = [0.0; 8];
    let chunks = n / 8;
    for i in 0..chunks {
        let (x, y) = (&a[8 * i..8 * i + 8], &b[8 * i..8 * i + 8]);
        for l in 0..8 {
            acc[l] += x[l] * y[l];
        }
    }
    for i in 8 * chunks..n {
        acc[i - 8 * chunks] += a[i] * b[i];
    }
    ((acc[0] + acc[4]) + (acc[2] + acc[6])) + ((acc[1] + acc[5]) + (acc[3] + acc[7]))
}

/// In-place Cholesky L L^T of an envelope matrix (row r holds columns `first[r]..=r` at
/// `val[start[r]..]`); Err(row) at a non-positive pivot.
#[inline(always)]
fn cholesky_generic(first: &[usize], start: &[usize], val: &mut [f64]) -> Result<(), usize> {
    let n = first.len();
    for r in 0..n {
        let fr = first[r];
        let (done, rest) = val.split_at_mut(start[r]);
        let row = &mut rest[..r - fr + 1];
        for c in fr..r {
            let fc = first[c];
            let k0 = fr.max(fc);
            let lc = &done[start[c]..start[c] + (c - fc + 1)];
            let s = row[c - fr] - dot(&row[k0 - fr..c - fr], &lc[k0 - fc..c - fc]);
            row[c - fr] = s / lc[c - fc];
        }
        let (off, diag) = row.split_at_mut(r - fr);
        let d = diag[0] - dot(off, off);
        if !(d > 0.0 && d.is_finite()) {
            return Err(r);
        }
        diag[0] = d.sqrt();
    }
    Ok(())
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn cholesky_avx2(first: &[usize], start: &[usize], val: &mut [f64]) -> Result<(), usize> {
    cholesky_generic(first, start, val)
}

/// [`cholesky_generic`] in the copy the run's SIMD choice names ([`super::simd`]).
pub(crate) fn cholesky(first: &[usize], start: &[usize], val: &mut [f64]) -> Result<(), usize> {
    #[cfg(target_arch = "x86_64")]
    match super::chosen() {
        // SAFETY: the dispatcher checked that the CPU has the copy's features.
        super::Isa::Avx2 | super::Isa::Avx512Vl => {
            return unsafe { cholesky_avx2(first, start, val) }
        }
        super::Isa::Baseline => {}
    }
    cholesky_generic(first, start, val)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A random banded positive definite matrix (envelope widths 0..12 per row, diagonally
    /// dominant) factorised by every copy this CPU has: the same bits as the portable copy.
    #[test]
    fn copies_are_bit_identical() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for n in [1, 5, 30, 97] {
            let first: Vec<usize> =
                (0..n).map(|r: usize| r.saturating_sub(rng.gen_range(0..12))).collect();
            let mut start = Vec::new();
            let mut total = 0;
            for (r, &f) in first.iter().enumerate() {
                start.push(total);
                total += r - f + 1;
            }
            let mut val: Vec<f64> = (0..total).map(|_| rng.gen_range(-1.0..1.0)).collect();
            for r in 0..n {
                val[start[r] + r - first[r]] = 30.0;
            }
            let mut want = val.clone();
            cholesky_generic(&first, &start, &mut want).unwrap();
            let mut got = val.clone();
            cholesky(&first, &start, &mut got).unwrap();
            assert_eq!(bits(&got), bits(&want), "n {n}");
            #[cfg(target_arch = "x86_64")]
            if super::super::avx2_fma() {
                let mut got = val.clone();
                // SAFETY: the CPU reports AVX2.
                unsafe { cholesky_avx2(&first, &start, &mut got) }.unwrap();
                assert_eq!(bits(&got), bits(&want), "AVX2 n {n}");
            }
        }
    }

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }
}
