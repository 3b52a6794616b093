//! Chapter 4 wiring: load the data sets, train every SOM cell on its own stream, log each finished
//! cell at once, and hand the runs to the report.

pub(crate) mod pictures;
pub(crate) mod report;
pub(crate) mod spec;

use crate::data::generators::{SpindleProfile, SpindleRings};
use crate::data::PointCloud;
use crate::experiment::spec::Spec;
use crate::experiment::packed::PackedPoints;
use crate::experiment::{runner, seeds, RunContext};
use crate::geom::Point3;
use crate::som::{self, FinalMetrics, NeuronCounts, OnlineMetrics, SomParams};
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::Arc;
pub use report::PUBLISHED;
pub use spec::{cells, SomCell, SomSpec};

/// One trained SOM cell.
#[derive(Debug, Clone)]
pub struct SomRun {
    pub cell: SomCell,
    pub row: SomRow,
    /// Trained weights of the units a picture draws (`Topology::drawn_units`: every unit, but
    /// only the outer shell of the 3-D lattice), in that order; rounded to single precision for
    /// every model but DNSOM (they serve the pictures only).
    pub weights: Vec<Point3>,
}

impl runner::Logged for SomRun {
    /// The weights in the compact form: exact bits, in single precision where the run rounded
    /// them so (every model but DNSOM, whose maps feed Chapters 5 and 6).
    type Record = (SomRow, PackedPoints);
    fn record(&self) -> Self::Record {
        // `run_cell` rounded them already: written as f32, they stay exact.
        let points = PackedPoints { points: self.weights.clone(), single: single(self.cell.model) };
        (self.row.clone(), points)
    }
}

/// Whether a model's weights are kept in single precision: they serve the pictures only (every
/// model but DNSOM, whose maps feed Chapters 5 and 6).
fn single(model: som::Model) -> bool {
    model != som::Model::Dnsom
}

/// One row of `runs.csv` (tidy: one row per cell x repeat).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SomRow {
    pub cell: String,
    pub dataset: String,
    pub model: String,
    pub nx: usize,
    pub ny: usize,
    pub repeat: usize,
    pub seed: String,
    pub iterations: usize,
    pub non: usize,
    pub nov: usize,
    pub nor: usize,
    pub min_error: f64,
    pub max_error: f64,
    pub qe: f64,
    pub te: f64,
    pub qe_final: f64,
    pub te_final: f64,
    pub cpu_s: f64,
}

impl SomRow {
    fn new(
        cell: &SomCell,
        seed: String,
        iterations: usize,
        c: NeuronCounts,
        o: OnlineMetrics,
        f: FinalMetrics,
        cpu_s: f64,
    ) -> SomRow {
        SomRow {
            cell: cell.key(),
            dataset: cell.dataset.clone(),
            model: cell.model.key().into(),
            nx: cell.grid.nx,
            ny: cell.grid.ny,
            repeat: cell.repeat,
            seed,
            iterations,
            non: c.non,
            nov: c.nov,
            nor: c.nor,
            min_error: o.min_error,
            max_error: o.max_error,
            qe: o.qe,
            te: o.te,
            qe_final: f.qe,
            te_final: f.te,
            cpu_s,
        }
    }
}

/// Load every data set a spec names, once, by its name (`crate::data::registry::dataset_name`).
pub fn load_datasets(
    spec: &Spec,
    names: &[String],
    ctx: &RunContext,
    spindle: (SpindleProfile, SpindleRings),
) -> Result<BTreeMap<String, Arc<PointCloud>>> {
    let loader = crate::data::registry::Loader { spindle, ..ctx.loader(spec) };
    let mut out = BTreeMap::new();
    for name in names {
        if !out.contains_key(&crate::data::registry::name_of(name)) {
            let cloud = loader.load(name)?;
            out.insert(cloud.name.clone(), Arc::new(cloud));
        }
    }
    Ok(out)
}

/// Refuse training a DNSOM `cell` on a data set (`entry`) of fewer points than its map has
/// neurons: its map nodes become the grid the B-spline surfaces are fitted to (Chapters 5, 6).
/// Other models may have more neurons than points (the thesis' 20x20x20 SOM3D on the 7352-point
/// cube), so they are not checked.
pub(crate) fn require_points(entry: &str, points: usize, cell: &SomCell) -> Result<()> {
    if cell.model != crate::som::Model::Dnsom {
        return Ok(());
    }
    let neurons =
        cell.model.topology(cell.grid.nx, cell.grid.ny).map_err(anyhow::Error::msg)?.counts().non;
    Ok(crate::data::require_points(
        entry,
        points,
        neurons,
        &format!("{} {}", cell.model.key(), cell.grid),
    )?)
}

/// The data sets of a `[som]` section, loaded, each checked against the maps trained on it
/// ([`require_points`]): what a run loads before its first cell, and what `--dry-run` checks
/// (through [`crate::experiment::family::Section::require_inputs`]).
pub(crate) fn load_checked(
    spec: &Spec,
    som_spec: &spec::SomSpec,
    ctx: &RunContext,
) -> Result<BTreeMap<String, Arc<PointCloud>>> {
    let spindle = (som_spec.spindle_profile, som_spec.spindle_rings);
    let data = load_datasets(spec, &som_spec.datasets, ctx, spindle)?;
    let cells = spec::cells(som_spec);
    for entry in &som_spec.datasets {
        let name = crate::data::registry::name_of(entry);
        for c in cells.iter().filter(|c| c.dataset == name) {
            require_points(entry, data[&name].points.len(), c)?;
        }
    }
    Ok(data)
}

/// Train one cell (pure apart from the CPU clock).
pub fn run_cell(
    cell: &SomCell,
    data: &[Point3],
    params: &SomParams,
    master_seed: u64,
) -> Result<SomRun> {
    let key = cell.key();
    let topo = cell
        .model
        .topology_with(cell.grid.nx, cell.grid.ny, params.som3d_adjacency)
        .map_err(anyhow::Error::msg)?;
    let (trained, cpu_s) =
        runner::on_stream(master_seed, &key, |rng| som::train(topo.as_ref(), data, params, rng));
    let trained = trained.map_err(anyhow::Error::msg).with_context(|| key.clone())?;
    let fin = som::final_map_metrics(topo.as_ref(), &trained.weights, data);
    let row = SomRow::new(
        cell,
        seeds::seed_hex(master_seed, &key),
        params.iterations,
        topo.counts(),
        trained.online,
        fin,
        cpu_s,
    );
    // Only the units a picture draws are kept (the 3-D lattice's shell; every other model's all),
    // and only for pictures, in single precision, but DNSOM's, whose maps feed Chapters 5 and 6:
    // a run resumed from its log draws the same pictures.
    let drawn: Vec<Point3> = topo.drawn_units().into_iter().map(|u| trained.weights[u]).collect();
    let weights = if single(cell.model) { PackedPoints::single(&drawn).points } else { drawn };
    Ok(SomRun { cell: cell.clone(), row, weights })
}

/// Each data set's frame (how its points were normalised), by name.
pub(crate) type Frames = BTreeMap<String, crate::data::frame::Frame>;

/// Run every SOM cell of a spec, logging each finished cell to the folder's cell log; also each
/// data set's frame, for the saved maps.
pub(crate) fn run(
    spec: &Spec,
    som_spec: &spec::SomSpec,
    ctx: &RunContext,
) -> Result<(Vec<SomRun>, Frames)> {
    let data = load_checked(spec, som_spec, ctx)?;
    let params = SomParams {
        iterations: som_spec.iterations,
        alpha0: som_spec.alpha0,
        sigma0: som_spec.sigma0,
        som3d_adjacency: som_spec.som3d_adjacency,
    };
    let cells = spec::cells(som_spec);
    let runs = runner::run_logged(
        &cells,
        ctx,
        &spec.file.name,
        |cell| run_cell(cell, &data[&cell.dataset].points, &params, spec.file.master_seed),
        |cell, (row, weights): (SomRow, PackedPoints)| {
            let units = cell
                .model
                .topology(cell.grid.nx, cell.grid.ny)
                .map_err(anyhow::Error::msg)?
                .drawn_units()
                .len();
            if weights.points.len() != units {
                anyhow::bail!(
                    "cell {}: the log holds {} weights for a map of {units} units",
                    cell.key(),
                    weights.points.len()
                );
            }
            Ok(SomRun { cell: cell.clone(), row, weights: weights.points })
        },
    )?;
    Ok((runs, data.iter().map(|(name, cloud)| (name.clone(), cloud.frame.clone())).collect()))
}

/// Chapter 4's family: the `[som]` section.
pub(crate) struct Som;

impl crate::experiment::family::Experiment for Som {
    fn title(&self) -> &'static str {
        "Chapter 4"
    }
    fn published(&self) -> crate::report::reference::Published {
        self::report::PUBLISHED
    }
    /// Chapter 4's metrics, exactly as computed (libraries disagree on them).
    fn definitions(&self) -> crate::experiment::Definitions {
        crate::experiment::Definitions(&[
            ("qe", "mean over training iterations of |X(t) - W_c(t)| (Euclidean, before the update) (thesis Eq. 4.15)"),
            ("te", "share of training iterations whose first and second winners are not adjacent (Eq. 4.16)"),
            ("te_adjacency", "index distance 1: 4-neighbourhood on 2-D maps, 6-neighbourhood in the 3-D lattice (another with som.som3d_adjacency) and CKSOM surface, 4-neighbourhood on either DNSOM view over class numbers"),
            ("qe_final", "mean Euclidean distance of every data point to its best-matching unit after training"),
            ("te_final", "share of data points whose two best units are not adjacent (adjacency as above)"),
            ("cpu_s", "thread CPU seconds of weight initialisation and the T training iterations"),
        ])
    }
    type Section = self::spec::SomSpec;
    fn logged_keys(&self, _spec: &Spec, s: &spec::SomSpec) -> Vec<String> {
        spec::cells(s).iter().map(|c| c.key()).collect()
    }
    fn run(
        &self,
        spec: &Spec,
        s: &spec::SomSpec,
        ctx: &RunContext,
        tables: bool,
    ) -> Result<crate::experiment::family::Outcome> {
        let (runs, frames) = run(spec, s, ctx)?;
        let section = if tables {
            Some(self::report::write(spec, s, &runs, &frames, &ctx.out, ctx.extras)?)
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
