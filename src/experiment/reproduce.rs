//! `somnurbs reproduce`: the thesis' chapters in order, each spec in its own sub-folder, the maps
//! of Chapter 4 feeding Chapters 5 and 6, then one REPORT.md that joins the chapters' reports
//! and adds what needs more than one spec: Tables 6.8 and 6.9 (Tables 6.4 + 6.5 and 6.6 + 6.7)
//! and one table of the thesis' claims with their verdicts. The list of specs is data
//! (`experiments/thesis.toml`).

use super::spec::Spec;
use super::{run_spec, RunContext};
use crate::report::claims::{self, Claim};
use crate::report::fsio::{csv_records, write_atomic};
use anyhow::{Context, Result};
use serde::Deserialize;
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A plan: `experiments/thesis.toml` (Chapters 4-6), `seeds.toml`, `all.toml`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plan {
    /// The combined report's title.
    #[serde(default = "default_title")]
    pub title: String,
    /// Spec names (files `<name>.toml` beside the plan), run in this order.
    pub specs: Vec<String>,
    /// The spec whose `maps/` folder the later specs read (plans with Chapters 5 or 6).
    #[serde(default)]
    pub maps_from: Option<String>,
}

fn default_title() -> String {
    "reproduction of the thesis".into()
}

impl Plan {
    pub fn load(path: &Path) -> Result<Plan> {
        let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
        let plan: Plan = toml::from_str(&text).map_err(|e| anyhow::anyhow!("{}: {}", path.display(), e.message()))?;
        if plan.specs.is_empty() {
            anyhow::bail!("{}: specs: is empty", path.display());
        }
        if let Some(m) = plan.maps_from.as_ref().filter(|m| !plan.specs.contains(m)) {
            anyhow::bail!("{}: maps_from: `{m}` is not one of the specs", path.display());
        }
        Ok(plan)
    }
}

/// Load every spec of the plan (all before any runs, so a bad one stops nothing half-way), with
/// the maps of the later ones pointed at `<out>/<maps_from>/maps`.
fn load_specs(dir: &Path, plan: &Plan, profile: Option<&str>, out: &Path) -> Result<Vec<Spec>> {
    let maps = plan.maps_from.as_ref().map(|m| out.join(m).join("maps").to_string_lossy().into_owned());
    plan.specs
        .iter()
        .map(|name| {
            let path = dir.join(format!("{name}.toml"));
            let mut spec = Spec::load(&path, profile.filter(|p| has_profile(&path, p)))?;
            if let Some(maps) = &maps {
                if let Some(f) = spec.file.fit.as_mut() {
                    f.maps = Some(maps.clone());
                }
                if let Some(o) = spec.file.optim.as_mut() {
                    o.maps = Some(maps.clone());
                }
            }
            Ok(spec)
        })
        .collect()
}

/// Whether a spec defines the profile (a spec without `quick` runs as it is, e.g. one that is
/// already quick).
fn has_profile(path: &Path, profile: &str) -> bool {
    std::fs::read_to_string(path).ok().and_then(|t| t.parse::<toml::Table>().ok()).and_then(|t| t.get("profiles").and_then(|p| p.get(profile)).map(|_| ())).is_some()
}

/// Run the plan into `ctx.out` and write the combined REPORT.md; returns its path.
pub fn reproduce(specs_dir: &Path, plan_name: &str, profile: &str, ctx: &RunContext) -> Result<PathBuf> {
    let plan_path = specs_dir.join(format!("{plan_name}.toml"));
    if !plan_path.exists() {
        anyhow::bail!("--plan {plan_name}: no plan file {}", plan_path.display());
    }
    let plan = Plan::load(&plan_path)?;
    let profile = if profile == "full" { None } else { Some(profile) };
    let specs = load_specs(specs_dir, &plan, profile, &ctx.out)?;
    // Every data set of every spec loads before the folder changes (a bad --data-dir changes nothing).
    for spec in &specs {
        for d in super::limits::dataset_entries(spec) {
            crate::data::registry::load_dataset(d, &ctx.data_dir).with_context(|| format!("{}: data set `{d}`", spec.path))?;
        }
    }
    let _lock = crate::outdir::lock(&ctx.out, &format!("reproduce --plan {plan_name}"))?;
    // Every spec has loaded: the folder is unfinished until the combined REPORT.md is written.
    let incomplete = ctx.out.join(crate::outdir::INCOMPLETE);
    write_atomic(&incomplete, format!("reproduce --plan {plan_name} --profile {} started here\n", profile.unwrap_or("full")).as_bytes())?;
    let started = Instant::now();
    let mut done = Vec::new();
    for spec in &specs {
        let sub = RunContext { out: ctx.out.join(&spec.file.name), ..ctx.clone() };
        eprintln!("somnurbs: reproduce: {} -> {}", spec.file.name, sub.out.display());
        let t = Instant::now();
        run_spec(spec, &sub)?;
        done.push((spec.file.name.clone(), t.elapsed().as_secs_f64()));
    }
    let report = combined_report(&ctx.out, &plan, plan_name, &specs, &done, profile.unwrap_or("full"), started.elapsed().as_secs_f64())?;
    let path = ctx.out.join("REPORT.md");
    write_atomic(&path, report.as_bytes())?;
    std::fs::remove_file(&incomplete).with_context(|| format!("cannot remove {}", incomplete.display()))?;
    crate::outdir::sync_dir(&ctx.out)?;
    Ok(path)
}

/// A win-count table (Tables 6.4-6.7: data, parameterisation, one column per optimiser, cells).
fn win_table(path: &Path) -> Result<Option<(Vec<String>, Vec<usize>)>> {
    if !path.exists() {
        return Ok(None);
    }
    let mut rd = csv::Reader::from_path(path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let header: Vec<String> = rd.headers().map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?.iter().map(String::from).collect();
    let opts: Vec<String> = header.iter().filter(|h| !["data", "parameterisation", "cells"].contains(&h.as_str())).cloned().collect();
    let mut sums = vec![0usize; opts.len() + 1];
    for (n, rec) in rd.records().enumerate() {
        let rec = rec.map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
        if rec.get(0) == Some("total") {
            continue;
        }
        for (k, name) in opts.iter().chain(std::iter::once(&"cells".to_string())).enumerate() {
            let col = header.iter().position(|h| h == name).context("column")?;
            sums[k] += rec.get(col).unwrap_or("").parse::<usize>().map_err(|_| anyhow::anyhow!("{}: line {}: {name} is not a count", path.display(), n + 2))?;
        }
    }
    Ok(Some((opts, sums)))
}

/// Table 6.8 (errors) or 6.9 (CPU time): one row per source table, `wins/cells` per optimiser,
/// and a total row; `None` if neither source table exists.
fn overall(out: &Path, sources: &[(&str, &str)], name: &str) -> Result<Option<(String, Vec<String>, Vec<Vec<String>>)>> {
    let mut rows = Vec::new();
    let mut opts: Vec<String> = Vec::new();
    let mut total: Vec<usize> = Vec::new();
    for (spec, table) in sources {
        if let Some((o, sums)) = win_table(&out.join(spec).join(format!("{table}.csv")))? {
            if opts.is_empty() {
                opts = o.clone();
                total = vec![0; o.len() + 1];
            }
            if o != opts {
                anyhow::bail!("{spec}/{table}.csv has optimisers {o:?}, another table has {opts:?}");
            }
            let cells = sums[o.len()];
            let mut row = vec![format!("Table {}", &table["table_".len()..].replace('_', "."))];
            row.extend(sums[..o.len()].iter().map(|w| format!("{w}/{cells}")));
            rows.push(row);
            for (t, s) in total.iter_mut().zip(&sums) {
                *t += s;
            }
        }
    }
    if rows.is_empty() {
        return Ok(None);
    }
    let cells = total[opts.len()];
    let mut row = vec!["overall".to_string()];
    row.extend(total[..opts.len()].iter().map(|w| format!("{w}/{cells}")));
    rows.push(row);
    let mut header = vec!["table".to_string()];
    header.extend(opts.iter().cloned());
    write_atomic(&out.join(format!("{name}.csv")), csv_records(&header, &rows)?.as_bytes())?;
    Ok(Some((name.to_string(), header, rows)))
}

fn markdown_table(header: &[String], rows: &[Vec<String>]) -> String {
    let mut s = format!("| {} |\n|{}|\n", header.join(" | "), header.iter().map(|_| "---").collect::<Vec<_>>().join("|"));
    for r in rows {
        let _ = writeln!(s, "| {} |", r.join(" | "));
    }
    s
}

/// The combined REPORT.md: header, claims, Tables 6.8/6.9, then each chapter's report with its
/// links pointed into its sub-folder.
fn combined_report(out: &Path, plan: &Plan, plan_name: &str, specs: &[Spec], done: &[(String, f64)], profile: &str, wall: f64) -> Result<String> {
    let mut s = format!("# somnurbs: {}\n\n", plan.title);
    let commit = env!("SOMNURBS_GIT_COMMIT");
    let _ = writeln!(
        s,
        "Plan `{plan_name}`, profile `{profile}`, somnurbs {} at commit {}{}, {}: {} specs in {:.1} s wall. Re-run: `somnurbs reproduce --plan {plan_name} --profile {profile}`.\n",
        env!("CARGO_PKG_VERSION"),
        &commit[..commit.len().min(12)],
        if env!("SOMNURBS_GIT_DIRTY") == "true" { " (dirty)" } else { "" },
        env!("SOMNURBS_RUSTC"),
        done.len(),
        wall
    );
    s.push_str("| spec | folder | wall s |\n|---|---|---|\n");
    for (name, secs) in done {
        let _ = writeln!(s, "| {name} | [`{name}/`]({name}/REPORT.md) | {secs:.1} |");
    }
    let names: Vec<&str> = specs.iter().map(|sp| sp.file.name.as_str()).collect();
    let find = |grid_same: bool| names.iter().copied().find(|n| n.starts_with("ch6") && n.ends_with(if grid_same { "same" } else { "diff" }));
    let (same, diff) = (find(true), find(false));
    let mut all: Vec<Claim> = Vec::new();
    let mut thesis_ch6: Vec<Claim> = Vec::new();
    for spec in specs {
        let path = out.join(&spec.file.name).join("claims.csv");
        if path.exists() {
            let mut cs = claims::read(&path)?;
            cs.retain(|c| c.ours.1 > 0);
            if Some(spec.file.name.as_str()) == same || Some(spec.file.name.as_str()) == diff {
                thesis_ch6.extend(cs.iter().cloned());
            } else {
                // Claims of the specs beyond the thesis' protocol say so.
                for c in cs.iter_mut().filter(|c| c.chapter == "6") {
                    c.chapter = format!("6 ({})", spec.file.name);
                }
            }
            all.extend(cs);
        }
    }
    all.extend(overall_claims(&thesis_ch6));
    let table = claims::write(out, &all)?;
    let holding = all.iter().filter(|c| c.holds()).count();
    if !all.is_empty() {
        let _ = writeln!(s, "\n## Claims\n\nEach claim of the thesis (or, for the other seeds, of the paper) is counted on this reproduction (`here`) and, where the published tables allow, on the source's own figures; {holding} of {} hold in every case checked here. Also in `claims.csv`.\n", all.len());
        s.push_str(&table);
    }
    let sources = |a: &'static str, b: &'static str| -> Vec<(&str, &str)> { same.map(|n| (n, a)).into_iter().chain(diff.map(|n| (n, b))).collect() };
    for (name, title, thesis, src) in [
        ("table_6_8", "Table 6.8: least average optimised surface error, overall", "thesis: GA 0/280, DE 243/280, PSO 37/280", sources("table_6_4", "table_6_5")),
        ("table_6_9", "Table 6.9: least average CPU time, overall", "thesis: GA 280/280, DE 0/280, PSO 0/280", sources("table_6_6", "table_6_7")),
    ] {
        if let Some((file, h, r)) = overall(out, &src, name)? {
            let _ = writeln!(s, "\n## {title}\n\n`{file}.csv` ({thesis}).\n\n{}", markdown_table(&h, &r));
        }
    }
    for spec in specs {
        let name = &spec.file.name;
        let path = out.join(name).join("REPORT.md");
        let text = std::fs::read_to_string(&path).with_context(|| format!("cannot read {}", path.display()))?;
        let _ = writeln!(s, "\n---\n\n# {name}\n");
        for line in text.lines().skip_while(|l| l.starts_with("# ") || l.trim().is_empty()) {
            // Sub-reports' headings one level down, their links into the sub-folder.
            let line = if line.starts_with('#') { format!("#{line}") } else { line.to_string() };
            s.push_str(&relink(&line, name));
            s.push('\n');
        }
    }
    Ok(s)
}

/// Chapter 6's claims over both grids (Tables 6.8 and 6.9): the per-grid counts summed, here
/// and on the thesis' own figures.
fn overall_claims(per_grid: &[Claim]) -> Vec<Claim> {
    let mut out = Vec::new();
    for (stem, statement, note) in [
        ("DE gives the least average error in most cells (grid", "DE gives the least average error in most cells, both grids (Table 6.8; thesis text: 243/280)", "sum of the two grids' counts"),
        ("GA is the fastest (grid", "GA is the fastest in every cell, both grids (Table 6.9; thesis text: 280/280)", "sum of the two grids' counts"),
    ] {
        let parts: Vec<&Claim> = per_grid.iter().filter(|c| c.statement.starts_with(stem)).collect();
        if parts.len() < 2 {
            continue;
        }
        let ours = parts.iter().fold((0, 0), |a, c| (a.0 + c.ours.0, a.1 + c.ours.1));
        let thesis = parts.iter().try_fold((0, 0), |a, c| c.thesis.map(|t| (a.0 + t.0, a.1 + t.1)));
        out.push(Claim { chapter: "6".into(), statement: statement.into(), ours, thesis, note: note.into() });
    }
    out
}

/// Point the relative links and images of a sub-report's line into its folder.
fn relink(line: &str, folder: &str) -> String {
    let mut out = String::with_capacity(line.len());
    let mut rest = line;
    while let Some(k) = rest.find("](") {
        out.push_str(&rest[..k + 2]);
        rest = &rest[k + 2..];
        if !(rest.starts_with("http") || rest.starts_with('/') || rest.starts_with('#')) {
            out.push_str(folder);
            out.push('/');
        }
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn links_point_into_the_sub_folder() {
        assert_eq!(relink("![a](png/a.png) and [b](https://x) [c](#c)", "ch4"), "![a](ch4/png/a.png) and [b](https://x) [c](#c)");
    }

    #[test]
    fn overall_tables_sum_the_win_counts() {
        let dir = tempfile::tempdir().unwrap();
        for (spec, table, rows) in [("ch6_same", "table_6_4", "cube,uniform,0,6,1,7\nsphere,uniform,1,5,1,7\ntotal,,1,11,2,14\n"), ("ch6_diff", "table_6_5", "cube,uniform,0,7,0,7\n")] {
            std::fs::create_dir_all(dir.path().join(spec)).unwrap();
            std::fs::write(dir.path().join(spec).join(format!("{table}.csv")), format!("data,parameterisation,ga,de,pso,cells\n{rows}")).unwrap();
        }
        let (_, h, r) = overall(dir.path(), &[("ch6_same", "table_6_4"), ("ch6_diff", "table_6_5")], "table_6_8").unwrap().unwrap();
        assert_eq!(h, vec!["table", "ga", "de", "pso"]);
        assert_eq!(r[0], vec!["Table 6.4", "1/14", "11/14", "2/14"]);
        assert_eq!(r[2], vec!["overall", "1/21", "18/21", "2/21"]);
        std::fs::write(dir.path().join("ch6_diff/table_6_5.csv"), "data,parameterisation,ga,de,pso,cells\ncube,uniform,x,7,0,7\n").unwrap();
        let e = overall(dir.path(), &[("ch6_same", "table_6_4"), ("ch6_diff", "table_6_5")], "t").unwrap_err().to_string();
        assert!(e.contains("table_6_5.csv: line 2: ga"), "{e}");
    }
}
