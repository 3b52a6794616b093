//! Every fast path of the crate in one place: which compiled copy runs ([`Isa`], the
//! `SOMNURBS_SIMD` choice and the dispatch helpers), the shared vector helpers, and one file per
//! kernel group, each holding the portable copy beside its ISA copies and the tests that they
//! give the same bits:
//!
//! - `fitness`: the control-net fitness (Eq. 6.2), portable and AVX2;
//! - `moves`: the optimisers' per-coordinate loops (DE's trial, PSO's move, the lanes' words);
//! - `levy`: cuckoo search's Levy factors and flights;
//! - `bezier`: seed 003's allocation-free least squares;
//! - `envelope`: the exact solver's envelope Cholesky.
//!
//! Determinism: results never depend on the instruction set. Every copy performs the same IEEE
//! operations (multiply, add, fused multiply-add `f64::mul_add` with one rounding in every copy,
//! compare) in the same order, or exact integer arithmetic; only the vector width differs. Each
//! file's tests run every copy this CPU has against the portable one, bit for bit.
//!
//! A copy is kept only where it gains at least 5% over the next copy on the machine kind that
//! has it (docs/speed.md has the figures); this module depends on nothing but `std` and
//! `core::arch`, the kernel files on the data types of the problems they serve.

/// Which compiled copy of the kernels runs. The AVX-512VL copies are hand-written with 256-bit
/// vectors and 32 registers: compiler-vectorised AVX-512 code picks 512-bit vectors, which an AMD
/// Zen 4 runs in two halves, and turns transposes into scatters. A kernel group without an
/// AVX-512VL copy of its own runs its AVX2 copy under `Avx512Vl`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Isa {
    Baseline,
    /// AVX2 with FMA.
    Avx2,
    /// AVX-512VL (256-bit vectors, 32 registers, native 64-bit rotates, three-input logic and
    /// compares into mask registers).
    Avx512Vl,
}

impl Isa {
    /// Every copy, slowest first.
    pub const ALL: [Isa; 3] = [Isa::Baseline, Isa::Avx2, Isa::Avx512Vl];

    /// The fastest copy this CPU supports.
    pub fn fastest() -> Isa {
        Isa::ALL.into_iter().rev().find(|isa| isa.supported()).unwrap_or(Isa::Baseline)
    }

    /// Whether this CPU runs this copy.
    pub fn supported(self) -> bool {
        match self {
            Isa::Baseline => true,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => avx2_fma(),
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512Vl => avx512vl(),
            #[cfg(not(target_arch = "x86_64"))]
            Isa::Avx2 | Isa::Avx512Vl => false,
        }
    }
}

/// Whether this CPU runs the AVX2 + FMA copies.
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn avx2_fma() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

/// Whether this CPU runs the AVX-512VL copies (256-bit vectors, 32 registers; compiled with
/// AVX2, FMA, AVX-512F and AVX-512VL).
#[cfg(target_arch = "x86_64")]
pub(crate) fn avx512vl() -> bool {
    avx2_fma()
        && std::arch::is_x86_feature_detected!("avx512f")
        && std::arch::is_x86_feature_detected!("avx512vl")
}

/// The environment variable that forces one compiled copy of every kernel of this module:
/// `scalar`, `avx2` or `avx512` (the AVX-512VL copies, and the AVX2 copy of a group without
/// one); unset, empty or `auto` runs the fastest copy this CPU has. All copies
/// give the same bits, so this only changes the speed; a copy the CPU lacks is refused with an
/// error.
pub(crate) const SIMD_ENV: &str = "SOMNURBS_SIMD";

/// A value of `SIMD_ENV` that names no copy, or one this CPU lacks; displayed as
/// `SOMNURBS_SIMD <message>`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SimdError {
    pub message: String,
}

impl std::fmt::Display for SimdError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{SIMD_ENV} {}", self.message)
    }
}

impl std::error::Error for SimdError {}

/// The copy `value` (the variable's value, if set) asks for, checked against this CPU.
pub fn parse_simd(value: Option<&str>) -> Result<Isa, SimdError> {
    let isa = match value.map(str::trim) {
        None | Some("") | Some("auto") => return Ok(Isa::fastest()),
        Some("scalar") => Isa::Baseline,
        Some("avx2") => Isa::Avx2,
        Some("avx512") => Isa::Avx512Vl,
        Some(other) => {
            return Err(SimdError {
                message: format!("must be scalar, avx2, avx512 or auto, got '{other}'"),
            })
        }
    };
    if !isa.supported() {
        let needs =
            if isa == Isa::Avx2 { "AVX2 and FMA" } else { "AVX2, FMA, AVX-512F and AVX-512VL" };
        return Err(SimdError {
            message: format!("asks for the {} copy, which needs {needs}, but this CPU lacks them (the fastest copy here is {:?})", value.unwrap_or_default().trim(), Isa::fastest()),
        });
    }
    Ok(isa)
}

/// The copy this process runs: [`SIMD_ENV`] if set (read once), else the fastest this CPU has.
/// Every optimiser run and every control-net problem checks it first, so a bad value is an
/// error before any work.
pub(crate) fn simd() -> Result<Isa, SimdError> {
    choice().clone()
}

/// [`SIMD_ENV`] parsed once for the process.
fn choice() -> &'static Result<Isa, SimdError> {
    static CHOICE: std::sync::OnceLock<Result<Isa, SimdError>> = std::sync::OnceLock::new();
    CHOICE.get_or_init(|| parse_simd(std::env::var(SIMD_ENV).ok().as_deref()))
}

/// The copy the dispatchers run ([`simd`]; the fastest copy if the variable is malformed, which
/// the runs have already refused). Read by reference: the dispatchers ask for every chunk of a
/// move, and cloning [`simd`]'s result each time took about 1% of a cuckoo-search run.
#[inline]
pub(crate) fn chosen() -> Isa {
    match choice() {
        Ok(isa) => *isa,
        Err(_) => Isa::fastest(),
    }
}

/// Whether the AVX2 (or AVX-512VL) copies run.
#[inline]
pub(crate) fn use_avx2() -> bool {
    matches!(chosen(), Isa::Avx2 | Isa::Avx512Vl)
}

/// Whether the AVX-512VL copies run.
#[inline]
pub(crate) fn use_avx512() -> bool {
    chosen() == Isa::Avx512Vl
}

/// `v` clamped to [lo, hi], written as `if v < lo { lo } else { v }` then
/// `if v > hi { hi } else { v }`: the same value as `max(lo).min(hi)` for every number (and NaN
/// passes through), but it compiles to one vector max and one vector min instead of NaN-aware
/// blends.
#[inline(always)]
pub(crate) fn clamp(v: f64, lo: f64, hi: f64) -> f64 {
    let v = if v < lo { lo } else { v };
    if v > hi {
        hi
    } else {
        v
    }
}

/// The few operations whose AVX2 and AVX-512VL forms differ, so that each hand-written kernel
/// is one body for both (`simd!(avx2, ..)` or `simd!(avx512vl, ..)`): AVX-512VL has native 64-bit
/// rotates, three-input logic and unsigned compares into mask registers; AVX2 builds them from
/// shifts, two-input logic and signed compares (exact here: the compared values are below 2^33).
#[cfg(target_arch = "x86_64")]
macro_rules! simd {
    (avx512vl, rol, $x:expr, $k:literal) => {
        _mm256_rol_epi64::<$k>($x)
    };
    (avx2, rol, $x:expr, $k:literal) => {{
        let x = $x;
        _mm256_or_si256(_mm256_slli_epi64::<$k>(x), _mm256_srli_epi64::<{ 64 - $k }>(x))
    }};
    // a ^ b ^ c
    (avx512vl, xor3, $a:expr, $b:expr, $c:expr) => {
        _mm256_ternarylogic_epi64::<0x96>($a, $b, $c)
    };
    (avx2, xor3, $a:expr, $b:expr, $c:expr) => {
        _mm256_xor_si256(_mm256_xor_si256($a, $b), $c)
    };
    // (a & b) | c
    (avx512vl, and_or, $a:expr, $b:expr, $c:expr) => {
        _mm256_ternarylogic_epi64::<0xEA>($a, $b, $c)
    };
    (avx2, and_or, $a:expr, $b:expr, $c:expr) => {
        _mm256_or_si256(_mm256_and_si256($a, $b), $c)
    };
    // Per 64-bit lane: h < threshold (both below 2^33) ? m : x.
    (avx512vl, choose, $h:expr, $thr:expr, $x:expr, $m:expr) => {
        _mm256_mask_blend_pd(_mm256_cmplt_epu64_mask($h, $thr), $x, $m)
    };
    (avx2, choose, $h:expr, $thr:expr, $x:expr, $m:expr) => {
        _mm256_blendv_pd($x, $m, _mm256_castsi256_pd(_mm256_cmpgt_epi64($thr, $h)))
    };
}

/// One xoshiro256++ step of four lanes in 256-bit instructions: `$s` is the four state rows, one
/// register each; evaluates to the four words.
#[cfg(target_arch = "x86_64")]
macro_rules! xoshiro4 {
    ($isa:ident, $s:ident) => {{
        let [a0, a1, a2, a3] = $s;
        let word = _mm256_add_epi64(simd!($isa, rol, _mm256_add_epi64(a0, a3), 23), a0);
        let t = _mm256_slli_epi64::<17>(a1);
        $s = [
            simd!($isa, xor3, a0, a3, a1),
            simd!($isa, xor3, a1, a2, a0),
            simd!($isa, xor3, a2, a0, t),
            simd!($isa, rol, _mm256_xor_si256(a3, a1), 45),
        ];
        word
    }};
}

pub(crate) mod bezier;
pub(crate) mod envelope;
pub(crate) mod fitness;
pub(crate) mod levy;
pub(crate) mod moves;
pub use fitness::building_blocks;
pub use levy::timing as levy_timing;
pub use moves::timing as moves_timing;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamp_matches_max_min_and_keeps_nan() {
        for v in [-3.0, -1.0, 0.0, 0.5, 1.0, 7.0, f64::INFINITY, f64::NEG_INFINITY] {
            assert_eq!(clamp(v, -1.0, 1.0), v.clamp(-1.0, 1.0));
        }
        assert!(clamp(f64::NAN, -1.0, 1.0).is_nan());
    }
}
