//! Chapter 5 pictures: per data set a page laid out like Appendices G/H (rows: control nets;
//! columns: each parameterisation's A beside B; the fitted surfaces as two-colour wireframes
//! evaluated densely between the data parameters), and a chart of surface error against control-net size.

use crate::report::plots::{self, style, LineMesh, Panel, Series};
use crate::families::fit::FitRun;
use crate::experiment::spec::GridSize;
use crate::spline::Approach;
use anyhow::Result;
use std::path::Path;

/// The two fitted surfaces, drawn from their dense evaluation (iso-lines through the data
/// parameters, each sampled between the data points), so a surface that swings out shows.
fn surface_meshes(run: &FitRun) -> Vec<LineMesh> {
    let [(bottom, be), (top, te)] = run.fit.dense_wireframes();
    vec![
        LineMesh { points: bottom, edges: be, colour: style::DNSOM_BOTTOM, label: "bottom surface".into() },
        LineMesh { points: top, edges: te, colour: style::DNSOM_TOP, label: "top surface".into() },
    ]
}

/// Write the pictures of one grid size; returns their paths relative to `out`.
pub fn write(runs: &[FitRun], grid: GridSize, out: &Path) -> Result<Vec<String>> {
    let mut written = Vec::new();
    let appendix = match (grid.nx, grid.ny) {
        (20, 20) => "appendix_g".to_string(),
        (18, 30) => "appendix_h".to_string(),
        _ => format!("surfaces_{grid}"),
    };
    let mut data: Vec<String> = Vec::new();
    let mut cns: Vec<GridSize> = Vec::new();
    let mut columns: Vec<(crate::spline::Parameterisation, Approach)> = Vec::new();
    for r in runs {
        if !data.contains(&r.cell.dataset) {
            data.push(r.cell.dataset.clone());
        }
        if !cns.contains(&r.cell.cn) {
            cns.push(r.cell.cn);
        }
        if !columns.contains(&(r.cell.param, r.cell.approach)) {
            columns.push((r.cell.param, r.cell.approach));
        }
    }
    for d in &data {
        let mut panels = Vec::new();
        for &cn in &cns {
            for &(p, a) in &columns {
                let run = runs.iter().find(|r| &r.cell.dataset == d && r.cell.cn == cn && r.cell.param == p && r.cell.approach == a);
                panels.push(Panel { title: format!("{cn} {} {}", p.name(), a.letter()), meshes: run.map(surface_meshes).unwrap_or_default() });
            }
        }
        let name = format!("png/{appendix}_{d}.png");
        crate::io::ensure_dir(&out.join("png"))?;
        let title = format!("{d}, grid {grid}: conventional (A) and improved (B) surfaces by control net and parameterisation");
        match plots::overview_png(&out.join(&name), &title, &panels, columns.len()) {
            Ok(()) => written.push(name),
            Err(e) => eprintln!("somnurbs: warning: picture skipped: {e}"),
        }
        // Surface error against control-net size (number of control points per view).
        let series: Vec<Series> = columns
            .iter()
            .enumerate()
            .map(|(k, &(p, a))| Series {
                label: format!("{} {}", p.name(), a.letter()),
                colour: style::cycle_colour(k),
                points: cns
                    .iter()
                    .filter_map(|&cn| runs.iter().find(|r| &r.cell.dataset == d && r.cell.cn == cn && r.cell.param == p && r.cell.approach == a))
                    .map(|r| ((r.cell.cn.nx * r.cell.cn.ny) as f64, r.row.surface_error))
                    .collect(),
                band: None,
            })
            .collect();
        let chart = format!("png/error_vs_cn_{grid}_{d}.png");
        match plots::line_chart_png(&out.join(&chart), &format!("{d}, grid {grid}: surface error (Eq. 5.13) against control-net size"), "control points per view (CNx x CNy)", "surface error", &series, true) {
            Ok(()) => written.push(chart),
            Err(e) => eprintln!("somnurbs: warning: picture skipped: {e}"),
        }
    }
    Ok(written)
}
