//! `somnurbs compare RESULTS --external DIR`: optimisers from outside somnurbs (issue 39), logged
//! in the IOHprofiler format by `ioh.logger.Analyzer` through the Python package's
//! `somnurbs.ioh_adapter.Logger`, joined to a Chapter 6 folder's runs so that every statistic of
//! `compare` ranks them beside GA, DE and PSO.
//!
//! A log is judged by the results folder and by its own traces, never by what its metadata claims
//! of itself, and refused on any mismatch before anything is written, in one line naming the file
//! and the field or run:
//!
//! - every field `compare` reads must be well formed (strings, whole numbers, finite numbers,
//!   non-empty lists) and a `.dat` path must stay in the JSON's folder;
//! - its experiment attributes (spec, profile, knot reading, search box) must be the results
//!   folder's (read from its fingerprint), every problem (IOHprofiler function name) one of the
//!   folder's with the same dimension, and every run's B error (run attribute `somnurbs_b`) bit
//!   for bit the folder's (which pins the map, the net, the parameterisation and the reading);
//! - where the folder certifies the problem (its own `exact_<grid>.csv`, a [`Certificate`]), no
//!   run's best (read from its `.dat` trace) may lie below the certified lower bound, and the
//!   log's own `somnurbs_bound` and `somnurbs_optimum`, where given, must not contradict it; they
//!   are never used otherwise. Where it does not, B's error and the traces are what is checked;
//! - every run's trace must agree with its JSON record: evaluations increasing from 1 and never
//!   beyond the run's `evals`, and the run's `best` (where given) the trace's best, at the same
//!   evaluation.

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

/// One run of an Analyzer `.dat` file: its rows as (1-based line, evaluation, value), in file
/// order.
type DatRun = Vec<(usize, u64, f64)>;
/// A checked run: its evaluations and the strict improvements of its trace.
type Trace = (u64, Vec<(u64, f64)>);

/// The runs of an Analyzer `.dat` file (a header line starts one), read from the `evaluations`
/// and `raw_y` columns. A value that is `nan` or minus infinity is refused, naming the line.
fn dat_runs(text: &str) -> Result<Vec<DatRun>, String> {
    let mut runs: Vec<DatRun> = Vec::new();
    let mut cols = (0, 1);
    for (n, line) in text.lines().enumerate() {
        let fields: Vec<&str> = line.split_whitespace().collect();
        if fields.is_empty() {
            continue;
        }
        if fields[0] == "evaluations" {
            let at = |name: &str| fields.iter().position(|f| *f == name);
            cols = (at("evaluations").unwrap_or(0), at("raw_y").ok_or("no raw_y column")?);
            runs.push(Vec::new());
            continue;
        }
        let run = runs.last_mut().ok_or("a data row before the first header")?;
        let get = |k: usize| fields.get(k).copied().ok_or(format!("line {}: too few columns", n + 1));
        let e: u64 = get(cols.0)?.parse().map_err(|_| format!("line {}: evaluations", n + 1))?;
        let y: f64 = get(cols.1)?.parse().map_err(|_| format!("line {}: raw_y", n + 1))?;
        if y.is_nan() || y == f64::NEG_INFINITY {
            return Err(format!("line {}: raw_y {y} is not a value", n + 1));
        }
        run.push((n + 1, e, y));
    }
    Ok(runs)
}

/// The strict improvements of the best so far of a run, as (evaluation, value).
fn improvements(run: &DatRun) -> Vec<(u64, f64)> {
    let mut best = f64::INFINITY;
    let mut out = Vec::new();
    for &(_, e, y) in run {
        if y < best {
            best = y;
            out.push((e, y));
        }
    }
    out
}

/// A malformed field of an IOHprofiler JSON, in one line naming the file and the field.
fn malformed(file: &Path, at: &str, want: &str) -> anyhow::Error {
    anyhow::anyhow!("{}: field `{at}` is missing or not {want} (a malformed IOHprofiler JSON)", file.display())
}

/// Field `key` of `v` (shown as `at`), a non-empty string.
fn text_field<'a>(v: &'a Value, key: &str, at: &str, file: &Path) -> Result<&'a str> {
    v.get(key)
        .and_then(Value::as_str)
        .filter(|s| !s.is_empty())
        .ok_or_else(|| malformed(file, at, "a non-empty string"))
}

/// Field `key` of `v` (shown as `at`), a whole number.
fn count_field(v: &Value, key: &str, at: &str, file: &Path) -> Result<u64> {
    v.get(key).and_then(Value::as_u64).ok_or_else(|| malformed(file, at, "a whole number"))
}

/// Field `key` of `v` (shown as `at`): None when absent, else a finite number.
fn number_field(v: &Value, key: &str, at: &str, file: &Path) -> Result<Option<f64>> {
    match v.get(key) {
        None => Ok(None),
        Some(x) => x
            .as_f64()
            .filter(|x| x.is_finite())
            .map(Some)
            .ok_or_else(|| malformed(file, at, "a finite number")),
    }
}

/// Field `key` of `v` (shown as `at`), a non-empty list.
fn list_field<'a>(v: &'a Value, key: &str, at: &str, file: &Path) -> Result<&'a Vec<Value>> {
    v.get(key)
        .and_then(Value::as_array)
        .filter(|a| !a.is_empty())
        .ok_or_else(|| malformed(file, at, "a non-empty list"))
}

/// The experiment attributes (a list of one-key objects with string values) as a map; an absent
/// list is an empty map.
fn experiment_attributes(v: &Value, file: &Path) -> Result<BTreeMap<String, String>> {
    let mut out = BTreeMap::new();
    let Some(list) = v.get("experiment_attributes") else { return Ok(out) };
    let want = "a list of objects with string values";
    for a in list.as_array().ok_or_else(|| malformed(file, "experiment_attributes", want))? {
        let a = a.as_object().ok_or_else(|| malformed(file, "experiment_attributes", want))?;
        for (k, val) in a {
            let at = format!("experiment_attributes.{k}");
            let s = val.as_str().ok_or_else(|| malformed(file, &at, "a string"))?;
            out.insert(k.clone(), s.to_string());
        }
    }
    Ok(out)
}

/// Refuse a file whose suite is not the folder's.
fn check_suite(v: &Value, suite: &[String; 4], file: &Path, results: &Path) -> Result<()> {
    let attrs = experiment_attributes(v, file)?;
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

/// The fields of the top level that `compare` does not read but that must not say something else
/// than a minimised problem logged as evaluations and raw values.
fn check_header(v: &Value, file: &Path) -> Result<()> {
    if !v.is_object() {
        anyhow::bail!("{}: not a JSON object (a malformed IOHprofiler JSON)", file.display());
    }
    if let Some(m) = v.get("maximization") {
        if m.as_bool() != Some(false) {
            return Err(malformed(file, "maximization", "false (compare's problems are minimised)"));
        }
    }
    if let Some(a) = v.get("attributes") {
        let names = a.as_array().filter(|l| l.iter().all(Value::is_string));
        let names = names.ok_or_else(|| malformed(file, "attributes", "a list of strings"))?;
        if !["evaluations", "raw_y"].iter().all(|c| names.iter().any(|n| n == c)) {
            return Err(malformed(file, "attributes", "a list holding evaluations and raw_y"));
        }
    }
    Ok(())
}

/// What a results folder certifies of one problem, read from its own `exact_<grid>.csv`: the
/// exact solver's optimum and its proven lower bound (printed at round-trip precision; a folder
/// of an older build has 9 decimals).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Certificate {
    pub(crate) optimum: f64,
    pub(crate) lower_bound: f64,
    /// The table it comes from (named in refusals).
    pub(crate) table: PathBuf,
}

/// How far a value may lie on the wrong side of a certificate read back from `exact_<grid>.csv`:
/// the table prints the solver's values exactly, an older build's 9 decimals within half of 1e-9.
pub(crate) const CERTIFICATE_TOLERANCE: f64 = 1e-9;

/// One problem's context while its external runs are read.
struct Problem<'a> {
    file: &'a Path,
    name: &'a str,
    row: &'a OptimRow,
    results: &'a Path,
    certificate: Option<&'a Certificate>,
}

/// Check one run (JSON record `r` at `at`, trace `rows` of `dat`) against the folder and its own
/// trace; returns its evaluations and improvements.
fn check_run(p: &Problem, r: &Value, at: &str, rows: &DatRun, dat: &Path) -> Result<Trace> {
    let file = p.file.display();
    let b = number_field(r, "somnurbs_b", &format!("{at}.somnurbs_b"), p.file)?
        .ok_or_else(|| malformed(p.file, &format!("{at}.somnurbs_b"), "a number (B's error)"))?;
    if b.to_bits() != p.row.b.to_bits() {
        anyhow::bail!("{file}: {}: B's error is {b:e} here but {:e} in {}: the problem differs (another map, reading or build)", p.name, p.row.b, p.results.display());
    }
    let imp = improvements(rows);
    let &(best_at, best) = imp.last().with_context(|| format!("{}: {} {at}: the run has no rows", dat.display(), p.name))?;
    // The log's own certificate is read only to be checked against the folder's.
    let bound = number_field(r, "somnurbs_bound", &format!("{at}.somnurbs_bound"), p.file)?;
    let optimum = number_field(r, "somnurbs_optimum", &format!("{at}.somnurbs_optimum"), p.file)?;
    if let Some(c) = p.certificate {
        if best < c.lower_bound - CERTIFICATE_TOLERANCE {
            anyhow::bail!("{file}: {} {at}: the run ends at {best:e} (its trace {}), below the certified lower bound {:e} of {}: not this problem, or a forged trace", p.name, dat.display(), c.lower_bound, c.table.display());
        }
        if let Some(lb) = bound.filter(|lb| *lb > c.optimum + CERTIFICATE_TOLERANCE) {
            anyhow::bail!("{file}: {} {at}: somnurbs_bound {lb:e} is above the certified optimum {:e} of {}: the log's certificate contradicts the folder's", p.name, c.optimum, c.table.display());
        }
        if let Some(f) = optimum.filter(|f| *f < c.lower_bound - CERTIFICATE_TOLERANCE) {
            anyhow::bail!("{file}: {} {at}: somnurbs_optimum {f:e} is below the certified lower bound {:e} of {}: the log's certificate contradicts the folder's", p.name, c.lower_bound, c.table.display());
        }
    }
    let evals = count_field(r, "evals", &format!("{at}.evals"), p.file)?;
    let mut previous = 0;
    for &(line, e, _) in rows {
        if e <= previous {
            anyhow::bail!("{}: line {line}: evaluation {e} does not follow {previous} ({file} {at}: a trace counts its evaluations up from 1)", dat.display());
        }
        if e > evals {
            anyhow::bail!("{file}: {} {at}: evals is {evals} but its trace {} logs evaluation {e} at line {line}: the count and the trace contradict each other", p.name, dat.display());
        }
        previous = e;
    }
    if let Some(claimed) = r.get("best") {
        let y = number_field(claimed, "y", &format!("{at}.best.y"), p.file)?;
        let y = y.ok_or_else(|| malformed(p.file, &format!("{at}.best.y"), "a finite number"))?;
        let e = count_field(claimed, "evals", &format!("{at}.best.evals"), p.file)?;
        if (y - best).abs() > 1e-12 * best.abs().max(1.0) || e != best_at {
            anyhow::bail!("{file}: {} {at}: best is {y:e} at evaluation {e} but its trace {} reaches {best:e} first at evaluation {best_at}: the record and the trace contradict each other", p.name, dat.display());
        }
    }
    Ok((evals, imp))
}

/// The `.dat` file a scenario names (`path`, relative to the JSON's folder and inside it).
fn dat_path(s: &Value, at: &str, file: &Path) -> Result<PathBuf> {
    let path = text_field(s, "path", &format!("{at}.path"), file)?;
    let rel = Path::new(path);
    let inside = rel.components().all(|c| matches!(c, std::path::Component::Normal(_)));
    if !inside {
        anyhow::bail!("{}: field `{at}.path` {path:?} leaves the JSON's folder (an absolute path or ..): a log names its .dat files beside it", file.display());
    }
    Ok(file.parent().unwrap_or(Path::new("")).join(rel))
}

/// The runs of one scenario (`at`, e.g. `scenarios[0]`), checked, as (evaluations, improvements).
fn read_scenario(p: &Problem, s: &Value, at: &str) -> Result<Vec<Trace>> {
    let dim = count_field(s, "dimension", &format!("{at}.dimension"), p.file)?;
    if dim != p.row.dimension as u64 {
        anyhow::bail!("{}: {} has dimension {dim} here but {} in {}", p.file.display(), p.name, p.row.dimension, p.results.display());
    }
    let dat = dat_path(s, at, p.file)?;
    let runs = dat_runs(&read_text(&dat)?)
        .map_err(anyhow::Error::msg)
        .with_context(|| dat.display().to_string())?;
    let listed = list_field(s, "runs", &format!("{at}.runs"), p.file)?;
    if listed.len() != runs.len() {
        anyhow::bail!("{}: {} runs listed in `{at}.runs` but {} in {}", p.file.display(), listed.len(), runs.len(), dat.display());
    }
    let mut out = Vec::new();
    for (k, (r, rows)) in listed.iter().zip(&runs).enumerate() {
        let at = format!("{at}.runs[{k}]");
        if !r.is_object() {
            return Err(malformed(p.file, &at, "an object"));
        }
        out.push(check_run(p, r, &at, rows, &dat)?);
    }
    Ok(out)
}

/// The external runs of one JSON file, checked against the folder's rows and certificates, as
/// rows and traces.
fn read_file(
    file: &Path,
    suite: &[String; 4],
    results: &Path,
    by_name: &BTreeMap<String, &OptimRow>,
    certificates: &BTreeMap<String, Certificate>,
) -> Result<(Vec<OptimRow>, LoadedProblem)> {
    let v: Value = serde_json::from_str(&read_text(file)?)
        .with_context(|| format!("{}: not JSON", file.display()))?;
    check_header(&v, file)?;
    check_suite(&v, suite, file, results)?;
    let name = text_field(&v, "function_name", "function_name", file)?.to_string();
    let algorithm = v.get("algorithm").unwrap_or(&Value::Null);
    let optimiser = text_field(algorithm, "name", "algorithm.name", file)?.to_string();
    let Some(row) = by_name.get(&name) else {
        anyhow::bail!("{}: problem {name} is not one of {}'s problems ({})", file.display(), results.display(), by_name.keys().cloned().collect::<Vec<_>>().join(", "));
    };
    let p = Problem { file, name: &name, row, results, certificate: certificates.get(&name) };
    let mut traces = Vec::new();
    for (k, s) in list_field(&v, "scenarios", "scenarios", file)?.iter().enumerate() {
        let at = format!("scenarios[{k}]");
        if !s.is_object() {
            return Err(malformed(file, &at, "an object"));
        }
        traces.extend(read_scenario(&p, s, &at)?);
    }
    let rows = traces
        .iter()
        .enumerate()
        .map(|(repeat, (evals, imp))| OptimRow {
            cell: format!("external/{optimiser}/{name}/r{repeat}"),
            optimiser: optimiser.clone(),
            variant: None,
            repeat,
            seed: String::new(),
            initial_best: imp[0].1,
            best: imp[imp.len() - 1].1,
            evaluations: *evals,
            excursion: f64::NAN,
            max_control: f64::NAN,
            cpu_s: f64::NAN,
            ..(*row).clone()
        })
        .collect();
    Ok((rows, LoadedProblem { optimiser, function_name: name, runs: traces }))
}

/// The runs of the external folders, as runs.csv rows beside `rows` (the folder's) and as the
/// traces of the runtime statistics; `rows` with the external ones appended. `certificates` are
/// the results folder's own (`exact_<grid>.csv`); a problem without one is named on stderr with
/// what is checked instead.
pub(crate) fn join(
    results: &Path,
    folders: &[PathBuf],
    mut rows: Vec<OptimRow>,
    certificates: &BTreeMap<String, Certificate>,
) -> Result<(Vec<OptimRow>, Vec<LoadedProblem>)> {
    if folders.is_empty() {
        return Ok((rows, Vec::new()));
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
    let mut traces: Vec<LoadedProblem> = Vec::new();
    for folder in folders {
        for file in json_files(folder)? {
            let (r, lp) = read_file(&file, &suite, results, &by_name, certificates)?;
            if ours.contains(&lp.optimiser) {
                anyhow::bail!("{}: algorithm name {:?} is one of {}'s optimisers: give the external optimiser another name", file.display(), lp.optimiser, results.display());
            }
            if traces.iter().any(|t| t.optimiser == lp.optimiser && t.function_name == lp.function_name) {
                anyhow::bail!("{}: {} on {} is given twice", file.display(), lp.optimiser, lp.function_name);
            }
            extra.extend(r);
            traces.push(lp);
        }
    }
    let uncertified: std::collections::BTreeSet<&str> = traces
        .iter()
        .map(|t| t.function_name.as_str())
        .filter(|n| !certificates.contains_key(*n))
        .collect();
    if !uncertified.is_empty() {
        let uncertified: Vec<&str> = uncertified.into_iter().collect();
        crate::notice::emit(&format!("somnurbs: note: {} certifies no lower bound of {} (no exact_<grid>.csv: its spec does not say exact = true): their external runs are checked by B's error and their own traces only", results.display(), uncertified.join(", ")));
    }
    rows.extend(extra);
    Ok((rows, traces))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An Analyzer `.dat`: a header per run, columns found by name, every row kept with its line;
    /// the improvements drop the closing row of a run that did not improve and keep only strict
    /// improvements; `nan` and minus infinity are refused with their line.
    #[test]
    fn dat_rows_become_strict_improvements_per_run() {
        let text = "evaluations raw_y\n1 3.5\n2 3.25\n5 3.75\nevaluations x0 raw_y\n1 0 2\n3 0 2\n4 0 1.5\n";
        let runs = dat_runs(text).unwrap();
        assert_eq!(runs[0], vec![(2, 1, 3.5), (3, 2, 3.25), (4, 5, 3.75)]);
        let imp: Vec<Vec<(u64, f64)>> = runs.iter().map(improvements).collect();
        assert_eq!(imp, vec![vec![(1, 3.5), (2, 3.25)], vec![(1, 2.0), (4, 1.5)]]);
        assert!(dat_runs("1 2\n").is_err());
        assert!(dat_runs("evaluations y\n1 2\n").is_err());
        for bad in ["nan", "-inf"] {
            let e = dat_runs(&format!("evaluations raw_y\n1 3\n2 {bad}\n")).unwrap_err();
            assert!(e.starts_with("line 3:"), "{e}");
        }
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
