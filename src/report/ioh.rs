//! Convergence traces in the IOHprofiler format, so IOHanalyzer can load a Chapter 6 folder:
//! per optimiser a folder `ioh/<optimiser>/` holding one meta-data file per problem,
//! `IOHprofiler_f<id>_<name>.info` (suite, funcId, funcName, DIM, maximization, algId, then one
//! `data file, instance:evaluations|best` line), and the raw data
//! `data_f<id>_<name>/IOHprofiler_f<id>_DIM<d>.dat`: per run a header line `evaluations raw_y`
//! and one row per trace point (evaluations, best-so-far fitness; minimisation).

use super::fsio::write_atomic;
use crate::experiment::ch6::OptimRun;
use anyhow::Result;
use std::fmt::Write;
use std::path::Path;

/// The .info and .dat texts of one (optimiser, problem) from its runs (in repeat order).
pub fn texts(fid: usize, name: &str, optimiser: &str, dim: usize, runs: &[&OptimRun]) -> (String, String) {
    let dat_rel = format!("data_f{fid}_{name}/IOHprofiler_f{fid}_DIM{dim}.dat");
    let mut info = format!("suite = 'somnurbs', funcId = {fid}, funcName = '{name}', DIM = {dim}, maximization = 'F', algId = '{optimiser}'\n%\n{dat_rel}");
    let mut dat = String::new();
    for r in runs {
        let _ = write!(info, ", 1:{}|{:e}", r.row.evaluations, r.row.best);
        dat.push_str("evaluations raw_y\n");
        for (e, y) in &r.trace {
            let _ = writeln!(dat, "{e} {y:e}");
        }
    }
    info.push('\n');
    (info, dat)
}

/// Write `ioh/` for every optimiser and problem of the runs; returns the number of .info files.
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
            let fid = k + 1;
            let (info, dat) = texts(fid, name, o, rs[0].row.dimension, &rs);
            let dir = out.join("ioh").join(o);
            write_atomic(&dir.join(format!("IOHprofiler_f{fid}_{name}.info")), info.as_bytes())?;
            write_atomic(&dir.join(format!("data_f{fid}_{name}/IOHprofiler_f{fid}_DIM{}.dat", rs[0].row.dimension)), dat.as_bytes())?;
            n += 1;
        }
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::ch6::OptimRow;
    use crate::experiment::spec::{GridSize, OptimCell};

    #[test]
    fn info_and_dat_layout() {
        let run = |rep: usize, best: f64| OptimRun {
            cell: OptimCell { dataset: "cube".into(), grid: GridSize { nx: 20, ny: 20 }, cn: GridSize { nx: 6, ny: 6 }, param: crate::spline::Parameterisation::Uniform, optimiser: "de".into(), repeat: rep },
            row: OptimRow { evaluations: 80, best, dimension: 156, ..Default::default() },
            trace: vec![(1, 3.0), (50, 2.5), (80, best)],
            best_x: Vec::new(),
        };
        let (a, b) = (run(0, 2.0), run(1, 1.5));
        let (info, dat) = texts(4, "cube_x", "de", 156, &[&a, &b]);
        let lines: Vec<&str> = info.lines().collect();
        assert_eq!(lines[0], "suite = 'somnurbs', funcId = 4, funcName = 'cube_x', DIM = 156, maximization = 'F', algId = 'de'");
        assert_eq!(lines[1], "%");
        assert_eq!(lines[2], "data_f4_cube_x/IOHprofiler_f4_DIM156.dat, 1:80|2e0, 1:80|1.5e0");
        assert_eq!(dat.matches("evaluations raw_y\n").count(), 2);
        assert!(dat.contains("\n50 2.5e0\n"));
    }
}
