//! Seed 001 wiring: one Growing Grid per data set (a logged cell on its own stream
//! `seed001/map/<data>`), one open cubic B-spline problem per (data, net, parameterisation) from
//! the least-squares fit of that map, then every (problem, optimiser, repeat) cell on its own
//! stream, logged at once.

pub(crate) mod report;
pub(crate) mod spec;

use crate::data::registry;
use crate::experiment::packed::PackedPoints;
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

/// One map cell: a data set and its points (its stream and log key `seed001/map/<data>`).
#[derive(Debug, Clone)]
pub(crate) struct MapCell {
    pub(crate) dataset: String,
    pub(crate) points: Vec<Point3>,
}

impl runner::Cell for MapCell {
    fn key(&self) -> String {
        format!("seed001/map/{}", self.dataset)
    }
}

/// A grown map as the cell log keeps it: everything the tables, the pictures and the problems
/// read, the weights exactly (so a resumed run, a merge or `somnurbs report` rebuilds the same
/// problems and the same tables, CPU time included).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct MapRecord {
    pub(crate) dataset: String,
    pub(crate) points: usize,
    pub(crate) nx: usize,
    pub(crate) ny: usize,
    pub(crate) weights: PackedPoints,
    pub(crate) insertions: usize,
    pub(crate) growth_steps: usize,
    pub(crate) fine_steps: usize,
    pub(crate) qe: f64,
    pub(crate) te: f64,
    pub(crate) cpu_s: f64,
}

impl runner::Logged for MapRun {
    type Record = MapRecord;
    fn record(&self) -> MapRecord {
        MapRecord {
            dataset: self.dataset.clone(),
            points: self.points,
            nx: self.map.nx,
            ny: self.map.ny,
            weights: PackedPoints { points: self.map.weights.clone(), single: false },
            insertions: self.map.insertions,
            growth_steps: self.map.growth_steps,
            fine_steps: self.map.fine_steps,
            qe: self.qe,
            te: self.te,
            cpu_s: self.cpu_s,
        }
    }
}

/// The map run a record holds, checked against its cell (data set, point count, map size).
fn restore_map(cell: &MapCell, r: MapRecord) -> Result<MapRun> {
    if r.dataset != cell.dataset || r.points != cell.points.len() {
        anyhow::bail!(
            "the log's map is of {} ({} points), the cell's data set is {} ({} points)",
            r.dataset,
            r.points,
            cell.dataset,
            cell.points.len()
        );
    }
    if r.weights.points.len() != r.nx * r.ny {
        anyhow::bail!(
            "the log holds {} weights for a {}x{} map",
            r.weights.points.len(),
            r.nx,
            r.ny
        );
    }
    let map = grown::GrowingGrid {
        nx: r.nx,
        ny: r.ny,
        weights: r.weights.points,
        insertions: r.insertions,
        growth_steps: r.growth_steps,
        fine_steps: r.fine_steps,
    };
    Ok(MapRun { dataset: r.dataset, points: r.points, map, qe: r.qe, te: r.te, cpu_s: r.cpu_s })
}

/// One map cell per data set, in the spec's order.
pub(crate) fn map_cells(
    spec: &Spec,
    g: &GrowingGridSpec,
    ctx: &RunContext,
) -> Result<Vec<MapCell>> {
    g.datasets
        .iter()
        .map(|d| {
            ctx.loader(spec)
                .load(d)
                .map(|c| MapCell { dataset: c.name, points: c.points })
                .with_context(|| format!("growing_grid.datasets: `{d}`"))
        })
        .collect()
}

/// Grow one map on its own stream.
fn grow_map(spec: &Spec, g: &GrowingGridSpec, cell: &MapCell) -> Result<MapRun> {
    let (d, points) = (&cell.dataset, &cell.points);
    let key = runner::Cell::key(cell);
    let params = g.params();
    let (map, cpu_s) =
        runner::on_stream(spec.file.master_seed, &key, |rng| grow(points, &params, rng));
    let map = map.map_err(anyhow::Error::msg).with_context(|| format!("growing grid on {d}"))?;
    let m = map.metrics(points);
    Ok(MapRun { dataset: d.clone(), points: points.len(), map, qe: m.qe, te: m.te, cpu_s })
}

/// Grow one map per data set (in parallel; each on its own stream), each a cell of the log. Every
/// shard runs every map (each of its optimisation cells needs its data set's map), so a shard's
/// log holds all of them.
pub(crate) fn maps(spec: &Spec, g: &GrowingGridSpec, ctx: &RunContext) -> Result<Vec<MapRun>> {
    let cells = map_cells(spec, g, ctx)?;
    runner::run_logged(
        &cells,
        &RunContext { shard: None, ..ctx.clone() },
        "growing grids",
        |c| grow_map(spec, g, c),
        restore_map,
    )
}

/// The same maps grown outside any folder (no cell log): what a suite builds its problems from.
pub(crate) fn grow_maps(spec: &Spec, g: &GrowingGridSpec, ctx: &RunContext) -> Result<Vec<MapRun>> {
    let cells = map_cells(spec, g, ctx)?;
    runner::run_cells(&cells, ctx.jobs, "growing grids", |c| grow_map(spec, g, c), |_, _| Ok(()))
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
        // The map cells first (as they run), named by the data sets' names.
        let maps = g.datasets.iter().map(|d| format!("seed001/map/{}", registry::name_of(d)));
        maps.chain(cells(g).iter().map(|c| c.key())).collect()
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
        Ok(crate::experiment::family::Outcome { section, cpu_s, cells: maps.len() + runs.len() })
    }
}
