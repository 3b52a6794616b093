//! The problem and optimiser traits (argmin's split: a problem says what to minimise, an optimiser
//! how), the evaluation budget, and the tracker that counts evaluations and records the
//! convergence trace at fixed evaluation counts, so that the traces of repeats line up.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// A box-constrained minimisation problem.
pub trait Problem: Sync {
    fn dim(&self) -> usize;
    /// Where the search starts (the thesis: approach B's control points).
    fn initial_point(&self) -> &[f64];
    /// Lower and upper bound of every coordinate.
    fn bounds(&self) -> (&[f64], &[f64]);
    /// The value to minimise.
    fn fitness(&self, x: &[f64]) -> f64;
}

/// How much an optimiser may do.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Budget {
    pub generations: usize,
    pub population: usize,
    /// Half-width r of the initial range: each initial individual is x0 + U[-r, r] per coordinate
    /// (the thesis: 5e-6), clamped to the bounds.
    pub init_range: f64,
}

/// The outcome of one run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunResult {
    pub best_x: Vec<f64>,
    pub best_fitness: f64,
    /// Best fitness of the initial population.
    pub initial_best: f64,
    pub evaluations: u64,
    /// (evaluations, best fitness so far) at the checkpoints of [`checkpoints`] and at the end.
    pub trace: Vec<(u64, f64)>,
}

/// An optimiser: parameters inside, randomness only from the stream it is given.
pub trait Optimiser: Send + Sync {
    fn name(&self) -> &'static str;
    fn run(&self, problem: &dyn Problem, budget: &Budget, rng: &mut ChaCha8Rng) -> RunResult;
}

/// Fixed trace checkpoints: 1, 2, 5 x 10^k evaluations up to `max`.
pub fn checkpoints(max: u64) -> Vec<u64> {
    let mut out = Vec::new();
    let mut base = 1u64;
    'outer: loop {
        for m in [1, 2, 5] {
            let c = m * base;
            if c > max {
                break 'outer;
            }
            out.push(c);
        }
        base *= 10;
    }
    out
}

/// Counts evaluations, keeps the best point, and records the trace.
pub struct Tracker<'a> {
    problem: &'a dyn Problem,
    pub evaluations: u64,
    pub best_fitness: f64,
    pub best_x: Vec<f64>,
    trace: Vec<(u64, f64)>,
    next: usize,
    marks: Vec<u64>,
}

impl<'a> Tracker<'a> {
    pub fn new(problem: &'a dyn Problem, max_evaluations: u64) -> Tracker<'a> {
        Tracker { problem, evaluations: 0, best_fitness: f64::INFINITY, best_x: problem.initial_point().to_vec(), trace: Vec::new(), next: 0, marks: checkpoints(max_evaluations) }
    }

    /// Evaluate `x`, updating the best and the trace.
    pub fn eval(&mut self, x: &[f64]) -> f64 {
        let f = self.problem.fitness(x);
        self.evaluations += 1;
        if f < self.best_fitness {
            self.best_fitness = f;
            self.best_x.copy_from_slice(x);
        }
        while self.next < self.marks.len() && self.marks[self.next] <= self.evaluations {
            self.trace.push((self.marks[self.next], self.best_fitness));
            self.next += 1;
        }
        f
    }

    pub fn finish(mut self, initial_best: f64) -> RunResult {
        if self.trace.last().map(|t| t.0) != Some(self.evaluations) {
            self.trace.push((self.evaluations, self.best_fitness));
        }
        RunResult { best_x: self.best_x, best_fitness: self.best_fitness, initial_best, evaluations: self.evaluations, trace: self.trace }
    }
}

/// Clamp every coordinate into the problem's box.
#[inline]
pub fn clamp_into(x: &mut [f64], lo: &[f64], hi: &[f64]) {
    for ((v, &l), &h) in x.iter_mut().zip(lo).zip(hi) {
        *v = v.clamp(l, h);
    }
}

/// The initial population: x0 + U[-r, r] per coordinate, clamped.
pub fn initial_population(problem: &dyn Problem, budget: &Budget, rng: &mut ChaCha8Rng) -> Vec<Vec<f64>> {
    let x0 = problem.initial_point();
    let (lo, hi) = problem.bounds();
    (0..budget.population)
        .map(|_| {
            let mut x: Vec<f64> = x0.iter().map(|&c| c + budget.init_range * (2.0 * rng.gen::<f64>() - 1.0)).collect();
            clamp_into(&mut x, lo, hi);
            x
        })
        .collect()
}

/// Number of trials until the first success of a Bernoulli(p) sequence, minus one (the count of
/// failures before it): the geometric skip that replaces one uniform draw per gene by one draw
/// per success, with exactly the same distribution.
#[inline]
pub fn geometric_skip(rng: &mut ChaCha8Rng, ln_one_minus_p: f64) -> usize {
    if ln_one_minus_p == f64::NEG_INFINITY {
        return 0;
    }
    if ln_one_minus_p == 0.0 {
        return usize::MAX;
    }
    let u: f64 = 1.0 - rng.gen::<f64>(); // (0, 1]
    let k = (u.ln() / ln_one_minus_p).floor();
    if k >= usize::MAX as f64 {
        usize::MAX
    } else {
        k as usize
    }
}

/// Two uniforms in [0, 1) from one 64-bit draw (32 bits each), for coordinate-wise factors.
#[inline]
pub fn two_uniforms(rng: &mut ChaCha8Rng) -> (f64, f64) {
    let r: u64 = rng.gen();
    const SCALE: f64 = 1.0 / 4_294_967_296.0;
    ((r >> 32) as f64 * SCALE, (r & 0xffff_ffff) as f64 * SCALE)
}

#[cfg(test)]
pub mod tests {
    use super::*;
    use rand::SeedableRng;

    /// The sphere function around `centre`, in a box.
    pub struct Sphere {
        pub centre: Vec<f64>,
        pub x0: Vec<f64>,
        pub lo: Vec<f64>,
        pub hi: Vec<f64>,
    }

    impl Sphere {
        pub fn new(dim: usize) -> Sphere {
            Sphere { centre: (0..dim).map(|k| 0.1 * k as f64 - 0.3).collect(), x0: vec![0.5; dim], lo: vec![-2.0; dim], hi: vec![2.0; dim] }
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
    fn checkpoints_are_1_2_5() {
        assert_eq!(checkpoints(600), vec![1, 2, 5, 10, 20, 50, 100, 200, 500]);
    }

    #[test]
    fn geometric_skip_has_the_bernoulli_rate() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let p: f64 = 0.2;
        let (mut hits, mut pos) = (0usize, 0usize);
        let n = 200_000;
        loop {
            pos += geometric_skip(&mut rng, (1.0 - p).ln());
            if pos >= n {
                break;
            }
            hits += 1;
            pos += 1;
        }
        let rate = hits as f64 / n as f64;
        assert!((rate - p).abs() < 0.005, "{rate}");
    }

    /// Shared checks for every optimiser: determinism, never worse than the initial population,
    /// bounds respected, evaluations as documented, progress on a convex problem.
    pub fn check_optimiser(opt: &dyn Optimiser, evals_per_generation: u64) {
        let p = Sphere::new(12);
        let budget = Budget { generations: 300, population: 20, init_range: 0.3 };
        let a = opt.run(&p, &budget, &mut ChaCha8Rng::seed_from_u64(9));
        let b = opt.run(&p, &budget, &mut ChaCha8Rng::seed_from_u64(9));
        assert_eq!(a, b, "{} is not deterministic", opt.name());
        assert!(a.best_fitness <= a.initial_best);
        assert!(a.best_fitness < 0.5 * a.initial_best, "{}: {} from {}", opt.name(), a.best_fitness, a.initial_best);
        assert_eq!(a.evaluations, 20 + evals_per_generation * 300, "{}", opt.name());
        assert!(a.best_x.iter().all(|&v| (-2.0..=2.0).contains(&v)));
        assert!((p.fitness(&a.best_x) - a.best_fitness).abs() < 1e-15);
        assert!(a.trace.windows(2).all(|w| w[0].0 < w[1].0 && w[1].1 <= w[0].1));
        assert_eq!(a.trace.last().unwrap(), &(a.evaluations, a.best_fitness));
    }
}
