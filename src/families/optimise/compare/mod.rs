//! `somnurbs compare RESULTS_DIR`: statistics over the optimiser runs of a Chapter 6 folder, read
//! from its runs.csv only (so a folder from another machine or an older run compares the same).
//!
//! Analysis first, over the records alone: the tests of each cell (`cells.rs`), the tests over
//! the cells every optimiser ran (`over_cells.rs` with `friedman.rs`, `bayes.rs`) and the runtime
//! distributions (`runtime.rs`); then the folder is written from those typed tables, each CSV row
//! a serde struct (`runtime_files.rs` for the runtime tables and charts). This file is the command:
//! its request, the checks of its folders and the writing of its folder.

mod bayes;
mod cells;
mod friedman;
mod over_cells;
mod read;
mod runtime;
mod runtime_files;

pub(crate) use friedman::friedman_table;

use crate::io::write_atomic;
use crate::report::plots;
use anyhow::{Context, Result};
use cells::{Coverage, PerCell};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What `somnurbs compare` is asked to do (the command line's `CompareArgs`, as the family takes
/// it).
#[derive(Debug, Clone)]
pub(crate) struct Request {
    /// The results folder of a Chapter 6 run (its runs.csv, ioh/ and exact_<grid>.csv).
    pub(crate) results: PathBuf,
    /// Significance level of the per-cell tests.
    pub(crate) alpha: f64,
    /// Region of practical equivalence of the Bayesian signed-rank test (of B's error).
    pub(crate) rope: f64,
    /// Monte Carlo samples of the Bayesian signed-rank test.
    pub(crate) bayes_samples: usize,
    /// The folder written (default RESULTS/compare).
    pub(crate) out: Option<PathBuf>,
    /// IOHprofiler folders of optimisers from outside somnurbs.
    pub(crate) external: Vec<PathBuf>,
}

impl Request {
    /// The folder compare writes.
    fn dest(&self) -> PathBuf {
        self.out.clone().unwrap_or_else(|| self.results.join(OUT_DIR))
    }
}

/// A chart that could not be made: one that cannot be drawn from its data is skipped with a
/// warning; a file that could not be written (a full disk, a folder that vanished) stops compare.
fn chart_skipped(e: plots::PlotError) -> Result<()> {
    if let plots::PlotError::Io { .. } = e {
        // Its message already holds the cause (no chain, or the cause would be said twice).
        anyhow::bail!("{e}");
    }
    crate::report::picture_skipped(&e);
    Ok(())
}

/// Write typed rows as a CSV table (header from the row type's field names).
fn write_table<T: serde::Serialize + Default>(path: &Path, rows: &[T]) -> Result<()> {
    write_atomic(path, crate::io::csv_table(rows)?.as_bytes())
}

/// `--bayes-samples`: Monte Carlo samples of the Bayesian signed-rank test (below the lower
/// bound its probabilities move in the second digit; above the upper one a run takes minutes).
pub(crate) const MIN_BAYES_SAMPLES: usize = 1_000;
pub(crate) const MAX_BAYES_SAMPLES: usize = 10_000_000;

/// The options' ranges, before anything is read: `--alpha` in (0, 1), `--rope` finite and >= 0,
/// `--bayes-samples` in [[`MIN_BAYES_SAMPLES`], [`MAX_BAYES_SAMPLES`]].
fn check_args(req: &Request) -> Result<()> {
    if !(req.alpha > 0.0 && req.alpha < 1.0) {
        anyhow::bail!("--alpha must be a number in (0, 1), got {}", req.alpha);
    }
    if !(req.rope >= 0.0 && req.rope.is_finite()) {
        anyhow::bail!("--rope must be finite and >= 0, got {}", req.rope);
    }
    if !(MIN_BAYES_SAMPLES..=MAX_BAYES_SAMPLES).contains(&req.bayes_samples) {
        anyhow::bail!(
            "--bayes-samples must be in [{MIN_BAYES_SAMPLES}, {MAX_BAYES_SAMPLES}], got {}",
            req.bayes_samples
        );
    }
    Ok(())
}

/// Everything `compare` writes, computed from the records before anything is written.
struct Analysis {
    opts: Vec<String>,
    coverage: Coverage,
    per_cell: PerCell,
    /// The tests over cells (with two or more cells every optimiser ran).
    over: Option<(over_cells::Overall, Vec<bayes::BayesRow>)>,
    /// The runtime distributions (with an ioh/ folder).
    runtime: Option<(runtime::Runtime, Vec<runtime::Problem>)>,
}

/// `somnurbs compare`: pairwise tests per cell, Friedman and Bayesian tests over cells, runtime
/// distributions from the traces; tables into the folder, a summary on stdout.
pub(crate) fn compare(req: &Request) -> Result<()> {
    check_args(req)?;
    let runs_csv = req.results.join("runs.csv");
    if !req.results.is_dir() {
        anyhow::bail!("{}: not found (no such results folder)", runs_csv.display());
    }
    // Only a finished, whole run is compared, and one compare at a time per results folder.
    crate::io::outdir::require_finished(&req.results, "the results folder")?;
    read::require_optimise_run(&req.results)?;
    let _lock = crate::io::outdir::lock(&req.results, "compare")?;
    let dest = req.dest();
    let stale = check_destination(req, &dest)?;
    require_compare_folder(&dest)?;
    let rows = read::read_runs(&req.results)?;
    let traced = req.results.join("ioh").is_dir();
    // What the folder itself certifies: the exact solver's optimum and lower bound per problem.
    let certified = if traced || !req.external.is_empty() {
        read::certificates(&req.results)?
    } else {
        BTreeMap::new()
    };
    // Optimisers from outside somnurbs (issue 39), matched and checked first: external.rs.
    let (rows, external) = super::external::join(&req.results, &req.external, rows, &certified)?;
    let (opts, cells) = cells::gather(&rows);
    if opts.len() < 2 {
        anyhow::bail!("{}: only one optimiser ({}); nothing to compare", runs_csv.display(), opts[0]);
    }
    // The traces first, so that a folder whose ioh/ does not match runs.csv gets nothing written.
    let probs = if traced {
        Some(runtime::problems(&rows, &req.results, external, &certified)?)
    } else {
        None
    };
    let coverage = Coverage::of(&cells, &opts);
    if let Some(line) = coverage.note() {
        crate::notice::emit(&format!("somnurbs: warning: {line} ({SUMMARY} names the cells each did not run)"));
    }
    let per_cell = cells::pairwise_cells(&cells, &opts, req.alpha);
    if let Some((n, sr, rs)) = per_cell.unreachable.smallest {
        let u = &per_cell.unreachable;
        crate::notice::emit(&format!("somnurbs: warning: of {} cell comparisons, {} cannot reach alpha {} by the signed-rank test and {} by the rank-sum test with their repeats (with {n} repeats a two-sided p is at least {sr} signed-rank, {rs} rank-sum): there h is 0 and no cell is favoured whatever the data (compare_cells.csv: min_p_signed_rank, min_p_rank_sum, can_reach_alpha)", u.of, u.signed_rank, req.alpha, u.rank_sum));
    }
    crate::io::outdir::remove_stale(&stale, &dest, "compare")?;
    // Built whole in a sibling folder and swapped in: a reader sees the old tables or the new, and
    // any failed step (a test, a table or a chart) leaves the old folder as it was.
    crate::io::outdir::replace_dir(&dest, |out| {
        analyse(req, &rows, opts, coverage, per_cell, probs)
            .and_then(|a| write_folder(req, &a, out))
            .with_context(|| format!("{} left as it was", dest.display()))
    })
}

/// The tests over cells and the runtime distributions of the gathered runs.
fn analyse(
    req: &Request,
    rows: &[super::OptimRow],
    opts: Vec<String>,
    coverage: Coverage,
    per_cell: PerCell,
    probs: Option<Vec<runtime::Problem>>,
) -> Result<Analysis> {
    let over = if coverage.common >= 2 {
        let runs_csv = req.results.join("runs.csv");
        let overall = over_cells::overall(rows, &opts, &per_cell.wins, &runs_csv)?;
        Some((overall, bayes::bayes_table(rows, &opts, req.rope, req.bayes_samples)?))
    } else {
        None
    };
    let runtime = probs.map(|p| (runtime::runtime(&p, &opts), p));
    Ok(Analysis { opts, coverage, per_cell, over, runtime })
}

/// Write every table and chart of `compare` into `out` (the staged folder), then compare.md, the
/// record last, with the summary on stdout.
fn write_folder(req: &Request, a: &Analysis, out: &Path) -> Result<()> {
    write_table(&out.join("compare_cells.csv"), &a.per_cell.rows)?;
    let mut written = String::from("compare_cells.csv");
    let mut cd_note = "";
    let mut said: Vec<String> = Vec::new();
    let mut say = |lines: Vec<String>| {
        for l in &lines {
            println!("{l}");
        }
        said.extend(lines);
    };
    match &a.over {
        Some((overall, bayes_rows)) => {
            write_table(&out.join("compare_overall.csv"), &overall.rows)?;
            match over_cells::render_cd(overall, &a.coverage, &out.join("cd_diagram.png")) {
                Ok(true) => cd_note = ", critical-difference diagram cd_diagram.png",
                Ok(false) => {}
                Err(e) => chart_skipped(e)?,
            }
            say(over_cells::summary(overall, &a.coverage));
            write_table(&out.join("compare_bayes.csv"), bayes_rows)?;
            say(bayes::summary(bayes_rows, &a.coverage));
            written.push_str(", compare_overall.csv, compare_bayes.csv");
        }
        None => say(vec![format!("  {} cell(s) that every optimiser ran: the tests over cells (Friedman, Nemenyi, Bayesian signed-rank) need two or more; the per-cell tests are in compare_cells.csv", a.coverage.common)]),
    }
    match &a.runtime {
        Some((rt, probs)) => {
            written.push_str(&runtime_files::runtime_outputs(rt, probs, &a.opts, out)?);
            said.extend(runtime_files::summary(rt, probs));
        }
        None => say(vec!["  no ioh/ folder: runtime distributions skipped".into()]),
    }
    write_atomic(&out.join(SUMMARY), markdown(req, a, &said).as_bytes())?;
    // Last: the record that makes the folder a compare's (a later compare may replace it).
    let record = format!(
        "results = {:?}\nalpha = {:?}\nrope = {:?}\nbayes_samples = {}\nsomnurbs = {:?}\n",
        req.results.display().to_string(),
        req.alpha,
        req.rope,
        req.bayes_samples,
        env!("CARGO_PKG_VERSION")
    );
    write_atomic(&out.join(RECORD), record.as_bytes())?;
    println!("wrote {written}, {SUMMARY}{cd_note} in {}", req.dest().display());
    Ok(())
}

/// The Markdown summary of a compare: which optimiser ran which cells and what the statistics
/// over cells use, then the summary lines of stdout.
fn markdown(req: &Request, a: &Analysis, said: &[String]) -> String {
    let c = &a.coverage;
    let mut md = format!("# somnurbs compare\n\nResults folder: `{}`; alpha {}, rope {:e}, {} Bayesian samples.\n\n## Which optimiser ran which cells\n\n| optimiser | cells run | of | cells not run |\n|---|---|---|---|\n", req.results.display(), req.alpha, req.rope, req.bayes_samples);
    for ((o, k), (_, missing)) in c.ran.iter().zip(&c.missing) {
        md.push_str(&format!("| {o} | {k} | {} | {} |\n", c.cells, missing.join("; ")));
    }
    md.push('\n');
    match c.note() {
        None => md.push_str(&format!("Every optimiser ran every cell: the tests over cells use all {}.\n", c.cells)),
        Some(note) => md.push_str(&format!("**Not every optimiser ran every cell** {}.\n", note.trim_start_matches("not every optimiser ran every cell "))),
    }
    md.push_str("\n## Summary\n\n```text\n");
    for l in said {
        md.push_str(l);
        md.push('\n');
    }
    md.push_str("```\n");
    md
}

/// `path` made absolute, with the links of its nearest existing ancestor resolved and the rest
/// (which need not exist yet) taken as written; and that ancestor.
fn resolved(path: &Path) -> Result<(PathBuf, PathBuf)> {
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
fn check_destination(req: &Request, dest: &Path) -> Result<Vec<PathBuf>> {
    let (anchor, full) = resolved(dest)?;
    let default = resolved(&req.results.join(OUT_DIR))?.1;
    if full != default {
        if let Some(folder) = crate::io::outdir::result_folder_of(&anchor.join(OUT_DIR)) {
            anyhow::bail!("compare --out {} is inside the result folder {}, which holds one run and nothing else: give --out a folder outside it (or no --out, for {})", dest.display(), folder.display(), req.results.join(OUT_DIR).display());
        }
    }
    let stale = match full.parent() {
        Some(_) => crate::io::outdir::stale_siblings(&full)?,
        None => Vec::new(),
    };
    for ext in &req.external {
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
/// The Markdown summary `compare` writes in its folder: which optimiser ran which cells, what the
/// statistics over cells use, and the summary lines of stdout.
const SUMMARY: &str = "compare.md";

/// `compare` writes a folder of its own: missing, empty, or an earlier compare's (which it
/// replaces whole); anything else is refused.
fn require_compare_folder(dest: &Path) -> Result<()> {
    let found = crate::io::outdir::entries(dest)?;
    if found.is_empty() || found.iter().any(|e| e == RECORD) {
        return Ok(());
    }
    crate::io::outdir::require_empty(dest).context("compare --out")
}

#[cfg(test)]
mod tests;
