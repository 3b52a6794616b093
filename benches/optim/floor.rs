//! The AVX2 fitness' two building blocks, each run alone with its data in L1 and nothing around
//! it (the kernel's own code, `simd::fitness::building_blocks`): what the kernel's data flow costs
//! on this core before any set-up, chunk change or interaction between the passes. Their sum over
//! one evaluation is a floor of that data flow, measured (the FMA bound counts only the
//! multiply-adds).
//!
//! - A first-pass block: four grid rows (lanes), each the sum of four control rows weighted by
//!   its own four basis values over four k (16 fused multiply-adds, one operand from memory),
//!   the 4 x 4 transpose (eight shuffles) and four stores. Timed over a segment of 50 blocks
//!   (the kernel's segments have 12-14), so that the set-up of a call counts little.
//! - A second-pass column: four broadcast weights, twelve transposed rows and three data rows
//!   from memory, 15 fused multiply-adds, one 4-wide square root and the running sum. Timed
//!   over 80 grid columns of one chunk (the kernel's chunks have 18-20), on the transposed rows
//!   of an 18-column net.
#![cfg_attr(not(target_arch = "x86_64"), allow(dead_code, unused_imports))]

use somnurbs::spline::SparseBasis;

/// Cycles of one first-pass block and of one second-pass column.
pub struct Blocks {
    pub pass1_block: f64,
    pub pass2_column: f64,
}

/// The timed segment's length in k (50 blocks of four), which is also its rows' stride.
const K: usize = 200;
/// Grid columns and transposed rows (an 18-column net: 3 x 18 = 54, padded to 56).
const COLUMNS: usize = 80;
const K3P: usize = 56;

/// Time both blocks with the bench's [`best_ns_per`] and convert to cycles at `mhz`; None
/// without AVX2 and FMA.
pub fn measure(mhz: f64) -> Option<Blocks> {
    #[cfg(target_arch = "x86_64")]
    {
        use crate::best_ns_per;
        use somnurbs::simd::building_blocks::{first_pass, second_pass};
        let rows: Vec<f64> = (0..5 * K).map(|k| 1.0 + k as f64 * 1e-3).collect();
        let w = [
            [0.1, 0.6, 0.25, 0.05],
            [0.05, 0.5, 0.4, 0.05],
            [0.2, 0.6, 0.15, 0.05],
            [0.1, 0.5, 0.3, 0.1],
        ];
        let out = std::cell::RefCell::new(vec![0.0; 4 * K]);
        first_pass(1, &rows, K, &w, &mut out.borrow_mut())?;
        let p1 = best_ns_per(5_000, |n| {
            first_pass(n, &rows, K, &w, &mut out.borrow_mut());
            out.borrow()[0]
        });
        // First indices 0..=14 (an 18-column net), rising across the columns.
        let nv = SparseBasis {
            first: (0..COLUMNS).map(|j| j * 14 / (COLUMNS - 1)).collect(),
            w: (0..COLUMNS).map(|j| w[j % 4]).collect(),
        };
        let rt: Vec<f64> = (0..4 * K3P).map(|k| 1.0 + k as f64 * 1e-3).collect();
        let data: Vec<f64> = (0..12 * COLUMNS).map(|k| 0.5 + k as f64 * 1e-3).collect();
        let p2 = best_ns_per(5_000, |n| second_pass(n, &nv, K3P, &data, &rt).unwrap_or(0.0));
        let cycles = |ns: f64| ns * mhz / 1e3;
        Some(Blocks {
            pass1_block: cycles(p1 / (K / 4) as f64),
            pass2_column: cycles(p2 / COLUMNS as f64),
        })
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = mhz;
        None
    }
}
