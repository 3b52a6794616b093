//! The tests over cells: Friedman on each optimiser's mean best per cell, with Holm-adjusted
//! pairwise tests (`compare_overall.csv`) and the critical-difference diagram, over the cells
//! every optimiser ran.

use super::cells::{Coverage, Wins};
use super::friedman::friedman_table;
use crate::families::optimise::OptimRow;
use crate::report::plots;
use crate::stats::friedman::{friedman, Friedman};
use anyhow::{Context, Result};
use serde::Serialize;
use std::path::Path;

/// One row of `compare_overall.csv`: a pair's Friedman-Nemenyi test, Holm-adjusted, and the
/// cells where the rank-sum test favours each side.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub(super) struct OverallRow {
    pub(super) x: String,
    pub(super) y: String,
    pub(super) mean_rank_x: String,
    pub(super) mean_rank_y: String,
    pub(super) z: String,
    pub(super) p: String,
    pub(super) p_holm: String,
    pub(super) cells_x_better: usize,
    pub(super) cells_y_better: usize,
    pub(super) cells_rank_sum_can_reach_alpha: usize,
}

/// The Friedman test over the cells every optimiser ran, and its table's rows.
pub(super) struct Overall {
    pub(super) friedman: Friedman,
    /// Each optimiser's mean rank (in `opts` order).
    pub(super) ranks: Vec<(String, f64)>,
    pub(super) rows: Vec<OverallRow>,
}

/// Friedman with Holm-adjusted pairwise tests over the cells every optimiser ran; `runs` names the
/// table in an error.
pub(super) fn overall(
    rows: &[OptimRow],
    opts: &[String],
    wins: &Wins,
    runs: &Path,
) -> Result<Overall> {
    let (_, table) = friedman_table(rows);
    let f = friedman(&table).with_context(|| format!("{}: Friedman test", runs.display()))?;
    let rows = f
        .pairwise
        .iter()
        .map(|&(i, j, z, p, ph)| {
            let w = wins.get(&(opts[i].clone(), opts[j].clone())).copied().unwrap_or((0, 0, 0));
            OverallRow {
                x: opts[i].clone(),
                y: opts[j].clone(),
                mean_rank_x: format!("{:.4}", f.mean_ranks[i]),
                mean_rank_y: format!("{:.4}", f.mean_ranks[j]),
                z: format!("{z:.4}"),
                p: format!("{p:.6}"),
                p_holm: format!("{ph:.6}"),
                cells_x_better: w.0,
                cells_y_better: w.1,
                cells_rank_sum_can_reach_alpha: w.2,
            }
        })
        .collect();
    let ranks = opts.iter().cloned().zip(f.mean_ranks.iter().copied()).collect();
    Ok(Overall { friedman: f, ranks, rows })
}

/// The critical-difference diagram of `o` into `png` (Ok(false): the test gives no critical
/// difference for this many optimisers, nothing drawn); its title says which cells it ranks.
pub(super) fn render_cd(o: &Overall, cov: &Coverage, png: &Path) -> Result<bool, plots::PlotError> {
    let Some(cd) = o.friedman.critical_difference else { return Ok(false) };
    let cells = if cov.full() {
        format!("{} cells", o.friedman.blocks)
    } else {
        format!("the {} of {} cells all ran", o.friedman.blocks, cov.cells)
    };
    let title = format!("Mean ranks over {cells} (Nemenyi CD = {cd:.3}, alpha 0.05)");
    plots::cd_diagram_png(png, &title, &o.ranks, cd).map(|()| true)
}

/// The summary of `o`, the lines printed on stdout and listed in compare.md.
pub(super) fn summary(o: &Overall, cov: &Coverage) -> Vec<String> {
    let f = &o.friedman;
    let mut lines = vec![format!(
        "Friedman over {} x {} optimisers: chi-squared {:.3}, df {}, p = {:.3e}",
        cov.used(),
        f.treatments,
        f.chi_squared,
        f.df,
        f.p_value
    )];
    for (o, r) in &o.ranks {
        lines.push(format!("  mean rank {o:<5} {r:.3}"));
    }
    for r in &o.rows {
        lines.push(format!("  {} vs {}: z {}, p {} (Holm {}); cells where the rank-sum test favours {}: {}, {}: {} (of {} where it can reach alpha)", r.x, r.y, r.z, r.p, r.p_holm, r.x, r.cells_x_better, r.y, r.cells_y_better, r.cells_rank_sum_can_reach_alpha));
    }
    lines
}
