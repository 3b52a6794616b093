//! Active-set refinement of a near-optimal point: the primal and the dual together.
//!
//! At the optimum of f(x) = sum_k |A_k x - d_k| over the box the terms split into those the
//! optimum interpolates (set I: r_k = 0, any dual y_k in the unit ball) and the others (set N:
//! y_k = r_k / |r_k| exactly), and the box coordinates into those at a bound and the free ones.
//! With the split guessed from the residuals of a near-optimal x, the optimum solves the square
//! system
//!
//!   G = sum_N A_k^T r_k / |r_k| + sum_I A_k^T y_k = 0 (free coordinates),   r_k = 0 (k in I),
//!
//! in (x, y_I). Newton's method on it, with the interpolation constraints relaxed to
//! r_k + A_k dx = tau dy_k (a proximal term that vanishes at the fixed point, so tau sets the
//! speed, not the answer), eliminates dy and solves
//!
//!   (sum_N A_k^T (I - u_k u_k^T) / |r_k| A_k + sum_I A_k^T A_k / tau) dx = -G - sum_I A_k^T r_k / tau,
//!   dy_k = (r_k + A_k dx) / tau,
//!
//! the same envelope structure as the primal Newton Hessian. Unlike the dual polish, x moves with
//! y, so the certificate's y_k = r_k / |r_k| on N stays exactly along its residual (no ball part of
//! the gap from turned terms) and only the interpolated terms carry open duals. A term of I whose
//! y_k leaves the unit ball is not interpolated at the optimum and joins N. Each round's
//! (x, y) is certified by weak duality and offered to the solver's best point and best bound.

use super::{
    apply_terms, lower_bound_with, norm_sum, weighted_apply, Best, Scratch, Stall, Workspace,
    IDENTITY, REFINE_STEPS, SHIFT,
};
use crate::geom::{norm, Point3};

/// At most this many Newton rounds per split; they stop early when the bound stops rising.
const ROUNDS: usize = 16;

/// Thresholds e: terms with |r_k| <= e * (f / m) start in the interpolated set I.
const SPLITS: [f64; 3] = [1e-6, 1e-9, 1e-4];

/// The proximal weight tau of the relaxed constraints, relative to f / m.
const TAU: f64 = 1e-6;

/// Refine from x (the solver's best point) for each split of `SPLITS`, offering every round's
/// point and dual to `best`; returns early once `done(best.f, best.lb)`.
pub(super) fn refine(
    ws: &mut Workspace,
    x: &[f64],
    best: &mut Best,
    sc: &mut Scratch,
    done: &dyn Fn(f64, f64) -> bool,
) {
    let (pb, m) = (ws.pb, ws.pb.n_terms());
    let mut r = vec![[0.0; 3]; m];
    pb.residuals(x, &mut r);
    let unit = norm_sum(&r) / m.max(1) as f64;
    if unit <= 0.0 || !unit.is_finite() {
        return;
    }
    let mut last = vec![false; m];
    for e in SPLITS {
        let interp: Vec<bool> = r.iter().map(|v| norm(*v) <= e * unit).collect();
        if interp == last {
            continue;
        }
        last.clone_from(&interp);
        refine_with(ws, x, interp, TAU * unit, best, sc);
        if done(best.f, best.lb) {
            return;
        }
    }
}

/// The dual point of the split at residuals r: y_k = r_k / |r_k| on N, the open y_k on I.
fn split_duals(r: &[Point3], interp: &[bool], y_open: &[Point3], y: &mut [Point3]) {
    for k in 0..r.len() {
        y[k] = if interp[k] {
            y_open[k]
        } else {
            let n = norm(r[k]);
            if n > 0.0 {
                [r[k][0] / n, r[k][1] / n, r[k][2] / n]
            } else {
                [0.0; 3]
            }
        };
    }
}

/// The Newton blocks of the split: (I - u u^T) / max(|r_k|, tau) on N, I / tau on I.
fn split_blocks(r: &[Point3], interp: &[bool], tau: f64, blocks: &mut [[[f64; 3]; 3]]) {
    for k in 0..r.len() {
        let nk = norm(r[k]);
        let (u, w) = if interp[k] || nk == 0.0 {
            ([0.0; 3], 1.0 / tau)
        } else {
            ([r[k][0] / nk, r[k][1] / nk, r[k][2] / nk], 1.0 / nk.max(tau))
        };
        for i in 0..3 {
            for c in 0..3 {
                blocks[k][i][c] = (IDENTITY[i][c] - u[i] * u[c]) * w;
            }
        }
    }
}

/// Newton rounds on the split `interp` from x (see the module doc), tau the proximal weight.
fn refine_with(
    ws: &mut Workspace,
    x0: &[f64],
    mut interp: Vec<bool>,
    tau: f64,
    best: &mut Best,
    sc: &mut Scratch,
) {
    let (pb, n, m) = (ws.pb, x0.len(), ws.pb.n_terms());
    let mut x = x0.to_vec();
    let mut r = vec![[0.0; 3]; m];
    pb.residuals(&x, &mut r);
    // The open duals start from the best certificate's (the smoothed duals r / s of the
    // Newton loop or a polished point), which also tells the bounds that hold.
    let mut y_open = best.y.clone();
    let mut y = vec![[0.0; 3]; m];
    let mut blocks = vec![[[0.0; 3]; 3]; m];
    let mut adx = vec![[0.0; 3]; m];
    let mut stall = Stall::new();
    split_duals(&r, &interp, &y_open, &mut y);
    let mut gap =
        norm_sum(&r) - lower_bound_with(&mut y, &r, &x, ws.lower, ws.upper, pb, &mut sc.g);
    for _ in 0..ROUNDS {
        split_duals(&r, &interp, &y_open, &mut y);
        pb.apply_transpose(&y, &mut sc.g);
        for j in 0..n {
            let (lo, hi) = ws.at_bounds(&x, j);
            sc.active[j] = (lo && sc.g[j] > 0.0) || (hi && sc.g[j] < 0.0);
        }
        ws.set_skip(&sc.active);
        split_blocks(&r, &interp, tau, &mut blocks);
        ws.assemble(|k| Some(blocks[k]));
        if !ws.factorise(SHIFT) {
            return;
        }
        // Right-hand side -G - sum_I A_k^T r_k / tau on the free coordinates.
        let [rhs0, rhs, sol] = &mut sc.vn;
        let [ri, w] = &mut sc.vm;
        for k in 0..m {
            ri[k] =
                if interp[k] { [r[k][0] / tau, r[k][1] / tau, r[k][2] / tau] } else { [0.0; 3] };
        }
        pb.apply_transpose(ri, rhs0);
        for j in 0..n {
            rhs0[j] = if sc.active[j] { 0.0 } else { -sc.g[j] - rhs0[j] };
        }
        sc.d.fill(0.0);
        let mut buf = vec![0.0; n];
        for _ in 0..=REFINE_STEPS {
            weighted_apply(pb, &blocks, &sc.d, ri, w, sol);
            for j in 0..n {
                rhs[j] = if sc.active[j] { 0.0 } else { rhs0[j] - sol[j] };
            }
            ws.solve(rhs, sol, &mut buf);
            for j in 0..n {
                sc.d[j] += sol[j];
            }
        }
        // dy_k = (r_k + A_k dx) / tau on I: the step is (dx, dy), damped until the certified
        // gap f(x) - LB(y) falls.
        apply_terms(pb, &sc.d, &mut adx);
        let Some((f, lb)) =
            damped_step(ws, &mut x, &mut r, &interp, &mut y_open, &adx, tau, gap, sc)
        else {
            return;
        };
        gap = f - lb;
        split_duals(&r, &interp, &y_open, &mut y);
        // The same LB, now with y rescaled into the balls as it was certified.
        let lb = lower_bound_with(&mut y, &r, &x, ws.lower, ws.upper, pb, &mut sc.vn[0]);
        best.offer_dual(lb, &y);
        best.offer_x(f, &x);
        // A y_k of I that left the unit ball: its term is not interpolated at the optimum.
        for k in 0..m {
            if interp[k] && norm(y_open[k]) > 1.0 {
                interp[k] = false;
            }
        }
        if stall.stalled(lb) {
            break;
        }
    }
}

/// Move (x, y_I) by alpha (dx, dy), alpha = 1, 1/2, ..., 1/2^9, dy_k = (r_k + A_k dx) / tau
/// (`adx` = A dx), at the first alpha whose certified gap f(x) - LB(y) is below `gap`; the new
/// x, r, y_I and Some((f, LB)), or None (nothing moved) when no alpha lowers the gap.
#[allow(clippy::too_many_arguments)]
fn damped_step(
    ws: &Workspace,
    x: &mut [f64],
    r: &mut [Point3],
    interp: &[bool],
    y_open: &mut [Point3],
    adx: &[Point3],
    tau: f64,
    gap: f64,
    sc: &mut Scratch,
) -> Option<(f64, f64)> {
    let (pb, n, m) = (ws.pb, x.len(), r.len());
    let mut xt = vec![0.0; n];
    let mut rt = vec![[0.0; 3]; m];
    let mut yt = y_open.to_vec();
    let mut y = vec![[0.0; 3]; m];
    let mut alpha = 1.0;
    for _ in 0..10 {
        for k in 0..m {
            if interp[k] {
                for c in 0..3 {
                    yt[k][c] = y_open[k][c] + alpha * (r[k][c] + adx[k][c]) / tau;
                }
            }
        }
        for j in 0..n {
            xt[j] = (x[j] + alpha * sc.d[j]).max(ws.lower[j]).min(ws.upper[j]);
        }
        pb.residuals(&xt, &mut rt);
        split_duals(&rt, interp, &yt, &mut y);
        let lb = lower_bound_with(&mut y, &rt, &xt, ws.lower, ws.upper, pb, &mut sc.vn[0]);
        let f = norm_sum(&rt);
        if f - lb < gap {
            x.copy_from_slice(&xt);
            r.copy_from_slice(&rt);
            y_open.copy_from_slice(&yt);
            return Some((f, lb));
        }
        alpha *= 0.5;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::super::tests::Plain;
    use super::super::{certify, certify_dual, SumOfNorms};
    use super::*;

    /// The polish test's two weighted geometric medians (x0 = 0 interpolates 3|x0|, dual
    /// (e1 + e2) / 3; x1 = d/2 interpolates |2 x1 - d|, dual e3 / 2) and a third point pulled
    /// out of its box, |x2 - 2 e1| with x2 in [-1, 1]^3 (optimum e1 on the upper bound, dual -e1):
    /// f* = 3 + 1 = 4. From a start 1e-7 off the optimum with no dual at all, the refinement
    /// certifies f* to 1e-9 and finds the closed-form duals.
    #[test]
    fn refine_certifies_an_interpolating_optimum_on_a_bound() {
        let d = [0.4, -0.2, 0.6];
        let pb = Plain {
            n: 3,
            points: vec![vec![0], vec![0], vec![0], vec![1], vec![1], vec![2]],
            coefs: vec![vec![3.0], vec![1.0], vec![1.0], vec![2.0], vec![1.0], vec![1.0]],
            data: vec![
                [0.0; 3],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                d,
                [0.2, -0.1, 1.3],
                [2.0, 0.0, 0.0],
            ],
        };
        let mut lower = vec![-5.0; 9];
        let mut upper = vec![5.0; 9];
        for j in 6..9 {
            (lower[j], upper[j]) = (-1.0, 1.0);
        }
        let opt = [0.0, 0.0, 0.0, 0.2, -0.1, 0.3, 1.0, 0.0, 0.0];
        let (f_opt, _) = certify(&pb, &lower, &upper, &opt);
        assert!((f_opt - 4.0).abs() < 1e-15, "{f_opt}");
        let off = [1e-7, -2e-7, 3e-7, -1e-7, 1e-7, 2e-7, -3e-7, 1e-7, -1e-7];
        let x: Vec<f64> = opt.iter().zip(off).map(|(a, b)| a + b).collect();
        let mut ws = Workspace::new(&pb, &lower, &upper).unwrap();
        let mut best =
            Best { x: x.clone(), f: pb.value(&x), lb: f64::NEG_INFINITY, y: vec![[0.0; 3]; 6] };
        let mut sc = Scratch::new(9, 6);
        refine(&mut ws, &x, &mut best, &mut sc, &|f, lb| f - lb <= 1e-13 * f);
        let (f, lb) = certify_dual(&pb, &lower, &upper, &best.x, &best.y);
        assert!(f == best.f && f <= pb.value(&x) && f - f_opt <= 1e-12, "f {f}");
        assert!(lb <= f_opt + 1e-15 && f - lb <= 1e-9, "gap {} y {:?}", f - lb, best.y);
        let want = [(0, [1.0 / 3.0, 1.0 / 3.0, 0.0]), (3, [0.0, 0.0, 0.5]), (5, [-1.0, 0.0, 0.0])];
        for (k, w) in want {
            for c in 0..3 {
                assert!((best.y[k][c] - w[c]).abs() < 1e-6, "term {k}: {:?}", best.y);
            }
        }
    }
}
