//! Chapter 5 across the readings, for a plan's combined report: the surface error against the
//! fitted surfaces' excursion between the data points, one series per reading.

use crate::experiment::family::{Combined, PlanView};
use anyhow::Result;
use serde::Deserialize;

/// One fitted cell as the chart needs it (from a Chapter 5 `runs.csv`).
#[derive(Debug, Deserialize)]
struct FitPoint {
    dataset: String,
    grid_x: usize,
    grid_y: usize,
    cn_x: usize,
    cn_y: usize,
    parameterisation: String,
    approach: String,
    surface_error: f64,
    excursion: f64,
}

/// The readings matrix's chart: the first fit spec every reading ran, its first data set, chord
/// length, approach B; nothing when no reading ran a fit spec.
pub(crate) fn combine(view: &PlanView<super::spec::FitSpec>) -> Result<Combined> {
    let mut readings = Vec::new();
    if let Some(chart) = error_vs_excursion(view)? {
        readings.push(format!("\n![{chart}]({chart})\n\nSurface error against the largest distance of the fitted surfaces from the data's bounding box (log scale), one point per control net, for one data set under each reading: a reading can lower the error at the data points while its surfaces leave the data between them.\n"));
    }
    Ok(Combined { readings, ..Combined::default() })
}

/// Draws the chart into the plan's folder; returns its file name.
fn error_vs_excursion(view: &PlanView<super::spec::FitSpec>) -> Result<Option<String>> {
    if view.readings.is_empty() {
        return Ok(None);
    }
    let Some(spec) = view.specs.iter().map(|(s, _)| s.file.name.as_str()).find(|s| {
        view.readings.iter().all(|r| r.specs.iter().any(|x| x == s))
            && view.out.join(s).join("runs.csv").exists()
    }) else {
        return Ok(None);
    };
    let mut folders = vec![(view.reading.to_string(), view.out.join(spec))];
    folders.extend(view.readings.iter().map(|r| (r.name.clone(), r.root.join(spec))));
    let mut series = Vec::new();
    let mut data_set = None;
    let mut nets: Vec<String> = Vec::new();
    let mut grid = None;
    for (k, (name, folder)) in folders.iter().enumerate() {
        let points: Vec<FitPoint> = crate::io::read_rows(&folder.join("runs.csv"))?;
        grid = grid.or(points.first().map(|p| (p.grid_x, p.grid_y)));
        let d = data_set
            .get_or_insert_with(|| points.first().map(|p| p.dataset.clone()).unwrap_or_default())
            .clone();
        let mut pts: Vec<(usize, f64, f64)> = points
            .iter()
            .filter(|p| {
                p.dataset == d
                    && p.parameterisation == "chord_length"
                    && p.approach == "B"
                    && p.excursion > 0.0
            })
            .map(|p| (p.cn_x, p.excursion.log10(), p.surface_error))
            .collect();
        pts.sort_by_key(|p| p.0);
        for p in points.iter().filter(|p| p.dataset == d && p.approach == "B") {
            let n = format!("{}x{}", p.cn_x, p.cn_y);
            if !nets.contains(&n) {
                nets.push(n);
            }
        }
        series.push(crate::report::plots::Series {
            label: name.clone(),
            colour: crate::report::plots::style::cycle_colour(k),
            points: pts.iter().map(|p| (p.1, p.2)).collect(),
            band: None,
        });
    }
    // The claim's threshold ("near the data": the data set's `near_bound`, from the map the
    // plan's folder saved), upright across the errors drawn.
    let errors = series.iter().flat_map(|s| s.points.iter().map(|p| p.1));
    let (lo, hi) = errors.fold((f64::INFINITY, f64::NEG_INFINITY), |a, y| (a.0.min(y), a.1.max(y)));
    if lo.is_finite() {
        let near = near_bound(&folders[0].1, data_set.as_deref().unwrap_or_default(), grid)?;
        series.push(crate::report::plots::Series {
            label: format!("near the data: excursion {}", crate::families::maps::near_text(near)),
            colour: crate::report::plots::style::GREY,
            points: vec![(near.log10(), lo), (near.log10(), hi)],
            band: None,
        });
    }
    let name = format!("readings_error_vs_excursion_{spec}.png");
    let title = format!(
        "{spec}, {}, chord length, B: control nets {} (one point each)",
        data_set.unwrap_or_default(),
        nets.join(", ")
    );
    match crate::report::plots::line_chart_png(
        &view.out.join(&name),
        &title,
        "log10 excursion from the data's box",
        "surface error (Eq. 5.13)",
        &series,
        false,
    ) {
        Ok(()) => Ok(Some(name)),
        Err(e) => {
            crate::report::picture_skipped(&e);
            Ok(None)
        }
    }
}

/// What counts as near the data for `dataset`'s map in `folder` (`maps/`; NEAR when the folder
/// kept none).
fn near_bound(folder: &std::path::Path, dataset: &str, grid: Option<(usize, usize)>) -> Result<f64> {
    let Some((nx, ny)) = grid else { return Ok(crate::spline::geometry::NEAR) };
    let grid = crate::experiment::spec::GridSize { nx, ny };
    let file = folder.join("maps").join(crate::families::maps::map_file_name(dataset, grid));
    if !file.exists() {
        return Ok(crate::spline::geometry::NEAR);
    }
    Ok(crate::families::maps::near_bound(&crate::families::maps::read_map(&file, grid)?))
}
