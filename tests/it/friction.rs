//! A researcher's own scan, start to finish (issue 49, items 4-6): what `--dry-run` checks,
//! SIGINT, the folders `compare` and `drift` take, the spellings of `fit`'s values, and the IGES
//! and manifest a `fit` folder holds.

use crate::common::*;

/// 100 points on a wavy patch, in XYZ.
fn hundred_points() -> String {
    (0..100)
        .map(|k| {
            let (u, v) = ((k % 10) as f64 / 9.0, (k / 10) as f64 / 9.0);
            format!("{u} {v} {}\n", 0.1 * (3.0 * u).sin() * (2.0 * v).cos())
        })
        .collect()
}

#[test]
fn dry_run_makes_the_checks_of_a_run() {
    let c = Case::new();
    let som = "name = \"s\"\nmaster_seed = 1\n[som]\ndatasets = [\"DATA\"]\niterations = 50\n[[som.group]]\nmodels = [\"dnsom\"]\ngrids = [\"20x20\"]\n";
    c.write("missing.toml", &som.replace("DATA", "nothere.xyz"));
    c.write("pts.xyz", &hundred_points());
    c.write("small.toml", &som.replace("DATA", "pts.xyz"));
    for args in [&["run", "missing.toml", "--out", "m"][..], &["run", "missing.toml", "--dry-run"]]
    {
        c.fails(args, &["nothere.xyz"]);
    }
    let needles = ["pts.xyz", "100 points", "fewer than the 800 neurons of the dnsom 20x20"];
    for args in [&["run", "small.toml", "--out", "s"][..], &["run", "small.toml", "--dry-run"]] {
        let out = c.run(args);
        assert_eq!(out.status.code(), Some(2), "{}", c.explain(args, &out));
        c.fails(args, &needles);
    }
    // Chapter 6 recomputing its maps from the same file: checked by the dry run too.
    let opt = SPEC.replace("\"sphere\"", "\"pts.xyz\"");
    c.write("o.toml", &opt);
    c.fails(&["run", "o.toml", "--dry-run"], &["pts.xyz", "fewer than the", "neurons"]);
    assert!(!c.path("m").exists() && !c.path("s").exists() && !c.path("results").exists());
    // A spec that passes every check is listed.
    c.write("ok.toml", &som.replace("DATA", "pts.xyz").replace("20x20", "5x5"));
    let listed = String::from_utf8(c.ok(&["run", "ok.toml", "--dry-run"]).stdout).unwrap();
    assert_eq!(listed.lines().count(), 1, "{listed}");
}
