//! Experiment specs: TOML text -> raw serde structs (unknown keys rejected) -> a validated plan.
//!
//! A spec may carry named profiles (`[profiles.quick]`): tables deep-merged over the spec before it
//! is read, so a profile can change any key (e.g. `som.iterations = 3000`) and nothing else.
//! Errors are one line and name the file, the line and column, and the key at fault.

use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;
use std::str::FromStr;

/// A spec error: one line, naming the file and (where known) line:column and key.
#[derive(Debug, Clone, PartialEq)]
pub struct SpecError(pub String);

impl fmt::Display for SpecError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SpecError {}

/// Grid or control-net size `nx x ny`, written "20x12" (or "20" for 20x20).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct GridSize {
    pub nx: usize,
    pub ny: usize,
}

impl fmt::Display for GridSize {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}x{}", self.nx, self.ny)
    }
}

impl FromStr for GridSize {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("`{s}` is not a grid size (write NXxNY, e.g. \"20x12\")");
        let parts: Vec<&str> = s.trim().split(['x', 'X']).collect();
        let num = |p: &str| p.trim().parse::<usize>().map_err(|_| bad());
        match parts.as_slice() {
            [n] => {
                let n = num(n)?;
                Ok(GridSize { nx: n, ny: n })
            }
            [a, b] => Ok(GridSize { nx: num(a)?, ny: num(b)? }),
            _ => Err(bad()),
        }
    }
}

impl<'de> Deserialize<'de> for GridSize {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Text(String),
            Square(usize),
        }
        match Raw::deserialize(d)? {
            Raw::Text(s) => s.parse().map_err(serde::de::Error::custom),
            Raw::Square(n) => Ok(GridSize { nx: n, ny: n }),
        }
    }
}

impl serde::Serialize for GridSize {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

fn default_s2_surfaces() -> Vec<String> {
    ["surface1", "surface2", "surface3", "surface4"].iter().map(|s| s.to_string()).collect()
}
fn default_s2_optimisers() -> Vec<String> {
    ["ga", "de", "pso"].iter().map(|s| s.to_string()).collect()
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
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Seed002Spec {
    /// surface1..surface4 (SPEC 7; domains fixed in `rational_bezier::TestSurface`).
    #[serde(default = "default_s2_surfaces")]
    pub surfaces: Vec<String>,
    /// ga, de, pso.
    #[serde(default = "default_s2_optimisers")]
    pub optimisers: Vec<String>,
    #[serde(default = "default_ten")]
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
    #[serde(default)]
    pub ga: crate::optim::ga::Ga,
    #[serde(default)]
    pub de: crate::optim::de::De,
    #[serde(default)]
    pub pso: crate::optim::pso::Pso,
}

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
pub struct Seed004Spec {
    /// Control points around (Table III's list); each is one family of `repeats` GA runs.
    #[serde(default = "default_s4_control_points")]
    pub control_points: Vec<usize>,
    /// The ones Table II follows generation by generation (must be in `control_points`).
    #[serde(default = "default_s4_table2_control_points")]
    pub table2_control_points: Vec<usize>,
    /// Table II's checkpoints (0 = the initial population; each at most `generations`).
    #[serde(default = "default_s4_table2_generations")]
    pub table2_generations: Vec<usize>,
    #[serde(default = "default_ten")]
    pub repeats: usize,
    #[serde(default = "default_s4_generations")]
    pub generations: usize,
    #[serde(default = "default_ten")]
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
    #[serde(default)]
    pub ga: crate::optim::binary_ga::BinaryGa,
}

/// The whole spec file as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpecFile {
    /// Experiment name; the default output folder is `results/<name>`.
    pub name: String,
    #[serde(default)]
    pub description: String,
    /// Master seed every (cell, repeat) stream is derived from.
    pub master_seed: u64,
    /// Output folder (overridden by `--out`).
    #[serde(default)]
    pub output: Option<String>,
    /// How the data sets are scaled: per_axis (the thesis), uniform (aspect ratios kept) or none.
    #[serde(default)]
    pub normalise: crate::data::Normalise,
    /// Chapter 4: SOM models.
    #[serde(default)]
    pub som: Option<SomSpec>,
    /// Chapter 5: cubic B-spline fits of saved DNSOM maps.
    #[serde(default)]
    pub fit: Option<FitSpec>,
    /// Chapter 6: optimisation of approach B's control points.
    #[serde(default)]
    pub optim: Option<OptimSpec>,
    /// Seed 002 (Yahya): four-patch G1 rational bi-quadratic Bezier surfaces by GA/DE/PSO.
    #[serde(default)]
    pub seed002: Option<Seed002Spec>,
    /// Seed 003 (Iglesias et al.): Bezier surfaces with CSA/ICSA-searched data parameters.
    #[serde(default)]
    pub seed003: Option<super::seed003::Seed003Spec>,
    /// Seed 001: growing grid on open surfaces, one B-spline surface, GA/DE/PSO.
    #[serde(default)]
    pub growing_grid: Option<GrowingGridSpec>,
    /// Seed 004: closed B-spline surface of a cylinder by a binary-coded GA.
    #[serde(default)]
    pub seed004: Option<Seed004Spec>,
    /// Named overrides, merged over the spec by `--profile NAME`.
    #[serde(default)]
    pub profiles: BTreeMap<String, toml::Table>,
}

fn default_iterations() -> usize {
    30_000
}
fn default_alpha0() -> f64 {
    0.9
}
fn default_repeats() -> usize {
    1
}
fn default_true() -> bool {
    true
}

/// Chapter 4 section: data sets x groups of (models x grids) x repeats.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SomSpec {
    /// Data-set names (`somnurbs datasets list`) or paths to point files.
    pub datasets: Vec<String>,
    /// Maximum iteration T (Table 4.1).
    #[serde(default = "default_iterations")]
    pub iterations: usize,
    /// Initial learning rate alpha0 (Table 4.1).
    #[serde(default = "default_alpha0")]
    pub alpha0: f64,
    /// Initial radius; default half the smaller grid side (Table 4.1).
    #[serde(default)]
    pub sigma0: Option<f64>,
    #[serde(default = "default_repeats")]
    pub repeats: usize,
    /// Which models at which grid sizes.
    #[serde(rename = "group")]
    pub groups: Vec<SomGroup>,
    /// DNSOM grid sizes whose organised maps are saved as `maps/dnsom_<data>_<nx>x<ny>.csv`.
    #[serde(default)]
    pub save_maps: Vec<GridSize>,
    /// One PNG per cell and the overview pictures.
    #[serde(default = "default_true")]
    pub pictures: bool,
}

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
    /// Folder holding `dnsom_<data>_<nx>x<ny>.csv` (Chapter 4's `maps/`); a missing map is
    /// recomputed from the same seed and settings as Chapter 4 (see `[fit.som]`).
    #[serde(default)]
    pub maps: Option<String>,
    /// How a missing map is recomputed (defaults: this spec's master seed, T = 30000, alpha0 0.9).
    #[serde(default)]
    pub som: Option<FitSom>,
    /// Pictures like Appendices G/H and the error-vs-control-net chart.
    #[serde(default = "default_true")]
    pub pictures: bool,
    /// Reading of the knot rule for nets smaller than the grid (README "Readings").
    #[serde(default)]
    pub knots: crate::spline::KnotRule,
    /// Reading of approach A's surface error (README "Readings").
    #[serde(default)]
    pub error_a: crate::spline::ErrorA,
    /// Beyond the thesis: penalised least squares weight (0 = the thesis' plain least squares).
    #[serde(default)]
    pub fairness: f64,
}

impl FitSpec {
    /// The readings and options every fit of this section uses.
    pub fn fit_options(&self) -> crate::spline::FitOptions {
        crate::spline::FitOptions { knots: self.knots, error_a: self.error_a, fairness: self.fairness }
    }
}

/// Chapter 6 section: data sets x control nets x parameterisations x optimisers x repeats, every
/// optimiser started from approach B's control net of its cell.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OptimSpec {
    pub datasets: Vec<String>,
    pub grid: GridSize,
    pub control_nets: Vec<GridSize>,
    pub parameterisations: Vec<String>,
    /// ga, de, pso, csa, icsa.
    pub optimisers: Vec<String>,
    #[serde(default = "default_ten")]
    pub repeats: usize,
    #[serde(default = "default_generations")]
    pub generations: usize,
    #[serde(default = "default_population")]
    pub population: usize,
    /// Half-width of the initial range around B (Table 6.1: 5e-6).
    #[serde(default = "default_init_range")]
    pub init_range: f64,
    /// The search box: the data and B's control points, widened by this share of its size.
    #[serde(default)]
    pub bounds_margin: f64,
    /// If set, the search box is instead B's control points +- this per coordinate (Table 6.1's
    /// "control point coordinate range", 5e-6).
    #[serde(default)]
    pub search_range: Option<f64>,
    #[serde(default)]
    pub maps: Option<String>,
    #[serde(default)]
    pub som: Option<FitSom>,
    /// Also solve each cell's convex problem exactly in the box (certified) and report every
    /// optimiser's gap to it.
    #[serde(default)]
    pub exact: bool,
    /// Newton-step cap of the exact solver.
    #[serde(default = "default_exact_newton_steps")]
    pub exact_newton_steps: usize,
    /// The exact solver stops when its certified gap is at most this share of the optimum.
    #[serde(default = "default_exact_tol")]
    pub exact_tol: f64,
    /// Trace checkpoint: the best fitness so far is recorded every this many evaluations.
    #[serde(default = "default_trace_every")]
    pub trace_every_evals: u64,
    #[serde(default)]
    pub ga: crate::optim::ga::Ga,
    #[serde(default)]
    pub de: crate::optim::de::De,
    #[serde(default)]
    pub pso: crate::optim::pso::Pso,
    #[serde(default)]
    pub csa: crate::optim::cuckoo::Csa,
    #[serde(default)]
    pub icsa: crate::optim::cuckoo::Icsa,
    /// Reading of the knot rule of approach B's start (README "Readings").
    #[serde(default)]
    pub knots: crate::spline::KnotRule,
    /// Beyond the thesis: penalised least squares weight of B's start (0 = plain least squares).
    #[serde(default)]
    pub fairness: f64,
}

impl OptimSpec {
    /// The readings and options of approach B's fit that every cell starts from.
    pub fn fit_options(&self) -> crate::spline::FitOptions {
        crate::spline::FitOptions { knots: self.knots, fairness: self.fairness, ..Default::default() }
    }
}

/// Seed 001 section: a Growing Grid (Fritzke 1995) per open-surface data set, one cubic B-spline
/// surface per (net, parameterisation) from its least-squares fit, then GA/DE/PSO on the control
/// points (Table 6.1 settings by default).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GrowingGridSpec {
    pub datasets: Vec<String>,
    /// Target size of the grown map.
    pub grid: GridSize,
    pub control_nets: Vec<GridSize>,
    pub parameterisations: Vec<String>,
    /// ga, de, pso.
    pub optimisers: Vec<String>,
    #[serde(default = "default_ten")]
    pub repeats: usize,
    #[serde(default = "default_generations")]
    pub generations: usize,
    #[serde(default = "default_population")]
    pub population: usize,
    #[serde(default = "default_init_range")]
    pub init_range: f64,
    /// The search box: the data and the least-squares control points, widened by this share.
    #[serde(default)]
    pub bounds_margin: f64,
    #[serde(default = "default_trace_every")]
    pub trace_every_evals: u64,
    /// Constants of the growing grid (defaults: `som::growing_grid::GrowingGridParams`).
    #[serde(default)]
    pub growth: GrowthSpec,
    #[serde(default)]
    pub ga: crate::optim::ga::Ga,
    #[serde(default)]
    pub de: crate::optim::de::De,
    #[serde(default)]
    pub pso: crate::optim::pso::Pso,
}

/// The growing grid's constants in a spec.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GrowthSpec {
    pub lambda_g: usize,
    pub eps_g: f64,
    pub lambda_f: usize,
    pub eps_f0: f64,
    pub eps_f1: f64,
    pub sigma: f64,
    pub reach2: i32,
}

impl Default for GrowthSpec {
    fn default() -> Self {
        let p = crate::som::growing_grid::GrowingGridParams::default();
        GrowthSpec { lambda_g: p.lambda_g, eps_g: p.eps_g, lambda_f: p.lambda_f, eps_f0: p.eps_f0, eps_f1: p.eps_f1, sigma: p.sigma, reach2: p.reach2 }
    }
}

impl GrowingGridSpec {
    /// The growing grid's parameters for the target grid.
    pub fn params(&self) -> crate::som::growing_grid::GrowingGridParams {
        let g = &self.growth;
        crate::som::growing_grid::GrowingGridParams { nx: self.grid.nx, ny: self.grid.ny, lambda_g: g.lambda_g, eps_g: g.eps_g, lambda_f: g.lambda_f, eps_f0: g.eps_f0, eps_f1: g.eps_f1, sigma: g.sigma, reach2: g.reach2 }
    }
}

fn default_ten() -> usize {
    10
}
fn default_generations() -> usize {
    2000
}
fn default_population() -> usize {
    40
}
fn default_exact_newton_steps() -> usize {
    300
}
fn default_exact_tol() -> f64 {
    1e-7
}
fn default_trace_every() -> u64 {
    400
}
fn default_init_range() -> f64 {
    5e-6
}

/// Settings of the DNSOM run that recomputes a missing map (the cell key is Chapter 4's,
/// `som/<data>/dnsom/<grid>/r0`, so the same seed gives the same map).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitSom {
    #[serde(default)]
    pub master_seed: Option<u64>,
    #[serde(default = "default_iterations")]
    pub iterations: usize,
    #[serde(default = "default_alpha0")]
    pub alpha0: f64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SomGroup {
    pub models: Vec<String>,
    pub grids: Vec<GridSize>,
}

/// A spec read from a file, with the profile applied.
#[derive(Debug, Clone)]
pub struct Spec {
    pub file: SpecFile,
    /// The spec's text as read (kept in the manifest).
    pub text: String,
    pub path: String,
    pub profile: Option<String>,
    /// The command line's `--set`/`--sweep` as written (empty for a plain run).
    pub cli: CliOverrides,
    /// Which variant of the spec this is: its `key=value` changes (empty for a plain run).
    pub variant: Variant,
}

/// The command line's changes to a spec, as written: `--set KEY=VALUE` (one value) and
/// `--sweep KEY=V1,V2,...` (every combination of the swept values is one variant, all run into
/// one folder). Recorded in the fingerprint and the manifest, so `--resume` and `merge` rebuild
/// the same variants.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CliOverrides {
    pub set: Vec<String>,
    pub sweep: Vec<String>,
}

/// One variant of a spec: the `key=value` changes of `--set` and those of `--sweep`, as written.
/// A plain run has none, and its cell keys and seeds are those of the spec alone.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Variant {
    pub set: Vec<String>,
    pub swept: Vec<String>,
}

impl Variant {
    /// What the cell keys (so the seeds) carry: every change, `--set` first (empty: plain run).
    pub fn key(&self) -> String {
        self.set.iter().chain(&self.swept).cloned().collect::<Vec<_>>().join(",")
    }

    /// The `variant` column of a sweep's rows: the swept values (empty without `--sweep`).
    pub fn label(&self) -> String {
        self.swept.join(",")
    }
}

/// Keys a sweep may vary: optimiser settings only, so that every variant solves the same
/// problems (same data, nets, search box) and the variants can be ranked like optimisers.
const SWEEPABLE: &str = "optim.<ga|de|pso|csa|icsa>.*, optim.generations, optim.population, optim.init_range, optim.repeats";

fn sweepable(key: &str) -> bool {
    ["optim.ga.", "optim.de.", "optim.pso.", "optim.csa.", "optim.icsa."].iter().any(|p| key.starts_with(p))
        || ["optim.generations", "optim.population", "optim.init_range", "optim.repeats"].contains(&key)
}

/// A command-line value as TOML (a number, a boolean, a quoted string, an array), else the text
/// itself as a string (so `--set optim.knots=nurbs_book` needs no quotes).
fn cli_value(raw: &str) -> toml::Value {
    match toml::from_str::<toml::Table>(&format!("v = {raw}")) {
        Ok(mut t) => t.remove("v").unwrap_or_else(|| toml::Value::String(raw.to_string())),
        Err(_) => toml::Value::String(raw.to_string()),
    }
}

impl CliOverrides {
    pub fn is_empty(&self) -> bool {
        self.set.is_empty() && self.sweep.is_empty()
    }

    /// Split `KEY=VALUE` (or `KEY=V1,V2` for a sweep) of `flag`, naming the flag on error.
    fn split<'a>(flag: &str, arg: &'a str) -> Result<(&'a str, &'a str), SpecError> {
        match arg.split_once('=') {
            Some((k, v)) if !k.trim().is_empty() && !v.trim().is_empty() => Ok((k.trim(), v.trim())),
            _ => Err(SpecError(format!("{flag} `{arg}`: expected KEY=VALUE, e.g. optim.de.f=0.5"))),
        }
    }

    /// The variants of the spec at `path` (its text and profile): one for a plain run or `--set`
    /// only, else one per combination of the swept values (the first `--sweep` outermost). Each
    /// is parsed and validated exactly as if its values were written in the file; an unknown key,
    /// a bad value, a key given twice or a swept value given twice is a one-line error naming
    /// the key.
    pub fn variants(&self, path: &str, text: &str, profile: Option<&str>) -> Result<Vec<Spec>, SpecError> {
        let base = Spec::parse(path, text, profile)?;
        if self.is_empty() {
            return Ok(vec![base]);
        }
        let flags = self.set.iter().map(|a| ("--set", a)).chain(self.sweep.iter().map(|a| ("--sweep", a)));
        let mut seen: Vec<String> = Vec::new();
        for (flag, arg) in flags {
            let (key, _) = Self::split(flag, arg)?;
            if seen.iter().any(|k| k == key) {
                return Err(SpecError(format!("{flag} {key}: the key is given twice (--set and --sweep take each key once)")));
            }
            seen.push(key.to_string());
            if !key.starts_with("optim.") {
                return Err(SpecError(format!("{flag} {key}: only keys of the [optim] section (optim.KEY) can be set or swept")));
            }
            if base.file.optim.is_none() {
                return Err(SpecError(format!("{flag} {key}: {path} has no [optim] section (--set and --sweep work on Chapter 6 specs)")));
            }
            if flag == "--sweep" && !sweepable(key) {
                return Err(SpecError(format!("{flag} {key}: a sweep varies optimiser settings only ({SWEEPABLE}), so that every variant solves the same problems")));
            }
        }
        let set: Vec<(String, String)> = self.set.iter().map(|a| Self::split("--set", a).map(|(k, v)| (k.to_string(), v.to_string()))).collect::<Result<_, _>>()?;
        // Every combination of the swept values, the first sweep outermost.
        let mut combos: Vec<Vec<(String, String)>> = vec![Vec::new()];
        for arg in &self.sweep {
            let (key, values) = Self::split("--sweep", arg)?;
            let values: Vec<&str> = values.split(',').map(str::trim).collect();
            if values.iter().any(|v| v.is_empty()) {
                return Err(SpecError(format!("--sweep {key}: an empty value in `{arg}`")));
            }
            if let Some(v) = values.iter().enumerate().find(|(k, v)| values[..*k].contains(v)).map(|(_, v)| v) {
                return Err(SpecError(format!("--sweep {key}: the value {v} is given twice")));
            }
            combos = combos.into_iter().flat_map(|c| values.iter().map(move |v| [c.clone(), vec![(key.to_string(), v.to_string())]].concat())).collect();
        }
        combos
            .into_iter()
            .map(|swept| {
                let overrides: Vec<Override> = set.iter().chain(&swept).map(|(k, v)| Override { key: k.clone(), value: cli_value(v) }).collect();
                let mut spec = Spec::parse_with(path, text, profile, &overrides)?;
                spec.cli = self.clone();
                let pairs = |l: &[(String, String)]| l.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>();
                spec.variant = Variant { set: pairs(&set), swept: pairs(&swept) };
                Ok(spec)
            })
            .collect()
    }
}

fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.len() - before.rfind('\n').map(|p| p + 1).unwrap_or(0) + 1;
    (line, col)
}

fn toml_error(path: &str, text: &str, e: &toml::de::Error) -> SpecError {
    let msg = e.message().replace('\n', " ");
    match e.span() {
        Some(span) => {
            let (l, c) = line_col(text, span.start);
            SpecError(format!("{path}:{l}:{c}: {msg}"))
        }
        None => SpecError(format!("{path}: {msg}")),
    }
}

/// Deep-merge `over` into `base` (tables merge, everything else replaces).
fn merge(base: &mut toml::Table, over: &toml::Table) {
    for (k, v) in over {
        match (base.get_mut(k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge(b, o),
            _ => {
                base.insert(k.clone(), v.clone());
            }
        }
    }
}

/// One change to a spec by a dotted key (`fit.knots`, `optim.de.f`), as a reading set of a plan
/// makes it: applied after the profile and validated exactly as the file's own value.
#[derive(Debug, Clone, PartialEq)]
pub struct Override {
    pub key: String,
    pub value: toml::Value,
}

impl fmt::Display for Override {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} = {}", self.key, self.value)
    }
}

/// Apply `over` to a spec table. A key whose section (first part) the spec does not have is
/// skipped (a reading set names keys of several families) and reported as `false`.
fn apply_override(table: &mut toml::Table, over: &Override) -> Result<bool, String> {
    let parts: Vec<&str> = over.key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err(format!("`{}` is not a dotted key", over.key));
    }
    if parts.len() > 1 && !matches!(table.get(parts[0]), Some(toml::Value::Table(_))) {
        return Ok(false);
    }
    let mut t = table;
    for p in &parts[..parts.len() - 1] {
        let entry = t.entry(p.to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new()));
        t = match entry {
            toml::Value::Table(inner) => inner,
            _ => return Err(format!("`{}`: `{p}` is not a table", over.key)),
        };
    }
    t.insert(parts[parts.len() - 1].to_string(), over.value.clone());
    Ok(true)
}

impl Spec {
    /// Parse spec text with a reading set's overrides applied after the profile (each validated
    /// as if written in the file); `path` is used in messages only.
    pub fn parse_with(path: &str, text: &str, profile: Option<&str>, overrides: &[Override]) -> Result<Spec, SpecError> {
        let mut spec = Spec::parse(path, text, profile)?;
        if overrides.is_empty() {
            return Ok(spec);
        }
        let mut table: toml::Table = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
        if let Some(over) = profile.and_then(|p| spec.file.profiles.get(p)) {
            merge(&mut table, &over.clone());
        }
        for o in overrides {
            apply_override(&mut table, o).map_err(|e| SpecError(format!("{path}: {e}")))?;
        }
        let merged = toml::to_string(&table).map_err(|e| SpecError(format!("{path}: {e}")))?;
        spec.file = toml::from_str(&merged).map_err(|e| SpecError(format!("{path}: with {}: {}", overrides.iter().map(|o| o.to_string()).collect::<Vec<_>>().join(", "), e.message().replace('\n', " "))))?;
        spec.validate()?;
        Ok(spec)
    }

    /// Parse spec text; `path` is used in messages only.
    pub fn parse(path: &str, text: &str, profile: Option<&str>) -> Result<Spec, SpecError> {
        let file: SpecFile = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
        let file = match profile {
            None => file,
            Some(name) => {
                let over = file.profiles.get(name).ok_or_else(|| {
                    let known: Vec<&str> = file.profiles.keys().map(|s| s.as_str()).collect();
                    SpecError(format!(
                        "{path}: no profile `{name}` (the spec defines: {})",
                        if known.is_empty() { "none".to_string() } else { known.join(", ") }
                    ))
                })?;
                let mut table: toml::Table = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
                merge(&mut table, over);
                let merged = toml::to_string(&table).map_err(|e| SpecError(format!("{path}: {e}")))?;
                toml::from_str(&merged).map_err(|e| {
                    SpecError(format!("{path}: [profiles.{name}]: {}", e.message().replace('\n', " ")))
                })?
            }
        };
        let spec = Spec { file, text: text.to_string(), path: path.to_string(), profile: profile.map(String::from), cli: CliOverrides::default(), variant: Variant::default() };
        spec.validate()?;
        Ok(spec)
    }

    /// Read and parse a spec file.
    pub fn load(path: &Path, profile: Option<&str>) -> Result<Spec, SpecError> {
        let shown = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| SpecError(format!("{shown}: cannot read spec: {e}")))?;
        Spec::parse(&shown, &text, profile)
    }

    /// Read a spec file and make its variants ([`CliOverrides::variants`]).
    pub fn load_variants(path: &Path, profile: Option<&str>, cli: &CliOverrides) -> Result<Vec<Spec>, SpecError> {
        let shown = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| SpecError(format!("{shown}: cannot read spec: {e}")))?;
        cli.variants(&shown, &text, profile)
    }

    fn err(&self, key: &str, msg: impl fmt::Display) -> SpecError {
        SpecError(format!("{}: {key}: {msg}", self.path))
    }

    /// Checks every value once, so that a run never starts on a spec it would fail on later.
    pub fn validate(&self) -> Result<(), SpecError> {
        let f = &self.file;
        if f.name.trim().is_empty() || f.name.contains(['/', '\\']) {
            return Err(self.err("name", "must be a non-empty name without slashes"));
        }
        // Bounds, duplicates and names first: later checks allocate from sizes.
        super::limits::check(self)?;
        let families = super::family::present(self);
        match families.len() {
            0 => return Err(SpecError(format!("{}: the spec has no experiment section (add one of {})", self.path, super::family::section_list()))),
            1 => {}
            _ => {
                let names: Vec<String> = families.iter().map(|f| format!("[{}]", f.section())).collect();
                return Err(SpecError(format!("{}: one experiment section per spec, this one has {} (they write the same files: split the spec)", self.path, names.join(" and "))));
            }
        }
        if let Some(g) = &f.growing_grid {
            return self.validate_growing_grid(g);
        }
        if let Some(s) = &f.seed003 {
            s.validate().map_err(|(key, msg)| self.err(&key, msg))?;
            return self.validate_optimiser_params("seed003", [s.csa.validate(), s.icsa.validate()]);
        }
        if let Some(o) = &f.optim {
            self.validate_optim(o)?;
        }
        if let Some(s) = &f.seed002 {
            self.validate_seed002(s)?;
        }
        if let Some(s) = &f.seed004 {
            self.validate_seed004(s)?;
        }
        if let Some(fit) = &f.fit {
            self.validate_fit(fit)?;
        }
        let Some(som) = &f.som else { return Ok(()) };
        if som.datasets.is_empty() {
            return Err(self.err("som.datasets", "is empty"));
        }
        if som.iterations == 0 {
            return Err(self.err("som.iterations", "must be at least 1"));
        }
        if !(som.alpha0 > 0.0 && som.alpha0 <= 1.0) {
            return Err(self.err("som.alpha0", format!("must be in (0, 1], got {}", som.alpha0)));
        }
        if let Some(s) = som.sigma0 {
            if !(s > 1.0) {
                return Err(self.err("som.sigma0", format!("must exceed 1 (tau = T / ln sigma0), got {s}")));
            }
        }
        if som.repeats == 0 {
            return Err(self.err("som.repeats", "must be at least 1"));
        }
        if som.groups.is_empty() {
            return Err(self.err("som.group", "no [[som.group]] given"));
        }
        for (g, group) in som.groups.iter().enumerate() {
            let key = format!("som.group[{g}]");
            if group.models.is_empty() {
                return Err(self.err(&format!("{key}.models"), "is empty"));
            }
            if group.grids.is_empty() {
                return Err(self.err(&format!("{key}.grids"), "is empty"));
            }
            for m in &group.models {
                let model: crate::som::Model = m.parse().map_err(|e| self.err(&format!("{key}.models"), e))?;
                for grid in &group.grids {
                    if som.sigma0.is_none() && grid.nx.min(grid.ny) < 3 {
                        return Err(self.err(
                            &format!("{key}.grids"),
                            format!("grid {grid} is too small: sigma0 = min(nx,ny)/2 must exceed 1"),
                        ));
                    }
                    model.topology(grid.nx, grid.ny).map_err(|e| self.err(&format!("{key}.grids"), e))?;
                }
            }
        }
        for grid in &som.save_maps {
            let has = self.som_cells().iter().any(|c| c.model == crate::som::Model::Dnsom && c.grid == *grid);
            if !has {
                return Err(self.err("som.save_maps", format!("no DNSOM cell at grid {grid} to save")));
            }
        }
        Ok(())
    }

    fn validate_fit(&self, fit: &FitSpec) -> Result<(), SpecError> {
        if fit.datasets.is_empty() {
            return Err(self.err("fit.datasets", "is empty"));
        }
        if fit.grid.nx.min(fit.grid.ny) < 3 {
            return Err(self.err("fit.grid", format!("grid {} is too small (each side at least 3)", fit.grid)));
        }
        if fit.control_nets.is_empty() {
            return Err(self.err("fit.control_nets", "is empty"));
        }
        for cn in &fit.control_nets {
            if cn.nx < 4 || cn.ny < 4 {
                return Err(self.err("fit.control_nets", format!("control net {cn} is smaller than 4 (cubic needs p + 1 = 4 control points a side)")));
            }
            if cn.nx > fit.grid.nx || cn.ny > fit.grid.ny {
                return Err(self.err("fit.control_nets", format!("control net {cn} is larger than the grid {}", fit.grid)));
            }
        }
        if fit.parameterisations.is_empty() {
            return Err(self.err("fit.parameterisations", "is empty"));
        }
        for p in &fit.parameterisations {
            p.parse::<crate::spline::Parameterisation>().map_err(|e| self.err("fit.parameterisations", e))?;
        }
        if fit.approaches.is_empty() {
            return Err(self.err("fit.approaches", "is empty"));
        }
        for a in &fit.approaches {
            a.parse::<crate::spline::Approach>().map_err(|e| self.err("fit.approaches", e))?;
        }
        if let Some(som) = &fit.som {
            if som.iterations == 0 {
                return Err(self.err("fit.som.iterations", "must be at least 1"));
            }
            if !(som.alpha0 > 0.0 && som.alpha0 <= 1.0) {
                return Err(self.err("fit.som.alpha0", format!("must be in (0, 1], got {}", som.alpha0)));
            }
        }
        Ok(())
    }

    fn validate_seed002(&self, s: &Seed002Spec) -> Result<(), SpecError> {
        if s.surfaces.is_empty() {
            return Err(self.err("seed002.surfaces", "is empty"));
        }
        for name in &s.surfaces {
            if crate::spline::rational_bezier::TestSurface::by_name(name).is_none() {
                return Err(self.err("seed002.surfaces", format!("unknown surface `{name}` (expected surface1, surface2, surface3 or surface4)")));
            }
        }
        self.validate_runs("seed002", &s.optimisers, &["ga", "de", "pso"], s.repeats, s.generations as u64, s.population)?;
        if s.grid < 5 || s.grid.is_multiple_of(2) {
            return Err(self.err("seed002.grid", format!("must be odd and at least 5, got {}", s.grid)));
        }
        if !(s.init_range >= 0.0 && s.init_range.is_finite()) {
            return Err(self.err("seed002.init_range", format!("must be a non-negative number, got {}", s.init_range)));
        }
        if !(s.bounds_margin >= 0.0 && s.bounds_margin.is_finite()) {
            return Err(self.err("seed002.bounds_margin", format!("must be a non-negative number, got {}", s.bounds_margin)));
        }
        if !(s.w_min > 0.0 && s.w_min < 1.0) {
            return Err(self.err("seed002.w_min", format!("must be in (0, 1), got {}", s.w_min)));
        }
        if s.trace_every_evals == 0 {
            return Err(self.err("seed002.trace_every_evals", "must be at least 1"));
        }
        for name in &s.outlines {
            if crate::spline::conic::outline(name).is_none() {
                return Err(self.err("seed002.outlines", format!("unknown outline `{name}` (expected square, letter_d or letter_p)")));
            }
        }
        if !(s.outline_spacing > 0.0 && s.outline_spacing <= 10.0) {
            return Err(self.err("seed002.outline_spacing", format!("must be in (0, 10], got {}", s.outline_spacing)));
        }
        if s.sam06_l < 2 {
            return Err(self.err("seed002.sam06_l", format!("must be at least 2, got {}", s.sam06_l)));
        }
        if !(s.sam06_d > 0.0 && s.sam06_d.is_finite()) {
            return Err(self.err("seed002.sam06_d", format!("must be a positive number, got {}", s.sam06_d)));
        }
        if s.curve_generations == 0 {
            return Err(self.err("seed002.curve_generations", "must be at least 1"));
        }
        self.validate_optimiser_params("seed002", [s.ga.validate(), s.de.validate(), s.pso.validate()])?;
        Ok(())
    }

    fn validate_seed004(&self, s: &Seed004Spec) -> Result<(), SpecError> {
        if s.control_points.is_empty() {
            return Err(self.err("seed004.control_points", "is empty"));
        }
        if s.order_around < 2 || s.order_around > 8 {
            return Err(self.err("seed004.order_around", format!("must be in [2, 8], got {}", s.order_around)));
        }
        if let Some(n) = s.control_points.iter().find(|&&n| n < s.order_around || n > 200) {
            return Err(self.err("seed004.control_points", format!("{n} is outside [order_around = {}, 200]", s.order_around)));
        }
        if let Some(n) = s.table2_control_points.iter().find(|n| !s.control_points.contains(n)) {
            return Err(self.err("seed004.table2_control_points", format!("{n} is not in seed004.control_points")));
        }
        if let Some(g) = s.table2_generations.iter().find(|&&g| g > s.generations) {
            return Err(self.err("seed004.table2_generations", format!("{g} exceeds seed004.generations = {}", s.generations)));
        }
        if s.order_vertical < 2 || s.rows < s.order_vertical {
            return Err(self.err("seed004.order_vertical", format!("must be at least 2 and at most rows = {}, got {}", s.rows, s.order_vertical)));
        }
        if s.repeats == 0 {
            return Err(self.err("seed004.repeats", "must be at least 1"));
        }
        if s.generations == 0 {
            return Err(self.err("seed004.generations", "must be at least 1"));
        }
        if s.population < 2 || s.population <= s.ga.elitism {
            return Err(self.err("seed004.population", format!("must be at least 2 and above seed004.ga.elitism, got {}", s.population)));
        }
        for (key, v) in [("radius", s.radius), ("height", s.height), ("grid_step", s.grid_step), ("accuracy", s.accuracy), ("search_range", s.search_range)] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(self.err(&format!("seed004.{key}"), format!("must be a positive number, got {v}")));
            }
        }
        if s.radius / s.grid_step > 2000.0 || s.height / s.grid_step > 2000.0 {
            return Err(self.err("seed004.grid_step", format!("{} makes more than 2000 lattice steps across the cylinder", s.grid_step)));
        }
        s.ga.validate().map_err(|e| match e {
            crate::optim::OptimError::InvalidParameter { key, message } => self.err(&format!("seed004.{}", key.replace("binary_ga", "ga")), message),
            other => self.err("seed004.ga", other),
        })?;
        Ok(())
    }

    fn validate_growing_grid(&self, g: &GrowingGridSpec) -> Result<(), SpecError> {
        if g.datasets.is_empty() {
            return Err(self.err("growing_grid.datasets", "is empty"));
        }
        if let Some(d) = g.datasets.iter().find(|d| d.trim().is_empty()) {
            return Err(self.err("growing_grid.datasets", format!("empty data set name `{d}`")));
        }
        g.params().validate().map_err(|e| self.err("growing_grid.growth", e))?;
        if g.control_nets.is_empty() {
            return Err(self.err("growing_grid.control_nets", "is empty"));
        }
        for cn in &g.control_nets {
            if cn.nx < 4 || cn.ny < 4 || cn.nx > g.grid.nx || cn.ny > g.grid.ny {
                return Err(self.err("growing_grid.control_nets", format!("net {cn} must be at least 4x4 (cubic) and at most the grid {}", g.grid)));
            }
        }
        if g.parameterisations.is_empty() {
            return Err(self.err("growing_grid.parameterisations", "is empty"));
        }
        for p in &g.parameterisations {
            p.parse::<crate::spline::Parameterisation>().map_err(|e| self.err("growing_grid.parameterisations", e))?;
        }
        self.validate_runs("growing_grid", &g.optimisers, &["ga", "de", "pso"], g.repeats, g.generations as u64, g.population)?;
        if !(g.init_range >= 0.0 && g.init_range.is_finite()) {
            return Err(self.err("growing_grid.init_range", format!("must be a non-negative number, got {}", g.init_range)));
        }
        if !(g.bounds_margin >= 0.0 && g.bounds_margin.is_finite()) {
            return Err(self.err("growing_grid.bounds_margin", format!("must be a non-negative number, got {}", g.bounds_margin)));
        }
        if g.trace_every_evals == 0 {
            return Err(self.err("growing_grid.trace_every_evals", "must be at least 1"));
        }
        Ok(())
    }

    /// The checks every optimisation section shares: its optimiser names (from `allowed`),
    /// repeats, generations and population, each error naming `<section>.<key>`.
    fn validate_runs(&self, section: &str, optimisers: &[String], allowed: &[&str], repeats: usize, generations: u64, population: usize) -> Result<(), SpecError> {
        let key = |k: &str| format!("{section}.{k}");
        if optimisers.is_empty() {
            return Err(self.err(&key("optimisers"), "is empty"));
        }
        let expected = match allowed.split_last() {
            Some((last, [])) => last.to_string(),
            Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
            None => String::new(),
        };
        for name in optimisers {
            if !allowed.contains(&name.as_str()) {
                return Err(self.err(&key("optimisers"), format!("unknown optimiser `{name}` (expected {expected})")));
            }
        }
        if repeats == 0 {
            return Err(self.err(&key("repeats"), "must be at least 1"));
        }
        if generations == 0 {
            return Err(self.err(&key("generations"), "must be at least 1"));
        }
        if population < 4 {
            return Err(self.err(&key("population"), format!("must be at least 4 (DE/rand/1 needs four), got {population}")));
        }
        Ok(())
    }

    /// The optimisers' own parameter checks, their keys placed under `section`.
    fn validate_optimiser_params<const N: usize>(&self, section: &str, checks: [Result<(), crate::optim::OptimError>; N]) -> Result<(), SpecError> {
        for check in checks {
            check.map_err(|e| match e {
                crate::optim::OptimError::InvalidParameter { key, message } => self.err(&format!("{section}.{key}"), message),
                other => self.err(section, other),
            })?;
        }
        Ok(())
    }

    fn validate_optim(&self, o: &OptimSpec) -> Result<(), SpecError> {
        let as_fit = FitSpec {
            datasets: o.datasets.clone(),
            grid: o.grid,
            control_nets: o.control_nets.clone(),
            parameterisations: o.parameterisations.clone(),
            approaches: vec!["B".into()],
            maps: o.maps.clone(),
            som: o.som.clone(),
            pictures: false,
            knots: o.knots,
            error_a: Default::default(),
            fairness: o.fairness,
        };
        self.validate_fit(&as_fit).map_err(|e| SpecError(e.0.replace(": fit.", ": optim.")))?;
        self.validate_runs("optim", &o.optimisers, &["ga", "de", "pso", "csa", "icsa"], o.repeats, o.generations as u64, o.population)?;
        if !(o.init_range >= 0.0 && o.init_range.is_finite()) {
            return Err(self.err("optim.init_range", format!("must be a non-negative number, got {}", o.init_range)));
        }
        if let Some(r) = o.search_range {
            if !(r > 0.0 && r.is_finite()) {
                return Err(self.err("optim.search_range", format!("must be a positive number, got {r}")));
            }
            if o.init_range > r {
                return Err(self.err("optim.init_range", format!("{} is wider than optim.search_range {r}", o.init_range)));
            }
        }
        if !(o.bounds_margin >= 0.0 && o.bounds_margin.is_finite()) {
            return Err(self.err("optim.bounds_margin", format!("must be a non-negative number, got {}", o.bounds_margin)));
        }
        if o.trace_every_evals == 0 {
            return Err(self.err("optim.trace_every_evals", "must be at least 1"));
        }
        if !(o.exact_tol > 0.0 && o.exact_tol < 1.0) {
            return Err(self.err("optim.exact_tol", format!("must be in (0,1), got {}", o.exact_tol)));
        }
        self.validate_optimiser_params("optim", [o.ga.validate(), o.de.validate(), o.pso.validate(), o.csa.validate(), o.icsa.validate()])?;
        Ok(())
    }

    /// The flat list of optimisation cells (data x net x parameterisation x optimiser x repeat).
    pub fn optim_cells(&self) -> Vec<OptimCell> {
        let Some(o) = &self.file.optim else { return Vec::new() };
        let mut cells = Vec::new();
        for dataset in &o.datasets {
            for cn in &o.control_nets {
                for p in &o.parameterisations {
                    let Ok(param) = p.parse() else { continue };
                    for opt in &o.optimisers {
                        for repeat in 0..o.repeats {
                            cells.push(OptimCell { dataset: crate::data::registry::name_of(dataset), grid: o.grid, cn: *cn, param, optimiser: opt.clone(), repeat, variant: self.variant.key() });
                        }
                    }
                }
            }
        }
        cells
    }

    /// The flat list of fit cells (data set x control net x parameterisation x approach).
    pub fn fit_cells(&self) -> Vec<FitCell> {
        let Some(fit) = &self.file.fit else { return Vec::new() };
        let mut cells = Vec::new();
        for dataset in &fit.datasets {
            for cn in &fit.control_nets {
                for p in &fit.parameterisations {
                    let Ok(param) = p.parse() else { continue };
                    for a in &fit.approaches {
                        let Ok(approach) = a.parse() else { continue };
                        cells.push(FitCell { dataset: crate::data::registry::name_of(dataset), grid: fit.grid, cn: *cn, param, approach });
                    }
                }
            }
        }
        cells
    }

    /// The flat list of SOM cells (data set x group x grid x model x repeat), in report order.
    pub fn som_cells(&self) -> Vec<SomCell> {
        let Some(som) = &self.file.som else { return Vec::new() };
        let mut cells = Vec::new();
        // Groups may share a (model, grid): each cell once, in first-seen order.
        let mut seen = std::collections::HashSet::new();
        for dataset in &som.datasets {
            for group in &som.groups {
                for grid in &group.grids {
                    for m in &group.models {
                        let Ok(model) = m.parse() else { continue };
                        for repeat in 0..som.repeats {
                            let cell = SomCell { dataset: crate::data::registry::name_of(dataset), model, grid: *grid, repeat };
                            if seen.insert(cell.key()) {
                                cells.push(cell);
                            }
                        }
                    }
                }
            }
        }
        cells
    }

    /// Output folder: `--out`, else the spec's `output`, else `results/<name>`.
    pub fn output_dir(&self, out: Option<&Path>) -> std::path::PathBuf {
        match (out, &self.file.output) {
            (Some(o), _) => o.to_path_buf(),
            (None, Some(o)) => o.into(),
            (None, None) => Path::new("results").join(&self.file.name),
        }
    }
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
        format!("fit/{}/{}/{}/{}/{}", self.dataset, self.grid, self.cn, self.param.name(), self.approach.letter())
    }
}

/// One Chapter 6 cell: one optimiser run from approach B's control net.
#[derive(Debug, Clone, PartialEq)]
pub struct OptimCell {
    pub dataset: String,
    pub grid: GridSize,
    pub cn: GridSize,
    pub param: crate::spline::Parameterisation,
    pub optimiser: String,
    pub repeat: usize,
    /// The spec variant's changes ([`Variant::key`]; empty for a plain run).
    pub variant: String,
}

impl crate::experiment::runner::Cell for OptimCell {
    fn key(&self) -> String {
        OptimCell::key(self)
    }
}

impl OptimCell {
    /// `optim/<data>/<grid>/<net>/<param>/<optimiser>/r<repeat>`; a variant's cells begin
    /// `optim[<changes>]/`, so their seeds differ from the plain run's and from each other's.
    pub fn key(&self) -> String {
        let head = if self.variant.is_empty() { "optim".to_string() } else { format!("optim[{}]", self.variant) };
        format!("{head}/{}/{}/{}/{}/{}/r{}", self.dataset, self.grid, self.cn, self.param.name(), self.optimiser, self.repeat)
    }
}

/// One SOM cell: a model trained once on a data set at a grid size.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SomCell {
    pub dataset: String,
    pub model: crate::som::Model,
    pub grid: GridSize,
    pub repeat: usize,
}

impl crate::experiment::runner::Cell for SomCell {
    fn key(&self) -> String {
        SomCell::key(self)
    }
}

impl SomCell {
    /// Stable key from which the cell's random stream is derived.
    pub fn key(&self) -> String {
        format!("som/{}/{}/{}/r{}", self.dataset, self.model.key(), self.grid, self.repeat)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPEC: &str = r#"
name = "t"
master_seed = 1
[som]
datasets = ["cube"]
iterations = 100
[[som.group]]
models = ["som2d", "dnsom"]
grids = ["10x10", "18x30"]
[profiles.quick.som]
iterations = 7
"#;

    #[test]
    fn parses_expands_and_applies_profile() {
        let s = Spec::parse("t.toml", SPEC, None).unwrap();
        assert_eq!(s.som_cells().len(), 4);
        assert_eq!(s.file.som.as_ref().unwrap().iterations, 100);
        let q = Spec::parse("t.toml", SPEC, Some("quick")).unwrap();
        assert_eq!(q.file.som.as_ref().unwrap().iterations, 7);
        assert_eq!(q.som_cells()[3].key(), "som/cube/dnsom/18x30/r0");
    }

    /// A reading set's keys go through the same parsing and validation as the file's own values;
    /// a key of a section the spec does not have is skipped.
    #[test]
    fn overrides_apply_after_the_profile_and_are_validated() {
        let text = "name = \"f\"\nmaster_seed = 1\n[fit]\ndatasets = [\"cube\"]\ngrid = \"20x20\"\ncontrol_nets = [\"6x6\"]\nparameterisations = [\"uniform\"]\napproaches = [\"A\"]\n[profiles.quick.fit]\nfairness = 0.5\n";
        let ov = |k: &str, v: toml::Value| Override { key: k.into(), value: v };
        let plain = Spec::parse("f.toml", text, Some("quick")).unwrap();
        let fit = plain.file.fit.as_ref().unwrap();
        assert_eq!((fit.knots, fit.error_a, fit.fairness), (crate::spline::KnotRule::Eq2_10, crate::spline::ErrorA::PerSurface, 0.5));
        let set = [ov("fit.knots", "nurbs_book".into()), ov("fit.error_a", "nov_bottom".into()), ov("optim.knots", "nurbs_book".into())];
        let s = Spec::parse_with("f.toml", text, Some("quick"), &set).unwrap();
        let fit = s.file.fit.as_ref().unwrap();
        assert_eq!((fit.knots, fit.error_a, fit.fairness), (crate::spline::KnotRule::NurbsBook, crate::spline::ErrorA::NovBottom, 0.5));
        assert!(s.file.optim.is_none(), "a key of an absent section is skipped");
        let e = Spec::parse_with("f.toml", text, None, &[ov("fit.knots", "9.69".into())]).unwrap_err().to_string();
        assert!(e.contains("fit.knots") && e.contains("9.69"), "{e}");
        let e = Spec::parse_with("f.toml", text, None, &[ov("fit.fairness", toml::Value::Float(-1.0))]).unwrap_err().to_string();
        assert!(e.contains("fit.fairness"), "{e}");
        let e = Spec::parse_with("f.toml", text, None, &[ov("fit.colour", "red".into())]).unwrap_err().to_string();
        assert!(e.contains("colour"), "{e}");
    }

    #[test]
    fn exactly_one_experiment_section() {
        let none = "name = \"t\"\nmaster_seed = 1\n";
        let e = Spec::parse("t.toml", none, None).unwrap_err().0;
        assert!(e.contains("no experiment section") && e.contains("[som]") && e.contains("[seed002]"), "{e}");
        let two = format!("{SPEC}\n[seed002]\nsurfaces = [\"surface1\"]\n");
        let e = Spec::parse("t.toml", &two, None).unwrap_err().0;
        assert!(e.contains("[som] and [seed002]"), "{e}");
    }

    #[test]
    fn unknown_key_names_line_and_key() {
        let bad = SPEC.replace("iterations = 100", "iteratons = 100");
        let e = Spec::parse("t.toml", &bad, None).unwrap_err().0;
        assert!(e.starts_with("t.toml:6:1:") && e.contains("iteratons"), "{e}");
        assert!(!e.contains('\n'));
    }

    #[test]
    fn bad_values_name_their_key() {
        for (from, to, key) in [
            ("\"som2d\", \"dnsom\"", "\"som2d\", \"kohonen\"", "som.group[0].models"),
            ("iterations = 100", "iterations = 0", "som.iterations"),
            ("\"10x10\", \"18x30\"", "\"2x2\"", "som.group[0].grids"),
            ("datasets = [\"cube\"]", "datasets = []", "som.datasets"),
        ] {
            let e = Spec::parse("t.toml", &SPEC.replace(from, to), None).unwrap_err().0;
            assert!(e.contains(key), "{e}");
        }
        let e = Spec::parse("t.toml", "name = \"x\"\nmaster_seed = -1\n", None).unwrap_err().0;
        assert!(e.starts_with("t.toml:2:"), "{e}");
        let e = Spec::parse("t.toml", SPEC, Some("full")).unwrap_err().0;
        assert!(e.contains("no profile `full`") && e.contains("quick"), "{e}");
    }

    #[test]
    fn grid_sizes() {
        assert_eq!("20x12".parse::<GridSize>().unwrap(), GridSize { nx: 20, ny: 12 });
        assert_eq!("7".parse::<GridSize>().unwrap(), GridSize { nx: 7, ny: 7 });
        assert!("20y12".parse::<GridSize>().is_err());
    }
}
