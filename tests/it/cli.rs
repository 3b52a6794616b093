//! Integration tests: run the real binary on tiny specs in temporary folders and read what it
//! writes. On failure each helper prints the command, the folder listing, stdout and stderr.

use crate::common::*;
use std::path::Path;

const TINY: &str = r#"
name = "tiny"
master_seed = 7
[som]
datasets = ["sphere", "cube"]
iterations = 400
save_maps = ["6x5"]
pictures = false
[[som.group]]
models = ["som2d", "som3d", "cksom", "dnsom"]
grids = ["4x4", "6x6"]
[[som.group]]
models = ["cksom", "dnsom"]
grids = ["6x5"]
"#;

#[test]
fn run_writes_every_table_with_the_thesis_columns() {
    let c = Case::new();
    c.write("tiny.toml", TINY);
    c.ok(&["run", "tiny.toml", "--out", "out", "--jobs", "2"]);
    let out = c.path("out");
    for f in [
        "runs.csv",
        "appendix_b.csv",
        "appendix_c.csv",
        "table_4_9.csv",
        "table_4_13.csv",
        "manifest.toml",
        "REPORT.md",
        "maps/dnsom_sphere_6x5.csv",
        "maps/dnsom_cube_6x5.csv",
    ] {
        assert!(out.join(f).exists(), "missing {f}: {:?}", walk(&out));
    }
    // A finished run keeps its cell log compressed.
    assert!(out.join("cells.jsonl.gz").exists() && out.join("fingerprint.toml").exists());
    assert!(!out.join("cells.jsonl").exists());
    let reference = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/reference");
    for t in ["appendix_b.csv", "appendix_c.csv"] {
        assert_eq!(read_csv(&out.join(t)).0, read_csv(&reference.join(t)).0, "{t} columns");
    }
    let (h, rows) = read_csv(&out.join("runs.csv"));
    assert_eq!(rows.len(), 2 * (4 * 2 + 2)); // 2 data x (4 models x 2 grids + 2 models x 1 grid)
    let col = |name: &str| h.iter().position(|x| x == name).unwrap();
    for r in &rows {
        let qe: f64 = r[col("qe")].parse().unwrap();
        let (mn, mx): (f64, f64) =
            (r[col("min_error")].parse().unwrap(), r[col("max_error")].parse().unwrap());
        assert!(mn <= qe && qe <= mx && mn >= 0.0, "{r:?}");
        let te: f64 = r[col("te")].parse().unwrap();
        assert!((0.0..=1.0).contains(&te));
    }
    // Table 4.13's DNSOM counts at 6x5 and the saved map has NON rows with both views.
    let (_, t413) = read_csv(&out.join("table_4_13.csv"));
    assert_eq!(t413[0][5..8], ["60".to_string(), "42".into(), "18".into()]);
    let (mh, map) = read_csv(&out.join("maps/dnsom_sphere_6x5.csv"));
    assert_eq!(mh, ["i", "j", "view", "class", "x", "y", "z"]);
    assert_eq!(map.len(), 60);
    let classes: std::collections::BTreeSet<&str> = map.iter().map(|r| r[3].as_str()).collect();
    assert_eq!(classes.len(), 42);
    let manifest = std::fs::read_to_string(out.join("manifest.toml")).unwrap();
    for key in ["master_seed = 7", "spec_text", "git_commit", "rustc", "[definitions]"] {
        assert!(manifest.contains(key), "manifest lacks {key}");
    }
    let report = std::fs::read_to_string(out.join("REPORT.md")).unwrap();
    assert!(report.contains("DNSOM has the lowest TE") && report.contains("Metric definitions"));
    // Table 4.14: the DNSOM structure built at the thesis' small grids, its published counts.
    let (_, t414) = read_csv(&out.join("table_4_14.csv"));
    let thesis = [
        ["2", "3", "12", "6", "6"],
        ["3", "4", "24", "14", "10"],
        ["4", "5", "40", "26", "14"],
        ["5", "6", "60", "42", "18"],
        ["6", "7", "84", "62", "22"],
        ["7", "8", "112", "86", "26"],
    ];
    assert_eq!(t414, thesis.map(|r| r.map(String::from)));
    assert!(report.contains("built at each (the counts depend on the grid alone"), "{report}");
}

#[test]
fn the_count_tables_show_only_the_grids_and_models_that_ran() {
    let c = Case::new();
    let spec = TINY
        .replace("models = [\"som2d\", \"som3d\", \"cksom\", \"dnsom\"]", "models = [\"som2d\"]")
        .replace(
            "models = [\"cksom\", \"dnsom\"]\ngrids = [\"6x5\"]",
            "models = [\"dnsom\"]\ngrids = [\"5x6\"]",
        )
        .replace("save_maps = [\"6x5\"]", "save_maps = []");
    c.write("own.toml", &spec);
    c.ok(&["run", "own.toml", "--out", "o"]);
    let (h, rows) = read_csv(&c.path("o/table_4_9.csv"));
    assert_eq!(h, ["n", "som2d"], "only the model that ran at n x n");
    assert_eq!(rows, [["4", "16"], ["6", "36"]]);
    let (h, rows) = read_csv(&c.path("o/table_4_13.csv"));
    assert_eq!(h, ["n_x", "n_y", "dnsom_non", "dnsom_nov", "dnsom_nor"]);
    assert_eq!(rows, [["5", "6", "60", "42", "18"]]);
    let (_, rows) = read_csv(&c.path("o/table_4_14.csv"));
    assert_eq!(rows.len(), 6, "the structure at each of the thesis' six grids");
    let report = std::fs::read_to_string(c.path("o/REPORT.md")).unwrap();
    for needle in
        ["3-D SOM, CKSOM, DNSOM did not run at these grids", "CKSOM did not run at these grids"]
    {
        assert!(report.contains(needle), "{needle}: {report}");
    }
    assert!(!report.contains("160/128/32") && !report.contains("six nx x ny faces"), "{report}");
}

#[test]
fn results_do_not_depend_on_thread_count() {
    let c = Case::new();
    c.write("tiny.toml", TINY);
    c.ok(&["run", "tiny.toml", "--out", "j1", "--jobs", "1"]);
    c.ok(&["run", "tiny.toml", "--out", "j2", "--jobs", "2"]);
    for f in [
        "runs.csv",
        "appendix_b.csv",
        "appendix_c.csv",
        "table_4_9.csv",
        "table_4_13.csv",
        "maps/dnsom_cube_6x5.csv",
    ] {
        assert_eq!(
            without_timing(&c.path("j1").join(f)),
            without_timing(&c.path("j2").join(f)),
            "{f} differs"
        );
    }
}

#[test]
fn dry_run_lists_cells_and_seeds() {
    let c = Case::new();
    c.write("tiny.toml", TINY);
    let out = c.ok(&["run", "tiny.toml", "--dry-run"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(text.lines().count(), 20);
    assert!(text.contains("som/sphere/dnsom/6x5/r0\tseed "));
    assert!(!c.path("results").exists());
}

#[test]
fn bad_specs_fail_on_one_line_naming_line_and_key() {
    let c = Case::new();
    c.write("broken.toml", "name = \"x\"\nmaster_seed = 1\n[som\n");
    c.fails(&["run", "broken.toml"], &["broken.toml:3:"]);
    c.write("unknown.toml", &TINY.replace("iterations = 400", "iteration = 400"));
    c.fails(&["run", "unknown.toml"], &["unknown.toml:6:1", "iteration"]);
    c.write("model.toml", &TINY.replace("\"som2d\", \"som3d\"", "\"som2d\", \"som4d\""));
    c.fails(&["run", "model.toml"], &["model.toml:", "unknown SOM model `som4d`"]);
    c.fails(&["run", "missing.toml"], &["missing.toml"]);
    c.fails(&["run", "unknown.toml", "--profile", "quick"], &["unknown.toml"]);
}

#[test]
fn bad_data_fails_before_any_table_is_written() {
    let c = Case::new();
    let spec = |data: &str| {
        TINY.replace("datasets = [\"sphere\", \"cube\"]", &format!("datasets = [\"{data}\"]"))
            .replace("save_maps = [\"6x5\"]", "")
    };
    // A data file that is not there: the error names it and the data directory.
    c.write("bunny.toml", &spec("bunny"));
    let out = bin()
        .args(["run", "bunny.toml", "--out", "o1", "--data-dir", "nowhere"])
        .current_dir(c.dir.path())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("bun_zipper.ply") && err.contains("nowhere"),
        "{err}"
    );
    assert!(!c.path("o1/appendix_b.csv").exists());
    // NaN and too few points in a user file.
    c.write("nan.xyz", "0 0 0\n1 1 1\n0.5 nan 0.5\n1 0 1\n0 1 0\n");
    c.write("nan.toml", &spec("nan.xyz"));
    c.fails(&["run", "nan.toml", "--out", "o2"], &["nan.xyz"]);
    assert!(!c.path("o2/appendix_b.csv").exists());
    c.write("few.xyz", "0 0 0\n1 1 1\n");
    c.write("few.toml", &spec("few.xyz"));
    c.fails(&["run", "few.toml", "--out", "o3"], &["few.xyz"]);
    assert!(!c.path("o3/runs.csv").exists());
}

#[test]
fn unwritable_output_folder_is_a_clear_error() {
    let c = Case::new();
    c.write("tiny.toml", TINY);
    c.write("file", "not a folder");
    c.fails(&["run", "tiny.toml", "--out", "file/out"], &["file/out"]);
}

#[test]
fn datasets_list_show_export() {
    let c = Case::new();
    let out = c.ok(&["datasets", "list"]);
    let text = String::from_utf8_lossy(&out.stdout);
    for name in ["cube", "sphere", "spindle", "oiltank", "talus", "bunny"] {
        assert!(text.contains(name), "{text}");
    }
    let out = c.ok(&["datasets", "show", "spindle"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("7552 points"));
    c.ok(&["datasets", "export", "oiltank", "oil.csv"]);
    let (h, rows) = read_csv(&c.path("oil.csv"));
    assert_eq!((h.len(), rows.len()), (3, 5942));
    // Exporting into a plain folder leaves only the file (no lock file of a results folder).
    assert!(!c.path(".somnurbs.lock").exists(), "datasets export left a lock file behind");
    c.fails(&["datasets", "show", "teapot"], &["teapot"]);
}

const CH5_TINY: &str = r#"
name = "fits"
master_seed = 11
[fit]
datasets = ["sphere"]
grid = "20x20"
control_nets = ["6x6", "12x12"]
parameterisations = ["uniform", "chord_length", "centripetal", "exponential"]
approaches = ["A", "B"]
maps = "MAPS"
pictures = false
[fit.som]
iterations = 500
"#;

#[test]
fn chapter_5_reads_or_recomputes_maps_and_writes_appendix_e() {
    let c = Case::new();
    c.write("maps.toml", CH4_FOR_FIT);
    c.ok(&["run", "maps.toml", "--out", "ch4"]);
    c.write("fits.toml", &CH5_TINY.replace("MAPS", "ch4/maps"));
    c.ok(&["run", "fits.toml", "--out", "read"]);
    c.write(
        "fits2.toml",
        &CH5_TINY
            .replace("MAPS", "nowhere")
            .replace("[fit.som]", "maps_missing = \"recompute\"\n[fit.som]"),
    );
    let said = c.ok(&["run", "fits2.toml", "--out", "recomputed"]);
    let said = String::from_utf8_lossy(&said.stderr);
    let line: Vec<&str> = said.lines().filter(|l| l.contains("recomputing")).collect();
    assert!(
        line.len() == 1
            && line[0].contains("no maps folder nowhere")
            && line[0].contains("dnsom_sphere_20x20.csv")
            && line[0].contains("[fit.som]"),
        "{said}"
    );
    let report = std::fs::read_to_string(c.path("read/REPORT.md")).unwrap();
    assert!(report.contains("sphere from ch4/maps/dnsom_sphere_20x20.csv"), "{report}");
    assert!(report.contains("Re-run: `somnurbs run fits.toml --out read`"), "{report}");
    let map = "maps/dnsom_sphere_20x20.csv";
    let original = std::fs::read_to_string(c.path("ch4").join(map)).unwrap();
    // A folder keeps the map it read gzip-compressed, its exact text in under half the bytes.
    let copy = |dir: &str| -> (String, u64) {
        use std::io::Read as _;
        let file = c.path(dir).join(format!("{map}.gz"));
        assert!(!c.path(dir).join(map).exists(), "{dir}: only the compressed copy");
        let mut text = String::new();
        flate2::read::GzDecoder::new(std::fs::File::open(&file).unwrap())
            .read_to_string(&mut text)
            .unwrap();
        (text, std::fs::metadata(&file).unwrap().len())
    };
    let (kept, bytes) = copy("read");
    assert_eq!(original, kept, "the map used is kept in the results folder");
    assert!(bytes * 2 < original.len() as u64, "{bytes} bytes for {}", original.len());
    assert_eq!(original, copy("recomputed").0, "a recomputed map equals Chapter 4's");
    assert_eq!(
        without_timing(&c.path("read/appendix_e.csv")),
        without_timing(&c.path("recomputed/appendix_e.csv"))
    );
    let reference =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/reference/appendix_e.csv");
    let (h, rows) = read_csv(&c.path("read/appendix_e.csv"));
    assert_eq!(h, read_csv(&reference).0);
    assert_eq!(rows.len(), 2);
    // Error falls from the 6x6 to the 12x12 net in every column.
    for col in 3..h.len() {
        let (a, b): (f64, f64) = (rows[0][col].parse().unwrap(), rows[1][col].parse().unwrap());
        assert!(b < a, "{}: {a} -> {b}", h[col]);
    }
    let (gh, gaps) = read_csv(&c.path("read/gaps_20x20.csv"));
    let gb = gh.iter().position(|x| x == "gap_B").unwrap();
    let ga = gh.iter().position(|x| x == "gap_A").unwrap();
    assert!(gaps.iter().all(|r| r[gb].parse::<f64>().unwrap() == 0.0));
    assert!(gaps.iter().any(|r| r[ga].parse::<f64>().unwrap() > 0.0));
    for t in [
        "table_5_4.csv",
        "table_5_5.csv",
        "table_5_6.csv",
        "runs.csv",
        "REPORT.md",
        "manifest.toml",
    ] {
        assert!(c.path("read").join(t).exists(), "{t}");
    }
}

#[test]
fn fit_writes_nets_iges_and_obj_and_refuses_bad_grids() {
    let c = Case::new();
    c.write("maps.toml", CH4_FOR_FIT);
    c.ok(&["run", "maps.toml", "--out", "ch4"]);
    let grid = "ch4/maps/dnsom_sphere_20x20.csv";
    c.ok(&[
        "fit",
        "--grid",
        grid,
        "--cn",
        "8x6",
        "--param",
        "centripetal",
        "--approach",
        "B",
        "--out",
        "f",
    ]);
    let (_, nets) = read_csv(&c.path("f/control_nets.csv"));
    assert_eq!(nets.len(), 2 * 8 * 6);
    let igs = std::fs::read_to_string(c.path("f/surfaces.igs")).unwrap();
    let surfaces = somnurbs::spline::parse_iges_128(&igs).unwrap();
    assert_eq!((surfaces.len(), surfaces[0].cn_x, surfaces[0].cn_y), (2, 8, 6));
    let (fh, fit) = read_csv(&c.path("f/fit.csv"));
    let at = |name: &str| fit[0][fh.iter().position(|h| h == name).unwrap()].clone();
    assert_eq!(at("gap").parse::<f64>().unwrap(), 0.0, "approach B has no gap");
    assert_eq!(at("dense_gap").parse::<f64>().unwrap(), 0.0, "nor between the data points");
    assert_eq!((at("knots").as_str(), at("error_a").as_str()), ("eq2_10", "per_surface"));
    // Between the data points: an 18x18 net on the 20x20 map stays near the data under Eq. 2.10's
    // knots and blows up under the NURBS Book's, which `fit` refuses (exit 2, nothing written,
    // Eq. 2.10's knots measured within the bound) unless told to write; fairness tames it.
    let out = c.ok(&["fit", "--grid", grid, "--cn", "18x18", "--out", "f18"]);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("warning"));
    let book = ["fit", "--grid", grid, "--cn", "18x18", "--knots", "nurbs_book", "--out", "f18b"];
    let out = c.run(&book);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(2), "{}", c.explain(&book, &out));
    assert!(
        err.contains("leave the map's bounding box") && err.contains("--knots eq2_10"),
        "{err}"
    );
    assert!(!c.path("f18b").exists(), "a refused fit writes nothing");
    let allowed = [&book[..], &["--allow-excursion"]].concat();
    let out = c.ok(&allowed);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("warning") && err.contains("Written anyway (--allow-excursion)"), "{err}");
    assert!(c.path("f18b/manifest.toml").exists());
    let out = c.ok(&[
        "fit",
        "--grid",
        grid,
        "--cn",
        "18x18",
        "--knots",
        "nurbs_book",
        "--fairness",
        "1e-3",
        "--out",
        "f18f",
    ]);
    assert!(
        !String::from_utf8_lossy(&out.stderr).contains("warning"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    c.fails(&["fit", "--grid", grid, "--cn", "8x8", "--knots", "9.69"], &["--knots", "9.69"]);
    assert!(std::fs::read_to_string(c.path("f/surfaces.obj")).unwrap().contains("o bottom"));

    let text = std::fs::read_to_string(c.path(grid)).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    c.write("short.csv", &lines[..lines.len() - 1].join("\n"));
    c.fails(&["fit", "--grid", "short.csv", "--cn", "8x8"], &["short.csv", "needs 800 rows"]);
    let mut nan = lines.clone();
    let bad_line = nan[5].rsplit_once(',').unwrap().0.to_string() + ",NaN";
    nan[5] = &bad_line;
    c.write("nan.csv", &nan.join("\n"));
    c.fails(&["fit", "--grid", "nan.csv", "--cn", "8x8"], &["nan.csv", "line 6"]);
    c.fails(&["fit", "--grid", grid, "--cn", "21x8"], &["larger than the grid"]);
    c.fails(&["fit", "--grid", grid, "--cn", "3x8"], &["smaller than 4"]);
    c.fails(&["fit", "--grid", grid, "--cn", "8x8", "--param", "spline"], &["--param", "spline"]);
    c.fails(&["fit", "--grid", "missing.csv", "--cn", "8x8"], &["missing.csv"]);
}

/// A 20x20 two-view grid of a pillow (z = +-0.3 sin(pi x) sin(pi y), flat on the shared border)
/// whose rows are bunched at both ends and far apart in the middle (each end's rows `step`
/// apart in index units): chord-length parameters then leave a long knot span without data.
fn uneven_grid(step: f64) -> String {
    let s = |i: usize| {
        let i = i as f64;
        (if i < 10.0 { i * step } else { 19.0 - (19.0 - i) * step }) / 19.0
    };
    let mut text = String::from("i,j,view,class,x,y,z\n");
    for (view, sign) in [("bottom", -1.0), ("top", 1.0)] {
        for i in 0..20 {
            for j in 0..20 {
                let (x, y) = (s(i), j as f64 / 19.0);
                let border = i == 0 || j == 0 || i == 19 || j == 19;
                let pi = std::f64::consts::PI;
                let z = if border { 0.0 } else { sign * 0.3 * (pi * x).sin() * (pi * y).sin() };
                text.push_str(&format!("{i},{j},{view},0,{x:?},{y:?},{z:?}\n"));
            }
        }
    }
    text
}

#[test]
fn fit_refuses_surfaces_that_leave_the_data_naming_measured_alternatives() {
    let c = Case::new();
    c.write("scan.csv", &uneven_grid(0.1));
    // The defaults (chord length, Eq. 2.10's knots) at 18x18 leave the data between the rows.
    let args = ["fit", "--grid", "scan.csv", "--cn", "18x18", "--out", "f"];
    let out = c.run(&args);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(2), "{}", c.explain(&args, &out));
    assert!(!c.path("f").exists(), "nothing written: {err}");
    assert!(
        err.contains("scan.csv: between the data points") && err.contains("the bound is 10%"),
        "{err}"
    );
    assert!(err.contains("Nothing was written") && err.contains("--allow-excursion"), "{err}");
    // It names the centripetal parameterisation with its measured excursion, which is what a fit
    // with that option measures, within the bound.
    let line = err.lines().find(|l| l.trim_start().starts_with("--param centripetal")).expect(&err);
    let said: f64 = line.split_whitespace().nth(3).unwrap().parse().unwrap();
    c.ok(&["fit", "--grid", "scan.csv", "--cn", "18x18", "--param", "centripetal", "--out", "g"]);
    let (h, rows) = read_csv(&c.path("g/fit.csv"));
    let at =
        |name: &str| rows[0][h.iter().position(|x| x == name).unwrap()].parse::<f64>().unwrap();
    assert_eq!(format!("{said:.3e}"), format!("{:.3e}", at("excursion")), "{line}");
    let diagonal: f64 =
        err.split("its diagonal ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    assert!(
        (2f64.sqrt()..1.5).contains(&diagonal),
        "the map's box: x, y in [0, 1], z small: {err}"
    );
    assert!(at("excursion") <= 0.1 * diagonal && said > 0.0, "{line}");
    // The flag writes the surfaces, with the same block as a warning.
    let out = c.ok(&[&args[..], &["--allow-excursion"]].concat());
    assert!(String::from_utf8_lossy(&out.stderr).contains("Written anyway"));
    let (h, rows) = read_csv(&c.path("f/fit.csv"));
    let e: f64 = rows[0][h.iter().position(|x| x == "excursion").unwrap()].parse().unwrap();
    assert!(e > 0.1 * diagonal, "the written fit is the refused one: {e}");
}

const CH6_TINY: &str = r#"
name = "opt"
master_seed = 5
[optimise]
datasets = ["sphere"]
grid = "20x20"
control_nets = ["6x6", "8x8"]
parameterisations = ["chord_length"]
optimisers = ["ga", "de", "pso"]
repeats = 2
generations = 15
population = 8
[optimise.som]
iterations = 500
"#;

#[test]
fn chapter_6_is_deterministic_paired_and_each_cell_reruns_alone() {
    let c = Case::new();
    c.write("opt.toml", CH6_TINY);
    c.ok(&["run", "opt.toml", "--out", "j1", "--jobs", "1"]);
    c.ok(&["run", "opt.toml", "--out", "j2", "--jobs", "2"]);
    for f in ["runs.csv", "appendix_k.csv", "table_6_4.csv"] {
        assert_eq!(
            without_timing(&c.path("j1").join(f)),
            without_timing(&c.path("j2").join(f)),
            "{f}"
        );
    }
    let reference =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/reference/appendix_k.csv");
    assert_eq!(read_csv(&c.path("j1/appendix_k.csv")).0, read_csv(&reference).0);
    assert_eq!(
        read_csv(&c.path("j1/appendix_m.csv")).0,
        read_csv(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/reference/appendix_m.csv")
        )
        .0
    );
    let (h, rows) = read_csv(&c.path("j1/runs.csv"));
    assert_eq!(rows.len(), 2 * 3 * 2);
    let col = |n: &str| h.iter().position(|x| x == n).unwrap();
    for r in &rows {
        let (best, init): (f64, f64) =
            (r[col("best")].parse().unwrap(), r[col("initial_best")].parse().unwrap());
        assert!(best <= init, "{r:?}");
    }
    // Paired: every optimiser of a cell starts from the same B.
    for cn in ["6", "8"] {
        let bs: std::collections::BTreeSet<&str> =
            rows.iter().filter(|r| r[col("cn_x")] == cn).map(|r| r[col("b")].as_str()).collect();
        assert_eq!(bs.len(), 1);
    }
    // One optimiser alone gives the same numbers as inside the full run.
    c.write(
        "de.toml",
        &CH6_TINY.replace("optimisers = [\"ga\", \"de\", \"pso\"]", "optimisers = [\"de\"]"),
    );
    c.ok(&["run", "de.toml", "--out", "alone"]);
    let alone = without_timing(&c.path("alone/runs.csv"));
    let full: Vec<Vec<String>> = without_timing(&c.path("j1/runs.csv"))
        .into_iter()
        .filter(|r| r[col("optimiser")] == "de")
        .collect();
    assert_eq!(alone, full);
}

#[test]
fn bad_optimiser_specs_are_refused_before_any_run() {
    let c = Case::new();
    for (from, to, needles) in [
        (
            "optimisers = [\"ga\", \"de\", \"pso\"]",
            "optimisers = [\"ga\", \"sa\"]",
            &["opt.toml:", "unknown optimiser `sa` (expected ga, de, pso, csa, icsa"][..],
        ),
        ("population = 8", "population = -1", &["opt.toml:"]),
        ("iterations = 500", "iterations = 500\n[optimise.de]\ncr = 1.5", &["de.cr"]),
        (
            "iterations = 500",
            "iterations = 500\n[optimise.de]\ncrr = 1",
            &["table `de`: unknown field `crr`"],
        ),
        (
            "population = 8",
            "population = 8\npopulaton = 9",
            &["unknown field `populaton`: neither a key"],
        ),
        ("control_nets = [\"6x6\", \"8x8\"]", "control_nets = []", &["optimise.control_nets"]),
    ] {
        c.write("opt.toml", &CH6_TINY.replace(from, to));
        c.fails(&["run", "opt.toml", "--out", "o"], needles);
        assert!(
            !c.path("o/cells.jsonl").exists() && !c.path("o/maps").exists(),
            "{needles:?}: something ran"
        );
    }
}

/// A run of one cell (own problem, a few optimisers) is compared cell by cell; the tests over
/// cells, which need two, are skipped with a line saying so instead of failing.
#[test]
fn compare_of_one_cell_gives_the_per_cell_tests() {
    let c = Case::new();
    let one = CH6_TINY.replace("control_nets = [\"6x6\", \"8x8\"]", "control_nets = [\"6x6\"]");
    c.write("opt.toml", &one.replace("repeats = 2", "repeats = 6"));
    c.ok(&["run", "opt.toml", "--out", "o"]);
    let out = c.ok(&["compare", "o"]);
    assert!(String::from_utf8_lossy(&out.stdout)
        .contains("1 cell(s) that every optimiser ran: the tests over cells"));
    let (_, rows) = read_csv(&c.path("o/compare/compare_cells.csv"));
    assert_eq!(rows.len(), 3, "three pairs of optimisers in the one cell");
    assert!(!c.path("o/compare/compare_overall.csv").exists());
}

#[test]
fn compare_writes_statistics_and_refuses_bad_folders() {
    let c = Case::new();
    c.write("opt.toml", &CH6_TINY.replace("repeats = 2", "repeats = 6"));
    c.ok(&["run", "opt.toml", "--out", "o"]);
    let out = c.ok(&["compare", "o"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("Friedman over 2 cells x 3 optimisers"));
    let (h, rows) = read_csv(&c.path("o/compare/compare_cells.csv"));
    assert_eq!(rows.len(), 2 * 3);
    let p = h.iter().position(|x| x == "rank_sum_p").unwrap();
    assert!(rows.iter().all(|r| (0.0..=1.0).contains(&r[p].parse::<f64>().unwrap())));
    // A12 by direction (minimisation) and the per-cell summaries: a12_x_better > 0.5 goes with a
    // smaller median of x unless the medians tie; `better` names a side and its grounds.
    let col = |n: &str| h.iter().position(|x| x == n).unwrap_or_else(|| panic!("no {n}"));
    for r in &rows {
        let a: f64 = r[col("a12_x_better")].parse().unwrap();
        let (mx, my): (f64, f64) =
            (r[col("median_x")].parse().unwrap(), r[col("median_y")].parse().unwrap());
        assert!((0.0..=1.0).contains(&a), "{r:?}");
        if a == 1.0 {
            assert!(mx < my && r[col("better")] == "x", "{r:?}");
        }
        assert!(r[col("mean_x")].parse::<f64>().is_ok() && r[col("mean_y")].parse::<f64>().is_ok());
        assert!(["x", "y", "none"].contains(&r[col("better")].as_str()), "{r:?}");
        assert!(!r[col("better_by")].is_empty());
        // Six repeats: 2/2^6 = 0.03125 and 2/C(12, 6) reach 0.05.
        assert_eq!(
            (r[col("min_p_signed_rank")].as_str(), r[col("can_reach_alpha")].as_str()),
            ("0.031250", "both")
        );
    }
    assert!(!String::from_utf8_lossy(&out.stderr).contains("cannot reach alpha"));
    let (oh, overall) = read_csv(&c.path("o/compare/compare_overall.csv"));
    assert_eq!(overall.len(), 3);
    let t = oh.iter().position(|x| x == "cells_rank_sum_can_reach_alpha").unwrap();
    assert!(overall.iter().all(|r| r[t] == "2"), "{overall:?}");
    assert!(c.path("o/compare/cd_diagram.png").exists());
    c.fails(&["compare", "missing"], &["missing/runs.csv"]);
    let text = std::fs::read_to_string(c.path("o/runs.csv")).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[3] = lines[3].replacen(",", ",,", 1);
    c.write("bad/runs.csv", &lines.join("\n"));
    c.fails(&["compare", "bad"], &["bad/runs.csv", "line 4"]);
}

/// Issue 18: the IOHprofiler export (JSON keys the readers require, .dat from evaluation 1), and
/// compare's Bayesian table and runtime distributions (ECDF non-decreasing in [0, 1], AOCC in
/// [0, 1], ERT hits within runs), no negative zero, and refusals (bad rope, stale traces).
#[test]
fn compare_writes_runtime_distributions_and_bayesian_table() {
    let c = Case::new();
    c.write("opt.toml", &CH6_TINY.replace("repeats = 2", "repeats = 3"));
    c.ok(&["run", "opt.toml", "--out", "o"]);
    let ioh = c.path("o/ioh/de");
    let json = std::fs::read_dir(&ioh)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| p.extension().is_some_and(|x| x == "json"))
        .unwrap();
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    for k in [
        "version",
        "suite",
        "function_id",
        "function_name",
        "maximization",
        "algorithm",
        "attributes",
        "scenarios",
    ] {
        assert!(v.get(k).is_some(), "{k}");
    }
    assert!(!std::fs::read_dir(&ioh)
        .unwrap()
        .flatten()
        .any(|e| e.path().extension().is_some_and(|x| x == "info")));
    let dat = ioh.join(v["scenarios"][0]["path"].as_str().unwrap());
    let text = std::fs::read_to_string(&dat).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let starts: Vec<&str> =
        lines.windows(2).filter(|w| w[0] == "evaluations raw_y").map(|w| w[1]).collect();
    assert_eq!(starts.len(), 3);
    assert!(starts.iter().all(|l| l.starts_with("1 ")), "{starts:?}");
    let out = c.ok(&["compare", "o", "--bayes-samples", "2000"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("Bayesian signed-rank"));
    // Three repeats: no test can reach 0.05 (2/2^3 = 0.25, 2/C(6, 3) = 0.1): one warning line.
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.matches("cannot reach alpha 0.05").count(), 1, "{err}");
    let (h, rows) = read_csv(&c.path("o/compare/compare_cells.csv"));
    let col = |n: &str| h.iter().position(|x| x == n).unwrap_or_else(|| panic!("no {n}"));
    for r in &rows {
        assert_eq!(
            (
                r[col("min_p_signed_rank")].as_str(),
                r[col("min_p_rank_sum")].as_str(),
                r[col("can_reach_alpha")].as_str(),
                r[col("h_rank_sum")].as_str()
            ),
            ("0.250000", "0.100000", "neither", "0"),
            "{r:?}"
        );
    }
    let (h, rows) = read_csv(&c.path("o/compare/compare_bayes.csv"));
    assert_eq!(rows.len(), 3);
    let col = |n: &str| h.iter().position(|x| x == n).unwrap();
    for r in &rows {
        let s: f64 = ["p_x_better", "p_rope", "p_y_better"]
            .iter()
            .map(|k| r[col(k)].parse::<f64>().unwrap())
            .sum();
        assert!((s - 1.0).abs() < 1e-3, "{r:?}");
    }
    let (h, rows) = read_csv(&c.path("o/compare/compare_ecdf.csv"));
    let (g, o, e) = (
        h.iter().position(|x| x == "group").unwrap(),
        h.iter().position(|x| x == "optimiser").unwrap(),
        h.iter().position(|x| x == "ecdf").unwrap(),
    );
    assert!(rows.iter().any(|r| r[g] == "all"));
    assert!(rows.iter().filter(|r| r[g] != "all").count() > 0);
    for w in rows.windows(2).filter(|w| w[0][g] == w[1][g] && w[0][o] == w[1][o]) {
        let (a, b): (f64, f64) = (w[0][e].parse().unwrap(), w[1][e].parse().unwrap());
        assert!((0.0..=1.0).contains(&a) && a <= b, "{w:?}");
    }
    // "all" weighs problems equally: at every budget its ECDF is the mean of the problems' ECDFs.
    let (w, pr) = (
        h.iter().position(|x| x == "weighting").unwrap(),
        h.iter().position(|x| x == "problems").unwrap(),
    );
    let ev = h.iter().position(|x| x == "evaluations").unwrap();
    for r in rows.iter().filter(|r| r[g] == "all") {
        assert_eq!(r[w], "problems_equal");
        let per: Vec<f64> = rows
            .iter()
            .filter(|x| x[g] != "all" && x[o] == r[o] && x[ev] == r[ev])
            .map(|x| x[e].parse().unwrap())
            .collect();
        assert_eq!(per.len().to_string(), r[pr]);
        let mean = per.iter().sum::<f64>() / per.len() as f64;
        assert!((mean - r[e].parse::<f64>().unwrap()).abs() < 2e-6, "{r:?} {per:?}");
    }
    let (h, rows) = read_csv(&c.path("o/compare/compare_aocc.csv"));
    let a = h.iter().position(|x| x == "aocc").unwrap();
    assert!(rows.iter().all(|r| (0.0..=1.0).contains(&r[a].parse::<f64>().unwrap())));
    // Every problem states its targets' rule; a fixed-budget gap is a number or left out with a
    // note, never a 0 standing for a zero denominator.
    let (h, rows) = read_csv(&c.path("o/compare/compare_targets.csv"));
    let (ru, nt) = (
        h.iter().position(|x| x == "rule").unwrap(),
        h.iter().position(|x| x == "n_targets").unwrap(),
    );
    for r in &rows {
        let rule = r[ru].as_str();
        assert!(
            ["b_to_best_known", "best_first_to_best_known", "worst_first_to_best_known", "none"]
                .contains(&rule),
            "{r:?}"
        );
        assert_eq!(r[nt], if rule == "none" { "1" } else { "16" }, "{r:?}");
    }
    let (h, rows) = read_csv(&c.path("o/compare/compare_fixed_budget.csv"));
    let (v, note) = (
        h.iter().position(|x| x == "mean_normalised_gap").unwrap(),
        h.iter().position(|x| x == "note").unwrap(),
    );
    for r in rows.iter().filter(|r| r[0] != "all") {
        assert_eq!(r[v].is_empty(), !r[note].is_empty(), "{r:?}");
    }
    let (h, rows) = read_csv(&c.path("o/compare/compare_ert.csv"));
    let (hi, ru) =
        (h.iter().position(|x| x == "hits").unwrap(), h.iter().position(|x| x == "runs").unwrap());
    assert!(rows
        .iter()
        .all(|r| r[hi].parse::<usize>().unwrap() <= r[ru].parse::<usize>().unwrap()));
    assert!(
        c.path("o/compare/compare_ecdf_all.png").exists()
            && c.path("o/compare/compare_fixed_budget_all.png").exists()
    );
    for f in [
        "compare_cells",
        "compare_overall",
        "compare_bayes",
        "compare_ecdf",
        "compare_aocc",
        "compare_fixed_budget",
        "compare_ert",
    ] {
        let (_, rows) = read_csv(&c.path(&format!("o/compare/{f}.csv")));
        assert!(
            !rows.iter().flatten().any(|x| x.starts_with('-') && x[1..].parse::<f64>() == Ok(0.0)),
            "{f}: negative zero"
        );
    }
    c.fails(&["compare", "o", "--rope=-1"], &["--rope"]);
    // Traces that do not match runs.csv are refused, naming the folder.
    std::fs::write(&dat, text.replacen("evaluations raw_y\n", "", 1)).unwrap();
    c.fails(&["compare", "o"], &["ioh/de"]);
}

#[test]
fn exact_optimum_bounds_every_run_from_below() {
    let c = Case::new();
    c.write(
        "opt.toml",
        &CH6_TINY.replace("[optimise.som]", "exact = true\ninit_range = 1e-3\n[optimise.som]"),
    );
    c.ok(&["run", "opt.toml", "--out", "o"]);
    let (h, rows) = read_csv(&c.path("o/exact_20x20.csv"));
    let col = |n: &str| h.iter().position(|x| x == n).unwrap();
    let (_, runs) = read_csv(&c.path("o/runs.csv"));
    let (rh, _) = read_csv(&c.path("o/runs.csv"));
    let best = rh.iter().position(|x| x == "best").unwrap();
    let cn = rh.iter().position(|x| x == "cn_x").unwrap();
    for r in &rows {
        let (f, lb): (f64, f64) =
            (r[col("exact_f")].parse().unwrap(), r[col("lower_bound")].parse().unwrap());
        let b: f64 = r[col("b")].parse().unwrap();
        assert!(lb <= f && f <= b, "{r:?}");
        for run in runs.iter().filter(|x| x[cn] == r[col("cn_x")]) {
            assert!(
                run[best].parse::<f64>().unwrap() >= lb,
                "{run:?} beats the certified bound {lb}"
            );
        }
    }
}

/// The readings matrix: a plan's reading set runs a spec again with its keys changed, from the
/// same maps; readings.csv holds every claim under both readings, runs.csv records the readings
/// and the dense excursion, which shows the NURBS Book knots blowing up an 18x18 net on a 20x20
/// map while Eq. 2.10's stay near the data.
#[test]
fn readings_matrix_runs_each_reading_set_and_sets_claims_side_by_side() {
    let c = Case::new();
    c.write("specs/maps.toml", CH4_FOR_FIT);
    c.write(
        "specs/fits.toml",
        &CH5_TINY
            .replace("MAPS", "unused")
            .replace(r#"["6x6", "12x12"]"#, r#"["6x6", "12x12", "18x18"]"#),
    );
    c.write(
        "specs/p.toml",
        r#"specs = ["maps", "fits"]
maps_from = "maps"
reading = "eq2_10"
[[readings]]
name = "nurbs_book"
description = "the old reading"
set = { "fit.knots" = "nurbs_book", "fit.error_a" = "nov_bottom" }
specs = ["fits"]
"#,
    );
    c.ok(&["reproduce", "--specs", "specs", "--plan", "p", "--out", "out"]);
    // Re-run lines: the plan's command with its --specs and --out, in the sub-reports too.
    let rerun = "Re-run: `somnurbs reproduce --plan p --profile full --specs specs --out out`";
    for r in ["out/REPORT.md", "out/fits/REPORT.md", "out/readings/nurbs_book/fits/REPORT.md"] {
        assert!(std::fs::read_to_string(c.path(r)).unwrap().contains(rerun), "{r}");
    }
    let (h, rows) = read_csv(&c.path("out/readings.csv"));
    let col = |name: &str| h.iter().position(|x| x == name).unwrap();
    let claims_of = |reading: &str| -> Vec<String> {
        rows.iter()
            .filter(|r| r[col("reading")] == reading)
            .map(|r| r[col("claim")].clone())
            .collect()
    };
    assert!(!claims_of("eq2_10").is_empty());
    assert_eq!(claims_of("eq2_10"), claims_of("nurbs_book"), "every claim under both readings");
    let max_excursion = |path: &str, knots: &str| -> f64 {
        let (h, rows) = read_csv(&c.path(path));
        let (k, e, cn) = (
            h.iter().position(|x| x == "knots").unwrap(),
            h.iter().position(|x| x == "excursion").unwrap(),
            h.iter().position(|x| x == "cn_x").unwrap(),
        );
        assert!(rows.iter().all(|r| r[k] == knots), "{path} records its knot reading");
        rows.iter()
            .filter(|r| r[cn] == "18")
            .map(|r| r[e].parse::<f64>().unwrap())
            .fold(0.0, f64::max)
    };
    let faithful = max_excursion("out/fits/runs.csv", "eq2_10");
    let old = max_excursion("out/readings/nurbs_book/fits/runs.csv", "nurbs_book");
    assert!(
        faithful < 0.1 && old > 10.0 * faithful.max(0.01),
        "eq2_10 {faithful}, nurbs_book {old}"
    );
    let report = std::fs::read_to_string(c.path("out/REPORT.md")).unwrap();
    assert!(report.contains("# Readings matrix") && report.contains("`nurbs_book`"));
    // A reading set naming a spec the plan does not have is refused before anything runs.
    c.write("specs/bad.toml", "specs = [\"fits\"]\n[[readings]]\nname = \"x\"\nset = { \"fit.knots\" = \"nurbs_book\" }\nspecs = [\"nope\"]\n");
    let out = c.run(&["reproduce", "--specs", "specs", "--plan", "bad", "--out", "bad_out"]);
    assert_eq!(out.status.code(), Some(2), "{}", c.explain(&["reproduce"], &out));
    assert!(String::from_utf8_lossy(&out.stderr).contains("readings.x.specs: `nope`"));
    assert!(!c.path("bad_out").exists());
    // A bad value under a reading set names the key.
    c.write("specs/badv.toml", "specs = [\"fits\"]\n[[readings]]\nname = \"x\"\nset = { \"fit.knots\" = \"9.69\" }\nspecs = [\"fits\"]\n");
    let out = c.run(&["reproduce", "--specs", "specs", "--plan", "badv", "--out", "bad_out"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("fit.knots") && err.contains("9.69"), "{err}");
}

/// Output piped into a reader that stops early ends the program quietly (SIGPIPE), not in a panic.
#[test]
fn a_closed_pipe_on_stdout_is_not_a_panic() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut child = crate::common::bin()
        .args(["run", "--dry-run"])
        .arg(root.join("experiments/ch6_same.toml"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // 4,200 cell lines are more than a pipe holds: the reader goes away before they are written.
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert_ne!(out.status.code(), Some(101), "{err}");
}

#[test]
fn the_optimise_report_states_the_spec_s_own_start() {
    let c = Case::new();
    c.write("d.toml", &SPEC.replace("repeats = 2", "repeats = 1\ninit_range = 1e-3"));
    c.ok(&["run", "d.toml", "--out", "r"]);
    let report = std::fs::read_to_string(c.path("r/REPORT.md")).unwrap();
    assert!(report.contains("the +-1e-3 start can leave an optimiser above B"), "{report}");
    assert!(!report.contains("5e-6"), "no number of the thesis plan's: {report}");
    // A search box of the spec's own is named as the spec's, not as the thesis' reading.
    let spec = SPEC.replace("repeats = 2", "repeats = 1\ninit_range = 1e-3\nsearch_range = 1e-3");
    c.write("e.toml", &spec);
    c.ok(&["run", "e.toml", "--out", "s"]);
    let report = std::fs::read_to_string(c.path("s/REPORT.md")).unwrap();
    assert!(
        report.contains("the search box is B +- 1e-3 per coordinate (the spec's `search_range`"),
        "{report}"
    );
    assert!(!report.contains("read as the search space"), "{report}");
}
