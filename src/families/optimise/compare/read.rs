//! What `compare` reads from a results folder: that it is a Chapter 6 run, its `runs.csv`, and
//! the certificates of its `exact_<grid>.csv` tables.

use crate::families::optimise::external::Certificate;
use crate::families::optimise::{ioh, OptimRow};
use anyhow::{Context, Result};
use std::collections::BTreeMap;
use std::path::Path;

/// Refuse a finished folder that is not a run of an `[optimise]` spec (a `fit` folder, a Chapter
/// 4 or 5 run, a reproduction), saying what it is and which folders `compare` takes.
pub(super) fn require_optimise_run(results: &Path) -> Result<()> {
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

/// The rows of `results/runs.csv`, every one checked.
pub(super) fn read_runs(results: &Path) -> Result<Vec<OptimRow>> {
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

/// The certificates of a folder's `exact_<grid>.csv` tables (the exact solver's optimum and its
/// proven lower bound), by problem name: what the folder itself certifies.
pub(super) fn certificates(folder: &Path) -> Result<BTreeMap<String, Certificate>> {
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
            let key = ioh::problem_name(
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
