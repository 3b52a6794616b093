//! Convergence data in the IOHprofiler format, so IOHanalyzer and iohinspector load a Chapter 6
//! folder: per optimiser a folder `ioh/<optimiser>/` holding, per problem (data set, grid,
//! control net, parameterisation), the JSON meta-data `IOHprofiler_f<id>_<name>.json` and the
//! improvement-based raw data `data_f<id>_<name>/IOHprofiler_f<id>_DIM<d>.dat` (layout:
//! [`crate::optim::ioh`]). Runs are listed in repeat order.

use super::OptimRun;
use crate::io::{read_text, write_atomic};
use crate::optim::ioh::{dat_text, json_text, parse_dat, IohMeta, IohRun};
use anyhow::{Context, Result};
use std::path::Path;

/// The IOHprofiler function name of a run's problem.
pub(crate) fn problem_name(dataset: &str, grid: &str, cn: &str, param: &str) -> String {
    format!("{dataset}_{grid}_{cn}_{param}")
}

/// Write `ioh/<optimiser>/` for every optimiser and problem of the runs (and remove the `.info`
/// files an older version wrote there, which would stop IOHanalyzer's format detection); returns
/// the number of (optimiser, problem) pairs.
pub(crate) fn write(runs: &[OptimRun], out: &Path) -> Result<usize> {
    let mut problems: Vec<String> = Vec::new();
    let mut opts: Vec<String> = Vec::new();
    let key = |r: &OptimRun| {
        problem_name(
            &r.cell.dataset,
            &r.cell.grid.to_string(),
            &r.cell.cn.to_string(),
            r.cell.param.name(),
        )
    };
    for r in runs {
        if !problems.contains(&key(r)) {
            problems.push(key(r));
        }
        if !opts.contains(&r.competitor) {
            opts.push(r.competitor.clone());
        }
    }
    let mut n = 0;
    for o in &opts {
        let dir = out.join("ioh").join(o);
        remove_info_files(&dir)?;
        for (k, name) in problems.iter().enumerate() {
            let mut rs: Vec<&OptimRun> =
                runs.iter().filter(|r| &r.competitor == o && &key(r) == name).collect();
            if rs.is_empty() {
                continue;
            }
            rs.sort_by_key(|r| r.cell.repeat);
            let ioh_runs: Vec<IohRun> = rs
                .iter()
                .map(|r| IohRun {
                    evaluations: r.row.evaluations,
                    improvements: &r.improvements,
                    best_x: &r.best_x,
                })
                .collect();
            let meta = IohMeta {
                suite: "somnurbs".into(),
                function_id: (k + 1) as u32,
                function_name: name.clone(),
                algorithm: o.clone(),
                algorithm_info: String::new(),
                dimension: rs[0].row.dimension,
            };
            write_atomic(&dir.join(meta.json_file_name()), json_text(&meta, &ioh_runs).as_bytes())?;
            write_atomic(&dir.join(meta.dat_path()), dat_text(&ioh_runs).as_bytes())?;
            n += 1;
        }
    }
    Ok(n)
}

fn remove_info_files(dir: &Path) -> Result<()> {
    if crate::io::outdir::is_filling(dir) {
        return Ok(());
    }
    let Ok(entries) = std::fs::read_dir(dir) else { return Ok(()) };
    for e in entries.flatten() {
        let p = e.path();
        if p.extension().is_some_and(|x| x == "info") {
            std::fs::remove_file(&p).with_context(|| format!("cannot remove {}", p.display()))?;
        }
    }
    Ok(())
}

/// The runs of one optimiser on one problem, read back from a folder's `ioh/`: (evaluations,
/// improvement rows) per run in the JSON's order.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LoadedProblem {
    pub(crate) optimiser: String,
    pub(crate) function_name: String,
    pub(crate) runs: Vec<(u64, Vec<(u64, f64)>)>,
}

/// Read every `ioh/<optimiser>/IOHprofiler_*.json` of a folder and its `.dat` file (sorted by
/// optimiser folder and file name). Errors name the file.
pub(crate) fn read(folder: &Path) -> Result<Vec<LoadedProblem>> {
    let root = folder.join("ioh");
    let mut out = Vec::new();
    let mut dirs: Vec<_> = std::fs::read_dir(&root)
        .with_context(|| format!("cannot read {}", root.display()))?
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_dir())
        .collect();
    dirs.sort();
    for dir in dirs {
        let mut files: Vec<_> = std::fs::read_dir(&dir)
            .with_context(|| format!("cannot read {}", dir.display()))?
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|x| x == "json"))
            .collect();
        files.sort();
        for f in files {
            let v: serde_json::Value = serde_json::from_str(&read_text(&f)?)
                .with_context(|| format!("{}: not JSON", f.display()))?;
            let field =
                |k: &str| v.get(k).with_context(|| format!("{}: no key `{k}`", f.display()));
            let optimiser = field("algorithm")?
                .get("name")
                .and_then(|s| s.as_str())
                .with_context(|| format!("{}: no algorithm.name", f.display()))?
                .to_string();
            let function_name = field("function_name")?
                .as_str()
                .with_context(|| format!("{}: function_name is not a string", f.display()))?
                .to_string();
            let mut runs = Vec::new();
            for s in field("scenarios")?
                .as_array()
                .with_context(|| format!("{}: scenarios is not a list", f.display()))?
            {
                let path = s
                    .get("path")
                    .and_then(|p| p.as_str())
                    .with_context(|| format!("{}: a scenario has no path", f.display()))?;
                let dat = dir.join(path);
                let rows = parse_dat(&read_text(&dat)?)
                    .map_err(anyhow::Error::msg)
                    .with_context(|| format!("{}", dat.display()))?;
                let listed = s
                    .get("runs")
                    .and_then(|r| r.as_array())
                    .with_context(|| format!("{}: a scenario has no runs list", f.display()))?;
                if listed.len() != rows.len() {
                    anyhow::bail!(
                        "{}: {} runs listed but {} in {}",
                        f.display(),
                        listed.len(),
                        rows.len(),
                        dat.display()
                    );
                }
                for (r, rows) in listed.iter().zip(rows) {
                    let evals = r
                        .get("evals")
                        .and_then(|e| e.as_u64())
                        .with_context(|| format!("{}: a run has no evals count", f.display()))?;
                    runs.push((evals, rows));
                }
            }
            out.push(LoadedProblem { optimiser, function_name, runs });
        }
    }
    Ok(out)
}
