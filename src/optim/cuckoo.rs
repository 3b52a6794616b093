//! Cuckoo search (Yang & Deb 2009) as seed 003 uses it: each generation every nest makes a new
//! solution by a Levy flight, x + alpha L (x - best) N(0,1), with L from Mantegna's algorithm
//! (beta = 1.5) and alpha = 0.01, kept if not worse than that nest; then each coordinate of each
//! nest is, with probability pa, moved by r (x_perm1 - x_perm2) (one uniform r per nest), again
//! kept if not worse. Two evaluations per nest and generation. ICSA (seed 003, after Valian et
//! al. 2011) lets pa fall linearly from pa_max = 0.5 to pa_min = 0.1 over the generations.

use super::problem::{clamp_into, initial_population, Budget, Optimiser, Problem, RunResult, Tracker};
use rand::seq::SliceRandom;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::Deserialize;

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Cuckoo {
    /// Discovery rate pa (CSA); ICSA's start value when `pa_min` is set.
    pub pa: f64,
    /// ICSA: pa falls linearly from `pa` to `pa_min` over the generations.
    pub pa_min: Option<f64>,
    /// Step scale alpha.
    pub step: f64,
    /// Levy exponent beta.
    pub beta: f64,
}

impl Cuckoo {
    pub fn csa() -> Cuckoo {
        Cuckoo { pa: 0.25, pa_min: None, step: 0.01, beta: 1.5 }
    }

    pub fn icsa() -> Cuckoo {
        Cuckoo { pa: 0.5, pa_min: Some(0.1), step: 0.01, beta: 1.5 }
    }

    pub fn validate(&self, key: &str) -> Result<(), String> {
        if !(0.0..=1.0).contains(&self.pa) || self.pa_min.map(|p| !(0.0..=1.0).contains(&p)).unwrap_or(false) {
            return Err(format!("{key}.pa must be in [0,1]"));
        }
        if !(self.beta > 0.0 && self.beta <= 2.0) {
            return Err(format!("{key}.beta must be in (0,2], got {}", self.beta));
        }
        if !(self.step > 0.0) {
            return Err(format!("{key}.step must be positive, got {}", self.step));
        }
        Ok(())
    }

    /// Mantegna's sigma_u for the Levy exponent beta.
    pub fn mantegna_sigma(beta: f64) -> f64 {
        let g = |x: f64| statrs::function::gamma::gamma(x);
        ((g(1.0 + beta) * (std::f64::consts::PI * beta / 2.0).sin()) / (g((1.0 + beta) / 2.0) * beta * 2f64.powf((beta - 1.0) / 2.0))).powf(1.0 / beta)
    }
}

impl Default for Cuckoo {
    fn default() -> Self {
        Cuckoo::csa()
    }
}

impl Optimiser for Cuckoo {
    fn name(&self) -> &'static str {
        if self.pa_min.is_some() {
            "icsa"
        } else {
            "csa"
        }
    }

    fn run(&self, problem: &dyn Problem, budget: &Budget, rng: &mut ChaCha8Rng) -> RunResult {
        let n = problem.dim();
        let np = budget.population;
        let (lo, hi) = problem.bounds();
        let sigma = Cuckoo::mantegna_sigma(self.beta);
        let mut tracker = Tracker::new(problem, (np * (2 * budget.generations + 1)) as u64);
        let mut nest = initial_population(problem, budget, rng);
        let mut fit: Vec<f64> = nest.iter().map(|x| tracker.eval(x)).collect();
        let initial_best = tracker.best_fitness;
        let mut new = vec![0.0; n];
        let mut perm1: Vec<usize> = (0..np).collect();
        let mut perm2: Vec<usize> = (0..np).collect();
        for gen in 0..budget.generations {
            let best = tracker.best_x.clone();
            for i in 0..np {
                for d in 0..n {
                    let u: f64 = rng.sample::<f64, _>(StandardNormal) * sigma;
                    let v: f64 = rng.sample(StandardNormal);
                    let levy = u / v.abs().powf(1.0 / self.beta);
                    let z: f64 = rng.sample(StandardNormal);
                    new[d] = nest[i][d] + self.step * levy * (nest[i][d] - best[d]) * z;
                }
                clamp_into(&mut new, lo, hi);
                let f = tracker.eval(&new);
                if f <= fit[i] {
                    nest[i].copy_from_slice(&new);
                    fit[i] = f;
                }
            }
            let pa = match self.pa_min {
                Some(min) if budget.generations > 1 => self.pa - (self.pa - min) * gen as f64 / (budget.generations - 1) as f64,
                _ => self.pa,
            };
            perm1.shuffle(rng);
            perm2.shuffle(rng);
            for i in 0..np {
                let r: f64 = rng.gen();
                let (a, b) = (&nest[perm1[i]], &nest[perm2[i]]);
                for d in 0..n {
                    let moved = rng.gen::<f64>() < pa;
                    new[d] = nest[i][d] + if moved { r * (a[d] - b[d]) } else { 0.0 };
                }
                clamp_into(&mut new, lo, hi);
                let f = tracker.eval(&new);
                if f <= fit[i] {
                    nest[i].copy_from_slice(&new);
                    fit[i] = f;
                }
            }
        }
        tracker.finish(initial_best)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cuckoo_contract_and_mantegna_sigma() {
        super::super::problem::tests::check_optimiser(&Cuckoo::csa(), 40);
        super::super::problem::tests::check_optimiser(&Cuckoo::icsa(), 40);
        // sigma_u(1.5) = 0.6966 (Yang 2010, Nature-Inspired Metaheuristic Algorithms).
        assert!((Cuckoo::mantegna_sigma(1.5) - 0.696574).abs() < 1e-5);
    }
}
