//! Particle swarm optimisation with constriction factor and velocity clamping (Clerc & Kennedy
//! 2002; thesis 6.2.4.3, Table 6.1: K = 0.729, c1 = c2 = 2.05, v0 = 0, |v| at most half the
//! range, positions kept in the range), global-best topology.
//!
//! Per coordinate: v <- K (v + c1 r1 (pbest - x) + c2 r2 (gbest - x)), r1, r2 ~ U[0, 1) drawn
//! anew for every coordinate (the two products added by fused multiply-adds); v is clamped to
//! +-(upper - lower)/2 and x + v to [lower, upper] (the velocity is kept when the position is
//! clamped). Updates are synchronous: every particle moves with the global best of the previous
//! iteration, and the global best is updated after all have moved and been evaluated (a
//! personal best moves only on strict improvement).
//! `population * (1 + generations)` evaluations.
//!
//! Random numbers: r1 and r2 are the two 32-bit halves of one 64-bit word (resolution 2^-32),
//! one word per coordinate from eight interleaved xoshiro256++ generators seeded from the run's
//! stream ([`super::sampling::PsoLanes`]; coordinate j from lane j % 8), generated and consumed
//! in the vectorised move loop.

use super::aligned::Aligned;
use super::kernels::{pso_move, PsoBounds, PsoCoefficients};
use super::problem::{check_problem, Budget, Evaluator, Optimiser, Population, Problem, RunResult};
use super::sampling::PsoLanes;
use super::{check_range, OptimError};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// PSO parameters (defaults: thesis Table 6.1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Pso {
    /// Constriction factor K.
    pub k: f64,
    /// Cognitive acceleration c1.
    pub c1: f64,
    /// Social acceleration c2.
    pub c2: f64,
    /// Velocity clamp as a fraction of the range (upper - lower) per coordinate.
    pub vmax_fraction: f64,
}

impl Default for Pso {
    fn default() -> Pso {
        Pso { k: 0.729, c1: 2.05, c2: 2.05, vmax_fraction: 0.5 }
    }
}

impl Pso {
    pub fn validate(&self) -> Result<(), OptimError> {
        check_range("pso.k", self.k, 0.0, 1.0)?;
        check_range("pso.c1", self.c1, 0.0, 10.0)?;
        check_range("pso.c2", self.c2, 0.0, 10.0)?;
        check_range("pso.vmax_fraction", self.vmax_fraction, 0.0, 1.0)
    }
}

impl Optimiser for Pso {
    fn name(&self) -> &'static str {
        "pso"
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
        let mut eval = Evaluator::new(problem, budget);
        // A particle's position is its personal best's buffer while the two are equal
        // (`at_best`, true after the initial population and after every improvement), else
        // `pos`; each move writes into `spare`, which then swaps with the personal best (an
        // improvement) or the position, so no vector is ever copied per evaluation.
        let Population { x: mut pbest, f: mut pbest_f } =
            Population::initial(problem, budget, &mut eval, rng);
        let n = pbest.len();
        let mut vel = vec![Aligned::zeros(d); n];
        let mut pos = vec![Aligned::zeros(d); n];
        let mut at_best = vec![true; n];
        let mut spare = Aligned::zeros(d);
        let mut g = argmin(&pbest_f);
        let initial_best = pbest_f[g];
        let mut gbest = pbest[g].clone();
        let mut bulk = PsoLanes::from_rng(rng);
        let co = PsoCoefficients { k: self.k, c1: self.c1, c2: self.c2 };
        let bounds = PsoBounds { lo, hi, vmax_fraction: self.vmax_fraction };
        for _ in 0..budget.generations {
            // Each particle is evaluated right after its move, while its coordinates are in
            // cache; the global best it moved towards is the previous iteration's (a copy).
            for i in 0..n {
                let x = if at_best[i] { &pbest[i] } else { &pos[i] };
                pso_move(&mut spare, x, &mut vel[i], &pbest[i], &gbest, &mut bulk, co, bounds);
                let f = eval.eval(&spare);
                at_best[i] = f < pbest_f[i];
                if at_best[i] {
                    pbest_f[i] = f;
                    std::mem::swap(&mut pbest[i], &mut spare);
                } else {
                    std::mem::swap(&mut pos[i], &mut spare);
                }
            }
            g = argmin(&pbest_f);
            gbest.copy_from_slice(&pbest[g]);
        }
        Ok(eval.finish(pbest.swap_remove(g), initial_best))
    }
}

fn argmin(f: &[f64]) -> usize {
    let mut b = 0;
    for i in 1..f.len() {
        if f[i] < f[b] {
            b = i;
        }
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::optimiser_tests::check;

    #[test]
    fn pso_passes_the_common_checks() {
        check(&Pso::default(), |b| b.population as u64 * (1 + b.generations));
    }

    #[test]
    fn parameters_are_validated_by_key() {
        assert_eq!(
            Pso { k: 1.2, ..Pso::default() }.validate().unwrap_err().to_string(),
            "pso.k must be in [0,1], got 1.2"
        );
        assert!(Pso { c2: -1.0, ..Pso::default() }
            .validate()
            .unwrap_err()
            .to_string()
            .starts_with("pso.c2"));
    }

    /// A single particle with v0 = 0 at its own best stays put: the velocity update is
    /// K (0 + c1 r1 0 + c2 r2 0) = 0 (checks the sign conventions of the update).
    #[test]
    fn lone_particle_at_its_best_does_not_move() {
        use crate::optim::problem::tests::Sphere;
        use rand::SeedableRng;
        let p = Sphere::new(4);
        let budget =
            Budget { generations: 20, population: 1, init_range: 0.0, trace_every_evals: 5 };
        let r = Pso::default().run(&p, &budget, &mut ChaCha8Rng::seed_from_u64(1)).unwrap();
        assert_eq!(r.best_x, p.x0);
        assert_eq!(r.evaluations, 21);
    }
}
