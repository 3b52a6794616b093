//! `somnurbs compare RESULTS --external DIR`: optimisers from outside somnurbs (issue 39), logged
//! in the IOHprofiler format by `ioh.logger.Analyzer` through the Python package's
//! `somnurbs.ioh_adapter.Logger`, joined to a Chapter 6 folder's runs so that every statistic of
//! `compare` ranks them beside GA, DE and PSO.
//!
//! A folder is matched by its metadata and refused on any mismatch, before anything is written:
//! its experiment attributes (spec, profile, knot reading, search box) must be the results
//! folder's (read from its fingerprint), every problem (IOHprofiler function name) one of the
//! folder's with the same dimension, every run's B error (run attribute `somnurbs_b`) bit for
//! bit the folder's (which pins the map, the net, the parameterisation and the reading), and no
//! run may end below the problem's certified lower bound (`somnurbs_bound`).

use super::ioh::{problem_name, LoadedProblem};
use super::OptimRow;
use crate::io::read_text;
use anyhow::{Context, Result};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The suite a results folder's runs solved: (spec, profile, knot reading, box), as the Python
/// package's `Logger` writes them (`somnurbs_spec`, `somnurbs_profile`, `somnurbs_reading`,
/// `somnurbs_box`; no profile is "").
fn folder_suite(results: &Path) -> Result<[String; 4]> {
    let fp = crate::experiment::log::Fingerprint::read(results)?.with_context(|| {
        format!("{}: no fingerprint: cannot tell which problems it holds", results.display())
    })?;
    let profile = if fp.profile == "default" { None } else { Some(fp.profile.as_str()) };
    let spec: crate::families::Loaded = fp
        .overrides()
        .variants(&fp.spec_path, &fp.spec_text, profile)?
        .into_iter()
        .next()
        .context("no spec")?;
    let o = spec.section_as::<super::spec::OptimSpec>().with_context(|| {
        format!("{}: its spec has no [optimise] section", results.display())
    })?;
    Ok([
        fp.spec_name.clone(),
        profile.unwrap_or("").to_string(),
        o.knots.name().to_string(),
        crate::families::suite::box_label(o),
    ])
}

/// The IOHprofiler JSON files of an external folder: the Analyzer's output folder itself, or a
/// root holding such folders (one level down), sorted.
fn json_files(folder: &Path) -> Result<Vec<PathBuf>> {
    let list = |dir: &Path| -> Result<Vec<PathBuf>> {
        let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
            .with_context(|| format!("cannot read {}", dir.display()))?
            .flatten()
            .map(|e| e.path())
            .collect();
        v.sort();
        Ok(v)
    };
    let is_json = |p: &PathBuf| {
        p.extension().is_some_and(|x| x == "json")
            && p.file_name().is_some_and(|n| n.to_string_lossy().starts_with("IOHprofiler_"))
    };
    let mut out: Vec<PathBuf> = list(folder)?.into_iter().filter(is_json).collect();
    if out.is_empty() {
        for sub in list(folder)?.into_iter().filter(|p| p.is_dir()) {
            out.extend(list(&sub)?.into_iter().filter(is_json));
        }
    }
    if out.is_empty() {
        anyhow::bail!("{}: no IOHprofiler_*.json (an ioh.logger.Analyzer folder)", folder.display());
    }
    Ok(out)
}

/// The runs of an Analyzer `.dat` file: per run (from its header line) the strict improvements of
/// the best so far as (evaluation, value), read from the `evaluations` and `raw_y` columns.
fn dat_runs(text: &str) -> Result<Vec<Vec<(u64, f64)>>, String> {
    let mut runs: Vec<Vec<(u64, f64)>> = Vec::new();
    let mut cols = (0, 1);
    let mut best = f64::INFINITY;
    for (n, line) in text.lines().enumerate() {
        let fields: Vec<&str> = line.split_whitespace().collect();
        if fields.is_empty() {
            continue;
        }
        if fields[0] == "evaluations" {
            let at = |name: &str| fields.iter().position(|f| *f == name);
            cols = (at("evaluations").unwrap_or(0), at("raw_y").ok_or("no raw_y column")?);
            runs.push(Vec::new());
            best = f64::INFINITY;
            continue;
        }
        let run = runs.last_mut().ok_or("a data row before the first header")?;
        let get = |k: usize| fields.get(k).copied().ok_or(format!("line {}: too few columns", n + 1));
        let e: u64 = get(cols.0)?.parse().map_err(|_| format!("line {}: evaluations", n + 1))?;
        let y: f64 = get(cols.1)?.parse().map_err(|_| format!("line {}: raw_y", n + 1))?;
        if y < best {
            best = y;
            run.push((e, y));
        }
    }
    Ok(runs)
}

/// A JSON field, or an error naming the file.
fn field<'a>(v: &'a Value, key: &str, file: &Path) -> Result<&'a Value> {
    v.get(key).with_context(|| format!("{}: no `{key}`", file.display()))
}

/// The experiment attributes (a list of one-key objects) as a map.
fn experiment_attributes(v: &Value) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    for a in v.get("experiment_attributes").and_then(|a| a.as_array()).into_iter().flatten() {
        for (k, val) in a.as_object().into_iter().flatten() {
            out.insert(k.clone(), val.as_str().unwrap_or_default().to_string());
        }
    }
    out
}

/// Refuse a file whose suite is not the folder's.
fn check_suite(v: &Value, suite: &[String; 4], file: &Path, results: &Path) -> Result<()> {
    let attrs = experiment_attributes(v);
    let names = ["somnurbs_spec", "somnurbs_profile", "somnurbs_reading", "somnurbs_box"];
    for (name, want) in names.iter().zip(suite) {
        let Some(have) = attrs.get(*name) else {
            anyhow::bail!("{}: no experiment attribute {name}: log with somnurbs.ioh_adapter.Logger, so that compare can check the problems are {}'s", file.display(), results.display());
        };
        if have != want {
            anyhow::bail!("{}: {name} is {have:?} but {} was run with {want:?}: these are other problems (a different spec, profile, reading or box)", file.display(), results.display());
        }
    }
    Ok(())
}

/// What the external folders add to `compare`: their runs' traces and, per problem, the certified
/// optimum their logs carry (run attribute `somnurbs_optimum`).
#[derive(Debug, Default)]
pub(crate) struct External {
    pub(crate) traces: Vec<LoadedProblem>,
    pub(crate) optima: BTreeMap<String, f64>,
}

impl External {
    /// The certified optima of the results folder (`exact_<grid>.csv`), with the external logs'
    /// for the problems it has none of (a folder run without `exact = true`).
    pub(crate) fn add_optima(&self, certified: &mut BTreeMap<String, f64>) {
        for (k, f) in &self.optima {
            certified.entry(k.clone()).or_insert(*f);
        }
    }
}

/// The external runs of one JSON file, checked against the folder's rows, as rows, traces and
/// the certified optimum the runs carry.
fn read_file(
    file: &Path,
    suite: &[String; 4],
    results: &Path,
    by_name: &BTreeMap<String, &OptimRow>,
) -> Result<(Vec<OptimRow>, LoadedProblem, Option<f64>)> {
    let v: Value = serde_json::from_str(&read_text(file)?)
        .with_context(|| format!("{}: not JSON", file.display()))?;
    check_suite(&v, suite, file, results)?;
    let name = field(&v, "function_name", file)?.as_str().unwrap_or_default().to_string();
    let optimiser = field(&v, "algorithm", file)?
        .get("name")
        .and_then(|s| s.as_str())
        .with_context(|| format!("{}: no algorithm.name", file.display()))?
        .to_string();
    let Some(row) = by_name.get(&name) else {
        anyhow::bail!("{}: problem {name} is not one of {}'s problems ({})", file.display(), results.display(), by_name.keys().cloned().collect::<Vec<_>>().join(", "));
    };
    let mut rows = Vec::new();
    let mut traces = Vec::new();
    let mut optimum: Option<f64> = None;
    for s in field(&v, "scenarios", file)?.as_array().into_iter().flatten() {
        let dim = s.get("dimension").and_then(|d| d.as_u64()).unwrap_or(0) as usize;
        if dim != row.dimension {
            anyhow::bail!("{}: {name} has dimension {dim} here but {} in {}", file.display(), row.dimension, results.display());
        }
        let path = s.get("path").and_then(|p| p.as_str()).unwrap_or_default();
        let dat = file.parent().unwrap_or(Path::new("")).join(path);
        let runs = dat_runs(&read_text(&dat)?)
            .map_err(anyhow::Error::msg)
            .with_context(|| dat.display().to_string())?;
        let listed: Vec<&Value> = s.get("runs").and_then(|r| r.as_array()).into_iter().flatten().collect();
        if listed.len() != runs.len() {
            anyhow::bail!("{}: {} runs listed but {} in {}", file.display(), listed.len(), runs.len(), dat.display());
        }
        for (r, imp) in listed.into_iter().zip(runs) {
            let num = |k: &str| r.get(k).and_then(|x| x.as_f64());
            let b = num("somnurbs_b").with_context(|| format!("{}: a run has no somnurbs_b (B's error)", file.display()))?;
            if b.to_bits() != row.b.to_bits() {
                anyhow::bail!("{}: {name}: B's error is {b:e} here but {:e} in {}: the problem differs (another map, reading or build)", file.display(), row.b, results.display());
            }
            let best = imp.last().map(|x| x.1).with_context(|| format!("{}: a run of {name} has no rows", dat.display()))?;
            if let Some(bound) = num("somnurbs_bound").filter(|lb| best < *lb) {
                anyhow::bail!("{}: {name}: a run ends at {best:e}, below the certified lower bound {bound:e}: not this problem, or a wrong bound", file.display());
            }
            if let Some(f) = num("somnurbs_optimum") {
                optimum = Some(optimum.map_or(f, |o| o.min(f)));
            }
            let evals = r.get("evals").and_then(|e| e.as_u64()).with_context(|| format!("{}: a run has no evals", file.display()))?;
            let repeat = rows.len();
            rows.push(OptimRow {
                cell: format!("external/{optimiser}/{name}/r{repeat}"),
                optimiser: optimiser.clone(),
                variant: String::new(),
                repeat,
                seed: String::new(),
                initial_best: imp[0].1,
                best,
                evaluations: evals,
                excursion: f64::NAN,
                max_control: f64::NAN,
                cpu_s: f64::NAN,
                ..(*row).clone()
            });
            traces.push((evals, imp));
        }
    }
    Ok((rows, LoadedProblem { optimiser, function_name: name, runs: traces }, optimum))
}

/// The runs of the external folders, as runs.csv rows beside `rows` (the folder's) and as the
/// traces and optima of the runtime statistics; `rows` with the external ones appended.
pub(crate) fn join(
    results: &Path,
    folders: &[PathBuf],
    mut rows: Vec<OptimRow>,
) -> Result<(Vec<OptimRow>, External)> {
    if folders.is_empty() {
        return Ok((rows, External::default()));
    }
    let suite = folder_suite(results)?;
    let by_name: BTreeMap<String, &OptimRow> = rows
        .iter()
        .map(|r| {
            let grid = format!("{}x{}", r.grid_x, r.grid_y);
            let net = format!("{}x{}", r.cn_x, r.cn_y);
            (problem_name(&r.dataset, &grid, &net, &r.parameterisation), r)
        })
        .collect();
    let ours: Vec<String> = rows.iter().map(|r| r.competitor()).collect();
    let mut extra = Vec::new();
    let mut ext = External::default();
    for folder in folders {
        for file in json_files(folder)? {
            let (r, lp, optimum) = read_file(&file, &suite, results, &by_name)?;
            if ours.contains(&lp.optimiser) {
                anyhow::bail!("{}: algorithm name {:?} is one of {}'s optimisers: give the external optimiser another name", file.display(), lp.optimiser, results.display());
            }
            if ext.traces.iter().any(|t| t.optimiser == lp.optimiser && t.function_name == lp.function_name) {
                anyhow::bail!("{}: {} on {} is given twice", file.display(), lp.optimiser, lp.function_name);
            }
            if let Some(f) = optimum {
                let o = ext.optima.entry(lp.function_name.clone()).or_insert(f);
                *o = o.min(f);
            }
            extra.extend(r);
            ext.traces.push(lp);
        }
    }
    rows.extend(extra);
    Ok((rows, ext))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An Analyzer `.dat`: a header per run, columns found by name, the closing row of a run that
    /// did not improve dropped, and only strict improvements kept.
    #[test]
    fn dat_rows_become_strict_improvements_per_run() {
        let text = "evaluations raw_y\n1 3.5\n2 3.25\n5 3.75\nevaluations x0 raw_y\n1 0 2\n3 0 2\n4 0 1.5\n";
        let runs = dat_runs(text).unwrap();
        assert_eq!(runs, vec![vec![(1, 3.5), (2, 3.25)], vec![(1, 2.0), (4, 1.5)]]);
        assert!(dat_runs("1 2\n").is_err());
        assert!(dat_runs("evaluations y\n1 2\n").is_err());
    }

    /// The four experiment attributes must all be there and equal the folder's.
    #[test]
    fn a_file_of_another_suite_is_refused_naming_the_attribute() {
        let suite = ["ch6_exact", "quick", "eq2_10", "B+-5e-6"].map(String::from);
        let json = |reading: &str| -> Value {
            serde_json::json!({ "experiment_attributes": [
                {"somnurbs_box": "B+-5e-6"}, {"somnurbs_profile": "quick"},
                {"somnurbs_reading": reading}, {"somnurbs_spec": "ch6_exact"}] })
        };
        let (f, r) = (Path::new("f.json"), Path::new("results"));
        assert!(check_suite(&json("eq2_10"), &suite, f, r).is_ok());
        let e = check_suite(&json("nurbs_book"), &suite, f, r).unwrap_err().to_string();
        assert!(e.contains("somnurbs_reading") && e.contains("nurbs_book"), "{e}");
        let e = check_suite(&serde_json::json!({}), &suite, f, r).unwrap_err().to_string();
        assert!(e.contains("no experiment attribute somnurbs_spec"), "{e}");
    }
}
