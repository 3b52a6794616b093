//! The `[fit]` section (thesis Chapter 5): data sets x control nets x parameterisations x
//! approaches on one grid size, its checks and its cells; the keys it shares with `[optim]` are
//! checked here for both.

use crate::experiment::limits::{self, Check};
use crate::experiment::spec::{GridSize, Spec, SpecError};
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
    pub parameterisations: Vec<String>,
    /// A (conventional) and/or B (improved).
    pub approaches: Vec<String>,
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
    pub som: Option<FitSom>,
    /// Pictures like Appendices G/H and the error-vs-control-net chart.
    #[serde(default = "crate::families::som::spec::default_true")]
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
    #[serde(default = "default_exponential_alpha")]
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

/// Section 2.3.2's alpha = 0.8 of the exponential method.
pub(crate) fn default_exponential_alpha() -> f64 {
    crate::spline::param::EXPONENTIAL_ALPHA
}

/// `<section>.exponential_alpha` in (0, 1] (Eq. 2.8; 1 is chord length).
pub(crate) fn check_exponential_alpha(c: &Check, section: &str, v: f64) -> Result<(), SpecError> {
    let (lo, hi) = crate::spline::param::EXPONENTIAL_ALPHA_RANGE;
    c.real(&format!("{section}.exponential_alpha"), v, lo, false, hi)
}

/// What a run does when the `maps` folder a spec names, or a map in it, is not there.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MapsMissing {
    /// Refuse the run, naming the folder or file (a mistyped path does not silently cost a
    /// Chapter 4 run).
    #[default]
    Error,
    /// Recompute the missing maps from `<section>.som`, saying so on stderr.
    Recompute,
}

/// Settings of the DNSOM run that recomputes a missing map (the cell key is Chapter 4's,
/// `som/<data>/dnsom/<grid>/r0`, so the same seed gives the same map).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitSom {
    #[serde(default)]
    pub master_seed: Option<u64>,
    #[serde(default = "crate::families::som::spec::default_iterations")]
    pub iterations: usize,
    #[serde(default = "crate::families::som::spec::default_alpha0")]
    pub alpha0: f64,
}

/// The keys a `[fit]` and an `[optim]` section share (data sets, grid, control nets,
/// parameterisations), each error naming `<section>.<key>`.
pub(crate) fn validate_grid_keys(
    spec: &Spec,
    section: &str,
    datasets: &[String],
    grid: GridSize,
    control_nets: &[GridSize],
    parameterisations: &[String],
) -> Result<(), SpecError> {
    let key = |k: &str| format!("{section}.{k}");
    if datasets.is_empty() {
        return Err(spec.err(&key("datasets"), "is empty"));
    }
    if grid.nx.min(grid.ny) < 3 {
        return Err(
            spec.err(&key("grid"), format!("grid {grid} is too small (each side at least 3)"))
        );
    }
    if control_nets.is_empty() {
        return Err(spec.err(&key("control_nets"), "is empty"));
    }
    for cn in control_nets {
        if cn.nx < 4 || cn.ny < 4 {
            return Err(spec.err(&key("control_nets"), format!("control net {cn} is smaller than 4 (cubic needs p + 1 = 4 control points a side)")));
        }
        if cn.nx > grid.nx || cn.ny > grid.ny {
            return Err(spec.err(
                &key("control_nets"),
                format!("control net {cn} is larger than the grid {grid}"),
            ));
        }
    }
    if parameterisations.is_empty() {
        return Err(spec.err(&key("parameterisations"), "is empty"));
    }
    for p in parameterisations {
        p.parse::<crate::spline::Parameterisation>()
            .map_err(|e| spec.err(&key("parameterisations"), e))?;
    }
    Ok(())
}

/// The settings of the map recomputation (`<section>.som`).
pub(crate) fn validate_map_som(
    spec: &Spec,
    section: &str,
    som: Option<&FitSom>,
) -> Result<(), SpecError> {
    let Some(som) = som else { return Ok(()) };
    if som.iterations == 0 {
        return Err(spec.err(&format!("{section}.som.iterations"), "must be at least 1"));
    }
    if !(som.alpha0 > 0.0 && som.alpha0 <= 1.0) {
        return Err(spec.err(
            &format!("{section}.som.alpha0"),
            format!("must be in (0, 1], got {}", som.alpha0),
        ));
    }
    Ok(())
}

/// Every value of the `[fit]` section (after the limits).
pub(crate) fn validate(spec: &Spec, fit: &FitSpec) -> Result<(), SpecError> {
    validate_grid_keys(
        spec,
        "fit",
        &fit.datasets,
        fit.grid,
        &fit.control_nets,
        &fit.parameterisations,
    )?;
    if fit.approaches.is_empty() {
        return Err(spec.err("fit.approaches", "is empty"));
    }
    for a in &fit.approaches {
        a.parse::<crate::spline::Approach>().map_err(|e| spec.err("fit.approaches", e))?;
    }
    validate_map_som(spec, "fit", fit.som.as_ref())
}

/// The flat list of fit cells (data set x control net x parameterisation x approach).
pub fn cells(spec: &Spec) -> Vec<FitCell> {
    let Some(fit) = spec.section::<FitSpec>() else { return Vec::new() };
    let mut cells = Vec::new();
    for dataset in &fit.datasets {
        for cn in &fit.control_nets {
            for p in &fit.parameterisations {
                let Ok(param) = p.parse() else { continue };
                for a in &fit.approaches {
                    let Ok(approach) = a.parse() else { continue };
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
pub struct FitCell {
    pub dataset: String,
    pub grid: GridSize,
    pub cn: GridSize,
    pub param: crate::spline::Parameterisation,
    pub approach: crate::spline::Approach,
}

impl crate::experiment::runner::Cell for FitCell {
    fn key(&self) -> String {
        FitCell::key(self)
    }
}

impl FitCell {
    pub fn key(&self) -> String {
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

/// The bounds of the `[fit]` section's sizes and counts (docs/specs.md, "Spec limits").
pub(crate) fn limits(c: &Check, s: &FitSpec) -> Result<(), SpecError> {
    c.datasets("fit.datasets", &s.datasets)?;
    c.grids("fit.grid", [&s.grid])?;
    c.list("fit.control_nets", &s.control_nets)?;
    c.grids("fit.control_nets", &s.control_nets)?;
    c.list("fit.parameterisations", &s.parameterisations)?;
    c.list("fit.approaches", &s.approaches)?;
    if let Some(som) = &s.som {
        c.int("fit.som.iterations", som.iterations, limits::MAX_ITERATIONS)?;
    }
    c.real("fit.fairness", s.fairness, 0.0, true, limits::MAX_FAIRNESS)?;
    check_exponential_alpha(c, "fit", s.exponential_alpha)?;
    c.cells(
        "fit",
        &[s.datasets.len(), s.control_nets.len(), s.parameterisations.len(), s.approaches.len()],
    )?;
    Ok(())
}
