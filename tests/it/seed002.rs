//! Seed 002 integration test: the quick profile of experiments/seed002_rational.toml through the
//! real binary, then the CSVs it wrote are read back and checked.

use crate::common::{col, read_csv};
use std::path::{Path, PathBuf};
use std::process::Command;

fn spec() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/seed002_rational.toml")
}

fn run(out: &Path, extra: &[&str]) -> std::process::Output {
    let spec = spec();
    let mut args =
        vec!["run", spec.to_str().unwrap(), "--profile", "quick", "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    Command::new(env!("CARGO_BIN_EXE_somnurbs")).args(&args).output().unwrap()
}

#[test]
fn seed002_quick_profile_writes_consistent_tables() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("res");
    let o = run(&out, &["-j", "2"]);
    assert!(o.status.success(), "stderr: {}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "REPORT.md",
        "manifest.toml",
        "runs.csv",
        "seed002_errors.csv",
        "seed002_traces.csv",
        "png/seed002_convergence_surface1.png",
        "png/seed002_convergence_surface4.png",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    // runs.csv: 4 surfaces x 3 optimisers x 2 repeats; RMSE = sqrt(SSE / n); the best of a run is
    // no worse than its initial population's best.
    let (h, rows) = read_csv(&out.join("runs.csv"));
    assert_eq!(rows.len(), 4 * 3 * 2);
    let (sse, rmse, n, init, w11, dim) = (
        col(&h, "best_sse"),
        col(&h, "rmse"),
        col(&h, "n_points"),
        col(&h, "initial_best"),
        col(&h, "w11"),
        col(&h, "dimension"),
    );
    for r in &rows {
        let f = |i: usize| r[i].parse::<f64>().unwrap();
        assert_eq!(r[n], "81", "quick grid is 9x9");
        assert_eq!(r[dim], "22");
        assert!(f(sse) >= 0.0 && f(sse) <= f(init), "{r:?}");
        assert!((f(rmse) - (f(sse) / f(n)).sqrt()).abs() <= 1e-12 * f(rmse).max(1.0), "{r:?}");
        assert!(f(w11) > 0.0 && f(w11) < 2.0, "{r:?}");
    }
    // Error table: best <= mean <= worst per (surface, optimiser), 12 rows of 2 runs.
    let (h, rows) = read_csv(&out.join("seed002_errors.csv"));
    assert_eq!(rows.len(), 12);
    let (b, m, w, runs) =
        (col(&h, "best_sse"), col(&h, "mean_sse"), col(&h, "worst_sse"), col(&h, "runs"));
    for r in &rows {
        let f = |i: usize| r[i].parse::<f64>().unwrap();
        assert_eq!(r[runs], "2");
        assert!(f(b) <= f(m) * (1.0 + 1e-12) && f(m) <= f(w) * (1.0 + 1e-12), "{r:?}");
    }
    // Traces never increase within a run (best so far).
    let (h, rows) = read_csv(&out.join("seed002_traces.csv"));
    let (c, v) = (col(&h, "cell"), col(&h, "best_sse"));
    for pair in rows.windows(2) {
        if pair[0][c] == pair[1][c] {
            assert!(pair[1][v].parse::<f64>().unwrap() <= pair[0][v].parse::<f64>().unwrap());
        }
    }
    // Curves: SAM06 finds every generated corner; conics = 2 per corner; best <= mean.
    let (h, rows) = read_csv(&out.join("seed002_curve_runs.csv"));
    assert_eq!(rows.len(), 3 * 3 * 2);
    let (t, f, m, c, sse) = (
        col(&h, "true_corners"),
        col(&h, "corners_found"),
        col(&h, "corners_matched"),
        col(&h, "conics"),
        col(&h, "sse"),
    );
    for r in &rows {
        assert_eq!(r[t], r[f], "{r:?}");
        assert_eq!(r[t], r[m], "{r:?}");
        assert_eq!(r[c].parse::<usize>().unwrap(), 2 * r[t].parse::<usize>().unwrap());
        assert!(r[sse].parse::<f64>().unwrap() >= 0.0);
    }
    let (h, rows) = read_csv(&out.join("seed002_curves.csv"));
    assert_eq!(rows.len(), 9);
    let (b, mn) = (col(&h, "best_sse"), col(&h, "mean_sse"));
    for r in &rows {
        assert!(
            r[b].parse::<f64>().unwrap() <= r[mn].parse::<f64>().unwrap() * (1.0 + 1e-12),
            "{r:?}"
        );
    }
    for f in [
        "png/seed002_outline_square.png",
        "png/seed002_outline_letter_d.png",
        "png/seed002_outline_letter_p.png",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    // Same seeds, one thread: identical runs (timing aside).
    let out1 = dir.path().join("res1");
    let o = run(&out1, &["-j", "1"]);
    assert!(o.status.success());
    let strip = |p: &Path| {
        let (h, rows) = read_csv(p);
        let cpu = col(&h, "cpu_s");
        rows.into_iter()
            .map(|mut r| {
                r[cpu].clear();
                r
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(strip(&out.join("runs.csv")), strip(&out1.join("runs.csv")));
    assert_eq!(
        strip(&out.join("seed002_curve_runs.csv")),
        strip(&out1.join("seed002_curve_runs.csv"))
    );
}

#[test]
fn seed002_bad_key_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(spec()).unwrap().replace("grid = 21", "grid = 20");
    let p = dir.path().join("bad.toml");
    std::fs::write(&p, text).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_somnurbs"))
        .args(["run", p.to_str().unwrap(), "--out", dir.path().join("o").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("rational_bezier.grid") && err.contains("odd"), "{err}");
}

/// `somnurbs report` makes every file of a finished quick run again, byte for byte, from the
/// cell log alone (no cell computed again).
#[test]
fn seed002_report_restores_every_file_from_the_log() {
    crate::common::report_restores_every_file("experiments/seed002_rational.toml");
}
