//! Runtime distributions from the IOHprofiler traces, computed: per problem its targets (from
//! approach B's error, or a first value of a run, down to the best known value), and per optimiser
//! the ECDF of (run, target) hitting times, its AOCC, the ERT per target and the fixed-budget
//! normalised gap, per problem and over the problems every optimiser ran ("all"). Written by
//! `runtime_files.rs`.

use crate::families::optimise::external::Certificate;
use crate::families::optimise::{ioh, OptimRow};
use crate::stats;
use anyhow::{Context, Result};
use super::cells::num;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Targets per problem: this many, log-spaced over this many decades of the gap between the
/// range's start (approach B's error, or where nothing beats B the best first value of a run: see
/// [`stats::runtime::target_range`]) and the best known value (the last target is the best known
/// value itself).
pub(super) const TARGETS: usize = 16;
pub(super) const TARGET_DECADES: f64 = 3.0;
/// Budgets at which the ECDF and the fixed-budget values are tabulated (log-spaced).
const BUDGETS: usize = 40;

/// A run's (evaluations, improvement rows).
pub(super) type RunTrace = (u64, Vec<(u64, f64)>);

/// One problem (data set, grid, net, parameterisation) as the runtime distributions see it.
#[derive(Debug, Clone)]
pub(super) struct Problem {
    pub(super) name: String,
    pub(super) b: f64,
    pub(super) best_known: f64,
    /// Where `best_known` comes from, in words (`compare_targets.csv`'s `best_known_from`).
    pub(super) from: String,
    /// The start of the targets' range (the fixed-budget gap's reference), None when no run ever
    /// improved, and the rule that chose it.
    pub(super) reference: Option<f64>,
    pub(super) rule: &'static str,
    pub(super) targets: Vec<f64>,
    /// Per optimiser, its runs' (evaluations, improvements).
    pub(super) runs: BTreeMap<String, Vec<RunTrace>>,
}

/// One ECDF (a problem's, or "all": the mean of an optimiser's per-problem ECDFs, each problem
/// weighing the same).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct EcdfRow {
    pub(super) group: String,
    pub(super) optimiser: String,
    /// At each budget.
    pub(super) values: Vec<f64>,
    pub(super) aocc: f64,
    /// (run, target) pairs behind it, and problems.
    pub(super) pairs: usize,
    pub(super) problems: usize,
}

/// One fixed-budget curve: at each budget the mean over runs of (best - best known) /
/// (reference - best known), the reference being the start of the problem's targets (approach B's
/// error where something beats it); None when the denominator is zero (then `note` says why). For
/// "all" the mean of the per-problem curves, each problem weighing the same.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct GapRow {
    pub(super) group: String,
    pub(super) optimiser: String,
    pub(super) values: Option<Vec<f64>>,
    pub(super) runs: usize,
    pub(super) problems: usize,
    pub(super) rule: String,
    pub(super) note: String,
}

/// The expected running time of one optimiser to one target of one problem.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct ErtRow {
    pub(super) problem: String,
    pub(super) optimiser: String,
    pub(super) target_index: usize,
    pub(super) target: f64,
    pub(super) hits: usize,
    pub(super) runs: usize,
    pub(super) ert: f64,
}

/// What the runtime-distribution tables and charts show, computed before anything is written.
#[derive(Debug)]
pub(super) struct Runtime {
    pub(super) budget: u64,
    pub(super) budgets: Vec<u64>,
    pub(super) ecdf: Vec<EcdfRow>,
    pub(super) fixed_budget: Vec<GapRow>,
    /// Targets per problem, for the charts' titles ("16 targets per problem", or the counts).
    pub(super) targets_desc: String,
    /// Per problem, optimiser and target.
    pub(super) ert: Vec<ErtRow>,
    /// The problems "all" aggregates, in words for the titles: "problems " when every optimiser
    /// ran every problem, else "problems every optimiser ran ".
    pub(super) common_desc: String,
}

/// Why a problem has no fixed-budget gap.
pub(super) const NO_GAP: &str = "left out: no run improved on its first value (zero denominator)";

/// A run's problem name, as the IOHprofiler logs name it.
fn problem_of(r: &OptimRow) -> String {
    ioh::problem_name(
        &r.dataset,
        &format!("{}x{}", r.grid_x, r.grid_y),
        &format!("{}x{}", r.cn_x, r.cn_y),
        &r.parameterisation,
    )
}

/// Gather the problems from runs.csv and the folder's `ioh/` traces (which must list the same runs
/// with the same evaluation counts and final values).
pub(super) fn problems(
    rows: &[OptimRow],
    folder: &Path,
    external: Vec<ioh::LoadedProblem>,
    certified: &BTreeMap<String, Certificate>,
) -> Result<Vec<Problem>> {
    let outside: BTreeSet<String> = external.iter().map(|lp| lp.optimiser.clone()).collect();
    let mut expected: BTreeMap<(String, String), Vec<&OptimRow>> = BTreeMap::new();
    for r in rows {
        expected.entry((problem_of(r), r.competitor())).or_default().push(r);
    }
    let mut out: BTreeMap<String, Problem> = BTreeMap::new();
    for lp in ioh::read(folder)?.into_iter().chain(external) {
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
            .filter(|r| &problem_of(r) == pn)
            .min_by(|a, b| a.best.total_cmp(&b.best).then(a.repeat.cmp(&b.repeat)));
        (p.best_known, p.from) = best_known(best_run, certified.get(pn), &outside);
        set_targets(p);
    }
    Ok(out.into_values().collect())
}

/// A problem's targets, from its best known value and its runs' first values.
fn set_targets(p: &mut Problem) {
    let firsts: Vec<f64> =
        p.runs.values().flatten().filter_map(|r| r.1.first().map(|x| x.1)).collect();
    (p.reference, p.rule) = stats::runtime::target_range(p.b, p.best_known, &firsts);
    p.targets = match p.reference {
        Some(start) => stats::runtime::log_targets(start, p.best_known, TARGETS, TARGET_DECADES),
        None => vec![p.best_known],
    };
}

/// The best known value of a problem and where it comes from, whichever source is lowest: the
/// exact solver's `f` (the upper end of its certified interval [lower_bound, f]), or a run that
/// ended below it (inside that interval), named as somnurbs' own (`run de repeat 3`) or an
/// external one (`external cma-es repeat 1`, its optimiser in `external`). A run that reached `f`
/// itself is named beside the solver.
pub(super) fn best_known(
    best_run: Option<&OptimRow>,
    cert: Option<&Certificate>,
    external: &BTreeSet<String>,
) -> (f64, String) {
    let run = |r: &OptimRow| {
        let kind = if external.contains(&r.competitor()) { "external" } else { "run" };
        format!("{kind} {} repeat {}", r.competitor(), r.repeat)
    };
    let solver = |c: &Certificate| {
        let (f, lb) = (num(c.optimum), num(c.lower_bound));
        format!("exact solver (f = {f}, the upper end of its certified interval [{lb}, {f}])")
    };
    match (best_run, cert) {
        (Some(r), Some(c)) if r.best < c.optimum => (
            r.best,
            format!("{}, below the exact solver's f = {}: inside its certified interval [{}, {}]", run(r), num(c.optimum), num(c.lower_bound), num(c.optimum)),
        ),
        (Some(r), Some(c)) if r.best == c.optimum => {
            (c.optimum, format!("{}; {} reached it", solver(c), run(r)))
        }
        (_, Some(c)) => (c.optimum, solver(c)),
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
        .map(|(k, &target)| {
            let (e, hits) = ert(&ts, target);
            ErtRow {
                problem: p.name.clone(),
                optimiser: o.to_string(),
                target_index: k,
                target,
                hits,
                runs: ts.len(),
                ert: e,
            }
        })
        .collect();
    (e, g, ert_rows)
}

/// The "all" rows of one optimiser: the mean of its per-problem ECDFs and fixed-budget curves
/// `es` and `gs`, each problem weighing the same.
fn aggregate(o: &str, es: &[EcdfRow], gs: &[GapRow]) -> (EcdfRow, GapRow) {
    let curves: Vec<&[f64]> = es.iter().map(|e| e.values.as_slice()).collect();
    let all = EcdfRow {
        group: "all".into(),
        optimiser: o.to_string(),
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
        optimiser: o.to_string(),
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
    (all, all_gap)
}

/// Compute every runtime table: per optimiser, per problem and over all problems ("all": every
/// problem every optimiser ran weighing the same, as IOHanalyzer and COCO aggregate over
/// functions).
pub(super) fn runtime(problems: &[Problem], opts: &[String]) -> Runtime {
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
    // "all" aggregates the problems every optimiser ran (all of them unless an external ran part),
    // so that every optimiser's aggregate is over the same problems; with none in common, each
    // optimiser's own.
    let common = |p: &Problem| opts.iter().all(|o| p.runs.contains_key(o));
    let any_common = problems.iter().any(common);
    if !any_common && !problems.is_empty() {
        rt.common_desc = "problems of its own (no problem every optimiser ran) ".into();
    } else if problems.iter().any(|p| !common(p)) {
        rt.common_desc = "problems every optimiser ran ".into();
    }
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
        let (all, all_gap) = aggregate(o, &es, &gs);
        rt.ecdf.extend(es);
        rt.ecdf.extend(own_e);
        rt.ecdf.push(all);
        rt.fixed_budget.extend(gs);
        rt.fixed_budget.extend(own_g);
        rt.fixed_budget.push(all_gap);
    }
    rt
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_best_known_value_names_where_it_comes_from() {
        let row = |o: &str, repeat: usize, best: f64| OptimRow {
            optimiser: o.into(),
            repeat,
            best,
            ..Default::default()
        };
        let cert = Certificate { optimum: 2.0, lower_bound: 1.5, table: "exact_6x6.csv".into() };
        let ext: BTreeSet<String> = ["cma-es".to_string(), "lbfgsb".to_string()].into();
        let solver = "exact solver (f = 2, the upper end of its certified interval [1.5, 2])";
        let (v, from) = best_known(Some(&row("de", 3, 2.5)), Some(&cert), &ext);
        assert_eq!((v, from.as_str()), (2.0, solver));
        let (v, from) = best_known(Some(&row("lbfgsb", 0, 2.0)), Some(&cert), &ext);
        assert_eq!((v, from), (2.0, format!("{solver}; external lbfgsb repeat 0 reached it")));
        let (v, from) = best_known(Some(&row("cma-es", 1, 1.9)), Some(&cert), &ext);
        assert_eq!(v, 1.9);
        assert_eq!(
            from,
            "external cma-es repeat 1, below the exact solver's f = 2: inside its certified interval [1.5, 2]"
        );
        let (v, from) = best_known(Some(&row("pso", 0, 4.0)), None, &ext);
        assert_eq!((v, from.as_str()), (4.0, "run pso repeat 0"));
        assert_eq!(best_known(None, None, &ext).1, "none");
    }
}
