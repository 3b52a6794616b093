//! The Bayesian signed-rank test of every pair of optimisers over the cells every optimiser ran
//! (`compare_bayes.csv`).

use super::cells::ran_by_all;
use crate::families::optimise::{ComparedCell, OptimRow};
use crate::stats;
use anyhow::Result;
use serde::Serialize;
use std::collections::BTreeMap;

/// One row of `compare_bayes.csv`.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub(super) struct BayesRow {
    pub(super) x: String,
    pub(super) y: String,
    pub(super) cells: usize,
    pub(super) rope: String,
    pub(super) samples: usize,
    pub(super) p_x_better: String,
    pub(super) p_rope: String,
    pub(super) p_y_better: String,
}

/// Per cell: approach B's error and per optimiser (sum of best errors, runs).
type CellSums = (f64, BTreeMap<String, (f64, usize)>);

/// The Bayesian signed-rank test of every pair over the cells every optimiser ran: each cell's
/// mean best error divided by the cell's approach-B error; `rope` on that scale, `samples` Monte
/// Carlo samples.
pub(super) fn bayes_table(
    rows: &[OptimRow],
    opts: &[String],
    rope: f64,
    samples: usize,
) -> Result<Vec<BayesRow>> {
    let mut cells: BTreeMap<ComparedCell, CellSums> = BTreeMap::new();
    for r in rows {
        let e = cells.entry(r.compared_cell()).or_insert((r.b, BTreeMap::new()));
        let s = e.1.entry(r.competitor()).or_default();
        s.0 += r.best;
        s.1 += 1;
    }
    let full: Vec<Vec<f64>> = cells
        .values()
        .filter(|(_, per)| ran_by_all(per, opts))
        .map(|(b, per)| opts.iter().map(|o| per[o].0 / per[o].1 as f64 / b).collect())
        .collect();
    let mut out = Vec::new();
    for i in 0..opts.len() {
        for j in i + 1..opts.len() {
            let a: Vec<f64> = full.iter().map(|c| c[i]).collect();
            let b: Vec<f64> = full.iter().map(|c| c[j]).collect();
            let seed = 0x5eed + (i * opts.len() + j) as u64;
            let r = stats::bayes::signed_rank(&a, &b, rope, stats::bayes::PRIOR, samples, seed)
                .map_err(|e| {
                    anyhow::anyhow!("Bayesian signed-rank test {} vs {}: {e}", opts[i], opts[j])
                })?;
            out.push(BayesRow {
                x: opts[i].clone(),
                y: opts[j].clone(),
                cells: r.n,
                rope: format!("{rope:e}"),
                samples: r.samples,
                p_x_better: format!("{:.4}", r.p_a_better),
                p_rope: format!("{:.4}", r.p_rope),
                p_y_better: format!("{:.4}", r.p_b_better),
            });
        }
    }
    Ok(out)
}

/// The summary of the Bayesian rows, the lines printed on stdout and listed in compare.md.
pub(super) fn summary(rows: &[BayesRow], cov: &super::cells::Coverage) -> Vec<String> {
    let over = |n: usize| if cov.full() { format!("{n} cells") } else { cov.used() };
    let mut lines = Vec::new();
    for r in rows {
        lines.push(format!("  Bayesian signed-rank {} vs {} over {} (rope {} of B's error): P({} better) {}, P(equivalent) {}, P({} better) {}", r.x, r.y, over(r.cells), r.rope, r.x, r.p_x_better, r.p_rope, r.y, r.p_y_better));
    }
    lines
}
