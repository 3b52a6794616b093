//! The `[rational_bezier]` section (Yahya: rational Bezier surfaces): its defaults and checks.

use crate::experiment::limits::{self, Check};
use crate::experiment::spec::{Spec, SpecError};
use serde::Deserialize;

fn default_s2_surfaces() -> Vec<String> {
    ["surface1", "surface2", "surface3", "surface4"].iter().map(|s| s.to_string()).collect()
}
fn default_s2_optimisers() -> Vec<crate::optim::Name> {
    ["ga", "de", "pso"].iter().map(|s| s.parse().expect("registered")).collect()
}
fn default_s2_generations() -> usize {
    1000
}
fn default_s2_grid() -> usize {
    21
}
fn default_s2_population() -> usize {
    40
}
fn default_s2_init_range() -> f64 {
    0.05
}
fn default_s2_margin() -> f64 {
    0.25
}
fn default_s2_w_min() -> f64 {
    0.01
}
fn default_s2_trace() -> u64 {
    400
}
fn default_s2_outlines() -> Vec<String> {
    crate::spline::conic::OUTLINES.iter().map(|s| s.to_string()).collect()
}
fn default_one() -> f64 {
    1.0
}
fn default_s2_l() -> usize {
    14
}
fn default_s2_d() -> f64 {
    2.6
}
fn default_s2_curve_generations() -> usize {
    200
}

/// Seed 002 section: surfaces x optimisers x repeats. The paper's settings tables did not survive
/// in the seed text, so the defaults are stated choices (see experiments/seed002_rational.toml).
///
/// No `deny_unknown_fields`: the flattened `tables` refuses every key it is handed that is not an
/// optimiser's table, with a message naming both kinds of key.
#[derive(Debug, Clone, Deserialize)]
pub struct RationalBezierSpec {
    /// surface1..surface4 (SPEC 7; domains fixed in `rational_bezier::TestSurface`).
    #[serde(default = "default_s2_surfaces")]
    pub surfaces: Vec<String>,
    /// Any registered optimiser (`optim::REGISTRY`).
    #[serde(default = "default_s2_optimisers")]
    pub(crate) optimisers: Vec<crate::optim::Name>,
    #[serde(default = "crate::experiment::defaults::ten")]
    pub repeats: usize,
    /// Iterations (the paper's charts run to 1000).
    #[serde(default = "default_s2_generations")]
    pub generations: usize,
    #[serde(default = "default_s2_population")]
    pub population: usize,
    /// Samples per side of the data grid (odd).
    #[serde(default = "default_s2_grid")]
    pub grid: usize,
    /// Half-width of the initial range around the start, as a share of the data's largest
    /// bounding-box extent (the data are not normalised; the domains differ in scale).
    #[serde(default = "default_s2_init_range")]
    pub init_range: f64,
    /// Search box: the data's bounding box widened by this share of its extent per axis.
    #[serde(default = "default_s2_margin")]
    pub bounds_margin: f64,
    /// w11 is searched in [w_min, 2 - w_min] (the G1 joins need 0 < w11 < 2).
    #[serde(default = "default_s2_w_min")]
    pub w_min: f64,
    #[serde(default = "default_s2_trace")]
    pub trace_every_evals: u64,
    /// Generated 2-D outlines for the conic curve fits (square, letter_d, letter_p); empty: none.
    #[serde(default = "default_s2_outlines")]
    pub outlines: Vec<String>,
    /// Arc-length spacing of the outline samples (one point per unit, pixel-like).
    #[serde(default = "default_one")]
    pub outline_spacing: f64,
    /// SAM06 length parameter L (default 14).
    #[serde(default = "default_s2_l")]
    pub sam06_l: usize,
    /// SAM06 distance threshold D (default 2.6).
    #[serde(default = "default_s2_d")]
    pub sam06_d: f64,
    /// SAM06 domination range R (default L).
    #[serde(default)]
    pub sam06_r: Option<usize>,
    /// Iterations of each conic fit (the paper's curve charts show 100 and 200).
    #[serde(default = "default_s2_curve_generations")]
    pub curve_generations: usize,
    /// Every registered optimiser's parameter table (`[rational_bezier.de]`, ...; Table 6.1 by default).
    #[serde(flatten)]
    pub(crate) tables: crate::optim::Tables,
}

impl crate::experiment::family::Section for RationalBezierSpec {
    /// The bounds of the `[rational_bezier]` section's sizes and counts (docs/specs.md, "Spec limits").
    fn limits(&self, c: &Check) -> Result<(), SpecError> {
        c.list("rational_bezier.surfaces", &self.surfaces)?;
        c.list("rational_bezier.optimisers", &self.optimisers)?;
        c.list("rational_bezier.outlines", &self.outlines)?;
        c.optimiser_run("rational_bezier", self.repeats, self.generations, self.population)?;
        c.int("rational_bezier.curve_generations", self.curve_generations, limits::MAX_GENERATIONS)?;
        c.int("rational_bezier.grid", self.grid, 1001)?;
        c.real("rational_bezier.init_range", self.init_range, 0.0, true, limits::MAX_RANGE)?;
        c.real("rational_bezier.bounds_margin", self.bounds_margin, 0.0, true, limits::MAX_RANGE)?;
        c.int("rational_bezier.trace_every_evals", self.trace_every_evals, limits::MAX_TRACE_EVERY)?;
        c.int("rational_bezier.sam06_l", self.sam06_l, 1000)?;
        if let Some(r) = self.sam06_r {
            c.int("rational_bezier.sam06_r", r, 1000)?;
        }
        c.real("rational_bezier.sam06_d", self.sam06_d, 0.0, false, limits::MAX_LENGTH)?;
        c.cells("rational_bezier", &[self.surfaces.len().max(self.outlines.len()), self.optimisers.len(), self.repeats])?;
        Ok(())
    }
    /// Every value of the `[rational_bezier]` section (after the limits).
    fn validate(&self, spec: &Spec) -> Result<(), SpecError> {
        if self.surfaces.is_empty() {
            return Err(spec.err("rational_bezier.surfaces", "is empty"));
        }
        for name in &self.surfaces {
            if crate::spline::rational_bezier::TestSurface::by_name(name).is_none() {
                return Err(spec.err(
                    "rational_bezier.surfaces",
                    format!(
                        "unknown surface `{name}` (expected surface1, surface2, surface3 or surface4)"
                    ),
                ));
            }
        }
        spec.validate_runs(
            "rational_bezier",
            &self.optimisers,
            &self.tables,
            self.repeats,
            self.generations as u64,
            self.population,
        )?;
        if self.grid < 5 || self.grid.is_multiple_of(2) {
            return Err(spec.err("rational_bezier.grid", format!("must be odd and at least 5, got {}", self.grid)));
        }
        if !(self.w_min > 0.0 && self.w_min < 1.0) {
            return Err(spec.err("rational_bezier.w_min", format!("must be in (0, 1), got {}", self.w_min)));
        }
        if self.trace_every_evals == 0 {
            return Err(spec.err("rational_bezier.trace_every_evals", "must be at least 1"));
        }
        for name in &self.outlines {
            if crate::spline::conic::outline(name).is_none() {
                return Err(spec.err(
                    "rational_bezier.outlines",
                    format!("unknown outline `{name}` (expected square, letter_d or letter_p)"),
                ));
            }
        }
        if !(self.outline_spacing > 0.0 && self.outline_spacing <= 10.0) {
            return Err(spec.err(
                "rational_bezier.outline_spacing",
                format!("must be in (0, 10], got {}", self.outline_spacing),
            ));
        }
        if self.sam06_l < 2 {
            return Err(spec.err("rational_bezier.sam06_l", format!("must be at least 2, got {}", self.sam06_l)));
        }
        if self.curve_generations == 0 {
            return Err(spec.err("rational_bezier.curve_generations", "must be at least 1"));
        }
        Ok(())
    }
}

