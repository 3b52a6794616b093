//! Integration tests: run the real binary on tiny specs in temporary folders and read what it
//! writes. On failure each helper prints the command, the folder listing, stdout and stderr.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_somnurbs"))
}

fn shared_data() -> PathBuf {
    match std::env::var_os("SOMNURBS_DATA") {
        Some(v) if !v.is_empty() => PathBuf::from(v),
        _ => Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data"),
    }
}

struct Case {
    dir: tempfile::TempDir,
}

impl Case {
    fn new() -> Case {
        Case { dir: tempfile::tempdir().unwrap() }
    }
    fn path(&self, p: &str) -> PathBuf {
        self.dir.path().join(p)
    }
    fn write(&self, p: &str, text: &str) -> PathBuf {
        let path = self.path(p);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, text).unwrap();
        path
    }
    fn run(&self, args: &[&str]) -> Output {
        let out = bin().args(args).current_dir(self.dir.path()).env("SOMNURBS_DATA", shared_data()).output().unwrap();
        out
    }
    fn explain(&self, args: &[&str], out: &Output) -> String {
        let listing: Vec<String> = walk(self.dir.path()).iter().map(|p| p.strip_prefix(self.dir.path()).unwrap().display().to_string()).collect();
        format!(
            "command: somnurbs {}\nfolder: {:?}\nstatus: {}\nstdout:\n{}\nstderr:\n{}",
            args.join(" "),
            listing,
            out.status,
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        )
    }
    fn ok(&self, args: &[&str]) -> Output {
        let out = self.run(args);
        assert!(out.status.success(), "{}", self.explain(args, &out));
        out
    }
    /// Runs a command that must fail with a one-line error containing every `needle`.
    fn fails(&self, args: &[&str], needles: &[&str]) -> String {
        let out = self.run(args);
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(!out.status.success(), "expected failure\n{}", self.explain(args, &out));
        assert_eq!(err.trim_end().lines().count(), 1, "error is not one line\n{}", self.explain(args, &out));
        for n in needles {
            assert!(err.contains(n), "error lacks {n:?}\n{}", self.explain(args, &out));
        }
        err
    }
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                out.extend(walk(&p));
            } else {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

const TINY: &str = r#"
name = "tiny"
master_seed = 7
[som]
datasets = ["sphere", "cube"]
iterations = 400
save_maps = ["6x5"]
pictures = false
[[som.group]]
models = ["som2d", "som3d", "cksom", "dnsom"]
grids = ["4x4", "6x6"]
[[som.group]]
models = ["cksom", "dnsom"]
grids = ["6x5"]
"#;

fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let h = r.headers().unwrap().iter().map(String::from).collect();
    let rows = r.records().map(|x| x.unwrap().iter().map(String::from).collect()).collect();
    (h, rows)
}

/// A CSV with the timing columns blanked, for comparisons across runs.
fn without_timing(path: &Path) -> Vec<Vec<String>> {
    let (h, rows) = read_csv(path);
    rows.into_iter()
        .map(|r| r.into_iter().zip(&h).map(|(v, c)| if c.starts_with("cpu_s") { String::new() } else { v }).collect())
        .collect()
}

#[test]
fn run_writes_every_table_with_the_thesis_columns() {
    let c = Case::new();
    c.write("tiny.toml", TINY);
    c.ok(&["run", "tiny.toml", "--out", "out", "--jobs", "2"]);
    let out = c.path("out");
    for f in ["runs.csv", "appendix_b.csv", "appendix_c.csv", "table_4_9.csv", "table_4_13.csv", "table_4_14.csv", "manifest.toml", "REPORT.md", "maps/dnsom_sphere_6x5.csv", "maps/dnsom_cube_6x5.csv"] {
        assert!(out.join(f).exists(), "missing {f}: {:?}", walk(&out));
    }
    assert!(!out.join("runs.csv.partial").exists());
    let reference = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/reference");
    for t in ["appendix_b.csv", "appendix_c.csv"] {
        assert_eq!(read_csv(&out.join(t)).0, read_csv(&reference.join(t)).0, "{t} columns");
    }
    let (h, rows) = read_csv(&out.join("runs.csv"));
    assert_eq!(rows.len(), 2 * (4 * 2 + 2)); // 2 data x (4 models x 2 grids + 2 models x 1 grid)
    let col = |name: &str| h.iter().position(|x| x == name).unwrap();
    for r in &rows {
        let qe: f64 = r[col("qe")].parse().unwrap();
        let (mn, mx): (f64, f64) = (r[col("min_error")].parse().unwrap(), r[col("max_error")].parse().unwrap());
        assert!(mn <= qe && qe <= mx && mn >= 0.0, "{r:?}");
        let te: f64 = r[col("te")].parse().unwrap();
        assert!((0.0..=1.0).contains(&te));
    }
    // Table 4.13's DNSOM counts at 6x5 and the saved map has NON rows with both views.
    let (_, t413) = read_csv(&out.join("table_4_13.csv"));
    assert_eq!(t413[0][5..8], ["60".to_string(), "42".into(), "18".into()]);
    let (mh, map) = read_csv(&out.join("maps/dnsom_sphere_6x5.csv"));
    assert_eq!(mh, ["i", "j", "view", "class", "x", "y", "z"]);
    assert_eq!(map.len(), 60);
    let classes: std::collections::BTreeSet<&str> = map.iter().map(|r| r[3].as_str()).collect();
    assert_eq!(classes.len(), 42);
    let manifest = std::fs::read_to_string(out.join("manifest.toml")).unwrap();
    for key in ["master_seed = 7", "spec_text", "git_commit", "rustc", "[definitions]"] {
        assert!(manifest.contains(key), "manifest lacks {key}");
    }
    let report = std::fs::read_to_string(out.join("REPORT.md")).unwrap();
    assert!(report.contains("DNSOM has the lowest TE") && report.contains("Metric definitions"));
}

#[test]
fn results_do_not_depend_on_thread_count() {
    let c = Case::new();
    c.write("tiny.toml", TINY);
    c.ok(&["run", "tiny.toml", "--out", "j1", "--jobs", "1"]);
    c.ok(&["run", "tiny.toml", "--out", "j2", "--jobs", "2"]);
    for f in ["runs.csv", "appendix_b.csv", "appendix_c.csv", "table_4_9.csv", "table_4_13.csv", "maps/dnsom_cube_6x5.csv"] {
        assert_eq!(without_timing(&c.path("j1").join(f)), without_timing(&c.path("j2").join(f)), "{f} differs");
    }
}

#[test]
fn dry_run_lists_cells_and_seeds() {
    let c = Case::new();
    c.write("tiny.toml", TINY);
    let out = c.ok(&["run", "tiny.toml", "--dry-run"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(text.lines().count(), 20);
    assert!(text.contains("som/sphere/dnsom/6x5/r0\tseed "));
    assert!(!c.path("results").exists());
}

#[test]
fn bad_specs_fail_on_one_line_naming_line_and_key() {
    let c = Case::new();
    c.write("broken.toml", "name = \"x\"\nmaster_seed = 1\n[som\n");
    c.fails(&["run", "broken.toml"], &["broken.toml:3:"]);
    c.write("unknown.toml", &TINY.replace("iterations = 400", "iteration = 400"));
    c.fails(&["run", "unknown.toml"], &["unknown.toml:6:1", "iteration"]);
    c.write("model.toml", &TINY.replace("\"som2d\", \"som3d\"", "\"som2d\", \"som4d\""));
    c.fails(&["run", "model.toml"], &["som.group[0].models", "som4d"]);
    c.fails(&["run", "missing.toml"], &["missing.toml"]);
    c.fails(&["run", "unknown.toml", "--profile", "quick"], &["unknown.toml"]);
}

#[test]
fn bad_data_fails_before_any_table_is_written() {
    let c = Case::new();
    let spec = |data: &str| TINY.replace("datasets = [\"sphere\", \"cube\"]", &format!("datasets = [\"{data}\"]")).replace("save_maps = [\"6x5\"]", "");
    // A data file that is not there: the error names it and the data directory.
    c.write("bunny.toml", &spec("bunny"));
    let out = bin().args(["run", "bunny.toml", "--out", "o1", "--data-dir", "nowhere"]).current_dir(c.dir.path()).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("bun_zipper.ply") && err.contains("nowhere"), "{err}");
    assert!(!c.path("o1/appendix_b.csv").exists());
    // NaN and too few points in a user file.
    c.write("nan.xyz", "0 0 0\n1 1 1\n0.5 nan 0.5\n1 0 1\n0 1 0\n");
    c.write("nan.toml", &spec("nan.xyz"));
    c.fails(&["run", "nan.toml", "--out", "o2"], &["nan.xyz"]);
    assert!(!c.path("o2/appendix_b.csv").exists());
    c.write("few.xyz", "0 0 0\n1 1 1\n");
    c.write("few.toml", &spec("few.xyz"));
    c.fails(&["run", "few.toml", "--out", "o3"], &["few.xyz"]);
    assert!(!c.path("o3/runs.csv").exists());
}

#[test]
fn unwritable_output_folder_is_a_clear_error() {
    let c = Case::new();
    c.write("tiny.toml", TINY);
    c.write("file", "not a folder");
    c.fails(&["run", "tiny.toml", "--out", "file/out"], &["file/out"]);
}

#[test]
fn datasets_list_show_export() {
    let c = Case::new();
    let out = c.ok(&["datasets", "list"]);
    let text = String::from_utf8_lossy(&out.stdout);
    for name in ["cube", "sphere", "spindle", "oiltank", "talus", "bunny"] {
        assert!(text.contains(name), "{text}");
    }
    let out = c.ok(&["datasets", "show", "spindle"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("7552 points"));
    c.ok(&["datasets", "export", "oiltank", "oil.csv"]);
    let (h, rows) = read_csv(&c.path("oil.csv"));
    assert_eq!((h.len(), rows.len()), (3, 5942));
    c.fails(&["datasets", "show", "teapot"], &["teapot"]);
}
