//! The runtime distributions written: `compare_ecdf.csv`, `compare_aocc.csv`,
//! `compare_fixed_budget.csv`, `compare_ert.csv`, `compare_targets.csv` (one serde row type each)
//! and the ECDF and fixed-budget charts, overall and per problem.

use super::cells::num;
use super::runtime::{EcdfRow, Problem, Runtime, NO_GAP};
use super::write_table;
use crate::report::plots;
use anyhow::Result;
use serde::Serialize;
use std::path::Path;

/// One row of `compare_ecdf.csv`: an ECDF at one budget.
#[derive(Debug, Default, Serialize)]
struct EcdfLine<'a> {
    group: &'a str,
    optimiser: &'a str,
    evaluations: u64,
    ecdf: String,
    pairs: usize,
    problems: usize,
    weighting: &'static str,
}

/// One row of `compare_aocc.csv`.
#[derive(Debug, Default, Serialize)]
struct AoccLine<'a> {
    group: &'a str,
    optimiser: &'a str,
    pairs: usize,
    problems: usize,
    weighting: &'static str,
    budget: u64,
    aocc: String,
}

/// One row of `compare_fixed_budget.csv`: a fixed-budget curve at one budget.
#[derive(Debug, Default, Serialize)]
struct GapLine<'a> {
    group: &'a str,
    optimiser: &'a str,
    evaluations: u64,
    mean_normalised_gap: String,
    runs: usize,
    problems: usize,
    rule: &'a str,
    note: &'a str,
}

/// One row of `compare_ert.csv`.
#[derive(Debug, Default, Serialize)]
struct ErtLine<'a> {
    problem: &'a str,
    optimiser: &'a str,
    target_index: usize,
    target: String,
    hits: usize,
    runs: usize,
    ert: String,
}

/// One row of `compare_targets.csv`.
#[derive(Debug, Default, Serialize)]
struct TargetLine<'a> {
    problem: &'a str,
    b: String,
    best_known: String,
    best_known_from: &'a str,
    rule: &'a str,
    reference: String,
    n_targets: usize,
    targets: String,
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
pub(super) fn write_runtime_tables(rt: &Runtime, problems: &[Problem], folder: &Path) -> Result<()> {
    let mut rows = Vec::new();
    for e in &rt.ecdf {
        for (b, v) in rt.budgets.iter().zip(&e.values) {
            rows.push(EcdfLine {
                group: &e.group,
                optimiser: &e.optimiser,
                evaluations: *b,
                ecdf: format!("{v:.6}"),
                pairs: e.pairs,
                problems: e.problems,
                weighting: weighting(e),
            });
        }
    }
    write_table(&folder.join("compare_ecdf.csv"), &rows)?;
    let rows: Vec<AoccLine> = rt
        .ecdf
        .iter()
        .map(|e| AoccLine {
            group: &e.group,
            optimiser: &e.optimiser,
            pairs: e.pairs,
            problems: e.problems,
            weighting: weighting(e),
            budget: rt.budget,
            aocc: format!("{:.6}", e.aocc),
        })
        .collect();
    write_table(&folder.join("compare_aocc.csv"), &rows)?;
    let mut rows = Vec::new();
    for g in &rt.fixed_budget {
        for (k, b) in rt.budgets.iter().enumerate() {
            rows.push(GapLine {
                group: &g.group,
                optimiser: &g.optimiser,
                evaluations: *b,
                mean_normalised_gap: g.values.as_ref().map(|v| num(v[k])).unwrap_or_default(),
                runs: g.runs,
                problems: g.problems,
                rule: &g.rule,
                note: &g.note,
            });
        }
    }
    write_table(&folder.join("compare_fixed_budget.csv"), &rows)?;
    write_ert_and_targets(rt, problems, folder)
}

/// `compare_ert.csv` and `compare_targets.csv`.
fn write_ert_and_targets(rt: &Runtime, problems: &[Problem], folder: &Path) -> Result<()> {
    let rows: Vec<ErtLine> = rt
        .ert
        .iter()
        .map(|e| ErtLine {
            problem: &e.problem,
            optimiser: &e.optimiser,
            target_index: e.target_index,
            target: num(e.target),
            hits: e.hits,
            runs: e.runs,
            ert: num(e.ert),
        })
        .collect();
    write_table(&folder.join("compare_ert.csv"), &rows)?;
    let rows: Vec<TargetLine> = problems
        .iter()
        .map(|p| TargetLine {
            problem: &p.name,
            b: num(p.b),
            best_known: num(p.best_known),
            best_known_from: &p.from,
            rule: p.rule,
            reference: p.reference.map(num).unwrap_or_default(),
            n_targets: p.targets.len(),
            targets: p.targets.iter().map(|t| num(*t)).collect::<Vec<_>>().join(" "),
        })
        .collect();
    write_table(&folder.join("compare_targets.csv"), &rows)
}

/// The runtime tables and the charts, overall and per problem (a chart that cannot be drawn is
/// skipped with a warning). Returns what it wrote, for the closing line.
pub(super) fn runtime_outputs(rt: &Runtime, probs: &[Problem], opts: &[String], results: &Path) -> Result<String> {
    write_runtime_tables(rt, probs, results)?;
    let mut written = String::from(", compare_ecdf.csv, compare_aocc.csv, compare_fixed_budget.csv, compare_ert.csv, compare_targets.csv");
    let groups: Vec<String> =
        std::iter::once("all".to_string()).chain(probs.iter().map(|p| p.name.clone())).collect();
    let mut pngs = 0;
    crate::io::ensure_dir(&results.join("png").join("compare"))?;
    for g in &groups {
        let dir =
            if g == "all" { results.to_path_buf() } else { results.join("png").join("compare") };
        match render_ecdf(rt, g, opts, &dir.join(format!("compare_ecdf_{g}.png"))) {
            Ok(()) => pngs += 1,
            Err(e) => super::chart_skipped(e)?,
        }
        let png = dir.join(format!("compare_fixed_budget_{g}.png"));
        match render_fixed_budget(rt, g, opts, &png) {
            Ok(true) => pngs += 1,
            Ok(false) => println!("  no fixed-budget chart of {g}: {NO_GAP}"),
            Err(e) => super::chart_skipped(e)?,
        }
    }
    for line in summary(rt, probs) {
        println!("{line}");
    }
    written.push_str(&format!(", {pngs} runtime charts (compare_ecdf_all.png, compare_fixed_budget_all.png, per problem in png/compare/)"));
    Ok(written)
}

/// The runtime summary (stdout and compare.md): moved targets and each optimiser's AOCC over all
/// problems.
pub(super) fn summary(rt: &Runtime, probs: &[Problem]) -> Vec<String> {
    let solver = probs.iter().filter(|p| p.from.starts_with("exact solver")).count();
    let mut lines = vec![format!(
        "  targets: log-spaced from B to each problem's best known value, the last target; it is the exact solver's f (the upper end of its certified interval [lower_bound, f]) in {solver} of {} problems, a run's best in the others (compare_targets.csv says which)",
        probs.len()
    )];
    let moved = probs.iter().filter(|p| p.rule != "b_to_best_known").count();
    if moved > 0 {
        lines.push(format!(
            "  targets: in {moved} of {} problems no run beats approach B; their targets start at a first value of a run (rule in compare_targets.csv)",
            probs.len()
        ));
    }
    for e in rt.ecdf.iter().filter(|r| r.group == "all") {
        lines.push(format!(
            "  runtime ECDF all {}: AOCC {:.4}, mean over {} {}weighing the same ({} (run, target) pairs), budget {}",
            e.optimiser, e.aocc, e.problems, rt.common_desc, e.pairs, rt.budget
        ));
    }
    lines
}

/// The curves of group `group`, one per optimiser that has one, in `opts` order, each in its
/// optimiser's colour.
fn series_of(
    rt_rows: &[(&str, &str, &[f64])],
    group: &str,
    budgets: &[u64],
    opts: &[String],
) -> Vec<plots::Series> {
    use crate::report::plots::style;
    opts.iter()
        .filter_map(|o| {
            let (_, _, v) = rt_rows.iter().find(|r| r.0 == group && r.1 == o)?;
            Some(plots::Series {
                label: o.clone(),
                colour: style::series_colour(o, opts),
                points: budgets.iter().zip(v.iter()).map(|(b, y)| ((*b as f64).log10(), *y)).collect(),
                band: None,
            })
        })
        .collect()
}

/// The problems behind the "all" curves: their count when every optimiser's aggregate has the
/// same, else each optimiser's, e.g. "(x 4, y 2)".
fn all_problems<'a>(counts: impl Iterator<Item = (&'a str, &'a str, usize)>) -> String {
    let all: Vec<(&str, usize)> =
        counts.filter(|(g, _, _)| *g == "all").map(|(_, o, n)| (o, n)).collect();
    match all.first() {
        Some((_, n)) if all.iter().all(|(_, m)| m == n) => n.to_string(),
        None => "0".into(),
        _ => {
            let each: Vec<String> = all.iter().map(|(o, n)| format!("{o} {n}")).collect();
            format!("({})", each.join(", "))
        }
    }
}

/// The ECDF chart of one group.
fn render_ecdf(
    rt: &Runtime,
    group: &str,
    opts: &[String],
    path: &Path,
) -> Result<(), plots::PlotError> {
    let rows: Vec<(&str, &str, &[f64])> =
        rt.ecdf.iter().map(|r| (r.group.as_str(), r.optimiser.as_str(), r.values.as_slice())).collect();
    let title = if group == "all" {
        let n = all_problems(
            rt.ecdf.iter().map(|e| (e.group.as_str(), e.optimiser.as_str(), e.problems)),
        );
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
    path: &Path,
) -> Result<bool, plots::PlotError> {
    let rows: Vec<(&str, &str, &[f64])> = rt
        .fixed_budget
        .iter()
        .filter_map(|r| Some((r.group.as_str(), r.optimiser.as_str(), r.values.as_deref()?)))
        .collect();
    let series = series_of(&rows, group, &rt.budgets, opts);
    if series.is_empty() {
        return Ok(false);
    }
    let title = if group == "all" {
        let n = all_problems(
            rt.fixed_budget.iter().map(|g| (g.group.as_str(), g.optimiser.as_str(), g.problems)),
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

#[cfg(test)]
mod tests {
    use super::super::runtime::{runtime, TARGETS, TARGET_DECADES};
    use super::*;
    use crate::stats;

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
        let probs = std::slice::from_ref(&problem);
        let rt = runtime(probs, &opts);
        let dir = tempfile::tempdir().unwrap();
        runtime_outputs(&rt, probs, &opts, dir.path()).unwrap();
        // A folder where the chart goes: the rename into place fails.
        let blocked = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(blocked.path().join("compare_ecdf_all.png/x")).unwrap();
        let e = runtime_outputs(&rt, probs, &opts, blocked.path()).unwrap_err().to_string();
        assert!(e.contains("compare_ecdf_all.png"), "{e}");
        let drawn = plots::PlotError::input(std::path::Path::new("a.png"), "no data");
        super::super::chart_skipped(drawn).unwrap();
    }
}
