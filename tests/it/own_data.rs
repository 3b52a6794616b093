//! Own data: a spec's relative data-set paths are read from the spec's folder (so it runs from
//! anywhere), its results are named by the file's stem, `normalise` chooses the scaling, and a
//! missing file is refused before anything is written.

use crate::common::*;

/// Points on an ellipsoid with semi-axes 40, 25 and 15.
fn ellipsoid() -> String {
    let mut s = String::new();
    for i in 0..40 {
        let t = std::f64::consts::PI * (i as f64 + 0.5) / 40.0;
        for j in 0..50 {
            let p = 2.0 * std::f64::consts::PI * j as f64 / 50.0;
            s.push_str(&format!(
                "{} {} {}\n",
                40.0 * t.sin() * p.cos(),
                25.0 * t.sin() * p.sin(),
                15.0 * t.cos()
            ));
        }
    }
    s
}

const OWN: &str = "name = \"own\"\nmaster_seed = 5\nNORMALISE\n[som]\ndatasets = [\"mydata/ellipsoid.xyz\"]\niterations = 2000\nsave_maps = [\"10x10\"]\n[[som.group]]\nmodels = [\"dnsom\"]\ngrids = [\"10x10\"]\n";

/// Extents (x, y, z) of a saved two-view map.
fn map_extents(c: &Case, path: &str) -> [f64; 3] {
    let (h, rows) = read_csv(&c.path(path));
    let mut ext = [0.0; 3];
    for (a, name) in ["x", "y", "z"].iter().enumerate() {
        let k = col(&h, name);
        let v: Vec<f64> = rows.iter().map(|r| r[k].parse().unwrap()).collect();
        ext[a] =
            v.iter().cloned().fold(f64::MIN, f64::max) - v.iter().cloned().fold(f64::MAX, f64::min);
    }
    ext
}

#[test]
fn a_spec_in_another_folder_reads_its_data_from_there_and_uniform_keeps_proportions() {
    let c = Case::new();
    c.write("specs/mydata/ellipsoid.xyz", &ellipsoid());
    c.write("specs/uniform.toml", &OWN.replace("NORMALISE", "normalise = \"uniform\""));
    c.write("specs/default.toml", &OWN.replace("NORMALISE", ""));
    // Run from the case folder: the data path is relative to specs/, not to the working folder.
    c.ok(&["run", "specs/uniform.toml", "--out", "u"]);
    c.ok(&["run", "specs/default.toml", "--out", "p"]);
    let u = map_extents(&c, "u/maps/dnsom_ellipsoid_10x10.csv");
    let (ry, rz) = (u[1] / u[0], u[2] / u[0]);
    assert!(
        (ry - 0.625).abs() < 0.06 && (rz - 0.375).abs() < 0.06,
        "uniform: extents {u:?} are not 40:25:15"
    );
    let p = map_extents(&c, "p/maps/dnsom_ellipsoid_10x10.csv");
    assert!(
        (p[1] / p[0] - 1.0).abs() < 0.1 && (p[2] / p[0] - 1.0).abs() < 0.1,
        "per_axis: extents {p:?} should be about equal"
    );
    let report = std::fs::read_to_string(c.path("u/REPORT.md")).unwrap();
    assert!(report.contains("normalised uniformly"), "the report does not state the normalisation");
    assert!(std::fs::read_to_string(c.path("p/REPORT.md"))
        .unwrap()
        .contains("normalised per axis"));
    let (h, rows) = read_csv(&c.path("u/runs.csv"));
    assert!(rows.iter().all(|r| r[col(&h, "dataset")] == "ellipsoid"), "{rows:?}");
    // From inside the spec's folder too (the same seeds: the name is the stem, not the path).
    let inside = bin()
        .args(["run", "uniform.toml", "--out", "../u2"])
        .current_dir(c.path("specs"))
        .output()
        .unwrap();
    assert!(inside.status.success(), "{}", String::from_utf8_lossy(&inside.stderr));
    assert_eq!(without_timing(&c.path("u/runs.csv")), without_timing(&c.path("u2/runs.csv")));
    // A bad option names the key.
    c.write("specs/bad.toml", &OWN.replace("NORMALISE", "normalise = \"cube\""));
    c.fails(
        &["run", "specs/bad.toml", "--out", "bad"],
        &["bad.toml:3:", "cube", "per_axis", "uniform"],
    );
}

#[test]
fn a_missing_data_file_is_refused_before_anything_is_written() {
    let c = Case::new();
    c.write("specs/none.toml", &OWN.replace("NORMALISE", "").replace("ellipsoid", "nothere"));
    let err = c.fails(
        &["run", "specs/none.toml", "--out", "out"],
        &["specs/mydata/nothere.xyz", "not found", "spec's folder"],
    );
    assert!(err.contains("none.toml"), "{err}");
    assert!(!c.path("out").exists(), "the run made its folder before refusing");
    let out = c.run(&["run", "specs/none.toml", "--out", "out"]);
    assert_eq!(out.status.code(), Some(2));
}
