//! `somnurbs compare` never writes outside its folder and never trusts a log it did not write
//! (issue 46): an external IOHprofiler log is judged by the results folder's own certificate and
//! by its own traces, malformed fields are named, `--out` stays out of result folders,
//! `--external` out of the folder compare replaces, an interrupted compare's leftovers are
//! removed, and a failed write stops compare with the old folder as it was.

use crate::common::*;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// A small Chapter 6 spec in the thesis' box with the exact solver (so `exact_20x20.csv`).
const SPEC: &str = r#"
name = "opt"
master_seed = 5
[optimise]
datasets = ["sphere"]
grid = "20x20"
control_nets = ["6x6", "8x8"]
parameterisations = ["chord_length"]
optimisers = ["de", "pso"]
repeats = 2
generations = 10
population = 8
init_range = 5e-6
search_range = 5e-6
exact = true
[optimise.som]
iterations = 500
"#;

/// The external optimiser's name in the fixture.
const EXT: &str = "extopt";

fn read_json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn write_json(path: &Path, v: &Value) {
    std::fs::write(path, serde_json::to_string_pretty(v).unwrap()).unwrap();
}

/// Column `name` of every row of a CSV, keyed by the row's problem name (its data set column is
/// `data` or `dataset`).
fn by_problem(path: &Path, name: &str) -> Vec<(String, String)> {
    let (h, rows) = read_csv(path);
    let data = h.iter().position(|c| c == "data" || c == "dataset").unwrap();
    rows.iter()
        .map(|r| {
            let (x, y, p) = (col(&h, "cn_x"), col(&h, "cn_y"), col(&h, "parameterisation"));
            (format!("{}_20x20_{}x{}_{}", r[data], r[x], r[y], r[p]), r[col(&h, name)].clone())
        })
        .collect()
}

/// A finished run `r` (exact spec) and, in `ext/extopt/`, its own DE traces logged as an external
/// optimiser with the attributes the Python adapter writes (suite, B's error, the certificate).
fn fixture(c: &Case) -> PathBuf {
    c.write("opt.toml", SPEC);
    c.ok(&["run", "opt.toml", "--out", "r"]);
    external_from(c, "r", "ext")
}

/// [`fixture`]'s external folder made from the run `run` into `ext/extopt/`.
fn external_from(c: &Case, run: &str, ext: &str) -> PathBuf {
    let bs = by_problem(&c.path(&format!("{run}/runs.csv")), "b");
    let b_of = |problem: &str| -> f64 {
        bs.iter().find(|(k, _)| k == problem).unwrap().1.parse().unwrap()
    };
    let exact = c.path(&format!("{run}/exact_20x20.csv"));
    let (optima, bounds) = if exact.exists() {
        (by_problem(&exact, "exact_f"), by_problem(&exact, "lower_bound"))
    } else {
        (Vec::new(), Vec::new())
    };
    let out = c.path(&format!("{ext}/{EXT}"));
    std::fs::create_dir_all(&out).unwrap();
    for e in std::fs::read_dir(c.path(&format!("{run}/ioh/de"))).unwrap().flatten() {
        let p = e.path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if p.is_dir() {
            std::fs::create_dir_all(out.join(&name)).unwrap();
            for f in std::fs::read_dir(&p).unwrap().flatten() {
                std::fs::copy(f.path(), out.join(&name).join(f.file_name())).unwrap();
            }
            continue;
        }
        let mut v = read_json(&p);
        let problem = v["function_name"].as_str().unwrap().to_string();
        v["algorithm"]["name"] = json!(EXT);
        v["experiment_attributes"] = json!([
            {"somnurbs_spec": "opt"}, {"somnurbs_profile": ""},
            {"somnurbs_reading": "eq2_10"}, {"somnurbs_box": "B+-5e-6"}
        ]);
        let find = |list: &[(String, String)]| {
            list.iter().find(|(k, _)| *k == problem).map(|(_, v)| v.parse::<f64>().unwrap())
        };
        for run in v["scenarios"][0]["runs"].as_array_mut().unwrap() {
            run["somnurbs_b"] = json!(b_of(&problem));
            if let (Some(f), Some(lb)) = (find(&optima), find(&bounds)) {
                run["somnurbs_optimum"] = json!(f);
                run["somnurbs_bound"] = json!(lb);
            }
        }
        write_json(&out.join(&name), &v);
    }
    out
}

/// The external folder's first JSON (6x6) and its `.dat` file.
fn first_log(ext: &Path) -> (PathBuf, PathBuf) {
    let mut jsons: Vec<PathBuf> = std::fs::read_dir(ext)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    jsons.sort();
    let v = read_json(&jsons[0]);
    let dat = ext.join(v["scenarios"][0]["path"].as_str().unwrap());
    (jsons[0].clone(), dat)
}

/// Set the best of the first run of a `.dat` (its lowest row) to `value`; returns the
/// evaluation it is at.
fn set_first_runs_best(dat: &Path, value: f64) -> u64 {
    let text = std::fs::read_to_string(dat).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let end = lines.iter().skip(1).position(|l| l.starts_with("evaluations")).unwrap() + 1;
    let y = |l: &String| l.split_whitespace().nth(1).unwrap().parse::<f64>().unwrap();
    let k = (1..end).min_by(|&a, &b| y(&lines[a]).total_cmp(&y(&lines[b]))).unwrap();
    let e: u64 = lines[k].split_whitespace().next().unwrap().parse().unwrap();
    lines[k] = format!("{e} {value:e}");
    std::fs::write(dat, lines.join("\n") + "\n").unwrap();
    e
}

/// Nothing was written: the old `compare` folder (or none) is as it was.
fn listing(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    walk(dir).into_iter().map(|p| (p.clone(), std::fs::read(&p).unwrap())).collect()
}

/// Defect 1: a run below the folder's certified lower bound is refused whatever the log says of
/// itself (bound and optimum removed, or 0), naming the file, the run and both values; a log
/// whose own certificate contradicts the folder's is refused; a folder without a certificate says
/// what is checked instead.
#[test]
fn external_runs_are_judged_by_the_folders_certificate() {
    let c = Case::new();
    let ext = fixture(&c);
    let out = c.ok(&["compare", "r", "--external", "ext", "--bayes-samples", "1000"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains(EXT));
    let (_, aocc) = read_csv(&c.path("r/compare/compare_aocc.csv"));
    assert!(aocc.iter().any(|r| r[1] == EXT), "{aocc:?}");
    let before = listing(&c.path("r/compare"));
    let (json, dat) = first_log(&ext);
    let (h, exact) = read_csv(&c.path("r/exact_20x20.csv"));
    let row = exact.iter().find(|r| r[col(&h, "cn_x")] == "6").unwrap();
    let lb: f64 = row[col(&h, "lower_bound")].parse().unwrap();
    let forged = lb - 1e-4;
    let at = set_first_runs_best(&dat, forged);
    // The log's own certificate removed, or set to 0: the folder's still holds.
    let mut v = read_json(&json);
    v["scenarios"][0]["runs"][0]["best"] = json!({"evals": at, "y": forged, "x": []});
    for claim in [None, Some(0.0)] {
        for run in v["scenarios"][0]["runs"].as_array_mut().unwrap() {
            let o = run.as_object_mut().unwrap();
            match claim {
                None => {
                    o.remove("somnurbs_bound");
                    o.remove("somnurbs_optimum");
                }
                Some(x) => {
                    o.insert("somnurbs_bound".into(), json!(x));
                    o.insert("somnurbs_optimum".into(), json!(x));
                }
            }
        }
        write_json(&json, &v);
        c.fails(
            &["compare", "r", "--external", "ext"],
            &[
                &json.file_name().unwrap().to_string_lossy(),
                "scenarios[0].runs[0]",
                "below the certified lower bound",
                &format!("{forged:e}"),
                &format!("{lb:e}"),
                "exact_20x20.csv",
            ],
        );
        assert_eq!(listing(&c.path("r/compare")), before);
    }
    // A folder without a certificate (no exact table) says what it checks instead and takes it.
    std::fs::remove_dir_all(c.path("r/compare")).unwrap();
    copy_dir(&c.path("r"), &c.path("u"));
    std::fs::remove_file(c.path("u/exact_20x20.csv")).unwrap();
    let out = c.ok(&["compare", "u", "--external", "ext", "--bayes-samples", "1000"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("certifies no lower bound") && err.contains("B's error and their own traces"),
        "{err}"
    );
    let (th, targets) = read_csv(&c.path("u/compare/compare_targets.csv"));
    assert!(
        targets.iter().all(|r| {
            let from = &r[col(&th, "best_known_from")];
            from.starts_with("run ") || from.starts_with(&format!("external {EXT} repeat "))
        }),
        "{targets:?}"
    );
}

/// Defect 1, the cross-check: a log's own certificate that contradicts the folder's is refused;
/// one that agrees, or none, is not used.
#[test]
fn a_log_whose_certificate_contradicts_the_folders_is_refused() {
    let c = Case::new();
    let ext = fixture(&c);
    let (json, _) = first_log(&ext);
    let good = read_json(&json);
    for (key, value, said) in [
        ("somnurbs_optimum", 0.0, "somnurbs_optimum 0e0 is below the certified lower bound"),
        ("somnurbs_bound", 1e9, "somnurbs_bound 1e9 is above the certified optimum"),
    ] {
        let mut v = good.clone();
        v["scenarios"][0]["runs"][1][key] = json!(value);
        write_json(&json, &v);
        c.fails(&["compare", "r", "--external", "ext"], &["scenarios[0].runs[1]", said]);
        assert!(!c.path("r/compare").exists());
    }
}

/// Defect 2: a run's trace must agree with its record: evaluations increasing, none beyond the
/// run's `evals`, and the record's best the trace's best at the same evaluation.
#[test]
fn a_run_whose_record_contradicts_its_trace_is_refused() {
    let c = Case::new();
    let ext = fixture(&c);
    let (json, dat) = first_log(&ext);
    let (good_json, good_dat) = (read_json(&json), std::fs::read_to_string(&dat).unwrap());
    let name = json.file_name().unwrap().to_string_lossy().into_owned();
    // evals 10 while the trace logs improvements later on.
    let mut v = good_json.clone();
    v["scenarios"][0]["runs"][0]["evals"] = json!(10);
    write_json(&json, &v);
    c.fails(
        &["compare", "r", "--external", "ext"],
        &[&name, "scenarios[0].runs[0]", "evals is 10", "the count and the trace contradict"],
    );
    // The record's best is not the trace's.
    let mut v = good_json.clone();
    let y = v["scenarios"][0]["runs"][1]["best"]["y"].as_f64().unwrap();
    v["scenarios"][0]["runs"][1]["best"]["y"] = json!(y * (1.0 + 1e-9));
    write_json(&json, &v);
    c.fails(
        &["compare", "r", "--external", "ext"],
        &[&name, "scenarios[0].runs[1]", "best is", "the record and the trace contradict"],
    );
    let mut v = good_json.clone();
    let e = v["scenarios"][0]["runs"][1]["best"]["evals"].as_u64().unwrap();
    v["scenarios"][0]["runs"][1]["best"]["evals"] = json!(e + 1);
    write_json(&json, &v);
    c.fails(
        &["compare", "r", "--external", "ext"],
        &[&name, "the record and the trace contradict"],
    );
    // Evaluations that go back.
    write_json(&json, &good_json);
    let mut lines: Vec<&str> = good_dat.lines().collect();
    lines.swap(2, 3);
    std::fs::write(&dat, lines.join("\n") + "\n").unwrap();
    c.fails(&["compare", "r", "--external", "ext"], &["line 4", "does not follow", &name]);
    assert!(!c.path("r/compare").exists());
    std::fs::write(&dat, &good_dat).unwrap();
    c.ok(&["compare", "r", "--external", "ext", "--bayes-samples", "1000"]);
}

/// Defect 7: every malformed field of an external JSON is named with its file.
#[test]
fn malformed_fields_of_an_external_log_are_named() {
    let c = Case::new();
    let ext = fixture(&c);
    let (json, _) = first_log(&ext);
    let name = json.file_name().unwrap().to_string_lossy().into_owned();
    let good = read_json(&json);
    type Edit = fn(&mut Value);
    let cases: [(Edit, &str); 12] = [
        (|v| v["scenarios"] = json!({"dimension": 156}), "field `scenarios`"),
        (|v| v["scenarios"] = json!([]), "field `scenarios`"),
        (|v| v["scenarios"][0] = json!(3), "field `scenarios[0]`"),
        (|v| v["scenarios"][0]["runs"] = json!("two"), "field `scenarios[0].runs`"),
        (|v| v["scenarios"][0]["runs"][0] = json!(1), "field `scenarios[0].runs[0]`"),
        (|v| v["scenarios"][0]["dimension"] = json!("156"), "field `scenarios[0].dimension`"),
        (|v| v["scenarios"][0]["path"] = json!(7), "field `scenarios[0].path`"),
        (|v| v["scenarios"][0]["path"] = json!("../x.dat"), "field `scenarios[0].path`"),
        (
            |v| v["scenarios"][0]["runs"][1]["evals"] = json!(-3),
            "field `scenarios[0].runs[1].evals`",
        ),
        (
            |v| v["scenarios"][0]["runs"][0]["somnurbs_bound"] = json!("low"),
            "field `scenarios[0].runs[0].somnurbs_bound`",
        ),
        (|v| v["function_name"] = json!(["x"]), "field `function_name`"),
        (|v| v["experiment_attributes"] = json!("opt"), "field `experiment_attributes`"),
    ];
    for (edit, said) in cases {
        let mut v = good.clone();
        edit(&mut v);
        write_json(&json, &v);
        c.fails(&["compare", "r", "--external", "ext"], &[&name, said]);
    }
    let mut v = good.clone();
    v["algorithm"] = json!("extopt");
    write_json(&json, &v);
    c.fails(&["compare", "r", "--external", "ext"], &[&name, "field `algorithm.name`"]);
    let mut v = good.clone();
    v["maximization"] = json!(true);
    write_json(&json, &v);
    c.fails(&["compare", "r", "--external", "ext"], &[&name, "field `maximization`"]);
    assert!(!c.path("r/compare").exists());
}

/// Defects 3 and 4: `--out` inside a result folder is refused (compare's own default aside, even
/// when its parent does not exist yet), and so is an `--external` folder inside the folder
/// compare replaces.
#[test]
fn compare_writes_outside_results_and_reads_outside_its_own_folder() {
    let c = Case::new();
    fixture(&c);
    for out in ["r/mycmp", "r/new/deeper/cmp", "r/ioh/../cmp"] {
        c.fails(
            &["compare", "r", "--out", out],
            &[&format!("compare --out {out} is inside the result folder"), "/r,", "r/compare"],
        );
    }
    std::os::unix::fs::symlink(c.path("r"), c.path("link")).unwrap();
    c.fails(&["compare", "r", "--out", "link/cmp"], &["is inside the result folder"]);
    assert!(!c.path("r/mycmp").exists() && !c.path("r/new").exists() && !c.path("r/cmp").exists());
    c.ok(&["compare", "r", "--out", "r/compare", "--bayes-samples", "1000"]);
    c.ok(&["compare", "r", "--out", "elsewhere", "--bayes-samples", "1000"]);
    // Logs inside the folder compare replaces would be deleted by its swap.
    copy_dir(&c.path("ext"), &c.path("r/compare/ext"));
    let before = listing(&c.path("r/compare"));
    c.fails(
        &["compare", "r", "--external", "r/compare/ext"],
        &["compare --external r/compare/ext is inside r/compare, the folder compare replaces"],
    );
    copy_dir(&c.path("ext"), &c.path("elsewhere/ext"));
    c.fails(
        &["compare", "r", "--out", "elsewhere", "--external", "elsewhere/ext/extopt"],
        &["elsewhere/ext/extopt is inside elsewhere"],
    );
    assert_eq!(listing(&c.path("r/compare")), before);
}

/// Defect 5: the folders an interrupted compare left beside its output (`.compare.PID.N.staged`
/// of a process that is gone) are removed by the next compare, which says so; a live process's
/// are not.
#[test]
fn an_interrupted_compares_leftovers_are_removed_by_the_next() {
    let c = Case::new();
    fixture(&c);
    c.write("r/.compare.999999999.0.staged/compare_cells.csv", "x\n");
    c.write("r/.compare.999999998.2.old/compare.toml", "");
    let live = format!("r/.compare.{}.0.staged/keep", std::process::id());
    c.write(&live, "");
    let out = c.ok(&["compare", "r", "--bayes-samples", "1000"]);
    let err = String::from_utf8_lossy(&out.stderr);
    let said: Vec<&str> = err.lines().filter(|l| l.contains("interrupted compare")).collect();
    assert_eq!(said.len(), 1, "{err}");
    assert!(
        said[0].contains("removed 2 folder(s)")
            && said[0].contains(".compare.999999999.0.staged")
            && said[0].contains(".compare.999999998.2.old"),
        "{err}"
    );
    assert!(!c.path("r/.compare.999999999.0.staged").exists());
    assert!(!c.path("r/.compare.999999998.2.old").exists());
    assert!(c.path(&live).exists());
    let out = c.ok(&["compare", "r", "--bayes-samples", "1000"]);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("interrupted compare"));
}

/// Defect 6: a chart that cannot be written (here: larger than the file-size limit, as on a full
/// disk) stops compare with exit 2 and leaves the previous `compare` folder as it was.
#[test]
fn a_failed_chart_write_stops_compare_and_keeps_the_old_folder() {
    let c = Case::new();
    c.write("one.toml", &SPEC.replace(r#"["6x6", "8x8"]"#, r#"["6x6"]"#));
    c.ok(&["run", "one.toml", "--out", "r"]);
    c.ok(&["compare", "r"]);
    let before = listing(&c.path("r/compare"));
    let size = |ext: &str| -> Vec<u64> {
        before
            .iter()
            .filter(|(p, _)| p.extension().is_some_and(|e| e == ext))
            .map(|(_, b)| b.len() as u64)
            .collect()
    };
    let (largest_table, smallest_chart) =
        (*size("csv").iter().max().unwrap(), *size("png").iter().min().unwrap());
    // A limit (bash's `ulimit -f`, KiB) every table fits under and no chart does.
    let limit = largest_table / 1024 + 1;
    assert!(
        limit * 1024 < smallest_chart,
        "tables up to {largest_table} B, charts from {smallest_chart} B"
    );
    let script = format!("trap '' XFSZ; ulimit -f {limit}; exec \"$0\" compare r");
    let out = std::process::Command::new("bash")
        .args(["-c", &script, env!("CARGO_BIN_EXE_somnurbs")])
        .current_dir(c.path(""))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("r/compare left as it was") && err.contains(".png"), "{err}");
    assert_eq!(listing(&c.path("r/compare")), before);
    let left: Vec<String> = std::fs::read_dir(c.path("r"))
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".compare."))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().flatten() {
        let (p, q) = (e.path(), to.join(e.file_name()));
        if e.file_type().unwrap().is_dir() {
            copy_dir(&p, &q);
        } else if e.file_type().unwrap().is_file() {
            std::fs::copy(&p, &q).unwrap();
        }
    }
}

/// A named pipe or a device in place of an external log's `.dat` or `.json` is refused for what it
/// is, at once (a plain read would wait on the pipe forever or read the device without end).
#[test]
fn an_external_log_that_is_a_pipe_or_a_device_is_refused_without_waiting() {
    let c = Case::new();
    let ext = fixture(&c);
    let (json, dat) = first_log(&ext);
    let fifo = |p: &Path| {
        std::fs::remove_file(p).unwrap();
        assert!(std::process::Command::new("mkfifo").arg(p).status().unwrap().success());
    };
    let start = std::time::Instant::now();
    let good_dat = std::fs::read(&dat).unwrap();
    fifo(&dat);
    let dat_name = dat.file_name().unwrap().to_string_lossy().into_owned();
    c.fails(&["compare", "r", "--external", "ext"], &[&dat_name, "named pipe"]);
    std::fs::remove_file(&dat).unwrap();
    std::os::unix::fs::symlink("/dev/zero", &dat).unwrap();
    c.fails(&["compare", "r", "--external", "ext"], &[&dat_name, "device"]);
    std::fs::remove_file(&dat).unwrap();
    std::fs::write(&dat, good_dat).unwrap();
    let json_name = json.file_name().unwrap().to_string_lossy().into_owned();
    fifo(&json);
    c.fails(&["compare", "r", "--external", "ext"], &[&json_name, "named pipe"]);
    assert!(start.elapsed().as_secs() < 60, "took {:?}", start.elapsed());
    assert!(!c.path("r/compare").exists());
}

/// An external that ran part of the problems: a one-line warning names its count and what the
/// statistics over cells use, and the runtime aggregate `all` is over the problems every
/// optimiser ran, for every optimiser alike.
#[test]
fn an_external_that_ran_part_of_the_problems_is_warned_and_aggregated_over_the_common_ones() {
    let c = Case::new();
    let ext = fixture(&c);
    let (json, dat) = first_log(&ext);
    std::fs::remove_file(&json).unwrap();
    std::fs::remove_file(&dat).unwrap();
    let (_, all_rows) = read_csv(&c.path("r/runs.csv"));
    let out = c.ok(&["compare", "r", "--external", "ext", "--bayes-samples", "1000"]);
    let err = String::from_utf8_lossy(&out.stderr);
    let warning = err.lines().find(|l| l.contains("not every optimiser ran every cell"));
    let warning = warning.unwrap_or_else(|| panic!("no coverage warning: {err}"));
    assert!(
        warning.contains(&format!("{EXT} ran ")) && warning.contains("cells every optimiser ran"),
        "{warning}"
    );
    // compare.md lists who ran which cells and what the statistics over cells use.
    let md = std::fs::read_to_string(c.path("r/compare/compare.md")).unwrap();
    assert!(md.contains(&format!("| {EXT} | 1 | 2 | sphere 20x20 6x6 chord_length |")), "{md}");
    assert!(
        md.contains("**Not every optimiser ran every cell** (") && md.contains("use the 1 cells"),
        "{md}"
    );
    let (h, rows) = read_csv(&c.path("r/compare/compare_aocc.csv"));
    let all: Vec<&Vec<String>> = rows.iter().filter(|r| r[col(&h, "group")] == "all").collect();
    assert!(all.len() >= 3 && all.iter().any(|r| r[col(&h, "optimiser")] == EXT), "{rows:?}");
    let n = &all[0][col(&h, "problems")];
    assert!(all.iter().all(|r| &r[col(&h, "problems")] == n), "{all:?}");
    assert!(!all_rows.is_empty());
}
