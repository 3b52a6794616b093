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

/// Runs `args` in the case folder, sends SIGINT once `ready` (a file) exists, and returns the
/// exit code and stderr.
fn interrupted(c: &Case, args: &[&str], ready: &str) -> (Option<i32>, String) {
    use std::time::{Duration, Instant};
    let child = bin()
        .args(args)
        .current_dir(c.dir.path())
        .env("SOMNURBS_DATA", data_dir())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while !c.path(ready).exists() {
        assert!(t0.elapsed() < Duration::from_secs(120), "{ready} never appeared");
        std::thread::sleep(Duration::from_millis(20));
    }
    // SAFETY: kill(2) on the child's own pid.
    assert_eq!(unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) }, 0);
    let out = child.wait_with_output().unwrap();
    (out.status.code(), String::from_utf8_lossy(&out.stderr).to_string())
}

#[test]
fn sigint_says_how_to_resume_and_exits_130() {
    let c = Case::new();
    // Ten times SLOW's generations: the run is still going when the signal comes.
    let slower = SLOW.replace("generations = 600", "generations = 6000");
    c.write("slow.toml", &slower);
    let args = ["run", "slow.toml", "--out", "my run", "--jobs", "1"];
    let (code, err) = interrupted(&c, &args, "my run/cells.jsonl");
    assert_eq!(code, Some(130), "{err}");
    let want =
        "somnurbs: interrupted; continue with: somnurbs run slow.toml --out 'my run' --resume";
    assert_eq!(err.lines().last(), Some(want), "{err}");
    assert!(!c.path("my run/manifest.toml").exists());
    // reproduce names its plan and profile.
    c.write("plans/p.toml", "specs = [\"slow\"]\n");
    c.write("plans/slow.toml", &slower);
    let args = ["reproduce", "--specs", "plans", "--plan", "p", "--out", "r", "--jobs", "1"];
    let (code, err) = interrupted(&c, &args, "r/slow/cells.jsonl");
    assert_eq!(code, Some(130), "{err}");
    let want = "somnurbs: interrupted; continue with: somnurbs reproduce --plan p --profile full --specs plans --out r --resume";
    assert_eq!(err.lines().last(), Some(want), "{err}");
}

/// A Chapter 4 folder `maps` with a saved 20x20 map, and `fit` folders from it.
fn maps_and_fit(c: &Case, fits: &[(&str, &str)]) {
    c.write("maps.toml", CH4_FOR_FIT);
    c.ok(&["run", "maps.toml", "--out", "maps"]);
    for (out, cn) in fits {
        c.ok(&["fit", "--grid", "maps/maps/dnsom_sphere_20x20.csv", "--cn", cn, "--out", out]);
    }
}

#[test]
fn compare_says_what_a_folder_is_when_it_is_no_chapter_6_run() {
    let c = Case::new();
    maps_and_fit(&c, &[("F", "8x8")]);
    let takes = "compare takes the folder of a finished run of a spec with an [optimise] section";
    c.fails(
        &["compare", "F"],
        &["F is a `somnurbs fit` folder, not a Chapter 6 (optimise) run", takes],
    );
    c.fails(
        &["compare", "maps"],
        &["maps is a run of spec maps ([som], Chapter 4), not a Chapter 6 (optimise) run", takes],
    );
    assert!(!c.path("F/compare").exists() && !c.path("maps/compare").exists());
}

#[test]
fn drift_refuses_other_runs_naming_both_folders_and_what_differs() {
    let c = Case::new();
    c.write("d.toml", SPEC);
    c.write("e.toml", &SPEC.replace("master_seed = 3", "master_seed = 4"));
    c.ok(&["run", "d.toml", "--out", "plain"]);
    c.ok(&["run", "d.toml", "--out", "set", "--set", "optimise.de.f=0.5"]);
    c.ok(&["run", "e.toml", "--out", "seed"]);
    let needles = [
        "plain and set hold different runs (--set none vs optimise.de.f=0.5)",
        "--allow-spec-change",
    ];
    c.fails(&["drift", "plain", "set"], &needles);
    c.fails(
        &["drift", "plain", "seed"],
        &["plain and seed hold different runs (", "master seed 3 vs 4"],
    );
    let err = c.fails(&["drift", "plain", "seed"], &[]);
    assert!(!err.contains(": .:") && !err.contains("error: ."), "{err}");
    assert!(!c.path("drift.csv").exists());
    let out = c.run(&["drift", "plain", "set", "--allow-spec-change"]);
    assert_eq!(out.status.code(), Some(1), "{}", c.explain(&["drift"], &out));
}

#[test]
fn fit_and_specs_take_one_spelling_per_value() {
    let c = Case::new();
    maps_and_fit(&c, &[]);
    let grid = "maps/maps/dnsom_sphere_20x20.csv";
    let fit = |extra: &[&str], needles: &[&str]| {
        let mut args = vec!["fit", "--grid", grid, "--out", "F"];
        args.extend_from_slice(extra);
        if !extra.contains(&"--cn") {
            args.extend_from_slice(&["--cn", "8x8"]);
        }
        c.fails(&args, needles);
        assert!(!c.path("F").exists());
    };
    fit(&["--cn", "18"], &["--cn", "`18` is not a grid size (write NXxNY"]);
    let params = "(expected uniform, chord_length, centripetal or exponential)";
    fit(&["--param", "chordal"], &["--param", "unknown parameterisation `chordal`", params]);
    fit(&["--param", "Chord-Length"], &["--param", "`Chord-Length`", params]);
    fit(&["--approach", "b"], &["--approach", "expected A/conventional or B/improved"]);
    // A spec is read the same way.
    let spec = SPEC.replace("\"chord_length\"", "\"chordal\"");
    c.write("p.toml", &spec);
    c.fails(&["run", "p.toml", "--dry-run"], &["p.toml:8", "`chordal`", params]);
    c.write("g.toml", &SPEC.replace("grid = \"20x20\"", "grid = 20"));
    c.fails(&["run", "g.toml", "--dry-run"], &["g.toml", "20 is not a grid size", "\"20x20\""]);
}

#[test]
fn a_fit_folder_has_a_real_iges_date_and_a_manifest_of_what_fit_did() {
    let c = Case::new();
    maps_and_fit(&c, &[]);
    let args = ["fit", "--grid", "maps/maps/dnsom_sphere_20x20.csv", "--cn", "8x8", "--out", "F"];
    let out = bin()
        .args(args)
        .current_dir(c.dir.path())
        .env("SOURCE_DATE_EPOCH", "1709251199")
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", c.explain(&args, &out));
    let iges = std::fs::read_to_string(c.path("F/surfaces.igs")).unwrap();
    let global: String =
        iges.lines().filter(|l| &l[72..73] == "G").map(|l| l[..72].trim_end()).collect();
    assert!(global.contains(",15H20240229.235959,1.0E-9,"), "{global}");
    assert!(!global.contains(",1.0E-9,0.0,"), "the maximum coordinate is written: {global}");
    let m: toml::Table =
        toml::from_str(&std::fs::read_to_string(c.path("F/manifest.toml")).unwrap()).unwrap();
    assert_eq!(m["kind"].as_str(), Some("fit"));
    assert_eq!(m["grid"].as_str(), Some("maps/maps/dnsom_sphere_20x20.csv"));
    assert_eq!(m["grid_sha256"].as_str().map(str::len), Some(64));
    assert_eq!(m["generated_unix"].as_integer(), Some(1_709_251_199));
    for absent in ["spec_name", "master_seed", "profile"] {
        assert!(!m.contains_key(absent), "{absent} in {m:?}");
    }
    let o = m["options"].as_table().unwrap();
    for (k, v) in [
        ("cn", "8x8"),
        ("param", "chord_length"),
        ("approach", "B"),
        ("knots", "eq2_10"),
        ("error_a", "per_surface"),
        ("frame", "data"),
        ("units", "unknown"),
    ] {
        assert_eq!(o[k].as_str(), Some(v), "{k}");
    }
    assert_eq!(o["fairness"].as_float(), Some(0.0));
    // A bad SOURCE_DATE_EPOCH is refused, naming it.
    let out = bin()
        .args(["fit", "--grid", "maps/maps/dnsom_sphere_20x20.csv", "--cn", "8x8", "--out", "G"])
        .current_dir(c.dir.path())
        .env("SOURCE_DATE_EPOCH", "yesterday")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("SOURCE_DATE_EPOCH: `yesterday`"));
    assert!(!c.path("G").exists());
    // Two fit folders: the same fit compares; another net is refused, a run beside a fit too.
    for (out, cn) in [("F1", "8x8"), ("F2", "8x8"), ("F3", "10x10")] {
        c.ok(&["fit", "--grid", "maps/maps/dnsom_sphere_20x20.csv", "--cn", cn, "--out", out]);
    }
    c.write("d.toml", SPEC);
    c.ok(&["run", "d.toml", "--out", "plain"]);
    c.ok(&["drift", "F1", "F2"]);
    c.fails(&["drift", "F1", "F3"], &["F1 and F3 hold different runs", "--cn"]);
    c.fails(
        &["drift", "F1", "plain"],
        &["F1 and plain hold different runs", "`somnurbs fit` folder vs a run of spec d"],
    );
}
