//! Convergence traces in the IOHprofiler format, so that IOHanalyzer can compare the optimisers
//! (fixed-budget and fixed-target views, ECDFs) without a converter. Pure: these functions return
//! file contents; writing them is the caller's business.
//!
//! Layout IOHanalyzer expects, per problem ("function") and algorithm: a meta-data file
//! `IOHprofiler_f<id>_<name>.json` (IOHexperimenter's v2 analyzer; or the older `.info` text) that
//! points to a raw-data file `data_f<id>_<name>/IOHprofiler_f<id>_DIM<d>.dat`. The raw-data file
//! holds every run one after the other, each starting with the header line `evaluations raw_y`
//! (space separated, as IOHexperimenter writes it) followed by one `evaluations value` row per
//! trace checkpoint. Minimisation is declared (`maximization: false`).

use super::problem::RunResult;
use std::fmt::Write;

/// What the meta-data file says about the runs.
#[derive(Debug, Clone, PartialEq)]
pub struct IohMeta {
    pub suite: String,
    pub function_id: u32,
    /// A name without spaces or slashes (e.g. "spindle_chord_cn18x18"); used in file names.
    pub function_name: String,
    pub algorithm: String,
    pub algorithm_info: String,
    pub dimension: usize,
}

impl IohMeta {
    /// The meta-data file name (`.json`; the `.info` variant has the same stem).
    pub fn json_file_name(&self) -> String {
        format!("IOHprofiler_f{}_{}.json", self.function_id, self.function_name)
    }

    pub fn info_file_name(&self) -> String {
        format!("IOHprofiler_f{}_{}.info", self.function_id, self.function_name)
    }

    /// The raw-data file, relative to the meta-data file.
    pub fn dat_path(&self) -> String {
        format!("data_f{}_{}/IOHprofiler_f{}_DIM{}.dat", self.function_id, self.function_name, self.function_id, self.dimension)
    }
}

/// A number as R reads it (shortest round-trip scientific notation; Inf/-Inf/NaN).
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

fn json_str(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// The raw-data (.dat) text of several runs of one algorithm on one problem.
pub fn dat_text(runs: &[&RunResult]) -> String {
    let mut out = String::new();
    for run in runs {
        out.push_str("evaluations raw_y\n");
        for &(e, y) in &run.trace {
            let _ = writeln!(out, "{e} {}", num(y));
        }
    }
    out
}

/// The evaluation count of the first trace checkpoint that reached the run's best (the exact
/// evaluation is known only to checkpoint resolution).
fn best_checkpoint(run: &RunResult) -> u64 {
    run.trace.iter().find(|t| t.1 <= run.best_fitness).map(|t| t.0).unwrap_or(run.evaluations)
}

/// The older `.info` meta-data text (three lines).
pub fn info_text(meta: &IohMeta, runs: &[&RunResult]) -> String {
    let mut out = format!(
        "suite = {}, funcId = {}, funcName = {}, DIM = {}, maximization = \"F\", algId = {}, algInfo = {}\n%\n{}",
        json_str(&meta.suite),
        meta.function_id,
        json_str(&meta.function_name),
        meta.dimension,
        json_str(&meta.algorithm),
        json_str(&meta.algorithm_info),
        meta.dat_path()
    );
    for run in runs {
        let _ = write!(out, ", 1:{}|{}", run.evaluations, num(run.best_fitness));
    }
    out.push('\n');
    out
}

/// The `.json` meta-data text (IOHexperimenter v2 analyzer layout); `with_x` adds each run's
/// best point.
pub fn json_text(meta: &IohMeta, runs: &[&RunResult], with_x: bool) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "{{");
    let _ = writeln!(out, "  \"suite\": {},", json_str(&meta.suite));
    let _ = writeln!(out, "  \"function_id\": {},", meta.function_id);
    let _ = writeln!(out, "  \"function_name\": {},", json_str(&meta.function_name));
    let _ = writeln!(out, "  \"maximization\": false,");
    let _ = writeln!(out, "  \"algorithm\": {{\"name\": {}, \"info\": {}}},", json_str(&meta.algorithm), json_str(&meta.algorithm_info));
    let _ = writeln!(out, "  \"scenarios\": [");
    let _ = writeln!(out, "    {{\"dimension\": {}, \"path\": {}, \"runs\": [", meta.dimension, json_str(&meta.dat_path()));
    for (k, run) in runs.iter().enumerate() {
        let x = if with_x {
            let xs: Vec<String> = run.best_x.iter().map(|&v| json_num(v)).collect();
            format!(", \"x\": [{}]", xs.join(", "))
        } else {
            String::new()
        };
        let _ = write!(
            out,
            "      {{\"instance\": 1, \"evals\": {}, \"best\": {{\"evals\": {}, \"y\": {}{x}}}}}",
            run.evaluations,
            best_checkpoint(run),
            json_num(run.best_fitness)
        );
        out.push_str(if k + 1 < runs.len() { ",\n" } else { "\n" });
    }
    let _ = writeln!(out, "    ]}}");
    let _ = writeln!(out, "  ]");
    let _ = writeln!(out, "}}");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(best: f64) -> RunResult {
        RunResult {
            best_x: vec![0.5, -1.25],
            best_fitness: best,
            initial_best_fitness: 2.0,
            evaluations: 90,
            trace: vec![(40, 2.0), (80, 1.5), (90, best)],
        }
    }

    #[test]
    fn dat_has_one_header_per_run_and_parseable_rows() {
        let (a, b) = (run(1.0), run(0.25));
        let text = dat_text(&[&a, &b]);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 8);
        assert_eq!(lines[0], "evaluations raw_y");
        assert_eq!(lines[4], "evaluations raw_y");
        for l in lines.iter().filter(|l| !l.starts_with('e')) {
            let cols: Vec<&str> = l.split(' ').collect();
            assert_eq!(cols.len(), 2);
            cols[0].parse::<u64>().unwrap();
            cols[1].parse::<f64>().unwrap();
        }
        assert_eq!(lines[7], "90 2.5e-1");
    }

    #[test]
    fn meta_data_point_to_the_dat_file_and_list_every_run() {
        let meta = IohMeta {
            suite: "somnurbs".into(),
            function_id: 3,
            function_name: "sphere_cn6x6".into(),
            algorithm: "de".into(),
            algorithm_info: "CR=0.8 \"F\"=0.3".into(),
            dimension: 2,
        };
        let (a, b) = (run(1.0), run(0.25));
        let info = info_text(&meta, &[&a, &b]);
        let lines: Vec<&str> = info.lines().collect();
        assert_eq!(lines.len(), 3);
        assert!(lines[0].starts_with("suite = \"somnurbs\", funcId = 3, funcName = \"sphere_cn6x6\", DIM = 2"));
        assert_eq!(lines[1], "%");
        assert_eq!(lines[2], "data_f3_sphere_cn6x6/IOHprofiler_f3_DIM2.dat, 1:90|1e0, 1:90|2.5e-1");
        let json = json_text(&meta, &[&a, &b], true);
        assert!(json.contains("\"path\": \"data_f3_sphere_cn6x6/IOHprofiler_f3_DIM2.dat\""));
        assert!(json.contains("\"info\": \"CR=0.8 \\\"F\\\"=0.3\""));
        assert!(json.contains("\"best\": {\"evals\": 90, \"y\": 2.5e-1, \"x\": [5e-1, -1.25e0]}"));
        assert_eq!(json.matches("\"instance\": 1").count(), 2);
        assert_eq!(meta.json_file_name(), "IOHprofiler_f3_sphere_cn6x6.json");
        // Balanced braces and brackets.
        assert_eq!(json.matches('{').count(), json.matches('}').count());
        assert_eq!(json.matches('[').count(), json.matches(']').count());
    }
}
