//! The blocks x treatments table of the Friedman test, shared by `compare` and the Chapter 6
//! report (`report.rs`, its overall ranking).

use super::cells::ran_by_all;
use crate::families::optimise::{ComparedCell, OptimRow};
use std::collections::BTreeMap;

/// The blocks x treatments table of the Friedman test: one row per cell (data, grid, net,
/// parameterisation) that every optimiser ran, the mean best fitness over repeats of each
/// optimiser (in order of first appearance).
pub(crate) fn friedman_table(rows: &[OptimRow]) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut opts: Vec<String> = Vec::new();
    let mut cells: BTreeMap<ComparedCell, BTreeMap<String, (f64, usize)>> = BTreeMap::new();
    for r in rows {
        if !opts.contains(&r.competitor()) {
            opts.push(r.competitor());
        }
        let e = cells.entry(r.compared_cell()).or_default().entry(r.competitor()).or_default();
        e.0 += r.best;
        e.1 += 1;
    }
    let table = cells
        .values()
        .filter(|per| ran_by_all(per, &opts))
        .map(|per| opts.iter().map(|o| per[o].0 / per[o].1 as f64).collect())
        .collect();
    (opts, table)
}
