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
        assert_eq!(map_text(&folder.join(map)), original);
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
    c.write("specs/opt.toml", &SPEC.replace("[optimise.som]", "maps = \"nomaps\"\n[optimise.som]"));
    c.fails(
        &["run", "specs/opt.toml", "--out", "o"],
        &["optimise.maps", "no maps folder specs/nomaps"],
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
        map_text(&c.path("rec").join(map)),
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

/// A smooth closed surface (an ellipsoid) spanning about [-3, 5] x [10, 11] x [0, 100]: the
/// points of a scan in its own frame.
fn scan() -> Vec<[f64; 3]> {
    let mut p = Vec::new();
    for i in 0..40 {
        let t = std::f64::consts::PI * (i as f64 + 0.5) / 40.0;
        for j in 0..50 {
            let f = 2.0 * std::f64::consts::PI * j as f64 / 50.0;
            p.push([
                1.0 + 4.0 * t.sin() * f.cos(),
                10.5 + 0.5 * t.sin() * f.sin(),
                50.0 + 50.0 * t.cos(),
            ]);
        }
    }
    p
}

const CH4_OWN: &str = "name = \"pts\"\nmaster_seed = 3\n[som]\ndatasets = [\"DATA\"]\niterations = 4000\nsave_maps = [\"12x12\"]\npictures = false\n[[som.group]]\nmodels = [\"dnsom\"]\ngrids = [\"12x12\"]\n";

/// The vertices of an OBJ file and the control points of an IGES file.
fn exported(c: &Case, dir: &str) -> (Vec<[f64; 3]>, Vec<[f64; 3]>, String, String) {
    let obj = std::fs::read_to_string(c.path(&format!("{dir}/surfaces.obj"))).unwrap();
    let igs = std::fs::read_to_string(c.path(&format!("{dir}/surfaces.igs"))).unwrap();
    let verts = obj
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let v: Vec<f64> = l.split(' ').map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    let control = somnurbs::spline::parse_iges_128(&igs)
        .unwrap()
        .iter()
        .flat_map(|s| s.control.clone())
        .collect();
    (verts, control, obj, igs)
}

/// Every point within the box [lo, hi] widened by `tol` of each axis' range.
fn within(points: &[[f64; 3]], lo: [f64; 3], hi: [f64; 3], tol: f64, what: &str) {
    assert!(!points.is_empty(), "{what}: no points");
    for p in points {
        for a in 0..3 {
            let slack = tol * (hi[a] - lo[a]);
            assert!(
                p[a] >= lo[a] - slack && p[a] <= hi[a] + slack,
                "{what}: {p:?} outside [{lo:?}, {hi:?}]"
            );
        }
    }
}

#[test]
fn off_and_obj_scans_export_in_their_own_frame_or_the_normalised_one() {
    let c = Case::new();
    let pts = scan();
    let mut off = format!("OFF\n# a scan\n{} 0 0\n", pts.len());
    let mut obj = String::from("# a scan\no scan\n");
    for p in &pts {
        off.push_str(&format!("{} {} {}\n", p[0], p[1], p[2]));
        obj.push_str(&format!("v {} {} {}\nvn 0 0 1\n", p[0], p[1], p[2]));
    }
    c.write("pts.off", &off);
    c.write("scan.obj", &obj);
    let lo = [0, 1, 2].map(|a| pts.iter().map(|p| p[a]).fold(f64::MAX, f64::min));
    let hi = [0, 1, 2].map(|a| pts.iter().map(|p| p[a]).fold(f64::MIN, f64::max));
    for (file, data) in [("pts.off", "pts"), ("scan.obj", "scan")] {
        c.write(&format!("{data}.toml"), &CH4_OWN.replace("DATA", file));
        c.ok(&["run", &format!("{data}.toml"), "--out", &format!("ch4_{data}")]);
        let map = format!("ch4_{data}/maps/dnsom_{data}_12x12.csv");
        let frame = std::fs::read_to_string(c.path(&map.replace(".csv", ".frame.toml"))).unwrap();
        assert!(frame.contains("normalise = \"per_axis\"") && frame.contains(file), "{frame}");
        // The data's frame (the default).
        let out = format!("{data}_f");
        c.ok(&["fit", "--grid", &map, "--cn", "6x6", "--out", &out]);
        let (verts, control, obj_text, igs) = exported(&c, &out);
        within(&verts, lo, hi, 0.05, "OBJ vertices (data)");
        // A control net lies outside the convex surface it shapes (by up to a third of the box
        // here, at the poles): near the box, far from [0, 1]^3 on y and z.
        within(&control, lo, hi, 0.5, "IGES control points (data)");
        assert!(verts.iter().any(|v| v[2] > 50.0), "not in the data's frame");
        assert!(
            obj_text
                .lines()
                .any(|l| l.starts_with("# Frame: the data's own coordinates") && l.contains(file)),
            "{obj_text}"
        );
        let start: String = igs
            .lines()
            .filter(|l| &l[72..73] == "S")
            .map(|l| l[..72].trim_end().to_string() + " ")
            .collect();
        assert!(
            start.contains("the data's own coordinates")
                && start.contains(file)
                && start.contains("Units: unknown"),
            "{start}"
        );
        let (h, rows) = read_csv(&c.path(&format!("{out}/fit.csv")));
        assert_eq!(rows[0][col(&h, "frame")], "data");
        let (nh, nets) = read_csv(&c.path(&format!("{out}/control_nets.csv")));
        assert!(nets.iter().any(|r| r[col(&nh, "z")].parse::<f64>().unwrap() > 50.0));
        // The normalised frame.
        let out = format!("{data}_n");
        c.ok(&["fit", "--grid", &map, "--cn", "6x6", "--frame", "normalised", "--out", &out]);
        let (n_verts, n_control, obj_text, _) = exported(&c, &out);
        within(&n_verts, [0.0; 3], [1.0; 3], 0.05, "OBJ vertices (normalised)");
        // The two exports are one affine map apart (the frame: offset lo, scale hi - lo).
        for (d, n) in control.iter().zip(&n_control).chain(verts.iter().zip(&n_verts)) {
            for a in 0..3 {
                let want = lo[a] + (hi[a] - lo[a]) * n[a];
                assert!((d[a] - want).abs() <= 1e-9 * (1.0 + want.abs()), "{d:?} {n:?}");
            }
        }
        within(&n_control, [0.0; 3], [1.0; 3], 0.5, "IGES control points (normalised)");
        assert!(obj_text.contains("# Frame: the normalised box"), "{obj_text}");
        let (h, rows) = read_csv(&c.path(&format!("{out}/fit.csv")));
        assert_eq!(rows[0][col(&h, "frame")], "normalised");
    }
    // A map without a frame: its own coordinates, said in one line.
    std::fs::copy(c.path("ch4_pts/maps/dnsom_pts_12x12.csv"), c.path("hand.csv")).unwrap();
    let said = c.ok(&["fit", "--grid", "hand.csv", "--cn", "6x6", "--units", "mm", "--out", "h"]);
    let said = String::from_utf8_lossy(&said.stderr);
    let notes: Vec<&str> = said.lines().filter(|l| l.contains("no frame")).collect();
    assert!(
        notes.len() == 1
            && notes[0].starts_with("somnurbs: note:")
            && notes[0].contains("hand.frame.toml"),
        "{said}"
    );
    let (verts, _, _, igs) = exported(&c, "h");
    within(&verts, [0.0; 3], [1.0; 3], 0.05, "OBJ vertices (no frame)");
    assert!(igs.contains("Units: MM."), "{igs}");
    let (h, rows) = read_csv(&c.path("h/fit.csv"));
    assert_eq!(rows[0][col(&h, "frame")], "map");
    c.fails(
        &["fit", "--grid", "hand.csv", "--cn", "6x6", "--frame", "box", "--out", "x"],
        &["--frame", "box"],
    );
}

#[test]
fn bad_off_counts_are_refused_and_xyz_normals_are_noted_once() {
    let c = Case::new();
    c.write("huge.off", "OFF\n# claims a trillion\n1000000000000 0 0\n0 0 0\n");
    c.write("huge.toml", &CH4_OWN.replace("DATA", "huge.off"));
    c.fails(&["run", "huge.toml", "--out", "o"], &["huge.off", "line 3", "1000000000000 vertices"]);
    let normals: String =
        scan().iter().map(|p| format!("{} {} {} 0 0 1\n", p[0], p[1], p[2])).collect();
    c.write("n.xyz", &format!("x y z nx ny nz\n{normals}"));
    c.write("n.toml", &CH4_OWN.replace("DATA", "n.xyz"));
    let said = c.ok(&["run", "n.toml", "--out", "n"]);
    assert!(c.path("n/maps/dnsom_n_12x12.frame.toml").exists());
    let said = String::from_utf8_lossy(&said.stderr);
    let notes: Vec<&str> = said.lines().filter(|l| l.contains("ignored")).collect();
    assert!(
        notes.len() == 1
            && notes[0].starts_with("somnurbs: note: ")
            && notes[0].contains("n.xyz")
            && notes[0].contains("3 columns"),
        "{said}"
    );
}
