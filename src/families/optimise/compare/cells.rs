//! The tests of each cell: every pair of optimisers that ran a cell, compared by the signed-rank
//! and rank-sum tests and A12 (`compare_cells.csv`), and which cells every optimiser ran (the
//! cells the tests over cells use).

use crate::families::optimise::{ComparedCell, OptimRow};
use crate::stats;
use crate::stats::{effect, rank_sum::rank_sum, wilcoxon::signed_rank, Alternative};
use serde::Serialize;
use std::collections::BTreeMap;

/// Per cell, per competitor: its (repeat, best) pairs.
pub(super) type Cells = BTreeMap<ComparedCell, BTreeMap<String, Vec<(usize, f64)>>>;
/// Per pair of competitors: cells where the rank-sum test favours the first, the second, and the
/// cells where the rank-sum test can reach alpha at all.
pub(super) type Wins = BTreeMap<(String, String), (usize, usize, usize)>;

/// The competitors in order of first appearance, and every cell's runs.
pub(super) fn gather(rows: &[OptimRow]) -> (Vec<String>, Cells) {
    let mut opts: Vec<String> = Vec::new();
    let mut cells: Cells = BTreeMap::new();
    for r in rows {
        if !opts.contains(&r.competitor()) {
            opts.push(r.competitor());
        }
        let runs = cells.entry(r.compared_cell()).or_default().entry(r.competitor()).or_default();
        runs.push((r.repeat, r.best));
    }
    (opts, cells)
}

/// Whether every optimiser of `opts` ran the cell whose per-optimiser entries are `per`: the one
/// rule for the cells the tests over cells (Friedman, Nemenyi, Bayesian signed-rank) use.
pub(super) fn ran_by_all<V>(per: &BTreeMap<String, V>, opts: &[String]) -> bool {
    opts.iter().all(|o| per.contains_key(o))
}

/// Which optimiser ran which cells: what the statistics over cells are computed on.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Coverage {
    /// Cells in all (run by any optimiser).
    pub(super) cells: usize,
    /// Cells every optimiser ran (what the tests over cells use).
    pub(super) common: usize,
    /// Per optimiser (in `opts` order), the cells it ran.
    pub(super) ran: Vec<(String, usize)>,
    /// Per optimiser (in `opts` order), the cells it did not run, named
    /// `data grid net parameterisation`.
    pub(super) missing: Vec<(String, Vec<String>)>,
}

impl Coverage {
    pub(super) fn of(cells: &Cells, opts: &[String]) -> Coverage {
        let ran = |o: &String| cells.values().filter(|per| per.contains_key(o)).count();
        let missing = |o: &String| {
            let name = |k: &ComparedCell| format!("{} {} {} {}", k.data, k.grid, k.cn, k.param);
            cells.iter().filter(|(_, per)| !per.contains_key(o)).map(|(k, _)| name(k)).collect()
        };
        Coverage {
            cells: cells.len(),
            common: cells.values().filter(|per| ran_by_all(per, opts)).count(),
            ran: opts.iter().map(|o| (o.clone(), ran(o))).collect(),
            missing: opts.iter().map(|o| (o.clone(), missing(o))).collect(),
        }
    }

    /// Whether every optimiser ran every cell.
    pub(super) fn full(&self) -> bool {
        self.common == self.cells
    }

    /// The cells the tests over cells use, in words: "4 cells", or where some optimiser ran part
    /// of them "the 2 of 4 cells every optimiser ran".
    pub(super) fn used(&self) -> String {
        if self.full() {
            format!("{} cells", self.common)
        } else {
            format!("the {} of {} cells every optimiser ran", self.common, self.cells)
        }
    }

    /// The optimisers that did not run every cell, as "name ran k of n".
    fn partial(&self) -> Vec<String> {
        self.ran
            .iter()
            .filter(|(_, k)| *k < self.cells)
            .map(|(o, k)| format!("{o} ran {k} of {}", self.cells))
            .collect()
    }

    /// Where some optimiser did not run every cell (an external logged on part of the problems):
    /// one line naming each such optimiser's count and what the statistics over cells use; None
    /// when every optimiser ran every cell.
    pub(super) fn note(&self) -> Option<String> {
        let partial = self.partial();
        if partial.is_empty() {
            return None;
        }
        Some(format!(
            "not every optimiser ran every cell ({}): the tests over cells (Friedman, the critical-difference diagram, the Bayesian signed-rank test) and the runtime aggregate `all` use the {} cells every optimiser ran; the per-cell tests and per-problem runtime tables use each pair's or optimiser's own",
            partial.join(", "),
            self.common
        ))
    }
}

/// One row of `compare_cells.csv`: x against y in one cell. Numbers are written as the tables
/// always wrote them (shortest round-trip for means and medians, fixed decimals for p and A12).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub(super) struct CellRow {
    pub(super) data: String,
    pub(super) grid: String,
    pub(super) cn: String,
    pub(super) parameterisation: String,
    pub(super) x: String,
    pub(super) y: String,
    pub(super) n: usize,
    pub(super) mean_x: String,
    pub(super) mean_y: String,
    pub(super) median_x: String,
    pub(super) median_y: String,
    pub(super) signed_rank_v: String,
    pub(super) signed_rank_p: String,
    pub(super) rank_sum_w: String,
    pub(super) rank_sum_p: String,
    pub(super) a12_x_better: String,
    pub(super) a12_magnitude: String,
    pub(super) h_signed_rank: String,
    pub(super) h_rank_sum: String,
    pub(super) min_p_signed_rank: String,
    pub(super) min_p_rank_sum: String,
    pub(super) can_reach_alpha: &'static str,
    pub(super) better: &'static str,
    pub(super) better_by: &'static str,
}

/// Cell comparisons whose tests cannot reach alpha with their repeats: by the signed-rank test, by
/// the rank-sum test, of all comparisons, and the smallest (n, signed-rank min p, rank-sum min p)
/// among them.
#[derive(Debug, Default)]
pub(super) struct Unreachable {
    pub(super) signed_rank: usize,
    pub(super) rank_sum: usize,
    pub(super) of: usize,
    pub(super) smallest: Option<(usize, f64, f64)>,
}

/// What the per-cell tests give: the rows of `compare_cells.csv`, the cells where the rank-sum test
/// favours each side of every pair, and the comparisons that cannot reach alpha.
#[derive(Debug)]
pub(super) struct PerCell {
    pub(super) rows: Vec<CellRow>,
    pub(super) wins: Wins,
    pub(super) unreachable: Unreachable,
}

/// A number as the tables write it: shortest round-trip, `nan`, `inf`.
pub(super) fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else if v.is_nan() {
        "nan".into()
    } else {
        "inf".into()
    }
}

/// Which of x and y is better in one cell (minimisation), and on what grounds: the signed-rank
/// test when its p < alpha (x when W+ < W-, i.e. x - y mostly negative); else the rank-sum test when
/// its p < alpha (direction by A12); else A12 alone when its magnitude is not negligible (no test
/// significant); else none.
pub(super) fn better(
    sr: Option<&stats::wilcoxon::SignedRank>,
    rs: Option<&stats::rank_sum::RankSum>,
    a12_x: f64,
    alpha: f64,
) -> (&'static str, &'static str) {
    let side = |x_better: bool| if x_better { "x" } else { "y" };
    match (sr.filter(|r| r.p_value < alpha), rs.filter(|r| r.p_value < alpha)) {
        (Some(r), _) => (side(r.w_plus < r.w_minus), "signed_rank"),
        (None, Some(_)) => (side(a12_x > 0.5), "rank_sum"),
        (None, None) if a12_x.is_finite() && effect::magnitude(a12_x) != "negligible" => {
            (side(a12_x > 0.5), "a12 (no test significant)")
        }
        _ => ("none", "none (no test significant, a12 negligible)"),
    }
}

/// One `compare_cells.csv` row: the tests and effect size of x against y in cell `k`, and whether
/// the rank-sum test favours x (Some(true)), y (Some(false)) or neither at alpha, and whether each
/// test (signed-rank, rank-sum) can reach alpha with these repeats.
fn cell_pair(
    k: &ComparedCell,
    (x, y): (&str, &str),
    (xa, xb): (&[f64], &[f64]),
    alpha: f64,
) -> (CellRow, Option<bool>, (bool, bool)) {
    let paired = xa.len() == xb.len();
    let sr = if paired { signed_rank(xa, xb, Alternative::TwoSided).ok() } else { None };
    let rs = rank_sum(xa, xb, Alternative::TwoSided).ok();
    let a12 = effect::a12_x_better(xa, xb);
    let min_sr = paired.then(|| stats::wilcoxon::min_p_two_sided(xa.len()));
    let min_rs = stats::rank_sum::min_p_two_sided(xa.len(), xb.len());
    let reach = (min_sr.is_some_and(|p| p < alpha), min_rs < alpha);
    let h = |p: Option<f64>| p.map(|p| if p < alpha { "1" } else { "0" }).unwrap_or("").to_string();
    let (better, better_by) = better(sr.as_ref(), rs.as_ref(), a12, alpha);
    let favours = rs.as_ref().filter(|r| r.p_value < alpha).map(|_| a12 > 0.5);
    let row = CellRow {
        data: k.data.clone(),
        grid: k.grid.to_string(),
        cn: k.cn.to_string(),
        parameterisation: k.param.clone(),
        x: x.to_string(),
        y: y.to_string(),
        n: xa.len(),
        mean_x: num(stats::describe::mean_var(xa).0),
        mean_y: num(stats::describe::mean_var(xb).0),
        median_x: num(stats::describe::median(xa)),
        median_y: num(stats::describe::median(xb)),
        signed_rank_v: sr.as_ref().map(|r| r.w_plus.to_string()).unwrap_or_default(),
        signed_rank_p: sr.as_ref().map(|r| format!("{:.6}", r.p_value)).unwrap_or_default(),
        rank_sum_w: rs.as_ref().map(|r| r.w.to_string()).unwrap_or_default(),
        rank_sum_p: rs.as_ref().map(|r| format!("{:.6}", r.p_value)).unwrap_or_default(),
        a12_x_better: format!("{a12:.4}"),
        a12_magnitude: effect::magnitude(a12).to_string(),
        h_signed_rank: h(sr.as_ref().map(|r| r.p_value)),
        h_rank_sum: h(rs.as_ref().map(|r| r.p_value)),
        min_p_signed_rank: min_sr.map(|p| format!("{p:.6}")).unwrap_or_default(),
        min_p_rank_sum: format!("{min_rs:.6}"),
        can_reach_alpha: match reach {
            (true, true) => "both",
            (true, false) => "signed_rank",
            (false, true) => "rank_sum",
            (false, false) => "neither",
        },
        better,
        better_by,
    };
    (row, favours, reach)
}

/// The signed-rank and rank-sum tests and A12 of every pair in every cell (`compare_cells.csv`
/// rows), the cells where the rank-sum test favours each side, and the pairs that cannot reach
/// alpha with their repeats.
pub(super) fn pairwise_cells(cells: &Cells, opts: &[String], alpha: f64) -> PerCell {
    let mut out = PerCell { rows: Vec::new(), wins: Wins::new(), unreachable: Unreachable::default() };
    let by_repeat = |runs: &[(usize, f64)]| {
        let mut runs = runs.to_vec();
        runs.sort_by_key(|x| x.0);
        runs.into_iter().map(|x| x.1).collect::<Vec<f64>>()
    };
    for (k, per) in cells {
        for i in 0..opts.len() {
            for j in i + 1..opts.len() {
                let (Some(a), Some(b)) = (per.get(&opts[i]), per.get(&opts[j])) else { continue };
                let (xa, xb) = (by_repeat(a), by_repeat(b));
                let (row, favours, reach) = cell_pair(k, (&opts[i], &opts[j]), (&xa, &xb), alpha);
                let e = out.wins.entry((opts[i].clone(), opts[j].clone())).or_default();
                match favours {
                    Some(true) => e.0 += 1,
                    Some(false) => e.1 += 1,
                    None => {}
                }
                e.2 += usize::from(reach.1);
                let u = &mut out.unreachable;
                u.of += 1;
                u.signed_rank += usize::from(!reach.0);
                u.rank_sum += usize::from(!reach.1);
                if !(reach.0 && reach.1) {
                    let n = xa.len().min(xb.len());
                    if u.smallest.is_none_or(|s| n < s.0) {
                        let sr = stats::wilcoxon::min_p_two_sided(n);
                        u.smallest = Some((n, sr, stats::rank_sum::min_p_two_sided(n, n)));
                    }
                }
                out.rows.push(row);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The `better` rule: the signed-rank test first (x when W+ < W-), then the rank-sum test
    /// (direction by A12), then A12 alone when not negligible, else none.
    #[test]
    fn better_rule() {
        let (x, y) = ([1.0, 2.0, 3.0, 4.0, 5.0, 6.0], [7.0, 8.0, 9.0, 10.0, 11.0, 12.0]);
        let sr = signed_rank(&x, &y, Alternative::TwoSided).unwrap();
        let rs = rank_sum(&x, &y, Alternative::TwoSided).unwrap();
        let a = effect::a12_x_better(&x, &y);
        assert_eq!(better(Some(&sr), Some(&rs), a, 0.05), ("x", "signed_rank"));
        assert_eq!(better(None, Some(&rs), a, 0.05), ("x", "rank_sum"));
        // Three repeats reach neither test at 0.05: A12 decides, and says so.
        let sr = signed_rank(&y[..3], &x[..3], Alternative::TwoSided).unwrap();
        let rs = rank_sum(&y[..3], &x[..3], Alternative::TwoSided).unwrap();
        let a = effect::a12_x_better(&y[..3], &x[..3]);
        assert_eq!(better(Some(&sr), Some(&rs), a, 0.05), ("y", "a12 (no test significant)"));
        assert_eq!(better(Some(&sr), Some(&rs), 0.52, 0.05).0, "none");
        assert_eq!(better(None, None, f64::NAN, 0.05).0, "none");
    }
}
