//! `somnurbs compare RESULTS_DIR`: statistics over the optimiser runs of a Chapter 6 folder, read
//! from its runs.csv only (so a folder from another machine or an older run compares the same).

use super::OptimRow;
use crate::cli::CompareArgs;
use crate::io::{csv_records, write_atomic};
use crate::report::plots;
use crate::stats;
use crate::stats::{
    effect, friedman::friedman, rank_sum::rank_sum, wilcoxon::signed_rank, Alternative,
};
use anyhow::{Context, Result};
use std::collections::BTreeMap;
use std::path::PathBuf;

use super::external::Certificate;
use super::ComparedCell;

/// Whether every optimiser of `opts` ran the cell whose per-optimiser entries are `per`: the one
/// rule for the cells the tests over cells (Friedman, Nemenyi, Bayesian signed-rank) use.
fn ran_by_all<V>(per: &BTreeMap<String, V>, opts: &[String]) -> bool {
    opts.iter().all(|o| per.contains_key(o))
}

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
        let e = cells
            .entry(r.compared_cell())
            .or_default()
            .entry(r.competitor())
            .or_default();
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

/// Per cell, per competitor: its (repeat, best) pairs.
type Cells = BTreeMap<ComparedCell, BTreeMap<String, Vec<(usize, f64)>>>;
/// Per pair of competitors: cells where the rank-sum test favours the first, the second, and the
/// cells where the rank-sum test can reach alpha at all.
type Wins = BTreeMap<(String, String), (usize, usize, usize)>;

/// The columns of `compare_cells.csv`.
const CELL_HEADER: [&str; 24] = [
    "data",
    "grid",
    "cn",
    "parameterisation",
    "x",
    "y",
    "n",
    "mean_x",
    "mean_y",
    "median_x",
    "median_y",
    "signed_rank_v",
    "signed_rank_p",
    "rank_sum_w",
    "rank_sum_p",
    "a12_x_better",
    "a12_magnitude",
    "h_signed_rank",
    "h_rank_sum",
    "min_p_signed_rank",
    "min_p_rank_sum",
    "can_reach_alpha",
    "better",
    "better_by",
];

/// Cell comparisons whose tests cannot reach alpha with their repeats: by the signed-rank test, by
/// the rank-sum test, of all comparisons, and the smallest (n, signed-rank min p, rank-sum min p)
/// among them.
#[derive(Default)]
struct Unreachable {
    signed_rank: usize,
    rank_sum: usize,
    of: usize,
    smallest: Option<(usize, f64, f64)>,
}

/// The rows of `results/runs.csv`, every one checked.
/// Refuse a finished folder that is not a run of an `[optimise]` spec (a `fit` folder, a Chapter
/// 4 or 5 run, a reproduction), saying what it is and which folders `compare` takes.
fn require_optimise_run(results: &std::path::Path) -> Result<()> {
    use crate::experiment::family::Families;
    let takes = "compare takes the folder of a finished run of a spec with an [optimise] section (Chapter 6), e.g. results/thesis/ch6_same";
    let shown = results.display();
    if results.join(crate::io::outdir::PLAN_FILE).exists() {
        anyhow::bail!("{shown} is a reproduction folder, not a Chapter 6 run; {takes} (one of its sub-folders)");
    }
    let manifest = results.join(crate::io::outdir::MANIFEST);
    if !manifest.exists() {
        return Ok(());
    }
    let id = crate::report::drift::Identity::read(&manifest)?;
    if id.is_fit() {
        anyhow::bail!("{shown} is a `somnurbs fit` folder, not a Chapter 6 (optimise) run; {takes}");
    }
    let spec: Option<toml::Table> = id.spec_text.as_deref().and_then(|t| toml::from_str(t).ok());
    let section = crate::families::Section::all()
        .iter()
        .find(|f| spec.as_ref().is_some_and(|s| s.contains_key(f.section())));
    match section {
        Some(f) if f.section() != "optimise" => anyhow::bail!(
            "{shown} is {} ([{}], {}), not a Chapter 6 (optimise) run; {takes}",
            id.describe(),
            f.section(),
            f.title()
        ),
        _ => Ok(()),
    }
}

fn read_runs(results: &std::path::Path) -> Result<Vec<OptimRow>> {
    let path = results.join("runs.csv");
    let text = crate::io::read_text(&path)?;
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let mut rows: Vec<OptimRow> = Vec::new();
    for (n, r) in reader.deserialize().enumerate() {
        rows.push(r.with_context(|| {
            format!("{}: line {}: not a Chapter 6 runs.csv row", path.display(), n + 2)
        })?);
    }
    if rows.is_empty() {
        anyhow::bail!("{}: no runs", path.display());
    }
    Ok(rows)
}

/// Which of x and y is better in one cell (minimisation), and on what grounds: the signed-rank
/// test when its p < alpha (x when W+ < W-, i.e. x - y mostly negative); else the rank-sum test when
/// its p < alpha (direction by A12); else A12 alone when its magnitude is not negligible (no test
/// significant); else none.
fn better(
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
/// the rank-sum test favours x (Some(true)), y (Some(false)) or neither at alpha.
fn cell_pair(
    k: &ComparedCell,
    (x, y): (&str, &str),
    (xa, xb): (&[f64], &[f64]),
    alpha: f64,
) -> (Vec<String>, Option<bool>, (bool, bool)) {
    let sr =
        if xa.len() == xb.len() { signed_rank(xa, xb, Alternative::TwoSided).ok() } else { None };
    let rs = rank_sum(xa, xb, Alternative::TwoSided).ok();
    let a12 = effect::a12_x_better(xa, xb);
    let min_sr = if xa.len() == xb.len() {
        Some(stats::wilcoxon::min_p_two_sided(xa.len()))
    } else {
        None
    };
    let min_rs = stats::rank_sum::min_p_two_sided(xa.len(), xb.len());
    let reach = (min_sr.is_some_and(|p| p < alpha), min_rs < alpha);
    let h = |p: Option<f64>| p.map(|p| if p < alpha { "1" } else { "0" }).unwrap_or("").to_string();
    let (b, by) = better(sr.as_ref(), rs.as_ref(), a12, alpha);
    let favours = rs.as_ref().filter(|r| r.p_value < alpha).map(|_| a12 > 0.5);
    let row = vec![
        k.data.clone(),
        k.grid.to_string(),
        k.cn.to_string(),
        k.param.clone(),
        x.to_string(),
        y.to_string(),
        xa.len().to_string(),
        num(stats::describe::mean_var(xa).0),
        num(stats::describe::mean_var(xb).0),
        num(stats::describe::median(xa)),
        num(stats::describe::median(xb)),
        sr.as_ref().map(|r| r.w_plus.to_string()).unwrap_or_default(),
        sr.as_ref().map(|r| format!("{:.6}", r.p_value)).unwrap_or_default(),
        rs.as_ref().map(|r| r.w.to_string()).unwrap_or_default(),
        rs.as_ref().map(|r| format!("{:.6}", r.p_value)).unwrap_or_default(),
        format!("{a12:.4}"),
        effect::magnitude(a12).to_string(),
        h(sr.as_ref().map(|r| r.p_value)),
        h(rs.as_ref().map(|r| r.p_value)),
        min_sr.map(|p| format!("{p:.6}")).unwrap_or_default(),
        format!("{min_rs:.6}"),
        match reach {
            (true, true) => "both",
            (true, false) => "signed_rank",
            (false, true) => "rank_sum",
            (false, false) => "neither",
        }
        .to_string(),
        b.to_string(),
        by.to_string(),
    ];
    (row, favours, reach)
}

/// The signed-rank and rank-sum tests and A12 of every pair in every cell (`compare_cells.csv`
/// rows), the cells where the rank-sum test favours each side, and the pairs that cannot reach
/// alpha with their repeats.
fn pairwise_cells(
    cells: &Cells,
    opts: &[String],
    alpha: f64,
) -> (Vec<Vec<String>>, Wins, Unreachable) {
    let mut out = Vec::new();
    let mut wins: Wins = BTreeMap::new();
    let mut unreachable = Unreachable::default();
    for (k, per) in cells {
        for i in 0..opts.len() {
            for j in i + 1..opts.len() {
                let (Some(a), Some(b)) = (per.get(&opts[i]), per.get(&opts[j])) else { continue };
                let mut a = a.clone();
                let mut b = b.clone();
                a.sort_by_key(|x| x.0);
                b.sort_by_key(|x| x.0);
                let xa: Vec<f64> = a.iter().map(|x| x.1).collect();
                let xb: Vec<f64> = b.iter().map(|x| x.1).collect();
                let (row, favours, reach) = cell_pair(k, (&opts[i], &opts[j]), (&xa, &xb), alpha);
                let e = wins.entry((opts[i].clone(), opts[j].clone())).or_default();
                match favours {
                    Some(true) => e.0 += 1,
                    Some(false) => e.1 += 1,
                    None => {}
                }
                unreachable.of += 1;
                unreachable.signed_rank += usize::from(!reach.0);
                unreachable.rank_sum += usize::from(!reach.1);
                e.2 += usize::from(reach.1);
                if !(reach.0 && reach.1) {
                    let n = xa.len().min(xb.len());
                    if unreachable.smallest.is_none_or(|s| n < s.0) {
                        let sr = stats::wilcoxon::min_p_two_sided(n);
                        unreachable.smallest = Some((n, sr, stats::rank_sum::min_p_two_sided(n, n)));
                    }
                }
                out.push(row);
            }
        }
    }
    (out, wins, unreachable)
}

/// The tests over cells: Friedman on the mean best of each optimiser, with Holm-adjusted pairwise
/// tests (`compare_overall.csv`, the critical-difference diagram), and the Bayesian signed-rank
/// test of every pair (`compare_bayes.csv`), with the summary on stdout. Returns the note naming
/// the diagram (empty without one).
fn over_cells(
    rows: &[OptimRow],
    opts: &[String],
    wins: &Wins,
    args: &CompareArgs,
    out: &std::path::Path,
) -> Result<String> {
    let (_, table) = friedman_table(rows);
    let f = friedman(&table)
        .with_context(|| format!("{}: Friedman test", args.results.join("runs.csv").display()))?;
    let oh: Vec<String> = [
        "x",
        "y",
        "mean_rank_x",
        "mean_rank_y",
        "z",
        "p",
        "p_holm",
        "cells_x_better",
        "cells_y_better",
        "cells_rank_sum_can_reach_alpha",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let orows: Vec<Vec<String>> = f
        .pairwise
        .iter()
        .map(|&(i, j, z, p, ph)| {
            let w =
                wins.get(&(opts[i].clone(), opts[j].clone())).copied().unwrap_or((0, 0, 0));
            vec![
                opts[i].clone(),
                opts[j].clone(),
                format!("{:.4}", f.mean_ranks[i]),
                format!("{:.4}", f.mean_ranks[j]),
                format!("{z:.4}"),
                format!("{p:.6}"),
                format!("{ph:.6}"),
                w.0.to_string(),
                w.1.to_string(),
                w.2.to_string(),
            ]
        })
        .collect();
    write_atomic(&out.join("compare_overall.csv"), csv_records(&oh, &orows)?.as_bytes())?;
    let ranks: Vec<(String, f64)> =
        opts.iter().cloned().zip(f.mean_ranks.iter().copied()).collect();
    let mut cd_note = String::new();
    if let Some(cd) = f.critical_difference {
        let png = out.join("cd_diagram.png");
        match plots::cd_diagram_png(
            &png,
            &format!("Mean ranks over {} cells (Nemenyi CD = {cd:.3}, alpha 0.05)", f.blocks),
            &ranks,
            cd,
        ) {
            Ok(()) => cd_note = ", critical-difference diagram cd_diagram.png".into(),
            Err(e) => chart_skipped(e)?,
        }
    }
    println!(
        "Friedman over {} cells x {} optimisers: chi-squared {:.3}, df {}, p = {:.3e}",
        f.blocks, f.treatments, f.chi_squared, f.df, f.p_value
    );
    for (o, r) in &ranks {
        println!("  mean rank {o:<5} {r:.3}");
    }
    for row in &orows {
        println!("  {} vs {}: z {}, p {} (Holm {}); cells where the rank-sum test favours {}: {}, {}: {} (of {} where it can reach alpha)", row[0], row[1], row[4], row[5], row[6], row[0], row[7], row[1], row[8], row[9]);
    }
    let brows = bayes_table(rows, opts, args)?;
    let bh: Vec<String> =
        ["x", "y", "cells", "rope", "samples", "p_x_better", "p_rope", "p_y_better"]
            .iter()
            .map(|s| s.to_string())
            .collect();
    write_atomic(&out.join("compare_bayes.csv"), csv_records(&bh, &brows)?.as_bytes())?;
    for r in &brows {
        println!("  Bayesian signed-rank {} vs {} over {} cells (rope {} of B's error): P({} better) {}, P(equivalent) {}, P({} better) {}", r[0], r[1], r[2], r[3], r[0], r[5], r[6], r[1], r[7]);
    }
    Ok(cd_note)
}

/// Runtime distributions from the IOHprofiler traces: the tables and the charts, overall and per
/// problem. Returns what it wrote, for the closing line.
fn runtime_outputs(
    probs: &[Problem],
    opts: &[String],
    results: &std::path::Path,
) -> Result<String> {
    let rt = runtime(probs, opts);
    write_runtime_tables(&rt, probs, results)?;
    let mut written = String::from(", compare_ecdf.csv, compare_aocc.csv, compare_fixed_budget.csv, compare_ert.csv, compare_targets.csv");
    let groups: Vec<String> =
        std::iter::once("all".to_string()).chain(probs.iter().map(|p| p.name.clone())).collect();
    let mut pngs = 0;
    crate::io::ensure_dir(&results.join("png").join("compare"))?;
    for g in &groups {
        let dir =
            if g == "all" { results.to_path_buf() } else { results.join("png").join("compare") };
        match render_ecdf(&rt, g, opts, &dir.join(format!("compare_ecdf_{g}.png"))) {
            Ok(()) => pngs += 1,
            Err(e) => chart_skipped(e)?,
        }
        let png = dir.join(format!("compare_fixed_budget_{g}.png"));
        match render_fixed_budget(&rt, g, opts, &png) {
            Ok(true) => pngs += 1,
            Ok(false) => println!("  no fixed-budget chart of {g}: {NO_GAP}"),
            Err(e) => chart_skipped(e)?,
        }
    }
    let moved: Vec<&Problem> = probs.iter().filter(|p| p.rule != "b_to_best_known").collect();
    if !moved.is_empty() {
        println!(
            "  targets: in {} of {} problems no run beats approach B; their targets start at a first value of a run (rule in compare_targets.csv)",
            moved.len(),
            probs.len()
        );
    }
    for e in rt.ecdf.iter().filter(|r| r.group == "all") {
        println!(
            "  runtime ECDF all {}: AOCC {:.4}, mean over {} problems weighing the same ({} (run, target) pairs), budget {}",
            e.optimiser, e.aocc, e.problems, e.pairs, rt.budget
        );
    }
    written.push_str(&format!(", {pngs} runtime charts (compare_ecdf_all.png, compare_fixed_budget_all.png, per problem in png/compare/)"));
    Ok(written)
}

/// A chart that could not be made: one that cannot be drawn from its data is skipped with a
/// warning; a file that could not be written (a full disk, a folder that vanished) stops compare.
fn chart_skipped(e: plots::PlotError) -> Result<()> {
    if let plots::PlotError::Io { .. } = e {
        // Its message already holds the cause (no chain, or the cause would be said twice).
        anyhow::bail!("{e}");
    }
    eprintln!("somnurbs: warning: picture skipped: {e}");
    Ok(())
}

/// `--bayes-samples`: Monte Carlo samples of the Bayesian signed-rank test (below the lower
/// bound its probabilities move in the second digit; above the upper one a run takes minutes).
pub(crate) const MIN_BAYES_SAMPLES: usize = 1_000;
pub(crate) const MAX_BAYES_SAMPLES: usize = 10_000_000;

/// The options' ranges, before anything is read: `--alpha` in (0, 1), `--rope` finite and >= 0,
/// `--bayes-samples` in [[`MIN_BAYES_SAMPLES`], [`MAX_BAYES_SAMPLES`]].
fn check_args(args: &CompareArgs) -> Result<()> {
    if !(args.alpha > 0.0 && args.alpha < 1.0) {
        anyhow::bail!("--alpha must be a number in (0, 1), got {}", args.alpha);
    }
    if !(args.rope >= 0.0 && args.rope.is_finite()) {
        anyhow::bail!("--rope must be finite and >= 0, got {}", args.rope);
    }
    if !(MIN_BAYES_SAMPLES..=MAX_BAYES_SAMPLES).contains(&args.bayes_samples) {
        anyhow::bail!(
            "--bayes-samples must be in [{MIN_BAYES_SAMPLES}, {MAX_BAYES_SAMPLES}], got {}",
            args.bayes_samples
        );
    }
    Ok(())
}

/// `somnurbs compare`: pairwise tests per cell, Friedman and Bayesian tests over cells, runtime
/// distributions from the traces; tables into the folder, a summary on stdout.
pub(crate) fn compare(args: &CompareArgs) -> Result<()> {
    check_args(args)?;
    if !args.results.is_dir() {
        anyhow::bail!(
            "{}: not found (no such results folder)",
            args.results.join("runs.csv").display()
        );
    }
    // Only a finished, whole run is compared, and one compare at a time per results folder.
    crate::io::outdir::require_finished(&args.results, "the results folder")?;
    require_optimise_run(&args.results)?;
    let _lock = crate::io::outdir::lock(&args.results, "compare")?;
    let dest = args.out.clone().unwrap_or_else(|| args.results.join(OUT_DIR));
    let stale = check_destination(args, &dest)?;
    require_compare_folder(&dest)?;
    let rows = read_runs(&args.results)?;
    let traced = args.results.join("ioh").is_dir();
    // What the folder itself certifies: the exact solver's optimum and lower bound per problem.
    let certified = if traced || !args.external.is_empty() {
        certificates(&args.results)?
    } else {
        BTreeMap::new()
    };
    // Optimisers from outside somnurbs (issue 39), matched and checked first: external.rs.
    let (rows, external) =
        super::external::join(&args.results, &args.external, rows, &certified)?;
    let mut opts: Vec<String> = Vec::new();
    let mut cells: Cells = BTreeMap::new();
    for r in &rows {
        if !opts.contains(&r.competitor()) {
            opts.push(r.competitor());
        }
        cells.entry(r.compared_cell()).or_default().entry(r.competitor()).or_default().push((r.repeat, r.best));
    }
    if opts.len() < 2 {
        anyhow::bail!(
            "{}: only one optimiser ({}); nothing to compare",
            args.results.join("runs.csv").display(),
            opts[0]
        );
    }
    // The traces first, so that a folder whose ioh/ does not match runs.csv gets nothing written.
    let probs = if traced {
        Some(problems(&rows, &args.results, external, &certified)?)
    } else {
        None
    };
    if let Some(line) = coverage_note(&cells, &opts) {
        eprintln!("somnurbs: warning: {line}");
    }
    let (cell_rows, wins, unreachable) = pairwise_cells(&cells, &opts, args.alpha);
    if let Some((n, sr, rs)) = unreachable.smallest {
        eprintln!("somnurbs: warning: of {} cell comparisons, {} cannot reach alpha {} by the signed-rank test and {} by the rank-sum test with their repeats (with {n} repeats a two-sided p is at least {sr} signed-rank, {rs} rank-sum): there h is 0 and no cell is favoured whatever the data (compare_cells.csv: min_p_signed_rank, min_p_rank_sum, can_reach_alpha)", unreachable.of, unreachable.signed_rank, args.alpha, unreachable.rank_sum);
    }
    crate::io::outdir::remove_stale(&stale, &dest, "compare")?;
    // Built whole in a sibling folder and swapped in: a reader sees the old tables or the new, and
    // any failed write (a table or a chart) leaves the old folder as it was.
    let common = cells.values().filter(|per| ran_by_all(per, &opts)).count();
    let tables = Tables { rows: &rows, opts: &opts, cells: common, cell_rows, wins };
    crate::io::outdir::replace_dir(&dest, |out| {
        write_folder(args, &tables, probs.as_deref(), out)
            .with_context(|| format!("{} left as it was", dest.display()))
    })
}

/// Where some optimiser did not run every cell (an external logged on part of the problems): one
/// line naming each such optimiser's count and what the statistics over cells use; None when
/// every optimiser ran every cell.
fn coverage_note(cells: &Cells, opts: &[String]) -> Option<String> {
    let ran = |o: &String| cells.values().filter(|per| per.contains_key(o)).count();
    let partial: Vec<String> = opts
        .iter()
        .filter(|o| ran(o) < cells.len())
        .map(|o| format!("{o} ran {} of {}", ran(o), cells.len()))
        .collect();
    if partial.is_empty() {
        return None;
    }
    let common = cells.values().filter(|per| ran_by_all(per, opts)).count();
    Some(format!(
        "not every optimiser ran every cell ({}): the tests over cells (Friedman, the critical-difference diagram, the Bayesian signed-rank test) and the runtime aggregate `all` use the {common} cells every optimiser ran; the per-cell tests and per-problem runtime tables use each pair's or optimiser's own",
        partial.join(", ")
    ))
}

/// What `compare` writes, computed before anything is written.
struct Tables<'a> {
    rows: &'a [OptimRow],
    opts: &'a [String],
    /// How many cells every optimiser ran (what the tests over cells use).
    cells: usize,
    cell_rows: Vec<Vec<String>>,
    wins: Wins,
}

/// Write every table and chart of `compare` into `out` (the staged folder), the record last.
fn write_folder(
    args: &CompareArgs,
    t: &Tables,
    probs: Option<&[Problem]>,
    out: &std::path::Path,
) -> Result<()> {
    let header: Vec<String> = CELL_HEADER.iter().map(|s| s.to_string()).collect();
    write_atomic(&out.join("compare_cells.csv"), csv_records(&header, &t.cell_rows)?.as_bytes())?;
    let (cd_note, mut written) = if t.cells >= 2 {
        (over_cells(t.rows, t.opts, &t.wins, args, out)?, String::from("compare_cells.csv, compare_overall.csv, compare_bayes.csv"))
    } else {
        println!("  {} cell(s) that every optimiser ran: the tests over cells (Friedman, Nemenyi, Bayesian signed-rank) need two or more; the per-cell tests are in compare_cells.csv", t.cells);
        (String::new(), String::from("compare_cells.csv"))
    };
    if let Some(probs) = probs {
        written.push_str(&runtime_outputs(probs, t.opts, out)?);
    } else {
        println!("  no ioh/ folder: runtime distributions skipped");
    }
    // Last: the record that makes the folder a compare's (a later compare may replace it).
    let record = format!(
        "results = {:?}\nalpha = {:?}\nrope = {:?}\nbayes_samples = {}\nsomnurbs = {:?}\n",
        args.results.display().to_string(),
        args.alpha,
        args.rope,
        args.bayes_samples,
        env!("CARGO_PKG_VERSION")
    );
    write_atomic(&out.join(RECORD), record.as_bytes())?;
    let dest = args.out.clone().unwrap_or_else(|| args.results.join(OUT_DIR));
    println!("wrote {written}{cd_note} in {}", dest.display());
    Ok(())
}

/// `path` made absolute, with the links of its nearest existing ancestor resolved and the rest
/// (which need not exist yet) taken as written; and that ancestor.
fn resolved(path: &std::path::Path) -> Result<(PathBuf, PathBuf)> {
    use std::path::Component;
    let cwd = std::env::current_dir().context("cannot read the working folder")?;
    let abs = cwd.join(path);
    let (anchor, rest) = abs
        .ancestors()
        .find_map(|a| Some((std::fs::canonicalize(a).ok()?, abs.strip_prefix(a).ok()?)))
        .with_context(|| format!("{}: no part of it exists", path.display()))?;
    let mut full = anchor.clone();
    for c in rest.components() {
        match c {
            Component::Normal(n) => full.push(n),
            Component::ParentDir => {
                full.pop();
            }
            _ => {}
        }
    }
    Ok((anchor, full))
}

/// Refuse a destination that lies inside a result folder (a run, shard, plan or `fit` folder;
/// compare's own default, `RESULTS/compare`, aside) and an `--external` folder inside the
/// destination (the swap would delete what was read) or inside a folder an interrupted compare
/// left beside it (removed before the swap). Returns those leftovers: the temporary siblings of
/// the destination whose process is gone.
fn check_destination(args: &CompareArgs, dest: &std::path::Path) -> Result<Vec<PathBuf>> {
    let (anchor, full) = resolved(dest)?;
    let default = resolved(&args.results.join(OUT_DIR))?.1;
    if full != default {
        if let Some(folder) = crate::io::outdir::result_folder_of(&anchor.join(OUT_DIR)) {
            anyhow::bail!("compare --out {} is inside the result folder {}, which holds one run and nothing else: give --out a folder outside it (or no --out, for {})", dest.display(), folder.display(), args.results.join(OUT_DIR).display());
        }
    }
    let stale = match full.parent() {
        Some(_) => crate::io::outdir::stale_siblings(&full)?,
        None => Vec::new(),
    };
    for ext in &args.external {
        let e = resolved(ext)?.1;
        if e.starts_with(&full) {
            anyhow::bail!("compare --external {} is inside {}, the folder compare replaces: move the logs out of it first", ext.display(), dest.display());
        }
        if let Some(s) = stale.iter().find(|s| e.starts_with(s)) {
            anyhow::bail!("compare --external {} is inside {}, a folder an interrupted compare left (removed before {} is written): move the logs out of it first", ext.display(), s.display(), dest.display());
        }
    }
    Ok(stale)
}

/// The folder `compare` writes into by default, inside the results folder it compares.
pub(crate) const OUT_DIR: &str = "compare";
/// The record `compare` writes last in its folder (what it compared, with which options).
const RECORD: &str = "compare.toml";

/// `compare` writes a folder of its own: missing, empty, or an earlier compare's (which it
/// replaces whole); anything else is refused.
fn require_compare_folder(dest: &std::path::Path) -> Result<()> {
    let found = crate::io::outdir::entries(dest)?;
    if found.is_empty() || found.iter().any(|e| e == RECORD) {
        return Ok(());
    }
    crate::io::outdir::require_empty(dest).context("compare --out")
}

/// Targets per problem: this many, log-spaced over this many decades of the gap between the
/// range's start (approach B's error, or where nothing beats B the best first value of a run: see
/// [`stats::runtime::target_range`]) and the best known value (the last target is the best known
/// value itself).
const TARGETS: usize = 16;
const TARGET_DECADES: f64 = 3.0;
/// Budgets at which the ECDF and the fixed-budget values are tabulated (log-spaced).
const BUDGETS: usize = 40;

/// (problem, optimiser, target index, target, hits, runs, ERT)
type ErtRow = (String, String, usize, f64, usize, usize, f64);
/// A run's (evaluations, improvement rows).
type RunTrace = (u64, Vec<(u64, f64)>);
/// Per cell: approach B's error and per optimiser (sum of best errors, runs).
type CellSums = (f64, BTreeMap<String, (f64, usize)>);

/// One problem (data set, grid, net, parameterisation) as the runtime distributions see it.
struct Problem {
    name: String,
    b: f64,
    best_known: f64,
    /// Where `best_known` comes from, in words (`compare_targets.csv`'s `best_known_from`).
    from: String,
    /// The start of the targets' range (the fixed-budget gap's reference), None when no run ever
    /// improved, and the rule that chose it.
    reference: Option<f64>,
    rule: &'static str,
    targets: Vec<f64>,
    /// Per optimiser, its runs' (evaluations, improvements).
    runs: BTreeMap<String, Vec<RunTrace>>,
}

/// One ECDF (a problem's, or "all": the mean of an optimiser's per-problem ECDFs, each problem
/// weighing the same).
struct EcdfRow {
    group: String,
    optimiser: String,
    /// At each budget.
    values: Vec<f64>,
    aocc: f64,
    /// (run, target) pairs behind it, and problems.
    pairs: usize,
    problems: usize,
}

/// One fixed-budget curve: at each budget the mean over runs of (best - best known) /
/// (reference - best known), the reference being the start of the problem's targets (approach B's error where
/// something beats it); None when the denominator is zero (then `note` says why). For "all" the
/// mean of the per-problem curves, each problem weighing the same.
struct GapRow {
    group: String,
    optimiser: String,
    values: Option<Vec<f64>>,
    runs: usize,
    problems: usize,
    rule: String,
    note: String,
}

/// What the runtime-distribution tables and charts show, computed before anything is written.
struct Runtime {
    budget: u64,
    budgets: Vec<u64>,
    ecdf: Vec<EcdfRow>,
    fixed_budget: Vec<GapRow>,
    /// Targets per problem, for the charts' titles ("16 targets per problem", or the counts).
    targets_desc: String,
    /// Per problem, optimiser and target.
    ert: Vec<ErtRow>,
    /// The problems "all" aggregates, in words for the titles: "problems " when every optimiser
    /// ran every problem, else "problems every optimiser ran ".
    common_desc: String,
}

/// The certificates of a folder's `exact_<grid>.csv` tables (the exact solver's optimum and its
/// proven lower bound), by problem name: what the folder itself certifies.
pub(crate) fn certificates(folder: &std::path::Path) -> Result<BTreeMap<String, Certificate>> {
    let mut out = BTreeMap::new();
    let Ok(entries) = std::fs::read_dir(folder) else { return Ok(out) };
    let mut tables: Vec<(std::path::PathBuf, String)> = entries
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let grid = name.strip_prefix("exact_")?.strip_suffix(".csv")?.to_string();
            Some((e.path(), grid))
        })
        .collect();
    tables.sort();
    for (p, grid) in tables {
        let text = crate::io::read_text(&p)?;
        let mut r = csv::Reader::from_reader(text.as_bytes());
        for (n, rec) in r.deserialize::<BTreeMap<String, String>>().enumerate() {
            let rec = rec.with_context(|| format!("{}: line {}", p.display(), n + 2))?;
            let get = |k: &str| {
                rec.get(k)
                    .with_context(|| format!("{}: line {}: no column {k}", p.display(), n + 2))
            };
            let value = |k: &str| -> Result<f64> {
                get(k)?.parse::<f64>().ok().filter(|v| v.is_finite()).with_context(|| {
                    format!("{}: line {}: {k} is not a number", p.display(), n + 2)
                })
            };
            let key = super::ioh::problem_name(
                get("data")?,
                &grid,
                &format!("{}x{}", get("cn_x")?, get("cn_y")?),
                get("parameterisation")?,
            );
            let c = Certificate {
                optimum: value("exact_f")?,
                lower_bound: value("lower_bound")?,
                table: p.clone(),
            };
            out.insert(key, c);
        }
    }
    Ok(out)
}

/// Gather the problems from runs.csv and the folder's `ioh/` traces (which must list the same runs
/// with the same evaluation counts and final values).
fn problems(
    rows: &[OptimRow],
    folder: &std::path::Path,
    external: Vec<super::ioh::LoadedProblem>,
    certified: &BTreeMap<String, Certificate>,
) -> Result<Vec<Problem>> {
    let name = |r: &OptimRow| {
        super::ioh::problem_name(
            &r.dataset,
            &format!("{}x{}", r.grid_x, r.grid_y),
            &format!("{}x{}", r.cn_x, r.cn_y),
            &r.parameterisation,
        )
    };
    let mut expected: BTreeMap<(String, String), Vec<&OptimRow>> = BTreeMap::new();
    for r in rows {
        expected.entry((name(r), r.competitor())).or_default().push(r);
    }
    let mut out: BTreeMap<String, Problem> = BTreeMap::new();
    for lp in super::ioh::read(folder)?.into_iter().chain(external) {
        let mut exp = expected
            .remove(&(lp.function_name.clone(), lp.optimiser.clone()))
            .with_context(|| {
                format!(
                    "{}: ioh/{} has problem {} that runs.csv does not",
                    folder.display(),
                    lp.optimiser,
                    lp.function_name
                )
            })?;
        exp.sort_by_key(|r| r.repeat);
        let agree = exp.len() == lp.runs.len()
            && exp.iter().zip(&lp.runs).all(|(r, (e, imp))| {
                *e == r.evaluations
                    && imp.iter().map(|x| x.1).fold(f64::INFINITY, f64::min) == r.best
            });
        if !agree {
            anyhow::bail!("{}: ioh/{} problem {}: the traces do not match runs.csv (runs, evaluations or final values differ; written by another run?)", folder.display(), lp.optimiser, lp.function_name);
        }
        let p = out.entry(lp.function_name.clone()).or_insert_with(|| Problem {
            name: lp.function_name.clone(),
            b: exp[0].b,
            best_known: f64::INFINITY,
            from: String::new(),
            reference: None,
            rule: "none",
            targets: Vec::new(),
            runs: BTreeMap::new(),
        });
        p.runs.insert(lp.optimiser, lp.runs);
    }
    if let Some(((p, o), _)) = expected.into_iter().next() {
        anyhow::bail!("{}: runs.csv has {o} on {p} but ioh/ has no trace of it", folder.display());
    }
    for (pn, p) in out.iter_mut() {
        let best_run = rows
            .iter()
            .filter(|r| &name(r) == pn)
            .min_by(|a, b| a.best.total_cmp(&b.best).then(a.repeat.cmp(&b.repeat)));
        (p.best_known, p.from) = best_known(best_run, certified.get(pn));
        let firsts: Vec<f64> =
            p.runs.values().flatten().filter_map(|r| r.1.first().map(|x| x.1)).collect();
        (p.reference, p.rule) = stats::runtime::target_range(p.b, p.best_known, &firsts);
        p.targets = match p.reference {
            Some(start) => {
                stats::runtime::log_targets(start, p.best_known, TARGETS, TARGET_DECADES)
            }
            None => vec![p.best_known],
        };
    }
    Ok(out.into_values().collect())
}

/// The best known value of a problem and its provenance: the exact solver's `f` (the upper end of
/// its certified interval [lower_bound, f]) unless a run ended below it (within the certified
/// gap), then that run, named.
fn best_known(best_run: Option<&OptimRow>, cert: Option<&Certificate>) -> (f64, String) {
    let run = |r: &OptimRow| format!("best run ({} repeat {})", r.competitor(), r.repeat);
    match (best_run, cert) {
        (Some(r), Some(c)) if r.best < c.optimum => (
            r.best,
            format!("{}, below the exact solver's f, within its certified gap", run(r)),
        ),
        (_, Some(c)) => (c.optimum, "certified optimum (the exact solver's f)".into()),
        (Some(r), None) => (r.best, run(r)),
        (None, None) => (f64::INFINITY, "none".into()),
    }
}

/// Targets per problem in words: "16 targets each", or "16 targets each (1 in 2)"
/// where some problems have another count.
fn targets_desc(problems: &[Problem]) -> String {
    let mut counts: BTreeMap<usize, usize> = BTreeMap::new();
    for p in problems {
        *counts.entry(p.targets.len()).or_default() += 1;
    }
    let others: Vec<String> = counts
        .iter()
        .filter(|(k, _)| **k != TARGETS)
        .map(|(k, n)| format!("{k} in {n}"))
        .collect();
    if others.is_empty() {
        format!("{TARGETS} targets each")
    } else {
        format!("{TARGETS} targets each ({})", others.join(", "))
    }
}

/// Why a problem has no fixed-budget gap.
const NO_GAP: &str = "left out: no run improved on its first value (zero denominator)";

/// One problem's curves for one optimiser: its ECDF row, its fixed-budget row, its ERT rows.
fn problem_runtime(
    p: &Problem,
    o: &str,
    runs: &[RunTrace],
    budgets: &[u64],
    budget: u64,
) -> (EcdfRow, GapRow, Vec<ErtRow>) {
    use stats::runtime::{aocc, ecdf, ert, hitting_times, Trace};
    let ts: Vec<Trace> =
        runs.iter().map(|(e, imp)| Trace { improvements: imp, evaluations: *e }).collect();
    let times = hitting_times(&ts, &p.targets);
    let e = EcdfRow {
        group: p.name.clone(),
        optimiser: o.to_string(),
        values: ecdf(&times, budgets),
        aocc: aocc(&times, budget),
        pairs: times.len(),
        problems: 1,
    };
    let values = p.reference.map(|r| {
        let span = r - p.best_known;
        budgets
            .iter()
            .map(|&b| {
                ts.iter().map(|t| (t.best_at(b) - p.best_known) / span).sum::<f64>()
                    / ts.len().max(1) as f64
            })
            .collect()
    });
    let g = GapRow {
        group: p.name.clone(),
        optimiser: o.to_string(),
        note: if values.is_some() { String::new() } else { NO_GAP.to_string() },
        values,
        runs: ts.len(),
        problems: 1,
        rule: p.rule.to_string(),
    };
    let ert_rows = p
        .targets
        .iter()
        .enumerate()
        .map(|(k, &t)| {
            let (e, hits) = ert(&ts, t);
            (p.name.clone(), o.to_string(), k, t, hits, ts.len(), e)
        })
        .collect();
    (e, g, ert_rows)
}

/// Compute every runtime table: per optimiser, per problem and over all problems ("all": every
/// problem the optimiser ran weighing the same, as IOHanalyzer and COCO aggregate over functions).
fn runtime(problems: &[Problem], opts: &[String]) -> Runtime {
    let budget =
        problems.iter().flat_map(|p| p.runs.values().flatten().map(|r| r.0)).max().unwrap_or(1);
    let budgets = stats::runtime::log_budgets(budget, BUDGETS);
    let mut rt = Runtime {
        budget,
        budgets: budgets.clone(),
        ecdf: Vec::new(),
        fixed_budget: Vec::new(),
        targets_desc: targets_desc(problems),
        ert: Vec::new(),
        common_desc: "problems ".into(),
    };
    if problems.iter().any(|p| opts.iter().any(|o| !p.runs.contains_key(o))) {
        rt.common_desc = "problems every optimiser ran ".into();
    }
    // "all" aggregates the problems every optimiser ran (all of them unless an external ran part),
    // so that every optimiser's aggregate is over the same problems.
    let common = |p: &Problem| opts.iter().all(|o| p.runs.contains_key(o));
    let any_common = problems.iter().any(common);
    for o in opts {
        let (mut es, mut gs) = (Vec::new(), Vec::new());
        let (mut own_e, mut own_g) = (Vec::new(), Vec::new());
        for p in problems {
            let Some(runs) = p.runs.get(o) else { continue };
            let (e, g, ert_rows) = problem_runtime(p, o, runs, &budgets, budget);
            rt.ert.extend(ert_rows);
            if common(p) || !any_common {
                es.push(e);
                gs.push(g);
            } else {
                own_e.push(e);
                own_g.push(g);
            }
        }
        if es.is_empty() {
            rt.ecdf.extend(own_e);
            rt.fixed_budget.extend(own_g);
            continue;
        }
        let curves: Vec<&[f64]> = es.iter().map(|e| e.values.as_slice()).collect();
        let all = EcdfRow {
            group: "all".into(),
            optimiser: o.clone(),
            values: stats::runtime::mean_curve(&curves),
            aocc: es.iter().map(|e| e.aocc).sum::<f64>() / es.len() as f64,
            pairs: es.iter().map(|e| e.pairs).sum(),
            problems: es.len(),
        };
        let with: Vec<&GapRow> = gs.iter().filter(|g| g.values.is_some()).collect();
        let curves: Vec<&[f64]> = with.iter().filter_map(|g| g.values.as_deref()).collect();
        let left_out = gs.len() - with.len();
        let all_gap = GapRow {
            group: "all".into(),
            optimiser: o.clone(),
            values: (!curves.is_empty()).then(|| stats::runtime::mean_curve(&curves)),
            runs: with.iter().map(|g| g.runs).sum(),
            problems: with.len(),
            rule: "per problem".into(),
            note: match (with.len(), left_out) {
                (0, _) => NO_GAP.to_string(),
                (_, 0) => "mean over problems, equal weight".to_string(),
                (_, k) => format!("mean over problems, equal weight; {k} {NO_GAP}"),
            },
        };
        rt.ecdf.extend(es);
        rt.ecdf.extend(own_e);
        rt.ecdf.push(all);
        rt.fixed_budget.extend(gs);
        rt.fixed_budget.extend(own_g);
        rt.fixed_budget.push(all_gap);
    }
    rt
}

fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else if v.is_nan() {
        "nan".into()
    } else {
        "inf".into()
    }
}

/// How an ECDF row weighs its (run, target) pairs.
fn weighting(e: &EcdfRow) -> &'static str {
    if e.group == "all" {
        "problems_equal"
    } else {
        "pairs_equal"
    }
}

/// Write the runtime tables (CSV).
fn write_runtime_tables(
    rt: &Runtime,
    problems: &[Problem],
    folder: &std::path::Path,
) -> Result<()> {
    let h = |v: &[&str]| -> Vec<String> { v.iter().map(|s| s.to_string()).collect() };
    let mut rows = Vec::new();
    for e in &rt.ecdf {
        for (b, v) in rt.budgets.iter().zip(&e.values) {
            rows.push(vec![
                e.group.clone(),
                e.optimiser.clone(),
                b.to_string(),
                format!("{v:.6}"),
                e.pairs.to_string(),
                e.problems.to_string(),
                weighting(e).to_string(),
            ]);
        }
    }
    let eh = ["group", "optimiser", "evaluations", "ecdf", "pairs", "problems", "weighting"];
    write_atomic(&folder.join("compare_ecdf.csv"), csv_records(&h(&eh), &rows)?.as_bytes())?;
    let rows: Vec<Vec<String>> = rt
        .ecdf
        .iter()
        .map(|e| {
            vec![
                e.group.clone(),
                e.optimiser.clone(),
                e.pairs.to_string(),
                e.problems.to_string(),
                weighting(e).to_string(),
                rt.budget.to_string(),
                format!("{:.6}", e.aocc),
            ]
        })
        .collect();
    let ah = ["group", "optimiser", "pairs", "problems", "weighting", "budget", "aocc"];
    write_atomic(&folder.join("compare_aocc.csv"), csv_records(&h(&ah), &rows)?.as_bytes())?;
    let mut rows = Vec::new();
    for g in &rt.fixed_budget {
        for (k, b) in rt.budgets.iter().enumerate() {
            rows.push(vec![
                g.group.clone(),
                g.optimiser.clone(),
                b.to_string(),
                g.values.as_ref().map(|v| num(v[k])).unwrap_or_default(),
                g.runs.to_string(),
                g.problems.to_string(),
                g.rule.clone(),
                g.note.clone(),
            ]);
        }
    }
    let fh = [
        "group",
        "optimiser",
        "evaluations",
        "mean_normalised_gap",
        "runs",
        "problems",
        "rule",
        "note",
    ];
    write_atomic(&folder.join("compare_fixed_budget.csv"), csv_records(&h(&fh), &rows)?.as_bytes())?;
    write_ert_and_targets(rt, problems, folder)
}

/// `compare_ert.csv` and `compare_targets.csv`.
fn write_ert_and_targets(
    rt: &Runtime,
    problems: &[Problem],
    folder: &std::path::Path,
) -> Result<()> {
    let h = |v: &[&str]| -> Vec<String> { v.iter().map(|s| s.to_string()).collect() };
    let rows: Vec<Vec<String>> = rt
        .ert
        .iter()
        .map(|(g, o, k, t, hits, n, e)| {
            vec![
                g.clone(),
                o.clone(),
                k.to_string(),
                num(*t),
                hits.to_string(),
                n.to_string(),
                num(*e),
            ]
        })
        .collect();
    write_atomic(
        &folder.join("compare_ert.csv"),
        csv_records(
            &h(&["problem", "optimiser", "target_index", "target", "hits", "runs", "ert"]),
            &rows,
        )?
        .as_bytes(),
    )?;
    let rows: Vec<Vec<String>> = problems
        .iter()
        .map(|p| {
            vec![
                p.name.clone(),
                num(p.b),
                num(p.best_known),
                p.from.clone(),
                p.rule.to_string(),
                p.reference.map(num).unwrap_or_default(),
                p.targets.len().to_string(),
                p.targets.iter().map(|t| num(*t)).collect::<Vec<_>>().join(" "),
            ]
        })
        .collect();
    let th = [
        "problem",
        "b",
        "best_known",
        "best_known_from",
        "rule",
        "reference",
        "n_targets",
        "targets",
    ];
    write_atomic(&folder.join("compare_targets.csv"), csv_records(&h(&th), &rows)?.as_bytes())?;
    Ok(())
}

fn series_of(
    rt_rows: &[(String, String, Vec<f64>)],
    group: &str,
    budgets: &[u64],
    opts: &[String],
) -> Vec<plots::Series> {
    use crate::report::plots::style;
    opts.iter()
        .filter_map(|o| {
            let (_, _, v) = rt_rows.iter().find(|r| r.0 == group && &r.1 == o)?;
            Some(plots::Series {
                label: o.clone(),
                colour: style::series_colour(o, opts),
                points: budgets.iter().zip(v).map(|(b, y)| ((*b as f64).log10(), *y)).collect(),
                band: None,
            })
        })
        .collect()
}

/// The problems behind group `group`'s curves (1 for a problem, the most any optimiser ran for
/// "all").
fn group_problems<'a>(counts: impl Iterator<Item = (&'a str, usize)>, group: &str) -> usize {
    counts.filter(|(g, _)| *g == group).map(|(_, n)| n).max().unwrap_or(0)
}

/// The ECDF chart of one group.
fn render_ecdf(
    rt: &Runtime,
    group: &str,
    opts: &[String],
    path: &std::path::Path,
) -> Result<(), plots::PlotError> {
    let rows: Vec<(String, String, Vec<f64>)> =
        rt.ecdf.iter().map(|r| (r.group.clone(), r.optimiser.clone(), r.values.clone())).collect();
    let title = if group == "all" {
        let n = group_problems(rt.ecdf.iter().map(|e| (e.group.as_str(), e.problems)), group);
        format!("all: mean ECDF of {n} {}(equal weight), {}", rt.common_desc, rt.targets_desc)
    } else {
        format!("{group}: share of (run, target) pairs reached")
    };
    plots::line_chart_png(
        path,
        &title,
        "log10 evaluations",
        "fraction of (run, target) pairs",
        &series_of(&rows, group, &rt.budgets, opts),
        false,
    )
}

/// The fixed-budget chart of one group (Ok(false): no optimiser has a gap there, nothing drawn).
fn render_fixed_budget(
    rt: &Runtime,
    group: &str,
    opts: &[String],
    path: &std::path::Path,
) -> Result<bool, plots::PlotError> {
    let rows: Vec<(String, String, Vec<f64>)> = rt
        .fixed_budget
        .iter()
        .filter_map(|r| Some((r.group.clone(), r.optimiser.clone(), r.values.clone()?)))
        .collect();
    let series = series_of(&rows, group, &rt.budgets, opts);
    if series.is_empty() {
        return Ok(false);
    }
    let title = if group == "all" {
        let n = group_problems(
            rt.fixed_budget.iter().map(|g| (g.group.as_str(), g.problems)),
            group,
        );
        format!("all: mean normalised gap of {n} {}(equal weight)", rt.common_desc)
    } else {
        let rule = rt.fixed_budget.iter().find(|g| g.group == group).map(|g| g.rule.as_str());
        let reference = match rule {
            Some("b_to_best_known") => "B's error",
            Some("best_first_to_best_known") => "best first value",
            _ => "worst first value",
        };
        format!("{group}: normalised gap, 1 = {reference}")
    };
    plots::line_chart_png(
        path,
        &title,
        "log10 evaluations",
        "normalised gap (1 = reference, 0 = best known)",
        &series,
        true,
    )
    .map(|()| true)
}

/// The Bayesian signed-rank test of every pair over the cells every optimiser ran: each cell's
/// mean best error divided by the cell's approach-B error.
fn bayes_table(rows: &[OptimRow], opts: &[String], args: &CompareArgs) -> Result<Vec<Vec<String>>> {
    let mut cells: BTreeMap<ComparedCell, CellSums> = BTreeMap::new();
    for r in rows {
        let e = cells
            .entry(r.compared_cell())
            .or_insert((r.b, BTreeMap::new()));
        let s = e.1.entry(r.competitor()).or_default();
        s.0 += r.best;
        s.1 += 1;
    }
    let full: Vec<(f64, Vec<f64>)> = cells
        .values()
        .filter(|(_, per)| ran_by_all(per, opts))
        .map(|(b, per)| (*b, opts.iter().map(|o| per[o].0 / per[o].1 as f64 / b).collect()))
        .collect();
    let mut out = Vec::new();
    for i in 0..opts.len() {
        for j in i + 1..opts.len() {
            let a: Vec<f64> = full.iter().map(|c| c.1[i]).collect();
            let b: Vec<f64> = full.iter().map(|c| c.1[j]).collect();
            let r = stats::bayes::signed_rank(
                &a,
                &b,
                args.rope,
                stats::bayes::PRIOR,
                args.bayes_samples,
                0x5eed + (i * opts.len() + j) as u64,
            )
            .map_err(|e| {
                anyhow::anyhow!("Bayesian signed-rank test {} vs {}: {e}", opts[i], opts[j])
            })?;
            out.push(vec![
                opts[i].clone(),
                opts[j].clone(),
                r.n.to_string(),
                format!("{:e}", args.rope),
                r.samples.to_string(),
                format!("{:.4}", r.p_a_better),
                format!("{:.4}", r.p_rope),
                format!("{:.4}", r.p_b_better),
            ]);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_best_known_value_names_where_it_comes_from() {
        use super::super::external::Certificate;
        let row = |o: &str, repeat: usize, best: f64| super::OptimRow {
            optimiser: o.into(),
            repeat,
            best,
            ..Default::default()
        };
        let cert = Certificate { optimum: 2.0, lower_bound: 1.5, table: "exact_6x6.csv".into() };
        let (v, from) = super::best_known(Some(&row("de", 3, 2.5)), Some(&cert));
        assert_eq!((v, from.as_str()), (2.0, "certified optimum (the exact solver's f)"));
        let (v, from) = super::best_known(Some(&row("cma-es", 1, 1.9)), Some(&cert));
        assert_eq!(v, 1.9);
        assert_eq!(from, "best run (cma-es repeat 1), below the exact solver's f, within its certified gap");
        let (v, from) = super::best_known(Some(&row("pso", 0, 4.0)), None);
        assert_eq!((v, from.as_str()), (4.0, "best run (pso repeat 0)"));
    }

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

    /// A chart whose file cannot be written stops the runtime outputs with an error naming it; a
    /// chart that cannot be drawn from its data is skipped.
    #[test]
    fn a_chart_that_cannot_be_written_is_an_error_and_one_that_cannot_be_drawn_a_note() {
        let runs = |first: f64, last: f64| vec![(10, vec![(1, first), (7, last)])];
        let problem = Problem {
            name: "p".into(),
            b: 2.0,
            best_known: 1.0,
            from: "best run (de repeat 0)".into(),
            reference: Some(2.0),
            rule: "b_to_best_known",
            targets: stats::runtime::log_targets(2.0, 1.0, TARGETS, TARGET_DECADES),
            runs: [("x".to_string(), runs(1.9, 1.0)), ("y".to_string(), runs(1.95, 1.5))]
                .into_iter()
                .collect(),
        };
        let opts = ["x".to_string(), "y".to_string()];
        let dir = tempfile::tempdir().unwrap();
        runtime_outputs(std::slice::from_ref(&problem), &opts, dir.path()).unwrap();
        // A folder where the chart goes: the rename into place fails.
        let blocked = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(blocked.path().join("compare_ecdf_all.png/x")).unwrap();
        let e = runtime_outputs(&[problem], &opts, blocked.path()).unwrap_err().to_string();
        assert!(e.contains("compare_ecdf_all.png"), "{e}");
        let drawn = plots::PlotError::input(std::path::Path::new("a.png"), "no data");
        chart_skipped(drawn).unwrap();
    }
}
