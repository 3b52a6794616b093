//! Chapter 6 wiring: one approach-B fit per (data, net, parameterisation), cached, so every
//! optimiser of a cell starts from the same control net (paired comparisons); each (cell, repeat)
//! runs on its own stream and is logged at once.

pub(crate) mod compare;
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
use crate::spline::{fit_two_view, Approach, Parameterisation};
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
    /// The swept settings of a `--sweep` run (e.g. `optimise.de.f=0.5`); no column otherwise.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub(crate) variant: String,
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
        if self.variant.is_empty() {
            self.optimiser.clone()
        } else {
            format!("{}@{}", self.optimiser, self.variant)
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
    /// The best control points found (for the pictures of Appendices I/J).
    pub(crate) best_x: Vec<f64>,
}

/// What the cell log keeps of a run (a log written before `improvements` existed does not fit:
/// `--resume` then names the cell and stops, as for any change of the record).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct OptimRecord {
    pub(crate) row: OptimRow,
    pub(crate) trace: Vec<(u64, f64)>,
    pub(crate) improvements: Vec<(u64, f64)>,
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
    Ok(out)
}

/// Run one cell (also alone: the same numbers as inside the full run).
pub(crate) fn run_cell(
    spec: &Spec,
    o: &OptimSpec,
    cell: &OptimCell,
    problem: &ControlNetProblem,
) -> Result<OptimRun> {
    let opt = o.tables.get(cell.optimiser);
    let budget = Budget {
        generations: o.generations as u64,
        population: o.population,
        init_range: o.init_range,
        trace_every_evals: o.trace_every_evals,
    };
    let key = cell.key();
    let (r, cpu_s) = runner::optimise(opt, problem, &budget, spec.file.master_seed, &key)?;
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
        variant: spec.variant.label(),
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

impl runner::Logged for OptimRun {
    /// The row and the convergence trace; the best control points are not logged (a run is
    /// deterministic, so the few the pictures need are recomputed: see [`picture_points`]).
    type Record = OptimRecord;
    fn record(&self) -> Self::Record {
        OptimRecord {
            row: self.row.clone(),
            trace: self.trace.clone(),
            improvements: self.improvements.clone(),
        }
    }
}

/// Whether a cell's best control points are kept for the Appendix I/J pictures (the largest
/// control net of its grid).
fn pictured(cell: &OptimCell, largest: GridSize) -> bool {
    cell.cn == largest
}

/// Run every optimisation cell of a spec (its shard's, with `--shard`).
pub(crate) fn run(
    spec: &Spec,
    o: &OptimSpec,
    ctx: &RunContext,
    problems: &BTreeMap<ProblemKey, ControlNetProblem>,
) -> Result<Vec<OptimRun>> {
    let cells = spec::cells(spec, o);
    let largest = cells.iter().map(|c| c.cn).max().unwrap_or(GridSize { nx: 0, ny: 0 });
    let problem = |cell: &OptimCell| &problems[&ProblemKey::new(&cell.dataset, cell.cn, cell.param)];
    let mut runs = runner::run_logged(
        &cells,
        ctx,
        &spec.file.name,
        |cell| {
            let mut r = run_cell(spec, o, cell, problem(cell))?;
            if !pictured(cell, largest) {
                r.best_x = Vec::new();
            }
            Ok(r)
        },
        |cell, rec: OptimRecord| {
            Ok(OptimRun {
                cell: cell.clone(),
                competitor: rec.row.competitor(),
                row: rec.row,
                trace: rec.trace,
                improvements: rec.improvements,
                best_x: Vec::new(),
            })
        },
    )?;
    if ctx.extras {
        picture_points(spec, o, &mut runs, largest, problem)?;
    }
    Ok(runs)
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

/// Give the MIN run of every (data set, parameterisation, optimiser) at the largest net (the
/// Appendix I/J pictures) and the run of each data set whose surfaces go furthest from the data
/// (its 3-D view) their best control points when they are not at hand, by running that cell
/// again; the re-run must reproduce the logged error exactly (a check of determinism across
/// processes).
fn picture_points<'a>(
    spec: &Spec,
    o: &OptimSpec,
    runs: &mut [OptimRun],
    largest: GridSize,
    problem: impl Fn(&OptimCell) -> &'a ControlNetProblem,
) -> Result<()> {
    let mut best: BTreeMap<(String, Parameterisation, crate::optim::Name), usize> = BTreeMap::new();
    for (k, r) in runs.iter().enumerate() {
        if !pictured(&r.cell, largest) {
            continue;
        }
        let e = best
            .entry((r.cell.dataset.clone(), r.cell.param, r.cell.optimiser))
            .or_insert(k);
        if r.row.best < runs[*e].row.best {
            *e = k;
        }
    }
    let wanted: std::collections::BTreeSet<usize> =
        best.into_values().chain(furthest(runs).into_values()).collect();
    for k in wanted {
        if runs[k].best_x.is_empty() {
            let again = run_cell(spec, o, &runs[k].cell, problem(&runs[k].cell))?;
            if again.row.best.to_bits() != runs[k].row.best.to_bits() {
                anyhow::bail!("cell {}: re-run gives {} but the cell log has {} (the code changed since the log was written?)", runs[k].row.cell, again.row.best, runs[k].row.best);
            }
            runs[k].best_x = again.best_x;
        }
    }
    Ok(())
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
        Some(r) => format!("{start}; the search box is B +- {r:e} per coordinate (Table 6.1's \"control point coordinate range [-5e-6, 5e-6]\" read as the search space, as the thesis' tiny improvements over B imply; PSO's maximum velocity is half that box)."),
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
        let problems = problems(first, o, ctx)?;
        let exact = if tables { exact_optima(o, ctx, &problems)? } else { BTreeMap::new() };
        let mut runs = Vec::new();
        for (v, vo) in variants {
            runs.extend(run(v, vo, ctx, &problems)?);
        }
        let section = if tables {
            Some(self::report::write(
                &first.file.name,
                &runs,
                &problems,
                &exact,
                &setting(o),
                &ctx.out,
                ctx.extras,
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
