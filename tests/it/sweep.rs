//! `run --set KEY=VALUE` and `run --sweep KEY=V1,V2,...`: a changed key changes the cells it
//! reaches (their identity and results) and no other, every variant of a place draws the place's
//! random numbers, a sweep writes one folder with a `variant` column that `compare` ranks and
//! computes a cell no swept key reaches once, resume and shards of a sweep give the plain
//! sweep's tables, and a run without either keeps its seeds.

use crate::common::*;
use std::collections::{BTreeMap, BTreeSet};

/// One optimiser, so that a sweep over its F is the whole comparison (two cells: Friedman needs two).
fn de_only() -> String {
    SPEC.replace("optimisers = [\"ga\", \"de\"]", "optimisers = [\"de\"]")
        .replace("repeats = 2", "repeats = 3")
        .replace("control_nets = [\"6x6\"]", "control_nets = [\"6x6\", \"8x8\"]")
}

/// runs.csv of a folder as (cell key -> (seed, best)).
fn runs(c: &Case, dir: &str) -> BTreeMap<String, (String, String)> {
    let (h, rows) = read_csv(&c.path(&format!("{dir}/runs.csv")));
    let (k, s, b) = (col(&h, "cell"), col(&h, "seed"), col(&h, "best"));
    rows.into_iter().map(|r| (r[k].clone(), (r[s].clone(), r[b].clone()))).collect()
}

/// Every table of `a` equals `b`'s (timing columns aside), except the CPU-time win counts
/// (`table_6_6.csv`): variants of one optimiser take the same time, so who wins is the clock's.
fn same_results(a: &std::path::Path, b: &std::path::Path) -> usize {
    let csvs = |d: &std::path::Path| -> Vec<std::path::PathBuf> {
        walk(d)
            .into_iter()
            .filter(|p| p.extension().is_some_and(|e| e == "csv") && !p.ends_with("table_6_6.csv"))
            .map(|p| p.strip_prefix(d).unwrap().to_path_buf())
            .collect()
    };
    let (ta, tb) = (csvs(a), csvs(b));
    assert_eq!(ta, tb, "different tables in {} and {}", a.display(), b.display());
    for t in &ta {
        assert_eq!(without_timing(&a.join(t)), without_timing(&b.join(t)), "{}", t.display());
    }
    ta.len()
}

fn exit_code(c: &Case, args: &[&str]) -> Option<i32> {
    c.run(args).status.code()
}

#[test]
fn set_changes_the_results_and_the_seeds_and_is_recorded() {
    let c = Case::new();
    c.write("d.toml", SPEC);
    c.ok(&["run", "d.toml", "--out", "plain"]);
    c.ok(&["run", "d.toml", "--out", "f5", "--set", "optimise.de.f=0.5"]);
    let (plain, f5) = (runs(&c, "plain"), runs(&c, "f5"));
    assert_eq!(plain.len(), f5.len());
    assert!(plain.keys().chain(f5.keys()).all(|k| k.starts_with("optim/")), "{f5:?}");
    // One place, one stream: the --set run's cells draw the plain run's random numbers.
    assert_eq!(
        plain.values().map(|v| &v.0).collect::<Vec<_>>(),
        f5.values().map(|v| &v.0).collect::<Vec<_>>(),
    );
    let best = |m: &BTreeMap<String, (String, String)>, opt: &str| {
        m.iter().filter(|(k, _)| k.contains(opt)).map(|(_, v)| v.1.clone()).collect::<Vec<_>>()
    };
    assert_ne!(best(&plain, "/de/"), best(&f5, "/de/"), "F = 0.5 gives DE the same results");
    assert_eq!(best(&plain, "/ga/"), best(&f5, "/ga/"), "DE's F moved GA's cells");
    let (h, _) = read_csv(&c.path("f5/runs.csv"));
    assert!(!h.contains(&"variant".to_string()), "--set alone adds no variant column: {h:?}");
    let manifest = std::fs::read_to_string(c.path("f5/manifest.toml")).unwrap();
    assert!(manifest.contains("set = [\"optimise.de.f=0.5\"]"), "{manifest}");
    assert!(std::fs::read_to_string(c.path("f5/REPORT.md"))
        .unwrap()
        .contains("--set optimise.de.f=0.5"));
    assert!(std::fs::read_to_string(c.path("f5/fingerprint.toml"))
        .unwrap()
        .contains("optimise.de.f=0.5"));
    // The same --set again resumes; without it, or with another value, the folder is another run's.
    c.ok(&["run", "d.toml", "--out", "f5", "--resume", "--set", "optimise.de.f=0.5"]);
    c.fails(&["run", "d.toml", "--out", "f5", "--resume"], &["cannot resume", "--set"]);
    c.fails(
        &["run", "d.toml", "--out", "f5", "--resume", "--set", "optimise.de.f=0.6"],
        &["cannot resume", "--set"],
    );
    // The dry run lists the variant's keys and seeds.
    let dry = String::from_utf8(
        c.ok(&["run", "d.toml", "--dry-run", "--set", "optimise.de.f=0.5"]).stdout,
    )
    .unwrap();
    assert!(dry.lines().count() == 4 && dry.lines().all(|l| l.starts_with("optim/")), "{dry}");
}

#[test]
fn bad_set_and_sweep_arguments_are_one_line_naming_the_key() {
    let c = Case::new();
    c.write("d.toml", SPEC);
    let cases: &[(&[&str], &[&str])] = &[
        (&["--set", "optimise.de.ff=0.5"], &["optimise.de.ff", "ff"]),
        (&["--set", "optimise.de.f=5"], &["optimise.de.f"]),
        (&["--set", "optimise.de.f=fast"], &["optimise.de.f"]),
        (&["--set", "optimise.de.f"], &["--set", "KEY=VALUE"]),
        (&["--set", "som.iterations=5"], &["som.iterations", "[optimise]"]),
        (
            &["--sweep", "optimise.de.f=0.3,0.5", "--sweep", "optimise.de.f=0.8"],
            &["optimise.de.f", "twice"],
        ),
        (
            &["--set", "optimise.de.f=0.3", "--sweep", "optimise.de.f=0.5,0.8"],
            &["optimise.de.f", "twice"],
        ),
        (&["--sweep", "optimise.de.f=0.3,0.3"], &["optimise.de.f", "0.3", "twice"]),
        (&["--sweep", "optimise.de.f=0.3,"], &["optimise.de.f", "empty"]),
        (&["--sweep", "optimise.de.f=0.3,7"], &["optimise.de.f"]),
        (&["--sweep", "optimise.grid=10x10,20x20"], &["optimise.grid", "optimiser settings"]),
    ];
    for (extra, needles) in cases {
        let args: Vec<&str> = ["run", "d.toml", "--out", "bad"]
            .iter()
            .copied()
            .chain(extra.iter().copied())
            .collect();
        c.fails(&args, needles);
        assert_eq!(exit_code(&c, &args), Some(2), "{args:?}");
        assert!(!c.path("bad").exists(), "{args:?} wrote the folder");
    }
    c.write("s.toml", "name = \"s\"\nmaster_seed = 1\n[som]\ndatasets = [\"cube\"]\niterations = 10\n[[som.group]]\nmodels = [\"som2d\"]\ngrids = [\"10x10\"]\n");
    c.fails(
        &["run", "s.toml", "--set", "optimise.de.f=0.5"],
        &["optimise.de.f", "no [optimise] section"],
    );
}

#[test]
fn a_sweep_over_de_f_writes_one_folder_whose_variants_differ_and_compare_ranks_them() {
    let c = Case::new();
    c.write("d.toml", &de_only());
    c.ok(&["run", "d.toml", "--out", "sweep", "--sweep", "optimise.de.f=0.3,0.5,0.8"]);
    let (h, rows) = read_csv(&c.path("sweep/runs.csv"));
    let (v, best, seed) = (col(&h, "variant"), col(&h, "best"), col(&h, "seed"));
    let variants: Vec<String> =
        rows.iter().map(|r| r[v].clone()).collect::<BTreeSet<_>>().into_iter().collect();
    assert_eq!(variants, vec!["optimise.de.f=0.3", "optimise.de.f=0.5", "optimise.de.f=0.8"]);
    assert_eq!(rows.len(), 18);
    let bests: BTreeSet<Vec<String>> = variants
        .iter()
        .map(|x| rows.iter().filter(|r| &r[v] == x).map(|r| r[best].clone()).collect())
        .collect();
    assert_eq!(bests.len(), 3, "the variants give the same results");
    assert_eq!(
        rows.iter().map(|r| &r[seed]).collect::<BTreeSet<_>>().len(),
        6,
        "the variants of one place draw other random numbers"
    );
    // The variant with F = 0.3 is not the plain spec (F = 0.3 is not DE's default here), and a
    // --set run of one variant gives exactly that variant's rows.
    c.ok(&["run", "d.toml", "--out", "one", "--sweep", "optimise.de.f=0.5"]);
    let one = read_csv(&c.path("one/runs.csv")).1;
    let cell = col(&h, "cell");
    for r in &one {
        let same = rows
            .iter()
            .find(|x| x[cell] == r[cell] && x[v] == r[v])
            .unwrap_or_else(|| panic!("{} not in the sweep", r[cell]));
        assert_eq!((&same[best], &same[seed]), (&r[best], &r[seed]));
    }
    let manifest = std::fs::read_to_string(c.path("sweep/manifest.toml")).unwrap();
    assert!(
        manifest.contains("sweep = [\"optimise.de.f=0.3,0.5,0.8\"]")
            && manifest.contains("cells = 18"),
        "{manifest}"
    );
    // compare ranks the variants like optimisers, with the runtime distributions and the Bayesian test.
    c.ok(&["compare", "sweep", "--bayes-samples", "2000"]);
    let (bh, brows) = read_csv(&c.path("sweep/compare/compare_bayes.csv"));
    assert_eq!(brows.len(), 3, "{bh:?} {brows:?}");
    let pairs: BTreeSet<(String, String)> =
        brows.iter().map(|r| (r[0].clone(), r[1].clone())).collect();
    assert!(
        pairs.contains(&("de@optimise.de.f=0.3".to_string(), "de@optimise.de.f=0.5".to_string())),
        "{pairs:?}"
    );
    // The per-cell table pairs the variants by name, A12 by direction.
    let (ch, crows) = read_csv(&c.path("sweep/compare/compare_cells.csv"));
    let (x, a12) = (col(&ch, "x"), col(&ch, "a12_x_better"));
    assert!(crows.iter().any(|r| r[x] == "de@optimise.de.f=0.3"), "{crows:?}");
    assert!(crows.iter().all(|r| (0.0..=1.0).contains(&r[a12].parse::<f64>().unwrap())));
    let (eh, erows) = read_csv(&c.path("sweep/compare/compare_aocc.csv"));
    let o = col(&eh, "optimiser");
    let ranked: BTreeSet<&str> = erows.iter().map(|r| r[o].as_str()).collect();
    assert_eq!(
        ranked,
        ["de@optimise.de.f=0.3", "de@optimise.de.f=0.5", "de@optimise.de.f=0.8"]
            .into_iter()
            .collect()
    );
    assert!(
        c.path("sweep/compare/compare_overall.csv").exists()
            && c.path("sweep/compare/compare_ert.csv").exists()
    );
}

#[test]
fn resume_and_shards_of_a_sweep_give_the_plain_sweeps_tables() {
    let c = Case::new();
    c.write("d.toml", SPEC);
    let sweep = ["--sweep", "optimise.de.f=0.3,0.8", "--sweep", "optimise.generations=10,20"];
    let with = |base: &[&str]| -> Vec<String> {
        base.iter().chain(sweep.iter()).map(|s| s.to_string()).collect()
    };
    let ok = |args: Vec<String>| c.ok(&args.iter().map(String::as_str).collect::<Vec<_>>());
    ok(with(&["run", "d.toml", "--out", "one"]));
    let n = read_csv(&c.path("one/runs.csv")).1.len();
    // DE's 2 x 2 variants, GA's 2 (only the generations reach it), 2 repeats each.
    assert_eq!(n, 12, "(2 x 2 + 2) variants x 2 repeats");
    let manifest = std::fs::read_to_string(c.path("one/manifest.toml")).unwrap();
    assert!(
        manifest.contains("cells = 12") && manifest.contains("cells_computed = 12"),
        "{manifest}"
    );
    // An interrupted sweep: half its log, no manifest, no tables.
    ok(with(&["run", "d.toml", "--out", "cut"]));
    let log = somnurbs::experiment::log_text(&c.path("cut")).unwrap();
    let half: String = log.lines().take(7).map(|l| format!("{l}\n")).collect();
    for f in walk(&c.path("cut")) {
        if f.file_name().unwrap() != "fingerprint.toml" {
            std::fs::remove_file(f).unwrap();
        }
    }
    std::fs::write(c.path("cut/cells.jsonl"), half).unwrap();
    let out = ok(with(&["run", "d.toml", "--out", "cut", "--resume"]));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("already done"), "{err}");
    assert!(same_results(&c.path("one"), &c.path("cut")) >= 5);
    // Shards, merged.
    for i in 1..=3 {
        ok(with(&["run", "d.toml", "--out", &format!("shard{i}"), "--shard", &format!("{i}/3")]));
    }
    c.ok(&["merge", "shard1", "shard2", "shard3", "--out", "merged"]);
    assert!(same_results(&c.path("one"), &c.path("merged")) >= 5);
    // A shard of another sweep does not merge with these.
    c.ok(&[
        "run",
        "d.toml",
        "--out",
        "other3",
        "--shard",
        "3/3",
        "--sweep",
        "optimise.de.f=0.3,0.9",
        "--sweep",
        "optimise.generations=10,20",
    ]);
    c.fails(&["merge", "shard1", "shard2", "other3", "--out", "m2"], &["another run", "--sweep"]);
}

/// The quick Chapter 6 spec without --set keeps today's keys and seeds: its tables match the
/// committed quick baseline's.
#[test]
fn a_run_without_set_still_matches_the_quick_baseline() {
    let c = Case::new();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let spec = root.join("experiments/ch6_same.toml");
    c.ok(&["run", spec.to_str().unwrap(), "--profile", "quick", "--out", "ch6_same"]);
    let base = root.join("results/baselines/quick/ch6_same");
    for table in ["runs.csv", "appendix_k.csv"] {
        assert_eq!(
            without_timing(&base.join(table)),
            without_timing(&c.path(&format!("ch6_same/{table}"))),
            "{table} moved"
        );
    }
}
