//! Differential evolution DE/rand/1/bin (thesis 6.2.4.2; SPEC 4): for each target, a mutant
//! x_r1 + F (x_r2 - x_r3) with r1, r2, r3 distinct and not the target; binomial crossover takes a
//! gene from the mutant with probability CR (and always at one random position j_rand); the trial
//! replaces the target if f(trial) <= f(target); generations are synchronous. Trials are clamped
//! to the bounds. Table 6.1 gives CR = 0.8, F = 0.3 (the default); the prose's F = 0.01, CR = 0.8
//! reading is `f = 0.01`.
//!
//! Crossover draws 32 random bits per gene (two genes per 64-bit draw): a gene comes from the
//! mutant when its bits are below CR * 2^32, a Bernoulli(CR) draw with CR rounded to 2^-32.

use super::problem::{clamp_into, initial_population, Budget, Optimiser, Problem, RunResult, Tracker};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct De {
    pub cr: f64,
    pub f: f64,
}

impl Default for De {
    fn default() -> Self {
        De { cr: 0.8, f: 0.3 }
    }
}

impl De {
    pub fn validate(&self) -> Result<(), String> {
        if !(0.0..=1.0).contains(&self.cr) {
            return Err(format!("de.cr must be in [0,1], got {}", self.cr));
        }
        if !(self.f > 0.0 && self.f <= 2.0) {
            return Err(format!("de.f must be in (0,2], got {}", self.f));
        }
        Ok(())
    }
}

impl Optimiser for De {
    fn name(&self) -> &'static str {
        "de"
    }

    fn run(&self, problem: &dyn Problem, budget: &Budget, rng: &mut ChaCha8Rng) -> RunResult {
        let n = problem.dim();
        let np = budget.population;
        let (lo, hi) = problem.bounds();
        let mut tracker = Tracker::new(problem, (np * (budget.generations + 1)) as u64);
        let mut pop = initial_population(problem, budget, rng);
        let mut fit: Vec<f64> = pop.iter().map(|x| tracker.eval(x)).collect();
        let initial_best = tracker.best_fitness;
        if np < 4 {
            return tracker.finish(initial_best);
        }
        let threshold = (self.cr * 4_294_967_296.0).min(4_294_967_296.0) as u64;
        let mut next = pop.clone();
        let mut next_fit = fit.clone();
        let mut trial = vec![0.0; n];
        for _ in 0..budget.generations {
            for i in 0..np {
                let pick = |rng: &mut ChaCha8Rng, not: &[usize]| loop {
                    let r = rng.gen_range(0..np);
                    if !not.contains(&r) {
                        break r;
                    }
                };
                let r1 = pick(rng, &[i]);
                let r2 = pick(rng, &[i, r1]);
                let r3 = pick(rng, &[i, r1, r2]);
                let (a, b, c, target) = (&pop[r1], &pop[r2], &pop[r3], &pop[i]);
                let jrand = rng.gen_range(0..n);
                let mut bits = 0u64;
                for g in 0..n {
                    let u = if g % 2 == 0 {
                        bits = rng.gen();
                        bits >> 32
                    } else {
                        bits & 0xffff_ffff
                    };
                    trial[g] = if u < threshold || g == jrand { a[g] + self.f * (b[g] - c[g]) } else { target[g] };
                }
                clamp_into(&mut trial, lo, hi);
                let ft = tracker.eval(&trial);
                if ft <= fit[i] {
                    next[i].copy_from_slice(&trial);
                    next_fit[i] = ft;
                } else {
                    next[i].copy_from_slice(&pop[i]);
                    next_fit[i] = fit[i];
                }
            }
            std::mem::swap(&mut pop, &mut next);
            std::mem::swap(&mut fit, &mut next_fit);
        }
        tracker.finish(initial_best)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn de_contract() {
        super::super::problem::tests::check_optimiser(&super::De::default(), 20);
        assert!(super::De { cr: 1.5, ..Default::default() }.validate().unwrap_err().contains("de.cr"));
    }
}
