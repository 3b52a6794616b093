//! Seed 003 wiring (Iglesias et al., cuckoo search for Bezier surface approximation): each
//! (example, method, run) draws the run's noisy data, parameterises it (uniform, chordal,
//! centripetal, or CSA/ICSA searching the parameters from a random start population), fits the
//! poles by least squares and records Y; every cell on its own stream, logged at once.
//!
//! The data of run r of an example are the same for every method (the noise comes from the stream
//! of the key `seed003/<example>/data/r<r>`), so the methods' runs pair by index for the signed-rank
//! test; Example III's clean surface and its 628 sampling parameters come from the stream
//! `seed003/example3/surface`, the same in every run.

pub(crate) mod report;
pub(crate) mod spec;

use crate::experiment::spec::Spec;
use crate::experiment::{runner, seeds, RunContext};
use crate::geom::Point3;
use crate::optim::{Budget, Csa, Icsa, Problem};
use crate::spline::bezier::{self, BezierParamProblem, Layout};
use crate::spline::Parameterisation;
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

/// The three examples in order.
pub(crate) const EXAMPLES: [&str; 3] = ["example1", "example2", "example3"];
/// The five methods in the paper's Table 4 order.
pub(crate) const METHODS: [&str; 5] = ["uniform", "chordal", "centripetal", "csa", "icsa"];

/// One example's data and budget.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExampleSpec {
    /// Grid side (Examples I, II: a size x size grid) or number of points (Example III).
    pub size: usize,
    /// Degree (eta, sigma) = (degree, degree) of the Bezier surface.
    pub degree: usize,
    /// Signal-to-noise ratio of the Gaussian noise, dB.
    pub snr_db: f64,
    /// CSA/ICSA iterations.
    pub generations: usize,
}

/// Where CSA/ICSA's start population lies (docs/readings.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Start {
    /// Section 5.2: "All data parameters are initialized with random numbers within the
    /// hypercube \[0,1\]^m x \[0,1\]^n": U[0, 1] per parameter.
    #[default]
    Random,
    /// Section 4.3's per-component bounds low_j^k, up_j^k read as a box around a classical
    /// parameterisation (Eqs. 11-13): that parameterisation +- `start_spread`, clamped to [0, 1].
    UniformParam,
    Chordal,
    Centripetal,
}

impl Start {
    /// The classical parameterisation the start is centred on (None: the random start).
    pub fn classical(self) -> Option<Parameterisation> {
        match self {
            Start::Random => None,
            Start::UniformParam => Some(Parameterisation::Uniform),
            Start::Chordal => Some(Parameterisation::ChordLength),
            Start::Centripetal => Some(Parameterisation::Centripetal),
        }
    }

    /// The spec value.
    pub fn key(self) -> &'static str {
        match self {
            Start::Random => "random",
            Start::UniformParam => "uniform_param",
            Start::Chordal => "chordal",
            Start::Centripetal => "centripetal",
        }
    }
}

fn default_start_spread() -> f64 {
    0.05
}

/// The `[cuckoo_bezier]` section.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CuckooBezierSpec {
    /// example1 (Franke), example2 (peaks), example3 (self-intersecting Bezier surface).
    pub examples: Vec<String>,
    /// uniform, chordal, centripetal, csa, icsa.
    pub methods: Vec<String>,
    /// Independent executions per (example, method) (the paper: 50).
    pub runs: usize,
    /// Host nests N_p (the paper: 100).
    pub nests: usize,
    /// Convergence trace: one point every this many iterations.
    pub trace_every: usize,
    /// Significance level of the tests (Table 5: 0.05).
    pub alpha: f64,
    pub example1: ExampleSpec,
    pub example2: ExampleSpec,
    pub example3: ExampleSpec,
    /// CSA/ICSA start: `random` (Section 5.2, the default) or centred on a classical
    /// parameterisation (`uniform_param`, `chordal`, `centripetal`) +- `start_spread`.
    #[serde(default)]
    pub start: Start,
    /// Half-width of the centred start box, in (0, 0.5] (unused by `random`).
    #[serde(default = "default_start_spread")]
    pub start_spread: f64,
    #[serde(default)]
    pub csa: Csa,
    #[serde(default)]
    pub icsa: Icsa,
}

impl CuckooBezierSpec {
    pub fn example(&self, name: &str) -> Option<&ExampleSpec> {
        match name {
            "example1" => Some(&self.example1),
            "example2" => Some(&self.example2),
            "example3" => Some(&self.example3),
            _ => None,
        }
    }

    /// Checks of the section, as (key, message) of the first fault.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let bad = |k: &str, m: String| Err((format!("cuckoo_bezier.{k}"), m));
        if self.examples.is_empty() {
            return bad("examples", "is empty".into());
        }
        if let Some(e) = self.examples.iter().find(|e| !EXAMPLES.contains(&e.as_str())) {
            return bad(
                "examples",
                format!("unknown example `{e}` (expected example1, example2 or example3)"),
            );
        }
        if self.methods.is_empty() {
            return bad("methods", "is empty".into());
        }
        if let Some(m) = self.methods.iter().find(|m| !METHODS.contains(&m.as_str())) {
            return bad(
                "methods",
                format!(
                    "unknown method `{m}` (expected uniform, chordal, centripetal, csa or icsa)"
                ),
            );
        }
        if self.runs == 0 {
            return bad("runs", "must be at least 1".into());
        }
        if self.nests < 2 {
            return bad("nests", format!("must be at least 2, got {}", self.nests));
        }
        if self.trace_every == 0 {
            return bad("trace_every", "must be at least 1".into());
        }
        if !(self.alpha > 0.0 && self.alpha < 1.0) {
            return bad("alpha", format!("must be in (0, 1), got {}", self.alpha));
        }
        if !(self.start_spread > 0.0 && self.start_spread <= 0.5) {
            return bad("start_spread", format!("must be in (0, 0.5], got {}", self.start_spread));
        }
        for name in EXAMPLES {
            let e = self.example(name).expect("known example");
            let key = |k: &str| format!("{name}.{k}");
            let min =
                if name == "example3" { (e.degree + 1) * (e.degree + 1) } else { e.degree + 1 };
            if e.degree == 0 || e.size < min.max(3) {
                return bad(
                    &key("size"),
                    format!(
                        "{} is too small for degree {} (at least {})",
                        e.size,
                        e.degree,
                        min.max(3)
                    ),
                );
            }
            if !(e.snr_db.is_finite()) {
                return bad(
                    &key("snr_db"),
                    format!("must be a finite number of dB, got {}", e.snr_db),
                );
            }
            if e.generations == 0 {
                return bad(&key("generations"), "must be at least 1".into());
            }
        }
        Ok(())
    }
}

/// One (example, method, run).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Cell {
    pub(crate) example: String,
    pub(crate) method: String,
    pub(crate) run: usize,
}

impl Cell {
    pub(crate) fn key(&self) -> String {
        format!("seed003/{}/{}/r{}", self.example, self.method, self.run)
    }
}

impl runner::Cell for Cell {
    fn key(&self) -> String {
        Cell::key(self)
    }
}

/// One row of runs.csv.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub(crate) struct Row {
    pub(crate) cell: String,
    pub(crate) example: String,
    pub(crate) method: String,
    pub(crate) run: usize,
    /// The cell's stream (CSA/ICSA start population and moves).
    pub(crate) seed: String,
    /// The stream of the run's noise (shared by the five methods).
    pub(crate) data_seed: String,
    pub(crate) n_points: usize,
    pub(crate) degree: usize,
    /// Parameters searched (grid: one per column and row; scattered: two per point).
    pub(crate) dimension: usize,
    pub(crate) snr_db: f64,
    /// Standard deviation of the noise drawn for this run's data.
    pub(crate) noise_sigma: f64,
    /// Sum of squared distances of the data to the fitted surface (the paper's Eq. 4/5).
    pub(crate) y: f64,
    /// sqrt(Y / n_points) (the paper's Eq. 14/15).
    pub(crate) rmse: f64,
    /// Best Y of the start population (CSA/ICSA); Y itself for a classical parameterisation.
    pub(crate) initial_best_y: f64,
    pub(crate) evaluations: u64,
    pub(crate) iterations: usize,
    pub(crate) cpu_s: f64,
}

/// One run with its convergence trace (evaluations, best Y so far).
#[derive(Debug, Clone)]
pub(crate) struct Run {
    pub(crate) row: Row,
    pub(crate) trace: Vec<(u64, f64)>,
}

impl runner::Logged for Run {
    type Record = (Row, Vec<(u64, f64)>);
    fn record(&self) -> Self::Record {
        (self.row.clone(), self.trace.clone())
    }
}

/// The flat list of cells: examples x methods x runs.
pub(crate) fn cells(s: &CuckooBezierSpec) -> Vec<Cell> {
    runner::product_cells(&s.examples, &s.methods, s.runs, |e, m, run| Cell {
        example: e.clone(),
        method: m.clone(),
        run,
    })
}

/// Data of one run: the points, their layout, and the noise sigma.
pub(crate) struct Data {
    pub(crate) points: Vec<Point3>,
    pub(crate) layout: Layout,
    pub(crate) sigma: f64,
}

/// The clean data of an example (Example III from its fixed stream).
pub(crate) fn clean(master_seed: u64, example: &str, e: &ExampleSpec) -> Result<(Vec<Point3>, Layout)> {
    Ok(match example {
        "example1" => (
            bezier::height_grid(bezier::franke, e.size, 0.0, 1.0),
            Layout::Grid { nu: e.size, nv: e.size },
        ),
        "example2" => (
            bezier::height_grid(bezier::peaks, e.size, -3.0, 3.0),
            Layout::Grid { nu: e.size, nv: e.size },
        ),
        "example3" => {
            let mut rng = seeds::cell_rng(master_seed, "seed003/example3/surface");
            (bezier::example3(e.size, &mut rng).1, Layout::Scattered)
        }
        other => anyhow::bail!("cuckoo_bezier.examples: unknown example `{other}`"),
    })
}

fn data_key(example: &str, run: usize) -> String {
    format!("seed003/{example}/data/r{run}")
}

/// Run r's noisy data of an example.
pub(crate) fn data(master_seed: u64, example: &str, e: &ExampleSpec, run: usize) -> Result<Data> {
    let (mut points, layout) = clean(master_seed, example, e)?;
    let mut rng = seeds::cell_rng(master_seed, &data_key(example, run));
    let sigma = bezier::add_noise(&mut points, e.snr_db, &mut rng);
    Ok(Data { points, layout, sigma })
}

fn classical(method: &str) -> Option<Parameterisation> {
    match method {
        "uniform" => Some(Parameterisation::Uniform),
        "chordal" => Some(Parameterisation::ChordLength),
        "centripetal" => Some(Parameterisation::Centripetal),
        _ => None,
    }
}

/// The decision vector of a classical parameterisation of the data.
pub(crate) fn classical_start(d: &Data, p: Parameterisation) -> Vec<f64> {
    match d.layout {
        Layout::Grid { nu, nv } => bezier::classical_grid_start(&d.points, nu, nv, p),
        Layout::Scattered => bezier::classical_scattered_start(&d.points, p),
    }
}

/// The CSA/ICSA budget of an example: N nests, G iterations; the start population is uniform on
/// [0, 1]^dim (centre 0.5, half-width 0.5) under `start = "random"`, else the centre +-
/// `start_spread`; one trace point every `trace_every` iterations (2N evaluations per iteration).
pub(crate) fn budget(s: &CuckooBezierSpec, e: &ExampleSpec) -> Budget {
    Budget {
        generations: e.generations as u64,
        population: s.nests,
        init_range: if s.start == Start::Random { 0.5 } else { s.start_spread },
        trace_every_evals: (2 * s.nests * s.trace_every) as u64,
    }
}

/// Run one cell (alone it gives the same numbers as inside the full run).
pub(crate) fn run_cell(spec: &Spec, s: &CuckooBezierSpec, cell: &Cell) -> Result<Run> {
    let e = s
        .example(&cell.example)
        .with_context(|| format!("cuckoo_bezier.examples: unknown example `{}`", cell.example))?;
    let key = cell.key();
    let master = spec.file.master_seed;
    let d = data(master, &cell.example, e, cell.run)?;
    let n = d.points.len();
    let ((y, initial, evaluations, iterations, trace, dim), cpu_s) = if let Some(p) =
        classical(&cell.method)
    {
        let x = classical_start(&d, p);
        let prob = BezierParamProblem::new(e.degree, e.degree, d.layout, d.points, x.clone())
            .map_err(|err| anyhow::anyhow!("{key}: {err}"))?;
        let (y, cpu_s) = runner::timed(|| prob.fitness(&x));
        ((y, y, 1, 0, Vec::new(), prob.dim()), cpu_s)
    } else {
        // The start population's centre: [0, 1]^dim's, or a classical parameterisation's.
        let centre = match s.start.classical() {
            None => vec![
                0.5;
                match d.layout {
                    Layout::Grid { nu, nv } => nu + nv,
                    Layout::Scattered => 2 * n,
                }
            ],
            Some(p) => classical_start(&d, p),
        };
        let prob = BezierParamProblem::new(e.degree, e.degree, d.layout, d.points, centre)
            .map_err(|err| anyhow::anyhow!("{key}: {err}"))?;
        let opt: &dyn crate::optim::Optimiser = match cell.method.as_str() {
            "csa" => &s.csa,
            "icsa" => &s.icsa,
            m => anyhow::bail!("cuckoo_bezier.methods: `{m}` is not a cuckoo search"),
        };
        let (r, cpu_s) = runner::optimise(opt, &prob, &budget(s, e), master, &key)?;
        let dim = prob.dim();
        ((r.best_fitness, r.initial_best_fitness, r.evaluations, e.generations, r.trace, dim), cpu_s)
    };
    let row = Row {
        cell: key.clone(),
        example: cell.example.clone(),
        method: cell.method.clone(),
        run: cell.run,
        seed: seeds::seed_hex(master, &key),
        data_seed: seeds::seed_hex(master, &data_key(&cell.example, cell.run)),
        n_points: n,
        degree: e.degree,
        dimension: dim,
        snr_db: e.snr_db,
        noise_sigma: d.sigma,
        y,
        rmse: (y / n as f64).sqrt(),
        initial_best_y: initial,
        evaluations,
        iterations,
        cpu_s,
    };
    Ok(Run { row, trace })
}

/// Run every cell of the spec.
pub(crate) fn run(spec: &Spec, s: &CuckooBezierSpec, ctx: &RunContext) -> Result<Vec<Run>> {
    let cells = cells(s);
    runner::run_logged(
        &cells,
        ctx,
        &spec.file.name,
        |cell| run_cell(spec, s, cell),
        |_, (row, trace)| Ok(Run { row, trace }),
    )
}

/// Seed 003's family: the `[cuckoo_bezier]` section.
pub(crate) struct CuckooBezier;

impl crate::experiment::family::Experiment for CuckooBezier {
    fn title(&self) -> &'static str {
        "Seed 003"
    }
    fn published(&self) -> crate::report::reference::Published {
        self::report::PUBLISHED
    }
    type Section = CuckooBezierSpec;
    fn logged_keys(&self, _spec: &Spec, s: &CuckooBezierSpec) -> Vec<String> {
        cells(s).iter().map(|c| c.key()).collect()
    }
    fn run(
        &self,
        spec: &Spec,
        s3: &CuckooBezierSpec,
        ctx: &RunContext,
        tables: bool,
    ) -> Result<crate::experiment::family::Outcome> {
        let runs = run(spec, s3, ctx)?;
        let section = if tables { Some(self::report::write(&spec.file.name, s3, &runs, &ctx.out)?) } else { None };
        Ok(crate::experiment::family::Outcome {
            section,
            cpu_s: runs.iter().map(|r| r.row.cpu_s).sum(),
            cells: runs.len(),
        })
    }
}

impl CuckooBezierSpec {
    /// The optimisers this section offers, each with its parameter table (`csa`, ...).
    pub fn offered(&self) -> Vec<&dyn crate::optim::Optimiser> {
        vec![&self.csa, &self.icsa]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec_with(extra: &str) -> Result<crate::families::Loaded, crate::experiment::spec::SpecError> {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/experiments/seed003_cuckoo_bezier.toml");
        let text = std::fs::read_to_string(path).unwrap();
        let text = text.replacen("[cuckoo_bezier]\n", &format!("[cuckoo_bezier]\n{extra}\n"), 1);
        crate::families::Loaded::parse(path, &text, Some("quick"))
    }

    fn csa_example3(spec: &crate::families::Loaded) -> Row {
        let cell = Cell { example: "example3".into(), method: "csa".into(), run: 0 };
        run_cell(&spec.spec, spec.section_as().unwrap(), &cell).unwrap().row
    }

    /// The default start is Section 5.2's U[0,1]; a centred start begins next to its classical
    /// parameterisation (centripetal Y within 2x) and far below the random start.
    #[test]
    fn start_readings() {
        let random = spec_with("").unwrap();
        let s = random.section_as::<CuckooBezierSpec>().unwrap();
        assert_eq!((s.start, budget(s, &s.example3).init_range), (Start::Random, 0.5));
        let centred = spec_with("start = \"centripetal\"\nstart_spread = 0.01").unwrap();
        let c = centred.section_as::<CuckooBezierSpec>().unwrap();
        assert_eq!(budget(c, &c.example3).init_range, 0.01);
        let classical = run_cell(
            &random.spec,
            s,
            &Cell { example: "example3".into(), method: "centripetal".into(), run: 0 },
        )
        .unwrap()
        .row
        .y;
        let (r, k) = (csa_example3(&random), csa_example3(&centred));
        assert!(k.initial_best_y < 2.0 * classical, "{} vs {classical}", k.initial_best_y);
        assert!(k.initial_best_y < 0.5 * r.initial_best_y, "{} {}", k.initial_best_y, r.initial_best_y);
        for bad in ["start_spread = 0.0", "start_spread = 0.6"] {
            let e = spec_with(bad).unwrap_err().to_string();
            assert!(e.contains("cuckoo_bezier.start_spread"), "{e}");
        }
        assert!(spec_with("start = \"somewhere\"").unwrap_err().to_string().contains("unknown variant `somewhere`"));
    }
}
