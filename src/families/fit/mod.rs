//! Chapter 5 wiring: read (or recompute) the DNSOM maps, fit every cell, log each at once.

pub(crate) mod command;
pub(crate) mod pictures;
pub(crate) mod readings;
pub(crate) mod report;
pub(crate) mod spec;

use super::maps::{maps_for, MapSource, MapsFrom};
use crate::experiment::spec::Spec;
use crate::experiment::{runner, RunContext};
use crate::spline::{fit_two_view, FitOptions, TwoSurfaceFit, TwoViewGrid};
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use spec::FitCell;
use std::collections::BTreeMap;

/// One row of a Chapter 5 `runs.csv`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub(crate) struct FitRow {
    pub(crate) cell: String,
    pub(crate) dataset: String,
    pub(crate) grid_x: usize,
    pub(crate) grid_y: usize,
    pub(crate) cn_x: usize,
    pub(crate) cn_y: usize,
    pub(crate) parameterisation: String,
    pub(crate) approach: String,
    /// Eq. 5.13 over the NOV grid classes.
    pub(crate) surface_error: f64,
    /// Largest distance between the two fitted surfaces along the shared border.
    pub(crate) gap: f64,
    /// The readings the fit used (docs/readings.md).
    pub(crate) knots: String,
    pub(crate) error_a: String,
    /// Between the data points (dense evaluation): largest distance of a surface point from the
    /// data's bounding box, largest absolute control-point coordinate, largest border gap.
    pub(crate) excursion: f64,
    pub(crate) max_control: f64,
    pub(crate) dense_gap: f64,
    pub(crate) cpu_s: f64,
}

/// One fitted cell.
#[derive(Debug, Clone)]
pub(crate) struct FitRun {
    pub(crate) cell: FitCell,
    pub(crate) row: FitRow,
    pub(crate) fit: TwoSurfaceFit,
}

impl runner::Logged for FitRun {
    type Record = FitRow;
    fn record(&self) -> FitRow {
        self.row.clone()
    }
}

/// Read each data set's map from the maps folder, or recompute it exactly as Chapter 4 does (same
/// cell key, seed and settings); every map used is copied into `<out>/maps/`.
pub(crate) fn maps(
    spec: &Spec,
    fit: &spec::FitSpec,
    ctx: &RunContext,
) -> Result<BTreeMap<String, MapSource>> {
    let from = MapsFrom {
        section: "fit",
        dir: fit.maps.as_deref(),
        missing: fit.maps_missing,
        som: fit.som.as_ref(),
    };
    maps_for(spec, ctx, &fit.datasets, fit.grid, &from)
}

/// Fit one cell.
pub(crate) fn run_cell(cell: &FitCell, grid: &TwoViewGrid, opts: &FitOptions) -> Result<FitRun> {
    let (fit, cpu_s) =
        runner::timed(|| fit_two_view(grid, cell.cn.nx, cell.cn.ny, cell.param, cell.approach, opts));
    let fit = fit.with_context(|| cell.key())?;
    let dense = fit.dense_geometry(grid);
    if !(fit.surface_error.is_finite() && dense.excursion.is_finite()) {
        anyhow::bail!(
            "{}: the fit is not finite (surface error {}, excursion {})",
            cell.key(),
            fit.surface_error,
            dense.excursion
        );
    }
    let row = FitRow {
        cell: cell.key(),
        dataset: cell.dataset.clone(),
        grid_x: cell.grid.nx,
        grid_y: cell.grid.ny,
        cn_x: cell.cn.nx,
        cn_y: cell.cn.ny,
        parameterisation: cell.param.name().into(),
        approach: cell.approach.letter().into(),
        surface_error: fit.surface_error,
        gap: fit.gap,
        knots: opts.knots.name().into(),
        error_a: opts.error_a.name().into(),
        excursion: dense.excursion,
        max_control: dense.max_control,
        dense_gap: dense.border_gap,
        cpu_s,
    };
    Ok(FitRun { cell: cell.clone(), row, fit })
}

/// Run every fit cell of a spec.
pub(crate) fn run(
    spec: &Spec,
    fit: &spec::FitSpec,
    ctx: &RunContext,
    maps: &BTreeMap<String, MapSource>,
) -> Result<Vec<FitRun>> {
    let cells = spec::cells(fit);
    let opts = fit.fit_options();
    // A logged cell's fit is rebuilt from its map (deterministic, a fraction of a millisecond);
    // the logged row, with its CPU time, is kept.
    runner::run_logged(
        &cells,
        ctx,
        &spec.file.name,
        |cell| run_cell(cell, &maps[&cell.dataset].grid, &opts),
        |cell, row| Ok(FitRun { row, ..run_cell(cell, &maps[&cell.dataset].grid, &opts)? }),
    )
}

/// Chapter 5's family: the `[fit]` section.
pub(crate) struct Fit;

impl crate::experiment::family::Experiment for Fit {
    fn title(&self) -> &'static str {
        "Chapter 5"
    }
    fn published(&self) -> crate::report::reference::Published {
        self::report::PUBLISHED
    }
    type Section = self::spec::FitSpec;
    fn combine(
        &self,
        view: &crate::experiment::family::PlanView<spec::FitSpec>,
    ) -> Result<crate::experiment::family::Combined> {
        readings::combine(view)
    }
    fn logged_keys(&self, _spec: &Spec, s: &spec::FitSpec) -> Vec<String> {
        spec::cells(s).iter().map(|c| c.key()).collect()
    }
    fn run(
        &self,
        spec: &Spec,
        s: &spec::FitSpec,
        ctx: &RunContext,
        tables: bool,
    ) -> Result<crate::experiment::family::Outcome> {
        let maps = maps(spec, s, ctx)?;
        let runs = run(spec, s, ctx, &maps)?;
        let origins: Vec<(String, String)> =
            maps.iter().map(|(d, m)| (d.clone(), m.origin.clone())).collect();
        let pictures = ctx.extras && s.pictures;
        let section = if tables {
            let near = super::maps::near_bounds(&maps);
            Some(self::report::write(&spec.file.name, &runs, &ctx.out, &origins, &near, pictures)?)
        } else {
            None
        };
        if tables && pictures {
            let grids: Vec<_> = maps.iter().map(|(d, m)| (d.clone(), &m.grid)).collect();
            crate::report::views3d::write(&ctx.out, &self::pictures::views(&runs, &grids))?;
        }
        Ok(crate::experiment::family::Outcome {
            section,
            cpu_s: runs.iter().map(|r| r.row.cpu_s).sum(),
            cells: runs.len(),
        })
    }
}
