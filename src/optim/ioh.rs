//! Convergence data in the IOHprofiler format, so that IOHanalyzer and iohinspector load the
//! optimisers' runs without a converter. Pure: these functions return file contents (and read
//! them back); writing and reading files is the caller's business.
//!
//! The layout is the one the `ioh` package's `Analyzer` logger writes (JSON meta-data, format
//! version 0.3.3 or later, which IOHanalyzer's `check_format` accepts as IOHprofiler data without
//! looking at the data files, and reads with `read_IOH_v1plus`), per problem ("function") and
//! algorithm:
//! - `IOHprofiler_f<id>_<name>.json`: `version`, `suite`, `function_id`, `function_name`,
//!   `maximization` (false: minimisation), `algorithm` {`name`, `info`}, `attributes` (the
//!   `.dat` columns, `["evaluations", "raw_y"]`; without it IOHanalyzer numbers rows 1, 2, ...),
//!   and `scenarios` [{`dimension`, `path`, `runs` [{`instance`, `evals`, `best` {`evals`, `y`,
//!   `x`}}]}];
//! - `data_f<id>_<name>/IOHprofiler_f<id>_DIM<d>.dat`, improvement-based: per run the header line
//!   `evaluations raw_y`, then one row per improvement of the best so far, the first at
//!   evaluation 1 (iohinspector starts a new run at every row with evaluations = 1), and a last
//!   row at the run's final evaluation when that was no improvement (as the `ioh` logger closes a
//!   run; its value here is the best so far, which the readers' running minimum leaves unchanged).
//!
//! No other index file (`.info`) may sit beside the JSON: IOHanalyzer takes the whole folder for
//! another format unless every index file has a version, and iohinspector parses `.info` files as
//! COCO's. The fixed-interval trace is not exported: the improvement rows hold every change of the
//! best, and the JSON-era readers read no `.idat`.

use std::fmt::Write;

/// The `version` written: the `ioh` logger version whose output this layout was checked against
/// (IOHanalyzer needs at least 0.3.3 to read the JSON form).
pub(crate) const FORMAT_VERSION: &str = "0.3.22";

/// The `.dat` header (the JSON's `attributes`).
pub(crate) const ATTRIBUTES: [&str; 2] = ["evaluations", "raw_y"];

/// What the meta-data file says about the runs.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct IohMeta {
    pub(crate) suite: String,
    pub(crate) function_id: u32,
    /// A name without spaces or slashes (e.g. "spindle_20x20_18x18_chord_length"); used in file
    /// names.
    pub(crate) function_name: String,
    pub(crate) algorithm: String,
    pub(crate) algorithm_info: String,
    pub(crate) dimension: usize,
}

impl IohMeta {
    /// The meta-data file name.
    pub(crate) fn json_file_name(&self) -> String {
        format!("IOHprofiler_f{}_{}.json", self.function_id, self.function_name)
    }

    /// The raw-data file, relative to the meta-data file.
    pub(crate) fn dat_path(&self) -> String {
        format!(
            "data_f{}_{}/IOHprofiler_f{}_DIM{}.dat",
            self.function_id, self.function_name, self.function_id, self.dimension
        )
    }
}

/// One run as the exporter sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct IohRun<'a> {
    /// Evaluations the run made.
    pub(crate) evaluations: u64,
    /// (evaluation, fitness) at every strict improvement, the first at evaluation 1.
    pub(crate) improvements: &'a [(u64, f64)],
    /// The best point, when known (empty: written as `[]`).
    pub(crate) best_x: &'a [f64],
}

impl IohRun<'_> {
    /// The best value and the evaluation that found it (+inf at 0 for a run with no finite value).
    pub(crate) fn best(&self) -> (u64, f64) {
        self.improvements.last().copied().unwrap_or((0, f64::INFINITY))
    }
}

/// A number as R and polars read it (shortest round-trip scientific notation; Inf/NaN).
fn num(v: f64) -> String {
    if v.is_nan() {
        "NaN".into()
    } else if v == f64::INFINITY {
        "Inf".into()
    } else if v == f64::NEG_INFINITY {
        "-Inf".into()
    } else {
        format!("{v:e}")
    }
}

/// A JSON number (JSON has no infinities: they become null).
fn json_num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:e}")
    } else {
        "null".into()
    }
}

/// A coordinate of a best point (most of the file) as a JSON number: shortest round-trip, in the
/// fewer characters of decimal (`0.4365105464024034`) and scientific (`4.365105464024034e-1`)
/// notation; the same f64 either way.
fn json_coordinate(v: f64) -> String {
    if !v.is_finite() {
        return "null".into();
    }
    let (decimal, scientific) = (format!("{v:?}"), format!("{v:e}"));
    if decimal.len() <= scientific.len() {
        decimal
    } else {
        scientific
    }
}

fn json_str(s: &str) -> String {
    serde_json::to_string(s).expect("a string serialises")
}

/// The raw-data (.dat) text of several runs of one algorithm on one problem.
pub(crate) fn dat_text(runs: &[IohRun]) -> String {
    let mut out = String::new();
    for run in runs {
        out.push_str(&ATTRIBUTES.join(" "));
        out.push('\n');
        let (last, best) = run.best();
        if run.improvements.first().map(|i| i.0) != Some(1) && run.evaluations >= 1 {
            // The first evaluation gave no finite value (it is the run's first row all the same).
            let _ = writeln!(out, "1 {}", num(f64::INFINITY));
        }
        for &(e, y) in run.improvements {
            let _ = writeln!(out, "{e} {}", num(y));
        }
        if run.evaluations > last.max(1) {
            let _ = writeln!(out, "{} {}", run.evaluations, num(best));
        }
    }
    out
}

/// The `.json` meta-data text.
pub(crate) fn json_text(meta: &IohMeta, runs: &[IohRun]) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "{{");
    let _ = writeln!(out, "  \"version\": {},", json_str(FORMAT_VERSION));
    let _ = writeln!(out, "  \"suite\": {},", json_str(&meta.suite));
    let _ = writeln!(out, "  \"function_id\": {},", meta.function_id);
    let _ = writeln!(out, "  \"function_name\": {},", json_str(&meta.function_name));
    let _ = writeln!(out, "  \"maximization\": false,");
    let _ = writeln!(
        out,
        "  \"algorithm\": {{\"name\": {}, \"info\": {}}},",
        json_str(&meta.algorithm),
        json_str(&meta.algorithm_info)
    );
    let attrs: Vec<String> = ATTRIBUTES.iter().map(|a| json_str(a)).collect();
    let _ = writeln!(out, "  \"attributes\": [{}],", attrs.join(", "));
    let _ = writeln!(out, "  \"scenarios\": [");
    let _ = writeln!(
        out,
        "    {{\"dimension\": {}, \"path\": {}, \"runs\": [",
        meta.dimension,
        json_str(&meta.dat_path())
    );
    for (k, run) in runs.iter().enumerate() {
        let xs: Vec<String> = run.best_x.iter().map(|&v| json_coordinate(v)).collect();
        let (at, best) = run.best();
        let _ = write!(
            out,
            "      {{\"instance\": 1, \"evals\": {}, \"best\": {{\"evals\": {at}, \"y\": {}, \"x\": [{}]}}}}",
            run.evaluations,
            json_num(best),
            xs.join(",")
        );
        out.push_str(if k + 1 < runs.len() { ",\n" } else { "\n" });
    }
    let _ = writeln!(out, "    ]}}");
    let _ = writeln!(out, "  ]");
    let _ = writeln!(out, "}}");
    out
}

/// Parse a `.dat` text back into runs of (evaluation, value) rows (a header line starts a run).
/// Errors name the 1-based line; a value that is not finite (`nan`, `Inf`) is one.
pub(crate) fn parse_dat(text: &str) -> Result<Vec<Vec<(u64, f64)>>, String> {
    let mut runs: Vec<Vec<(u64, f64)>> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        if line.starts_with(|c: char| c.is_ascii_alphabetic()) {
            runs.push(Vec::new());
            continue;
        }
        let mut cols = line.split_whitespace();
        let (Some(e), Some(y)) = (cols.next(), cols.next()) else {
            return Err(format!("line {}: expected `evaluations value`, got {line:?}", n + 1));
        };
        let e: u64 =
            e.parse().map_err(|_| format!("line {}: evaluations {e:?} is not a count", n + 1))?;
        let y: f64 = match y {
            "Inf" => f64::INFINITY,
            "-Inf" => f64::NEG_INFINITY,
            y => y.parse().map_err(|_| format!("line {}: value {y:?} is not a number", n + 1))?,
        };
        if !y.is_finite() {
            return Err(format!(
                "line {}: value {y} is not finite (a trace holds the best fitness so far)",
                n + 1
            ));
        }
        runs.last_mut()
            .ok_or_else(|| format!("line {}: a row before the first header", n + 1))?
            .push((e, y));
    }
    Ok(runs)
}

#[cfg(test)]
mod tests {
    use super::*;

    const IMP: [(u64, f64); 3] = [(1, 2.0), (3, 1.5), (70, 0.25)];

    fn meta() -> IohMeta {
        IohMeta {
            suite: "somnurbs".into(),
            function_id: 3,
            function_name: "sphere_cn6x6".into(),
            algorithm: "de".into(),
            algorithm_info: "CR=0.8 \"F\"=0.3".into(),
            dimension: 2,
        }
    }

    #[test]
    fn dat_is_improvement_based_from_evaluation_one() {
        let a = IohRun { evaluations: 90, improvements: &IMP, best_x: &[] };
        let b = IohRun { evaluations: 70, improvements: &IMP, best_x: &[] };
        let text = dat_text(&[a, b]);
        assert_eq!(text, "evaluations raw_y\n1 2e0\n3 1.5e0\n70 2.5e-1\n90 2.5e-1\nevaluations raw_y\n1 2e0\n3 1.5e0\n70 2.5e-1\n");
        let back = parse_dat(&text).unwrap();
        assert_eq!(back.len(), 2);
        assert_eq!(back[1], IMP.to_vec());
        assert_eq!(back[0].last(), Some(&(90, 0.25)));
        // A first evaluation with no finite value still opens the run at evaluation 1.
        let c = IohRun { evaluations: 5, improvements: &[(2, 1.0)], best_x: &[] };
        assert_eq!(dat_text(&[c]), "evaluations raw_y\n1 Inf\n2 1e0\n5 1e0\n");
        assert!(parse_dat("1 2\n").unwrap_err().contains("line 1"));
        assert!(parse_dat("evaluations raw_y\n1 x\n").unwrap_err().contains("line 2"));
        for bad in ["nan", "NaN", "inf", "Inf", "-Inf", "1e999"] {
            let e = parse_dat(&format!("evaluations raw_y\n1 2\n5 {bad}\n")).unwrap_err();
            assert!(e.starts_with("line 3: value") && e.contains("is not finite"), "{bad}: {e}");
        }
    }

    #[test]
    fn json_has_every_key_the_readers_require() {
        let x = [0.5, -1.25];
        let a = IohRun { evaluations: 90, improvements: &IMP, best_x: &x };
        let b = IohRun { evaluations: 90, improvements: &IMP[..2], best_x: &[] };
        let json = json_text(&meta(), &[a, b]);
        let v: serde_json::Value = serde_json::from_str(&json).unwrap();
        for k in [
            "version",
            "suite",
            "function_id",
            "function_name",
            "maximization",
            "algorithm",
            "attributes",
            "scenarios",
        ] {
            assert!(v.get(k).is_some(), "{k}");
        }
        assert_eq!(v["version"], "0.3.22");
        assert_eq!(v["maximization"], false);
        assert_eq!(v["algorithm"]["info"], "CR=0.8 \"F\"=0.3");
        assert_eq!(v["attributes"], serde_json::json!(["evaluations", "raw_y"]));
        let s = &v["scenarios"][0];
        assert_eq!(s["path"], "data_f3_sphere_cn6x6/IOHprofiler_f3_DIM2.dat");
        assert_eq!(s["dimension"], 2);
        assert_eq!(
            s["runs"][0],
            serde_json::json!({"instance": 1, "evals": 90, "best": {"evals": 70, "y": 0.25, "x": [0.5, -1.25]}})
        );
        assert_eq!(s["runs"][1]["best"], serde_json::json!({"evals": 3, "y": 1.5, "x": []}));
        assert_eq!(meta().json_file_name(), "IOHprofiler_f3_sphere_cn6x6.json");
    }

    /// A best point's coordinates take the shorter notation and read back as the same f64s.
    #[test]
    fn coordinates_are_short_and_exact() {
        let x = [0.43651054640240344, -0.09344637539406099, 5e-324, 1.25e-7, 3.0e17, -0.0, 7.0];
        let text: Vec<String> = x.iter().map(|&v| json_coordinate(v)).collect();
        assert_eq!(text[0], "0.43651054640240344");
        assert_eq!((text[2].as_str(), text[3].as_str()), ("5e-324", "1.25e-7"));
        assert_eq!((text[4].as_str(), text[6].as_str()), ("3e17", "7.0"));
        for (v, t) in x.iter().zip(&text) {
            let back: f64 = serde_json::from_str(t).unwrap();
            assert_eq!(back.to_bits(), v.to_bits(), "{t}");
            assert!(t.len() <= format!("{v:e}").len(), "{t}");
        }
        assert_eq!(json_coordinate(f64::NAN), "null");
        let run = IohRun { evaluations: 90, improvements: &IMP, best_x: &x };
        assert!(json_text(&meta(), &[run])
            .contains("\"x\": [0.43651054640240344,-0.09344637539406099,"));
    }
}
