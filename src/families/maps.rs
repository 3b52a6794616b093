//! The DNSOM maps Chapter 4 saves and Chapters 5 and 6 fit (`[fit]` and `[optimise]` read them
//! alike): where a section's maps come from (`maps`, `maps_missing`, `[<section>.som]`), reading
//! them, recomputing a missing one exactly as Chapter 4's cell would (same key, seed and
//! settings), and the keys both sections share. It sits beside the registry, not in a family,
//! because two families use it; it reaches Chapter 4's family only to train a map.

use super::som::{self, spec::SomCell};
use crate::double_net::TwoViewGrid;
use crate::experiment::spec::{GridSize, Spec, SpecError};
use crate::experiment::RunContext;
use crate::io::write_atomic;
use crate::som::{Model, SomParams};
use anyhow::{Context, Result};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One control-net problem: the data set, the control net and the parameterisation (the grid is
/// the spec's). Chapter 6's problems, exact optima and table cells, and seed 001's problems, are
/// keyed by it; the order of its fields is the order of `runs.csv`'s cells.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ProblemKey {
    pub data: String,
    pub cn: GridSize,
    pub param: crate::spline::Parameterisation,
}

impl ProblemKey {
    pub(crate) fn new(data: &str, cn: GridSize, param: crate::spline::Parameterisation) -> Self {
        ProblemKey { data: data.to_string(), cn, param }
    }
}

impl std::fmt::Display for ProblemKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} {} {}", self.data, self.cn, self.param.name())
    }
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
pub struct MapSom {
    #[serde(default)]
    pub master_seed: Option<u64>,
    #[serde(default = "crate::experiment::defaults::som_iterations")]
    pub iterations: usize,
    #[serde(default = "crate::experiment::defaults::som_alpha0")]
    pub alpha0: f64,
}

/// Section 2.3.2's alpha = 0.8 of the exponential method.
pub(crate) fn default_exponential_alpha() -> f64 {
    crate::spline::param::EXPONENTIAL_ALPHA
}

/// `<section>.exponential_alpha` in (0, 1] (Eq. 2.8; 1 is chord length).
pub(crate) fn check_exponential_alpha(
    c: &crate::experiment::limits::Check,
    section: &str,
    v: f64,
) -> Result<(), SpecError> {
    let (lo, hi) = crate::spline::param::EXPONENTIAL_ALPHA_RANGE;
    c.real(&format!("{section}.exponential_alpha"), v, lo, false, hi)
}

/// The bounds of the keys a `[fit]`, an `[optimise]` and a `[growing_grid]` section share (data
/// sets, grid, control nets, parameterisations), each error naming `<section>.<key>`.
pub(crate) fn limit_grid_keys(
    c: &crate::experiment::limits::Check,
    section: &str,
    datasets: &[String],
    grid: &GridSize,
    control_nets: &[GridSize],
    parameterisations: &[crate::spline::Parameterisation],
) -> Result<(), SpecError> {
    let key = |k: &str| format!("{section}.{k}");
    c.datasets(&key("datasets"), datasets)?;
    c.grids(&key("grid"), [grid])?;
    c.list(&key("control_nets"), control_nets)?;
    c.grids(&key("control_nets"), control_nets)?;
    c.list(&key("parameterisations"), parameterisations)
}

/// The keys a `[fit]`, an `[optimise]` and a `[growing_grid]` section share (data sets, grid,
/// control nets, parameterisations), each error naming `<section>.<key>`.
pub(crate) fn validate_grid_keys(
    spec: &Spec,
    section: &str,
    datasets: &[String],
    grid: GridSize,
    control_nets: &[GridSize],
    parameterisations: &[crate::spline::Parameterisation],
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
    Ok(())
}

/// The settings of the map recomputation (`<section>.som`).
pub(crate) fn validate_map_som(
    spec: &Spec,
    section: &str,
    som: Option<&MapSom>,
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

/// Where a map came from.
#[derive(Debug, Clone)]
pub(crate) struct MapSource {
    pub(crate) grid: TwoViewGrid,
    pub(crate) origin: String,
    /// The data set's frame (the map file's sidecar, or the recomputation's cloud); None: a map
    /// saved without one.
    pub(crate) frame: Option<crate::data::frame::Frame>,
}

/// What counts as "near the data" for surfaces fitted to `source`'s map, in the map's units:
/// [`NEAR`](crate::spline::geometry::NEAR) of the longest side of the data's bounding box.
/// Normalised data (`per_axis`, `uniform`) have a longest side of 1 in the map's coordinates, by
/// construction, so the bound is NEAR itself; for data used as they are (`normalise = "none"`)
/// it is NEAR of the longest side of the data's box the frame keeps, and for a frame without it
/// or a map without a frame, of the map's own box (which lies inside the data's).
pub(crate) fn near_bound(source: &MapSource) -> f64 {
    let near = crate::spline::geometry::NEAR;
    if source.frame.as_ref().is_some_and(|f| f.normalise != crate::data::Normalise::None) {
        return near;
    }
    if let Some(side) = source.frame.as_ref().and_then(|f| f.longest_side_in_map()) {
        return near * side;
    }
    let grid = &source.grid;
    let (lo, hi) = crate::spline::geometry::bounding_box(grid.bottom.iter().chain(&grid.top));
    near * (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max)
}

/// [`near_bound`] of every data set's map.
pub(crate) fn near_bounds(maps: &BTreeMap<String, MapSource>) -> BTreeMap<String, f64> {
    maps.iter().map(|(d, m)| (d.clone(), near_bound(m))).collect()
}

/// The bound of `dataset` (NEAR when it has none: a map not loaded).
pub(crate) fn near_of(bounds: &BTreeMap<String, f64>, dataset: &str) -> f64 {
    bounds.get(dataset).copied().unwrap_or(crate::spline::geometry::NEAR)
}

/// A bound as the reports write it: 4 decimals, trailing zeros dropped (0.1, 19.8765).
pub(crate) fn near_text(v: f64) -> String {
    let v = format!("{v:.4}");
    v.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// A claim's words for the bounds of `datasets`, in their maps' units: "at most NEAR of the
/// longest side of the data's bounding box: 0.1 for cube, sphere; 19.9 for radar".
pub(crate) fn near_note(bounds: &BTreeMap<String, f64>, datasets: &[String]) -> String {
    let mut groups: Vec<(String, Vec<&str>)> = Vec::new();
    for d in datasets {
        let v = near_text(near_of(bounds, d));
        match groups.iter_mut().find(|(w, _)| *w == v) {
            Some((_, ds)) => ds.push(d),
            None => groups.push((v, vec![d])),
        }
    }
    let each: Vec<String> =
        groups.iter().map(|(v, ds)| format!("{v} for {}", ds.join(", "))).collect();
    format!(
        "at most {} of the longest side of the data's bounding box, in the data's units as the map has them (normalised data: the unit box, side 1): {}",
        crate::spline::geometry::NEAR,
        each.join("; ")
    )
}

/// The map file name Chapter 4 writes and Chapter 5 reads.
pub(crate) fn map_file_name(dataset: &str, grid: GridSize) -> String {
    format!("dnsom_{dataset}_{grid}.csv")
}

/// The map file `name` in `dir`: the CSV Chapter 4 writes, else the gzip-compressed copy a folder
/// that read it keeps (`<name>.gz`), else the CSV's path (which is not there).
fn map_in(dir: &Path, name: &str) -> PathBuf {
    let plain = dir.join(name);
    let copy = dir.join(format!("{name}.gz"));
    if !plain.exists() && copy.exists() {
        copy
    } else {
        plain
    }
}

/// Where a section's maps come from: its `maps` key as written (relative to the spec's folder),
/// what a named folder or map that is not there means, and how a map is recomputed.
#[derive(Debug, Clone, Copy)]
pub(crate) struct MapsFrom<'a> {
    /// `fit` or `optim`, for messages.
    pub(crate) section: &'static str,
    pub(crate) dir: Option<&'a str>,
    pub(crate) missing: MapsMissing,
    pub(crate) som: Option<&'a MapSom>,
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
            let file = dir.as_ref().map(|d| map_in(d, &map_file_name(&data, grid)));
            wanted.push((entry, data, file));
        }
    }
    wanted
}

/// Whether the maps a section names are there: an error naming the missing folder or map, unless
/// `maps_missing = "recompute"`, then the line that says what is recomputed (None: nothing is
/// missing, or no folder is named and every map is recomputed as the spec says).
pub(crate) fn require_maps(
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
pub(crate) fn maps_for(
    spec: &Spec,
    ctx: &RunContext,
    datasets: &[String],
    grid: GridSize,
    from: &MapsFrom,
) -> Result<BTreeMap<String, MapSource>> {
    if let Some(line) = require_maps(spec, datasets, grid, from)? {
        crate::notice::emit(&line);
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
    // Every map has loaded: only now may the folder change. The folder keeps each map it read,
    // gzip-compressed (its own copy, read back exactly, in under half the bytes).
    ctx.begin()?;
    for (data, source) in out.iter().filter(|_| ctx.keep_maps) {
        let text = crate::io::map_file::text(&source.grid)?;
        let file = ctx.out.join("maps").join(format!("{}.gz", map_file_name(data, grid)));
        write_atomic(&file, &crate::io::map_file::gzip(text.as_bytes())?)?;
        if let Some(frame) = &source.frame {
            crate::io::map_file::write_frame(&file, frame)?;
        }
    }
    Ok(out)
}

pub(crate) fn read_map(path: &Path, grid: GridSize) -> Result<MapSource> {
    let text = crate::io::map_file::read(path)?;
    let g = crate::data::grid_csv::parse_two_view_grid(&text)
        .with_context(|| path.display().to_string())?;
    if (g.nx, g.ny) != (grid.nx, grid.ny) {
        anyhow::bail!("{}: map is {}x{}, the spec's grid is {grid}", path.display(), g.nx, g.ny);
    }
    Ok(MapSource {
        grid: g,
        origin: crate::io::shown(path),
        frame: crate::io::map_file::read_frame(path)?,
    })
}

/// The cloud a recomputed map of `data` at `grid` trains on, checked to have enough points for
/// it, and the map's cell.
fn recompute_input(
    spec: &Spec,
    ctx: &RunContext,
    data: &str,
    grid: GridSize,
) -> Result<(std::sync::Arc<crate::data::PointCloud>, SomCell)> {
    let mut clouds = som::load_datasets(spec, &[data.to_string()], ctx, Default::default())?;
    let name = crate::data::registry::name_of(data);
    let cloud = clouds.remove(&name).context("internal: a loaded data set is not listed")?;
    let cell = SomCell { dataset: name, model: Model::Dnsom, grid, repeat: 0 };
    som::require_points(data, cloud.points.len(), &cell)?;
    Ok((cloud, cell))
}

/// What a run checks of a section's maps before its first cell ([`require_maps`]), and for each
/// map to recompute, that its data set has enough points for it: the section's
/// `require_inputs`, so `--dry-run` checks it too.
pub(crate) fn require_maps_and_data(
    spec: &Spec,
    ctx: &RunContext,
    datasets: &[String],
    grid: GridSize,
    from: &MapsFrom,
) -> Result<()> {
    require_maps(spec, datasets, grid, from)?;
    for (entry, _, file) in map_files(spec, datasets, grid, from) {
        if file.filter(|f| f.exists()).is_none() {
            recompute_input(spec, ctx, entry, grid)?;
        }
    }
    Ok(())
}

fn recompute_map(
    spec: &Spec,
    ctx: &RunContext,
    data: &str,
    grid: GridSize,
    som: Option<&MapSom>,
) -> Result<MapSource> {
    let (seed, params) = match som {
        Some(s) => (
            s.master_seed.unwrap_or(spec.file.master_seed),
            SomParams { iterations: s.iterations, alpha0: s.alpha0, ..SomParams::default() },
        ),
        None => (spec.file.master_seed, SomParams::default()),
    };
    let (cloud, cell) = recompute_input(spec, ctx, data, grid)?;
    let run = som::run_cell(&cell, &cloud.points, &params, seed)?;
    Ok(MapSource {
        frame: Some(cloud.frame.clone()),
        grid: TwoViewGrid::from_weights(grid.nx, grid.ny, &run.weights)
            .with_context(|| format!("{}: not a DNSOM map", cell.key()))?,
        origin: format!(
            "recomputed: {} with master seed {seed}, T = {}",
            cell.key(),
            params.iterations
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::{frame::Frame, Normalise};

    /// A 2x2 map spanning 200 x 50 x 10 units, with the frame of `normalise` (None: no frame).
    fn source(normalise: Option<Normalise>) -> MapSource {
        let bottom =
            vec![[0.0, 0.0, 0.0], [200.0, 0.0, 0.0], [0.0, 50.0, 0.0], [200.0, 50.0, 10.0]];
        let grid = TwoViewGrid { nx: 2, ny: 2, top: bottom.clone(), bottom };
        let frame = normalise.map(|n| Frame::of(n, &grid.bottom, "scan", "scan.xyz"));
        MapSource { grid, origin: "scan".into(), frame }
    }

    #[test]
    fn near_is_a_tenth_of_the_data_s_longest_side_in_the_map_s_units() {
        // Normalised data: the unit box, so exactly NEAR (the thesis' verdicts unchanged).
        for n in [Normalise::PerAxis, Normalise::Uniform] {
            assert_eq!(near_bound(&source(Some(n))), crate::spline::geometry::NEAR);
        }
        // Data used as they are: a tenth of the data's 200 units; a map without a frame (or a
        // frame that does not keep the data's box): of the map's own box.
        assert_eq!(near_bound(&source(Some(Normalise::None))), 20.0);
        let mut wider = source(Some(Normalise::None));
        wider.frame.as_mut().unwrap().data_box = Some([[-50.0, 0.0, 0.0], [250.0, 50.0, 10.0]]);
        assert_eq!(near_bound(&wider), 30.0, "the data's box, not the map's");
        wider.frame.as_mut().unwrap().data_box = None;
        assert_eq!(near_bound(&wider), 20.0);
        assert_eq!(near_bound(&source(None)), 20.0);
        let bounds: BTreeMap<String, f64> =
            [("cube".to_string(), 0.1), ("radar".to_string(), 19.87654)].into_iter().collect();
        let names = ["cube", "radar", "sphere"].map(String::from);
        let note = near_note(&bounds, &names);
        assert!(note.ends_with(": 0.1 for cube, sphere; 19.8765 for radar"), "{note}");
        assert_eq!(near_of(&bounds, "sphere"), crate::spline::geometry::NEAR);
    }
}
