//! `somnurbs drift` on folders written by real runs: exit 0 / 1 / 2, the moved cell named, and
//! `--accept`.

use crate::common::*;

fn status(out: &std::process::Output) -> i32 {
    out.status.code().unwrap_or(-1)
}

#[test]
fn drift_names_moved_cells_and_refuses_bad_input() {
    let c = Case::new();
    c.write("d.toml", SPEC);
    c.ok(&["run", "d.toml", "--out", "a", "--jobs", "1"]);
    c.ok(&["run", "d.toml", "--out", "b", "--jobs", "2"]);
    let out = c.ok(&["drift", "a", "b"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("no drift"));
    assert!(c.path("drift.csv").exists());
    // Baseline on purpose.
    c.ok(&["drift", "--accept", "base", "a"]);
    assert!(c.path("base/appendix_k.csv").exists() && c.path("base/manifest.toml").exists());
    // Move one number of the current run.
    let k = std::fs::read_to_string(c.path("b/appendix_k.csv")).unwrap();
    let row = k.lines().nth(1).unwrap();
    let cols: Vec<&str> = row.split(',').collect();
    let de_avg =
        read_csv(&c.path("b/appendix_k.csv")).0.iter().position(|h| h == "de_avg").unwrap();
    let moved: Vec<String> = cols
        .iter()
        .enumerate()
        .map(|(i, v)| {
            if i == de_avg {
                format!("{}", v.parse::<f64>().unwrap() + 1e-3)
            } else {
                v.to_string()
            }
        })
        .collect();
    std::fs::write(c.path("b/appendix_k.csv"), k.replacen(row, &moved.join(","), 1)).unwrap();
    let out = c.run(&["drift", "base", "b"]);
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    assert_eq!(status(&out), 1, "{}", c.explain(&["drift", "base", "b"], &out));
    assert!(
        text.contains("DRIFT in 1 places")
            && text.contains("appendix_k.csv:sphere/chord_length/6/6:de_avg"),
        "{text}"
    );
    let (h, rows) = read_csv(&c.path("drift.csv"));
    let drifted = h.iter().position(|x| x == "drifted").unwrap();
    assert_eq!(rows.iter().filter(|r| r[drifted] == "yes").count(), 1);
    // A loose tolerance for that column hides it.
    c.ok(&["drift", "base", "b", "--tol", "de_*=0.01"]);
    // Bad input: exit 2 with one line naming the place.
    c.fails(&["drift", "base", "nowhere"], &["nowhere", "not a folder"]);
    std::fs::write(
        c.path("b/table_6_4.csv"),
        "data,parameterisation,ga,de,cells\nsphere,chord_length,1\n",
    )
    .unwrap();
    let err = c.fails(&["drift", "base", "b"], &["table_6_4.csv", "line 2"]);
    assert!(err.contains("malformed"), "{err}");
    c.write("other.toml", &SPEC.replace("master_seed = 3", "master_seed = 4"));
    c.ok(&["run", "other.toml", "--out", "o"]);
    c.fails(&["drift", "base", "o"], &["master seed 3 vs 4", "--allow-spec-change"]);
    let out = c.run(&["drift", "base", "o", "--allow-spec-change"]);
    assert_eq!(status(&out), 1, "another seed moves the numbers");
    // A missing table is drift.
    std::fs::remove_file(c.path("o/appendix_m.csv")).unwrap();
    let out = c.run(&["drift", "base", "o", "--allow-spec-change"]);
    assert!(String::from_utf8_lossy(&out.stdout)
        .contains("appendix_m.csv: missing in the current folder"));
    // Accepting the current tables makes the next check pass.
    c.ok(&["drift", "--accept", "base", "a"]);
    c.ok(&["run", "d.toml", "--out", "again"]);
    c.ok(&["drift", "base", "again"]);
}
