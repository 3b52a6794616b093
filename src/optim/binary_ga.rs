//! Binary-coded generational GA of seed 004 (Chaurasiya & Agarwal 2013, Table I and section II.C):
//! every real decision variable is a `bits`-bit unsigned integer k mapped linearly onto its bounds,
//! x = lo + (hi - lo) k / (2^bits - 1) (plain binary, most significant bit first), so a run of
//! 2N variables is a string of 2N * bits bits (Table I: "10 x 2 x number of control points").
//!
//! One generation: the population is ranked (worst rank 0, best rank mu - 1; ties by index) and mu
//! parents are drawn with replacement with the linear-ranking probabilities of Eq. 10,
//! Pr(i) = (alpha + rank(i) / (mu - 1) (beta - alpha)) / mu, alpha = 2 - beta (beta = 2: the worst
//! is never drawn); consecutive parents are paired and, with probability `pc`, uniform crossover
//! swaps each bit between the two children with probability `swap`, else the children copy their
//! parents; every bit of every child is then flipped with probability `pm`. The children replace
//! the whole population. The paper names no elitism and its Table II best RMS rises between
//! generations (0.0179 at 200, 0.0187 at 300), so `elitism = 0` is the default; `elitism = e`
//! copies the e best parents over the e worst children. Every individual is evaluated once per
//! generation: `population * (generations + 1)` evaluations (the initial population included).
//! The initial population is uniformly random bits (the problem's start point is not used, and
//! neither is `Budget::init_range`).
//!
//! Random bits: one uniform per parent draw, one per crossover decision, 64-bit masks for the
//! uniform crossover when swap = 0.5 (else one uniform per bit), geometric skips for the mutation.

use super::problem::{check_problem, Budget, Evaluator, Optimiser, Problem, RunResult};
use super::sampling::{unit, BitPool, Geometric};
use super::{check_range, OptimError};
use rand::RngCore;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Binary GA parameters (defaults: the paper's Table I and Eq. 10).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BinaryGa {
    /// Bits per decision variable (Table I: 10).
    pub bits: u32,
    /// Probability that a pair of parents is crossed (Table I: "crossover rate 0.5").
    pub pc: f64,
    /// Per-bit swap probability of the uniform crossover ("both parents have an equal chance": 0.5).
    pub swap: f64,
    /// Per-bit flip probability (Table I: 0.01).
    pub pm: f64,
    /// Linear-ranking selective pressure beta in [1, 2] (Eq. 10; alpha = 2 - beta).
    pub beta: f64,
    /// Best parents copied over the worst children each generation (the paper: none).
    pub elitism: usize,
}

impl Default for BinaryGa {
    fn default() -> BinaryGa {
        BinaryGa { bits: 10, pc: 0.5, swap: 0.5, pm: 0.01, beta: 2.0, elitism: 0 }
    }
}

/// A run with the per-generation history the paper's Table II reads.
#[derive(Debug, Clone, PartialEq)]
pub struct BinaryGaRun {
    pub result: RunResult,
    /// Best fitness in the population at generation g (g = 0: the initial population).
    pub population_best: Vec<f64>,
    /// Best fitness seen up to and including generation g.
    pub best_so_far: Vec<f64>,
}

impl BinaryGaRun {
    /// The first generation at which the final best was reached.
    pub fn best_generation(&self) -> usize {
        let best = self.result.best_fitness;
        self.best_so_far.iter().position(|&f| f <= best).unwrap_or(0)
    }
}

impl BinaryGa {
    pub fn validate(&self) -> Result<(), OptimError> {
        if !(1..=32).contains(&self.bits) {
            return Err(OptimError::param(
                "binary_ga.bits",
                format!("must be in [1,32], got {}", self.bits),
            ));
        }
        check_range("binary_ga.pc", self.pc, 0.0, 1.0)?;
        check_range("binary_ga.swap", self.swap, 0.0, 1.0)?;
        check_range("binary_ga.pm", self.pm, 0.0, 1.0)?;
        check_range("binary_ga.beta", self.beta, 1.0, 2.0)?;
        Ok(())
    }

    /// Linear-ranking selection probabilities by rank (index 0 = worst), Eq. 10.
    pub fn rank_probabilities(&self, mu: usize) -> Vec<f64> {
        if mu == 1 {
            return vec![1.0];
        }
        let alpha = 2.0 - self.beta;
        (0..mu)
            .map(|r| (alpha + r as f64 / (mu - 1) as f64 * (self.beta - alpha)) / mu as f64)
            .collect()
    }

    /// Decode variable `j` of a chromosome (bits MSB first, packed 64 to a word).
    fn decode(&self, chrom: &[u64], lo: &[f64], hi: &[f64], x: &mut [f64]) {
        let b = self.bits as usize;
        let top = ((1u64 << self.bits) - 1) as f64;
        for (j, xj) in x.iter_mut().enumerate() {
            let mut k = 0u64;
            for t in j * b..(j + 1) * b {
                k = (k << 1) | ((chrom[t / 64] >> (t % 64)) & 1);
            }
            *xj = if hi[j] > lo[j] {
                (lo[j] + (hi[j] - lo[j]) * (k as f64 / top)).min(hi[j])
            } else {
                lo[j]
            };
        }
    }

    /// Uniform crossover with probability `pc` (each bit swapped with probability `swap`), or
    /// copies of the parents.
    fn crossover(
        &self,
        pa: &[u64],
        pb: &[u64],
        c1: &mut [u64],
        c2: &mut [u64],
        rng: &mut ChaCha8Rng,
    ) {
        let cross = unit(rng) < self.pc;
        for w in 0..pa.len() {
            let m = if !cross {
                0
            } else if self.swap == 0.5 {
                rng.next_u64()
            } else {
                (0..64).fold(0u64, |m, t| m | (((unit(rng) < self.swap) as u64) << t))
            };
            c1[w] = (pa[w] & !m) | (pb[w] & m);
            c2[w] = (pb[w] & !m) | (pa[w] & m);
        }
    }

    /// Elitism: the `elitism` best parents replace the worst children (`order` ranks the parents
    /// worst first, so the best are at its end).
    fn keep_elite(
        &self,
        pop: &[Vec<u64>],
        f: &[f64],
        order: &[usize],
        children: &mut [Vec<u64>],
        fc: &mut [f64],
    ) {
        if self.elitism == 0 {
            return;
        }
        let mu = pop.len();
        let mut child_order: Vec<usize> = (0..mu).collect();
        child_order.sort_by(|&a, &b| fc[b].total_cmp(&fc[a]).then(a.cmp(&b)));
        for e in 0..self.elitism {
            let (dst, src) = (child_order[e], order[mu - 1 - e]);
            children[dst].copy_from_slice(&pop[src]);
            fc[dst] = f[src];
        }
    }

    /// One run with its per-generation history.
    pub fn run_with_history(
        &self,
        problem: &dyn Problem,
        budget: &Budget,
        rng: &mut ChaCha8Rng,
    ) -> Result<BinaryGaRun, OptimError> {
        self.validate()?;
        budget.validate(2)?;
        check_problem(problem)?;
        if self.elitism >= budget.population {
            return Err(OptimError::param(
                "binary_ga.elitism",
                format!(
                    "must be below the population ({}), got {}",
                    budget.population, self.elitism
                ),
            ));
        }
        let d = problem.dim();
        let (lo, hi) = problem.bounds();
        let nbits = d * self.bits as usize;
        let words = nbits.div_ceil(64);
        let tail_mask =
            if nbits.is_multiple_of(64) { u64::MAX } else { (1u64 << (nbits % 64)) - 1 };
        let mu = budget.population;
        let mut eval = Evaluator::new(problem, budget);
        let mut x = vec![0.0; d];
        let mut best_x = vec![0.0; d];
        // The best individual so far (the first evaluated one until a finite value improves on it).
        let mut best_f: Option<f64> = None;
        let evaluate = |chrom: &[u64],
                        eval: &mut Evaluator,
                        x: &mut [f64],
                        best_x: &mut [f64],
                        best_f: &mut Option<f64>| {
            self.decode(chrom, lo, hi, x);
            let f = eval.eval(x);
            if best_f.is_none_or(|b| f < b) {
                *best_f = Some(f);
                best_x.copy_from_slice(x);
            }
            f
        };
        let mut pop: Vec<Vec<u64>> = (0..mu)
            .map(|_| {
                let mut c: Vec<u64> = (0..words).map(|_| rng.next_u64()).collect();
                if let Some(last) = c.last_mut() {
                    *last &= tail_mask;
                }
                c
            })
            .collect();
        let mut f: Vec<f64> =
            pop.iter().map(|c| evaluate(c, &mut eval, &mut x, &mut best_x, &mut best_f)).collect();
        let pop_best = |f: &[f64]| f.iter().cloned().fold(f64::INFINITY, f64::min);
        let initial_best = pop_best(&f);
        let mut population_best = vec![initial_best];
        let mut best_so_far = vec![eval.best()];
        let cumulative: Vec<f64> = self
            .rank_probabilities(mu)
            .iter()
            .scan(0.0, |s, p| {
                *s += p;
                Some(*s)
            })
            .collect();
        let mutation = Geometric::new(self.pm);
        let mut pool = BitPool::new();
        let mut order: Vec<usize> = (0..mu).collect();
        let mut children: Vec<Vec<u64>> = vec![vec![0u64; words]; mu];
        for _ in 0..budget.generations {
            // Ranks: worst first (rank 0); ties keep index order.
            order.sort_by(|&a, &b| f[b].total_cmp(&f[a]).then(a.cmp(&b)));
            let parents: Vec<usize> = (0..mu)
                .map(|_| {
                    let u = unit(rng) * cumulative[mu - 1];
                    order[cumulative.iter().position(|&c| u < c).unwrap_or(mu - 1)]
                })
                .collect();
            for pair in 0..mu.div_ceil(2) {
                let a = parents[2 * pair];
                if 2 * pair + 1 == mu {
                    children[2 * pair].copy_from_slice(&pop[a]);
                    continue;
                }
                let b = parents[2 * pair + 1];
                let (left, right) = children.split_at_mut(2 * pair + 1);
                self.crossover(&pop[a], &pop[b], &mut left[2 * pair], &mut right[0], rng);
            }
            for c in children.iter_mut() {
                mutation.for_each(nbits, &mut pool, rng, |t| c[t / 64] ^= 1u64 << (t % 64));
            }
            let mut fc: Vec<f64> = children
                .iter()
                .map(|c| evaluate(c, &mut eval, &mut x, &mut best_x, &mut best_f))
                .collect();
            self.keep_elite(&pop, &f, &order, &mut children, &mut fc);
            std::mem::swap(&mut pop, &mut children);
            std::mem::swap(&mut f, &mut fc);
            population_best.push(pop_best(&f));
            best_so_far.push(eval.best());
        }
        let result = eval.finish(best_x, initial_best);
        Ok(BinaryGaRun { result, population_best, best_so_far })
    }
}

impl Optimiser for BinaryGa {
    fn validate(&self) -> Result<(), OptimError> {
        BinaryGa::validate(self)
    }
    fn name(&self) -> &'static str {
        "binary_ga"
    }

    fn min_population(&self) -> super::problem::MinPopulation {
        if self.elitism >= 2 {
            super::problem::MinPopulation {
                n: self.elitism + 1,
                key: Some("elitism"),
                why: "the elite parents must leave room for a child",
            }
        } else {
            super::problem::MinPopulation { n: 2, key: None, why: "rank selection needs two ranks" }
        }
    }

    fn run(
        &self,
        problem: &dyn Problem,
        budget: &Budget,
        rng: &mut ChaCha8Rng,
    ) -> Result<RunResult, OptimError> {
        self.run_with_history(problem, budget, rng).map(|r| r.result)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::optimiser_tests::check;
    use crate::optim::problem::tests::Sphere;
    use rand::SeedableRng;

    #[test]
    fn binary_ga_passes_the_common_checks() {
        check(&BinaryGa::default(), |b| b.population as u64 * (b.generations + 1));
        check(&BinaryGa { elitism: 1, pc: 0.9, ..BinaryGa::default() }, |b| {
            b.population as u64 * (b.generations + 1)
        });
    }

    #[test]
    fn rank_probabilities_follow_eq_10() {
        let ga = BinaryGa::default();
        let p = ga.rank_probabilities(10);
        // beta = 2, alpha = 0: Pr(rank r) = 2 r / (mu (mu - 1)).
        for (r, v) in p.iter().enumerate() {
            assert!((v - 2.0 * r as f64 / 90.0).abs() < 1e-15);
        }
        assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-14);
        let flat = BinaryGa { beta: 1.0, ..ga }.rank_probabilities(4);
        assert!(flat.iter().all(|v| (v - 0.25).abs() < 1e-15));
    }

    #[test]
    fn decoding_maps_the_integer_range_onto_the_bounds() {
        let ga = BinaryGa { bits: 4, ..BinaryGa::default() };
        // Variables: 1111 -> hi, 0000 -> lo, 1000 (MSB first) -> lo + 8/15 (hi - lo).
        let chrom = [0b0001_0000_1111u64];
        let mut x = [0.0; 3];
        ga.decode(&chrom, &[-1.0, 0.0, 2.0], &[1.0, 3.0, 17.0], &mut x);
        assert_eq!(x[0], 1.0);
        assert_eq!(x[1], 0.0);
        assert!((x[2] - (2.0 + 15.0 * 8.0 / 15.0)).abs() < 1e-12, "{x:?}");
        let chrom = [0b1000u64];
        let mut x = [0.0; 1];
        ga.decode(&chrom, &[0.0], &[15.0], &mut x);
        assert!((x[0] - 1.0).abs() < 1e-12, "bit order: {x:?}");
    }

    #[test]
    fn selection_frequencies_match_the_ranks() {
        // Draws with the cumulative table the run uses hit each rank with its Eq. 10 probability.
        let ga = BinaryGa::default();
        let p = ga.rank_probabilities(5);
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let cum: Vec<f64> = p
            .iter()
            .scan(0.0, |s, v| {
                *s += v;
                Some(*s)
            })
            .collect();
        let mut counts = [0usize; 5];
        let n = 100_000;
        for _ in 0..n {
            let u = unit(&mut rng) * cum[4];
            counts[cum.iter().position(|&c| u < c).unwrap()] += 1;
        }
        assert_eq!(counts[0], 0, "the worst is never drawn at beta = 2");
        for r in 1..5 {
            assert!((counts[r] as f64 / n as f64 - p[r]).abs() < 0.01, "{counts:?}");
        }
    }

    #[test]
    fn history_is_consistent_and_without_elitism_the_population_best_may_rise() {
        let p = Sphere::new(6);
        let budget =
            Budget { generations: 60, population: 10, init_range: 0.0, trace_every_evals: 10 };
        let r = BinaryGa::default()
            .run_with_history(&p, &budget, &mut ChaCha8Rng::seed_from_u64(4))
            .unwrap();
        assert_eq!(r.population_best.len(), 61);
        assert_eq!(r.best_so_far.len(), 61);
        assert_eq!(r.population_best[0], r.result.initial_best_fitness);
        for g in 0..=60 {
            let min = r.population_best[..=g].iter().cloned().fold(f64::INFINITY, f64::min);
            assert_eq!(r.best_so_far[g], min);
            // The trace records best so far after every generation (10 evaluations each).
            assert_eq!(r.result.trace[g], (10 * (g as u64 + 1), r.best_so_far[g]));
        }
        assert_eq!(r.best_so_far[r.best_generation()], r.result.best_fitness);
        // With one elite the population best never rises.
        let e = BinaryGa { elitism: 1, ..BinaryGa::default() }
            .run_with_history(&p, &budget, &mut ChaCha8Rng::seed_from_u64(4))
            .unwrap();
        assert!(e.population_best.windows(2).all(|w| w[1] <= w[0]));
    }

    #[test]
    fn parameters_are_validated_by_key() {
        assert_eq!(
            BinaryGa { beta: 2.5, ..BinaryGa::default() }.validate().unwrap_err().to_string(),
            "binary_ga.beta must be in [1,2], got 2.5"
        );
        assert!(BinaryGa { bits: 0, ..BinaryGa::default() }
            .validate()
            .unwrap_err()
            .to_string()
            .starts_with("binary_ga.bits"));
        let p = Sphere::new(2);
        let budget =
            Budget { generations: 2, population: 4, init_range: 0.0, trace_every_evals: 4 };
        let e = BinaryGa { elitism: 4, ..BinaryGa::default() }
            .run(&p, &budget, &mut ChaCha8Rng::seed_from_u64(1))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("binary_ga.elitism"), "{e}");
        let g: BinaryGa = toml::from_str("bits = 12").unwrap();
        assert_eq!(g, BinaryGa { bits: 12, ..BinaryGa::default() });
        assert!(toml::from_str::<BinaryGa>("bit = 12").is_err());
    }
}
