//! The `[fit]` section (thesis Chapter 5): data sets x control nets x parameterisations x
//! approaches on one grid size, its checks and its cells; the keys it shares with `[optimise]` are
//! checked here for both.

use crate::experiment::limits::{self, Check};
use crate::experiment::spec::{GridSize, Spec, SpecError};
use crate::families::maps::{
    validate_grid_keys, validate_map_som, MapSom, MapsFrom, MapsMissing,
};
use serde::Deserialize;

/// Chapter 5 section: data sets x control nets x parameterisations x approaches on one grid size.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitSpec {
    pub datasets: Vec<String>,
    /// DNSOM grid size the maps were organised at (20x20: Appendix E; 18x30: Appendix F).
    pub grid: GridSize,
    /// Control-net sizes CNx x CNy.
    pub control_nets: Vec<GridSize>,
    /// uniform, chord_length, centripetal, exponential.
    pub parameterisations: Vec<crate::spline::Parameterisation>,
    /// A (conventional) and/or B (improved).
    pub approaches: Vec<crate::spline::Approach>,
    /// Folder holding `dnsom_<data>_<nx>x<ny>.csv` (Chapter 4's `maps/`), relative to the spec's
    /// folder; unset, every map is recomputed from the same seed and settings as Chapter 4 (see
    /// `[fit.som]`).
    #[serde(default)]
    pub maps: Option<String>,
    /// What a named `maps` folder or map that is not there means: an error (default) or
    /// `"recompute"` (said on stderr).
    #[serde(default)]
    pub maps_missing: MapsMissing,
    /// How a missing map is recomputed (defaults: this spec's master seed, T = 30000, alpha0 0.9).
    #[serde(default)]
    pub som: Option<MapSom>,
    /// Pictures like Appendices G/H and the error-vs-control-net chart.
    #[serde(default = "crate::experiment::defaults::yes")]
    pub pictures: bool,
    /// Reading of the knot rule for nets smaller than the grid (docs/readings.md).
    #[serde(default)]
    pub knots: crate::spline::KnotRule,
    /// Reading of approach A's surface error (docs/readings.md).
    #[serde(default)]
    pub error_a: crate::spline::ErrorA,
    /// Beyond the thesis: penalised least squares weight (0 = the thesis' plain least squares).
    #[serde(default)]
    pub fairness: f64,
    /// Reading of Eq. 2.8's power factor for the exponential method (Section 2.3.2: 0.8), in
    /// (0, 1] (docs/readings.md).
    #[serde(default = "crate::families::maps::default_exponential_alpha")]
    pub exponential_alpha: f64,
    /// Reading of the grid lines Eq. 5.1/5.2 average: `all` or `middle` (docs/readings.md).
    #[serde(default)]
    pub param_rows: crate::spline::ParamRows,
}

impl FitSpec {
    /// The readings and options every fit of this section uses.
    pub fn fit_options(&self) -> crate::spline::FitOptions {
        crate::spline::FitOptions {
            knots: self.knots,
            error_a: self.error_a,
            fairness: self.fairness,
            param: crate::spline::ParamReading {
                exponential_alpha: self.exponential_alpha,
                rows: self.param_rows,
            },
        }
    }
}

impl crate::experiment::family::Section for FitSpec {
    /// The bounds of the `[fit]` section's sizes and counts (docs/specs.md, "Spec limits").
    fn limits(&self, c: &Check) -> Result<(), SpecError> {
        crate::families::maps::limit_grid_keys(
            c,
            "fit",
            &self.datasets,
            &self.grid,
            &self.control_nets,
            &self.parameterisations,
        )?;
        c.list("fit.approaches", &self.approaches)?;
        if let Some(som) = &self.som {
            c.int("fit.som.iterations", som.iterations, limits::MAX_ITERATIONS)?;
        }
        c.real("fit.fairness", self.fairness, 0.0, true, limits::MAX_FAIRNESS)?;
        crate::families::maps::check_exponential_alpha(c, "fit", self.exponential_alpha)?;
        c.cells(
            "fit",
            &[self.datasets.len(), self.control_nets.len(), self.parameterisations.len(), self.approaches.len()],
        )?;
        Ok(())
    }
    /// Every value of the `[fit]` section (after the limits).
    fn validate(&self, spec: &Spec) -> Result<(), SpecError> {
        validate_grid_keys(
            spec,
            "fit",
            &self.datasets,
            self.grid,
            &self.control_nets,
            &self.parameterisations,
        )?;
        if self.approaches.is_empty() {
            return Err(spec.err("fit.approaches", "is empty"));
        }
        validate_map_som(spec, "fit", self.som.as_ref())
    }
    fn datasets(&self) -> &[String] {
        &self.datasets
    }
    fn use_maps(&mut self, maps: &str) {
        self.maps = Some(maps.to_string());
    }
    fn require_inputs(
        &self,
        spec: &Spec,
        ctx: &crate::experiment::RunContext,
    ) -> anyhow::Result<()> {
        let from = MapsFrom {
            section: "fit",
            dir: self.maps.as_deref(),
            missing: self.maps_missing,
            som: self.som.as_ref(),
        };
        crate::families::maps::require_maps_and_data(spec, ctx, &self.datasets, self.grid, &from)
    }
}

/// The flat list of fit cells (data set x control net x parameterisation x approach).
pub(crate) fn cells(fit: &FitSpec) -> Vec<FitCell> {
    let mut cells = Vec::new();
    for dataset in &fit.datasets {
        for cn in &fit.control_nets {
            for &param in &fit.parameterisations {
                for &approach in &fit.approaches {
                    cells.push(FitCell {
                        dataset: crate::data::registry::name_of(dataset),
                        grid: fit.grid,
                        cn: *cn,
                        param,
                        approach,
                    });
                }
            }
        }
    }
    cells
}

/// One Chapter 5 cell: a two-surface fit of one DNSOM map (deterministic: no random stream).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct FitCell {
    pub(crate) dataset: String,
    pub(crate) grid: GridSize,
    pub(crate) cn: GridSize,
    pub(crate) param: crate::spline::Parameterisation,
    pub(crate) approach: crate::spline::Approach,
}

impl crate::experiment::runner::Cell for FitCell {
    fn key(&self) -> String {
        FitCell::key(self)
    }
}

impl FitCell {
    pub(crate) fn key(&self) -> String {
        format!(
            "fit/{}/{}/{}/{}/{}",
            self.dataset,
            self.grid,
            self.cn,
            self.param.name(),
            self.approach.letter()
        )
    }
}
