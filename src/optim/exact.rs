//! The exact optimum of the control-net problem inside its box, with a certificate.
//!
//! f(x) = sum_k |A_k x - d_k| is convex; unconstrained it is ill-posed for near-square nets
//! (condition number ~1e7 for an 18x18 net on a 20x20 grid), hence the box l <= x <= u. Solver:
//! the primal-dual hybrid gradient method (Chambolle & Pock 2011) on the saddle problem
//! min_x max_{|y_k| <= 1} sum_k y_k . (A_k x - d_k) + box(x), with fixed balanced steps. Its
//! dual iterate is always feasible, so every iterate yields a proven lower bound,
//! min_box f >= sum_k y_k . r_k(0) + sum_j min(g_j l_j, g_j u_j), g = sum_k A_k^T y_k, and the
//! reported gap f(x) - bound is stated, never assumed.

use super::control_net::ControlNetProblem;
use super::problem::Problem;

/// A certified solution.
#[derive(Debug, Clone, PartialEq)]
pub struct ExactResult {
    pub x: Vec<f64>,
    /// f at x: an upper bound of the optimum.
    pub f: f64,
    /// A proven lower bound of the optimum over the box.
    pub lower_bound: f64,
    /// f - lower_bound.
    pub gap: f64,
    pub iterations: usize,
}

fn norm(v: &[f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// The bound of a feasible dual point y (every |y_k| <= 1).
fn dual_bound(p: &ControlNetProblem, y: &[[f64; 3]], r0: &[[f64; 3]], g: &mut [f64]) -> f64 {
    let (lo, hi) = p.bounds();
    p.apply_transpose(y, g);
    let constant: f64 = y.iter().zip(r0).map(|(a, b)| a[0] * b[0] + a[1] * b[1] + a[2] * b[2]).sum();
    constant + g.iter().zip(lo.iter().zip(hi)).map(|(&gj, (&l, &u))| (gj * l).min(gj * u)).sum::<f64>()
}

/// The dual point a primal iterate suggests: y_k = r_k / |r_k|; a term whose residual is (nearly)
/// zero is non-smooth there, so its y_k is chosen in the unit ball to cancel, in least squares,
/// what the other terms leave of the gradient on its control points.
fn primal_dual_point(p: &ControlNetProblem, rows: &[(Vec<(u32, f64)>, [f64; 3])], r: &[[f64; 3]], g: &mut [f64]) -> Vec<[f64; 3]> {
    let scale = r.iter().map(norm).sum::<f64>() / r.len().max(1) as f64;
    let small = |v: &[f64; 3]| norm(v) <= 1e-6 * scale;
    let mut y: Vec<[f64; 3]> = r.iter().map(|v| if small(v) { [0.0; 3] } else { let nn = norm(v); [v[0] / nn, v[1] / nn, v[2] / nn] }).collect();
    p.apply_transpose(&y, g);
    for (k, v) in r.iter().enumerate() {
        if !small(v) {
            continue;
        }
        let entries = &rows[k].0;
        let ww: f64 = entries.iter().map(|e| e.1 * e.1).sum();
        if ww == 0.0 {
            continue;
        }
        let mut yk = [0.0; 3];
        for &(c, w) in entries {
            for d in 0..3 {
                yk[d] -= w * g[3 * c as usize + d] / ww;
            }
        }
        let nn = norm(&yk).max(1.0);
        y[k] = [yk[0] / nn, yk[1] / nn, yk[2] / nn];
    }
    y
}

/// Solve to a relative gap `tol` or `max_iterations` iterations.
pub fn solve(p: &ControlNetProblem, tol: f64, max_iterations: usize) -> ExactResult {
    let n = p.dim();
    let (lo, hi) = p.bounds();
    let (lo, hi) = (lo.to_vec(), hi.to_vec());
    let terms = p.terms();
    let rows = p.rows();
    let mut r0 = Vec::with_capacity(terms);
    p.residuals(&vec![0.0; n], &mut r0);
    // ||A||^2 by power iteration on A^T A (A v = r(v) - r(0)).
    let mut v: Vec<f64> = (0..n).map(|k| 1.0 + (k % 5) as f64 * 0.1).collect();
    let (mut av, mut g) = (Vec::new(), vec![0.0; n]);
    let mut lam = 1.0;
    for _ in 0..60 {
        let nv = v.iter().map(|a| a * a).sum::<f64>().sqrt();
        v.iter_mut().for_each(|a| *a /= nv);
        p.residuals(&v, &mut av);
        let lin: Vec<[f64; 3]> = av.iter().zip(&r0).map(|(a, b)| [a[0] - b[0], a[1] - b[1], a[2] - b[2]]).collect();
        p.apply_transpose(&lin, &mut g);
        lam = g.iter().zip(&v).map(|(a, b)| a * b).sum::<f64>();
        v.copy_from_slice(&g);
    }
    let op_norm = (lam * 1.02).sqrt();
    let mut x: Vec<f64> = p.initial_point().iter().zip(lo.iter().zip(&hi)).map(|(&a, (&l, &u))| a.clamp(l, u)).collect();
    let mut r = Vec::with_capacity(terms);
    p.residuals(&x, &mut r);
    let mut y: Vec<[f64; 3]> = r.iter().map(|v| { let nn = norm(v); if nn > 0.0 { [v[0] / nn, v[1] / nn, v[2] / nn] } else { [0.0; 3] } }).collect();
    let mut best_f = r.iter().map(norm).sum::<f64>();
    let mut best_x = x.clone();
    let mut bound = dual_bound(p, &y, &r0, &mut g);
    // Steps with tau * sigma * ||A||^2 = 0.99, balanced by the scale of f per variable.
    let ratio = best_f.max(1e-12) / n as f64;
    let mut x_bar = x.clone();
    let mut x_prev = x.clone();
    let mut it = 0;
    while it < max_iterations && best_f - bound > tol * best_f.abs() {
        it += 1;
        let tau = ratio.sqrt() * 0.99 / op_norm;
        let sigma = 0.99 / (op_norm * ratio.sqrt());
        // Dual ascent: y <- proj_ball(y + sigma (A x_bar - d)).
        p.residuals(&x_bar, &mut r);
        for (yk, rk) in y.iter_mut().zip(&r) {
            let t = [yk[0] + sigma * rk[0], yk[1] + sigma * rk[1], yk[2] + sigma * rk[2]];
            let nn = norm(&t).max(1.0);
            *yk = [t[0] / nn, t[1] / nn, t[2] / nn];
        }
        // Primal descent: x <- proj_box(x - tau A^T y).
        p.apply_transpose(&y, &mut g);
        x_prev.copy_from_slice(&x);
        for j in 0..n {
            x[j] = (x[j] - tau * g[j]).clamp(lo[j], hi[j]);
            x_bar[j] = 2.0 * x[j] - x_prev[j];
        }
        if it % 25 == 0 || it == max_iterations {
            p.residuals(&x, &mut r);
            let f = r.iter().map(norm).sum::<f64>();
            if f < best_f {
                best_f = f;
                best_x.copy_from_slice(&x);
            }
            let b = dual_bound(p, &y, &r0, &mut g);
            // Also the dual point the primal iterate suggests, when it is better.
            let bp = dual_bound(p, &primal_dual_point(p, &rows, &r, &mut g), &r0, &mut g);
            bound = bound.max(b).max(bp);
        }
    }
    ExactResult { gap: best_f - bound, x: best_x, f: best_f, lower_bound: bound, iterations: it }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::control_net::tests::problem;
    use crate::optim::{de::De, ga::Ga, pso::Pso, Budget, Optimiser};
    use rand::SeedableRng;

    #[test]
    fn certified_and_below_every_optimiser() {
        let pr = problem(12, 10, 8, 7);
        let ex = solve(&pr, 1e-6, 40000);
        eprintln!("{} iterations, f {}, bound {}, gap {}", ex.iterations, ex.f, ex.lower_bound, ex.gap);
        assert!(ex.lower_bound <= ex.f);
        assert!(ex.f <= pr.fitness(pr.initial_point()) + 1e-12);
        let budget = Budget { generations: 100, population: 20, init_range: 1e-3 };
        for opt in [&Ga::default() as &dyn Optimiser, &De::default(), &Pso::default()] {
            let run = opt.run(&pr, &budget, &mut rand_chacha::ChaCha8Rng::seed_from_u64(1));
            assert!(run.best_fitness >= ex.lower_bound, "{} beat the certified bound", opt.name());
        }
        assert!(ex.gap <= 1e-3 * ex.f, "gap {} of f {}", ex.gap, ex.f);
    }
}
