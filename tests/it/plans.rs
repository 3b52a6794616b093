//! Plans and the keys that change a spec: a plan reads only the specs in its own folder, a
//! reading set changes every spec it lists and nothing else, a key is given once under one of its
//! spellings, and a former section name works in every place a key is written, with its note.
//! Also the inputs `fit` and `datasets` read beside a spec: a map's frame and a path that is no
//! regular file.

use crate::common::{Case, CH4_FOR_FIT, SPEC};
use std::time::{Duration, Instant};

/// A command refused before anything is written: one line naming every `needle`, exit 2, and no
/// folder `out` made.
fn refused(c: &Case, args: &[&str], out: &str, needles: &[&str]) -> String {
    let err = c.fails(args, needles);
    let run = c.run(args);
    assert_eq!(run.status.code(), Some(2), "{}", c.explain(args, &run));
    assert!(err.starts_with("somnurbs: error: "), "{err}");
    assert!(!c.path(out).exists(), "{}", c.explain(args, &run));
    err
}

/// `reproduce --plan NAME` of the plans under `specs/` into `o`.
fn plan(name: &str) -> [&str; 7] {
    ["reproduce", "--specs", "specs", "--plan", name, "--out", "o"]
}

/// The specs `specs/d.toml` (an `[optimise]` spec) and `specs/maps.toml` (a `[som]` spec).
fn two_families() -> Case {
    let c = Case::new();
    c.write("specs/d.toml", SPEC);
    c.write("specs/maps.toml", CH4_FOR_FIT);
    c
}

/// A plan of the specs `d` and `maps` with one reading set `r` of `set` (a TOML inline table)
/// over `specs` (a TOML array).
fn with_set(set: &str, specs: &str) -> String {
    format!("specs = [\"maps\", \"d\"]\n[[readings]]\nname = \"r\"\nset = {set}\nspecs = {specs}\n")
}

#[test]
fn a_reading_set_must_change_every_spec_it_lists_with_every_key() {
    let c = two_families();
    // No key of the set reaches its one spec: it would run an unchanged copy as a reading.
    c.write("specs/none.toml", &with_set("{ \"fit.knots\" = \"nurbs_book\" }", "[\"d\"]"));
    refused(
        &c,
        &plan("none"),
        "o",
        &["none.toml: readings.r.set: `fit.knots` changes none of the set's specs (d: [optimise])"],
    );
    // Two keys that reach none, named together.
    c.write(
        "specs/two.toml",
        &with_set("{ \"fit.knots\" = \"nurbs_book\", \"growing_grid.repeats\" = 2 }", "[\"d\"]"),
    );
    refused(
        &c,
        &plan("two"),
        "o",
        &["readings.r.set: `fit.knots`, `growing_grid.repeats` change none of the set's specs"],
    );
    // One key reaches the set's specs, another none of them.
    c.write(
        "specs/some.toml",
        &with_set("{ \"som.iterations\" = 200, \"fit.knots\" = \"nurbs_book\" }", "[\"maps\"]"),
    );
    refused(&c, &plan("some"), "o", &["some.toml: readings.r.set: `fit.knots` changes none"]);
    // Every key reaches a spec, but one listed spec would run as written.
    c.write("specs/idle.toml", &with_set("{ \"som.iterations\" = 200 }", "[\"maps\", \"d\"]"));
    refused(
        &c,
        &plan("idle"),
        "o",
        &["idle.toml: readings.r.specs: none of the set's keys changes `d` (its section is [optimise]), so it would run as written"],
    );
}

#[test]
fn a_reading_set_with_no_specs_is_refused() {
    let c = two_families();
    c.write("specs/empty.toml", &with_set("{ \"som.iterations\" = 200 }", "[]"));
    refused(
        &c,
        &plan("empty"),
        "o",
        &["empty.toml: readings.r.specs: is empty; list the plan's specs this set runs again (e.g. specs = [\"maps\"])"],
    );
}

#[test]
fn one_key_under_its_former_and_present_name_is_refused_everywhere() {
    let c = two_families();
    c.write(
        "specs/both.toml",
        &with_set("{ \"optim.generations\" = 10, \"optimise.generations\" = 12 }", "[\"d\"]"),
    );
    refused(
        &c,
        &plan("both"),
        "o",
        &["both.toml: readings.r.set: `optim.generations` and `optimise.generations` are one key ([optim] is the former name of [optimise]); give it once"],
    );
    let both =
        "`optim.de.f` and `optimise.de.f` are one key ([optim] is the former name of [optimise])";
    for args in [
        ["--set", "optim.de.f=0.5", "--set", "optimise.de.f=0.6"],
        ["--set", "optim.de.f=0.5", "--sweep", "optimise.de.f=0.6,0.7"],
        ["--sweep", "optimise.de.f=0.5,0.6", "--sweep", "optim.de.f=0.6,0.7"],
    ] {
        let mut run = vec!["run", "specs/d.toml", "--out", "o"];
        run.extend(args);
        refused(&c, &run, "o", &[both]);
        run.push("--dry-run");
        refused(&c, &run, "o", &[both]);
    }
}

#[test]
fn a_plan_reads_no_spec_outside_its_folder() {
    let c = two_families();
    // The files these names would have read are there: only the rule refuses them.
    c.write("x.toml", SPEC);
    let outside = c.path("x").display().to_string();
    c.write("specs/up.toml", "title = \"t\"\nspecs = [\"d\",\n  \"../x\"]\n");
    refused(
        &c,
        &plan("up"),
        "o",
        &["up.toml:3: specs: `../x` holds a folder part; a plan runs only the specs in its own folder, each named by its file name without .toml"],
    );
    c.write("specs/abs.toml", &format!("specs = [\"{outside}\"]\n"));
    refused(&c, &plan("abs"), "o", &["abs.toml:1: specs: `", "` is an absolute path;"]);
    c.write("specs/sub/y.toml", SPEC);
    c.write("specs/sub.toml", "specs = [\"sub/y\"]\n");
    refused(&c, &plan("sub"), "o", &["sub.toml:1: specs: `sub/y` holds a folder part"]);
    c.write("specs/dots.toml", "specs = [\"..\"]\n");
    refused(&c, &plan("dots"), "o", &["dots.toml:1: specs: `..` is a folder"]);
}

/// The note a former section name makes, as the binary prints it.
fn notes(stderr: &[u8]) -> usize {
    String::from_utf8_lossy(stderr).matches("[optim] is now called [optimise]").count()
}

#[test]
fn a_former_section_name_works_in_set_and_sweep_keys_with_one_note() {
    let c = two_families();
    let dry = |extra: &[&str]| {
        let mut args = vec!["run", "specs/d.toml", "--dry-run"];
        args.extend(extra);
        c.ok(&args)
    };
    // --sweep takes the former name as --set does: the same variants, one note.
    let old = dry(&["--sweep", "optim.de.f=0.3,0.5", "--sweep", "optim.generations=10,12"]);
    let new = dry(&["--sweep", "optimise.de.f=0.3,0.5", "--sweep", "optimise.generations=10,12"]);
    let lines = |o: &std::process::Output| String::from_utf8_lossy(&o.stdout).lines().count();
    assert_eq!(lines(&old), lines(&new));
    // Four cells per variant, four variants.
    assert!(lines(&old) >= 4 * 4, "{}", String::from_utf8_lossy(&old.stdout));
    assert_eq!(notes(&old.stderr), 1, "{}", String::from_utf8_lossy(&old.stderr));
    assert_eq!(notes(&new.stderr), 0);
    assert!(String::from_utf8_lossy(&old.stderr).contains("somnurbs: note: --set/--sweep: [optim]"));
    // A former name that is not a sweepable key is refused as the present one is.
    c.fails(
        &["run", "specs/d.toml", "--dry-run", "--sweep", "optim.grid=20x20,10x10"],
        &["--sweep optim.grid: a sweep varies optimiser settings only"],
    );
    let set = dry(&["--set", "optim.de.f=0.5", "--set", "optim.de.cr=0.5"]);
    assert_eq!(notes(&set.stderr), 1, "{}", String::from_utf8_lossy(&set.stderr));
    assert_eq!(notes(&dry(&["--set", "optimise.de.f=0.5"]).stderr), 0);
}

#[test]
fn a_reading_set_key_with_a_former_name_runs_with_one_note() {
    let c = two_families();
    c.write(
        "specs/old.toml",
        "specs = [\"d\"]\n[[readings]]\nname = \"r\"\nset = { \"optim.generations\" = 10, \"optim.population\" = 6 }\nspecs = [\"d\"]\n",
    );
    let out = c.ok(&plan("old"));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(notes(&out.stderr), 1, "{err}");
    assert!(err.contains("old.toml: [optim] is now called [optimise]"), "{err}");
    // The reading's runs are the smaller ones its keys ask for.
    let evaluations = |path: &str| -> Vec<u64> {
        let (h, rows) = crate::common::read_csv(&c.path(path));
        let e = crate::common::col(&h, "evaluations");
        rows.iter().map(|r| r[e].parse().unwrap()).collect()
    };
    let (plain, reading) = (evaluations("o/d/runs.csv"), evaluations("o/readings/r/d/runs.csv"));
    assert_eq!(plain.len(), reading.len());
    assert!(reading.iter().zip(&plain).all(|(r, p)| r < p), "{reading:?} against {plain:?}");
}

/// A map's frame whose scale or offset would map the exports wrongly is refused by `fit`.
#[test]
fn fit_refuses_a_frame_with_a_zero_or_non_finite_scale() {
    let c = Case::new();
    let mut grid = String::from("i,j,view,class,x,y,z\n");
    for (v, view) in ["bottom", "top"].iter().enumerate() {
        for i in 0..6 {
            for j in 0..6 {
                let h = 0.01 * (i * (5 - i) * j * (5 - j)) as f64;
                let z = if v == 0 { -h } else { h };
                grid.push_str(&format!(
                    "{i},{j},{view},0,{},{},{z}\n",
                    i as f64 / 5.0,
                    j as f64 / 5.0
                ));
            }
        }
    }
    c.write("g.csv", &grid);
    let frame = |offset: &str, scale: &str| {
        format!("dataset = \"g\"\nsource = \"generated\"\nnormalise = \"per_axis\"\noffset = {offset}\nscale = {scale}\n")
    };
    let fit = ["fit", "--grid", "g.csv", "--cn", "4x4", "--out", "o"];
    for (offset, scale, key) in [
        ("[0, 0, 0]", "[0, 0, 0]", "scale: the x scale is 0;"),
        ("[0, 0, 0]", "[2.0, 0.0, 1.0]", "scale: the y scale is 0;"),
        ("[0, 0, 0]", "[1.0, 1.0, -3.0]", "scale: the z scale is -3;"),
        ("[0, 0, 0]", "[1.0, nan, 1.0]", "scale: the y scale is NaN;"),
        ("[0, inf, 0]", "[1.0, 1.0, 1.0]", "offset: the y offset is inf;"),
    ] {
        c.write("g.frame.toml", &frame(offset, scale));
        refused(&c, &fit, "o", &["g.frame.toml: ", key]);
    }
    c.write("g.frame.toml", &frame("[10, 20, 30]", "[2, 2, 2]"));
    c.ok(&fit);
    let (h, nets) = crate::common::read_csv(&c.path("o/control_nets.csv"));
    let x = crate::common::col(&h, "x");
    assert!(nets.iter().all(|r| r[x].parse::<f64>().unwrap() >= 9.0), "in the data's frame");
}

/// Runs `datasets show PATH` and gives up (killing it) after 20 s, so that a reader that
/// blocked on a FIFO fails the test instead of hanging it.
fn show(c: &Case, path: &str) -> (Option<i32>, String) {
    let mut child = crate::common::bin()
        .args(["datasets", "show", path])
        .current_dir(c.dir.path())
        .env("SOMNURBS_DATA", crate::common::data_dir())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(20) {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("datasets show {path} blocked");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn datasets_show_names_what_a_path_is_and_no_spec() {
    let c = Case::new();
    std::fs::create_dir(c.path("scans.xyz")).unwrap();
    std::os::unix::fs::symlink("/dev/null", c.path("null.ply")).unwrap();
    let fifo = std::ffi::CString::new(c.path("pipe.xyz").display().to_string()).unwrap();
    // SAFETY: a valid NUL-terminated path; mkfifo only creates the FIFO, nothing opens it.
    assert_eq!(unsafe { libc::mkfifo(fifo.as_ptr(), 0o600) }, 0);
    for (path, kind) in
        [("scans.xyz", "a folder"), ("null.ply", "a device"), ("pipe.xyz", "a FIFO (named pipe)")]
    {
        let (code, err) = show(&c, path);
        assert_eq!(code, Some(2), "{path}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(&format!("{path} is {kind}, not a data file")), "{err}");
        assert!(!err.contains("spec") && !err.contains("not found"), "{err}");
    }
    let (code, err) = show(&c, "none.xyz");
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("none.xyz: data file not found") && !err.contains("spec"), "{err}");
}
