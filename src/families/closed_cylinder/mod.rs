//! Seed 004 wiring (Chaurasiya & Agarwal): the lattice cylinder, sorted into rings, is fitted by
//! the analytical method (chord length + SVD) for every number of control points around; each
//! (control points, repeat) cell then runs the binary-coded GA on the columns' (x, y) in a box
//! around the analytical net, on its own stream, logged at once.

pub(crate) mod report;
pub(crate) mod spec;

use crate::data::cylinder::{lattice_cylinder, sort_into_rings};
use crate::experiment::spec::Spec;
use crate::experiment::{runner, seeds, RunContext};
use crate::optim::{Budget, Problem};
use crate::spline::closed::{fit_closed, ClosedNetShape, RingData, RingNetProblem};
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use spec::ClosedCylinderSpec;

/// One (number of control points around, repeat).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Cell {
    pub(crate) control_points: usize,
    pub(crate) repeat: usize,
}

impl Cell {
    pub(crate) fn key(&self) -> String {
        format!("seed004/cp{}/r{}", self.control_points, self.repeat)
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
    pub(crate) control_points: usize,
    pub(crate) repeat: usize,
    pub(crate) seed: String,
    pub(crate) n_points: usize,
    pub(crate) order_around: usize,
    pub(crate) order_vertical: usize,
    pub(crate) rows: usize,
    /// GA decision variables (x, y per control column) and chromosome length in bits.
    pub(crate) dimension: usize,
    pub(crate) string_length: usize,
    /// RMS error of the analytical (chord length + SVD) net.
    pub(crate) analytical_rms: f64,
    /// Best RMS of the GA's initial population (generation 0).
    pub(crate) initial_best_rms: f64,
    /// Best RMS the GA found (best so far at the end).
    pub(crate) best_rms: f64,
    /// First generation at which `best_rms` was reached.
    pub(crate) best_generation: usize,
    /// Best RMS in the final population (no elitism: may exceed `best_rms`).
    pub(crate) final_population_best_rms: f64,
    /// (analytical - best) / analytical * 100.
    pub(crate) improvement_pct: f64,
    pub(crate) evaluations: u64,
    pub(crate) cpu_s: f64,
}

/// One run: its row, per-generation histories and best decision vector.
#[derive(Debug, Clone)]
pub(crate) struct Run {
    pub(crate) cell: Cell,
    pub(crate) row: Row,
    pub(crate) population_best: Vec<f64>,
    pub(crate) best_so_far: Vec<f64>,
    pub(crate) best_x: Vec<f64>,
}

impl runner::Logged for Run {
    type Record = (Row, Vec<f64>, Vec<f64>, Vec<f64>);
    fn record(&self) -> Self::Record {
        (
            self.row.clone(),
            self.population_best.clone(),
            self.best_so_far.clone(),
            self.best_x.clone(),
        )
    }
}

/// The flat list of cells.
pub(crate) fn cells(s: &ClosedCylinderSpec) -> Vec<Cell> {
    s.control_points
        .iter()
        .flat_map(|&control_points| {
            (0..s.repeats).map(move |repeat| Cell { control_points, repeat })
        })
        .collect()
}

/// The paper's data: lattice cylinder sorted into rings.
pub(crate) fn data(s: &ClosedCylinderSpec) -> RingData {
    sort_into_rings(
        &lattice_cylinder(s.radius, s.height, s.grid_step, s.accuracy),
        s.grid_step * 1e-3,
    )
}

pub(crate) fn shape(s: &ClosedCylinderSpec, control_points: usize) -> ClosedNetShape {
    ClosedNetShape {
        order_around: s.order_around,
        order_up: s.order_vertical,
        n_around: control_points,
        rows: s.rows,
    }
}

/// The GA problem (and analytical fit) for a number of control points.
pub(crate) fn problem(s: &ClosedCylinderSpec, data: &RingData, control_points: usize) -> Result<RingNetProblem> {
    let fit = fit_closed(data, shape(s, control_points))
        .with_context(|| format!("seed004, {control_points} control points"))?;
    Ok(RingNetProblem::new(data, fit, s.search_range).with_measure(s.error))
}

/// Run one cell (alone it gives the same numbers as inside the full run).
#[cfg(test)]
pub(crate) fn run_cell(spec: &Spec, s: &ClosedCylinderSpec, data: &RingData, cell: &Cell) -> Result<Run> {
    run_cell_on(spec, s, &problem(s, data, cell.control_points)?, cell)
}

/// Run one cell on its number of control points' problem (built once for all its repeats).
fn run_cell_on(spec: &Spec, s: &ClosedCylinderSpec, problem: &RingNetProblem, cell: &Cell) -> Result<Run> {
    let budget = Budget {
        generations: s.generations as u64,
        population: s.population,
        init_range: 0.0,
        trace_every_evals: s.population as u64,
    };
    let key = cell.key();
    let (r, cpu_s) = runner::on_stream(spec.file.master_seed, &key, |rng| {
        s.ga.run_with_history(problem, &budget, rng)
    });
    let r = r.with_context(|| key.clone())?;
    let analytical = problem.analytical_rms();
    let row = Row {
        cell: key.clone(),
        control_points: cell.control_points,
        repeat: cell.repeat,
        seed: seeds::seed_hex(spec.file.master_seed, &key),
        n_points: problem.n_points(),
        order_around: s.order_around,
        order_vertical: s.order_vertical,
        rows: s.rows,
        dimension: problem.dim(),
        string_length: problem.dim() * s.ga.bits as usize,
        analytical_rms: analytical,
        initial_best_rms: r.result.initial_best_fitness,
        best_rms: r.result.best_fitness,
        best_generation: r.best_generation(),
        final_population_best_rms: *r.population_best.last().unwrap_or(&f64::NAN),
        improvement_pct: (analytical - r.result.best_fitness) / analytical * 100.0,
        evaluations: r.result.evaluations,
        cpu_s,
    };
    Ok(Run {
        cell: cell.clone(),
        row,
        population_best: r.population_best,
        best_so_far: r.best_so_far,
        best_x: r.result.best_x,
    })
}

/// Run every cell of the spec on `data` (the analytical fit of each number of control points
/// once, on the worker threads).
pub(crate) fn run(spec: &Spec, s: &ClosedCylinderSpec, ctx: &RunContext, data: &RingData) -> Result<Vec<Run>> {
    let cps: Vec<usize> = crate::report::ordered(s.control_points.iter().copied());
    let problems = runner::run_cells(
        &cps,
        ctx.jobs,
        "seed004 analytical fits",
        |&cp| problem(s, data, cp),
        |_, _| Ok(()),
    )?;
    let by_cp: std::collections::BTreeMap<usize, &RingNetProblem> =
        cps.iter().copied().zip(problems.iter()).collect();
    let cells = cells(s);
    runner::run_logged(
        &cells,
        ctx,
        &spec.file.name,
        |cell| {
            run_cell_on(
                spec,
                s,
                by_cp
                    .get(&cell.control_points)
                    .context("seed004: no problem for a cell's control points")?,
                cell,
            )
        },
        |cell, (row, population_best, best_so_far, best_x)| {
            Ok(Run { cell: cell.clone(), row, population_best, best_so_far, best_x })
        },
    )
}

/// The analytical method alone at every number of control points from the smallest to the
/// largest of the spec's list (deterministic and cheap: not logged): (control points, RMS).
pub(crate) fn analytical_sweep(s: &ClosedCylinderSpec, data: &RingData) -> Result<Vec<(usize, f64)>> {
    let (lo, hi) = (
        s.control_points.iter().min().copied().unwrap_or(0),
        s.control_points.iter().max().copied().unwrap_or(0),
    );
    (lo..=hi).map(|n| Ok((n, problem(s, data, n)?.analytical_rms()))).collect()
}

/// RMS distance of the data to the exact cylinder (sqrt(x^2 + y^2) - radius): a floor under
/// every fit's RMS error at the data's own radial scatter.
pub(crate) fn data_floor(s: &ClosedCylinderSpec, data: &RingData) -> f64 {
    let sse: f64 =
        data.points().map(|p| ((p[0] * p[0] + p[1] * p[1]).sqrt() - s.radius).powi(2)).sum();
    (sse / data.n_points().max(1) as f64).sqrt()
}

/// What the Fig. 2(a) analogue draws: the bottom ring of the data, the GA's best curve and its
/// control polygon, and the analytical curve, all seen from the top (x, y).
#[derive(Debug, Clone)]
pub(crate) struct TopView {
    pub(crate) control_points: usize,
    pub(crate) best_rms: f64,
    pub(crate) analytical_rms: f64,
    pub(crate) data: Vec<(f64, f64)>,
    pub(crate) ga_curve: Vec<(f64, f64)>,
    pub(crate) ga_control: Vec<(f64, f64)>,
    pub(crate) analytical_curve: Vec<(f64, f64)>,
}

/// The top view of the lowest-RMS run at `control_points` (None if there is no such run).
pub(crate) fn top_view(
    s: &ClosedCylinderSpec,
    data: &RingData,
    runs: &[Run],
    control_points: usize,
) -> Result<Option<TopView>> {
    let Some(best) = runs
        .iter()
        .filter(|r| r.cell.control_points == control_points && !r.best_x.is_empty())
        .min_by(|a, b| a.row.best_rms.total_cmp(&b.row.best_rms))
    else {
        return Ok(None);
    };
    let problem = problem(s, data, control_points)?;
    let ga = problem.surface(&best.best_x);
    let an = &problem.analytical().surface;
    let curve = |surf: &crate::spline::closed::ClosedSurface| -> Vec<(f64, f64)> {
        (0..=400)
            .map(|k| surf.eval(k as f64 / 400.0 * control_points as f64, 0.0))
            .map(|p| (p[0], p[1]))
            .collect()
    };
    let mut ga_control: Vec<(f64, f64)> = best.best_x.chunks(2).map(|c| (c[0], c[1])).collect();
    ga_control.push(ga_control[0]);
    Ok(Some(TopView {
        control_points,
        best_rms: best.row.best_rms,
        analytical_rms: best.row.analytical_rms,
        data: data
            .rings
            .first()
            .map(|r| r.iter().map(|p| (p[0], p[1])).collect())
            .unwrap_or_default(),
        ga_curve: curve(&ga),
        ga_control,
        analytical_curve: curve(an),
    }))
}

/// Seed 004's family: the `[closed_cylinder]` section.
pub(crate) struct ClosedCylinder;

impl crate::experiment::family::Experiment for ClosedCylinder {
    fn title(&self) -> &'static str {
        "Seed 004"
    }
    fn published(&self) -> crate::report::reference::Published {
        self::report::PUBLISHED
    }
    type Section = self::spec::ClosedCylinderSpec;
    fn logged_keys(&self, _spec: &Spec, s: &ClosedCylinderSpec) -> Vec<String> {
        cells(s).iter().map(|c| c.key()).collect()
    }
    fn run(
        &self,
        spec: &Spec,
        s4: &ClosedCylinderSpec,
        ctx: &RunContext,
        tables: bool,
    ) -> Result<crate::experiment::family::Outcome> {
        // The lattice and its rings once, for the runs and the report.
        let data = data(s4);
        let runs = run(spec, s4, ctx, &data)?;
        let section = if tables {
            let sweep = analytical_sweep(s4, &data)?;
            let top = top_view(s4, &data, &runs, 7)?;
            Some(self::report::write(
                &spec.file.name,
                s4,
                &runs,
                &sweep,
                data_floor(s4, &data),
                top.as_ref(),
                &ctx.out,
            )?)
        } else {
            None
        };
        Ok(crate::experiment::family::Outcome {
            section,
            cpu_s: runs.iter().map(|r| r.row.cpu_s).sum(),
            cells: runs.len(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec_with(extra: &str) -> Result<crate::families::Loaded, crate::experiment::spec::SpecError> {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/experiments/seed004_cylinder.toml");
        let text = std::fs::read_to_string(path).unwrap();
        let text = text.replacen("[closed_cylinder]\n", &format!("[closed_cylinder]\n{extra}\n"), 1);
        crate::families::Loaded::parse(path, &text, Some("quick"))
    }

    /// `error` defaults to Eq. 9 at the parameters; `closest_point` measures the analytical net
    /// and the GA alike by foot points (below the at-parameter figure on the lattice).
    #[test]
    fn error_readings() {
        let at = spec_with("").unwrap();
        let foot = spec_with("error = \"closest_point\"").unwrap();
        let (sa, sf): (&ClosedCylinderSpec, &ClosedCylinderSpec) =
            (at.section_as().unwrap(), foot.section_as().unwrap());
        assert_eq!(sa.error, crate::spline::closed::PointError::AtParameters);
        let d = data(sa);
        let cell = Cell { control_points: 7, repeat: 0 };
        let (ra, rf) = (
            run_cell(&at.spec, sa, &d, &cell).unwrap().row,
            run_cell(&foot.spec, sf, &d, &cell).unwrap().row,
        );
        assert_eq!(ra.analytical_rms, problem(sa, &d, 7).unwrap().analytical().rms);
        assert_eq!(rf.analytical_rms, problem(sf, &d, 7).unwrap().analytical_rms());
        assert!(rf.analytical_rms < ra.analytical_rms, "{} {}", rf.analytical_rms, ra.analytical_rms);
        assert!(spec_with("error = \"max\"").unwrap_err().to_string().contains("unknown variant `max`"));
    }
}
