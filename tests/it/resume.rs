//! Resume after SIGKILL, shards merged back into one run, refusals, and `reproduce`.

use crate::common::*;
use std::collections::BTreeSet;
use std::time::{Duration, Instant};

/// The keys of a folder's cell log (`path` is its `cells.jsonl`; a finished run's is compressed).
fn log_keys(path: &std::path::Path) -> Vec<String> {
    somnurbs::experiment::log_text(path.parent().unwrap())
        .unwrap_or_default()
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .map(|v| v["key"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn a_killed_run_resumes_to_the_same_tables() {
    let c = Case::new();
    c.write("slow.toml", SLOW);
    c.ok(&["run", "slow.toml", "--out", "plain", "--jobs", "2"]);
    // Start again in another folder and kill it (SIGKILL) once some cells are logged.
    let mut child = bin()
        .args(["run", "slow.toml", "--out", "killed", "--jobs", "1"])
        .current_dir(c.dir.path())
        .env("SOMNURBS_DATA", data_dir())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let log = c.path("killed/cells.jsonl");
    let t0 = Instant::now();
    while log_keys(&log).len() < 8 {
        assert!(t0.elapsed() < Duration::from_secs(120), "no progress");
        assert!(
            child.try_wait().unwrap().is_none(),
            "finished before it could be killed; make SLOW slower"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let before = log_keys(&log).len();
    assert!(before < 72, "killed after {before} of 72 cells");
    assert!(!c.path("killed/manifest.toml").exists() && !c.path("killed/runs.csv").exists());
    // A different seed may not resume there.
    c.write("other.toml", &SLOW.replace("master_seed = 11", "master_seed = 12"));
    c.fails(
        &["run", "other.toml", "--out", "killed", "--resume"],
        &["cannot resume", "master seed: 11 vs 12"],
    );
    c.fails(
        &["run", "slow.toml", "--out", "killed", "--resume", "--profile", "quick"],
        &["profile"],
    );
    // Resume: the rest runs, nothing is duplicated or lost, the tables equal the plain run's.
    let out = c.ok(&["run", "slow.toml", "--out", "killed", "--resume", "--jobs", "2"]);
    assert!(
        String::from_utf8_lossy(&out.stderr)
            .contains(&format!("{before} of 72 cells already done"))
            || before == 0
    );
    let keys = log_keys(&log);
    assert_eq!(keys.len(), 72, "every cell logged once");
    assert_eq!(keys.iter().collect::<BTreeSet<_>>().len(), 72);
    let compared = same_tables(&c.path("plain"), &c.path("killed"));
    assert!(compared >= 5, "{compared} tables");
}

#[test]
fn shards_merge_into_the_one_machine_run() {
    let c = Case::new();
    let spec = SLOW
        .replace("repeats = 12", "repeats = 2")
        .replace("generations = 600", "generations = 40");
    c.write("s.toml", &spec);
    c.ok(&["run", "s.toml", "--out", "one"]);
    for i in 1..=3 {
        c.ok(&["run", "s.toml", "--out", &format!("shard{i}"), "--shard", &format!("{i}/3")]);
        assert!(!c.path(&format!("shard{i}/runs.csv")).exists(), "a shard writes no tables");
    }
    let sizes: Vec<usize> =
        (1..=3).map(|i| log_keys(&c.path(&format!("shard{i}/cells.jsonl"))).len()).collect();
    assert_eq!(sizes.iter().sum::<usize>(), 12);
    c.fails(&["merge", "shard1", "shard2", "--out", "m"], &["shard 3/3 is missing"]);
    c.fails(&["merge", "shard1", "shard1", "shard2", "--out", "m2"], &["given twice"]);
    c.fails(&["merge", "one", "--out", "m3"], &["not a shard"]);
    c.ok(&["merge", "shard3", "shard1", "shard2", "--out", "merged"]);
    // The merged folder gets the same report.html as a one-machine run.
    assert!(c.path("merged/report.html").is_file() && c.path("one/report.html").is_file());
    let compared = same_tables(&c.path("one"), &c.path("merged"));
    assert!(compared >= 5);
    c.fails(&["run", "s.toml", "--shard", "4/3"], &["--shard"]);
}

#[test]
fn reproduce_quick_writes_one_report_with_claims_and_tables_6_8_6_9() {
    let c = Case::new();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let specs = root.join("experiments");
    c.ok(&[
        "reproduce",
        "--profile",
        "quick",
        "--out",
        "thesis",
        "--specs",
        specs.to_str().unwrap(),
        "--jobs",
        "2",
    ]);
    let report = std::fs::read_to_string(c.path("thesis/REPORT.md")).unwrap();
    for needle in [
        "## Claims",
        "B beats A in most cells",
        "DNSOM has the lowest TE",
        "Table 6.8",
        "Table 6.9",
        "](ch4_models/",
        "**Under calibration only.** 3 of this plan's readings are calibrated",
        "| The 3-D SOM's adjacency for TE | `som.som3d_adjacency` | `layer` | **calibrated** |",
        "**The price of reading literally**",
    ] {
        assert!(report.contains(needle), "REPORT.md lacks {needle:?}");
    }
    // Every claim of the as-written set's specs has its as-written verdict.
    let (h, rows) = read_csv(&c.path("thesis/claims.csv"));
    let (spec, aw) = (0, h.iter().position(|x| x == "verdict_as_written").unwrap());
    assert!(rows.iter().filter(|r| r[spec].starts_with("ch4_models")).all(|r| !r[aw].is_empty()));
    let (_, price) = read_csv(&c.path("thesis/readings_price.csv"));
    assert!(price.iter().any(|r| r[0] == "Chapter 4") && price.iter().any(|r| r[0] == "Chapter 6"));
    let (h, rows) = read_csv(&c.path("thesis/table_6_8.csv"));
    assert_eq!(h, vec!["table", "ga", "de", "pso"]);
    assert_eq!(rows.last().unwrap()[0], "overall");
    // The overall wins add up to the cells of Tables 6.4 and 6.5.
    let cells: usize = rows.last().unwrap()[1].split('/').nth(1).unwrap().parse().unwrap();
    let wins: usize = rows.last().unwrap()[1..]
        .iter()
        .map(|v| v.split('/').next().unwrap().parse::<usize>().unwrap())
        .sum();
    assert!(wins >= cells && cells > 0, "{wins} wins over {cells} cells (ties count for each)");
    let (h, claims) = read_csv(&c.path("thesis/claims.csv"));
    let verdict = h.iter().position(|x| x == "verdict").unwrap();
    assert!(claims.len() >= 15);
    assert!(
        claims
            .iter()
            .all(|r| ["holds", "undecided", "does not hold"].contains(&r[verdict].as_str())),
        "{claims:?}"
    );
    // One row per (spec, grid, claim).
    let key = |r: &Vec<String>| {
        let at = |n: &str| r[h.iter().position(|x| x == n).unwrap()].clone();
        (at("spec"), at("grid"), at("claim"))
    };
    let mut keys: Vec<_> = claims.iter().map(key).collect();
    keys.sort();
    keys.dedup();
    assert_eq!(keys.len(), claims.len(), "a (spec, grid, claim) repeats: {claims:?}");
    quick_sizes_keep_their_budget(&c);
    // A plan's sub-folders re-render from their records alone: a spec that reads the plan's
    // maps (its compressed copies too), and reading sets' Chapter 4 and 6 folders (their keys
    // applied again from the fingerprint, half of as_written's cells reused from the plan's
    // folder).
    for dir in [
        "thesis/ch5_same",
        "thesis/readings/as_written/ch4_models",
        "thesis/readings/as_written/ch6_same",
        "thesis/readings/nurbs_book/ch6_diff",
    ] {
        report_restores_folder(&c, dir);
    }
    c.fails(&["report", "thesis"], &["a `reproduce` folder", "thesis/ch6_same"]);
}

/// The quick reproduction's bytes by kind, against the budgets of docs/outputs.md (issue 49
/// item 7): Chapter 4 keeps its maps as CSV, a folder that read a map and a reading variant keep
/// them gzip-compressed, and the whole folder stays within its total.
fn quick_sizes_keep_their_budget(c: &Case) {
    let map = "maps/dnsom_cube_20x20.csv";
    assert!(c.path("thesis/ch4_models").join(map).is_file());
    for dir in ["thesis/ch5_same", "thesis/readings/as_written/ch4_models"] {
        assert!(c.path(dir).join(format!("{map}.gz")).is_file(), "{dir}: no compressed map");
        assert!(!c.path(dir).join(map).exists(), "{dir}: a plain copy of the map");
    }
    let files = walk(&c.path("thesis"));
    let bytes = |f: &dyn Fn(&str) -> bool| -> u64 {
        let of = |p: &std::path::PathBuf| std::fs::metadata(p).unwrap().len();
        files.iter().filter(|p| f(&p.to_string_lossy())).map(of).sum()
    };
    let mib = |b: u64| b as f64 / (1 << 20) as f64;
    for (kind, budget, of) in [
        ("all", 31.5, &(|_: &str| true) as &dyn Fn(&str) -> bool),
        ("maps/", 3.5, &|p: &str| p.contains("/maps/")),
        ("views3d.js", 1.3, &|p: &str| p.ends_with("views3d.js")),
        ("cells.jsonl.gz", 10.2, &|p: &str| p.ends_with("cells.jsonl.gz")),
        ("ioh/", 4.5, &|p: &str| p.contains("/ioh/")),
    ] {
        let got = mib(bytes(of));
        assert!(got <= budget, "{kind}: {got:.2} MiB, over its budget of {budget} MiB");
    }
}

#[test]
fn reproduce_plan_seeds_runs_the_other_seeds_and_a_missing_plan_is_named() {
    let c = Case::new();
    let specs = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments");
    let specs = specs.to_str().unwrap();
    c.ok(&[
        "reproduce",
        "--plan",
        "seeds",
        "--profile",
        "quick",
        "--out",
        "seeds",
        "--specs",
        specs,
        "--jobs",
        "2",
    ]);
    let report = std::fs::read_to_string(c.path("seeds/REPORT.md")).unwrap();
    assert!(
        report.starts_with("# somnurbs: the other seeds' experiments"),
        "{}",
        &report[..200.min(report.len())]
    );
    let plan: toml::Table =
        std::fs::read_to_string(format!("{specs}/seeds.toml")).unwrap().parse().unwrap();
    for name in plan["specs"].as_array().unwrap() {
        let name = name.as_str().unwrap();
        assert!(c.path(&format!("seeds/{name}/manifest.toml")).exists(), "{name} did not finish");
        assert!(report.contains(&format!("# {name}")), "REPORT.md lacks {name}");
    }
    c.fails(
        &["reproduce", "--plan", "nosuch", "--profile", "quick", "--out", "x", "--specs", specs],
        &["--plan nosuch", "nosuch.toml"],
    );
}

/// With stderr in a file (a log), progress comes as plain lines: at the start, every
/// SOMNURBS_PROGRESS_SECS (here 0.2 s instead of 15) and at the end.
#[test]
fn progress_lines_appear_in_a_log() {
    let c = Case::new();
    c.write("slow.toml", SLOW);
    let log = std::fs::File::create(c.path("stderr.log")).unwrap();
    let status = bin()
        .args(["run", "slow.toml", "--out", "o", "--jobs", "1"])
        .current_dir(c.dir.path())
        .env("SOMNURBS_DATA", data_dir())
        .env("SOMNURBS_PROGRESS_SECS", "0.2")
        .stderr(log)
        .status()
        .unwrap();
    assert!(status.success());
    let text = std::fs::read_to_string(c.path("stderr.log")).unwrap();
    let lines: Vec<&str> =
        text.lines().filter(|l| l.starts_with("somnurbs: progress slow: ")).collect();
    assert!(
        lines.first().is_some_and(|l| l.contains(" 0/72 cells, elapsed 0s, eta unknown")),
        "{text}"
    );
    assert!(
        lines.last().is_some_and(|l| l.contains(" 72/72 cells") && l.ends_with("eta 0s")),
        "{text}"
    );
    let between = lines.iter().filter(|l| !l.contains(" 0/72 ") && !l.contains(" 72/72 ")).count();
    assert!(
        between >= 1 && lines.iter().all(|l| l.contains(", elapsed ") && l.contains(", eta ")),
        "no progress during the run:\n{text}"
    );
    assert!(!text.contains('\r'), "a terminal bar was drawn into the log");
}
