//! Seed 003 integration test: the quick profile of experiments/seed003_cuckoo_bezier.toml through
//! the real binary, the CSVs read back and checked; thread count does not change a number; a bad
//! key is refused by name; --dry-run lists the cells.

use crate::common::{col, read_csv, same_tables, Case};
use std::path::{Path, PathBuf};

fn spec() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/seed003_cuckoo_bezier.toml")
}

fn header(path: &Path) -> Vec<String> {
    read_csv(path).0
}

#[test]
fn seed003_quick_profile_writes_the_papers_tables() {
    let case = Case::new();
    let spec = spec();
    let out2 = case.path("j2");
    case.ok(&[
        "run",
        spec.to_str().unwrap(),
        "--profile",
        "quick",
        "--out",
        out2.to_str().unwrap(),
        "--jobs",
        "2",
    ]);
    for f in [
        "REPORT.md",
        "manifest.toml",
        "runs.csv",
        "seed003_table3.csv",
        "seed003_table4.csv",
        "seed003_table5.csv",
        "seed003_agreement.csv",
        "seed003_traces.csv",
    ] {
        assert!(out2.join(f).is_file(), "{f} missing");
    }
    for e in ["example1", "example2", "example3"] {
        assert!(
            out2.join(format!("png/seed003_convergence_{e}.png")).is_file(),
            "{e} picture missing"
        );
    }
    // runs.csv: 3 examples x 5 methods x 4 runs; RMSE = sqrt(Y / n); CSA/ICSA never end above
    // their start population's best; the classical methods are one evaluation.
    let (h, rows) = read_csv(&out2.join("runs.csv"));
    assert_eq!(rows.len(), 3 * 5 * 4);
    let (y, rmse, n, init, method, evals) = (
        col(&h, "y"),
        col(&h, "rmse"),
        col(&h, "n_points"),
        col(&h, "initial_best_y"),
        col(&h, "method"),
        col(&h, "evaluations"),
    );
    let iters = col(&h, "iterations");
    for c in ["cell", "example", "run", "seed", "data_seed", "cpu_s", "dimension", "noise_sigma"] {
        col(&h, c);
    }
    for r in &rows {
        let f = |i: usize| r[i].parse::<f64>().unwrap();
        assert!(f(y) > 0.0 && f(y) <= f(init), "{r:?}");
        assert!((f(rmse) - (f(y) / f(n)).sqrt()).abs() <= 1e-12 * f(rmse), "{r:?}");
        if ["csa", "icsa"].contains(&r[method].as_str()) {
            // 10 nests: 10 (1 + 2 G) evaluations.
            assert_eq!(f(evals), 10.0 * (1.0 + 2.0 * f(iters)), "{r:?}");
        } else {
            assert_eq!(r[evals], "1");
            assert_eq!(r[y], r[init]);
        }
    }
    // The paper's layouts.
    assert_eq!(
        header(&out2.join("seed003_table3.csv")),
        ["statistic", "example1", "example2", "example3"]
    );
    let (_, t3) = read_csv(&out2.join("seed003_table3.csv"));
    assert_eq!(
        t3.iter().map(|r| r[0].as_str()).collect::<Vec<_>>(),
        ["y_mean", "y_best", "y_var", "y_std", "rmse_mean", "rmse_best"]
    );
    assert_eq!(
        header(&out2.join("seed003_table4.csv")),
        ["example", "statistic", "uniform", "chordal", "centripetal", "csa", "icsa"]
    );
    let (_, t4) = read_csv(&out2.join("seed003_table4.csv"));
    assert_eq!(t4.len(), 3 * 10);
    for r in t4.iter().filter(|r| r[1].starts_with("er_")) {
        // The best method of an error-rate row is blank, the others are above 100 %.
        assert_eq!(r[2..].iter().filter(|v| v.is_empty()).count(), 1, "{r:?}");
        assert!(
            r[2..].iter().filter(|v| !v.is_empty()).all(|v| v.parse::<f64>().unwrap() >= 100.0),
            "{r:?}"
        );
    }
    assert_eq!(
        header(&out2.join("seed003_table5.csv")),
        ["comparison", "index", "example1", "example2", "example3"]
    );
    let (_, t5) = read_csv(&out2.join("seed003_table5.csv"));
    assert_eq!(t5.len(), 4 * 6);
    for r in &t5 {
        for v in &r[2..] {
            let v: f64 = v.parse().unwrap();
            match r[1].as_str() {
                "p_sign" | "p_sum" => assert!((0.0..=1.0).contains(&v), "{r:?}"),
                "h_sign" | "h_sum" => assert!(v == 0.0 || v == 1.0, "{r:?}"),
                "signed_rank" => assert!((0.0..=10.0).contains(&v), "4 pairs: W+ in 0..=10, {r:?}"),
                _ => {
                    assert!((10.0..=26.0).contains(&v), "4 + 4 values: rank sum in 10..=26, {r:?}")
                }
            }
        }
    }
    let (h, agree) = read_csv(&out2.join("seed003_agreement.csv"));
    assert_eq!(agree.len(), 12);
    let d = col(&h, "direction_agrees");
    let (g, all) = (col(&h, "significance_agrees"), col(&h, "agrees"));
    assert!(agree.iter().all(|r| r[d] == "yes" || r[d] == "no"));
    assert!(agree.iter().all(|r| (r[all] == "yes") == (r[d] == "yes" && r[g] == "yes")));
    let report = std::fs::read_to_string(out2.join("REPORT.md")).unwrap();
    assert!(report.contains("### Table 5") && report.contains("Direction agrees in"), "{report}");

    // One thread: the same numbers.
    let out1 = case.path("j1");
    case.ok(&[
        "run",
        spec.to_str().unwrap(),
        "--profile",
        "quick",
        "--out",
        out1.to_str().unwrap(),
        "--jobs",
        "1",
    ]);
    assert_eq!(same_tables(&out1, &out2), 7);
}

#[test]
fn seed003_bad_keys_are_named() {
    let case = Case::new();
    let text = std::fs::read_to_string(spec()).unwrap();
    let out = case.path("o");
    for (from, to, needles) in [
        ("\nnests = 100", "\nnests = 100\nnestz = 3", &["nestz"][..]),
        ("\nruns = 50", "\nruns = 0", &["cuckoo_bezier.runs"][..]),
        (
            "snr_db = 12.5\ngenerations = 2000",
            "snr_db = 12.5\ngenerations = 0",
            &["cuckoo_bezier.example2.generations"][..],
        ),
        ("\npa = 0.25", "\npa = 1.5", &["cuckoo_bezier.csa.pa"][..]),
        ("\"icsa\"]", "\"icsa\", \"pso\"]", &["cuckoo_bezier.methods", "pso"][..]),
    ] {
        assert!(text.contains(from), "{from}");
        let p = case.write("bad.toml", &text.replacen(from, to, 1));
        case.fails(&["run", p.to_str().unwrap(), "--out", out.to_str().unwrap()], needles);
    }
}

#[test]
fn seed003_dry_run_lists_every_cell() {
    let case = Case::new();
    let spec = spec();
    let o = case.ok(&["run", spec.to_str().unwrap(), "--dry-run"]);
    let text = String::from_utf8_lossy(&o.stdout);
    let keys: Vec<&str> = text.lines().filter(|l| l.starts_with("seed003/")).collect();
    assert_eq!(keys.len(), 3 * 5 * 50, "{text}");
    assert!(keys.iter().any(|l| l.starts_with("seed003/example2/icsa/r49")));
}

/// `somnurbs report` makes every file of a finished quick run again, byte for byte, from the
/// cell log alone (no cell computed again).
#[test]
fn seed003_report_restores_every_file_from_the_log() {
    crate::common::report_restores_every_file("experiments/seed003_cuckoo_bezier.toml");
}
