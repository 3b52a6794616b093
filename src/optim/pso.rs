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
use super::problem::{check_problem, Budget, Evaluator, Optimiser, Population, Problem, RunResult};
use super::sampling::PsoLanes;
use super::{check_range, OptimError};
use crate::simd::moves::{pso_move, PsoBounds, PsoCoefficients};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;

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
    /// Velocity clamp as a fraction of the width of the range `vmax_range` names, per
    /// coordinate, in [0, 1]. Table 6.1, row 11: "PSO Maximum Velocity: Half of the range of the
    /// dataset". 0.5 (default) reads "range" as the search box's width (2 x 5e-6 in the thesis'
    /// specs, so |v| <= 5e-6); 0.25 reads it as Table 6.1's "control point coordinate range
    /// [-5e-6, 5e-6]" taken as +-r, r = 5e-6, so |v| <= r / 2 = 2.5e-6 (the reading of
    /// `ch6_same` and `ch6_diff`, calibrated; the thesis plan's set `as_written` runs 0.5, the
    /// as-written value: docs/readings.md).
    pub vmax_fraction: f64,
    /// The range the velocity clamp is a fraction of: `"search_box"` (default: the problem's
    /// search box, B +- 5e-6 in the thesis' specs, so |v| <= 5e-6) or `"data"` (the data set's
    /// range along the coordinate's axis, so |v| <= half the data's width). A reading of Section
    /// 6.2.2: "The maximum velocity and position of the PSO was set to half of the range of the
    /// data set and the range of the data set respectively. Maximum velocity was used as the
    /// velocity clamping" (Table 6.1, row 11: "PSO Maximum Velocity: Half of the range of the
    /// dataset").
    pub vmax_range: PsoRange,
    /// Where positions are kept: `"search_box"` (default: the problem's search box) or `"data"`
    /// (the data set's range along the coordinate's axis, widened where the search box sticks
    /// out of it so that every start is inside; PSO may then leave the search box that bounds
    /// GA and DE). A reading of Section 6.2.2: "maximum position is set to prevent the particle
    /// from moving beyond the boundaries of the search space" (Table 6.1, row 12: "PSO Maximum
    /// Position: The range of the dataset").
    pub position_range: PsoRange,
}

/// The range a PSO bound is taken from (`vmax_range`, `position_range`): one of two values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PsoRange {
    /// The problem's search box ([`Problem::bounds`]).
    #[default]
    SearchBox,
    /// The data set's range per coordinate ([`Problem::data_range`]).
    Data,
}

impl Default for Pso {
    fn default() -> Pso {
        Pso {
            k: 0.729,
            c1: 2.05,
            c2: 2.05,
            vmax_fraction: 0.5,
            vmax_range: PsoRange::SearchBox,
            position_range: PsoRange::SearchBox,
        }
    }
}

/// The boxes of one run: positions in `lo..hi`, the clamp a fraction of `vlo..vhi`'s width
/// (borrowed from the problem where they are its own, so that by default the move reads the
/// search box's cache lines only).
struct RunBoxes<'a> {
    lo: Cow<'a, [f64]>,
    hi: Cow<'a, [f64]>,
    vlo: &'a [f64],
    vhi: &'a [f64],
}

impl RunBoxes<'_> {
    fn pso_bounds(&self, vmax_fraction: f64) -> PsoBounds<'_> {
        PsoBounds { lo: &self.lo, hi: &self.hi, vlo: self.vlo, vhi: self.vhi, vmax_fraction }
    }
}

impl Pso {
    /// The position box and the clamp's range of `problem` under `position_range` and
    /// `vmax_range`; an error if one names the data and the problem has none.
    fn boxes<'a>(&self, problem: &'a dyn Problem) -> Result<RunBoxes<'a>, OptimError> {
        let (lo, hi) = problem.bounds();
        let uses_data = [self.vmax_range, self.position_range].contains(&PsoRange::Data);
        let (dlo, dhi) = match problem.data_range() {
            Some(d) => d,
            None if uses_data => {
                return Err(OptimError::param(
                    "pso.vmax_range/position_range",
                    "\"data\" needs a problem with a data set's range".to_string(),
                ))
            }
            None => (lo, hi),
        };
        let (vlo, vhi) = match self.vmax_range {
            PsoRange::SearchBox => (lo, hi),
            PsoRange::Data => (dlo, dhi),
        };
        let (lo, hi) = match self.position_range {
            PsoRange::SearchBox => (Cow::Borrowed(lo), Cow::Borrowed(hi)),
            PsoRange::Data => (
                lo.iter().zip(dlo).map(|(a, b)| a.min(*b)).collect(),
                hi.iter().zip(dhi).map(|(a, b)| a.max(*b)).collect(),
            ),
        };
        Ok(RunBoxes { lo, hi, vlo, vhi })
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
    fn validate(&self) -> Result<(), OptimError> {
        Pso::validate(self)
    }
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
        let boxes = self.boxes(problem)?;
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
        let bounds = boxes.pso_bounds(self.vmax_fraction);
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

    /// Sphere's box with a data set's range beside it.
    struct WithData {
        inner: crate::optim::problem::tests::Sphere,
        dlo: Vec<f64>,
        dhi: Vec<f64>,
    }

    impl Problem for WithData {
        fn dim(&self) -> usize {
            self.inner.dim()
        }
        fn initial_point(&self) -> &[f64] {
            self.inner.initial_point()
        }
        fn bounds(&self) -> (&[f64], &[f64]) {
            self.inner.bounds()
        }
        fn data_range(&self) -> Option<(&[f64], &[f64])> {
            Some((&self.dlo, &self.dhi))
        }
        fn fitness(&self, x: &[f64]) -> f64 {
            self.inner.fitness(x)
        }
    }

    /// One move with K = 1, c1 = c2 = 0 (so v is kept, then clamped) from x = (0.5, 0) with
    /// v = (10, 10), in the box [-1, 1]^2 beside data ranges [-4, 4] and [0.5, 0.75], at
    /// vmax_fraction 0.5. By hand: the box's clamp is 0.5 * 2 = 1 on both coordinates, the
    /// data's 0.5 * 8 = 4 and 0.5 * 0.25 = 0.125; positions stay in [-1, 1] (search box), or in
    /// [-4, 4] and [-1, 1] (data, widened to hold the box).
    #[test]
    fn velocity_and_position_ranges_clamp_as_computed_by_hand() {
        use crate::optim::problem::tests::Sphere;
        use crate::simd::moves::pso_move;
        use rand::SeedableRng;
        let mut inner = Sphere::new(2);
        (inner.lo, inner.hi) = (vec![-1.0; 2], vec![1.0; 2]);
        let p = WithData { inner, dlo: vec![-4.0, 0.5], dhi: vec![4.0, 0.75] };
        let (b, d) = (PsoRange::SearchBox, PsoRange::Data);
        let cases = [
            (b, b, [1.0, 1.0], [1.0, 1.0]),
            (d, b, [4.0, 0.125], [1.0, 0.125]),
            (b, d, [1.0, 1.0], [1.5, 1.0]),
            (d, d, [4.0, 0.125], [4.0, 0.125]),
        ];
        for (vmax_range, position_range, v_want, x_want) in cases {
            let pso =
                Pso { k: 1.0, c1: 0.0, c2: 0.0, vmax_range, position_range, ..Pso::default() };
            let boxes = pso.boxes(&p).unwrap();
            let (x, mut v, mut out) = ([0.5, 0.0], [10.0, 10.0], [0.0; 2]);
            let mut lanes = PsoLanes::from_rng(&mut ChaCha8Rng::seed_from_u64(3));
            let co = PsoCoefficients { k: pso.k, c1: pso.c1, c2: pso.c2 };
            let bounds = boxes.pso_bounds(pso.vmax_fraction);
            pso_move(&mut out, &x, &mut v, &[0.0; 2], &[0.0; 2], &mut lanes, co, bounds);
            assert_eq!((v, out), (v_want, x_want), "{vmax_range:?} {position_range:?}");
        }
    }

    #[test]
    fn ranges_are_read_by_name_and_data_needs_a_data_range() {
        let pso: Pso = toml::from_str("vmax_range = \"data\"\nposition_range = \"data\"").unwrap();
        assert_eq!((pso.vmax_range, pso.position_range), (PsoRange::Data, PsoRange::Data));
        assert!(toml::from_str::<Pso>("vmax_range = \"dataset\"").is_err());
        let p = crate::optim::problem::tests::Sphere::new(3);
        assert!(pso.boxes(&p).is_err());
        let b = Pso::default().boxes(&p).unwrap();
        assert_eq!(
            (&b.lo[..], &b.hi[..], b.vlo, b.vhi),
            (&p.lo[..], &p.hi[..], &p.lo[..], &p.hi[..])
        );
    }
}
