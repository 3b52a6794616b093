//! Seed 002 wiring (Yahya): each (surface, optimiser, repeat) fits the four-patch G1 rational
//! bi-quadratic Bezier surface to the surface's grid by minimising the sum of squared errors over
//! the seven free control points and w11, on its own stream, logged at once; each (outline,
//! optimiser, repeat) samples a 2-D outline, finds its corners and fits its conics, a cell logged
//! the same way.

pub(crate) mod report;
pub(crate) mod spec;

use crate::experiment::packed::PackedFloats;
use crate::experiment::spec::Spec;
use crate::experiment::{runner, seeds, RunContext};
use crate::optim::{Budget, Problem};
use crate::spline::conic::{self, ConicProblem, P2};
use crate::spline::rational_bezier::{SurfaceSse, TestSurface};
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use spec::RationalBezierSpec;

/// One (surface, optimiser, repeat).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Cell {
    pub(crate) surface: String,
    pub(crate) optimiser: crate::optim::Name,
    pub(crate) repeat: usize,
}

impl Cell {
    pub(crate) fn key(&self) -> String {
        format!("seed002/{}/{}/r{}", self.surface, self.optimiser, self.repeat)
    }
}

/// One row of runs.csv.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub(crate) struct Row {
    pub(crate) cell: String,
    pub(crate) surface: String,
    pub(crate) optimiser: String,
    pub(crate) repeat: usize,
    pub(crate) seed: String,
    pub(crate) dimension: usize,
    pub(crate) n_points: usize,
    /// SSE of the start (free points on the data, w11 = 1).
    pub(crate) start_sse: f64,
    pub(crate) initial_best: f64,
    /// Best sum of squared errors found.
    pub(crate) best_sse: f64,
    /// sqrt(best_sse / n_points).
    pub(crate) rmse: f64,
    pub(crate) w11: f64,
    pub(crate) evaluations: u64,
    pub(crate) cpu_s: f64,
}

/// One run with its convergence trace.
#[derive(Debug, Clone)]
pub(crate) struct Run {
    pub(crate) row: Row,
    pub(crate) trace: Vec<(u64, f64)>,
}

impl runner::Cell for Cell {
    fn key(&self) -> String {
        Cell::key(self)
    }
}

impl runner::Logged for Run {
    /// The row and the trace (the report needs no control points).
    type Record = (Row, Vec<(u64, f64)>);
    fn record(&self) -> Self::Record {
        (self.row.clone(), self.trace.clone())
    }
}

/// The flat list of cells.
pub(crate) fn cells(s: &RationalBezierSpec) -> Vec<Cell> {
    runner::product_cells(&s.surfaces, &s.optimisers, s.repeats, |sf, o, repeat| Cell {
        surface: sf.clone(),
        optimiser: *o,
        repeat,
    })
}

/// The SSE problem of a surface with the spec's grid and box.
pub(crate) fn problem(s: &RationalBezierSpec, surface: &str) -> Result<SurfaceSse> {
    let ts = TestSurface::by_name(surface)
        .with_context(|| format!("rational_bezier.surfaces: unknown surface `{surface}`"))?;
    Ok(SurfaceSse::new(ts.grid(s.grid), s.bounds_margin, s.w_min))
}

/// Run one cell (alone it gives the same numbers as inside the full run).
pub(crate) fn run_cell(spec: &Spec, s: &RationalBezierSpec, cell: &Cell) -> Result<Run> {
    let problem = problem(s, &cell.surface)?;
    let opt = s.tables.get(cell.optimiser);
    // init_range is a share of the data's largest bounding-box extent (the domains differ in scale).
    let extent = (0..3)
        .map(|k| {
            let (lo, hi) =
                problem.data.points.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                    (a.min(p[k]), b.max(p[k]))
                });
            hi - lo
        })
        .fold(0.0, f64::max);
    let budget = Budget {
        generations: s.generations as u64,
        population: s.population,
        init_range: s.init_range * extent,
        trace_every_evals: s.trace_every_evals,
    };
    let key = cell.key();
    let (r, cpu_s) = runner::optimise(opt, &problem, &budget, spec.file.master_seed, &key)?;
    let n = problem.n_points();
    let row = Row {
        cell: key.clone(),
        surface: cell.surface.clone(),
        optimiser: cell.optimiser.to_string(),
        repeat: cell.repeat,
        seed: seeds::seed_hex(spec.file.master_seed, &key),
        dimension: problem.dim(),
        n_points: n,
        start_sse: problem.fitness(problem.initial_point()),
        initial_best: r.initial_best_fitness,
        best_sse: r.best_fitness,
        rmse: (r.best_fitness / n as f64).sqrt(),
        w11: r.best_x[21],
        evaluations: r.evaluations,
        cpu_s,
    };
    Ok(Run { row, trace: r.trace })
}

/// Run every cell of the spec.
pub(crate) fn run(spec: &Spec, s: &RationalBezierSpec, ctx: &RunContext) -> Result<Vec<Run>> {
    let cells = cells(s);
    runner::run_logged(
        &cells,
        ctx,
        &spec.file.name,
        |cell| run_cell(spec, s, cell),
        |_, (row, trace)| Ok(Run { row, trace }),
    )
}

/// One conic curve fit: (outline, optimiser, repeat).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct CurveCell {
    pub(crate) outline: String,
    pub(crate) optimiser: crate::optim::Name,
    pub(crate) repeat: usize,
}

impl CurveCell {
    pub(crate) fn key(&self) -> String {
        format!("seed002/curve/{}/{}/r{}", self.outline, self.optimiser, self.repeat)
    }
}

/// One row of seed002_curve_runs.csv.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub(crate) struct CurveRow {
    pub(crate) cell: String,
    pub(crate) outline: String,
    pub(crate) optimiser: String,
    pub(crate) repeat: usize,
    pub(crate) seed: String,
    pub(crate) n_points: usize,
    pub(crate) true_corners: usize,
    pub(crate) corners_found: usize,
    /// Found corners within one spacing of a true corner.
    pub(crate) corners_matched: usize,
    pub(crate) conics: usize,
    /// Sum over conics of the best SSE (data points shared by two conics count in both).
    pub(crate) sse: f64,
    /// SSE of the starts (b1 by least squares at w = 1).
    pub(crate) start_sse: f64,
    pub(crate) evaluations: u64,
    pub(crate) cpu_s: f64,
}

/// A curve run: its row, the outline, the corners and each conic (b0, b1, b2, w).
#[derive(Debug, Clone)]
pub(crate) struct CurveRun {
    pub(crate) row: CurveRow,
    pub(crate) points: Vec<P2>,
    pub(crate) corners: Vec<usize>,
    pub(crate) conics: Vec<([P2; 3], f64)>,
}

pub(crate) fn curve_cells(s: &RationalBezierSpec) -> Vec<CurveCell> {
    runner::product_cells(&s.outlines, &s.optimisers, s.repeats, |ol, o, repeat| CurveCell {
        outline: ol.clone(),
        optimiser: *o,
        repeat,
    })
}

/// Sample the outline, detect its corners (SAM06), cut it into conic runs and fit each run's
/// conic with the cell's optimiser, all on the cell's stream in run order.
pub(crate) fn run_curve_cell(spec: &Spec, s: &RationalBezierSpec, cell: &CurveCell) -> Result<CurveRun> {
    let (pieces, truth) = conic::outline(&cell.outline)
        .with_context(|| format!("rational_bezier.outlines: unknown outline `{}`", cell.outline))?;
    let points = conic::sample_closed(&pieces, s.outline_spacing);
    let corners = conic::sam06(&points, s.sam06_l, s.sam06_d, s.sam06_r.unwrap_or(s.sam06_l));
    let matched = truth
        .iter()
        .filter(|c| {
            corners.iter().any(|&i| {
                ((points[i][0] - c[0]).powi(2) + (points[i][1] - c[1]).powi(2)).sqrt()
                    <= s.outline_spacing
            })
        })
        .count();
    let opt = s.tables.get(cell.optimiser);
    let key = cell.key();
    // Every conic of the outline runs on the cell's one stream, in order.
    let (fits, cpu_s) = runner::on_stream(spec.file.master_seed, &key, |rng| {
        let (mut sse, mut start_sse, mut evals, mut conics) = (0.0, 0.0, 0u64, Vec::new());
        for run in conic::conic_runs(&points, &corners) {
            let problem = ConicProblem::new(run, s.bounds_margin, s.w_min, 10.0);
            let ext = problem.bounds().1[0] - problem.bounds().0[0];
            let budget = Budget {
                generations: s.curve_generations as u64,
                population: s.population,
                init_range: s.init_range * ext,
                trace_every_evals: s.trace_every_evals,
            };
            let r = opt.run(&problem, &budget, rng).with_context(|| key.clone())?;
            start_sse += problem.fitness(problem.initial_point());
            sse += r.best_fitness;
            evals += r.evaluations;
            conics.push(problem.control(&r.best_x));
        }
        anyhow::Ok((sse, start_sse, evals, conics))
    });
    let (sse, start_sse, evals, conics) = fits?;
    let row = CurveRow {
        cell: key.clone(),
        outline: cell.outline.clone(),
        optimiser: cell.optimiser.to_string(),
        repeat: cell.repeat,
        seed: seeds::seed_hex(spec.file.master_seed, &key),
        n_points: points.len(),
        true_corners: truth.len(),
        corners_found: corners.len(),
        corners_matched: matched,
        conics: conics.len(),
        sse,
        start_sse,
        evaluations: evals,
        cpu_s,
    };
    Ok(CurveRun { row, points, corners, conics })
}

impl runner::Cell for CurveCell {
    fn key(&self) -> String {
        CurveCell::key(self)
    }
}

/// A curve run as the cell log keeps it: the row, the outline's points (x, y pairs), the corners
/// and each conic (b0, b1, b2 as x, y pairs, then w), the floats exactly, so a resumed run, a
/// merge or `somnurbs report` draws and tabulates the same (CPU time included).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct CurveRecord {
    pub(crate) row: CurveRow,
    pub(crate) points: PackedFloats,
    pub(crate) corners: Vec<usize>,
    pub(crate) conics: PackedFloats,
}

impl runner::Logged for CurveRun {
    type Record = CurveRecord;
    fn record(&self) -> CurveRecord {
        let conics = self.conics.iter().flat_map(|(b, w)| b.iter().flatten().copied().chain([*w]));
        CurveRecord {
            row: self.row.clone(),
            points: PackedFloats(self.points.iter().flatten().copied().collect()),
            corners: self.corners.clone(),
            conics: PackedFloats(conics.collect()),
        }
    }
}

/// The curve run a record holds, its sizes checked against its row.
fn restore_curve(r: CurveRecord) -> Result<CurveRun> {
    let (p, c) = (&r.points.0, &r.conics.0);
    if p.len() != 2 * r.row.n_points || c.len() != 7 * r.row.conics {
        anyhow::bail!(
            "the log holds {} coordinates and {} conic numbers for {} points and {} conics",
            p.len(),
            c.len(),
            r.row.n_points,
            r.row.conics
        );
    }
    if let Some(&i) = r.corners.iter().find(|&&i| i >= r.row.n_points) {
        anyhow::bail!("corner {i} is past the outline's {} points", r.row.n_points);
    }
    let points = p.chunks_exact(2).map(|q| [q[0], q[1]]).collect();
    let conics =
        c.chunks_exact(7).map(|q| ([[q[0], q[1]], [q[2], q[3]], [q[4], q[5]]], q[6])).collect();
    Ok(CurveRun { row: r.row, points, corners: r.corners, conics })
}

/// The curve cells, logged at once as the surface cells are.
pub(crate) fn run_curves(
    spec: &Spec,
    s: &RationalBezierSpec,
    ctx: &RunContext,
) -> Result<Vec<CurveRun>> {
    let cells = curve_cells(s);
    runner::run_logged(
        &cells,
        ctx,
        "seed002 curves",
        |c| run_curve_cell(spec, s, c),
        |_, r| restore_curve(r),
    )
}

/// Seed 002's family: the `[rational_bezier]` section (surface and curve cells, both logged).
pub(crate) struct RationalBezier;

impl crate::experiment::family::Experiment for RationalBezier {
    fn title(&self) -> &'static str {
        "Seed 002"
    }
    type Section = self::spec::RationalBezierSpec;
    fn logged_keys(&self, _spec: &Spec, s: &RationalBezierSpec) -> Vec<String> {
        // The surface cells, then the curve cells (as they run).
        let curves = curve_cells(s);
        cells(s).iter().map(|c| c.key()).chain(curves.iter().map(|c| c.key())).collect()
    }
    fn run(
        &self,
        spec: &Spec,
        s: &RationalBezierSpec,
        ctx: &RunContext,
        tables: bool,
    ) -> Result<crate::experiment::family::Outcome> {
        let runs = run(spec, s, ctx)?;
        let curves = run_curves(spec, s, ctx)?;
        let section = if tables {
            Some(self::report::write(&runs, &curves, s.population, &ctx.out)?)
        } else {
            None
        };
        let cpu_s =
            runs.iter().map(|r| r.row.cpu_s).chain(curves.iter().map(|c| c.row.cpu_s)).sum();
        Ok(crate::experiment::family::Outcome { section, cpu_s, cells: runs.len() + curves.len() })
    }
}
