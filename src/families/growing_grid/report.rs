//! Seed 001 report: map quality per data set (maps.csv), least-squares fit error per net and
//! parameterisation (fit_error.csv), the average-error table per optimiser (avg_error.csv and
//! optimiser_summary.csv), and per data set a picture of the map beside the fitted surfaces.
//!
//! The seed's tables did not survive (only its front matter), so there are no published numbers
//! to print beside ours; the verdicts compare each optimiser with its least-squares start.

use super::{MapRun, ProblemKey, Run};
use crate::io::{csv_records, ensure_dir, write_atomic};
use crate::optim::Problem;
use crate::report::markdown::{num, table};
use crate::report::plots::{self, grid_edges, style, LineMesh, Panel};
use crate::spline::open_surface::OpenSurfaceProblem;
use anyhow::Result;
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::Path;

use crate::stats::describe::mean_std;

fn write_csv(out: &Path, name: &str, header: &[&str], rows: &[Vec<String>]) -> Result<()> {
    let h: Vec<String> = header.iter().map(|s| s.to_string()).collect();
    write_atomic(&out.join(name), csv_records(&h, rows)?.as_bytes())
}

/// Write the tables and pictures; return the REPORT.md section.
pub(crate) fn write(
    maps: &[MapRun],
    problems: &BTreeMap<ProblemKey, OpenSurfaceProblem>,
    runs: &[Run],
    out: &Path,
) -> Result<String> {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "## Seed 001: Growing Grid on open surfaces, one cubic B-spline surface, GA/DE/PSO\n"
    );
    let _ = writeln!(md, "The seed's own tables did not survive (only its front matter), so no published figures are printed beside ours.\n");

    let rows: Vec<_> = runs.iter().map(|r| r.row.clone()).collect();
    write_atomic(&out.join("runs.csv"), crate::io::csv_text(&rows)?.as_bytes())?;

    map_quality(maps, out, &mut md)?;
    least_squares(problems, out, &mut md)?;
    optimisers(runs, out, &mut md)?;
    pictures(maps, problems, runs, out, &mut md)?;
    Ok(md)
}

/// Map quality per data set (maps.csv and its REPORT.md table).
fn map_quality(maps: &[MapRun], out: &Path, md: &mut String) -> Result<()> {
    let map_rows: Vec<Vec<String>> = maps
        .iter()
        .map(|m| {
            vec![
                m.dataset.clone(),
                m.points.to_string(),
                m.map.nx.to_string(),
                m.map.ny.to_string(),
                m.map.insertions.to_string(),
                m.map.growth_steps.to_string(),
                m.map.fine_steps.to_string(),
                format!("{:?}", m.qe),
                format!("{:?}", m.te),
                format!("{:?}", m.cpu_s),
            ]
        })
        .collect();
    let map_header = [
        "dataset",
        "points",
        "grid_x",
        "grid_y",
        "insertions",
        "growth_steps",
        "fine_steps",
        "qe",
        "te",
        "cpu_s",
    ];
    write_csv(out, "maps.csv", &map_header, &map_rows)?;
    let _ = writeln!(md, "### Map quality (maps.csv)\n\nQE: mean distance of a data point to its winner; TE: share of data points whose two best units are not 4-neighbours (data normalised per axis to [0,1]).\n");
    let shown: Vec<Vec<String>> = maps
        .iter()
        .map(|m| {
            vec![
                m.dataset.clone(),
                format!("{}x{}", m.map.nx, m.map.ny),
                m.map.insertions.to_string(),
                num(Some(m.qe), 5),
                num(Some(m.te), 4),
                num(Some(m.cpu_s), 3),
            ]
        })
        .collect();
    md.push_str(&table(
        &[
            "data".into(),
            "final size".into(),
            "insertions".into(),
            "QE".into(),
            "TE".into(),
            "CPU s".into(),
        ],
        &shown,
    ));
    md.push('\n');

    Ok(())
}

/// The least-squares fit per net and parameterisation (fit_error.csv).
fn least_squares(
    problems: &BTreeMap<ProblemKey, OpenSurfaceProblem>,
    out: &Path,
    md: &mut String,
) -> Result<()> {
    let mut fit_rows = Vec::new();
    for (ProblemKey { data: d, cn, param: p }, pr) in problems {
        let e = pr.fitness(pr.initial_point());
        fit_rows.push(vec![
            d.clone(),
            cn.to_string(),
            p.name().to_string(),
            format!("{:?}", e),
            format!("{:?}", e / (pr.nx * pr.ny) as f64),
        ]);
    }
    write_csv(
        out,
        "fit_error.csv",
        &["dataset", "control_net", "parameterisation", "lsq_error", "lsq_error_per_point"],
        &fit_rows,
    )?;
    let _ = writeln!(md, "### Least-squares fit (fit_error.csv)\n\nSurface error = sum over the grid points of |S(u_i,v_j) - D_ij| (Eq. 5.13, one view).\n");
    let shown: Vec<Vec<String>> = fit_rows
        .iter()
        .map(|r| vec![r[0].clone(), r[1].clone(), r[2].clone(), num(r[3].parse().ok(), 6)])
        .collect();
    md.push_str(&table(
        &["data".into(), "net".into(), "parameterisation".into(), "error".into()],
        &shown,
    ));
    md.push('\n');

    Ok(())
}

/// Per optimiser: the improvements on the least-squares start (%, one per cell), the runs below
/// it, the runs.
type PerOpt = BTreeMap<String, (Vec<f64>, usize, usize)>;

/// One `avg_error.csv` row per (data, net, parameterisation, optimiser), and the per-optimiser
/// improvements.
fn avg_error(runs: &[Run]) -> (Vec<Vec<String>>, PerOpt) {
    let mut groups: BTreeMap<(String, String, String, String), Vec<&Run>> = BTreeMap::new();
    for r in runs {
        groups
            .entry((
                r.row.dataset.clone(),
                format!("{}x{}", r.row.cn_x, r.row.cn_y),
                r.row.parameterisation.clone(),
                r.row.optimiser.clone(),
            ))
            .or_default()
            .push(r);
    }
    let mut avg_rows = Vec::new();
    let mut per_opt: PerOpt = BTreeMap::new();
    for ((d, cn, p, o), rs) in &groups {
        let best: Vec<f64> = rs.iter().map(|r| r.row.best).collect();
        let (m, s) = mean_std(&best);
        let lsq = rs[0].row.lsq;
        let min = best.iter().cloned().fold(f64::INFINITY, f64::min);
        let max = best.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let imp = 100.0 * (lsq - m) / lsq;
        let e = per_opt.entry(o.clone()).or_default();
        e.0.push(imp);
        e.1 += best.iter().filter(|&&b| b < lsq).count();
        e.2 += best.len();
        avg_rows.push(vec![
            d.clone(),
            cn.clone(),
            p.clone(),
            o.clone(),
            rs.len().to_string(),
            format!("{:?}", lsq),
            format!("{:?}", m),
            format!("{:?}", s),
            format!("{:?}", min),
            format!("{:?}", max),
            format!("{:?}", imp),
        ]);
    }
    (avg_rows, per_opt)
}

/// The mean-error table shown in REPORT.md (one row per cell, least squares beside each
/// optimiser's mean), the number of cells and each optimiser's cells with the lowest mean.
fn mean_table(
    avg_rows: &[Vec<String>],
    opts: &[String],
) -> (String, usize, BTreeMap<String, usize>) {
    let mut cells: BTreeMap<(String, String, String), BTreeMap<String, f64>> = BTreeMap::new();
    for r in avg_rows {
        cells
            .entry((r[0].clone(), r[1].clone(), r[2].clone()))
            .or_default()
            .insert(r[3].clone(), r[6].parse().unwrap_or(f64::NAN));
    }
    let mut wins: BTreeMap<String, usize> = BTreeMap::new();
    let mut header =
        vec!["data".to_string(), "net".into(), "parameterisation".into(), "least squares".into()];
    header.extend(opts.iter().map(|o| format!("{} mean", o.to_uppercase())));
    let mut shown = Vec::new();
    for ((d, cn, p), by) in &cells {
        if let Some((o, _)) = by.iter().min_by(|a, b| a.1.total_cmp(b.1)) {
            *wins.entry(o.clone()).or_default() += 1;
        }
        let lsq = avg_rows
            .iter()
            .find(|r| &r[0] == d && &r[1] == cn && &r[2] == p)
            .and_then(|r| r[5].parse().ok());
        let mut row = vec![d.clone(), cn.clone(), p.clone(), num(lsq, 6)];
        row.extend(opts.iter().map(|o| num(by.get(o).copied(), 6)));
        shown.push(row);
    }
    (table(&header, &shown), cells.len(), wins)
}

/// The optimisers over all cells in REPORT.md, and each one's verdict against its start.
fn render_summary(summary: &[Vec<String>], md: &mut String) {
    let _ = writeln!(md, "### Optimisers over all cells (optimiser_summary.csv)\n");
    let shown: Vec<Vec<String>> = summary
        .iter()
        .map(|r| {
            vec![
                r[0].to_uppercase(),
                format!("{} of {}", r[2], r[1]),
                num(r[3].parse().ok(), 3),
                format!("{} of {}", r[4], r[5]),
            ]
        })
        .collect();
    md.push_str(&table(
        &[
            "optimiser".into(),
            "lowest mean error".into(),
            "mean improvement on LSQ (%)".into(),
            "runs below LSQ".into(),
        ],
        &shown,
    ));
    let _ = writeln!(md);
    for r in summary {
        let (improved, n): (usize, usize) = (r[4].parse().unwrap_or(0), r[5].parse().unwrap_or(0));
        let verdict = if improved == n {
            "improves on the least-squares start in every run"
        } else if improved > 0 {
            "improves on the least-squares start in some runs"
        } else {
            "never improves on the least-squares start"
        };
        let _ = writeln!(md, "- {}: {verdict} ({improved} of {n}).", r[0].to_uppercase());
    }
    md.push('\n');
}

/// The average error per optimiser and cell (avg_error.csv), the optimisers over all cells
/// (optimiser_summary.csv) and each optimiser's verdict against its least-squares start.
fn optimisers(runs: &[Run], out: &Path, md: &mut String) -> Result<()> {
    let (avg_rows, per_opt) = avg_error(runs);
    write_csv(
        out,
        "avg_error.csv",
        &[
            "dataset",
            "control_net",
            "parameterisation",
            "optimiser",
            "runs",
            "lsq",
            "mean_best",
            "std_best",
            "min_best",
            "max_best",
            "improvement_pct",
        ],
        &avg_rows,
    )?;
    let opts: Vec<String> = per_opt.keys().cloned().collect();
    let (means, n_cells, wins) = mean_table(&avg_rows, &opts);
    let _ = writeln!(md, "### Average error per optimiser (avg_error.csv)\n\nMean over the repeats of the best surface error each optimiser found, starting from the least-squares net.\n");
    md.push_str(&means);
    md.push('\n');
    let summary: Vec<Vec<String>> = opts
        .iter()
        .map(|o| {
            let (imp, improved, n) = &per_opt[o];
            let (mi, _) = mean_std(imp);
            vec![
                o.clone(),
                n_cells.to_string(),
                wins.get(o).copied().unwrap_or(0).to_string(),
                format!("{:?}", mi),
                improved.to_string(),
                n.to_string(),
            ]
        })
        .collect();
    write_csv(
        out,
        "optimiser_summary.csv",
        &[
            "optimiser",
            "cells",
            "lowest_mean_cells",
            "mean_improvement_pct",
            "runs_below_lsq",
            "runs",
        ],
        &summary,
    )?;
    render_summary(&summary, md);
    Ok(())
}

/// Per data set the grown map and, per control net, the surface of the lowest-error run,
/// evaluated densely between the data parameters (a near-square net is free to swing out between
/// them, and the picture shows it).
fn pictures(
    maps: &[MapRun],
    problems: &BTreeMap<ProblemKey, OpenSurfaceProblem>,
    runs: &[Run],
    out: &Path,
    md: &mut String,
) -> Result<()> {
    ensure_dir(&out.join("png"))?;
    let _ = writeln!(md, "### Pictures\n\nPer data set: the grown map and, per control net, the surface of the lowest-error run evaluated densely between the data parameters.\n");
    for m in maps {
        let mut panels = vec![Panel {
            title: format!("growing grid {}x{}", m.map.nx, m.map.ny),
            meshes: vec![LineMesh {
                points: m.map.weights.clone(),
                edges: grid_edges(m.map.nx, m.map.ny),
                colour: style::BLUE,
                label: "map".into(),
            }],
        }];
        let mut nets: Vec<_> = problems.keys().filter(|k| k.data == m.dataset).map(|k| k.cn).collect();
        nets.dedup();
        for cn in nets {
            let best = runs
                .iter()
                .filter(|r| r.cell.dataset == m.dataset && r.cell.cn == cn)
                .min_by(|a, b| a.row.best.total_cmp(&b.row.best));
            if let Some(r) = best {
                let pr = &problems[&ProblemKey::new(&r.cell.dataset, r.cell.cn, r.cell.param)];
                // Dense: between the data parameters a near-square net is free to swing out
                // (only the grid points are fitted), and the picture must show it.
                let (pts, edges) = crate::spline::geometry::dense_wireframe(
                    &pr.surface(&r.best_x),
                    &pr.us,
                    &pr.vs,
                    crate::spline::DENSE_FACTOR,
                );
                panels.push(Panel {
                    title: format!(
                        "{cn} {} {} ({:.4})",
                        r.cell.param.name(),
                        r.cell.optimiser.as_str().to_uppercase(),
                        r.row.best
                    ),
                    meshes: vec![LineMesh {
                        points: pts,
                        edges,
                        colour: style::VERMILLION,
                        label: "surface, evaluated densely".into(),
                    }],
                });
            }
        }
        let name = format!("png/seed001_{}.png", m.dataset);
        let cols = panels.len().min(4);
        match plots::overview_png(
            &out.join(&name),
            &format!("{}: growing grid, best surface per net", m.dataset),
            &panels,
            cols,
        ) {
            Ok(()) => {
                let _ = writeln!(md, "![{}]({name})\n", m.dataset);
            }
            Err(e) => crate::report::picture_skipped(&e),
        }
    }
    Ok(())
}
