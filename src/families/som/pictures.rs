//! Chapter 4 pictures: one wireframe per cell (`png/<data>_<model>_<grid>.png`, the DNSOM views in
//! two colours) and overview pages laid out like the thesis' Appendix A (rows data x n, columns the
//! four models) and Appendix D (rows data x grid, columns CKSOM and DNSOM).

use super::SomRun;
use crate::report::plots::{self, style, LineMesh, Panel};
use crate::som::Model;
use anyhow::Result;
use rayon::prelude::*;
use std::path::Path;

/// The wireframe meshes of a trained map.
pub(crate) fn meshes(run: &SomRun) -> Vec<LineMesh> {
    let topo = match run.cell.model.topology(run.cell.grid.nx, run.cell.grid.ny) {
        Ok(t) => t,
        Err(_) => return Vec::new(),
    };
    let groups = topo.edge_groups();
    let two = groups.len() > 1;
    groups
        .into_iter()
        .enumerate()
        .map(|(g, group)| LineMesh {
            points: run.weights.clone(),
            edges: group.edges,
            colour: match (two, g) {
                (true, 0) => style::DNSOM_BOTTOM,
                (true, _) => style::DNSOM_TOP,
                _ => style::BLUE,
            },
            label: if two { format!("{} view", group.label) } else { String::new() },
        })
        .collect()
}

/// The lattice a cell trains: n x n x n for the 3-D SOM, the grid otherwise.
fn lattice_label(model: Model, grid: crate::experiment::spec::GridSize) -> String {
    match model {
        Model::Som3d => format!("{0}x{0}x{0} lattice", grid.nx),
        _ => grid.to_string(),
    }
}

fn cell_picture_name(run: &SomRun) -> String {
    format!("png/{}_{}_{}.png", run.cell.dataset, run.cell.model.key(), run.cell.grid)
}

/// Write every Chapter 4 picture; returns the written paths relative to `out`. A picture that
/// fails is reported on stderr and the others are still written.
pub(crate) fn write(runs: &[SomRun], out: &Path) -> Result<Vec<String>> {
    crate::io::ensure_dir(&out.join("png"))?;
    let first: Vec<&SomRun> = runs.iter().filter(|r| r.cell.repeat == 0).collect();
    let mut written: Vec<String> = first
        .par_iter()
        .filter_map(|run| {
            let name = cell_picture_name(run);
            let title = format!(
                "{} {} {}",
                run.cell.dataset,
                run.cell.model.label(),
                lattice_label(run.cell.model, run.cell.grid)
            );
            match plots::mesh_png(&out.join(&name), &title, &meshes(run), style::MESH_SIZE) {
                Ok(()) => Some(name),
                Err(e) => {
                    eprintln!("somnurbs: warning: picture skipped: {e}");
                    None
                }
            }
        })
        .collect();
    for (square, name, title) in [
        (true, "appendix_a.png", "Appendix A: the SOM models on each data set (rows: data, n"),
        (false, "appendix_d.png", "Appendix D: the models at different width and length of grid (rows: data, grid"),
    ] {
        // Only the models that ran: no empty column.
        let shown: &[Model] = if square { &Model::ALL } else { &[Model::Cksom, Model::Dnsom] };
        let models: Vec<Model> = shown.iter().copied().filter(|&m| first.iter().any(|r| r.cell.model == m)).collect();
        let labels: Vec<&str> = models.iter().map(|m| m.label()).collect();
        let title = format!("{title}; columns: {})", labels.join(", "));
        let mut rows: Vec<(String, crate::experiment::spec::GridSize)> = Vec::new();
        for r in &first {
            let key = (r.cell.dataset.clone(), r.cell.grid);
            if (r.cell.grid.nx == r.cell.grid.ny) == square && !rows.contains(&key) {
                rows.push(key);
            }
        }
        if rows.is_empty() {
            continue;
        }
        let mut panels = Vec::new();
        for (data, grid) in &rows {
            for &m in &models {
                let run = first.iter().find(|r| &r.cell.dataset == data && r.cell.grid == *grid && r.cell.model == m);
                panels.push(Panel {
                    title: format!("{data} {} {}", m.label(), lattice_label(m, *grid)),
                    meshes: run.map(|r| meshes(r)).unwrap_or_default(),
                });
            }
        }
        if models.is_empty() {
            continue;
        }
        match plots::overview_png(&out.join(name), &title, &panels, models.len()) {
            Ok(()) => written.push(name.to_string()),
            Err(e) => eprintln!("somnurbs: warning: picture skipped: {e}"),
        }
    }
    written.sort();
    Ok(written)
}
