//! Steady-state genetic algorithm (thesis 6.2.4.1, Table 6.1; SPEC 4): two parents by tournaments
//! of 4, uniform crossover (each gene swapped with probability 0.5) applied with probability Pc,
//! uniform mutation with probability Pm per gene (a mutated gene becomes x0 + U[-r, r]), and each
//! offspring replaces its parent only if strictly better. Two evaluations per generation.

use super::problem::{clamp_into, geometric_skip, initial_population, Budget, Optimiser, Problem, RunResult, Tracker};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Ga {
    /// Crossover probability Pc.
    pub pc: f64,
    /// Mutation probability Pm per gene.
    pub pm: f64,
    /// Tournament size.
    pub tournament: usize,
}

impl Default for Ga {
    fn default() -> Self {
        Ga { pc: 0.7, pm: 0.01, tournament: 4 }
    }
}

impl Ga {
    pub fn validate(&self) -> Result<(), String> {
        if !(0.0..=1.0).contains(&self.pc) {
            return Err(format!("ga.pc must be in [0,1], got {}", self.pc));
        }
        if !(0.0..=1.0).contains(&self.pm) {
            return Err(format!("ga.pm must be in [0,1], got {}", self.pm));
        }
        if self.tournament == 0 {
            return Err("ga.tournament must be at least 1".into());
        }
        Ok(())
    }

    fn tournament(&self, fit: &[f64], rng: &mut ChaCha8Rng) -> usize {
        let mut best = rng.gen_range(0..fit.len());
        for _ in 1..self.tournament {
            let c = rng.gen_range(0..fit.len());
            if fit[c] < fit[best] {
                best = c;
            }
        }
        best
    }
}

impl Optimiser for Ga {
    fn name(&self) -> &'static str {
        "ga"
    }

    fn run(&self, problem: &dyn Problem, budget: &Budget, rng: &mut ChaCha8Rng) -> RunResult {
        let n = problem.dim();
        let (lo, hi) = problem.bounds();
        let x0 = problem.initial_point();
        let mut tracker = Tracker::new(problem, (budget.population + 2 * budget.generations) as u64);
        let mut pop = initial_population(problem, budget, rng);
        let mut fit: Vec<f64> = pop.iter().map(|x| tracker.eval(x)).collect();
        let initial_best = tracker.best_fitness;
        let ln_keep = (1.0 - self.pm).ln();
        let (mut c1, mut c2) = (vec![0.0; n], vec![0.0; n]);
        for _ in 0..budget.generations {
            let p1 = self.tournament(&fit, rng);
            let p2 = self.tournament(&fit, rng);
            c1.copy_from_slice(&pop[p1]);
            c2.copy_from_slice(&pop[p2]);
            if rng.gen::<f64>() < self.pc {
                let mut bits = 0u64;
                for g in 0..n {
                    if g % 64 == 0 {
                        bits = rng.gen();
                    }
                    if bits & 1 == 1 {
                        std::mem::swap(&mut c1[g], &mut c2[g]);
                    }
                    bits >>= 1;
                }
            }
            for child in [&mut c1, &mut c2] {
                let mut g = geometric_skip(rng, ln_keep);
                while g < n {
                    child[g] = x0[g] + budget.init_range * (2.0 * rng.gen::<f64>() - 1.0);
                    g = g.saturating_add(1).saturating_add(geometric_skip(rng, ln_keep));
                }
                clamp_into(child, lo, hi);
            }
            let f1 = tracker.eval(&c1);
            if f1 < fit[p1] {
                pop[p1].copy_from_slice(&c1);
                fit[p1] = f1;
            }
            let f2 = tracker.eval(&c2);
            if f2 < fit[p2] {
                pop[p2].copy_from_slice(&c2);
                fit[p2] = f2;
            }
        }
        tracker.finish(initial_best)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn ga_contract() {
        super::super::problem::tests::check_optimiser(&super::Ga { pm: 0.1, ..Default::default() }, 2);
        assert!(super::Ga { pc: 1.5, ..Default::default() }.validate().unwrap_err().contains("ga.pc"));
    }
}
