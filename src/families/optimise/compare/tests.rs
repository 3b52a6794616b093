//! The analysis of `compare` from small hand-made records: every expected value a closed form.

use super::cells::{gather, pairwise_cells, Coverage};
use super::friedman::friedman_table;
use super::runtime::{runtime, Problem};
use crate::families::optimise::OptimRow;
use std::collections::BTreeMap;

/// A run of optimiser `o` on data set `data` (20x20 grid, 6x6 net, chord length), B's error 10.
fn run(o: &str, data: &str, repeat: usize, best: f64) -> OptimRow {
    OptimRow {
        dataset: data.into(),
        grid_x: 20,
        grid_y: 20,
        cn_x: 6,
        cn_y: 6,
        parameterisation: "chord_length".into(),
        optimiser: o.into(),
        repeat,
        b: 10.0,
        best,
        ..Default::default()
    }
}

/// `repeats` runs of each optimiser on each data set: optimiser k's repeat r ends at
/// 10 k + (k + 1) (r + 1) (so ga < de < pso in every repeat of every cell, and the paired
/// differences of two optimisers are distinct: no ties).
fn fixture(opts: &[&str], data: &[&str], repeats: usize) -> Vec<OptimRow> {
    let mut rows = Vec::new();
    for d in data {
        for (k, o) in opts.iter().enumerate() {
            for r in 0..repeats {
                rows.push(run(o, d, r, (10 * k + (k + 1) * (r + 1)) as f64));
            }
        }
    }
    rows
}

fn strings(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

/// Friedman's table holds each optimiser's mean over repeats per cell; with the same order in
/// all n = 3 cells of k = 3 optimisers the mean ranks are 1, 2, 3 and chi-squared is
/// 12 n / (k (k + 1)) sum R_j^2 - 3 n (k + 1) = 3 * 14 - 36 = 6, p = exp(-6 / 2) (df 2).
#[test]
fn friedman_over_three_cells_of_three_optimisers() {
    let rows = fixture(&["ga", "de", "pso"], &["a", "b", "c"], 2);
    let (opts, table) = friedman_table(&rows);
    assert_eq!(opts, strings(&["ga", "de", "pso"]));
    assert_eq!(table, vec![vec![1.5, 13.0, 24.5]; 3]);
    let (_, cells) = gather(&rows);
    let per = pairwise_cells(&cells, &opts, 0.05);
    let o = super::over_cells::overall(&rows, &opts, &per.wins, "runs.csv".as_ref()).unwrap();
    assert_eq!(o.friedman.mean_ranks, vec![1.0, 2.0, 3.0]);
    assert!((o.friedman.chi_squared - 6.0).abs() < 1e-12, "{}", o.friedman.chi_squared);
    assert!((o.friedman.p_value - (-3.0f64).exp()).abs() < 1e-12, "{}", o.friedman.p_value);
    let pairs: Vec<(&str, &str)> = o.rows.iter().map(|r| (r.x.as_str(), r.y.as_str())).collect();
    assert_eq!(pairs, [("ga", "de"), ("ga", "pso"), ("de", "pso")]);
    assert_eq!((o.rows[0].mean_rank_x.as_str(), o.rows[0].mean_rank_y.as_str()), ("1.0000", "2.0000"));
}

/// Per cell: six repeats all lower for x reach both tests (signed-rank p = 2 / 2^6, rank-sum
/// p = 2 / C(12, 6)); three repeats reach neither (min p 2 / 2^3 and 2 / C(6, 3)), so A12 = 1
/// decides, and says so.
#[test]
fn per_cell_winners_and_what_the_repeats_can_reach() {
    let rows = fixture(&["ga", "de"], &["a"], 6);
    let (opts, cells) = gather(&rows);
    let per = pairwise_cells(&cells, &opts, 0.05);
    let r = &per.rows[0];
    assert_eq!((r.x.as_str(), r.y.as_str(), r.n), ("ga", "de", 6));
    assert_eq!((r.better, r.better_by, r.can_reach_alpha), ("x", "signed_rank", "both"));
    assert_eq!(r.signed_rank_p, format!("{:.6}", 2.0 / 64.0));
    assert_eq!(r.rank_sum_p, format!("{:.6}", 2.0 / 924.0));
    assert_eq!((r.mean_x.as_str(), r.mean_y.as_str()), ("3.5", "17"));
    assert_eq!(r.a12_x_better, "1.0000");
    assert_eq!(per.wins[&("ga".to_string(), "de".to_string())], (1, 0, 1));
    assert!(per.unreachable.smallest.is_none());

    let rows = fixture(&["ga", "de"], &["a"], 3);
    let (opts, cells) = gather(&rows);
    let per = pairwise_cells(&cells, &opts, 0.05);
    let r = &per.rows[0];
    assert_eq!((r.better, r.better_by, r.can_reach_alpha), ("x", "a12 (no test significant)", "neither"));
    assert_eq!(r.min_p_signed_rank, format!("{:.6}", 2.0 / 8.0));
    assert_eq!(r.min_p_rank_sum, format!("{:.6}", 2.0 / 20.0));
    assert_eq!(per.wins[&("ga".to_string(), "de".to_string())], (0, 0, 0));
    let u = &per.unreachable;
    assert_eq!((u.of, u.signed_rank, u.rank_sum), (1, 1, 1));
    assert_eq!(u.smallest, Some((3, 0.25, 0.1)));
}

/// An optimiser that ran 2 of 4 cells: the tests over cells use the 2 cells every optimiser ran,
/// and the note says so, naming its count; with full coverage there is no note.
#[test]
fn partial_coverage_is_stated_and_the_tests_over_cells_use_the_common_cells() {
    let mut rows = fixture(&["ga", "de"], &["a", "b", "c", "d"], 2);
    rows.extend(fixture(&["cma"], &["b", "d"], 2));
    let (opts, cells) = gather(&rows);
    let c = Coverage::of(&cells, &opts);
    let ran = vec![("ga".to_string(), 4), ("de".to_string(), 4), ("cma".to_string(), 2)];
    let not = |v: &[&str]| v.iter().map(|d| format!("{d} 20x20 6x6 chord_length")).collect();
    let missing =
        vec![("ga".to_string(), not(&[])), ("de".to_string(), not(&[])), ("cma".to_string(), not(&["a", "c"]))];
    assert_eq!(c, Coverage { cells: 4, common: 2, ran, missing });
    assert!(!c.full());
    assert_eq!(c.used(), "the 2 of 4 cells every optimiser ran");
    let note = c.note().unwrap();
    assert!(note.contains("(cma ran 2 of 4)") && note.contains("use the 2 cells every optimiser ran"), "{note}");
    let (_, table) = friedman_table(&rows);
    assert_eq!(table.len(), 2);
    let b = super::bayes::bayes_table(&rows, &opts, 0.0, 1000).unwrap();
    assert!(b.iter().all(|r| r.cells == 2), "{b:?}");
    // The per-cell tests keep every pair's own cells: ga-de in 4, each with cma in 2.
    let per = pairwise_cells(&cells, &opts, 0.05);
    assert_eq!(per.rows.len(), 4 + 2 + 2);
    let full = fixture(&["ga", "de"], &["a", "b"], 2);
    let (opts, cells) = gather(&full);
    let c = Coverage::of(&cells, &opts);
    assert_eq!((c.note(), c.full(), c.used().as_str()), (None, true, "2 cells"));
}

/// One problem with targets 3, 2, 1 and two runs of x: run 1 reaches 3 at 10 and 2 and 1 at
/// 100 (its budget), run 2 reaches 3 at 20 and stops at 50. Of the 6 (run, target) pairs, 1 is
/// reached by 10 evaluations, 2 by 20, 4 by 100; AOCC over B = 100 is
/// ((100 - 10 + 1) + (100 - 20 + 1) + 2 (100 - 100 + 1)) / 100 / 6 = 0.29; ERT of target 3 is
/// (10 + 20) / 2, of target 2 (100 + 50) / 1.
#[test]
fn ecdf_aocc_and_ert_of_a_hand_made_problem() {
    let runs = vec![(100, vec![(1, 5.0), (10, 2.5), (100, 1.0)]), (50, vec![(1, 5.0), (20, 2.9)])];
    let p = Problem {
        name: "p".into(),
        b: 5.0,
        best_known: 1.0,
        from: "test".into(),
        reference: Some(5.0),
        rule: "b_to_best_known",
        targets: vec![3.0, 2.0, 1.0],
        runs: BTreeMap::from([("x".to_string(), runs)]),
    };
    let rt = runtime(std::slice::from_ref(&p), &strings(&["x"]));
    assert_eq!(rt.budget, 100);
    let e = rt.ecdf.iter().find(|e| e.group == "p").unwrap();
    assert_eq!(e.pairs, 6);
    for (b, v) in rt.budgets.iter().zip(&e.values) {
        let reached = match b {
            0..=9 => 0,
            10..=19 => 1,
            20..=99 => 2,
            _ => 4,
        };
        assert_eq!(*v, reached as f64 / 6.0, "at {b} evaluations");
    }
    assert!((e.aocc - 0.29).abs() < 1e-12, "{}", e.aocc);
    let all = rt.ecdf.iter().find(|e| e.group == "all").unwrap();
    assert_eq!((all.problems, all.pairs, &all.values), (1, 6, &e.values));
    let ert: Vec<(f64, usize)> = rt.ert.iter().map(|r| (r.ert, r.hits)).collect();
    assert_eq!(ert, [(15.0, 2), (150.0, 1), (150.0, 1)]);
    // The fixed-budget gap at the end: run 1 at (1 - 1) / 4, run 2 at (2.9 - 1) / 4.
    let g = rt.fixed_budget.iter().find(|g| g.group == "p").unwrap();
    let last = *g.values.as_ref().unwrap().last().unwrap();
    assert!((last - (0.0 + 1.9 / 4.0) / 2.0).abs() < 1e-12, "{last}");
}

/// "all" is over the problems every optimiser ran: with y on one of two problems, both
/// optimisers' aggregates are over that one problem, and x's other problem keeps its own rows.
#[test]
fn the_runtime_aggregate_is_over_the_common_problems() {
    let problem = |name: &str, opts: &[&str]| Problem {
        name: name.into(),
        b: 5.0,
        best_known: 1.0,
        from: "test".into(),
        reference: Some(5.0),
        rule: "b_to_best_known",
        targets: vec![3.0, 1.0],
        runs: opts.iter().map(|o| (o.to_string(), vec![(10, vec![(1, 5.0), (10, 2.0)])])).collect(),
    };
    let probs = [problem("p", &["x", "y"]), problem("q", &["x"])];
    let rt = runtime(&probs, &strings(&["x", "y"]));
    let all: Vec<(&str, usize)> = rt
        .ecdf
        .iter()
        .filter(|e| e.group == "all")
        .map(|e| (e.optimiser.as_str(), e.problems))
        .collect();
    assert_eq!(all, [("x", 1), ("y", 1)]);
    assert_eq!(rt.common_desc, "problems every optimiser ran ");
    assert!(rt.ecdf.iter().any(|e| e.group == "q" && e.optimiser == "x"));
}

/// The tables' columns, from their row types (an empty table still names them).
#[test]
fn empty_tables_name_their_columns() {
    use crate::io::csv_table;
    let cells = csv_table::<super::cells::CellRow>(&[]).unwrap();
    assert_eq!(cells, "data,grid,cn,parameterisation,x,y,n,mean_x,mean_y,median_x,median_y,signed_rank_v,signed_rank_p,rank_sum_w,rank_sum_p,a12_x_better,a12_magnitude,h_signed_rank,h_rank_sum,min_p_signed_rank,min_p_rank_sum,can_reach_alpha,better,better_by\n");
    let overall = csv_table::<super::over_cells::OverallRow>(&[]).unwrap();
    assert_eq!(overall, "x,y,mean_rank_x,mean_rank_y,z,p,p_holm,cells_x_better,cells_y_better,cells_rank_sum_can_reach_alpha\n");
    let bayes = csv_table::<super::bayes::BayesRow>(&[]).unwrap();
    assert_eq!(bayes, "x,y,cells,rope,samples,p_x_better,p_rope,p_y_better\n");
}
