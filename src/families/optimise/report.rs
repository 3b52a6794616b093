//! Chapter 6 outputs: runs.csv, Appendix K/L (AVG/MIN/MAX optimised surface error per optimiser
//! beside B) and M/N (CPU seconds), the win-count tables 6.4-6.9, each optimiser's count of cells
//! where it beats B, convergence curves and box plots, and the REPORT.md section.

use super::{OptimRun, ProblemKey};
use crate::experiment::spec::GridSize;
use crate::io::{csv_records, csv_text, write_atomic};
use crate::optim::exact::ExactResult;
use crate::optim::Problem;
use crate::report::claims::Claim;
use crate::report::markdown::table;
use crate::report::ordered;
use crate::report::plots::{self, style, Series};
use crate::report::reference;
use crate::spline::ControlNetProblem;
use crate::spline::Parameterisation;
use anyhow::Result;
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::Path;

fn stats(v: &[f64]) -> Option<(f64, f64, f64)> {
    if v.is_empty() {
        return None;
    }
    let avg = v.iter().sum::<f64>() / v.len() as f64;
    Some((
        avg,
        v.iter().cloned().fold(f64::INFINITY, f64::min),
        v.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
    ))
}


/// The thesis' Appendices K and L (optimised surface error) and M and N (CPU time).
pub(crate) const PUBLISHED: crate::report::reference::Published = &[
    ("appendix_k", include_str!("../../../experiments/reference/appendix_k.csv")),
    ("appendix_l", include_str!("../../../experiments/reference/appendix_l.csv")),
    ("appendix_m", include_str!("../../../experiments/reference/appendix_m.csv")),
    ("appendix_n", include_str!("../../../experiments/reference/appendix_n.csv")),
];

/// One value of ours beside the thesis' (Appendices K-N): the row key (data, parameterisation,
/// cn_x, cn_y), the column, ours, the thesis'.
struct Beside {
    key: Vec<String>,
    measure: String,
    ours: f64,
    thesis: f64,
}

/// Every cell of our appendix table that the published one also has.
fn side_by_side(
    header: &[String],
    rows: &[Vec<String>],
    thesis: &reference::RefTable,
) -> Vec<Beside> {
    let keys = ["data", "parameterisation", "cn_x", "cn_y"];
    let mut out = Vec::new();
    for row in rows {
        let key = row[..keys.len()].to_vec();
        for (col, v) in header.iter().zip(row).skip(keys.len()) {
            if let (Ok(ours), Some(t)) = (v.parse::<f64>(), thesis.value(&keys, &key, col)) {
                out.push(Beside { key: key.clone(), measure: col.clone(), ours, thesis: t });
            }
        }
    }
    out
}

/// `<name>_vs_thesis.csv` (long: one row per cell and column, ours, the thesis', the ratio) and
/// the Markdown table of the median ratio per control net and column.
fn render_side_by_side(pairs: &[Beside], name: &str, timing: bool, out: &Path) -> Result<String> {
    // CPU seconds are measured, never identical across runs: their columns end in `_s`, which
    // marks a timing column for `drift` (reported, not judged).
    let values: [&str; 3] =
        if timing { ["ours_s", "thesis_s", "ratio_s"] } else { ["ours", "thesis", "ratio"] };
    let h: Vec<String> = ["data", "parameterisation", "cn_x", "cn_y", "measure"]
        .iter()
        .chain(&values)
        .map(|s| s.to_string())
        .collect();
    let rows: Vec<Vec<String>> = pairs
        .iter()
        .map(|b| {
            let mut r = b.key.clone();
            r.extend([
                b.measure.clone(),
                format!("{:.6}", b.ours),
                format!("{:.6}", b.thesis),
                if b.thesis != 0.0 { format!("{:.6}", b.ours / b.thesis) } else { String::new() },
            ]);
            r
        })
        .collect();
    write_atomic(&out.join(format!("{name}_vs_thesis.csv")), csv_records(&h, &rows)?.as_bytes())?;
    let measures = ordered(pairs.iter().map(|b| b.measure.clone()));
    let shown: Vec<&String> = measures
        .iter()
        .filter(|m| m.as_str() == "b" || m.ends_with("_avg") || m.ends_with("_avg_s"))
        .collect();
    let nets =
        ordered(pairs.iter().map(|b| {
            (b.key[2].parse::<usize>().unwrap_or(0), b.key[3].parse::<usize>().unwrap_or(0))
        }));
    let mh: Vec<String> = ["CN", "measure", "ours (median)", "thesis (median)", "median ratio ours/thesis", "cells"]
        .iter()
        .map(|x| x.to_string())
        .collect();
    let mut mrows = Vec::new();
    for (cx, cy) in nets {
        for m in &shown {
            let here: Vec<&Beside> = pairs
                .iter()
                .filter(|b| {
                    &&b.measure == m && b.key[2] == cx.to_string() && b.key[3] == cy.to_string()
                })
                .collect();
            let med = |f: &dyn Fn(&Beside) -> f64| {
                crate::report::markdown::median(&here.iter().map(|b| f(b)).collect::<Vec<_>>())
            };
            let ratios: Vec<f64> =
                here.iter().filter(|b| b.thesis != 0.0).map(|b| b.ours / b.thesis).collect();
            mrows.push(vec![
                format!("{cx}x{cy}"),
                m.to_string(),
                significant(med(&|b| b.ours)),
                significant(med(&|b| b.thesis)),
                significant(crate::report::markdown::median(&ratios)),
                here.len().to_string(),
            ]);
        }
    }
    let what = if timing { "CPU seconds per run" } else { "surface error" };
    Ok(format!("\n**`{name}_vs_thesis.csv`**: ours beside the thesis' {what}, cell by cell; below, per control net, the medians over the cells of ours, the thesis' and their ratio\n\n{}", table(&mh, &mrows)))
}

/// Five significant digits, in scientific notation outside [1e-2, 1e5) (CPU seconds of 1e-4
/// must not print as 0.000).
fn significant(v: Option<f64>) -> String {
    match v {
        None => "-".into(),
        Some(0.0) => "0".into(),
        Some(v) if (1e-2..1e5).contains(&v.abs()) => {
            let d = (4 - v.abs().log10().floor() as i32).max(0) as usize;
            format!("{v:.d$}")
        }
        Some(v) => format!("{v:.4e}"),
    }
}

/// The runs of one (cell, optimiser), mapped by `f`.
fn of(g: &[&OptimRun], c: &ProblemKey, o: &str, f: &dyn Fn(&OptimRun) -> f64) -> Vec<f64> {
    g.iter()
        .filter(|r| {
            r.cell.dataset == c.data
                && r.cell.param == c.param
                && r.cell.cn == c.cn
                && r.competitor == o
        })
        .map(|r| f(r))
        .collect()
}

/// One grid's runs reduced to Appendices K-N and the win counts of Tables 6.4-6.7.
struct GridTables {
    opts: Vec<String>,
    cells: Vec<ProblemKey>,
    /// Appendix K/L (errors) and M/N (CPU seconds): headers and rows.
    eh: Vec<String>,
    erows: Vec<Vec<String>>,
    th: Vec<String>,
    trows: Vec<Vec<String>>,
    /// Per optimiser: cells with the least AVG error, the least AVG CPU time, AVG below B.
    err_wins: Vec<usize>,
    time_wins: Vec<usize>,
    beats_b: Vec<usize>,
    /// Per (data, parameterisation): the error and time wins per optimiser.
    per_dp: Vec<(String, Parameterisation, Vec<usize>, Vec<usize>)>,
    /// Per cell (in `cells` order): the optimiser with the least AVG error.
    winner: Vec<Option<usize>>,
}

impl GridTables {
    fn compute(g: &[&OptimRun]) -> GridTables {
        let opts = ordered(g.iter().map(|r| r.competitor.clone()));
        let cells: Vec<ProblemKey> =
            ordered(g.iter().map(|r| ProblemKey::new(&r.cell.dataset, r.cell.cn, r.cell.param)));
        let mut eh =
            vec!["data".to_string(), "parameterisation".into(), "cn_x".into(), "cn_y".into()];
        let mut th = eh.clone();
        for o in &opts {
            for m in ["avg", "min", "max"] {
                eh.push(format!("{o}_{m}"));
                th.push(format!("{o}_{m}_s"));
            }
        }
        eh.push("b".into());
        let n = opts.len();
        let mut t = GridTables {
            opts,
            cells: Vec::new(),
            eh,
            erows: Vec::new(),
            th,
            trows: Vec::new(),
            err_wins: vec![0; n],
            time_wins: vec![0; n],
            beats_b: vec![0; n],
            per_dp: Vec::new(),
            winner: Vec::new(),
        };
        for c in &cells {
            t.add_cell(g, c);
        }
        t.cells = cells;
        t
    }

    /// One cell's rows of the appendices and its wins.
    fn add_cell(&mut self, g: &[&OptimRun], c: &ProblemKey) {
        let key = vec![c.data.clone(), c.param.name().to_string(), c.cn.nx.to_string(), c.cn.ny.to_string()];
        let (mut er, mut tr) = (key.clone(), key);
        let mut avgs = Vec::new();
        let mut tavgs = Vec::new();
        let mut b = f64::NAN;
        for (k, o) in self.opts.iter().enumerate() {
            let best = of(g, c, o, &|r| r.row.best);
            b = of(g, c, o, &|r| r.row.b).first().copied().unwrap_or(b);
            let (a, mn, mx) = stats(&best).unwrap_or((f64::NAN, f64::NAN, f64::NAN));
            er.extend([a, mn, mx].iter().map(|v| format!("{v:.6}")));
            let (ta, tmn, tmx) =
                stats(&of(g, c, o, &|r| r.row.cpu_s)).unwrap_or((f64::NAN, f64::NAN, f64::NAN));
            tr.extend([ta, tmn, tmx].iter().map(|v| format!("{v:.6}")));
            avgs.push(a);
            tavgs.push(ta);
            self.beats_b[k] += (a < b) as usize;
        }
        er.push(format!("{b:.6}"));
        self.erows.push(er);
        self.trows.push(tr);
        let argmin =
            |v: &[f64]| v.iter().enumerate().min_by(|x, y| x.1.total_cmp(y.1)).map(|(i, _)| i);
        let n = self.opts.len();
        let dp = match self.per_dp.iter().position(|x| x.0 == c.data && x.1 == c.param) {
            Some(i) => i,
            None => {
                self.per_dp.push((c.data.clone(), c.param, vec![0; n], vec![0; n]));
                self.per_dp.len() - 1
            }
        };
        self.winner.push(argmin(&avgs));
        if let Some(k) = argmin(&avgs) {
            self.err_wins[k] += 1;
            self.per_dp[dp].2[k] += 1;
        }
        if let Some(k) = argmin(&tavgs) {
            self.time_wins[k] += 1;
            self.per_dp[dp].3[k] += 1;
        }
    }

    /// A win-count table (6.4-6.7): per (data, parameterisation) and a total row.
    fn win_rows(&self, time: bool) -> (Vec<String>, Vec<Vec<String>>) {
        let mut wh = vec!["data".to_string(), "parameterisation".into()];
        wh.extend(self.opts.iter().cloned());
        wh.push("cells".into());
        let per_cells = |d: &str, p: Parameterisation| {
            self.cells.iter().filter(|c| c.data == d && c.param == p).count()
        };
        let mut rows: Vec<Vec<String>> = self
            .per_dp
            .iter()
            .map(|x| {
                let w = if time { &x.3 } else { &x.2 };
                let mut r = vec![x.0.clone(), x.1.name().to_string()];
                r.extend(w.iter().map(|v| v.to_string()));
                r.push(per_cells(&x.0, x.1).to_string());
                r
            })
            .collect();
        let tot = if time { &self.time_wins } else { &self.err_wins };
        let mut r = vec!["total".to_string(), String::new()];
        r.extend(tot.iter().map(|v| v.to_string()));
        r.push(self.cells.len().to_string());
        rows.push(r);
        (wh, rows)
    }

    /// The grid's summary: per optimiser its wins, cells below B and CPU seconds.
    fn summary(&self, g: &[&OptimRun]) -> String {
        let h: Vec<String> = [
            "optimiser",
            "least AVG error (cells)",
            "least AVG CPU time (cells)",
            "AVG below B (cells)",
            "CPU s, all runs",
        ]
        .iter()
        .map(|x| x.to_string())
        .collect();
        let n = self.cells.len();
        let rows: Vec<Vec<String>> = self
            .opts
            .iter()
            .enumerate()
            .map(|(k, o)| {
                let cpu: f64 =
                    g.iter().filter(|r| &r.competitor == o).map(|r| r.row.cpu_s).sum();
                vec![
                    o.clone(),
                    format!("{}/{n}", self.err_wins[k]),
                    format!("{}/{n}", self.time_wins[k]),
                    format!("{}/{n}", self.beats_b[k]),
                    format!("{cpu:.2}"),
                ]
            })
            .collect();
        // One optimiser is least of nothing: its "least" columns are left out.
        let keep: Vec<usize> = if self.opts.len() > 1 { (0..h.len()).collect() } else { vec![0, 3, 4] };
        let pick = |r: &Vec<String>| keep.iter().map(|&k| r[k].clone()).collect::<Vec<_>>();
        table(&pick(&h), &rows.iter().map(pick).collect::<Vec<_>>())
    }
}

/// The thesis' own win count of optimiser `o` in its table `t` (`suffix` "" for errors, "_s"
/// for CPU seconds) over the cells this run has: (wins, cells of ours the table has).
fn thesis_wins(
    t: Option<&reference::RefTable>,
    suffix: &str,
    o: &str,
    cells: &[ProblemKey],
) -> Option<(usize, usize)> {
    let t = t?;
    let winners: Vec<&str> = cells.iter().filter_map(|c| thesis_winner(t, c, suffix)).collect();
    Some((winners.iter().filter(|w| **w == o).count(), winners.len()))
}

/// The thesis' optimiser with the least AVG of `<o>_avg<suffix>` in one of our cells (from its
/// Appendix K-N); None where the table lacks the cell or a value.
fn thesis_winner(t: &reference::RefTable, c: &ProblemKey, suffix: &str) -> Option<&'static str> {
    let key = [c.data.clone(), c.param.name().to_string(), c.cn.nx.to_string(), c.cn.ny.to_string()];
    let row = t.find(&["data", "parameterisation", "cn_x", "cn_y"], &key)?;
    let names = ["ga", "de", "pso"];
    let v: Vec<f64> = names
        .iter()
        .map(|n| row.get(&format!("{n}_avg{suffix}")).and_then(|x| x.parse().ok()))
        .collect::<Option<_>>()?;
    v.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1)).map(|(k, _)| names[k])
}

/// Chapter 6's winner pattern by net size (`winners_by_net_<grid>.csv` and its chart): per
/// control net, the cells where each optimiser has the least AVG error, and the thesis' count over
/// the same cells where this run compared the thesis' three optimisers.
fn winners_by_net(t: &GridTables, grid: GridSize, err_name: &str, out: &Path, extras: bool) -> Result<String> {
    let mut sorted = t.opts.clone();
    sorted.sort();
    let thesis = if sorted == ["de", "ga", "pso"] { reference::lookup(PUBLISHED, err_name) } else { None };
    let nets = ordered(t.cells.iter().map(|c| c.cn));
    let mut h = vec!["cn_x".to_string(), "cn_y".into(), "cells".into()];
    h.extend(t.opts.iter().map(|o| format!("{o}_wins")));
    let mut any_thesis = false;
    let mut rows = Vec::new();
    let mut ours_series: Vec<Vec<(f64, f64)>> = vec![Vec::new(); t.opts.len()];
    let mut thesis_series: Vec<Vec<(f64, f64)>> = vec![Vec::new(); t.opts.len()];
    for cn in &nets {
        let here: Vec<usize> = (0..t.cells.len()).filter(|&i| t.cells[i].cn == *cn).collect();
        let mut row = vec![cn.nx.to_string(), cn.ny.to_string(), here.len().to_string()];
        let ours: Vec<usize> =
            (0..t.opts.len()).map(|k| here.iter().filter(|&&i| t.winner[i] == Some(k)).count()).collect();
        row.extend(ours.iter().map(|w| w.to_string()));
        // The thesis' count only where it has every one of these cells.
        let theirs: Option<Vec<usize>> = thesis.as_ref().and_then(|tt| {
            let w: Option<Vec<&str>> = here.iter().map(|&i| thesis_winner(tt, &t.cells[i], "")).collect();
            w.map(|w| t.opts.iter().map(|o| w.iter().filter(|x| **x == o).count()).collect())
        });
        if let Some(th) = &theirs {
            any_thesis = true;
            row.extend(th.iter().map(|w| w.to_string()));
        }
        for k in 0..t.opts.len() {
            ours_series[k].push((cn.nx as f64, ours[k] as f64));
            if let Some(th) = &theirs {
                thesis_series[k].push((cn.nx as f64, th[k] as f64));
            }
        }
        rows.push(row);
    }
    if any_thesis {
        h.extend(t.opts.iter().map(|o| format!("{o}_wins_thesis")));
        rows.retain(|r| r.len() == h.len());
    }
    let name = format!("winners_by_net_{grid}");
    write_atomic(&out.join(format!("{name}.csv")), csv_records(&h, &rows)?.as_bytes())?;
    let mut s = format!("\n**`{name}.csv`**: per control net, the cells where each optimiser has the least AVG error{}\n\n{}", if any_thesis { ", ours beside the thesis' over the same cells" } else { "" }, table(&h, &rows));
    if extras {
        let series = |pts: &[Vec<(f64, f64)>]| -> Vec<Series> {
            t.opts
                .iter()
                .enumerate()
                .map(|(k, o)| Series {
                    label: label(o),
                    colour: style::series_colour(o, &t.opts),
                    points: pts[k].clone(),
                    band: None,
                })
                .collect()
        };
        let mut panels = vec![("this run".to_string(), series(&ours_series))];
        if any_thesis {
            panels.push(("the thesis, same cells".to_string(), series(&thesis_series)));
        }
        let png = format!("png/{name}.png");
        crate::io::ensure_dir(&out.join("png"))?;
        match plots::small_multiples_png(
            &out.join(&png),
            &format!("Grid {grid}: cells where each optimiser has the least average error, by control net"),
            "control net (first side)",
            "cells won",
            &panels,
            2,
            false,
        ) {
            Ok(()) => {
                let _ = writeln!(s, "\n![{png}]({png})");
            }
            Err(e) => eprintln!("somnurbs: warning: picture skipped: {e}"),
        }
    }
    Ok(s)
}

/// An optimiser's name as the reports write it (GA, DE, PSO, CSA, ICSA).
pub(crate) fn label(o: &str) -> String {
    o.to_uppercase()
}

/// The grid's claims, with the thesis' own counts over the same cells where this run compared
/// the thesis' three optimisers (its counts rank GA, DE and PSO against each other only).
fn grid_claims(
    t: &GridTables,
    grid: GridSize,
    (err_name, time_name): (&str, &str),
    init_range: f64,
) -> Vec<Claim> {
    let n = t.cells.len();
    let mut claims = Vec::new();
    let mut sorted = t.opts.clone();
    sorted.sort();
    let thesis_set = sorted == ["de", "ga", "pso"];
    let against = |me: &str| -> String {
        let others: Vec<String> = t.opts.iter().filter(|o| *o != me).map(|o| label(o)).collect();
        others.join(" and ")
    };
    let own = |table: &str, suffix: &str, o: &str| {
        if thesis_set {
            thesis_wins(reference::lookup(PUBLISHED, table).as_ref(), suffix, o, &t.cells)
        } else {
            None
        }
    };
    // A comparison needs a rival: with one optimiser no "least" claim is made.
    if let Some(k) = t.opts.iter().position(|o| o == "de").filter(|_| t.opts.len() > 1) {
        claims.push(
            Claim::most(
                "6",
                format!("DE gives the least average error in most cells (against {})", against("de")),
                (t.err_wins[k], n),
            )
            .on_grid(grid)
            .thesis(own(err_name, "", "de"))
            .note("least AVG error per cell (Tables 6.4, 6.5)"),
        );
    }
    if let Some(k) = t.opts.iter().position(|o| o == "ga").filter(|_| t.opts.len() > 1) {
        claims.push(
            Claim::most(
                "6",
                format!("GA is the fastest (against {})", against("ga")),
                (t.time_wins[k], n),
            )
            .on_grid(grid)
            .thesis(own(time_name, "_s", "ga"))
            .note("least AVG CPU time per cell (Tables 6.6, 6.7); GA makes 2 evaluations per generation, DE and PSO a population's")
            .timing(),
        );
    }
    for (k, o) in t.opts.iter().enumerate() {
        claims.push(
            Claim::most("6", format!("{} lowers the surface error below B", label(o)), (t.beats_b[k], n))
                .on_grid(grid)
                .note(format!("cells whose AVG over repeats is below B's error; the +-{init_range:e} start can leave an optimiser above B")),
        );
    }
    claims
}

/// The certified exact optimum of each cell that has one and each optimiser's distance to it:
/// `exact_<grid>.csv`, its REPORT.md part and the bound claim (None without exact cells).
fn exact_section(
    g: &[&OptimRun],
    t: &GridTables,
    exact: &BTreeMap<ProblemKey, ExactResult>,
    grid: GridSize,
    out: &Path,
) -> Result<Option<(String, Claim)>> {
    let ex_cells: Vec<(&ProblemKey, &ExactResult)> = t
        .cells
        .iter()
        .filter_map(|c| exact.get(c).map(|e| (c, e)))
        .collect();
    if ex_cells.is_empty() {
        return Ok(None);
    }
    let mut h: Vec<String> = [
        "data",
        "parameterisation",
        "cn_x",
        "cn_y",
        "b",
        "exact_f",
        "lower_bound",
        "certified_gap",
    ]
    .iter()
    .map(|x| x.to_string())
    .collect();
    h.extend(t.opts.iter().map(|o| format!("{o}_min_minus_exact")));
    let mut rows = Vec::new();
    let (mut below, mut checked) = (0usize, 0usize);
    for (c, e) in &ex_cells {
        let b = g
            .iter()
            .find(|r| r.cell.dataset == c.data && r.cell.param == c.param && r.cell.cn == c.cn)
            .map(|r| r.row.b)
            .unwrap_or(f64::NAN);
        let mut row = vec![
            c.data.clone(),
            c.param.name().to_string(),
            c.cn.nx.to_string(),
            c.cn.ny.to_string(),
            format!("{b:.9}"),
            // Round-trip precision: these are the targets compare and external logs are judged by.
            format!("{}", e.f),
            format!("{}", e.lower_bound),
            format!("{:.3e}", e.gap),
        ];
        for o in &t.opts {
            let best = of(g, c, o, &|r| r.row.best);
            checked += best.len();
            below += best.iter().filter(|&&v| v < e.lower_bound).count();
            let mn = best.iter().cloned().fold(f64::INFINITY, f64::min);
            row.push(format!("{:.3e}", mn - e.f));
        }
        rows.push(row);
    }
    let name = format!("exact_{grid}.csv");
    write_atomic(&out.join(&name), csv_records(&h, &rows)?.as_bytes())?;
    let mut s = String::new();
    let _ = writeln!(s, "\n`{name}`: the convex problem solved in its box (projected Newton on the smoothed sum of norms), certified as an interval: its minimum lies in [lower_bound, exact_f], exact_f the value of the best point found (the upper end), lower_bound proven by weak duality, certified_gap their difference; each optimiser's best minus exact_f (a run may end below exact_f, by at most the gap).\n\n{}", table(&h, &rows));
    // A cell whose certified gap did not reach `exact_tol` is named, with its gap.
    for (c, e) in ex_cells.iter().filter(|(_, e)| !e.converged) {
        let _ = writeln!(
            s,
            "\n{c}: not certified, gap {:.3e} ({:.3e} relative) after {} Newton steps.",
            e.gap,
            e.gap / e.f,
            e.iterations
        );
    }
    let claim =
        Claim::every("6", "No optimiser beats the certified lower bound", (checked - below, checked))
            .on_grid(grid)
            .note("a sanity check of the bound and the fitness");
    Ok(Some((s, claim)))
}

/// "Fitness evaluations per run: ..." (the budgets differ by optimiser, and Tables 6.6/6.7,
/// "GA is the fastest", rest on them).
fn budgets(runs: &[OptimRun]) -> String {
    let budgets: Vec<String> = ordered(runs.iter().map(|r| r.competitor.clone()))
        .iter()
        .map(|o| {
            let e: Vec<u64> =
                runs.iter().filter(|r| &r.competitor == o).map(|r| r.row.evaluations).collect();
            let (lo, hi) =
                (e.iter().min().copied().unwrap_or(0), e.iter().max().copied().unwrap_or(0));
            if lo == hi {
                format!("{o} {lo}")
            } else {
                format!("{o} {lo}-{hi}")
            }
        })
        .collect();
    let ga = if runs.iter().any(|r| r.competitor == "ga") && budgets.len() > 1 {
        " GA is steady-state (thesis 6.2.4.1) and evaluates two offspring per generation, the others their whole population each generation; its lead in CPU time (Tables 6.6, 6.7) rests on that smaller budget."
    } else {
        ""
    };
    format!("Fitness evaluations per run: {}.{ga}\n", budgets.join(", "))
}

/// The claims over every run: the surfaces stay near the data, elitism holds.
fn run_claims(runs: &[OptimRun], bounds: &BTreeMap<String, f64>) -> Vec<Claim> {
    use crate::families::maps::{near_note, near_of};
    let near = runs.iter().filter(|r| r.row.excursion <= near_of(bounds, &r.cell.dataset)).count();
    let datasets = ordered(runs.iter().map(|r| r.cell.dataset.clone()));
    let worst = runs.iter().max_by(|a, b| a.row.excursion.total_cmp(&b.row.excursion));
    let kept = runs.iter().filter(|r| r.row.best <= r.row.initial_best).count();
    vec![
        Claim::every("6", "The optimised surfaces stay near the data", (near, runs.len()))
            .note(format!("runs whose best surfaces' dense excursion from the data's bounding box is {}{}", near_note(bounds, &datasets), worst.map(|w| format!("; largest {:.3e} at {}", w.row.excursion, w.row.cell)).unwrap_or_default())),
        Claim::every("6", "Every run's best is no worse than its initial population's best", (kept, runs.len()))
            .note("elitism check over all runs"),
    ]
}

/// One grid's files and REPORT.md part: Appendices K-N (and the thesis' beside them), Tables
/// 6.4-6.7, the summary, the exact optimum, Appendices I/J and the convergence charts.
fn write_grid(
    g: &[&OptimRun],
    grid: GridSize,
    problems: &BTreeMap<ProblemKey, ControlNetProblem>,
    exact: &BTreeMap<ProblemKey, ExactResult>,
    out: &Path,
    as_run: &AsRun,
    s: &mut String,
) -> Result<Vec<Claim>> {
    let extras = as_run.extras;
    let t = GridTables::compute(g);
    let (err_name, time_name, t_err, t_time) = table_names(grid.nx, grid.ny).unwrap_or((
        "optimised_error",
        "optimiser_cpu",
        "wins_error",
        "wins_time",
    ));
    write_atomic(&out.join(format!("{err_name}.csv")), csv_records(&t.eh, &t.erows)?.as_bytes())?;
    write_atomic(&out.join(format!("{time_name}.csv")), csv_records(&t.th, &t.trows)?.as_bytes())?;
    let mut beside_md = String::new();
    for (name, h, rows, timing) in
        [(err_name, &t.eh, &t.erows, false), (time_name, &t.th, &t.trows, true)]
    {
        // Only where the thesis has values for some of these cells: no empty table.
        let pairs = reference::lookup(PUBLISHED, name).map(|r| side_by_side(h, rows, &r)).unwrap_or_default();
        if !pairs.is_empty() {
            beside_md.push_str(&render_side_by_side(&pairs, name, timing, out)?);
        }
    }
    for (name, time) in [(t_err, false), (t_time, true)] {
        let (wh, rows) = t.win_rows(time);
        write_atomic(&out.join(format!("{name}.csv")), csv_records(&wh, &rows)?.as_bytes())?;
    }
    let _ = writeln!(
        s,
        "\n### Grid {grid}: `{err_name}.csv`, `{time_name}.csv`, `{t_err}.csv`, `{t_time}.csv`\n"
    );
    s.push_str(&t.summary(g));
    if t.opts.iter().any(|o| o == "de") {
        s.push_str(&beside_md);
    }
    if t.opts.len() > 1 {
        s.push_str(&winners_by_net(&t, grid, err_name, out, extras)?);
    }
    let mut claims = grid_claims(&t, grid, (err_name, time_name), as_run.init_range);
    if let Some((part, claim)) = exact_section(g, &t, exact, grid, out)? {
        s.push_str(&part);
        claims.push(claim);
    }
    if extras {
        appendix_ij(g, &t.cells, &t.opts, problems, grid, out, s)?;
        convergence_charts(g, &t.cells, &t.opts, problems, exact, grid, out, s)?;
    }
    Ok(claims)
}

/// What the report takes from the spec as it ran, besides its records: every number its text
/// states comes from here, never from the thesis plan's defaults.
pub(crate) struct AsRun {
    /// One sentence on the readings, the start and the search box ([`super::setting`]).
    pub(crate) setting: String,
    /// The half-width of the start's spread around B (`optimise.init_range`).
    pub(crate) init_range: f64,
    /// Per data set, what counts as near its data ([`crate::families::maps::near_bound`]).
    pub(crate) near: BTreeMap<String, f64>,
    /// Pictures, appendices I/J and the IOHprofiler files too.
    pub(crate) extras: bool,
}

/// Write every Chapter 6 file; returns the REPORT.md section.
pub(crate) fn write(
    spec_name: &str,
    runs: &[OptimRun],
    problems: &BTreeMap<ProblemKey, ControlNetProblem>,
    exact: &BTreeMap<ProblemKey, ExactResult>,
    as_run: &AsRun,
    out: &Path,
) -> Result<String> {
    let (setting, extras) = (&as_run.setting, as_run.extras);
    let rows: Vec<_> = runs.iter().map(|r| r.row.clone()).collect();
    write_atomic(&out.join("runs.csv"), csv_text(&rows)?.as_bytes())?;
    let mut s = String::from("## Chapter 6: optimisation of the control points\n\n");
    let reps = runs.iter().map(|r| r.cell.repeat).max().map(|m| m + 1).unwrap_or(0);
    let _ = writeln!(s, "{} runs ({} repeats per cell), every optimiser of a cell started from the same approach-B control net; fitness Eq. 6.2 (= Eq. 5.13). {setting}\n", runs.len(), reps);
    let _ = writeln!(s, "{}", budgets(runs));
    let mut claims = Vec::new();
    for grid in ordered(runs.iter().map(|r| r.cell.grid)) {
        let g: Vec<&OptimRun> = runs.iter().filter(|r| r.cell.grid == grid).collect();
        claims.extend(write_grid(&g, grid, problems, exact, out, as_run, &mut s)?);
    }
    s.push_str(&friedman_section(runs));
    if extras {
        let n_ioh = super::ioh::write(runs, out)?;
        let _ = writeln!(s, "\nEvery run's improvements of the best so far in the IOHprofiler format (`ioh/<optimiser>/`: {n_ioh} JSON meta-data files, format version 0.3.3 or later, each with its improvement-based `.dat`), loadable by IOHanalyzer and iohinspector.");
    }
    claims.extend(run_claims(runs, &as_run.near));
    let claims_md = crate::report::claims::write(out, spec_name, &claims, false)?;
    if !claims_md.is_empty() {
        s.push_str("\n### Claims\n\n");
        s.push_str(&claims_md);
    }
    Ok(s)
}

/// Appendix I/J: B beside the MIN-error surface of each optimiser (its difference from B,
/// magnified), largest net, per data set, drawn from the dense evaluation.
fn appendix_ij(
    g: &[&OptimRun],
    cells: &[ProblemKey],
    opts: &[String],
    problems: &BTreeMap<ProblemKey, ControlNetProblem>,
    grid: GridSize,
    out: &Path,
    s: &mut String,
) -> Result<()> {
    if let Some(&cn) = cells.iter().map(|c| &c.cn).max() {
        let appendix = match (grid.nx, grid.ny) {
            (20, 20) => "appendix_i",
            (18, 30) => "appendix_j",
            _ => "optimised_surfaces",
        };
        let params: Vec<Parameterisation> = ordered(cells.iter().map(|c| c.param));
        for d in ordered(cells.iter().map(|c| c.data.clone())) {
            let mut panels = Vec::new();
            for &p in &params {
                let Some(problem) = problems.get(&ProblemKey::new(&d, cn, p)) else { continue };
                // Drawn from the dense evaluation, so a surface that swings out between the
                // data points shows.
                let meshes = |x: &[f64]| {
                    let [(bottom, be), (top, te)] = problem.parts().dense_wireframes(x);
                    vec![
                        plots::LineMesh {
                            points: bottom,
                            edges: be,
                            colour: style::DNSOM_BOTTOM,
                            label: "bottom surface".into(),
                        },
                        plots::LineMesh {
                            points: top,
                            edges: te,
                            colour: style::DNSOM_TOP,
                            label: "top surface".into(),
                        },
                    ]
                };
                let b = meshes(problem.initial_point());
                panels.push(plots::Panel {
                    title: format!(
                        "{} {cn} B ({:.4})",
                        p.name(),
                        problem.fitness(problem.initial_point())
                    ),
                    meshes: b.clone(),
                });
                // The optimised surfaces differ from B by ~1e-4: each is drawn as its
                // difference from B, magnified, over B in grey.
                let grey: Vec<plots::LineMesh> = b
                    .iter()
                    .map(|m| plots::LineMesh {
                        colour: plotters::style::RGBColor(190, 190, 190),
                        label: "B, under each optimiser's magnified difference".into(),
                        ..m.clone()
                    })
                    .collect();
                for o in opts {
                    let min = g
                        .iter()
                        .filter(|r| {
                            r.cell.dataset == d
                                && r.cell.param == p
                                && r.cell.cn == cn
                                && &r.competitor == o
                        })
                        .min_by(|a, b| a.row.best.total_cmp(&b.row.best));
                    if let Some(r) = min {
                        let (title, shown) =
                            match plots::magnified_difference(&b, &meshes(&r.best_x), 0.15) {
                                Some((m, k, dmax)) => (
                                    format!(
                                        "{}: (MIN - B) x{k:.0}, max {dmax:.0e}",
                                        label(o)
                                    ),
                                    grey.iter().cloned().chain(m).collect(),
                                ),
                                None => (
                                    format!("{} MIN ({:.4}) = B", label(o), r.row.best),
                                    b.clone(),
                                ),
                            };
                        panels.push(plots::Panel { title, meshes: shown });
                    }
                }
            }
            if panels.is_empty() {
                continue;
            }
            crate::io::ensure_dir(&out.join("png"))?;
            let name = format!("png/{appendix}_{d}.png");
            match plots::overview_png(
                &out.join(&name),
                &format!(
                    "{d}, {cn} on {grid}: approach B and the MIN-error surface of each optimiser"
                ),
                &panels,
                opts.len() + 1,
            ) {
                Ok(()) => {
                    let _ = writeln!(s, "\n![{name}]({name})");
                }
                Err(e) => eprintln!("somnurbs: warning: picture skipped: {e}"),
            }
        }
    }
    Ok(())
}

/// Convergence (median and quartiles over repeats, with B and the certified optimum) and box
/// plots for the largest net with the first parameterisation, per data set.
#[allow(clippy::too_many_arguments)]
fn convergence_charts(
    g: &[&OptimRun],
    cells: &[ProblemKey],
    opts: &[String],
    problems: &BTreeMap<ProblemKey, ControlNetProblem>,
    exact: &BTreeMap<ProblemKey, ExactResult>,
    grid: GridSize,
    out: &Path,
    s: &mut String,
) -> Result<()> {
    if let Some(&cn) = cells.iter().map(|c| &c.cn).max() {
        let p0 = cells[0].param;
        for d in ordered(cells.iter().map(|c| c.data.clone())) {
            let mut series = Vec::new();
            let mut groups = Vec::new();
            for o in opts {
                let rs: Vec<&&OptimRun> = g
                    .iter()
                    .filter(|r| {
                        r.cell.dataset == d
                            && r.cell.param == p0
                            && r.cell.cn == cn
                            && &r.competitor == o
                    })
                    .collect();
                groups.push((o.clone(), rs.iter().map(|r| r.row.best).collect::<Vec<f64>>()));
                let marks: Vec<u64> =
                    rs.first().map(|r| r.trace.iter().map(|t| t.0).collect()).unwrap_or_default();
                let mut pts = Vec::new();
                let mut band = Vec::new();
                for (m, &e) in marks.iter().enumerate() {
                    let mut v: Vec<f64> =
                        rs.iter().filter_map(|r| r.trace.get(m).map(|t| t.1)).collect();
                    v.sort_by(|a, b| a.total_cmp(b));
                    if v.is_empty() {
                        continue;
                    }
                    let q = |p: f64| plots::boxplot::quantile_type7(&v, p);
                    pts.push((e as f64, q(0.5)));
                    band.push((e as f64, q(0.25), q(0.75)));
                }
                series.push(Series {
                    label: o.clone(),
                    colour: style::series_colour(o, opts),
                    points: pts,
                    band: Some(band),
                });
            }
            // B (where every run starts) and, where the folder has it, the certified optimum:
            // flat lines on the convergence chart, dashed levels across the box plot (so an
            // optimiser that ends above B shows as such).
            let mut levels = Vec::new();
            if let Some(problem) = problems.get(&ProblemKey::new(&d, cn, p0)) {
                let b = problem.fitness(problem.initial_point());
                levels.push(plots::Level { key: "b", label: format!("B {b:.6}"), y: b });
            }
            if let Some(e) = exact.get(&ProblemKey::new(&d, cn, p0)) {
                let label = format!("certified optimum {:.6} (upper end f, gap {:.0e})", e.f, e.gap);
                levels.push(plots::Level { key: "exact", label, y: e.f });
            }
            let (x0, x1) = series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p.0))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
            series.extend(levels.iter().map(|l| Series {
                label: l.label.clone(),
                colour: style::optimiser_colour(l.key).unwrap_or(style::GREY),
                points: vec![(x0, l.y), (x1, l.y)],
                band: None,
            }));
            let conv = format!("png/convergence_{grid}_{d}_{}_{cn}.png", p0.name());
            crate::io::ensure_dir(&out.join("png"))?;
            if let Err(e) = plots::line_chart_png(
                &out.join(&conv),
                &format!("{d}, {} {cn} on {grid}: best fitness (median, quartiles)", p0.name()),
                "evaluations",
                "surface error",
                &series,
                false,
            ) {
                eprintln!("somnurbs: warning: picture skipped: {e}");
            } else {
                let _ = writeln!(s, "\n![{conv}]({conv})");
            }
            let bx = format!("png/boxplot_{grid}_{d}_{}_{cn}.png", p0.name());
            if let Err(e) = plots::box_plot_png(
                &out.join(&bx),
                &format!("{d}, {} {cn} on {grid}: best surface error per repeat", p0.name()),
                "surface error",
                &groups,
                &levels,
            ) {
                eprintln!("somnurbs: warning: picture skipped: {e}");
            } else {
                let _ = writeln!(s, "\n![{bx}]({bx})");
            }
        }
    }
    Ok(())
}

/// The Friedman test over all cells (mean best per optimiser) with its pairwise tests, for
/// REPORT.md (empty with fewer than two optimisers).
fn friedman_section(runs: &[OptimRun]) -> String {
    let mut s = String::new();
    let all_rows: Vec<super::OptimRow> = runs.iter().map(|r| r.row.clone()).collect();
    let (fopts, ftable) = super::compare::friedman_table(&all_rows);
    if fopts.len() > 1 {
        if let Ok(f) = crate::stats::friedman::friedman(&ftable) {
            let _ = writeln!(s, "\n### Statistics over all cells\n\nFriedman test over {} cells (mean best per optimiser): chi-squared {:.3}, df {}, p = {:.3e}. Mean ranks (1 = least error): {}.{}\n", f.blocks, f.chi_squared, f.df, f.p_value, fopts.iter().zip(&f.mean_ranks).map(|(o, r)| format!("{o} {r:.2}")).collect::<Vec<_>>().join(", "), f.critical_difference.map(|cd| format!(" Nemenyi critical difference (alpha 0.05): {cd:.3}.")).unwrap_or_default());
            let h: Vec<String> =
                ["pair", "z", "p", "p (Holm)"].iter().map(|x| x.to_string()).collect();
            let rows: Vec<Vec<String>> = f
                .pairwise
                .iter()
                .map(|&(i, j, z, p, ph)| {
                    vec![
                        format!("{} vs {}", fopts[i], fopts[j]),
                        format!("{z:.3}"),
                        format!("{p:.3e}"),
                        format!("{ph:.3e}"),
                    ]
                })
                .collect();
            s.push_str(&table(&h, &rows));
            s.push_str("\nPer-cell Wilcoxon signed-rank and rank-sum tests with A12 effect sizes and a critical-difference diagram: `somnurbs compare <this folder>`.\n");
        }
    }
    s
}

/// The thesis' names of a grid's tables: (errors appendix, CPU appendix, error wins, time wins);
/// None for a grid the thesis did not use.
pub(crate) fn table_names(
    nx: usize,
    ny: usize,
) -> Option<(&'static str, &'static str, &'static str, &'static str)> {
    match (nx, ny) {
        (20, 20) => Some(("appendix_k", "appendix_m", "table_6_4", "table_6_6")),
        (18, 30) => Some(("appendix_l", "appendix_n", "table_6_5", "table_6_7")),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::significant;

    #[test]
    fn significant_keeps_small_cpu_seconds_visible() {
        assert_eq!(significant(Some(1.07612)), "1.0761");
        assert_eq!(significant(Some(32.846866)), "32.847");
        assert_eq!(significant(Some(0.000123456)), "1.2346e-4");
        assert_eq!(significant(Some(0.0)), "0");
        assert_eq!(significant(None), "-");
    }
}
