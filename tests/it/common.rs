//! Helpers shared by the integration tests: run the real binary in a temporary folder, print the
//! command, folder listing, stdout and stderr on failure, and read the CSVs it writes.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_somnurbs"))
}

/// The data folder the tests give the binary: where a user's main job finds the data when run
/// from the top of this clone (`SOMNURBS_DATA` if set, else `<clone>/data`; one rule,
/// `somnurbs::data::clone_data_dir`).
pub fn data_dir() -> PathBuf {
    somnurbs::data::clone_data_dir()
}

pub struct Case {
    pub dir: tempfile::TempDir,
}

impl Case {
    pub fn new() -> Case {
        Case { dir: tempfile::tempdir().unwrap() }
    }
    pub fn path(&self, p: &str) -> PathBuf {
        self.dir.path().join(p)
    }
    pub fn write(&self, p: &str, text: &str) -> PathBuf {
        let path = self.path(p);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, text).unwrap();
        path
    }
    pub fn run(&self, args: &[&str]) -> Output {
        let out = bin()
            .args(args)
            .current_dir(self.dir.path())
            .env("SOMNURBS_DATA", data_dir())
            .output()
            .unwrap();
        out
    }
    /// Runs the binary with the working folder `sub` of the case folder (made if missing).
    pub fn run_from(&self, sub: &str, args: &[&str]) -> Output {
        let dir = self.path(sub);
        std::fs::create_dir_all(&dir).unwrap();
        bin().args(args).current_dir(dir).env("SOMNURBS_DATA", data_dir()).output().unwrap()
    }
    /// [`Case::run_from`] that must succeed.
    pub fn ok_from(&self, sub: &str, args: &[&str]) -> Output {
        let out = self.run_from(sub, args);
        assert!(out.status.success(), "in {sub}: {}", self.explain(args, &out));
        out
    }
    pub fn explain(&self, args: &[&str], out: &Output) -> String {
        let listing: Vec<String> = walk(self.dir.path())
            .iter()
            .map(|p| p.strip_prefix(self.dir.path()).unwrap().display().to_string())
            .collect();
        format!(
            "command: somnurbs {}\nfolder: {:?}\nstatus: {}\nstdout:\n{}\nstderr:\n{}",
            args.join(" "),
            listing,
            out.status,
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        )
    }
    pub fn ok(&self, args: &[&str]) -> Output {
        let out = self.run(args);
        assert!(out.status.success(), "{}", self.explain(args, &out));
        out
    }
    /// Runs a command that must fail with a one-line error containing every `needle`.
    pub fn fails(&self, args: &[&str], needles: &[&str]) -> String {
        let out = self.run(args);
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(!out.status.success(), "expected failure\n{}", self.explain(args, &out));
        assert_eq!(
            err.trim_end().lines().count(),
            1,
            "error is not one line\n{}",
            self.explain(args, &out)
        );
        for n in needles {
            assert!(err.contains(n), "error lacks {n:?}\n{}", self.explain(args, &out));
        }
        err
    }
}

pub fn walk(dir: &Path) -> Vec<PathBuf> {
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

pub fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let h = r.headers().unwrap().iter().map(String::from).collect();
    let rows = r.records().map(|x| x.unwrap().iter().map(String::from).collect()).collect();
    (h, rows)
}

/// A CSV with the timing columns blanked, for comparisons across runs.
pub fn without_timing(path: &Path) -> Vec<Vec<String>> {
    let (h, rows) = read_csv(path);
    rows.into_iter()
        .map(|r| {
            r.into_iter()
                .zip(&h)
                .map(|(v, c)| if is_timing(c) { String::new() } else { v })
                .collect()
        })
        .collect()
}

/// The index of a column, or a panic naming it and the header.
pub fn col(h: &[String], name: &str) -> usize {
    h.iter().position(|c| c == name).unwrap_or_else(|| panic!("no column {name} in {h:?}"))
}

/// Timing columns: measured, never identical across runs.
pub fn is_timing(column: &str) -> bool {
    column.starts_with("cpu_s") || column.ends_with("_s") || column == "wall_seconds"
}

/// Every CSV under `a` equals the one at the same place under `b` apart from timing columns
/// (and `b` has no CSV that `a` lacks); returns how many tables were compared.
pub fn same_tables(a: &Path, b: &Path) -> usize {
    let csvs = |d: &Path| -> Vec<PathBuf> {
        walk(d)
            .into_iter()
            .filter(|p| p.extension().is_some_and(|e| e == "csv"))
            .map(|p| p.strip_prefix(d).unwrap().to_path_buf())
            .collect()
    };
    let (ta, tb) = (csvs(a), csvs(b));
    assert_eq!(ta, tb, "different tables in {} and {}", a.display(), b.display());
    for t in &ta {
        assert_eq!(read_csv(&a.join(t)).0, read_csv(&b.join(t)).0, "{}: header", t.display());
        assert_eq!(without_timing(&a.join(t)), without_timing(&b.join(t)), "{}", t.display());
    }
    ta.len()
}

/// A small Chapter 6 spec (a second or two).
pub const SPEC: &str = r#"
name = "d"
master_seed = 3
[optimise]
datasets = ["sphere"]
grid = "20x20"
control_nets = ["6x6"]
parameterisations = ["chord_length"]
optimisers = ["ga", "de"]
repeats = 2
generations = 20
population = 8
[optimise.som]
iterations = 300
"#;

/// A Chapter 6 spec of several seconds on one thread: long enough to be killed or raced part-way.
pub const SLOW: &str = r#"
name = "slow"
master_seed = 11
[optimise]
datasets = ["sphere"]
grid = "20x20"
control_nets = ["10x10", "12x12"]
parameterisations = ["chord_length"]
optimisers = ["ga", "de", "pso"]
repeats = 12
generations = 600
population = 20
[optimise.som]
iterations = 500
"#;

/// A Chapter 4 spec that saves one small DNSOM map (sphere, 20x20) for Chapter 5 and 6 tests.
pub const CH4_FOR_FIT: &str = r#"
name = "maps"
master_seed = 11
[som]
datasets = ["sphere"]
iterations = 500
save_maps = ["20x20"]
pictures = false
[[som.group]]
models = ["dnsom"]
grids = ["20x20"]
"#;

/// A SOM spec of a fraction of a second on the data set `DATA` (replace it).
pub const SOM_TINY: &str = r#"
name = "s"
master_seed = 5
[som]
datasets = ["DATA"]
iterations = 200
[[som.group]]
models = ["dnsom"]
grids = ["6x5"]
"#;

/// Every file under `dir` with its bytes (the lock file aside: its record is rewritten by every
/// writer that takes it, refused or not, and is empty once released).
pub fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    walk(dir)
        .into_iter()
        .filter(|p| p.file_name().is_some_and(|n| n != ".somnurbs.lock"))
        .map(|p| (p.strip_prefix(dir).unwrap().display().to_string(), std::fs::read(&p).unwrap()))
        .collect()
}

/// Run `spec` (a path under the clone, e.g. `experiments/seed001_growing_grid.toml`) under the
/// quick profile, delete every file of the folder but its cell log, fingerprint and manifest, run
/// `somnurbs report` on it and check every file came back byte for byte (the cell records hold
/// everything the tables, pictures, REPORT.md and report.html are made of, CPU times included).
pub fn report_restores_every_file(spec: &str) {
    let c = Case::new();
    let spec = Path::new(env!("CARGO_MANIFEST_DIR")).join(spec);
    c.ok(&["run", spec.to_str().unwrap(), "--profile", "quick", "--out", "o"]);
    report_restores_folder(&c, "o");
}

/// Delete every file of the finished folder `dir` (under `c`) but its cell log, fingerprint and
/// manifest, run `somnurbs report` on it, and check every file came back byte for byte.
pub fn report_restores_folder(c: &Case, dir: &str) {
    let before = snapshot(&c.path(dir));
    let kept = ["cells.jsonl", "cells.jsonl.gz", "fingerprint.toml", "manifest.toml"];
    let mut deleted = 0;
    for p in walk(&c.path(dir)) {
        let name = p.file_name().unwrap().to_str().unwrap();
        if !kept.contains(&name) && name != ".somnurbs.lock" {
            std::fs::remove_file(&p).unwrap();
            deleted += 1;
        }
    }
    assert!(deleted > 0, "the run wrote no table to delete");
    c.ok(&["report", dir]);
    let after = snapshot(&c.path(dir));
    let names = |s: &[(String, Vec<u8>)]| s.iter().map(|(f, _)| f.clone()).collect::<Vec<_>>();
    assert_eq!(names(&after), names(&before), "{dir}: report did not make the same files");
    for ((f, a), (_, b)) in after.iter().zip(&before) {
        assert!(a == b, "{dir}/{f} differs after somnurbs report");
    }
}

/// A saved map's text: the CSV at `path`, or its gzip-compressed copy `path.gz` (the copy a
/// folder that reads a map keeps).
pub fn map_text(path: &Path) -> String {
    if path.is_file() {
        return std::fs::read_to_string(path).unwrap();
    }
    let gz = path.with_file_name(format!("{}.gz", path.file_name().unwrap().to_str().unwrap()));
    let mut text = String::new();
    use std::io::Read;
    flate2::read::GzDecoder::new(std::fs::File::open(&gz).unwrap())
        .read_to_string(&mut text)
        .unwrap_or_else(|e| panic!("{}: {e}", gz.display()));
    text
}
