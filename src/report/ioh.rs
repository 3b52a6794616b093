//! Convergence traces in the IOHprofiler format, so IOHanalyzer can load a Chapter 6 folder:
//! per optimiser a folder `ioh/<optimiser>/` holding one meta-data file per problem,
//! `IOHprofiler_f<id>_<name>.info` (suite, funcId, funcName, DIM, maximization, algId, then one
//! `data file, instance:evaluations|best` line), and the raw data
//! `data_f<id>_<name>/IOHprofiler_f<id>_DIM<d>.dat`: per run a header line `evaluations raw_y`
//! and one row per trace point (evaluations, best-so-far fitness; minimisation).

use super::fsio::write_atomic;
use crate::experiment::ch6::OptimRun;
use crate::optim::ioh::{dat_text, info_text, json_text, IohMeta};
use crate::optim::RunResult;
use anyhow::Result;
use std::path::Path;

/// The run as the exporter sees it (no control points: the files stay small).
fn as_result(r: &OptimRun) -> RunResult {
    RunResult { best_x: Vec::new(), best_fitness: r.row.best, initial_best_fitness: r.row.initial_best, evaluations: r.row.evaluations, trace: r.trace.clone() }
}

/// Write `ioh/<optimiser>/` (a `.json` and an `.info` meta-data file and the `.dat` raw data) for
/// every optimiser and problem of the runs; returns the number of (optimiser, problem) pairs.
pub fn write(runs: &[OptimRun], out: &Path) -> Result<usize> {
    let mut problems: Vec<String> = Vec::new();
    let mut opts: Vec<String> = Vec::new();
    let key = |r: &OptimRun| format!("{}_{}_{}_{}", r.cell.dataset, r.cell.grid, r.cell.cn, r.cell.param.name());
    for r in runs {
        if !problems.contains(&key(r)) {
            problems.push(key(r));
        }
        if !opts.contains(&r.cell.optimiser) {
            opts.push(r.cell.optimiser.clone());
        }
    }
    let mut n = 0;
    for o in &opts {
        for (k, name) in problems.iter().enumerate() {
            let mut rs: Vec<&OptimRun> = runs.iter().filter(|r| &r.cell.optimiser == o && &key(r) == name).collect();
            if rs.is_empty() {
                continue;
            }
            rs.sort_by_key(|r| r.cell.repeat);
            let results: Vec<RunResult> = rs.iter().map(|r| as_result(r)).collect();
            let refs: Vec<&RunResult> = results.iter().collect();
            let meta = IohMeta { suite: "somnurbs".into(), function_id: (k + 1) as u32, function_name: name.clone(), algorithm: o.clone(), algorithm_info: String::new(), dimension: rs[0].row.dimension };
            let dir = out.join("ioh").join(o);
            write_atomic(&dir.join(meta.info_file_name()), info_text(&meta, &refs).as_bytes())?;
            write_atomic(&dir.join(meta.json_file_name()), json_text(&meta, &refs, false).as_bytes())?;
            write_atomic(&dir.join(meta.dat_path()), dat_text(&refs).as_bytes())?;
            n += 1;
        }
    }
    Ok(n)
}

