//! The problem/optimiser split (as in argmin): a [`Problem`] says what to minimise inside which
//! box, an [`Optimiser`] says how, and an [`Evaluator`] between them counts every evaluation and
//! records the convergence trace at fixed evaluation counts, so that budgets are measured outside
//! the algorithms and the traces of repeats line up checkpoint by checkpoint.

use super::aligned::Aligned;
use super::sampling::symmetric_from;
use super::OptimError;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// A box-constrained minimisation problem.
pub trait Problem: Sync {
    /// Number of coordinates of a decision vector.
    fn dim(&self) -> usize;
    /// Where the search starts (the thesis: approach B's control points).
    fn initial_point(&self) -> &[f64];
    /// Lower and upper bound of every coordinate.
    fn bounds(&self) -> (&[f64], &[f64]);
    /// The data set's range per coordinate (its min and max along the coordinate's axis), for
    /// the optimisers whose parameters the thesis states against "the range of the dataset"
    /// (PSO's `vmax_range` and `position_range`); None where the problem has no data set.
    fn data_range(&self) -> Option<(&[f64], &[f64])> {
        None
    }
    /// The value to minimise.
    fn fitness(&self, x: &[f64]) -> f64;
}

/// A population-based optimiser; parameters inside, randomness only from the stream given.
pub trait Optimiser: Send + Sync + std::fmt::Debug {
    /// The name specs, tables and charts use (`de`), unique among the registered optimisers.
    fn name(&self) -> &'static str;
    /// The smallest population a run takes with these parameters (checked by the run and, for
    /// the optimisers a spec names, when the spec is read).
    fn min_population(&self) -> MinPopulation {
        MinPopulation { n: 1, key: None, why: "one individual" }
    }
    /// Check the parameter table (each error names its key: `cr must be in [0,1], got 1.5`); a
    /// spec is checked with it when it is read.
    fn validate(&self) -> Result<(), super::OptimError> {
        Ok(())
    }
    /// One run. Errors only for a malformed problem, budget or parameter set (checked before the
    /// first evaluation).
    fn run(
        &self,
        problem: &dyn Problem,
        budget: &Budget,
        rng: &mut ChaCha8Rng,
    ) -> Result<RunResult, OptimError>;
}

/// An optimiser's smallest population: `n`, the parameter of the optimiser's table that sets it
/// (None: the method itself) and why, for messages.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MinPopulation {
    pub n: usize,
    pub key: Option<&'static str>,
    pub why: &'static str,
}

/// How much one run may do (thesis Table 6.1: 2000 generations of 40, initial range 5e-6).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Budget {
    pub generations: u64,
    pub population: usize,
    /// Half-width r of the initial range: each initial individual is x0 + U[-r, r] per
    /// coordinate, clamped to the bounds (the GA's mutation draws from the same range).
    pub init_range: f64,
    /// Trace checkpoints: the best-so-far fitness is recorded after every multiple of this many
    /// evaluations, and once more after the last evaluation.
    pub trace_every_evals: u64,
}

impl Default for Budget {
    fn default() -> Budget {
        Budget { generations: 2000, population: 40, init_range: 5e-6, trace_every_evals: 400 }
    }
}

impl Budget {
    /// Check the budget for an optimiser that needs at least `min_population` individuals.
    pub fn validate(&self, min_population: usize) -> Result<(), OptimError> {
        if self.population < min_population {
            return Err(OptimError::param(
                "budget.population",
                format!(
                    "must be at least {min_population} for this optimiser, got {}",
                    self.population
                ),
            ));
        }
        if !(self.init_range >= 0.0 && self.init_range.is_finite()) {
            return Err(OptimError::param(
                "budget.init_range",
                format!("must be finite and >= 0, got {}", self.init_range),
            ));
        }
        if self.trace_every_evals == 0 {
            return Err(OptimError::param(
                "budget.trace_every_evals",
                "must be at least 1, got 0".to_string(),
            ));
        }
        Ok(())
    }
}

/// The outcome of one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunResult {
    pub best_x: Vec<f64>,
    pub best_fitness: f64,
    /// Best fitness of the initial population.
    pub initial_best_fitness: f64,
    /// Number of fitness evaluations, initial population included.
    pub evaluations: u64,
    /// (evaluations, best fitness so far) at every multiple of `Budget::trace_every_evals` and at
    /// the end.
    pub trace: Vec<(u64, f64)>,
    /// (evaluation, its fitness) at strict improvements of the best so far, from the first
    /// evaluation (1-based, as IOHprofiler's improvement-based `.dat` files record a run): the
    /// first improvement at or after each of 20 log-spaced marks per decade of evaluations, and
    /// always the last one, so a run of 80,000 evaluations that improves at nearly every one
    /// (DE, PSO in a tiny box) keeps about 100 rows, not tens of thousands. Every row is a true
    /// (evaluation, best) pair; a skipped improvement is seen at the next kept one (at most a
    /// factor 10^(1/20) = 1.12 later in evaluations) and the final best at its own evaluation.
    pub improvements: Vec<(u64, f64)>,
}

/// Check a problem's shapes and box before a run.
pub(crate) fn check_problem(problem: &dyn Problem) -> Result<(), OptimError> {
    crate::simd::simd()?;
    let d = problem.dim();
    if d == 0 {
        return Err(OptimError::Problem("dimension is 0".into()));
    }
    let x0 = problem.initial_point();
    let (lo, hi) = problem.bounds();
    if x0.len() != d || lo.len() != d || hi.len() != d {
        return Err(OptimError::Problem(format!(
            "dimension {d} but initial point has {}, lower bounds {}, upper bounds {}",
            x0.len(),
            lo.len(),
            hi.len()
        )));
    }
    if let Some(j) = x0.iter().position(|v| !v.is_finite()) {
        return Err(OptimError::Problem(format!(
            "initial point coordinate {j} is not finite ({})",
            x0[j]
        )));
    }
    if let Some(j) = (0..d).find(|&j| lo[j].is_nan() || hi[j].is_nan() || lo[j] > hi[j]) {
        return Err(OptimError::Problem(format!(
            "bounds of coordinate {j} are not an interval: [{}, {}]",
            lo[j], hi[j]
        )));
    }
    Ok(())
}

/// Counts evaluations, keeps the best value, and records the trace (the argmin-style counting
/// wrapper). A NaN fitness is recorded as +inf so that it never wins a comparison.
pub(crate) struct Evaluator<'a> {
    problem: &'a dyn Problem,
    evaluations: u64,
    best: f64,
    every: u64,
    trace: Vec<(u64, f64)>,
    improvements: Vec<(u64, f64)>,
    /// The next log-spaced mark at or after which an improvement is kept, and the last
    /// improvement not kept (kept at the end if no later one is).
    next_mark: u64,
    pending: Option<(u64, f64)>,
}

/// Marks per decade of evaluations for the kept improvements.
const MARKS_PER_DECADE: f64 = 20.0;

/// The least mark ceil(10^(k/20)) greater than `e`.
fn mark_after(e: u64) -> u64 {
    let mut k = (MARKS_PER_DECADE * (e.max(1) as f64).log10()).floor();
    loop {
        let m = 10f64.powf(k / MARKS_PER_DECADE).ceil() as u64;
        if m > e {
            return m;
        }
        k += 1.0;
    }
}

impl<'a> Evaluator<'a> {
    pub(crate) fn new(problem: &'a dyn Problem, budget: &Budget) -> Evaluator<'a> {
        Evaluator {
            problem,
            evaluations: 0,
            best: f64::INFINITY,
            every: budget.trace_every_evals.max(1),
            trace: Vec::new(),
            improvements: Vec::new(),
            next_mark: 1,
            pending: None,
        }
    }

    /// Evaluate `x`, counting it and updating the best and the trace.
    #[inline]
    pub(crate) fn eval(&mut self, x: &[f64]) -> f64 {
        let f = self.problem.fitness(x);
        let f = if f.is_nan() { f64::INFINITY } else { f };
        self.evaluations += 1;
        if f < self.best {
            self.best = f;
            if self.evaluations >= self.next_mark {
                self.improvements.push((self.evaluations, f));
                self.next_mark = mark_after(self.evaluations);
                self.pending = None;
            } else {
                self.pending = Some((self.evaluations, f));
            }
        }
        if self.evaluations.is_multiple_of(self.every) {
            self.trace.push((self.evaluations, self.best));
        }
        f
    }

    pub(crate) fn best(&self) -> f64 {
        self.best
    }

    /// Close the run: `best_x` is the optimiser's best individual (whose fitness is the best
    /// value seen, since every optimiser here keeps its best).
    pub(crate) fn finish(
        mut self,
        best_x: impl Into<Vec<f64>>,
        initial_best_fitness: f64,
    ) -> RunResult {
        let best_x = best_x.into();
        if self.trace.last().map(|t| t.0) != Some(self.evaluations) {
            self.trace.push((self.evaluations, self.best));
        }
        self.improvements.extend(self.pending.take());
        RunResult {
            best_x,
            best_fitness: self.best,
            initial_best_fitness,
            evaluations: self.evaluations,
            trace: self.trace,
            improvements: self.improvements,
        }
    }
}

/// Clamp every coordinate into the box.
#[inline]
pub(crate) fn clamp_into(x: &mut [f64], lo: &[f64], hi: &[f64]) {
    let n = x.len();
    let (lo, hi) = (&lo[..n], &hi[..n]);
    for j in 0..n {
        x[j] = x[j].max(lo[j]).min(hi[j]);
    }
}

/// A population: one vector per individual and its fitness.
pub(crate) struct Population {
    pub(crate) x: Vec<Aligned>,
    pub(crate) f: Vec<f64>,
}

impl Population {
    /// The thesis' initialisation (6.2.4.1 step 1): x0 + U[-r, r] per coordinate, clamped to the
    /// bounds, each individual evaluated once.
    pub(crate) fn initial(
        problem: &dyn Problem,
        budget: &Budget,
        eval: &mut Evaluator,
        rng: &mut ChaCha8Rng,
    ) -> Population {
        let x0 = problem.initial_point();
        let (lo, hi) = problem.bounds();
        let mut x = Vec::with_capacity(budget.population);
        let mut f = Vec::with_capacity(budget.population);
        // One individual's 64-bit draws in bulk (the words `symmetric` would take one by one, in
        // the same order: ChaCha8's stream read as little-endian 64-bit words either way).
        let mut words = vec![0u64; x0.len()];
        let r = budget.init_range;
        for _ in 0..budget.population {
            rng.fill(&mut words[..]);
            let mut v = Aligned::zeros(x0.len());
            for ((vj, &c), &w) in v.iter_mut().zip(x0).zip(&words) {
                *vj = c + symmetric_from(w, r);
            }
            clamp_into(&mut v, lo, hi);
            f.push(eval.eval(&v));
            x.push(v);
        }
        Population { x, f }
    }

    /// Index of the best individual (the first one on ties).
    pub(crate) fn best(&self) -> usize {
        let mut b = 0;
        for i in 1..self.f.len() {
            if self.f[i] < self.f[b] {
                b = i;
            }
        }
        b
    }

    pub(crate) fn best_fitness(&self) -> f64 {
        self.f[self.best()]
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The sphere function sum (x_j - c_j)^2 in a box: a known convex problem with optimum 0.
    pub(crate) struct Sphere {
        pub(crate) centre: Vec<f64>,
        pub(crate) x0: Vec<f64>,
        pub(crate) lo: Vec<f64>,
        pub(crate) hi: Vec<f64>,
    }

    impl Sphere {
        pub(crate) fn new(dim: usize) -> Sphere {
            Sphere {
                centre: (0..dim).map(|k| 0.05 * (k % 13) as f64 - 0.3).collect(),
                x0: vec![0.5; dim],
                lo: vec![-2.0; dim],
                hi: vec![2.0; dim],
            }
        }
    }

    impl Problem for Sphere {
        fn dim(&self) -> usize {
            self.x0.len()
        }
        fn initial_point(&self) -> &[f64] {
            &self.x0
        }
        fn bounds(&self) -> (&[f64], &[f64]) {
            (&self.lo, &self.hi)
        }
        fn fitness(&self, x: &[f64]) -> f64 {
            x.iter().zip(&self.centre).map(|(a, b)| (a - b) * (a - b)).sum()
        }
    }

    #[test]
    fn trace_checkpoints_and_final_point() {
        let p = Sphere::new(3);
        let budget = Budget { trace_every_evals: 4, ..Budget::default() };
        let mut e = Evaluator::new(&p, &budget);
        for k in 0..10 {
            e.eval(&[k as f64 * 0.1, 0.0, 0.0]);
        }
        let r = e.finish(vec![0.0; 3], 1.0);
        assert_eq!(r.evaluations, 10);
        assert_eq!(r.trace.iter().map(|t| t.0).collect::<Vec<_>>(), vec![4, 8, 10]);
        // Best so far is monotone.
        assert!(r.trace.windows(2).all(|w| w[1].1 <= w[0].1));
    }

    /// Improvements: every strict decrease of the best, at its 1-based evaluation; equal values
    /// and NaN (recorded as +inf) are not improvements.
    #[test]
    fn improvements_from_the_first_evaluation() {
        let mut p = Sphere::new(1);
        p.centre = vec![0.0];
        let budget = Budget { trace_every_evals: 100, ..Budget::default() };
        let mut e = Evaluator::new(&p, &budget);
        for x in [2.0, 1.0, 1.5, -1.0, 0.5, f64::NAN, 0.25] {
            e.eval(&[x]);
        }
        let r = e.finish(vec![0.25], 4.0);
        assert_eq!(r.improvements, vec![(1, 4.0), (2, 1.0), (5, 0.25), (7, 0.0625)]);
        assert_eq!(r.trace, vec![(7, 0.0625)]);
    }

    /// A run that improves at every evaluation keeps one improvement per log-spaced mark and the
    /// last one: about 20 per decade, each a true (evaluation, best) pair.
    #[test]
    fn improvements_are_thinned_on_log_marks_and_keep_the_last() {
        let mut p = Sphere::new(1);
        p.centre = vec![0.0];
        let mut e = Evaluator::new(&p, &Budget::default());
        let n = 100_000u64;
        for k in 0..n {
            e.eval(&[1.0 / (1.0 + k as f64)]);
        }
        let r = e.finish(vec![0.0], 1.0);
        assert!(
            r.improvements.len() <= 20 * 5 + 2 && r.improvements.len() >= 80,
            "{}",
            r.improvements.len()
        );
        assert_eq!(r.improvements[0], (1, 1.0));
        assert_eq!(*r.improvements.last().unwrap(), (n, r.best_fitness));
        for &(ev, f) in &r.improvements {
            let x = 1.0 / ev as f64;
            assert_eq!(f, x * x, "evaluation {ev}");
        }
        assert!(r.improvements.windows(2).all(|w| w[1].0 > w[0].0 && w[1].1 < w[0].1));
        // Consecutive kept rows are at most one mark apart (a factor 10^(1/20), rounded up).
        for w in r.improvements.windows(2) {
            assert!(w[1].0 <= mark_after(w[0].0).max(w[0].0 + 1), "{w:?}");
        }
        assert_eq!((mark_after(1), mark_after(2), mark_after(9), mark_after(10)), (2, 3, 10, 12));
    }

    #[test]
    fn malformed_problems_and_budgets_are_named() {
        let mut p = Sphere::new(3);
        p.lo[1] = 3.0;
        let e = check_problem(&p).unwrap_err().to_string();
        assert!(e.contains("coordinate 1"), "{e}");
        let b = Budget { population: 3, ..Budget::default() };
        let e = b.validate(4).unwrap_err().to_string();
        assert!(e.contains("budget.population"), "{e}");
        let b = Budget { init_range: -1.0, ..Budget::default() };
        assert!(b.validate(1).unwrap_err().to_string().contains("budget.init_range"));
    }

    #[test]
    fn budget_deserialises_with_defaults_and_rejects_unknown_keys() {
        let b: Budget = toml::from_str("generations = 10").unwrap();
        assert_eq!(b, Budget { generations: 10, ..Budget::default() });
        assert!(toml::from_str::<Budget>("generation = 10").is_err());
    }

    /// The bulk initial population is the per-draw one: x0 + `symmetric` per coordinate in
    /// order, clamped, for lengths whose words end inside and at a ChaCha8 block (16 words), and
    /// the stream is left where the per-draw loop leaves it.
    #[test]
    fn initial_population_is_the_per_draw_one() {
        use crate::optim::sampling::symmetric;
        use rand::{RngCore, SeedableRng};
        for n in [1, 3, 16, 17, 33, 1740] {
            let mut p = Sphere::new(n);
            p.lo = p.x0.iter().map(|c| c - 2e-6).collect();
            let budget = Budget { population: 5, init_range: 5e-6, ..Budget::default() };
            let mut rng = ChaCha8Rng::seed_from_u64(n as u64);
            let mut want_rng = rng.clone();
            let _ = want_rng.next_u32(); // start the blocks off an even word
            let _ = rng.next_u32();
            let mut e = Evaluator::new(&p, &budget);
            let pop = Population::initial(&p, &budget, &mut e, &mut rng);
            for (i, x) in pop.x.iter().enumerate() {
                let want: Vec<f64> = (0..n)
                    .map(|j| (p.x0[j] + symmetric(&mut want_rng, 5e-6)).max(p.lo[j]).min(p.hi[j]))
                    .collect();
                assert!(
                    x.iter().zip(&want).all(|(a, b)| a.to_bits() == b.to_bits()),
                    "n {n} i {i}"
                );
                assert_eq!(pop.f[i], p.fitness(x));
            }
            assert!(pop
                .x
                .iter()
                .flat_map(|x| x.iter())
                .zip(p.lo.iter().cycle())
                .any(|(a, l)| a == l));
            assert_eq!(rng.next_u64(), want_rng.next_u64());
        }
    }
}
