//! Chapter 6 wiring: one approach-B fit per (data, net, parameterisation), cached, so every
//! optimiser of a cell starts from the same control net (paired comparisons); each (cell, repeat)
//! runs on its own stream and is logged at once.

pub(crate) mod compare;
pub(crate) mod export;
pub(crate) mod external;
pub(crate) mod ioh;
pub(crate) mod overall;
pub(crate) mod pictures;
pub(crate) mod report;
pub(crate) mod spec;

use crate::experiment::spec::GridSize;
use crate::experiment::spec::Spec;
use crate::experiment::{runner, seeds, RunContext};
use crate::families::maps;
use crate::optim::{Budget, Problem};
use crate::spline::BoxSpec;
use crate::spline::ControlNetProblem;
use crate::spline::{fit_two_view, Approach};
use crate::experiment::packed::PackedPoints;
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use spec::OptimCell;
use std::collections::BTreeMap;
pub use spec::OptimSpec;

/// The cell of a `runs.csv` row as `somnurbs compare` groups rows from any folders: the data
/// set, grid, control net and parameterisation as written (its own, beside [`ProblemKey`]: rows
/// of several specs and grids meet here, and an external optimiser's rows are matched by name).
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct ComparedCell {
    pub(crate) data: String,
    pub(crate) grid: GridSize,
    pub(crate) cn: GridSize,
    pub(crate) param: String,
}

/// One row of a Chapter 6 `runs.csv`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub(crate) struct OptimRow {
    pub(crate) cell: String,
    pub(crate) dataset: String,
    pub(crate) grid_x: usize,
    pub(crate) grid_y: usize,
    pub(crate) cn_x: usize,
    pub(crate) cn_y: usize,
    pub(crate) parameterisation: String,
    pub(crate) optimiser: String,
    /// The swept settings of a `--sweep` run that reach the row's cell (e.g. `optimise.de.f=0.5`;
    /// empty for a cell no swept setting reaches); no column without `--sweep`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) variant: Option<String>,
    pub(crate) repeat: usize,
    pub(crate) seed: String,
    pub(crate) dimension: usize,
    /// Surface error of approach B (the start).
    pub(crate) b: f64,
    /// Best fitness of the initial population.
    pub(crate) initial_best: f64,
    /// Best fitness found (Eq. 6.2).
    pub(crate) best: f64,
    pub(crate) evaluations: u64,
    /// The best surfaces between the data points (dense evaluation, see `spline::geometry`).
    pub(crate) excursion: f64,
    pub(crate) max_control: f64,
    pub(crate) cpu_s: f64,
}

impl OptimRow {
    /// The cell this row belongs to, as `compare` groups rows.
    pub(crate) fn compared_cell(&self) -> ComparedCell {
        ComparedCell {
            data: self.dataset.clone(),
            grid: GridSize { nx: self.grid_x, ny: self.grid_y },
            cn: GridSize { nx: self.cn_x, ny: self.cn_y },
            param: self.parameterisation.clone(),
        }
    }

    /// What `compare` and the tables rank: the optimiser, or in a sweep `optimiser@variant`.
    pub(crate) fn competitor(&self) -> String {
        match self.variant.as_deref() {
            None | Some("") => self.optimiser.clone(),
            Some(v) => format!("{}@{v}", self.optimiser),
        }
    }
}

/// One optimiser run.
#[derive(Debug, Clone)]
pub(crate) struct OptimRun {
    pub(crate) cell: OptimCell,
    /// What the tables, charts and `compare` rank it as: its optimiser, or in a sweep
    /// `optimiser@variant` ([`OptimRow::competitor`]).
    pub(crate) competitor: String,
    pub(crate) row: OptimRow,
    pub(crate) trace: Vec<(u64, f64)>,
    /// (evaluation, fitness) at every improvement of the best so far, from evaluation 1 (the
    /// IOHprofiler `.dat` rows and the runtime distributions of `compare`).
    pub(crate) improvements: Vec<(u64, f64)>,
    /// The best control points found: the optimised net (pictures, 3-D views, `export`).
    pub(crate) best_x: Vec<f64>,
}

/// What the cell log keeps of a run: its one result, from which every table, picture and
/// export is made (a log written before `best_x` was kept does not fit: `--resume` then names
/// the cell and stops, as for any change of the record).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct OptimRecord {
    pub(crate) row: OptimRow,
    pub(crate) trace: Vec<(u64, f64)>,
    pub(crate) improvements: Vec<(u64, f64)>,
    /// The best control points, bit for bit (x, y, z of each control point in turn).
    pub(crate) best_x: PackedPoints,
}

pub use crate::families::maps::ProblemKey;

/// The certified exact optimum of every problem, when the spec asks for it (deterministic, so
/// computed once per problem and in parallel).
pub fn exact_optima(
    o: &OptimSpec,
    ctx: &RunContext,
    problems: &BTreeMap<ProblemKey, ControlNetProblem>,
) -> Result<BTreeMap<ProblemKey, crate::optim::exact::ExactResult>> {
    if !o.exact {
        return Ok(BTreeMap::new());
    }
    let keys: Vec<&ProblemKey> = problems.keys().collect();
    let solved = runner::run_cells(
        &keys,
        ctx.jobs,
        "exact optima",
        |k| {
            problems[*k].exact_optimum(&o.exact_options()).map_err(|e| {
                anyhow::anyhow!("exact optimum of {k}: {e}")
            })
        },
        |_, _| Ok(()),
    )?;
    Ok(keys.into_iter().cloned().zip(solved).collect())
}

/// The control-net problems of every (data, net, parameterisation), from approach B's fit.
pub fn problems(
    spec: &Spec,
    o: &OptimSpec,
    ctx: &RunContext,
) -> Result<BTreeMap<ProblemKey, ControlNetProblem>> {
    Ok(problems_and_near(spec, o, ctx)?.0)
}

/// [`problems`], and per data set what counts as near its data ([`maps::near_bound`]).
pub(crate) fn problems_and_near(
    spec: &Spec,
    o: &OptimSpec,
    ctx: &RunContext,
) -> Result<(BTreeMap<ProblemKey, ControlNetProblem>, BTreeMap<String, f64>)> {
    let from = maps::MapsFrom {
        section: "optimise",
        dir: o.maps.as_deref(),
        missing: o.maps_missing,
        som: o.som.as_ref(),
    };
    let maps = maps::maps_for(spec, ctx, &o.datasets, o.grid, &from)?;
    let mut out = BTreeMap::new();
    for entry in &o.datasets {
        let d = &crate::data::registry::name_of(entry);
        for &cn in &o.control_nets {
            for &param in &o.parameterisations {
                let grid = &maps[d].grid;
                let fit =
                    fit_two_view(grid, cn.nx, cn.ny, param, Approach::Improved, &o.fit_options())
                        .with_context(|| format!("{d} {cn} {param}"))?;
                let parts = fit.control_net_parts(grid)?;
                let bounds = match o.search_range {
                    Some(half_width) => BoxSpec::AroundStart { half_width },
                    None => BoxSpec::Cover { fraction: o.bounds_margin },
                };
                let problem = ControlNetProblem::new(parts, bounds)
                    .with_context(|| format!("{d} {cn} {param}"))?;
                out.insert(ProblemKey::new(d, cn, param), problem);
            }
        }
    }
    Ok((out, maps::near_bounds(&maps)))
}

/// Run one cell (also alone: the same numbers as inside the full run) on its place's stream.
pub(crate) fn run_cell(
    spec: &Spec,
    o: &OptimSpec,
    cell: &OptimCell,
    problem: &ControlNetProblem,
) -> Result<OptimRun> {
    let opt = o.tables.get(cell.optimiser);
    let key = cell.key();
    let (r, cpu_s) = runner::optimise(opt, problem, &budget(o), spec.file.master_seed, &key)?;
    if !r.best_fitness.is_finite() {
        anyhow::bail!("{key}: the best fitness is not finite ({})", r.best_fitness);
    }
    let dense = problem.parts().dense_geometry(&r.best_x);
    let row = OptimRow {
        cell: key.clone(),
        dataset: cell.dataset.clone(),
        grid_x: cell.grid.nx,
        grid_y: cell.grid.ny,
        cn_x: cell.cn.nx,
        cn_y: cell.cn.ny,
        parameterisation: cell.param.name().into(),
        optimiser: cell.optimiser.to_string(),
        variant: (!spec.variant.swept.is_empty()).then(|| cell.variant.clone()),
        repeat: cell.repeat,
        seed: seeds::seed_hex(spec.file.master_seed, &key),
        dimension: problem.dim(),
        b: problem.fitness(problem.initial_point()),
        initial_best: r.initial_best_fitness,
        best: r.best_fitness,
        evaluations: r.evaluations,
        excursion: dense.excursion,
        max_control: dense.max_control,
        cpu_s,
    };
    Ok(OptimRun {
        cell: cell.clone(),
        competitor: row.competitor(),
        row,
        trace: r.trace,
        improvements: r.improvements,
        best_x: r.best_x,
    })
}

/// The budget of every run of a section.
fn budget(o: &OptimSpec) -> Budget {
    Budget {
        generations: o.generations as u64,
        population: o.population,
        init_range: o.init_range,
        trace_every_evals: o.trace_every_evals,
    }
}

impl runner::Logged for OptimRun {
    type Record = OptimRecord;
    fn record(&self) -> Self::Record {
        OptimRecord {
            row: self.row.clone(),
            trace: self.trace.clone(),
            improvements: self.improvements.clone(),
            best_x: PackedPoints {
                points: self.best_x.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect(),
                single: false,
            },
        }
    }
}

/// A cell of one variant of a run, known by what it computes: its place (the stream), the
/// problem's content ([`ControlNetProblem::digest`]), the optimiser's parameter table, the
/// budget and the master seed. Two variants' cells with one identity are one cell, computed
/// once; a folder named by `--reuse` gives the record of a cell with the same identity.
struct Job {
    cell: OptimCell,
    /// Index of the variant whose section runs it (the first that has it).
    variant: usize,
    identity: String,
}

impl runner::Cell for Job {
    fn key(&self) -> String {
        self.identity.clone()
    }
}

/// The identity of `cell` under section `o` (see [`Job`]).
fn identity(spec: &Spec, o: &OptimSpec, cell: &OptimCell, digest: &[u8; 32]) -> String {
    let b = budget(o);
    let table = format!("{:?}", o.tables.get(cell.optimiser));
    let budget = format!(
        "{} {} {:016x} {}",
        b.generations,
        b.population,
        b.init_range.to_bits(),
        b.trace_every_evals
    );
    seeds::identity_key(
        &cell.key(),
        &[&spec.file.master_seed.to_le_bytes(), digest, table.as_bytes(), budget.as_bytes()],
    )
}

/// The cells of every variant, each identity once, in the variants' order.
fn jobs(
    variants: &[(&Spec, &OptimSpec)],
    problems: &BTreeMap<ProblemKey, ControlNetProblem>,
) -> Vec<Job> {
    let digests: BTreeMap<&ProblemKey, [u8; 32]> =
        problems.iter().map(|(k, p)| (k, p.digest())).collect();
    let mut seen = std::collections::BTreeSet::new();
    let mut jobs = Vec::new();
    for (v, (spec, o)) in variants.iter().enumerate() {
        for cell in spec::cells(spec, o) {
            let digest = &digests[&ProblemKey::new(&cell.dataset, cell.cn, cell.param)];
            let identity = identity(spec, o, &cell, digest);
            if seen.insert(identity.clone()) {
                jobs.push(Job { cell, variant: v, identity });
            }
        }
    }
    jobs
}

/// Run every optimisation cell of the variants (their shard's, with `--shard`), each identity
/// once, taking the records the folder's log or a `--reuse` folder holds.
pub(crate) fn run(
    variants: &[(&Spec, &OptimSpec)],
    ctx: &RunContext,
    problems: &BTreeMap<ProblemKey, ControlNetProblem>,
) -> Result<Vec<OptimRun>> {
    let jobs = jobs(variants, problems);
    let problem = |cell: &OptimCell| &problems[&ProblemKey::new(&cell.dataset, cell.cn, cell.param)];
    runner::run_logged(
        &jobs,
        ctx,
        &variants[0].0.file.name,
        |job| {
            let (spec, o) = variants[job.variant];
            run_cell(spec, o, &job.cell, problem(&job.cell))
        },
        |job, rec: OptimRecord| {
            Ok(OptimRun {
                cell: job.cell.clone(),
                competitor: rec.row.competitor(),
                row: rec.row,
                trace: rec.trace,
                improvements: rec.improvements,
                best_x: rec.best_x.points.into_iter().flatten().collect(),
            })
        },
    )
}

/// The run of each (grid, data set) whose best surfaces go furthest from the data (largest dense
/// excursion; the first of equal ones), by index into `runs`: its 3-D view in report.html.
pub(crate) fn furthest(runs: &[OptimRun]) -> BTreeMap<(GridSize, String), usize> {
    let mut out: BTreeMap<(GridSize, String), usize> = BTreeMap::new();
    for (k, r) in runs.iter().enumerate() {
        let f = out.entry((r.cell.grid, r.cell.dataset.clone())).or_insert(k);
        if r.row.excursion > runs[*f].row.excursion {
            *f = k;
        }
    }
    out
}

/// One sentence on the start and the search box of a spec's runs, for the report.
pub(crate) fn setting(o: &OptimSpec) -> String {
    let fair = if o.fairness > 0.0 { format!(", fairness {:e}", o.fairness) } else { String::new() };
    let start = format!(
        "Readings: knots `{}`{fair} (docs/readings.md). Each individual starts at B + U[-{r:e}, {r:e}] per coordinate",
        o.knots.name(),
        r = o.init_range
    );
    match o.search_range {
        Some(r) if r == crate::experiment::defaults::init_range() => format!("{start}; the search box is B +- {r:e} per coordinate (Table 6.1's \"control point coordinate range [-5e-6, 5e-6]\" read as the search space, as the thesis' tiny improvements over B imply; PSO's maximum velocity is half that box)."),
        Some(r) => format!("{start}; the search box is B +- {r:e} per coordinate (the spec's `search_range`; the thesis' reading of Table 6.1 gives B +- 5e-6; PSO's maximum velocity is half that box)."),
        None if o.bounds_margin == 0.0 => format!("{start}; the search box is the smallest per-axis box holding the data and B's control points."),
        None => format!("{start}; the search box is the smallest per-axis box holding the data and B's control points, widened by {} of its size on each side.", o.bounds_margin),
    }
}

/// Chapter 6's family: the `[optimise]` section.
pub(crate) struct Optim;

/// What `--sweep` may vary in `[optimise]`: every registered optimiser's table (a table the section
/// does not have is refused when the variant is read) and the run's budget and start range.
fn sweepable_keys() -> Vec<String> {
    let opts = crate::optim::Name::all().map(|n| format!("optimise.{n}."));
    opts.chain(
        ["optimise.generations", "optimise.population", "optimise.init_range", "optimise.repeats"]
            .map(String::from),
    )
    .collect()
}

impl crate::experiment::family::Experiment for Optim {
    fn title(&self) -> &'static str {
        "Chapter 6"
    }
    fn published(&self) -> crate::report::reference::Published {
        self::report::PUBLISHED
    }
    type Section = self::spec::OptimSpec;
    fn logged_keys(&self, spec: &Spec, s: &OptimSpec) -> Vec<String> {
        spec::cells(spec, s).iter().map(|c| c.key()).collect()
    }
    fn run(
        &self,
        spec: &Spec,
        s: &OptimSpec,
        ctx: &RunContext,
        tables: bool,
    ) -> Result<crate::experiment::family::Outcome> {
        self.run_variants(&[(spec, s)], ctx, tables)
    }
    fn combine(
        &self,
        view: &crate::experiment::family::PlanView<OptimSpec>,
    ) -> Result<crate::experiment::family::Combined> {
        overall::combine(view)
    }
    /// Every variant's cells on the first variant's problems (a sweep varies optimiser settings
    /// only), then one set of tables in which each `optimiser@variant` of a sweep is a column.
    fn run_variants(
        &self,
        variants: &[(&Spec, &OptimSpec)],
        ctx: &RunContext,
        tables: bool,
    ) -> Result<crate::experiment::family::Outcome> {
        let [(first, o), ..] = variants else { anyhow::bail!("no variant to run") };
        let (problems, near) = problems_and_near(first, o, ctx)?;
        let exact = if tables { exact_optima(o, ctx, &problems)? } else { BTreeMap::new() };
        let runs = run(variants, ctx, &problems)?;
        let section = if tables {
            Some(self::report::write(
                &first.file.name,
                &runs,
                &problems,
                &exact,
                &self::report::AsRun {
                    setting: setting(o),
                    init_range: o.init_range,
                    near,
                    extras: ctx.extras,
                },
                &ctx.out,
            )?)
        } else {
            None
        };
        if tables && ctx.extras {
            crate::report::views3d::write(&ctx.out, &pictures::views(&runs, &problems))?;
        }
        Ok(crate::experiment::family::Outcome {
            section,
            cpu_s: runs.iter().map(|r| r.row.cpu_s).sum(),
            cells: runs.len(),
        })
    }
}
