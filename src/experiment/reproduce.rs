//! `somnurbs reproduce`: the thesis' chapters in order, each spec in its own sub-folder, the maps
//! of Chapter 4 feeding Chapters 5 and 6, then one REPORT.md that joins the chapters' reports
//! and adds what needs more than one spec: Tables 6.8 and 6.9 (Tables 6.4 + 6.5 and 6.6 + 6.7)
//! and one table of the thesis' claims with their verdicts. The list of specs is data
//! (`experiments/thesis.toml`).

use super::spec::{Override, Spec};
use super::{run_spec, RunContext};
use crate::io::{csv_records, write_atomic};
use crate::report::claims::{self, Claim};
use anyhow::{Context, Result};
use serde::Deserialize;
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A table's header and rows, as `csv_records` takes them.
type Header = Vec<String>;
type Rows = Vec<Vec<String>>;

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
    /// The name of the readings the specs make as written (a row label of the readings matrix).
    #[serde(default = "default_reading")]
    pub reading: String,
    /// Other reading sets: each runs the specs it names again with its overrides, into
    /// `readings/<name>/`, and the report sets every claim under every reading side by side.
    #[serde(default)]
    pub readings: Vec<ReadingSet>,
}

/// A named set of readings (README "Readings"): dotted spec keys and the values to use.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReadingSet {
    pub name: String,
    #[serde(default)]
    pub description: String,
    /// E.g. `"fit.knots" = "nurbs_book"`; a key is applied to the specs that have its section.
    pub set: std::collections::BTreeMap<String, toml::Value>,
    /// Which of the plan's specs run under this set.
    pub specs: Vec<String>,
}

impl ReadingSet {
    fn overrides(&self) -> Vec<Override> {
        self.set.iter().map(|(k, v)| Override { key: k.clone(), value: v.clone() }).collect()
    }
}

fn default_reading() -> String {
    "as_written".into()
}

/// A reading-set name is a folder name: lower-case letters, digits and `_`.
fn valid_name(name: &str) -> bool {
    !name.is_empty()
        && name.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
}

fn default_title() -> String {
    "reproduction of the thesis".into()
}

impl Plan {
    pub fn load(path: &Path) -> Result<Plan> {
        let plan: Plan = crate::io::read_toml(path)?;
        if plan.specs.is_empty() {
            anyhow::bail!("{}: specs: is empty", path.display());
        }
        if let Some(m) = plan.maps_from.as_ref().filter(|m| !plan.specs.contains(m)) {
            anyhow::bail!("{}: maps_from: `{m}` is not one of the specs", path.display());
        }
        let mut names = vec![plan.reading.as_str()];
        for r in &plan.readings {
            if !valid_name(&r.name) {
                anyhow::bail!(
                    "{}: readings: name `{}` must be lower-case letters, digits and _",
                    path.display(),
                    r.name
                );
            }
            if names.contains(&r.name.as_str()) {
                anyhow::bail!("{}: readings: the name `{}` is used twice", path.display(), r.name);
            }
            names.push(&r.name);
            if let Some(s) = r.specs.iter().find(|s| !plan.specs.contains(s)) {
                anyhow::bail!(
                    "{}: readings.{}.specs: `{s}` is not one of the plan's specs",
                    path.display(),
                    r.name
                );
            }
            if r.set.is_empty() {
                anyhow::bail!("{}: readings.{}.set: is empty", path.display(), r.name);
            }
        }
        Ok(plan)
    }
}

/// Load every spec of the plan (all before any runs, so a bad one stops nothing half-way), with
/// the maps of the later ones pointed at `<out>/<maps_from>/maps`; `names` and `overrides` select
/// a reading set's specs and apply its keys.
fn load_specs(
    dir: &Path,
    plan: &Plan,
    names: &[String],
    overrides: &[Override],
    profile: Option<&str>,
    out: &Path,
) -> Result<Vec<Spec>> {
    let maps =
        plan.maps_from.as_ref().map(|m| out.join(m).join("maps").to_string_lossy().into_owned());
    names
        .iter()
        .map(|name| {
            let path = dir.join(format!("{name}.toml"));
            let shown = path.display().to_string();
            let text = std::fs::read_to_string(&path)
                .with_context(|| format!("{shown}: cannot read spec"))?;
            let mut spec = Spec::parse_with(
                &shown,
                &text,
                profile.filter(|p| has_profile(&path, p)),
                overrides,
            )?;
            if let Some(maps) = &maps {
                for family in super::family::present(&spec) {
                    family.use_maps(&mut spec, maps);
                }
            }
            Ok(spec)
        })
        .collect()
}

/// Whether a spec defines the profile (a spec without `quick` runs as it is, e.g. one that is
/// already quick).
fn has_profile(path: &Path, profile: &str) -> bool {
    std::fs::read_to_string(path)
        .ok()
        .and_then(|t| t.parse::<toml::Table>().ok())
        .and_then(|t| t.get("profiles").and_then(|p| p.get(profile)).map(|_| ()))
        .is_some()
}

/// Run the plan into `ctx.out` and write the combined REPORT.md; returns its path.
pub fn reproduce(
    specs_dir: &Path,
    plan_name: &str,
    profile: &str,
    ctx: &RunContext,
) -> Result<PathBuf> {
    let plan_path = specs_dir.join(format!("{plan_name}.toml"));
    if !plan_path.exists() {
        anyhow::bail!("--plan {plan_name}: no plan file {}", plan_path.display());
    }
    let plan = Plan::load(&plan_path)?;
    let profile = if profile == "full" { None } else { Some(profile) };
    let specs = load_specs(specs_dir, &plan, &plan.specs, &[], profile, &ctx.out)?;
    let reading_specs: Vec<(&ReadingSet, Vec<Spec>)> = plan
        .readings
        .iter()
        .map(|r| {
            Ok((r, load_specs(specs_dir, &plan, &r.specs, &r.overrides(), profile, &ctx.out)?))
        })
        .collect::<Result<_>>()?;
    // Every data set of every spec loads before the folder changes (a bad --data-dir changes nothing).
    for spec in &specs {
        for d in super::limits::dataset_entries(spec) {
            ctx.loader(spec).load(d).with_context(|| format!("{}: data set `{d}`", spec.path))?;
        }
    }
    let _lock = crate::io::outdir::lock(&ctx.out, &format!("reproduce --plan {plan_name}"))?;
    // Every spec has loaded: the folder is unfinished until the combined REPORT.md is written.
    let incomplete = ctx.out.join(crate::io::outdir::INCOMPLETE);
    write_atomic(
        &incomplete,
        format!(
            "reproduce --plan {plan_name} --profile {} started here\n",
            profile.unwrap_or("full")
        )
        .as_bytes(),
    )?;
    let started = Instant::now();
    let mut done = Vec::new();
    for spec in &specs {
        let sub = RunContext { out: ctx.out.join(&spec.file.name), ..ctx.clone() };
        eprintln!("somnurbs: reproduce: {} -> {}", spec.file.name, sub.out.display());
        let t = Instant::now();
        run_spec(spec, &sub)?;
        done.push((spec.file.name.clone(), t.elapsed().as_secs_f64()));
    }
    for (reading, rspecs) in &reading_specs {
        for spec in rspecs {
            let folder = Path::new(READINGS_DIR).join(&reading.name).join(&spec.file.name);
            let sub = RunContext { out: ctx.out.join(&folder), ..ctx.clone() };
            eprintln!(
                "somnurbs: reproduce: {} under the readings `{}` -> {}",
                spec.file.name,
                reading.name,
                sub.out.display()
            );
            let t = Instant::now();
            run_spec(spec, &sub)?;
            done.push((folder.to_string_lossy().into_owned(), t.elapsed().as_secs_f64()));
        }
    }
    let mut report = combined_report(
        &ctx.out,
        &plan,
        plan_name,
        &specs,
        &done,
        profile.unwrap_or("full"),
        started.elapsed().as_secs_f64(),
    )?;
    if !plan.readings.is_empty() {
        let matrix = readings_matrix(&ctx.out, &plan)?;
        report.push_str(&render_readings(&ctx.out, &plan, &matrix)?);
    }
    let path = ctx.out.join("REPORT.md");
    write_atomic(&path, report.as_bytes())?;
    crate::report::html::write(&ctx.out)?;
    std::fs::remove_file(&incomplete)
        .with_context(|| format!("cannot remove {}", incomplete.display()))?;
    crate::io::outdir::sync_dir(&ctx.out)?;
    Ok(path)
}

/// Where the reading sets' runs go, inside the plan's output folder.
pub const READINGS_DIR: &str = "readings";

/// One claim under one reading.
struct ReadingClaim {
    reading: String,
    folder: String,
    claim: Claim,
}

/// Every claim of the specs that some reading set runs, under the plan's own reading and under
/// each set (read back from each run's `claims.csv`).
fn readings_matrix(out: &Path, plan: &Plan) -> Result<Vec<ReadingClaim>> {
    let mut compared: Vec<&String> = Vec::new();
    for r in &plan.readings {
        for s in &r.specs {
            if !compared.contains(&s) {
                compared.push(s);
            }
        }
    }
    let mut rows = Vec::new();
    let mut collect = |reading: &str, folder: PathBuf, name: &str| -> Result<()> {
        let path = folder.join("claims.csv");
        if path.exists() {
            for claim in claims::read(&path)? {
                rows.push(ReadingClaim {
                    reading: reading.to_string(),
                    folder: name.to_string(),
                    claim,
                });
            }
        }
        Ok(())
    };
    for s in &compared {
        collect(&plan.reading, out.join(s), s)?;
    }
    for r in &plan.readings {
        for s in &r.specs {
            collect(&r.name, out.join(READINGS_DIR).join(&r.name).join(s), s)?;
        }
    }
    Ok(rows)
}

/// `readings.csv` and the REPORT.md section: one row per (spec, claim), one column per reading,
/// and whether the verdict changes with the reading.
fn render_readings(out: &Path, plan: &Plan, rows: &[ReadingClaim]) -> Result<String> {
    let header: Vec<String> =
        ["spec", "chapter", "claim", "reading", "verdict", "holds", "checked", "note"]
            .iter()
            .map(|s| s.to_string())
            .collect();
    let csv_rows: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                r.folder.clone(),
                r.claim.chapter.clone(),
                r.claim.statement.clone(),
                r.reading.clone(),
                r.claim.verdict().to_string(),
                r.claim.ours.0.to_string(),
                r.claim.ours.1.to_string(),
                r.claim.note.clone(),
            ]
        })
        .collect();
    write_atomic(&out.join("readings.csv"), csv_records(&header, &csv_rows)?.as_bytes())?;
    let mut readings = vec![plan.reading.clone()];
    readings.extend(plan.readings.iter().map(|r| r.name.clone()));
    let mut s = String::from("\n---\n\n# Readings matrix\n\nThe thesis leaves some steps ambiguous; each is a named spec option (README, \"Readings\"). The plan's specs ran as written");
    let _ = write!(s, " (reading `{}`) and again under each reading set below, from the same maps and seeds; every claim is shown under every reading, so a reader sees which conclusions rest on which reading (`readings.csv`).\n\n", plan.reading);
    for r in &plan.readings {
        let keys: Vec<String> = r.set.iter().map(|(k, v)| format!("`{k} = {v}`")).collect();
        let _ = writeln!(
            s,
            "- `{}`: {} ({}; specs {}; folders `readings/{}/`)",
            r.name,
            r.description,
            keys.join(", "),
            r.specs.join(", "),
            r.name
        );
    }
    let mut keys: Vec<(String, String)> = Vec::new();
    for r in rows {
        let k = (r.folder.clone(), r.claim.statement.clone());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    let mut h = vec!["spec".to_string(), "claim".into()];
    h.extend(readings.iter().map(|r| format!("`{r}`")));
    h.push("changes with the reading".into());
    let mut md_rows = Vec::new();
    let mut changing = 0;
    for (folder, statement) in &keys {
        let cells: Vec<Option<&Claim>> = readings
            .iter()
            .map(|rd| {
                rows.iter()
                    .find(|r| {
                        &r.reading == rd && &r.folder == folder && &r.claim.statement == statement
                    })
                    .map(|r| &r.claim)
            })
            .collect();
        let verdicts: Vec<&str> = cells.iter().flatten().map(|c| c.verdict()).collect();
        let changes = verdicts.windows(2).any(|w| w[0] != w[1]);
        changing += changes as usize;
        let mut row = vec![folder.clone(), statement.clone()];
        row.extend(cells.iter().map(|c| {
            c.map(|c| format!("{} {}/{}", c.verdict(), c.ours.0, c.ours.1))
                .unwrap_or_else(|| "-".into())
        }));
        row.push(if changes { "**yes**".into() } else { "no".into() });
        md_rows.push(row);
    }
    let _ = writeln!(
        s,
        "\n{changing} of {} claims change their verdict with the reading.\n",
        keys.len()
    );
    s.push_str(&markdown_table(&h, &md_rows));
    if let Some(chart) = error_vs_excursion(out, plan)? {
        let _ = writeln!(s, "\n![{chart}]({chart})\n\nSurface error against the largest distance of the fitted surfaces from the data's bounding box (log scale), one point per control net, for one data set under each reading: a reading can lower the error at the data points while its surfaces leave the data between them.");
    }
    Ok(s)
}

/// One fitted cell as a readings chart needs it (from a Chapter 5 `runs.csv`).
#[derive(Debug, Deserialize)]
struct FitPoint {
    dataset: String,
    cn_x: usize,
    parameterisation: String,
    approach: String,
    surface_error: f64,
    excursion: f64,
}

/// The chart of surface error against excursion across readings: the first Chapter 5 spec every
/// reading ran, its first data set, chord length, approach B. Returns its path in `out`.
fn error_vs_excursion(out: &Path, plan: &Plan) -> Result<Option<String>> {
    let Some(spec) = plan.specs.iter().find(|s| {
        plan.readings.iter().all(|r| r.specs.contains(s))
            && out.join(s).join("runs.csv").exists()
            && is_fit_runs(&out.join(s).join("runs.csv"))
    }) else {
        return Ok(None);
    };
    let mut folders = vec![(plan.reading.clone(), out.join(spec))];
    folders.extend(
        plan.readings
            .iter()
            .map(|r| (r.name.clone(), out.join(READINGS_DIR).join(&r.name).join(spec))),
    );
    let mut series = Vec::new();
    let mut data_set = None;
    for (k, (name, folder)) in folders.iter().enumerate() {
        let path = folder.join("runs.csv");
        let points: Vec<FitPoint> = crate::io::read_rows(&path)?;
        let d = data_set
            .get_or_insert_with(|| points.first().map(|p| p.dataset.clone()).unwrap_or_default())
            .clone();
        let mut pts: Vec<(usize, f64, f64)> = points
            .iter()
            .filter(|p| {
                p.dataset == d
                    && p.parameterisation == "chord_length"
                    && p.approach == "B"
                    && p.excursion > 0.0
            })
            .map(|p| (p.cn_x, p.excursion.log10(), p.surface_error))
            .collect();
        pts.sort_by_key(|p| p.0);
        series.push(crate::report::plots::Series {
            label: name.clone(),
            colour: crate::report::plots::style::cycle_colour(k),
            points: pts.iter().map(|p| (p.1, p.2)).collect(),
            band: None,
        });
    }
    let name = format!("readings_error_vs_excursion_{spec}.png");
    let title = format!(
        "{spec}, {}, chord length, B: one point per control net",
        data_set.unwrap_or_default()
    );
    match crate::report::plots::line_chart_png(
        &out.join(&name),
        &title,
        "log10 excursion from the data's box",
        "surface error (Eq. 5.13)",
        &series,
        false,
    ) {
        Ok(()) => Ok(Some(name)),
        Err(e) => {
            eprintln!("somnurbs: warning: picture skipped: {e}");
            Ok(None)
        }
    }
}

fn is_fit_runs(path: &Path) -> bool {
    std::fs::read_to_string(path)
        .ok()
        .and_then(|t| {
            t.lines().next().map(|h| {
                h.split(',').any(|c| c == "excursion") && h.split(',').any(|c| c == "approach")
            })
        })
        .unwrap_or(false)
}

/// A win-count table (Tables 6.4-6.7: data, parameterisation, one column per optimiser, cells).
fn win_table(path: &Path) -> Result<Option<(Vec<String>, Vec<usize>)>> {
    if !path.exists() {
        return Ok(None);
    }
    let mut rd = csv::Reader::from_path(path).with_context(|| format!("{}", path.display()))?;
    let header: Vec<String> = rd
        .headers()
        .with_context(|| format!("{}", path.display()))?
        .iter()
        .map(String::from)
        .collect();
    let opts: Vec<String> = header
        .iter()
        .filter(|h| !["data", "parameterisation", "cells"].contains(&h.as_str()))
        .cloned()
        .collect();
    let mut sums = vec![0usize; opts.len() + 1];
    for (n, rec) in rd.records().enumerate() {
        let rec = rec.with_context(|| format!("{}", path.display()))?;
        if rec.get(0) == Some("total") {
            continue;
        }
        for (k, name) in opts.iter().chain(std::iter::once(&"cells".to_string())).enumerate() {
            let col = header.iter().position(|h| h == name).context("column")?;
            sums[k] += rec.get(col).unwrap_or("").parse::<usize>().map_err(|_| {
                anyhow::anyhow!("{}: line {}: {name} is not a count", path.display(), n + 2)
            })?;
        }
    }
    Ok(Some((opts, sums)))
}

/// Table 6.8 (errors) or 6.9 (CPU time): one row per source table, `wins/cells` per optimiser,
/// and a total row; `None` if neither source table exists.
fn overall(
    out: &Path,
    sources: &[(&str, &str)],
    name: &str,
) -> Result<Option<(String, Header, Rows)>> {
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
                anyhow::bail!(
                    "{spec}/{table}.csv has optimisers {o:?}, another table has {opts:?}"
                );
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
    let mut s = format!(
        "| {} |\n|{}|\n",
        header.join(" | "),
        header.iter().map(|_| "---").collect::<Vec<_>>().join("|")
    );
    for r in rows {
        let _ = writeln!(s, "| {} |", r.join(" | "));
    }
    s
}

/// The combined REPORT.md: header, claims, Tables 6.8/6.9, then each chapter's report with its
/// links pointed into its sub-folder.
fn combined_report(
    out: &Path,
    plan: &Plan,
    plan_name: &str,
    specs: &[Spec],
    done: &[(String, f64)],
    profile: &str,
    wall: f64,
) -> Result<String> {
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
    let find = |grid_same: bool| {
        names
            .iter()
            .copied()
            .find(|n| n.starts_with("ch6") && n.ends_with(if grid_same { "same" } else { "diff" }))
    };
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
        let _ = writeln!(s, "\n## Claims\n\nEach claim of the thesis (or, for the other seeds, of the paper) is counted on this reproduction (`here`) and, where the published tables allow, on the source's own figures; {holding} of {} hold here without qualification (verdict **holds**: in every case checked, or, for a best-of-several claim, ahead of every rival). Also in `claims.csv`.\n", all.len());
        s.push_str(&table);
    }
    let sources = |a: &'static str, b: &'static str| -> Vec<(&str, &str)> {
        same.map(|n| (n, a)).into_iter().chain(diff.map(|n| (n, b))).collect()
    };
    for (name, title, thesis, src) in [
        (
            "table_6_8",
            "Table 6.8: least average optimised surface error, overall",
            "thesis: GA 0/280, DE 243/280, PSO 37/280",
            sources("table_6_4", "table_6_5"),
        ),
        (
            "table_6_9",
            "Table 6.9: least average CPU time, overall",
            "thesis: GA 280/280, DE 0/280, PSO 0/280",
            sources("table_6_6", "table_6_7"),
        ),
    ] {
        if let Some((file, h, r)) = overall(out, &src, name)? {
            let _ = writeln!(
                s,
                "\n## {title}\n\n`{file}.csv` ({thesis}).\n\n{}",
                markdown_table(&h, &r)
            );
        }
    }
    let mut seen: Vec<(String, String)> = Vec::new();
    for spec in specs {
        let name = &spec.file.name;
        let path = out.join(name).join("REPORT.md");
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        let _ = writeln!(s, "\n---\n\n# {name}\n");
        s.push_str(&sub_report(&text, name, &mut seen));
    }
    Ok(s)
}

/// A spec's REPORT.md inside the combined one: headings one level down, links into its folder,
/// its claims left to the table at the top (a link to its `claims.csv` instead), and a
/// sub-section said word for word by an earlier spec (the metric definitions) replaced by a
/// pointer to it. `seen` holds (sub-section text, spec) of the specs so far.
fn sub_report(text: &str, name: &str, seen: &mut Vec<(String, String)>) -> String {
    let mut s = String::new();
    // Split at the sub-sections ("### " in a spec's report); the part before the first is kept.
    let mut parts: Vec<(Option<&str>, Vec<&str>)> = vec![(None, Vec::new())];
    for line in text.lines().skip_while(|l| l.starts_with("# ") || l.trim().is_empty()) {
        match line.strip_prefix("### ") {
            Some(h) => parts.push((Some(h), Vec::new())),
            None => parts.last_mut().expect("starts with one part").1.push(line),
        }
    }
    for (heading, lines) in parts {
        let body = lines.join("\n");
        if let Some(h) = heading {
            let _ = writeln!(s, "#### {h}");
            if h.trim() == "Claims" {
                let _ = writeln!(s, "\nIn the claims table at the top (`{name}/claims.csv`).\n");
                continue;
            }
            let key = format!("{h}\n{body}");
            if let Some((_, first)) = seen.iter().find(|(k, _)| *k == key) {
                let _ = writeln!(s, "\nAs under [{first}](#{first}) above.\n");
                continue;
            }
            seen.push((key, name.to_string()));
        }
        for line in lines {
            let line = if line.starts_with('#') { format!("#{line}") } else { line.to_string() };
            s.push_str(&relink(&line, name));
            s.push('\n');
        }
    }
    s
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
        out.push(Claim { rival: None, chapter: "6".into(), statement: statement.into(), ours, thesis, note: note.into() });
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
    fn sub_reports_say_a_repeated_section_once_and_leave_claims_to_the_top() {
        let a = "# report: a\n\n## Chapter\n\nintro ![p](png/p.png)\n### Metric definitions\n\n- QE\n### Claims\n\n| x |\n### Tables\n\nA\n";
        let b = "# report: b\n\n## Chapter\n\n### Metric definitions\n\n- QE\n### Tables\n\nB\n";
        let mut seen = Vec::new();
        let ra = sub_report(a, "a", &mut seen);
        let rb = sub_report(b, "b", &mut seen);
        assert!(ra.contains("### Chapter") && ra.contains("![p](a/png/p.png)"), "{ra}");
        assert!(ra.contains("#### Metric definitions\n\n- QE"), "{ra}");
        assert!(
            ra.contains("In the claims table at the top (`a/claims.csv`)") && !ra.contains("| x |")
        );
        assert!(
            rb.contains("#### Metric definitions\n\nAs under [a](#a) above.")
                && !rb.contains("- QE")
        );
        // Sections that differ are kept.
        assert!(ra.contains("#### Tables\n\nA") && rb.contains("#### Tables\n\nB"), "{rb}");
    }

    #[test]
    fn links_point_into_the_sub_folder() {
        assert_eq!(
            relink("![a](png/a.png) and [b](https://x) [c](#c)", "ch4"),
            "![a](ch4/png/a.png) and [b](https://x) [c](#c)"
        );
    }

    #[test]
    fn overall_tables_sum_the_win_counts() {
        let dir = tempfile::tempdir().unwrap();
        for (spec, table, rows) in [
            (
                "ch6_same",
                "table_6_4",
                "cube,uniform,0,6,1,7\nsphere,uniform,1,5,1,7\ntotal,,1,11,2,14\n",
            ),
            ("ch6_diff", "table_6_5", "cube,uniform,0,7,0,7\n"),
        ] {
            std::fs::create_dir_all(dir.path().join(spec)).unwrap();
            std::fs::write(
                dir.path().join(spec).join(format!("{table}.csv")),
                format!("data,parameterisation,ga,de,pso,cells\n{rows}"),
            )
            .unwrap();
        }
        let (_, h, r) = overall(
            dir.path(),
            &[("ch6_same", "table_6_4"), ("ch6_diff", "table_6_5")],
            "table_6_8",
        )
        .unwrap()
        .unwrap();
        assert_eq!(h, vec!["table", "ga", "de", "pso"]);
        assert_eq!(r[0], vec!["Table 6.4", "1/14", "11/14", "2/14"]);
        assert_eq!(r[2], vec!["overall", "1/21", "18/21", "2/21"]);
        std::fs::write(
            dir.path().join("ch6_diff/table_6_5.csv"),
            "data,parameterisation,ga,de,pso,cells\ncube,uniform,x,7,0,7\n",
        )
        .unwrap();
        let e = overall(dir.path(), &[("ch6_same", "table_6_4"), ("ch6_diff", "table_6_5")], "t")
            .unwrap_err()
            .to_string();
        assert!(e.contains("table_6_5.csv: line 2: ga"), "{e}");
    }
}
