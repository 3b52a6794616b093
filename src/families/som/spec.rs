//! The `[som]` section (thesis Chapter 4): data sets x groups of (models x grids) x repeats, its
//! defaults, its checks and its cells.

use crate::experiment::limits::{self, Check};
use crate::experiment::spec::{GridSize, Spec, SpecError};
use serde::Deserialize;

fn default_repeats() -> usize {
    1
}

/// Chapter 4 section: data sets x groups of (models x grids) x repeats.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SomSpec {
    /// Data-set names (`somnurbs datasets list`) or paths to point files.
    pub datasets: Vec<String>,
    /// Maximum iteration T (Table 4.1).
    #[serde(default = "crate::experiment::defaults::som_iterations")]
    pub iterations: usize,
    /// Initial learning rate alpha0 (Table 4.1).
    #[serde(default = "crate::experiment::defaults::som_alpha0")]
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
    #[serde(default = "crate::experiment::defaults::yes")]
    pub pictures: bool,
    /// Which 3-D SOM units are adjacent for TE (Eq. 4.16): `n6` (index distance 1), `n18`, `n26`,
    /// `layer` (within one k layer), `shell` (along the lattice's outer faces).
    #[serde(default)]
    pub som3d_adjacency: crate::som::LatticeAdjacency,
    /// The spindle's radius at ring parameter t (Section 3.2.2 gives no curve): `sin2`, `sin`,
    /// `cone`.
    #[serde(default)]
    pub spindle_profile: crate::data::generators::SpindleProfile,
    /// Where the spindle's rings sit along its axis: `cos` (y = .5 + .5 cos(pi t)), `uniform`.
    #[serde(default)]
    pub spindle_rings: crate::data::generators::SpindleRings,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SomGroup {
    pub models: Vec<crate::som::Model>,
    pub grids: Vec<GridSize>,
}

impl crate::experiment::family::Section for SomSpec {
    /// The bounds of the `[som]` section's sizes and counts (docs/specs.md, "Spec limits").
    fn limits(&self, c: &Check) -> Result<(), SpecError> {
        c.datasets("som.datasets", &self.datasets)?;
        c.int("som.iterations", self.iterations, limits::MAX_ITERATIONS)?;
        if let Some(sigma0) = self.sigma0 {
            c.real("som.sigma0", sigma0, 1.0, false, limits::MAX_SIGMA0)?;
        }
        c.int("som.repeats", self.repeats, limits::MAX_REPEATS)?;
        c.list("som.group", &(0..self.groups.len()).collect::<Vec<_>>())?;
        let mut per_data = 0usize;
        for (g, group) in self.groups.iter().enumerate() {
            c.list(&format!("som.group[{g}].models"), &group.models)?;
            c.list(&format!("som.group[{g}].grids"), &group.grids)?;
            c.grids(&format!("som.group[{g}].grids"), &group.grids)?;
            per_data = per_data.saturating_add(group.models.len().saturating_mul(group.grids.len()));
        }
        c.list("som.save_maps", &self.save_maps)?;
        c.grids("som.save_maps", &self.save_maps)?;
        c.cells("som", &[self.datasets.len(), per_data, self.repeats])?;
        Ok(())
    }
    /// Every value of the `[som]` section (after the limits).
    fn validate(&self, spec: &Spec) -> Result<(), SpecError> {
        if self.datasets.is_empty() {
            return Err(spec.err("som.datasets", "is empty"));
        }
        if self.iterations == 0 {
            return Err(spec.err("som.iterations", "must be at least 1"));
        }
        if !(self.alpha0 > 0.0 && self.alpha0 <= 1.0) {
            return Err(spec.err("som.alpha0", format!("must be in (0, 1], got {}", self.alpha0)));
        }
        if let Some(s) = self.sigma0 {
            if s.is_nan() || s <= 1.0 {
                return Err(
                    spec.err("som.sigma0", format!("must exceed 1 (tau = T / ln sigma0), got {s}"))
                );
            }
        }
        if self.repeats == 0 {
            return Err(spec.err("som.repeats", "must be at least 1"));
        }
        if self.groups.is_empty() {
            return Err(spec.err("som.group", "no [[som.group]] given"));
        }
        for (g, group) in self.groups.iter().enumerate() {
            let key = format!("som.group[{g}]");
            if group.models.is_empty() {
                return Err(spec.err(&format!("{key}.models"), "is empty"));
            }
            if group.grids.is_empty() {
                return Err(spec.err(&format!("{key}.grids"), "is empty"));
            }
            for &model in &group.models {
                for grid in &group.grids {
                    if self.sigma0.is_none() && grid.nx.min(grid.ny) < 3 {
                        return Err(spec.err(
                            &format!("{key}.grids"),
                            format!("grid {grid} is too small: sigma0 = min(nx,ny)/2 must exceed 1"),
                        ));
                    }
                    model
                        .topology(grid.nx, grid.ny)
                        .map_err(|e| spec.err(&format!("{key}.grids"), e))?;
                }
            }
        }
        for grid in &self.save_maps {
            let has =
                cells(self).iter().any(|c| c.model == crate::som::Model::Dnsom && c.grid == *grid);
            if !has {
                return Err(spec.err("som.save_maps", format!("no DNSOM cell at grid {grid} to save")));
            }
        }
        Ok(())
    }
    fn datasets(&self) -> &[String] {
        &self.datasets
    }
    /// Each data set has enough points for the DNSOM maps trained on it.
    fn require_inputs(
        &self,
        spec: &Spec,
        ctx: &crate::experiment::RunContext,
    ) -> anyhow::Result<()> {
        super::load_checked(spec, self, ctx).map(drop)
    }
}

/// The flat list of SOM cells (data set x group x grid x model x repeat), in report order.
pub fn cells(som: &SomSpec) -> Vec<SomCell> {
    let mut cells = Vec::new();
    // Groups may share a (model, grid): each cell once, in first-seen order.
    let mut seen = std::collections::HashSet::new();
    for dataset in &som.datasets {
        for group in &som.groups {
            for grid in &group.grids {
                for &model in &group.models {
                    for repeat in 0..som.repeats {
                        let cell = SomCell {
                            dataset: crate::data::registry::name_of(dataset),
                            model,
                            grid: *grid,
                            repeat,
                        };
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
