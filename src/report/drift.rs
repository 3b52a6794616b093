//! Result drift: every table cell of a results folder compared with a committed baseline folder.
//!
//! Tables are the CSV files under the baseline (not under `png/`, `ioh/`, `maps/`), matched by
//! relative path; columns by name; rows by position, and a row whose key (its non-numeric cells and
//! identity columns such as `cn_x` or `repeat`) differs is a moved row, not a set of moved numbers.
//! Numbers are equal within `abs + rel * max(|a|, |b|)`; timing columns (CPU or wall seconds) and
//! the tables and rows the baseline's `drift.toml` declares timing-dependent are compared and
//! reported but never judged. Bad input (a folder or CSV that cannot be read, a malformed CSV, a
//! run of another spec, seed or profile) is an error, not drift, and so is a folder that does not
//! hold a finished, whole run ([`crate::io::outdir::require_finished`]). Non-finite numbers compare by
//! identity (`inf` equals only `inf` of the same sign, `NaN` only `NaN`) and are always reported.

use crate::io::{csv_records, write_atomic};
use anyhow::{bail, Context, Result};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Equality of two numbers: |a - b| <= abs + rel * max(|a|, |b|).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Tolerance {
    pub(crate) abs: f64,
    pub(crate) rel: f64,
}

impl Default for Tolerance {
    fn default() -> Tolerance {
        Tolerance { abs: 1e-9, rel: 1e-9 }
    }
}

impl Tolerance {
    pub(crate) fn equal(&self, a: f64, b: f64) -> bool {
        if a.is_nan() || b.is_nan() {
            return a.is_nan() && b.is_nan();
        }
        if a == b {
            return true;
        }
        // |inf - x| <= abs + rel * inf would call inf equal to anything.
        if a.is_infinite() || b.is_infinite() {
            return false;
        }
        (a - b).abs() <= self.abs + self.rel * a.abs().max(b.abs())
    }
}

/// `drift.toml` in a baseline folder: what is timing-dependent and per-column tolerances.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct DriftConfig {
    /// Tables (glob over the relative path, `*` any run of characters) whose every cell is
    /// timing-dependent (e.g. win counts of CPU time).
    #[serde(default)]
    pub(crate) timing_tables: Vec<String>,
    /// Rows holding any of these strings in a cell are timing-dependent (e.g. claims about speed).
    #[serde(default)]
    pub(crate) timing_rows: Vec<String>,
    /// Per-column tolerances (`column` is a glob over column names).
    #[serde(default)]
    pub(crate) tolerance: Vec<ColumnTolerance>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ColumnTolerance {
    pub(crate) column: String,
    pub(crate) abs: f64,
    #[serde(default)]
    pub(crate) rel: f64,
}

/// How to compare.
#[derive(Debug, Clone, Default)]
pub(crate) struct DriftOptions {
    pub(crate) default: Tolerance,
    /// Per-column tolerances (globs); the first match wins; command-line ones come first.
    pub(crate) columns: Vec<(String, Tolerance)>,
    pub(crate) config: DriftConfig,
}

impl DriftOptions {
    fn tolerance(&self, column: &str) -> Tolerance {
        self.columns.iter().find(|(g, _)| glob(g, column)).map(|(_, t)| *t).unwrap_or(self.default)
    }
}

/// Parse `--tol COLUMN=ABS[,REL]`.
pub(crate) fn parse_tol(s: &str) -> Result<(String, Tolerance)> {
    let (col, v) =
        s.split_once('=').with_context(|| format!("--tol `{s}`: expected COLUMN=ABS[,REL]"))?;
    let mut it = v.split(',');
    let num = |x: Option<&str>, what: &str| -> Result<f64> {
        let x = x.unwrap_or("0").trim();
        let v: f64 =
            x.parse().map_err(|_| anyhow::anyhow!("--tol `{s}`: {what} `{x}` is not a number"))?;
        if !(v >= 0.0 && v.is_finite()) {
            bail!("--tol `{s}`: {what} must be a finite number >= 0");
        }
        Ok(v)
    };
    let abs = num(it.next(), "ABS")?;
    let rel = num(it.next(), "REL")?;
    Ok((col.trim().to_string(), Tolerance { abs, rel }))
}

/// `*` matches any run of characters; everything else literally.
pub(crate) fn glob(pattern: &str, s: &str) -> bool {
    let parts: Vec<&str> = pattern.split('*').collect();
    if parts.len() == 1 {
        return pattern == s;
    }
    let (first, last) = (parts[0], parts[parts.len() - 1]);
    if !s.starts_with(first)
        || !s[first.len()..].ends_with(last)
        || s.len() < first.len() + last.len()
    {
        return false;
    }
    let mut rest = &s[first.len()..s.len() - last.len()];
    for p in &parts[1..parts.len() - 1] {
        match rest.find(p) {
            Some(k) => rest = &rest[k + p.len()..],
            None => return false,
        }
    }
    true
}

/// Columns that hold measured time: reported, never judged.
pub(crate) fn is_timing_column(name: &str) -> bool {
    name.ends_with("_s")
        || name.contains("cpu")
        || name.contains("seconds")
        || name.starts_with("time")
}

/// Columns that identify a row even when numeric.
const IDENTITY: [&str; 10] =
    ["cn_x", "cn_y", "grid_x", "grid_y", "nx", "ny", "repeat", "n", "cells", "seed"];

/// A cell's value as a number, if it is written as one: text that only parses by overflowing (the
/// hex seed `9e71084187728100` read as 9e71084187728100) is text, not infinity.
fn number(v: &str) -> Option<f64> {
    let x = v.parse::<f64>().ok()?;
    let spelt_inf = v.trim_start_matches(['+', '-']).to_ascii_lowercase().starts_with("inf");
    (!x.is_infinite() || spelt_inf).then_some(x)
}

/// One difference.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Finding {
    MissingTable {
        table: String,
    },
    ExtraTable {
        table: String,
    },
    MissingColumn {
        table: String,
        column: String,
    },
    ExtraColumn {
        table: String,
        column: String,
    },
    RowCount {
        table: String,
        baseline: usize,
        current: usize,
    },
    RowKey {
        table: String,
        row: usize,
        baseline: String,
        current: String,
    },
    Cell {
        table: String,
        row: String,
        column: String,
        baseline: String,
        current: String,
        abs: f64,
        rel: f64,
        judged: bool,
    },
    /// A non-finite number equal on both sides (not drift, but never silent).
    NonFinite {
        table: String,
        row: String,
        column: String,
        value: String,
    },
}

impl Finding {
    /// Whether it counts as drift (an extra table or a timing cell does not).
    pub(crate) fn drifted(&self) -> bool {
        match self {
            Finding::ExtraTable { .. }
            | Finding::ExtraColumn { .. }
            | Finding::NonFinite { .. } => false,
            Finding::Cell { judged, .. } => *judged,
            _ => true,
        }
    }

    fn describe(&self) -> String {
        match self {
            Finding::MissingTable { table } => format!("{table}: missing in the current folder"),
            Finding::ExtraTable { table } => format!("{table}: new table (not in the baseline)"),
            Finding::MissingColumn { table, column } => {
                format!("{table}: column {column} is missing")
            }
            Finding::ExtraColumn { table, column } => format!("{table}: new column {column}"),
            Finding::NonFinite { table, row, column, value } => {
                format!("{table}:{row}:{column} is {value} in both folders")
            }
            Finding::RowCount { table, baseline, current } => {
                format!("{table}: {baseline} rows in the baseline, {current} now")
            }
            Finding::RowKey { table, row, baseline, current } => {
                format!("{table}: row {row} is {current}, the baseline has {baseline}")
            }
            Finding::Cell { table, row, column, baseline, current, rel, judged, .. } => {
                format!(
                    "{table}:{row}:{column} {baseline} -> {current} (rel {rel:.2e}){}",
                    if *judged { "" } else { " [timing, not judged]" }
                )
            }
        }
    }
}

/// The outcome of a comparison.
#[derive(Debug, Clone, Default)]
pub(crate) struct DriftReport {
    pub(crate) tables: usize,
    pub(crate) cells: usize,
    pub(crate) findings: Vec<Finding>,
}

impl DriftReport {
    pub(crate) fn drifted(&self) -> bool {
        self.findings.iter().any(Finding::drifted)
    }

    /// The summary printed by `somnurbs drift`.
    pub(crate) fn summary(&self, most: usize) -> String {
        let drifted: Vec<&Finding> = self.findings.iter().filter(|f| f.drifted()).collect();
        let mut s = format!("compared {} tables, {} cells: ", self.tables, self.cells);
        if drifted.is_empty() {
            s.push_str("no drift");
        } else {
            let mut per_table: BTreeMap<&str, (usize, f64)> = BTreeMap::new();
            for f in &drifted {
                let (t, rel) = match f {
                    Finding::MissingTable { table }
                    | Finding::MissingColumn { table, .. }
                    | Finding::RowCount { table, .. }
                    | Finding::RowKey { table, .. } => (table.as_str(), f64::INFINITY),
                    Finding::Cell { table, rel, .. } => (table.as_str(), *rel),
                    Finding::ExtraTable { table }
                    | Finding::ExtraColumn { table, .. }
                    | Finding::NonFinite { table, .. } => (table.as_str(), 0.0),
                };
                let e = per_table.entry(t).or_insert((0, 0.0));
                e.0 += 1;
                e.1 = e.1.max(rel);
            }
            let _ = write!(s, "DRIFT in {} places", drifted.len());
            for (t, (n, rel)) in &per_table {
                let _ = write!(s, "\n  {t}: {n} moved (largest relative change {rel:.2e})");
            }
            // Structural findings (a missing table, column or row) always show, before the cells.
            let structural: Vec<&&Finding> =
                drifted.iter().filter(|f| !matches!(f, Finding::Cell { .. })).collect();
            for f in &structural {
                let _ = write!(s, "\n  {}", f.describe());
            }
            s.push_str("\nfirst moves:");
            for f in drifted.iter().filter(|f| matches!(f, Finding::Cell { .. })).take(most) {
                let _ = write!(s, "\n  {}", f.describe());
            }
        }
        let timing = self
            .findings
            .iter()
            .filter(|f| matches!(f, Finding::Cell { judged: false, .. }))
            .count();
        if timing > 0 {
            let _ =
                write!(s, "\n{timing} timing cells differ (reported in the diff CSV, not judged)");
        }
        for f in self.findings.iter().filter(|f| {
            matches!(
                f,
                Finding::ExtraTable { .. }
                    | Finding::ExtraColumn { .. }
                    | Finding::NonFinite { .. }
            )
        }) {
            let _ = write!(s, "\nnote: {}", f.describe());
        }
        s
    }

    /// The per-cell diff CSV.
    pub(crate) fn csv(&self) -> Result<String> {
        let header: Vec<String> = [
            "table", "row", "column", "baseline", "current", "abs_diff", "rel_diff", "judged",
            "drifted", "what",
        ]
        .iter()
        .map(|h| h.to_string())
        .collect();
        let rows: Vec<Vec<String>> = self
            .findings
            .iter()
            .map(|f| match f {
                Finding::Cell { table, row, column, baseline, current, abs, rel, judged } => {
                    vec![
                        table.clone(),
                        row.clone(),
                        column.clone(),
                        baseline.clone(),
                        current.clone(),
                        format!("{abs:e}"),
                        format!("{rel:e}"),
                        yes(*judged),
                        yes(f.drifted()),
                        "cell".into(),
                    ]
                }
                other => {
                    let table = match other {
                        Finding::MissingTable { table }
                        | Finding::ExtraTable { table }
                        | Finding::MissingColumn { table, .. }
                        | Finding::ExtraColumn { table, .. }
                        | Finding::RowCount { table, .. }
                        | Finding::RowKey { table, .. }
                        | Finding::NonFinite { table, .. } => table.clone(),
                        Finding::Cell { .. } => unreachable!(),
                    };
                    vec![
                        table,
                        String::new(),
                        String::new(),
                        String::new(),
                        String::new(),
                        String::new(),
                        String::new(),
                        "yes".into(),
                        yes(other.drifted()),
                        other.describe(),
                    ]
                }
            })
            .collect();
        csv_records(&header, &rows)
    }
}

fn yes(b: bool) -> String {
    if b { "yes" } else { "no" }.into()
}

/// A parsed CSV table.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Table {
    pub(crate) header: Vec<String>,
    pub(crate) rows: Vec<Vec<String>>,
}

impl Table {
    pub(crate) fn parse(name: &str, text: &str) -> Result<Table> {
        let mut rd = csv::ReaderBuilder::new().has_headers(true).from_reader(text.as_bytes());
        let header: Vec<String> = rd
            .headers()
            .with_context(|| format!("{name}: malformed CSV header"))?
            .iter()
            .map(String::from)
            .collect();
        let mut rows = Vec::new();
        for rec in rd.records() {
            let rec = rec.map_err(|e| {
                let line = e.position().map(|p| p.line()).unwrap_or(0);
                anyhow::anyhow!("{name}: line {line}: malformed CSV: {e}")
            })?;
            rows.push(rec.iter().map(String::from).collect());
        }
        Ok(Table { header, rows })
    }
}

/// Compare one table (pure).
pub(crate) fn compare_table(
    name: &str,
    base: &Table,
    cur: &Table,
    opts: &DriftOptions,
    report: &mut DriftReport,
) {
    report.tables += 1;
    let timing_table = opts.config.timing_tables.iter().any(|g| glob(g, name));
    for c in &base.header {
        if !cur.header.contains(c) {
            report.findings.push(Finding::MissingColumn { table: name.into(), column: c.clone() });
        }
    }
    for c in &cur.header {
        if !base.header.contains(c) {
            report.findings.push(Finding::ExtraColumn { table: name.into(), column: c.clone() });
        }
    }
    if base.rows.len() != cur.rows.len() {
        report.findings.push(Finding::RowCount {
            table: name.into(),
            baseline: base.rows.len(),
            current: cur.rows.len(),
        });
    }
    let cols: Vec<(usize, usize, &String)> = base
        .header
        .iter()
        .enumerate()
        .filter_map(|(i, c)| cur.header.iter().position(|d| d == c).map(|j| (i, j, c)))
        .collect();
    let is_key = |c: &str, v: &str| IDENTITY.contains(&c) || (!v.is_empty() && number(v).is_none());
    for (r, (b, c)) in base.rows.iter().zip(&cur.rows).enumerate() {
        let key_cols: Vec<(usize, usize)> = cols
            .iter()
            .filter(|(i, _, name)| is_key(name, b.get(*i).map(String::as_str).unwrap_or("")))
            .map(|(i, j, _)| (*i, *j))
            .collect();
        let kb = key_cols
            .iter()
            .map(|(i, _)| b.get(*i).cloned().unwrap_or_default())
            .collect::<Vec<_>>()
            .join("/");
        let kc = key_cols
            .iter()
            .map(|(_, j)| c.get(*j).cloned().unwrap_or_default())
            .collect::<Vec<_>>()
            .join("/");
        // A timing-dependent row (e.g. a claim about speed) may change its text cells too (its
        // verdict): those are reported as unjudged cells, not as a different row.
        let timing_row = opts
            .config
            .timing_rows
            .iter()
            .any(|t| b.iter().chain(c).any(|v| v.contains(t.as_str())));
        if kb != kc && !timing_row {
            report.findings.push(Finding::RowKey {
                table: name.into(),
                row: r + 1,
                baseline: kb,
                current: kc,
            });
            continue;
        }
        let key = if kb.is_empty() { format!("row {}", r + 1) } else { kb };
        for &(i, j, col) in &cols {
            let (vb, vc) = (
                b.get(i).map(String::as_str).unwrap_or(""),
                c.get(j).map(String::as_str).unwrap_or(""),
            );
            let judged = !(timing_table || timing_row || is_timing_column(col));
            compare_cell(name, &key, col, (vb, vc), judged, opts, report);
        }
    }
}

/// Compare one cell of a table (same column, same row key); findings go into `report`.
fn compare_cell(
    name: &str,
    key: &str,
    col: &str,
    (vb, vc): (&str, &str),
    judged: bool,
    opts: &DriftOptions,
    report: &mut DriftReport,
) {
    report.cells += 1;
    if vb == vc {
        if number(vb).is_some_and(|x| !x.is_finite()) {
            report.findings.push(Finding::NonFinite {
                table: name.into(),
                row: key.into(),
                column: col.into(),
                value: vb.into(),
            });
        }
        return;
    }
    match (number(vb), number(vc)) {
        (Some(x), Some(y)) => {
            if judged && opts.tolerance(col).equal(x, y) {
                return;
            }
            let abs = (x - y).abs();
            let rel = if x.is_finite() && y.is_finite() {
                abs / x.abs().max(y.abs()).max(f64::MIN_POSITIVE)
            } else {
                f64::INFINITY
            };
            report.findings.push(Finding::Cell {
                table: name.into(),
                row: key.into(),
                column: col.into(),
                baseline: vb.into(),
                current: vc.into(),
                abs,
                rel,
                judged,
            });
        }
        _ => report.findings.push(Finding::Cell {
            table: name.into(),
            row: key.into(),
            column: col.into(),
            baseline: vb.into(),
            current: vc.into(),
            abs: f64::NAN,
            rel: f64::INFINITY,
            judged,
        }),
    }
}

/// The tables of a folder: relative paths of its CSVs outside `png/`, `ioh/` and `maps/` (links
/// to folders are not followed).
pub(crate) fn tables(dir: &Path) -> Result<Vec<PathBuf>> {
    if !dir.is_dir() {
        bail!("{} is not a folder", dir.display());
    }
    let skipped = |p: &Path| {
        p.components().any(|c| ["png", "ioh", "maps"].iter().any(|s| c.as_os_str() == *s))
    };
    let (files, _) = crate::io::outdir::walk(dir)?;
    Ok(files
        .into_iter()
        .filter(|f| {
            f.extension().is_some_and(|e| e == "csv")
                && f.file_name().is_some_and(|n| n != "drift.csv")
                && !skipped(f.parent().unwrap_or(Path::new("")))
        })
        .collect())
}

/// What made a result folder, from its `manifest.toml`: the fields two folders must share for
/// their tables to be compared (a run's spec, seed, profile and `--set`/`--sweep`; a `fit`
/// folder's grid and options).
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub(crate) struct Identity {
    /// `fit` for a `somnurbs fit` folder (absent in a run's manifest).
    #[serde(default)]
    pub(crate) kind: Option<String>,
    #[serde(default)]
    pub(crate) spec_name: Option<String>,
    #[serde(default)]
    spec_sha256: Option<String>,
    #[serde(default)]
    profile: Option<String>,
    #[serde(default)]
    master_seed: Option<u64>,
    #[serde(default)]
    set: Vec<String>,
    #[serde(default)]
    sweep: Vec<String>,
    /// A fit folder's grid file, its hash and options.
    #[serde(default)]
    grid_sha256: Option<String>,
    #[serde(default)]
    options: BTreeMap<String, toml::Value>,
    /// The run's spec text (its sections tell which chapter made it).
    #[serde(default)]
    pub(crate) spec_text: Option<String>,
}

impl Identity {
    /// Read the identity of the folder holding `manifest`.
    pub(crate) fn read(manifest: &Path) -> Result<Identity> {
        crate::io::read_toml(manifest)
    }

    /// Whether the folder was written by `somnurbs fit` (today's manifest says `kind = "fit"`; an
    /// older one named its spec `fit` and had a `command` line).
    pub(crate) fn is_fit(&self) -> bool {
        self.kind.as_deref() == Some("fit")
            || (self.spec_name.as_deref() == Some("fit") && self.master_seed == Some(0))
    }

    /// What the folder holds, for messages: `a somnurbs fit folder`, `a run of spec ch6_same`.
    pub(crate) fn describe(&self) -> String {
        if self.is_fit() {
            return "a `somnurbs fit` folder".into();
        }
        match &self.spec_name {
            Some(n) => format!("a run of spec {n}"),
            None => "a result folder".into(),
        }
    }

    /// What differs between two identities (None: the same run), e.g. `master seed 11 vs 12;
    /// --set none vs optimise.de.f=0.5`.
    pub(crate) fn difference(&self, other: &Identity) -> Option<String> {
        let mut what: Vec<String> = Vec::new();
        let opt = |v: &Option<String>| v.clone().unwrap_or_else(|| "none".into());
        let list = |v: &[String]| if v.is_empty() { "none".into() } else { v.join(" ") };
        if self.is_fit() != other.is_fit() {
            what.push(format!("kind: {} vs {}", self.describe(), other.describe()));
            return Some(what.join("; "));
        }
        if self.spec_name != other.spec_name {
            what.push(format!("spec {} vs {}", opt(&self.spec_name), opt(&other.spec_name)));
        } else if self.spec_sha256 != other.spec_sha256 {
            let short = |v: &Option<String>| opt(v).chars().take(12).collect::<String>();
            what.push(format!(
                "spec text (sha256 {} vs {})",
                short(&self.spec_sha256),
                short(&other.spec_sha256)
            ));
        }
        if self.master_seed != other.master_seed {
            let seed = |v: Option<u64>| v.map_or("none".into(), |s| s.to_string());
            what.push(format!(
                "master seed {} vs {}",
                seed(self.master_seed),
                seed(other.master_seed)
            ));
        }
        if self.profile != other.profile {
            what.push(format!("profile {} vs {}", opt(&self.profile), opt(&other.profile)));
        }
        if self.set != other.set {
            what.push(format!("--set {} vs {}", list(&self.set), list(&other.set)));
        }
        if self.sweep != other.sweep {
            what.push(format!("--sweep {} vs {}", list(&self.sweep), list(&other.sweep)));
        }
        if self.grid_sha256 != other.grid_sha256 {
            what.push("grid file (sha256)".into());
        }
        for (k, v) in &self.options {
            let o = other.options.get(k);
            if o != Some(v) {
                let shown = o.map_or("none".into(), |o| o.to_string());
                what.push(format!("--{} {v} vs {shown}", k.replace('_', "-")));
            }
        }
        (!what.is_empty()).then(|| what.join("; "))
    }
}

/// The identity of every `manifest.toml` under a folder, by relative folder.
fn identities(dir: &Path) -> Result<BTreeMap<PathBuf, Identity>> {
    let mut out = BTreeMap::new();
    for f in crate::io::outdir::walk(dir)?
        .0
        .into_iter()
        .filter(|f| f.file_name().is_some_and(|n| n == crate::io::outdir::MANIFEST))
    {
        let id = Identity::read(&dir.join(&f))?;
        out.insert(f.parent().unwrap_or(Path::new("")).to_path_buf(), id);
    }
    Ok(out)
}

/// Refuse two folders whose runs differ (naming both folders and what differs).
fn require_same_runs(baseline: &Path, current: &Path) -> Result<()> {
    let (ib, ic) = (identities(baseline)?, identities(current)?);
    for (dir, b) in &ib {
        let Some(c) = ic.get(dir) else { continue };
        if let Some(w) = b.difference(c) {
            let at = |root: &Path| {
                if dir.as_os_str().is_empty() {
                    root.to_path_buf()
                } else {
                    root.join(dir)
                }
            };
            bail!("{} and {} hold different runs ({w}): drift is expected; compare them anyway with --allow-spec-change", at(baseline).display(), at(current).display());
        }
    }
    Ok(())
}

/// Read `drift.toml` of a baseline folder (absent: defaults).
pub(crate) fn read_config(baseline: &Path) -> Result<DriftConfig> {
    let p = baseline.join("drift.toml");
    if !p.exists() {
        return Ok(DriftConfig::default());
    }
    crate::io::read_toml(&p)
}

/// Compare two folders. `allow_spec_change`: runs of other specs are compared anyway.
pub(crate) fn compare_dirs(
    baseline: &Path,
    current: &Path,
    opts: &DriftOptions,
    allow_spec_change: bool,
) -> Result<DriftReport> {
    crate::io::outdir::require_finished(baseline, "the baseline")?;
    crate::io::outdir::require_finished(current, "the current folder")?;
    let (tb, tc) = (tables(baseline)?, tables(current)?);
    if tb.is_empty() {
        bail!("{} holds no tables (*.csv): not a baseline", baseline.display());
    }
    if !allow_spec_change {
        require_same_runs(baseline, current)?;
    }
    let mut report = DriftReport::default();
    for t in &tb {
        let name = t.to_string_lossy().to_string();
        if !tc.contains(t) {
            report.findings.push(Finding::MissingTable { table: name });
            continue;
        }
        let read = |root: &Path| -> Result<Table> {
            let p = root.join(t);
            let text = crate::io::read_text(&p)?;
            Table::parse(&p.display().to_string(), &text)
        };
        compare_table(&name, &read(baseline)?, &read(current)?, opts, &mut report);
    }
    for t in tc.iter().filter(|t| !tb.contains(t)) {
        report.findings.push(Finding::ExtraTable { table: t.to_string_lossy().to_string() });
    }
    Ok(report)
}

/// Make `baseline` hold the current tables (and manifests); tables the current folder lacks are
/// removed, other files of the baseline (its drift.toml) kept. The current folder must hold a
/// finished, whole run. The new baseline is built beside the old one and swapped in whole
/// ([`crate::io::outdir::replace_dir`]) under the baseline's lock: a failure leaves the old baseline
/// as it was. Returns one line per file changed.
pub(crate) fn accept(baseline: &Path, current: &Path) -> Result<Vec<String>> {
    crate::io::outdir::require_finished(current, "the current folder")?;
    let tc = tables(current)?;
    if tc.is_empty() {
        bail!("{} holds no tables (*.csv)", current.display());
    }
    let _lock = crate::io::outdir::lock(baseline, "drift --accept")?;
    let stale = crate::io::outdir::stale_siblings(baseline)?;
    crate::io::outdir::remove_stale(&stale, baseline, "drift --accept")?;
    let (old_files, _) = crate::io::outdir::walk(baseline)?;
    let tb = tables(baseline)?;
    let mut files: Vec<PathBuf> = tc.clone();
    files.extend(identities(current)?.keys().map(|d| d.join(crate::io::outdir::MANIFEST)));
    let mut said = Vec::new();
    crate::io::outdir::replace_dir(baseline, |staged| {
        // The old baseline's files first (not lock files, nor the tables the current run lacks) ...
        let lock = |f: &Path| f.file_name().is_some_and(|n| n == crate::io::outdir::LOCK_FILE);
        for f in old_files
            .iter()
            .filter(|f| !tc.contains(f) && !tb.contains(f) && !files.contains(f) && !lock(f))
        {
            let text = crate::io::input::read(&baseline.join(f), crate::io::input::Kind::Text)?;
            write_atomic(&staged.join(f), &text)?;
        }
        // ... then the current run's tables and manifests.
        for f in &files {
            let text = crate::io::input::read(&current.join(f), crate::io::input::Kind::Text)?;
            let old = crate::io::input::read(&baseline.join(f), crate::io::input::Kind::Text).ok();
            write_atomic(&staged.join(f), &text)?;
            if old.as_deref() != Some(&text[..]) {
                said.push(format!(
                    "{} {}",
                    if old.is_some() { "replaced" } else { "added" },
                    f.display()
                ));
            }
        }
        said.extend(
            tb.iter().filter(|f| !tc.contains(f)).map(|f| format!("removed {}", f.display())),
        );
        Ok(())
    })?;
    Ok(said)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(text: &str) -> Table {
        Table::parse("t.csv", text).unwrap()
    }

    fn cmp(a: &str, b: &str, opts: &DriftOptions) -> DriftReport {
        let mut r = DriftReport::default();
        compare_table("t.csv", &t(a), &t(b), opts, &mut r);
        r
    }

    const BASE: &str = "data,cn_x,err,cpu_s\ncube,6,1.5,0.01\ncube,8,1.25,0.02\n";

    #[test]
    fn identical_tables_do_not_drift() {
        let r = cmp(BASE, BASE, &DriftOptions::default());
        assert!(!r.drifted() && r.findings.is_empty());
        assert_eq!((r.tables, r.cells), (1, 8));
    }

    #[test]
    fn a_moved_number_is_named_and_small_noise_is_not() {
        let moved = BASE.replace("1.25,", "1.2500001,");
        let r = cmp(BASE, &moved, &DriftOptions::default());
        assert!(r.drifted());
        assert_eq!(r.findings.len(), 1);
        let Finding::Cell { row, column, baseline, current, .. } = &r.findings[0] else { panic!() };
        assert_eq!(
            (row.as_str(), column.as_str(), baseline.as_str(), current.as_str()),
            ("cube/8", "err", "1.25", "1.2500001")
        );
        assert!(r.summary(5).contains("t.csv:cube/8:err 1.25 -> 1.2500001"));
        let tiny = BASE.replace("1.25,", "1.25000000000001,");
        assert!(!cmp(BASE, &tiny, &DriftOptions::default()).drifted());
        let loose = DriftOptions {
            columns: vec![("e*".into(), Tolerance { abs: 1e-3, rel: 0.0 })],
            ..DriftOptions::default()
        };
        assert!(!cmp(BASE, &moved, &loose).drifted());
    }

    #[test]
    fn timing_is_reported_not_judged() {
        let slower = BASE.replace("0.02", "0.5");
        let r = cmp(BASE, &slower, &DriftOptions::default());
        assert!(!r.drifted());
        assert!(matches!(&r.findings[0], Finding::Cell { judged: false, .. }));
        assert!(r.summary(5).contains("1 timing cells differ"));
        // A table declared timing-dependent.
        let opts = DriftOptions {
            config: DriftConfig { timing_tables: vec!["t.*".into()], ..DriftConfig::default() },
            ..DriftOptions::default()
        };
        assert!(!cmp(BASE, &BASE.replace("1.25,", "9,"), &opts).drifted());
        let rows = DriftOptions {
            config: DriftConfig { timing_rows: vec!["cube".into()], ..DriftConfig::default() },
            ..DriftOptions::default()
        };
        assert!(!cmp(BASE, &BASE.replace("1.25,", "9,"), &rows).drifted());
        // A claim about speed whose verdict (a text cell, part of the row key) flips on timing
        // noise is reported, not judged; the same flip in another row is drift.
        let claims = "claim,verdict,holds\nA is the fastest,holds,5\nB is exact,holds,5\n";
        let speed = DriftOptions {
            config: DriftConfig { timing_rows: vec!["fastest".into()], ..DriftConfig::default() },
            ..DriftOptions::default()
        };
        let r = cmp(claims, &claims.replace("fastest,holds,5", "fastest,undecided,4"), &speed);
        assert!(
            !r.drifted()
                && r.findings.iter().all(|f| matches!(f, Finding::Cell { judged: false, .. })),
            "{:?}",
            r.findings
        );
        assert!(cmp(claims, &claims.replace("exact,holds", "exact,undecided"), &speed).drifted());
    }

    #[test]
    fn missing_columns_rows_and_moved_keys_drift() {
        let r = cmp(BASE, "data,cn_x,cpu_s\ncube,6,0.01\n", &DriftOptions::default());
        assert!(r
            .findings
            .iter()
            .any(|f| matches!(f, Finding::MissingColumn { column, .. } if column == "err")));
        assert!(r
            .findings
            .iter()
            .any(|f| matches!(f, Finding::RowCount { baseline: 2, current: 1, .. })));
        let r = cmp(BASE, &BASE.replace("cube,8", "cube,10"), &DriftOptions::default());
        assert!(matches!(&r.findings[0], Finding::RowKey { row: 2, .. }), "{:?}", r.findings);
        let r = cmp(
            BASE,
            "data,cn_x,err,cpu_s,new\ncube,6,1.5,0.01,1\ncube,8,1.25,0.02,2\n",
            &DriftOptions::default(),
        );
        assert!(!r.drifted(), "a new column is noted, not drift");
    }

    #[test]
    fn malformed_csv_names_file_and_line() {
        let e = Table::parse("x/appendix_k.csv", "a,b\n1,2\n3\n").unwrap_err().to_string();
        assert!(e.contains("x/appendix_k.csv: line 3"), "{e}");
    }

    #[test]
    fn tolerances_and_globs_parse() {
        assert_eq!(
            parse_tol("err=1e-6").unwrap(),
            ("err".into(), Tolerance { abs: 1e-6, rel: 0.0 })
        );
        assert_eq!(parse_tol("*_avg=0,1e-3").unwrap().1, Tolerance { abs: 0.0, rel: 1e-3 });
        assert!(
            parse_tol("err").is_err()
                && parse_tol("err=-1").is_err()
                && parse_tol("err=x").is_err()
        );
        assert!(
            glob("*_avg", "de_avg")
                && glob("ch6*/table_6_6.csv", "ch6_same/table_6_6.csv")
                && !glob("a*b", "ac")
                && glob("x", "x")
        );
        assert!(
            Tolerance::default().equal(f64::NAN, f64::NAN)
                && !Tolerance::default().equal(1.0, f64::NAN)
        );
    }

    #[test]
    fn non_finite_numbers_compare_by_identity_and_are_reported() {
        let t = Tolerance { abs: 1e-9, rel: 1e-9 };
        let (inf, nan) = (f64::INFINITY, f64::NAN);
        assert!(
            !t.equal(1.5, inf) && !t.equal(inf, 1.5) && !t.equal(-inf, inf) && !t.equal(inf, nan)
        );
        assert!(t.equal(inf, inf) && t.equal(-inf, -inf) && t.equal(nan, nan));
        let loose = Tolerance { abs: 1e300, rel: 1.0 };
        assert!(!loose.equal(f64::MAX, inf));
        let base = "k,v\na,1.5\nb,inf\n";
        let r = cmp(base, "k,v\na,inf\nb,inf\n", &DriftOptions::default());
        assert!(r.drifted(), "{:?}", r.findings);
        assert!(
            r.summary(5).contains("t.csv:a:v 1.5 -> inf")
                && r.summary(5).contains("b:v is inf in both"),
            "{}",
            r.summary(5)
        );
        assert!(cmp(base, "k,v\na,1.5\nb,-inf\n", &DriftOptions::default()).drifted());
        let r = cmp(base, base, &DriftOptions::default());
        assert!(
            !r.drifted() && r.summary(5).contains("note: t.csv:b:v is inf in both folders"),
            "{}",
            r.summary(5)
        );
    }

    /// A hex seed that reads as an overflowing number is text (no "inf" note), and a seed is part
    /// of its row's key, so two all-digit seeds that differ in the last digit are a drift, not a
    /// difference within the tolerance.
    #[test]
    fn seeds_are_keys_and_hex_is_not_infinity() {
        let base = "cell,seed,best\na,9e71084187728100,1.5\nb,1234567890123456,2.5\n";
        let r = cmp(base, base, &DriftOptions::default());
        assert!(!r.drifted() && !r.summary(5).contains("inf"), "{}", r.summary(5));
        let moved = base.replace("1234567890123456", "1234567890123457");
        let r = cmp(base, &moved, &DriftOptions::default());
        assert!(r.drifted() && r.summary(5).contains("1234567890123457"), "{}", r.summary(5));
        assert_eq!(number("inf"), Some(f64::INFINITY));
        assert_eq!(number("-Infinity"), Some(f64::NEG_INFINITY));
        assert_eq!((number("9e71084187728100"), number("1e5")), (None, Some(1e5)));
    }
}
