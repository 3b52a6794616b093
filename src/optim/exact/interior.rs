//! Interior-point (log-barrier) Newton on the box, for boxes so tight that most coordinates end
//! on a bound.
//!
//! The projected Newton loop identifies the box's active set one projection at a time; in the
//! optimisers' box B +- 5e-6 of Chapter 6 the residuals (~f / m ~ 3e-3) hardly change across the
//! box, the objective is almost linear there and about four coordinates in five end on a bound,
//! so the projection arcs cut nearly every step short (`nurbs_book` 18x18 nets: 300 steps, gaps
//! 9e-7 to 3e-6). Here the bounds enter the objective instead,
//!
//!   Phi(x) = sum_k sqrt(|r_k|^2 + mu^2) - beta sum_j [ln(x_j - l_j) + ln(u_j - x_j)],
//!
//! whose gradient is the smoothed one plus the barrier's -beta / (x_j - l_j) + beta / (u_j - x_j).
//! Newton's method on Phi uses the primal-dual form of the barrier's Hessian, the diagonal
//! z_l / (x_j - l_j) + z_u / (u_j - x_j) with multipliers z (z (x - l) = beta on the path; each
//! moves by its own Newton step), which a primal barrier's beta / (x - l)^2 would understate
//! right after beta shrinks (measured on talus 18x18 alone it was no faster: 82 steps against
//! 75); the Jacobi scaling of the factorisation makes its huge entries harmless. Steps go at
//! most TO_BOUNDARY of the way to a bound, with an Armijo search on Phi, and mu and beta shrink
//! together once the Newton decrement is below beta (beta = 0.03 mu m / n: the smoothing gap of
//! the terms the optimum interpolates and the barrier's gap, ~beta per coordinate near a bound,
//! shrink at one rate). Every iterate is certified as in the main loop: at a point of the path,
//! y = r / s leaves g_j = beta / (x_j - l_j) - beta / (u_j - x_j) on each coordinate, so LB(y)
//! loses ~beta per coordinate near a bound and nothing on the free ones.

use super::{
    certificates, dual_newton_certificate, hessian_apply, hessian_block, norm_sum, smooth, Best,
    Iterate, Scratch, Workspace, REFINE_STEPS, SHIFT,
};

/// A stage ends when the Newton decrement of Phi is below this multiple of beta.
const STAGE_TOL: f64 = 1.0;

/// beta = BETA_RATIO mu m / n (measured on the `nurbs_book` 16x16 and 18x18 cells of
/// `ch6_exact`: 1 took 92-158 steps in all, 0.1 92-111, 0.03 83-96, 0.01 103-106).
const BETA_RATIO: f64 = 0.03;

/// The fraction of the way to the nearest bound a step may go.
const TO_BOUNDARY: f64 = 0.99;

/// The multipliers stay within this factor of their central values beta / distance.
const KAPPA: f64 = 1e10;

/// The interior start: x_start moved at least this fraction of the box width inside.
const MARGIN: f64 = 1e-2;

/// The barrier's state: weight beta and which coordinates it covers (boxes of width 0 are not
/// variables).
pub(super) struct Barrier {
    /// The smoothing mu of the norms, the barrier weight beta, and their common shrink factor.
    mu: f64,
    beta: f64,
    shrink: f64,
    fixed: Vec<bool>,
    /// The barrier's gradient -beta / (x - l) + beta / (u - x) and the primal-dual Hessian
    /// diagonal z_l / (x - l) + z_u / (u - x).
    grad: Vec<f64>,
    diag: Vec<f64>,
    /// The bounds' multipliers z_l, z_u (z_l (x - l) = z_u (u - x) = beta on the path).
    zl: Vec<f64>,
    zu: Vec<f64>,
}

impl Barrier {
    /// The barrier's gradient and Hessian diagonal at x: Phi's box part.
    fn at(&mut self, ws: &Workspace, x: &[f64]) {
        for j in 0..x.len() {
            if self.fixed[j] {
                (self.grad[j], self.diag[j]) = (0.0, 0.0);
                continue;
            }
            let (a, b) = (x[j] - ws.lower[j], ws.upper[j] - x[j]);
            self.grad[j] = -self.beta / a + self.beta / b;
            self.diag[j] = self.zl[j] / a + self.zu[j] / b;
        }
    }

    /// Move the multipliers by their Newton step for the primal step dx taken from x_old to x
    /// (dz_l = beta / a - z_l - z_l dx / a, dz_u = beta / b - z_u + z_u dx / b at x_old), at most
    /// TO_BOUNDARY of the way to 0, then keep each within a factor KAPPA of beta over its
    /// distance at x.
    fn update_duals(&mut self, ws: &Workspace, x_old: &[f64], x: &[f64]) {
        let n = x.len();
        let mut dl = vec![0.0; n];
        let mut du = vec![0.0; n];
        let mut alpha: f64 = 1.0;
        for j in (0..n).filter(|&j| !self.fixed[j]) {
            let (a, b) = (x_old[j] - ws.lower[j], ws.upper[j] - x_old[j]);
            let dx = x[j] - x_old[j];
            dl[j] = self.beta / a - self.zl[j] - self.zl[j] * dx / a;
            du[j] = self.beta / b - self.zu[j] + self.zu[j] * dx / b;
            for (z, dz) in [(self.zl[j], dl[j]), (self.zu[j], du[j])] {
                if dz < 0.0 {
                    alpha = alpha.min(TO_BOUNDARY * z / -dz);
                }
            }
        }
        for j in (0..n).filter(|&j| !self.fixed[j]) {
            let (a, b) = (x[j] - ws.lower[j], ws.upper[j] - x[j]);
            let zl = self.zl[j] + alpha * dl[j];
            let zu = self.zu[j] + alpha * du[j];
            self.zl[j] = zl.max(self.beta / (KAPPA * a)).min(KAPPA * self.beta / a);
            self.zu[j] = zu.max(self.beta / (KAPPA * b)).min(KAPPA * self.beta / b);
        }
    }

    /// -beta sum_j [ln(x_j - l_j) + ln(u_j - x_j)].
    fn value(&self, ws: &Workspace, x: &[f64]) -> f64 {
        let mut s = 0.0;
        for j in 0..x.len() {
            if !self.fixed[j] {
                s += ((x[j] - ws.lower[j]) * (ws.upper[j] - x[j])).ln();
            }
        }
        -self.beta * s
    }
}

/// Move the iterate strictly inside the box (MARGIN of each width; zero-width coordinates on
/// their bound) and build the barrier at smoothing mu, weight beta = BETA_RATIO mu m / n, both
/// shrinking by `shrink` per stage.
pub(super) fn enter(ws: &Workspace, it: &mut Iterate, mu: f64, shrink: f64) -> Barrier {
    let n = it.x.len();
    let mut fixed = vec![false; n];
    for j in 0..n {
        let (l, u) = (ws.lower[j], ws.upper[j]);
        let w = u - l;
        let (lo, hi) = (l + MARGIN * w, u - MARGIN * w);
        if !(lo > l && hi < u && lo < hi) {
            fixed[j] = true;
            it.x[j] = it.x[j].max(l).min(u);
            continue;
        }
        it.x[j] = it.x[j].max(lo).min(hi);
    }
    ws.pb.residuals(&it.x, &mut it.r);
    it.f = norm_sum(&it.r);
    let beta = BETA_RATIO * mu * ws.pb.n_terms() as f64 / n.max(1) as f64;
    let mut bar = Barrier {
        mu,
        beta,
        shrink,
        fixed,
        grad: vec![0.0; n],
        diag: vec![0.0; n],
        zl: vec![0.0; n],
        zu: vec![0.0; n],
    };
    for j in (0..n).filter(|&j| !bar.fixed[j]) {
        bar.zl[j] = beta / (it.x[j] - ws.lower[j]);
        bar.zu[j] = beta / (ws.upper[j] - it.x[j]);
    }
    bar
}

/// Run barrier Newton from the (interior) iterate until `done(best.f, best.lb)`, `max_steps`
/// steps, or mu below `mu_min`; returns the steps taken.
pub(super) fn run(
    ws: &mut Workspace,
    it: &mut Iterate,
    bar: &mut Barrier,
    (max_steps, mu_min): (usize, f64),
    best: &mut Best,
    sc: &mut Scratch,
    done: &dyn Fn(f64, f64) -> bool,
) -> usize {
    let n = it.x.len();
    let mut steps = 0;
    loop {
        let mu = bar.mu;
        certificates(ws, it, mu, best, sc);
        best.offer_point(it);
        if done(best.f, best.lb) || steps >= max_steps || mu < mu_min {
            return steps;
        }
        steps += 1;
        bar.at(ws, &it.x);
        for j in 0..n {
            sc.active[j] = bar.fixed[j];
        }
        ws.set_skip(&sc.active);
        let r = &it.r;
        ws.assemble(|k| Some(hessian_block(r[k], mu)));
        ws.add_diagonal(&bar.diag);
        if !ws.factorise(SHIFT) {
            return steps;
        }
        let decrement = direction(ws, it, bar, mu, sc);
        dual_newton_certificate(ws, it, mu, best, sc);
        let moved = line_search(ws, it, bar, mu, sc);
        if moved {
            bar.update_duals(ws, &it.x_new, &it.x);
        }
        if !moved || decrement <= STAGE_TOL * bar.beta {
            bar.mu *= bar.shrink;
            bar.beta *= bar.shrink;
        }
    }
}

/// The Newton direction d = -(H + D)^-1 (g + grad barrier) on the barrier's coordinates, with
/// iterative refinement; returns the decrement -(g + grad barrier).d.
fn direction(ws: &Workspace, it: &Iterate, bar: &Barrier, mu: f64, sc: &mut Scratch) -> f64 {
    let n = sc.g.len();
    let [rhs, sol, buf] = &mut sc.vn;
    let grad = |j: usize| if bar.fixed[j] { 0.0 } else { sc.g[j] + bar.grad[j] };
    for j in 0..n {
        rhs[j] = -grad(j);
    }
    ws.solve(rhs, &mut sc.d, buf);
    for _ in 0..REFINE_STEPS {
        let [av, w] = &mut sc.vm;
        hessian_apply(ws.pb, &it.r, mu, &sc.d, av, w, sol);
        for j in 0..n {
            rhs[j] = if bar.fixed[j] { 0.0 } else { -grad(j) - sol[j] - bar.diag[j] * sc.d[j] };
        }
        ws.solve(rhs, sol, buf);
        for j in 0..n {
            sc.d[j] += sol[j];
        }
    }
    -(0..n).map(|j| grad(j) * sc.d[j]).sum::<f64>()
}

/// Armijo search on Phi along x + alpha d, alpha at most TO_BOUNDARY of the way to the nearest
/// bound; moves the iterate and returns true on success.
fn line_search(ws: &Workspace, it: &mut Iterate, bar: &Barrier, mu: f64, sc: &Scratch) -> bool {
    let n = it.x.len();
    let mut alpha: f64 = 1.0;
    for j in (0..n).filter(|&j| !bar.fixed[j] && sc.d[j] != 0.0) {
        let d = sc.d[j];
        let room = if d < 0.0 { it.x[j] - ws.lower[j] } else { ws.upper[j] - it.x[j] };
        alpha = alpha.min(TO_BOUNDARY * room / d.abs());
    }
    let phi = smooth(&it.r, mu) + bar.value(ws, &it.x);
    let slope: f64 = (0..n).map(|j| (sc.g[j] + bar.grad[j]) * sc.d[j]).sum();
    if slope.is_nan() || slope >= 0.0 {
        return false;
    }
    for _ in 0..40 {
        for j in 0..n {
            it.x_new[j] = it.x[j] + alpha * sc.d[j];
        }
        ws.pb.residuals(&it.x_new, &mut it.r_new);
        let phi_new = smooth(&it.r_new, mu) + bar.value(ws, &it.x_new);
        if phi_new <= phi + 1e-4 * alpha * slope {
            return it.accept_trial();
        }
        alpha *= 0.5;
    }
    false
}

#[cfg(test)]
mod tests {
    use super::super::tests::random_plain;
    use super::super::{certify_dual, norm_sum, Best, Iterate, Scratch, Workspace};
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Boxes of half-width 1e-4 around a random start, tiny against residuals of ~1: f is almost
    /// linear over the box and most coordinates end on a bound, the case the barrier is for. The
    /// barrier path alone certifies the optimum to 1e-9 relative, its point in the box, its f
    /// below the start's; and most coordinates end within 1e-3 of the width of a bound.
    #[test]
    fn barrier_path_certifies_a_nearly_linear_box() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for case in 0..6 {
            let n_points = rng.gen_range(3..8);
            let pb = random_plain(&mut rng, n_points, 4 * n_points, 3);
            let n = 3 * n_points;
            let x0: Vec<f64> = (0..n).map(|_| rng.gen_range(-1.0..1.0)).collect();
            let lower: Vec<f64> = x0.iter().map(|v| v - 1e-4).collect();
            let mut upper: Vec<f64> = x0.iter().map(|v| v + 1e-4).collect();
            upper[0] = lower[0]; // a coordinate of zero width stays put
            let mut ws = Workspace::new(&pb, &lower, &upper).unwrap();
            let m = pb.data.len();
            let mut r = vec![[0.0; 3]; m];
            let mut x = x0.clone();
            x[0] = lower[0];
            ws.pb.residuals(&x, &mut r);
            let f = norm_sum(&r);
            let mut best = Best { x: x.clone(), f, lb: f64::NEG_INFINITY, y: vec![[0.0; 3]; m] };
            let mut it = Iterate { x_new: vec![0.0; n], r_new: vec![[0.0; 3]; m], x, r, f };
            let mut sc = Scratch::new(n, m);
            let mut bar = enter(&ws, &mut it, f / m as f64, 0.1);
            let done = |f: f64, lb: f64| f - lb <= 1e-9 * f;
            let steps = run(&mut ws, &mut it, &mut bar, (300, 1e-15), &mut best, &mut sc, &done);
            let (fc, lb) = certify_dual(&pb, &lower, &upper, &best.x, &best.y);
            assert!(fc - lb <= 1e-9 * fc && fc <= f, "case {case}: {fc} {lb} after {steps}");
            assert!(best.x.iter().zip(&lower).zip(&upper).all(|((v, l), u)| v >= l && v <= u));
            assert_eq!(best.x[0], lower[0]);
            let near = (0..n)
                .filter(|&j| (best.x[j] - lower[j]).min(upper[j] - best.x[j]) <= 2e-7)
                .count();
            assert!(2 * near > n, "case {case}: {near} of {n} near a bound");
        }
    }
}
