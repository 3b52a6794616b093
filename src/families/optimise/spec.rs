//! The `[optimise]` section (thesis Chapter 6): data sets x control nets x parameterisations x
//! optimisers x repeats, its defaults (Table 6.1), its checks and its cells.

use crate::experiment::limits::{self, Check};
use crate::experiment::spec::{GridSize, Spec, SpecError};
use crate::families::maps::{validate_grid_keys, validate_map_som, MapSom, MapsMissing};
use serde::Deserialize;

/// Chapter 6 section: data sets x control nets x parameterisations x optimisers x repeats, every
/// optimiser started from approach B's control net of its cell.
///
/// No `deny_unknown_fields`: the flattened `tables` refuses every key it is handed that is not an
/// optimiser's table, with a message naming both kinds of key.
#[derive(Debug, Clone, Deserialize)]
pub struct OptimSpec {
    pub datasets: Vec<String>,
    pub grid: GridSize,
    pub control_nets: Vec<GridSize>,
    pub parameterisations: Vec<crate::spline::Parameterisation>,
    /// Any registered optimiser (`optim::REGISTRY`: ga, de, pso, csa, icsa, binary_ga).
    pub(crate) optimisers: Vec<crate::optim::Name>,
    #[serde(default = "crate::experiment::defaults::ten")]
    pub repeats: usize,
    #[serde(default = "crate::experiment::defaults::generations")]
    pub generations: usize,
    #[serde(default = "crate::experiment::defaults::population")]
    pub population: usize,
    /// Half-width of the initial range around B (Table 6.1: 5e-6).
    #[serde(default = "crate::experiment::defaults::init_range")]
    pub init_range: f64,
    /// The search box: the data and B's control points, widened by this share of its size.
    #[serde(default)]
    pub bounds_margin: f64,
    /// If set, the search box is instead B's control points +- this per coordinate (Table 6.1's
    /// "control point coordinate range", 5e-6).
    #[serde(default)]
    pub search_range: Option<f64>,
    /// As `[fit] maps`: Chapter 4's maps folder, relative to the spec's folder.
    #[serde(default)]
    pub maps: Option<String>,
    /// As `[fit] maps_missing`.
    #[serde(default)]
    pub maps_missing: MapsMissing,
    #[serde(default)]
    pub som: Option<MapSom>,
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
    #[serde(default = "crate::experiment::defaults::trace_every")]
    pub trace_every_evals: u64,
    /// Every registered optimiser's parameter table (`[optimise.de]`, ...; Table 6.1 by default).
    #[serde(flatten)]
    pub(crate) tables: crate::optim::Tables,
    /// Reading of the knot rule of approach B's start (docs/readings.md).
    #[serde(default)]
    pub knots: crate::spline::KnotRule,
    /// Beyond the thesis: penalised least squares weight of B's start (0 = plain least squares).
    #[serde(default)]
    pub fairness: f64,
    /// Reading of Eq. 2.8's power factor for the exponential method of B's start (Section 2.3.2:
    /// 0.8), in (0, 1] (docs/readings.md).
    #[serde(default = "crate::families::maps::default_exponential_alpha")]
    pub exponential_alpha: f64,
    /// Reading of the grid lines Eq. 5.1/5.2 average for B's start: `all` or `middle`.
    #[serde(default)]
    pub param_rows: crate::spline::ParamRows,
}

impl OptimSpec {
    /// The readings and options of approach B's fit that every cell starts from.
    pub fn fit_options(&self) -> crate::spline::FitOptions {
        crate::spline::FitOptions {
            knots: self.knots,
            fairness: self.fairness,
            param: crate::spline::ParamReading {
                exponential_alpha: self.exponential_alpha,
                rows: self.param_rows,
            },
            ..Default::default()
        }
    }

    /// The exact solver's settings (`exact_tol`, `exact_newton_steps`).
    pub fn exact_options(&self) -> crate::optim::ExactOptions {
        crate::optim::ExactOptions {
            tol_rel_gap: self.exact_tol,
            max_newton_steps: self.exact_newton_steps,
            ..crate::optim::ExactOptions::default()
        }
    }
}

fn default_exact_newton_steps() -> usize {
    300
}
fn default_exact_tol() -> f64 {
    1e-9
}

impl crate::experiment::family::Section for OptimSpec {
    /// The bounds of the `[optimise]` section's sizes and counts (docs/specs.md, "Spec limits").
    fn limits(&self, c: &Check) -> Result<(), SpecError> {
        crate::families::maps::limit_grid_keys(
            c,
            "optimise",
            &self.datasets,
            &self.grid,
            &self.control_nets,
            &self.parameterisations,
        )?;
        c.list("optimise.optimisers", &self.optimisers)?;
        c.optimiser_run("optimise", self.repeats, self.generations, self.population)?;
        c.real("optimise.fairness", self.fairness, 0.0, true, limits::MAX_FAIRNESS)?;
        crate::families::maps::check_exponential_alpha(c, "optimise", self.exponential_alpha)?;
        c.real("optimise.init_range", self.init_range, 0.0, true, limits::MAX_RANGE)?;
        c.real("optimise.bounds_margin", self.bounds_margin, 0.0, true, limits::MAX_RANGE)?;
        if let Some(r) = self.search_range {
            c.real("optimise.search_range", r, 0.0, false, limits::MAX_RANGE)?;
        }
        c.int("optimise.trace_every_evals", self.trace_every_evals, limits::MAX_TRACE_EVERY)?;
        c.int("optimise.exact_newton_steps", self.exact_newton_steps, limits::MAX_NEWTON_STEPS)?;
        if let Some(som) = &self.som {
            c.int("optimise.som.iterations", som.iterations, limits::MAX_ITERATIONS)?;
        }
        c.cells(
            "optimise",
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
    /// Every value of the `[optimise]` section (after the limits).
    fn validate(&self, spec: &Spec) -> Result<(), SpecError> {
        validate_grid_keys(spec, "optimise", &self.datasets, self.grid, &self.control_nets, &self.parameterisations)?;
        validate_map_som(spec, "optimise", self.som.as_ref())?;
        spec.validate_runs(
            "optimise",
            &self.optimisers,
            &self.tables,
            self.repeats,
            self.generations as u64,
            self.population,
        )?;
        if let Some(r) = self.search_range {
            if self.init_range > r {
                return Err(spec.err(
                    "optimise.init_range",
                    format!("{} is wider than optimise.search_range {r}", self.init_range),
                ));
            }
        }
        if self.trace_every_evals == 0 {
            return Err(spec.err("optimise.trace_every_evals", "must be at least 1"));
        }
        if !(self.exact_tol > 0.0 && self.exact_tol < 1.0) {
            return Err(spec.err("optimise.exact_tol", format!("must be in (0,1), got {}", self.exact_tol)));
        }
        Ok(())
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
        let from = crate::families::maps::MapsFrom {
            section: "optimise",
            dir: self.maps.as_deref(),
            missing: self.maps_missing,
            som: self.som.as_ref(),
        };
        crate::families::maps::require_maps_and_data(spec, ctx, &self.datasets, self.grid, &from)
    }
    /// Optimiser settings only, so that every variant solves the same problems (same data,
    /// nets, search box) and the variants can be ranked like optimisers.
    const OVERRIDES: Option<crate::experiment::family::Overrides> =
        Some(crate::experiment::family::Overrides { sweepable: super::sweepable_keys });
}

/// The flat list of optimisation cells (data x net x parameterisation x optimiser x repeat).
pub(crate) fn cells(spec: &Spec, o: &OptimSpec) -> Vec<OptimCell> {
    let mut cells = Vec::new();
    for dataset in &o.datasets {
        for cn in &o.control_nets {
            for &param in &o.parameterisations {
                for opt in &o.optimisers {
                    for repeat in 0..o.repeats {
                        cells.push(OptimCell {
                            dataset: crate::data::registry::name_of(dataset),
                            grid: o.grid,
                            cn: *cn,
                            param,
                            optimiser: *opt,
                            repeat,
                            variant: spec.variant.label_reaching(|k| reaches(k, *opt)),
                        });
                    }
                }
            }
        }
    }
    cells
}

/// Whether the swept key `key` reaches the cells of optimiser `opt`: its own table, or the budget
/// and start every optimiser shares (`repeats` only says how many cells there are).
fn reaches(key: &str, opt: crate::optim::Name) -> bool {
    let own = format!("optimise.{opt}.");
    key.starts_with(&own)
        || ["optimise.generations", "optimise.population", "optimise.init_range"].contains(&key)
}

/// One Chapter 6 cell: one optimiser run from approach B's control net.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct OptimCell {
    pub(crate) dataset: String,
    pub(crate) grid: GridSize,
    pub(crate) cn: GridSize,
    pub(crate) param: crate::spline::Parameterisation,
    pub(crate) optimiser: crate::optim::Name,
    pub(crate) repeat: usize,
    /// The swept settings of a `--sweep` that reach this cell (`optimise.de.f=0.5`; empty for a
    /// plain run and for a cell every variant shares): what its row's `variant` names.
    pub(crate) variant: String,
}

impl OptimCell {
    /// The cell's place, `optim/<data>/<grid>/<net>/<param>/<optimiser>/r<repeat>`: it names
    /// the cell's random stream, so every variant of one place (a sweep's, a reading set's)
    /// draws the same numbers; the log knows the cell by its identity (`Job`).
    pub(crate) fn key(&self) -> String {
        format!(
            "optim/{}/{}/{}/{}/{}/r{}",
            self.dataset,
            self.grid,
            self.cn,
            self.param.name(),
            self.optimiser,
            self.repeat
        )
    }
}


#[cfg(test)]
mod tests {
    /// `[optimise]` offers every registered optimiser, and docs/specs.md lists the shipped ones
    /// and no name that is not registered.
    #[test]
    fn offered_optimisers_are_the_registry_and_the_docs_list() {
        let text = "name = \"t\"\nmaster_seed = 1\n[optimise]\ndatasets = [\"sphere\"]\ngrid = \"20x20\"\ncontrol_nets = [\"6x6\"]\nparameterisations = [\"uniform\"]\noptimisers = [\"de\"]\n";
        let spec = crate::families::Loaded::parse("t.toml", text, None).unwrap();
        let o: &super::OptimSpec = spec.section_as().unwrap();
        let offered: Vec<&str> = o.tables.all().iter().map(|t| t.name()).collect();
        let registered: Vec<&str> =
            crate::optim::registry::REGISTRY.iter().map(|r| (r.make)().name()).collect();
        assert_eq!(offered, registered);
        let docs = std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/specs.md"),
        )
        .unwrap();
        let row = docs.lines().find(|l| l.starts_with("| `optimisers` |")).unwrap();
        let listed: Vec<&str> =
            row.split('|').nth(2).unwrap().split(',').map(|s| s.trim().trim_matches('`')).collect();
        let shipped = ["ga", "de", "pso", "csa", "icsa", "binary_ga"];
        assert!(shipped.iter().all(|n| listed.contains(n)), "docs/specs.md: {listed:?}");
        assert!(listed.iter().all(|n| offered.contains(n)), "docs/specs.md: {listed:?}");
    }
}
