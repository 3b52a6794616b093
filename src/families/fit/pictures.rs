//! Chapter 5 pictures: per data set a page laid out like Appendices G/H (rows: control nets;
//! columns: each parameterisation's A beside B; the fitted surfaces as two-colour wireframes
//! evaluated densely between the data parameters), and a chart of surface error against control-net size.

use super::FitRun;
use crate::experiment::spec::GridSize;
use crate::report::plots::{self, style, LineMesh, Panel, Series};
use crate::spline::Approach;
use anyhow::Result;
use std::path::Path;

/// The two fitted surfaces, drawn from their dense evaluation (iso-lines through the data
/// parameters, each sampled between the data points), so a surface that swings out shows.
fn surface_meshes(run: &FitRun) -> Vec<LineMesh> {
    let [(bottom, be), (top, te)] = run.fit.dense_wireframes();
    vec![
        LineMesh {
            points: bottom,
            edges: be,
            colour: style::DNSOM_BOTTOM,
            label: "bottom surface".into(),
        },
        LineMesh { points: top, edges: te, colour: style::DNSOM_TOP, label: "top surface".into() },
    ]
}

/// Write the pictures of one grid size; returns their paths relative to `out`.
pub(crate) fn write(runs: &[FitRun], grid: GridSize, out: &Path) -> Result<Vec<String>> {
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
                let run = runs.iter().find(|r| {
                    &r.cell.dataset == d
                        && r.cell.cn == cn
                        && r.cell.param == p
                        && r.cell.approach == a
                });
                panels.push(Panel {
                    title: format!("{cn} {} {}", p.name(), a.letter()),
                    meshes: run.map(surface_meshes).unwrap_or_default(),
                });
            }
        }
        let name = format!("png/{appendix}_{d}.png");
        crate::io::ensure_dir(&out.join("png"))?;
        let title = format!("{d}, grid {grid}: conventional (A) and improved (B) surfaces by control net and parameterisation");
        match plots::overview_png(&out.join(&name), &title, &panels, columns.len()) {
            Ok(()) => written.push(name),
            Err(e) => eprintln!("somnurbs: warning: picture skipped: {e}"),
        }
        // Surface error against control-net size: one small panel per parameterisation with its
        // A and B (eight curves on one chart lie on top of each other).
        let params = crate::report::ordered(columns.iter().map(|c| c.0));
        let panels: Vec<(String, Vec<Series>)> = params
            .iter()
            .map(|&p| {
                let series = columns
                    .iter()
                    .filter(|c| c.0 == p)
                    .map(|&(_, a)| Series {
                        label: format!(
                            "{} ({})",
                            a.letter(),
                            if a == Approach::Improved { "improved" } else { "conventional" }
                        ),
                        colour: if a == Approach::Improved { style::BLUE } else { style::ORANGE },
                        points: cns
                            .iter()
                            .filter_map(|&cn| {
                                runs.iter().find(|r| {
                                    &r.cell.dataset == d
                                        && r.cell.cn == cn
                                        && r.cell.param == p
                                        && r.cell.approach == a
                                })
                            })
                            .map(|r| ((r.cell.cn.nx * r.cell.cn.ny) as f64, r.row.surface_error))
                            .collect(),
                        band: None,
                    })
                    .collect();
                (p.name().to_string(), series)
            })
            .collect();
        let chart = format!("png/error_vs_cn_{grid}_{d}.png");
        match plots::small_multiples_png(
            &out.join(&chart),
            &format!("{d}, grid {grid}: surface error (Eq. 5.13) against control-net size"),
            "control points per view (CNx x CNy)",
            "surface error",
            &panels,
            2,
            true,
        ) {
            Ok(()) => written.push(chart),
            Err(e) => eprintln!("somnurbs: warning: picture skipped: {e}"),
        }
    }
    Ok(written)
}

/// The 3-D views of report.html (`views3d.js`): per data set its DNSOM map (both views, joined
/// along the grid rows and columns) and, per approach, the fitted surfaces evaluated densely of
/// the cell whose surfaces go furthest from the data (largest `excursion`), so a blow-up between
/// the data points shows.
pub(crate) fn views(
    runs: &[FitRun],
    maps: &[(String, &crate::double_net::TwoViewGrid)],
) -> Vec<crate::report::views3d::View> {
    use crate::report::views3d::{hex, Trace, View};
    let mut views = Vec::new();
    for (d, grid) in maps {
        let (nx, ny) = (grid.nx, grid.ny);
        let mut lines: Vec<Vec<usize>> =
            (0..nx).map(|i| (0..ny).map(|j| i * ny + j).collect()).collect();
        lines.extend((0..ny).map(|j| (0..nx).map(|i| i * ny + j).collect()));
        let traces = [
            ("bottom view", &grid.bottom, style::DNSOM_BOTTOM),
            ("top view", &grid.top, style::DNSOM_TOP),
        ]
        .map(|(label, pts, c)| Trace::Points {
            label: label.into(),
            colour: hex(c),
            points: pts.clone(),
            lines: lines.clone(),
        });
        views.push(View { title: format!("{d}: DNSOM map {nx}x{ny}"), traces: traces.to_vec() });
        for a in [Approach::Conventional, Approach::Improved] {
            let worst = runs
                .iter()
                .filter(|r| &r.cell.dataset == d && r.cell.approach == a)
                .max_by(|x, y| x.row.excursion.total_cmp(&y.row.excursion));
            let Some(r) = worst else { continue };
            let f = &r.fit;
            let traces = [
                ("bottom surface", &f.bottom, 0, style::DNSOM_BOTTOM),
                ("top surface", &f.top, 1, style::DNSOM_TOP),
            ]
            .map(|(label, s, k, c)| {
                let (points, du, dv) = crate::spline::geometry::dense_grid(
                    s,
                    &f.params_u[k],
                    &f.params_v[k],
                    crate::spline::DENSE_FACTOR,
                );
                Trace::Surface {
                    label: label.into(),
                    colour: hex(c),
                    rows: du.len(),
                    cols: dv.len(),
                    points,
                }
            });
            let title = format!(
                "{d}: {} surfaces furthest from the data (CN {}, {}, excursion {:.3e})",
                a.letter(),
                r.cell.cn,
                r.cell.param.name(),
                r.row.excursion
            );
            views.push(View { title, traces: traces.to_vec() });
        }
    }
    views
}
