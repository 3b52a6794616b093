//! Issue 17: never lose, mix or misjudge a result; refuse every bad input cleanly. One test per
//! class of the issue, each with the reproduction commands and more.

use crate::common::*;
use std::process::Stdio;
use std::time::{Duration, Instant};

fn code(out: &std::process::Output) -> i32 {
    out.status.code().unwrap_or(-1)
}

/// Start a slow run in the background and wait until it holds its folder.
fn start_slow(c: &Case, spec: &str, out: &str) -> std::process::Child {
    let child = bin()
        .args(["run", spec, "--out", out, "--jobs", "1"])
        .current_dir(c.dir.path())
        .env("SOMNURBS_DATA", data_dir())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let lock = c.path(&format!("{out}/.somnurbs.lock"));
    let t0 = Instant::now();
    while !std::fs::read_to_string(&lock)
        .unwrap_or_default()
        .contains(&format!("pid = {}", child.id()))
    {
        assert!(t0.elapsed() < Duration::from_secs(30), "the run never took its lock");
        std::thread::sleep(Duration::from_millis(10));
    }
    child
}

#[test]
fn drift_compares_non_finite_numbers_by_identity() {
    let c = Case::new();
    // The reproduction: inf against 1.5 used to be "no drift".
    c.write("b/t.csv", "k,v\na,1.5\n");
    c.write("c/t.csv", "k,v\na,inf\n");
    let out = c.run(&["drift", "b", "c"]);
    assert_eq!(code(&out), 1, "{}", c.explain(&["drift", "b", "c"], &out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("t.csv:a:v 1.5 -> inf"));
    c.write("d/t.csv", "k,v\na,-inf\n");
    assert_eq!(code(&c.run(&["drift", "c", "d"])), 1, "-inf is not inf");
    c.write("e/t.csv", "k,v\na,NaN\n");
    assert_eq!(code(&c.run(&["drift", "c", "e"])), 1);
    // Equal non-finite values are no drift, but said.
    let out = c.ok(&["drift", "c", "c"]);
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("a:v is inf in both"),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    c.write("f/t.csv", "k,v\na,1.5000000001e0\n");
    c.ok(&["drift", "b", "f"]);
}

#[test]
fn a_rerun_with_bad_inputs_leaves_a_finished_folder_as_it_was() {
    let c = Case::new();
    c.write("r.toml", SPEC);
    c.ok(&["run", "r.toml", "--out", "done", "--jobs", "1"]);
    let before = snapshot(&c.path("done"));
    // The reproduction: a wrong --data-dir used to cost the manifest and the cell log.
    c.write("bunny.toml", &SPEC.replace("\"sphere\"", "\"bunny\""));
    for args in [
        vec!["run", "bunny.toml", "--out", "done", "--data-dir", "nowhere"],
        vec!["run", "bunny.toml", "--out", "done", "--data-dir", "nowhere", "--resume"],
    ] {
        let out = bin().args(&args).current_dir(c.dir.path()).output().unwrap();
        assert_eq!(code(&out), 2, "{}", c.explain(&args, &out));
    }
    // Into the finished folder, every other run is refused before its inputs load; into a fresh
    // one, the bad input is named.
    c.fails(&["run", "bunny.toml", "--out", "done"], &["already holds a finished run"]);
    c.fails(&["run", "bunny.toml", "--out", "fresh", "--data-dir", "nowhere"], &["bun_zipper.ply"]);
    // Another spec whose data file is broken (a mistyped --out): refused before the folder changes.
    c.write("bad.xyz", "1e308 0 0\n-1e308 1 1\n0 0 2\n5 5 5\n");
    c.write(
        "bad.toml",
        &SPEC.replace("\"sphere\"", "\"bad.xyz\"").replace("master_seed = 3", "master_seed = 4"),
    );
    c.fails(&["run", "bad.toml", "--out", "done"], &["bad.xyz: line 1"]);
    c.fails(
        &["run", "bad.toml", "--out", "fresh"],
        &["bad.xyz: line 1", "x = 1e308, beyond the limit"],
    );
    assert!(!c.path("fresh").exists(), "a refused input made the output folder");
    // Maps that do not load.
    c.write("maps/dnsom_sphere_20x20.csv", "i,j,view\n1,2\n");
    c.write(
        "m.toml",
        &SPEC.replace(
            "[optimise.som]",
            "maps = \"maps\"
[optimise.som]",
        ),
    );
    c.fails(&["run", "m.toml", "--out", "done"], &["already holds a finished run"]);
    c.fails(&["run", "m.toml", "--out", "fresh"], &["dnsom_sphere_20x20.csv"]);
    assert!(snapshot(&c.path("done")) == before, "the finished folder changed");
    c.ok(&["drift", "done", "done"]);
}

#[test]
fn one_writer_per_folder_and_readers_wait_for_it() {
    let c = Case::new();
    c.write("slow.toml", SLOW);
    c.write("other.toml", &SLOW.replace("master_seed = 11", "master_seed = 12"));
    c.write("r.toml", SPEC);
    c.ok(&["run", "r.toml", "--out", "base", "--jobs", "1"]);
    let mut child = start_slow(&c, "slow.toml", "busy");
    let pid = format!("pid {}", child.id());
    // A second writer of another seed, the same spec, a merge, an accept: all refused, naming the holder.
    c.fails(&["run", "other.toml", "--out", "busy"], &["in use", &pid, "run slow.toml"]);
    c.fails(&["run", "slow.toml", "--out", "busy", "--resume"], &["in use", &pid]);
    c.fails(&["merge", "x", "--out", "busy"], &["in use", &pid]);
    c.fails(&["drift", "--accept", "busy", "base"], &["in use", &pid]);
    // Readers of a folder being written are refused too.
    c.fails(&["drift", "base", "busy"], &["being written", &pid]);
    c.fails(&["drift", "--accept", "acc", "busy"], &["being written", &pid]);
    assert!(!c.path("acc").exists());
    // Killed once it has logged a cell (the kernel drops its lock): the folder is unfinished,
    // and holds the first run's cells only.
    let t0 = Instant::now();
    while std::fs::read_to_string(c.path("busy/cells.jsonl")).unwrap_or_default().lines().count()
        < 2
    {
        assert!(
            t0.elapsed() < Duration::from_secs(60) && child.try_wait().unwrap().is_none(),
            "no progress"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    c.fails(&["drift", "base", "busy"], &["unfinished", "no manifest.toml"]);
    c.fails(
        &["run", "other.toml", "--out", "busy", "--resume"],
        &["cannot resume", "master seed: 11 vs 12"],
    );
    for line in std::fs::read_to_string(c.path("busy/cells.jsonl"))
        .unwrap()
        .lines()
        .filter(|l| l.ends_with('}'))
    {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        assert_eq!(
            v["seed"].as_str().unwrap(),
            // A key is `PLACE#IDENTITY`; the stream is the place's.
            somnurbs::experiment::seed_hex(
                11,
                v["key"].as_str().unwrap().split('#').next().unwrap()
            )
        );
    }
    // The lock died with its holder: the next writer is not blocked, and is told what is there.
    c.fails(
        &["run", "r.toml", "--out", "busy"],
        &["already holds an unfinished run of spec `slow`"],
    );
}

#[test]
fn drift_merge_accept_and_resume_refuse_unfinished_or_mixed_folders() {
    let c = Case::new();
    let spec = SLOW
        .replace("repeats = 12", "repeats = 2")
        .replace("generations = 600", "generations = 40");
    c.write("s.toml", &spec);
    c.ok(&["run", "s.toml", "--out", "one", "--jobs", "2"]);
    c.ok(&["drift", "--accept", "base", "one"]);
    let base = snapshot(&c.path("base"));
    // An unfinished run: a finished one with its manifest gone (what a kill leaves).
    c.ok(&["run", "s.toml", "--out", "half", "--jobs", "2"]);
    std::fs::remove_file(c.path("half/manifest.toml")).unwrap();
    c.fails(&["drift", "base", "half"], &["half", "unfinished", "no manifest.toml"]);
    c.fails(&["drift", "--accept", "base", "half"], &["half", "unfinished", "manifest.toml"]);
    assert!(snapshot(&c.path("base")) == base, "a refused accept changed the baseline");
    // A shard is not a whole run.
    c.ok(&["run", "s.toml", "--out", "sh1", "--shard", "1/2"]);
    c.ok(&["run", "s.toml", "--out", "sh2", "--shard", "2/2"]);
    c.fails(&["drift", "base", "sh1"], &["shard 1/2", "merge"]);
    c.fails(&["drift", "--accept", "base", "sh1"], &["shard 1/2"]);
    // merge: the logged records must be exactly the spec's cells, with the spec's seeds.
    let log = std::fs::read_to_string(c.path("sh2/cells.jsonl")).unwrap();
    let first: serde_json::Value = serde_json::from_str(log.lines().next().unwrap()).unwrap();
    let key = first["key"].as_str().unwrap().to_string();
    let moved = format!("{key}9");
    let forged = log.replacen(&key, &moved, 1).replacen(
        first["seed"].as_str().unwrap(),
        &somnurbs::experiment::seed_hex(11, &moved),
        1,
    );
    std::fs::write(c.path("sh2/cells.jsonl"), &forged).unwrap();
    // The log knows a cell by `PLACE#IDENTITY`; the merge names the place no shard holds.
    let place = key.split('#').next().unwrap();
    c.fails(&["merge", "sh1", "sh2", "--out", "m1"], &["merge", "no shard logged cell", place]);
    std::fs::write(
        c.path("sh2/cells.jsonl"),
        format!("{log}{}\n", log.lines().next().unwrap().replace(&key, &moved)),
    )
    .unwrap();
    c.fails(
        &["merge", "sh1", "sh2", "--out", "m2"],
        &["merge", "cells.jsonl", &moved, "mixes runs"],
    );
    std::fs::write(c.path("sh2/cells.jsonl"), &log).unwrap();
    c.ok(&["merge", "sh1", "sh2", "--out", "m3"]);
    c.ok(&["drift", "base", "m3"]);
    // --resume: a record of another seed in the log is refused, naming the cell and line.
    let own = somnurbs::experiment::log_text(&c.path("half")).unwrap();
    std::fs::remove_file(c.path("half/cells.jsonl.gz")).unwrap();
    let line = own.lines().nth(1).unwrap();
    let rec: serde_json::Value = serde_json::from_str(line).unwrap();
    let wrong = line.replace(
        rec["seed"].as_str().unwrap(),
        &somnurbs::experiment::seed_hex(12, rec["key"].as_str().unwrap()),
    );
    std::fs::write(c.path("half/cells.jsonl"), format!("{own}{wrong}\n")).unwrap();
    c.fails(
        &["run", "s.toml", "--out", "half", "--resume"],
        &["cells.jsonl:", rec["key"].as_str().unwrap(), "mixes runs"],
    );
    std::fs::write(c.path("half/cells.jsonl"), &own).unwrap();
    c.ok(&["run", "s.toml", "--out", "half", "--resume"]);
    c.ok(&["drift", "base", "half"]);
    // A folder with two links to itself is walked once (this used to hang).
    std::os::unix::fs::symlink(c.path("half"), c.path("half/loop1")).unwrap();
    std::os::unix::fs::symlink(c.dir.path(), c.path("half/loop2")).unwrap();
    let t0 = Instant::now();
    c.ok(&["drift", "base", "half"]);
    assert!(t0.elapsed() < Duration::from_secs(10));
    // An accept swaps the whole baseline: the new one holds the current tables and keeps its drift.toml.
    c.write("base/drift.toml", "timing_rows = [\"fastest\"]\n");
    c.ok(&["drift", "--accept", "base", "m3"]);
    assert!(c.path("base/drift.toml").exists() && c.path("base/manifest.toml").exists());
    let left: Vec<String> = std::fs::read_dir(c.dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".base"))
        .collect();
    assert!(left.is_empty(), "temporary folders left: {left:?}");
}

#[test]
fn bad_inputs_are_refused_on_one_line_quickly() {
    let c = Case::new();
    let som = |data: &str| SOM_TINY.replace("DATA", data);
    let timed = |args: &[&str], needles: &[&str]| {
        let t0 = Instant::now();
        c.fails(args, needles);
        assert!(t0.elapsed() < Duration::from_secs(2), "{args:?} took {:?}", t0.elapsed());
    };
    // A PLY header claiming 10^12 vertices with a short body (crashed).
    c.write("big.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n0123456789ab");
    c.write("big.toml", &som("big.ply"));
    timed(&["run", "big.toml", "--out", "o1"], &["big.ply", "1000000000000"]);
    // A binary PLY element of no properties and 10^18 items (hung).
    c.write("none.ply", "ply\nformat binary_little_endian 1.0\nelement junk 1000000000000000000\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nend_header\n");
    c.write("none.toml", &som("none.ply"));
    timed(&["run", "none.toml", "--out", "o2"], &["none.ply", "junk"]);
    // A list count stored as a double (misread every vertex).
    c.write("dbl.ply", "ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list double int vertex_indices\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nend_header\n");
    c.write("dbl.toml", &som("dbl.ply"));
    timed(&["run", "dbl.toml", "--out", "o3"], &["dbl.ply", "integer type"]);
    // An STL sampled with a huge point count (crashed).
    c.write("huge.toml", &som("tri.stl:100000000000"));
    timed(&["run", "huge.toml", "--out", "o4", "--dry-run"], &["som.datasets", "100000000000"]);
    // XYZ values that overflow the normalisation (ran with qe = inf; now beyond |x| <= 1e15,
    // refused naming the line) and all-equal points.
    c.write("far.xyz", "1e308 0 0\n-1e308 1 1\n0 0 2\n5 5 5\n");
    c.write("far.toml", &som("far.xyz"));
    timed(&["run", "far.toml", "--out", "o5"], &["far.xyz: line 1", "beyond the limit"]);
    c.write("same.xyz", "1 2 3\n1 2 3\n1 2 3\n1 2 3\n");
    c.write("same.toml", &som("same.xyz"));
    timed(&["run", "same.toml", "--out", "o6"], &["same.xyz", "same point"]);
    for o in ["o1", "o2", "o3", "o5", "o6"] {
        assert!(
            !c.path(&format!("{o}/manifest.toml")).exists()
                && !c.path(&format!("{o}/cells.jsonl")).exists(),
            "{o}"
        );
    }
    // Spec sizes, in validation (so --dry-run too).
    for (from, to, needles) in [
        (
            "grids = [\"6x5\"]",
            "grids = [\"100000x100000\"]",
            vec!["som.group[0].grids", "100000x100000"],
        ),
        ("iterations = 200", "iterations = 200\nsigma0 = 1e5", vec!["som.sigma0"]),
        ("iterations = 200", "iterations = 200\nsigma0 = inf", vec!["som.sigma0"]),
        ("iterations = 200", "iterations = 1000000000000000", vec!["som.iterations"]),
        ("iterations = 200", "iterations = 200\nrepeats = 1000000000", vec!["som.repeats"]),
        (
            "models = [\"dnsom\"]",
            "models = [\"dnsom\", \"dnsom\"]",
            vec!["som.group[0].models", "`dnsom` is listed twice"],
        ),
        ("name = \"s\"", "name = \"..\"", vec!["name"]),
        ("name = \"s\"", "name = \".\"", vec!["name"]),
    ] {
        let text = som("cube").replace(from, to);
        c.write("bad.toml", &text);
        timed(&["run", "bad.toml", "--dry-run"], &needles);
        timed(&["run", "bad.toml", "--out", "o7"], &needles);
    }
    for (from, to, needles) in [
        ("population = 8", "population = 1000000000000", vec!["optimise.population"]),
        ("generations = 20", "generations = 1000000000000000000", vec!["optimise.generations"]),
        ("population = 8", "population = 8\nsearch_range = 1e308", vec!["optimise.search_range"]),
        (
            "optimisers = [\"ga\", \"de\"]",
            "optimisers = [\"de\", \"ga\", \"de\"]",
            vec!["optimise.optimisers", "`de` is listed twice"],
        ),
        (
            "parameterisations = [\"chord_length\"]",
            "parameterisations = [\"chord_length\", \"chord_length\"]",
            vec!["optimise.parameterisations", "chord_length"],
        ),
        (
            "control_nets = [\"6x6\"]",
            "control_nets = [\"6x6\", \"6x6\"]",
            vec!["optimise.control_nets", "6x6"],
        ),
    ] {
        c.write("bad.toml", &SPEC.replace(from, to));
        timed(&["run", "bad.toml", "--dry-run"], &needles);
    }
    assert!(!c.path("o7").exists());
    // Many repeats expand in linear time (the cell de-duplication was quadratic).
    c.write(
        "many.toml",
        &som("cube").replace("iterations = 200", "iterations = 200\nrepeats = 10000"),
    );
    let t0 = Instant::now();
    let out = c.ok(&["run", "many.toml", "--dry-run"]);
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), 10000);
    assert!(t0.elapsed() < Duration::from_secs(5), "{:?}", t0.elapsed());
}

#[test]
fn results_do_not_depend_on_where_a_data_file_lives_and_stay_in_the_output_folder() {
    let c = Case::new();
    let points: String = (0..60)
        .map(|k| {
            format!("{} {} {}\n", (k as f64 * 0.37).sin(), (k as f64 * 0.11).cos(), k as f64 / 60.0)
        })
        .collect();
    c.write("here/part.xyz", &points);
    c.write("deep/down/part.xyz", &points);
    let abs = c.path("deep/down/part.xyz");
    let spec = |data: &str| {
        SOM_TINY
            .replace("DATA", data)
            .replace("iterations = 200", "iterations = 200\nsave_maps = [\"6x5\"]")
    };
    c.write("a.toml", &spec("here/part.xyz"));
    c.write("b.toml", &spec(abs.to_str().unwrap()));
    c.write("c.toml", &spec("here/../deep/down/part.xyz"));
    let list =
        |spec: &str| String::from_utf8_lossy(&c.ok(&["run", spec, "--dry-run"]).stdout).to_string();
    let a = list("a.toml");
    assert!(a.starts_with("som/part/dnsom/6x5/r0\tseed "), "{a}");
    assert_eq!(a, list("b.toml"), "an absolute path changed keys or seeds");
    assert_eq!(a, list("c.toml"));
    c.ok(&["run", "a.toml", "--out", "oa"]);
    c.ok(&["run", "b.toml", "--out", "ob"]);
    // A path with ../ keeps the maps inside --out.
    c.ok(&["run", "c.toml", "--out", "oc"]);
    assert!(
        c.path("oa/maps/dnsom_part_6x5.csv").exists()
            && c.path("oc/maps/dnsom_part_6x5.csv").exists()
    );
    let outside: Vec<String> = walk(c.dir.path())
        .iter()
        .map(|p| p.strip_prefix(c.dir.path()).unwrap().display().to_string())
        .filter(|p| {
            !["oa/", "ob/", "oc/", "here/", "deep/", "a.toml", "b.toml", "c.toml"]
                .iter()
                .any(|k| p.starts_with(k))
        })
        .collect();
    assert!(outside.is_empty(), "written outside the output folders: {outside:?}");
    assert_eq!(
        same_tables(&c.path("oa"), &c.path("ob")),
        same_tables(&c.path("oa"), &c.path("oc"))
    );
    // Two files of one name in one spec are refused, naming both.
    c.write(
        "twice.toml",
        &SOM_TINY.replace("\"DATA\"", &format!("\"here/part.xyz\", \"{}\"", abs.display())),
    );
    c.fails(&["run", "twice.toml", "--dry-run"], &["som.datasets", "both go by the name `part`"]);
}

#[test]
fn big_endian_ply_reads_like_ascii() {
    let c = Case::new();
    let pts: Vec<[f32; 3]> =
        (0..8).map(|k| [k as f32 * 0.5, (k * k) as f32 * 0.25, 1.0 - k as f32 * 0.125]).collect();
    let mut ascii = format!("ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nend_header\n", pts.len());
    let mut big = format!("ply\nformat binary_big_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nend_header\n", pts.len()).into_bytes();
    for p in &pts {
        ascii.push_str(&format!("{} {} {}\n", p[0], p[1], p[2]));
        for v in p {
            big.extend(v.to_be_bytes());
        }
    }
    c.write("a.ply", &ascii);
    std::fs::write(c.path("b.ply"), &big).unwrap();
    let show = |f: &str| {
        String::from_utf8_lossy(&c.ok(&["datasets", "show", f]).stdout)
            .replace(&format!("{}:", &f[..1]), ":")
    };
    assert_eq!(show("a.ply"), show("b.ply"));
}

/// A two-view grid CSV of `n` x `n` positions (a lens), for `fit`.
pub(crate) fn small_grid(n: usize) -> String {
    let mut s = String::from("i,j,view,class,x,y,z\n");
    for (view, sign) in [("bottom", -1.0), ("top", 1.0)] {
        for i in 0..n {
            for j in 0..n {
                let (x, y) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
                // The views meet on the border (z = 0 there), as a two-view grid must.
                s.push_str(&format!(
                    "{i},{j},{view},0,{x},{y},{}\n",
                    sign * x * (1.0 - x) * y * (1.0 - y)
                ));
            }
        }
    }
    s
}

#[test]
fn fit_export_and_compare_refuse_a_folder_another_writer_holds() {
    let c = Case::new();
    c.write("slow.toml", SLOW);
    c.write("g.csv", &small_grid(6));
    c.write(
        "r.toml",
        &SPEC.replace("control_nets = [\"6x6\"]", "control_nets = [\"6x6\", \"8x8\"]"),
    );
    c.ok(&["run", "r.toml", "--out", "done", "--jobs", "1"]);
    let mut child = start_slow(&c, "slow.toml", "busy");
    let pid = format!("pid {}", child.id());
    c.fails(
        &["fit", "--grid", "g.csv", "--cn", "4x4", "--out", "busy"],
        &["in use", &pid, "run slow.toml"],
    );
    c.fails(&["datasets", "export", "sphere", "busy/sphere.xyz"], &["inside the result folder"]);
    c.fails(&["compare", "busy"], &["being written", &pid]);
    assert!(
        !c.path("busy/control_nets.csv").exists()
            && !c.path("busy/sphere.xyz").exists()
            && !c.path("busy/compare_cells.csv").exists()
    );
    child.kill().unwrap();
    child.wait().unwrap();
    // Free folders are written, and each command leaves the lock released for the next writer.
    c.ok(&["fit", "--grid", "g.csv", "--cn", "4x4", "--out", "free"]);
    c.ok(&["datasets", "export", "sphere", "sphere.xyz"]);
    c.ok(&["compare", "done", "--bayes-samples", "1000"]);
    c.ok(&["compare", "done", "--bayes-samples", "1000"]);
    c.fails(&["compare", "nothere"], &["nothere", "no such results folder"]);
    assert!(!c.path("nothere").exists());
}

#[test]
fn data_with_fewer_points_than_the_maps_neurons_is_refused_naming_the_file() {
    let c = Case::new();
    let pts: String = (0..60)
        .map(|k| {
            let t = k as f64 * 0.7;
            format!("{} {} {}\n", t.cos(), t.sin(), (k as f64 * 0.37).sin())
        })
        .collect();
    c.write("few.xyz", &pts);
    let som = "name = \"s\"\nmaster_seed = 1\n[som]\ndatasets = [\"few.xyz\"]\niterations = 50\n[[som.group]]\nmodels = [\"som2d\", \"dnsom\"]\ngrids = [\"GRID\"]\n";
    c.write("big.toml", &som.replace("GRID", "10x10"));
    c.fails(
        &["run", "big.toml", "--out", "big"],
        &["few.xyz", "60 points", "fewer than the", "neurons of the dnsom 10x10"],
    );
    assert!(!c.path("big/cells.jsonl").exists() && !c.path("big/manifest.toml").exists());
    // A SOM2D may have more neurons than points (as the thesis' SOM3D does); a small DNSOM runs.
    c.write("s2d.toml", &som.replace("GRID", "10x10").replace("\"som2d\", \"dnsom\"", "\"som2d\""));
    c.ok(&["run", "s2d.toml", "--out", "s2d"]);
    c.write("small.toml", &som.replace("GRID", "4x4"));
    c.ok(&["run", "small.toml", "--out", "small"]);
    // Chapter 6 recomputing a 20x20 DNSOM map from it.
    c.write("o.toml", &SPEC.replace("\"sphere\"", "\"few.xyz\""));
    c.fails(&["run", "o.toml", "--out", "o"], &["few.xyz", "fewer than", "neurons"]);
}
