//! Own data: a spec's relative data-set paths and maps folder are read from the spec's folder (so
//! it runs from anywhere), its results are named by the file's stem, `normalise` chooses the
//! scaling, and a missing file or maps folder is refused before anything is written (a maps folder
//! only unless `maps_missing = "recompute"`); `reproduce` finds its plans from any folder.

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

/// A Chapter 5 spec on CH4_FOR_FIT's map; MAPS is its `maps` line.
const FIT: &str = "name = \"fits\"\nmaster_seed = 11\n[fit]\ndatasets = [\"sphere\"]\ngrid = \"20x20\"\ncontrol_nets = [\"6x6\"]\nparameterisations = [\"chord_length\"]\napproaches = [\"A\", \"B\"]\npictures = false\nMAPS\n[fit.som]\niterations = 500\n";

#[test]
fn a_maps_folder_resolves_against_the_spec_from_any_working_folder() {
    let c = Case::new();
    c.write("maps.toml", CH4_FOR_FIT);
    c.ok(&["run", "maps.toml", "--out", "ch4"]);
    c.write("specs/fits.toml", &FIT.replace("MAPS", "maps = \"../ch4/maps\""));
    let map = "maps/dnsom_sphere_20x20.csv";
    let original = std::fs::read_to_string(c.path("ch4").join(map)).unwrap();
    for (cwd, spec, out, shown) in [
        ("", "specs/fits.toml", "top", "ch4/maps/dnsom_sphere_20x20.csv"),
        ("elsewhere/deeper", "../../specs/fits.toml", "o", "../../ch4/maps/dnsom_sphere_20x20.csv"),
    ] {
        let said = c.ok_from(cwd, &["run", spec, "--out", out]);
        let folder = c.path(cwd).join(out);
        assert!(
            !String::from_utf8_lossy(&said.stderr).contains("recomput"),
            "read, not recomputed"
        );
        assert_eq!(std::fs::read_to_string(folder.join(map)).unwrap(), original);
        let report = std::fs::read_to_string(folder.join("REPORT.md")).unwrap();
        assert!(report.contains(&format!("sphere from {shown}")), "{report}");
        assert!(report.contains(&format!("Re-run: `somnurbs run {spec} --out {out}`")), "{report}");
    }
    assert_eq!(
        without_timing(&c.path("top/runs.csv")),
        without_timing(&c.path("elsewhere/deeper/o/runs.csv"))
    );
}

#[test]
fn a_named_maps_folder_that_is_not_there_is_refused_unless_recomputing_is_asked_for() {
    let c = Case::new();
    c.write("maps.toml", CH4_FOR_FIT);
    c.ok(&["run", "maps.toml", "--out", "ch4"]);
    // Relative to the spec's folder: ch4/maps beside the spec is not there.
    c.write("specs/here.toml", &FIT.replace("MAPS", "maps = \"ch4/maps\""));
    c.fails(
        &["run", "specs/here.toml", "--out", "o"],
        &["specs/here.toml", "fit.maps", "no maps folder specs/ch4/maps", "maps_missing"],
    );
    assert_eq!(c.run(&["run", "specs/here.toml", "--out", "o"]).status.code(), Some(2));
    assert!(!c.path("o").exists(), "the refused run made its folder");
    // A folder without the map names the file.
    std::fs::create_dir_all(c.path("specs/empty")).unwrap();
    c.write("specs/empty.toml", &FIT.replace("MAPS", "maps = \"empty\""));
    c.fails(
        &["run", "specs/empty.toml", "--out", "o"],
        &["fit.maps", "no map specs/empty/dnsom_sphere_20x20.csv"],
    );
    // Chapter 6 too.
    c.write("specs/opt.toml", &SPEC.replace("[optim.som]", "maps = \"nomaps\"\n[optim.som]"));
    c.fails(
        &["run", "specs/opt.toml", "--out", "o"],
        &["optim.maps", "no maps folder specs/nomaps"],
    );
    // Asked for: recomputed exactly as Chapter 4 made it, said in one line.
    c.write(
        "specs/rec.toml",
        &FIT.replace("MAPS", "maps = \"nomaps\"\nmaps_missing = \"recompute\""),
    );
    let said = c.ok(&["run", "specs/rec.toml", "--out", "rec"]);
    let said = String::from_utf8_lossy(&said.stderr);
    let lines: Vec<&str> = said.lines().filter(|l| l.contains("recomput")).collect();
    assert!(
        lines.len() == 1
            && lines[0].contains("no maps folder specs/nomaps")
            && lines[0].contains("recomputing dnsom_sphere_20x20.csv from [fit.som]"),
        "{said}"
    );
    let map = "maps/dnsom_sphere_20x20.csv";
    assert_eq!(
        std::fs::read_to_string(c.path("rec").join(map)).unwrap(),
        std::fs::read_to_string(c.path("ch4").join(map)).unwrap()
    );
    // Another value names the key and the values allowed.
    c.write("specs/bad.toml", &FIT.replace("MAPS", "maps = \"nomaps\"\nmaps_missing = \"skip\""));
    c.fails(&["run", "specs/bad.toml", "--out", "o"], &["bad.toml:", "skip", "recompute"]);
}

#[test]
fn reproduce_finds_its_plans_from_another_working_folder() {
    let c = Case::new();
    // No experiments/ here: the plans of the clone the binary was built from.
    let out = c.ok_from(
        "elsewhere",
        &["reproduce", "--plan", "seeds", "--profile", "quick", "--out", "o"],
    );
    let clone = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments");
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(
        said.contains(&format!(
            "using the plans of the clone somnurbs was built from, {}",
            clone.display()
        )),
        "{said}"
    );
    let report = std::fs::read_to_string(c.path("elsewhere/o/REPORT.md")).unwrap();
    let rerun = format!(
        "Re-run: `somnurbs reproduce --plan seeds --profile quick --specs {} --out o`",
        clone.display()
    );
    assert!(report.contains(&rerun), "{report}");
    // A plan neither here nor in the clone: the folders tried, and --specs.
    let out = c.run_from("elsewhere", &["reproduce", "--plan", "nosuch", "--out", "x"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("no folder experiments/")
            && err.contains(&clone.join("nosuch.toml").display().to_string())
            && err.contains("--specs DIR"),
        "{err}"
    );
    // A folder of its own named experiments/ is used as it is (no fallback).
    c.write("mine/experiments/x.toml", "name = \"x\"\n");
    let out = c.run_from("mine", &["reproduce", "--plan", "seeds", "--out", "x"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success()
            && err.contains("experiments/seeds.toml")
            && err.contains("--specs DIR"),
        "{err}"
    );
}
