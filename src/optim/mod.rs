//! Control-point optimisation (thesis Chapter 6, SPEC 4): problem-agnostic optimisers (GA, DE,
//! PSO from Table 6.1; CSA and ICSA from seed 003), the thesis' control-net problem with a fast
//! fitness, and its exact optimum with a certificate, which the thesis did not have: the fitness
//! is convex, so how far each metaheuristic stops from the true optimum can be stated, not
//! guessed. Pure code: no file or terminal I/O (the IOHprofiler export returns text).

pub(crate) mod aligned;
pub(crate) mod exact;
pub(crate) mod ioh;
pub(crate) mod levy;
pub(crate) mod problem;
pub(crate) mod registry;
pub(crate) mod sampling;

// The optimisers: each file's module, its optimiser types and their chart colours (Okabe-Ito).
// A new optimiser is its file plus one line here (docs/architecture.md, "Adding an optimiser").
registry::optimisers! {
    ga: Ga [230, 159, 0];
    de: De [0, 114, 178];
    pso: Pso [0, 158, 115];
    cuckoo: Csa [204, 121, 167], Icsa [213, 94, 0];
    binary_ga: BinaryGa [86, 180, 233];
}

pub use cuckoo::Csa;
pub(crate) use cuckoo::Icsa;
pub use de::De;
pub use exact::{certify_dual, ExactOptions, ExactResult};
pub use problem::{Budget, Problem};
pub(crate) use problem::{Optimiser, RunResult};
pub use pso::Pso;
pub use registry::default_optimiser;
pub(crate) use registry::{registered, Name, Tables};

/// What can go wrong before an optimisation starts.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OptimError {
    /// A parameter out of range, named by its key (e.g. `de.cr must be in [0,1], got 1.5`).
    #[error("{key} {message}")]
    InvalidParameter { key: String, message: String },
    /// A problem whose shapes or box do not agree.
    #[error("problem: {0}")]
    Problem(String),
    /// Control-net parts that do not fit together.
    #[error("control net: {0}")]
    ControlNet(String),
}

impl OptimError {
    pub(crate) fn param(key: &str, message: String) -> OptimError {
        OptimError::InvalidParameter { key: key.to_string(), message }
    }
}

impl From<crate::simd::SimdError> for OptimError {
    fn from(e: crate::simd::SimdError) -> OptimError {
        OptimError::param(crate::simd::SIMD_ENV, e.message)
    }
}

/// Require `value` in [lo, hi] (finite), naming the key in the error.
pub(crate) fn check_range(key: &str, value: f64, lo: f64, hi: f64) -> Result<(), OptimError> {
    if value >= lo && value <= hi {
        Ok(())
    } else {
        Err(OptimError::param(key, format!("must be in [{lo},{hi}], got {value}")))
    }
}

/// Shared checks every optimiser must pass.
#[cfg(test)]
pub(crate) mod optimiser_tests {
    use super::problem::tests::Sphere;
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// A box that cuts through the sphere's optimum, so clamping is exercised.
    pub(crate) fn boxed_sphere(dim: usize) -> Sphere {
        let mut p = Sphere::new(dim);
        for j in 0..dim {
            p.lo[j] = -0.1;
            p.hi[j] = 0.9;
            p.x0[j] = 0.85;
        }
        p
    }

    /// Determinism, exact evaluation count, bounds, best not worse than the initial best,
    /// best_fitness = f(best_x), a monotone trace on the fixed checkpoints, improvement.
    pub(crate) fn check(opt: &dyn Optimiser, expected_evals: impl Fn(&Budget) -> u64) {
        let p = boxed_sphere(25);
        let budget =
            Budget { generations: 150, population: 12, init_range: 0.1, trace_every_evals: 50 };
        let run = |seed| opt.run(&p, &budget, &mut ChaCha8Rng::seed_from_u64(seed)).unwrap();
        let a = run(7);
        let b = run(7);
        assert_eq!(a, b, "{}: same seed, same result", opt.name());
        let c = run(8);
        assert_ne!(a.best_x, c.best_x, "{}: another seed, another run", opt.name());
        assert_eq!(a.evaluations, expected_evals(&budget), "{}: evaluations", opt.name());
        assert!(a.best_fitness <= a.initial_best_fitness, "{}", opt.name());
        assert_eq!(
            a.best_fitness,
            p.fitness(&a.best_x),
            "{}: best_fitness = f(best_x)",
            opt.name()
        );
        for (j, v) in a.best_x.iter().enumerate() {
            assert!(
                *v >= p.lo[j] && *v <= p.hi[j],
                "{}: coordinate {j} = {v} out of bounds",
                opt.name()
            );
        }
        let marks: Vec<u64> = a.trace.iter().map(|t| t.0).collect();
        let mut want: Vec<u64> =
            (1..).map(|k| k * 50).take_while(|&e| e <= a.evaluations).collect();
        if want.last() != Some(&a.evaluations) {
            want.push(a.evaluations);
        }
        assert_eq!(marks, want, "{}: checkpoints", opt.name());
        assert!(a.trace.windows(2).all(|w| w[1].1 <= w[0].1), "{}: monotone trace", opt.name());
        assert_eq!(a.trace.last().unwrap().1, a.best_fitness);
        assert!(
            a.best_fitness < a.initial_best_fitness,
            "{}: sphere should improve: {} -> {}",
            opt.name(),
            a.initial_best_fitness,
            a.best_fitness
        );
    }
}
