//! A cell's record is its one result: a sweep computes a cell no swept key reaches once, `--reuse`
//! takes a cell that computes the same from another folder (never one matched by name alone),
//! `somnurbs report` makes a finished folder's files again from its records, byte for byte, and
//! `somnurbs export` writes the net an optimiser found, its error equal to the record's.

use crate::common::*;

/// The files `report` makes again: all but the records, the fingerprint and the manifest.
fn rendered(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    let kept = ["cells.jsonl.gz", "fingerprint.toml", "manifest.toml"];
    snapshot(dir).into_iter().filter(|(p, _)| !kept.contains(&p.as_str())).collect()
}

/// Remove every rendered file of `dir` (its records, fingerprint and manifest stay).
fn strip(dir: &std::path::Path) {
    for (p, _) in rendered(dir) {
        std::fs::remove_file(dir.join(p)).unwrap();
    }
}

#[test]
fn a_sweep_computes_a_cell_it_does_not_change_once_and_lists_it_once() {
    let c = Case::new();
    c.write("d.toml", SPEC);
    c.ok(&["run", "d.toml", "--out", "s", "--sweep", "optimise.de.f=0.3,0.5,0.8"]);
    let (h, rows) = read_csv(&c.path("s/runs.csv"));
    let (o, v) = (col(&h, "optimiser"), col(&h, "variant"));
    let ga: Vec<&Vec<String>> = rows.iter().filter(|r| r[o] == "ga").collect();
    assert_eq!(ga.len(), 2, "GA's two repeats, once");
    assert!(ga.iter().all(|r| r[v].is_empty()), "no swept key reaches GA");
    assert_eq!(rows.len(), 2 + 3 * 2);
    let manifest = std::fs::read_to_string(c.path("s/manifest.toml")).unwrap();
    assert!(
        manifest.contains("cells = 8\n") && manifest.contains("cells_computed = 8"),
        "{manifest}"
    );
    let report = std::fs::read_to_string(c.path("s/REPORT.md")).unwrap();
    assert!(!report.contains("ga@"), "GA is listed per variant");
    // The plain run's GA cells are the sweep's, to the bit (one place, one stream, one identity).
    c.ok(&["run", "d.toml", "--out", "plain"]);
    let (ph, prows) = read_csv(&c.path("plain/runs.csv"));
    let pga: Vec<(String, String)> = prows
        .iter()
        .filter(|r| r[col(&ph, "optimiser")] == "ga")
        .map(|r| (r[col(&ph, "cell")].clone(), r[col(&ph, "best")].clone()))
        .collect();
    let sga: Vec<(String, String)> =
        ga.iter().map(|r| (r[col(&h, "cell")].clone(), r[col(&h, "best")].clone())).collect();
    assert_eq!(pga, sga);
}

#[test]
fn reuse_takes_the_cells_that_compute_the_same_and_computes_the_rest() {
    let c = Case::new();
    c.write("d.toml", SPEC);
    c.ok(&["run", "d.toml", "--out", "a"]);
    c.ok(&["run", "d.toml", "--out", "fresh", "--set", "optimise.de.f=0.5"]);
    c.ok(&["run", "d.toml", "--out", "b", "--set", "optimise.de.f=0.5", "--reuse", "a"]);
    let manifest = std::fs::read_to_string(c.path("b/manifest.toml")).unwrap();
    assert!(
        manifest.contains("cells_computed = 2") && manifest.contains("cells_reused = 2"),
        "GA's two cells are a's, DE's two are new: {manifest}"
    );
    assert!(std::fs::read_to_string(c.path("b/REPORT.md")).unwrap().contains("2 reused"));
    // Reused or computed, the folder's tables are those of the run that computed every cell.
    assert!(same_tables(&c.path("fresh"), &c.path("b")) >= 5);
    // A folder whose cells compute something else gives none: another master seed.
    c.write("e.toml", &SPEC.replace("master_seed = 3", "master_seed = 4"));
    c.ok(&["run", "e.toml", "--out", "e", "--reuse", "a"]);
    let manifest = std::fs::read_to_string(c.path("e/manifest.toml")).unwrap();
    assert!(manifest.contains("cells_reused = 0"), "{manifest}");
    // A family whose cells are known by place alone never reuses (a Chapter 4 folder's records
    // would otherwise stand for another reading's).
    c.fails(&["run", "d.toml", "--out", "x", "--reuse", "nowhere"], &["--reuse", "nowhere"]);
    c.fails(&["run", "d.toml", "--out", "y", "--reuse", "d.toml"], &["--reuse", "d.toml"]);
    assert!(!c.path("x").exists() && !c.path("y").exists());
}

#[test]
fn report_makes_a_finished_folders_files_again_from_its_records_alone() {
    let c = Case::new();
    c.write("d.toml", SPEC);
    c.ok(&["run", "d.toml", "--out", "r"]);
    let dir = c.path("r");
    let before = rendered(&dir);
    assert!(before.iter().any(|(p, _)| p.ends_with(".png")) && before.len() > 15);
    // Every rendered file removed: report gives each back, byte for byte, without a cell run.
    strip(&dir);
    let out = c.ok(&["report", "r"]);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("progress"), "a cell ran");
    assert_eq!(rendered(&dir), before);
    // Again on a whole folder: nothing changes.
    c.ok(&["report", "r"]);
    assert_eq!(rendered(&dir), before);
    // An edited table is named and left as it is; so is a folder whose record is gone.
    std::fs::write(dir.join("appendix_k.csv"), "edited\n").unwrap();
    c.fails(&["report", "r"], &["appendix_k.csv", "differently"]);
    assert_eq!(std::fs::read_to_string(dir.join("appendix_k.csv")).unwrap(), "edited\n");
    // A folder that is not a finished run's is refused.
    c.ok(&["run", "d.toml", "--out", "sh", "--shard", "1/2"]);
    c.fails(&["report", "sh"], &["shard 1/2", "merge"]);
    c.fails(&["report", "nowhere"], &["nowhere"]);
}

#[test]
fn report_is_byte_equal_for_a_chapter_4_and_a_seed_spec() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    for spec in ["ch4_models", "seed003_cuckoo_bezier"] {
        let c = Case::new();
        let path = root.join(format!("experiments/{spec}.toml"));
        c.ok(&["run", path.to_str().unwrap(), "--profile", "quick", "--out", "r"]);
        let before = rendered(&c.path("r"));
        strip(&c.path("r"));
        c.ok(&["report", "r"]);
        assert_eq!(rendered(&c.path("r")), before, "{spec}");
    }
}

#[test]
fn export_writes_the_optimised_net_whose_error_is_the_records() {
    // The talus scan: its map is trained in a normalised box, so its frame is not the identity.
    let c = Case::new();
    c.write("d.toml", &SPEC.replace("\"sphere\"", "\"talus\""));
    c.ok(&["run", "d.toml", "--out", "r", "--data-dir", data_dir().to_str().unwrap()]);
    let (h, rows) = read_csv(&c.path("r/runs.csv"));
    let de = rows.iter().find(|r| r[col(&h, "optimiser")] == "de").unwrap();
    let cell = de[col(&h, "cell")].clone();
    let data = data_dir();
    let data = data.to_str().unwrap();
    c.ok(&["export", "r", "--cell", &cell, "--out", "x", "--data-dir", data]);
    let (eh, erows) = read_csv(&c.path("x/export.csv"));
    let error: f64 = erows[0][col(&eh, "surface_error")].parse().unwrap();
    let best: f64 = de[col(&h, "best")].parse().unwrap();
    assert_eq!(error.to_bits(), best.to_bits());
    assert_eq!(erows[0][col(&eh, "frame")], "data");
    // Two 6x6 nets.
    assert_eq!(read_csv(&c.path("x/control_nets.csv")).1.len(), 2 * 36);
    let iges = std::fs::read_to_string(c.path("x/surfaces.igs")).unwrap();
    assert!(iges.lines().all(|l| l.len() == 80), "IGES lines are 80 columns");
    // The start: approach B's net, its error B's.
    c.ok(&["export", "r", "--cell", &cell, "--start", "--out", "b", "--data-dir", data]);
    let (bh, brows) = read_csv(&c.path("b/export.csv"));
    let b: f64 = de[col(&h, "b")].parse().unwrap();
    assert_eq!(brows[0][col(&bh, "surface_error")].parse::<f64>().unwrap().to_bits(), b.to_bits());
    // The data's frame is the normalised net put back: offset + scale * x, per axis.
    c.ok(&[
        "export",
        "r",
        "--cell",
        &cell,
        "--frame",
        "normalised",
        "--out",
        "n",
        "--data-dir",
        data,
    ]);
    let frame = std::fs::read_to_string(c.path("r/maps/dnsom_talus_20x20.frame.toml")).unwrap();
    let t: toml::Table = toml::from_str(&frame).unwrap();
    let vec3 = |k: &str| -> Vec<f64> {
        t[k].as_array().unwrap().iter().map(|v| v.as_float().unwrap()).collect()
    };
    let (offset, scale) = (vec3("offset"), vec3("scale"));
    assert!(scale.iter().any(|s| *s != 1.0), "the talus' frame is the identity: {frame}");
    let (nh, nrows) = read_csv(&c.path("n/control_nets.csv"));
    let (_, drows) = read_csv(&c.path("x/control_nets.csv"));
    for (n, d) in nrows.iter().zip(&drows) {
        for (a, axis) in ["x", "y", "z"].iter().enumerate() {
            let k = col(&nh, axis);
            let (xn, xd): (f64, f64) = (n[k].parse().unwrap(), d[k].parse().unwrap());
            assert!(
                (offset[a] + scale[a] * xn - xd).abs() <= 1e-12 * (1.0 + xd.abs()),
                "{xn} {xd}"
            );
        }
    }
    // A cell the folder does not have, and a taken --out, are refused naming them.
    c.fails(
        &["export", "r", "--cell", "optim/cube/20x20/6x6/uniform/de/r0", "--out", "y"],
        &["optim/cube"],
    );
    c.fails(&["export", "r", "--cell", &cell, "--out", "x"], &["x"]);
}

#[test]
fn export_refuses_a_net_that_leaves_the_data_unless_allowed() {
    // The NURBS Book's knots at an 18x18 net on a 20x20 map: B's start, and so every optimised
    // net, leaves the map's box between the data points by orders of magnitude.
    let c = Case::new();
    let spec = SPEC
        .replace("control_nets = [\"6x6\"]", "control_nets = [\"18x18\"]")
        .replace("optimisers = [\"ga\", \"de\"]", "optimisers = [\"de\"]")
        .replace("repeats = 2", "repeats = 1\nknots = \"nurbs_book\"")
        .replace("generations = 20", "generations = 3");
    c.write("d.toml", &spec);
    c.ok(&["run", "d.toml", "--out", "r"]);
    let (h, rows) = read_csv(&c.path("r/runs.csv"));
    let cell = rows[0][col(&h, "cell")].clone();
    let args = ["export", "r", "--cell", &cell, "--out", "x"];
    let out = c.run(&args);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(2), "{}", c.explain(&args, &out));
    assert!(!c.path("x").exists(), "nothing written: {err}");
    for needle in [
        "leave the map's bounding box",
        "the bound is 10%",
        "Measured: the start",
        "--allow-excursion",
    ] {
        assert!(err.contains(needle), "{needle}: {err}");
    }
    let out = c.ok(&[&args[..], &["--allow-excursion"]].concat());
    assert!(String::from_utf8_lossy(&out.stderr).contains("Written anyway"));
    assert!(c.path("x/surfaces.igs").exists() && c.path("x/export.csv").exists());
}
