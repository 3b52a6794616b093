//! Steady-state genetic algorithm of thesis 6.2.4.1 (value encoding, tournament selection,
//! uniform crossover, uniform mutation, weak-parent replacement; Table 6.1: Pc = 0.7,
//! Pm = 0.01).
//!
//! One generation: two tournaments of 4 distinct individuals each pick the parents (least
//! fitness wins, the first drawn on ties); with probability Pc uniform crossover swaps each gene
//! between the two offspring with probability 0.5; each gene of each offspring is then mutated
//! with probability Pm to x0 + U[-r, r] (the initialisation range, clamped to the bounds);
//! offspring 1 replaces parent 1 and offspring 2 replaces parent 2, each only if strictly
//! better (when both parents are the same individual, offspring 2 competes with whatever holds
//! the slot after offspring 1). Both offspring are always evaluated: 2 evaluations per
//! generation, `population + 2 * generations` in all.
//!
//! Random bits: one fair bit per gene for the crossover (64 genes per draw) and geometric skips
//! for the mutation (one draw per mutated gene, not per gene; see `sampling::Geometric`).

use super::aligned::Aligned;
use super::problem::{check_problem, Budget, Evaluator, Optimiser, Population, Problem, RunResult};
use super::sampling::{index, symmetric, unit, BitPool, Geometric};
use super::{check_range, OptimError};
use rand::RngCore;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// GA parameters (defaults: thesis Table 6.1).
#[derive(Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct Ga {
    /// Crossover probability Pc.
    pub pc: f64,
    /// Mutation probability Pm, per gene or per offspring ([`Mutation`]).
    pub pm: f64,
    /// Tournament size.
    pub tournament: usize,
    /// Per-gene swap probability of the uniform crossover (only 0.5 is implemented: one fair
    /// bit per gene).
    pub swap: f64,
    /// What Pm is the probability of (docs/readings.md, "GA's mutation").
    pub mutation: Mutation,
    /// Under [`Mutation::PerOffspring`]: how many distinct genes a mutated offspring has redrawn
    /// (Section 2.4's "a predefined number of genes"), in [1, 1000].
    pub mutated_genes: usize,
}

/// What the GA's mutation probability Pm is the probability of: each gene is redrawn with
/// probability Pm (`per_gene`, Section 2.4: "If the mutation probability is 1, the whole
/// chromosome is altered"), or one draw per offspring decides, with probability Pm, that
/// `mutated_genes` of its genes are redrawn (`per_offspring`, Section 6.2.4.1 step 5: "A random
/// number is generated and mutation will be executed if the random number is less than" Pm).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum Mutation {
    #[default]
    PerGene,
    PerOffspring,
}

impl Default for Ga {
    fn default() -> Ga {
        Ga {
            pc: 0.7,
            pm: 0.01,
            tournament: 4,
            swap: 0.5,
            mutation: Mutation::PerGene,
            mutated_genes: 1,
        }
    }
}

/// The table as a cell's identity reads it: the mutation's reading only where it is not the
/// default, so the identity of every cell the GA computed before the option existed is the same.
impl std::fmt::Debug for Ga {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut s = f.debug_struct("Ga");
        s.field("pc", &self.pc)
            .field("pm", &self.pm)
            .field("tournament", &self.tournament)
            .field("swap", &self.swap);
        if self.mutation != Mutation::PerGene || self.mutated_genes != 1 {
            s.field("mutation", &self.mutation).field("mutated_genes", &self.mutated_genes);
        }
        s.finish()
    }
}

impl Ga {
    pub(crate) fn validate(&self) -> Result<(), OptimError> {
        check_range("ga.pc", self.pc, 0.0, 1.0)?;
        check_range("ga.pm", self.pm, 0.0, 1.0)?;
        if !(1..=MAX_TOURNAMENT).contains(&self.tournament) {
            return Err(OptimError::param(
                "ga.tournament",
                format!("must be in [1,{MAX_TOURNAMENT}], got {}", self.tournament),
            ));
        }
        if !(1..=MAX_MUTATED_GENES).contains(&self.mutated_genes) {
            return Err(OptimError::param(
                "ga.mutated_genes",
                format!("must be in [1,{MAX_MUTATED_GENES}], got {}", self.mutated_genes),
            ));
        }
        if self.swap != 0.5 {
            return Err(OptimError::param(
                "ga.swap",
                format!("must be 0.5 (uniform crossover), got {}", self.swap),
            ));
        }
        Ok(())
    }

    /// Tournament among `self.tournament` distinct individuals (needs population >= size).
    fn tournament(&self, f: &[f64], rng: &mut ChaCha8Rng) -> usize {
        let mut drawn = [0usize; MAX_TOURNAMENT];
        let mut winner = usize::MAX;
        let mut n = 0;
        while n < self.tournament {
            let c = index(rng, f.len());
            if drawn[..n].contains(&c) {
                continue;
            }
            drawn[n] = c;
            n += 1;
            if winner == usize::MAX || f[c] < f[winner] {
                winner = c;
            }
        }
        winner
    }
}

const MAX_TOURNAMENT: usize = 16;
const MAX_MUTATED_GENES: usize = 1000;

impl Optimiser for Ga {
    fn validate(&self) -> Result<(), OptimError> {
        Ga::validate(self)
    }
    fn name(&self) -> &'static str {
        "ga"
    }

    fn min_population(&self) -> super::problem::MinPopulation {
        super::problem::MinPopulation {
            n: self.tournament,
            key: Some("tournament"),
            why: "a tournament draws that many distinct individuals",
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
        let x0 = problem.initial_point();
        let (lo, hi) = problem.bounds();
        let mut eval = Evaluator::new(problem, budget);
        let mut pop = Population::initial(problem, budget, &mut eval, rng);
        let initial_best = pop.best_fitness();
        let mutation = Geometric::new(self.pm);
        let mut pool = BitPool::new();
        let mut c1 = Aligned::zeros(d);
        let mut c2 = Aligned::zeros(d);
        for _ in 0..budget.generations {
            let a = self.tournament(&pop.f, rng);
            let b = self.tournament(&pop.f, rng);
            if unit(rng) < self.pc {
                // Uniform crossover: gene j is swapped when its bit is set.
                let (pa, pb) = (&pop.x[a], &pop.x[b]);
                for start in (0..d).step_by(64) {
                    let bits = rng.next_u64();
                    let end = (start + 64).min(d);
                    for j in start..end {
                        let swap = (bits >> (j - start)) & 1 == 1;
                        let (u, v) = (pa[j], pb[j]);
                        c1[j] = if swap { v } else { u };
                        c2[j] = if swap { u } else { v };
                    }
                }
            } else {
                c1.copy_from_slice(&pop.x[a]);
                c2.copy_from_slice(&pop.x[b]);
            }
            for child in [&mut c1, &mut c2] {
                let mut redraw = |j: usize, rng: &mut ChaCha8Rng| {
                    child[j] = (x0[j] + symmetric(rng, budget.init_range)).max(lo[j]).min(hi[j]);
                };
                match self.mutation {
                    Mutation::PerGene => {
                        let mut j = mutation.skip(&mut pool, rng);
                        while j < d {
                            redraw(j, rng);
                            j = mutation.next_after(j, &mut pool, rng);
                        }
                    }
                    Mutation::PerOffspring => {
                        if unit(rng) < self.pm {
                            for j in distinct(rng, d, self.mutated_genes.min(d)) {
                                redraw(j, rng);
                            }
                        }
                    }
                }
            }
            let f1 = eval.eval(&c1);
            if f1 < pop.f[a] {
                std::mem::swap(&mut pop.x[a], &mut c1);
                pop.f[a] = f1;
            }
            let f2 = eval.eval(&c2);
            if f2 < pop.f[b] {
                std::mem::swap(&mut pop.x[b], &mut c2);
                pop.f[b] = f2;
            }
        }
        let best = pop.best();
        Ok(eval.finish(pop.x.swap_remove(best), initial_best))
    }
}

/// `k` distinct indices below `d`, drawn in turn (a drawn index is drawn again).
fn distinct(rng: &mut ChaCha8Rng, d: usize, k: usize) -> Vec<usize> {
    let mut out = Vec::with_capacity(k);
    while out.len() < k {
        let j = index(rng, d);
        if !out.contains(&j) {
            out.push(j);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::optimiser_tests::check;

    #[test]
    fn ga_passes_the_common_checks() {
        check(&Ga::default(), |b| b.population as u64 + 2 * b.generations);
    }

    #[test]
    fn parameters_are_validated_by_key() {
        let e = Ga { pc: 1.5, ..Ga::default() }.validate().unwrap_err().to_string();
        assert_eq!(e, "ga.pc must be in [0,1], got 1.5");
        assert!(Ga { pm: -0.1, ..Ga::default() }
            .validate()
            .unwrap_err()
            .to_string()
            .starts_with("ga.pm"));
        assert!(Ga { tournament: 0, ..Ga::default() }
            .validate()
            .unwrap_err()
            .to_string()
            .starts_with("ga.tournament"));
        let g: Ga = toml::from_str("pc = 0.9").unwrap();
        assert_eq!(g, Ga { pc: 0.9, ..Ga::default() });
        assert!(toml::from_str::<Ga>("pcc = 0.9").is_err());
    }

    #[test]
    fn tournament_picks_the_best_of_distinct_draws() {
        use rand::SeedableRng;
        let ga = Ga::default();
        let f = [5.0, 4.0, 3.0, 2.0];
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        // With 4 of 4 distinct individuals drawn, the best always wins.
        for _ in 0..100 {
            assert_eq!(ga.tournament(&f, &mut rng), 3);
        }
        // With 4 distinct of 40, P(the winner is one of the 4 best) = 1 - C(36,4)/C(40,4)
        // = 1 - 58905/91390 = 0.35546.
        let f: Vec<f64> = (0..40).map(|i| i as f64).collect();
        let n = 40_000;
        let top = (0..n).filter(|_| ga.tournament(&f, &mut rng) < 4).count() as f64 / n as f64;
        assert!((top - 0.35546).abs() < 0.01, "{top}");
    }

    /// The sphere, keeping every point it evaluates.
    struct Recording(crate::optim::problem::tests::Sphere, std::sync::Mutex<Vec<Vec<f64>>>);

    impl Problem for Recording {
        fn dim(&self) -> usize {
            self.0.dim()
        }
        fn initial_point(&self) -> &[f64] {
            self.0.initial_point()
        }
        fn bounds(&self) -> (&[f64], &[f64]) {
            self.0.bounds()
        }
        fn fitness(&self, x: &[f64]) -> f64 {
            self.1.lock().unwrap().push(x.to_vec());
            self.0.fitness(x)
        }
    }

    /// Without crossover, each offspring is its parent with the mutated genes redrawn: per
    /// offspring, at most `mutated_genes` genes (and none at Pm = 0); per gene at Pm = 1, every
    /// gene.
    #[test]
    fn per_offspring_mutation_redraws_the_stated_number_of_genes() {
        use crate::optim::problem::tests::Sphere;
        use rand::SeedableRng;
        let budget =
            Budget { generations: 30, population: 6, init_range: 0.1, trace_every_evals: 10 };
        let most_changed = |ga: Ga| {
            let p = Recording(Sphere::new(8), Default::default());
            ga.run(&p, &budget, &mut ChaCha8Rng::seed_from_u64(9)).unwrap();
            let seen = p.1.into_inner().unwrap();
            let (init, children) = seen.split_at(budget.population);
            let mut pool: Vec<Vec<f64>> = init.to_vec();
            let mut most = 0;
            for c in children {
                let changed = |x: &Vec<f64>| x.iter().zip(c).filter(|(a, b)| a != b).count();
                most = most.max(pool.iter().map(changed).min().unwrap());
                pool.push(c.clone());
            }
            most
        };
        let per = |pm, k| Ga {
            pc: 0.0,
            pm,
            mutation: Mutation::PerOffspring,
            mutated_genes: k,
            ..Ga::default()
        };
        assert_eq!(most_changed(per(1.0, 2)), 2);
        assert_eq!(most_changed(per(1.0, 1)), 1);
        assert_eq!(most_changed(per(0.0, 3)), 0);
        assert_eq!(most_changed(Ga { pc: 0.0, pm: 1.0, ..Ga::default() }), 8);
        assert!(Ga { mutated_genes: 0, ..Ga::default() }
            .validate()
            .unwrap_err()
            .to_string()
            .starts_with("ga.mutated_genes"));
        let g: Ga = toml::from_str("mutation = \"per_offspring\"\nmutated_genes = 3").unwrap();
        assert_eq!((g.mutation, g.mutated_genes), (Mutation::PerOffspring, 3));
    }

    /// A cell's identity reads the table's Debug text: the default's is the text from before the
    /// mutation option, so no cell the GA computed changes its key; another reading's differs.
    #[test]
    fn the_default_tables_identity_text_is_unchanged() {
        assert_eq!(
            format!("{:?}", Ga::default()),
            "Ga { pc: 0.7, pm: 0.01, tournament: 4, swap: 0.5 }"
        );
        let other = Ga { mutation: Mutation::PerOffspring, ..Ga::default() };
        assert_ne!(format!("{other:?}"), format!("{:?}", Ga::default()));
    }

    #[test]
    fn mutation_only_ga_resamples_around_x0() {
        use crate::optim::problem::tests::Sphere;
        use rand::SeedableRng;
        // Pc = 0, Pm = 1: every offspring is x0 + U[-r, r], so the best stays within r of x0.
        let p = Sphere::new(5);
        let ga = Ga { pc: 0.0, pm: 1.0, ..Ga::default() };
        let budget =
            Budget { generations: 50, population: 8, init_range: 0.01, trace_every_evals: 10 };
        let r = ga.run(&p, &budget, &mut ChaCha8Rng::seed_from_u64(3)).unwrap();
        assert!(r.best_x.iter().zip(&p.x0).all(|(a, b)| (a - b).abs() <= 0.01));
    }
}
