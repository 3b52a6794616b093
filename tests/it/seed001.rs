//! Seed 001 end to end: the quick profile of experiments/seed001_growing_grid.toml in a temp dir,
//! then real properties of the CSVs it wrote.

use crate::common::{bin, col, data_dir, read_csv};
use std::path::Path;
use std::process::Output;

fn run(dir: &Path, args: &[&str]) -> Output {
    bin().args(args).current_dir(dir).env("SOMNURBS_DATA", data_dir()).output().unwrap()
}

fn f(s: &str) -> f64 {
    s.parse().unwrap_or_else(|_| panic!("not a number: {s:?}"))
}

fn spec() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("experiments/seed001_growing_grid.toml")
        .display()
        .to_string()
}

#[test]
fn quick_profile_writes_consistent_tables() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o =
        run(dir.path(), &["run", &spec(), "--profile", "quick", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    // Maps: both data sets grown to the quick profile's 10x10, QE/TE in range.
    let (h, maps) = read_csv(&out.join("maps.csv"));
    assert_eq!(maps.len(), 2);
    for r in &maps {
        assert_eq!((r[col(&h, "grid_x")].as_str(), r[col(&h, "grid_y")].as_str()), ("10", "10"));
        assert_eq!(r[col(&h, "insertions")], "16");
        let (qe, te) = (f(&r[col(&h, "qe")]), f(&r[col(&h, "te")]));
        assert!(qe > 0.0 && qe < 0.2, "{qe}");
        assert!((0.0..=1.0).contains(&te));
    }

    // runs.csv: 2 data x 1 net x 2 parameterisations x 3 optimisers x 2 repeats.
    let (h, runs) = read_csv(&out.join("runs.csv"));
    assert_eq!(runs.len(), 2 * 2 * 3 * 2);
    for r in &runs {
        let (lsq, init, best) =
            (f(&r[col(&h, "lsq")]), f(&r[col(&h, "initial_best")]), f(&r[col(&h, "best")]));
        assert!(best <= init && best > 0.0, "{r:?}");
        // The start is LSQ + U[-5e-6, 5e-6]: the initial best is close to the LSQ error.
        assert!((init - lsq).abs() < 1e-3 * lsq.max(1.0), "{r:?}");
        assert!((f(&r[col(&h, "best_per_point")]) - best / 100.0).abs() < 1e-12 * best);
        assert_eq!(r[col(&h, "dimension")], "108");
    }
    let keys: std::collections::BTreeSet<&String> = runs.iter().map(|r| &r[0]).collect();
    assert_eq!(keys.len(), runs.len(), "cell keys are unique");

    // avg_error.csv: min <= mean <= max; the mean is the mean of runs.csv's best.
    let (ha, avg) = read_csv(&out.join("avg_error.csv"));
    assert_eq!(avg.len(), 2 * 2 * 3);
    for a in &avg {
        let (mn, me, mx) = (
            f(&a[col(&ha, "min_best")]),
            f(&a[col(&ha, "mean_best")]),
            f(&a[col(&ha, "max_best")]),
        );
        assert!(mn <= me && me <= mx, "{a:?}");
        let bests: Vec<f64> = runs
            .iter()
            .filter(|r| {
                r[col(&h, "dataset")] == a[0]
                    && format!("{}x{}", r[col(&h, "cn_x")], r[col(&h, "cn_y")]) == a[1]
                    && r[col(&h, "parameterisation")] == a[2]
                    && r[col(&h, "optimiser")] == a[3]
            })
            .map(|r| f(&r[col(&h, "best")]))
            .collect();
        assert_eq!(bests.len(), 2);
        assert!((bests.iter().sum::<f64>() / 2.0 - me).abs() <= 1e-12 * me);
    }
    let (_, fit) = read_csv(&out.join("fit_error.csv"));
    assert_eq!(fit.len(), 4);
    let (_, summary) = read_csv(&out.join("optimiser_summary.csv"));
    assert_eq!(summary.len(), 3);
    assert!(
        out.join("png/seed001_saddle.png").exists()
            && out.join("png/seed001_semi_sphere.png").exists()
    );
    assert!(std::fs::read_to_string(out.join("REPORT.md"))
        .unwrap()
        .contains("Average error per optimiser"));

    // Determinism: a second run gives the same rows (timing aside).
    let out2 = dir.path().join("out2");
    let o = run(
        dir.path(),
        &["run", &spec(), "--profile", "quick", "--out", out2.to_str().unwrap(), "--jobs", "1"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, runs2) = read_csv(&out2.join("runs.csv"));
    let strip =
        |rows: &[Vec<String>]| rows.iter().map(|r| r[..r.len() - 1].to_vec()).collect::<Vec<_>>();
    assert_eq!(strip(&runs), strip(&runs2));
}

#[test]
fn bad_key_is_named_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(spec()).unwrap().replace("repeats = 10", "repeats = 0");
    let path = dir.path().join("bad.toml");
    std::fs::write(&path, text).unwrap();
    let o = run(
        dir.path(),
        &["run", path.to_str().unwrap(), "--out", dir.path().join("o").to_str().unwrap()],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("growing_grid.repeats: must be at least 1"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
}

/// `somnurbs report` makes every file of a finished quick run again, byte for byte, from the
/// cell log alone (no cell computed again).
#[test]
fn seed001_report_restores_every_file_from_the_log() {
    crate::common::report_restores_every_file("experiments/seed001_growing_grid.toml");
}
