//! Seed 001 wiring: one Growing Grid per data set (its own stream `seed001/map/<data>`), one open
//! cubic B-spline problem per (data, net, parameterisation) from the least-squares fit of that map,
//! then every (problem, optimiser, repeat) cell on its own stream, logged at once.

pub(crate) mod report;
pub(crate) mod spec;

use crate::data::registry;
use crate::experiment::spec::{GridSize, Spec};
use crate::experiment::{runner, seeds, RunContext};
use crate::geom::Point3;
use crate::optim::{Budget, Problem};
use crate::som::growing_grid::{self as grown, grow};
use crate::spline::open_surface::OpenSurfaceProblem;
use crate::spline::Parameterisation;
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use spec::GrowingGridSpec;
use std::collections::BTreeMap;

/// One grown map.
#[derive(Debug, Clone)]
pub(crate) struct MapRun {
    pub(crate) dataset: String,
    pub(crate) points: usize,
    pub(crate) map: grown::GrowingGrid,
    pub(crate) qe: f64,
    pub(crate) te: f64,
    pub(crate) cpu_s: f64,
}

/// One optimisation cell.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Cell {
    pub(crate) dataset: String,
    pub(crate) cn: GridSize,
    pub(crate) param: Parameterisation,
    pub(crate) optimiser: crate::optim::Name,
    pub(crate) repeat: usize,
}

impl Cell {
    pub(crate) fn key(&self) -> String {
        format!(
            "seed001/{}/{}/{}/{}/r{}",
            self.dataset,
            self.cn,
            self.param.name(),
            self.optimiser,
            self.repeat
        )
    }
}

/// One row of `runs.csv`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub(crate) struct Row {
    pub(crate) cell: String,
    pub(crate) dataset: String,
    pub(crate) grid_x: usize,
    pub(crate) grid_y: usize,
    pub(crate) cn_x: usize,
    pub(crate) cn_y: usize,
    pub(crate) parameterisation: String,
    pub(crate) optimiser: String,
    pub(crate) repeat: usize,
    pub(crate) seed: String,
    pub(crate) dimension: usize,
    /// Surface error (Eq. 5.13, one view) of the least-squares net, the start.
    pub(crate) lsq: f64,
    pub(crate) initial_best: f64,
    /// Best surface error found.
    pub(crate) best: f64,
    /// best / number of grid points: mean distance per grid point.
    pub(crate) best_per_point: f64,
    pub(crate) evaluations: u64,
    pub(crate) cpu_s: f64,
}

#[derive(Debug, Clone)]
pub(crate) struct Run {
    pub(crate) cell: Cell,
    pub(crate) row: Row,
    pub(crate) best_x: Vec<f64>,
}

impl runner::Cell for Cell {
    fn key(&self) -> String {
        Cell::key(self)
    }
}

impl runner::Logged for Run {
    /// The row and the best control points (the pictures draw the lowest-error surface).
    type Record = (Row, Vec<f64>);
    fn record(&self) -> Self::Record {
        (self.row.clone(), self.best_x.clone())
    }
}

pub(crate) use crate::families::maps::ProblemKey;

/// Every cell in a fixed order: data, net, parameterisation, optimiser, repeat.
pub(crate) fn cells(g: &GrowingGridSpec) -> Vec<Cell> {
    let mut out = Vec::new();
    for d in g.datasets.iter().map(|d| registry::name_of(d)) {
        for &cn in &g.control_nets {
            for &param in &g.parameterisations {
                for o in &g.optimisers {
                    for repeat in 0..g.repeats {
                        out.push(Cell {
                            dataset: d.clone(),
                            cn,
                            param,
                            optimiser: *o,
                            repeat,
                        });
                    }
                }
            }
        }
    }
    out
}

/// Grow one map per data set (in parallel; each on its own stream).
pub(crate) fn maps(spec: &Spec, g: &GrowingGridSpec, ctx: &RunContext) -> Result<Vec<MapRun>> {
    let params = g.params();
    let data: Vec<(String, Vec<Point3>)> = g
        .datasets
        .iter()
        .map(|d| {
            ctx.loader(spec)
                .load(d)
                .map(|c| (c.name, c.points))
                .with_context(|| format!("growing_grid.datasets: `{d}`"))
        })
        .collect::<Result<_>>()?;
    runner::run_cells(
        &data,
        ctx.jobs,
        "growing grids",
        |(d, points)| {
            let key = format!("seed001/map/{d}");
            let (map, cpu_s) =
                runner::on_stream(spec.file.master_seed, &key, |rng| grow(points, &params, rng));
            let map =
                map.map_err(anyhow::Error::msg).with_context(|| format!("growing grid on {d}"))?;
            let m = map.metrics(points);
            Ok(MapRun { dataset: d.clone(), points: points.len(), map, qe: m.qe, te: m.te, cpu_s })
        },
        |_, _| Ok(()),
    )
}

/// The problem of every (data, net, parameterisation).
pub(crate) fn problems(
    g: &GrowingGridSpec,
    maps: &[MapRun],
) -> Result<BTreeMap<ProblemKey, OpenSurfaceProblem>> {
    let mut out = BTreeMap::new();
    for m in maps {
        for &cn in &g.control_nets {
            for &param in &g.parameterisations {
                let pr = OpenSurfaceProblem::new(
                    &m.map.weights,
                    m.map.nx,
                    m.map.ny,
                    cn.nx,
                    cn.ny,
                    param,
                    g.bounds_margin,
                )
                .map_err(anyhow::Error::msg)
                .with_context(|| format!("{} {cn} {param}", m.dataset))?;
                out.insert(ProblemKey::new(&m.dataset, cn, param), pr);
            }
        }
    }
    Ok(out)
}

/// Run one cell (alone or inside the full run: the same numbers).
pub(crate) fn run_cell(
    spec: &Spec,
    g: &GrowingGridSpec,
    cell: &Cell,
    problem: &OpenSurfaceProblem,
) -> Result<Run> {
    let opt = g.tables.get(cell.optimiser);
    let budget = Budget {
        generations: g.generations as u64,
        population: g.population,
        init_range: g.init_range,
        trace_every_evals: g.trace_every_evals,
    };
    let key = cell.key();
    let (r, cpu_s) = runner::optimise(opt, problem, &budget, spec.file.master_seed, &key)?;
    let n = (problem.nx * problem.ny) as f64;
    let row = Row {
        cell: key.clone(),
        dataset: cell.dataset.clone(),
        grid_x: problem.nx,
        grid_y: problem.ny,
        cn_x: cell.cn.nx,
        cn_y: cell.cn.ny,
        parameterisation: cell.param.name().into(),
        optimiser: cell.optimiser.to_string(),
        repeat: cell.repeat,
        seed: seeds::seed_hex(spec.file.master_seed, &key),
        dimension: problem.dim(),
        lsq: problem.fitness(problem.initial_point()),
        initial_best: r.initial_best_fitness,
        best: r.best_fitness,
        best_per_point: r.best_fitness / n,
        evaluations: r.evaluations,
        cpu_s,
    };
    Ok(Run { cell: cell.clone(), row, best_x: r.best_x })
}

/// Run every cell of the spec.
pub(crate) fn run(
    spec: &Spec,
    g: &GrowingGridSpec,
    ctx: &RunContext,
    problems: &BTreeMap<ProblemKey, OpenSurfaceProblem>,
) -> Result<Vec<Run>> {
    let cells = cells(g);
    runner::run_logged(
        &cells,
        ctx,
        &spec.file.name,
        |c| run_cell(spec, g, c, &problems[&ProblemKey::new(&c.dataset, c.cn, c.param)]),
        |c, (row, best_x)| Ok(Run { cell: c.clone(), row, best_x }),
    )
}

/// Seed 001's family: the `[growing_grid]` section.
pub(crate) struct GrowingGrid;

impl crate::experiment::family::Experiment for GrowingGrid {
    fn title(&self) -> &'static str {
        "Seed 001"
    }
    type Section = self::spec::GrowingGridSpec;
    fn logged_keys(&self, _spec: &Spec, g: &GrowingGridSpec) -> Vec<String> {
        cells(g).iter().map(|c| c.key()).collect()
    }
    fn run(
        &self,
        spec: &Spec,
        g: &GrowingGridSpec,
        ctx: &RunContext,
        tables: bool,
    ) -> Result<crate::experiment::family::Outcome> {
        let maps = maps(spec, g, ctx)?;
        let problems = problems(g, &maps)?;
        let runs = run(spec, g, ctx, &problems)?;
        let section = if tables {
            Some(self::report::write(&maps, &problems, &runs, &ctx.out)?)
        } else {
            None
        };
        let cpu_s = maps.iter().map(|m| m.cpu_s).sum::<f64>()
            + runs.iter().map(|r| r.row.cpu_s).sum::<f64>();
        Ok(crate::experiment::family::Outcome { section, cpu_s, cells: runs.len() })
    }
}
