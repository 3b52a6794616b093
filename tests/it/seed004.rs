//! Seed 004 integration test: the quick profile of experiments/seed004_cylinder.toml through the
//! real binary, then the tables it wrote are read back and checked.

use crate::common::{col, read_csv, same_tables, Case};
use std::path::{Path, PathBuf};

fn spec() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/seed004_cylinder.toml")
}

fn quick(case: &Case, out: &str, jobs: &str) -> PathBuf {
    let spec = spec();
    let out = case.path(out);
    case.ok(&[
        "run",
        spec.to_str().unwrap(),
        "--profile",
        "quick",
        "--out",
        out.to_str().unwrap(),
        "--jobs",
        jobs,
    ]);
    out
}

#[test]
fn seed004_quick_profile_writes_the_papers_tables() {
    let case = Case::new();
    let out = quick(&case, "res2", "2");
    for f in [
        "REPORT.md",
        "manifest.toml",
        "runs.csv",
        "seed004_table2.csv",
        "seed004_table3.csv",
        "seed004_analytical.csv",
        "claims.csv",
        "png/seed004_convergence.png",
        "png/seed004_fitness_vs_control_points.png",
        "png/seed004_top_view.png",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    // runs.csv: 3 numbers of control points x 2 repeats, 3876 points, 2N variables of 10 bits;
    // the GA's best is never worse than its initial best; the analytical RMS is the same per N.
    let (h, rows) = read_csv(&out.join("runs.csv"));
    assert_eq!(rows.len(), 3 * 2);
    let (cp, n, dim, bits, an, init, best, evals, gen) = (
        col(&h, "control_points"),
        col(&h, "n_points"),
        col(&h, "dimension"),
        col(&h, "string_length"),
        col(&h, "analytical_rms"),
        col(&h, "initial_best_rms"),
        col(&h, "best_rms"),
        col(&h, "evaluations"),
        col(&h, "best_generation"),
    );
    for r in &rows {
        let f = |i: usize| r[i].parse::<f64>().unwrap();
        let c: usize = r[cp].parse().unwrap();
        assert_eq!(r[n], "3876");
        assert_eq!(r[dim], (2 * c).to_string());
        assert_eq!(r[bits], (20 * c).to_string(), "Table I: 10 x 2 x control points");
        assert_eq!(r[evals], (10 * 41).to_string());
        assert!(f(best) <= f(init), "{r:?}");
        assert!(f(an) > 0.0 && f(best) > 0.0 && r[gen].parse::<usize>().unwrap() <= 40);
    }
    // Table II: expected columns; per (cp, generation) best <= mean; best so far never rises.
    let (h, rows) = read_csv(&out.join("seed004_table2.csv"));
    assert_eq!(
        h,
        [
            "control_points",
            "generation",
            "analytical_rms",
            "ga_best_rms",
            "ga_mean_rms",
            "ga_median_rms",
            "ga_population_best_rms",
            "ga_population_mean_rms",
            "runs"
        ]
    );
    assert_eq!(rows.len(), 2 * 4, "5 and 7 control points x generations 0, 10, 25, 40");
    let (b, m) = (col(&h, "ga_best_rms"), col(&h, "ga_mean_rms"));
    for r in &rows {
        assert!(
            r[b].parse::<f64>().unwrap() <= r[m].parse::<f64>().unwrap() * (1.0 + 1e-12),
            "{r:?}"
        );
    }
    for pair in rows.windows(2) {
        if pair[0][0] == pair[1][0] {
            assert!(pair[1][b].parse::<f64>().unwrap() <= pair[0][b].parse::<f64>().unwrap());
        }
    }
    // Table III: one row per number of control points, analytical error falls with N.
    let (h, rows) = read_csv(&out.join("seed004_table3.csv"));
    assert_eq!(
        h,
        [
            "control_points",
            "analytical_rms",
            "ga_best_rms",
            "ga_mean_rms",
            "ga_worst_rms",
            "ga_std_rms",
            "best_generation",
            "mean_best_generation",
            "improvement_pct",
            "runs"
        ]
    );
    assert_eq!(rows.iter().map(|r| r[0].as_str()).collect::<Vec<_>>(), ["5", "7", "10"]);
    let an: Vec<f64> = rows.iter().map(|r| r[1].parse().unwrap()).collect();
    assert!(an[0] > an[1] && an[1] > an[2], "{an:?}");
    let report = std::fs::read_to_string(out.join("REPORT.md")).unwrap();
    assert!(
        report.contains("Seed 004") && report.contains("0.0790") && report.contains("0.00470"),
        "paper's numbers beside ours"
    );
    // One thread: identical numbers.
    let out1 = quick(&case, "res1", "1");
    assert!(same_tables(&out, &out1) >= 5);
}

#[test]
fn seed004_dry_run_lists_cells_and_bad_keys_are_named() {
    let case = Case::new();
    let spec = spec();
    let o = case.ok(&["run", spec.to_str().unwrap(), "--dry-run"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert_eq!(text.lines().filter(|l| l.contains("seed004/cp")).count(), 12 * 10, "{text}");
    assert!(text.contains("seed004/cp25/r9"));
    let bad = std::fs::read_to_string(&spec)
        .unwrap()
        .replace("search_range = 0.25", "search_range = 0.25\nsearch_rang = 1.0");
    let p = case.write("bad.toml", &bad);
    case.fails(&["run", p.to_str().unwrap(), "--out", "o"], &["search_rang"]);
    let bad = std::fs::read_to_string(&spec)
        .unwrap()
        .replace("table2_control_points = [5, 7]", "table2_control_points = [5, 11]");
    let p = case.write("bad2.toml", &bad);
    case.fails(
        &["run", p.to_str().unwrap(), "--out", "o"],
        &["closed_cylinder.table2_control_points", "11"],
    );
    let bad = std::fs::read_to_string(&spec).unwrap().replace("beta = 2.0", "beta = 3.0");
    let p = case.write("bad3.toml", &bad);
    case.fails(&["run", p.to_str().unwrap(), "--out", "o"], &["closed_cylinder.ga.beta"]);
}

/// `somnurbs report` makes every file of a finished quick run again, byte for byte, from the
/// cell log alone (no cell computed again).
#[test]
fn seed004_report_restores_every_file_from_the_log() {
    crate::common::report_restores_every_file("experiments/seed004_cylinder.toml");
}
