//! Differential evolution DE/rand/1/bin (Storn & Price 1997; thesis 6.2.4.2).
//!
//! For each target i in order: three distinct indices r1, r2, r3, all different from i, give the
//! mutant v = x_r1 + F (x_r2 - x_r3) (one fused multiply-add), clamped to the bounds; binomial
//! crossover builds the trial, each gene from the mutant with probability CR and at one uniformly
//! drawn position j_rand always; the trial replaces the target if f(trial) <= f(target).
//! Generations are synchronous (mutants are built from the population of the previous
//! generation). `population` evaluations per generation, `population * (1 + generations)` in all.
//!
//! Table 6.1 gives CR = 0.8, F = 0.3 (the default); the prose of 6.2.2 reads CR = 0.01,
//! F = 0.8 (`De::thesis_prose()`).
//!
//! Crossover: gene j of the trial is the mutant's when a 32-bit uniform h_j is below
//! floor(CR 2^32) (probability within 2^-32 of CR), drawn from four xoshiro256++ lanes seeded
//! from the run's stream ([`super::sampling::DeLanes`]; one step of the four gives the halves
//! for eight genes), so the mutant, the choices and the trial are one vectorised pass over the
//! genes ([`crate::simd::moves::de_trial`]); j_rand is drawn from the run's stream.

use super::aligned::Aligned;
use super::problem::{check_problem, Budget, Evaluator, Optimiser, Population, Problem, RunResult};
use super::sampling::{bernoulli_threshold_32, index, DeLanes};
use super::{check_range, OptimError};
use crate::simd::moves::{de_mutant_gene, de_trial, DeSources};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// DE parameters (defaults: thesis Table 6.1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct De {
    /// Crossover probability CR.
    pub cr: f64,
    /// Differential weight F.
    pub f: f64,
}

impl Default for De {
    fn default() -> De {
        De { cr: 0.8, f: 0.3 }
    }
}

impl De {
    /// The values read in the prose of thesis 6.2.2 (CR = 0.01, F = 0.8).
    pub fn thesis_prose() -> De {
        De { cr: 0.01, f: 0.8 }
    }

    pub fn validate(&self) -> Result<(), OptimError> {
        check_range("de.cr", self.cr, 0.0, 1.0)?;
        check_range("de.f", self.f, 0.0, 2.0)
    }
}

/// Three distinct indices in 0..n, all different from `i` (n >= 4).
#[inline]
fn three_others(i: usize, n: usize, rng: &mut ChaCha8Rng) -> (usize, usize, usize) {
    let mut pick = |taken: &[usize]| loop {
        let c = index(rng, n);
        if !taken.contains(&c) {
            return c;
        }
    };
    let r1 = pick(&[i]);
    let r2 = pick(&[i, r1]);
    let r3 = pick(&[i, r1, r2]);
    (r1, r2, r3)
}

impl Optimiser for De {
    fn validate(&self) -> Result<(), OptimError> {
        De::validate(self)
    }
    fn name(&self) -> &'static str {
        "de"
    }

    fn min_population(&self) -> super::problem::MinPopulation {
        super::problem::MinPopulation {
            n: 4,
            key: None,
            why: "DE/rand/1 draws three donors besides the target",
        }
    }

    fn run(
        &self,
        problem: &dyn Problem,
        budget: &Budget,
        rng: &mut ChaCha8Rng,
    ) -> Result<RunResult, OptimError> {
        self.validate()?;
        budget.validate(self.min_population().n)?;
        check_problem(problem)?;
        let d = problem.dim();
        let (lo, hi) = problem.bounds();
        let n = budget.population;
        let mut eval = Evaluator::new(problem, budget);
        let mut pop = Population::initial(problem, budget, &mut eval, rng);
        let initial_best = pop.best_fitness();
        let threshold = bernoulli_threshold_32(self.cr);
        let mut lanes = DeLanes::from_rng(rng);
        // Trial buffers: a rejected trial's buffer is reused by the next target, an accepted one
        // waits until the end of the generation (the population is still needed as donors) and
        // then swaps with its target. Only accepted trials occupy memory, which keeps the
        // working set near the population's size (cache).
        let mut spare: Vec<Aligned> = Vec::with_capacity(n + 1);
        let mut accepted: Vec<(usize, Aligned, f64)> = Vec::with_capacity(n);
        let mut t_buf = Aligned::zeros(d);
        let fw = self.f;
        for _ in 0..budget.generations {
            for i in 0..n {
                let (r1, r2, r3) = three_others(i, n, rng);
                let j_rand = index(rng, d);
                let (a, b, c, x) =
                    (&pop.x[r1][..d], &pop.x[r2][..d], &pop.x[r3][..d], &pop.x[i][..d]);
                let t = &mut t_buf[..d];
                de_trial(t, DeSources { a, b, c, x, lo, hi }, fw, &mut lanes, threshold);
                t[j_rand] =
                    de_mutant_gene(a[j_rand], b[j_rand], c[j_rand], fw, lo[j_rand], hi[j_rand]);
                let ft = eval.eval(t);
                if ft <= pop.f[i] {
                    let next = spare.pop().unwrap_or_else(|| Aligned::zeros(d));
                    accepted.push((i, std::mem::replace(&mut t_buf, next), ft));
                }
            }
            for (i, mut trial, ft) in accepted.drain(..) {
                std::mem::swap(&mut pop.x[i], &mut trial);
                pop.f[i] = ft;
                spare.push(trial);
            }
        }
        let best = pop.best();
        Ok(eval.finish(pop.x.swap_remove(best), initial_best))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::optimiser_tests::check;
    use rand::SeedableRng;

    #[test]
    fn de_passes_the_common_checks() {
        check(&De::default(), |b| b.population as u64 * (1 + b.generations));
        check(&De::thesis_prose(), |b| b.population as u64 * (1 + b.generations));
    }

    #[test]
    fn parameters_are_validated_by_key() {
        assert_eq!(
            De { cr: 1.5, f: 0.3 }.validate().unwrap_err().to_string(),
            "de.cr must be in [0,1], got 1.5"
        );
        assert!(De { cr: 0.5, f: -1.0 }.validate().unwrap_err().to_string().starts_with("de.f "));
        let p: De = toml::from_str("f = 0.8\ncr = 0.01").unwrap();
        assert_eq!(p, De::thesis_prose());
    }

    #[test]
    fn three_others_are_distinct_and_uniform() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let mut counts = [0usize; 6];
        for _ in 0..30_000 {
            let (a, b, c) = three_others(2, 6, &mut rng);
            assert!(a != b && b != c && a != c && a != 2 && b != 2 && c != 2);
            counts[a] += 1;
        }
        assert_eq!(counts[2], 0);
        for (k, &c) in counts.iter().enumerate().filter(|(k, _)| *k != 2) {
            assert!((c as f64 - 6000.0).abs() < 400.0, "index {k}: {c}");
        }
    }

    /// The crossover takes each gene from the mutant with probability CR (plus j_rand): measured
    /// on a problem whose population differs only in known ways.
    #[test]
    fn crossover_rate_is_cr() {
        struct Flat(Vec<f64>, Vec<f64>, Vec<f64>);
        impl Problem for Flat {
            fn dim(&self) -> usize {
                self.0.len()
            }
            fn initial_point(&self) -> &[f64] {
                &self.0
            }
            fn bounds(&self) -> (&[f64], &[f64]) {
                (&self.1, &self.2)
            }
            fn fitness(&self, x: &[f64]) -> f64 {
                // Accept every trial (<=) and count how many genes left x0.
                let _ = x;
                0.0
            }
        }
        for cr in [0.8, 0.01, 0.3, 0.0, 1.0] {
            let d = 2000;
            let p = Flat(vec![0.0; d], vec![-1.0; d], vec![1.0; d]);
            let de = De { cr, f: 0.5 };
            // One generation from a population spread by init_range: every trial is accepted, so
            // the new population's genes equal a mutant gene with probability CR (+1/d).
            let budget =
                Budget { generations: 1, population: 10, init_range: 0.5, trace_every_evals: 1000 };
            let mut rng = ChaCha8Rng::seed_from_u64(9);
            let init = {
                let mut r2 = rng.clone();
                let mut e = Evaluator::new(&p, &budget);
                Population::initial(&p, &budget, &mut e, &mut r2)
            };
            let out = de.run(&p, &budget, &mut rng).unwrap();
            // best_x is individual 0 (all fitness 0, first on ties), trial of target 0.
            let same = out.best_x.iter().zip(&init.x[0]).filter(|(a, b)| a == b).count();
            // CR = 0: the forced gene j_rand alone; CR = 1: every gene from the mutant.
            if cr == 0.0 || cr == 1.0 {
                assert_eq!(same, if cr == 0.0 { d - 1 } else { 0 }, "cr {cr}");
            }
            let frac_mutant = 1.0 - same as f64 / d as f64;
            let want = cr + (1.0 - cr) / d as f64;
            let sd = (want * (1.0 - want) / d as f64).sqrt();
            assert!((frac_mutant - want).abs() < 5.0 * sd + 1e-3, "cr {cr}: {frac_mutant}");
        }
    }
}
