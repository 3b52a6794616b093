//! Chapter 5 wiring: read (or recompute) the DNSOM maps, fit every cell, log each at once.

pub mod command;
pub mod pictures;
pub mod readings;
pub mod report;
pub mod spec;

use crate::double_net::{DoubleNet, View};
use crate::experiment::spec::{GridSize, Spec, SpecError};
use crate::experiment::{runner, RunContext};
use crate::families::som;
use crate::families::som::spec::SomCell;
use crate::io::write_atomic;
use crate::som::{Model, SomParams};
use crate::spline::{fit_two_view, FitOptions, TwoSurfaceFit, TwoViewGrid};
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use spec::{FitCell, FitSom, MapsMissing};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One row of a Chapter 5 `runs.csv`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct FitRow {
    pub cell: String,
    pub dataset: String,
    pub grid_x: usize,
    pub grid_y: usize,
    pub cn_x: usize,
    pub cn_y: usize,
    pub parameterisation: String,
    pub approach: String,
    /// Eq. 5.13 over the NOV grid classes.
    pub surface_error: f64,
    /// Largest distance between the two fitted surfaces along the shared border.
    pub gap: f64,
    /// The readings the fit used (docs/readings.md).
    pub knots: String,
    pub error_a: String,
    /// Between the data points (dense evaluation): largest distance of a surface point from the
    /// data's bounding box, largest absolute control-point coordinate, largest border gap.
    pub excursion: f64,
    pub max_control: f64,
    pub dense_gap: f64,
    pub cpu_s: f64,
}

/// One fitted cell.
#[derive(Debug, Clone)]
pub struct FitRun {
    pub cell: FitCell,
    pub row: FitRow,
    pub fit: TwoSurfaceFit,
}

impl runner::Logged for FitRun {
    type Record = FitRow;
    fn record(&self) -> FitRow {
        self.row.clone()
    }
}

/// Where a map came from.
#[derive(Debug, Clone)]
pub struct MapSource {
    pub grid: TwoViewGrid,
    pub origin: String,
    /// The data set's frame (the map file's sidecar, or the recomputation's cloud); None: a map
    /// saved without one.
    pub frame: Option<crate::data::frame::Frame>,
}

/// The map file name Chapter 4 writes and Chapter 5 reads.
pub fn map_file_name(dataset: &str, grid: GridSize) -> String {
    format!("dnsom_{dataset}_{grid}.csv")
}

/// A trained DNSOM's weights as a two-view grid (border positions share their class's weight).
pub fn grid_from_weights(nx: usize, ny: usize, weights: &[crate::geom::Point3]) -> TwoViewGrid {
    let net = DoubleNet::new(nx, ny).expect("grid sides at least 2");
    let view = |v: View| {
        (0..nx)
            .flat_map(|i| (0..ny).map(move |j| (i, j)))
            .map(|(i, j)| weights[net.class(v, i, j)])
            .collect()
    };
    TwoViewGrid { nx, ny, bottom: view(View::Bottom), top: view(View::Top) }
}

/// Read each data set's map from the maps folder, or recompute it exactly as Chapter 4 does (same
/// cell key, seed and settings); every map used is copied into `<out>/maps/`.
pub fn maps(spec: &Spec, ctx: &RunContext) -> Result<BTreeMap<String, MapSource>> {
    let fit = spec.require::<spec::FitSpec>()?;
    let from = MapsFrom {
        section: "fit",
        dir: fit.maps.as_deref(),
        missing: fit.maps_missing,
        som: fit.som.as_ref(),
    };
    maps_for(spec, ctx, &fit.datasets, fit.grid, &from)
}

/// Where a section's maps come from: its `maps` key as written (relative to the spec's folder),
/// what a named folder or map that is not there means, and how a map is recomputed.
#[derive(Debug, Clone, Copy)]
pub struct MapsFrom<'a> {
    /// `fit` or `optim`, for messages.
    pub section: &'static str,
    pub dir: Option<&'a str>,
    pub missing: MapsMissing,
    pub som: Option<&'a FitSom>,
}

/// Each data set's entry, name and map file in the folder `from.dir` names (resolved against the
/// spec's folder; None: no folder named).
fn map_files<'a>(
    spec: &Spec,
    datasets: &'a [String],
    grid: GridSize,
    from: &MapsFrom,
) -> Vec<(&'a String, String, Option<PathBuf>)> {
    let dir: Option<PathBuf> = from.dir.map(|m| spec.resolve(m));
    let mut wanted: Vec<(&String, String, Option<PathBuf>)> = Vec::new();
    for entry in datasets {
        let data = crate::data::registry::name_of(entry);
        if wanted.iter().all(|(_, d, _)| *d != data) {
            let file = dir.as_ref().map(|d| d.join(map_file_name(&data, grid)));
            wanted.push((entry, data, file));
        }
    }
    wanted
}

/// Whether the maps a section names are there: an error naming the missing folder or map, unless
/// `maps_missing = "recompute"`, then the line that says what is recomputed (None: nothing is
/// missing, or no folder is named and every map is recomputed as the spec says).
pub fn require_maps(
    spec: &Spec,
    datasets: &[String],
    grid: GridSize,
    from: &MapsFrom,
) -> Result<Option<String>> {
    let Some(dir) = from.dir.map(|m| spec.resolve(m)) else { return Ok(None) };
    let wanted = map_files(spec, datasets, grid, from);
    let absent: Vec<&Path> =
        wanted.iter().filter_map(|(_, _, f)| f.as_deref()).filter(|f| !f.exists()).collect();
    let Some(first) = absent.first() else { return Ok(None) };
    let section = from.section;
    let what = if dir.is_dir() {
        format!("no map {}", crate::io::shown(first))
    } else {
        format!("no maps folder {}", crate::io::shown(&dir))
    };
    if from.missing == MapsMissing::Error {
        anyhow::bail!("{}: {section}.maps: {what} (run the spec that saves the maps first, e.g. Chapter 4's, or set {section}.maps_missing = \"recompute\")", spec.path);
    }
    let names: Vec<String> = absent
        .iter()
        .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    Ok(Some(format!(
        "somnurbs: {}: {what}: recomputing {} from [{section}.som] ({section}.maps_missing = \"recompute\")",
        spec.path,
        names.join(", ")
    )))
}

/// The maps of `datasets` at `grid`: read from the folder `from.dir` names (resolved against the
/// spec's folder), recomputed with `from.som` when the spec names no folder. A named folder or map
/// that is not there is an error naming it, unless `maps_missing = "recompute"`, in which case
/// one stderr line says what is recomputed ([`require_maps`]).
pub fn maps_for(
    spec: &Spec,
    ctx: &RunContext,
    datasets: &[String],
    grid: GridSize,
    from: &MapsFrom,
) -> Result<BTreeMap<String, MapSource>> {
    if let Some(line) = require_maps(spec, datasets, grid, from)? {
        eprintln!("{line}");
    }
    let wanted = map_files(spec, datasets, grid, from);
    let mut out = BTreeMap::new();
    for (entry, data, file) in wanted {
        let source = match file.filter(|f| f.exists()) {
            Some(path) => read_map(&path, grid)?,
            None => recompute_map(spec, ctx, entry, grid, from.som)?,
        };
        out.insert(data, source);
    }
    // Every map has loaded: only now may the folder change.
    ctx.begin()?;
    for (data, source) in &out {
        let text = crate::families::som::report::two_view_grid_csv(&source.grid)?;
        let file = ctx.out.join("maps").join(map_file_name(data, grid));
        write_atomic(&file, text.as_bytes())?;
        if let Some(frame) = &source.frame {
            crate::families::som::report::write_frame(&file, frame)?;
        }
    }
    Ok(out)
}

fn read_map(path: &Path, grid: GridSize) -> Result<MapSource> {
    let text = crate::io::read_text(path)?;
    let g = crate::data::grid_csv::parse_two_view_grid(&text)
        .with_context(|| path.display().to_string())?;
    if (g.nx, g.ny) != (grid.nx, grid.ny) {
        anyhow::bail!("{}: map is {}x{}, the spec's grid is {grid}", path.display(), g.nx, g.ny);
    }
    Ok(MapSource { grid: g, origin: crate::io::shown(path), frame: read_frame(path)? })
}

/// The frame saved beside a map (`X.frame.toml` beside `X.csv`), None when there is none; a frame
/// file that is there but cannot be read is an error naming it.
pub fn read_frame(map: &Path) -> Result<Option<crate::data::frame::Frame>> {
    let file = crate::data::frame::sidecar(map);
    if !file.exists() {
        return Ok(None);
    }
    let text = crate::io::read_text(&file)?;
    let frame =
        crate::data::frame::Frame::parse(&text).map_err(|e| e.in_file(&crate::io::shown(&file)))?;
    Ok(Some(frame))
}

fn recompute_map(
    spec: &Spec,
    ctx: &RunContext,
    data: &str,
    grid: GridSize,
    som: Option<&FitSom>,
) -> Result<MapSource> {
    let (seed, params) = match som {
        Some(s) => (
            s.master_seed.unwrap_or(spec.file.master_seed),
            SomParams { iterations: s.iterations, alpha0: s.alpha0, ..SomParams::default() },
        ),
        None => (spec.file.master_seed, SomParams::default()),
    };
    let clouds = som::load_datasets(spec, &[data.to_string()], ctx)?;
    let name = crate::data::registry::name_of(data);
    let cell = SomCell { dataset: name.clone(), model: Model::Dnsom, grid, repeat: 0 };
    som::require_points(data, clouds[&name].points.len(), &cell)?;
    let run = som::run_cell(&cell, &clouds[&name].points, &params, seed)?;
    Ok(MapSource {
        frame: Some(clouds[&name].frame.clone()),
        grid: grid_from_weights(grid.nx, grid.ny, &run.weights),
        origin: format!(
            "recomputed: {} with master seed {seed}, T = {}",
            cell.key(),
            params.iterations
        ),
    })
}

/// Fit one cell.
pub fn run_cell(cell: &FitCell, grid: &TwoViewGrid, opts: &FitOptions) -> Result<FitRun> {
    let t0 = runner::thread_cpu_seconds();
    let fit = fit_two_view(grid, cell.cn.nx, cell.cn.ny, cell.param, cell.approach, opts)
        .with_context(|| cell.key())?;
    let cpu_s = runner::thread_cpu_seconds() - t0;
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
pub fn run(
    spec: &Spec,
    ctx: &RunContext,
    maps: &BTreeMap<String, MapSource>,
) -> Result<Vec<FitRun>> {
    let cells = spec::cells(spec);
    let opts = spec.require::<spec::FitSpec>()?.fit_options();
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
pub struct Fit;

impl crate::experiment::family::Section for self::spec::FitSpec {
    fn limits(&self, c: &crate::experiment::limits::Check) -> Result<(), SpecError> {
        self::spec::limits(c, self)
    }
    fn validate(&self, spec: &Spec) -> Result<(), SpecError> {
        self::spec::validate(spec, self)
    }
    fn datasets(&self) -> &[String] {
        &self.datasets
    }
    fn use_maps(&mut self, maps: &str) {
        self.maps = Some(maps.to_string());
    }
    fn require_inputs(&self, spec: &Spec) -> Result<()> {
        let from = MapsFrom {
            section: "fit",
            dir: self.maps.as_deref(),
            missing: self.maps_missing,
            som: self.som.as_ref(),
        };
        require_maps(spec, &self.datasets, self.grid, &from).map(drop)
    }
}

impl crate::experiment::family::Experiment for Fit {
    type Section = self::spec::FitSpec;
    fn combine(
        &self,
        view: &crate::experiment::family::PlanView,
    ) -> Result<crate::experiment::family::Combined> {
        readings::combine(view)
    }
    fn logged_keys(&self, spec: &Spec) -> Vec<String> {
        spec::cells(spec).iter().map(|c| c.key()).collect()
    }
    fn run(
        &self,
        spec: &Spec,
        ctx: &RunContext,
        tables: bool,
    ) -> Result<crate::experiment::family::Outcome> {
        let maps = maps(spec, ctx)?;
        let runs = run(spec, ctx, &maps)?;
        let origins: Vec<(String, String)> =
            maps.iter().map(|(d, m)| (d.clone(), m.origin.clone())).collect();
        let pictures =
            ctx.extras && spec.section::<spec::FitSpec>().map(|f| f.pictures).unwrap_or(false);
        let section = if tables {
            Some(self::report::write(&spec.file.name, &runs, &ctx.out, &origins, pictures)?)
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
