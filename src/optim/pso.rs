//! Particle swarm optimisation with Clerc's constriction (thesis 6.2.4.3; SPEC 4):
//! v <- K (v + c1 r1 (p_i - x) + c2 r2 (g - x)), K = 0.729, c1 = c2 = 2.05, r1, r2 uniform per
//! coordinate; v0 = 0; |v| clamped to half the range of each coordinate; positions clamped to the
//! bounds; global-best topology, personal bests updated when strictly better.

use super::problem::{initial_population, two_uniforms, Budget, Optimiser, Problem, RunResult, Tracker};
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Pso {
    /// Constriction factor K.
    pub k: f64,
    pub c1: f64,
    pub c2: f64,
}

impl Default for Pso {
    fn default() -> Self {
        Pso { k: 0.729, c1: 2.05, c2: 2.05 }
    }
}

impl Pso {
    pub fn validate(&self) -> Result<(), String> {
        if !(self.k > 0.0 && self.k <= 1.0) {
            return Err(format!("pso.k must be in (0,1], got {}", self.k));
        }
        if self.c1 < 0.0 || self.c2 < 0.0 {
            return Err("pso.c1 and pso.c2 must be non-negative".into());
        }
        Ok(())
    }
}

impl Optimiser for Pso {
    fn name(&self) -> &'static str {
        "pso"
    }

    fn run(&self, problem: &dyn Problem, budget: &Budget, rng: &mut ChaCha8Rng) -> RunResult {
        let n = problem.dim();
        let np = budget.population;
        let (lo, hi) = problem.bounds();
        let vmax: Vec<f64> = lo.iter().zip(hi).map(|(l, h)| 0.5 * (h - l)).collect();
        let mut tracker = Tracker::new(problem, (np * (budget.generations + 1)) as u64);
        let mut x = initial_population(problem, budget, rng);
        let mut v = vec![vec![0.0; n]; np];
        let mut pbest = x.clone();
        let mut pfit: Vec<f64> = x.iter().map(|p| tracker.eval(p)).collect();
        let initial_best = tracker.best_fitness;
        let mut g = pfit.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1)).map(|(i, _)| i).unwrap_or(0);
        let mut gbest = pbest[g].clone();
        let mut gfit = pfit[g];
        for _ in 0..budget.generations {
            for i in 0..np {
                let (xi, vi, pi) = (&mut x[i], &mut v[i], &pbest[i]);
                for d in 0..n {
                    let (r1, r2) = two_uniforms(rng);
                    let vel = self.k * (vi[d] + self.c1 * r1 * (pi[d] - xi[d]) + self.c2 * r2 * (gbest[d] - xi[d]));
                    vi[d] = vel.clamp(-vmax[d], vmax[d]);
                    xi[d] = (xi[d] + vi[d]).clamp(lo[d], hi[d]);
                }
                let f = tracker.eval(xi);
                if f < pfit[i] {
                    pfit[i] = f;
                    pbest[i].copy_from_slice(xi);
                    if f < gfit {
                        gfit = f;
                        g = i;
                        gbest.copy_from_slice(&pbest[g]);
                    }
                }
            }
        }
        tracker.finish(initial_best)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn pso_contract() {
        super::super::problem::tests::check_optimiser(&super::Pso::default(), 20);
        assert!(super::Pso { k: 0.0, ..Default::default() }.validate().unwrap_err().contains("pso.k"));
    }
}
