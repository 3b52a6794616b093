//! The `[closed_cylinder]` section (Chaurasiya & Agarwal: closed cylinder surface): its defaults and
//! checks.

use crate::experiment::limits::{self, Check};
use crate::experiment::spec::{Spec, SpecError};
use serde::Deserialize;

fn default_s4_control_points() -> Vec<usize> {
    vec![5, 6, 7, 8, 9, 10, 15, 20, 25, 30, 35, 40]
}
fn default_s4_table2_control_points() -> Vec<usize> {
    vec![5, 7]
}
fn default_s4_table2_generations() -> Vec<usize> {
    vec![0, 10, 25, 50, 100, 200, 300, 400, 500]
}
fn default_s4_generations() -> usize {
    500
}
fn default_s4_two() -> usize {
    2
}
fn default_s4_three() -> usize {
    3
}
fn default_five() -> f64 {
    5.0
}
fn default_s4_step() -> f64 {
    0.1
}
fn default_s4_search_range() -> f64 {
    0.25
}

/// Seed 004 section (Chaurasiya & Agarwal: closed B-spline surface of a cylinder by a binary GA):
/// numbers of control points around x repeats; defaults are the paper's (Tables I-III) and the
/// stated readings of experiments/seed004_cylinder.toml.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClosedCylinderSpec {
    /// Control points around (Table III's list); each is one family of `repeats` GA runs.
    #[serde(default = "default_s4_control_points")]
    pub control_points: Vec<usize>,
    /// The ones Table II follows generation by generation (must be in `control_points`).
    #[serde(default = "default_s4_table2_control_points")]
    pub table2_control_points: Vec<usize>,
    /// Table II's checkpoints (0 = the initial population; each at most `generations`).
    #[serde(default = "default_s4_table2_generations")]
    pub table2_generations: Vec<usize>,
    #[serde(default = "crate::experiment::defaults::ten")]
    pub repeats: usize,
    #[serde(default = "default_s4_generations")]
    pub generations: usize,
    #[serde(default = "crate::experiment::defaults::ten")]
    pub population: usize,
    /// Order around (closed; 3 = quadratic pieces) and up (clamped; 2 = linear), rows of the net.
    #[serde(default = "default_s4_three")]
    pub order_around: usize,
    #[serde(default = "default_s4_two")]
    pub order_vertical: usize,
    #[serde(default = "default_s4_two")]
    pub rows: usize,
    /// Cylinder and lattice: radius, height, lattice step, accuracy of |x^2 + y^2 - r^2|.
    #[serde(default = "default_five")]
    pub radius: f64,
    #[serde(default = "default_five")]
    pub height: f64,
    #[serde(default = "default_s4_step")]
    pub grid_step: f64,
    #[serde(default = "default_s4_step")]
    pub accuracy: f64,
    /// GA box: the analytical (x, y) of each control column +- this (data units).
    #[serde(default = "default_s4_search_range")]
    pub search_range: f64,
    /// What the GA's RMS measures (docs/readings.md): `at_parameters` (Eq. 9 at the chord-length
    /// parameters) or `closest_point` (Table II's "modelled curve and data points": foot points).
    #[serde(default)]
    pub error: crate::spline::closed::PointError,
    #[serde(default)]
    pub ga: crate::optim::binary_ga::BinaryGa,
}

impl crate::experiment::family::Section for ClosedCylinderSpec {
    /// The bounds of the `[closed_cylinder]` section's sizes and counts (docs/specs.md, "Spec limits").
    fn limits(&self, c: &Check) -> Result<(), SpecError> {
        c.list("closed_cylinder.control_points", &self.control_points)?;
        c.list("closed_cylinder.table2_control_points", &self.table2_control_points)?;
        c.list("closed_cylinder.table2_generations", &self.table2_generations)?;
        c.optimiser_run("closed_cylinder", self.repeats, self.generations, self.population)?;
        c.int("closed_cylinder.rows", self.rows, limits::MAX_GRID_SIDE as u64)?;
        for (key, v) in [
            ("radius", self.radius),
            ("height", self.height),
            ("grid_step", self.grid_step),
            ("accuracy", self.accuracy),
            ("search_range", self.search_range),
        ] {
            c.real(&format!("closed_cylinder.{key}"), v, 0.0, false, limits::MAX_LENGTH)?;
        }
        c.cells("closed_cylinder", &[self.control_points.len(), self.repeats])?;
        Ok(())
    }
    /// Every value of the `[closed_cylinder]` section (after the limits).
    fn validate(&self, spec: &Spec) -> Result<(), SpecError> {
        if self.control_points.is_empty() {
            return Err(spec.err("closed_cylinder.control_points", "is empty"));
        }
        if self.order_around < 2 || self.order_around > 8 {
            return Err(
                spec.err("closed_cylinder.order_around", format!("must be in [2, 8], got {}", self.order_around))
            );
        }
        if let Some(n) = self.control_points.iter().find(|&&n| n < self.order_around || n > 200) {
            return Err(spec.err(
                "closed_cylinder.control_points",
                format!("{n} is outside [order_around = {}, 200]", self.order_around),
            ));
        }
        if let Some(n) = self.table2_control_points.iter().find(|n| !self.control_points.contains(n)) {
            return Err(spec.err(
                "closed_cylinder.table2_control_points",
                format!("{n} is not in closed_cylinder.control_points"),
            ));
        }
        if let Some(g) = self.table2_generations.iter().find(|&&g| g > self.generations) {
            return Err(spec.err(
                "closed_cylinder.table2_generations",
                format!("{g} exceeds closed_cylinder.generations = {}", self.generations),
            ));
        }
        if self.order_vertical < 2 || self.rows < self.order_vertical {
            return Err(spec.err(
                "closed_cylinder.order_vertical",
                format!("must be at least 2 and at most rows = {}, got {}", self.rows, self.order_vertical),
            ));
        }
        if self.repeats == 0 {
            return Err(spec.err("closed_cylinder.repeats", "must be at least 1"));
        }
        if self.generations == 0 {
            return Err(spec.err("closed_cylinder.generations", "must be at least 1"));
        }
        if self.population < 2 || self.population <= self.ga.elitism {
            return Err(spec.err(
                "closed_cylinder.population",
                format!("must be at least 2 and above closed_cylinder.ga.elitism, got {}", self.population),
            ));
        }
        if self.radius / self.grid_step > 2000.0 || self.height / self.grid_step > 2000.0 {
            return Err(spec.err(
                "closed_cylinder.grid_step",
                format!("{} makes more than 2000 lattice steps across the cylinder", self.grid_step),
            ));
        }
        self.ga.validate().map_err(|e| match e {
            crate::optim::OptimError::InvalidParameter { key, message } => {
                spec.err(&format!("closed_cylinder.{}", key.replace("binary_ga", "ga")), message)
            }
            other => spec.err("closed_cylinder.ga", other),
        })?;
        Ok(())
    }
}
