//! The `[growing_grid]` section (seed 001): its settings and checks.

use crate::experiment::limits::{self, Check};
use crate::experiment::spec::{GridSize, Spec, SpecError};
use crate::som::growing_grid::GrowingGridParams;
use serde::Deserialize;

/// Seed 001 section: a Growing Grid (Fritzke 1995) per open-surface data set, one cubic B-spline
/// surface per (net, parameterisation) from its least-squares fit, then GA/DE/PSO on the control
/// points (Table 6.1 settings by default).
///
/// No `deny_unknown_fields`: the flattened `tables` refuses every key it is handed that is not an
/// optimiser's table, with a message naming both kinds of key.
#[derive(Debug, Clone, Deserialize)]
pub struct GrowingGridSpec {
    pub datasets: Vec<String>,
    /// Target size of the grown map.
    pub grid: GridSize,
    pub control_nets: Vec<GridSize>,
    pub parameterisations: Vec<crate::spline::Parameterisation>,
    /// Any registered optimiser (`optim::REGISTRY`).
    pub(crate) optimisers: Vec<crate::optim::Name>,
    #[serde(default = "crate::experiment::defaults::ten")]
    pub repeats: usize,
    #[serde(default = "crate::experiment::defaults::generations")]
    pub generations: usize,
    #[serde(default = "crate::experiment::defaults::population")]
    pub population: usize,
    #[serde(default = "crate::experiment::defaults::init_range")]
    pub init_range: f64,
    /// The search box: the data and the least-squares control points, widened by this share.
    #[serde(default)]
    pub bounds_margin: f64,
    #[serde(default = "crate::experiment::defaults::trace_every")]
    pub trace_every_evals: u64,
    /// Constants of the growing grid (defaults: `som::growing_grid::GrowingGridParams`).
    #[serde(default)]
    pub growth: GrowingGridParams,
    /// Every registered optimiser's parameter table (`[growing_grid.de]`, ...; Table 6.1 by default).
    #[serde(flatten)]
    pub(crate) tables: crate::optim::Tables,
}

impl GrowingGridSpec {
    /// The growing grid's parameters for the target grid.
    pub fn params(&self) -> GrowingGridParams {
        GrowingGridParams { nx: self.grid.nx, ny: self.grid.ny, ..self.growth }
    }
}

impl crate::experiment::family::Section for GrowingGridSpec {
    /// The bounds of the `[growing_grid]` section's sizes and counts (docs/specs.md, "Spec limits").
    fn limits(&self, c: &Check) -> Result<(), SpecError> {
        crate::families::maps::limit_grid_keys(
            c,
            "growing_grid",
            &self.datasets,
            &self.grid,
            &self.control_nets,
            &self.parameterisations,
        )?;
        c.list("growing_grid.optimisers", &self.optimisers)?;
        c.optimiser_run("growing_grid", self.repeats, self.generations, self.population)?;
        c.real("growing_grid.init_range", self.init_range, 0.0, true, limits::MAX_RANGE)?;
        c.real("growing_grid.bounds_margin", self.bounds_margin, 0.0, true, limits::MAX_RANGE)?;
        c.int("growing_grid.trace_every_evals", self.trace_every_evals, limits::MAX_TRACE_EVERY)?;
        c.int("growing_grid.growth.lambda_g", self.growth.lambda_g, limits::MAX_ITERATIONS)?;
        c.int("growing_grid.growth.lambda_f", self.growth.lambda_f, limits::MAX_ITERATIONS)?;
        c.cells(
            "growing_grid",
            &[
                self.datasets.len(),
                self.control_nets.len(),
                self.parameterisations.len(),
                self.optimisers.len(),
                self.repeats,
            ],
        )?;
        Ok(())
    }
    /// Every value of the `[growing_grid]` section (after the limits).
    fn validate(&self, spec: &Spec) -> Result<(), SpecError> {
        crate::families::maps::validate_grid_keys(
            spec,
            "growing_grid",
            &self.datasets,
            self.grid,
            &self.control_nets,
            &self.parameterisations,
        )?;
        self.params().validate().map_err(|e| spec.err("growing_grid.growth", e))?;
        spec.validate_runs(
            "growing_grid",
            &self.optimisers,
            &self.tables,
            self.repeats,
            self.generations as u64,
            self.population,
        )?;
        if self.trace_every_evals == 0 {
            return Err(spec.err("growing_grid.trace_every_evals", "must be at least 1"));
        }
        Ok(())
    }
    fn datasets(&self) -> &[String] {
        &self.datasets
    }
}

